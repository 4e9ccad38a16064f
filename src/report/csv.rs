//! Time series with named columns, written as CSV or as an OpenSim storage (`.sto`) file
//! (through [`crate::data::storage_text`]; [`crate::data::parse_storage`] reads it back).
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
//! use footfall::data::parse_storage;
//! use footfall::report::csv::TimeSeries;
//!
//! let mut ts = TimeSeries::new(vec![0.0, 0.01]).unwrap();
//! ts.push("knee_r", vec![-0.1, f64::NAN]).unwrap();
//! assert_eq!(ts.to_csv(), "time,knee_r\n0.000000000e0,-1.000000000e-1\n1.000000000e-2,\n");
//! let sto = parse_storage(&ts.to_sto("tracking"), "tracking.sto".as_ref()).unwrap();
//! assert_eq!(sto.columns, ["time", "knee_r"]);
//! assert!(sto.column("knee_r").unwrap()[1].is_nan());
//! ```

use super::table::csv_field;
use super::ReportError;
use crate::data::storage_text;
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

    /// The `.sto` text of the numeric columns, with `name` on the first header line
    /// (written by [`crate::data::storage_text`], the crate's one `.sto` writer).
    pub fn to_sto(&self, name: &str) -> String {
        let numeric: Vec<(&str, &[f64])> = self
            .columns
            .iter()
            .filter_map(|(n, v)| match v {
                Values::Numbers(x) => Some((n.as_str(), x.as_slice())),
                Values::Text(_) => None,
            })
            .collect();
        storage_text(name, &self.time, &numeric)
    }
}
