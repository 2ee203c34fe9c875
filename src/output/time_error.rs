//! The figure of a benchmark table: run time (s, log scale) against error (log scale),
//! one marker per row, one series (colour and shape) per strategy or backend, one panel
//! per model size when the table has several. Drawn by the benchmarks (`--plot DIR`:
//! `benches/strategies.rs`, `dfem bench-solvers`) and again from their saved tables
//! (`--csv FILE`, then `dfem plot FILE.csv`), as docs/performance.md shows them.
//!
//! Which columns are drawn is read from the table's header ([`axes_of`]): [`STRATEGIES`]
//! (error of the critical load factor λ against λ_ref, wall time of the analysis) or
//! [`SOLVERS`] (true residual ‖b − A x‖₂ / ‖b‖₂ against set-up + factorization + solve).
//! A row without a positive error or time (the reference run, a run without λ, a failed
//! backend) cannot be placed on a log scale: it is left out and counted under the figure.

use super::bench_table::{leading_number, Table};
use super::figures::{create_figures_dir, draw_atomic, draw_legend, plot_err, Format};
use crate::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// The columns a figure is drawn from and how it is labelled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Axes {
    /// Short name: the figure files are `NAME_time_error.png` and `.svg`.
    pub name: &'static str,
    /// Column naming the series (strategy, backend).
    pub series: &'static str,
    /// Column grouping the rows into panels (model size), if any.
    pub group: Option<&'static str>,
    /// Column of the error (dimensionless) and of the run time (s).
    pub error: &'static str,
    pub time: &'static str,
    pub title: &'static str,
    pub error_label: &'static str,
    pub time_label: &'static str,
}

/// `benches/strategies.rs`: the capacity of rigid walls by each iteration strategy.
pub const STRATEGIES: Axes = Axes {
    name: "strategies",
    series: "strategy",
    group: Some("blocks"),
    error: "error",
    time: "wall time (s)",
    title: "Capacity of rigid walls: iteration strategies",
    error_label: "error of λ, |λ − λ_ref| / λ_ref",
    time_label: "wall time of the analysis, s",
};

/// `dfem bench-solvers`: the linear backends on one stiffness matrix.
pub const SOLVERS: Axes = Axes {
    name: "solvers",
    series: "backend",
    group: None,
    error: "true residual",
    time: "total (s)",
    title: "Linear backends on one stiffness matrix",
    error_label: "true residual ‖b − A x‖ / ‖b‖",
    time_label: "set-up + factorization + solve, s",
};

/// The kinds of tables known.
pub const KINDS: [Axes; 2] = [STRATEGIES, SOLVERS];

/// The kind of a table: the first of [`KINDS`] whose columns it has.
pub fn axes_of(table: &Table) -> Option<Axes> {
    KINDS.iter().copied().find(|a| {
        [Some(a.series), a.group, Some(a.error), Some(a.time)]
            .iter()
            .flatten()
            .all(|c| table.column(c).is_some())
    })
}

/// One row placed on the figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub series: String,
    /// The group cell ("" without groups).
    pub group: String,
    /// Error (dimensionless, > 0) and run time (s, > 0).
    pub error: f64,
    pub time_s: f64,
}

/// What a figure draws.
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    pub axes: Axes,
    /// The rows with a positive error and time, in table order.
    pub points: Vec<Point>,
    /// Rows left out (no positive error or time).
    pub left_out: usize,
    /// Series and groups in order of first appearance (among all rows).
    pub series: Vec<String>,
    pub groups: Vec<String>,
}

impl Plot {
    /// The figure of `table` with the columns of `axes`; an error names a missing column.
    pub fn new(table: &Table, axes: Axes) -> Result<Plot> {
        let col = |name: &str| {
            table.column(name).ok_or_else(|| {
                Error::new(format!("the table has no column '{name}'"))
                    .place(format!("header: {}", table.header.join(", ")))
                    .fix("draw a table written by benches/strategies.rs or dfem bench-solvers (--csv FILE)")
            })
        };
        let (s, e, t) = (col(axes.series)?, col(axes.error)?, col(axes.time)?);
        let g = axes.group.map(col).transpose()?;
        let mut plot = Plot {
            axes,
            points: Vec::new(),
            left_out: 0,
            series: Vec::new(),
            groups: Vec::new(),
        };
        for r in &table.rows {
            let series = r[s].replace('`', "");
            let group = g.map(|g| r[g].clone()).unwrap_or_default();
            if !plot.series.contains(&series) {
                plot.series.push(series.clone());
            }
            if !plot.groups.contains(&group) {
                plot.groups.push(group.clone());
            }
            let positive = |c: &str| leading_number(c).filter(|v| v.is_finite() && *v > 0.0);
            match (positive(&r[e]), positive(&r[t])) {
                (Some(error), Some(time_s)) => plot.points.push(Point {
                    series,
                    group,
                    error,
                    time_s,
                }),
                _ => plot.left_out += 1,
            }
        }
        Ok(plot)
    }

    /// The error and time ranges drawn: whole decades around the points.
    pub fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        (
            decades(self.points.iter().map(|p| p.error)),
            decades(self.points.iter().map(|p| p.time_s)),
        )
    }

    /// The file stem of the figure: `NAME_time_error`.
    pub fn stem(&self) -> String {
        format!("{}_time_error", self.axes.name)
    }
}

/// The smallest range [10ᵃ, 10ᵇ], a < b integers, that holds the positive `values`
/// (10⁻¹ to 10⁰ when there are none).
pub fn decades(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if !(lo > 0.0 && lo.is_finite() && hi.is_finite()) {
        return (0.1, 1.0);
    }
    let mut a = lo.log10().floor() as i32;
    let mut b = hi.log10().ceil() as i32;
    // rounding of log10 near an exact power: keep 10ᵃ ≤ lo and hi ≤ 10ᵇ
    if pow10(a) > lo {
        a -= 1;
    }
    if pow10(b) < hi {
        b += 1;
    }
    (pow10(a), pow10(b.max(a + 1)))
}

/// 10ᵏ as the nearest f64 (as the literal `1eK` reads).
fn pow10(k: i32) -> f64 {
    format!("1e{k}").parse().expect("a power of ten")
}

/// Colours of the series (RGB), in order; the shapes cycle through circle, triangle,
/// square and diamond, so series k and k + 10 differ in shape.
pub const COLORS: [(u8, u8, u8); 10] = [
    (31, 90, 180),
    (220, 110, 20),
    (40, 150, 60),
    (200, 30, 40),
    (130, 80, 180),
    (140, 80, 60),
    (220, 90, 170),
    (0, 160, 170),
    (170, 170, 20),
    (90, 90, 220),
];

/// Colour and shape (0 circle, 1 triangle, 2 square, 3 diamond) of series `k`.
pub fn series_style(k: usize) -> (RGBColor, usize) {
    let (r, g, b) = COLORS[k % COLORS.len()];
    (RGBColor(r, g, b), k % 4)
}

/// Draw `pts` as filled markers of `shape` (about 10 px across) and `color`, with a legend
/// entry `label` showing the same marker.
fn markers<'a, DB: DrawingBackend + 'a, X: Ranged<ValueType = f64>, Y: Ranged<ValueType = f64>>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    pts: Vec<(f64, f64)>,
    shape: usize,
    color: RGBColor,
    label: &str,
) -> std::result::Result<(), String> {
    let style = color.filled();
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    // the square and the diamond in pixels around the point
    const SQUARE: [(i32, i32); 2] = [(-5, -5), (5, 5)];
    const DIAMOND: [(i32, i32); 4] = [(0, -6), (6, 0), (0, 6), (-6, 0)];
    let pts = pts.into_iter();
    let series = match shape {
        0 => chart
            .draw_series(pts.map(|at| Circle::new(at, 5, style)))
            .map_err(e)?
            .legend(move |at| Circle::new(at, 5, style)),
        1 => chart
            .draw_series(pts.map(|at| TriangleMarker::new(at, 6, style)))
            .map_err(e)?
            .legend(move |at| TriangleMarker::new(at, 6, style)),
        2 => chart
            .draw_series(pts.map(|at| EmptyElement::at(at) + Rectangle::new(SQUARE, style)))
            .map_err(e)?
            .legend(move |at| EmptyElement::at(at) + Rectangle::new(SQUARE, style)),
        _ => chart
            .draw_series(pts.map(|at| EmptyElement::at(at) + Polygon::new(DIAMOND, style)))
            .map_err(e)?
            .legend(move |at| EmptyElement::at(at) + Polygon::new(DIAMOND, style)),
    };
    series.label(label);
    Ok(())
}

/// Panel width and height (px).
const PANEL: (u32, u32) = (620, 560);
/// Height of the title and of the note under the panels (px).
const TITLE_H: u32 = 40;
const NOTE_H: u32 = 30;

/// Draw `plot` into `path`.
pub fn draw(path: &Path, plot: &Plot, format: Format) -> Result<()> {
    let n = plot.groups.len().max(1) as u32;
    let size = (PANEL.0 * n, PANEL.1 + TITLE_H + NOTE_H);
    match format {
        Format::Svg => draw_on(SVGBackend::new(path, size).into_drawing_area(), plot),
        Format::Png => draw_on(BitMapBackend::new(path, size).into_drawing_area(), plot),
    }
    .map_err(plot_err(path))
}

fn draw_on<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    plot: &Plot,
) -> std::result::Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let h = root.dim_in_pixel().1;
    let (head, rest) = root.split_vertically(TITLE_H);
    let (body, foot) = rest.split_vertically(h - TITLE_H - NOTE_H);
    head.draw_text(
        plot.axes.title,
        &("sans-serif", 20).into_text_style(&head),
        (15, 12),
    )
    .map_err(e)?;
    let total = plot.points.len() + plot.left_out;
    let note = if plot.left_out > 0 {
        format!(
            "{} of {total} rows drawn; {} without a positive {} or time (reference runs, failed runs) are left out",
            plot.points.len(),
            plot.left_out,
            plot.axes.error
        )
    } else {
        format!("{total} rows drawn")
    };
    foot.draw_text(&note, &("sans-serif", 14).into_text_style(&foot), (15, 6))
        .map_err(e)?;
    let ((x0, x1), (y0, y1)) = plot.ranges();
    // the ends are exact decades: widen by 1e-9 so that rounding keeps their ticks
    let (x0, x1, y0, y1) = (
        x0 * (1.0 - 1e-9),
        x1 * (1.0 + 1e-9),
        y0 * (1.0 - 1e-9),
        y1 * (1.0 + 1e-9),
    );
    let groups: Vec<String> = if plot.groups.is_empty() {
        vec![String::new()]
    } else {
        plot.groups.clone()
    };
    let panels = body.split_evenly((1, groups.len()));
    for (area, group) in panels.iter().zip(&groups) {
        let mut builder = ChartBuilder::on(area);
        builder
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(65);
        if let Some(g) = plot.axes.group.filter(|_| !group.is_empty()) {
            builder.caption(format!("{group} {g}"), ("sans-serif", 17));
        }
        let mut chart = builder
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc(plot.axes.error_label)
            .y_desc(plot.axes.time_label)
            .x_label_formatter(&|v| tick_label(*v, x1 / x0))
            .y_label_formatter(&|v| tick_label(*v, y1 / y0))
            .light_line_style(RGBColor(238, 238, 238))
            .draw()
            .map_err(e)?;
        for (k, name) in plot.series.iter().enumerate() {
            let (color, shape) = series_style(k);
            let pts: Vec<(f64, f64)> = plot
                .points
                .iter()
                .filter(|p| &p.series == name && &p.group == group)
                .map(|p| (p.error, p.time_s))
                .collect();
            if pts.is_empty() {
                continue;
            }
            markers(&mut chart, pts, shape, color, name)?;
        }
        let mine = plot.points.iter().filter(|p| &p.group == group);
        draw_legend(&mut chart, legend_corner(mine, (x0, x1), (y0, y1)))?;
    }
    root.present().map_err(e)?;
    Ok(())
}

/// The corner of the legend: the one whose quarter of the panel (in log coordinates)
/// holds the fewest points; on ties upper right, upper left, lower right, lower left.
fn legend_corner<'a>(
    points: impl Iterator<Item = &'a Point>,
    x: (f64, f64),
    y: (f64, f64),
) -> SeriesLabelPosition {
    let frac = |v: f64, r: (f64, f64)| (v / r.0).ln() / (r.1 / r.0).ln();
    let mut count = [0usize; 4];
    for p in points {
        let right = frac(p.error, x) > 0.5;
        let upper = frac(p.time_s, y) > 0.5;
        count[match (upper, right) {
            (true, true) => 0,
            (true, false) => 1,
            (false, true) => 2,
            (false, false) => 3,
        }] += 1;
    }
    let best = (0..4).min_by_key(|&k| (count[k], k)).unwrap_or(0);
    [
        SeriesLabelPosition::UpperRight,
        SeriesLabelPosition::UpperLeft,
        SeriesLabelPosition::LowerRight,
        SeriesLabelPosition::LowerLeft,
    ][best]
        .clone()
}

/// Tick labels of a log axis spanning the ratio `span`: `1e-3` at decades, and `2e-3`,
/// `5e-3` between them when the axis spans one decade; none at other ticks.
fn tick_label(v: f64, span: f64) -> String {
    let k = v.log10().floor();
    let m = v / 10f64.powf(k);
    let near = |t: f64| (m - t).abs() < 1e-6 * t;
    let m = if near(1.0) || near(10.0) {
        if near(10.0) {
            return format!("1e{}", k + 1.0);
        }
        1
    } else if span <= 10.0 * (1.0 + 1e-6) && near(2.0) {
        2
    } else if span <= 10.0 * (1.0 + 1e-6) && near(5.0) {
        5
    } else {
        return String::new();
    };
    format!("{m}e{k}")
}

/// Draw `plot` into `dir` (created) as `STEM.png` / `.svg` for each of `formats`, each file
/// whole or absent; `stem` `None`: [`Plot::stem`]. Returns the files written.
pub fn write(
    dir: &Path,
    stem: Option<&str>,
    plot: &Plot,
    formats: &[Format],
) -> Result<Vec<PathBuf>> {
    create_figures_dir(dir)?;
    let stem = stem.map_or_else(|| plot.stem(), str::to_string);
    let mut written = Vec::new();
    for &f in formats {
        let path = dir.join(format!("{stem}.{}", f.extension()));
        draw_atomic(&path, |tmp| draw(tmp, plot, f))?;
        written.push(path);
    }
    Ok(written)
}

/// Draw a table saved by a benchmark (`--csv FILE`) into `dir`, as the benchmark's
/// `--plot DIR` draws it.
pub fn redraw(csv: &Path, dir: &Path, formats: &[Format]) -> Result<Vec<PathBuf>> {
    let table = Table::read_csv(csv)?;
    let axes = axes_of(&table).ok_or_else(|| {
        Error::new(format!(
            "the table has none of the column sets of a benchmark (header: {})",
            table.header.join(", ")
        ))
        .file(csv)
        .fix("give a CSV written by benches/strategies.rs or dfem bench-solvers with --csv FILE")
    })?;
    write(dir, None, &Plot::new(&table, axes)?, formats)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decades_hold_the_values_and_are_powers_of_ten() {
        assert_eq!(decades([2.7e-11, 3.7e-11].into_iter()), (1e-11, 1e-10));
        assert_eq!(decades([0.14, 12.67].into_iter()), (0.1, 100.0));
        // exact powers stay the ends, a single power gets one decade above it
        assert_eq!(decades([1e-3, 1e-1].into_iter()), (1e-3, 1e-1));
        assert_eq!(decades([1.0].into_iter()), (1.0, 10.0));
        assert_eq!(decades(std::iter::empty()), (0.1, 1.0));
    }

    #[test]
    fn tick_labels_at_decades_and_at_2_and_5_on_short_axes() {
        assert_eq!(tick_label(1e-3, 1e3), "1e-3");
        assert_eq!(tick_label(100.0, 1e3), "1e2");
        assert_eq!(tick_label(0.9999999999 * 1e-2, 1e3), "1e-2");
        assert_eq!(tick_label(2e-3, 1e3), "");
        assert_eq!(tick_label(2e-3, 1e2), "");
        assert_eq!(tick_label(2e-3, 10.0), "2e-3");
        assert_eq!(tick_label(5.0, 10.0), "5e0");
        assert_eq!(tick_label(3.0, 10.0), "");
    }

    #[test]
    fn the_kind_of_a_table_is_read_from_its_header() {
        let solvers = Table::new(&["backend", "total (s)", "true residual"]);
        assert_eq!(axes_of(&solvers), Some(SOLVERS));
        let strategies = Table::new(&["blocks", "strategy", "error", "wall time (s)"]);
        assert_eq!(axes_of(&strategies), Some(STRATEGIES));
        assert_eq!(axes_of(&Table::new(&["a", "b"])), None);
    }
}
