//! `footfall study MANIFEST --out DIR`: many trials, one command. Each row of the
//! manifest ([`manifest`]) is checked (and on request tracked) into its own run folder
//! `DIR/trials/<id>/` ([`trial`]); a trial whose folders are complete is skipped, a trial
//! that fails records its error and the others go on. The study table
//! (`study.csv`, `study.json`, `report.html`) is then built from the trial folders alone
//! ([`table`], one row per trial as [`entry`] reads it), with the readings of an instrument pooled over a lab session's trials and
//! those of the body over a subject's ([`pool`], [`findings`]). The same trials run as a
//! Slurm job array ([`slurm`]): one task per row, the table gathered from the folders.

pub mod entry;
pub mod findings;
pub mod manifest;
pub mod pool;
pub mod report;
pub mod slurm;
pub mod table;
pub mod trial;

use super::Progress;
use crate::problems::check::CheckSettings;
pub use manifest::{ManifestError, TrialRow};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
pub use table::StudyTable;

/// Marker of a study folder: footfall writes into, and `--collect` reads, only a folder
/// that holds it (or an empty or new one).
pub const STUDY_MARKER: &str = ".footfall-study";

/// Where a study keeps how it was asked for, so that `--collect` and the Slurm tasks read
/// the same rows and settings.
pub const SETTINGS_FILE: &str = "study-settings.json";

/// Why a study cannot run (a trial's own failure is not one: it is recorded in the table).
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The manifest cannot be read.
    #[error(transparent)]
    Manifest(#[from] ManifestError),
    /// The output folder holds files of something else.
    #[error("output folder {0} exists and is not a footfall study folder (no {STUDY_MARKER} marker): choose another --out, or an empty folder")]
    Foreign(PathBuf),
    /// `--collect` of a folder without the study's settings.
    #[error("{0} is not a study folder: it has no {SETTINGS_FILE} (run `footfall study MANIFEST --out DIR` or `--slurm` first)")]
    NotAStudy(PathBuf),
    /// `--only-row` outside the manifest.
    #[error("--only-row {row}: the manifest {manifest} has rows 1 to {rows}")]
    NoSuchRow {
        /// The row asked for.
        row: usize,
        /// Rows in the manifest.
        rows: usize,
        /// The manifest.
        manifest: PathBuf,
    },
    /// A file of the study folder cannot be read or written.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// `--jobs 0`.
    #[error("--jobs 0: at least one trial at a time")]
    NoJobs,
}

impl StudyError {
    fn file(path: &Path, e: impl std::fmt::Display) -> Self {
        StudyError::File {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    }
}

/// What each trial runs beyond the check, and the study-wide settings a row may override.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudySettings {
    /// The manifest (absolute).
    pub manifest: PathBuf,
    /// Track each trial after its check.
    pub track: bool,
    /// Diagnose each track (with `track`).
    #[serde(default)]
    pub diagnose: bool,
    /// The track's iteration limit (a row's `max_iter` overrides it), and the diagnosis's
    /// re-fits'.
    pub max_iter: usize,
    /// The check's low-pass cutoff (Hz; a row's `cutoff` overrides it).
    pub cutoff_hz: f64,
    /// The check's family-wise level, and the pooled readings'.
    pub level: f64,
}

impl StudySettings {
    /// The check's settings for `row`.
    pub fn check_settings(&self, row: &TrialRow) -> CheckSettings {
        CheckSettings {
            cutoff_hz: row.cutoff_hz.unwrap_or(self.cutoff_hz),
            level: self.level,
            ..CheckSettings::default()
        }
    }
}

/// A study to run.
#[derive(Debug, Clone)]
pub struct StudyRequest {
    /// How the trials run.
    pub settings: StudySettings,
    /// The study folder.
    pub out: PathBuf,
    /// Trials at once (each check runs on one thread; a track uses the shared pool).
    pub jobs: usize,
    /// Run only this 1-based row, and write no table (a Slurm array task).
    pub only_row: Option<usize>,
}

/// What a study did.
#[derive(Debug)]
pub struct StudyOutcome {
    /// Trials run now.
    pub ran: usize,
    /// Trials skipped because their folders were complete.
    pub skipped: usize,
    /// Trials that failed now.
    pub failed: usize,
    /// Whether a stop was asked (Ctrl-C): the trials running stopped, none was started
    /// after it; the table holds what is done.
    pub interrupted: bool,
    /// The table, when written (not for `--only-row`).
    pub table: Option<StudyTable>,
}

/// Run the study `req` describes: every row's trial (or only one), then the table.
pub fn run(req: &StudyRequest, progress: &dyn Progress) -> Result<StudyOutcome, StudyError> {
    if req.jobs == 0 {
        return Err(StudyError::NoJobs);
    }
    let rows = manifest::read(&req.settings.manifest)?;
    let chosen: Vec<&TrialRow> = match req.only_row {
        Some(r) => vec![rows.get(r.wrapping_sub(1)).ok_or(StudyError::NoSuchRow {
            row: r,
            rows: rows.len(),
            manifest: req.settings.manifest.clone(),
        })?],
        None => rows.iter().collect(),
    };
    prepare_folder(&req.out)?;
    if req.only_row.is_none() {
        write_settings(&req.out, &req.settings)?;
    }
    let done = trial::run_all(&chosen, &req.settings, &req.out, req.jobs, progress);
    let count = |r: trial::Ran| done.iter().filter(|d| **d == r).count();
    let mut outcome = StudyOutcome {
        ran: count(trial::Ran::Done) + count(trial::Ran::Failed),
        skipped: count(trial::Ran::Skipped),
        failed: count(trial::Ran::Failed),
        interrupted: crate::interrupt::requested(),
        table: None,
    };
    if req.only_row.is_none() {
        let table = table::collect(&req.out, &rows, &req.settings);
        report::write(&req.out, &table)?;
        progress.result(&report::summary_text(&table));
        outcome.table = Some(table);
    }
    Ok(outcome)
}

/// The arguments of `footfall study` that give `s` (the manifest first): what every
/// Slurm task repeats.
pub fn task_args(s: &StudySettings) -> Vec<String> {
    let mut a = vec![
        s.manifest.display().to_string(),
        "--cutoff".into(),
        s.cutoff_hz.to_string(),
        "--level".into(),
        s.level.to_string(),
    ];
    if s.track {
        a.extend([
            "--track".into(),
            "--max-iter".into(),
            s.max_iter.to_string(),
        ]);
    }
    if s.track && s.diagnose {
        a.push("--diagnose".into());
    }
    a
}

/// Make `out` a study folder for `settings` and write the Slurm scripts that run its
/// rows as an array ([`slurm`]); the job and the scripts' paths.
pub fn prepare_slurm(
    settings: &StudySettings,
    out: &Path,
    exe: &Path,
    cpus_per_task: usize,
    time: Option<String>,
    partition: Option<String>,
) -> Result<(slurm::SlurmJob, PathBuf, PathBuf), StudyError> {
    let rows = manifest::read(&settings.manifest)?;
    prepare_folder(out)?;
    write_settings(out, settings)?;
    let job = slurm::SlurmJob {
        exe: exe.to_path_buf(),
        out: out.to_path_buf(),
        rows: rows.len(),
        args: task_args(settings),
        cpus_per_task,
        time,
        partition,
    };
    let (array, collect) = slurm::write_scripts(&job)?;
    Ok((job, array, collect))
}

/// Build the study table of `dir` from its trial folders and write it (`--collect`).
pub fn collect(dir: &Path, progress: &dyn Progress) -> Result<StudyTable, StudyError> {
    let settings = read_settings(dir)?;
    let rows = manifest::read(&settings.manifest)?;
    let table = table::collect(dir, &rows, &settings);
    report::write(dir, &table)?;
    progress.result(&report::summary_text(&table));
    Ok(table)
}

/// Make `dir` a study folder: new, empty, or already one.
pub fn prepare_folder(dir: &Path) -> Result<(), StudyError> {
    if dir.exists() {
        let marked = dir.join(STUDY_MARKER).is_file();
        let empty = std::fs::read_dir(dir)
            .map_err(|e| StudyError::file(dir, e))?
            .next()
            .is_none();
        if !marked && !empty {
            return Err(StudyError::Foreign(dir.to_path_buf()));
        }
        if marked {
            return Ok(());
        }
    }
    std::fs::create_dir_all(dir.join("trials")).map_err(|e| StudyError::file(dir, e))?;
    crate::runfolder::write_atomic(
        dir,
        STUDY_MARKER,
        b"This folder is a footfall study: `footfall study` writes its trials/ and tables here.\n",
    )
    .map_err(|e| StudyError::file(dir, e))
}

/// Write the study's settings into `dir` (atomically).
pub fn write_settings(dir: &Path, s: &StudySettings) -> Result<(), StudyError> {
    let text = serde_json::to_string_pretty(s).map_err(|e| StudyError::file(dir, e))?;
    crate::runfolder::write_atomic(dir, SETTINGS_FILE, text.as_bytes())
        .map_err(|e| StudyError::file(&dir.join(SETTINGS_FILE), e))
}

/// The settings a study folder was made with.
pub fn read_settings(dir: &Path) -> Result<StudySettings, StudyError> {
    let p = dir.join(SETTINGS_FILE);
    if !p.is_file() {
        return Err(StudyError::NotAStudy(dir.to_path_buf()));
    }
    crate::runfolder::read_json(&p).map_err(|e| StudyError::file(&p, e))
}
