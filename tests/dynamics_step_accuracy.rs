//! Accuracy of the dynamic driver at a ground-motion record's own sampling step
//! (docs/theory.md §5, "Stick–slip events"; docs/validation.md).
//!
//! A rigid 1 m × 0.5 m block on a fixed base (`common::box_on_base`) shaken by El Centro
//! 1940 N-S (0.02 s), with the default settings and `dt` = the record's step: its largest
//! slip against Newmark's (1965) rigid sliding block integrated here with 200 steps per
//! sample (`common::rigid_plastic_sliding_step`, converged: 10⁻⁴ s and 2·10⁻⁵ s agree to
//! 0.1 %). And halving the step moves the largest slip by less than the run's error
//! estimate (`step_error_sum` of the summary).
//!
//! The Imperial Valley 1979 record (El Centro Array #1, PEER `.AT2`, 0.005 s) may not be
//! redistributed: the ignored tests read it from the path in `DFEM_AT2_RECORD`.

mod common;
use common::col;
use std::time::Instant;

const G: f64 = 9.81;

/// A record (t s, a m/s²).
struct Record {
    file: String,
    format: &'static str,
    t: Vec<f64>,
    a: Vec<f64>,
    dt: f64,
}

fn el_centro() -> Record {
    let (file, t, a) = common::el_centro_record();
    Record {
        file: file.into(),
        format: "csv",
        t,
        a,
        dt: 0.02,
    }
}

/// A PEER `.AT2` record named by the environment variable `DFEM_AT2_RECORD` (PEER's terms
/// keep such records out of the repository), read here independently of dfem's parser.
fn at2_record() -> Option<Record> {
    let file = std::env::var("DFEM_AT2_RECORD").ok()?;
    let text = std::fs::read_to_string(&file).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let head = lines[3].to_uppercase();
    let dt: f64 = head
        .split("DT=")
        .nth(1)
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let a: Vec<f64> = lines[4..]
        .iter()
        .flat_map(|l| l.split_whitespace())
        .map(|x| x.parse::<f64>().unwrap() * G)
        .collect();
    let t = (0..a.len()).map(|k| k as f64 * dt).collect();
    Some(Record {
        file,
        format: "at2",
        t,
        a,
        dt,
    })
}

impl Record {
    fn duration(&self) -> f64 {
        *self.t.last().unwrap()
    }
    /// The reference: the largest slip (m) of the rigid sliding block, step `h` (s).
    fn reference(&self, mu: f64, h: f64) -> f64 {
        let f = |x: f64| common::interpolate(&self.t, &self.a, x);
        common::rigid_plastic_sliding_step(f, |_| 0.0, mu, self.duration(), h).0
    }
    /// dfem's largest slip (m) of the box, with `extra` `[analysis]` keys, the run's
    /// error estimate `step_error_sum` (m) and its run time (s).
    fn dfem(&self, mu: f64, dt: f64, extra: &str) -> (f64, f64, f64) {
        let text = common::box_on_base(
            mu,
            &format!(
                "[analysis]\ntype = \"dynamic\"\ndt = {dt}\nduration = {}\nground_motion = {{ file = \"{}\", format = \"{}\" }}\n{extra}\n",
                self.duration(),
                self.file,
                self.format
            ),
        );
        let start = Instant::now();
        let (_, out) = common::solve(&common::scene(&text));
        let time = start.elapsed().as_secs_f64();
        assert_eq!(out.status, dfem::analysis::Status::Stable);
        let h = out.history.expect("a dynamic run has a history");
        let ux = col(&h, "box.ux");
        let umax = ux.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        (umax, out.stats.step_error_sum, time)
    }
}

/// The largest slip with the default settings at the record's step, against the
/// reference, within 3 % (issue 46's target; a friction event located a step late, as
/// before the event cuts, was off by 16 % to 24 % on El Centro); and the slip at dt/2
/// differs from it by less than the error estimate of the run at dt.
fn check(rec: &Record, mu: f64) {
    check_at(rec, mu, rec.dt);
}

/// [`check`] at the step `dt` (s).
fn check_at(rec: &Record, mu: f64, dt: f64) {
    let reference = rec.reference(mu, 1e-4);
    let (u, estimate, _) = rec.dfem(mu, dt, "");
    let (u2, _, _) = rec.dfem(mu, dt / 2.0, "");
    let err = common::rel_err(u, reference);
    eprintln!(
        "{} μ = {mu}, dt = {dt}: {:.4} mm vs {:.4} mm, {:+.2} %; dt/2 moves it by {:.2e} m, estimate {estimate:.2e} m",
        rec.format,
        1e3 * u,
        1e3 * reference,
        100.0 * (u - reference) / reference,
        (u2 - u).abs()
    );
    assert!(err < 0.03, "{u} vs {reference}");
    assert!(
        (u2 - u).abs() < estimate,
        "{u2} vs {u}: estimate {estimate}"
    );
}

#[test]
fn el_centro_slip_at_the_record_step_mu_0_1() {
    check(&el_centro(), 0.1);
}

#[test]
fn el_centro_slip_at_the_record_step_mu_0_2() {
    check(&el_centro(), 0.2);
}

/// Imperial Valley 1979, El Centro Array #1 (0.005 s), μ = 0.05: `DFEM_AT2_RECORD`
/// names its `.AT2` file.
#[test]
#[ignore]
fn imperial_valley_slip_at_the_record_step() {
    let rec = at2_record().expect("DFEM_AT2_RECORD names the Imperial Valley .AT2 file");
    check(&rec, 0.05);
}

/// Other friction coefficients (μ ≥ 0.05) on both records (the second when
/// `DFEM_AT2_RECORD` names it).
#[test]
#[ignore]
fn other_friction_coefficients_at_the_record_step() {
    for mu in [0.05, 0.15] {
        check(&el_centro(), mu);
    }
    if let Some(rec) = at2_record() {
        for mu in [0.08, 0.1] {
            check(&rec, mu);
        }
    }
}

/// El Centro with μ = 0.3, just under its peak of 0.319 g: the block slips 16 μm in
/// 22 ms, about one step of the record, which the record's step does not resolve (−18 %
/// at 0.02 s and 0.01 s, with each integrator −13 % to −18 %:
/// docs/decisions/0036-stick-slip-events.md); within 3 % from a quarter of it, 5 ms.
#[test]
#[ignore]
fn el_centro_slip_of_one_record_step_mu_0_3() {
    let rec = el_centro();
    check_at(&rec, 0.3, rec.dt / 4.0);
}

/// The table of docs/decisions/0036-stick-slip-events.md: error and run time against
/// the step, per integrator (`DFEM_STUDY_INTEGRATORS`, comma-separated; extra
/// `[analysis]` keys in `DFEM_STUDY_EXTRA`; the friction coefficients of the rows, comma-
/// separated, in `DFEM_STUDY_EL_CENTRO_MUS` (default 0.1,0.2) and `DFEM_STUDY_AT2_MUS`
/// (the `.AT2` record's, default 0.05); the divisors of the record's step in
/// `DFEM_STUDY_DIVS`, default 1,2,4).
#[test]
#[ignore]
fn step_study_table() {
    let list = |key: &str, default: &str| -> Vec<f64> {
        std::env::var(key)
            .unwrap_or(default.into())
            .split(',')
            .filter(|m| !m.is_empty())
            .map(|m| m.parse().unwrap())
            .collect()
    };
    let mut rows: Vec<(Record, f64)> = list("DFEM_STUDY_EL_CENTRO_MUS", "0.1,0.2")
        .into_iter()
        .map(|mu| (el_centro(), mu))
        .collect();
    for mu in list("DFEM_STUDY_AT2_MUS", "0.05") {
        if let Some(r) = at2_record() {
            rows.push((r, mu));
        }
    }
    let divs = list("DFEM_STUDY_DIVS", "1,2,4");
    let integrators: Vec<String> = std::env::var("DFEM_STUDY_INTEGRATORS")
        .unwrap_or("hht,newmark,generalized-alpha".into())
        .split(',')
        .map(String::from)
        .collect();
    let extra = std::env::var("DFEM_STUDY_EXTRA").unwrap_or_default();
    for (rec, mu) in &rows {
        let r = rec.reference(*mu, 1e-4);
        let r2 = rec.reference(*mu, 2e-5);
        eprintln!(
            "{} mu {mu}: reference {:.3} mm (1e-4 s), {:.3} mm (2e-5 s)",
            rec.format,
            1e3 * r,
            1e3 * r2
        );
        for integ in &integrators {
            for &div in &divs {
                let dt = rec.dt / div;
                let (u, estimate, time) =
                    rec.dfem(*mu, dt, &format!("integrator = \"{integ}\"\n{extra}"));
                eprintln!(
                    "  {integ:>18} dt {dt:.5}: {:.3} mm, {:+.2} %, estimate {:.3} mm, {time:.2} s",
                    1e3 * u,
                    100.0 * (u - r2) / r2,
                    1e3 * estimate
                );
            }
        }
    }
}

/// The integrator table on rocking (docs/decisions/0036-stick-slip-events.md): the
/// slender block of tests/validation_dynamics.rs landing back on its heel, the ratio of
/// its angular velocities after and before the impact against Housner's (1963)
/// 1 − (3/2) sin²α, at 2, 1 and 0.5 ms, per integrator, with the run time.
#[test]
#[ignore]
fn rocking_integrator_table() {
    for integ in [
        "integrator = \"hht\"",
        "integrator = \"newmark\"",
        "integrator = \"generalized-alpha\"",
        "integrator = \"generalized-alpha\"\nrho_inf = 0.0",
    ] {
        for dt in [0.002, 0.001, 0.0005] {
            let start = Instant::now();
            let h = common::dynamic_history(&common::rocking_block(dt, integ));
            let time = start.elapsed().as_secs_f64();
            let r = common::rocking_impact(&h);
            eprintln!(
                "  {:>44} dt {dt}: tilt {:.4} rad, lands {}, ratio {:.4} vs {:.4}: {:+.2} %, {time:.2} s",
                integ.replace('\n', " "),
                r.p0,
                r.landed,
                r.ratio,
                r.housner,
                100.0 * (r.ratio / r.housner - 1.0)
            );
        }
    }
}
