//! The user's workflows as library calls: track, predict, compare, synth and diagnose
//! (and the report of a run), each taking a setup struct and returning a result struct,
//! reporting progress through a [`Progress`] observer, and writing run folders through one
//! writer ([`run_folder`]). The command line (`src/cli/`) parses arguments into these
//! structs, prints what the observer receives and maps the errors to exit codes.
//!
//! Errors are `anyhow` chains whose root says what kind of failure it was: an
//! [`Unsolved`] solve (with the solver's status), a physically [`Invalid`] solution, or
//! anything else (bad input, I/O).

pub mod check;
pub mod compare;
pub mod compare_contact;
pub mod diagnose;
pub mod diff;
pub mod fit_foot;
pub mod inputs;
pub mod predict;
pub mod refine;
pub mod report;
pub mod run_folder;
pub mod session;
pub mod simulate;
pub mod solve;
pub mod study;
pub mod synth;
pub mod track;
pub mod trial;

use crate::data::GaitData;
use crate::problems::evaluation::GaitSolution;
use crate::sqp::{IterationRecord, SqpStatus};
use anyhow::{bail, Context};
use std::path::{Path, PathBuf};

pub use session::{solve_interruptibly, solve_interruptibly_warm, Judge};

/// Where a workflow reports what it is doing.
///
/// `Sync`, so that a workflow may report from worker threads.
pub trait Progress: Sync {
    /// A line of news: what is being solved, a stage that starts, a result.
    fn note(&self, text: &str);
    /// Something the user should see even when news is not wanted (a warning).
    fn warn(&self, text: &str) {
        self.note(text)
    }
    /// An SQP iteration (iteration 0 is the starting point).
    fn iteration(&self, _rec: &IterationRecord) {}
    /// A result to show the user (the command line prints it on standard output).
    fn result(&self, text: &str) {
        self.note(text)
    }
}

/// Progress that goes nowhere (warnings included).
pub struct Quiet;

impl Progress for Quiet {
    fn note(&self, _text: &str) {}
}

/// Only the warnings of another progress (for a step whose news would repeat the
/// caller's).
pub struct WarningsOnly<'a>(pub &'a dyn Progress);

impl Progress for WarningsOnly<'_> {
    fn note(&self, _text: &str) {}
    fn warn(&self, text: &str) {
        self.0.warn(text)
    }
}

/// Which of a front end's streams a line of progress goes to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stream {
    /// Results (the command line's standard output).
    Results,
    /// News, the SQP's iteration table and warnings (standard error).
    Messages,
}

/// Progress as lines of text, for a front end that shows them (the command line, the
/// Python binding): news, the SQP's iteration table and results unless quiet, warnings
/// always, each line handed to `write` with the stream it belongs to.
#[derive(Clone, Copy)]
pub struct TextProgress {
    /// Only warnings.
    pub quiet: bool,
    /// Shows a line.
    pub write: fn(Stream, &str),
}

impl Progress for TextProgress {
    fn note(&self, text: &str) {
        if !self.quiet {
            (self.write)(Stream::Messages, text);
        }
    }
    fn warn(&self, text: &str) {
        (self.write)(Stream::Messages, text);
    }
    fn result(&self, text: &str) {
        if !self.quiet {
            (self.write)(Stream::Results, text);
        }
    }
    fn iteration(&self, rec: &IterationRecord) {
        if !self.quiet {
            if rec.iter == 0 {
                (self.write)(Stream::Messages, &IterationRecord::table_head());
            }
            (self.write)(Stream::Messages, &rec.table_row());
        }
    }
}

/// Progress kept in memory: notes, warnings and iterations, in order (for tests and
/// notebooks).
#[derive(Default)]
pub struct Collected {
    /// Every note and warning.
    pub lines: std::sync::Mutex<Vec<String>>,
    /// Every SQP iteration.
    pub iterations: std::sync::Mutex<Vec<IterationRecord>>,
}

impl Progress for Collected {
    fn note(&self, text: &str) {
        self.lines
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .push(text.to_string());
    }
    fn iteration(&self, rec: &IterationRecord) {
        self.iterations
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .push(rec.clone());
    }
}

/// A formatted note to a [`Progress`].
macro_rules! note {
    ($p:expr, $($t:tt)*) => {
        $p.note(&format!($($t)*))
    };
}
/// A formatted warning to a [`Progress`].
macro_rules! warn_note {
    ($p:expr, $($t:tt)*) => {
        $p.warn(&format!($($t)*))
    };
}
/// A formatted result to a [`Progress`].
macro_rules! result_note {
    ($p:expr, $($t:tt)*) => {
        $p.result(&format!($($t)*))
    };
}
pub(crate) use {note, result_note, warn_note};

/// A model file and a foot (`ellipse`, `double-circle` or a foot file).
#[derive(Debug, Clone)]
pub struct ModelFiles {
    /// Model file (JSON).
    pub model: PathBuf,
    /// Foot: `ellipse`, `double-circle` or a foot file (JSON).
    pub foot: String,
}

/// Write `value` as pretty JSON to `name` in the run folder's staging area.
pub fn write_json(
    folder: &crate::runfolder::RunFolder,
    name: &str,
    value: &impl serde::Serialize,
) -> anyhow::Result<()> {
    folder.write(name, serde_json::to_string_pretty(value)?.as_bytes())?;
    Ok(())
}

/// The foot file of a foot argument: `ellipse`, `double-circle` or a file.
pub fn foot_path(arg: &str) -> PathBuf {
    match arg {
        "ellipse" => PathBuf::from("models/feet/ellipse.json"),
        "double-circle" | "double_circle" => PathBuf::from("models/feet/double_circle.json"),
        other => PathBuf::from(other),
    }
}

/// The default phase file of a foot argument: the phase graphs of Millard & Mombaur (2019) for the bundled feet, the
/// single continuous phase of `phases/volumetric_ellipse_walk.json` for a foot file whose
/// primitives are all volumetric (no contact constraints, so it fits any such foot), else
/// the ellipse's graph.
pub fn default_phases(foot: &str) -> PathBuf {
    match foot {
        "double-circle" | "double_circle" => PathBuf::from("phases/double_circle_walk.json"),
        "ellipse" => PathBuf::from("phases/ellipse_walk.json"),
        file if all_volumetric(Path::new(file)) => {
            PathBuf::from("phases/volumetric_ellipse_walk.json")
        }
        _ => PathBuf::from("phases/ellipse_walk.json"),
    }
}

/// Whether the foot file `path` has primitives and every one says `"contact": {"type":
/// "volumetric", …}` (false for a file that cannot be read; loading it reports why).
fn all_volumetric(path: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(crate::bundled::resolve(path)) else {
        return false;
    };
    let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) else {
        return false;
    };
    v["primitives"]
        .as_array()
        .is_some_and(|ps| !ps.is_empty() && ps.iter().all(|p| p["contact"]["type"] == "volumetric"))
}

/// A solution from a run folder (`solution.json` inside) or a solution file.
pub fn read_solution(path: &Path) -> anyhow::Result<GaitSolution> {
    if !path.exists() {
        bail!("{}: no such run folder or solution file (give a track or predict run folder, or its solution.json)", path.display());
    }
    let file = if path.is_dir() {
        path.join("solution.json")
    } else {
        path.to_path_buf()
    };
    let text = std::fs::read_to_string(&file)
        .with_context(|| format!("reading the initial solution {}", file.display()))?;
    serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: not a footfall solution (expected the solution.json of a track or predict run)",
            file.display()
        )
    })
}

/// Measured data from a sagittal CSV (moved overground when its meta file gives a belt
/// speed), or the bundled trial; its units and conventions checked
/// ([`GaitData::check_conventions`]; `overground`: take a trial without a belt speed as
/// it is).
///
/// A `.mot`/`.sto` path needs its forces: read it with [`trial::load_trial`].
pub fn load_data(path: Option<&Path>, overground: bool) -> anyhow::Result<GaitData> {
    Ok(trial::load_trial(&trial::TrialFiles::csv(
        path.map(Path::to_path_buf),
        overground,
    ))?
    .data)
}

/// The error of a written gait run (`track`, `predict`) whose solve `res` did not
/// converge ([`Unsolved`]) or whose solution breaks physics on the 1 ms grid
/// ([`Invalid`]).
pub fn check_run(
    out: &run_folder::GaitRunOutput,
    res: &crate::sqp::SqpResult,
) -> anyhow::Result<()> {
    Unsolved::check(res, &out.path)?;
    Invalid::check(out)
}

/// A converged solution that breaks physics on the 1 ms grid (exit 5).
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct Invalid {
    /// What to print.
    pub message: String,
}

impl Invalid {
    /// The error of a written gait run that converged but is physically invalid.
    pub fn check(out: &run_folder::GaitRunOutput) -> anyhow::Result<()> {
        match &out.validity {
            Some(v) if !v.is_valid() => Err(Invalid {
                message: format!(
                    "converged, physically invalid: {} (results written to {})",
                    v.violations
                        .iter()
                        .map(|x| x.to_string())
                        .collect::<Vec<_>>()
                        .join("; "),
                    out.path.display()
                ),
            }
            .into()),
            _ => Ok(()),
        }
    }
}

/// A solve that stopped without converging; its status picks the exit code.
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct Unsolved {
    /// Why the solver stopped.
    pub status: SqpStatus,
    /// Whether it stopped at the initial point, before any iteration.
    pub at_start: bool,
    /// What to print.
    pub message: String,
}

impl Unsolved {
    /// The error of a solve that ended with `res` (None when it converged); `written`
    /// names the run folder.
    pub fn check(res: &crate::sqp::SqpResult, written: &std::path::Path) -> anyhow::Result<()> {
        if res.status == SqpStatus::Converged {
            return Ok(());
        }
        Err(Unsolved {
            status: res.status.clone(),
            at_start: res.history.is_empty(),
            message: format!(
                "the solver stopped without converging: {} (results written to {})",
                res.status,
                written.display()
            ),
        }
        .into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_all_volumetric_foot_defaults_to_the_continuous_phase_graph() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let vol = root.join("models/feet/volumetric_ellipse.json");
        assert_eq!(
            default_phases(vol.to_str().unwrap()),
            PathBuf::from("phases/volumetric_ellipse_walk.json")
        );
        let rigid = root.join("models/feet/ellipse.json");
        assert_eq!(
            default_phases(rigid.to_str().unwrap()),
            PathBuf::from("phases/ellipse_walk.json")
        );
        assert_eq!(
            default_phases("double-circle"),
            PathBuf::from("phases/double_circle_walk.json")
        );
        // a file that cannot be read keeps the ellipse's graph (loading the foot says why)
        assert_eq!(
            default_phases("no/such/foot.json"),
            PathBuf::from("phases/ellipse_walk.json")
        );
    }
}

/// The error and its causes joined by ": ", skipping a cause whose text the message
/// already contains (library errors often quote their cause).
pub fn error_text(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if out.is_empty() {
            out = text;
        } else if !out.contains(&text) {
            out.push_str(": ");
            out.push_str(&text);
        }
    }
    out
}
