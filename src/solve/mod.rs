//! Linear backend selection (the PETSc pattern: chosen at run time by name, a backend not
//! compiled in is an error, not a crash).

pub use dfem_kernels::{LinearBackend, SolveError, BACKENDS};

/// Default backend: faer's supernodal Cholesky (LLᵀ) with the symbolic phase cached.
pub const DEFAULT: &str = "faer-cholesky";

/// Build a backend from its name (`--solver`).
pub fn backend(name: &str) -> crate::Result<Box<dyn LinearBackend>> {
    dfem_kernels::backend_from_name(name).map_err(|e| {
        crate::Error::new(e)
            .place("option --solver")
            .fix(format!("use one of: {}", BACKENDS.join(", ")))
    })
}
pub mod reuse;
