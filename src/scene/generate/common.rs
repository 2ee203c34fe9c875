//! Shared pieces of the generators: parameter parsing and validation, and the polygon
//! helpers (cleaning, welding, hole splitting) around `geo::BooleanOps`.

use std::collections::HashMap;

use geo::{BooleanOps, Coord, LineString, MultiPolygon, Polygon};
use serde::de::DeserializeOwned;

use super::{GenError, GeneratedBlock};

pub type P = [f64; 2];

/// Largest number of blocks a generator may produce.
pub const MAX_BLOCKS: usize = 2_000_000;

pub fn gen_err(key: Option<&str>, what: impl Into<String>, fix: impl Into<String>) -> GenError {
    GenError {
        key: key.map(str::to_string),
        what: what.into(),
        fix: fix.into(),
    }
}

/// Parse a generator's parameter table into `T`. `keys` lists (key, what it takes).
///
/// Unknown keys are reported with the list of valid ones; a value of the wrong type is
/// reported under its own key (found by deserialising each key alone, which works since
/// every field has a default).
pub fn parse_params<T: DeserializeOwned>(
    kind: &str,
    params: &toml::Table,
    keys: &[(&str, &str)],
) -> Result<T, GenError> {
    let names: Vec<&str> = keys.iter().map(|k| k.0).collect();
    for k in params.keys() {
        if !names.contains(&k.as_str()) {
            return Err(gen_err(
                Some(k),
                format!("unknown key '{k}' for generator '{kind}'"),
                format!("use only the keys {}", names.join(", ")),
            ));
        }
    }
    match toml::Value::Table(params.clone()).try_into::<T>() {
        Ok(v) => Ok(v),
        Err(e) => {
            let msg = e.to_string().trim().replace('\n', " ");
            for (k, v) in params {
                let mut one = toml::Table::new();
                one.insert(k.clone(), v.clone());
                if let Err(e1) = toml::Value::Table(one).try_into::<T>() {
                    let hint = keys.iter().find(|x| x.0 == k).map_or("", |x| x.1);
                    return Err(gen_err(
                        Some(k),
                        format!(
                            "key '{k}' has a wrong value: {}",
                            e1.to_string().trim().replace('\n', " ")
                        ),
                        format!("give {k} = {hint}"),
                    ));
                }
            }
            Err(gen_err(
                None,
                format!("bad parameters for generator '{kind}': {msg}"),
                "check the keys and their types",
            ))
        }
    }
}

/// A finite number > 0.
pub fn positive(key: &str, v: f64, unit: &str) -> Result<f64, GenError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(gen_err(
            Some(key),
            format!("{key} must be a positive number, got {v}"),
            format!("give {key} > 0 ({unit})"),
        ))
    }
}

/// A finite number ≥ 0.
pub fn non_negative(key: &str, v: f64, unit: &str) -> Result<f64, GenError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(gen_err(
            Some(key),
            format!("{key} must be zero or positive, got {v}"),
            format!("give {key} >= 0 ({unit})"),
        ))
    }
}

pub fn finite(key: &str, v: f64) -> Result<f64, GenError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(gen_err(
            Some(key),
            format!("{key} must be a finite number, got {v}"),
            format!("give a finite {key}"),
        ))
    }
}

/// A count ≥ 1.
pub fn count(key: &str, v: usize) -> Result<usize, GenError> {
    if v >= 1 {
        Ok(v)
    } else {
        Err(gen_err(
            Some(key),
            format!("{key} must be at least 1, got 0"),
            format!("give {key} >= 1"),
        ))
    }
}

/// Refuse absurd sizes before building anything.
pub fn check_count(key: &str, n: f64) -> Result<(), GenError> {
    if n.is_nan() || n > MAX_BLOCKS as f64 {
        return Err(gen_err(
            Some(key),
            format!("these parameters would make about {n:.0} blocks, more than the limit of {MAX_BLOCKS}"),
            "use fewer or larger blocks",
        ));
    }
    Ok(())
}

pub fn block(name: impl Into<String>, vertices: Vec<P>, fixed: bool) -> GeneratedBlock {
    GeneratedBlock {
        name: name.into(),
        vertices,
        fixed,
        unit: None,
    }
}

/// Axis-aligned rectangle, counter-clockwise.
pub fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<P> {
    vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
}

/// Signed area (positive for counter-clockwise).
pub fn signed_area(p: &[P]) -> f64 {
    let n = p.len();
    let mut a = 0.0;
    for i in 0..n {
        let (u, v) = (p[i], p[(i + 1) % n]);
        a += u[0] * v[1] - v[0] * u[1];
    }
    0.5 * a
}

pub fn to_ring(p: &[P]) -> LineString<f64> {
    let mut c: Vec<Coord<f64>> = p.iter().map(|q| Coord { x: q[0], y: q[1] }).collect();
    if let Some(&f) = c.first() {
        c.push(f);
    }
    LineString(c)
}

pub fn to_poly(p: &[P]) -> Polygon<f64> {
    Polygon::new(to_ring(p), vec![])
}

fn ring_points(r: &LineString<f64>) -> Vec<P> {
    let mut v: Vec<P> = r.0.iter().map(|c| [c.x, c.y]).collect();
    if v.len() > 1 && v.first() == v.last() {
        v.pop();
    }
    v
}

/// Remove repeated vertices (closer than `tol`) and vertices within `tol` of the line
/// through their neighbours; orient counter-clockwise. Returns `None` if fewer than three
/// vertices remain.
pub fn clean(mut p: Vec<P>, tol: f64) -> Option<Vec<P>> {
    loop {
        let n = p.len();
        if n < 3 {
            return None;
        }
        let mut removed = false;
        for i in 0..n {
            let a = p[(i + n - 1) % n];
            let b = p[i];
            let c = p[(i + 1) % n];
            let (dx, dy) = (c[0] - a[0], c[1] - a[1]);
            let len = dx.hypot(dy);
            let dup = (b[0] - a[0]).hypot(b[1] - a[1]) <= tol;
            let off = if len > 0.0 {
                ((b[0] - a[0]) * dy - (b[1] - a[1]) * dx).abs() / len
            } else {
                0.0
            };
            // collinear: b on the line ac; a spike (b beyond c and back) also goes.
            if dup || off <= tol {
                p.remove(i);
                removed = true;
                break;
            }
        }
        if !removed {
            break;
        }
    }
    if signed_area(&p) < 0.0 {
        p.reverse();
    }
    Some(p)
}

/// Split every polygon that has holes with a vertical line through the centroid of its
/// first hole (intersections with two half-planes), until none has holes.
pub fn split_holes(polys: Vec<Polygon<f64>>) -> Vec<Polygon<f64>> {
    let mut out = Vec::new();
    let mut stack = polys;
    let mut guard = 0usize;
    while let Some(p) = stack.pop() {
        if p.interiors().is_empty() || guard > 100_000 {
            out.push(p);
            continue;
        }
        guard += 1;
        let hole = ring_points(&p.interiors()[0]);
        let xc = hole.iter().map(|q| q[0]).sum::<f64>() / hole.len() as f64;
        let ext = ring_points(p.exterior());
        let (mut y0, mut y1, mut x0, mut x1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for q in &ext {
            x0 = x0.min(q[0]);
            x1 = x1.max(q[0]);
            y0 = y0.min(q[1]);
            y1 = y1.max(q[1]);
        }
        let m = (x1 - x0).max(y1 - y0) + 1.0;
        let left = to_poly(&rect(x0 - m, y0 - m, xc, y1 + m));
        let right = to_poly(&rect(xc, y0 - m, x1 + m, y1 + m));
        for half in [left, right] {
            stack.extend(p.intersection(&half).0);
        }
    }
    out
}

/// Exterior rings of a multipolygon (holes split first), as point lists.
pub fn pieces(mp: MultiPolygon<f64>) -> Vec<Vec<P>> {
    split_holes(mp.0)
        .iter()
        .map(|p| ring_points(p.exterior()))
        .collect()
}

/// Merge vertices closer than `tol` (over all polygons) into the first one seen, so that
/// touching blocks share their vertices exactly.
pub fn weld(polys: &mut [Vec<P>], tol: f64) {
    let cell = 4.0 * tol;
    let key = |q: P| ((q[0] / cell).floor() as i64, (q[1] / cell).floor() as i64);
    let mut grid: HashMap<(i64, i64), Vec<P>> = HashMap::new();
    for poly in polys.iter_mut() {
        for q in poly.iter_mut() {
            let (i, j) = key(*q);
            let mut found = None;
            'search: for di in -1..=1 {
                for dj in -1..=1 {
                    if let Some(v) = grid.get(&(i + di, j + dj)) {
                        for r in v {
                            if (r[0] - q[0]).hypot(r[1] - q[1]) <= tol {
                                found = Some(*r);
                                break 'search;
                            }
                        }
                    }
                }
            }
            match found {
                Some(r) => *q = r,
                None => grid.entry((i, j)).or_default().push(*q),
            }
        }
    }
}

/// Snap `v` to the nearest of `known` when closer than `tol`.
pub fn snap_to(v: f64, known: &[f64], tol: f64) -> f64 {
    let mut best = v;
    let mut d = tol;
    for &k in known {
        if (k - v).abs() <= d {
            d = (k - v).abs();
            best = k;
        }
    }
    best
}
