//! docs/scene-reference.md lists every key the parser and the generators accept, so the
//! reference cannot drift from the code: the keys are read from the parser's `Raw*`
//! structs, its `[analysis]` key list and the generators' parameter structs.

use std::path::Path;

fn fields_of_structs(src: &str, name_filter: impl Fn(&str) -> bool) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    for line in src.lines() {
        let t = line.trim();
        if let Some(rest) = t
            .strip_prefix("struct ")
            .or_else(|| t.strip_prefix("pub struct "))
        {
            let name = rest
                .split(|c: char| !c.is_alphanumeric() && c != '_')
                .next()
                .unwrap_or("");
            inside = name_filter(name) && t.ends_with('{');
            continue;
        }
        if inside {
            if t.starts_with('}') {
                inside = false;
                continue;
            }
            if t.starts_with('#') || t.starts_with("//") || t.is_empty() {
                continue;
            }
            let t = t.strip_prefix("pub ").unwrap_or(t);
            if let Some((f, _)) = t.split_once(':') {
                out.push(f.trim().trim_start_matches("r#").to_string());
            }
        }
    }
    out
}

#[test]
fn every_key_is_documented() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/scene-reference.md")).unwrap();
    let parse = std::fs::read_to_string(root.join("src/scene/parse.rs")).unwrap();
    let mut keys = fields_of_structs(&parse, |n| n.starts_with("Raw"));
    let list = parse
        .split("const ANALYSIS_KEYS")
        .nth(1)
        .unwrap()
        .split(';')
        .next()
        .unwrap();
    keys.extend(list.split('"').skip(1).step_by(2).map(str::to_string));
    for entry in std::fs::read_dir(root.join("src/scene/generate")).unwrap() {
        let p = entry.unwrap().path();
        let src = std::fs::read_to_string(&p).unwrap();
        keys.extend(fields_of_structs(&src, |n| {
            n.ends_with("Params") || n.ends_with("Spec")
        }));
    }
    assert!(keys.len() > 30, "too few keys found: {keys:?}");
    let missing: Vec<&String> = keys
        .iter()
        .filter(|k| !doc.contains(&format!("`{k}`")))
        .collect();
    assert!(
        missing.is_empty(),
        "keys missing from docs/scene-reference.md: {missing:?}"
    );
}
