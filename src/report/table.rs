//! Error statistics and tables in Markdown, CSV and HTML.
//!
//! [`ErrorStats`] summarises a tracking error ε(t) = |model − measurement| over the
//! samples where it is defined: mean, standard deviation (population, 1/n, as NumPy's
//! default `std` in the CasADi peer's `evaluate.py`) and maximum. [`error_table`] lays
//! such figures out as in seed 001 Table 3: one row per channel, one column per run, each
//! cell `mean ± sd (max M)`, the unit in the row label.
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
use std::fmt::Write;

/// Mean, standard deviation and maximum of absolute errors.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ErrorStats {
    /// Mean of |ε| (NaN when `n == 0`).
    pub mean: f64,
    /// Population standard deviation of |ε| (NaN when `n == 0`).
    pub sd: f64,
    /// Maximum of |ε| (NaN when `n == 0`).
    pub max: f64,
    /// Number of samples used (NaN samples are left out).
    pub n: usize,
}

impl ErrorStats {
    /// Statistics of |e| over the entries of `errors` that are not NaN. Infinite errors
    /// are kept (they make the mean infinite rather than hide a failure).
    pub fn from_errors(errors: &[f64]) -> Self {
        let abs: Vec<f64> = errors
            .iter()
            .filter(|e| !e.is_nan())
            .map(|e| e.abs())
            .collect();
        let n = abs.len();
        if n == 0 {
            return Self {
                mean: f64::NAN,
                sd: f64::NAN,
                max: f64::NAN,
                n: 0,
            };
        }
        let mean = abs.iter().sum::<f64>() / n as f64;
        let var = abs.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / n as f64;
        let max = abs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Self {
            mean,
            sd: var.sqrt(),
            max,
            n,
        }
    }

    /// Statistics of |model − measured| sample by sample (over the shorter length); a
    /// sample where either is NaN is left out.
    pub fn from_pair(model: &[f64], measured: &[f64]) -> Self {
        let e: Vec<f64> = model.iter().zip(measured).map(|(m, d)| m - d).collect();
        Self::from_errors(&e)
    }

    /// The same statistics in other units: mean, sd and max multiplied by `factor`
    /// (e.g. 180/π for radians to degrees, 100 for metres to centimetres).
    pub fn scaled(self, factor: f64) -> Self {
        let k = factor.abs();
        Self {
            mean: self.mean * k,
            sd: self.sd * k,
            max: self.max * k,
            n: self.n,
        }
    }

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

/// The errors of one channel (a joint angle, a GRF component, the CoP) in every run.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelErrors {
    /// Channel name, e.g. "knee angle θ_K − θ_K^EXP".
    pub name: String,
    /// Unit of the statistics, e.g. "°", "cm", "N" (convert with [`ErrorStats::scaled`]).
    pub unit: String,
    /// Digits after the decimal point.
    pub decimals: usize,
    /// One entry per run, in the order of the run names; `None`: not available (`—`).
    pub runs: Vec<Option<ErrorStats>>,
}

/// A table like seed 001 Table 3: rows = channels, labelled `name (unit)`; columns =
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
