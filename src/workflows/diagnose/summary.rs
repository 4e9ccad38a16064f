//! A diagnosis's `summary.json` as one serde struct, [`DiagnosisSummary`]: `diagnose`
//! fills and writes it, and readers (the report, tests, scripts) read it back through it.
//! Reading names the file and the JSON path of a field that is missing or of the wrong
//! kind ([`crate::runfolder::read_json`]); the fields a reader needs (`command`,
//! `ranking`) are required, the rest default when absent.

use crate::problems::diagnose::ScoreTest;
use crate::runfolder::{read_json, RunFileError};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What `command` holds in a diagnosis's summary (a gait run's says `track`, …).
pub const COMMAND: &str = "diagnose";

/// One channel's variance inflation `φ = N/N_eff` (`None`: too short a series).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelInflation {
    /// Table 3 channel name.
    pub channel: String,
    /// Its variance inflation.
    pub inflation: Option<f64>,
}

/// The variance inflation of the run's residuals.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct VarianceInflation {
    /// Over all channels alike.
    pub all_channels: f64,
    /// Channel by channel.
    pub channels: Vec<ChannelInflation>,
}

/// The largest model (every scored candidate added), whose residuals stand for the noise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NoiseModel {
    /// Its effects' labels.
    pub effects: Vec<String>,
    /// Its cost after the re-fit.
    pub objective: f64,
    /// Each channel's variance inflation in its residuals.
    pub inflation: Vec<ChannelInflation>,
}

/// One identified parameter of a verifying re-fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VerifiedParameter {
    /// Parameter name, e.g. `ground_slope.angle`.
    pub name: String,
    /// Its identified value (parameter unit).
    pub value: f64,
    /// Its unit.
    pub unit: String,
    /// Its standard deviation, when the re-fit gave one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sd: Option<f64>,
}

/// A verifying re-fit of a candidate (a track run folder of its own).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VerifiedRecord {
    /// The effect re-fitted.
    pub effect: crate::model::effects::EffectSpec,
    /// Its label.
    pub label: String,
    /// The re-fit's run folder.
    pub folder: PathBuf,
    /// Whether the re-fit converged.
    pub converged: bool,
    /// Cost of the diagnosed run.
    pub objective_before: f64,
    /// Cost after the re-fit.
    pub objective_after: f64,
    /// The decrease the test predicted, as a fraction of the cost.
    pub predicted_fraction: f64,
    /// The decrease the re-fit made, as a fraction of the cost.
    pub verified_fraction: f64,
    /// Its identified parameters.
    pub parameters: Vec<VerifiedParameter>,
    /// What it explains, in a sentence.
    pub sentence: String,
}

/// A diagnosis's `summary.json`.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct DiagnosisSummary {
    /// Always [`COMMAND`].
    pub command: String,
    /// The diagnosed track run folder.
    #[serde(default)]
    pub run: PathBuf,
    /// Its tracking cost J.
    #[serde(default)]
    pub objective: f64,
    /// Its data residual count N.
    #[serde(default)]
    pub data_residuals: usize,
    /// The decrease a truncated re-fit of the plain model still makes (the baseline
    /// every candidate's decrease is measured against).
    #[serde(default)]
    pub baseline_decrease: f64,
    /// The variance inflation of the run's residuals.
    #[serde(default)]
    pub variance_inflation: VarianceInflation,
    /// The largest model's residuals (when more than one candidate was scored).
    #[serde(default)]
    pub noise_model: Option<NoiseModel>,
    /// Every candidate's test, in rank order.
    pub ranking: Vec<ScoreTest>,
    /// How many are significant in-sample.
    #[serde(default)]
    pub significant: usize,
    /// How many are found (significant and confirmed on a held-out half cycle).
    #[serde(default)]
    pub found: usize,
    /// How many are not testable with the run's cost.
    #[serde(default)]
    pub untestable: usize,
    /// How the held-out validation went (empty when none was needed).
    #[serde(default)]
    pub held_out_note: String,
    /// The measurement stage's verdict (`footfall check`), shown first (`None`: the
    /// trial could not be checked).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measurement: Option<String>,
    /// The verdict in a sentence.
    #[serde(default)]
    pub verdict: String,
    /// The most likely missing effect in `track --effect` form, at its reading: what to
    /// add with one line, re-fit and diagnose again (empty when nothing was found).
    #[serde(default)]
    pub add_effects: Vec<String>,
    /// The verifying re-fits.
    #[serde(default)]
    pub verified: Vec<VerifiedRecord>,
    /// Candidates not tested, and why.
    #[serde(default)]
    pub skipped: Vec<String>,
}

/// Why a file is not a diagnosis's summary.
#[derive(Debug, thiserror::Error)]
pub enum DiagnosisSummaryError {
    /// It could not be read or decoded.
    #[error(transparent)]
    File(#[from] RunFileError),
    /// It is another command's summary.
    #[error("{path}: `command` is {command:?}: not the summary of a `footfall diagnose`")]
    NotADiagnosis {
        /// The file.
        path: PathBuf,
        /// The command it names.
        command: String,
    },
}

impl DiagnosisSummary {
    /// Read the `summary.json` in a diagnosis folder.
    pub fn read(folder: &Path) -> Result<Self, DiagnosisSummaryError> {
        let path = folder.join("summary.json");
        let summary: DiagnosisSummary = read_json(&path)?;
        if summary.command != COMMAND {
            return Err(DiagnosisSummaryError::NotADiagnosis {
                path,
                command: summary.command,
            });
        }
        Ok(summary)
    }

    /// A summary holding only `ranking` (the rest empty).
    pub fn of_ranking(ranking: Vec<ScoreTest>) -> Self {
        DiagnosisSummary {
            command: COMMAND.into(),
            ranking,
            ..Default::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::effects::EffectSpec;
    use crate::problems::diagnose::refit_test;

    fn slope_test() -> ScoreTest {
        let effect = EffectSpec::GroundSlope {
            angle: 0.0,
            free: vec!["angle".into()],
        };
        refit_test(
            &effect,
            vec!["ground_slope.angle".into()],
            vec![-0.021],
            2.0,
            1.0,
            100,
            3,
        )
    }

    /// What `diagnose` writes reads back to the same JSON, field for field.
    #[test]
    fn a_written_summary_reads_back_the_same() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = DiagnosisSummary::of_ranking(vec![slope_test()]);
        s.objective = 7.9;
        s.variance_inflation.channels.push(ChannelInflation {
            channel: "knee angle".into(),
            inflation: None,
        });
        s.verified.push(VerifiedRecord {
            effect: s.ranking[0].effect.clone(),
            label: "ground slope".into(),
            folder: "runs/x+ground_slope".into(),
            converged: true,
            objective_before: 7.9,
            objective_after: 7.1,
            predicted_fraction: 0.1,
            verified_fraction: 0.101,
            parameters: vec![VerifiedParameter {
                name: "ground_slope.angle".into(),
                value: -0.021,
                unit: "rad".into(),
                sd: Some(0.001),
            }],
            sentence: "ground slope explains …".into(),
        });
        let text = serde_json::to_string_pretty(&s).unwrap();
        std::fs::write(dir.path().join("summary.json"), &text).unwrap();
        let back = DiagnosisSummary::read(dir.path()).unwrap();
        assert_eq!(
            serde_json::to_value(&back).unwrap(),
            serde_json::to_value(&s).unwrap()
        );
        assert_eq!(back.ranking[0].step_values, vec![-0.021]);
    }

    /// Another command's summary, or a ranking entry without a field the reader needs, is
    /// refused with the file and the field named.
    #[test]
    fn a_foreign_or_broken_summary_names_the_file_and_the_field() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("summary.json");
        let mut v = serde_json::to_value(DiagnosisSummary::of_ranking(vec![slope_test()])).unwrap();
        v["command"] = "track".into();
        std::fs::write(&file, v.to_string()).unwrap();
        let e = DiagnosisSummary::read(dir.path()).unwrap_err().to_string();
        assert!(e.contains("summary.json") && e.contains("\"track\""), "{e}");

        v["command"] = COMMAND.into();
        v["ranking"][0].as_object_mut().unwrap().remove("label");
        std::fs::write(&file, v.to_string()).unwrap();
        let e = DiagnosisSummary::read(dir.path()).unwrap_err().to_string();
        assert!(
            e.contains("summary.json") && e.contains("ranking[0]"),
            "{e}"
        );
        assert!(e.contains("label"), "{e}");
    }
}
