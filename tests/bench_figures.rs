//! The run-time-against-error figures of the benchmark tables (docs/performance.md,
//! src/output/time_error.rs): drawn from a small table, saved as CSV and redrawn by
//! `dfem plot FILE.csv`, each row must be one marker of its series' colour at the pixel
//! its error and time map to (the mapping read back from the axis labels of the SVG), and
//! the labelled axis ranges must hold every row. The figures under the tables of
//! docs/performance.md must show one marker per drawable row of their table.
//!
//! The figures of the docs are drawn by the ignored test `draw_the_figures_of_the_docs`:
//!
//!     cargo test --release --test bench_figures -- --ignored

mod common;
use dfem::output::bench_table::Table;
use dfem::output::figures::Format;
use dfem::output::time_error::{self, Plot, COLORS};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// One element of an SVG: its tag, attributes and the text up to the next tag.
#[derive(Debug)]
struct Element {
    tag: String,
    attrs: HashMap<String, String>,
    text: String,
}

/// The elements of an SVG as plotters writes it (one flat list, attributes `k="v"`).
fn elements(svg: &str) -> Vec<Element> {
    svg.split('<')
        .skip(1)
        .filter(|c| !c.starts_with('/') && !c.starts_with('?'))
        .map(|chunk| {
            let (head, text) = chunk.split_once('>').unwrap_or((chunk, ""));
            let tag: String = head.chars().take_while(|c| c.is_alphanumeric()).collect();
            let mut attrs = HashMap::new();
            let mut rest = &head[tag.len()..];
            while let Some(eq) = rest.find("=\"") {
                let key = rest[..eq].trim().to_string();
                let after = &rest[eq + 2..];
                let end = after.find('"').unwrap();
                attrs.insert(key, after[..end].to_string());
                rest = &after[end + 1..];
            }
            Element {
                tag,
                attrs,
                text: text.trim().to_string(),
            }
        })
        .collect()
}

fn num(e: &Element, k: &str) -> f64 {
    e.attrs[k].parse().unwrap()
}

/// The centre (px) of a marker element: a circle, a rectangle or a polygon (the middle of
/// its bounding box).
fn centre(e: &Element) -> Option<(f64, f64)> {
    match e.tag.as_str() {
        "circle" => Some((num(e, "cx"), num(e, "cy"))),
        "rect" => Some((
            num(e, "x") + 0.5 * num(e, "width"),
            num(e, "y") + 0.5 * num(e, "height"),
        )),
        "polygon" => {
            let p: Vec<(f64, f64)> = e.attrs["points"]
                .split_whitespace()
                .map(|xy| {
                    let (x, y) = xy.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect();
            let (x0, x1) = p
                .iter()
                .fold((f64::MAX, f64::MIN), |a, q| (a.0.min(q.0), a.1.max(q.0)));
            let (y0, y1) = p
                .iter()
                .fold((f64::MAX, f64::MIN), |a, q| (a.0.min(q.1), a.1.max(q.1)));
            Some((0.5 * (x0 + x1), 0.5 * (y0 + y1)))
        }
        _ => None,
    }
}

fn hex(k: usize) -> String {
    let (r, g, b) = COLORS[k % COLORS.len()];
    format!("#{r:02X}{g:02X}{b:02X}")
}

/// The markers (centres, px) of series `k`: the filled shapes of its colour.
fn markers(els: &[Element], k: usize) -> Vec<(f64, f64)> {
    let c = hex(k);
    els.iter()
        .filter(|e| e.attrs.get("fill") == Some(&c))
        .filter_map(centre)
        .collect()
}

/// The numeric tick labels of an axis: (value, position in px) of the `<text>` elements
/// with the given anchor (x axis: "middle", position x; y axis: "end", position y).
fn ticks(els: &[Element], anchor: &str, coord: &str) -> Vec<(f64, f64)> {
    els.iter()
        .filter(|e| {
            e.tag == "text" && e.attrs.get("text-anchor").map(String::as_str) == Some(anchor)
        })
        .filter_map(|e| Some((e.text.parse::<f64>().ok()?, num(e, coord))))
        .collect()
}

/// px = a + b log10(v) through the lowest and highest labelled ticks.
fn log_map(t: &[(f64, f64)]) -> impl Fn(f64) -> f64 {
    let lo = t
        .iter()
        .copied()
        .fold((f64::MAX, 0.0), |a, q| if q.0 < a.0 { q } else { a });
    let hi = t
        .iter()
        .copied()
        .fold((f64::MIN, 0.0), |a, q| if q.0 > a.0 { q } else { a });
    assert!(hi.0 > lo.0, "two distinct tick labels: {t:?}");
    let b = (hi.1 - lo.1) / (hi.0.log10() - lo.0.log10());
    let a = lo.1 - b * lo.0.log10();
    move |v| a + b * v.log10()
}

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

fn check_png(path: &Path) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(bytes[..8], PNG_SIGNATURE, "{}", path.display());
    // a 620 × 630 px figure with text and markers compresses to tens of kB; an empty white
    // image to under 5 kB
    assert!(
        bytes.len() > 10_000,
        "{}: {} bytes",
        path.display(),
        bytes.len()
    );
}

/// A small `dfem bench-solvers` table: 3 backends, one of them twice, one failed row.
fn solvers_table() -> Table {
    let mut t = Table::new(&dfem::output::bench_table::SOLVER_COLUMNS);
    for (name, total, res) in [
        ("faer-cholesky", "3.047", "2.7e-11"),
        ("faer-ldlt", "2.635", "2.1e-11"),
        ("petsc, `-ksp_rtol 1e-8`", "3.929", "6.0e-9"),
        ("faer-cholesky", "1.320", "3.1e-11"),
        ("mumps", "0.000", "NaN (failed: no memory)"),
        ("petsc (CG + GAMG, rtol 1e-12)", "36.31", "3.7e-12"),
    ] {
        let mut r = vec!["-".to_string(); t.header.len()];
        r[0] = name.into();
        r[4] = total.into();
        r[8] = res.into();
        t.rows.push(r);
    }
    t
}

#[test]
fn a_saved_table_redraws_one_marker_per_row_at_its_place() {
    let dir = common::tmp_dir("bench_figures_solvers");
    let table = solvers_table();
    let csv = dir.join("solvers.csv");
    table.write_csv(&csv).unwrap();
    // the user's way: dfem plot FILE.csv (into the CSV's directory)
    let out = common::dfem_ok(&["plot", csv.to_str().unwrap()]);
    let png = dir.join("solvers_time_error.png");
    let svg_path = dir.join("solvers_time_error.svg");
    assert_eq!(
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .collect::<Vec<_>>(),
        [png.to_str().unwrap(), svg_path.to_str().unwrap()]
    );
    check_png(&png);
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    let els = elements(&svg);

    // the rows drawable on log axes: positive error and time (not the failed one)
    let rows: Vec<(&str, f64, f64)> = vec![
        ("faer-cholesky", 2.7e-11, 3.047),
        ("faer-ldlt", 2.1e-11, 2.635),
        ("petsc, -ksp_rtol 1e-8", 6.0e-9, 3.929),
        ("faer-cholesky", 3.1e-11, 1.320),
        ("petsc (CG + GAMG, rtol 1e-12)", 3.7e-12, 36.31),
    ];
    assert!(
        svg.contains("5 of 6 rows drawn; 1 without"),
        "the note on the left-out row"
    );
    let series = [
        "faer-cholesky",
        "faer-ldlt",
        "petsc, -ksp_rtol 1e-8",
        "mumps",
        "petsc (CG + GAMG, rtol 1e-12)",
    ];
    let xt = ticks(&els, "middle", "x");
    let yt = ticks(&els, "end", "y");
    // the labelled axes hold the data: the extreme labels bracket every row
    let (emin, emax) = (3.7e-12, 6.0e-9);
    let (tmin, tmax) = (1.320, 36.31);
    let ext = |t: &[(f64, f64)]| {
        t.iter()
            .fold((f64::MAX, f64::MIN), |a, q| (a.0.min(q.0), a.1.max(q.0)))
    };
    let (x0, x1) = ext(&xt);
    let (y0, y1) = ext(&yt);
    assert!(
        x0 <= emin && x1 >= emax,
        "x labels {x0}..{x1}, errors {emin}..{emax}"
    );
    assert!(
        y0 <= tmin && y1 >= tmax,
        "y labels {y0}..{y1}, times {tmin}..{tmax}"
    );
    // and they are the decades around the data (1e-12..1e-8, 1e0..1e2), not wider
    assert_eq!((x0, x1, y0, y1), (1e-12, 1e-8, 1.0, 100.0));
    let (mx, my) = (log_map(&xt), log_map(&yt));
    for (k, name) in series.iter().enumerate() {
        let mut found = markers(&els, k);
        let mine: Vec<_> = rows.iter().filter(|r| r.0 == *name).collect();
        // one marker per drawable row, and one in the legend
        let legend = usize::from(!mine.is_empty());
        assert_eq!(found.len(), mine.len() + legend, "{name}: {found:?}");
        for r in mine {
            let at = (mx(r.1), my(r.2));
            // plotters rounds to whole pixels and a triangle's box is off its anchor by
            // ≤ 1.5 px: 3 px is well under the 20 px between the rows' positions here
            let i = found
                .iter()
                .position(|p| (p.0 - at.0).abs() <= 3.0 && (p.1 - at.1).abs() <= 3.0)
                .unwrap_or_else(|| panic!("{name}: no marker at {at:?} for {r:?}: {found:?}"));
            found.remove(i);
        }
    }

    // the bench's own way (dfem::output::time_error::write) draws the same figure
    let fig = Plot::new(&table, time_error::SOLVERS).unwrap();
    let again = dir.join("again");
    time_error::write(&again, None, &fig, &[Format::Svg]).unwrap();
    assert_eq!(
        std::fs::read_to_string(again.join("solvers_time_error.svg")).unwrap(),
        svg
    );
}

#[test]
fn a_strategies_table_draws_one_panel_per_wall() {
    let dir = common::tmp_dir("bench_figures_strategies");
    let mut t = Table::new(&dfem::output::bench_table::STRATEGY_COLUMNS);
    for (blocks, strategy, error, wall) in [
        ("105", "secant", "(reference)", "1.62"),
        ("105", "initial", "2.2e-1", "2.10"),
        ("105", "secant", "6.2e-3", "0.14"),
        ("105", "newton", "6.2e-3", "7.24"),
        ("915", "secant", "(reference)", "18.69"),
        ("915", "secant", "5.7e-4", "5.13"),
        ("915", "newton", "–", "600.00 (stopped after 600 s (limit))"),
    ] {
        t.rows.push(
            [
                blocks, "3", strategy, "1e-4", "1e-2", "0.5", error, "1", "1", wall,
            ]
            .map(String::from)
            .to_vec(),
        );
    }
    let csv = dir.join("strategies.csv");
    t.write_csv(&csv).unwrap();
    let written = time_error::redraw(&csv, &dir, &[Format::Png, Format::Svg]).unwrap();
    assert_eq!(
        written,
        [
            dir.join("strategies_time_error.png"),
            dir.join("strategies_time_error.svg")
        ]
    );
    check_png(&written[0]);
    let svg = std::fs::read_to_string(&written[1]).unwrap();
    assert!(
        svg.contains("105 blocks") && svg.contains("915 blocks"),
        "panel titles"
    );
    assert!(
        svg.contains("4 of 7 rows drawn; 3 without"),
        "references and the stopped run"
    );
    let els = elements(&svg);
    // series in order of appearance: secant, initial, newton; the legend of each panel
    // shows the series drawn in it: secant in both, initial and newton in the first
    for (k, (name, n)) in [("secant", 2 + 2), ("initial", 1 + 1), ("newton", 1 + 1)]
        .iter()
        .enumerate()
    {
        assert_eq!(markers(&els, k).len(), *n, "{name}");
    }
}

/// The figures of docs/performance.md: each image `![..](figures/NAME.png)` shows the last
/// benchmark table above it.
fn doc_figures() -> Vec<(String, Table)> {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/performance.md"))
            .unwrap();
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = doc[from..].find("](figures/") {
        let at = from + i;
        let start = at + "](figures/".len();
        from = start;
        let target = doc[start..].split(')').next().unwrap();
        let Some(name) = target.strip_suffix(".png").map(String::from) else {
            continue; // a link to the SVG of the same figure
        };
        let table = Table::markdown_tables(&doc[..at])
            .into_iter()
            .rfind(|t| time_error::axes_of(t).is_some())
            .unwrap_or_else(|| panic!("figure {name}: no benchmark table above it"));
        out.push((name, table));
    }
    out
}

fn docs_figures_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/figures")
}

#[test]
fn the_figures_of_the_docs_show_their_tables() {
    let figs = doc_figures();
    // the two strategy tables and the solver table
    assert_eq!(
        figs.len(),
        3,
        "{:?}",
        figs.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    for (name, table) in figs {
        let plot = Plot::new(&table, time_error::axes_of(&table).unwrap()).unwrap();
        check_png(&docs_figures_dir().join(format!("{name}.png")));
        let svg = std::fs::read_to_string(docs_figures_dir().join(format!("{name}.svg")))
            .unwrap_or_else(|e| {
                panic!("{name}.svg: {e} (draw it: cargo test --test bench_figures -- --ignored)")
            });
        let els = elements(&svg);
        for (k, s) in plot.series.iter().enumerate() {
            let rows = plot.points.iter().filter(|p| &p.series == s).count();
            let panels = plot
                .groups
                .iter()
                .filter(|g| plot.points.iter().any(|p| &p.series == s && &p.group == *g))
                .count();
            assert_eq!(
                markers(&els, k).len(),
                rows + panels,
                "{name}: series {s} ({rows} rows in {panels} panels); redraw the figures: cargo test --test bench_figures -- --ignored"
            );
        }
    }
}

/// Draw the figures of docs/performance.md from its tables (the CSV a bench would have
/// saved, re-created from the markdown rows), with the code the benches call.
#[test]
#[ignore]
fn draw_the_figures_of_the_docs() {
    let tmp = common::tmp_dir("bench_figures_docs");
    for (name, table) in doc_figures() {
        let csv = tmp.join(format!("{name}.csv"));
        table.write_csv(&csv).unwrap();
        let drawn = time_error::redraw(&csv, &tmp, &[Format::Png, Format::Svg]).unwrap();
        for f in drawn {
            let ext = f.extension().unwrap().to_str().unwrap();
            let to = docs_figures_dir().join(format!("{name}.{ext}"));
            // whole or absent, for a test reading it at the same time
            dfem::output::write_atomic(&to, &std::fs::read(&f).unwrap()).unwrap();
            println!("{}", to.display());
        }
    }
}
