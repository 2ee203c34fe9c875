#![warn(missing_docs)]
//! `dfem-kernels`: physics-free sparse linear algebra for dfem, on faer and rayon.
//!
//! * [`csr`]: the sparsity pattern ([`CsrPattern`], built once per topology) and matrices
//!   holding values on it ([`CsrMatrix`]).
//! * [`assembly`]: deterministic parallel assembly ([`AssemblyPlan`]).
//! * [`backend`]: the [`LinearBackend`] trait, its errors and counters.
//! * [`registry`]: every built-in backend by name ([`backend_from_name`], [`BACKENDS`]).
//! * [`faer_backend`]: sparse Cholesky LLᵀ, LDLᵀ and LU on faer.
//! * [`lowrank`]: solves with a matrix changed on few unknowns through the held
//!   Cholesky factor of the old one (Woodbury inside the factor).
//! * [`split`]: sparse Cholesky on two threads through a METIS vertex bisection.
//! * [`condensed`]: sparse Cholesky with the blocks' interiors condensed out (static
//!   condensation), only the changed blocks and the boundary system refactorized.
//! * [`substructure`]: sparse Cholesky by substructuring, k subdomains in parallel, the
//!   unchanged ones reused between factorizations.
//! * [`pcg`]: preconditioned conjugate gradients (Jacobi, block-Jacobi, two-level with a
//!   rigid-body coarse space).
//! * [`ordering`]: fill-reducing orderings (AMD, METIS nested dissection).
//! * [`mm`]: Matrix Market input and output.
//!
//! Determinism: assembly, `mul_vec` and PCG reductions use fixed chunking; the direct
//! factorizations run sequentially. Results are bit-identical for any thread count.

pub mod assembly;
pub mod backend;
mod cholesky;
pub mod condensed;
pub mod csr;
pub mod faer_backend;
pub mod lowrank;
pub mod mm;
pub mod ordering;
mod partial;
pub mod pcg;
pub mod registry;
pub mod split;
pub mod substructure;

pub use assembly::{unpack_symmetric, AssemblyPlan, Connectivity, Form, CONSTRAINED};
pub use backend::{max_relative_difference, same_bits, LinearBackend, SolveError, SolverStats};
pub use condensed::{Decision, FaerCholeskyCondensed};
pub use csr::{CsrMatrix, CsrPattern};
pub use faer_backend::{FaerCholesky, FaerLdlt, FaerLu};
pub use lowrank::{LowRankCorrection, LowRankStats};
pub use ordering::{metis_partition, metis_partition_graph, FillOrdering};
pub use pcg::{BlockNodes2d, CoarseCorrection, CoarseSpace, Pcg, Preconditioner};
pub use registry::{backend_from_name, BACKENDS};
pub use split::FaerCholeskySplit;
pub use substructure::{FaerCholeskySubstructured, SubstructureStats};
