//! Subdomain-parallel factorization (issue 11): `faer-substructured` against faer's
//! single-thread Cholesky of the whole matrix (`faer-cholesky`, AMD) on the built-in
//! running-bond wall (`dfem example wall`) scaled to n × n bricks, its elastic stiffness
//! of the first solve (K of METHOD.md §2–3) and its gravity load.
//!
//!     cargo bench --bench substructure -- [--n 300] [--kind deformable|rigid]
//!         [--subdomains 1,2,4] [--threads 2] [--reps 3] [--ordering metis|amd]
//!         [--subdomain-threads 1]
//!
//! n = 300 deformable bricks give 1,079,402 unknowns. For each configuration: the
//! analysis (block partition, orderings, symbolic factorizations), the first numeric
//! factorization, the median and best of `reps` refactorizations with every value
//! changed (all scaled by 1 + r·2⁻²⁰), one solve, and where a refactorization's time goes
//! (thread time summed over the subdomains' sparse factorizations, over their Schur
//! complements, and over the dense interface fronts). Then the reuse case of a secant
//! iteration in which the contacts of one subdomain changed: 5 % of the contacts joining
//! two blocks of subdomain 0 have their springs divided by 1000 (an opening joint),
//! alternately on and off, so that each factorization sees one changed subdomain; its
//! median time against a full refactorization. Every solution is compared with
//! faer-cholesky's (max-norm relative difference). The tables are markdown,
//! with the load average before and after.

use dfem::analysis;
use dfem::assembly::System;
use dfem::solve::{block_partition, configure, LinearBackend};
use dfem_kernels::{
    max_relative_difference, CsrMatrix, FaerCholesky, FaerCholeskySubstructured, FillOrdering,
};
use std::time::Instant;

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    let k = args.iter().position(|a| a == name)?;
    args.get(k + 1).cloned()
}

fn list(name: &str, default: &str) -> Vec<usize> {
    arg(name)
        .unwrap_or_else(|| default.to_string())
        .split(',')
        .map(|v| v.parse().unwrap_or_else(|_| panic!("{name}: {v}")))
        .collect()
}

fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .unwrap_or_default()
        .trim()
        .to_string()
}

/// The wall example with `n` courses of `n` bricks (rigid bricks if `rigid`).
fn wall_scene(n: usize, rigid: bool) -> dfem::scene::Scene {
    dfem::scene::parse_str(&dfem::scene::examples::scaled_wall(n, rigid), None)
        .expect("scaled wall")
}

/// All values scaled by 1 + r·2⁻²⁰ (every bit pattern changes; the solution scales).
fn scaled(k: &CsrMatrix, r: usize) -> CsrMatrix {
    let mut a = k.clone();
    let s = 1.0 + r as f64 * (-20f64).exp2();
    a.values.iter_mut().for_each(|v| *v *= s);
    a
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

struct Timed {
    analysis: f64,
    first: f64,
    refactor: f64,
    best: f64,
    solve: f64,
    x: Vec<f64>,
}

/// Analysis, first factorization, `reps` full refactorizations, a solve of `k x = f`.
fn time_backend(be: &mut dyn LinearBackend, k: &CsrMatrix, f: &[f64], reps: usize) -> Timed {
    let t = Instant::now();
    be.analyze(&k.pattern).expect("analysis");
    let analysis = t.elapsed().as_secs_f64();
    let t = Instant::now();
    be.factorize(k).expect("factorization");
    let first = t.elapsed().as_secs_f64();
    let mut times: Vec<f64> = (1..=reps)
        .map(|r| {
            let a = scaled(k, r);
            let t = Instant::now();
            be.factorize(&a).expect("refactorization");
            t.elapsed().as_secs_f64()
        })
        .collect();
    be.factorize(k).expect("factorization");
    let mut x = f.to_vec();
    let t = Instant::now();
    be.solve(&mut x).expect("solve");
    let solve = t.elapsed().as_secs_f64();
    let best = times.iter().copied().fold(f64::INFINITY, f64::min);
    Timed {
        analysis,
        first,
        refactor: median(&mut times),
        best,
        solve,
        x,
    }
}

fn main() {
    let n: usize = arg("--n").map_or(300, |v| v.parse().expect("--n"));
    let rigid = arg("--kind").as_deref() == Some("rigid");
    let reps: usize = arg("--reps").map_or(3, |v| v.parse().expect("--reps"));
    let parts = list("--subdomains", "1,2,4");
    let threads = list("--threads", "2");
    let sub_threads: usize =
        arg("--subdomain-threads").map_or(1, |v| v.parse().expect("--subdomain-threads"));
    let ordering = match arg("--ordering").as_deref() {
        Some("amd") => FillOrdering::Amd,
        _ => FillOrdering::Metis,
    };
    println!("# load average before: {}", load());
    let t = Instant::now();
    let sc = wall_scene(n, rigid);
    let m = dfem::mesh::build(&sc);
    let system = System::new(&sc, &m);
    let springs = analysis::elastic_springs(&sc, &m);
    let k = system.stiffness(&m, &springs);
    let f = analysis::external_load(&sc, &m);
    println!(
        "# wall {n} x {n} {} bricks: {} unknowns, {} stored entries, {} blocks, {} contacts; model {:.1} s; interior ordering {ordering:?}, {sub_threads} task(s) inside each subdomain; {reps} refactorizations each\n",
        if rigid { "rigid" } else { "deformable" },
        k.pattern.n(),
        k.pattern.nnz(),
        m.blocks.len(),
        m.contacts.len(),
        t.elapsed().as_secs_f64()
    );

    // the reference: faer's Cholesky of the whole matrix, AMD, one thread
    let mut faer = FaerCholesky::new();
    let base = time_backend(&mut faer, &k, &f, reps);
    let base_mb = faer.stats().factor_nnz as f64 * 8.0 / 1e6;
    println!("| backend | subdomains | threads | interface unknowns | analysis (s) | first factorization (s) | refactorization, median (s) | best (s) | solve (s) | speed-up: faer-cholesky / (refactorization + solve) | interface fronts (Γ, B) | sparse factorizations, Σ (s) | Schur complements, Σ (s) | interface fronts, Σ (s) | factor entries (M) | factor memory (MB) | rel. difference to faer-cholesky |");
    println!(
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|"
    );
    println!(
        "| faer-cholesky (AMD) | 1 | 1 | 0 | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | 1.00 | | | | | {:.1} | {:.0} | 0 |",
        base.analysis,
        base.first,
        base.refactor,
        base.best,
        base.solve,
        faer.stats().factor_nnz as f64 / 1e6,
        base_mb
    );
    let base_total = base.refactor + base.solve;
    let mut reuse_rows = Vec::new();
    for &kp in &parts {
        let part = block_partition(&m, kp).expect("block partition");
        for &nt in &threads {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(nt)
                .build()
                .expect("pool");
            pool.install(|| {
                let mut be = FaerCholeskySubstructured::new()
                    .with_subdomains(kp)
                    .with_ordering(ordering)
                    .with_subdomain_threads(sub_threads);
                configure(&mut be, &m).expect("configure");
                let r = time_backend(&mut be, &k, &f, reps);
                let ss = be.substructure_stats().clone();
                let nf = (reps + 2) as f64;
                println!(
                    "| faer-substructured | {kp} | {nt} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | {} | {:.3} | {:.3} | {:.3} | {:.1} | {:.0} | {:.1e} |",
                    ss.interface_size,
                    r.analysis,
                    r.first,
                    r.refactor,
                    r.best,
                    r.solve,
                    base_total / (r.refactor + r.solve),
                    ss.front_sizes
                        .iter()
                        .map(|(o, b)| format!("({o}, {b})"))
                        .collect::<Vec<_>>()
                        .join(" "),
                    ss.subdomain_factor_seconds / nf,
                    ss.schur_seconds / nf,
                    ss.interface_seconds / nf,
                    be.stats().factor_nnz as f64 / 1e6,
                    be.stats().memory_bytes as f64 / 1e6,
                    max_relative_difference(&r.x, &base.x)
                );
                if kp < 2 {
                    return;
                }
                // reuse: 5 % of the contacts inside subdomain 0 open
                let block_part = |b: u32| {
                    let blk = &m.blocks[b as usize];
                    let node = blk.nodes.start as usize;
                    match blk.dofs {
                        dfem::mesh::BlockDofs::Rigid { first, .. } => Some(part[first as usize]),
                        _ => {
                            let d = m.node_dofs[node][0];
                            (d != dfem_kernels::CONSTRAINED).then(|| part[d as usize])
                        }
                    }
                };
                let inside: Vec<usize> = (0..m.contacts.len())
                    .filter(|&c| {
                        let ct = &m.contacts[c];
                        block_part(ct.block_l) == Some(0) && block_part(ct.block_m) == Some(0)
                    })
                    .collect();
                let mut opened = springs.clone();
                for &c in inside.iter().step_by(20) {
                    opened[c].kn *= 1e-3;
                    opened[c].ks *= 1e-3;
                }
                let k2 = system.stiffness(&m, &opened);
                let mut times = Vec::new();
                let before = be.substructure_stats().subdomain_factorizations;
                for r in 0..2 * reps {
                    let a = if r % 2 == 0 { &k2 } else { &k };
                    let t = Instant::now();
                    be.factorize(a).expect("refactorization");
                    times.push(t.elapsed().as_secs_f64());
                }
                let refactored = be.substructure_stats().subdomain_factorizations - before;
                let fronts = be.substructure_stats().last_fronts;
                be.factorize(&k2).expect("factorization");
                let mut x = f.clone();
                be.solve(&mut x).expect("solve");
                let mut xf = f.clone();
                faer.factorize(&k2).expect("faer");
                faer.solve(&mut xf).expect("faer");
                let t_one = median(&mut times);
                reuse_rows.push(format!(
                    "| {kp} | {nt} | {} | {:.2} | {fronts} | {} | {:.3} | {:.3} | {:.0} % | {:.3} | {:.0} % | {:.1e} |",
                    inside.len().div_ceil(20),
                    refactored as f64 / (2 * reps) as f64,
                    ss.interface_size,
                    t_one,
                    r.refactor,
                    100.0 * t_one / r.refactor,
                    base.refactor,
                    100.0 * t_one / base.refactor,
                    max_relative_difference(&x, &xf)
                ));
            });
        }
    }
    println!(
        "\nOne subdomain changed (a secant iteration in which contacts of subdomain 0 open):\n"
    );
    println!("| subdomains | threads | contacts changed | subdomains refactorized per factorization | fronts recomputed | interface unknowns | factorization, median (s) | full refactorization, same backend (s) | ratio | faer-cholesky refactorization (s) | ratio | rel. difference to faer-cholesky |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in reuse_rows {
        println!("{r}");
    }
    println!("\n# load average after: {}", load());
}
