//! Reading a run's `summary.json` back: its per-channel error statistics, overall and
//! phase by phase ([`RunSummary`]), with errors that name the file and the field.

use crate::report::run_summary::RunSummaryFile;
use crate::runfolder::RunFileError;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Failure to read a run's `summary.json`: every message names the file, and the field
/// (as a JSON path such as `errors[2].stats.mean`) where one is at fault.
#[derive(Debug, thiserror::Error)]
pub enum DiffError {
    /// The given run path does not exist.
    #[error("{0}: no such run folder or summary file")]
    NoRun(PathBuf),
    /// The run folder has no `summary.json`.
    #[error("{0}: not found (a run folder written by `track` or `predict` has one)")]
    NoSummary(PathBuf),
    /// The summary could not be read, is not JSON, or a field is missing or wrong (the
    /// file and the field's JSON path named).
    #[error(transparent)]
    File(#[from] RunFileError),
}

pub use crate::report::run_summary::{PhaseErrors, SummaryStats};

/// The errors of one channel in one run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelSummary {
    /// Channel name, e.g. "knee angle".
    pub channel: String,
    /// Display unit of the statistics, e.g. "°", "cm", "N".
    pub unit: String,
    /// Statistics over all nodes (both legs pooled).
    pub stats: SummaryStats,
    /// Statistics phase by phase, in the run's phase order (empty when not recorded).
    pub phases: Vec<PhaseErrors>,
}

/// The error figures of one run, read from its `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunSummary {
    /// The summary file read.
    pub path: PathBuf,
    /// Short name of the run: its folder's name.
    pub name: String,
    /// The command that wrote the run (`track`, `predict`), when recorded.
    pub command: Option<String>,
    /// The foot of the run, when recorded.
    pub foot: Option<String>,
    /// The solver's status (`converged`, `line_search_failure`, …), when recorded.
    pub status: Option<String>,
    /// Why the solver stopped, in words, when recorded.
    pub stop_reason: Option<String>,
    /// Channels in the order of the summary's `"errors"`.
    pub channels: Vec<ChannelSummary>,
    /// Whether the summary has `"errors_by_phase"` (older or foreign runs may not).
    pub has_phases: bool,
}

/// Where a run's summary is and the run's short name: `run` is a run folder (its
/// `summary.json` is read) or the summary file itself.
fn locate(run: &Path) -> Result<(PathBuf, String), DiffError> {
    let folder_name = |p: &Path| {
        p.canonicalize()
            .ok()
            .and_then(|c| c.file_name().map(|n| n.to_string_lossy().into_owned()))
            .unwrap_or_else(|| "run".to_string())
    };
    if run.is_dir() {
        let summary = run.join("summary.json");
        if !summary.exists() {
            return Err(DiffError::NoSummary(summary));
        }
        Ok((summary, folder_name(run)))
    } else if run.exists() {
        let parent = run
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        Ok((run.to_path_buf(), folder_name(parent)))
    } else {
        Err(DiffError::NoRun(run.to_path_buf()))
    }
}

impl RunSummary {
    /// Read the summary of the run `run`: a run folder written by `track` or `predict`
    /// (its `summary.json`), or a summary file. The run's name is its folder's name.
    pub fn read(run: &Path) -> Result<Self, DiffError> {
        let (path, name) = locate(run)?;
        let text = std::fs::read_to_string(&path).map_err(|source| RunFileError::Read {
            path: path.clone(),
            source,
        })?;
        Self::parse(&text, &path, name)
    }

    /// Parse summary text; `path` is only used to name the file in errors and in the
    /// result. `"errors"` is required, `"errors_by_phase"` optional (read through the
    /// summary's one serde struct, [`RunSummaryFile`]).
    pub fn parse(text: &str, path: &Path, name: impl Into<String>) -> Result<Self, DiffError> {
        let file = RunSummaryFile::parse(text, path)?;
        Ok(Self::from_file(file, path, name))
    }

    /// The errors of a summary already read from `path`.
    pub fn from_file(file: RunSummaryFile, path: &Path, name: impl Into<String>) -> Self {
        let has_phases = file.errors_by_phase.is_some();
        let by_phase = file.errors_by_phase.unwrap_or_default();
        let channels = file
            .errors
            .into_iter()
            .map(|c| {
                // a channel without any defined sample has no overall entry; its (then
                // empty) phase list has nothing to add
                let phases = by_phase
                    .iter()
                    .find(|p| p.channel == c.channel && p.unit == c.unit && !p.phases.is_empty())
                    .map(|p| p.phases.clone())
                    .unwrap_or_default();
                ChannelSummary {
                    channel: c.channel,
                    unit: c.unit,
                    stats: c.stats,
                    phases,
                }
            })
            .collect();
        // the status as its one word (`converged`, …), as the file spells it
        let status = file.status.as_ref().map(|s| match serde_json::to_value(s) {
            Ok(serde_json::Value::String(w)) => w,
            _ => s.to_string(),
        });
        Self {
            path: path.to_path_buf(),
            name: name.into(),
            command: file.command,
            foot: file.foot,
            status,
            stop_reason: file.stop_reason,
            channels,
            has_phases,
        }
    }

    /// One line describing the run: its name, command and foot, and the summary's path.
    pub fn describe(&self) -> String {
        let mut what: Vec<String> = Vec::new();
        what.extend(self.command.clone());
        what.extend(self.foot.as_ref().map(|f| format!("{f} foot")));
        let what = if what.is_empty() {
            String::new()
        } else {
            format!(" ({})", what.join(", "))
        };
        format!("{}{what}: {}", self.name, self.path.display())
    }
}
