//! Simplicial against supernodal numeric factorization on dfem's own matrices (issue 6,
//! "Direct solvers"): faer picks one of its two factorizations from the symbolic factor's
//! flops per entry, at 40 by default; dfem sets the switch at
//! [`dfem_kernels::faer_backend::SUPERNODAL_FLOP_RATIO`]. This bench times both, and the
//! backends' default, on the elastic stiffness matrix of each case (the matrix
//! `dfem export-matrix` writes), for the Cholesky backend and the LU one (the Newton
//! strategy's, and the arc-length corrector's), one numeric factorization and one solve at
//! a time, each repeated for about 0.3 s after a first call.
//!
//!     cargo bench --bench supernodal -- [--threads 1] [--cases a,b,...]
//!
//! Cases (default all): the built-in examples `arch`, `tower`, `wall`, `tunnel`, `column`
//! (uncondensed) and `eindhoven` (J4D); `rigid10`, `rigid30`, `rigid60`: the rigid
//! running-bond walls of the strategies bench (n × n bricks 0.4 × 0.2 m); `p2-rigid`,
//! `p2-deformable`: benches/scenes. The columns: unknowns, the flop ratio (faer's
//! measure, of the Cholesky factor), then for each variant the numeric factorization and
//! the solve (ms), which variant the default took (Cholesky), and the default's
//! factorization time over the faster variant's. `--threads` gives faer's dense kernels `Par::rayon(k)`
//! inside a pool of k threads (dfem's runs keep them at 1).

use dfem_kernels::faer_backend::{DEFAULT_SUPERNODAL_THRESHOLD, SUPERNODAL_FLOP_RATIO};
use dfem_kernels::{CsrMatrix, FaerCholesky, FaerLu, LinearBackend};
use std::time::Instant;

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    let k = args.iter().position(|a| a == name)?;
    args.get(k + 1).cloned()
}

/// The rigid running-bond wall of benches/strategies.rs, `n` × `n` bricks.
fn rigid_wall(n: usize) -> String {
    format!(
        "[model]\nplane = \"stress\"\nthickness = 0.1\ngravity = [0.0, -9.81]\n\
         [[material]]\nname = \"brick\"\nlame_lambda = 1.389e9\nlame_mu = 2.083e9\nunit_weight = 18e3\n\
         [[joint]]\nname = \"mortar\"\nnormal_modulus = 8.2e8\nshear_modulus = 3.6e8\nband = 0.010\n\
         friction_angle = 31.0\n\
         [[generate]]\ntype = \"wall\"\nmaterial = \"brick\"\nkind = \"rigid\"\ncourses = {n}\n\
         bricks_per_course = {n}\nbrick_length = 0.4\nbrick_height = 0.2\n\
         [contacts]\njoint = \"mortar\"\n[analysis]\ntype = \"static\"\n"
    )
}

fn scene_text(case: &str) -> String {
    let file = |p: &str| {
        std::fs::read_to_string(format!("{}/benches/scenes/{p}", env!("CARGO_MANIFEST_DIR")))
            .expect("bench scene")
    };
    match case {
        "rigid10" => rigid_wall(10),
        "rigid30" => rigid_wall(30),
        "rigid60" => rigid_wall(60),
        "p2-rigid" => file("p2_wall40_rigid.toml"),
        "p2-deformable" => file("p2_wall40_deformable.toml"),
        name => dfem::scene::examples::get(name)
            .unwrap_or_else(|| panic!("unknown case {name}"))
            .to_string(),
    }
}

/// The elastic stiffness matrix of the scene, as `dfem export-matrix` assembles it.
fn matrix(case: &str) -> CsrMatrix {
    let sc = dfem::scene::parse_str(&scene_text(case), None).expect("scene parses");
    let mesh = dfem::mesh::build(&sc);
    let system = dfem::assembly::System::new(&sc, &mesh);
    system.stiffness(&mesh, &dfem::analysis::elastic_springs(&sc, &mesh))
}

/// Seconds of one numeric factorization and of one solve, each repeated for about
/// 0.3 s after a first call (a diagonal entry nudged by 1e-12 before each factorization,
/// so that the backend does not skip it as unchanged), and the factor's flops per entry
/// (faer's measure: 1 + ours).
fn time(backend: &mut dyn LinearBackend, a: &CsrMatrix) -> (f64, f64, f64) {
    let diag = a.pattern.diagonal_positions();
    let mut m = a.clone();
    backend.factorize(&m).expect("factorizes");
    let t = Instant::now();
    m.values[diag[0]] *= 1.0 + 1e-12;
    backend.factorize(&m).expect("factorizes");
    let reps = (0.3 / t.elapsed().as_secs_f64()).clamp(3.0, 2000.0) as usize;
    let t = Instant::now();
    for r in 0..reps {
        m.values[diag[r % diag.len()]] *= 1.0 + 1e-12;
        backend.factorize(&m).expect("factorizes");
    }
    let fact = t.elapsed().as_secs_f64() / reps as f64;
    let mut x = vec![1.0; a.pattern.n()];
    let t = Instant::now();
    for _ in 0..reps {
        backend.solve(&mut x).expect("solves");
    }
    let solve = t.elapsed().as_secs_f64() / reps as f64;
    let s = backend.stats();
    let ratio = if s.factor_nnz > 0 {
        1.0 + s.factor_flops / s.factor_nnz as f64
    } else {
        f64::NAN
    };
    (fact, solve, ratio)
}

fn main() {
    let threads: usize = arg("--threads").map_or(1, |t| t.parse().expect("--threads"));
    let cases = arg("--cases").unwrap_or_else(|| {
        "arch,tower,wall,tunnel,rigid10,rigid30,column,p2-rigid,eindhoven,rigid60,p2-deformable"
            .into()
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    println!(
        "numeric factorization and solve (ms), {threads} thread(s); flop ratio: faer's \
         (flops per factor entry); default: dfem's switch at a ratio of {}",
        SUPERNODAL_FLOP_RATIO
    );
    println!(
        "| case | unknowns | factor | flop ratio | simplicial | supernodal | default | default took | default / best |"
    );
    println!("|---|---:|---|---:|---|---|---|---|---:|");
    pool.install(|| {
        for case in cases.split(',') {
            let a = matrix(case);
            for lu in [false, true] {
                let make = |t: f64| -> Box<dyn LinearBackend> {
                    if lu {
                        Box::new(FaerLu::new().with_supernodal_threshold(t))
                    } else {
                        Box::new(
                            FaerCholesky::new()
                                .with_supernodal_threshold(t)
                                .with_threads(threads),
                        )
                    }
                };
                let simp = time(make(f64::INFINITY).as_mut(), &a);
                let sup = time(make(0.0).as_mut(), &a);
                // the default, and which kernel it took (the Cholesky backend's analysis
                // says; faer's LU does not expose its choice)
                let (dflt, took) = if lu {
                    (time(make(DEFAULT_SUPERNODAL_THRESHOLD).as_mut(), &a), "–")
                } else {
                    let mut b = FaerCholesky::new().with_threads(threads);
                    let t = time(&mut b, &a);
                    let took = match b.supernodal() {
                        Some(true) => "supernodal",
                        _ => "simplicial",
                    };
                    (t, took)
                };
                let ms = |v: (f64, f64, f64)| format!("{:.3} / {:.3}", v.0 * 1e3, v.1 * 1e3);
                println!(
                    "| {case} | {} | {} | {} | {} | {} | {} | {took} | {:.2} |",
                    a.pattern.n(),
                    if lu { "LU" } else { "LLᵀ" },
                    if lu {
                        "–".to_string()
                    } else {
                        format!("{:.1}", sup.2)
                    },
                    ms(simp),
                    ms(sup),
                    ms(dflt),
                    dflt.0 / simp.0.min(sup.0)
                );
            }
        }
    });
}
