//! `tower`: a masonry tower section, a tall narrow running-bond wall on a fixed base
//! (built by `super::wall::build`).

use serde::Deserialize;

use super::common::*;
use super::wall::{build, Opening, WallSpec};
use super::{GenError, GeneratedBlock};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    pub width: f64,
    pub height: f64,
    pub courses: usize,
    /// A multiple of 0.5.
    pub blocks_per_course: f64,
    pub origin: [f64; 2],
    pub base: bool,
    pub openings: Vec<Opening>,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            width: 2.0,
            height: 8.0,
            courses: 16,
            blocks_per_course: 2.0,
            origin: [0.0, 0.0],
            base: true,
            openings: Vec::new(),
        }
    }
}

pub const KEYS: &[(&str, &str)] = &[
    ("width", "the tower width in m, > 0"),
    ("height", "the tower height in m, > 0"),
    ("courses", "the number of courses, an integer >= 1"),
    (
        "blocks_per_course",
        "the width in blocks, a multiple of 0.5, >= 1",
    ),
    ("origin", "[x, y], the lower-left corner in m"),
    ("base", "true or false (a fixed base under the tower)"),
    (
        "openings",
        "an array of tables {x, y, width, height} in m, relative to the origin",
    ),
];

pub fn generate(params: &toml::Table) -> Result<Vec<GeneratedBlock>, GenError> {
    let p: Params = parse_params("tower", params, KEYS)?;
    let width = positive("width", p.width, "m")?;
    let height = positive("height", p.height, "m")?;
    let courses = count("courses", p.courses)?;
    let bpc = p.blocks_per_course;
    if !(bpc.is_finite() && bpc >= 1.0) {
        return Err(gen_err(
            Some("blocks_per_course"),
            format!("blocks_per_course must be >= 1, got {bpc}"),
            "give blocks_per_course = 1, 1.5, 2, ...",
        ));
    }
    build(
        WallSpec {
            courses,
            bricks_per_course: bpc,
            block_length: width / bpc,
            block_height: height / courses as f64,
            origin: p.origin,
            base: p.base,
            top_beam: false,
            openings: p.openings,
            split_bricks: false,
        },
        ("courses", "blocks_per_course"),
    )
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;

    #[test]
    fn tower_default_and_with_openings() {
        let b = run("tower", "");
        assert_eq!(b.len(), 8 * 2 + 8 * 3 + 1);
        check_blocks(&b);
        assert!((total_area(&b[1..]) - 16.0).abs() < 1e-9);
        assert_connected(&b, 1e-6);
        let b = run("tower", "width = 3\nheight = 12\ncourses = 24\nblocks_per_course = 3\nopenings = [{x = 1.0, y = 0.0, width = 1.0, height = 2.25}, {x = 1.1, y = 8.0, width = 0.8, height = 1.2}]");
        check_blocks(&b);
        assert!((total_area(&b[1..]) - (36.0 - 2.25 - 0.96)).abs() < 1e-9);
        assert_connected(&b, 1e-6);
    }

    #[test]
    fn tower_bad_parameters() {
        assert_err_key("tower", "width = 0", "width");
        assert_err_key("tower", "height = -1", "height");
        assert_err_key("tower", "courses = 0", "courses");
        assert_err_key("tower", "blocks_per_course = 0.5", "blocks_per_course");
        assert_err_key("tower", "blocks_per_course = 1.7", "blocks_per_course");
        assert_err_key(
            "tower",
            "openings = [{x = 1.5, y = 0.0, width = 1.0, height = 2.0}]",
            "openings",
        );
        assert_err_key("tower", "top_beam = true", "top_beam");
    }
}
