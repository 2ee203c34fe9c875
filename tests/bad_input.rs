//! Bad input gets a one-line error naming the file, the line and the fix, exit status 2,
//! and never a panic. One test per file of `tests/bad_input/`; each file says in its
//! header the message it must print (`# expect: ...`) and the line it must name
//! (`# line: N`).

mod common;
use std::path::Path;
use std::process::Command;

fn check_case(name: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/bad_input")
        .join(format!("{name}.toml"));
    let text = std::fs::read_to_string(&path).unwrap();
    let header = |k: &str| -> String {
        text.lines()
            .find_map(|l| l.strip_prefix(&format!("# {k}: ")).map(str::to_string))
            .unwrap_or_else(|| panic!("{name}: no '# {k}:' header"))
    };
    let expect = header("expect");
    let line: usize = header("line").parse().unwrap();
    let out_dir = common::tmp_dir(&format!("bad_{name}"));
    let out = Command::new(common::dfem_bin())
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(&out_dir)
        .arg("--quiet")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{name}: exit status {:?}, stderr: {stderr}",
        out.status.code()
    );
    assert!(
        !stderr.contains("panicked") && !stderr.contains("internal error"),
        "{name}: {stderr}"
    );
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{name}: one line expected: {stderr}");
    let msg = lines[0];
    let place = format!("{}:{line}: ", path.display());
    assert!(
        msg.starts_with("error: ") && msg.contains(&place),
        "{name}: message must name {place}: {msg}"
    );
    assert!(
        msg.contains(&expect),
        "{name}: expected «{expect}» in: {msg}"
    );
    assert!(
        msg.contains("; fix: "),
        "{name}: the message must say how to fix it: {msg}"
    );
    // nothing written for bad input
    assert!(
        !out_dir.join("summary.json").exists(),
        "{name}: a summary was written"
    );
}

/// The `[analysis]` settings are checked when the scene is read: `dfem check` reports a bad
/// one with its line, before any run.
#[test]
fn analysis_settings_are_checked_by_dfem_check() {
    for name in [
        "unknown_strategy",
        "tolerance_out_of_range",
        "push_unknown_block",
        "arc_length_without_push",
        "unknown_integrator",
        "rayleigh_one_number",
        "line_search_not_boolean",
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/bad_input")
            .join(format!("{name}.toml"));
        let out = Command::new(common::dfem_bin())
            .arg("check")
            .arg(&path)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let text = std::fs::read_to_string(&path).unwrap();
        let line = text
            .lines()
            .find_map(|l| l.strip_prefix("# line: "))
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
        assert!(
            stderr.contains(&format!("{}:{line}: [analysis] key", path.display())),
            "{name}: {stderr}"
        );
    }
}

macro_rules! cases {
    ($($name:ident),* $(,)?) => {
        $(#[test] fn $name() { check_case(stringify!($name)); })*
        const LISTED: &[&str] = &[$(stringify!($name)),*];
    };
}

#[test]
fn every_file_has_a_test() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_input");
    let mut files: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            e.unwrap()
                .path()
                .file_stem()
                .unwrap()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    files.sort();
    let mut listed: Vec<String> = LISTED.iter().map(|s| s.to_string()).collect();
    listed.sort();
    assert_eq!(files, listed);
}

cases! {
    three_dimensional_scene,
    dimension_not_2_or_3,
    accept_residual_without_arc_length,
    arc_length_without_push,
    push_deformable_block,
    push_unknown_block,
    rayleigh_one_number,
    tolerance_out_of_range,
    unknown_integrator,
    unknown_strategy,
    softening_without_fracture_energy,
    cap_without_softening,
    line_search_not_boolean,
    cap_energy_without_peak,
    dilatancy_without_stress,
    dilatancy_above_friction,
    dilatancy_stress_alone,
    within_unknown,
    tension_cut_off_beyond_apex,
    all_fixed,
    checkpoint_every_zero,
    frame_interval_zero,
    every_and_frame_interval,
    in_situ_without_stress,
    degenerate_collinear,
    degenerate_two_vertices,
    dt_longer_than_duration,
    duplicate_block_name,
    dynamic_without_dt,
    empty_scene,
    far_apart_unsupported,
    friction_90,
    generate_missing_material,
    generate_ten_million_blocks,
    generate_unknown_type,
    import_dxf_arc,
    import_dxf_bad_number,
    import_dxf_no_polylines,
    import_group_without_material,
    import_missing_file,
    import_msh_bad_number,
    import_msh_binary,
    import_msh_hole,
    import_msh_unclosed,
    import_unknown_format,
    import_unknown_group,
    ground_motion_bad_expression,
    ground_motion_bad_value,
    ground_motion_empty_record,
    ground_motion_missing_file,
    ground_motion_zero_dt,
    ground_motion_two_along_x,
    frame_unknown,
    frame_absolute_without_inertia,
    inf_unit_weight,
    infinite_vertex,
    load_steps_zero,
    load_unknown_block,
    missing_friction,
    missing_material,
    missing_material_key,
    missing_modulus,
    missing_vertices,
    nan_gravity,
    nan_modulus,
    negative_band,
    negative_dt,
    negative_lambda,
    negative_modulus,
    no_joint,
    only_title,
    overlapping_blocks,
    repeated_vertex,
    self_intersecting,
    syntax_duplicate_key,
    syntax_missing_equals,
    syntax_unclosed_bracket,
    track_unknown_block,
    unknown_analysis_type,
    unknown_joint_in_contacts,
    unknown_key_analysis,
    unknown_key_block,
    unknown_key_material,
    unknown_key_top,
    unknown_kind,
    unknown_plane,
    unknown_support,
    wrong_type_modulus_string,
    wrong_type_thickness,
    wrong_type_vertices,
    zero_joint_modulus,
    zero_modulus,
    zero_thickness,
}
