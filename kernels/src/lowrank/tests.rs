use super::*;
use crate::backend::LinearBackend;
use crate::csr::CsrPattern;
use crate::faer_backend::FaerCholesky;
use std::sync::Arc;

/// A spring: nodes a and b, stiffness (kx, ky) on their relative displacement, N/m
/// (b = None: a spring to the ground).
#[derive(Clone, Copy)]
struct Spring {
    a: usize,
    b: Option<usize>,
    k: [f64; 2],
}

/// An nx × ny grid of nodes with two unknowns each (x, y), springs between
/// neighbours (normal stiffness 1 along the joining line, shear 0.4 across, a few
/// varied by ±30 %) and the bottom row tied to the ground: a small analogue of the
/// wall's contacts.
fn grid(nx: usize, ny: usize) -> (usize, Vec<Spring>) {
    let id = |i: usize, j: usize| j * nx + i;
    let vary = |s: usize| 1.0 + 0.3 * (((s * 7919) % 13) as f64 / 6.0 - 1.0);
    let mut springs = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let s = springs.len();
            if i + 1 < nx {
                springs.push(Spring {
                    a: id(i, j),
                    b: Some(id(i + 1, j)),
                    k: [vary(s), 0.4],
                });
            }
            if j + 1 < ny {
                springs.push(Spring {
                    a: id(i, j),
                    b: Some(id(i, j + 1)),
                    k: [0.4, vary(s + 1)],
                });
            }
            if j == 0 {
                springs.push(Spring {
                    a: id(i, j),
                    b: None,
                    k: [1.0, 1.0],
                });
            }
        }
    }
    (2 * nx * ny, springs)
}

/// The stiffness of `springs` on n unknowns (pattern from all of `pattern_of`).
fn stiffness(n: usize, pattern_of: &[Spring], springs: &[Spring]) -> CsrMatrix {
    let mut e: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
    for s in pattern_of {
        if let Some(b) = s.b {
            for c in 0..2 {
                e.push((2 * s.a + c, 2 * b + c));
                e.push((2 * b + c, 2 * s.a + c));
            }
        }
    }
    let mut k = CsrMatrix::zeros(Arc::new(CsrPattern::from_entries(n, e)));
    for s in springs {
        for c in 0..2 {
            let (i, kc) = (2 * s.a + c, s.k[c]);
            k.add(i, i, kc);
            if let Some(b) = s.b {
                let j = 2 * b + c;
                k.add(j, j, kc);
                k.add(i, j, -kc);
                k.add(j, i, -kc);
            }
        }
    }
    k
}

fn load(n: usize) -> Vec<f64> {
    (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) / 5.0).collect()
}

fn norm(v: impl Iterator<Item = f64>) -> f64 {
    v.map(|a| a * a).sum::<f64>().sqrt()
}

fn residual(k: &CsrMatrix, x: &[f64], f: &[f64]) -> f64 {
    let mut kx = vec![0.0; x.len()];
    k.mul_vec(x, &mut kx);
    norm(f.iter().zip(&kx).map(|(a, b)| a - b)) / norm(f.iter().copied())
}

fn backends() -> [FaerCholesky; 2] {
    [
        FaerCholesky::new().with_supernodal_threshold(0.0),
        FaerCholesky::new().with_supernodal_threshold(f64::INFINITY),
    ]
}

/// Ground —k1— node 0 —k2— node 1 (x only; y held by ground springs of 1): with a
/// load F at node 1, u₀ = F/k1 and u₁ = F/k1 + F/k2 for any k2 > 0. k1 = 2, k2 = 3
/// factorized, k2 changed to 0.5 (a downdate) and to 30 (an update): a few roundings
/// of numbers of order 1, so 1e-14.
#[test]
fn two_springs_closed_form() {
    let chain = |k2: f64| {
        vec![
            Spring {
                a: 0,
                b: None,
                k: [2.0, 1.0],
            },
            Spring {
                a: 1,
                b: None,
                k: [0.0, 1.0],
            },
            Spring {
                a: 0,
                b: Some(1),
                k: [k2, 0.0],
            },
        ]
    };
    let old = chain(3.0);
    for mut backend in backends() {
        backend.factorize(&stiffness(4, &old, &old)).unwrap();
        let mut c = LowRankCorrection::new();
        for k2 in [0.5, 30.0] {
            c.update(&backend, &stiffness(4, &old, &chain(k2))).unwrap();
            assert_eq!(c.stats().rank, 1);
            let mut x = vec![0.0, 0.0, 1.0, 0.0];
            c.solve(&backend, &mut x).unwrap();
            let want = [0.5, 0.0, 0.5 + 1.0 / k2, 0.0];
            for (a, b) in x.iter().zip(want) {
                assert!((a - b).abs() < 1e-14, "k2 = {k2}: {x:?} against {want:?}");
            }
        }
        // k2 → 0 leaves node 1 free along x: singular, reported
        let err = c
            .update(&backend, &stiffness(4, &old, &chain(0.0)))
            .unwrap_err();
        assert!(
            matches!(err, SolveError::NotPositiveDefinite { index, .. } if index == 0 || index == 2),
            "{err:?}"
        );
        // and a spring of negative stiffness beyond it: indefinite, reported
        let err = c
            .update(&backend, &stiffness(4, &old, &chain(-1.0)))
            .unwrap_err();
        assert!(
            matches!(err, SolveError::NotPositiveDefinite { .. }),
            "{err:?}"
        );
        let mut x = vec![1.0; 4];
        assert!(
            c.solve(&backend, &mut x).is_err(),
            "no solve after a failed update"
        );
    }
}

/// Springs of a 30 × 20 grid opened (both stiffnesses removed: a rank-2 downdate),
/// slipping (shear removed: rank 1), stiffened (×5 normal: a rank-1 update), two
/// changes sharing a node (one block of ΔK): the solution against faer's fresh
/// factorization of K_new, supernodal and simplicial. Both carry an error of about
/// cond(K)·ε (cond ≈ 10⁴ for this grid held at one edge), so they agree to 1e-9
/// relative; the true residual of the correction ‖f − K x‖/‖f‖ is below 1e-12.
#[test]
fn against_a_fresh_factorization() {
    let (n, old) = grid(30, 20);
    let mut new = old.clone();
    let mut expected_rank = 0;
    for (t, s) in (0..old.len()).step_by(47).enumerate() {
        match t % 3 {
            0 => {
                new[s].k = [0.0, 0.0];
                expected_rank += 2;
            }
            1 => {
                let normal = if new[s].k[0] == 0.4 { 1 } else { 0 };
                new[s].k[1 - normal] = 0.0;
                expected_rank += 1;
            }
            _ => {
                new[s].k = [5.0 * new[s].k[0], new[s].k[1]];
                expected_rank += 1;
            }
        }
    }
    // two changes sharing node a of spring 99 (springs 99 and 100 leave it)
    assert_eq!(old[99].a, old[100].a);
    new[99].k = [0.0, 0.0];
    new[100].k[0] *= 0.5;
    expected_rank += 3;
    let (k_old, k_new) = (stiffness(n, &old, &old), stiffness(n, &old, &new));
    let f = load(n);
    for (mut backend, mut fresh) in backends().into_iter().zip(backends()) {
        backend.factorize(&k_old).unwrap();
        let mut c = LowRankCorrection::new();
        let mut x = f.clone();
        assert!(c.solve(&backend, &mut x).is_err(), "solve before update");
        c.update(&backend, &k_new).unwrap();
        assert_eq!(c.stats().rank, expected_rank);
        c.solve(&backend, &mut x).unwrap();
        fresh.factorize(&k_new).unwrap();
        let mut want = f.clone();
        fresh.solve(&mut want).unwrap();
        let diff = norm(x.iter().zip(&want).map(|(a, b)| a - b)) / norm(want.iter().copied());
        assert!(diff < 1e-9, "relative difference {diff:e}");
        let res = residual(&k_new, &x, &f);
        assert!(res < 1e-12, "true residual {res:e}");
        // no change: the plain solve with the held factor, bit for bit
        c.update(&backend, &k_old).unwrap();
        assert_eq!(c.stats().rank, 0);
        let (mut a, mut b) = (f.clone(), f.clone());
        c.solve(&backend, &mut a).unwrap();
        backend.solve(&mut b).unwrap();
        assert!(a
            .iter()
            .zip(&b)
            .all(|(p, q)| (p - q).abs() <= 1e-14 * q.abs().max(1e-3)));
        // a refactorization makes the update stale
        backend.factorize(&k_new).unwrap();
        assert!(c.solve(&backend, &mut a).is_err(), "stale update");
    }
}

/// All springs around an interior node opened: the node floats, K_new is singular,
/// the update reports it at one of the node's unknowns or a neighbour's.
#[test]
fn downdate_to_a_mechanism_is_reported() {
    let (n, old) = grid(12, 8);
    let node = 5 * 12 + 6;
    let mut new = old.clone();
    let mut around = vec![node];
    for s in new.iter_mut() {
        if s.a == node || s.b == Some(node) {
            around.push(if s.a == node { s.b.unwrap() } else { s.a });
            s.k = [0.0, 0.0];
        }
    }
    assert_eq!(around.len(), 5);
    for mut backend in backends() {
        backend.factorize(&stiffness(n, &old, &old)).unwrap();
        let mut c = LowRankCorrection::new();
        let err = c.update(&backend, &stiffness(n, &old, &new)).unwrap_err();
        match err {
            SolveError::NotPositiveDefinite { index, .. } => {
                assert!(around.contains(&(index / 2)), "unknown {index}")
            }
            e => panic!("{e:?}"),
        }
        // one spring left: positive definite again, and solved
        new[old.iter().position(|s| s.a == node).unwrap()].k = [0.1, 0.1];
        let k_new = stiffness(n, &old, &new);
        c.update(&backend, &k_new).unwrap();
        let f = load(n);
        let mut x = f.clone();
        c.solve(&backend, &mut x).unwrap();
        assert!(residual(&k_new, &x, &f) < 1e-12);
        new = old.clone();
        for s in new.iter_mut() {
            if s.a == node || s.b == Some(node) {
                s.k = [0.0, 0.0];
            }
        }
    }
}

/// The substitutions on the [`Split`]'s parts give faer's sequential ones bit for bit
/// (the same operations on every entry, in the same order: see [`Split`]) in rayon
/// pools of 1, 2 and 8 threads (the split called directly: `Tree::substitute` takes
/// faer's kernels on one thread), forward and backward, on the supernodal factor of
/// an 80 × 60 grid (METIS and AMD orderings), whose tree has at least two parts.
#[test]
fn split_substitution_is_faers_bit_for_bit() {
    let (n, springs) = grid(80, 60);
    let k = stiffness(n, &springs, &springs);
    for name in ["faer-cholesky", "faer-cholesky-metis"] {
        let mut backend = FaerCholesky::new().with_supernodal_threshold(0.0);
        if name.ends_with("metis") {
            backend = backend.with_ordering(crate::ordering::FillOrdering::Metis);
        }
        backend.factorize(&k).unwrap();
        let an = held(backend.core()).unwrap();
        let mut tree = Tree::new(backend.core()).unwrap();
        let parts = tree.split.as_ref().map_or(0, |s| s.parts.len());
        assert!(parts >= 2, "{name}: {parts} parts");
        let f = load(n);
        for transpose in [false, true] {
            let mut want = f.clone();
            substitute(an, &mut want, transpose, &mut tree.mem);
            for threads in [1, 2, 8] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut y = f.clone();
                let mut split = tree.split.take().expect("split");
                pool.install(|| split.substitute(&tree, &an.l_values, &mut y, transpose));
                tree.split = Some(split);
                assert!(
                    crate::backend::same_bits(&y, &want),
                    "{name}, transpose {transpose}, {threads} threads"
                );
            }
        }
    }
}

/// [`FaerCholesky`]'s solve on 2 and 8 threads (the split's substitutions) gives its
/// solve on one thread (faer's `solve_in_place_with_conj`, permutation included) bit
/// for bit, on the 80 × 60 grid with both orderings.
#[test]
fn held_solve_on_threads_is_faers_bit_for_bit() {
    let (n, springs) = grid(80, 60);
    let k = stiffness(n, &springs, &springs);
    for ordering in [
        crate::ordering::FillOrdering::Amd,
        crate::ordering::FillOrdering::Metis,
    ] {
        let mut backend = FaerCholesky::new()
            .with_supernodal_threshold(0.0)
            .with_ordering(ordering);
        backend.factorize(&k).unwrap();
        let f = load(n);
        let pool = |t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
        };
        let mut want = f.clone();
        pool(1).install(|| backend.solve(&mut want)).unwrap();
        let mut c = LowRankCorrection::new();
        let mut y = f.clone();
        assert!(!pool(1)
            .install(|| c.solve_held(backend.core(), &mut y))
            .unwrap());
        for threads in [2, 8] {
            let mut y = f.clone();
            assert!(pool(threads)
                .install(|| c.solve_held(backend.core(), &mut y))
                .unwrap());
            assert!(
                crate::backend::same_bits(&y, &want),
                "{ordering:?}, {threads}"
            );
            let mut y = f.clone();
            pool(threads).install(|| backend.solve(&mut y)).unwrap();
            assert!(
                crate::backend::same_bits(&y, &want),
                "{ordering:?}, {threads}"
            );
        }
        assert_eq!(backend.stats().solves, 3);
    }
}

/// Timing of one solve's two substitutions (L⁻¹ then L⁻ᵀ) on the supernodal factor of
/// a 120 × 100 grid (24,000 unknowns, x and y uncoupled: two 12,000-unknown problems;
/// factor about the size of the deformable 40 × 40 wall P2's): faer's
/// sequential kernels against the [`Split`] in pools of 1 and 2 threads, 400 rounds
/// taken in turn, minimum and median printed (docs/performance.md, "P2: the 40 × 40 wall against OpenSees"). Not a
/// check of speed (that depends on the machine's load); the bits are checked.
/// `cargo test --release -p dfem-kernels --lib split_substitution_timing -- --ignored --nocapture`
#[test]
#[ignore]
fn split_substitution_timing() {
    let (n, springs) = grid(120, 100);
    let k = stiffness(n, &springs, &springs);
    let mut backend = FaerCholesky::new().with_supernodal_threshold(0.0);
    backend.factorize(&k).unwrap();
    let an = held(backend.core()).unwrap();
    let mut tree = Tree::new(backend.core()).unwrap();
    println!(
        "factor nnz {}, {} parts",
        an.l_values.len(),
        tree.split.as_ref().map_or(0, |s| s.parts.len())
    );
    let f = load(n);
    let pools: Vec<rayon::ThreadPool> = [1, 2]
        .iter()
        .map(|&t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
        })
        .collect();
    let mut times = vec![Vec::new(); 3];
    let mut want = f.clone();
    for round in 0..400 {
        let t = Instant::now();
        let mut y = f.clone();
        substitute(an, &mut y, false, &mut tree.mem);
        substitute(an, &mut y, true, &mut tree.mem);
        times[0].push(t.elapsed().as_secs_f64());
        if round == 0 {
            want = y;
        }
        for (i, pool) in pools.iter().enumerate() {
            let t = Instant::now();
            let mut y = f.clone();
            let mut split = tree.split.take().expect("split");
            pool.install(|| {
                split.substitute(&tree, &an.l_values, &mut y, false);
                split.substitute(&tree, &an.l_values, &mut y, true);
            });
            tree.split = Some(split);
            times[i + 1].push(t.elapsed().as_secs_f64());
            assert!(crate::backend::same_bits(&y, &want));
        }
    }
    for (name, mut t) in ["faer sequential", "split, 1 thread", "split, 2 threads"]
        .into_iter()
        .zip(times)
    {
        t.sort_by(f64::total_cmp);
        println!(
            "{name}: min {:.1} µs, median {:.1} µs",
            1e6 * t[0],
            1e6 * t[t.len() / 2]
        );
    }
}

/// The scan of ΔK in chunks of rows (an 80 × 60 grid: 9600 unknowns, three chunks)
/// reports what a sequential scan would: with a rank limit of 2 and every entry
/// changed, the 129th changed entry's row (the first one, in row order, beyond
/// 64 × 2); a NaN in the last chunk after that: still the limit; a NaN with few
/// changes before it: the NaN, at its row; and a rank-5 change spread over the
/// chunks is split into one block and one term per changed spring direction (x and y
/// unknowns are not coupled in this grid): 5 blocks, rank 5.
#[test]
fn chunked_scan_reports_as_a_sequential_one() {
    let (n, old) = grid(80, 60);
    let k_old = stiffness(n, &old, &old);
    assert!(k_old.values.len() > 2 * crate::backend::SAME_BITS_CHUNK);
    let limits = Some((ENTRIES_PER_RANK * 2, UNKNOWNS_PER_RANK * 2));
    let rp = k_old.pattern.row_ptr();
    let row_of = |e: usize| (0..n).find(|&i| rp[i + 1] > e).unwrap();
    let mut scaled = k_old.clone();
    scaled.values.iter_mut().for_each(|v| *v *= 1.001);
    // entries are numbered row by row: the 129th nonzero change is entry 128
    let err = |k: &CsrMatrix| match split_change(k, &k_old.values, limits) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("accepted"),
    };
    let want = format!(
        "more than 128 entries changed (from row {} on)",
        row_of(128)
    );
    assert!(err(&scaled).contains(&want), "{}", err(&scaled));
    let last = k_old.values.len() - 1;
    scaled.values[last] = f64::NAN;
    assert!(err(&scaled).contains(&want), "{}", err(&scaled));
    let mut nan = k_old.clone();
    nan.values[7] *= 2.0;
    nan.values[last] = f64::NAN;
    let e = err(&nan);
    assert!(
        e.contains("non-finite") && e.contains(&format!("at row {}", n - 1)),
        "{e}"
    );
    let mut new = old.clone();
    for s in [3, 4000, 9000] {
        new[s].k[0] *= 2.0;
    }
    new[9500].k = [0.0, 0.0];
    let terms = split_change(&stiffness(n, &old, &new), &k_old.values, limits).unwrap();
    let rank: usize = terms.iter().map(|b| b.signs.len()).sum();
    assert_eq!((terms.len(), rank), (5, 5));
}

/// A non-finite value in K_new, or a matrix of another size, is an error, not a panic.
#[test]
fn bad_input_is_an_error() {
    let (n, old) = grid(6, 5);
    let k_old = stiffness(n, &old, &old);
    let mut backend = FaerCholesky::new();
    let mut c = LowRankCorrection::new();
    assert!(c.update(&backend, &k_old).is_err(), "nothing factorized");
    backend.factorize(&k_old).unwrap();
    let mut k_new = k_old.clone();
    k_new.values[7] = f64::NAN;
    assert!(c.update(&backend, &k_new).is_err());
    let (m, small) = grid(3, 2);
    assert!(c.update(&backend, &stiffness(m, &small, &small)).is_err());
    c.update(&backend, &k_old).unwrap();
    assert!(c.solve(&backend, &mut vec![1.0; n + 1]).is_err());
}

/// The rank limit refuses a larger change with an error naming the fix.
#[test]
fn rank_limit() {
    let (n, old) = grid(6, 5);
    let mut new = old.clone();
    new[3].k = [0.0, 0.0];
    let mut backend = FaerCholesky::new();
    backend.factorize(&stiffness(n, &old, &old)).unwrap();
    let mut c = LowRankCorrection::new().with_max_rank(1);
    let err = c.update(&backend, &stiffness(n, &old, &new)).unwrap_err();
    assert!(err.to_string().contains("rank 2") && err.to_string().contains("refactorize"));
}

/// `LinearBackend::solve_changed` of `faer-cholesky` (through the trait object, as
/// the driver calls it): the grid's springs changed as in
/// [`against_a_fresh_factorization`] (rank 5) give faer's fresh solution of K_new to
/// the same 1e-9 (both carry cond(K)·ε ≈ 10⁻¹², see there) and count in the
/// backend's stats; the held factor still solves K_old (compared with a second
/// backend's factorization of K_old: bit-identical, the same factorization); a second
/// call with the same K_new reuses the update and gives the same bits.
#[test]
fn solve_changed_through_the_trait() {
    let (n, old) = grid(20, 12);
    let mut new = old.clone();
    new[30].k = [0.0, 0.0];
    new[101].k[0] *= 4.0;
    new[250].k = [0.0, 0.0];
    let (k_old, k_new) = (stiffness(n, &old, &old), stiffness(n, &old, &new));
    let f = load(n);
    for name in ["faer-cholesky", "faer-cholesky-metis"] {
        let mut backend = crate::registry::backend_from_name(name).unwrap();
        let mut x = f.clone();
        assert!(
            backend.solve_changed(&k_new, &mut x).is_err(),
            "{name}: nothing factorized"
        );
        backend.factorize(&k_old).unwrap();
        let mut x = f.clone();
        backend.solve_changed(&k_new, &mut x).unwrap();
        let mut fresh = crate::registry::backend_from_name(name).unwrap();
        fresh.factorize(&k_new).unwrap();
        let mut want = f.clone();
        fresh.solve(&mut want).unwrap();
        let diff = norm(x.iter().zip(&want).map(|(a, b)| a - b)) / norm(want.iter().copied());
        assert!(diff < 1e-9, "{name}: relative difference {diff:e}");
        let st = backend.stats();
        assert_eq!(
            (st.changed_solves, st.last_changed_rank, st.max_changed_rank),
            (1, 5, 5),
            "{name}"
        );
        assert_eq!(st.numeric_factorizations, 1, "{name}: no refactorization");
        let mut again = f.clone();
        backend.solve_changed(&k_new, &mut again).unwrap();
        assert!(crate::backend::same_bits(&again, &x), "{name}");
        let (mut a, mut b) = (f.clone(), f.clone());
        backend.solve(&mut a).unwrap();
        fresh.factorize(&k_old).unwrap();
        fresh.solve(&mut b).unwrap();
        assert!(crate::backend::same_bits(&a, &b), "{name}: the held factor");
    }
}

/// A change of every entry (the matrix of a new geometry: all values × 1.001) is
/// refused after reading 64 × the rank limit of them, with an error naming the fix;
/// so is one connected change on more unknowns than 8 × the limit (a row of springs
/// along the grid all changed, one block of 2 × 20 unknowns, limit 2), before its
/// eigendecomposition; the backend then refactorizes as usual. Backends without the
/// path report `Unsupported`.
#[test]
fn solve_changed_refuses_what_does_not_pay() {
    let (n, old) = grid(20, 12);
    let k_old = stiffness(n, &old, &old);
    let f = load(n);
    let mut backend = FaerCholesky::new().with_changed_max_rank(2);
    backend.factorize(&k_old).unwrap();
    let mut scaled = k_old.clone();
    scaled.values.iter_mut().for_each(|v| *v *= 1.001);
    let err = backend.solve_changed(&scaled, &mut f.clone()).unwrap_err();
    assert!(
        err.to_string().contains("more than 128 entries changed")
            && err.to_string().contains("refactorize"),
        "{err}"
    );
    // the horizontal springs of the bottom row (nodes 0..20), stiffened: one block
    let mut new = old.clone();
    for s in new.iter_mut() {
        if s.a < 19 && s.b == Some(s.a + 1) {
            s.k[0] *= 2.0;
        }
    }
    let err = backend
        .solve_changed(&stiffness(n, &old, &new), &mut f.clone())
        .unwrap_err();
    assert!(err.to_string().contains("on 20 unknowns"), "{err}");
    assert_eq!(backend.stats().changed_solves, 0);
    backend.factorize(&scaled).unwrap();
    let mut x = f.clone();
    backend.solve(&mut x).unwrap();
    assert!(residual(&scaled, &x, &f) < 1e-12);
    for name in ["faer-ldlt", "faer-lu", "pcg", "faer-cholesky-split"] {
        let mut other = crate::registry::backend_from_name(name).unwrap();
        other.factorize(&k_old).unwrap();
        let err = other.solve_changed(&scaled, &mut f.clone()).unwrap_err();
        assert!(
            matches!(err, SolveError::Unsupported { backend, .. } if backend == name),
            "{name}: {err:?}"
        );
    }
}
