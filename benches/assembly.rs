//! Assembly throughput (issue 6): the stiffness matrix of a deformable running-bond wall
//! (CST triangles and band contacts, `System::stiffness_into`, the call every secant
//! iteration makes) in triangles per second on 1 and 2 threads, against the memory
//! bandwidth of this machine measured in the same run (a STREAM-like triad) and a byte
//! count of what one assembly moves.
//!
//!     cargo bench --bench assembly -- [--courses 40] [--mesh 0.02] [--reps 7]
//!
//! Prints one table (median of `reps` assemblies after one warm-up). The byte model of an
//! assembly (kernels/src/assembly.rs: the element kernels fill one buffer, then every
//! stored entry sums its contributions through a gather map): per element slot, the
//! buffer is written and read (2 × 8 B; it is zeroed block by block just before its
//! kernel writes it, in cache) and its gather position read (8 B); per
//! stored entry of the matrix, the value written and its gather pointer read (2 × 8 B);
//! per triangle, its three nodes' coordinates and tDₑ read (6 × 8 + 9 × 8 B) and per
//! contact its geometry (about 64 B). The bound is the triad's bandwidth divided by that
//! count: no assembly of this design can beat it.

use dfem::assembly::{diagonal, System};
use dfem::material::ContactSprings;
use dfem_kernels::csr::CsrMatrix;
use rayon::prelude::*;
use std::time::Instant;

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

fn main() {
    let courses = arg("--courses", 40.0) as usize;
    let mesh_size = arg("--mesh", 0.02);
    let reps = arg("--reps", 7.0) as usize;
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
    let system = System::new(&scene, &mesh);
    let (nt, nc) = (mesh.triangles.len(), mesh.contacts.len());
    let local: Vec<_> = (0..nc)
        .map(|_| diagonal(ContactSprings { kn: 1e8, ks: 4e7 }))
        .collect();
    let pattern = system.plan.pattern().clone();
    let nnz = pattern.nnz();
    // element slots: 36 per triangle, (len_l + len_m)² per contact
    let slots: usize = (0..system.plan.n_elements())
        .map(|e| system.plan.connectivity().dofs(e).len().pow(2))
        .sum();
    let bytes = (slots * 3 * 8 + nnz * 2 * 8 + nt * (6 + 9) * 8 + nc * 64) as f64;
    println!(
        "# wall {courses} x {courses}, mesh {mesh_size} m: {nt} triangles, {nc} contacts, {} unknowns, {nnz} stored entries, {slots} element slots (meshed in {t_mesh:.1} s); {:.0} B moved per assembly ({:.0} B per triangle)",
        mesh.n_dofs,
        bytes,
        bytes / nt as f64
    );
    println!(
        "\n| threads | assembly (s) | triangles/s | elements/s | triad bandwidth (GB/s) | bandwidth bound (triangles/s) | of the bound |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    let mut first: Option<CsrMatrix> = None;
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut k = CsrMatrix::zeros(pattern.clone());
        let times: Vec<f64> = (0..reps + 1)
            .map(|_| {
                let t = Instant::now();
                pool.install(|| system.stiffness_into(&mesh, &local, &mut k));
                t.elapsed().as_secs_f64()
            })
            .skip(1)
            .collect();
        // the same matrix to the bit on any number of threads
        match &first {
            None => first = Some(k.clone()),
            Some(k1) => assert!(
                k1.values
                    .iter()
                    .zip(&k.values)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "the assembly depends on the thread count"
            ),
        }
        let time = median(times);
        let bw = triad_bandwidth(threads, 5);
        let bound = bw / (bytes / nt as f64);
        println!(
            "| {threads} | {time:.4} | {:.3e} | {:.3e} | {:.1} | {bound:.3e} | {:.0} % |",
            nt as f64 / time,
            (nt + nc) as f64 / time,
            bw / 1e9,
            100.0 * (nt as f64 / time) / bound
        );
    }
}
