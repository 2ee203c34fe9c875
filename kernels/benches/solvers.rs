//! Benchmark P1 of docs/validation.md: the sparse direct and iterative solvers of
//! dfem-kernels on a 2D plane-strain CST elasticity matrix (n × n grid of unit-square
//! cells split into two triangles, E = 1e4, ν = 0.2, thickness 1, bottom edge fixed,
//! gravity plus a lateral load on the top edge; n = 353 gives 249,924 unknowns and
//! 3.49 M stored entries) — the same matrix as `peers/gen_matrix.py`.
//!
//! ```text
//! cargo bench -p dfem-kernels --bench solvers -- [--n 353] [--reps 3] [--patch 4]
//!     [--write-mtx DIR] [--no-time] [--json FILE] [--skip-pcg] [--two-level-only]
//!     [--tune ROUNDS] [--fill]
//! ```
//! Prints a markdown table; times are the median over `--reps` runs, each run with a new
//! backend (new symbolic analysis); PCG Jacobi and block-Jacobi (slow) run once. `--write-mtx DIR` writes `elast2d_<n>.mtx` and
//! `elast2d_<n>_rhs.mtx` with dfem's Matrix Market writer; `--json FILE` appends one JSON
//! line per measurement (the format of `benches/peers/bench_peers.py`).

use dfem_kernels::mm::{write_matrix_market, write_vector_market};
use dfem_kernels::pcg::dot;
use dfem_kernels::*;
use std::io::Write;
use std::time::Instant;

/// The P1 system: matrix, right-hand side, and for the preconditioners the node
/// coordinates and unknowns (`CONSTRAINED` on the fixed bottom edge).
struct P1 {
    a: CsrMatrix,
    b: Vec<f64>,
    n_cells: usize,
    xy: Vec<[f64; 2]>,
    dofs: Vec<[u32; 2]>,
}

fn p1(n: usize) -> P1 {
    let (young, nu, t) = (1.0e4, 0.2, 1.0);
    let h = 1.0 / n as f64;
    let nn = n + 1;
    let nid = |i: usize, j: usize| j * nn + i;
    let xy: Vec<[f64; 2]> = (0..nn * nn)
        .map(|k| [(k % nn) as f64 * h, (k / nn) as f64 * h])
        .collect();
    // unknowns in the order of gen_matrix.py: nodes row by row, the bottom row removed
    let dofs: Vec<[u32; 2]> = (0..nn * nn)
        .map(|k| {
            if k < nn {
                [CONSTRAINED; 2]
            } else {
                let f = 2 * (k - nn) as u32;
                [f, f + 1]
            }
        })
        .collect();
    let n_dofs = 2 * nn * (nn - 1);
    let mut tri = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            tri.push([nid(i, j), nid(i + 1, j), nid(i + 1, j + 1)]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            tri.push([nid(i, j), nid(i + 1, j + 1), nid(i, j + 1)]);
        }
    }
    let mut conn = Connectivity::new();
    for tr in &tri {
        let d: Vec<u32> = tr.iter().flat_map(|&v| [dofs[v][0], dofs[v][1]]).collect();
        conn.push(&d);
    }
    let plan = AssemblyPlan::new(n_dofs, &conn);
    let f = young / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let dm = [
        [f * (1.0 - nu), f * nu, 0.0],
        [f * nu, f * (1.0 - nu), 0.0],
        [0.0, 0.0, f * (1.0 - 2.0 * nu) / 2.0],
    ];
    let geom = |e: usize| {
        let [p1, p2, p3] = tri[e].map(|v| xy[v]);
        let a2 = (p2[0] - p1[0]) * (p3[1] - p1[1]) - (p3[0] - p1[0]) * (p2[1] - p1[1]);
        let bb = [p2[1] - p3[1], p3[1] - p1[1], p1[1] - p2[1]].map(|v| v / a2);
        let cc = [p3[0] - p2[0], p1[0] - p3[0], p2[0] - p1[0]].map(|v| v / a2);
        (a2, bb, cc)
    };
    let mut a = CsrMatrix::zeros(plan.pattern().clone());
    plan.assemble(
        |e, out| {
            let (a2, bb, cc) = geom(e);
            let mut bm = [[0.0; 6]; 3];
            for k in 0..3 {
                bm[0][2 * k] = bb[k];
                bm[1][2 * k + 1] = cc[k];
                bm[2][2 * k] = cc[k];
                bm[2][2 * k + 1] = bb[k];
            }
            for i in 0..6 {
                for j in 0..6 {
                    let mut v = 0.0;
                    for p in 0..3 {
                        for q in 0..3 {
                            v += bm[p][i] * dm[p][q] * bm[q][j];
                        }
                    }
                    out[i * 6 + j] = v * 0.5 * a2 * t;
                }
            }
        },
        &mut a,
    );
    // gravity (ρg = 1 per unit area) lumped to the nodes, lateral 0.1·h on the top row
    let mut b = vec![0.0; n_dofs];
    plan.assemble_vector(
        |e, out| {
            let (a2, _, _) = geom(e);
            for k in 0..3 {
                out[2 * k] = 0.0;
                out[2 * k + 1] = -0.5 * a2 / 3.0;
            }
        },
        &mut b,
    );
    for i in 0..nn {
        b[dofs[nid(i, n)][0] as usize] += 0.1 * h;
    }
    P1 {
        a,
        b,
        n_cells: n,
        xy,
        dofs,
    }
}

/// Square patches of `p × p` nodes as the blocks of block-Jacobi and of the coarse space.
fn patches(m: &P1, p: usize) -> Vec<BlockNodes2d> {
    let nn = m.n_cells + 1;
    let np = nn.div_ceil(p);
    let mut blocks = vec![BlockNodes2d::default(); np * np];
    for k in 0..nn * nn {
        let (i, j) = (k % nn, k / nn);
        let blk = &mut blocks[(j / p) * np + i / p];
        blk.dofs.push(m.dofs[k]);
        blk.xy.push(m.xy[k]);
    }
    blocks.retain(|b| b.dofs.iter().flatten().any(|&d| d != CONSTRAINED));
    blocks
}

fn rel_residual(a: &CsrMatrix, x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; b.len()];
    a.mul_vec(x, &mut ax);
    ax.iter_mut().zip(b).for_each(|(p, q)| *p -= q);
    (dot(&ax, &ax) / dot(b, b)).sqrt()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let k = v.len();
    if k == 0 {
        f64::NAN
    } else if k % 2 == 1 {
        v[k / 2]
    } else {
        0.5 * (v[k / 2 - 1] + v[k / 2])
    }
}

/// One row of the output.
#[derive(Default)]
struct Row {
    method: String,
    symbolic: f64,
    ordering: f64,
    numeric: f64,
    refactor: f64,
    solve: f64,
    factor_solve: f64,
    factor_solve_best: f64,
    nnz_l: usize,
    iterations: usize,
    relres: f64,
}

fn direct(
    m: &P1,
    label: &str,
    make: &dyn Fn() -> Box<dyn LinearBackend>,
    reps: usize,
) -> Result<Row, SolveError> {
    let mut sym = Vec::new();
    let mut ord = Vec::new();
    let mut num = Vec::new();
    let mut re = Vec::new();
    let mut sol = Vec::new();
    let mut tot = Vec::new();
    let mut relres = 0.0;
    let mut nnz_l = 0;
    // the refactorization sees new values on the same pattern (a secant/Newton update)
    let mut a2 = m.a.clone();
    a2.values.iter_mut().for_each(|v| *v *= 1.001);
    for _ in 0..reps {
        let mut s = make();
        let t = Instant::now();
        s.analyze(&m.a.pattern)?;
        let ts = t.elapsed().as_secs_f64();
        let t = Instant::now();
        s.factorize(&m.a)?;
        let tn = t.elapsed().as_secs_f64();
        let mut x = m.b.clone();
        let t = Instant::now();
        s.solve(&mut x)?;
        let tv = t.elapsed().as_secs_f64();
        relres = rel_residual(&m.a, &x, &m.b);
        let t = Instant::now();
        s.factorize(&a2)?;
        let tr = t.elapsed().as_secs_f64();
        sym.push(ts);
        ord.push(s.stats().ordering_seconds);
        num.push(tn);
        re.push(tr);
        sol.push(tv);
        tot.push(ts + tn + tv);
        nnz_l = s.stats().factor_nnz;
    }
    Ok(Row {
        method: label.into(),
        symbolic: median(sym),
        ordering: median(ord),
        numeric: median(num),
        refactor: median(re),
        solve: median(sol),
        factor_solve_best: tot.iter().copied().fold(f64::INFINITY, f64::min),
        factor_solve: median(tot),
        nnz_l,
        iterations: 0,
        relres,
    })
}

fn iterative(m: &P1, label: &str, make: &dyn Fn() -> Pcg, reps: usize) -> Row {
    let mut setup = Vec::new();
    let mut sol = Vec::new();
    let mut tot = Vec::new();
    let mut its = 0;
    let mut relres = f64::NAN;
    let mut method = label.to_string();
    for _ in 0..reps {
        let mut s = make();
        let t = Instant::now();
        if let Err(e) = s.factorize(&m.a) {
            method = format!("{label} (set-up failed: {e})");
            break;
        }
        let tn = t.elapsed().as_secs_f64();
        let mut x = m.b.clone();
        let t = Instant::now();
        let r = s.solve(&mut x);
        let tv = t.elapsed().as_secs_f64();
        its = s.stats().last_iterations;
        relres = s.stats().last_true_residual;
        if let Err(e) = r {
            method = format!("{label} ({e})");
        }
        setup.push(tn);
        sol.push(tv);
        tot.push(tn + tv);
    }
    Row {
        method,
        numeric: median(setup),
        solve: median(sol),
        factor_solve_best: tot.iter().copied().fold(f64::INFINITY, f64::min),
        factor_solve: median(tot),
        iterations: its,
        relres,
        ..Default::default()
    }
}

fn json_line(r: &Row, n: usize, direct: bool) -> String {
    let num = |v: f64| {
        if v.is_finite() {
            format!("{v:e}")
        } else {
            "null".into()
        }
    };
    let mut s = format!(
        "{{\"tool\": \"dfem-kernels\", \"matrix\": \"elast2d_{n}\", \"method\": \"{}\", \"kind\": \"{}\", \"factor_solve_s\": {}, \"factor_solve_best_s\": {}, \"solve_s\": {}, \"relres\": {}",
        r.method.replace('"', "'"),
        if direct { "direct" } else { "iterative" },
        num(r.factor_solve),
        num(r.factor_solve_best),
        num(r.solve),
        num(r.relres)
    );
    if direct {
        s += &format!(
            ", \"analyze_s\": {}, \"factor_s\": {}, \"refactor_s\": {}, \"nnzL\": {}",
            num(r.symbolic),
            num(r.numeric),
            num(r.refactor),
            r.nnz_l
        );
    } else {
        s += &format!(
            ", \"setup_s\": {}, \"iters\": {}",
            num(r.numeric),
            r.iterations
        );
    }
    s + "}"
}

fn main() {
    let mut n = 353usize;
    let mut reps = 3usize;
    let mut patch = 4usize;
    let mut write_dir: Option<String> = None;
    let mut json: Option<String> = None;
    let mut time = true;
    let mut pcg = true;
    let mut tune = 0usize;
    let mut direct_on = true;
    let mut one_level = true;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut val = |what: &str| {
            args.next()
                .unwrap_or_else(|| panic!("{what} needs a value"))
        };
        match a.as_str() {
            "--n" => n = val("--n").parse().expect("--n: an integer"),
            "--reps" => reps = val("--reps").parse().expect("--reps: an integer"),
            "--patch" => patch = val("--patch").parse().expect("--patch: an integer"),
            "--write-mtx" => write_dir = Some(val("--write-mtx")),
            "--json" => json = Some(val("--json")),
            "--no-time" => time = false,
            "--skip-pcg" => pcg = false,
            "--two-level-only" => {
                direct_on = false;
                one_level = false;
            }
            "--tune" => tune = val("--tune").parse().expect("--tune: rounds"),
            "--bench" | "--fill" => {} // --bench: passed by `cargo bench`
            other => panic!("unknown argument {other}"),
        }
    }
    let t = Instant::now();
    let m = p1(n);
    let t_asm = t.elapsed().as_secs_f64();
    eprintln!(
        "# P1 n = {n}: {} unknowns, {} stored entries, built in {t_asm:.2} s",
        m.a.n(),
        m.a.pattern.nnz()
    );
    if let Some(dir) = &write_dir {
        let dir = std::path::Path::new(dir);
        std::fs::create_dir_all(dir).expect("create the output directory");
        write_matrix_market(&dir.join(format!("elast2d_{n}.mtx")), &m.a).expect("write matrix");
        write_vector_market(&dir.join(format!("elast2d_{n}_rhs.mtx")), &m.b).expect("write rhs");
        eprintln!("# wrote {}/elast2d_{n}.mtx and _rhs.mtx", dir.display());
    }
    if !time {
        return;
    }
    if std::env::args().any(|a| a == "--fill") {
        for ord in [FillOrdering::Metis, FillOrdering::Amd] {
            let mut s = FaerCholeskySplit::new().with_ordering(ord);
            let t = Instant::now();
            s.analyze(&m.a.pattern).unwrap();
            println!(
                "split {ord:?}: nnz {:.2} M, analysis {:.3} s, split {}",
                s.stats().factor_nnz as f64 / 1e6,
                t.elapsed().as_secs_f64(),
                s.is_split()
            );
        }
        return;
    }
    if tune > 0 {
        tune_faer(&m, tune);
        return;
    }
    let threads = rayon::current_num_threads();
    let mut rows_direct = Vec::new();
    type Make = Box<dyn Fn() -> Box<dyn LinearBackend>>;
    let variants: Vec<(&str, Make)> = vec![
        (
            "faer LLT, AMD, 1 thread",
            Box::new(|| Box::new(FaerCholesky::new())),
        ),
        (
            "faer LLT, METIS, 1 thread",
            Box::new(|| Box::new(FaerCholesky::new().with_ordering(FillOrdering::Metis))),
        ),
        (
            "faer LLT, AMD, 2 threads",
            Box::new(|| Box::new(FaerCholesky::new().with_threads(2))),
        ),
        (
            "faer LLT, METIS, 2 threads",
            Box::new(|| {
                Box::new(
                    FaerCholesky::new()
                        .with_ordering(FillOrdering::Metis)
                        .with_threads(2),
                )
            }),
        ),
        (
            "faer LLT split (METIS bisection, METIS halves), 2 threads",
            Box::new(|| Box::new(FaerCholeskySplit::new())),
        ),
        (
            "faer LLT split (METIS bisection, AMD halves), 2 threads",
            Box::new(|| Box::new(FaerCholeskySplit::new().with_ordering(FillOrdering::Amd))),
        ),
        (
            "faer LDLT, AMD, 1 thread",
            Box::new(|| Box::new(FaerLdlt::new())),
        ),
    ];
    for (label, make) in variants.iter().filter(|_| direct_on) {
        match direct(&m, label, make.as_ref(), reps) {
            Ok(r) => rows_direct.push(r),
            Err(e) => eprintln!("{label}: {e}"),
        }
    }
    let mut rows_iter = Vec::new();
    if pcg {
        let blocks = patches(&m, patch);
        let lists: Vec<Vec<usize>> = blocks.iter().map(|b| b.dof_list()).collect();
        let t = Instant::now();
        let z = CoarseSpace::rigid_body_modes_2d(m.a.n(), &blocks).expect("coarse space");
        let t_z = t.elapsed().as_secs_f64();
        eprintln!(
            "# {} patches of {patch}×{patch} nodes, coarse space {} columns (built in {t_z:.3} s)",
            blocks.len(),
            z.n_columns()
        );
        let tol = 1e-8;
        let max_it = 20_000;
        let base = move || Pcg::new().with_tolerance(tol).with_max_iterations(max_it);
        if one_level {
            rows_iter.push(iterative(&m, "PCG Jacobi, rtol 1e-8", &|| base(), 1));
            let l2 = lists.clone();
            rows_iter.push(iterative(
                &m,
                &format!("PCG block-Jacobi ({patch}×{patch}-node patches), rtol 1e-8"),
                &move || {
                    base().with_preconditioner(Preconditioner::BlockJacobi { blocks: l2.clone() })
                },
                1,
            ));
        }
        for (name, corr) in [
            ("additive", CoarseCorrection::Additive),
            ("balanced", CoarseCorrection::Balanced),
        ] {
            let (l3, z3) = (lists.clone(), z.clone());
            rows_iter.push(iterative(
                &m,
                &format!("PCG two-level {name} (rigid modes of the patches), rtol 1e-8"),
                &move || {
                    base()
                        .with_preconditioner(Preconditioner::TwoLevel {
                            blocks: l3.clone(),
                            correction: corr,
                        })
                        .with_coarse_space(z3.clone())
                },
                reps,
            ));
        }
    }
    println!(
        "\nP1: 2D plane-strain CST elasticity, n = {n}: {} unknowns, {} stored entries; rayon pool {threads} threads; median of {reps} runs\n",
        m.a.n(),
        m.a.pattern.nnz()
    );
    println!("| solver | symbolic (s) [ordering] | first numeric (s) | refactor (s) | refactor / first numeric | refactor / (symbolic + first numeric) | solve (s) | factor + solve (s) | best (s) | nnz(L) | ‖b − Ax‖/‖b‖ |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for r in &rows_direct {
        println!(
            "| {} | {:.3} [{:.3}] | {:.3} | {:.3} | {:.0} % | {:.0} % | {:.3} | **{:.3}** | {:.3} | {:.2} M | {:.1e} |",
            r.method,
            r.symbolic,
            r.ordering,
            r.numeric,
            r.refactor,
            100.0 * r.refactor / r.numeric,
            100.0 * r.refactor / (r.symbolic + r.numeric),
            r.solve,
            r.factor_solve,
            r.factor_solve_best,
            r.nnz_l as f64 / 1e6,
            r.relres
        );
    }
    if !rows_iter.is_empty() {
        println!("\n| iterative solver | set-up (s) | solve (s) | total (s) | iterations | true ‖b − Ax‖/‖b‖ |");
        println!("|---|---|---|---|---|---|");
        for r in &rows_iter {
            println!(
                "| {} | {:.3} | {:.3} | **{:.3}** | {} | {:.1e} |",
                r.method, r.numeric, r.solve, r.factor_solve, r.iterations, r.relres
            );
        }
    }
    if let Some(path) = json {
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .expect("open the JSON output");
        for r in &rows_direct {
            writeln!(f, "{}", json_line(r, n, true)).expect("write JSON");
        }
        for r in &rows_iter {
            writeln!(f, "{}", json_line(r, n, false)).expect("write JSON");
        }
    }
}

/// Interleaved rounds over faer settings; prints the minimum time of each phase.
fn tune_faer(m: &P1, rounds: usize) {
    const MAX: usize = usize::MAX;
    type MakeChol = Box<dyn Fn() -> FaerCholesky>;
    let variants: Vec<(&str, MakeChol)> = vec![
        ("default (THP)", Box::new(FaerCholesky::new)),
        (
            "no THP",
            Box::new(|| FaerCholesky::new().with_huge_pages(false)),
        ),
        (
            "relax 8/32/96",
            Box::new(|| {
                FaerCholesky::new().with_supernode_relaxation(Some(vec![
                    (8, 1.0),
                    (32, 0.8),
                    (96, 0.2),
                    (MAX, 0.08),
                ]))
            }),
        ),
        (
            "relax 16/64/256",
            Box::new(|| {
                FaerCholesky::new().with_supernode_relaxation(Some(vec![
                    (16, 1.0),
                    (64, 0.5),
                    (256, 0.2),
                    (MAX, 0.1),
                ]))
            }),
        ),
        (
            "relax less",
            Box::new(|| {
                FaerCholesky::new().with_supernode_relaxation(Some(vec![
                    (4, 1.0),
                    (16, 0.5),
                    (MAX, 0.02),
                ]))
            }),
        ),
        (
            "METIS",
            Box::new(|| FaerCholesky::new().with_ordering(FillOrdering::Metis)),
        ),
        (
            "METIS relax 8/32/96",
            Box::new(|| {
                FaerCholesky::new()
                    .with_ordering(FillOrdering::Metis)
                    .with_supernode_relaxation(Some(vec![
                        (8, 1.0),
                        (32, 0.8),
                        (96, 0.2),
                        (MAX, 0.08),
                    ]))
            }),
        ),
    ];
    let mut best = vec![[f64::INFINITY; 4]; variants.len()];
    let mut nnz = vec![0; variants.len()];
    let mut a2 = m.a.clone();
    a2.values.iter_mut().for_each(|v| *v *= 1.001);
    for _ in 0..rounds {
        for (k, (_, make)) in variants.iter().enumerate() {
            let mut s = make();
            let t = Instant::now();
            s.analyze(&m.a.pattern).unwrap();
            let ta = t.elapsed().as_secs_f64();
            let t = Instant::now();
            s.factorize(&m.a).unwrap();
            let tn = t.elapsed().as_secs_f64();
            let mut x = m.b.clone();
            let t = Instant::now();
            s.solve(&mut x).unwrap();
            let tv = t.elapsed().as_secs_f64();
            let t = Instant::now();
            s.factorize(&a2).unwrap();
            let tr = t.elapsed().as_secs_f64();
            for (b, v) in best[k].iter_mut().zip([ta, tn, tr, tv]) {
                *b = b.min(v);
            }
            nnz[k] = s.stats().factor_nnz;
        }
    }
    println!("| variant | analysis | first numeric | refactor | solve | nnz(L) stored |");
    println!("|---|---|---|---|---|---|");
    for (k, (name, _)) in variants.iter().enumerate() {
        let b = best[k];
        println!(
            "| {name} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} M |",
            b[0],
            b[1],
            b[2],
            b[3],
            nnz[k] as f64 / 1e6
        );
    }
}
