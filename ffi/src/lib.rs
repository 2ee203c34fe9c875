//! `dfem-ffi`: linear backends from outside Rust, each behind a cargo feature (issue 7):
//!
//! * `mumps`: `mumps::Mumps`, MUMPS' multifrontal LDLᵀ / LU through a hand-written binding
//!   of its C interface (`mumps_sys`).
//! * `petsc`: `petsc::Petsc`, PETSc's KSP (Krylov method + preconditioner chosen in
//!   PETSc's options database, default CG + GAMG with the rigid-body near-null space)
//!   through bindgen.
//! * `mpi`: under `mpirun`, the PETSc backend and (with `mumps`) MUMPS solve on every rank
//!   together, each rank giving the rows of its part of dfem's block partition (MUMPS'
//!   distributed input, ICNTL(18) = 3), see the modules `petsc` and `mumps` (built with
//!   their features); [`allgather`] and [`process_rank`] serve dfem's distributed
//!   assembly.
//!
//! [`backend_from_name`] builds them by name; [`BACKENDS`] lists the names compiled in.
//! Without features the crate is empty apart from the registry, which then explains which
//! feature to enable.

#[cfg(feature = "mumps")]
pub mod mumps;
#[cfg(feature = "mumps")]
pub mod mumps_sys;
#[cfg(feature = "petsc")]
pub mod petsc;
#[cfg(feature = "petsc")]
pub mod petsc_sys;

use dfem_kernels::LinearBackend;

/// Every backend name this crate knows, with the feature that provides it.
pub const ALL: &[(&str, &str)] = &[
    ("mumps", "mumps"),
    ("mumps-spd", "mumps"),
    ("mumps-lu", "mumps"),
    ("petsc", "petsc"),
];

/// Names of the backends compiled in (a subset of [`ALL`]).
pub const BACKENDS: &[&str] = &[
    #[cfg(feature = "mumps")]
    "mumps",
    #[cfg(feature = "mumps")]
    "mumps-spd",
    #[cfg(feature = "mumps")]
    "mumps-lu",
    #[cfg(feature = "petsc")]
    "petsc",
];

/// Options handed to the backends of this crate.
#[derive(Debug, Clone, Default)]
pub struct FfiOptions {
    /// PETSc options database entries, as on PETSc's command line
    /// (`-ksp_type cg -pc_type gamg ...`), added before the solver reads them.
    pub petsc_options: String,
}

/// Builds the backend `name`. `None`: not a name of this crate; `Some(Err)`: a name of
/// this crate that is not compiled in (the message names the feature) or that failed to
/// start.
pub fn backend_from_name(
    name: &str,
    opts: &FfiOptions,
) -> Option<Result<Box<dyn LinearBackend>, String>> {
    let feature = ALL.iter().find(|(n, _)| *n == name)?.1;
    let _ = opts;
    let built: Result<Box<dyn LinearBackend>, String> = match name {
        #[cfg(feature = "mumps")]
        "mumps" => mumps::Mumps::new(mumps::Symmetry::Symmetric)
            .map(|b| Box::new(b) as Box<dyn LinearBackend>)
            .map_err(|e| e.to_string()),
        #[cfg(feature = "mumps")]
        "mumps-spd" => mumps::Mumps::new(mumps::Symmetry::PositiveDefinite)
            .map(|b| Box::new(b) as Box<dyn LinearBackend>)
            .map_err(|e| e.to_string()),
        #[cfg(feature = "mumps")]
        "mumps-lu" => mumps::Mumps::new(mumps::Symmetry::General)
            .map(|b| Box::new(b) as Box<dyn LinearBackend>)
            .map_err(|e| e.to_string()),
        #[cfg(feature = "petsc")]
        "petsc" => petsc::Petsc::new(&opts.petsc_options)
            .map(|b| Box::new(b) as Box<dyn LinearBackend>)
            .map_err(|e| e.to_string()),
        _ => Err(format!(
            "the linear backend '{name}' is not compiled into this dfem; rebuild with \
             `cargo build --release --features {feature}` (it needs the system libraries \
             listed in README.md)"
        )),
    };
    Some(built)
}

/// This process's rank and the number of processes of a distributed run: `(0, 1)` unless
/// built with feature `mpi` and started by `mpirun` (then MPI starts here).
pub fn process_rank() -> (usize, usize) {
    #[cfg(feature = "mpi")]
    {
        petsc::rank_and_size().unwrap_or((0, 1))
    }
    #[cfg(not(feature = "mpi"))]
    {
        (0, 1)
    }
}

/// Concatenates the `local` values of every process of a distributed run, in rank order,
/// into `out` on every process: process r contributes `counts[r]` values (`counts[rank]`
/// is `local.len()`, `out.len()` the sum of `counts`). With one process, a copy; several
/// processes need feature `mpi` (under `mpirun`, [`process_rank`] tells).
pub fn allgather(local: &[f64], counts: &[usize], out: &mut [f64]) -> Result<(), String> {
    #[cfg(feature = "mpi")]
    {
        petsc::allgather(local, counts, out).map_err(|e| e.to_string())
    }
    #[cfg(not(feature = "mpi"))]
    {
        if counts.len() != 1 || out.len() != local.len() || counts[0] != local.len() {
            return Err(format!(
                "allgather over {} processes needs a dfem built with feature `mpi`",
                counts.len()
            ));
        }
        out.copy_from_slice(local);
        Ok(())
    }
}

/// Ends PETSc and MPI if they were started (call once, at the end of the program; a no-op
/// otherwise). Needed under `mpirun`, which reports processes that exit without it.
pub fn finalize() {
    #[cfg(feature = "petsc")]
    petsc::finalize();
}
