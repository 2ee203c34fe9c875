//! Subdomain-parallel factorization (issue 11): `faer-substructured` against faer's
//! single-thread Cholesky of the whole matrix (`faer-cholesky`, AMD) on the built-in
//! running-bond wall (`dfem example wall`) scaled to n × n bricks, its elastic stiffness
//! of the first solve (K of docs/theory.md §2–3) and its gravity load.
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
//! complements, and over the dense interface fronts), with the critical path in thread
//! CPU time (`SubstructureStats::last_critical_path_seconds`: the time with a free core
//! per subdomain, which the other jobs of a shared machine do not inflate the way they
//! inflate the wall time). Then the reuse case of a secant
//! iteration in which the contacts of one subdomain changed: 5 % of the contacts joining
//! two blocks of subdomain 0 have their springs divided by 1000 (an opening joint),
//! alternately on and off, so that each factorization sees one changed subdomain; its
//! median time against a full refactorization. Every solution is compared with
//! faer-cholesky's (max-norm relative difference). The tables are markdown,
//! with the load average before and after.
//!
//! `--secant 0.0002,0.001,0.01` measures instead the cost of a secant iteration of the
//! static driver (issue 6) on the deformable wall: those fractions of the contacts change
//! state (every 1/fraction-th contact, alternately opening and slipping), and for each
//! the table gives the update of the matrix (`System::stiffness_update`, re-assembling
//! only the changed contacts) against a whole assembly, the correction by conjugate
//! gradients preconditioned with the factorization of the matrix before the change
//! (`solve::reuse::solve_with_factor`, relative tolerance 1e-10, at most `--pcg-max`
//! iterations) with its iterations and true residual, and the numeric refactorization
//! plus solve the driver does instead when more than a few contacts changed, all against
//! one numeric refactorization of the same matrix (faer-cholesky, AMD, one thread).
//! The last columns give the exact correction through the held factor instead
//! (`dfem_kernels::LowRankCorrection`, the Woodbury identity inside the factor): the
//! rank of the change, the rows and entries of W = L⁻¹ P U, the set-up and the solve
//! (medians of 10), the true residual, and the whole iteration (update of the matrix +
//! set-up + solve) against the refactorization.

use dfem::analysis;
use dfem::assembly::{diagonal, LocalStiffness, System};
use dfem::solve::reuse::solve_with_factor;
use dfem::solve::{block_partition, configure, LinearBackend};
use dfem_kernels::{
    max_relative_difference, CsrMatrix, FaerCholesky, FaerCholeskySubstructured, FillOrdering,
    LowRankCorrection,
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

/// CPU time (user + system) of this process so far, s (`/proc/self/stat`, in units of
/// Linux's USER_HZ = 1/100 s); NaN where unavailable. On a loaded machine the wall times
/// include waits for a core, the CPU times only the work done.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or(Vec::new(), |(_, r)| r.split_whitespace().collect());
    // after the command: state is field 3, utime 14 and stime 15 (1-based, man proc)
    let tick = |k: usize| fields.get(k - 3).and_then(|v| v.parse::<f64>().ok());
    match (tick(14), tick(15)) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}

/// Wall and CPU time of `f`, s.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let (t, c) = (Instant::now(), cpu_seconds());
    let r = f();
    (r, t.elapsed().as_secs_f64(), cpu_seconds() - c)
}

struct Timed {
    analysis: f64,
    /// Median CPU time of a refactorization, s.
    refactor_cpu: f64,
    first: f64,
    refactor: f64,
    best: f64,
    solve: f64,
    /// Median of `probe` after each refactorization.
    probe: f64,
    x: Vec<f64>,
}

/// Analysis, first factorization, `reps` full refactorizations (`probe` read after each),
/// a solve of `k x = f`.
fn time_backend<B: LinearBackend + ?Sized>(
    be: &mut B,
    k: &CsrMatrix,
    f: &[f64],
    reps: usize,
    mut probe: impl FnMut(&B) -> f64,
) -> Timed {
    let t = Instant::now();
    be.analyze(&k.pattern).expect("analysis");
    let analysis = t.elapsed().as_secs_f64();
    let t = Instant::now();
    be.factorize(k).expect("factorization");
    let first = t.elapsed().as_secs_f64();
    let mut probes = Vec::new();
    let (mut times, mut cpu): (Vec<f64>, Vec<f64>) = (1..=reps)
        .map(|r| {
            let a = scaled(k, r);
            let (_, wall, cpu) = timed(|| be.factorize(&a).expect("refactorization"));
            probes.push(probe(be));
            (wall, cpu)
        })
        .unzip();
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
        refactor_cpu: median(&mut cpu),
        best,
        solve,
        probe: median(&mut probes),
        x,
    }
}

/// Relative true residual ‖f − K x‖₂ / ‖f‖₂.
fn true_residual(k: &CsrMatrix, x: &[f64], f: &[f64]) -> f64 {
    let mut kx = vec![0.0; x.len()];
    k.mul_vec(x, &mut kx);
    let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|a| a * a).sum::<f64>().sqrt();
    norm(&mut f.iter().zip(&kx).map(|(a, b)| a - b)) / norm(&mut f.iter().copied())
}

/// Repetitions of the low-rank correction in the `--secant` table.
const LOWRANK_REPS: usize = 10;

/// The `--secant` table (see the module's documentation).
fn secant_iteration(
    sc: &dfem::scene::Scene,
    m: &dfem::mesh::Mesh,
    system: &System,
    fractions: &[f64],
    reps: usize,
    pcg_max: usize,
) {
    let springs = analysis::elastic_springs(sc, m);
    let local0: Vec<LocalStiffness> = springs.iter().map(|&s| diagonal(s)).collect();
    let mut k = CsrMatrix::zeros(system.plan.pattern().clone());
    // twice: from the second assembly on one geometry the triangles' part is kept, as in
    // the driver's iterations within an increment
    system.stiffness_into(m, &local0, &mut k);
    system.stiffness_into(m, &local0, &mut k);
    let f = analysis::external_load(sc, m);
    let mut held = FaerCholesky::new();
    held.factorize(&k).expect("factorization");
    let mut fresh = FaerCholesky::new();
    fresh.factorize(&k).expect("factorization");
    let (mut wall, mut cpu): (Vec<f64>, Vec<f64>) = (1..=reps)
        .map(|r| {
            let a = scaled(&k, r);
            let (_, w, c) = timed(|| fresh.factorize(&a).expect("refactorization"));
            (w, c)
        })
        .unzip();
    let (refactor, refactor_cpu) = (median(&mut wall), median(&mut cpu));
    let mut x = f.clone();
    let (_, solve, solve_cpu) = timed(|| fresh.solve(&mut x).expect("solve"));
    // the low-rank correction's symbolic phase (the supernodes' elimination tree), once
    // per analysis: timed with a change of rank 0
    let mut lowrank = LowRankCorrection::new();
    let (_, t_sym, _) = timed(|| lowrank.update(&held, &k).expect("no change"));
    // the first update of the matrix builds the element adjacency, once per run: made
    // here so that every row of the table times a warm update
    let mut warm = local0.clone();
    warm[0] = [[0.0; 2]; 2];
    let (_, t_first, _) = timed(|| system.stiffness_update(m, &local0, &warm, &mut k.clone()));
    println!(
        "# deformable wall: {} unknowns, {} contacts, factor {} entries; numeric refactorization (faer-cholesky, AMD, 1 thread), median of {reps}: {refactor:.3} s wall, {refactor_cpu:.2} s CPU; one solve {solve:.3} s wall, {solve_cpu:.2} s CPU; low-rank correction's symbolic phase {t_sym:.3} s; first update of the matrix (builds the element adjacency) {t_first:.3} s\n",
        k.pattern.n(),
        local0.len(),
        fresh.stats().factor_nnz
    );
    println!("| contacts changed | share | whole assembly (s) | update (s) | PCG on the old factor: iterations | PCG (s) | PCG true residual | update + PCG / refactorization | (CPU) | refactorization + solve (s) | its true residual | update + refactorization + solve / refactorization | (CPU) | low-rank: rank | W rows, entries | correction set-up (s) | its solve (s) | its true residual | update + correction + solve / refactorization | (CPU) |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let nc = local0.len();
    for &share in fractions {
        let every = ((1.0 / share).round() as usize).max(1);
        let mut local = local0.clone();
        let changed: Vec<usize> = (0..nc).step_by(every).collect();
        for (i, &c) in changed.iter().enumerate() {
            let kn = local0[c][0][0];
            // alternately an opening contact (nothing) and a slipping one (no shear)
            local[c] = if i % 2 == 0 {
                [[0.0; 2]; 2]
            } else {
                [[kn, 0.0], [0.0, 0.0]]
            };
        }
        let mut whole = k.clone();
        let (_, t_whole, _) = timed(|| system.stiffness_into(m, &local, &mut whole));
        let mut upd = k.clone();
        let (_, t_upd, c_upd) = timed(|| system.stiffness_update(m, &local0, &local, &mut upd));
        assert!(
            upd.values
                .iter()
                .zip(&whole.values)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "the update differs from a whole assembly"
        );
        let (pcg, t_pcg, c_pcg) = timed(|| solve_with_factor(&upd, &mut held, &f, 1e-10, pcg_max));
        let (its, pcg_res) = match &pcg {
            Some(o) => (o.iterations.to_string(), true_residual(&upd, &o.x, &f)),
            None => (format!("> {pcg_max}"), f64::NAN),
        };
        let mut x = f.clone();
        let (_, t_ref, c_ref) = timed(|| {
            fresh.factorize(&upd).expect("refactorization");
            fresh.solve(&mut x).expect("solve");
        });
        // the low-rank correction, LOWRANK_REPS times (each takes a few hundredths of a
        // second: the medians of the walls, the mean of the CPU ticks)
        let (mut w_set, mut w_solve, mut cpu) = (Vec::new(), Vec::new(), 0.0);
        let mut x_lr = f.clone();
        let mut outcome = Ok(());
        for _ in 0..LOWRANK_REPS {
            x_lr.copy_from_slice(&f);
            let (lr, t_lr, c_lr) = timed(|| lowrank.update(&held, &upd));
            let (lr_solve, t_lr_solve, c_lr_solve) = timed(|| lowrank.solve(&held, &mut x_lr));
            outcome = lr.and(lr_solve);
            w_set.push(t_lr);
            w_solve.push(t_lr_solve);
            cpu += (c_lr + c_lr_solve) / LOWRANK_REPS as f64;
        }
        let lr_cells = match outcome {
            Ok(()) => {
                let (t_lr, t_lr_solve) = (median(&mut w_set), median(&mut w_solve));
                format!(
                    "{} | {}, {} | {t_lr:.4} | {t_lr_solve:.4} | {:.1e} | {:.2} | {:.2}",
                    lowrank.stats().rank,
                    lowrank.stats().reach_rows,
                    lowrank.stats().w_entries,
                    true_residual(&upd, &x_lr, &f),
                    (t_upd + t_lr + t_lr_solve) / refactor,
                    (c_upd + cpu) / refactor_cpu,
                )
            }
            Err(e) => format!("{e} | | | | | |"),
        };
        println!(
            "| {} | {:.2} % | {t_whole:.4} | {t_upd:.4} | {its} | {t_pcg:.3} | {pcg_res:.1e} | {:.2} | {:.2} | {t_ref:.3} | {:.1e} | {:.2} | {:.2} | {lr_cells} |",
            changed.len(),
            100.0 * changed.len() as f64 / nc as f64,
            (t_upd + t_pcg) / refactor,
            (c_upd + c_pcg) / refactor_cpu,
            true_residual(&upd, &x, &f),
            (t_upd + t_ref) / refactor,
            (c_upd + c_ref) / refactor_cpu,
        );
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
    if let Some(fractions) = arg("--secant") {
        let fractions: Vec<f64> = fractions
            .split(',')
            .map(|v| v.parse().unwrap_or_else(|_| panic!("--secant: {v}")))
            .collect();
        let pcg_max = arg("--pcg-max").map_or(200, |v| v.parse().expect("--pcg-max"));
        secant_iteration(&sc, &m, &system, &fractions, reps, pcg_max);
        println!("\n# load average after: {}", load());
        return;
    }
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
    let base = time_backend(&mut faer, &k, &f, reps, |_| f64::NAN);
    let base_mb = faer.stats().factor_nnz as f64 * 8.0 / 1e6;
    println!("| backend | subdomains | threads | interface unknowns | analysis (s) | first factorization (s) | refactorization, median (s) | best (s) | CPU time of a refactorization, median (s) | critical path, thread CPU, median (s) | solve (s) | speed-up: faer-cholesky / (refactorization + solve) | interface fronts (Γ, B) | sparse factorizations, Σ (s) | Schur complements, Σ (s) | interface fronts, Σ (s) | factor entries (M) | factor memory (MB) | work (G multiply-adds) | critical path (G) | work-bound speed-up | rel. difference to faer-cholesky |");
    println!(
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    println!(
        "| faer-cholesky (AMD) | 1 | 1 | 0 | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | | {:.3} | 1.00 | | | | | {:.1} | {:.0} | {:.1} | {:.1} | 1.00 | 0 |",
        base.analysis,
        base.first,
        base.refactor,
        base.best,
        base.refactor_cpu,
        base.solve,
        faer.stats().factor_nnz as f64 / 1e6,
        base_mb,
        faer.stats().factor_flops / 1e9,
        faer.stats().factor_flops / 1e9,
    );
    let base_flops = faer.stats().factor_flops;
    let base_total = base.refactor + base.solve;
    // the same whole factorization with METIS nested dissection: what the ordering alone gives
    let mut metis = FaerCholesky::new().with_ordering(FillOrdering::Metis);
    let r = time_backend(&mut metis, &k, &f, reps, |_| f64::NAN);
    let st = metis.stats();
    println!(
        "| faer-cholesky-metis | 1 | 1 | 0 | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | | {:.3} | {:.2} | | | | | {:.1} | {:.0} | {:.1} | {:.1} | {:.2} | {:.1e} |",
        r.analysis,
        r.first,
        r.refactor,
        r.best,
        r.refactor_cpu,
        r.solve,
        base_total / (r.refactor + r.solve),
        st.factor_nnz as f64 / 1e6,
        st.factor_nnz as f64 * 8.0 / 1e6,
        st.factor_flops / 1e9,
        st.factor_flops / 1e9,
        base_flops / st.factor_flops,
        max_relative_difference(&r.x, &base.x)
    );
    drop(metis);
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
                let r = time_backend(&mut be, &k, &f, reps, |b| {
                    b.substructure_stats().last_critical_path_seconds
                });
                let ss = be.substructure_stats().clone();
                let nf = (reps + 2) as f64;
                println!(
                    "| faer-substructured | {kp} | {nt} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | {:.3} | {:.3} | {:.2} | {} | {:.3} | {:.3} | {:.3} | {:.1} | {:.0} | {:.1} | {:.1} | {:.2} | {:.1e} |",
                    ss.interface_size,
                    r.analysis,
                    r.first,
                    r.refactor,
                    r.best,
                    r.refactor_cpu,
                    r.probe,
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
                    be.stats().factor_flops / 1e9,
                    ss.critical_path_flops / 1e9,
                    base_flops
                        / (be.stats().factor_flops / nt as f64).max(ss.critical_path_flops),
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
                let mut cpu = Vec::new();
                let mut path = Vec::new();
                for r in 0..2 * reps {
                    let a = if r % 2 == 0 { &k2 } else { &k };
                    let (_, wall, c) = timed(|| be.factorize(a).expect("refactorization"));
                    times.push(wall);
                    cpu.push(c);
                    path.push(be.substructure_stats().last_critical_path_seconds);
                }
                let refactored = be.substructure_stats().subdomain_factorizations - before;
                let fronts = be.substructure_stats().last_fronts;
                let work = be.substructure_stats().last_flops;
                be.factorize(&k2).expect("factorization");
                let mut x = f.clone();
                be.solve(&mut x).expect("solve");
                let mut xf = f.clone();
                faer.factorize(&k2).expect("faer");
                faer.solve(&mut xf).expect("faer");
                let t_one = median(&mut times);
                let c_one = median(&mut cpu);
                let p_one = median(&mut path);
                reuse_rows.push(format!(
                    "| {kp} | {nt} | {} | {:.2} | {fronts} | {} | {:.3} | {:.3} | {:.0} % | {:.3} | {:.0} % | {:.0} % | {:.0} % | {:.3} | {:.0} % | {:.0} % | {:.1} | {:.0} % | {:.0} % | {:.1e} |",
                    inside.len().div_ceil(20),
                    refactored as f64 / (2 * reps) as f64,
                    ss.interface_size,
                    t_one,
                    r.refactor,
                    100.0 * t_one / r.refactor,
                    base.refactor,
                    100.0 * t_one / base.refactor,
                    100.0 * c_one / r.refactor_cpu,
                    100.0 * c_one / base.refactor_cpu,
                    p_one,
                    100.0 * p_one / r.probe,
                    100.0 * p_one / base.refactor_cpu,
                    work / 1e9,
                    100.0 * work / be.stats().factor_flops,
                    100.0 * work / base_flops,
                    max_relative_difference(&x, &xf)
                ));
            });
        }
    }
    println!(
        "\nOne subdomain changed (a secant iteration in which contacts of subdomain 0 open):\n"
    );
    println!("| subdomains | threads | contacts changed | subdomains refactorized per factorization | fronts recomputed | interface unknowns | factorization, median (s) | full refactorization, same backend (s) | ratio | faer-cholesky refactorization (s) | ratio | CPU-time ratio to the full refactorization | CPU-time ratio to faer-cholesky | critical path, thread CPU (s) | its ratio to the full refactorization's | its ratio to faer-cholesky's CPU time | work recomputed (G multiply-adds) | work ratio to the full refactorization | work ratio to faer-cholesky | rel. difference to faer-cholesky |");
    println!(
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for r in reuse_rows {
        println!("{r}");
    }
    println!("\n# load average after: {}", load());
}
