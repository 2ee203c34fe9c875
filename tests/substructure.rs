//! `faer-substructured` (issue 11): one-level substructuring on a partition of the blocks,
//! checked against faer's Cholesky of the whole matrix (`faer-cholesky`), an independent
//! factorization in another order.
//!
//! The model is the built-in running-bond wall (`dfem example wall`) scaled to n × n
//! bricks, deformable (corner and contact nodes, CST) or rigid, with its elastic stiffness
//! of the first solve and its gravity load. Tolerance 1e-10 (max-norm relative): both
//! are backward-stable Cholesky factorizations, so they differ by round-off amplified by
//! the condition number of the stiffness (~1e5 on these walls: 0.4 m bricks of E = 5 GPa
//! on 10 mm joint bands of 0.8 GPa), about 1e-12 measured; a wrong Schur complement or
//! interface term would give errors of order 1.

mod common;

use dfem::assembly::System;
use dfem::mesh::Mesh;
use dfem::solve::{block_partition, configure, LinearBackend, SolveError};
use dfem_kernels::{max_relative_difference, CsrMatrix, FaerCholesky, FaerCholeskySubstructured};

const TOL: f64 = 1e-10;

struct Wall {
    mesh: Mesh,
    system: System,
    springs: Vec<dfem::material::ContactSprings>,
    k: CsrMatrix,
    f: Vec<f64>,
}

fn wall(n: usize, rigid: bool) -> Wall {
    let sc = common::scene(&dfem::scene::examples::scaled_wall(n, rigid));
    let mesh = dfem::mesh::build(&sc);
    let system = System::new(&sc, &mesh);
    let springs = dfem::analysis::elastic_springs(&sc, &mesh);
    let k = system.stiffness(&mesh, &springs);
    let f = dfem::analysis::external_load(&sc, &mesh);
    Wall {
        mesh,
        system,
        springs,
        k,
        f,
    }
}

/// The part of each block (None for fixed blocks).
fn block_parts(m: &Mesh, part: &[u32]) -> Vec<Option<u32>> {
    (0..m.blocks.len())
        .map(|b| m.block_unknowns(b).first().map(|&d| part[d]))
        .collect()
}

fn solve(be: &mut dyn LinearBackend, k: &CsrMatrix, f: &[f64]) -> Vec<f64> {
    be.factorize(k).unwrap();
    let mut x = f.to_vec();
    be.solve(&mut x).unwrap();
    x
}

fn reference(k: &CsrMatrix, f: &[f64]) -> Vec<f64> {
    solve(&mut FaerCholesky::new(), k, f)
}

fn substructured(w: &Wall, k: usize) -> FaerCholeskySubstructured {
    let mut be = FaerCholeskySubstructured::new().with_subdomains(k);
    configure(&mut be, &w.mesh).unwrap();
    be
}

#[test]
fn substructured_matches_faer_cholesky_on_rigid_and_deformable_walls() {
    for rigid in [false, true] {
        let w = wall(12, rigid);
        let xr = reference(&w.k, &w.f);
        for k in [1, 2, 4] {
            // the partition keeps blocks whole and uses k parts
            let part = block_partition(&w.mesh, k).unwrap();
            let bp = block_parts(&w.mesh, &part);
            for (b, p) in bp.iter().enumerate() {
                assert!(w
                    .mesh
                    .block_unknowns(b)
                    .iter()
                    .all(|&d| Some(part[d]) == *p));
            }
            let mut used: Vec<u32> = part.clone();
            used.sort_unstable();
            used.dedup();
            assert_eq!(used, (0..k as u32).collect::<Vec<_>>());
            let mut be = substructured(&w, k);
            assert_eq!(be.name(), "faer-substructured");
            let x = solve(&mut be, &w.k, &w.f);
            let err = max_relative_difference(&x, &xr);
            assert!(err < TOL, "rigid {rigid}, {k} subdomains: {err:e}");
            let ss = be.substructure_stats();
            assert_eq!(ss.subdomains, k);
            // the interface: one side of the joints cut, nothing when k = 1
            let cut = w
                .mesh
                .contacts
                .iter()
                .filter(|c| {
                    let (l, m) = (bp[c.block_l as usize], bp[c.block_m as usize]);
                    l.is_some() && m.is_some() && l != m
                })
                .count();
            if k == 1 {
                assert_eq!(ss.interface_size, 0);
            } else if rigid {
                // whole rigid blocks on one side of the cut
                assert!(ss.interface_size > 0 && ss.interface_size.is_multiple_of(3));
            } else {
                // one node (2 unknowns) per cut contact at most: a single side
                assert!(
                    ss.interface_size > 0 && ss.interface_size <= 2 * cut,
                    "{} interface unknowns for {cut} contacts cut",
                    ss.interface_size
                );
            }
            // the pivots of the global factorization in the order (interiors, interface)
            let r = be.stats().min_pivot_ratio;
            assert!(r > 1e-9 && r <= 1.0 + 1e-12, "{r}");
        }
    }
}

/// Springs of `w` with those of `contacts` divided by 1000 (joints opening).
fn opened(w: &Wall, contacts: &[usize]) -> CsrMatrix {
    let mut s = w.springs.clone();
    for &c in contacts {
        s[c].kn *= 1e-3;
        s[c].ks *= 1e-3;
    }
    w.system.stiffness(&w.mesh, &s)
}

#[test]
fn only_the_subdomain_whose_values_changed_is_refactorized() {
    let w = wall(12, false);
    let k = 4;
    let part = block_partition(&w.mesh, k).unwrap();
    let bp = block_parts(&w.mesh, &part);
    let mut be = substructured(&w, k);
    let x0 = solve(&mut be, &w.k, &w.f);
    assert!(max_relative_difference(&x0, &reference(&w.k, &w.f)) < TOL);
    let ss = be.substructure_stats().clone();
    assert_eq!(ss.last_refactorized, vec![0, 1, 2, 3]);
    // contacts inside subdomain 2 open: only subdomain 2 is refactorized
    let inside: Vec<usize> = (0..w.mesh.contacts.len())
        .filter(|&c| {
            let ct = &w.mesh.contacts[c];
            bp[ct.block_l as usize] == Some(2) && bp[ct.block_m as usize] == Some(2)
        })
        .step_by(7)
        .collect();
    assert!(!inside.is_empty());
    let k2 = opened(&w, &inside);
    let x = solve(&mut be, &k2, &w.f);
    let ss2 = be.substructure_stats();
    assert_eq!(ss2.last_refactorized, vec![2]);
    // and the fronts on its path: its parent's (parts 2 and 3) and the root's
    assert_eq!(ss2.last_fronts, 2);
    assert_eq!(
        ss2.subdomain_factorizations,
        ss.subdomain_factorizations + 1
    );
    assert_eq!(ss2.subdomain_reuses, ss.subdomain_reuses + 3);
    let xr = reference(&k2, &w.f);
    // the old solution is far from the new one: reusing the wrong factor would show
    assert!(
        max_relative_difference(&x0, &xr) > 1e3 * TOL,
        "{:e}",
        max_relative_difference(&x0, &xr)
    );
    assert!(
        max_relative_difference(&x, &xr) < TOL,
        "{:e}",
        max_relative_difference(&x, &xr)
    );
    // and the same answer as a fresh factorization of the new matrix on the same
    // partition, to the bit: the kept factor and Schur complements of subdomains 0, 1
    // and 3 are those a fresh factorization computes, and the rest is redone in the
    // same order
    let bits = |v: &[f64]| v.iter().map(|a| a.to_bits()).collect::<Vec<_>>();
    let fresh = |a: &CsrMatrix| solve(&mut substructured(&w, k), a, &w.f);
    assert!(bits(&x) == bits(&fresh(&k2)));
    // contacts across the cut between subdomains: the interiors of one side and the
    // interface change; the other side keeps its factor and Schur complement
    let across: Vec<usize> = (0..w.mesh.contacts.len())
        .filter(|&c| {
            let ct = &w.mesh.contacts[c];
            let (l, m) = (bp[ct.block_l as usize], bp[ct.block_m as usize]);
            l.is_some() && m.is_some() && l != m
        })
        .take(3)
        .collect();
    let k3 = opened(&w, &across);
    let x = solve(&mut be, &k3, &w.f);
    let ss3 = be.substructure_stats();
    assert!(
        !ss3.last_refactorized.is_empty() && ss3.last_refactorized.len() < k,
        "{:?}",
        ss3.last_refactorized
    );
    assert!(max_relative_difference(&x, &reference(&k3, &w.f)) < TOL);
    assert!(bits(&x) == bits(&fresh(&k3)));
    // the same values again: nothing is factorized
    let skipped = be.stats().skipped_factorizations;
    be.factorize(&k3.clone()).unwrap();
    assert_eq!(be.stats().skipped_factorizations, skipped + 1);
}

/// The stiffness of `w` with the springs of every contact of block `b` at zero: the
/// block is free (a mechanism).
fn without_springs(w: &Wall, b: usize) -> CsrMatrix {
    let mut s = w.springs.clone();
    for (c, ct) in w.mesh.contacts.iter().enumerate() {
        if ct.block_l as usize == b || ct.block_m as usize == b {
            s[c].kn = 0.0;
            s[c].ks = 0.0;
        }
    }
    w.system.stiffness(&w.mesh, &s)
}

#[test]
fn a_mechanism_is_an_error_at_an_unknown_of_the_free_block() {
    // rigid blocks: a block without springs has exactly zero rows, so a Cholesky pivot
    // of its unknowns is exactly zero; one block inside a subdomain, one on the cut
    let w = wall(8, true);
    let part = block_partition(&w.mesh, 2).unwrap();
    let bp = block_parts(&w.mesh, &part);
    let on_cut = |b: usize| {
        w.mesh.contacts.iter().any(|c| {
            let (l, m) = (c.block_l as usize, c.block_m as usize);
            (l == b || m == b) && bp[l].is_some() && bp[m].is_some() && bp[l] != bp[m]
        })
    };
    let movable: Vec<usize> = (0..w.mesh.blocks.len())
        .filter(|&b| bp[b].is_some())
        .collect();
    let inner = *movable.iter().find(|&&b| !on_cut(b)).unwrap();
    let cut = *movable.iter().find(|&&b| on_cut(b)).unwrap();
    for b in [inner, cut] {
        let k = without_springs(&w, b);
        let mut be = substructured(&w, 2);
        match be.factorize(&k) {
            Err(SolveError::NotPositiveDefinite { index, .. }) => {
                assert!(
                    w.mesh.block_unknowns(b).contains(&index),
                    "block {b}: unknown {index}"
                )
            }
            other => panic!("block {b}: {other:?}"),
        }
        let mut x = w.f.clone();
        assert!(be.solve(&mut x).is_err());
    }
    // a deformable block without springs: singular up to round-off, caught by the error
    // or by the pivot ratio the analyses test (dfem::analysis::SINGULAR_PIVOT_RATIO)
    let w = wall(8, false);
    let b = w.mesh.blocks.len() / 2;
    let k = without_springs(&w, b);
    let mut be = substructured(&w, 2);
    let unknowns = w.mesh.block_unknowns(b);
    match be.factorize(&k) {
        Err(SolveError::NotPositiveDefinite { index, .. }) => {
            assert!(unknowns.contains(&index), "unknown {index}")
        }
        Ok(()) => {
            let st = be.stats();
            assert!(
                st.min_pivot_ratio < dfem::analysis::SINGULAR_PIVOT_RATIO
                    && unknowns.contains(&st.min_pivot_index),
                "ratio {} at {}",
                st.min_pivot_ratio,
                st.min_pivot_index
            );
        }
        Err(e) => panic!("{e:?}"),
    }
}

#[test]
fn a_partition_that_does_not_fit_is_an_error() {
    let w = wall(4, true);
    let n = w.k.n();
    let mut be = FaerCholeskySubstructured::new();
    be.set_partition(&vec![0; n - 1]).unwrap();
    assert!(matches!(be.factorize(&w.k), Err(SolveError::Other(_))));
    let mut be = FaerCholeskySubstructured::new();
    be.set_partition(&vec![n as u32 + 5; n]).unwrap();
    assert!(matches!(be.factorize(&w.k), Err(SolveError::Other(_))));
    // without a partition it makes its own (METIS on the node graph)
    let mut be = FaerCholeskySubstructured::new();
    let x = solve(&mut be, &w.k, &w.f);
    assert!(max_relative_difference(&x, &reference(&w.k, &w.f)) < TOL);
}

#[test]
fn substructured_is_bit_identical_for_1_and_2_threads() {
    // large enough for an interface (about 400 unknowns with 4 subdomains) on which faer's
    // dense Cholesky splits its work into parallel tasks
    let w = wall(30, false);
    let pool = |t| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
    };
    let (one_thread, two_threads) = (pool(1), pool(2));
    // also with faer's kernels split into two tasks inside each subdomain
    for (k, inner) in [(2, 1), (4, 1), (2, 2)] {
        let run = || {
            let mut be = FaerCholeskySubstructured::new()
                .with_subdomains(k)
                .with_subdomain_threads(inner);
            configure(&mut be, &w.mesh).unwrap();
            let x = solve(&mut be, &w.k, &w.f);
            assert!(be.substructure_stats().interface_size > 150);
            x.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        };
        assert!(
            one_thread.install(run) == two_threads.install(run),
            "{k} subdomains, {inner} task(s) inside each"
        );
    }
}

/// `dfem run --example wall` (static, gravity) with `--solver faer-substructured`, by
/// default (2 subdomains) and with `--subdomains 1, 2, 4` (the entry point users use): the
/// same status and iterations as the default backend and the block displacements of
/// summary.json to 1e-8 relative (each solve agrees to ~1e-12; the secant iterations'
/// out-of-balance tolerance bounds what can differ after them). The factor's stored
/// entries (summary.json) differ between 1, 2 and 4 subdomains — the interface fronts are
/// dense — which shows that the option reached the backend.
#[test]
fn static_wall_example_end_to_end_matches_the_default_backend() {
    let dir = common::tmp_dir("substructured_wall");
    let run = |solver: &str, k: Option<&str>| {
        let out = dir.join(format!("{solver}_{}", k.unwrap_or("default")));
        let mut args = vec![
            "run",
            "--example",
            "wall",
            "--solver",
            solver,
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--no-plots",
        ];
        if let Some(k) = k {
            args.extend(["--subdomains", k]);
        }
        common::dfem_ok(&args);
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        s
    };
    let motions = |s: &serde_json::Value| -> Vec<f64> {
        s["blocks"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|bl| {
                let d = &bl["displacement"];
                [d[0].as_f64().unwrap(), d[1].as_f64().unwrap()]
            })
            .collect()
    };
    let a = run("faer-cholesky", None);
    let ma = motions(&a);
    assert!(ma.len() >= 2 * 50);
    let mut nnz = Vec::new();
    for k in [None, Some("1"), Some("2"), Some("4")] {
        let b = run("faer-substructured", k);
        assert_eq!(a["status"], b["status"], "{k:?}");
        assert_eq!(a["stats"]["iterations"], b["stats"]["iterations"], "{k:?}");
        let mb = motions(&b);
        assert_eq!(ma.len(), mb.len());
        let err = max_relative_difference(&mb, &ma);
        assert!(
            err < 1e-8,
            "{k:?} subdomains: block displacements differ by {err:e}"
        );
        nnz.push(b["stats"]["factor_nnz"].as_u64().unwrap());
    }
    // the default is 2 subdomains; 1, 2 and 4 give different factors
    assert_eq!(nnz[0], nnz[2]);
    assert!(
        nnz[1] != nnz[2] && nnz[2] != nnz[3] && nnz[1] != nnz[3],
        "{nnz:?}"
    );
}

/// `--subdomains` below 1, or with another backend than faer-substructured, is refused
/// with a message that names the option and the fix (exit status 2, no panic).
#[test]
fn bad_subdomains_option_is_a_clear_error() {
    let dir = common::tmp_dir("substructured_bad_option");
    let out = dir.join("out");
    for (args, says) in [
        (
            &["--solver", "faer-substructured", "--subdomains", "0"][..],
            "at least 1",
        ),
        (
            &["--subdomains", "2"][..],
            "applies to --solver faer-substructured only",
        ),
        (
            &["--solver", "pcg", "--subdomains", "4"][..],
            "not to 'pcg'",
        ),
    ] {
        let o = std::process::Command::new(common::dfem_bin())
            .args(["run", "--example", "wall", "--quiet", "--out"])
            .arg(&out)
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("option --subdomains") && err.contains(says) && err.contains("fix:"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    // the library entry point: the backend asks for the partition it was given
    for k in [1, 3, 4] {
        let opts = dfem::solve::BackendOptions {
            subdomains: Some(k),
            ..Default::default()
        };
        let be = dfem::solve::backend_with("faer-substructured", &opts).unwrap();
        assert_eq!(be.partition_parts(), Some(k));
    }
}
