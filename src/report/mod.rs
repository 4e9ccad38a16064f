//! Run-folder artefacts that a gait researcher reads: SVG line plots ([`plot`]), error
//! statistics and tables in Markdown, CSV and HTML ([`table`]), one self-contained
//! `report.html` ([`html`]), time series as CSV and OpenSim `.sto` ([`csv`]), and the
//! before/after comparison of two runs' tracking errors ([`diff`]).
//!
//! This layer knows nothing about how a solution was found: callers hand it numbers,
//! names and strings. Every output is deterministic (the same input gives the same bytes)
//! and self-contained (no external resources; the one script plays the body animation).
//!
//! The SVG is written by hand rather than through a plotting crate: the plots need only
//! lines, bars, markers, shaded spans and text, and writing them directly keeps full control of
//! the layout (label collision avoidance, NaN gaps, byte-identical output), adds no
//! dependency and no font-rendering stack (a crate such as `plotters` must measure text
//! with a font library to place its labels), and costs about 600 lines.
//!
//! # Example
//!
//! ```
//! use footfall::report::html::{Report, Section, Summary, Tone};
//! use footfall::report::plot::{LinePlot, LineStyle, Series, Span};
//!
//! let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.02).collect();
//! let knee: Vec<f64> = t.iter().map(|t| -30.0 * (6.0 * t).sin()).collect();
//! let mut plot = LinePlot::new("knee angle", "time (s)", "angle (°)");
//! plot.series.push(Series::new("model", t.clone(), knee, LineStyle::Solid));
//! plot.shaded.push(Span::new(0.0, 0.6, "stance"));
//! let report = Report {
//!     title: "tracking".into(),
//!     summary: Summary::new("converged", Tone::Good, "KKT tolerance reached"),
//!     sections: vec![Section { heading: "Kinematics".into(), svgs: vec![plot.to_svg()], ..Section::default() }],
//! };
//! let html = report.to_html();
//! assert!(html.contains("<svg") && html.contains("knee angle"));
//! ```

pub mod body;
pub mod csv;
pub mod diff;
pub mod gait_figures;
pub mod html;
pub mod plot;
pub mod run_summary;
pub mod runs;
pub mod table;
pub mod tracking;

use std::path::PathBuf;

/// Failure to build or write a report artefact.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A column's length differs from the time column's.
    #[error("column {column:?} has {found} values, expected {expected} (one per time sample)")]
    LengthMismatch {
        /// Column name.
        column: String,
        /// Number of time samples.
        expected: usize,
        /// Number of values given.
        found: usize,
    },
    /// A column name that the output formats cannot carry.
    #[error("column name {name:?} is not usable: {reason}")]
    BadColumnName {
        /// The name.
        name: String,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// Two columns with the same name.
    #[error("column {0:?} appears twice")]
    DuplicateColumn(String),
    /// A time value that is not finite or goes backwards.
    #[error("time sample {row} ({value}) is {reason}")]
    BadTime {
        /// Row index (0-based).
        row: usize,
        /// The value.
        value: f64,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// An I/O error on a path.
    #[error("{path}: {source}")]
    Io {
        /// Path.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
}

/// Escape text for XML and HTML content and attribute values.
pub(crate) fn escape_xml(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}
