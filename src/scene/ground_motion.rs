//! Ground motion of a dynamic analysis (`[analysis] ground_motion`, docs/scene-reference.md): a
//! record read from a file (PEER `at2`, `csv` with columns t and acceleration, plain
//! `values` at a constant `dt`), values written inline, or an expression of the time `t`.
//!
//! The acceleration a_g(t) (m/s²) enters the relative-frame equation of motion as the
//! load −M ι a_g(t) (docs/theory.md §5). Between samples it is interpolated linearly; before
//! the first sample and after the last one it is zero (the record has ended).
//!
//! Errors name the scene line of the `ground_motion` key and, for a record, the record's
//! file and line, and say how to fix them.

use super::STANDARD_GRAVITY;
use std::path::{Path, PathBuf};

/// Direction of the shaking (the ι of docs/theory.md §5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    X,
    Y,
}

impl Direction {
    /// Component index (0 = x, 1 = y).
    pub fn index(self) -> usize {
        match self {
            Direction::X => 0,
            Direction::Y => 1,
        }
    }
}

/// How the ground motion enters a dynamic analysis (`[analysis] frame`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Frame {
    /// The frame of the ground: the fixed blocks stay put and the free blocks carry the
    /// load −M ι a_g(t) (docs/theory.md §5). The default.
    #[default]
    Relative,
    /// A fixed frame: the fixed blocks (the foundation) move with the ground, their
    /// displacement u_g(t) integrated from a_g along the time steps, and the free blocks
    /// follow through their contacts alone (docs/theory.md "Ground motion").
    Absolute,
}

/// Where the accelerations come from.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// Samples (t_i in s ascending, a_i in the record's units), linearly interpolated.
    Samples { t: Vec<f64>, a: Vec<f64> },
    /// An expression of t (s).
    Expression { text: String, expr: Expr },
}

/// A validated ground motion.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundMotion {
    pub source: Source,
    /// m/s² per unit of the record (9.81 for records in g) times `scale`.
    pub factor: f64,
    pub direction: Direction,
    /// The record file, when read from one.
    pub file: Option<PathBuf>,
}

impl GroundMotion {
    /// Ground acceleration a_g(t) (m/s²) along [`Self::direction`].
    pub fn acceleration(&self, t: f64) -> f64 {
        self.factor
            * match &self.source {
                Source::Expression { expr, .. } => expr.eval(t),
                Source::Samples { t: ts, a } => interpolate(ts, a, t),
            }
    }

    /// The acceleration vector (m/s²) at time t.
    pub fn vector(&self, t: f64) -> [f64; 2] {
        let mut v = [0.0; 2];
        v[self.direction.index()] = self.acceleration(t);
        v
    }
}

fn interpolate(ts: &[f64], a: &[f64], t: f64) -> f64 {
    let n = ts.len();
    if n == 0 || t < ts[0] || t > ts[n - 1] {
        return 0.0;
    }
    if n == 1 {
        return a[0];
    }
    // first sample after t
    let k = ts.partition_point(|&x| x <= t).clamp(1, n - 1);
    let (t0, t1) = (ts[k - 1], ts[k]);
    let w = if t1 > t0 { (t - t0) / (t1 - t0) } else { 1.0 };
    a[k - 1] + w * (a[k] - a[k - 1])
}

/// A ground-motion error: what, fix, and optionally the record file and its line.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionError {
    pub what: String,
    pub fix: String,
    /// The record file and 1-based line the error is about.
    pub at: Option<(PathBuf, Option<usize>)>,
}

fn merr(what: impl Into<String>, fix: impl Into<String>) -> MotionError {
    MotionError {
        what: what.into(),
        fix: fix.into(),
        at: None,
    }
}

const KEYS: &[&str] = &[
    "file",
    "format",
    "dt",
    "direction",
    "scale",
    "units",
    "expression",
    "values",
];

fn number(v: &toml::Value) -> Option<f64> {
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
}

/// The ground acceleration vector (m/s²) at time t of a set of components (one per
/// direction; none: no shaking).
pub fn vector(components: &[GroundMotion], t: f64) -> [f64; 2] {
    let mut v = [0.0; 2];
    for g in components {
        v[g.direction.index()] += g.acceleration(t);
    }
    v
}

/// Read `ground_motion`: one table `{ ... }` (one component), or an array of them, one per
/// direction (`[{ ..., direction = "x" }, { ..., direction = "y" }]`: the horizontal and
/// vertical components of a record shaking together). Relative file names are taken from
/// `base` (the scene file's directory). An error in the k-th table of an array says so.
pub fn components_from_toml(
    v: &toml::Value,
    base: Option<&Path>,
) -> Result<Vec<GroundMotion>, MotionError> {
    let Some(arr) = v.as_array() else {
        return Ok(vec![from_toml(v, base)?]);
    };
    if arr.is_empty() {
        return Err(merr(
            "'ground_motion' is an empty array",
            "give one table per direction, for example ground_motion = [{ file = \"ns.AT2\", direction = \"x\" }, { file = \"up.AT2\", direction = \"y\" }], or remove the key",
        ));
    }
    let mut out: Vec<GroundMotion> = Vec::with_capacity(arr.len());
    for (k, item) in arr.iter().enumerate() {
        let g = from_toml(item, base).map_err(|e| MotionError {
            what: format!("component #{} of {}: {}", k + 1, arr.len(), e.what),
            ..e
        })?;
        if out.iter().any(|o| o.direction == g.direction) {
            let d = if g.direction == Direction::X {
                "x"
            } else {
                "y"
            };
            return Err(merr(
                format!("component #{} of ground_motion is a second one along {d}", k + 1),
                "give at most one component per direction (direction = \"x\" and direction = \"y\"); scale or combine records before",
            ));
        }
        out.push(g);
    }
    Ok(out)
}

/// Read one `ground_motion = { ... }` table. Relative file names are taken from `base`
/// (the scene file's directory).
pub fn from_toml(v: &toml::Value, base: Option<&Path>) -> Result<GroundMotion, MotionError> {
    let t = v.as_table().ok_or_else(|| {
        merr(
            "'ground_motion' must be a table",
            "write ground_motion = { file = \"record.csv\", format = \"csv\" } or { expression = \"sin(3*t)\", units = \"g\" }",
        )
    })?;
    for k in t.keys() {
        if !KEYS.contains(&k.as_str()) {
            return Err(merr(
                format!("unknown ground_motion key '{k}'"),
                format!("use only: {}", KEYS.join(", ")),
            ));
        }
    }
    let string = |k: &str| -> Result<Option<&str>, MotionError> {
        match t.get(k) {
            None => Ok(None),
            Some(v) => v.as_str().map(Some).ok_or_else(|| {
                merr(
                    format!("ground_motion '{k}' must be a string"),
                    format!("write {k} = \"...\" in quotes"),
                )
            }),
        }
    };
    let num = |k: &str| -> Result<Option<f64>, MotionError> {
        match t.get(k) {
            None => Ok(None),
            Some(v) => number(v).map(Some).ok_or_else(|| {
                merr(
                    format!("ground_motion '{k}' must be a number"),
                    "write a number without quotes",
                )
            }),
        }
    };
    let direction = match string("direction")? {
        None | Some("x") | Some("X") => Direction::X,
        Some("y") | Some("Y") => Direction::Y,
        Some(d) => {
            return Err(merr(
                format!("unknown ground_motion direction '{d}'"),
                "use direction = \"x\" or \"y\"",
            ))
        }
    };
    let scale = num("scale")?.unwrap_or(1.0);
    if !scale.is_finite() {
        return Err(merr(
            format!("ground_motion scale {scale} is not finite"),
            "give a finite factor, for example scale = 1.0",
        ));
    }
    let units = match string("units")? {
        None | Some("g") => STANDARD_GRAVITY,
        Some("m/s2") | Some("m/s^2") | Some("m/s²") => 1.0,
        Some("gal") | Some("cm/s2") => 0.01,
        Some(u) => {
            return Err(merr(
                format!("unknown ground_motion units '{u}'"),
                "use units = \"g\" (default), \"m/s2\" or \"gal\"",
            ))
        }
    };
    let dt = num("dt")?;
    if let Some(dt) = dt {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(merr(
                format!("ground_motion dt must be a positive time in s, not {dt}"),
                "give the record's sampling interval, for example dt = 0.02",
            ));
        }
    }
    let given: Vec<&str> = ["file", "expression", "values"]
        .into_iter()
        .filter(|k| t.contains_key(*k))
        .collect();
    if given.len() != 1 {
        return Err(merr(
            if given.is_empty() {
                "ground_motion gives no acceleration".to_string()
            } else {
                format!("ground_motion gives both '{}' and '{}'", given[0], given[1])
            },
            "give exactly one of file = \"...\", expression = \"...\" or values = [...]",
        ));
    }
    let mut file = None;
    let source = match given[0] {
        "expression" => {
            if t.contains_key("format") {
                return Err(merr(
                    "ground_motion 'format' applies to files, not to an expression",
                    "remove format",
                ));
            }
            let text = string("expression")?.unwrap_or_default().to_string();
            let expr = Expr::parse(&text).map_err(|(col, what)| {
                merr(
                    format!("in the expression \"{text}\" at character {col}: {what}"),
                    "write a formula of t with + - * / ^, parentheses, numbers, pi and sin cos tan exp ln log10 sqrt abs min max, for example 0.8*t*exp(-0.5*t)*sin(t)",
                )
            })?;
            Source::Expression { text, expr }
        }
        "values" => {
            let arr = t["values"].as_array().ok_or_else(|| {
                merr(
                    "ground_motion 'values' must be an array of numbers",
                    "write values = [0.0, 0.01, ...]",
                )
            })?;
            let dt = dt.ok_or_else(|| {
                merr(
                    "ground_motion 'values' needs 'dt'",
                    "add dt = <sampling interval in s>",
                )
            })?;
            let mut a = Vec::with_capacity(arr.len());
            for (k, v) in arr.iter().enumerate() {
                match number(v) {
                    Some(x) if x.is_finite() => a.push(x),
                    _ => {
                        return Err(merr(
                            format!("ground_motion value #{} is not a finite number", k + 1),
                            "write the accelerations as plain numbers",
                        ))
                    }
                }
            }
            samples_from_values(a, dt)?
        }
        _ => {
            let name = string("file")?.unwrap_or_default();
            let path = match base {
                Some(b) if Path::new(name).is_relative() => b.join(name),
                _ => PathBuf::from(name),
            };
            let format = match string("format")? {
                Some(f) => f.to_ascii_lowercase(),
                None => match path
                    .extension()
                    .map(|e| e.to_string_lossy().to_ascii_lowercase())
                {
                    Some(e) if e == "at2" => "at2".into(),
                    Some(e) if e == "csv" => "csv".into(),
                    _ => "values".into(),
                },
            };
            let text = std::fs::read(&path).map_err(|e| MotionError {
                what: format!("cannot read the ground-motion record: {e}"),
                fix: "check the file name (relative names are taken from the scene's directory)"
                    .into(),
                at: Some((path.clone(), None)),
            })?;
            let text = String::from_utf8_lossy(&text);
            let at = |e: MotionError| MotionError {
                at: Some((path.clone(), e.at.and_then(|x| x.1))),
                ..e
            };
            let s = match format.as_str() {
                "at2" => read_at2(&text).map_err(at)?,
                "csv" => read_csv(&text).map_err(at)?,
                "values" => {
                    let dt = dt.ok_or_else(|| {
                        merr(
                            "format \"values\" needs 'dt'",
                            "add dt = <sampling interval in s> to ground_motion",
                        )
                    })?;
                    read_values(&text, dt).map_err(at)?
                }
                f => {
                    return Err(merr(
                        format!("unknown ground_motion format '{f}'"),
                        "use format = \"at2\", \"csv\" or \"values\"",
                    ))
                }
            };
            file = Some(path);
            s
        }
    };
    Ok(GroundMotion {
        source,
        factor: units * scale,
        direction,
        file,
    })
}

fn line_err(line: usize, what: impl Into<String>, fix: impl Into<String>) -> MotionError {
    MotionError {
        what: what.into(),
        fix: fix.into(),
        at: Some((PathBuf::new(), Some(line))),
    }
}

fn samples_from_values(a: Vec<f64>, dt: f64) -> Result<Source, MotionError> {
    if a.is_empty() {
        return Err(MotionError {
            what: "the ground-motion record holds no acceleration values".into(),
            fix: "give at least one value".into(),
            at: None,
        });
    }
    let t = (0..a.len()).map(|k| k as f64 * dt).collect();
    Ok(Source::Samples { t, a })
}

/// Parse one number of a record (Fortran `D` exponents accepted).
fn parse_num(tok: &str) -> Option<f64> {
    let v: f64 = tok
        .parse()
        .ok()
        .or_else(|| tok.replace(['D', 'd'], "E").parse().ok())?;
    v.is_finite().then_some(v)
}

/// Plain values: numbers separated by blanks or commas, any number per line, lines
/// starting with `#` or `%` are comments (the El Centro `.dat` layout).
fn read_values(text: &str, dt: f64) -> Result<Source, MotionError> {
    let mut a = Vec::new();
    for (k, l) in text.lines().enumerate() {
        let l = l.trim();
        if l.is_empty() || l.starts_with('#') || l.starts_with('%') {
            continue;
        }
        for tok in l
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
        {
            a.push(parse_num(tok).ok_or_else(|| {
                line_err(
                    k + 1,
                    format!("'{tok}' is not a number"),
                    "the record must hold only numbers (comment lines start with #)",
                )
            })?);
        }
    }
    samples_from_values(a, dt).map_err(|e| MotionError {
        at: Some((PathBuf::new(), None)),
        ..e
    })
}

/// CSV: two columns, time (s) and acceleration; a first line that is not numeric is a
/// header; `#` lines are comments. Times must increase.
fn read_csv(text: &str) -> Result<Source, MotionError> {
    let (mut ts, mut a) = (Vec::new(), Vec::new());
    let mut first = true;
    for (k, l) in text.lines().enumerate() {
        let l = l.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let cols: Vec<&str> = l.split([',', ';', '\t']).map(str::trim).collect();
        let nums: Option<Vec<f64>> = cols.iter().map(|c| parse_num(c)).collect();
        let is_first = first;
        first = false;
        let Some(nums) = nums else {
            if is_first {
                continue; // header
            }
            let bad = cols.iter().find(|c| parse_num(c).is_none()).unwrap_or(&"");
            return Err(line_err(
                k + 1,
                format!("'{bad}' is not a number"),
                "each line must be: time in s, acceleration",
            ));
        };
        if nums.len() < 2 {
            return Err(line_err(
                k + 1,
                format!("{} column(s), two expected", nums.len()),
                "each line must be: time in s, acceleration",
            ));
        }
        if let Some(&last) = ts.last() {
            if nums[0] <= last {
                return Err(line_err(
                    k + 1,
                    format!("time {} s does not increase (previous {last} s)", nums[0]),
                    "sort the record by time, without repeated times",
                ));
            }
        }
        ts.push(nums[0]);
        a.push(nums[1]);
    }
    if ts.is_empty() {
        return Err(MotionError {
            what: "the ground-motion record holds no data lines".into(),
            fix: "give lines of: time in s, acceleration".into(),
            at: None,
        });
    }
    Ok(Source::Samples { t: ts, a })
}

/// PEER strong-motion `.AT2`: three free header lines, the fourth with `NPTS=` and
/// `DT=` (or, in the older layout, the two numbers NPTS and DT first), then the values.
fn read_at2(text: &str) -> Result<Source, MotionError> {
    let lines: Vec<&str> = text.lines().collect();
    if lines.len() < 4 {
        return Err(line_err(
            lines.len().max(1),
            "the AT2 header is incomplete (4 lines expected)",
            "give the PEER header: 3 text lines, then NPTS= ..., DT= ... SEC",
        ));
    }
    let h = lines[3].to_ascii_uppercase();
    let after = |key: &str| -> Option<f64> {
        let i = h.find(key)?;
        let rest = h[i + key.len()..]
            .trim_start()
            .trim_start_matches('=')
            .trim_start();
        let tok: String = rest
            .chars()
            .take_while(|c| c.is_ascii_digit() || matches!(c, '.' | 'E' | '-' | '+'))
            .collect();
        tok.parse().ok()
    };
    let (npts, dt) = match (after("NPTS"), after("DT")) {
        (Some(n), Some(d)) if h.contains('=') => (n, d),
        _ => {
            let nums: Vec<f64> = h
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter_map(parse_num)
                .collect();
            if nums.len() < 2 {
                return Err(line_err(
                    4,
                    "no NPTS and DT in the AT2 header",
                    "line 4 must read like: NPTS=  7807, DT= .00500 SEC",
                ));
            }
            (nums[0], nums[1])
        }
    };
    if !(dt.is_finite() && dt > 0.0) {
        return Err(line_err(
            4,
            format!("DT = {dt} is not a positive time step"),
            "give the sampling interval in s after DT=",
        ));
    }
    if !(npts >= 1.0 && npts.fract() == 0.0) {
        return Err(line_err(
            4,
            format!("NPTS = {npts} is not a positive whole number"),
            "give the number of values after NPTS=",
        ));
    }
    let mut a = Vec::with_capacity(npts as usize);
    for (k, l) in lines.iter().enumerate().skip(4) {
        for tok in l.split_whitespace() {
            a.push(parse_num(tok).ok_or_else(|| {
                line_err(
                    k + 1,
                    format!("'{tok}' is not a number"),
                    "the values after the header must be numbers",
                )
            })?);
        }
    }
    if a.len() != npts as usize {
        return Err(line_err(
            lines.len(),
            format!(
                "the record holds {} values but its header says NPTS = {npts}",
                a.len()
            ),
            "correct NPTS or restore the missing values",
        ));
    }
    samples_from_values(a, dt)
}

/// An arithmetic expression of the time `t` (s).
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    Num(f64),
    T,
    Neg(Box<Expr>),
    Bin(char, Box<Expr>, Box<Expr>),
    Call(Func, Vec<Expr>),
}

/// Functions an expression may call.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    Sin,
    Cos,
    Tan,
    Exp,
    Ln,
    Log10,
    Sqrt,
    Abs,
    Sinh,
    Cosh,
    Tanh,
    Min,
    Max,
    Step,
}

const FUNCS: &[(&str, Func, usize)] = &[
    ("sin", Func::Sin, 1),
    ("cos", Func::Cos, 1),
    ("tan", Func::Tan, 1),
    ("exp", Func::Exp, 1),
    ("ln", Func::Ln, 1),
    ("log", Func::Ln, 1),
    ("log10", Func::Log10, 1),
    ("sqrt", Func::Sqrt, 1),
    ("abs", Func::Abs, 1),
    ("sinh", Func::Sinh, 1),
    ("cosh", Func::Cosh, 1),
    ("tanh", Func::Tanh, 1),
    ("min", Func::Min, 2),
    ("max", Func::Max, 2),
    ("step", Func::Step, 1),
];

impl Expr {
    /// Parse; the error gives the 1-based character position and what is wrong.
    pub fn parse(text: &str) -> Result<Expr, (usize, String)> {
        let mut p = ExprParser {
            s: text.chars().collect(),
            i: 0,
        };
        let e = p.sum()?;
        p.ws();
        if p.i < p.s.len() {
            return Err((p.i + 1, format!("unexpected '{}'", p.s[p.i])));
        }
        // evaluating at a few times finds nothing new, but a constant NaN would
        if e.eval(0.5).is_nan() && e.eval(1.5).is_nan() {
            return Err((1, "the expression is not a number for any t".into()));
        }
        Ok(e)
    }

    /// Value at time t (s); `step(x)` is 1 for x ≥ 0 and 0 otherwise.
    pub fn eval(&self, t: f64) -> f64 {
        match self {
            Expr::Num(x) => *x,
            Expr::T => t,
            Expr::Neg(a) => -a.eval(t),
            Expr::Bin(op, a, b) => {
                let (x, y) = (a.eval(t), b.eval(t));
                match op {
                    '+' => x + y,
                    '-' => x - y,
                    '*' => x * y,
                    '/' => x / y,
                    _ => x.powf(y),
                }
            }
            Expr::Call(f, args) => {
                let x = args[0].eval(t);
                match f {
                    Func::Sin => x.sin(),
                    Func::Cos => x.cos(),
                    Func::Tan => x.tan(),
                    Func::Exp => x.exp(),
                    Func::Ln => x.ln(),
                    Func::Log10 => x.log10(),
                    Func::Sqrt => x.sqrt(),
                    Func::Abs => x.abs(),
                    Func::Sinh => x.sinh(),
                    Func::Cosh => x.cosh(),
                    Func::Tanh => x.tanh(),
                    Func::Min => x.min(args[1].eval(t)),
                    Func::Max => x.max(args[1].eval(t)),
                    Func::Step => {
                        if x >= 0.0 {
                            1.0
                        } else {
                            0.0
                        }
                    }
                }
            }
        }
    }
}

struct ExprParser {
    s: Vec<char>,
    i: usize,
}

type PResult = Result<Expr, (usize, String)>;

impl ExprParser {
    fn ws(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_whitespace() {
            self.i += 1;
        }
    }
    fn peek(&mut self) -> Option<char> {
        self.ws();
        self.s.get(self.i).copied()
    }
    fn sum(&mut self) -> PResult {
        let mut e = self.product()?;
        while let Some(c @ ('+' | '-')) = self.peek() {
            self.i += 1;
            e = Expr::Bin(c, Box::new(e), Box::new(self.product()?));
        }
        Ok(e)
    }
    fn product(&mut self) -> PResult {
        let mut e = self.unary()?;
        loop {
            match self.peek() {
                Some('*') if self.s.get(self.i + 1) == Some(&'*') => break,
                Some(c @ ('*' | '/')) => {
                    self.i += 1;
                    e = Expr::Bin(c, Box::new(e), Box::new(self.unary()?));
                }
                _ => break,
            }
        }
        Ok(e)
    }
    fn unary(&mut self) -> PResult {
        match self.peek() {
            Some('-') => {
                self.i += 1;
                Ok(Expr::Neg(Box::new(self.unary()?)))
            }
            Some('+') => {
                self.i += 1;
                self.unary()
            }
            _ => self.power(),
        }
    }
    fn power(&mut self) -> PResult {
        let base = self.atom()?;
        match self.peek() {
            Some('^') => {
                self.i += 1;
            }
            Some('*') if self.s.get(self.i + 1) == Some(&'*') => {
                self.i += 2;
            }
            _ => return Ok(base),
        }
        Ok(Expr::Bin('^', Box::new(base), Box::new(self.unary()?)))
    }
    fn atom(&mut self) -> PResult {
        let start = self.i;
        match self.peek() {
            None => Err((self.s.len() + 1, "the expression ends too early".into())),
            Some('(') => {
                self.i += 1;
                let e = self.sum()?;
                if self.peek() != Some(')') {
                    return Err((self.i + 1, "')' expected".into()));
                }
                self.i += 1;
                Ok(e)
            }
            Some(c) if c.is_ascii_digit() || c == '.' => {
                let s0 = self.i;
                while self.i < self.s.len()
                    && (self.s[self.i].is_ascii_digit() || self.s[self.i] == '.')
                {
                    self.i += 1;
                }
                // exponent
                if self.i < self.s.len() && matches!(self.s[self.i], 'e' | 'E') {
                    let mut j = self.i + 1;
                    if j < self.s.len() && matches!(self.s[j], '+' | '-') {
                        j += 1;
                    }
                    if j < self.s.len() && self.s[j].is_ascii_digit() {
                        self.i = j;
                        while self.i < self.s.len() && self.s[self.i].is_ascii_digit() {
                            self.i += 1;
                        }
                    }
                }
                let tok: String = self.s[s0..self.i].iter().collect();
                tok.parse()
                    .map(Expr::Num)
                    .map_err(|_| (s0 + 1, format!("'{tok}' is not a number")))
            }
            Some(c) if c.is_ascii_alphabetic() || c == '_' => {
                let s0 = self.i;
                while self.i < self.s.len()
                    && (self.s[self.i].is_ascii_alphanumeric() || self.s[self.i] == '_')
                {
                    self.i += 1;
                }
                let name: String = self.s[s0..self.i].iter().collect();
                match name.as_str() {
                    "t" => return Ok(Expr::T),
                    "pi" => return Ok(Expr::Num(std::f64::consts::PI)),
                    "e" => return Ok(Expr::Num(std::f64::consts::E)),
                    _ => {}
                }
                let Some(&(_, f, arity)) = FUNCS.iter().find(|x| x.0 == name) else {
                    return Err((s0 + 1, format!("unknown name '{name}'")));
                };
                if self.peek() != Some('(') {
                    return Err((self.i + 1, format!("'(' expected after {name}")));
                }
                self.i += 1;
                let mut args = vec![self.sum()?];
                while self.peek() == Some(',') {
                    self.i += 1;
                    args.push(self.sum()?);
                }
                if self.peek() != Some(')') {
                    return Err((self.i + 1, "')' expected".into()));
                }
                self.i += 1;
                if args.len() != arity {
                    return Err((
                        s0 + 1,
                        format!("{name} takes {arity} argument(s), not {}", args.len()),
                    ));
                }
                Ok(Expr::Call(f, args))
            }
            Some(c) => Err((start.max(self.i) + 1, format!("unexpected '{c}'"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gm(text: &str) -> Result<GroundMotion, MotionError> {
        let v: toml::Table = format!("g = {text}").parse().unwrap();
        from_toml(&v["g"], None)
    }

    #[test]
    fn seed_accelerations() {
        let g = gm(r#"{ expression = "0.8*t*exp(-0.5*t)*sin(t)", units = "g" }"#).unwrap();
        for t in [0.0f64, 0.3, 2.0, 7.5] {
            let want = 0.8 * t * (-0.5 * t).exp() * t.sin() * 9.81;
            assert!((g.acceleration(t) - want).abs() < 1e-12);
        }
        let g = gm(r#"{ expression = "sin(3*t)", direction = "y", scale = 2 }"#).unwrap();
        assert_eq!(g.direction, Direction::Y);
        assert!((g.vector(0.4)[1] - 2.0 * 9.81 * 1.2f64.sin()).abs() < 1e-12);
    }

    #[test]
    fn expression_grammar() {
        let e = Expr::parse("-2^2 + 3*(1 - t)/2 + 2**3 + 1e-1*10 + max(t, 2) + pi*0").unwrap();
        assert!((e.eval(1.0) - (-4.0 + 0.0 + 8.0 + 1.0 + 2.0)).abs() < 1e-12);
        assert!(Expr::parse("exq(t)")
            .unwrap_err()
            .1
            .contains("unknown name 'exq'"));
        assert!(Expr::parse("sin(t").is_err());
        assert!(Expr::parse("2*").is_err());
        assert!(Expr::parse("t t").is_err());
        assert!(Expr::parse("min(t)").is_err());
    }

    #[test]
    fn records() {
        let s =
            read_at2("H1\nH2\nH3\nNPTS=  3, DT= .01000 SEC\n .1E+00  -.2E+00\n .3E+00\n").unwrap();
        assert_eq!(
            s,
            Source::Samples {
                t: vec![0.0, 0.01, 0.02],
                a: vec![0.1, -0.2, 0.3]
            }
        );
        let s = read_at2("H1\nH2\nH3\n   3   0.0100   NPTS, DT\n 0.1 -0.2 0.3\n").unwrap();
        assert!(matches!(s, Source::Samples { ref t, .. } if t.len() == 3));
        let e = read_at2("H1\nH2\nH3\nNPTS=  4, DT= .01000 SEC\n .1E+00  -.2E+00\n .3E+00\n")
            .unwrap_err();
        assert!(e.what.contains("NPTS = 4"), "{e:?}");
        let e = read_at2("H1\nH2\nH3\nNPTS=  2, DT= .01000 SEC\n .1E+00  x\n").unwrap_err();
        assert_eq!(e.at.unwrap().1, Some(5));
        let s = read_csv("t_s,acc_g\n0,0\n0.5,1\n1.0,0\n").unwrap();
        let Source::Samples { t, a } = &s else {
            panic!()
        };
        assert!((interpolate(t, a, 0.25) - 0.5).abs() < 1e-15);
        assert_eq!(interpolate(t, a, 1.5), 0.0);
        assert_eq!(
            read_csv("t,a\n0,0\n0,1\n").unwrap_err().at.unwrap().1,
            Some(3)
        );
        assert!(read_csv("t,a\n").is_err());
        let s = read_values("# c\n1 2 3\n4,5\n", 0.5).unwrap();
        let Source::Samples { t, .. } = &s else {
            panic!()
        };
        assert_eq!(t[4], 2.0);
        assert_eq!(
            read_values("1 2\n3 zz\n", 0.5).unwrap_err().at.unwrap().1,
            Some(2)
        );
        assert!(read_values("# nothing\n", 0.5).is_err());
    }

    #[test]
    fn bad_tables() {
        assert!(gm(r#"{ values = [1.0, 2.0], dt = 0.0 }"#)
            .unwrap_err()
            .what
            .contains("dt"));
        assert!(gm(r#"{ values = [1.0] }"#).is_err());
        assert!(gm(r#"{ values = [] , dt = 0.1}"#).is_err());
        assert!(gm(r#"{ expression = "t", file = "a.csv" }"#).is_err());
        assert!(gm(r#"{ expression = "t", directon = "x" }"#).is_err());
        assert!(gm(r#"{ expression = "t", direction = "z" }"#).is_err());
        let e = gm(r#"{ file = "/nonexistent/record.at2" }"#).unwrap_err();
        assert!(e.what.contains("cannot read"));
        assert_eq!(e.at.unwrap().0, PathBuf::from("/nonexistent/record.at2"));
    }
}
