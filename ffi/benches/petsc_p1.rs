//! The PETSc backend on the exact matrix of docs/validation.md P1 (`elast2d_353.mtx` and
//! `elast2d_353_rhs.mtx`, written by `cargo bench -p dfem-kernels --bench solvers --
//! --write-mtx DIR` or the peers' gen_matrix.py) with the near-null space of the peers'
//! harness (bench_petsc.py: rigid-body modes from the structured grid's coordinates), so
//! that its times compare with petsc4py's on the same matrix.
//!
//! ```text
//! cargo bench -p dfem-ffi --features petsc --bench petsc_p1 --no-run
//! target/release/deps/petsc_p1-* DIR [--reps 3] [--petsc-options "-ksp_rtol 1e-8"]
//! ```
//! Prints, per run: set-up (matrix creation + KSPSetUp) and solve times, iterations, true
//! residual.

#[cfg(feature = "petsc")]
fn main() {
    use dfem_kernels::LinearBackend;
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dir = std::path::PathBuf::from(args.first().map(String::as_str).unwrap_or("."));
    let get = |k: &str| {
        args.iter()
            .position(|a| a == k)
            .map(|i| args[i + 1].clone())
    };
    let reps: usize = get("--reps").map_or(3, |v| v.parse().unwrap());
    let opts = get("--petsc-options").unwrap_or_else(|| "-ksp_rtol 1e-8".into());
    let a = dfem_kernels::mm::read_matrix_market(&dir.join("elast2d_353.mtx")).unwrap();
    let b = dfem_kernels::mm::read_vector_market(&dir.join("elast2d_353_rhs.mtx")).unwrap();
    let n = a.pattern.n();
    // grid of nn × nn nodes, spacing 1/(nn-1), the bottom row fixed: n = 2 nn (nn - 1)
    let nn = ((1.0 + (1.0 + 2.0 * n as f64).sqrt()) / 2.0).round() as usize;
    assert_eq!(2 * nn * (nn - 1), n, "not a P1 matrix");
    let h = 1.0 / (nn - 1) as f64;
    let mut modes = vec![vec![0.0; n]; 3];
    for k in nn..nn * nn {
        let (x, y) = ((k % nn) as f64 * h, (k / nn) as f64 * h);
        let d = 2 * (k - nn);
        modes[0][d] = 1.0;
        modes[1][d + 1] = 1.0;
        modes[2][d] = -y;
        modes[2][d + 1] = x;
    }
    println!(
        "P1: {n} unknowns, {} entries; PETSc options: {opts}",
        a.pattern.nnz()
    );
    for _ in 0..reps {
        let mut p = dfem_ffi::petsc::Petsc::new(&opts).unwrap();
        p.set_near_null_space(&modes).unwrap();
        let t = std::time::Instant::now();
        p.factorize(&a).unwrap();
        let setup = t.elapsed().as_secs_f64();
        let mut x = b.clone();
        let t = std::time::Instant::now();
        p.solve(&mut x).unwrap();
        let solve = t.elapsed().as_secs_f64();
        let s = p.stats();
        println!(
            "{}: matrix {:.3} s, KSPSetUp {:.3} s, solve {:.3} s, set-up + solve {:.3} s, {} iterations, true residual {:.1e}",
            p.method(),
            s.symbolic_seconds,
            s.numeric_seconds,
            solve,
            setup + solve,
            s.last_iterations,
            s.last_true_residual
        );
    }
    drop(modes);
    dfem_ffi::finalize();
}

#[cfg(not(feature = "petsc"))]
fn main() {
    eprintln!("build with --features petsc");
}
