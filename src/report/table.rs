//! Error statistics and tables in Markdown, CSV and HTML.
//!
//! [`ErrorStats`] (computed in [`crate::problems::errors`], re-exported here) summarises a
//! tracking error ε(t) = |model − measurement|; [`ErrorStats::cell`] writes it as a table
//! cell. [`error_table`] lays such figures out as in Millard & Mombaur (2019), Table 3: one
//! row per channel, one column per run, each cell `mean ± sd (max M)`, the unit in the row
//! label.
//!
//! # Example
//!
//! ```
//! use footfall::report::table::{error_table, ChannelErrors, ErrorStats};
//!
//! let knee = ErrorStats::from_pair(&[1.0, 2.0, 4.0], &[1.5, 1.0, f64::NAN]);
//! assert_eq!((knee.n, knee.max), (2, 1.0));
//! let t = error_table(
//!     "Tracking errors",
//!     &["ellipse".to_string()],
//!     &[ChannelErrors { name: "knee angle".into(), unit: "°".into(), decimals: 2, runs: vec![Some(knee)] }],
//! );
//! assert!(t.to_markdown().contains("| knee angle (°) | 0.75 ± 0.25 (max 1.00) |"));
//! ```

use super::escape_xml;
pub use crate::problems::errors::{ChannelErrors, ErrorStats};
use std::fmt::Write;

/// Rendering of [`ErrorStats`] (computed in [`crate::problems::errors`]).
impl ErrorStats {
    /// `mean ± sd (max M)` with `decimals` digits after the point; `—` when `n == 0`.
    pub fn cell(&self, decimals: usize) -> String {
        if self.n == 0 {
            return "—".to_string();
        }
        format!(
            "{:.d$} ± {:.d$} (max {:.d$})",
            self.mean,
            self.sd,
            self.max,
            d = decimals
        )
    }
}

/// A titled table of text cells.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// Title (Markdown: a bold line above; HTML: the caption; CSV: not written).
    pub title: String,
    /// Column headers.
    pub headers: Vec<String>,
    /// Rows of cells; short rows are padded with empty cells.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// Number of columns: the longest of the header and the rows.
    fn n_cols(&self) -> usize {
        self.rows
            .iter()
            .map(Vec::len)
            .chain([self.headers.len()])
            .max()
            .unwrap_or(0)
    }

    /// Cell `c` of `row`, or "" beyond its end.
    fn cell(row: &[String], c: usize) -> &str {
        row.get(c).map(String::as_str).unwrap_or("")
    }

    /// A GitHub-flavoured Markdown table, columns padded to equal width, `|` escaped and
    /// line breaks replaced by spaces; the title, if any, as a bold line before it.
    pub fn to_markdown(&self) -> String {
        let nc = self.n_cols();
        let md = |s: &str| s.replace('|', "\\|").replace(['\n', '\r'], " ");
        let header: Vec<String> = (0..nc).map(|c| md(Self::cell(&self.headers, c))).collect();
        let body: Vec<Vec<String>> = self
            .rows
            .iter()
            .map(|r| (0..nc).map(|c| md(Self::cell(r, c))).collect())
            .collect();
        let width: Vec<usize> = (0..nc)
            .map(|c| {
                body.iter()
                    .map(|r| r[c].chars().count())
                    .chain([header[c].chars().count(), 3])
                    .max()
                    .unwrap_or(3)
            })
            .collect();
        let line = |cells: &[String]| {
            let mut s = String::from("|");
            for (c, v) in cells.iter().enumerate() {
                let pad = width[c] - v.chars().count();
                write!(s, " {v}{} |", " ".repeat(pad)).ok();
            }
            s.push('\n');
            s
        };
        let mut out = String::new();
        if !self.title.is_empty() {
            writeln!(out, "**{}**\n", md(&self.title)).ok();
        }
        if nc == 0 {
            return out;
        }
        out.push_str(&line(&header));
        out.push('|');
        for w in &width {
            write!(out, "{}|", "-".repeat(w + 2)).ok();
        }
        out.push('\n');
        for r in &body {
            out.push_str(&line(r));
        }
        out
    }

    /// RFC 4180 CSV: the header row then the rows, fields quoted when they hold a comma,
    /// a quote or a line break; `\n` line ends. The title is not written.
    pub fn to_csv(&self) -> String {
        let nc = self.n_cols();
        let mut out = String::new();
        for row in std::iter::once(&self.headers).chain(&self.rows) {
            let cells: Vec<String> = (0..nc).map(|c| csv_field(Self::cell(row, c))).collect();
            out.push_str(&cells.join(","));
            out.push('\n');
        }
        out
    }

    /// An HTML `<table>` with the title as its caption; text is escaped.
    pub fn to_html(&self) -> String {
        let nc = self.n_cols();
        let mut out = String::from("<table>\n");
        if !self.title.is_empty() {
            writeln!(out, "<caption>{}</caption>", escape_xml(&self.title)).ok();
        }
        out.push_str("<thead><tr>");
        for c in 0..nc {
            write!(out, "<th>{}</th>", escape_xml(Self::cell(&self.headers, c))).ok();
        }
        out.push_str("</tr></thead>\n<tbody>\n");
        for r in &self.rows {
            out.push_str("<tr>");
            for c in 0..nc {
                let tag = if c == 0 { "th scope=\"row\"" } else { "td" };
                let end = if c == 0 { "th" } else { "td" };
                write!(out, "<{tag}>{}</{end}>", escape_xml(Self::cell(r, c))).ok();
            }
            out.push_str("</tr>\n");
        }
        out.push_str("</tbody>\n</table>\n");
        out
    }
}

/// One field of a CSV line, quoted if needed.
pub(crate) fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The fields of one CSV line as [`csv_field`] writes them: `"` quotes a field, `""`
/// inside quotes is one `"`; fields are not trimmed.
pub fn csv_fields(line: &str) -> Vec<String> {
    let mut cells = Vec::new();
    let mut cell = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                cell.push('"');
            }
            '"' => quoted = !quoted,
            ',' if !quoted => cells.push(std::mem::take(&mut cell)),
            _ => cell.push(c),
        }
    }
    cells.push(cell);
    cells
}

/// A table like Millard & Mombaur's (2019) Table 3: rows = channels, labelled `name (unit)`; columns =
/// runs; cells `mean ± sd (max M)`, `—` where a run lacks the channel or has no defined
/// sample.
pub fn error_table(title: &str, runs: &[String], channels: &[ChannelErrors]) -> Table {
    let mut headers = vec!["error".to_string()];
    headers.extend(runs.iter().cloned());
    let rows = channels
        .iter()
        .map(|ch| {
            let label = if ch.unit.is_empty() {
                ch.name.clone()
            } else {
                format!("{} ({})", ch.name, ch.unit)
            };
            let mut row = vec![label];
            row.extend((0..runs.len()).map(|r| match ch.runs.get(r) {
                Some(Some(s)) => s.cell(ch.decimals),
                _ => "—".to_string(),
            }));
            row
        })
        .collect();
    Table {
        title: title.to_string(),
        headers,
        rows,
    }
}
