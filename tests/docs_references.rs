//! The documentation is a reference that a clone of the repository carries whole:
//!
//! (a) no file under src/, kernels/, ffi/ or docs/ cites the project's working notes
//!     outside the repository (the method, interface and benchmark notes, or a path into
//!     the directory beside it);
//! (b) docs/performance.md stays a reference of the current figures: fewer than
//!     [`PERFORMANCE_MAX_LINES`] lines (the history lives in docs/decisions/);
//! (c) every `docs/….md` path cited in src/, kernels/, ffi/, tests/ and docs/ (the
//!     decision records included, also where a comment wraps after the directory's name)
//!     names a file that exists, every record is indexed in its README, and every
//!     relative markdown link `](….md)` in docs/ leads to a file;
//! (d) every row of docs/theory.md's table "Where each equation lives" names a file that
//!     exists and a function that the file defines (`fn NAME`, NAME the last segment of
//!     `Type::name`).
//!
//! Each test lists every problem it finds, one per line, with the file and line.

use std::fs;
use std::path::{Path, PathBuf};

/// docs/performance.md must stay under this many lines.
const PERFORMANCE_MAX_LINES: usize = 600;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file under `dir` (relative to the repository root), recursively, skipping
/// build output and hidden directories; sorted, for a stable report.
fn files_under(dir: &str) -> Vec<PathBuf> {
    fn walk(p: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = fs::read_dir(p) else {
            return;
        };
        for e in entries.flatten() {
            let path = e.path();
            let name = e.file_name();
            let name = name.to_string_lossy();
            if name.starts_with('.') || name == "target" {
                continue;
            }
            if path.is_dir() {
                walk(&path, out);
            } else {
                out.push(path);
            }
        }
    }
    let mut out = Vec::new();
    walk(&root().join(dir), &mut out);
    out.sort();
    out
}

/// The file's path relative to the repository root, for messages.
fn rel(p: &Path) -> String {
    p.strip_prefix(root()).unwrap_or(p).display().to_string()
}

/// The text of a file, or None for a binary one (figures).
fn text(p: &Path) -> Option<String> {
    fs::read(p).ok().and_then(|b| String::from_utf8(b).ok())
}

fn report(what: &str, problems: &[String]) {
    assert!(
        problems.is_empty(),
        "{what}: {} problem(s)\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn no_reference_to_files_outside_the_repository() {
    // assembled so that this file does not cite them itself
    let banned: Vec<String> = ["METHOD", "INTERFACE", "BENCHMARKS"]
        .iter()
        .map(|n| format!("{n}.md"))
        .chain(std::iter::once(format!("..{}shared", '/')))
        .collect();
    let mut problems = Vec::new();
    for dir in ["src", "kernels", "ffi", "docs"] {
        for f in files_under(dir) {
            let Some(t) = text(&f) else { continue };
            for (i, line) in t.lines().enumerate() {
                for b in &banned {
                    if line.contains(b.as_str()) {
                        problems.push(format!(
                            "{}:{}: cites `{b}`, which a clone of the repository does not have: \
                             cite docs/theory.md, docs/scene-reference.md, docs/outputs.md or \
                             docs/validation.md instead\n    {}",
                            rel(&f),
                            i + 1,
                            line.trim()
                        ));
                    }
                }
            }
        }
    }
    report("references to files outside the repository", &problems);
}

#[test]
fn performance_page_is_a_reference_not_a_notebook() {
    let p = root().join("docs/performance.md");
    let t = fs::read_to_string(&p).expect("docs/performance.md");
    let n = t.lines().count();
    let mut problems = Vec::new();
    if n >= PERFORMANCE_MAX_LINES {
        problems.push(format!(
            "docs/performance.md has {n} lines (at most {} allowed): keep the latest figure \
             of each measured quantity there and move what was tried into a record under \
             docs/decisions/",
            PERFORMANCE_MAX_LINES - 1
        ));
    }
    report("docs/performance.md", &problems);
}

/// Every block of docs/performance.md that benches/performance.py writes is closed, and
/// names a section the script has (its `SECTIONS` table, on one line or several): a
/// renamed section leaves no block that the script can no longer regenerate.
#[test]
fn performance_blocks_name_sections_of_the_script() {
    let doc = fs::read_to_string(root().join("docs/performance.md")).expect("docs/performance.md");
    let script =
        fs::read_to_string(root().join("benches/performance.py")).expect("benches/performance.py");
    let start = script
        .find("\nSECTIONS = {")
        .expect("the script's SECTIONS table");
    let table = &script[start..start + script[start..].find('}').expect("SECTIONS closed")];
    let mut problems = Vec::new();
    let mut blocks = 0;
    for (i, line) in doc.lines().enumerate() {
        let Some(name) = line
            .strip_prefix("<!-- performance.py ")
            .and_then(|r| r.strip_suffix(" -->"))
        else {
            continue;
        };
        blocks += 1;
        if !table.contains(&format!("\"{name}\":")) {
            problems.push(format!(
                "docs/performance.md:{}: section `{name}` is not in benches/performance.py",
                i + 1
            ));
        }
        if !doc.contains(&format!("<!-- end performance.py {name} -->")) {
            problems.push(format!(
                "docs/performance.md:{}: block `{name}` is not closed",
                i + 1
            ));
        }
    }
    if blocks == 0 {
        problems.push("docs/performance.md: no block written by benches/performance.py".into());
    }
    report("docs/performance.md blocks", &problems);
}

/// Characters of a path inside the repository.
fn path_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '/')
}

/// The `docs/….md` paths a text cites, with their line numbers. A citation that a comment
/// wraps right after `docs/decisions/` is joined with the file name on the next line.
fn cited_docs(t: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let bytes = t.as_bytes();
    let mut from = 0;
    while let Some(k) = t[from..].find("docs/") {
        let at = from + k;
        from = at + 5;
        // a path starts here, not inside a longer word (`mydocs/`)
        if at > 0 {
            let prev = t[..at].chars().next_back().unwrap();
            if prev.is_ascii_alphanumeric() || prev == '_' || prev == '-' {
                continue;
            }
        }
        let mut end = at;
        while end < t.len() && path_char(bytes[end] as char) {
            end += 1;
        }
        let mut path = t[at..end].to_string();
        if path == "docs/decisions/" {
            // wrapped: skip white space and comment markers, then read the file name
            let mut j = end;
            while j < t.len()
                && matches!(
                    bytes[j] as char,
                    ' ' | '\t' | '\n' | '\r' | '/' | '!' | '#' | '*'
                )
            {
                j += 1;
            }
            let mut e = j;
            while e < t.len() && path_char(bytes[e] as char) {
                e += 1;
            }
            let name = &t[j..e];
            if name.len() > 5 && name.as_bytes()[..4].iter().all(u8::is_ascii_digit) {
                path.push_str(name);
            }
        }
        // trailing punctuation of the sentence
        while path.ends_with('.') || path.ends_with('/') {
            path.pop();
        }
        if path.ends_with(".md") {
            let line = t[..at].matches('\n').count() + 1;
            out.push((line, path));
        }
    }
    out
}

/// Relative markdown links to `.md` files in a text: `](target)`, without the anchor.
fn md_links(t: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(k) = t[from..].find("](") {
        let at = from + k + 2;
        from = at;
        let Some(close) = t[at..].find(')') else {
            break;
        };
        let target = t[at..at + close].split('#').next().unwrap_or("");
        if target.ends_with(".md") && !target.contains("://") {
            out.push((t[..at].matches('\n').count() + 1, target.to_string()));
        }
    }
    out
}

#[test]
fn cited_docs_exist() {
    let mut problems = Vec::new();
    let mut cited = 0;
    for dir in ["src", "kernels", "ffi", "tests", "docs"] {
        for f in files_under(dir) {
            let Some(t) = text(&f) else { continue };
            for (line, path) in cited_docs(&t) {
                cited += 1;
                if !root().join(&path).is_file() {
                    problems.push(format!(
                        "{}:{line}: cites {path}, which does not exist",
                        rel(&f)
                    ));
                }
            }
            if dir == "docs" && f.extension().is_some_and(|e| e == "md") {
                for (line, target) in md_links(&t) {
                    let to = f.parent().unwrap().join(&target);
                    if !to.is_file() {
                        problems.push(format!(
                            "{}:{line}: links to {target}, which does not exist",
                            rel(&f)
                        ));
                    }
                }
            }
        }
    }
    assert!(
        cited > 0,
        "no docs/….md citation found at all: is the scan broken?"
    );
    // every decision record is indexed
    let index = fs::read_to_string(root().join("docs/decisions/README.md")).unwrap_or_default();
    for f in files_under("docs/decisions") {
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        if name != "README.md" && !index.contains(&format!("({name})")) {
            problems.push(format!("docs/decisions/README.md: does not index {name}"));
        }
    }
    report("cited documentation files", &problems);
}

/// Whether `src` defines a function `name` (`fn name(` or `fn name<`).
fn defines(src: &str, name: &str) -> bool {
    let pat = format!("fn {name}");
    src.match_indices(&pat).any(|(i, _)| {
        let before_ok = i == 0 || !src[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_');
        let after = src[i + pat.len()..].chars().next();
        before_ok && matches!(after, Some('(') | Some('<') | Some(' '))
    })
}

/// The cells of a markdown table row.
fn cells(row: &str) -> Vec<String> {
    let r = row.trim();
    let r = r.strip_prefix('|').unwrap_or(r);
    let r = r.strip_suffix('|').unwrap_or(r);
    r.split('|').map(|c| c.trim().to_string()).collect()
}

/// The text between backticks in a cell: `a`, `b` → [a, b].
fn ticked(cell: &str) -> Vec<String> {
    cell.split('`')
        .enumerate()
        .filter(|(i, s)| i % 2 == 1 && !s.is_empty())
        .map(|(_, s)| s.to_string())
        .collect()
}

#[test]
fn the_equation_map_names_existing_files_and_functions() {
    let theory = fs::read_to_string(root().join("docs/theory.md")).expect("docs/theory.md");
    let heading = "## Where each equation lives";
    let Some(at) = theory.find(heading) else {
        panic!("docs/theory.md: no section \"{heading}\"");
    };
    let first_line = theory[..at].matches('\n').count() + 1;
    let section = &theory[at + heading.len()..];
    let section = match section.find("\n## ") {
        Some(end) => &section[..end],
        None => section,
    };
    let mut problems = Vec::new();
    let mut header: Option<(usize, usize)> = None;
    let mut rows = 0;
    for (k, line) in section.lines().enumerate() {
        let lineno = first_line + k;
        if !line.trim_start().starts_with('|') {
            continue;
        }
        let c = cells(line);
        if header.is_none() {
            let file = c.iter().position(|h| h.eq_ignore_ascii_case("file"));
            let func = c.iter().position(|h| h.eq_ignore_ascii_case("function"));
            match (file, func) {
                (Some(f), Some(g)) => header = Some((f, g)),
                _ => {
                    problems.push(format!(
                        "docs/theory.md:{lineno}: the table's header has no \"file\" and \"function\" columns"
                    ));
                    break;
                }
            }
            continue;
        }
        if c.iter()
            .all(|s| s.chars().all(|ch| matches!(ch, '-' | ':' | ' ')))
        {
            continue; // the separator row
        }
        let (fc, gc) = header.unwrap();
        rows += 1;
        let files = c.get(fc).map(|s| ticked(s)).unwrap_or_default();
        let funcs = c.get(gc).map(|s| ticked(s)).unwrap_or_default();
        let Some(file) = files.first() else {
            problems.push(format!(
                "docs/theory.md:{lineno}: no file named (in backticks)\n    {line}"
            ));
            continue;
        };
        if funcs.is_empty() {
            problems.push(format!(
                "docs/theory.md:{lineno}: no function named (in backticks)\n    {line}"
            ));
            continue;
        }
        let path = root().join(file);
        let Ok(src) = fs::read_to_string(&path) else {
            problems.push(format!("docs/theory.md:{lineno}: {file} does not exist"));
            continue;
        };
        for f in &funcs {
            let name = f.rsplit("::").next().unwrap().trim_end_matches("()");
            if !defines(&src, name) {
                problems.push(format!(
                    "docs/theory.md:{lineno}: {file} has no `fn {name}` (the row names `{f}`)"
                ));
            }
        }
    }
    if header.is_none() && problems.is_empty() {
        problems
            .push("docs/theory.md: the section \"Where each equation lives\" has no table".into());
    } else if rows == 0 && problems.is_empty() {
        problems.push("docs/theory.md: the table \"Where each equation lives\" has no rows".into());
    }
    report("docs/theory.md, \"Where each equation lives\"", &problems);
}
