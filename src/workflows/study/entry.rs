//! One trial's row of the study table, as its folder holds it: its status and error, its
//! check's readings, its track and its diagnosis ([`super::table`] reads them).

use serde::Serialize;

/// Whether a trial has results.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Every stage asked for is complete.
    Done,
    /// A stage failed (see `error`).
    Failed,
    /// Not run yet (or killed before a stage was complete).
    NotRun,
}

impl Status {
    /// In files.
    pub fn name(self) -> &'static str {
        match self {
            Status::Done => "done",
            Status::Failed => "failed",
            Status::NotRun => "not run",
        }
    }
}

/// One candidate's reading in one trial, as the check's `summary.json` gives it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Reading {
    /// Candidate ([`crate::problems::check::Param::name`]).
    pub effect: String,
    /// Estimate (SI units; `None` where not read).
    pub estimate: Option<f64>,
    /// Standard deviation, the untouched trials' spread included.
    pub sd: Option<f64>,
    /// The window's own standard deviation.
    pub sd_within: Option<f64>,
    /// What untouched trials read as it: the centre of the check's band (SI units).
    pub centre: Option<f64>,
    /// Share of the trial's residual it explains, read alone.
    pub explained: Option<f64>,
    /// The check's verdict.
    pub verdict: String,
}

/// A trial's check, as its folder holds it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckResult {
    /// Every candidate's reading, jointly with those found (the check's report).
    pub readings: Vec<Reading>,
    /// Every candidate read alone (what is pooled: the same reading in every trial).
    pub alone: Vec<Reading>,
    /// The candidates found, in the order found.
    pub found: Vec<String>,
    /// The model's mass and the mass the vertical forces imply (kg).
    pub mass_kg: (Option<f64>, Option<f64>),
}

/// A trial's track, as its folder holds it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackResult {
    /// The solver's status.
    pub status: String,
    /// The objective J.
    pub objective: Option<f64>,
    /// SQP iterations.
    pub iterations: Option<u64>,
}

/// A trial's diagnosis, as its folder holds it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiagnoseResult {
    /// What the diagnosis concludes, in words.
    pub verdict: String,
    /// Candidates significant against the noise.
    pub significant: Option<u64>,
    /// Candidates found (significant and validated).
    pub found: Option<u64>,
    /// The `--effect` lines it suggests.
    pub add_effects: Vec<String>,
}

/// One row of the study table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrialEntry {
    /// 1-based manifest row.
    pub row: usize,
    /// The trial's id (its folder under `trials/`).
    pub id: String,
    /// Subject.
    pub subject: String,
    /// Lab session.
    pub session: String,
    /// Condition.
    pub condition: String,
    /// The trial file.
    pub data: String,
    /// Whether it has results.
    pub status: Status,
    /// Why it failed (`status` failed), or which stage is missing (not run).
    pub error: Option<String>,
    /// The check (also of a trial whose track failed).
    pub check: Option<CheckResult>,
    /// The track (with `--track`).
    pub track: Option<TrackResult>,
    /// The track's diagnosis (with `--diagnose`).
    pub diagnose: Option<DiagnoseResult>,
}
