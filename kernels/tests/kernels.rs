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
            if name.starts_with("faer-cholesky") || name.starts_with("faer-ldlt") {
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
        assert!(nm < na * 3 / 2, "{metis_name}: nnz(L) {nm} against AMD {na}");
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
