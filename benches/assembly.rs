//! Assembly throughput (issue 6): the stiffness matrix of a deformable running-bond wall
//! (CST triangles and band contacts) in triangles per second on 1 and 2 threads, for the
//! design before issue 6's rework and for each path of the present one, against the memory
//! bandwidth of this machine measured in the same run (a STREAM-like triad) and a byte
//! count of what each path moves.
//!
//!     cargo bench --bench assembly -- [--courses 40] [--mesh 0.02] [--reps 7]
//!
//! Prints one table (median of `reps` assemblies after one warm-up) and the load average
//! before and after. The paths:
//!
//! * **old**: the design of commit 9cf55c2, rebuilt here as the baseline: every element
//!   matrix (the dense triple product Bᵀ(tD)B, tD stored per triangle) written into one
//!   element buffer, then every stored entry sums its contributions through a gather map
//!   of 8-byte positions and is averaged with its transpose. Bytes: per element slot the
//!   buffer written and read and its gather position read (3 × 8 B); per stored entry its
//!   sum written and read, its value written, its gather pointer and transpose position
//!   read (5 × 8 B); per triangle its nodes, coordinates and tD (12 + 48 + 72 B); per
//!   contact its geometry (about 150 B).
//! * **full** (`System::stiffness_full_into`, what `stiffness_into` does on a new
//!   geometry): each element's packed upper triangle scattered straight into the CSR
//!   values in the plan's colour order. Bytes: per element slot its 4-byte scatter
//!   position; per stored entry the value read and written once (2 × 8 B: chunks of
//!   consecutive elements keep an entry's additions in cache); per triangle its nodes and
//!   material (16 B) and per node its coordinates (16 B); per contact its geometry and
//!   local stiffness (about 150 B).
//! * **kept blocks + contacts** (`System::stiffness_into` on a geometry seen before, as
//!   every iteration of a static increment): a copy of the kept triangles' part (per
//!   stored entry 8 B read, 8 B written), the node positions compared with the kept ones
//!   (2 × 16 B per node), and the contacts scattered as in *full*.
//! * **update, 1 % changed** (`System::stiffness_update`): only the entries of the
//!   contacts whose local stiffness changed (every 100th contact switches between its
//!   elastic springs and zero, an opening), recomputed from the kept part and the
//!   contacts adding into them. Its bytes are those of the compared local stiffnesses and
//!   the node positions; its time is mostly fixed costs, so no bound is given.
//!
//! After the table, per thread count: the time of the kept path's copy alone (the same
//! parallel copy of the stored values), the contacts' share of the kept path (its time
//! less the copy) in contacts per second, and the update's time as a share of the full
//! and the kept paths.
//!
//! The bound of a path is the triad's bandwidth divided by its bytes per triangle: no
//! assembly that moves those bytes can beat it. Every path's matrix is checked: the same
//! to the bit on 1 and 2 threads and on every path of the present design, and within
//! 1e-12 (relative to the largest entry of its row) of the old design's.

use dfem::assembly::{contact_map, contact_stiffness, cst_b, diagonal, LocalStiffness, System};
use dfem::material::ContactSprings;
use dfem::mesh::Mesh;
use dfem_kernels::csr::CsrMatrix;
use dfem_kernels::{Connectivity, CsrPattern, CONSTRAINED};
use rayon::prelude::*;
use std::time::Instant;

/// Values per rayon task of the kept part's copy, as `AssemblyPlan::assemble_groups` copies
/// its base (2,048 rows × 8).
const COPY_TASK: usize = 16384;

fn arg(name: &str, default: f64) -> f64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|k| args.get(k + 1))
        .map(|v| v.parse().unwrap_or_else(|_| panic!("{name}: a number")))
        .unwrap_or(default)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v[v.len() / 2]
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "?".into())
}

/// Triad a = b + s c over 3 × 2²⁵ doubles (800 MB): bytes moved per second (3 × 8 B per
/// entry; write-allocate traffic not counted, as STREAM does not).
fn triad_bandwidth(threads: usize, reps: usize) -> f64 {
    let n = 1usize << 25;
    let b = vec![1.0f64; n];
    let c = vec![2.0f64; n];
    let mut a = vec![0.0f64; n];
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let times: Vec<f64> = (0..reps + 1)
        .map(|_| {
            let t = Instant::now();
            pool.install(|| {
                a.par_chunks_mut(1 << 16)
                    .zip(b.par_chunks(1 << 16))
                    .zip(c.par_chunks(1 << 16))
                    .for_each(|((a, b), c)| {
                        for i in 0..a.len() {
                            a[i] = b[i] + 3.0 * c[i];
                        }
                    })
            });
            t.elapsed().as_secs_f64()
        })
        .skip(1)
        .collect();
    assert!(a[n / 2] == 7.0);
    (3 * 8 * n) as f64 / median(times)
}

/// The assembly design before issue 6's rework (commit 9cf55c2), rebuilt as the bench's
/// baseline: element buffer, gather map of 8-byte positions in ascending element order,
/// symmetrised with the transpose's sum; its CST kernel the dense triple product with tD
/// stored per triangle.
mod old {
    use super::*;

    pub struct GatherPlan {
        offset: Vec<usize>,
        gather_ptr: Vec<usize>,
        gather_pos: Vec<usize>,
        transpose: Vec<usize>,
        buf: Vec<f64>,
        sums: Vec<f64>,
    }

    impl GatherPlan {
        pub fn new(conn: &Connectivity, pattern: &CsrPattern) -> Self {
            let n_el = conn.len();
            let mut offset = vec![0];
            let mut end = 0;
            for e in 0..n_el {
                end += conn.dofs(e).len().pow(2);
                offset.push(end);
            }
            // (entry, buffer position) for every live slot pair, then a stable counting
            // sort by entry: ascending element, then slot, within each entry
            let nnz = pattern.nnz();
            let mut pairs = Vec::new();
            for (e, &start) in offset[..n_el].iter().enumerate() {
                let d = conn.dofs(e);
                for (a, &i) in d.iter().enumerate() {
                    for (b, &j) in d.iter().enumerate() {
                        if i != CONSTRAINED && j != CONSTRAINED {
                            let k = pattern.find(i as usize, j as usize).unwrap();
                            pairs.push((k, start + a * d.len() + b));
                        }
                    }
                }
            }
            let mut gather_ptr = vec![0usize; nnz + 1];
            for &(k, _) in &pairs {
                gather_ptr[k + 1] += 1;
            }
            for k in 0..nnz {
                gather_ptr[k + 1] += gather_ptr[k];
            }
            let mut fill = gather_ptr.clone();
            let mut gather_pos = vec![0; pairs.len()];
            for &(k, p) in &pairs {
                gather_pos[fill[k]] = p;
                fill[k] += 1;
            }
            let rp = pattern.row_ptr();
            let transpose = (0..pattern.n())
                .flat_map(|i| (rp[i]..rp[i + 1]).map(move |k| (i, k)))
                .map(|(i, k)| pattern.find(pattern.col_idx()[k] as usize, i).unwrap())
                .collect();
            Self {
                buf: vec![0.0; offset[n_el]],
                sums: vec![0.0; nnz],
                offset,
                gather_ptr,
                gather_pos,
                transpose,
            }
        }

        pub fn assemble<F: Fn(usize, &mut [f64]) + Sync>(&mut self, kernel: F, out: &mut [f64]) {
            let offset = &self.offset;
            let n_el = offset.len() - 1;
            let mut pieces = Vec::new();
            let mut rest: &mut [f64] = &mut self.buf;
            let mut e0 = 0;
            while e0 < n_el {
                let e1 = (e0 + 256).min(n_el);
                let (head, tail) = rest.split_at_mut(offset[e1] - offset[e0]);
                pieces.push((e0, head));
                rest = tail;
                e0 = e1;
            }
            pieces.into_par_iter().for_each(|(e0, piece)| {
                for e in e0..(e0 + 256).min(n_el) {
                    let block = &mut piece[offset[e] - offset[e0]..offset[e + 1] - offset[e0]];
                    block.fill(0.0);
                    kernel(e, block);
                }
            });
            let (ptr, pos, buf) = (&self.gather_ptr, &self.gather_pos, &self.buf);
            self.sums
                .par_chunks_mut(2048)
                .enumerate()
                .for_each(|(c, chunk)| {
                    for (j, o) in chunk.iter_mut().enumerate() {
                        let k = c * 2048 + j;
                        *o = pos[ptr[k]..ptr[k + 1]].iter().map(|&p| buf[p]).sum();
                    }
                });
            let (sums, t) = (&self.sums, &self.transpose);
            out.par_chunks_mut(2048).enumerate().for_each(|(c, chunk)| {
                for (j, v) in chunk.iter_mut().enumerate() {
                    let k = c * 2048 + j;
                    *v = 0.5 * (sums[k] + sums[t[k]]);
                }
            });
        }
    }

    /// The old element kernel: Kₑ = A Bᵀ (tD) B as dense products, tD per triangle.
    pub fn kernel<'a>(
        mesh: &'a Mesh,
        tri_dt: &'a [[[f64; 3]; 3]],
        local: &'a [LocalStiffness],
    ) -> impl Fn(usize, &mut [f64]) + Sync + 'a {
        let nt = mesh.triangles.len();
        move |e, ke| {
            if e < nt {
                let (b, area) = cst_b(mesh.triangles[e].map(|n| mesh.nodes[n as usize]));
                let dt = &tri_dt[e];
                let mut db = [[0.0; 6]; 3];
                for i in 0..3 {
                    for j in 0..6 {
                        db[i][j] = dt[i][0] * b[0][j] + dt[i][1] * b[1][j] + dt[i][2] * b[2][j];
                    }
                }
                for i in 0..6 {
                    for j in 0..6 {
                        ke[6 * i + j] =
                            area * (b[0][i] * db[0][j] + b[1][i] * db[1][j] + b[2][i] * db[2][j]);
                    }
                }
            } else {
                let map = contact_map(mesh, &mesh.contacts[e - nt]);
                contact_stiffness(&map.g[..map.len], &local[e - nt], ke);
            }
        }
    }
}

fn same_bits(a: &CsrMatrix, b: &CsrMatrix) -> bool {
    a.values
        .iter()
        .zip(&b.values)
        .all(|(x, y)| x.to_bits() == y.to_bits())
}

/// Largest |a − b| over an entry's row, relative to the row's largest |entry|.
fn row_relative_difference(a: &CsrMatrix, b: &[f64]) -> f64 {
    let rp = a.pattern.row_ptr();
    (0..a.n())
        .map(|i| {
            let r = rp[i]..rp[i + 1];
            let scale = a.values[r.clone()]
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()));
            let d = r.fold(0.0f64, |m, k| m.max((a.values[k] - b[k]).abs()));
            if scale > 0.0 {
                d / scale
            } else {
                d
            }
        })
        .fold(0.0, f64::max)
}

fn main() {
    let courses = arg("--courses", 40.0) as usize;
    let mesh_size = arg("--mesh", 0.02);
    let reps = arg("--reps", 7.0) as usize;
    let load_before = load_average();
    // the built-in wall example, n × n bricks, meshed
    let text = dfem::scene::examples::get("wall")
        .expect("the wall example")
        .replace("courses = 10", &format!("courses = {courses}"))
        .replace(
            "bricks_per_course = 5",
            &format!("bricks_per_course = {courses}\nmesh_size = {mesh_size}"),
        );
    let scene = dfem::scene::parse_str(&text, None).expect("the bench's scene");
    let t = Instant::now();
    let mesh = dfem::mesh::build(&scene);
    let t_mesh = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let system = System::new(&scene, &mesh);
    let t_plan = t.elapsed().as_secs_f64();
    let plan = &system.plan;
    let (nt, nc) = (mesh.triangles.len(), mesh.contacts.len());
    let elastic = diagonal(ContactSprings { kn: 1e8, ks: 4e7 });
    let local: Vec<LocalStiffness> = vec![elastic; nc];
    // every 100th contact opens (and closes again at the next update)
    let opened: Vec<LocalStiffness> = (0..nc)
        .map(|c| if c % 100 == 0 { [[0.0; 2]; 2] } else { elastic })
        .collect();
    let pattern = plan.pattern().clone();
    let nnz = pattern.nnz();
    let n_nodes = mesh.nodes.len() as f64;
    let slots_t = plan.map_len(0);
    let slots_c = plan.map_len(1);
    let entries_c = plan.entries_of_group(1);
    let (nt_f, nc_f) = (nt as f64, nc as f64);
    // bytes per assembly of each path (the models of the header)
    let bytes_old = (slots_t + slots_c) as f64 * 24.0
        + nnz as f64 * 40.0
        + nt_f * (12.0 + 48.0 + 72.0)
        + nc_f * 150.0;
    let contacts_part = slots_c as f64 * 4.0 + entries_c as f64 * 16.0 + nc_f * 150.0;
    let bytes_full =
        slots_t as f64 * 4.0 + (nnz as f64) * 16.0 + nt_f * 16.0 + n_nodes * 16.0 + contacts_part;
    let bytes_kept = nnz as f64 * 16.0 + n_nodes * 32.0 + contacts_part;
    println!(
        "# wall {courses} x {courses}, mesh {mesh_size} m: {nt} triangles, {nc} contacts, {} unknowns, {nnz} stored entries ({entries_c} of them touched by contacts), {slots_t} + {slots_c} scatter positions; meshed in {t_mesh:.1} s, plan in {t_plan:.2} s; colours: {} (triangles) + {} (contacts)",
        mesh.n_dofs,
        plan.n_colours(0),
        plan.n_colours(1),
    );
    println!(
        "# bytes per triangle: old {:.0}, full {:.0}, kept blocks + contacts {:.0}",
        bytes_old / nt_f,
        bytes_full / nt_f,
        bytes_kept / nt_f
    );
    let t = Instant::now();
    let tri_dt: Vec<[[f64; 3]; 3]> = (0..nt).map(|t| *system.tri_dt(t)).collect();
    let mut old_plan = old::GatherPlan::new(plan.connectivity(), &pattern);
    println!("# old plan in {:.2} s", t.elapsed().as_secs_f64());

    println!(
        "\n| path | threads | assembly (s) | triangles/s | elements/s | triad (GB/s) | bound (triangles/s) | of the bound | speed-up over old |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut reference: Option<CsrMatrix> = None;
    let mut notes = Vec::new();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let time = |f: &mut (dyn FnMut(usize) + Send)| -> f64 {
            median(
                (0..reps + 1)
                    .map(|r| {
                        let t = Instant::now();
                        pool.install(|| f(r));
                        t.elapsed().as_secs_f64()
                    })
                    .skip(1)
                    .collect(),
            )
        };
        let mut k_old = vec![0.0; nnz];
        let t_old =
            time(&mut |_| old_plan.assemble(old::kernel(&mesh, &tri_dt, &local), &mut k_old));
        let mut k_full = CsrMatrix::zeros(pattern.clone());
        let t_full = time(&mut |_| system.stiffness_full_into(&mesh, &local, &mut k_full));
        let mut k_kept = CsrMatrix::zeros(pattern.clone());
        // the second call on a geometry keeps the triangles' part
        for _ in 0..2 {
            pool.install(|| system.stiffness_into(&mesh, &local, &mut k_kept));
        }
        let t_kept = time(&mut |_| system.stiffness_into(&mesh, &local, &mut k_kept));
        // the kept path's copy of the triangles' part alone, as it does it: the rest of
        // its time is the contacts'
        let kept_part = k_kept.values.clone();
        let mut copy = vec![0.0; nnz];
        let t_copy = time(&mut |_| {
            copy.par_chunks_mut(COPY_TASK)
                .zip(kept_part.par_chunks(COPY_TASK))
                .for_each(|(o, b)| o.copy_from_slice(b))
        });
        // the update alternates between the elastic and the opened local stiffnesses, so
        // that every call changes 1 % of the contacts; after an even number of calls it
        // holds the elastic matrix again
        let mut k_upd = k_kept.clone();
        let mut calls = 0;
        let t_upd = time(&mut |r| {
            let (prev, next) = if r % 2 == 0 {
                (&local, &opened)
            } else {
                (&opened, &local)
            };
            system.stiffness_update(&mesh, prev, next, &mut k_upd);
            calls += 1;
        });
        if calls % 2 == 1 {
            system.stiffness_update(&mesh, &opened, &local, &mut k_upd);
        }
        let mut k_open = CsrMatrix::zeros(pattern.clone());
        system.stiffness_full_into(&mesh, &opened, &mut k_open);
        let mut k_open_upd = k_upd.clone();
        system.stiffness_update(&mesh, &local, &opened, &mut k_open_upd);

        // the same matrix to the bit on every path and thread count; the old design's
        // to round-off
        for (name, k) in [("kept", &k_kept), ("update", &k_upd)] {
            assert!(same_bits(&k_full, k), "{name} differs from full");
        }
        assert!(same_bits(&k_open, &k_open_upd), "update to opened");
        match &reference {
            None => reference = Some(k_full.clone()),
            Some(k1) => assert!(same_bits(k1, &k_full), "depends on the thread count"),
        }
        let diff = row_relative_difference(&k_full, &k_old);
        assert!(diff < 1e-12, "old and new designs differ by {diff:e}");

        let bw = triad_bandwidth(threads, 5);
        for (name, t, bytes) in [
            ("old (element buffer + gather)", t_old, Some(bytes_old)),
            ("full (colour-ordered scatter)", t_full, Some(bytes_full)),
            ("kept blocks + contacts", t_kept, Some(bytes_kept)),
            ("update, 1 % of contacts changed", t_upd, None),
        ] {
            let bound = bytes.map(|b| bw / (b / nt_f));
            println!(
                "| {name} | {threads} | {t:.4} | {:.3e} | {:.3e} | {:.1} | {} | {} | {:.2} |",
                nt_f / t,
                (nt_f + nc_f) / t,
                bw / 1e9,
                bound.map_or("–".into(), |b| format!("{b:.3e}")),
                bound.map_or("–".into(), |b| format!("{:.0} %", 100.0 * nt_f / t / b)),
                t_old / t
            );
        }
        let t_contacts = t_kept - t_copy;
        notes.push(format!(
            "# {threads} thread(s): copy of the kept triangles' part {t_copy:.4} s; contacts alone (kept - copy) {t_contacts:.4} s = {:.3e} contacts/s; update of 1 % of the contacts = {:.1} % of full, {:.1} % of kept blocks + contacts",
            nc_f / t_contacts,
            100.0 * t_upd / t_full,
            100.0 * t_upd / t_kept
        ));
    }
    for line in &notes {
        println!("{line}");
    }
    println!(
        "\n# load average before: {load_before}; after: {}",
        load_average()
    );
}
