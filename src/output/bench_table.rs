//! The table of a benchmark (`dfem bench-solvers`, `benches/strategies.rs`): a header and
//! rows of text cells, printed as markdown (docs/performance.md) and saved as CSV
//! (`--csv FILE`), from which [`super::time_error`] draws the run time against the error.
//! The CSV holds the same cells as the markdown, so a table copied from the docs and one
//! saved by a bench are read alike.

use super::write_atomic;
use crate::{Error, Result};
use std::path::Path;

/// A table: column names and rows of cells (each row as long as the header).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// An empty table with these column names.
    pub fn new(header: &[&str]) -> Table {
        Table {
            header: header.iter().map(|h| h.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    /// The markdown header line and its alignment line (`---:` for the columns `numeric`).
    pub fn markdown_header(&self, numeric: &[bool]) -> String {
        let align: Vec<&str> = (0..self.header.len())
            .map(|i| {
                if numeric.get(i).copied().unwrap_or(false) {
                    "---:"
                } else {
                    "---"
                }
            })
            .collect();
        format!("{}\n|{}|\n", markdown_line(&self.header), align.join("|"))
    }

    /// The whole table as markdown (every column left-aligned).
    pub fn markdown(&self) -> String {
        let mut s = self.markdown_header(&[]);
        for r in &self.rows {
            s.push_str(&markdown_line(r));
            s.push('\n');
        }
        s
    }

    /// The table as CSV (RFC 4180: a cell with a comma, a quote or a line break is quoted,
    /// its quotes doubled).
    pub fn csv(&self) -> String {
        let mut s = String::new();
        for r in std::iter::once(&self.header).chain(&self.rows) {
            let cells: Vec<String> = r.iter().map(|c| csv_cell(c)).collect();
            s.push_str(&cells.join(","));
            s.push('\n');
        }
        s
    }

    /// Write the CSV to `path` (atomically).
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        write_atomic(path, self.csv().as_bytes())
    }

    /// Read a CSV written by [`Table::csv`]: the first record is the header; every record
    /// must have as many cells.
    pub fn read_csv(path: &Path) -> Result<Table> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            Error::new(format!("cannot read the table: {e}"))
                .file(path)
                .fix("give the CSV file a benchmark wrote with --csv FILE")
        })?;
        Table::parse_csv(&text).map_err(|(line, what)| {
            Error::new(format!("cannot read the table: {what}"))
                .file(path)
                .line(Some(line))
                .fix("the file must be a CSV table with a header line, as the benchmarks write with --csv FILE")
        })
    }

    /// Parse CSV text; on error the 1-based line and what is wrong.
    pub fn parse_csv(text: &str) -> std::result::Result<Table, (usize, String)> {
        let mut records = csv_records(text)?.into_iter();
        let Some((_, header)) = records.next() else {
            return Err((1, "the file is empty".into()));
        };
        let mut t = Table {
            header,
            rows: Vec::new(),
        };
        for (line, r) in records {
            if r.len() != t.header.len() {
                return Err((
                    line,
                    format!(
                        "{} cells where the header has {} columns",
                        r.len(),
                        t.header.len()
                    ),
                ));
            }
            t.rows.push(r);
        }
        Ok(t)
    }

    /// Every table of a markdown document, in order: a header line `| a | b |`, an
    /// alignment line `|---|---:|`, and the `|` lines that follow. Cells are trimmed; a
    /// row with another number of cells than its header ends the table.
    pub fn markdown_tables(text: &str) -> Vec<Table> {
        let lines: Vec<&str> = text.lines().map(str::trim).collect();
        let mut tables = Vec::new();
        let mut i = 0;
        while i + 1 < lines.len() {
            let is_align = |l: &str| {
                l.starts_with('|')
                    && markdown_cells(l)
                        .iter()
                        .all(|c| !c.is_empty() && c.chars().all(|ch| ch == '-' || ch == ':'))
            };
            if lines[i].starts_with('|') && is_align(lines[i + 1]) {
                let header = markdown_cells(lines[i]);
                let mut t = Table {
                    header,
                    rows: Vec::new(),
                };
                i += 2;
                while i < lines.len() && lines[i].starts_with('|') {
                    let r = markdown_cells(lines[i]);
                    if r.len() != t.header.len() {
                        break;
                    }
                    t.rows.push(r);
                    i += 1;
                }
                tables.push(t);
            } else {
                i += 1;
            }
        }
        tables
    }

    /// The index of column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }
}

/// One markdown table line `| a | b |`.
pub fn markdown_line<S: AsRef<str>>(cells: &[S]) -> String {
    let mut s = String::from("|");
    for c in cells {
        s.push(' ');
        s.push_str(c.as_ref());
        s.push_str(" |");
    }
    s
}

/// The cells of a markdown table line (outer pipes dropped, cells trimmed). A `|` inside
/// backticks belongs to its cell.
fn markdown_cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|');
    let inner = inner.strip_suffix('|').unwrap_or(inner);
    let mut cells = Vec::new();
    let mut cur = String::new();
    let mut code = false;
    for ch in inner.chars() {
        match ch {
            '`' => {
                code = !code;
                cur.push(ch);
            }
            '|' if !code => cells.push(std::mem::take(&mut cur).trim().to_string()),
            _ => cur.push(ch),
        }
    }
    cells.push(cur.trim().to_string());
    cells
}

fn csv_cell(c: &str) -> String {
    if c.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", c.replace('"', "\"\""))
    } else {
        c.to_string()
    }
}

/// A CSV record: the 1-based line it starts on and its cells.
type Record = (usize, Vec<String>);

/// The records of CSV text; on error the line and what is wrong.
fn csv_records(text: &str) -> std::result::Result<Vec<Record>, (usize, String)> {
    let mut out = Vec::new();
    let mut chars = text.chars().peekable();
    let mut line = 1;
    while chars.peek().is_some() {
        let start = line;
        let mut rec = Vec::new();
        let mut cell = String::new();
        let mut quoted = false;
        loop {
            match chars.next() {
                None => {
                    if quoted {
                        return Err((start, "a quoted cell is not closed".into()));
                    }
                    break;
                }
                Some('"') if quoted => {
                    if chars.peek() == Some(&'"') {
                        chars.next();
                        cell.push('"');
                    } else {
                        quoted = false;
                    }
                }
                Some('"') if cell.is_empty() => quoted = true,
                Some(',') if !quoted => rec.push(std::mem::take(&mut cell)),
                Some('\r') if !quoted && chars.peek() == Some(&'\n') => {}
                Some('\n') if !quoted => {
                    line += 1;
                    break;
                }
                Some(c) => {
                    if c == '\n' {
                        line += 1;
                    }
                    cell.push(c);
                }
            }
        }
        rec.push(cell);
        if !(rec.len() == 1 && rec[0].is_empty()) {
            out.push((start, rec));
        }
    }
    Ok(out)
}

/// The number a cell starts with (`"2.10 (stopped after 600 s)"` → 2.1); `None` for a
/// cell that does not start with one (`"–"`, `"(reference)"`).
pub fn leading_number(cell: &str) -> Option<f64> {
    cell.split_whitespace().next()?.parse().ok()
}

/// A time in s: three decimals, or three significant digits under 10 ms (a small matrix
/// solves in microseconds, which the figure's log axis must still place).
fn seconds(s: f64) -> String {
    if s >= 0.01 || s == 0.0 || !s.is_finite() {
        format!("{s:.3}")
    } else {
        format!("{s:.2e}")
    }
}

/// The columns of the table of `benches/strategies.rs` (those of
/// [`super::time_error::STRATEGIES`] among them).
pub const STRATEGY_COLUMNS: [&str; 10] = [
    "blocks",
    "dofs",
    "strategy",
    "tolerance",
    "bracket",
    "λ",
    "error",
    "iterations",
    "numeric factorizations",
    "wall time (s)",
];

/// The columns of the table of `dfem bench-solvers` (those [`super::time_error::SOLVERS`]
/// draws among them).
pub const SOLVER_COLUMNS: [&str; 9] = [
    "backend",
    "setup (s)",
    "factor / precond. (s)",
    "solve (s)",
    "total (s)",
    "iterations",
    "factor nnz",
    "memory (MB)",
    "true residual",
];

/// The table of `dfem bench-solvers` (printed as markdown, saved as CSV by `--csv`).
pub fn solvers(rows: &[crate::solve::bench::BenchRow]) -> Table {
    let num = |v: usize| {
        if v == 0 {
            "-".to_string()
        } else {
            format!("{:.2}M", v as f64 / 1e6)
        }
    };
    let mut t = Table::new(&SOLVER_COLUMNS);
    for r in rows {
        let total = r.setup_s + r.factor_s + r.solve_s;
        t.rows.push(vec![
            r.name.clone(),
            seconds(r.setup_s),
            seconds(r.factor_s),
            seconds(r.solve_s),
            seconds(total),
            r.iterations.to_string(),
            num(r.factor_nnz),
            if r.memory_bytes == 0 {
                "-".to_string()
            } else {
                format!("{:.0}", r.memory_bytes as f64 / 1e6)
            },
            format!(
                "{:.1e}{}",
                r.residual,
                r.error
                    .as_ref()
                    .map(|e| format!(" (failed: {e})"))
                    .unwrap_or_default()
            ),
        ]);
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trips_cells_with_commas_and_quotes() {
        let mut t = Table::new(&["backend", "total (s)"]);
        t.rows
            .push(vec!["petsc, \"-ksp_rtol 1e-8\"".into(), "3.929".into()]);
        t.rows.push(vec!["faer-lu".into(), "".into()]);
        let back = Table::parse_csv(&t.csv()).unwrap();
        assert_eq!(back, t);
    }

    #[test]
    fn csv_rows_of_another_width_are_refused_with_their_line() {
        assert_eq!(
            Table::parse_csv("a,b\n1,2\n3\n").unwrap_err().0,
            3,
            "the short row is on line 3"
        );
    }

    #[test]
    fn markdown_tables_read_back_what_markdown_writes() {
        let mut t = Table::new(&["backend", "residual"]);
        t.rows
            .push(vec!["petsc, `-a | b`".into(), "2.7e-11".into()]);
        t.rows.push(vec!["mumps".into(), "2.2e-11".into()]);
        let doc = format!("# title\n\ntext | not a table\n\n{}\nafter\n", t.markdown());
        assert_eq!(Table::markdown_tables(&doc), vec![t]);
    }

    #[test]
    fn seconds_keep_three_significant_digits_below_10_ms() {
        assert_eq!(seconds(3.0474), "3.047");
        assert_eq!(seconds(0.0123), "0.012");
        assert_eq!(seconds(0.000_123_4), "1.23e-4");
        assert_eq!(seconds(0.0), "0.000");
    }

    #[test]
    fn leading_numbers_of_cells() {
        assert_eq!(leading_number("2.10 (stopped after 600 s)"), Some(2.1));
        assert_eq!(leading_number("6.2e-3"), Some(6.2e-3));
        assert_eq!(leading_number("(reference)"), None);
        assert_eq!(leading_number("–"), None);
    }
}
