//! Tests of dfem-kernels on a 2D Laplacian and a small plane-strain CST elasticity problem.

use dfem_kernels::mm::{
    read_matrix_market, read_vector_market, write_matrix_market, write_vector_market,
};
use dfem_kernels::*;
use std::sync::Arc;

/// A triangulated rectangle: (nx+1)×(ny+1) nodes, 2 triangles per cell.
struct Mesh {
    xy: Vec<[f64; 2]>,
    tri: Vec<[usize; 3]>,
    nx: usize,
}

fn mesh(nx: usize, ny: usize, lx: f64, ly: f64) -> Mesh {
    let mut xy = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            // slightly distorted grid so that the matrices are not too regular
            let x =
                lx * i as f64 / nx as f64 + 0.01 * ((i * 7 + j * 3) % 5) as f64 * lx / nx as f64;
            let y = ly * j as f64 / ny as f64;
            xy.push([x, y]);
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut tri = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            tri.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tri.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Mesh { xy, tri, nx }
}

/// Node → first unknown, CONSTRAINED for the nodes of the left edge when `fix_left`.
fn number_nodes(m: &Mesh, dofs_per_node: usize, fix_left: bool) -> (Vec<u32>, usize) {
    let mut first = vec![CONSTRAINED; m.xy.len()];
    let mut n = 0;
    for (k, f) in first.iter_mut().enumerate() {
        if fix_left && k % (m.nx + 1) == 0 {
            continue;
        }
        *f = n as u32;
        n += dofs_per_node;
    }
    (first, n)
}

fn connectivity(m: &Mesh, first: &[u32], dofs_per_node: usize) -> Connectivity {
    let mut c = Connectivity::new();
    for t in &m.tri {
        let mut d = Vec::new();
        for &v in t {
            for k in 0..dofs_per_node {
                d.push(if first[v] == CONSTRAINED {
                    CONSTRAINED
                } else {
                    first[v] + k as u32
                });
            }
        }
        c.push(&d);
    }
    c
}

/// Linear triangle geometry: area and the b, c coefficients of the shape function gradients.
fn tri_geom(m: &Mesh, e: usize) -> (f64, [f64; 3], [f64; 3]) {
    let [p0, p1, p2] = m.tri[e].map(|v| m.xy[v]);
    let area = 0.5 * ((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (p1[1] - p0[1]));
    let b = [p1[1] - p2[1], p2[1] - p0[1], p0[1] - p1[1]];
    let c = [p2[0] - p1[0], p0[0] - p2[0], p1[0] - p0[0]];
    (area, b, c)
}

/// Laplacian (conductivity 1) element matrix of a linear triangle, plus a small mass term.
fn laplace_kernel(m: &Mesh, e: usize, out: &mut [f64], mass: f64) {
    let (a, b, c) = tri_geom(m, e);
    for i in 0..3 {
        for j in 0..3 {
            out[i * 3 + j] = (b[i] * b[j] + c[i] * c[j]) / (4.0 * a)
                + mass * a * if i == j { 1.0 / 6.0 } else { 1.0 / 12.0 };
        }
    }
}

/// Plane-strain CST stiffness K = t A Bᵀ D B (E in Pa, thickness t in m).
fn cst_kernel(m: &Mesh, e: usize, out: &mut [f64], young: f64, nu: f64, t: f64) {
    let (a, b, c) = tri_geom(m, e);
    let f = young / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let d = [
        [f * (1.0 - nu), f * nu, 0.0],
        [f * nu, f * (1.0 - nu), 0.0],
        [0.0, 0.0, f * (1.0 - 2.0 * nu) / 2.0],
    ];
    let s = 1.0 / (2.0 * a);
    let mut bm = [[0.0; 6]; 3];
    for k in 0..3 {
        bm[0][2 * k] = s * b[k];
        bm[1][2 * k + 1] = s * c[k];
        bm[2][2 * k] = s * c[k];
        bm[2][2 * k + 1] = s * b[k];
    }
    for i in 0..6 {
        for j in 0..6 {
            let mut v = 0.0;
            for p in 0..3 {
                for q in 0..3 {
                    v += bm[p][i] * d[p][q] * bm[q][j];
                }
            }
            out[i * 6 + j] = t * a * v;
        }
    }
}

/// Element load vector: a body force plus a position-dependent term (not a physical load,
/// just a non-trivial right-hand side).
fn load_kernel(m: &Mesh, e: usize, out: &mut [f64], dofs_per_node: usize) {
    let (a, _, _) = tri_geom(m, e);
    for (k, &v) in m.tri[e].iter().enumerate() {
        for d in 0..dofs_per_node {
            out[k * dofs_per_node + d] =
                a / 3.0 * (1.0 + m.xy[v][0] * (d as f64 + 1.0) - 0.5 * m.xy[v][1]);
        }
    }
}

struct Problem {
    plan: AssemblyPlan,
    a: CsrMatrix,
    b: Vec<f64>,
}

fn laplace_problem(nx: usize, ny: usize) -> Problem {
    let m = mesh(nx, ny, 2.0, 1.0);
    let (first, n) = number_nodes(&m, 1, true);
    let plan = AssemblyPlan::new(n, &connectivity(&m, &first, 1));
    let mut a = CsrMatrix::zeros(plan.pattern().clone());
    plan.assemble(|e, out| laplace_kernel(&m, e, out, 0.0), &mut a);
    let mut b = vec![0.0; n];
    plan.assemble_vector(|e, out| load_kernel(&m, e, out, 1), &mut b);
    Problem { plan, a, b }
}

fn cst_problem(nx: usize, ny: usize, fix_left: bool) -> (Mesh, Problem) {
    let m = mesh(nx, ny, 4.0, 1.0);
    let (first, n) = number_nodes(&m, 2, fix_left);
    let plan = AssemblyPlan::new(n, &connectivity(&m, &first, 2));
    let mut a = CsrMatrix::zeros(plan.pattern().clone());
    plan.assemble(|e, out| cst_kernel(&m, e, out, 30e9, 0.2, 0.5), &mut a);
    let mut b = vec![0.0; n];
    plan.assemble_vector(|e, out| load_kernel(&m, e, out, 2), &mut b);
    // scale the load so that displacements are O(1e-9 .. 1e-6) m as in practice
    for v in &mut b {
        *v *= 1e4;
    }
    (m, Problem { plan, a, b })
}

/// Gaussian elimination with partial pivoting on a dense row-major copy.
fn dense_solve(a: &CsrMatrix, b: &[f64]) -> Vec<f64> {
    let n = a.n();
    let mut m = a.to_dense();
    let mut x = b.to_vec();
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| m[i * n + k].abs().total_cmp(&m[j * n + k].abs()))
            .unwrap();
        if p != k {
            for j in 0..n {
                m.swap(k * n + j, p * n + j);
            }
            x.swap(k, p);
        }
        let piv = m[k * n + k];
        for i in k + 1..n {
            let f = m[i * n + k] / piv;
            if f != 0.0 {
                for j in k..n {
                    m[i * n + j] -= f * m[k * n + j];
                }
                x[i] -= f * x[k];
            }
        }
    }
    for k in (0..n).rev() {
        let mut s = x[k];
        for j in k + 1..n {
            s -= m[k * n + j] * x[j];
        }
        x[k] = s / m[k * n + k];
    }
    x
}

fn rel_err(x: &[f64], y: &[f64]) -> f64 {
    let num = x
        .iter()
        .zip(y)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let den = y.iter().map(|a| a.abs()).fold(0.0, f64::max);
    num / den
}

fn backend(name: &str) -> Box<dyn LinearBackend> {
    if name == "pcg" {
        // tight tolerance so that the solution error is comparable to the direct solvers
        Box::new(Pcg::new().with_tolerance(1e-15).with_max_iterations(20_000))
    } else {
        backend_from_name(name).unwrap()
    }
}

#[test]
fn every_backend_matches_a_dense_solve() {
    let (_, cst) = cst_problem(8, 3, true);
    let lap = laplace_problem(12, 9);
    for (what, p) in [("laplace", &lap), ("cst", &cst)] {
        let xd = dense_solve(&p.a, &p.b);
        for &name in BACKENDS {
            let mut s = backend(name);
            assert_eq!(s.name(), name);
            s.factorize(&p.a).unwrap();
            let mut x = p.b.clone();
            s.solve(&mut x).unwrap();
            let err = rel_err(&x, &xd);
            assert!(err < 1e-10, "{name} on {what}: relative error {err:e}");
            // the split backend does not compute the pivot ratio
            if (name.starts_with("faer-cholesky") || name.starts_with("faer-ldlt"))
                && name != "faer-cholesky-split"
            {
                let r = s.stats().min_pivot_ratio;
                assert!(
                    r > 1e-6 && r <= 1.0 + 1e-12,
                    "{name} on {what}: min pivot ratio {r}"
                );
            }
            if name == "pcg" {
                assert!(s.stats().iterations > 0);
            }
        }
    }
}

#[test]
fn constrained_slots_are_dropped() {
    let (m, p) = cst_problem(3, 2, true);
    // the left edge has 3 nodes: 2 * (4 * 3 - 3) unknowns
    assert_eq!(p.a.n(), 2 * (m.xy.len() - 3));
    // the matrix is symmetric and matches a sequential triplet assembly
    let (first, n) = number_nodes(&m, 2, true);
    let conn = connectivity(&m, &first, 2);
    let mut dense = vec![0.0; n * n];
    let mut ke = vec![0.0; 36];
    for e in 0..conn.len() {
        cst_kernel(&m, e, &mut ke, 30e9, 0.2, 0.5);
        let d = conn.dofs(e);
        for i in 0..6 {
            for j in 0..6 {
                if d[i] != CONSTRAINED && d[j] != CONSTRAINED {
                    dense[d[i] as usize * n + d[j] as usize] += ke[i * 6 + j];
                }
            }
        }
    }
    let ad = p.a.to_dense();
    for i in 0..n {
        for j in 0..n {
            assert!(
                (ad[i * n + j] - dense[i * n + j]).abs() <= 1e-6 * (1.0 + dense[i * n + j].abs())
            );
            assert_eq!(p.a.get(i, j), p.a.get(j, i));
        }
    }
    // mul_vec against the dense product
    let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
    let mut y = vec![0.0; n];
    p.a.mul_vec(&x, &mut y);
    for i in 0..n {
        let yd: f64 = (0..n).map(|j| dense[i * n + j] * x[j]).sum();
        let scale: f64 = (0..n).map(|j| (dense[i * n + j] * x[j]).abs()).sum();
        assert!((y[i] - yd).abs() <= 1e-12 * scale);
    }
    assert_eq!(p.a.diagonal().len(), n);
}

fn assemble_in_pool(threads: usize, m: &Mesh, plan: &AssemblyPlan) -> (Vec<u64>, Vec<u64>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut a = CsrMatrix::zeros(plan.pattern().clone());
        plan.assemble(|e, out| cst_kernel(m, e, out, 30e9, 0.2, 0.5), &mut a);
        let mut b = vec![0.0; plan.pattern().n()];
        plan.assemble_vector(|e, out| load_kernel(m, e, out, 2), &mut b);
        let mut y = vec![0.0; b.len()];
        a.mul_vec(&b, &mut y);
        let mut pcg = Pcg::new().with_tolerance(1e-8);
        pcg.factorize(&a).unwrap();
        let mut x = b.clone();
        pcg.solve(&mut x).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        let mut vb = bits(&b);
        vb.extend(bits(&y));
        vb.extend(bits(&x));
        (bits(&a.values), vb)
    })
}

#[test]
fn assembly_is_bit_identical_for_1_and_2_threads() {
    // 40 × 30 cells: 2 * 41 * 31 dofs, several row chunks and element chunks
    let (m, p) = cst_problem(40, 30, true);
    assert!(p.a.n() > 2048 && p.plan.n_elements() > 256);
    let one = assemble_in_pool(1, &m, &p.plan);
    let two = assemble_in_pool(2, &m, &p.plan);
    assert!(one == two, "results differ between 1 and 2 threads");
    // and the same as in the global pool
    let again = assemble_in_pool(3, &m, &p.plan);
    assert!(one == again);
}

#[test]
fn symbolic_phase_is_reused_across_refactorizations() {
    let (_, p) = cst_problem(6, 3, true);
    for name in ["faer-cholesky", "faer-ldlt", "faer-lu"] {
        let mut s = backend_from_name(name).unwrap();
        s.analyze(&p.a.pattern).unwrap();
        s.analyze(&p.a.pattern).unwrap();
        for k in 0..3 {
            let mut a = p.a.clone();
            let scale = 1.0 + k as f64;
            for (idx, v) in a.values.iter_mut().enumerate() {
                *v *= scale * (1.0 + 1e-3 * (idx % 7) as f64 * 0.0);
            }
            // change the values non-uniformly too: add to the diagonal
            for i in 0..a.n() {
                let d = a.pattern.find(i, i).unwrap();
                a.values[d] *= 1.0 + 0.1 * k as f64;
            }
            s.factorize(&a).unwrap();
            let mut x = p.b.clone();
            s.solve(&mut x).unwrap();
            let xd = dense_solve(&a, &p.b);
            assert!(rel_err(&x, &xd) < 1e-10, "{name} refactorization {k}");
        }
        let st = s.stats();
        assert_eq!(st.symbolic_factorizations, 1, "{name}");
        assert_eq!(st.numeric_factorizations, 3, "{name}");
        assert_eq!(st.solves, 3, "{name}");
        if name != "faer-lu" {
            assert!(st.factor_nnz >= p.a.pattern.nnz() / 2, "{name}");
        }
        // a new pattern (even if identical in structure) triggers a new analysis
        let (_, q) = cst_problem(6, 3, true);
        s.factorize(&q.a).unwrap();
        assert_eq!(s.stats().symbolic_factorizations, 2, "{name}");
    }
}

#[test]
fn singular_pure_neumann_problem_is_detected() {
    let (_, p) = cst_problem(6, 3, false);
    for name in ["faer-cholesky", "faer-ldlt"] {
        let mut s = backend_from_name(name).unwrap();
        match s.factorize(&p.a) {
            Err(e) => eprintln!("{name}: {e}"),
            Ok(()) => {
                let r = s.stats().min_pivot_ratio;
                eprintln!(
                    "{name}: min pivot ratio {r:e} at {}",
                    s.stats().min_pivot_index
                );
                assert!(r < 1e-10, "{name}: min pivot ratio {r:e}");
            }
        }
    }
}

#[test]
fn indefinite_matrix_reports_the_pivot() {
    let pattern = Arc::new(CsrPattern::from_entries(4, [(0, 1), (2, 3)]));
    let mut a = CsrMatrix::zeros(pattern);
    for (i, d) in [4.0, 3.0, -2.0, 5.0].into_iter().enumerate() {
        a.add(i, i, d);
    }
    a.add(0, 1, 1.0);
    a.add(1, 0, 1.0);
    let mut s = FaerCholesky::new();
    let e = s.factorize(&a).unwrap_err();
    assert_eq!(
        e,
        SolveError::NotPositiveDefinite {
            index: 2,
            pivot: -2.0
        }
    );
    assert!(s.solve(&mut [0.0; 4]).is_err());
    // LDLᵀ accepts it and reports a negative ratio at unknown 2
    let mut l = FaerLdlt::new();
    l.factorize(&a).unwrap();
    assert_eq!(l.stats().min_pivot_index, 2);
    assert!((l.stats().min_pivot_ratio + 1.0).abs() < 1e-15);
    let mut x = vec![5.0, 4.0, -2.0, 5.0];
    l.solve(&mut x).unwrap();
    assert!(rel_err(&x, &[1.0, 1.0, 1.0, 1.0]) < 1e-15);
    // PCG rejects a non-positive diagonal
    let mut pcg = Pcg::new();
    assert!(matches!(
        pcg.factorize(&a),
        Err(SolveError::NotPositiveDefinite { index: 2, .. })
    ));
}

#[test]
fn registry_lists_names() {
    for &n in BACKENDS {
        assert_eq!(backend_from_name(n).unwrap().name(), n);
    }
    let e = backend_from_name("mumps").err().unwrap();
    assert!(BACKENDS.iter().all(|n| e.contains(n)), "{e}");
}

#[test]
fn matrix_market_round_trip() {
    let (_, p) = cst_problem(4, 2, true);
    let dir = std::env::temp_dir().join(format!("dfem-kernels-mm-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fa = dir.join("a.mtx");
    let fb = dir.join("b.mtx");
    write_matrix_market(&fa, &p.a).unwrap();
    write_vector_market(&fb, &p.b).unwrap();
    let text = std::fs::read_to_string(&fa).unwrap();
    assert!(text.starts_with("%%MatrixMarket matrix coordinate real symmetric\n"));
    let a = read_matrix_market(&fa).unwrap();
    let b = read_vector_market(&fb).unwrap();
    assert_eq!(a.pattern.row_ptr(), p.a.pattern.row_ptr());
    assert_eq!(a.pattern.col_idx(), p.a.pattern.col_idx());
    assert!(a
        .values
        .iter()
        .zip(&p.a.values)
        .all(|(x, y)| x.to_bits() == y.to_bits()));
    assert!(b.iter().zip(&p.b).all(|(x, y)| x.to_bits() == y.to_bits()));
    // a general file: the pattern is symmetrised and the diagonal added
    let fg = dir.join("g.mtx");
    std::fs::write(
        &fg,
        "%%MatrixMarket matrix coordinate real general\n% c\n3 3 3\n1 1 2.0\n3 1 -1.5\n2 3 4\n",
    )
    .unwrap();
    let g = read_matrix_market(&fg).unwrap();
    assert_eq!(g.pattern.nnz(), 3 + 4);
    assert_eq!(g.get(2, 0), -1.5);
    assert_eq!(g.get(0, 2), 0.0);
    assert_eq!(g.get(1, 2), 4.0);
    assert!(g.pattern.find(1, 1).is_some());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn pattern_validation() {
    assert!(CsrPattern::from_parts(2, vec![0, 2, 4], vec![0, 1, 0, 1]).is_ok());
    assert!(CsrPattern::from_parts(2, vec![0, 1, 3], vec![0, 0, 1]).is_err()); // not symmetric
    assert!(CsrPattern::from_parts(2, vec![0, 1, 2], vec![1, 0]).is_err()); // no diagonal
    let p = CsrPattern::from_parts(2, vec![0, 2, 4], vec![0, 1, 0, 1]).unwrap();
    let q = CsrPattern::from_parts(2, vec![0, 2, 4], vec![0, 1, 0, 1]).unwrap();
    assert_ne!(p.id(), q.id());
    assert_eq!(p.find(1, 0), Some(2));
    assert_eq!(p.find(1, 5), None);
}

#[test]
fn unsymmetric_values_with_lu() {
    // LU solves A x = b also for unsymmetric values on a symmetric pattern
    let pattern = Arc::new(CsrPattern::from_entries(3, [(0, 1), (1, 2)]));
    let mut a = CsrMatrix::zeros(pattern);
    for (i, j, v) in [
        (0, 0, 2.0),
        (0, 1, 1.0),
        (1, 0, -3.0),
        (1, 1, 4.0),
        (1, 2, 0.5),
        (2, 1, 2.0),
        (2, 2, 5.0),
    ] {
        a.add(i, j, v);
    }
    let b = [1.0, 2.0, 3.0];
    let xd = dense_solve(&a, &b);
    let mut s = FaerLu::new();
    s.factorize(&a).unwrap();
    let mut x = b.to_vec();
    s.solve(&mut x).unwrap();
    assert!(rel_err(&x, &xd) < 1e-14, "{x:?} {xd:?}");
}

/// The Cholesky backends take faer's supernodal factorization where the symbolic factor
/// has more than `SUPERNODAL_FLOP_RATIO` (12) flops per entry (faer's measure: 1 + ours),
/// below faer's own switch at 40 (kernels/src/cholesky.rs;
/// docs/decisions/0015-supernodal-flop-ratio.md); LLᵀ and LDLᵀ alike, and both give the dense
/// solution.
#[test]
fn the_default_factorization_is_supernodal_from_a_flop_ratio_of_12() {
    let threshold = dfem_kernels::faer_backend::SUPERNODAL_FLOP_RATIO;
    let (mut below, mut between) = (false, false);
    for (nx, ny) in [(3, 2), (6, 3), (12, 6), (24, 12)] {
        let (_, p) = cst_problem(nx, ny, true);
        let mut s = FaerCholesky::new();
        assert_eq!(s.supernodal(), None);
        s.factorize(&p.a).unwrap();
        let st = s.stats();
        let ratio = 1.0 + st.factor_flops / st.factor_nnz as f64;
        assert_eq!(
            s.supernodal(),
            Some(ratio > threshold),
            "{nx} x {ny}: ratio {ratio}"
        );
        below |= ratio < threshold;
        between |= ratio > threshold && ratio < 40.0;
        let mut l = FaerLdlt::new();
        l.factorize(&p.a).unwrap();
        assert_eq!(l.supernodal(), s.supernodal(), "{nx} x {ny}");
        let xd = dense_solve(&p.a, &p.b);
        let mut x = p.b.clone();
        s.solve(&mut x).unwrap();
        assert!(
            rel_err(&x, &xd) < 1e-10,
            "{nx} x {ny}: {:e}",
            rel_err(&x, &xd)
        );
        eprintln!(
            "{nx} x {ny}: n {} ratio {ratio:.1} supernodal {:?}",
            p.a.pattern.n(),
            s.supernodal()
        );
    }
    // the cases cover both sides of the switch, and the range where faer's default differs
    assert!(
        below && between,
        "below {below}, between 12 and 40 {between}"
    );
}

#[test]
fn non_positive_pivot_index_simplicial_and_supernodal() {
    let (_, p) = cst_problem(20, 10, true);
    let bad = 137;
    let mut a = p.a.clone();
    let d = a.pattern.find(bad, bad).unwrap();
    a.values[d] = -a.values[d];
    for threshold in [f64::INFINITY, 0.0, 1.0] {
        let mut s = FaerCholesky::new().with_supernodal_threshold(threshold);
        match s.factorize(&a) {
            Err(SolveError::NotPositiveDefinite { index, pivot }) => {
                // the failing pivot is at the modified unknown or eliminated after it
                assert!(pivot <= 0.0, "threshold {threshold}: pivot {pivot}");
                assert_eq!(index, bad, "threshold {threshold}");
                eprintln!("threshold {threshold}: index {index} pivot {pivot:e}");
            }
            other => panic!("threshold {threshold}: {other:?}"),
        }
        // without the failed pivot's value (the drivers' setting): the same unknown, NaN,
        // one numeric factorization, and the same factorization of the matrix afterwards
        for backend in [
            Box::new(FaerCholesky::new().with_supernodal_threshold(threshold))
                as Box<dyn LinearBackend>,
            Box::new(FaerCholeskyCondensed::new()),
        ] {
            let mut s = backend;
            s.set_failed_pivot_value(false);
            match s.factorize(&a) {
                Err(SolveError::NotPositiveDefinite { index, pivot }) => {
                    assert!(pivot.is_nan(), "threshold {threshold}: pivot {pivot}");
                    assert_eq!(index, bad, "threshold {threshold}");
                }
                other => panic!("threshold {threshold}: {other:?}"),
            }
            s.factorize(&p.a).unwrap();
            let mut x = p.b.clone();
            s.solve(&mut x).unwrap();
            assert!(rel_err(&x, &dense_solve(&p.a, &p.b)) < 1e-10);
        }
        let mut l = FaerLdlt::new().with_supernodal_threshold(threshold);
        l.factorize(&a).unwrap();
        assert!(l.stats().min_pivot_ratio < 0.0);
        let mut x = p.b.clone();
        l.solve(&mut x).unwrap();
        let xd = dense_solve(&a, &p.b);
        assert!(
            rel_err(&x, &xd) < 1e-8,
            "threshold {threshold}: {:e}",
            rel_err(&x, &xd)
        );
    }
    // the small diagonal example in both modes
    let pattern = Arc::new(CsrPattern::from_entries(4, [(0, 1), (2, 3)]));
    let mut a = CsrMatrix::zeros(pattern);
    for (i, d) in [4.0, 3.0, -2.0, 5.0].into_iter().enumerate() {
        a.add(i, i, d);
    }
    for threshold in [f64::INFINITY, 0.0] {
        let mut s = FaerCholesky::new().with_supernodal_threshold(threshold);
        assert_eq!(
            s.factorize(&a).unwrap_err(),
            SolveError::NotPositiveDefinite {
                index: 2,
                pivot: -2.0
            }
        );
        let mut z = a.clone();
        let d = z.pattern.find(2, 2).unwrap();
        z.values[d] = 0.0;
        let mut l = FaerLdlt::new().with_supernodal_threshold(threshold);
        assert_eq!(
            l.factorize(&z).unwrap_err(),
            SolveError::Singular { index: 2 }
        );
    }
}

#[test]
fn unsymmetric_assembly_keeps_each_entry_as_summed() {
    // two 2-dof elements sharing dof 1, each with an unsymmetric 2x2 matrix
    let mut conn = Connectivity::new();
    conn.push(&[0, 1]);
    conn.push(&[1, 2]);
    let plan = AssemblyPlan::new(3, &conn);
    let mats = [[1.0, 2.0, 3.0, 4.0], [5.0, 6.0, 7.0, 8.0]];
    let mut k = CsrMatrix::zeros(plan.pattern().clone());
    plan.assemble_unsymmetric(|e, ke| ke.copy_from_slice(&mats[e]), &mut k);
    let expect = [[1.0, 2.0, 0.0], [3.0, 4.0 + 5.0, 6.0], [0.0, 7.0, 8.0]];
    for (i, row) in expect.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            assert_eq!(k.get(i, j), *v, "entry ({i}, {j})");
        }
    }
    // the symmetric assembly averages the two triangles
    plan.assemble(|e, ke| ke.copy_from_slice(&mats[e]), &mut k);
    assert_eq!(k.get(0, 1), 2.5);
    assert_eq!(k.get(1, 0), 2.5);
}

#[test]
fn metis_ordering_matches_amd() {
    // 60 × 20 cells: large enough for nested dissection to differ from AMD
    let (_, p) = cst_problem(60, 20, true);
    for (amd_name, metis_name) in [
        ("faer-cholesky", "faer-cholesky-metis"),
        ("faer-ldlt", "faer-ldlt-metis"),
    ] {
        let mut amd = backend_from_name(amd_name).unwrap();
        let mut metis = backend_from_name(metis_name).unwrap();
        assert_eq!(metis.name(), metis_name);
        amd.factorize(&p.a).unwrap();
        metis.factorize(&p.a).unwrap();
        let mut xa = p.b.clone();
        amd.solve(&mut xa).unwrap();
        let mut xm = p.b.clone();
        metis.solve(&mut xm).unwrap();
        let err = rel_err(&xm, &xa);
        assert!(err < 1e-10, "{metis_name}: {err:e}");
        let (na, nm) = (amd.stats().factor_nnz, metis.stats().factor_nnz);
        eprintln!("{metis_name}: nnz(L) AMD {na}, METIS {nm}");
        // a swapped perm/iperm would give several times the fill of AMD
        assert!(
            nm < na * 3 / 2,
            "{metis_name}: nnz(L) {nm} against AMD {na}"
        );
        assert!(metis.stats().ordering_seconds > 0.0);
        assert_eq!(amd.stats().ordering_seconds, 0.0);
    }
    // the builder gives the same backend as the registry name
    let s = FaerCholesky::new().with_ordering(FillOrdering::Metis);
    assert_eq!(s.name(), "faer-cholesky-metis");
    assert_eq!(s.ordering(), FillOrdering::Metis);
    // and the ordering is a permutation that keeps the two unknowns of a node together
    let (fwd, inv) = dfem_kernels::ordering::metis_nested_dissection(&p.a.pattern).unwrap();
    assert_eq!(fwd.len(), p.a.n());
    for (new, &old) in fwd.iter().enumerate() {
        assert_eq!(inv[old as usize] as usize, new);
    }
    for pair in fwd.chunks(2) {
        assert_eq!(pair[0] % 2, 0);
        assert_eq!(pair[1], pair[0] + 1);
    }
}

#[test]
fn identical_values_skip_the_numeric_factorization() {
    let (_, p) = cst_problem(8, 4, true);
    for &name in BACKENDS {
        let mut s = backend(name);
        s.factorize(&p.a).unwrap();
        let mut x1 = p.b.clone();
        s.solve(&mut x1).unwrap();
        // the same values in a fresh copy: skipped
        let a2 = p.a.clone();
        s.factorize(&a2).unwrap();
        assert_eq!(s.stats().numeric_factorizations, 1, "{name}");
        assert_eq!(s.stats().skipped_factorizations, 1, "{name}");
        let mut x2 = p.b.clone();
        s.solve(&mut x2).unwrap();
        assert!(
            x1.iter().zip(&x2).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{name}"
        );
        // one entry changed by one ulp: factorized again, and the new matrix is used
        let mut a3 = p.a.clone();
        let d = a3.pattern.find(5, 5).unwrap();
        a3.values[d] = f64::from_bits(a3.values[d].to_bits() + 1);
        s.factorize(&a3).unwrap();
        assert_eq!(s.stats().numeric_factorizations, 2, "{name}");
        assert_eq!(s.stats().skipped_factorizations, 1, "{name}");
        let mut a4 = p.a.clone();
        a4.values[d] *= 2.0;
        s.factorize(&a4).unwrap();
        let mut x4 = p.b.clone();
        s.solve(&mut x4).unwrap();
        assert!(rel_err(&x4, &dense_solve(&a4, &p.b)) < 1e-10, "{name}");
        assert_eq!(s.stats().numeric_factorizations, 3, "{name}");
        // the same values on a new pattern object: a new analysis, not a skip
        let q = CsrMatrix {
            pattern: Arc::new(
                CsrPattern::from_parts(
                    a4.n(),
                    a4.pattern.row_ptr().to_vec(),
                    a4.pattern.col_idx().to_vec(),
                )
                .unwrap(),
            ),
            values: a4.values.clone(),
        };
        s.factorize(&q).unwrap();
        assert_eq!(s.stats().numeric_factorizations, 4, "{name}");
        assert_eq!(s.stats().skipped_factorizations, 1, "{name}");
    }
    // a failed factorization is never skipped: the same values fail again
    let pattern = Arc::new(CsrPattern::from_entries(2, [(0, 1)]));
    let mut a = CsrMatrix::zeros(pattern);
    a.add(0, 0, 1.0);
    a.add(1, 1, -1.0);
    let mut s = FaerCholesky::new();
    assert!(s.factorize(&a).is_err());
    assert!(s.factorize(&a).is_err());
    assert_eq!(s.stats().skipped_factorizations, 0);
}

/// A wall of bx × by rectangular blocks (each kx × ky CST cells, its own nodes) whose
/// coincident interface nodes are tied by springs of stiffness `k_spring` (N/m) in x and
/// y; the bottom edge of the bottom row is fixed. Returns the matrix, the load, the
/// faer-cholesky solution, and the block nodes for the coarse space.
struct BlockWall {
    a: CsrMatrix,
    b: Vec<f64>,
    blocks: Vec<BlockNodes2d>,
}

fn block_wall(bx: usize, by: usize, kx: usize, ky: usize, ratio: f64) -> BlockWall {
    let (lx, ly) = (1.0, 0.5);
    let young = 1e4;
    let (nu, t) = (0.2, 1.0);
    let k_spring = ratio * young * t;
    let mut xy = Vec::new();
    let mut node_block = Vec::new();
    let mut tris: Vec<[usize; 3]> = Vec::new();
    // node index of (block, i, j)
    let npb = (kx + 1) * (ky + 1);
    for bj in 0..by {
        for bi in 0..bx {
            let b = bj * bx + bi;
            for j in 0..=ky {
                for i in 0..=kx {
                    xy.push([
                        bi as f64 * lx + lx * i as f64 / kx as f64,
                        bj as f64 * ly + ly * j as f64 / ky as f64,
                    ]);
                    node_block.push(b);
                }
            }
            let id = |i: usize, j: usize| b * npb + j * (kx + 1) + i;
            for j in 0..ky {
                for i in 0..kx {
                    tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                    tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                }
            }
        }
    }
    // springs between coincident nodes of different blocks
    let mut springs = Vec::new();
    for p in 0..xy.len() {
        for q in p + 1..xy.len() {
            if node_block[p] != node_block[q]
                && (xy[p][0] - xy[q][0]).abs() < 1e-9
                && (xy[p][1] - xy[q][1]).abs() < 1e-9
            {
                springs.push([p, q]);
            }
        }
    }
    let mut first = vec![CONSTRAINED; xy.len()];
    let mut n = 0u32;
    for (k, f) in first.iter_mut().enumerate() {
        if xy[k][1] == 0.0 {
            continue;
        }
        *f = n;
        n += 2;
    }
    let dof = |v: usize, c: u32| {
        if first[v] == CONSTRAINED {
            CONSTRAINED
        } else {
            first[v] + c
        }
    };
    let mut conn = Connectivity::new();
    for tr in &tris {
        let d: Vec<u32> = tr.iter().flat_map(|&v| [dof(v, 0), dof(v, 1)]).collect();
        conn.push(&d);
    }
    for s in &springs {
        conn.push(&[dof(s[0], 0), dof(s[0], 1), dof(s[1], 0), dof(s[1], 1)]);
    }
    let n = n as usize;
    let plan = AssemblyPlan::new(n, &conn);
    let m = Mesh {
        xy: xy.clone(),
        tri: tris.clone(),
        nx: 0,
    };
    let nt = tris.len();
    let mut a = CsrMatrix::zeros(plan.pattern().clone());
    plan.assemble(
        |e, out| {
            if e < nt {
                cst_kernel(&m, e, out, young, nu, t);
            } else {
                out.fill(0.0);
                for c in 0..2 {
                    out[c * 4 + c] = k_spring;
                    out[(c + 2) * 4 + c + 2] = k_spring;
                    out[c * 4 + c + 2] = -k_spring;
                    out[(c + 2) * 4 + c] = -k_spring;
                }
            }
        },
        &mut a,
    );
    // gravity on every node plus a lateral load that grows with height
    let mut b = vec![0.0; n];
    for (v, p) in xy.iter().enumerate() {
        if first[v] != CONSTRAINED {
            b[first[v] as usize] += 0.1 * p[1];
            b[first[v] as usize + 1] -= 1.0;
        }
    }
    let blocks = (0..bx * by)
        .map(|bl| {
            let nodes = bl * npb..(bl + 1) * npb;
            BlockNodes2d {
                dofs: nodes.clone().map(|v| [dof(v, 0), dof(v, 1)]).collect(),
                xy: nodes.map(|v| xy[v]).collect(),
            }
        })
        .collect();
    BlockWall { a, b, blocks }
}

fn pcg_with(w: &BlockWall, which: &str, tol: f64, max_it: usize) -> Pcg {
    let blocks: Vec<Vec<usize>> = w.blocks.iter().map(|b| b.dof_list()).collect();
    let pcg = Pcg::new().with_tolerance(tol).with_max_iterations(max_it);
    match which {
        "jacobi" => pcg,
        "block-jacobi" => pcg.with_preconditioner(Preconditioner::BlockJacobi { blocks }),
        "two-level" | "two-level-additive" => pcg
            .with_preconditioner(Preconditioner::TwoLevel {
                blocks,
                correction: if which == "two-level" {
                    CoarseCorrection::Balanced
                } else {
                    CoarseCorrection::Additive
                },
            })
            .with_coarse_space(CoarseSpace::rigid_body_modes_2d(w.a.n(), &w.blocks).unwrap()),
        _ => unreachable!(),
    }
}

#[test]
fn two_level_pcg_beats_jacobi_on_weakly_coupled_blocks() {
    for ratio in [1e-3, 1e-6] {
        let w = block_wall(6, 5, 6, 3, ratio);
        let mut chol = FaerCholesky::new();
        chol.factorize(&w.a).unwrap();
        let mut xr = w.b.clone();
        chol.solve(&mut xr).unwrap();
        // the residual a backward-stable solve reaches on this matrix (rounding floor)
        let mut ax = vec![0.0; xr.len()];
        w.a.mul_vec(&xr, &mut ax);
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let diff: Vec<f64> = ax.iter().zip(&w.b).map(|(p, q)| p - q).collect();
        let floor = norm(&diff) / norm(&w.b);
        eprintln!("ratio {ratio:e} faer-cholesky: true residual {floor:e}");
        let mut its = std::collections::BTreeMap::new();
        for which in ["jacobi", "block-jacobi", "two-level-additive", "two-level"] {
            let mut s = pcg_with(&w, which, 1e-12, 50_000);
            s.factorize(&w.a).unwrap();
            let mut x = w.b.clone();
            let r = s.solve(&mut x);
            let st = s.stats();
            eprintln!(
                "ratio {ratio:e} {which}: {:?} iterations {} true residual {:e} error {:e}",
                r.as_ref().err(),
                st.last_iterations,
                st.last_true_residual,
                rel_err(&x, &xr)
            );
            r.unwrap();
            if which.starts_with("two-level") {
                let bound = 100.0 * floor.max(1e-12);
                assert!(st.last_true_residual < bound, "{which}: {bound:e}");
            }
            let err = rel_err(&x, &xr);
            assert!(err < 1e-8, "ratio {ratio:e} {which}: error {err:e}");
            its.insert(which, st.last_iterations);
        }
        let two = its["two-level"];
        assert!(two * 5 < its["jacobi"], "{its:?}");
        assert!(two * 3 < its["block-jacobi"], "{its:?}");
        assert!(its["two-level-additive"] < its["block-jacobi"], "{its:?}");
    }
}

#[test]
fn pcg_preconditioners_are_bit_identical_for_1_and_2_threads() {
    // 14 × 10 blocks of 6 × 4 cells: about 9,700 unknowns, several reduction chunks
    // (4096) and row chunks (2048)
    let w = block_wall(14, 10, 6, 4, 1e-4);
    assert!(w.a.n() > 2 * 4096, "n = {}", w.a.n());
    for which in ["jacobi", "block-jacobi", "two-level-additive", "two-level"] {
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut s = pcg_with(&w, which, 1e-9, 300);
                s.factorize(&w.a).unwrap();
                let mut x = w.b.clone();
                // convergence is not required here, only identical iterates
                let _ = s.solve(&mut x);
                let st = s.stats();
                let mut bits: Vec<u64> = x.iter().map(|v| v.to_bits()).collect();
                bits.push(st.last_true_residual.to_bits());
                bits.push(st.last_iterations as u64);
                bits
            })
        };
        let one = run(1);
        let two = run(2);
        assert!(one == two, "{which}: 1 and 2 threads differ");
    }
}

#[test]
fn pcg_rejects_bad_preconditioner_input() {
    let w = block_wall(2, 2, 2, 2, 1e-3);
    let n = w.a.n();
    // overlapping blocks
    let mut s = Pcg::new().with_preconditioner(Preconditioner::BlockJacobi {
        blocks: vec![vec![0, 1, 2], vec![2, 3]],
    });
    assert!(matches!(s.factorize(&w.a), Err(SolveError::Other(_))));
    assert!(s.solve(&mut w.b.clone()).is_err());
    // out of range
    let mut s = Pcg::new().with_preconditioner(Preconditioner::BlockJacobi {
        blocks: vec![vec![n]],
    });
    assert!(s.factorize(&w.a).is_err());
    // two-level without a coarse space
    let mut s = Pcg::new().with_preconditioner(Preconditioner::TwoLevel {
        blocks: vec![],
        correction: CoarseCorrection::Balanced,
    });
    assert!(s.factorize(&w.a).is_err());
    // dependent coarse columns: a singular coarse matrix is an error, not a panic
    let col: Vec<(usize, f64)> = (0..n).map(|i| (i, 1.0)).collect();
    let z = CoarseSpace::from_columns(n, &[col.clone(), col]).unwrap();
    let mut s = Pcg::new()
        .with_preconditioner(Preconditioner::TwoLevel {
            blocks: vec![],
            correction: CoarseCorrection::Balanced,
        })
        .with_coarse_space(z);
    assert!(s.factorize(&w.a).is_err());
    assert!(CoarseSpace::from_columns(n, &[vec![(n, 1.0)]]).is_err());
    assert!(CoarseSpace::from_columns(n, &[vec![(0, f64::NAN)]]).is_err());
    // a block whose diagonal block is not positive definite
    let mut a = w.a.clone();
    let d = a.pattern.find(3, 3).unwrap();
    a.values[d] = -1.0;
    let mut s = Pcg::new().with_preconditioner(Preconditioner::BlockJacobi {
        blocks: vec![vec![0, 1, 2, 3]],
    });
    assert!(matches!(
        s.factorize(&a),
        Err(SolveError::NotPositiveDefinite { index: 3, .. })
    ));
    // rigid-body modes: 3 per block with enough free nodes, none for a fixed block
    let z = CoarseSpace::rigid_body_modes_2d(n, &w.blocks).unwrap();
    assert_eq!(z.n_columns(), 3 * w.blocks.len());
    let fixed = BlockNodes2d {
        dofs: vec![[CONSTRAINED; 2]; 3],
        xy: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
    };
    let one_node = BlockNodes2d {
        dofs: vec![[0, 1]],
        xy: vec![[0.3, 0.4]],
    };
    let z = CoarseSpace::rigid_body_modes_2d(n, &[fixed, one_node]).unwrap();
    assert_eq!(z.n_columns(), 2);
}

#[test]
fn split_cholesky_matches_the_whole_factorization() {
    // large enough to be split; the small problems of the other tests fall back or split
    let (_, p) = cst_problem(60, 20, true);
    let mut whole = FaerCholesky::new();
    whole.factorize(&p.a).unwrap();
    let mut xw = p.b.clone();
    whole.solve(&mut xw).unwrap();
    for ord in [FillOrdering::Amd, FillOrdering::Metis] {
        let mut s = FaerCholeskySplit::new().with_ordering(ord);
        s.factorize(&p.a).unwrap();
        assert!(s.is_split());
        assert_eq!(s.name(), "faer-cholesky-split");
        let mut xs = p.b.clone();
        s.solve(&mut xs).unwrap();
        let err = rel_err(&xs, &xw);
        assert!(err < 1e-10, "split {ord:?}: {err:e}");
    }
    let mut s = FaerCholeskySplit::new();
    // refactorization with new values, and a skipped identical one
    let mut a2 = p.a.clone();
    for (k, v) in a2.values.iter_mut().enumerate() {
        *v *= 1.0 + 1e-3 * (k % 3) as f64 * 0.0 + 0.5;
    }
    s.factorize(&a2).unwrap();
    s.factorize(&a2.clone()).unwrap();
    assert_eq!(s.stats().skipped_factorizations, 1);
    let mut x2 = p.b.clone();
    s.solve(&mut x2).unwrap();
    assert!(rel_err(&x2, &xw.iter().map(|v| v / 1.5).collect::<Vec<_>>()) < 1e-10);
    // bit-identical for 1 and 2 threads
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut s = FaerCholeskySplit::new();
                s.factorize(&p.a).unwrap();
                let mut x = p.b.clone();
                s.solve(&mut x).unwrap();
                x.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            })
    };
    assert!(run(1) == run(2));
    // a non-positive pivot inside a half is reported at its global unknown
    let mut bad = p.a.clone();
    let d = bad.pattern.find(137, 137).unwrap();
    bad.values[d] = -bad.values[d];
    match FaerCholeskySplit::new().factorize(&bad) {
        Err(SolveError::NotPositiveDefinite { .. }) => {}
        other => panic!("{other:?}"),
    }
    // a tiny matrix falls back to one factorization
    let pattern = Arc::new(CsrPattern::from_entries(1, []));
    let mut one = CsrMatrix::zeros(pattern);
    one.add(0, 0, 4.0);
    let mut s = FaerCholeskySplit::new();
    s.factorize(&one).unwrap();
    assert!(!s.is_split());
    let mut x = vec![2.0];
    s.solve(&mut x).unwrap();
    assert_eq!(x, vec![0.5]);
}
