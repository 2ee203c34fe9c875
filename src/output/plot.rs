//! Figures drawn with `plotters` (PNG or SVG by the file's extension).

use crate::{Error, Result};
use plotters::prelude::*;
use std::path::Path;

/// One computed point of the Hoek–Bray chart.
#[derive(Debug, Clone, PartialEq)]
pub struct ModePoint {
    /// Slope angle α (degrees).
    pub alpha: f64,
    /// Aspect ratio b/d of the block.
    pub ratio: f64,
    /// "stable" | "sliding" | "toppling" | "sliding+toppling".
    pub mode: String,
}

fn plot_err(path: &Path) -> impl Fn(String) -> Error + '_ {
    move |e| {
        Error::new(format!("cannot draw the figure: {e}"))
            .file(path)
            .fix("check that the directory is writable")
    }
}

/// The Hoek and Bray (1977) chart of one block on an incline (seed Fig. 3): b/d against
/// the slope angle α, the boundaries α = φ and b/d = tan α, and the computed modes.
pub fn hoek_bray_chart(path: &Path, phi_deg: f64, points: &[ModePoint]) -> Result<()> {
    let svg = path.extension().is_some_and(|e| e == "svg");
    if svg {
        let root = SVGBackend::new(path, (800, 640)).into_drawing_area();
        draw_hoek_bray(root, phi_deg, points).map_err(plot_err(path))
    } else {
        let root = BitMapBackend::new(path, (800, 640)).into_drawing_area();
        draw_hoek_bray(root, phi_deg, points).map_err(plot_err(path))
    }
}

fn draw_hoek_bray<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    phi: f64,
    points: &[ModePoint],
) -> std::result::Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("One block on an incline, φ = {phi}°: DFEM against Hoek and Bray (1977)"),
            ("sans-serif", 20),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(55)
        .build_cartesian_2d(0.0..2.1f64, 0.0..62.0f64)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("block breadth / height, b/d")
        .y_desc("slope angle α (degrees)")
        .light_line_style(WHITE)
        .draw()
        .map_err(e)?;
    // boundaries: α = φ and b/d = tan α
    chart
        .draw_series(LineSeries::new(
            [(0.0, phi), (2.1, phi)],
            BLACK.stroke_width(2),
        ))
        .map_err(e)?;
    chart
        .draw_series(LineSeries::new(
            (0..=120)
                .map(|i| {
                    let a = 0.5 * i as f64;
                    (a.to_radians().tan(), a)
                })
                .filter(|p| p.0 <= 2.1),
            BLACK.stroke_width(2),
        ))
        .map_err(e)?;
    let style = |mode: &str| match mode {
        "stable" => (GREEN.mix(0.9), 0),
        "sliding" => (BLUE.mix(0.9), 1),
        "toppling" => (RED.mix(0.9), 2),
        _ => (MAGENTA.mix(0.9), 3),
    };
    for (label, mode) in [
        ("stable", "stable"),
        ("sliding", "sliding"),
        ("toppling", "toppling"),
        ("sliding and toppling", "sliding+toppling"),
    ] {
        let (color, shape) = style(mode);
        let pts: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.mode == mode)
            .map(|p| (p.ratio, p.alpha))
            .collect();
        let series = chart
            .draw_series(pts.iter().map(|&(x, y)| -> DynElement<DB, (f64, f64)> {
                match shape {
                    0 => Circle::new((x, y), 3, color.filled()).into_dyn(),
                    1 => TriangleMarker::new((x, y), 4, color.filled()).into_dyn(),
                    2 => Cross::new((x, y), 4, color.stroke_width(2)).into_dyn(),
                    _ => {
                        Rectangle::new([(x - 0.012, y - 0.5), (x + 0.012, y + 0.5)], color.filled())
                            .into_dyn()
                    }
                }
            }))
            .map_err(e)?;
        series
            .label(label)
            .legend(move |(x, y)| Circle::new((x, y), 4, color.filled()));
    }
    super::figures::draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(e)?;
    Ok(())
}

/// One computed load–displacement curve of [`load_displacement_chart`]: its label, its
/// points (displacement mm, load kN) and its colour index.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveSeries {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub color: usize,
    /// Dashed (a coarser model of the same wall).
    pub dashed: bool,
    /// Drawn as its points (squares, 4 px) joined by a thin line: a reference curve
    /// digitised from a published figure, not a computed one.
    pub markers: bool,
}

/// A reference band of [`load_displacement_chart`]: a load (kN) with a relative width
/// (the band is load × (1 ± width)), its label and colour index.
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    pub label: String,
    pub load: f64,
    pub width: f64,
    pub color: usize,
}

const CURVE_COLORS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// Load (kN) against displacement (mm) of pushed walls (docs/performance.md, "Eindhoven
/// walls"): one line per computed curve, and reference loads as shaded bands.
pub fn load_displacement_chart(
    path: &Path,
    title: &str,
    curves: &[CurveSeries],
    bands: &[Band],
) -> Result<()> {
    let svg = path.extension().is_some_and(|e| e == "svg");
    if svg {
        let root = SVGBackend::new(path, (900, 640)).into_drawing_area();
        draw_load_displacement(root, title, curves, bands).map_err(plot_err(path))
    } else {
        let root = BitMapBackend::new(path, (900, 640)).into_drawing_area();
        draw_load_displacement(root, title, curves, bands).map_err(plot_err(path))
    }
}

fn draw_load_displacement<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    curves: &[CurveSeries],
    bands: &[Band],
) -> std::result::Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let xmax = curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.0))
        .fold(1.0f64, f64::max);
    let ymax = curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.1))
        .chain(bands.iter().map(|b| b.load * (1.0 + b.width)))
        .fold(1.0f64, f64::max)
        * 1.1;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..xmax * 1.02, 0.0..ymax)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("horizontal displacement of the top, mm")
        .y_desc("horizontal load, kN")
        .light_line_style(WHITE)
        .draw()
        .map_err(e)?;
    for b in bands {
        let c = CURVE_COLORS[b.color % CURVE_COLORS.len()];
        let (lo, hi) = (b.load * (1.0 - b.width), b.load * (1.0 + b.width));
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(0.0, lo), (xmax * 1.02, hi)],
                c.mix(0.15).filled(),
            )))
            .map_err(e)?
            .label(b.label.clone())
            .legend(move |(x, y)| {
                Rectangle::new([(x - 8, y - 5), (x + 8, y + 5)], c.mix(0.3).filled())
            });
        chart
            .draw_series(LineSeries::new(
                [(0.0, b.load), (xmax * 1.02, b.load)],
                c.mix(0.6).stroke_width(1),
            ))
            .map_err(e)?;
    }
    for s in curves {
        let c = CURVE_COLORS[s.color % CURVE_COLORS.len()];
        let style = c.stroke_width(if s.dashed { 1 } else { 2 });
        let series =
            if s.markers {
                chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(1)))
                    .map_err(e)?;
                chart
                    .draw_series(s.points.iter().map(|&p| {
                        EmptyElement::at(p) + Rectangle::new([(-4, -4), (4, 4)], c.filled())
                    }))
                    .map_err(e)?
            } else if s.dashed {
                chart
                    .draw_series(DashedLineSeries::new(s.points.iter().copied(), 6, 4, style))
                    .map_err(e)?
            } else {
                chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), style))
                    .map_err(e)?
            };
        let series = series.label(s.label.clone());
        if s.markers {
            series.legend(move |(x, y)| {
                EmptyElement::at((x, y)) + Rectangle::new([(-4, -4), (4, 4)], c.filled())
            });
        } else {
            series.legend(move |(x, y)| PathElement::new([(x - 10, y), (x + 10, y)], style));
        }
    }
    super::figures::draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
    root.present().map_err(e)?;
    Ok(())
}
