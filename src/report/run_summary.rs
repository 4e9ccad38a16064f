//! A gait run's `summary.json` (`track`, `predict`) as one serde struct,
//! [`RunSummaryFile`]: the run-folder writer fills and writes it, and `diff`, `report`
//! and the side-by-side report read it back through it. Every field but `errors` may be
//! absent on reading (older or foreign summaries); errors name the file and the field
//! (`errors[2].stats.mean`). Command-specific fields (`setup`, `prediction`,
//! `cost_breakdown`, …) are written beside these and ignored on reading.

use crate::problems::evaluation::FineGridFigures;
use crate::problems::transient::ForceTransient;
use crate::problems::validity::Validity;
use crate::runfolder::{decode_json, json_kind, RunFileError};
use crate::sqp::{IterationRecord, SqpStatus, SqpTimings, Violation};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Paths of a run's inputs relative to its run folder (copies under `inputs/`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunInputs {
    /// Model file.
    pub model: PathBuf,
    /// Foot file.
    pub foot: PathBuf,
    /// Phase file.
    pub phases: PathBuf,
    /// Sagittal CSV (its meta file, if any, beside it), or OpenSim kinematics.
    pub data: PathBuf,
    /// The forces file of a trial given as kinematics and forces (OpenSim external loads).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub forces: Option<PathBuf>,
}

/// Error statistics of one channel as a run summary records them: mean, standard
/// deviation and maximum of |model − measurement|, in the channel's display unit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SummaryStats {
    /// Mean of |error| (finite, ≥ 0).
    pub mean: f64,
    /// Population standard deviation of |error|, when recorded.
    #[serde(default)]
    pub sd: Option<f64>,
    /// Largest |error|, when recorded.
    #[serde(default)]
    pub max: Option<f64>,
}

/// The errors of one channel over all nodes (`errors[i]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelStats {
    /// Channel name, e.g. "knee angle".
    pub channel: String,
    /// Display unit of the statistics, e.g. "°", "cm", "N".
    pub unit: String,
    /// Statistics over all nodes (both legs pooled).
    pub stats: SummaryStats,
}

/// The errors of one channel within one phase of the gait cycle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhaseErrors {
    /// Phase name as in the phase file, e.g. "1e".
    pub phase: String,
    /// Statistics over the nodes of that phase.
    pub stats: SummaryStats,
}

/// The errors of one channel phase by phase (`errors_by_phase[i]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelPhaseErrors {
    /// Channel name.
    pub channel: String,
    /// Display unit.
    pub unit: String,
    /// The phases with a defined sample, in the run's phase order.
    pub phases: Vec<PhaseErrors>,
}

/// The gait cycle the run's figures are drawn against.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GaitCycleRecord {
    /// Duration of a gait cycle (s).
    pub period_s: f64,
    /// Heel strike of the right and the left leg (s).
    pub heel_strike_s: [f64; 2],
}

/// One continuous phase of the solution in time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhaseSpan {
    /// Phase name.
    pub phase: String,
    /// Start (s).
    pub from_s: f64,
    /// End (s).
    pub to_s: f64,
}

/// A gait run's `summary.json`; the field names are the file's.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct RunSummaryFile {
    /// `track` or `predict`.
    pub command: Option<String>,
    /// Model name.
    pub model: Option<String>,
    /// Foot name.
    pub foot: Option<String>,
    /// Phase file (relative to the run folder when it holds its inputs).
    pub phases: Option<PathBuf>,
    /// Trial (relative to the run folder when it holds its inputs).
    pub data: Option<PathBuf>,
    /// The inputs copied into the run folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inputs: Option<RunInputs>,
    /// Time window of the solution (s).
    pub window_s: Option<[f64; 2]>,
    /// The gait cycle of the figures' x axis.
    pub gait_cycle: Option<GaitCycleRecord>,
    /// The continuous phases in time.
    #[serde(default)]
    pub phase_spans: Vec<PhaseSpan>,
    /// The solver's status.
    pub status: Option<SqpStatus>,
    /// `converged`, `not converged`, `converged, physically invalid`, ….
    pub verdict: Option<String>,
    /// Whether the 1 ms re-integration breaks no contact condition (None: it failed).
    pub physically_valid: Option<bool>,
    /// The validity check on the 1 ms grid.
    pub validity: Option<Validity>,
    /// Number of check points between the nodes.
    pub check_points: Option<usize>,
    /// Why the solver stopped, in words.
    pub stop_reason: Option<String>,
    /// SQP iterations.
    pub iterations: Option<usize>,
    /// Wall time of the solve (s).
    pub seconds: Option<f64>,
    /// Objective at the solution.
    pub objective: Option<f64>,
    /// KKT residual at the solution.
    pub kkt: Option<f64>,
    /// Largest constraint violation at the solution.
    pub infeasibility: Option<f64>,
    /// Where the solver's time went.
    #[serde(default)]
    pub timings: SqpTimings,
    /// Errors per channel over all nodes (the one field a summary must have).
    pub errors: Vec<ChannelStats>,
    /// Errors per channel phase by phase (None: not recorded).
    pub errors_by_phase: Option<Vec<ChannelPhaseErrors>>,
    /// Figures of the 1 ms re-integration (None: it failed).
    pub fine_grid: Option<FineGridFigures>,
    /// Why the 1 ms re-integration failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fine_grid_error: Option<String>,
    /// Ground-force excursions above the measurement larger than this are reported (N).
    pub transient_threshold_n: Option<f64>,
    /// Ground-force transients, strongest first.
    #[serde(default)]
    pub transients: Vec<ForceTransient>,
    /// The most violated constraints at the solution.
    #[serde(default)]
    pub most_violated: Vec<Violation>,
    /// The solver's iterations.
    #[serde(default)]
    pub history: Vec<IterationRecord>,
}

impl RunSummaryFile {
    /// The summary as JSON with the command's own fields `extra` beside (an extra field
    /// of the same name replaces the summary's).
    pub fn to_json(
        &self,
        extra: serde_json::Map<String, serde_json::Value>,
    ) -> serde_json::Result<serde_json::Value> {
        let mut v = serde_json::to_value(self)?;
        if let Some(obj) = v.as_object_mut() {
            obj.extend(extra);
        }
        Ok(v)
    }

    /// Read a summary file (see [`parse`](Self::parse)).
    pub fn read(path: &Path) -> Result<Self, RunFileError> {
        let text = std::fs::read_to_string(path).map_err(|source| RunFileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parse summary text read from `path` (named in errors): a JSON object whose
    /// `errors` are present, channel and phase names non-empty and unique, and every
    /// mean a finite number ≥ 0.
    pub fn parse(text: &str, path: &Path) -> Result<Self, RunFileError> {
        let root: serde_json::Value =
            serde_json::from_str(text).map_err(|source| RunFileError::Json {
                path: path.to_path_buf(),
                source,
            })?;
        if !root.is_object() {
            return Err(RunFileError::field(
                path,
                "(top level)",
                format!("expected a JSON object, found {}", json_kind(&root)),
            ));
        }
        let s: Self = decode_json(&root, path).map_err(|e| match e {
            RunFileError::Field { field, message, .. } if field == "errors" && message == "missing" => {
                RunFileError::field(path, field, "missing (a run folder written by `track` or `predict` records its per-channel errors here)")
            }
            other => other,
        })?;
        s.check(path)?;
        Ok(s)
    }

    /// The checks serde cannot make.
    fn check(&self, path: &Path) -> Result<(), RunFileError> {
        let bad = |field: String, message: String| RunFileError::field(path, field, message);
        let name = |at: String, s: &str| {
            if s.trim().is_empty() {
                Err(bad(at, "empty name".into()))
            } else {
                Ok(())
            }
        };
        let mean = |at: String, st: &SummaryStats| {
            if st.mean.is_finite() && st.mean >= 0.0 {
                Ok(())
            } else {
                Err(bad(
                    at,
                    format!(
                        "{} is not a mean of absolute errors (need a finite number ≥ 0)",
                        st.mean
                    ),
                ))
            }
        };
        for (i, c) in self.errors.iter().enumerate() {
            name(format!("errors[{i}].channel"), &c.channel)?;
            if let Some(j) = self.errors[..i]
                .iter()
                .position(|o| o.channel == c.channel && o.unit == c.unit)
            {
                return Err(bad(
                    format!("errors[{i}].channel"),
                    format!(
                        "channel {:?} ({}) appears twice (also errors[{j}])",
                        c.channel, c.unit
                    ),
                ));
            }
            mean(format!("errors[{i}].stats.mean"), &c.stats)?;
        }
        for (i, c) in self.errors_by_phase.iter().flatten().enumerate() {
            let at = format!("errors_by_phase[{i}]");
            name(format!("{at}.channel"), &c.channel)?;
            if self
                .errors_by_phase
                .iter()
                .flatten()
                .take(i)
                .any(|o| o.channel == c.channel && o.unit == c.unit && !o.phases.is_empty())
                && !c.phases.is_empty()
            {
                return Err(bad(
                    format!("{at}.channel"),
                    format!("channel {:?} ({}) appears twice", c.channel, c.unit),
                ));
            }
            for (k, p) in c.phases.iter().enumerate() {
                let pat = format!("{at}.phases[{k}]");
                name(format!("{pat}.phase"), &p.phase)?;
                if c.phases[..k].iter().any(|q| q.phase == p.phase) {
                    return Err(bad(
                        format!("{pat}.phase"),
                        format!("phase {:?} appears twice", p.phase),
                    ));
                }
                mean(format!("{pat}.stats.mean"), &p.stats)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(mean: f64) -> SummaryStats {
        SummaryStats {
            mean,
            sd: Some(0.5),
            max: Some(2.0 * mean),
        }
    }

    #[test]
    fn written_summary_reads_back_with_its_extra_fields_beside() {
        let s = RunSummaryFile {
            command: Some("track".into()),
            status: Some(SqpStatus::MaxIterations),
            objective: Some(1.25),
            window_s: Some([0.1, 0.7]),
            errors: vec![ChannelStats {
                channel: "knee angle".into(),
                unit: "°".into(),
                stats: stats(3.0),
            }],
            errors_by_phase: Some(vec![ChannelPhaseErrors {
                channel: "knee angle".into(),
                unit: "°".into(),
                phases: vec![PhaseErrors {
                    phase: "1e".into(),
                    stats: stats(1.5),
                }],
            }]),
            ..Default::default()
        };
        let mut extra = serde_json::Map::new();
        extra.insert(
            "setup".into(),
            serde_json::json!({"model": "inputs/model/m.json"}),
        );
        let v = s.to_json(extra).unwrap();
        // the file's field names
        assert_eq!(v["status"], "max_iterations");
        assert_eq!(v["errors"][0]["stats"]["mean"], 3.0);
        assert_eq!(v["errors_by_phase"][0]["phases"][0]["phase"], "1e");
        assert_eq!(v["setup"]["model"], "inputs/model/m.json");
        assert!(v.get("fine_grid_error").is_none() && v.get("inputs").is_none());
        let back = RunSummaryFile::parse(&v.to_string(), Path::new("r/summary.json")).unwrap();
        assert_eq!(back.errors, s.errors);
        assert_eq!(back.errors_by_phase, s.errors_by_phase);
        assert_eq!(back.status, s.status);
        assert_eq!(back.window_s, s.window_s);
    }

    #[test]
    fn bad_summaries_name_the_file_and_the_field() {
        let cases = [
            (r#"{"command": "track"}"#, "field `errors`: missing"),
            (
                "[1]",
                "field `(top level)`: expected a JSON object, found an array",
            ),
            (
                r#"{"errors": [{"channel": "k", "unit": "°", "stats": {"mean": "4"}}]}"#,
                "field `errors[0].stats.mean`: expected a number, found the string \"4\"",
            ),
            (
                r#"{"errors": [{"channel": "k", "unit": "°", "stats": {"mean": -1}}]}"#,
                "field `errors[0].stats.mean`: -1 is not a mean of absolute errors",
            ),
            (
                r#"{"errors": [{"channel": "k", "unit": "°"}]}"#,
                "field `errors[0].stats`: missing",
            ),
            (
                r#"{"errors": [{"channel": " ", "unit": "°", "stats": {"mean": 1}}]}"#,
                "field `errors[0].channel`: empty name",
            ),
            (r#"{"errors": [], "window_s": [0.1]}"#, "field `window_s`"),
            (
                r#"{"errors": {}}"#,
                "field `errors`: expected an array, found an object",
            ),
            (
                r#"{"errors": [], "errors_by_phase": [{"channel": "k", "unit": "°", "phases": [{"phase": "1", "stats": {"mean": 1}}, {"phase": "1", "stats": {"mean": 1}}]}]}"#,
                "field `errors_by_phase[0].phases[1].phase`: phase \"1\" appears twice",
            ),
        ];
        for (text, want) in cases {
            let e = RunSummaryFile::parse(text, Path::new("r/summary.json"))
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("r/summary.json: "), "{e}");
            assert!(e.contains(want), "{text}: {e} (want {want})");
        }
    }
}
