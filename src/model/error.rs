//! Errors of model construction and evaluation.

use std::path::PathBuf;

/// Failure to read, validate or assemble a model, foot or phase file.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// A foot that is neither a bundled foot nor an existing file.
    #[error("foot {path}: no such file; a foot is `ellipse`, `double-circle`, a bundled foot file ({bundled}) or the path of a foot file (JSON)")]
    NoFoot {
        /// The foot as given.
        path: PathBuf,
        /// The bundled foot files, comma-separated.
        bundled: String,
    },
    /// The file is not valid JSON or does not match the schema.
    #[error("{path}: {message} (line {line}, column {column})")]
    Json {
        /// File.
        path: PathBuf,
        /// serde's description, naming the field where it can.
        message: String,
        /// Line of the problem.
        line: usize,
        /// Column of the problem.
        column: usize,
    },
    /// A value is physically or logically invalid.
    #[error("{path}: field '{field}': {reason}")]
    Invalid {
        /// File (or `<memory>`).
        path: PathBuf,
        /// Dotted path of the field.
        field: String,
        /// What is wrong and what would be valid.
        reason: String,
    },
}

impl ModelError {
    /// The error of a foot none of whose primitives reaches below the ankle (`lowest`: its
    /// lowest point above the ankle in the neutral pose, m).
    pub(crate) fn foot_above_ankle(path: &std::path::Path, lowest: f64) -> Self {
        ModelError::invalid(
            path,
            "primitives",
            format!(
                "no primitive reaches below the ankle (lowest point {lowest:.4} m above it in the neutral pose), \
                 so the foot cannot touch the ground; primitive positions are in the ankle frame, y up"
            ),
        )
    }

    pub(crate) fn invalid(
        path: &std::path::Path,
        field: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        ModelError::Invalid {
            path: path.to_path_buf(),
            field: field.into(),
            reason: reason.into(),
        }
    }
}

/// Failure of one dynamics evaluation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// The mass matrix is not positive definite (non-physical inertias or state).
    #[error("mass matrix not positive definite at pivot {pivot}")]
    MassMatrix {
        /// Pivot index.
        pivot: usize,
    },
    /// The active constraint rows are linearly dependent: the body is over-constrained.
    #[error(
        "constraint set '{set}' over-constrains the body (row {row} is dependent on the others)"
    )]
    OverConstrained {
        /// Constraint set name.
        set: String,
        /// Dependent row.
        row: usize,
    },
    /// A state or input value is not finite.
    #[error("non-finite {what}")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
}
