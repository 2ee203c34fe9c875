//! The time-history figure of a dynamic run (`DIR/figures/history.png/.svg`, as the seed's
//! Fig. 6b draws it): the displacements ux and uy (m, relative to the ground, centroid of
//! each block; docs/theory.md §5) of the tracked blocks against the time t (s), read from the
//! columns `NAME.ux`, `NAME.uy` of history.csv (docs/outputs.md). Two panels, ux above and
//! uy below, sharing the time axis; one colour per block.

use super::figures::Format;
use crate::analysis::dynamics::History;
use crate::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Blocks drawn with a legend entry; more blocks are drawn without one.
const LEGEND_MAX: usize = 12;

/// The series of a history: block names with the row indices of their ux and uy.
fn series(h: &History) -> Vec<(String, usize, usize)> {
    h.columns
        .iter()
        .enumerate()
        .filter_map(|(i, c)| {
            let name = c.strip_suffix(".ux")?;
            let j = h.columns.iter().position(|d| *d == format!("{name}.uy"))?;
            Some((name.to_string(), i, j))
        })
        .collect()
}

/// Draw the displacement histories of `h` into `path`. An error when the history has no
/// time column or no tracked block.
pub fn history(path: &Path, title: &str, h: &History, format: Format) -> Result<()> {
    let t = h.columns.iter().position(|c| c == "t");
    let s = series(h);
    let Some(t) = t.filter(|_| !s.is_empty()) else {
        return Err(
            Error::new("the history has no time or displacement columns")
                .file(path)
                .fix("history.csv needs the columns t and NAME.ux, NAME.uy ([output] track)"),
        );
    };
    let err = |e: String| {
        Error::new(format!("cannot draw the figure: {e}"))
            .file(path)
            .fix("check that the directory is writable and a font is installed (fontconfig, e.g. fonts-dejavu-core)")
    };
    let size = (900, 760);
    match format {
        Format::Svg => draw(
            SVGBackend::new(path, size).into_drawing_area(),
            title,
            h,
            t,
            &s,
        ),
        Format::Png => draw(
            BitMapBackend::new(path, size).into_drawing_area(),
            title,
            h,
            t,
            &s,
        ),
    }
    .map_err(err)
}

/// Time intervals of a history figure drawn by their extremes (900 px wide: about two
/// a pixel; docs/decisions/0042-output-writer-thread.md).
const DRAWN_INTERVALS: usize = 2000;

/// The points (t, column `c`) of the line drawn (finite values only): every row, or for
/// more than 4 × [`DRAWN_INTERVALS`] rows, in each of that many equal intervals of
/// [t0, t1] the first, lowest, highest and last point, in time order: the line then
/// reaches the same extremes in every pixel column as through every row.
fn drawn(h: &History, t: usize, c: usize, t0: f64, t1: f64) -> Vec<(f64, f64)> {
    let points = h
        .rows
        .iter()
        .filter(|r| r[t].is_finite() && r[c].is_finite())
        .map(|r| (r[t], r[c]));
    if h.rows.len() <= 4 * DRAWN_INTERVALS {
        return points.collect();
    }
    let n = DRAWN_INTERVALS;
    let slot = |x: f64| (((x - t0) / (t1 - t0) * n as f64) as usize).min(n - 1);
    let mut out = Vec::with_capacity(4 * n);
    // the current interval and its first, lowest, highest and last points (row, point)
    type Kept = [(usize, (f64, f64)); 4];
    let mut cur: Option<(usize, Kept)> = None;
    let flush = |out: &mut Vec<(f64, f64)>, k: &Kept| {
        let mut k = *k;
        k.sort_by_key(|p| p.0);
        let mut last = usize::MAX;
        for (i, p) in k {
            if i != last {
                out.push(p);
                last = i;
            }
        }
    };
    for (i, p) in points.enumerate() {
        let s = slot(p.0);
        match &mut cur {
            Some((cs, k)) if *cs == s => {
                if p.1 < k[1].1 .1 {
                    k[1] = (i, p);
                }
                if p.1 > k[2].1 .1 {
                    k[2] = (i, p);
                }
                k[3] = (i, p);
            }
            _ => {
                if let Some((_, k)) = &cur {
                    flush(&mut out, k);
                }
                cur = Some((s, [(i, p); 4]));
            }
        }
    }
    if let Some((_, k)) = &cur {
        flush(&mut out, k);
    }
    out
}

/// The range [lo, hi] of the finite values of column `c` over the series, padded by 5 %
/// (and widened to ±1 µm when it is flat).
fn range(h: &History, cols: impl Iterator<Item = usize> + Clone) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for r in &h.rows {
        for c in cols.clone() {
            if r[c].is_finite() {
                lo = lo.min(r[c]);
                hi = hi.max(r[c]);
            }
        }
    }
    if lo > hi {
        return (-1e-6, 1e-6);
    }
    if hi - lo < 1e-6 {
        return (lo - 1e-6, hi + 1e-6);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    h: &History,
    t: usize,
    s: &[(String, usize, usize)],
) -> std::result::Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let caption = if title.is_empty() {
        "Displacement histories".to_string()
    } else {
        format!("Displacement histories: {title}")
    };
    let root = root.titled(&caption, ("sans-serif", 18)).map_err(e)?;
    let (t0, mut t1) = range(h, std::iter::once(t));
    t1 = t1.max(t0 + 1e-9);
    let panels = root.split_evenly((2, 1));
    for (p, (area, comp)) in panels.iter().zip(["ux", "uy"]).enumerate() {
        let col = |x: &(String, usize, usize)| if p == 0 { x.1 } else { x.2 };
        let (y0, y1) = range(h, s.iter().map(col));
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .build_cartesian_2d(t0..t1, y0..y1)
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("time t, s")
            .y_desc(format!("{comp}, m"))
            .y_label_formatter(&|v| {
                if super::figures::zero_tick(*v, y1 - y0) {
                    "0".to_string()
                } else {
                    format!("{v:.2e}")
                }
            })
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(e)?;
        for (k, x) in s.iter().enumerate() {
            let c = Palette99::pick(k).to_rgba();
            let line = chart
                .draw_series(LineSeries::new(
                    drawn(h, t, col(x), t0, t1),
                    c.stroke_width(2),
                ))
                .map_err(e)?;
            if k < LEGEND_MAX {
                line.label(x.0.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
            }
        }
        super::figures::draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    }
    root.present().map_err(e)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A long history is drawn through the first, lowest, highest and last point of each
    /// interval (found here by a plain scan of the rows), in time order; a short one
    /// through every point.
    #[test]
    fn long_histories_are_drawn_by_the_extremes_of_each_interval() {
        let rows = 78_001;
        let h = History {
            columns: ["t", "a.ux"].map(String::from).to_vec(),
            rows: (0..rows)
                .map(|k| {
                    let t = k as f64 * 5e-4;
                    // a spike at one row between smooth ones
                    let spike = if k == 40_000 { 1.0 } else { 0.0 };
                    vec![t, (7.0 * t).sin() * 1e-3 + 1e-4 * (k % 3) as f64 + spike]
                })
                .collect(),
            ..Default::default()
        };
        let (t0, t1) = (0.0, 39.0);
        let d = drawn(&h, 0, 1, t0, t1);
        assert!(d.len() <= 4 * DRAWN_INTERVALS && d.len() > 2 * DRAWN_INTERVALS);
        assert!(d.windows(2).all(|w| w[0].0 < w[1].0), "in time order");
        assert!(
            d.contains(&(h.rows[40_000][0], h.rows[40_000][1])),
            "the spike"
        );
        // each interval's extremes and ends, by a scan of all rows
        let n = DRAWN_INTERVALS as f64;
        let mut by: std::collections::BTreeMap<usize, Vec<(f64, f64)>> = Default::default();
        for r in &h.rows {
            let s = (((r[0] - t0) / (t1 - t0) * n) as usize).min(DRAWN_INTERVALS - 1);
            by.entry(s).or_default().push((r[0], r[1]));
        }
        for pts in by.values() {
            let lo = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            let hi = pts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
            for want in [pts[0], *pts.last().unwrap()] {
                assert!(d.contains(&want));
            }
            let mine: Vec<f64> = d
                .iter()
                .filter(|p| p.0 >= pts[0].0 && p.0 <= pts.last().unwrap().0)
                .map(|p| p.1)
                .collect();
            assert!(mine.contains(&lo) && mine.contains(&hi));
        }
        // short: every point
        let short = History {
            rows: h.rows[..8000].to_vec(),
            ..h.clone()
        };
        assert_eq!(drawn(&short, 0, 1, t0, t1).len(), 8000);
    }

    #[test]
    fn series_pair_the_columns_of_each_block() {
        let h = History {
            columns: [
                "t",
                "a.ux",
                "a.uy",
                "a.rz",
                "b.ux",
                "b.uy",
                "b.rz",
                "ground_ax",
            ]
            .map(String::from)
            .to_vec(),
            ..Default::default()
        };
        assert_eq!(
            series(&h),
            vec![("a".to_string(), 1, 2), ("b".to_string(), 4, 5)]
        );
    }
}
