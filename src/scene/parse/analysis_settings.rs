//! The typed settings of `[analysis]` ([`StaticSettings`], [`DynamicSettings`]): each key
//! read and checked here, once, with its line in the error.

use super::{err_at, Src};
use crate::error::{Error, Result};
use crate::scene::ground_motion::Frame;
use crate::scene::settings::{
    ArcLength, DynamicSettings, Push, Scheme, Start, StaticSettings, Strategy,
};
use crate::scene::{AnalysisType, Block, BlockKind, Support};

/// The `[analysis]` table and where it starts in the text.
pub(super) struct AnalysisTable<'a> {
    pub src: &'a Src<'a>,
    pub at: usize,
    pub t: &'a toml::Table,
}

impl AnalysisTable<'_> {
    /// An error at key `key`'s line.
    fn err(&self, key: &str, what: impl Into<String>, fix: impl Into<String>) -> Error {
        err_at(
            self.src.key_line(self.at, key),
            format!("[analysis] key '{key}'"),
            what,
            fix,
        )
    }

    /// The number under `key`, `d` when absent; an error naming the allowed range
    /// `[lo, hi]` when it is not a finite number in it.
    fn number(&self, key: &str, d: f64, lo: f64, hi: f64) -> Result<f64> {
        let Some(v) = self.t.get(key) else {
            return Ok(d);
        };
        let f = as_number(v).unwrap_or(f64::NAN);
        if f.is_finite() && f >= lo && f <= hi {
            Ok(f)
        } else {
            Err(self.err(
                key,
                format!(
                    "'{key}' must be a number from {} to {}",
                    short(lo),
                    short(hi)
                ),
                format!("for example {key} = {}", short(d)),
            ))
        }
    }

    /// The number under `key` if given, checked as [`AnalysisTable::number`].
    fn optional_number(&self, key: &str, example: f64, lo: f64, hi: f64) -> Result<Option<f64>> {
        match self.t.get(key) {
            None => Ok(None),
            Some(_) => self.number(key, example, lo, hi).map(Some),
        }
    }

    /// The switch under `key`: true or false, `d` when absent.
    fn switch(&self, key: &str, d: bool, fix: &str) -> Result<bool> {
        match self.t.get(key) {
            None => Ok(d),
            Some(v) => v
                .as_bool()
                .ok_or_else(|| self.err(key, format!("'{key}' must be true or false"), fix)),
        }
    }

    /// The string under `key` (`None` when absent); a value that is not a string reads as
    /// `Some("")`, which no choice matches.
    fn choice(&self, key: &str) -> Option<&str> {
        self.t.get(key).map(|v| v.as_str().unwrap_or(""))
    }

    /// The static driver's settings of a static or capacity analysis over `blocks`.
    pub fn statics(&self, kind: AnalysisType, blocks: &[Block]) -> Result<StaticSettings> {
        let strategy = match self.choice("strategy") {
            None => Strategy::Secant,
            Some(s) => Strategy::parse(s).ok_or_else(|| {
                self.err(
                    "strategy",
                    "unknown strategy",
                    "use \"initial\", \"secant\" or \"newton\"",
                )
            })?,
        };
        let d = StaticSettings::with_strategy(strategy);
        let switch = |k: &str, d: bool| {
            self.switch(
                k,
                d,
                &format!("write {k} = true or {k} = false (default {d})"),
            )
        };
        let push = self.push(kind, blocks)?;
        let arc = self.arc(push.is_some())?;
        Ok(StaticSettings {
            strategy,
            tolerance: self.number("tolerance", d.tolerance, 1e-14, 0.1)?,
            max_iterations: self.number("max_iterations", d.max_iterations as f64, 1.0, 1e6)?
                as usize,
            max_cuts: self.number("max_cuts", d.max_cuts as f64, 0.0, 30.0)? as usize,
            initial_step: self.number("initial_step", d.initial_step, 1e-9, 1e3)?,
            bracket: self.number("bracket", d.bracket, 1e-9, 0.5)?,
            line_search: switch("line_search", d.line_search)?,
            fallout: switch("fallout", d.fallout)?,
            reuse_across_increments: switch("reuse_across_increments", d.reuse_across_increments)?,
            gravity_steps: self
                .optional_number("gravity_steps", 10.0, 1.0, 1e6)?
                .map(|s| s.round() as usize),
            push,
            arc,
        })
    }

    /// Displacement control (`push_block` with `push_displacement`), if given.
    fn push(&self, kind: AnalysisType, blocks: &[Block]) -> Result<Option<Push>> {
        let (name, disp) = match (self.t.get("push_block"), self.t.get("push_displacement")) {
            (None, None) => return Ok(None),
            (Some(b), Some(d)) => (b, d),
            (Some(_), None) => {
                return Err(self.err(
                    "push_block",
                    "push_block is given without push_displacement",
                    "add push_displacement = <m> (horizontal, vertical free) or [<m>, <m>]",
                ))
            }
            (None, Some(_)) => {
                return Err(self.err(
                    "push_displacement",
                    "push_displacement is given without push_block",
                    "add push_block = \"<name of the free rigid block to push>\"",
                ))
            }
        };
        let name = name.as_str().ok_or_else(|| {
            self.err(
                "push_block",
                "push_block is not a block name",
                "give the name of a block as a string, for example \"top\"",
            )
        })?;
        let block = blocks.iter().position(|b| b.name == name).ok_or_else(|| {
            self.err(
                "push_block",
                format!("there is no block '{name}'"),
                "name a block of the scene (generated walls call their top beam \"top\")",
            )
        })?;
        let b = &blocks[block];
        if b.support != Support::Free || b.kind != BlockKind::Rigid {
            return Err(self.err(
                "push_block",
                format!("block '{name}' is not a free rigid block"),
                "push a free block of kind = \"rigid\" (a loading beam); fixed blocks move with their 'prescribed' key",
            ));
        }
        let bad = || {
            self.err(
                "push_displacement",
                "push_displacement is not a displacement",
                "give a finite number of m (horizontal; the vertical motion free) or [horizontal, vertical] in m",
            )
        };
        let (horizontal, vertical) = match disp {
            toml::Value::Array(a) if a.len() == 2 => {
                let h = as_number(&a[0]).ok_or_else(bad)?;
                let v = as_number(&a[1]).ok_or_else(bad)?;
                (h, Some(v))
            }
            v => (as_number(v).ok_or_else(bad)?, None),
        };
        if !horizontal.is_finite() || !vertical.unwrap_or(0.0).is_finite() {
            return Err(bad());
        }
        if kind != AnalysisType::Static {
            return Err(self.err(
                "push_block",
                "displacement control belongs to a static analysis",
                "set [analysis] type = \"static\" (the capacity analysis raises a load factor instead)",
            ));
        }
        Ok(Some(Push {
            block,
            horizontal,
            vertical,
        }))
    }

    /// Arc-length path following (`path`, `arc_length`, `accept_residual`), if asked for.
    fn arc(&self, pushed: bool) -> Result<Option<ArcLength>> {
        let paths = "give path = \"displacement\" (the default), \"arc_length\" or \"dissipation\"";
        let (arc, dissipation) = match self.t.get("path") {
            None => (false, false),
            Some(v) => match v.as_str() {
                None => return Err(self.err("path", "path is not a string", paths)),
                Some("displacement") => (false, false),
                Some("arc_length") => (true, false),
                Some("dissipation") => (true, true),
                Some(other) => {
                    return Err(self.err("path", format!("unknown path \"{other}\""), paths))
                }
            },
        };
        if !arc {
            for key in ["arc_length", "accept_residual"] {
                if self.t.contains_key(key) {
                    return Err(self.err(
                        key,
                        format!("{key} is given but the path is not arc length"),
                        format!("add path = \"arc_length\" or \"dissipation\", or remove {key}"),
                    ));
                }
            }
            return Ok(None);
        }
        if !pushed {
            return Err(self.err(
                "path",
                "arc-length path following needs a pushed block",
                "add push_block = \"<free rigid block>\" and push_displacement = <m> (the end of the path), or remove path",
            ));
        }
        Ok(Some(ArcLength {
            length: self.optional_number("arc_length", 0.0, 1e-15, 1e3)?,
            dissipation,
            accept: self.number("accept_residual", 0.0, 0.0, 0.1)?,
        }))
    }

    /// The time integration's settings of a dynamic analysis with step `dt` over
    /// `duration` (s) in `frame`.
    pub fn dynamics(&self, dt: f64, duration: f64, frame: Frame) -> Result<DynamicSettings> {
        let d = DynamicSettings::new(dt, duration);
        let scheme = match self.choice("integrator") {
            None | Some("hht") => Scheme::hht(self.number("alpha", 0.05, 0.0, 1.0 / 3.0)?),
            Some("newmark") => Scheme::newmark(),
            Some("generalized-alpha") => {
                Scheme::generalized_alpha(self.number("rho_inf", 0.8, 0.0, 1.0)?)
            }
            _ => {
                return Err(self.err(
                    "integrator",
                    "unknown integrator",
                    "use \"newmark\", \"hht\" or \"generalized-alpha\"",
                ))
            }
        };
        let rayleigh = match self.t.get("rayleigh") {
            None => d.rayleigh,
            Some(v) => {
                let r: Option<Vec<f64>> = v
                    .as_array()
                    .map(|a| a.iter().map(|v| as_number(v).unwrap_or(f64::NAN)).collect());
                match r {
                    Some(r) if r.len() == 2 && r.iter().all(|c| c.is_finite() && *c >= 0.0) => {
                        [r[0], r[1]]
                    }
                    _ => {
                        return Err(self.err(
                            "rayleigh",
                            "'rayleigh' must be two non-negative numbers [a0, a1]",
                            "for example rayleigh = [0.1, 0.001] (C = a0 M + a1 K)",
                        ))
                    }
                }
            }
        };
        let start = match self.choice("initial") {
            None | Some("static") => Start::Elastic,
            Some("equilibrium") => Start::Equilibrium,
            Some("rest") => Start::Rest,
            _ => return Err(self.err(
                "initial",
                "unknown initial state",
                "use \"static\" (elastic equilibrium of gravity returned to the joints' strength, default), \"equilibrium\" (static equilibrium of gravity under the joints' law) or \"rest\" (no contact force at t = 0)",
            )),
        };
        Ok(DynamicSettings {
            scheme,
            dt,
            duration,
            rayleigh,
            tolerance: self.number("tolerance", d.tolerance, 1e-14, 0.1)?,
            max_iterations: self.number("max_iterations", d.max_iterations as f64, 1.0, 1e6)?
                as usize,
            max_cuts: self.number("max_cuts", d.max_cuts as f64, 0.0, 30.0)? as usize,
            start,
            reset_on_impact: self.switch(
                "impact_reset",
                d.reset_on_impact,
                "impact_reset = true (default) or false",
            )?,
            inertia: self.switch(
                "inertia",
                d.inertia,
                "inertia = true (default: M ü kept) or false (pseudo-dynamic: C u̇ + F_int = F(t))",
            )?,
            adaptive: self.optional_number("adaptive_tolerance", 1e-6, 1e-15, 1.0)?,
            event_cuts: self.number("event_cuts", d.event_cuts as f64, 0.0, 30.0)? as usize,
            absolute: frame == Frame::Absolute,
        })
    }
}

/// A number as a scene would write it: 1e-14 rather than 0.00000000000001.
fn short(x: f64) -> String {
    if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e7) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// A TOML number (integer or float) as f64.
fn as_number(v: &toml::Value) -> Option<f64> {
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
}
