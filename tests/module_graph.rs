//! The top-level modules of src/ (scene, geometry, mesh, material, assembly, solve,
//! analysis, output, cli, ...) use one another without a circle, so that data flows one
//! way (src/lib.rs) and each module can be read, tested and changed with only the ones
//! before it in mind.
//!
//! Reads every src/**/*.rs, maps each file to its top-level module, collects its
//! `crate::X` references in code (use declarations with their `crate::{a, b}` groups, and
//! paths; comments and string literals left out) and fails with the cycles of the graph
//! they make, each edge with a place that makes it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Module → module it refers to → the first place (file:line) that does.
type Graph = BTreeMap<String, BTreeMap<String, String>>;

#[test]
fn top_level_modules_form_no_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = module_graph(&src);
    // the scanner sees the references (a graph without edges would pass for nothing)
    assert!(
        graph
            .get("analysis")
            .is_some_and(|e| e.contains_key("mesh")),
        "analysis → mesh not found: {graph:?}"
    );
    let cycles = cycles(&graph);
    assert!(
        cycles.is_empty(),
        "the top-level modules of src/ refer to one another in a circle:\n{}",
        cycles.join("\n")
    );
}

#[test]
fn references_in_code_only() {
    let text = r##"
use crate::{geometry::{a, b}, mesh::Mesh as M,
    scene};
// crate::output in a comment, /* crate::cli /* nested */ crate::cli */
let s = "crate::solve"; let r = r#"crate::solve "# ; let c = '"'; let l: &'static str;
fn f<'a>() -> crate::material::X { crate :: assembly::f() }
pub(crate) fn g() {}
"##;
    let found: Vec<(String, usize)> = references(&code_only(text));
    let names: Vec<&str> = found.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["geometry", "mesh", "scene", "material", "assembly"]);
    assert_eq!(found[2].1, 3);
    assert_eq!(found[4].1, 6);
}

/// The graph of `crate::` references among the top-level modules of the crate in `src`
/// (the crate roots lib.rs and main.rs left out; a name re-exported by lib.rs counts
/// for the module it comes from).
fn module_graph(src: &Path) -> Graph {
    let roots = root_names(&code_only(&read(&src.join("lib.rs"))));
    let mut graph = Graph::new();
    for file in rust_files(src) {
        let rel = file.strip_prefix(src).unwrap();
        let first = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let module = first.trim_end_matches(".rs").to_string();
        if module == "lib" || module == "main" {
            continue;
        }
        for (name, line) in references(&code_only(&read(&file))) {
            let target = roots
                .get(&name)
                .unwrap_or_else(|| {
                    panic!("{}:{line}: crate::{name} is not in lib.rs", file.display())
                })
                .clone();
            if target != module {
                graph
                    .entry(module.clone())
                    .or_default()
                    .entry(target)
                    .or_insert_with(|| format!("src/{}:{line}", rel.display()));
            }
        }
    }
    graph
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Every .rs file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                todo.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// lib.rs's names: each module (`mod x;`) for itself, each name it re-exports
/// (`pub use x::{A, B};`) for the module it comes from.
fn root_names(lib: &str) -> BTreeMap<String, String> {
    let mut names = BTreeMap::new();
    for statement in lib.split(';') {
        let words: Vec<&str> = statement.split_whitespace().collect();
        if let [.., "mod", name] = words.as_slice() {
            names.insert(name.to_string(), name.to_string());
        } else if let Some(u) = words.iter().position(|&w| w == "use") {
            let path = words[u + 1..].join(" ");
            let path = path
                .trim_start_matches("crate::")
                .trim_start_matches("self::");
            let Some((module, rest)) = path.split_once("::") else {
                continue;
            };
            for item in rest.trim_matches(|c| c == '{' || c == '}').split(',') {
                // `a::B as C` is C
                let last = item.split_whitespace().last().unwrap_or("");
                let name = last.rsplit("::").next().unwrap();
                if !name.is_empty() {
                    names.insert(name.to_string(), module.to_string());
                }
            }
        }
    }
    names
}

/// `text` with its comments and the contents of its string and character literals
/// blanked (lines kept), so that only code is left to scan.
fn code_only(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out: Vec<char> = c.clone();
    let blank = |out: &mut Vec<char>, from: usize, to: usize| {
        for x in &mut out[from..to.min(c.len())] {
            if *x != '\n' {
                *x = ' ';
            }
        }
    };
    let ident = |x: char| x.is_alphanumeric() || x == '_';
    let mut i = 0;
    while i < c.len() {
        let at = |k: usize| c.get(k).copied().unwrap_or('\0');
        if at(i) == '/' && at(i + 1) == '/' {
            let end = (i..c.len()).find(|&k| c[k] == '\n').unwrap_or(c.len());
            blank(&mut out, i, end);
            i = end;
        } else if at(i) == '/' && at(i + 1) == '*' {
            let (mut depth, mut k) = (1, i + 2);
            while k < c.len() && depth > 0 {
                if at(k) == '/' && at(k + 1) == '*' {
                    depth += 1;
                    k += 2;
                } else if at(k) == '*' && at(k + 1) == '/' {
                    depth -= 1;
                    k += 2;
                } else {
                    k += 1;
                }
            }
            blank(&mut out, i, k);
            i = k;
        } else if (at(i) == 'r' || (at(i) == 'b' && at(i + 1) == 'r'))
            && (i == 0 || !ident(c[i - 1]))
            && {
                let k = i + if at(i) == 'b' { 2 } else { 1 };
                let hashes = (k..c.len()).take_while(|&j| c[j] == '#').count();
                at(k + hashes) == '"'
            }
        {
            // raw string: r#"..."# with as many #s at the end
            let k = i + if at(i) == 'b' { 2 } else { 1 };
            let hashes = (k..c.len()).take_while(|&j| c[j] == '#').count();
            let start = k + hashes + 1;
            let mut end = start;
            while end < c.len() && !(c[end] == '"' && (1..=hashes).all(|h| at(end + h) == '#')) {
                end += 1;
            }
            blank(&mut out, start, end);
            i = end + 1 + hashes;
        } else if at(i) == '"' {
            let mut k = i + 1;
            while k < c.len() && c[k] != '"' {
                k += if c[k] == '\\' { 2 } else { 1 };
            }
            blank(&mut out, i + 1, k);
            i = k + 1;
        } else if at(i) == '\'' && (at(i + 1) == '\\' || at(i + 2) == '\'') {
            // a character literal ('x', '\n', '\u{..}'); not a lifetime ('a)
            let mut k = i + 1;
            while k < c.len() && c[k] != '\'' {
                k += if c[k] == '\\' { 2 } else { 1 };
            }
            blank(&mut out, i + 1, k);
            i = k + 1;
        } else {
            i += 1;
        }
    }
    out.into_iter().collect()
}

/// The top-level names after `crate::` in `code` (from [`code_only`]), with their line
/// (1-based): `crate::x::...` gives x, `crate::{x::..., y}` gives x and y.
fn references(code: &str) -> Vec<(String, usize)> {
    let c: Vec<char> = code.chars().collect();
    let ident = |x: char| x.is_alphanumeric() || x == '_';
    let skip_space = |mut k: usize| {
        while k < c.len() && c[k].is_whitespace() {
            k += 1;
        }
        k
    };
    let word = |k: usize| -> String { c[k..].iter().take_while(|&&x| ident(x)).collect() };
    let line = |k: usize| 1 + c[..k].iter().filter(|&&x| x == '\n').count();
    let mut found = Vec::new();
    let mut i = 0;
    while i + 5 <= c.len() {
        let is_crate = c[i..i + 5].iter().collect::<String>() == "crate"
            && (i == 0 || !ident(c[i - 1]))
            && !ident(c.get(i + 5).copied().unwrap_or(' '));
        if !is_crate {
            i += 1;
            continue;
        }
        let mut k = skip_space(i + 5);
        if !(c.get(k) == Some(&':') && c.get(k + 1) == Some(&':')) {
            i += 5;
            continue;
        }
        k = skip_space(k + 2);
        if c.get(k) == Some(&'{') {
            // a group: the first name of each of its items
            let (mut depth, mut start) = (1, true);
            k += 1;
            while k < c.len() && depth > 0 {
                match c[k] {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 1 => start = true,
                    x if start && depth == 1 && ident(x) => {
                        let w = word(k);
                        found.push((w.clone(), line(k)));
                        k += w.len();
                        start = false;
                        continue;
                    }
                    _ => {}
                }
                k += 1;
            }
        } else if k < c.len() && ident(c[k]) {
            found.push((word(k), line(k)));
        }
        i = k.max(i + 5);
    }
    found
}

/// One cycle through each group of modules that reach one another (strongly connected
/// components of more than one module), written `a → b (place) → ... → a`.
fn cycles(graph: &Graph) -> Vec<String> {
    let nodes: BTreeSet<&str> = graph
        .iter()
        .flat_map(|(a, e)| std::iter::once(a.as_str()).chain(e.keys().map(String::as_str)))
        .collect();
    let reach = |from: &str| -> BTreeSet<String> {
        let mut seen = BTreeSet::new();
        let mut todo = vec![from.to_string()];
        while let Some(n) = todo.pop() {
            for m in graph.get(&n).into_iter().flat_map(|e| e.keys()) {
                if seen.insert(m.clone()) {
                    todo.push(m.clone());
                }
            }
        }
        seen
    };
    let reaches: BTreeMap<&str, BTreeSet<String>> = nodes.iter().map(|&n| (n, reach(n))).collect();
    let mut done = BTreeSet::new();
    let mut out = Vec::new();
    for &n in &nodes {
        if done.contains(n) || !reaches[n].contains(n) {
            continue;
        }
        // the component of n: the modules n reaches that reach n back
        let component: BTreeSet<&str> = nodes
            .iter()
            .copied()
            .filter(|&m| m == n || (reaches[n].contains(m) && reaches[m].contains(n)))
            .collect();
        done.extend(component.iter().copied());
        // a shortest way from n back to n, within the component (breadth first)
        let mut back: BTreeMap<&str, &str> = BTreeMap::new();
        let mut queue = std::collections::VecDeque::from([n]);
        let mut last = None;
        while let Some(a) = queue.pop_front() {
            for b in graph[a].keys().map(String::as_str) {
                if b == n {
                    last = Some(a);
                    break;
                }
                if component.contains(b) && !back.contains_key(b) {
                    back.insert(b, a);
                    queue.push_back(b);
                }
            }
            if last.is_some() {
                break;
            }
        }
        let mut path = vec![n];
        let mut a = last.expect("n is on a cycle");
        while a != n {
            path.push(a);
            a = back[a];
        }
        path.push(n);
        path.reverse();
        let mut text = path[0].to_string();
        for w in path.windows(2) {
            text += &format!(" → {} ({})", w[1], graph[w[0]][w[1]]);
        }
        let members: Vec<&str> = component.into_iter().collect();
        out.push(format!(
            "{text}   [modules in the circle: {}]",
            members.join(", ")
        ));
    }
    out
}
