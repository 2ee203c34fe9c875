//! Static condensation of the blocks' interiors (issue 6, "skip what a scene doesn't
//! need"): whole analyses with `faer-condensed` (the default backend) against
//! `faer-cholesky` (the whole matrix factorized), on scenes where the condensation pays
//! and on one where the backend decides it does not.
//!
//!     cargo bench --bench condensation -- [--reps 3] [--threads 2] [--cases a,b,...]
//!
//! Cases (`--cases`, default all but `column-capacity`):
//! * `column`, `column-fine`: the `column` example (six marble drums 0.8 × 1.0 m on a
//!   fixed base, contacts on their top and bottom faces only), drums meshed at 0.05 and
//!   0.025 m, gravity then 0.1 g lateral in 5 increments;
//! * `column-dynamic`: the same at 0.05 m, 1 s of a 0.15 g, 5 Hz sine ground motion
//!   (dt = 0.005 s);
//! * `column-capacity`: its lateral capacity at 0.05 m (a capacity search: thousands of
//!   factorizations; about a minute each);
//! * `tower`: a tower of 8 courses of one drum (alternate courses split in two, 12
//!   deformable blocks) 1 m × 8 m meshed at 0.04 m, gravity in 2 then 0.1 g in 10;
//! * `wall`: the built-in wall scaled to 12 × 12 deformable bricks meshed at 0.04 m,
//!   gravity then 0.3 g in 30 — contacts all round every brick: not condensed.
//!
//! Each case runs both backends alternately `--reps` times (configured as `dfem run`
//! configures them), and the table gives the split (interior and kept unknowns), S's
//! factorization against the whole matrix's in multiply-adds, whether it condensed, the
//! iterations and numeric factorizations, the analysis' wall time of each backend (every
//! run, and the median) and their ratio, and the largest difference of the final
//! unknowns relative to the largest one (max norm). Machine load: the load average
//! before and after.

use dfem::analysis::{self, Outcome};
use dfem::solve::{configure, LinearBackend};
use dfem_kernels::{max_relative_difference, Decision, FaerCholesky, FaerCholeskyCondensed};
use std::time::Instant;

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    let k = args.iter().position(|a| a == name)?;
    args.get(k + 1).cloned()
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "?".into())
}

fn tower() -> String {
    // the column example's model, marble and joint; its blocks replaced by the generator's
    let column = dfem::scene::examples::drum_column(0.05, "");
    let head = column
        .split("[[block]]")
        .next()
        .expect("the example has blocks");
    format!(
        "{head}[[generate]]\ntype = \"tower\"\nmaterial = \"marble\"\nkind = \"deformable\"\n\
         mesh_size = 0.04\nwidth = 1.0\nheight = 8.0\ncourses = 8\nblocks_per_course = 1\n\
         [contacts]\njoint = \"dry\"\n\
         [analysis]\ntype = \"static\"\nlateral = 0.1\nload_steps = 10\ngravity_steps = 2\n"
    )
}

fn wall() -> String {
    let w = dfem::scene::examples::scaled_wall(12, false);
    let head = w.split("[analysis]").next().expect("analysis table");
    format!(
        "{}[analysis]\ntype = \"static\"\nlateral = 0.3\nload_steps = 30\ngravity_steps = 5\n",
        head.replace("type = \"wall\"", "type = \"wall\"\nmesh_size = 0.04")
    )
}

fn case(name: &str) -> String {
    use dfem::scene::examples::drum_column;
    let lateral =
        "[analysis]\ntype = \"static\"\nlateral = 0.1\nload_steps = 5\ngravity_steps = 1\n";
    match name {
        "column" => drum_column(0.05, lateral),
        "column-fine" => drum_column(0.025, lateral),
        "column-dynamic" => drum_column(
            0.05,
            "[analysis]\ntype = \"dynamic\"\ndt = 0.005\nduration = 1.0\n\
             ground_motion = { expression = \"0.15*sin(31.4*t)\", units = \"g\" }\n",
        ),
        "column-capacity" => drum_column(0.05, "[analysis]\ntype = \"capacity\"\n"),
        "tower" => tower(),
        "wall" => wall(),
        other => panic!("unknown case '{other}'"),
    }
}

fn run(text: &str, backend: &mut dyn LinearBackend) -> (Outcome, f64) {
    let sc = dfem::scene::parse_str(text, None).expect("scene parses");
    let mesh = dfem::mesh::build(&sc);
    configure(backend, &mesh).expect("configure");
    let t = Instant::now();
    let out = analysis::run(&sc, &mesh, backend).expect("analysis runs");
    (out, t.elapsed().as_secs_f64())
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}

fn main() {
    let reps: usize = arg("--reps").map_or(3, |s| s.parse().expect("--reps N"));
    let threads: usize = arg("--threads").map_or(2, |s| s.parse().expect("--threads N"));
    let cases =
        arg("--cases").unwrap_or_else(|| "column,column-fine,column-dynamic,tower,wall".into());
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .expect("thread pool");
    println!("load average before: {}", load_average());
    println!(
        "| case | unknowns | interior / kept | S / whole (multiply-adds) | condensed | iterations | factorizations (whole / condensed) | whole (s) | condensed (s) | whole / condensed | max rel. difference |"
    );
    println!("|---|---:|---|---|---|---:|---|---|---|---:|---:|");
    for name in cases.split(',') {
        let text = case(name);
        let (mut tw, mut tc) = (Vec::new(), Vec::new());
        let mut last = None;
        for _ in 0..reps {
            let (w, t) = run(&text, &mut FaerCholesky::new());
            tw.push(t);
            let mut be = FaerCholeskyCondensed::new();
            let (c, t) = run(&text, &mut be);
            tc.push(t);
            last = Some((w, c, be.decision(), be.is_condensed()));
        }
        let (w, c, decision, condensed) = last.expect("reps ≥ 1");
        let (split, share) = match decision {
            Some(Decision {
                interior,
                kept,
                blocks,
                condensed_flops,
                whole_flops,
                ..
            }) => (
                format!("{interior} in {blocks} blocks / {kept}"),
                format!(
                    "{condensed_flops:.3e} / {whole_flops:.3e} ({:.2})",
                    condensed_flops / whole_flops
                ),
            ),
            None => ("0 / all".into(), "–".into()),
        };
        let iters = if w.stats.iterations == c.stats.iterations {
            w.stats.iterations.to_string()
        } else {
            format!("{} / {}", w.stats.iterations, c.stats.iterations)
        };
        let list = |v: &[f64]| {
            let s: Vec<String> = v.iter().map(|t| format!("{t:.3}")).collect();
            format!("{} ({:.3})", s.join(", "), median(v))
        };
        println!(
            "| {name} | {} | {split} | {share} | {condensed} | {iters} | {} / {} | {} | {} | {:.2} | {:.1e} |",
            w.u.len(),
            w.stats.factorizations,
            c.stats.factorizations,
            list(&tw),
            list(&tc),
            median(&tw) / median(&tc),
            max_relative_difference(&c.u, &w.u),
        );
    }
    println!("load average after: {}", load_average());
}
