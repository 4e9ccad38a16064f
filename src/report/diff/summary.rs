//! Reading a run's `summary.json` back: its per-channel error statistics, overall and
//! phase by phase ([`RunSummary`]), with errors that name the file and the field.

use serde::Serialize;
use serde_json::Value;
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
    /// The summary could not be read.
    #[error("{path}: {source}")]
    Read {
        /// The summary file.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// The summary is not JSON.
    #[error("{path}: not valid JSON: {source}")]
    Json {
        /// The summary file.
        path: PathBuf,
        /// Cause (with line and column).
        source: serde_json::Error,
    },
    /// A field is missing or has the wrong type or value.
    #[error("{path}: field `{field}`: {message}")]
    Field {
        /// The summary file.
        path: PathBuf,
        /// JSON path of the field, e.g. `errors[2].stats.mean`.
        field: String,
        /// What is wrong.
        message: String,
    },
}

/// Error statistics of one channel as a run summary records them: mean, standard
/// deviation and maximum of |model − measurement|, in the channel's display unit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SummaryStats {
    /// Mean of |error| (finite, ≥ 0).
    pub mean: f64,
    /// Population standard deviation of |error|, when recorded.
    pub sd: Option<f64>,
    /// Largest |error|, when recorded.
    pub max: Option<f64>,
}

/// The errors of one channel within one phase of the gait cycle.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PhaseErrors {
    /// Phase name as in the phase file, e.g. "1e".
    pub phase: String,
    /// Statistics over the nodes of that phase.
    pub stats: SummaryStats,
}

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

/// A JSON value's kind in words, for error messages.
fn kind(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => format!("the boolean {b}"),
        Value::Number(n) => format!("the number {n}"),
        Value::String(s) => format!("the string {s:?}"),
        Value::Array(_) => "an array".into(),
        Value::Object(_) => "an object".into(),
    }
}

/// Reads fields of one summary file, naming the file and field in every error.
struct Reader<'a> {
    path: &'a Path,
}

impl Reader<'_> {
    fn err(&self, field: &str, message: impl Into<String>) -> DiffError {
        DiffError::Field {
            path: self.path.to_path_buf(),
            field: field.to_string(),
            message: message.into(),
        }
    }

    /// Field `key` of the object `v` (at JSON path `at`), which must be present.
    fn get<'v>(&self, v: &'v Value, at: &str, key: &str) -> Result<&'v Value, DiffError> {
        let field = if at.is_empty() {
            key.to_string()
        } else {
            format!("{at}.{key}")
        };
        v.get(key).ok_or_else(|| self.err(&field, "missing"))
    }

    fn array<'v>(&self, v: &'v Value, field: &str) -> Result<&'v Vec<Value>, DiffError> {
        v.as_array()
            .ok_or_else(|| self.err(field, format!("expected an array, found {}", kind(v))))
    }

    fn string(&self, v: &Value, at: &str, key: &str) -> Result<String, DiffError> {
        let s = self.get(v, at, key)?;
        s.as_str().map(str::to_string).ok_or_else(|| {
            self.err(
                &format!("{at}.{key}"),
                format!("expected a string, found {}", kind(s)),
            )
        })
    }

    /// The non-empty channel or phase name `key` of `v`.
    fn name(&self, v: &Value, at: &str, key: &str) -> Result<String, DiffError> {
        let s = self.string(v, at, key)?;
        if s.trim().is_empty() {
            return Err(self.err(&format!("{at}.{key}"), "empty name"));
        }
        Ok(s)
    }

    /// An optional number: absent or null gives `None`.
    fn optional_number(&self, v: &Value, at: &str, key: &str) -> Result<Option<f64>, DiffError> {
        match v.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(x) => x.as_f64().map(Some).ok_or_else(|| {
                self.err(
                    &format!("{at}.{key}"),
                    format!("expected a number, found {}", kind(x)),
                )
            }),
        }
    }

    fn stats(&self, v: &Value, at: &str) -> Result<SummaryStats, DiffError> {
        let at = format!("{at}.stats");
        let s = v.get("stats").ok_or_else(|| self.err(&at, "missing"))?;
        if !s.is_object() {
            return Err(self.err(
                &at,
                format!(
                    "expected an object with mean, sd and max, found {}",
                    kind(s)
                ),
            ));
        }
        let m = self.get(s, &at, "mean")?;
        let mean = m.as_f64().ok_or_else(|| {
            self.err(
                &format!("{at}.mean"),
                format!("expected a number, found {}", kind(m)),
            )
        })?;
        if !(mean.is_finite() && mean >= 0.0) {
            return Err(self.err(
                &format!("{at}.mean"),
                format!("{mean} is not a mean of absolute errors (need a finite number ≥ 0)"),
            ));
        }
        Ok(SummaryStats {
            mean,
            sd: self.optional_number(s, &at, "sd")?,
            max: self.optional_number(s, &at, "max")?,
        })
    }
}

impl RunSummary {
    /// Read the summary of the run `run`: a run folder written by `track` or `predict`
    /// (its `summary.json`), or a summary file. The run's name is its folder's name.
    pub fn read(run: &Path) -> Result<Self, DiffError> {
        let (path, name) = locate(run)?;
        let text = std::fs::read_to_string(&path).map_err(|source| DiffError::Read {
            path: path.clone(),
            source,
        })?;
        Self::parse(&text, &path, name)
    }

    /// Parse summary text; `path` is only used to name the file in errors and in the
    /// result. `"errors"` is required, `"errors_by_phase"` optional.
    pub fn parse(text: &str, path: &Path, name: impl Into<String>) -> Result<Self, DiffError> {
        let root: Value = serde_json::from_str(text).map_err(|source| DiffError::Json {
            path: path.to_path_buf(),
            source,
        })?;
        let r = Reader { path };
        if !root.is_object() {
            return Err(r.err(
                "(top level)",
                format!("expected a JSON object, found {}", kind(&root)),
            ));
        }
        let errors = root.get("errors").ok_or_else(|| r.err("errors", "missing (a run folder written by `track` or `predict` records its per-channel errors here)"))?;
        let mut channels: Vec<ChannelSummary> = Vec::new();
        for (i, e) in r.array(errors, "errors")?.iter().enumerate() {
            let at = format!("errors[{i}]");
            if !e.is_object() {
                return Err(r.err(
                    &at,
                    format!(
                        "expected an object with channel, unit and stats, found {}",
                        kind(e)
                    ),
                ));
            }
            let channel = r.name(e, &at, "channel")?;
            let unit = r.string(e, &at, "unit")?;
            if let Some(j) = channels
                .iter()
                .position(|c| c.channel == channel && c.unit == unit)
            {
                return Err(r.err(
                    &format!("{at}.channel"),
                    format!("channel {channel:?} ({unit}) appears twice (also errors[{j}])"),
                ));
            }
            channels.push(ChannelSummary {
                channel,
                unit,
                stats: r.stats(e, &at)?,
                phases: Vec::new(),
            });
        }
        let has_phases = match root.get("errors_by_phase") {
            None | Some(Value::Null) => false,
            Some(by_phase) => {
                for (i, e) in r.array(by_phase, "errors_by_phase")?.iter().enumerate() {
                    let at = format!("errors_by_phase[{i}]");
                    if !e.is_object() {
                        return Err(r.err(
                            &at,
                            format!(
                                "expected an object with channel, unit and phases, found {}",
                                kind(e)
                            ),
                        ));
                    }
                    let channel = r.name(e, &at, "channel")?;
                    let unit = r.string(e, &at, "unit")?;
                    let list = r.array(r.get(e, &at, "phases")?, &format!("{at}.phases"))?;
                    let mut phases: Vec<PhaseErrors> = Vec::new();
                    for (k, p) in list.iter().enumerate() {
                        let pat = format!("{at}.phases[{k}]");
                        if !p.is_object() {
                            return Err(r.err(
                                &pat,
                                format!(
                                    "expected an object with phase and stats, found {}",
                                    kind(p)
                                ),
                            ));
                        }
                        let phase = r.name(p, &pat, "phase")?;
                        if phases.iter().any(|q| q.phase == phase) {
                            return Err(r.err(
                                &format!("{pat}.phase"),
                                format!("phase {phase:?} appears twice"),
                            ));
                        }
                        phases.push(PhaseErrors {
                            phase,
                            stats: r.stats(p, &pat)?,
                        });
                    }
                    // a channel without any defined sample has no overall entry; its
                    // (then empty) phase list has nothing to add
                    if let Some(c) = channels
                        .iter_mut()
                        .find(|c| c.channel == channel && c.unit == unit)
                    {
                        if !c.phases.is_empty() {
                            return Err(r.err(
                                &format!("{at}.channel"),
                                format!("channel {channel:?} ({unit}) appears twice"),
                            ));
                        }
                        c.phases = phases;
                    }
                }
                true
            }
        };
        let text_field = |k: &str| root.get(k).and_then(Value::as_str).map(str::to_string);
        Ok(Self {
            path: path.to_path_buf(),
            name: name.into(),
            command: text_field("command"),
            foot: text_field("foot"),
            status: text_field("status"),
            stop_reason: text_field("stop_reason"),
            channels,
            has_phases,
        })
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
