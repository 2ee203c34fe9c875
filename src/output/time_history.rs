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
                    h.rows
                        .iter()
                        .filter(|r| r[t].is_finite() && r[col(x)].is_finite())
                        .map(|r| (r[t], r[col(x)])),
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
