//! Process-wide state of one `footfall` invocation: interruption, the run folder's
//! checkpoints, and resuming a killed or interrupted run.
//!
//! * Interruption: a stop asked through [`crate::interrupt`] (the CLI's Ctrl-C handler)
//!   ends a solve within a fraction of a second, inside an iteration too, at its last
//!   accepted iterate; the run folder is written with status `interrupted`.
//! * Checkpoints: `track`, `predict` and `solve` write their command line and, after every
//!   accepted SQP iteration, the solver's state into the run's staging folder
//!   (`.resume-*`, written atomically). A run killed outright (`kill -9`, a power cut)
//!   leaves that staging folder behind; an interrupted run keeps them in its run folder.
//! * Resume: `--resume DIR` finds the staging folder a dead process left for the output
//!   folder `DIR`, or the interrupted run folder `DIR`, runs its command again in its
//!   working folder, and continues each solve from its last checkpoint (solves are counted
//!   in the order the command runs them, so a staged solve resumes at the stage it
//!   reached); an interrupted run's folder is replaced by the resumed run's. Evaluations
//!   are deterministic, so the resumed run follows the same iterates, bit for bit, as one
//!   that was never stopped.

use super::{note, warn_note, Progress};
use crate::runfolder::{self, RunFolder, RESUME_PREFIX};
use crate::sqp::checkpoint::SqpCheckpoint;
use crate::sqp::{IterationRecord, Nlp, Observer, SqpResult, SqpSettings};
use anyhow::{anyhow, bail, Context};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Solves started so far by this process (the index of a solve's checkpoint file).
static SOLVES: AtomicUsize = AtomicUsize::new(0);

/// Where checkpoints go, and what a resumed run continues from.
struct Session {
    /// The command line and working folder to record in a run folder.
    command: Option<RecordedCommand>,
    /// Staging folder of the run folder that takes checkpoints.
    checkpoint_dir: Option<PathBuf>,
    /// Checkpoints of the killed run being resumed, by solve index.
    resume: BTreeMap<usize, SqpCheckpoint>,
    /// The interrupted run folder being resumed, which the resumed run replaces.
    replaces: Option<PathBuf>,
}

static SESSION: Mutex<Session> = Mutex::new(Session {
    command: None,
    checkpoint_dir: None,
    resume: BTreeMap::new(),
    replaces: None,
});

fn session() -> std::sync::MutexGuard<'static, Session> {
    SESSION.lock().unwrap_or_else(|p| p.into_inner())
}

const COMMAND_FILE: &str = ".resume-command.json";

fn checkpoint_file(solve: usize) -> String {
    format!("{RESUME_PREFIX}checkpoint-{solve}.json")
}

/// A command line as it was started.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RecordedCommand {
    /// Arguments after the program name.
    pub args: Vec<String>,
    /// Working folder it ran in.
    pub cwd: PathBuf,
}

/// Record the command line of this invocation (written into checkpointed run folders).
pub fn record_command(args: Vec<String>) -> anyhow::Result<()> {
    let cwd = std::env::current_dir().context("reading the current folder")?;
    session().command = Some(RecordedCommand { args, cwd });
    Ok(())
}

/// Create the run folder of a `track`, `predict` or `solve` run: its staging folder takes
/// the command line and the solver's checkpoints, so a killed run can be resumed.
pub fn create_checkpointed_run_folder(out: &Path, overwrite: bool) -> anyhow::Result<RunFolder> {
    // the interrupted run folder being resumed is replaced by the resumed run's
    let replaces = session().replaces.take();
    let resumed_here = replaces.is_some() && out.canonicalize().ok() == replaces;
    let folder = RunFolder::create(out, overwrite || resumed_here)?;
    let mut s = session();
    if let Some(cmd) = &s.command {
        folder.write(COMMAND_FILE, serde_json::to_string_pretty(cmd)?.as_bytes())?;
    }
    // a resumed run's checkpoints move into the new staging folder at once, so that a
    // second kill before the next iteration still leaves them
    for (k, cp) in &s.resume {
        folder.write(&checkpoint_file(*k), serde_json::to_string(cp)?.as_bytes())?;
    }
    s.checkpoint_dir = Some(folder.staging_path().to_path_buf());
    Ok(folder)
}

/// Wraps an SQP observer: a stop asked ends the solve (at the latest after the current
/// iteration), and checkpoints go to the run's staging folder.
struct Interruptible<'a, 'j> {
    progress: &'a dyn Progress,
    checkpoints: Option<(PathBuf, String)>,
    /// The judge at the solve's milestone ([`crate::sqp::Observer::milestone`]).
    judge: Option<Judge<'j>>,
}

/// Whether a solve at its milestone ([`SqpSettings::milestone_tol`]) goes on, given its
/// iterate.
pub type Judge<'a> = &'a mut dyn FnMut(&[f64]) -> bool;

impl Observer for Interruptible<'_, '_> {
    fn iteration(&mut self, rec: &IterationRecord) -> bool {
        self.progress.iteration(rec);
        !crate::interrupt::requested()
    }
    fn wants_checkpoints(&self) -> bool {
        self.checkpoints.is_some()
    }
    fn note(&mut self, text: &str) {
        self.progress.note(text);
    }
    fn milestone(&mut self, w: &[f64]) -> bool {
        self.judge.as_mut().is_none_or(|judge| judge(w))
    }
    fn checkpoint(&mut self, state: &SqpCheckpoint) {
        let Some((dir, name)) = &self.checkpoints else {
            return;
        };
        let written = serde_json::to_string(state)
            .map_err(anyhow::Error::from)
            .and_then(|text| Ok(runfolder::write_atomic(dir, name, text.as_bytes())?));
        if let Err(e) = written {
            // the solve goes on; only resuming it would be lost
            warn_note!(
                self.progress,
                "warning: checkpoint not written ({e}); this run cannot be resumed if it is killed"
            );
            self.checkpoints = None;
        }
    }
}

/// Solve `nlp` from `w0`, stopping when asked ([`crate::interrupt`]), logging each
/// iteration to stderr unless `progress`; checkpointed in a run folder made by [`create_checkpointed_run_folder`], and
/// continued from the killed run's checkpoint when resuming.
pub fn solve_interruptibly(
    nlp: &dyn Nlp,
    w0: &[f64],
    settings: &SqpSettings,
    progress: &dyn Progress,
) -> anyhow::Result<SqpResult> {
    solve_interruptibly_warm(nlp, w0, None, settings, progress, None)
}

/// [`solve_interruptibly`] from the multipliers `warm` ([`crate::sqp::solve_warm`]).
pub fn solve_interruptibly_warm(
    nlp: &dyn Nlp,
    w0: &[f64],
    warm: Option<crate::sqp::WarmStart<'_>>,
    settings: &SqpSettings,
    progress: &dyn Progress,
    judge: Option<Judge<'_>>,
) -> anyhow::Result<SqpResult> {
    let index = SOLVES.fetch_add(1, Ordering::SeqCst);
    let (resume, checkpoints) = {
        let mut s = session();
        (
            s.resume.remove(&index),
            s.checkpoint_dir
                .clone()
                .map(|d| (d, checkpoint_file(index))),
        )
    };
    let mut observer = Interruptible {
        progress,
        checkpoints,
        judge,
    };
    let res = match &resume {
        Some(cp) => {
            cp.check(nlp.n(), nlp.m())
                .context("resuming: the checkpoint does not fit the problem")?;
            {
                note!(
                    progress,
                    "resuming at iteration {} from the killed run's checkpoint",
                    cp.next_iter
                );
            }
            crate::sqp::solve_resumed(nlp, cp, settings, &mut observer)
        }
        None => match warm {
            Some(ws) => crate::sqp::solve_warm(nlp, w0, ws, settings, &mut observer),
            None => crate::sqp::solve(nlp, w0, settings, &mut observer),
        },
    };
    Ok(res)
}

/// The arguments of this invocation with `--resume DIR` removed, and DIR.
fn split_resume(args: &[String]) -> (Vec<String>, Option<String>) {
    let mut rest = Vec::new();
    let mut dir = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "--resume" {
            dir = it.next().cloned();
        } else if let Some(d) = a.strip_prefix("--resume=") {
            dir = Some(d.to_string());
        } else {
            rest.push(a.clone());
        }
    }
    (rest, dir)
}

/// Prepare to resume the killed run whose output folder is `dir`: check that no other
/// option was given, load its checkpoints, move into its working folder, and return its
/// command line (arguments after the program name).
pub fn prepare_resume(subcommand: &str, args: &[String]) -> anyhow::Result<Vec<String>> {
    let (rest, dir) = split_resume(args);
    let dir = dir.ok_or_else(|| anyhow!("--resume needs the output folder of the killed run"))?;
    let others: Vec<&String> = rest
        .iter()
        .filter(|a| a.as_str() != subcommand && a.as_str() != "--quiet")
        .collect();
    if !others.is_empty() {
        bail!(
            "--resume continues a run with the options it was started with; give no other options (found {})",
            others.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(" ")
        );
    }
    let target = PathBuf::from(&dir);
    let stale: Vec<PathBuf> = runfolder::stale_staging(&target)
        .into_iter()
        .map(|(p, _)| p)
        .filter(|p| p.join(COMMAND_FILE).is_file())
        .collect();
    // the newest, if several runs into the same folder were killed
    let newest = stale.iter().max_by_key(|p| {
        std::fs::metadata(p.join(COMMAND_FILE))
            .and_then(|m| m.modified())
            .ok()
    });
    // else an interrupted run's folder, which keeps its checkpoints
    let interrupted = (target.join(runfolder::MARKER).is_file()
        && target.join(COMMAND_FILE).is_file())
    .then_some(&target);
    let Some(staging) = newest.or(interrupted) else {
        bail!(
            "{dir}: no killed or interrupted run to resume (a killed run leaves a hidden staging folder .NAME.partial-PID beside the output folder, an interrupted one its checkpoints in the run folder; a run that finished or failed has none)"
        );
    };
    let replaces = match newest {
        Some(_) => None,
        None => Some(target.canonicalize().with_context(|| dir.clone())?),
    };
    let text = std::fs::read_to_string(staging.join(COMMAND_FILE))
        .with_context(|| staging.join(COMMAND_FILE).display().to_string())?;
    let cmd: RecordedCommand = serde_json::from_str(&text)
        .with_context(|| staging.join(COMMAND_FILE).display().to_string())?;
    if cmd
        .args
        .iter()
        .find(|a| !a.starts_with('-'))
        .map(String::as_str)
        != Some(subcommand)
    {
        bail!(
            "{dir}: the killed run was not a `footfall {subcommand}` run (it was `footfall {}`)",
            cmd.args.join(" ")
        );
    }
    let mut resume = BTreeMap::new();
    for entry in std::fs::read_dir(staging)
        .with_context(|| staging.display().to_string())?
        .flatten()
    {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(k) = name
            .strip_prefix(&format!("{RESUME_PREFIX}checkpoint-"))
            .and_then(|r| r.strip_suffix(".json"))
        else {
            continue;
        };
        let Ok(k) = k.parse::<usize>() else { continue };
        let text = std::fs::read_to_string(entry.path())
            .with_context(|| entry.path().display().to_string())?;
        let cp: SqpCheckpoint = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a footfall checkpoint", entry.path().display()))?;
        cp.check_finite()
            .with_context(|| entry.path().display().to_string())?;
        resume.insert(k, cp);
    }
    std::env::set_current_dir(&cmd.cwd)
        .with_context(|| format!("resuming in the run's working folder {}", cmd.cwd.display()))?;
    let mut s = session();
    s.resume = resume;
    s.command = Some(cmd.clone());
    s.replaces = replaces;
    Ok(cmd.args)
}
