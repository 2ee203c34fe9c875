//! Arc-length path following of a push (`[analysis] path = "arc_length"`; docs/theory.md,
//! "Arc length"): Crisfield's (1981) cylindrical arc length. The pushed rigid block is no
//! longer moved by prescribed increments: it carries the force λ P̂ (N), P̂ the unit vector
//! of `push_displacement`'s non-zero components, and λ is an unknown of every increment,
//! fixed by the constraint that the increment Δu of the free unknowns has the length Δl:
//!
//! ```text
//! ‖Δu‖² = n Δl²                                            (theory.md, Eq. A1)
//! ```
//!
//! (‖·‖ the Euclidean norm over the n free unknowns, so Δl is their root-mean-square
//! increment, m). Each iteration solves K δu_r = r and K δu_P = P̂ with the tangent matrix
//! K (the contacts' tangents by finite differences of their laws, LU; the secant matrix
//! where the tangent step does not lower the out-of-balance force), and δλ is the root of
//! the quadratic Eq. A1 for Δu + δu_r + δλ δu_P that keeps the increment closest in
//! direction to its previous iterate (Crisfield's angle criterion).
//! The load can fall while the displacement grows, and both can fall together: the
//! path is followed through limit points of the load and through snap-backs, where
//! displacement control has no solution in the neighbourhood of the last converged state.
//!
//! With `path = "dissipation"` the cylinder holds until the contacts start to spend
//! energy; then λ is fixed by the energy the increment spends against the softening and
//! hardening strengths of the contacts (docs/theory.md, "Dissipation-based arc length";
//! Gutiérrez 2004, Verhoosel, Remmers and Gutiérrez 2009):
//!
//! ```text
//! Σ_contacts A (G Δξ + σ̄(κ₃) Δκ₃) = Δτ                           (theory.md, Eq. A2)
//! ```
//!
//! (J; [`crate::material::Softening::softening_work`], docs/theory.md §3 for the law), a local
//! constraint: only the contacts where a crack grows or a toe crushes take part, where the
//! cylinder measures all unknowns and lets a local snap-back or an elastic mode pass.
//! An increment whose dissipation constraint cannot be met falls back to displacement
//! control of the pushed block, P̂ · Δu = Δa (theory.md, Eq. A3), then to the cylinder,
//! before the step is cut; an increment that would end with a pull on the block (λ < 0,
//! the foot of a snap-back) is not taken, and the block is pushed on from there.
//!
//! The block's rotation is held as under displacement control, and so is any translation
//! whose `push_displacement` component is 0 (its increment pinned to zero, its force a
//! reaction); a vertical motion left free (`push_displacement` a number) stays free.
//!
//! This module is a child of [`super`] (the static driver), whose state it advances.

use super::*;

mod path_step;

/// Changes of state of a contact within one arc-length increment after which it is
/// frozen at the chord of its law from its committed force (the contact-state corrector,
/// docs/theory.md, Eq. F1): contacts at the kinks of their laws otherwise alternate sides
/// at every iteration (docs/decisions/0027-contact-state-corrector-and-chords.md).
pub(super) const FLIP_LIMIT: u32 = 3;

pub use crate::scene::settings::ArcLength;

/// The set-up of the arc-length push: the unknowns of the block, P̂ and the pins.
struct Setup {
    /// Unit load vector P̂ over all unknowns (N per unit λ).
    p: Vec<f64>,
    /// First unknown of the block and the direction P̂ in the plane.
    first: usize,
    dir: Point,
    /// The end of the path: the displacement along P̂ (m).
    target: f64,
}

fn setup(d: &Driver, push: &Push) -> Setup {
    let crate::mesh::BlockDofs::Rigid { first, .. } = d.cur.blocks[push.block].dofs else {
        unreachable!("the scene reader admits rigid pushed blocks only")
    };
    let f = first as usize;
    let (dir, target) = push.direction();
    let mut p = vec![0.0; d.cur.n_dofs];
    p[f] = dir[0];
    p[f + 1] = dir[1];
    Setup {
        p,
        first: f,
        dir,
        target,
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The constraint that fixes the load factor of an increment.
#[derive(Debug, Clone, Copy)]
enum Constraint {
    /// ‖Δu‖² = n Δl² (Eq. A1): the value n Δl² (m²).
    Cylinder(f64),
    /// The energy the contacts dissipate in the increment, Σ ΔD = Δτ (Eq. A2): Δτ (J).
    Dissipation(f64),
    /// The increment of the pushed block's displacement along P̂, P̂ · Δu = Δa (Eq. A3,
    /// displacement control of the block with λ its force): Δa (m).
    Push(f64),
}

/// The constraints of [`Constraint`] without their values, in the order of the counts
/// of [`run()`].
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Cylinder = 0,
    Dissipation = 1,
    Push = 2,
}

/// A dissipation-controlled increment is accepted at its predictor only when the
/// predictor is in equilibrium and dissipates at least this fraction of Δτ: an increment
/// that dissipates nothing would let the path turn back along an elastic mode (on the
/// Eindhoven wall the cylinder accepted 4,000 such increments without moving the beam).
const PREDICTOR_DISSIPATION: f64 = 0.5;

/// The least scale of the last increment in a dissipation-controlled predictor: as
/// small as Δτ's least value against its largest (2⁻¹² with `max_cuts` = 6), so that
/// cutting Δτ shortens the predictor (with a floor of ¼ the cuts on J7D's snap-back left
/// the predictor, and its out-of-balance force of 7·10⁻³, unchanged).
const PREDICTOR_LEAST_SCALE: f64 = 1.0 / 4096.0;

/// The switch from the cylinder to the dissipation constraint: after the first converged
/// increment whose dissipated energy exceeds this fraction of the work of the push in it
/// (or any increment past a peak, where the push's work is not positive and the
/// contacts still dissipate). Verhoosel et al. (2009) switch at a threshold of the
/// dissipation itself; a fraction of the work does not depend on the units or the size
/// of the model.
const SWITCH_FRACTION: f64 = 0.1;

/// The failed checks of Eq. F2 in a row, each with the true laws' out-of-balance force
/// within [`CHECK_SAME`] of the one before, after which the increment has failed: the
/// chords can lead back to a point where the iterate does not move; a check that raises
/// the force is not such a repeat (docs/decisions/0027-contact-state-corrector-and-chords.md).
const CHECK_LIMIT: usize = 10;

/// The relative difference (of the out-of-balance force with the true laws) within
/// which two checks of Eq. F2 in a row count as the same point ([`CHECK_LIMIT`]).
const CHECK_SAME: f64 = 1e-3;

/// The secant iterations on δλ of the dissipation constraint in one correction.
const SECANT_STEPS: usize = 4;

/// A correction on the arc ([`Driver::corrector`]): the norm of the out-of-balance force
/// after it (N), the new increment of the unknowns, its δλ (N) and the trial there.
type Correction = (f64, Vec<f64>, f64, Trial);

/// The iterate of a failed increment with the least out-of-balance force under the
/// true laws (no contact frozen), kept for `accept_residual` ([`ArcLength::accept`]).
struct Unconverged {
    /// Its relative out-of-balance force.
    residual: f64,
    trial: Trial,
    /// Its Δλ (N).
    dlam: f64,
}

impl Unconverged {
    /// Keep `trial` in `best` if it is better than the one there.
    fn keep(best: &mut Option<Box<Unconverged>>, residual: f64, trial: &Trial, dlam: f64) {
        if best.as_ref().is_none_or(|b| residual < b.residual) {
            *best = Some(Box::new(Unconverged {
                residual,
                trial: trial.clone(),
                dlam,
            }));
        }
    }
}

/// Why an arc-length increment failed.
enum StepFailure {
    /// Not converged: the relative out-of-balance force left, and the best iterate
    /// with the true laws when `accept_residual` is set.
    NoConvergence(f64, Option<Box<Unconverged>>),
    /// The constraint has no real root for any δλ near the path.
    Divergence,
    /// With `path = "dissipation"`: the increment ends with a pull on the pushed block.
    Pulls,
}

/// The frozen law (Eq. F1) of a contact whose law gives the force `f` (N) and the state
/// `state` at the increment `d` (m) from its committed force `f0` (N): the chord from
/// (0, `f0`) to (`d`, `f`), each component on its own, the elastic spring `springs`
/// where that component has not moved. The chord lies between the slopes on the two
/// sides of a kink the contact has crossed, so that the new chords of Eq. F2
/// close in on the kink as by regula falsi: at the peak of the snap-back joint of
/// tests/validation_softening.rs (c) the tangent of either side cycled, and J7D with the
/// tangent in place of the chord stopped where it had stopped without the corrector
/// (2.088 mm).
///
/// Each slope is bounded by the component's elastic spring, |T_jj| ≤ k_j (the law's
/// slopes along a component lie within ±k_j: its stiffest response is the elastic one,
/// and the softening slopes of the walls' joints, about fₜ²/G_f^I per unit area, are
/// far below it). A component whose force moved with the other one — a slipping
/// joint's shear force following μ Fₙ as the joint closes or opens, over a slip of
/// 10⁻¹¹ m — otherwise gets a chord far stiffer than any slope of the law (7.5·10¹³ N/m
/// against kₛ = 4·10⁸ N/m in the unit test below), with which the frozen laws meet
/// equilibrium by moving the contact a negligible distance while the true law does not
/// follow, and the checks of Eq. F2 return to the same point. With the bound J4D
/// converges in 14 % fewer iterations to the same curve and J7D goes on down its
/// softening branch (docs/decisions/0027-contact-state-corrector-and-chords.md). A bounded slope keeps the
/// frozen law through (`d`, `f`), so the check at the point reached still reads the
/// true force there.
fn chord_law(
    springs: crate::material::ContactSprings,
    f0: [f64; 2],
    d: [f64; 2],
    f: [f64; 2],
    state: ContactState,
) -> Frozen {
    let chord = |j: usize, k0: f64| {
        if d[j].abs() > 1e-9 * (f0[j].abs() / k0).max(1e-15) {
            ((f[j] - f0[j]) / d[j]).clamp(-k0, k0)
        } else {
            k0
        }
    };
    Frozen {
        d,
        f,
        t: [[chord(0, springs.kn), 0.0], [0.0, chord(1, springs.ks)]],
        state,
    }
}

/// The tangent (N/m, in the contact's frame: rows (Fₙ, Fₛ), columns (δₙ, δₛ)) of
/// contact `k`'s law at the increment of relative displacement `d` (m) where it gives
/// the force `base` (N), by forward differences of the law's return from the committed
/// state: ∂F/∂δ ≈ (F(Δδ + ε eⱼ) − F(Δδ)) / ε, ε = 10⁻⁷ of the band's elastic
/// displacement at its strength scale or of the increment, whichever is larger.
fn law_tangent(
    laws: &PerContact<JointLaw>,
    areas: &[f64],
    committed: &Committed,
    k: usize,
    d: [f64; 2],
    base: [f64; 2],
) -> crate::assembly::LocalStiffness {
    let law = laws.get(k);
    let a = areas[k];
    let sp = law.springs(a);
    let f0 = committed.force[k];
    let h = committed.history.get(k).copied().unwrap_or([0.0; 2]);
    let scale = [
        (f0[0].abs() / sp.kn).max(d[0].abs()).max(1e-12),
        (f0[1].abs() / sp.ks).max(d[1].abs()).max(1e-12),
    ];
    let mut t = [[0.0; 2]; 2];
    for j in 0..2 {
        let eps = 1e-7 * scale[j];
        let mut dd = d;
        dd[j] += eps;
        let (f, _, _) = law.update_history(a, f0, h, dd);
        t[0][j] = (f[0] - base[0]) / eps;
        t[1][j] = (f[1] - base[1]) / eps;
    }
    t
}

impl Driver<'_> {
    /// The energy (J) the contacts spend from the committed state to `trial` against the
    /// strengths that soften or harden with their history (Eq. A2,
    /// [`crate::material::Softening::softening_work`]; nothing for the laws without
    /// history), summed in contact order whatever the number of threads.
    fn dissipated(&self, trial: &Trial) -> f64 {
        (0..self.area.len())
            .map(|k| match self.law.get(k) {
                crate::material::JointLaw::Softening(m) => m.softening_work(
                    self.area[k],
                    self.committed.history.get(k).copied().unwrap_or([0.0; 2]),
                    trial.history.get(k).copied().unwrap_or([0.0; 2]),
                    trial.state[k],
                ),
                crate::material::JointLaw::MohrCoulomb(_) => 0.0,
            })
            .sum()
    }

    /// `DFEM_TRACE`: how many contacts spend energy in the increment to `trial` (Eq. A2)
    /// and the four that spend the most, with their increments of ξ and κ₃, of relative
    /// displacement (Δδₙ, Δδₛ) (m), their forces (N) and nodes (m).
    fn trace_spending(&self, trial: &Trial) {
        let mut spent: Vec<(usize, f64)> = Vec::new();
        for k in 0..self.area.len() {
            if let crate::material::JointLaw::Softening(m) = self.law.get(k) {
                let h0 = self.committed.history.get(k).copied().unwrap_or([0.0; 2]);
                let h1 = trial.history.get(k).copied().unwrap_or([0.0; 2]);
                let w = m.softening_work(self.area[k], h0, h1, trial.state[k]);
                if w > 0.0 {
                    spent.push((k, w));
                }
            }
        }
        let total: f64 = spent.iter().map(|s| s.1).sum();
        spent.sort_by(|a, b| b.1.total_cmp(&a.1));
        // the work done on the contacts less the change of their elastic energy: what
        // they dissipate in all, friction included (J)
        let mut plastic = 0.0;
        for k in 0..self.area.len().min(trial.rel.len()) {
            let sp = self.law.get(k).springs(self.area[k]);
            let f0 = self.committed.force.get(k).copied().unwrap_or([0.0; 2]);
            let f1 = trial.force[k];
            let d = trial.rel[k];
            for (i, kk) in [sp.kn, sp.ks].into_iter().enumerate() {
                plastic +=
                    0.5 * (f0[i] + f1[i]) * d[i] - (f1[i] * f1[i] - f0[i] * f0[i]) / (2.0 * kk);
            }
        }
        // where: the joints of the lowest and the highest contact rows (a base and a
        // loading beam), the strong joints (brick cracks: fₜ > 1 MPa) and the rest (J)
        let (lo, hi) = self
            .cur
            .contacts
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), c| {
                let y = self.cur.nodes[c.node_m as usize][1];
                (a.min(y), b.max(y))
            });
        let mut by = [0.0; 4];
        for &(k, w) in &spent {
            let y = self.cur.nodes[self.cur.contacts[k].node_m as usize][1];
            let strong = matches!(self.law.get(k), crate::material::JointLaw::Softening(m) if m.tensile_strength > 1e6);
            let i = if (y - lo).abs() < 1e-3 {
                0
            } else if (y - hi).abs() < 1e-3 {
                1
            } else if strong {
                2
            } else {
                3
            };
            by[i] += w;
        }
        eprintln!(
            "arc spending: {} contacts spend {total:.3e} J (lowest row {:.2e}, highest row {:.2e}, strong joints {:.2e}, the rest {:.2e}); all the contacts dissipate {plastic:.3e} J",
            spent.len(), by[0], by[1], by[2], by[3]
        );
        for &(k, w) in spent.iter().take(4) {
            let h0 = self.committed.history.get(k).copied().unwrap_or([0.0; 2]);
            let h1 = trial.history.get(k).copied().unwrap_or([0.0; 2]);
            if let Some(c) = self.cur.contacts.get(k) {
                eprintln!(
                    "  contact {k} at {:?} spends {w:.3e} J (Δξ {:.2e}, Δκ₃ {:.2e} m, {:?}), force {:?}, Δδ {:?}",
                    self.cur.nodes[c.node_m as usize],
                    h1[0] - h0[0],
                    h1[1] - h0[1],
                    trial.state[k],
                    trial.force[k],
                    trial.rel.get(k)
                );
            }
        }
    }

    /// The load-factor correction δλ (N) along the line `w` + δλ `dp` on which the
    /// contacts dissipate Δτ = `tau` (J) in the increment: secant iterations from δλ = 0
    /// and a trial step that moves the increment by 10⁻³ of its length. `None` when the
    /// dissipation does not change along the line.
    fn dissipation_root(&self, w: &[f64], dp: &[f64], tau: f64) -> Option<f64> {
        let zero = vec![[0.0; 2]; self.cur.blocks.len()];
        let g = |x: f64| {
            let cand: Vec<f64> = w.iter().zip(dp).map(|(a, b)| a + x * b).collect();
            self.dissipated(&self.trial(&cand, &zero)) - tau
        };
        let scale = (dot(w, w) / dot(dp, dp).max(1e-300)).sqrt();
        let (mut x0, mut g0) = (0.0, g(0.0));
        let mut x1 = 1e-3 * scale.max(1e-300);
        let mut g1 = g(x1);
        for _ in 0..SECANT_STEPS {
            if (g1 - g0).abs() <= 1e-14 * tau.abs().max(g0.abs()) {
                break;
            }
            let x2 = x1 - g1 * (x1 - x0) / (g1 - g0);
            if !x2.is_finite() {
                return None;
            }
            (x0, g0) = (x1, g1);
            x1 = x2;
            g1 = g(x1);
            if g1.abs() <= 1e-3 * tau {
                return Some(x1);
            }
        }
        (g1.abs() < g0.abs().min(tau)).then_some(x1)
    }

    /// The tangent of every contact's law at the trial (N/m, in the contact's frame:
    /// rows (Fₙ, Fₛ), columns (δₙ, δₛ)), by forward differences of the law's return
    /// from the committed state: ∂F/∂δ ≈ (F(Δδ + ε eⱼ) − F(Δδ)) / ε, ε = 10⁻⁷ of the
    /// band's elastic displacement at its strength scale or of the increment, whichever
    /// is larger. A softening contact gets its negative stiffness, a spent or open one
    /// nothing, a slipping one the friction coupling ∂Fₛ/∂δₙ.
    fn tangent_local(&self, trial: &Trial) -> Vec<crate::assembly::LocalStiffness> {
        use rayon::prelude::*;
        let (laws, areas, committed, frozen) =
            (&self.law, &self.area, &self.committed, &self.frozen);
        (0..areas.len())
            .into_par_iter()
            .with_min_len(256)
            .map(|k| match frozen.get(k) {
                // held by the contact-state corrector: its frozen law's tangent
                Some(Some(fr)) => fr.t,
                _ => law_tangent(laws, areas, committed, k, trial.rel[k], trial.force[k]),
            })
            .collect()
    }

    /// The contact-state corrector's frozen law of contact `k` at `trial` (whose force
    /// at `k` is the true law's): Eq. F1 with the chord of [`chord_law`].
    fn freeze(&self, k: usize, trial: &Trial) -> Frozen {
        chord_law(
            self.law.get(k).springs(self.area[k]),
            self.committed.force[k],
            trial.rel[k],
            trial.force[k],
            trial.state[k],
        )
    }

    /// Solve K x = b for the two right-hand sides: with the tangent matrix of `trial`
    /// (`tangent`: nonsymmetric and, past a peak, indefinite: LU) or its secant matrix
    /// (Cholesky; K_s + ε K₀ when K_s is singular). `None` when the matrix cannot be
    /// factorized.
    fn solve_pair(
        &mut self,
        trial: &Trial,
        b1: &[f64],
        b2: &[f64],
        tangent: bool,
    ) -> Result<Option<(Vec<f64>, Vec<f64>)>> {
        let (mut x1, mut x2) = (b1.to_vec(), b2.to_vec());
        if tangent {
            let local = self.tangent_local(trial);
            self.system
                .stiffness_into(&trial.mesh, &local, &mut self.lin.kbuf);
            self.lin.kbuf_local = None;
            CorrectionSolver::pin_rows(&self.pins, &mut self.lin.kbuf);
            let size = self.model_size();
            let ok = self.lin.factor_solve_each(true, &mut [&mut x1, &mut x2])?
                // LU has no pivot measure: a singular tangent shows as a huge response
                && x2.iter().all(|v| v.abs() < 1e3 * size);
            return Ok(ok.then_some((x1, x2)));
        }
        let local = self.local_stiffness(trial, &trial.state, false);
        self.system
            .stiffness_into(&trial.mesh, &local, &mut self.lin.kbuf);
        self.lin.kbuf_local = None;
        CorrectionSolver::pin_rows(&self.pins, &mut self.lin.kbuf);
        if !self.lin.factorize(true) {
            let Some(x1) = self.blended_step(trial, b1, BLEND)? else {
                return Ok(None);
            };
            // the blended matrix is still factorized
            return Ok(self.lin.backend.solve(&mut x2).is_ok().then_some((x1, x2)));
        }
        let ok = self.lin.solve(&mut x1) && self.lin.solve(&mut x2);
        Ok(ok.then_some((x1, x2)))
    }

    /// One correction on the arc from the iterate `dq` at the load factor `lam` (the
    /// out-of-balance force `r`, its norm `rn`): the solves with the tangent or secant
    /// matrix, δλ from the constraint — on the cylinder ‖dq + δu_r + δλ δu_P‖² = n Δl²
    /// the root that turns the increment least, on the dissipation the root of Eq. A2
    /// along the line ([`Driver::dissipation_root`]) — and backtracking (the best of the
    /// steps 1, ½, …, 2⁻¹¹ of [`LONG_LINE_SEARCH_STEPS`] where the full one raises the
    /// out-of-balance force). Returns (the norm of the
    /// out-of-balance force after it, the new dq, its δλ, its trial), or `None` when the matrix
    /// cannot be factorized or the line meets no point of the cylinder.
    #[allow(clippy::too_many_arguments)]
    fn corrector(
        &mut self,
        trial: &Trial,
        r: &[f64],
        rn: f64,
        (p, base): (&[f64], &[f64]),
        dq: &[f64],
        lam: f64,
        constraint: Constraint,
        tangent: bool,
    ) -> Result<Option<Correction>> {
        let Some((dr, dp)) = self.solve_pair(trial, r, p, tangent)? else {
            return Ok(None);
        };
        let w: Vec<f64> = dq.iter().zip(&dr).map(|(a, b)| a + b).collect();
        let len2 = match constraint {
            Constraint::Cylinder(len2) => len2,
            Constraint::Dissipation(tau) => {
                let Some(dl) = self.dissipation_root(&w, &dp, tau) else {
                    return Ok(None);
                };
                return Ok(Some(self.backtrack(&w, &dp, dl, rn, (p, base), dq, lam)));
            }
            Constraint::Push(da) => {
                // P̂ · (w + δλ dp) = Δa: linear in δλ; P̂ · dp is the block's compliance
                // under its force, zero only where the block cannot move
                let ep = dot(p, &dp);
                let dl = (da - dot(p, &w)) / ep;
                if !dl.is_finite() {
                    return Ok(None);
                }
                return Ok(Some(self.backtrack(&w, &dp, dl, rn, (p, base), dq, lam)));
            }
        };
        // ‖dq + dr + δλ dp‖² = n Δl²: a δλ² + b δλ + c = 0
        let a = dot(&dp, &dp);
        let b = 2.0 * dot(&dp, &w);
        let c = dot(&w, &w) - len2;
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 || a <= 0.0 {
            return Ok(None);
        }
        let sq = disc.sqrt();
        let score = |l: f64| {
            dq.iter()
                .zip(&w)
                .zip(&dp)
                .map(|((q, wi), pi)| q * (wi + l * pi))
                .sum::<f64>()
        };
        let roots = [(-b + sq) / (2.0 * a), (-b - sq) / (2.0 * a)];
        let dl = if score(roots[0]) >= score(roots[1]) {
            roots[0]
        } else {
            roots[1]
        };
        Ok(Some(self.backtrack(&w, &dp, dl, rn, (p, base), dq, lam)))
    }

    /// The best of the steps α = 1, ½, …, 2⁻¹¹ ([`LONG_LINE_SEARCH_STEPS`]) from `dq` towards
    /// `w` + δλ `dp` at the load factor `lam` + α δλ (the first that does not raise the
    /// out-of-balance force above `rn`; [`Driver::line_search_along`]): (its
    /// out-of-balance force, the iterate, α δλ, the iterate's trial).
    #[allow(clippy::too_many_arguments)]
    fn backtrack(
        &self,
        w: &[f64],
        dp: &[f64],
        dl: f64,
        rn: f64,
        (p, base): (&[f64], &[f64]),
        dq: &[f64],
        lam: f64,
    ) -> Correction {
        let zero = vec![[0.0; 2]; self.cur.blocks.len()];
        let delta: Vec<f64> = dq
            .iter()
            .zip(w)
            .zip(dp)
            .map(|((q, wi), pi)| wi + dl * pi - q)
            .collect();
        let load = Load::Along {
            base,
            p,
            lam,
            dlam: dl,
        };
        let (rn2, t, cand, alpha) =
            self.line_search_along(dq, &delta, rn, &load, &zero, LONG_LINE_SEARCH_STEPS);
        (rn2, cand, alpha * dl, t)
    }

    /// One arc-length increment under `constraint` from the committed state at the load
    /// factor `lam0`, after the increment `previous` (unknowns, Δλ, dissipated energy in
    /// J): the converged trial, its Δλ and the energy it dissipates, or why not.
    /// With the contact-state corrector: a
    /// contact that changes state [`FLIP_LIMIT`] times in the increment is frozen
    /// (Eq. F1) for the rest of it; when the iterations converge with contacts frozen,
    /// the true laws decide: the increment is accepted if the out-of-balance force with
    /// the true laws is within the tolerance, else every frozen contact takes the chord
    /// to the point reached and the iterations go on from there (Eq. F2).
    fn arc_step(
        &mut self,
        base: &[f64],
        p: &[f64],
        lam0: f64,
        constraint: Constraint,
        previous: Option<(&[f64], f64, f64)>,
    ) -> Result<std::result::Result<(Trial, f64, f64), StepFailure>> {
        let n = self.cur.n_dofs;
        let zero = vec![[0.0; 2]; self.cur.blocks.len()];
        let f_ext =
            |lam: f64| -> Vec<f64> { base.iter().zip(p).map(|(b, q)| b + lam * q).collect() };
        // predictor: the last increment scaled to the arc length or to the energy to
        // dissipate (a secant predictor, which turns with the path at limit points and
        // snap-backs; the dissipation taken as proportional to the increment), or at the
        // first increment the secant matrix's response to P̂
        let mut dq = vec![0.0; n];
        let dlam;
        // the previous increment's scale factor, or None for a fresh predictor: a push
        // increment is scaled only from a previous one that moved the block forward
        let scaled = previous.and_then(|(prev, _, prev_d)| match constraint {
            Constraint::Cylinder(len2) => Some((len2 / dot(prev, prev).max(1e-300)).sqrt()),
            Constraint::Dissipation(tau) => {
                Some((tau / prev_d.max(1e-300)).clamp(PREDICTOR_LEAST_SCALE, 2.0))
            }
            Constraint::Push(da) => {
                let moved = dot(p, prev);
                (moved > 0.0).then(|| (da / moved).min(4.0))
            }
        });
        match (previous, scaled) {
            (Some((prev, prev_dlam, _)), Some(f)) => {
                for (q, a) in dq.iter_mut().zip(prev) {
                    *q = f * a;
                }
                dlam = f * prev_dlam;
            }
            _ => {
                let trial = self.trial(&dq, &zero);
                let r = self.out_of_balance(&f_ext(lam0), &trial.f_int);
                // a push that reverses the last increment (the foot of a snap-back): the
                // contacts that softened on the way down unload along their elastic
                // springs, which the secant matrix has and the tangent (their softening
                // slopes) has not
                let reverses = previous.is_some() && matches!(constraint, Constraint::Push(_));
                let Some((ur, up)) = self.solve_pair(&trial, &r, p, !reverses)? else {
                    return Ok(Err(StepFailure::Divergence));
                };
                dlam = match constraint {
                    Constraint::Push(da) => (da - dot(p, &ur)) / dot(p, &up),
                    Constraint::Cylinder(len2) => (len2 / dot(&up, &up).max(1e-300)).sqrt(),
                    Constraint::Dissipation(_) => {
                        unreachable!("the dissipation constraint follows a converged increment")
                    }
                };
                if !dlam.is_finite() {
                    return Ok(Err(StepFailure::Divergence));
                }
                for ((q, a), b) in dq.iter_mut().zip(&ur).zip(&up) {
                    *q = a + dlam * b;
                }
            }
        }
        let size = self.model_size();
        self.flips = vec![0; self.cur.contacts.len()];
        // the caller clears it after the increment
        self.frozen = vec![None; self.cur.contacts.len()];
        let trial = self.trial(&dq, &zero);
        let controls = IterationControls {
            tolerance: self.settings.tolerance,
            max_iterations: self.settings.max_iterations,
            stall_progress: STALL_PROGRESS,
        };
        let keep = self.settings.arc.is_some_and(|a| a.accept > 0.0);
        let mut step = path_step::PathStep {
            d: self,
            base,
            p,
            lam0,
            constraint,
            dq,
            dlam,
            trial,
            r: Vec::new(),
            scale: 0.0,
            residual: f64::INFINITY,
            last_check: f64::INFINITY,
            stuck: 0,
            keep,
            best_true: None,
            dissipated: 0.0,
            failure: None,
            size,
        };
        let end = solver::iterate(&mut step, &controls)?;
        Ok(step.finish(end))
    }
}

/// How [`run()`] ended: the fraction of the path's end reached, why it stopped short (if it
/// did), the converged increments on the cylinder, the dissipation and under
/// displacement control, and the increments accepted unconverged with the largest
/// relative out-of-balance force one was left at.
type PathRun = (f64, Option<String>, [usize; 3], (usize, f64));

/// Follow the push of `push` by arc length from the committed state under the external
/// force `base` (N), to the displacement `push_displacement` along P̂, in increments of
/// the settings' Δl (halved when one fails, up to `max_cuts` times in a row, and grown
/// back after increments that converge); with `path = "dissipation"` each increment tries
/// Eq. A2, Eq. A3 and Eq. A1 in turn; with `accept_residual` an increment that fails
/// them all is taken at its best iterate within it ([`ArcLength::accept`]). Returns how
/// the path ended ([`PathRun`]).
pub(super) fn run(
    d: &mut Driver,
    base: &[f64],
    push: &Push,
    arc: &ArcLength,
    steps: usize,
) -> Result<PathRun> {
    let s = setup(d, push);
    let f = s.first;
    let mut pins = vec![(f + 2, 0.0)];
    if push.horizontal == 0.0 {
        pins.push((f, 0.0));
    }
    if push.vertical == Some(0.0) {
        pins.push((f + 1, 0.0));
    }
    // blocks that fell out before the push (`fallout`) stay held
    pins.extend(d.fallen_pins.iter().copied());
    d.pins = pins;
    d.lin.held = Held::Nothing;
    let start = [d.committed.u[f], d.committed.u[f + 1]];
    let along = |d: &Driver| {
        (d.committed.u[f] - start[0]) * s.dir[0] + (d.committed.u[f + 1] - start[1]) * s.dir[1]
    };
    let p0 = d.push_point(push.block, 0.0, None);
    d.push_curve.push(p0);
    // Δl: given, or the one whose elastic predictor moves the block by target / steps
    let dl_max = match arc.length {
        Some(l) => l,
        None => {
            let zero = vec![[0.0; 2]; d.cur.blocks.len()];
            let trial = d.trial(&vec![0.0; d.cur.n_dofs], &zero);
            let Some((_, up)) = d.solve_pair(&trial, &vec![0.0; d.cur.n_dofs], &s.p, true)? else {
                return Ok((
                    0.0,
                    Some("the pushed block is free to move: no stiffness holds it".into()),
                    [0; 3],
                    (0, 0.0),
                ));
            };
            let moved = up[f] * s.dir[0] + up[f + 1] * s.dir[1];
            let free = (d.cur.n_dofs - d.pins.len()) as f64;
            (dot(&up, &up) / free).sqrt() * (s.target / steps as f64) / moved.abs().max(1e-300)
        }
    };
    let mut dl = dl_max;
    // Δa (m), the push increment of displacement control (Eq. A3), and its largest
    // value: the push over `steps` increments
    let da_max = s.target / steps.max(1) as f64;
    let mut da = da_max;
    // with path = "dissipation", once switched: Δτ (J) and its largest value, the energy
    // dissipated by the increment that switched it on (grown back to it after quick
    // increments as Δl is)
    let mut tau: Option<(f64, f64)> = None;
    // with path = "dissipation": the last increment was taken under displacement control
    // because the dissipation constraint could not be met, and spent less than Δτ
    let mut pushing = false;
    let mut lam = 0.0;
    // the last converged increment (unknowns, Δλ, dissipated energy)
    let mut previous: Option<(Vec<f64>, f64, f64)> = None;
    let mut cuts = 0;
    // the constraint tried for this increment: 0 the first of `order`, then the others
    // once it has failed `max_cuts` times in a row (or would pull on the block)
    let mut level = 0;
    // the increments taken on the cylinder, the dissipation and displacement control
    let mut counts = [0usize; 3];
    // a path that never reaches its end (it turns back for good) stops after this many
    let limit = 50 * steps.max(1);
    let mut done = 0;
    // `accept_residual`: the best iterate of the current increment's failed tries (with
    // the constraint it was tried under), the one taken in place of a failure, and the
    // increments so taken with their largest out-of-balance force
    let mut unconverged: Option<(Box<Unconverged>, Kind, Constraint)> = None;
    let mut forced: Option<(Box<Unconverged>, Kind, Constraint)> = None;
    let mut accepted = (0usize, 0.0f64);
    // the constraints' steps (Δl, Δa, Δτ) at the first try of the increment, which the
    // increment after an accepted one starts from again (the cuts of the failed tries
    // do not carry over: at the least steps J7D crept by 2·10⁻⁹ m an increment)
    let mut sizes = (dl, da, tau);
    while along(d) < s.target * (1.0 - 1e-9) && done < limit {
        let free = (d.cur.n_dofs - d.pins.len()) as f64;
        if cuts == 0 && level == 0 && forced.is_none() {
            sizes = (dl, da, tau);
        }
        // the constraints in the order they are tried for this increment (Gutiérrez
        // 2004; Verhoosel et al. 2009): with path = "dissipation" the one that worked
        // last, then the others; plain arc length has the cylinder alone
        let order: Vec<Kind> = match (arc.dissipation, tau.is_some()) {
            (false, _) => vec![Kind::Cylinder],
            (true, false) => vec![Kind::Cylinder, Kind::Push],
            (true, true) if pushing => vec![Kind::Push, Kind::Dissipation, Kind::Cylinder],
            (true, true) => vec![Kind::Dissipation, Kind::Push, Kind::Cylinder],
        };
        let mut kind = order[level];
        let mut constraint = match kind {
            Kind::Cylinder => Constraint::Cylinder(dl * dl * free),
            Kind::Dissipation => Constraint::Dissipation(tau.map_or(0.0, |t| t.0)),
            Kind::Push => Constraint::Push(da.min(s.target - along(d))),
        };
        let step = match forced.take() {
            Some((best, k, c)) => {
                // every constraint failed: the best iterate, within `accept_residual`
                (kind, constraint) = (k, c);
                accepted.0 += 1;
                accepted.1 = accepted.1.max(best.residual);
                if super::super::tracing() {
                    eprintln!(
                        "arc increment accepted unconverged at {:.3e} of the load ({constraint:?})",
                        best.residual
                    );
                }
                let dissipated = d.dissipated(&best.trial);
                Ok(Ok((best.trial, best.dlam, dissipated)))
            }
            None => {
                let prev = previous.as_ref().map(|(q, l, e)| (q.as_slice(), *l, *e));
                d.arc_step(base, &s.p, lam, constraint, prev)
            }
        };
        d.frozen.clear();
        let step = match step? {
            // a push cannot pull: with path = "dissipation" an increment that takes the
            // force on the block below zero (the foot of a snap-back) is not taken, and
            // the next constraint pushes the block on from the last state
            Ok((_, dlam, _)) if arc.dissipation && lam + dlam < 0.0 => Err(StepFailure::Pulls),
            other => other,
        };
        match step {
            Ok((trial, dlam, dissipated)) => {
                let fe: Vec<f64> = base
                    .iter()
                    .zip(&s.p)
                    .map(|(b, q)| b + (lam + dlam) * q)
                    .collect();
                if super::super::tracing() {
                    d.trace_spending(&trial);
                }
                let mut reaction = d.reaction(push.block, &trial.f_int, &fe);
                let dq = trial.dq.clone();
                d.commit(trial, &dq, &vec![[0.0; 2]; d.cur.blocks.len()]);
                lam += dlam;
                reaction[0] += lam * s.dir[0];
                reaction[1] += lam * s.dir[1];
                let fraction = along(d) / s.target;
                d.converged(fraction);
                let pt = d.push_point(push.block, fraction, Some(reaction));
                d.push_curve.push(pt);
                // the work of the push in the increment (J), by the trapezoidal rule
                let moved = dot(&s.p, &dq);
                let work = (lam - 0.5 * dlam) * moved;
                counts[kind as usize] += 1;
                match kind {
                    // displacement control until an increment spends Δτ again
                    Kind::Push => pushing = tau.is_some_and(|(t, _)| dissipated < t),
                    Kind::Dissipation => pushing = false,
                    Kind::Cylinder => {}
                }
                if arc.dissipation
                    && tau.is_none()
                    && dissipated > 0.0
                    && (dissipated > SWITCH_FRACTION * work || work <= 0.0)
                {
                    tau = Some((dissipated, dissipated));
                }
                if super::super::tracing() {
                    eprintln!(
                        "arc increment: load {lam:.6e} at {:.6e}, dissipated {dissipated:.3e} J, push work {work:.3e} J, constraint {constraint:?}",
                        along(d)
                    );
                }
                previous = Some((dq, dlam, dissipated));
                if lam < 0.0 {
                    d.pins.clear();
                    return Ok((
                        along(d) / s.target,
                        Some(
                            "the path turned back: the force on the pushed block changed sign"
                                .into(),
                        ),
                        counts,
                        accepted,
                    ));
                }
                done += 1;
                cuts = 0;
                level = 0;
                unconverged = None;
                if d.report.iterations <= d.settings.max_iterations / 10 {
                    dl = (2.0 * dl).min(dl_max);
                    da = (2.0 * da).min(da_max);
                    if let Some((t, t_max)) = &mut tau {
                        *t = (2.0 * *t).min(*t_max);
                    }
                }
            }
            Err(mut why) => {
                let pulls = matches!(why, StepFailure::Pulls);
                if let StepFailure::NoConvergence(_, best) = &mut why {
                    if let Some(b) = best.take() {
                        if unconverged
                            .as_ref()
                            .is_none_or(|u| b.residual < u.0.residual)
                        {
                            unconverged = Some((b, kind, constraint));
                        }
                    }
                }
                // the step of this constraint halved, unless that takes it below its
                // least value: Δl and Δa their largest halved `max_cuts` times, Δτ its
                // largest halved 2 `max_cuts` times (J4D at 26 mm turns its snap-back
                // with Δτ at 2⁻¹⁰ of its largest; the increments that converge at smaller
                // steps go nowhere: J7D crept by 10⁻¹² m and 10⁻¹¹ J an increment)
                let least = 0.5f64.powi(d.settings.max_cuts as i32);
                let size = match kind {
                    Kind::Cylinder => (&mut dl, least * dl_max),
                    Kind::Push => (&mut da, least * da_max),
                    Kind::Dissipation => match &mut tau {
                        Some((t, t_max)) => (t, least * least * *t_max),
                        None => unreachable!("the dissipation constraint is on"),
                    },
                };
                if cuts < d.settings.max_cuts && !pulls && 0.5 * *size.0 >= size.1 {
                    // cut the step of this constraint and retry
                    cuts += 1;
                    d.stats.load_cuts += 1;
                    *size.0 *= 0.5;
                    continue;
                }
                if level + 1 < order.len() {
                    // the next constraint, at the pace of the last converged increment
                    level += 1;
                    cuts = 0;
                    if let Some((q, _, e)) = &previous {
                        match order[level] {
                            Kind::Cylinder => {
                                dl = (dot(q, q) / free).sqrt().clamp(least * dl_max, dl_max)
                            }
                            Kind::Push => {
                                let moved = dot(&s.p, q).abs();
                                da = if moved > 0.0 {
                                    moved.clamp(least * da_max, da_max)
                                } else {
                                    da_max
                                };
                            }
                            Kind::Dissipation => {
                                if let Some((t, t_max)) = &mut tau {
                                    *t = if *e > 0.0 {
                                        e.clamp(least * least * *t_max, *t_max)
                                    } else {
                                        *t_max
                                    };
                                }
                            }
                        }
                    }
                    continue;
                }
                if let Some(u) = unconverged.take() {
                    // (not an iterate that pulls on the block, which would fail again)
                    if u.0.residual <= arc.accept && !(arc.dissipation && lam + u.0.dlam < 0.0) {
                        // take the best iterate of the tries, and go on from there
                        forced = Some(u);
                        cuts = 0;
                        level = 0;
                        (dl, da, tau) = sizes;
                        continue;
                    }
                }
                let what = match order.len() {
                    1 => "",
                    2 => " (the cylinder and displacement control of the block tried)",
                    _ => " (the dissipation, displacement control of the block and the cylinder tried)",
                };
                if let StepFailure::NoConvergence(r, _) = why {
                    d.path_stall = Some(r);
                }
                let why = match why {
                    StepFailure::NoConvergence(r, _) => format!("the out-of-balance force stays at {r:.2e} of the load along the arc{what}"),
                    StepFailure::Divergence => format!("the displacements grow without bound along the arc{what}: the blocks move without restraint"),
                    StepFailure::Pulls => format!("the path turns back to a pull on the block{what}"),
                };
                d.pins.clear();
                return Ok((along(d) / s.target, Some(why), counts, accepted));
            }
        }
    }
    d.pins.clear();
    let reached = along(d) / s.target;
    if reached < 1.0 - 1e-9 {
        return Ok((
            reached,
            Some(format!(
                "the path did not reach the end of the push in {limit} increments"
            )),
            counts,
            accepted,
        ));
    }
    Ok((1.0, None, counts, accepted))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{ElasticBand, MohrCoulomb};

    /// A dry Coulomb contact (no cohesion, no tension): kₙ = 10⁹ N/m, kₛ = 4·10⁸ N/m
    /// over 1 m², tan φ = 0.75, committed at Fₙ = −1000 N, Fₛ = 600 N (|Fₛ| = 0.8 of
    /// μ|Fₙ| = 750 N: sticking, 150 N below the Coulomb kink).
    fn contact() -> (PerContact<JointLaw>, Vec<f64>, Committed) {
        let law = JointLaw::MohrCoulomb(MohrCoulomb {
            elastic: ElasticBand {
                normal_modulus: 1e7,
                shear_modulus: 4e6,
                band: 0.01,
            },
            tan_phi: 0.75,
            cohesion: 0.0,
            tensile_strength: 0.0,
        });
        let committed = Committed {
            stress: Vec::new(),
            force: vec![[-1000.0, 600.0]],
            state: vec![ContactState::Stick],
            u: Vec::new(),
            history: vec![[0.0; 2]],
        };
        (
            PerContact {
                laws: vec![law],
                of: vec![0],
            },
            vec![1.0],
            committed,
        )
    }

    fn close(a: f64, b: f64, scale: f64) -> bool {
        // forward differences of a law linear on each side of its kinks: round-off of
        // forces of 10³ N over a step of 10⁻⁷ of the displacement scale, ~10⁻⁸ relative
        (a - b).abs() <= 1e-6 * scale
    }

    /// The law's tangent on each side of the Coulomb kink and in tension, against the
    /// closed forms of docs/theory.md §3: stick diag(kₙ, kₛ); slip Fₛ = −sgn(Fₛ) tan φ Fₙ,
    /// so ∂Fₛ/∂δₙ = −sgn(Fₛ) tan φ kₙ and ∂Fₛ/∂δₛ = 0; open nothing.
    #[test]
    fn law_tangent_matches_the_closed_forms_on_each_side_of_the_kink() {
        let (laws, areas, committed) = contact();
        let (kn, ks) = (1e9, 4e8);
        let tangent = |d: [f64; 2]| {
            let (f, st, _) = laws
                .get(0)
                .update_history(1.0, committed.force[0], [0.0; 2], d);
            (law_tangent(&laws, &areas, &committed, 0, d, f), st)
        };
        // stick: shear 600 + 4·10⁸ · 2·10⁻⁷ = 680 N < 750 N
        let (t, st) = tangent([0.0, 2e-7]);
        assert_eq!(st, ContactState::Stick);
        assert!(close(t[0][0], kn, kn) && close(t[1][1], ks, kn), "{t:?}");
        assert!(close(t[0][1], 0.0, kn) && close(t[1][0], 0.0, kn), "{t:?}");
        // slip: shear trial 600 + 4·10⁸ · 10⁻⁶ = 1000 N > 750 N
        let (t, st) = tangent([0.0, 1e-6]);
        assert_eq!(st, ContactState::Slip);
        assert!(close(t[0][0], kn, kn) && close(t[1][1], 0.0, kn), "{t:?}");
        assert!(close(t[1][0], -0.75 * kn, kn), "{t:?}");
        // open: Fₙ = −1000 + 10⁹ · 2·10⁻⁶ = 1000 N > 0
        let (t, st) = tangent([2e-6, 0.0]);
        assert_eq!(st, ContactState::Open);
        assert!(t.iter().flatten().all(|v| close(*v, 0.0, kn)), "{t:?}");
    }

    /// The frozen law (Eq. F1) of a contact frozen in slip at Δδ* = (0, 10⁻⁶ m), driven
    /// back across the Coulomb kink. At Δδ = (0, s) the law gives 600 + kₛ s in stick and
    /// μ|Fₙ| = 750 N in slip: the kink is at s* = 150 N / kₛ = 3.75·10⁻⁷ m. The chord from
    /// the committed (0, 600 N) to (10⁻⁶ m, 750 N) has the slope 1.5·10⁸ N/m, between the
    /// slip side's 0 and the stick side's kₛ = 4·10⁸ N/m; the normal component has not
    /// moved and keeps kₙ. The frozen law's error against the law is the closed form
    /// (kₛ − 1.5·10⁸) s in stick and 150 N − 1.5·10⁸ s in slip, largest at the kink
    /// (93.75 N), and zero at both ends of the chord.
    #[test]
    fn frozen_chord_law_brackets_the_coulomb_kink() {
        let (laws, _, committed) = contact();
        let (kn, ks) = (1e9, 4e8);
        let law = laws.get(0);
        let at = |d: [f64; 2]| law.update_history(1.0, committed.force[0], [0.0; 2], d);
        let d0 = [0.0, 1e-6];
        let (f0, st, _) = at(d0);
        assert_eq!(st, ContactState::Slip);
        assert!(close(f0[1], 750.0, 1e3), "{f0:?}");
        let fr = chord_law(law.springs(1.0), committed.force[0], d0, f0, st);
        assert_eq!(fr.state, ContactState::Slip);
        let slope = 1.5e8;
        assert!(
            close(fr.t[1][1], slope, kn) && close(fr.t[0][0], kn, kn),
            "{:?}",
            fr.t
        );
        assert!(fr.t[0][1] == 0.0 && fr.t[1][0] == 0.0);
        // through both ends of the chord
        assert_eq!(fr.force(d0), f0);
        let g = fr.force([0.0; 2]);
        assert!(
            close(g[0], -1000.0, 1e3) && close(g[1], 600.0, 1e3),
            "{g:?}"
        );
        let kink = 150.0 / ks;
        for s in [0.5 * kink, kink, 2.0 * kink] {
            let (f, st, _) = at([0.0, s]);
            let g = fr.force([0.0, s]);
            let err = if s <= kink {
                assert_eq!(st, ContactState::Stick);
                (ks - slope) * s
            } else {
                assert_eq!(st, ContactState::Slip);
                150.0 - slope * s
            };
            assert!(
                close(f[1] - g[1], err, 1e3),
                "s {s}: law {f:?}, frozen {g:?}"
            );
            assert!(close(f[0], g[0], 1e3), "s {s}: law {f:?}, frozen {g:?}");
        }
        assert!(close((ks - slope) * kink, 93.75, 1e3));
    }

    /// A slipping contact whose shear force follows the normal one: committed at the
    /// Coulomb limit (Fₙ = −1000 N, Fₛ = 750 N = μ|Fₙ|), opened by 10⁻⁷ m with a slip of
    /// 10⁻¹² m. The law gives Fₙ = −1000 + kₙ 10⁻⁷ = −900 N and, slipping, Fₛ = μ 900 =
    /// 675 N: the shear chord (675 − 750) / 10⁻¹² = −7.5·10¹³ N/m is bounded to
    /// −kₛ = −4·10⁸ N/m, the normal one is kₙ; the frozen law still gives the law's force
    /// at the point reached and moves by at most kₛ per metre of slip from it.
    #[test]
    fn a_chord_driven_by_the_other_component_is_bounded_by_the_spring() {
        let (laws, _, _) = contact();
        let (kn, ks) = (1e9, 4e8);
        let law = laws.get(0);
        let f0 = [-1000.0, 750.0];
        let d = [1e-7, 1e-12];
        let (f, st, _) = law.update_history(1.0, f0, [0.0; 2], d);
        assert_eq!(st, ContactState::Slip);
        assert!(close(f[0], -900.0, 1e3) && close(f[1], 675.0, 1e3), "{f:?}");
        let fr = chord_law(law.springs(1.0), f0, d, f, st);
        assert!(close(fr.t[0][0], kn, kn), "{:?}", fr.t);
        assert_eq!(fr.t[1][1], -ks, "{:?}", fr.t);
        assert_eq!(fr.force(d), f);
        let g = fr.force([d[0], d[1] + 1e-9]);
        assert!(close(g[1], f[1] - ks * 1e-9, 1e3), "{g:?}");
    }
}
