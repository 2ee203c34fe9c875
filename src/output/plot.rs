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
