//! The study table, built from the trial folders alone (so that a local run and a Slurm
//! array give the same table): one row per manifest row with its status, its error, the
//! check's readings (estimate, sd, verdict per candidate), with `--track` the track's
//! status, objective and iterations, and with `--diagnose` what the diagnosis suggests; and the pooled readings ([`super::findings`]).

use super::entry::{CheckResult, DiagnoseResult, Reading, Status, TrackResult, TrialEntry};
use super::findings::{self, GroupFindings};
use super::trial::{complete, folder, Stage, DIAGNOSIS, ERROR_FILE};
use super::{StudySettings, TrialRow};
use crate::problems::check::Param;
use serde::Serialize;
use std::path::Path;

/// The study table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StudyTable {
    /// One entry per manifest row, in its order.
    pub trials: Vec<TrialEntry>,
    /// Readings pooled over sessions (instruments) and subjects (body).
    pub pooled: Vec<GroupFindings>,
    /// The |z| a pooled reading must exceed: the family-wise level over every pooled
    /// reading of the study, Bonferroni-corrected.
    pub threshold: Option<f64>,
    /// The family-wise level.
    pub level: f64,
}

/// Read every row's trial folder under `dir` and pool the readings.
pub fn collect(dir: &Path, rows: &[TrialRow], settings: &StudySettings) -> StudyTable {
    let trials: Vec<TrialEntry> = rows.iter().map(|r| entry(dir, r, settings)).collect();
    let (pooled, threshold) = findings::pool_study(&trials, settings.level);
    StudyTable {
        trials,
        pooled,
        threshold,
        level: settings.level,
    }
}

fn entry(dir: &Path, row: &TrialRow, settings: &StudySettings) -> TrialEntry {
    let tdir = folder(dir, &row.id);
    let mut e = TrialEntry {
        row: row.row,
        id: row.id.clone(),
        subject: row.subject.clone(),
        session: row.session.clone(),
        condition: row.condition.clone(),
        data: row
            .files
            .data
            .as_ref()
            .map(|d| d.display().to_string())
            .unwrap_or_default(),
        status: Status::NotRun,
        error: None,
        check: None,
        track: None,
        diagnose: None,
    };
    let read = |stage: Stage| {
        let dir = tdir.join(stage.name());
        complete(&dir, &stage.inputs(row, settings))
            .then(|| read_summary(&dir))
            .flatten()
    };
    e.check = read(Stage::Check).map(|s| check_result(&s));
    e.track = if settings.track {
        read(Stage::Track).map(|s| track_result(&s))
    } else {
        None
    };
    let diagnosing = settings.track && settings.diagnose;
    if diagnosing {
        let dir = tdir.join(Stage::Diagnose.name());
        e.diagnose = complete(&dir, &Stage::Diagnose.inputs(row, settings))
            .then(|| read_summary(&dir.join(DIAGNOSIS)))
            .flatten()
            .map(|s| diagnose_result(&s));
    }
    let missing = match (&e.check, settings.track, &e.track) {
        (None, _, _) => Some("check"),
        (Some(_), true, None) => Some("track"),
        _ if diagnosing && e.diagnose.is_none() => Some("diagnose"),
        _ => None,
    };
    (e.status, e.error) = match (read_error(&tdir), missing) {
        (Some(err), Some(_)) => (Status::Failed, Some(err)),
        (_, Some(m)) => (
            Status::NotRun,
            Some(format!(
                "no complete {m} folder for this row and these settings"
            )),
        ),
        (_, None) => (Status::Done, None),
    };
    e
}

/// The recorded error of a trial folder, if any.
fn read_error(dir: &Path) -> Option<String> {
    let text = std::fs::read_to_string(dir.join(ERROR_FILE)).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    Some(format!(
        "{}: {}",
        v["stage"].as_str().unwrap_or("?"),
        v["error"].as_str().unwrap_or("?")
    ))
}

/// A committed stage folder's `summary.json`.
fn read_summary(stage: &Path) -> Option<serde_json::Value> {
    let text = std::fs::read_to_string(stage.join("summary.json")).ok()?;
    serde_json::from_str(&text).ok()
}

fn reading(v: &serde_json::Value) -> Reading {
    Reading {
        effect: v["effect"].as_str().unwrap_or_default().to_string(),
        estimate: v["estimate"].as_f64(),
        sd: v["sd"].as_f64(),
        sd_within: v["sd_within"].as_f64(),
        centre: v["untouched"]["mean"].as_f64(),
        explained: v["explained"].as_f64(),
        verdict: v["verdict"].as_str().unwrap_or_default().to_string(),
    }
}

fn check_result(s: &serde_json::Value) -> CheckResult {
    let list = |k: &str| -> Vec<Reading> {
        let mut r: Vec<Reading> = s[k]
            .as_array()
            .map(|a| a.iter().map(reading).collect())
            .unwrap_or_default();
        // in θ order, whatever order the check found them in
        r.sort_by_key(|x| Param::from_name(&x.effect));
        r
    };
    CheckResult {
        readings: list("candidates"),
        alone: list("alone"),
        found: s["found"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default(),
        mass_kg: (
            s["mass_kg"]["model"].as_f64(),
            s["mass_kg"]["implied_by_forces"].as_f64(),
        ),
    }
}

fn diagnose_result(s: &serde_json::Value) -> DiagnoseResult {
    DiagnoseResult {
        verdict: s["verdict"].as_str().unwrap_or_default().to_string(),
        significant: s["significant"].as_u64(),
        found: s["found"].as_u64(),
        add_effects: s["add_effects"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default(),
    }
}

fn track_result(s: &serde_json::Value) -> TrackResult {
    TrackResult {
        // a status with a reason is written as an object keyed by its name
        status: match &s["status"] {
            serde_json::Value::Object(o) => o.keys().next().cloned().unwrap_or_default(),
            v => v.as_str().unwrap_or_default().to_string(),
        },
        objective: s["objective"].as_f64(),
        iterations: s["iterations"].as_u64(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A track's status is read whether the summary writes it as a name or, with its
    /// reason, as an object keyed by the name.
    #[test]
    fn a_tracks_status_is_read_with_or_without_its_reason() {
        let plain =
            serde_json::json!({"status": "max_iterations", "objective": 8.2, "iterations": 200});
        assert_eq!(track_result(&plain).status, "max_iterations");
        let with_reason = serde_json::json!({
            "status": {"evaluation_failure": "non-finite value at t = 0.93"},
            "objective": 7.77,
            "iterations": 121
        });
        let r = track_result(&with_reason);
        assert_eq!(r.status, "evaluation_failure");
        assert_eq!((r.objective, r.iterations), (Some(7.77), Some(121)));
    }
}
