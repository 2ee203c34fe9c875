//! `dfem bench-solvers`: every linear backend of this build on one matrix, the elastic
//! stiffness of a scene at its first solve (K of docs/theory.md §2–3 with the contacts'
//! elastic springs, the load vector of the scene), and one table of what each costs.

use super::{backend_with, BackendOptions};
use dfem_kernels::CsrMatrix;
use std::time::Instant;

/// One backend's measurements on the matrix.
#[derive(Debug, Clone)]
pub struct BenchRow {
    pub name: String,
    /// Symbolic phase (ordering, elimination tree; PETSc: matrix creation), s.
    pub setup_s: f64,
    /// Numeric factorization or preconditioner set-up, s.
    pub factor_s: f64,
    /// One solve, s.
    pub solve_s: f64,
    /// Krylov iterations (0 for the direct solvers).
    pub iterations: usize,
    /// Entries of the factor (direct solvers; 0 when not reported).
    pub factor_nnz: usize,
    /// Memory reported by the backend, bytes (0 when not reported).
    pub memory_bytes: usize,
    /// ‖b − A x‖₂ / ‖b‖₂ recomputed here from the matrix.
    pub residual: f64,
    /// Why the backend failed, if it did.
    pub error: Option<String>,
}

/// Runs each backend of `names` once on `k x = b` (a new instance each, so every phase
/// is timed from scratch), each given what dfem knows of `mesh` ([`super::configure`]:
/// the near-null space, ignored by the direct backends, and the block partition for
/// those that ask for one).
pub fn bench(
    k: &CsrMatrix,
    b: &[f64],
    mesh: &crate::mesh::Mesh,
    names: &[&str],
    opts: &BackendOptions,
) -> Vec<BenchRow> {
    names
        .iter()
        .map(|name| {
            let mut row = BenchRow {
                name: name.to_string(),
                setup_s: f64::NAN,
                factor_s: f64::NAN,
                solve_s: f64::NAN,
                iterations: 0,
                factor_nnz: 0,
                memory_bytes: 0,
                residual: f64::NAN,
                error: None,
            };
            if let Err(e) = run_one(k, b, mesh, name, opts, &mut row) {
                row.error = Some(e);
            }
            row
        })
        .collect()
}

fn run_one(
    k: &CsrMatrix,
    b: &[f64],
    mesh: &crate::mesh::Mesh,
    name: &str,
    opts: &BackendOptions,
    row: &mut BenchRow,
) -> Result<(), String> {
    // --subdomains is for the substructured backend only
    let own = BackendOptions {
        subdomains: opts.subdomains.filter(|_| name == super::SUBSTRUCTURED),
        ..opts.clone()
    };
    let mut be = backend_with(name, &own).map_err(|e| e.to_string())?;
    super::configure(be.as_mut(), mesh).map_err(|e| e.to_string())?;
    let t = Instant::now();
    be.analyze(&k.pattern).map_err(|e| e.to_string())?;
    row.setup_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    be.factorize(k).map_err(|e| e.to_string())?;
    row.factor_s = t.elapsed().as_secs_f64();
    let mut x = b.to_vec();
    let t = Instant::now();
    let solved = be.solve(&mut x);
    row.solve_s = t.elapsed().as_secs_f64();
    let s = be.stats();
    row.iterations = s.last_iterations;
    row.factor_nnz = s.factor_nnz;
    row.memory_bytes = s.memory_bytes;
    row.residual = relative_residual(k, &x, b);
    solved.map_err(|e| e.to_string())
}

/// ‖b − A x‖₂ / ‖b‖₂.
pub fn relative_residual(a: &CsrMatrix, x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; b.len()];
    a.mul_vec(x, &mut ax);
    let r: f64 = ax.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum();
    let bn: f64 = b.iter().map(|v| v * v).sum();
    (r / bn).sqrt()
}
