//! Time series with named columns, written as CSV or as an OpenSim storage (`.sto`) file,
//! and a reader for `.sto` files.
//!
//! CSV: header `time,<names>`, numbers as `{:.9e}`, an empty cell where a value is NaN or
//! otherwise not finite (undefined, e.g. the CoP of an unloaded foot), text columns
//! quoted when needed.
//!
//! `.sto` (OpenSim 4 storage, loadable by OpenSim's `Storage` and `TimeSeriesTable`):
//!
//! ```text
//! <name>
//! version=1
//! nRows=<samples>
//! nColumns=<numeric columns + 1>
//! inDegrees=no
//! endheader
//! time<TAB><names…>
//! <rows, tab-separated>
//! ```
//!
//! footfall works in SI units and radians, hence `inDegrees=no`. Text columns (such as a
//! phase name) are left out of `.sto` files, which hold numbers only; a NaN is written as
//! `NaN` (OpenSim parses numbers with `strtod`/`std::stod`, which accept it).
//!
//! # Example
//!
//! ```
//! use footfall::report::csv::{parse_sto, TimeSeries};
//!
//! let mut ts = TimeSeries::new(vec![0.0, 0.01]).unwrap();
//! ts.push("knee_r", vec![-0.1, f64::NAN]).unwrap();
//! assert_eq!(ts.to_csv(), "time,knee_r\n0.000000000e0,-1.000000000e-1\n1.000000000e-2,\n");
//! let sto = parse_sto(&ts.to_sto("tracking")).unwrap();
//! assert_eq!(sto.labels, ["time", "knee_r"]);
//! assert!(sto.rows[1][1].is_nan());
//! ```

use super::table::csv_field;
use super::ReportError;
use std::fmt::Write;

/// The values of one column.
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    /// Numbers; NaN (or ±∞) marks an undefined sample.
    Numbers(Vec<f64>),
    /// Text, such as a phase name (CSV only).
    Text(Vec<String>),
}

/// Samples in time with named columns.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeSeries {
    time: Vec<f64>,
    columns: Vec<(String, Values)>,
}

impl TimeSeries {
    /// A series on the sample times `time` (s), which must be finite and non-decreasing
    /// (equal times are allowed: the samples just before and after an impact).
    pub fn new(time: Vec<f64>) -> Result<Self, ReportError> {
        for (row, &t) in time.iter().enumerate() {
            if !t.is_finite() {
                return Err(ReportError::BadTime {
                    row,
                    value: t,
                    reason: "not finite",
                });
            }
            if row > 0 && t < time[row - 1] {
                return Err(ReportError::BadTime {
                    row,
                    value: t,
                    reason: "earlier than the sample before it",
                });
            }
        }
        Ok(Self {
            time,
            columns: Vec::new(),
        })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// Column names, `time` first.
    pub fn names(&self) -> Vec<&str> {
        std::iter::once("time")
            .chain(self.columns.iter().map(|(n, _)| n.as_str()))
            .collect()
    }

    fn check(&self, name: &str, len: usize) -> Result<(), ReportError> {
        let bad = |reason| {
            Err(ReportError::BadColumnName {
                name: name.to_string(),
                reason,
            })
        };
        if name.is_empty() {
            return bad("empty");
        }
        if name.chars().any(char::is_whitespace) {
            return bad("contains white space (.sto column labels are separated by it)");
        }
        if self.names().contains(&name) {
            return Err(ReportError::DuplicateColumn(name.to_string()));
        }
        if len != self.time.len() {
            return Err(ReportError::LengthMismatch {
                column: name.to_string(),
                expected: self.time.len(),
                found: len,
            });
        }
        Ok(())
    }

    /// Add a numeric column (one value per sample; NaN where undefined).
    pub fn push(
        &mut self,
        name: impl Into<String>,
        values: Vec<f64>,
    ) -> Result<&mut Self, ReportError> {
        let name = name.into();
        self.check(&name, values.len())?;
        self.columns.push((name, Values::Numbers(values)));
        Ok(self)
    }

    /// Add a text column (CSV only; left out of `.sto` files).
    pub fn push_text(
        &mut self,
        name: impl Into<String>,
        values: Vec<String>,
    ) -> Result<&mut Self, ReportError> {
        let name = name.into();
        self.check(&name, values.len())?;
        self.columns.push((name, Values::Text(values)));
        Ok(self)
    }

    /// The CSV text.
    pub fn to_csv(&self) -> String {
        let mut out = self
            .names()
            .iter()
            .map(|n| csv_field(n))
            .collect::<Vec<_>>()
            .join(",");
        out.push('\n');
        for (i, t) in self.time.iter().enumerate() {
            write!(out, "{t:.9e}").ok();
            for (_, v) in &self.columns {
                out.push(',');
                match v {
                    Values::Numbers(x) if x[i].is_finite() => {
                        write!(out, "{:.9e}", x[i]).unwrap_or(())
                    }
                    Values::Numbers(_) => {}
                    Values::Text(s) => out.push_str(&csv_field(&s[i])),
                }
            }
            out.push('\n');
        }
        out
    }

    /// The `.sto` text, with `name` on the first header line (line breaks and tabs in it
    /// become spaces).
    pub fn to_sto(&self, name: &str) -> String {
        let numeric: Vec<(&str, &[f64])> = self
            .columns
            .iter()
            .filter_map(|(n, v)| match v {
                Values::Numbers(x) => Some((n.as_str(), x.as_slice())),
                Values::Text(_) => None,
            })
            .collect();
        let name = name.replace(['\n', '\r', '\t'], " ");
        let mut out = String::new();
        writeln!(
            out,
            "{name}\nversion=1\nnRows={}\nnColumns={}\ninDegrees=no\nendheader",
            self.time.len(),
            numeric.len() + 1
        )
        .ok();
        out.push_str("time");
        for (n, _) in &numeric {
            write!(out, "\t{n}").ok();
        }
        out.push('\n');
        for (i, t) in self.time.iter().enumerate() {
            write!(out, "{t:.9e}").ok();
            for (_, x) in &numeric {
                if x[i].is_nan() {
                    out.push_str("\tNaN");
                } else {
                    write!(out, "\t{:.9e}", x[i]).ok();
                }
            }
            out.push('\n');
        }
        out
    }
}

/// A parsed `.sto` file.
#[derive(Debug, Clone, PartialEq)]
pub struct StoTable {
    /// The name on the first header line.
    pub name: String,
    /// `inDegrees` (false when absent).
    pub in_degrees: bool,
    /// Header lines `key=value`, in order (including `version`, `nRows`, …).
    pub header: Vec<(String, String)>,
    /// Column labels, usually `time` first.
    pub labels: Vec<String>,
    /// Rows of values, one per sample, as many as labels.
    pub rows: Vec<Vec<f64>>,
}

impl StoTable {
    /// The values of the column labelled `label`.
    pub fn column(&self, label: &str) -> Option<Vec<f64>> {
        let c = self.labels.iter().position(|l| l == label)?;
        Some(self.rows.iter().map(|r| r[c]).collect())
    }
}

/// Parse an OpenSim `.sto` (or `.mot`) file: the header up to `endheader`, the column
/// labels, then rows of numbers separated by tabs or spaces. `nRows` and `nColumns`, when
/// present, must match the data.
pub fn parse_sto(text: &str) -> Result<StoTable, ReportError> {
    let err = |line: usize, message: String| ReportError::Sto { line, message };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
    let mut name = String::new();
    let mut header = Vec::new();
    let mut ended = false;
    for (no, line) in lines.by_ref() {
        let t = line.trim();
        if t == "endheader" {
            ended = true;
            break;
        }
        match t.split_once('=') {
            Some((k, v)) => header.push((k.trim().to_string(), v.trim().to_string())),
            None if no == 1 => name = t.to_string(),
            None if t.is_empty() => {}
            None => header.push((t.to_string(), String::new())),
        }
    }
    if !ended {
        return Err(err(
            text.lines().count().max(1),
            "no `endheader` line".into(),
        ));
    }
    let get = |k: &str| {
        header
            .iter()
            .find(|(key, _)| key == k)
            .map(|(_, v)| v.as_str())
    };
    let in_degrees = match get("inDegrees") {
        None | Some("no") => false,
        Some("yes") => true,
        Some(v) => return Err(err(0, format!("inDegrees={v}: expected yes or no"))),
    };
    let (label_no, label_line) = lines
        .by_ref()
        .find(|(_, l)| !l.trim().is_empty())
        .ok_or_else(|| err(0, "no column labels".into()))?;
    let split = |l: &str| -> Vec<String> {
        if l.contains('\t') {
            l.split('\t').map(|s| s.trim().to_string()).collect()
        } else {
            l.split_whitespace().map(str::to_string).collect()
        }
    };
    let labels = split(label_line);
    let mut rows = Vec::new();
    for (no, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let cells = split(line.trim_end());
        if cells.len() != labels.len() {
            return Err(err(
                no,
                format!(
                    "{} values, expected {} (one per column label)",
                    cells.len(),
                    labels.len()
                ),
            ));
        }
        let row = cells
            .iter()
            .map(|c| {
                c.parse::<f64>()
                    .map_err(|_| err(no, format!("{c:?} is not a number")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        rows.push(row);
    }
    let count = |k: &str, found: usize| -> Result<(), ReportError> {
        match get(k) {
            None => Ok(()),
            Some(v) => match v.parse::<usize>() {
                Ok(n) if n == found => Ok(()),
                _ => Err(err(label_no, format!("{k}={v} but the data has {found}"))),
            },
        }
    };
    count("nRows", rows.len())?;
    count("nColumns", labels.len())?;
    Ok(StoTable {
        name,
        in_degrees,
        header,
        labels,
        rows,
    })
}
