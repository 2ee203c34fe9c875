//! Every built-in example (`dfem example NAME`) parses, passes validation (valid,
//! non-overlapping polygons), has contacts wherever blocks should touch (every free block
//! touches another block), runs to its end and writes its results.
//!
//! The Eindhoven walls run here with their push shortened (`common::example_scene`).

mod common;
use std::process::Command;

#[test]
fn every_example_runs() {
    for (name, _, text) in dfem::scene::examples::EXAMPLES {
        let sc = dfem::scene::parse_str(text, None).unwrap_or_else(|e| panic!("{name}: {e}"));
        let m = dfem::mesh::build(&sc);
        for (i, b) in sc.blocks.iter().enumerate() {
            let touches = m
                .contacts
                .iter()
                .any(|c| c.block_l as usize == i || c.block_m as usize == i);
            assert!(touches, "{name}: block '{}' touches nothing", b.name);
        }
        let dir = common::tmp_dir(&format!("example_{name}"));
        let mut cmd = Command::new(common::dfem_bin());
        cmd.arg("run");
        match common::example_scene(name, text, &dir) {
            Some(file) => cmd.arg(file),
            None => cmd.args(["--example", name]),
        };
        let out = cmd.args(["--quiet", "--out"]).arg(&dir).output().unwrap();
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        let status = v["status"].as_str().unwrap();
        assert!(
            status == "stable" || status == "failed" || status == "completed",
            "{name}: {status}"
        );
        if v["analysis"] == "dynamic" {
            assert_eq!(status, "completed", "{name}");
            let h = std::fs::read_to_string(dir.join("history.csv")).unwrap();
            assert!(h.starts_with("t,"), "{name}: {}", &h[..h.len().min(80)]);
            assert!(h.lines().count() > 2, "{name}: history");
            assert!(dir.join("results.pvd").exists(), "{name}: no .pvd");
        }
        eprintln!(
            "{name}: {status} {} ({} dofs, {} contacts, {:.3} s)",
            v["message"], v["stats"]["dofs"], v["stats"]["contacts"], v["stats"]["wall_time_s"]
        );
    }
}
