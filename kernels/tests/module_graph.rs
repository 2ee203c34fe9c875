//! The kernels' top-level modules must import each other without a cycle, so that a
//! reader can take them in order, each one needing only those before it (`backend` before
//! the backends, the backends before `registry`). This test reads `src/`, collects every
//! module's references to a sibling module (`crate::x`, or `super::x` from a top-level
//! file, also inside `use crate::{x::.., y::..}` groups), and reports any cycle.
//!
//! Read as dependencies: code only (comments and doc links are not imports) and not the
//! unit tests (`#[cfg(test)]` items and `tests.rs` files), which may use any module.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// The source with comments removed (line comments and `/* .. */` blocks; string
/// literals, which may hold `//`, kept as they are).
fn strip_comments(src: &str) -> String {
    let b = src.as_bytes();
    let mut out = String::with_capacity(src.len());
    let (mut i, mut in_str) = (0, false);
    while i < b.len() {
        let c = b[i];
        if in_str {
            if c == b'\\' && i + 1 < b.len() {
                out.push_str(&src[i..i + 2]);
                i += 2;
                continue;
            }
            in_str = c != b'"';
        } else if c == b'"' {
            in_str = !(i > 0 && b[i - 1] == b'\'');
        } else if src[i..].starts_with("//") {
            i += src[i..].find('\n').unwrap_or(src.len() - i);
            continue;
        } else if src[i..].starts_with("/*") {
            i += src[i..].find("*/").map_or(src.len() - i, |k| k + 2);
            continue;
        }
        let ch = src[i..].chars().next().unwrap();
        out.push(ch);
        i += ch.len_utf8();
    }
    out
}

/// The code without the items marked `#[cfg(test)]` (a `mod tests;` line, or an item
/// with its braces).
fn strip_test_items(code: &str) -> String {
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    while let Some(k) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..k]);
        let item = &rest[k..];
        let end = match (item.find(';'), item.find('{')) {
            (Some(semi), Some(open)) if semi < open => semi + 1,
            (_, Some(open)) => {
                let mut depth = 0usize;
                let mut end = item.len();
                for (j, c) in item[open..].char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = open + j + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                end
            }
            (Some(semi), None) => semi + 1,
            (None, None) => item.len(),
        };
        rest = &item[end..];
    }
    out.push_str(rest);
    out
}

/// The identifier at the start of `s`.
fn ident(s: &str) -> &str {
    let end = s
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(s.len());
    &s[..end]
}

/// The first path segments named after `prefix` (`crate::`, `super::`) in `code`: the
/// segment itself, or each first segment of a `{a::.., b}` group.
fn first_segments(code: &str, prefix: &str) -> Vec<String> {
    let mut found = Vec::new();
    let mut at = 0;
    while let Some(k) = code[at..].find(prefix) {
        let start = at + k;
        at = start + prefix.len();
        let before = code[..start].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue; // e.g. `dfem_crate::`
        }
        let after = &code[at..];
        if let Some(group) = after.strip_prefix('{') {
            let mut depth = 0usize;
            let mut item_start = true;
            for (j, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => item_start = true,
                    c if c.is_whitespace() => {}
                    _ if item_start => {
                        found.push(ident(&group[j..]).to_string());
                        item_start = false;
                    }
                    _ => {}
                }
            }
        } else {
            found.push(ident(after).to_string());
        }
    }
    found
}

/// Every `.rs` file under `dir`, recursively.
fn rust_files(dir: &Path, into: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("read src") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            rust_files(&path, into);
        } else if path.extension().is_some_and(|e| e == "rs") {
            into.push(path);
        }
    }
}

/// Module → the sibling top-level modules its code refers to.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let top = |p: &Path| -> (String, usize) {
        let rel = p.strip_prefix(src).expect("under src");
        let first = rel.components().next().expect("a component");
        let name = first.as_os_str().to_string_lossy();
        (
            name.trim_end_matches(".rs").to_string(),
            rel.components().count() - 1,
        )
    };
    let modules: BTreeSet<String> = files
        .iter()
        .map(|p| top(p).0)
        .filter(|m| m != "lib" && m != "main")
        .collect();
    let mut graph: BTreeMap<String, BTreeSet<String>> = modules
        .iter()
        .map(|m| (m.clone(), BTreeSet::new()))
        .collect();
    for path in &files {
        let (module, depth) = top(path);
        if module == "lib" || path.file_name().is_some_and(|f| f == "tests.rs") {
            continue;
        }
        let code = strip_test_items(&strip_comments(&fs::read_to_string(path).expect("read")));
        // `super::` leads to the crate root from a top-level file only; from deeper files,
        // `super::super::..` as many times as the file is deep.
        let to_root = "super::".repeat(depth + 1);
        let mut uses = first_segments(&code, "crate::");
        uses.extend(first_segments(&code, &to_root));
        for dep in uses {
            if dep != module && modules.contains(&dep) {
                graph.get_mut(&module).expect("module").insert(dep);
            }
        }
    }
    graph
}

/// A cycle of `graph` as the list of its modules (the first repeated at the end), if any.
fn find_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        New,
        OnPath,
        Done,
    }
    fn visit<'a>(
        m: &'a str,
        graph: &'a BTreeMap<String, BTreeSet<String>>,
        mark: &mut BTreeMap<&'a str, Mark>,
        path: &mut Vec<&'a str>,
    ) -> Option<Vec<String>> {
        mark.insert(m, Mark::OnPath);
        path.push(m);
        for dep in &graph[m] {
            match mark[dep.as_str()] {
                Mark::OnPath => {
                    let from = path.iter().position(|p| p == dep).expect("on the path");
                    let mut cycle: Vec<String> =
                        path[from..].iter().map(|s| s.to_string()).collect();
                    cycle.push(dep.clone());
                    return Some(cycle);
                }
                Mark::New => {
                    if let Some(c) = visit(dep, graph, mark, path) {
                        return Some(c);
                    }
                }
                Mark::Done => {}
            }
        }
        path.pop();
        mark.insert(m, Mark::Done);
        None
    }
    let mut mark: BTreeMap<&str, Mark> = graph.keys().map(|k| (k.as_str(), Mark::New)).collect();
    for m in graph.keys() {
        if mark[m.as_str()] == Mark::New {
            if let Some(c) = visit(m, graph, &mut mark, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn modules_import_each_other_without_a_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = module_graph(&src);
    assert!(
        graph
            .get("faer_backend")
            .is_some_and(|d| d.contains("backend")),
        "the scan misses imports: {graph:?}"
    );
    if let Some(cycle) = find_cycle(&graph) {
        panic!(
            "import cycle among kernels' modules: {}\n(the graph: {graph:#?})",
            cycle.join(" → ")
        );
    }
}

#[test]
fn the_scan_sees_groups_and_skips_comments_and_tests() {
    let code = strip_test_items(&strip_comments(
        "use crate::{a::X, b::{Y, Z}};\n/// [`crate::c`]\nlet s = \"//\"; crate::d::f();\n\
         #[cfg(test)]\nmod tests { use crate::e; }\n#[cfg(test)]\nmod more;\nsuper::g::h();",
    ));
    assert_eq!(first_segments(&code, "crate::"), ["a", "b", "d"]);
    assert_eq!(first_segments(&code, "super::"), ["g"]);
    let graph: BTreeMap<String, BTreeSet<String>> = [("a", "b"), ("b", "c"), ("c", "a")]
        .iter()
        .map(|(m, d)| (m.to_string(), BTreeSet::from([d.to_string()])))
        .collect();
    assert_eq!(find_cycle(&graph).expect("a cycle"), ["a", "b", "c", "a"]);
}
