//! One trial of a study, into `DIR/trials/<id>/`: its check (`check/`) and, when asked,
//! its track (`track/`) and the track's diagnosis (`diagnose/`), each a run folder committed whole ([`crate::runfolder`]) that
//! holds the inputs it was made from (`study-row.json`). A stage whose folder holds the
//! same inputs is complete and skipped; one made from other inputs (an edited row, other
//! settings) is replaced. A failed stage writes `error.json` beside them (removed when
//! the trial later succeeds), and the study goes on.

use super::{StudySettings, TrialRow};
use crate::runfolder::{write_atomic, RunFolder};
use crate::sqp::SqpStatus;
use crate::workflows::check::{self as check_flow, CheckRequest};
use crate::workflows::diagnose::{self, DiagnoseRequest};
use crate::workflows::track::{track, TrackRequest};
use crate::workflows::{Progress, WarningsOnly};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// The file inside each stage's folder that records what it was made from.
pub const INPUTS_FILE: &str = "study-row.json";

/// The file that records a trial's failure.
pub const ERROR_FILE: &str = "error.json";

/// What happened to one trial.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ran {
    /// Every stage was complete already.
    Skipped,
    /// Run now, every stage written.
    Done,
    /// A stage failed; its error is recorded.
    Failed,
    /// Not started: the study was interrupted first.
    NotStarted,
}

/// The folder of a trial.
pub fn folder(out: &Path, id: &str) -> PathBuf {
    out.join("trials").join(id)
}

/// Threads each of `jobs` trials at once may use for its own parallel work (a track's
/// shooting intervals): the machine's cores shared out, at least one.
pub fn threads_per_trial(jobs: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    (cores / jobs.max(1)).max(1)
}

/// Run `rows` with at most `jobs` at once, each in a thread pool of its own
/// ([`threads_per_trial`]); each trial's outcome, in `rows`' order.
pub fn run_all(
    rows: &[&TrialRow],
    settings: &StudySettings,
    out: &Path,
    jobs: usize,
    progress: &dyn Progress,
) -> Vec<Ran> {
    let next = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let results = Mutex::new(vec![Ran::NotStarted; rows.len()]);
    let threads = threads_per_trial(jobs);
    std::thread::scope(|s| {
        for _ in 0..jobs.min(rows.len()) {
            s.spawn(|| loop {
                if crate::interrupt::requested() {
                    // Ctrl-C: the trials running stop; none is started
                    break;
                }
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(row) = rows.get(i) else { break };
                let start = std::time::Instant::now();
                let (ran, what) = in_pool(threads, || run_one(row, settings, out, progress));
                let k = finished.fetch_add(1, Ordering::SeqCst) + 1;
                progress.note(&format!(
                    "[{k}/{}] {}: {what} ({:.1} s)",
                    rows.len(),
                    row.id,
                    start.elapsed().as_secs_f64()
                ));
                results.lock().unwrap_or_else(|p| p.into_inner())[i] = ran;
            });
        }
    });
    results.into_inner().unwrap_or_else(|p| p.into_inner())
}

/// `f` run in a thread pool of `threads` (in the caller's thread where the pool cannot
/// be made).
fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
        Ok(pool) => pool.install(f),
        Err(_) => f(),
    }
}

/// Run one trial's stages; what happened, in words.
pub fn run_one(
    row: &TrialRow,
    settings: &StudySettings,
    out: &Path,
    progress: &dyn Progress,
) -> (Ran, String) {
    let dir = folder(out, &row.id);
    let mut did = Vec::new();
    let mut stages = vec![Stage::Check];
    if settings.track {
        stages.push(Stage::Track);
    }
    if settings.track && settings.diagnose {
        stages.push(Stage::Diagnose);
    }
    for stage in stages {
        let inputs = stage.inputs(row, settings);
        let target = dir.join(stage.name());
        if complete(&target, &inputs) {
            continue;
        }
        let result = match stage {
            Stage::Check => run_check(row, settings, &target, &inputs, progress),
            Stage::Track => run_track(row, settings, &target, &inputs, progress),
            Stage::Diagnose => run_diagnose(row, settings, &dir, &inputs, progress),
        };
        match result {
            Ok(text) => did.push(format!("{}: {text}", stage.name())),
            Err(e) => {
                let message = crate::workflows::error_text(&e);
                let record = json!({"stage": stage.name(), "error": message});
                let text = serde_json::to_string_pretty(&record).unwrap_or_default();
                let _ = std::fs::create_dir_all(&dir);
                if let Err(w) = write_atomic(&dir, ERROR_FILE, text.as_bytes()) {
                    progress.warn(&format!("{}: {w}", row.id));
                }
                return (Ran::Failed, format!("{} failed: {message}", stage.name()));
            }
        }
    }
    let _ = std::fs::remove_file(dir.join(ERROR_FILE));
    if did.is_empty() {
        (Ran::Skipped, "complete, skipped".into())
    } else {
        (Ran::Done, did.join("; "))
    }
}

/// The stages of a trial.
#[derive(Debug, Clone, Copy)]
pub enum Stage {
    /// The measurement check (`check/`).
    Check,
    /// The track (`track/`).
    Track,
    /// The track's diagnosis (`diagnose/`, its run folder `diagnose/diagnosis/`; the
    /// re-fits beside the track, `track+<effect>/`).
    Diagnose,
}

impl Stage {
    /// Its folder's name.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Check => "check",
            Stage::Track => "track",
            Stage::Diagnose => "diagnose",
        }
    }

    /// What the stage's results depend on.
    pub fn inputs(self, row: &TrialRow, s: &StudySettings) -> serde_json::Value {
        let f = &row.files;
        let files = json!({
            "data": f.data, "forces": f.forces, "plates": f.plates, "lab_axes": f.lab_axes,
            "belt_speed": f.belt_speed, "overground": f.overground, "model": row.model,
        });
        match self {
            Stage::Check => json!({"stage": "check", "files": files,
                "cutoff_hz": row.cutoff_hz.unwrap_or(s.cutoff_hz), "level": s.level}),
            Stage::Track | Stage::Diagnose => json!({"stage": self.name(), "files": files,
                "foot": row.foot, "max_iter": row.max_iter.unwrap_or(s.max_iter),
                "kinematics_cutoff": row.kinematics_cutoff}),
        }
    }
}

/// Whether the committed folder `target` was made from `inputs`.
pub fn complete(target: &Path, inputs: &serde_json::Value) -> bool {
    let Ok(text) = std::fs::read_to_string(target.join(INPUTS_FILE)) else {
        return false;
    };
    serde_json::from_str::<serde_json::Value>(&text)
        .ok()
        .as_ref()
        == Some(inputs)
}

fn run_check(
    row: &TrialRow,
    settings: &StudySettings,
    target: &Path,
    inputs: &serde_json::Value,
    progress: &dyn Progress,
) -> anyhow::Result<String> {
    let req = CheckRequest {
        trial: row.files.clone(),
        model: row.model.clone(),
        out: Some(target.to_path_buf()),
        overwrite: true,
        settings: settings.check_settings(row),
    };
    let (data, check, half) = check_flow::read(&req)?;
    for w in &check.warnings {
        progress.warn(&format!("{}: warning: {w}", row.id));
    }
    let folder = RunFolder::create(target, true)?;
    check_flow::write_folder(&folder, &req, &data, &check, &half)?;
    folder.write(
        INPUTS_FILE,
        serde_json::to_string_pretty(inputs)?.as_bytes(),
    )?;
    folder.commit()?;
    let found: Vec<&str> = check.found().map(|r| r.param.name()).collect();
    Ok(if found.is_empty() {
        "nothing found".into()
    } else {
        format!("found {}", found.join(", "))
    })
}

fn run_track(
    row: &TrialRow,
    settings: &StudySettings,
    target: &Path,
    inputs: &serde_json::Value,
    progress: &dyn Progress,
) -> anyhow::Result<String> {
    let mut req = TrackRequest::new(&row.foot);
    let f = &row.files;
    req.run.model = row.model.clone();
    req.run.data = f.data.clone();
    req.run.forces = f.forces.clone();
    req.run.plates = f.plates.clone();
    req.run.lab_axes = f.lab_axes.clone();
    req.run.belt_speed = f.belt_speed;
    req.run.overground = f.overground;
    req.run.kinematics_cutoff = row.kinematics_cutoff;
    req.sqp.max_iter = row.max_iter.unwrap_or(settings.max_iter);
    let folder = RunFolder::create(target, true)?;
    folder.write(
        INPUTS_FILE,
        serde_json::to_string_pretty(inputs)?.as_bytes(),
    )?;
    let run = track(&req, folder, &WarningsOnly(progress))?;
    if run.result.status == SqpStatus::Interrupted {
        // a study's track is run again whole, never resumed: the stopped one is not its result
        std::fs::remove_dir_all(&run.output.path)?;
        anyhow::bail!("interrupted: the track runs again when the study is run again");
    }
    Ok(format!(
        "{}, {}",
        run.result.status,
        run.result.objective_text(4)
    ))
}

/// The diagnosis of the trial's track: `diagnose` written into this stage's folder, its
/// re-fits (at the track's iteration limit) beside the track.
fn run_diagnose(
    row: &TrialRow,
    settings: &StudySettings,
    dir: &Path,
    inputs: &serde_json::Value,
    progress: &dyn Progress,
) -> anyhow::Result<String> {
    let folder = RunFolder::create(&dir.join(Stage::Diagnose.name()), true)?;
    folder.write(
        INPUTS_FILE,
        serde_json::to_string_pretty(inputs)?.as_bytes(),
    )?;
    let mut req = DiagnoseRequest::new(dir.join(Stage::Track.name()));
    req.out = Some(folder.staging_path().join(DIAGNOSIS));
    req.overwrite = true;
    req.max_iter = row.max_iter.unwrap_or(settings.max_iter);
    diagnose::run(&req, &WarningsOnly(progress))?;
    let summary: serde_json::Value =
        crate::runfolder::read_json(&folder.staging_path().join(DIAGNOSIS).join("summary.json"))?;
    folder.commit()?;
    let effects = summary["add_effects"].as_array().map_or(0, Vec::len);
    Ok(format!("{} effect(s) to add", effects))
}

/// The diagnosis's run folder inside the diagnose stage's folder.
pub const DIAGNOSIS: &str = "diagnosis";
