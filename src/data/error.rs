//! Errors of reading, validating and processing measured gait data.

use std::path::{Path, PathBuf};

/// Why measured data were refused.
///
/// Every variant names the file (`<memory>` for data built in memory); variants about one
/// value also name the row (1-based line number in the file, header lines included) and
/// the column. Nothing in [`crate::data`] panics on input: bad input becomes one of these.
#[derive(Debug, thiserror::Error)]
pub enum DataError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// A JSON (meta) file is not valid JSON or a field has the wrong type.
    #[error("{path}: {message} (line {line}, column {column})")]
    Json {
        /// File.
        path: PathBuf,
        /// serde's description.
        message: String,
        /// Line of the problem.
        line: usize,
        /// Column (character) of the problem.
        column: usize,
    },
    /// The layout of the file is wrong: no header, no `endheader`, a row count that
    /// disagrees with the header, too few data rows.
    #[error("{path}: line {row}: {reason}")]
    Format {
        /// File.
        path: PathBuf,
        /// Line (1-based).
        row: usize,
        /// What is wrong.
        reason: String,
    },
    /// A required column is absent.
    #[error("{path}: line {row}: missing column '{column}' ({reason})")]
    MissingColumn {
        /// File.
        path: PathBuf,
        /// Line of the column labels (1-based).
        row: usize,
        /// Name of the missing column.
        column: String,
        /// Context: what the column is needed for, what was found.
        reason: String,
    },
    /// Two columns have the same name.
    #[error("{path}: line {row}: column '{column}' appears more than once")]
    DuplicateColumn {
        /// File.
        path: PathBuf,
        /// Line of the column labels (1-based).
        row: usize,
        /// The repeated name.
        column: String,
    },
    /// A data row has the wrong number of fields.
    #[error("{path}: line {row}: {found} fields, expected {expected} (one per column label)")]
    RowLength {
        /// File.
        path: PathBuf,
        /// Line (1-based).
        row: usize,
        /// Number of column labels.
        expected: usize,
        /// Number of fields in the row.
        found: usize,
    },
    /// A field is not a number.
    #[error("{path}: line {row}, column '{column}': cannot parse '{text}' as a number ({reason})")]
    Parse {
        /// File.
        path: PathBuf,
        /// Line (1-based).
        row: usize,
        /// Column name.
        column: String,
        /// The offending text.
        text: String,
        /// The parser's reason.
        reason: String,
    },
    /// A value is NaN or infinite where that is not allowed (in the sagittal CSV NaN
    /// means "not measured" in `grf_*` and `cop_x_*`, is a gap in an extra column, and
    /// marks a force-only row when every coordinate of the row is NaN).
    #[error("{path}: line {row}, column '{column}': {reason}")]
    NotFinite {
        /// File.
        path: PathBuf,
        /// Line (1-based).
        row: usize,
        /// Column name.
        column: String,
        /// What the value is and why it is not allowed.
        reason: String,
    },
    /// A value is beyond what the column can physically hold (e.g. a ground force above
    /// [`crate::limits::MAX_FORCE`]).
    #[error("{path}: line {row}, column '{column}': {} {unit} is beyond the sensible limit; expected a magnitude of at most {} {unit}", crate::limits::show(*value), crate::limits::show(*limit))]
    OutOfRange {
        /// File.
        path: PathBuf,
        /// Line (1-based).
        row: usize,
        /// Column name.
        column: String,
        /// The value.
        value: f64,
        /// The largest magnitude allowed.
        limit: f64,
        /// Unit of both.
        unit: &'static str,
    },
    /// Time does not increase strictly from one row to the next.
    #[error("{path}: line {row}: time {time} s does not increase (previous row: {previous} s)")]
    NonMonotonicTime {
        /// File.
        path: PathBuf,
        /// Line (1-based) of the row whose time is not larger than the previous one.
        row: usize,
        /// Its time (s).
        time: f64,
        /// Time of the previous row (s).
        previous: f64,
    },
    /// A unit declaration does not parse (e.g. `inDegrees=maybe`, `"angles": "grad"`).
    #[error("{path}: {}'{column}' = '{text}': {reason}", row.map(|r| format!("line {r}: ")).unwrap_or_default())]
    Units {
        /// File.
        path: PathBuf,
        /// Line (1-based), where known.
        row: Option<usize>,
        /// The header key or meta field declaring the unit.
        column: String,
        /// The declared unit.
        text: String,
        /// What would be valid.
        reason: String,
    },
    /// No foot's normal force ever exceeds the contact threshold: the trial has no stance.
    #[error("{path}: no stance phase: {}", no_stance(*threshold, *peak))]
    NoStance {
        /// File.
        path: PathBuf,
        /// Contact threshold used (N).
        threshold: f64,
        /// Largest normal force of either foot (N; NaN if none was measured).
        peak: f64,
    },
    /// The data do not hold one complete gait cycle.
    #[error("{path}: shorter than one gait cycle: {reason}")]
    TooShort {
        /// File.
        path: PathBuf,
        /// What was found (heel strikes per foot, time span).
        reason: String,
    },
    /// A C3D file's parameters cannot be converted (no force platform, an unsupported
    /// plate type, unknown units, channels out of range) or the file does not parse as C3D.
    #[error("{path}: C3D parameter {parameter}: {reason}")]
    C3d {
        /// File.
        path: PathBuf,
        /// `GROUP:NAME` of the parameter (e.g. `FORCE_PLATFORM:TYPE`), or `file` when the
        /// file as a whole does not parse.
        parameter: String,
        /// What is wrong and what would be valid.
        reason: String,
    },
    /// An argument or an in-memory value is invalid.
    #[error("{path}: {field}: {reason}")]
    Invalid {
        /// File the data came from (or `<memory>`).
        path: PathBuf,
        /// Argument, channel or field.
        field: String,
        /// What is wrong and what would be valid.
        reason: String,
    },
}

impl DataError {
    /// A [`DataError::RowLength`] when data row `row` of `path` has `found` fields
    /// instead of one per column label (`expected`).
    pub(crate) fn check_row_length(
        path: &Path,
        row: usize,
        expected: usize,
        found: usize,
    ) -> Result<(), DataError> {
        if found == expected {
            return Ok(());
        }
        Err(DataError::RowLength {
            path: path.to_path_buf(),
            row,
            expected,
            found,
        })
    }

    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            DataError::Io { path, .. }
            | DataError::Json { path, .. }
            | DataError::Format { path, .. }
            | DataError::MissingColumn { path, .. }
            | DataError::DuplicateColumn { path, .. }
            | DataError::RowLength { path, .. }
            | DataError::Parse { path, .. }
            | DataError::NotFinite { path, .. }
            | DataError::OutOfRange { path, .. }
            | DataError::NonMonotonicTime { path, .. }
            | DataError::Units { path, .. }
            | DataError::NoStance { path, .. }
            | DataError::TooShort { path, .. }
            | DataError::C3d { path, .. }
            | DataError::Invalid { path, .. } => path,
        }
    }

    /// The 1-based line the error is about, where there is one.
    pub fn row(&self) -> Option<usize> {
        match self {
            DataError::Json { line, .. } => Some(*line),
            DataError::Format { row, .. }
            | DataError::MissingColumn { row, .. }
            | DataError::DuplicateColumn { row, .. }
            | DataError::RowLength { row, .. }
            | DataError::Parse { row, .. }
            | DataError::NotFinite { row, .. }
            | DataError::OutOfRange { row, .. }
            | DataError::NonMonotonicTime { row, .. } => Some(*row),
            DataError::Units { row, .. } => *row,
            _ => None,
        }
    }

    /// The column (or header key, meta field, argument) the error is about, where there is one.
    pub fn column(&self) -> Option<&str> {
        match self {
            DataError::MissingColumn { column, .. }
            | DataError::DuplicateColumn { column, .. }
            | DataError::Parse { column, .. }
            | DataError::NotFinite { column, .. }
            | DataError::OutOfRange { column, .. }
            | DataError::Units { column, .. } => Some(column),
            DataError::Invalid { field, .. } => Some(field),
            DataError::C3d { parameter, .. } => Some(parameter),
            _ => None,
        }
    }

    pub(crate) fn invalid(
        path: &Path,
        field: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        DataError::Invalid {
            path: path.to_path_buf(),
            field: field.into(),
            reason: reason.into(),
        }
    }

    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        DataError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// A text that is not a signed lab axis ([`LabAxis`](crate::data::c3d::LabAxis)'s
/// `from_str`).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{text}' is not a lab axis; valid: +x, -x, +y, -y, +z, -z")]
pub struct LabAxisError {
    /// The text as given.
    pub text: String,
}

/// The path used for data built in memory.
pub(crate) fn memory_path() -> PathBuf {
    PathBuf::from("<memory>")
}

/// Why a trial has no stance: no normal force measured at all, or none above the
/// threshold.
fn no_stance(threshold: f64, peak: f64) -> String {
    if peak.is_nan() {
        return "no normal force was measured (every grf_y value is NaN or missing); a trial needs the vertical ground force of at least one foot".into();
    }
    format!(
        "no normal force exceeds the threshold {} N (peak normal force {} N)",
        crate::limits::show(threshold),
        crate::limits::show(peak)
    )
}
