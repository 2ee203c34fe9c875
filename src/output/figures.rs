//! The default figures of a run (`DIR/figures/`): the deformed configuration
//! (`deformed.png/.svg`, as the seed's Figs. 4 and 6 draw it: the initial blocks and the
//! deformed ones with an amplified displacement) and, for a capacity analysis, the
//! capacity curve (`capacity_curve.png/.svg`); for a dynamic run, the displacement
//! histories (`history.png/.svg`, [`super::time_history`]).
//!
//! A figure is drawn from a [`Deformed`], which is built either from a run in memory
//! ([`Deformed::from_run`]) or from the files it wrote ([`Deformed::from_dir`]); both hold
//! the same cells in the same order (those of the `.vtu` files, whose numbers read back
//! exactly), so `dfem plot DIR` redraws the figures of `dfem run` identically.

use super::read::{self, Vtu};
use crate::analysis::Outcome;
use crate::mesh::{BlockDofs, Mesh};
use crate::scene::Scene;
use crate::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Image formats of the figures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Png,
    Svg,
}

impl Format {
    pub fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Svg => "svg",
        }
    }
    pub fn parse(s: &str) -> Option<Format> {
        match s {
            "png" => Some(Format::Png),
            "svg" => Some(Format::Svg),
            _ => None,
        }
    }
}

/// Contact states as written in `contacts_NNNN.vtu` (`state_0stick_1slip_2open`).
const SLIP: u8 = 1;
const OPEN: u8 = 2;

/// Above this many triangles, deformable blocks are filled as one polygon each (the mean
/// colour of their nodes) instead of triangle by triangle.
const MAX_TRIANGLES: usize = 50_000;

/// What the deformed-configuration figure shows.
#[derive(Debug, Clone, PartialEq)]
pub struct Deformed {
    /// Initial node positions (m).
    pub points: Vec<[f64; 2]>,
    /// Node displacements (m).
    pub disp: Vec<[f64; 2]>,
    /// Cells: the triangles of deformable blocks, then one polygon per rigid or fixed block.
    pub cells: Vec<Vec<u32>>,
    /// Block of each cell.
    pub cell_block: Vec<u32>,
    /// Whether each cell belongs to a fixed block.
    pub cell_fixed: Vec<bool>,
    /// Contacts: the two nodes' initial positions, their displacements, and the state code.
    pub contacts: Vec<ContactMark>,
    /// Scene title.
    pub title: String,
    /// One line: the status, the failure mode and λ.
    pub status: String,
    /// Blocks that move in the failure mechanism (summary.json `failure.blocks` whose
    /// motion is not "none"), or that fell out (`fallen`), by block number.
    pub moving: Vec<u32>,
}

/// A contact as the figure draws it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactMark {
    pub at: [[f64; 2]; 2],
    pub disp: [[f64; 2]; 2],
    /// 0 stick, 1 slip, 2 open.
    pub state: u8,
}

/// The blocks that move in the mechanism of a summary: `failure.blocks` name the free
/// blocks, and `blocks` lists every free block in block order, so the k-th free block
/// (not fixed) of the cells is the k-th entry of `blocks`.
fn moving_blocks(summary: &serde_json::Value, cell_block: &[u32], cell_fixed: &[bool]) -> Vec<u32> {
    let failed = summary["failure"]["blocks"].as_array();
    // the blocks that fell out (`fallout`), drawn as the mechanism is
    let fallen = summary["fallen"].as_array();
    if failed.is_none() && fallen.is_none_or(|f| f.is_empty()) {
        return Vec::new();
    }
    let moving: std::collections::HashSet<&str> = failed
        .into_iter()
        .flatten()
        .filter(|b| b["motion"].as_str().is_some_and(|m| m != "none"))
        .filter_map(|b| b["name"].as_str())
        .chain(fallen.into_iter().flatten().filter_map(|b| b.as_str()))
        .collect();
    let mut free: Vec<u32> = cell_block
        .iter()
        .zip(cell_fixed)
        .filter(|(_, &f)| !f)
        .map(|(&b, _)| b)
        .collect();
    free.sort_unstable();
    free.dedup();
    let names = summary["blocks"]
        .as_array()
        .map(|v| v.as_slice())
        .unwrap_or(&[]);
    free.iter()
        .zip(names)
        .filter(|(_, n)| n["name"].as_str().is_some_and(|n| moving.contains(n)))
        .map(|(&b, _)| b)
        .collect()
}

/// The status line of a figure from a summary document.
fn status_line(summary: &serde_json::Value) -> String {
    let mut s = summary["status"].as_str().unwrap_or("unknown").to_string();
    if let Some(mode) = summary["failure"]["mode"].as_str() {
        s.push_str(&format!(" ({mode})"));
    }
    if let Some(l) = summary["load_factor"].as_f64() {
        s.push_str(&format!(", λ = {l:.4}"));
    }
    s
}

impl Deformed {
    /// From a run in memory: `mesh` is the initial mesh, `out` the outcome.
    pub fn from_run(scene: &Scene, mesh: &Mesh, out: &Outcome) -> Deformed {
        let mut cells: Vec<Vec<u32>> = mesh.triangles.iter().map(|t| t.to_vec()).collect();
        let mut cell_block = mesh.tri_block.clone();
        for (i, b) in mesh.blocks.iter().enumerate() {
            if b.dofs != BlockDofs::Deformable {
                cells.push(b.boundary.clone());
                cell_block.push(i as u32);
            }
        }
        let cell_fixed: Vec<bool> = cell_block
            .iter()
            .map(|&b| mesh.blocks[b as usize].dofs == BlockDofs::Fixed)
            .collect();
        // the contacts of the current configuration (a dynamic run adds and drops some)
        let contacts = out
            .current
            .as_ref()
            .map_or(&mesh.contacts, |m| &m.contacts)
            .iter()
            .zip(&out.contact_states)
            .map(|(c, s)| {
                let m = c.node_m as usize;
                ContactMark {
                    at: [c.at_l(|n| mesh.nodes[n as usize]), mesh.nodes[m]],
                    disp: [c.at_l(|n| out.node_disp[n as usize]), out.node_disp[m]],
                    state: s.code() as u8,
                }
            })
            .collect();
        let summary = super::summary(scene, mesh, out);
        let moving = moving_blocks(&summary, &cell_block, &cell_fixed);
        Deformed {
            moving,
            points: mesh.nodes.clone(),
            disp: out.node_disp.clone(),
            cells,
            cell_block,
            cell_fixed,
            contacts,
            title: scene.title.clone(),
            status: status_line(&summary),
        }
    }

    /// From the files of a finished run in `dir`: the last `blocks_NNNN.vtu` and
    /// `contacts_NNNN.vtu`, and `summary.json`.
    pub fn from_dir(dir: &Path) -> Result<Deformed> {
        let summary = read::summary(dir)?;
        let (bf, cf) = read::last_step(dir)?;
        let b = Vtu::read(&bf)?;
        let points = b.points(&bf)?;
        let disp = b.vectors("displacement_m", points.len(), &bf)?;
        let cells = b.cells(points.len(), &bf)?;
        let per_cell = |name: &str| -> Result<Vec<f64>> {
            let a = b.array(name, &bf)?;
            if a.len() != cells.len() {
                return Err(Error::new(format!(
                    "cannot read the result file: '{name}' has {} values for {} cells",
                    a.len(),
                    cells.len()
                ))
                .file(&bf)
                .fix("this file is damaged; run the analysis again"));
            }
            Ok(a.to_vec())
        };
        let cell_block: Vec<u32> = per_cell("block")?.iter().map(|&v| v as u32).collect();
        let cell_fixed: Vec<bool> = per_cell("fixed")?.iter().map(|&v| v != 0.0).collect();
        let c = Vtu::read(&cf)?;
        let cpts = c.points(&cf)?;
        let cdisp = c.vectors("displacement_m", cpts.len(), &cf)?;
        let states = c.array("state_0stick_1slip_2open", &cf)?;
        if cpts.len() != 2 * states.len() {
            return Err(Error::new(format!(
                "cannot read the result file: {} points for {} contacts",
                cpts.len(),
                states.len()
            ))
            .file(&cf)
            .fix("this file is damaged; run the analysis again"));
        }
        let contacts = states
            .iter()
            .enumerate()
            .map(|(k, &s)| ContactMark {
                at: [cpts[2 * k], cpts[2 * k + 1]],
                disp: [cdisp[2 * k], cdisp[2 * k + 1]],
                state: s as u8,
            })
            .collect();
        let moving = moving_blocks(&summary, &cell_block, &cell_fixed);
        Ok(Deformed {
            moving,
            points,
            disp,
            cells,
            cell_block,
            cell_fixed,
            contacts,
            title: summary["title"].as_str().unwrap_or("").to_string(),
            status: status_line(&summary),
        })
    }

    /// Largest node displacement (m).
    pub fn max_displacement(&self) -> f64 {
        self.disp
            .iter()
            .map(|d| d[0].hypot(d[1]))
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
    }

    /// Size of the model: the larger side of the initial bounding box (m).
    pub fn size(&self) -> f64 {
        let b = bbox(self.points.iter().copied());
        (b[2] - b[0]).max(b[3] - b[1])
    }

    /// The automatic amplification: the largest displacement shows as about 5 % of the
    /// model's size, rounded down to 1, 2 or 5 × 10ᵏ; never below 1 (a displacement
    /// already larger than that is drawn true to scale).
    pub fn auto_amplification(&self) -> f64 {
        let (u, size) = (self.max_displacement(), self.size());
        if u <= 0.0 || size <= 0.0 {
            return 1.0;
        }
        let a = 0.05 * size / u;
        if a <= 1.0 {
            return 1.0;
        }
        let p = 10f64.powf(a.log10().floor());
        let m = a / p;
        let nice = if m >= 5.0 {
            5.0
        } else if m >= 2.0 {
            2.0
        } else {
            1.0
        };
        nice * p
    }

    /// Each block's outline rings (node ids, counter-clockwise): the polygon cell of a rigid
    /// or fixed block, or the boundary edges of a deformable block's triangles chained.
    /// In block order; a block may have more than one ring only if its triangles do.
    pub fn outlines(&self) -> Vec<(u32, Vec<Vec<u32>>)> {
        let mut by_block: Vec<(u32, Vec<usize>)> = Vec::new();
        let mut index: HashMap<u32, usize> = HashMap::new();
        for (c, &b) in self.cell_block.iter().enumerate() {
            let k = *index.entry(b).or_insert_with(|| {
                by_block.push((b, Vec::new()));
                by_block.len() - 1
            });
            by_block[k].1.push(c);
        }
        by_block
            .into_iter()
            .map(|(b, cells)| {
                if cells.len() == 1 && self.cells[cells[0]].len() != 3 {
                    return (b, vec![self.cells[cells[0]].clone()]);
                }
                (b, boundary_rings(cells.iter().map(|&c| &self.cells[c][..])))
            })
            .collect()
    }
}

/// The boundary of a set of triangles as closed rings: the directed edges whose reverse is
/// not an edge, chained; each ring starts at its smallest node (deterministic).
fn boundary_rings<'a>(cells: impl Iterator<Item = &'a [u32]>) -> Vec<Vec<u32>> {
    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
    for c in cells {
        for i in 0..c.len() {
            *edges.entry((c[i], c[(i + 1) % c.len()])).or_default() += 1;
        }
    }
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    for &(a, b) in edges.keys() {
        if !edges.contains_key(&(b, a)) {
            next.entry(a).or_default().push(b);
        }
    }
    for v in next.values_mut() {
        v.sort_unstable();
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut rings = Vec::new();
    for s in starts {
        while next.get(&s).is_some_and(|v| !v.is_empty()) {
            let mut ring = vec![s];
            let mut at = s;
            while let Some(n) = next.get_mut(&at).and_then(|v| v.pop()) {
                if n == s {
                    break;
                }
                ring.push(n);
                at = n;
            }
            if ring.len() >= 3 {
                rings.push(ring);
            }
        }
    }
    rings
}

/// [xmin, ymin, xmax, ymax] of points (zeros when there are none).
fn bbox(pts: impl Iterator<Item = [f64; 2]>) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in pts {
        if p[0].is_finite() && p[1].is_finite() {
            b = [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ];
        }
    }
    if b[0] > b[2] {
        [0.0; 4]
    } else {
        b
    }
}

pub(crate) fn plot_err(path: &Path) -> impl Fn(String) -> Error + '_ {
    move |e| {
        Error::new(format!("cannot draw the figure: {e}"))
            .file(path)
            .fix("check that the directory is writable and a font is installed (fontconfig, e.g. fonts-dejavu-core)")
    }
}

/// Pixel layout of the deformed figure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layout {
    /// Image size (px).
    pub width: u32,
    pub height: u32,
    /// Plotting area (px) and the data ranges it shows (m): the same m/px along x and y.
    pub plot: (u32, u32),
    pub x: (f64, f64),
    pub y: (f64, f64),
}

const TITLE_H: u32 = 64;
const LEFT: u32 = 70;
const BOTTOM: u32 = 50;
const RIGHT: u32 = 20;
const TOP: u32 = 10;
const BAR_W: u32 = 150;

/// The layout for data in the box `b` = [xmin, ymin, xmax, ymax] (m): the plotting area
/// fits in 1000 × 750 px, at least 460 × 300 px, at one scale in x and y.
pub fn layout(b: [f64; 4]) -> Layout {
    let (mut dx, mut dy) = (b[2] - b[0], b[3] - b[1]);
    let pad = 0.04 * dx.max(dy).max(1e-9);
    dx += 2.0 * pad;
    dy += 2.0 * pad;
    let scale = (1000.0 / dx).min(750.0 / dy); // px per m
    let pw = (dx * scale).round().max(460.0) as u32;
    let ph = (dy * scale).round().max(300.0) as u32;
    let (cx, cy) = (0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3]));
    let (hx, hy) = (0.5 * pw as f64 / scale, 0.5 * ph as f64 / scale);
    Layout {
        width: LEFT + pw + RIGHT + BAR_W,
        height: TITLE_H + TOP + ph + BOTTOM,
        plot: (pw, ph),
        x: (cx - hx, cx + hx),
        y: (cy - hy, cy + hy),
    }
}

/// Draw the deformed configuration into `path` (PNG or SVG by `format`) with the
/// amplification `amp` (automatic when `None`). Returns the amplification used.
pub fn deformed(path: &Path, fig: &Deformed, amp: Option<f64>, format: Format) -> Result<f64> {
    let amp = amp.unwrap_or_else(|| fig.auto_amplification());
    let moved: Vec<[f64; 2]> = fig
        .points
        .iter()
        .zip(&fig.disp)
        .map(|(p, d)| [p[0] + amp * d[0], p[1] + amp * d[1]])
        .collect();
    let lay = layout(bbox(fig.points.iter().chain(&moved).copied()));
    match format {
        Format::Svg => {
            let root = SVGBackend::new(path, (lay.width, lay.height)).into_drawing_area();
            draw_deformed(root, fig, &moved, amp, &lay).map_err(plot_err(path))?;
        }
        Format::Png => {
            let root = BitMapBackend::new(path, (lay.width, lay.height)).into_drawing_area();
            draw_deformed(root, fig, &moved, amp, &lay).map_err(plot_err(path))?;
        }
    }
    Ok(amp)
}

/// Whether tick value `v` on an axis spanning `range` is zero but for the tick
/// positions' round-off (within 10⁻⁹ of the range: the tunnel's history drew
/// "-3.39e-21").
pub(crate) fn zero_tick(v: f64, range: f64) -> bool {
    v.abs() <= 1e-9 * range.abs()
}

/// A number for a label: plain for moderate magnitudes, scientific otherwise, "0" for a
/// [`zero_tick`].
fn fmt_num(v: f64, range: f64) -> String {
    if zero_tick(v, range) {
        "0".into()
    } else if (1e-2..1e4).contains(&range) {
        let digits = (2.0 - range.log10().floor()).clamp(0.0, 6.0) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:.2e}")
    }
}

fn fmt_amp(a: f64) -> String {
    if a >= 1e6 {
        format!("{a:.0e}")
    } else if a == a.round() {
        format!("{a:.0}")
    } else {
        format!("{a:.3}")
    }
}

fn draw_deformed<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    fig: &Deformed,
    moved: &[[f64; 2]],
    amp: f64,
    lay: &Layout,
) -> std::result::Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let (top, rest) = root.split_vertically(TITLE_H);
    let title = if fig.title.is_empty() {
        "Deformed configuration".to_string()
    } else {
        fig.title.clone()
    };
    top.draw(&Text::new(
        title,
        (LEFT as i32, 10),
        ("sans-serif", 20).into_font(),
    ))
    .map_err(e)?;
    top.draw(&Text::new(
        format!(
            "{}; deformed configuration, displacements × {}",
            fig.status,
            fmt_amp(amp)
        ),
        (LEFT as i32, 38),
        ("sans-serif", 15).into_font(),
    ))
    .map_err(e)?;
    let (main, side) = rest.split_horizontally(LEFT + lay.plot.0 + RIGHT);
    let mut chart = ChartBuilder::on(&main)
        .margin_top(TOP)
        .margin_right(RIGHT)
        .x_label_area_size(BOTTOM)
        .y_label_area_size(LEFT)
        .build_cartesian_2d(lay.x.0..lay.x.1, lay.y.0..lay.y.1)
        .map_err(e)?;
    let rx = lay.x.1 - lay.x.0;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .x_labels(8)
        .y_labels(8)
        .x_label_formatter(&|v| fmt_num(*v, rx))
        .y_label_formatter(&|v| fmt_num(*v, rx))
        .draw()
        .map_err(e)?;

    let umax = fig.max_displacement();
    let mag: Vec<f64> = fig.disp.iter().map(|d| d[0].hypot(d[1])).collect();
    let colour = |u: f64| -> RGBColor {
        if umax > 0.0 {
            ViridisRGB::get_color_normalized(u.clamp(0.0, umax), 0.0, umax)
        } else {
            ViridisRGB::get_color(0.0)
        }
    };
    let fixed_fill = RGBColor(85, 85, 85);
    let outlines = fig.outlines();
    let fixed_block: HashMap<u32, bool> = fig
        .cell_block
        .iter()
        .zip(&fig.cell_fixed)
        .map(|(&b, &f)| (b, f))
        .collect();
    let ring_pts = |ring: &[u32], pts: &[[f64; 2]]| -> Vec<(f64, f64)> {
        ring.iter()
            .chain(ring.first())
            .map(|&n| (pts[n as usize][0], pts[n as usize][1]))
            .collect()
    };
    let mean_mag = |ring: &[u32]| -> f64 {
        ring.iter().map(|&n| mag[n as usize]).sum::<f64>() / ring.len().max(1) as f64
    };

    // the initial configuration, light grey
    let grey = RGBColor(190, 190, 190);
    chart
        .draw_series(outlines.iter().flat_map(|(_, rings)| {
            rings
                .iter()
                .map(|r| PathElement::new(ring_pts(r, &fig.points), grey.stroke_width(1)))
        }))
        .map_err(e)?;

    // deformed fill: triangles of deformable blocks (unless there are too many), polygons
    let n_tri = fig.cells.iter().filter(|c| c.len() == 3).count();
    let triangulated: std::collections::HashSet<u32> = fig
        .cells
        .iter()
        .zip(&fig.cell_block)
        .filter(|(c, _)| c.len() == 3)
        .map(|(_, &b)| b)
        .collect();
    let per_triangle = n_tri <= MAX_TRIANGLES;
    let polygon_of = |c: &[u32]| -> Vec<(f64, f64)> {
        c.iter()
            .map(|&n| (moved[n as usize][0], moved[n as usize][1]))
            .collect()
    };
    chart
        .draw_series(
            fig.cells
                .iter()
                .zip(&fig.cell_fixed)
                .filter(|(c, _)| per_triangle && c.len() == 3)
                .map(|(c, &fixed)| {
                    let fill = if fixed {
                        fixed_fill
                    } else {
                        colour(mean_mag(c))
                    };
                    Polygon::new(polygon_of(c), fill.filled())
                }),
        )
        .map_err(e)?;
    chart
        .draw_series(
            outlines
                .iter()
                .filter(|(b, _)| !(per_triangle && triangulated.contains(b)))
                .flat_map(|(b, rings)| {
                    let fixed = fixed_block.get(b).copied().unwrap_or(false);
                    rings.iter().map(move |r| {
                        let fill = if fixed {
                            fixed_fill
                        } else {
                            colour(mean_mag(r))
                        };
                        Polygon::new(polygon_of(r), fill.filled())
                    })
                }),
        )
        .map_err(e)?;
    // deformed outlines
    let edge = RGBColor(20, 20, 20);
    chart
        .draw_series(outlines.iter().flat_map(|(_, rings)| {
            rings
                .iter()
                .map(|r| PathElement::new(ring_pts(r, moved), edge.stroke_width(1)))
        }))
        .map_err(e)?;
    // the blocks of the failure mechanism, outlined
    let mech = RGBColor(200, 0, 160);
    let moving: std::collections::HashSet<u32> = fig.moving.iter().copied().collect();
    chart
        .draw_series(
            outlines
                .iter()
                .filter(|(b, _)| moving.contains(b))
                .flat_map(|(_, rings)| {
                    rings
                        .iter()
                        .map(|r| PathElement::new(ring_pts(r, moved), mech.stroke_width(3)))
                }),
        )
        .map_err(e)?;
    // contacts: open red, slipping orange; sticking ones are not drawn
    // markers no larger than about a sixth of a block's size in pixels
    let blocks = outlines.len().max(1) as f64;
    let block_px = ((lay.plot.0 as f64 * lay.plot.1 as f64) / blocks).sqrt();
    let radius = (block_px / 6.0).clamp(1.0, 3.0).round() as i32;
    let orange = RGBColor(255, 140, 0);
    let red = RGBColor(220, 20, 20);
    let at = |c: &ContactMark, i: usize| {
        (
            c.at[i][0] + amp * c.disp[i][0],
            c.at[i][1] + amp * c.disp[i][1],
        )
    };
    for (state, col) in [(SLIP, orange), (OPEN, red)] {
        let marks = fig.contacts.iter().filter(|c| c.state == state);
        chart
            .draw_series(
                marks
                    .clone()
                    .map(|c| PathElement::new(vec![at(c, 0), at(c, 1)], col.stroke_width(2))),
            )
            .map_err(e)?;
        chart
            .draw_series(marks.map(|c| {
                let (a, b) = (at(c, 0), at(c, 1));
                Circle::new((0.5 * (a.0 + b.0), 0.5 * (a.1 + b.1)), radius, col.filled())
            }))
            .map_err(e)?;
    }

    // the colour bar and the legend
    let (bar_area, legend) = side.split_vertically(TOP + lay.plot.1 * 3 / 5 + 30);
    let mut bar = ChartBuilder::on(&bar_area)
        .margin_top(TOP + 22)
        .margin_left(10)
        .margin_bottom(8)
        .right_y_label_area_size(BAR_W as i32 - 50)
        .build_cartesian_2d(0.0..1.0f64, 0.0..umax.max(f64::MIN_POSITIVE))
        .map_err(e)?;
    let ru = umax;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(6)
        .y_label_style(("sans-serif", 12).into_font())
        .y_label_formatter(&|v| fmt_num(*v, ru))
        .draw()
        .map_err(e)?;
    let n = 64;
    bar.draw_series((0..n).map(|k| {
        let (a, b) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
        Rectangle::new(
            [(0.0, a * umax), (1.0, b * umax)],
            colour((a + b) * 0.5 * umax).filled(),
        )
    }))
    .map_err(e)?;
    bar_area
        .draw(&Text::new(
            "|u| (m)",
            (10, TOP as i32),
            ("sans-serif", 14).into_font(),
        ))
        .map_err(e)?;
    let font = ("sans-serif", 13).into_font();
    let count = |st: u8| fig.contacts.iter().filter(|c| c.state == st).count();
    let (open_label, slip_label) = (
        format!("open contact ({})", count(OPEN)),
        format!("slipping contact ({})", count(SLIP)),
    );
    let mech_label = if fig.status.starts_with("stable") {
        format!("fallen out ({} blocks)", fig.moving.len())
    } else {
        format!("mechanism ({} blocks)", fig.moving.len())
    };
    let items: [(&str, ShapeStyle); 5] = [
        (&open_label, red.filled()),
        (&slip_label, orange.filled()),
        ("fixed block", fixed_fill.filled()),
        ("initial position", grey.stroke_width(2)),
        (&mech_label, mech.stroke_width(3)),
    ];
    for (i, (label, style)) in items.iter().enumerate() {
        let y = 10 + 20 * i as i32;
        if i < 2 {
            legend
                .draw(&Circle::new((16, y + 7), 4, *style))
                .map_err(e)?;
        } else if i == 2 {
            legend
                .draw(&Rectangle::new([(11, y + 2), (21, y + 12)], *style))
                .map_err(e)?;
        } else {
            if i == 4 && fig.moving.is_empty() {
                continue;
            }
            legend
                .draw(&PathElement::new(vec![(8, y + 7), (24, y + 7)], *style))
                .map_err(e)?;
        }
        legend
            .draw(&Text::new(*label, (30, y), font.clone()))
            .map_err(e)?;
    }
    root.present().map_err(e)?;
    Ok(())
}

/// A capacity curve as drawn ([`capacity_curve`]), from the rows of curve.csv
/// (docs/outputs.md, "The capacity curve").
#[derive(Debug, Clone, PartialEq)]
pub struct CurveFigure {
    /// A push's curve (`[analysis] push_block`): the load drawn is the horizontal force on
    /// the pushed block (N, `force_x_N`); otherwise the load factor λ.
    pub push: bool,
    /// The control block's name (the pushed block of a push) and the top block's.
    pub control: String,
    pub top: String,
    /// Per converged state: the load (λ, or N), the control block's ux and the top
    /// block's ux (m).
    pub rows: Vec<[f64; 3]>,
}

impl CurveFigure {
    /// From curve.csv's `columns` and `rows` (a file without `top_ux_m`, written before
    /// that column, draws the control block alone); `None` without the columns it needs.
    pub fn from_columns(
        columns: &[String],
        rows: &[Vec<f64>],
        control: &str,
        top: &str,
    ) -> Option<CurveFigure> {
        let col = |name: &str| columns.iter().position(|c| c == name);
        let push = col("force_x_N");
        let (y, ux) = (push.or(col("load_factor"))?, col("ux_m")?);
        let (top_ux, top) = match col("top_ux_m") {
            Some(c) => (c, top),
            None => (ux, control),
        };
        let get = |r: &Vec<f64>, c: usize| r.get(c).copied().unwrap_or(f64::NAN);
        Some(CurveFigure {
            push: push.is_some(),
            control: control.to_string(),
            top: top.to_string(),
            rows: rows
                .iter()
                .map(|r| [get(r, y), get(r, ux), get(r, top_ux)])
                .collect(),
        })
    }
}

/// Draw the capacity curve (the load against the horizontal displacement of the control
/// block, and of the top block where that is another block) into `path`.
pub fn capacity_curve(path: &Path, title: &str, curve: &CurveFigure, format: Format) -> Result<()> {
    match format {
        Format::Svg => {
            let root = SVGBackend::new(path, (900, 640)).into_drawing_area();
            draw_curve(root, title, curve).map_err(plot_err(path))
        }
        Format::Png => {
            let root = BitMapBackend::new(path, (900, 640)).into_drawing_area();
            draw_curve(root, title, curve).map_err(plot_err(path))
        }
    }
}

fn draw_curve<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    curve: &CurveFigure,
) -> std::result::Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let rows = &curve.rows;
    let two = curve.top != curve.control;
    root.fill(&WHITE).map_err(e)?;
    let xs = rows
        .iter()
        .flat_map(|r| [r[1], if two { r[2] } else { r[1] }])
        .filter(|v| v.is_finite());
    let (mut x0, mut x1) = xs.fold((0.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if x1 - x0 <= 0.0 {
        x1 = x0 + 1e-6;
    }
    let pad = 0.05 * (x1 - x0);
    x0 -= if x0 < 0.0 { pad } else { 0.0 };
    x1 += pad;
    let ys = rows.iter().map(|r| r[0]).filter(|v| v.is_finite());
    let (lmin, lmax) = ys.fold((0.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    let y1 = if lmax > 0.0 { 1.12 * lmax } else { 1.0 };
    let y0 = 1.12 * lmin;
    let rx = x1 - x0;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            if title.is_empty() {
                "Capacity curve".to_string()
            } else {
                format!("Capacity curve: {title}")
            },
            ("sans-serif", 18),
        )
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(65)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(e)?;
    let (control, top) = (&curve.control, &curve.top);
    chart
        .configure_mesh()
        .x_desc(if two {
            "horizontal displacement of the block's centroid, m".to_string()
        } else {
            format!("horizontal displacement of block '{control}' (centroid), m")
        })
        .y_desc(if curve.push {
            format!("horizontal force on block '{control}', N")
        } else {
            "load factor λ (lateral force / weight)".to_string()
        })
        .x_label_formatter(&|v| fmt_num(*v, rx))
        .y_label_formatter(&|v| fmt_num(*v, y1 - y0))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(e)?;
    let blue = RGBColor(31, 90, 180);
    let orange = RGBColor(230, 120, 20);
    let role = if two { "control" } else { "control and top" };
    let mut series = vec![(1, blue, format!("block '{control}' ({role})"))];
    if two {
        series.push((2, orange, format!("block '{top}' (top)")));
    }
    for (c, colour, label) in series {
        chart
            .draw_series(LineSeries::new(
                rows.iter().map(|r| (r[c], r[0])),
                colour.stroke_width(2),
            ))
            .map_err(e)?
            .label(label)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(
                rows.iter()
                    .map(|r| Circle::new((r[c], r[0]), 3, colour.filled())),
            )
            .map_err(e)?;
    }
    // a capacity curve marks its last converged λ (the capacity), a push its peak force
    let mark = if curve.push {
        rows.iter()
            .map(|r| r[0])
            .filter(|v| v.is_finite())
            .reduce(f64::max)
            .map(|f| (f, format!("peak force = {f:.4e} N")))
    } else {
        rows.last()
            .map(|r| (r[0], format!("last converged λ = {:.4}", r[0])))
    };
    if let Some((y, label)) = mark {
        let red = RGBColor(200, 30, 30);
        chart
            .draw_series(LineSeries::new([(x0, y), (x1, y)], red.stroke_width(1)))
            .map_err(e)?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], red));
    }
    if !rows.is_empty() {
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
    }
    root.present().map_err(e)?;
    Ok(())
}

/// The legend's font size (px). plotters 0.3's TrueType text (`src/style/font/ttf.rs`,
/// `draw`) rasterizes every glyph on its own square canvas whose left edge is the pen
/// position, so the ink of a glyph with a negative left side bearing is cut off in the
/// bitmap backend: DejaVu Sans (what "sans-serif" resolves to here) draws its "J" with
/// the hook left of the pen, and at 12 px (the legend's default) and below the "J" of
/// "J4D" came out as a comma. At 13 and 14 px the "J" is whole (checked by eye on the
/// PNG of docs/figures/eindhoven_walls; a lowercase "j" still loses its hook at 13 px).
/// The SVG backend writes text, not pixels, and is unaffected.
const LEGEND_FONT_PX: f64 = 13.0;

/// The legend of a chart as every figure draws it: at `pos`, in a white box with a black
/// border that lets the grid show through a little.
pub(crate) fn draw_legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    pos: SeriesLabelPosition,
) -> std::result::Result<(), String> {
    chart
        .configure_series_labels()
        .position(pos)
        .label_font(("sans-serif", LEGEND_FONT_PX))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())
}

/// The figure files written for `formats` into `dir` (created): deformed.* always,
/// capacity_curve.* when `curve` is given, history.* when
/// a dynamic run's `history` is given ([`super::time_history`]).
pub fn write_figures(
    dir: &Path,
    fig: &Deformed,
    curve: Option<&CurveFigure>,
    history: Option<&crate::analysis::dynamics::History>,
    amplification: Option<f64>,
    formats: &[Format],
) -> Result<Vec<PathBuf>> {
    create_figures_dir(dir)?;
    let mut written = Vec::new();
    for &f in formats {
        let path = dir.join(format!("deformed.{}", f.extension()));
        draw_atomic(&path, |tmp| {
            deformed(tmp, fig, amplification, f).map(|_| ())
        })?;
        written.push(path);
        if let Some(curve) = curve {
            let path = dir.join(format!("capacity_curve.{}", f.extension()));
            draw_atomic(&path, |tmp| capacity_curve(tmp, &fig.title, curve, f))?;
            written.push(path);
        }
        if let Some(h) = history {
            let path = dir.join(format!("history.{}", f.extension()));
            draw_atomic(&path, |tmp| {
                super::time_history::history(tmp, &fig.title, h, f)
            })?;
            written.push(path);
        }
    }
    Ok(written)
}

/// Create the directory of figures `dir` (and its parents).
pub(crate) fn create_figures_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| {
        Error::new(format!("cannot create the figures directory: {e}"))
            .file(dir)
            .fix("choose a writable output directory")
    })
}

/// Draw into a temporary file beside `path`, then rename: a figure is whole or absent.
pub(crate) fn draw_atomic(path: &Path, draw: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp{}.{ext}", std::process::id()));
    let r = draw(&tmp);
    if r.is_err() {
        let _ = std::fs::remove_file(&tmp);
        return r;
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::new(format!("cannot write the figure: {e}"))
            .file(path)
            .fix("check that the output directory is writable")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tick labels: a tick that round-off put a hair off zero reads "0"; small and large
    /// ranges in scientific notation, moderate ones plain.
    #[test]
    fn tick_labels_read_zero_at_zero() {
        assert_eq!(fmt_num(-3.39e-21, 7e-5), "0");
        assert_eq!(fmt_num(-5.0e-6, 7e-5), "-5.00e-6");
        assert_eq!(fmt_num(0.25, 1.0), "0.25");
        assert_eq!(fmt_num(-1e-12, 1.0), "0");
    }

    #[test]
    fn rings_of_two_triangles_form_one_square() {
        let cells: Vec<Vec<u32>> = vec![vec![0, 1, 2], vec![0, 2, 3]];
        let rings = boundary_rings(cells.iter().map(|c| &c[..]));
        assert_eq!(rings, vec![vec![0, 1, 2, 3]]);
    }

    #[test]
    fn layout_keeps_one_scale() {
        for b in [
            [0.0, 0.0, 2.0, 8.0],
            [0.0, 0.0, 40.0, 3.0],
            [-5.0, 1.0, 5.0, 2.0],
        ] {
            let l = layout(b);
            let sx = l.plot.0 as f64 / (l.x.1 - l.x.0);
            let sy = l.plot.1 as f64 / (l.y.1 - l.y.0);
            assert!((sx / sy - 1.0).abs() < 1e-9, "{b:?}: {sx} {sy}");
            assert!(l.x.0 <= b[0] && l.x.1 >= b[2] && l.y.0 <= b[1] && l.y.1 >= b[3]);
        }
    }

    #[test]
    fn auto_amplification_is_five_percent_of_the_size() {
        let mut f = Deformed {
            points: vec![[0.0, 0.0], [10.0, 0.0], [0.0, 4.0]],
            disp: vec![[0.0, 0.0], [1e-3, 0.0], [0.0, 0.0]],
            cells: vec![vec![0, 1, 2]],
            cell_block: vec![0],
            cell_fixed: vec![false],
            contacts: vec![],
            title: String::new(),
            status: String::new(),
            moving: vec![],
        };
        // 5 % of 10 m = 0.5 m over 1 mm: 500
        assert_eq!(f.auto_amplification(), 500.0);
        f.disp[1] = [3e-3, 0.0];
        // 166.7 -> 100
        assert_eq!(f.auto_amplification(), 100.0);
        f.disp[1] = [2.0, 0.0];
        assert_eq!(f.auto_amplification(), 1.0);
    }
}
