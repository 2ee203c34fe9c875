//! The run-time registry of the built-in backends: their names ([`BACKENDS`]) and
//! [`backend_from_name`], which builds one. It sits above every backend module (it
//! imports them all), so that [`crate::backend`], which they all import, imports none.

use crate::backend::LinearBackend;
use crate::ordering::FillOrdering;

/// Names accepted by [`backend_from_name`].
pub const BACKENDS: &[&str] = &[
    "faer-cholesky",
    "faer-cholesky-metis",
    "faer-cholesky-split",
    "faer-ldlt",
    "faer-ldlt-metis",
    "faer-lu",
    "faer-condensed",
    "faer-substructured",
    "pcg",
];

/// Builds a backend from its name (one of [`BACKENDS`]) with default settings. The
/// `-metis` variants order the unknowns by METIS nested dissection instead of AMD;
/// `faer-substructured` is [`crate::substructure::FaerCholeskySubstructured`] with two
/// subdomains; `faer-condensed` is [`crate::condensed::FaerCholeskyCondensed`] (the
/// blocks' interiors condensed out, given [`LinearBackend::set_interiors`]).
/// The error message lists the valid names.
pub fn backend_from_name(name: &str) -> Result<Box<dyn LinearBackend>, String> {
    match name {
        "faer-cholesky" => Ok(Box::new(crate::faer_backend::FaerCholesky::new())),
        "faer-cholesky-metis" => Ok(Box::new(
            crate::faer_backend::FaerCholesky::new().with_ordering(FillOrdering::Metis),
        )),
        "faer-cholesky-split" => Ok(Box::new(crate::split::FaerCholeskySplit::new())),
        "faer-ldlt" => Ok(Box::new(crate::faer_backend::FaerLdlt::new())),
        "faer-ldlt-metis" => Ok(Box::new(
            crate::faer_backend::FaerLdlt::new().with_ordering(FillOrdering::Metis),
        )),
        "faer-lu" => Ok(Box::new(crate::faer_backend::FaerLu::new())),
        "faer-condensed" => Ok(Box::new(crate::condensed::FaerCholeskyCondensed::new())),
        "faer-substructured" => Ok(Box::new(
            crate::substructure::FaerCholeskySubstructured::new(),
        )),
        "pcg" => Ok(Box::new(crate::pcg::Pcg::new())),
        _ => Err(format!(
            "unknown linear backend '{name}'; valid names: {}",
            BACKENDS.join(", ")
        )),
    }
}
