//! The direct-scatter assembly of `AssemblyPlan` (issue 6) against a straightforward
//! triplet sum, and its paths (whole, in groups onto a base, re-assembly of a few changed
//! elements) against one another, on 1 and 2 threads.
//!
//! The elements mix every kind of scatter map the plan builds: CST-like 6-slot triangles
//! over a distorted grid (paired maps: x, y unknowns of a node consecutive), the same
//! triangles next to a constrained edge (general maps with constrained slots), 2-slot
//! springs acting on the x unknowns only (general maps; the triangles sharing their rows
//! have blocks whose four entries get their first additions from different elements, so
//! the plan must fall back to general maps there), and 3-slot elements with a repeated
//! unknown. Element matrices are pseudo-random (a fixed integer hash of element and
//! slots), symmetric or not as a form needs, so that a wrong position, a missed or a
//! doubled contribution shows.
//!
//! Reference: every contribution K_e(a, b) added into a hash map keyed by (dofs[a],
//! dofs[b]) with the sum of absolute values. An entry is a sum of at most a few dozen
//! terms, so its rounding error is below 64 · 2⁻⁵³ · Σ|terms| ≈ 7e-15 Σ|terms|; the test
//! asks for 1e-12 Σ|terms|, far below the size of any one contribution (≥ 1e-3 of the
//! sum here), so a missed or doubled term cannot pass.

use dfem_kernels::{AssemblyPlan, Connectivity, CsrMatrix, Form, CONSTRAINED};
use std::collections::HashMap;

/// A grid of nx × ny cells, 2 triangles each; returns the connectivity and its group ends
/// (triangles, springs, repeated-dof elements) and the number of unknowns.
fn mixed(nx: usize, ny: usize) -> (Connectivity, Vec<usize>, usize) {
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    // the nodes of the left edge are constrained
    let mut first = vec![CONSTRAINED; (nx + 1) * (ny + 1)];
    let mut n = 0u32;
    for j in 0..=ny {
        for i in 1..=nx {
            first[id(i, j)] = n;
            n += 2;
        }
    }
    let dof = |v: usize, k: u32| {
        if first[v] == CONSTRAINED {
            CONSTRAINED
        } else {
            first[v] + k
        }
    };
    let mut conn = Connectivity::new();
    for j in 0..ny {
        for i in 0..nx {
            for t in [
                [id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                [id(i, j), id(i + 1, j + 1), id(i, j + 1)],
            ] {
                let d: Vec<u32> = t.iter().flat_map(|&v| [dof(v, 0), dof(v, 1)]).collect();
                conn.push(&d);
            }
        }
    }
    let nt = conn.len();
    // x-only springs along the bottom row and the middle column
    for i in 1..nx {
        conn.push(&[dof(id(i, 0), 0), dof(id(i + 1, 0), 0)]);
    }
    for j in 0..ny {
        conn.push(&[dof(id(nx / 2, j), 0), dof(id(nx / 2, j + 1), 0)]);
    }
    let ns = conn.len();
    // an unknown twice in one element
    for j in 0..ny {
        let v = id(nx, j);
        conn.push(&[dof(v, 1), dof(v + nx + 1, 1), dof(v, 1)]);
    }
    let nr = conn.len();
    (conn, vec![nt, ns, nr], n as usize)
}

/// A pseudo-random value in [0.001, 1) from integers (fixed hash, no state).
fn hash(e: usize, a: usize, b: usize, salt: u64) -> f64 {
    let mut x = (e as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((a as u64) << 32 | b as u64)
        .wrapping_add(salt.wrapping_mul(0xD1B5_4A32_D192_ED03));
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 29;
    0.001 + 0.999 * (x >> 11) as f64 / (1u64 << 53) as f64
}

/// Element e's full matrix: symmetric (K_ab from the unordered pair) or not.
fn element(e: usize, m: usize, symmetric: bool, salt: u64) -> Vec<f64> {
    let mut k = vec![0.0; m * m];
    for a in 0..m {
        for b in 0..m {
            let (p, q) = if symmetric && a > b { (b, a) } else { (a, b) };
            k[a * m + b] = hash(e, p, q, salt) * if p == q { 4.0 } else { -1.0 };
        }
    }
    k
}

/// The kernel of `form` for the element matrices of [`element`].
fn kernel<'a>(
    conn: &'a Connectivity,
    form: Form,
    salt: impl Fn(usize) -> u64 + Sync + 'a,
) -> impl Fn(usize, &mut [f64]) + Sync + 'a {
    move |e, out| {
        let m = conn.dofs(e).len();
        let k = element(e, m, form != Form::Unsymmetric, salt(e));
        if form == Form::Packed {
            let mut t = 0;
            for a in 0..m {
                for b in a..m {
                    out[t] = k[a * m + b];
                    t += 1;
                }
            }
        } else {
            out.copy_from_slice(&k);
        }
    }
}

fn bits(k: &CsrMatrix) -> Vec<u64> {
    k.values.iter().map(|v| v.to_bits()).collect()
}

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

#[test]
fn direct_scatter_matches_a_triplet_sum() {
    let (conn, ends, n) = mixed(80, 45);
    let plan = AssemblyPlan::with_groups(n, &conn, &ends);
    assert!(plan.n_elements() > 3 * dfem_kernels::assembly::ELEM_CHUNK);
    assert!(
        plan.n_paired(0) > 0 && plan.n_paired(0) < ends[0],
        "paired and general maps"
    );
    for form in [Form::Packed, Form::Symmetrised, Form::Unsymmetric] {
        let symmetric = form != Form::Unsymmetric;
        // the triplet sum: (sum, sum of |terms|)
        let mut reference: HashMap<(u32, u32), (f64, f64)> = HashMap::new();
        for e in 0..conn.len() {
            let d = conn.dofs(e);
            let m = d.len();
            let k = element(e, m, symmetric, 7);
            for a in 0..m {
                for b in 0..m {
                    if d[a] != CONSTRAINED && d[b] != CONSTRAINED {
                        let r = reference.entry((d[a], d[b])).or_default();
                        r.0 += k[a * m + b];
                        r.1 += k[a * m + b].abs();
                    }
                }
            }
        }
        let mut out = CsrMatrix::zeros(plan.pattern().clone());
        out.values.fill(f64::NAN); // every value must be overwritten
        plan.assemble_groups(form, 0..3, None, kernel(&conn, form, |_| 7), &mut out);
        let p = plan.pattern();
        assert_eq!(
            p.nnz(),
            reference.len()
                + (0..n)
                    .filter(|&i| !reference.contains_key(&(i as u32, i as u32)))
                    .count()
        );
        for i in 0..n {
            for k in p.row_ptr()[i]..p.row_ptr()[i + 1] {
                let j = p.col_idx()[k];
                let (sum, scale) = reference.get(&(i as u32, j)).copied().unwrap_or((0.0, 0.0));
                let v = out.values[k];
                assert!(
                    (v - sum).abs() <= 1e-12 * scale,
                    "{form:?} ({i}, {j}): {v} against {sum} (scale {scale})"
                );
                if symmetric {
                    let t = p.find(j as usize, i).unwrap();
                    assert_eq!(v.to_bits(), out.values[t].to_bits(), "({i}, {j}) symmetric");
                }
            }
        }
    }
}

#[test]
fn groups_and_reassembly_are_bit_identical_to_a_whole_assembly() {
    let (conn, ends, n) = mixed(80, 45);
    let plan = AssemblyPlan::with_groups(n, &conn, &ends);
    // changed elements: a few triangles, springs and repeated-dof elements
    let changed_tri: Vec<usize> = (0..ends[0]).step_by(997).collect();
    let changed_later: Vec<usize> = (ends[0]..ends[2]).step_by(13).collect();
    let run = |threads: usize| {
        in_pool(threads, || {
            let mut results = Vec::new();
            for form in [Form::Packed, Form::Symmetrised, Form::Unsymmetric] {
                let whole = |salt: &(dyn Fn(usize) -> u64 + Sync)| {
                    let mut k = CsrMatrix::zeros(plan.pattern().clone());
                    plan.assemble_groups(form, 0..3, None, kernel(&conn, form, salt), &mut k);
                    k
                };
                let old = whole(&|_| 1);
                // in parts: group 0, then groups 1..3 onto it (the kept part + contacts)
                let mut base = CsrMatrix::zeros(plan.pattern().clone());
                base.values.fill(f64::NAN);
                plan.assemble_groups(form, 0..1, None, kernel(&conn, form, |_| 1), &mut base);
                let mut parts = CsrMatrix::zeros(plan.pattern().clone());
                plan.assemble_groups(
                    form,
                    1..3,
                    Some(&base),
                    kernel(&conn, form, |_| 1),
                    &mut parts,
                );
                assert_eq!(bits(&parts), bits(&old), "{form:?}: in parts");
                // and 0..2 then 2..3
                let mut base2 = CsrMatrix::zeros(plan.pattern().clone());
                plan.assemble_groups(form, 0..2, None, kernel(&conn, form, |_| 1), &mut base2);
                plan.assemble_groups(
                    form,
                    2..3,
                    Some(&base2),
                    kernel(&conn, form, |_| 1),
                    &mut parts,
                );
                assert_eq!(bits(&parts), bits(&old), "{form:?}: 0..2 then 2..3");

                // later groups changed: re-assembled onto the base of group 0
                let salt = |e: usize| if changed_later.contains(&e) { 2 } else { 1 };
                let new = whole(&salt);
                assert_ne!(bits(&new), bits(&old));
                let mut k = old.clone();
                plan.reassemble(
                    form,
                    &changed_later,
                    Some(&base),
                    kernel(&conn, form, salt),
                    &mut k,
                );
                assert_eq!(bits(&k), bits(&new), "{form:?}: re-assembled");
                // triangles changed too: no base
                let salt2 = |e: usize| {
                    if changed_tri.contains(&e) || changed_later.contains(&e) {
                        3
                    } else {
                        1
                    }
                };
                let new2 = whole(&salt2);
                let mut all_changed = changed_tri.clone();
                all_changed.extend(&changed_later);
                let mut k = old.clone();
                plan.reassemble(form, &all_changed, None, kernel(&conn, form, salt2), &mut k);
                assert_eq!(bits(&k), bits(&new2), "{form:?}: re-assembled from zero");
                results.push(bits(&new2));
            }
            // the vector assembly too
            let mut v = vec![f64::NAN; n];
            plan.assemble_vector(
                |e, out| {
                    for (a, x) in out.iter_mut().enumerate() {
                        *x = hash(e, a, 0, 5);
                    }
                },
                &mut v,
            );
            results.push(v.iter().map(|x| x.to_bits()).collect());
            results
        })
    };
    let one = run(1);
    assert!(one == run(2), "1 and 2 threads differ");
}
