//! `footfall report RUN`: re-evaluate a track run's solution and rewrite its run folder —
//! errors per channel and phase, where the cost comes from, the worst stretches, the
//! residual actuators, plots with the phases shaded — without solving again. Useful after
//! an upgrade of footfall, or to write the report somewhere else; the solver's own figures
//! (status, iterations, KKT residual, time) are carried over from the run's summary.

use super::track::{read_run_setup, RunWriting, TrackingProblem};
#[allow(unused_imports)]
use super::{note, result_note, warn_note, Progress};
use crate::report::run_summary::RunSummaryFile;
use crate::runfolder::RunFolder;
use crate::sqp::{IterationRecord, SqpResult, SqpStatus, SqpTimings, Violation};
use anyhow::{anyhow, bail, Context};
use std::path::{Path, PathBuf};

/// What `report` does: the arguments of `footfall report`.
#[derive(Debug, Clone)]
pub struct ReportRequest {
    /// A track run folder (with setup.json, solution.json and summary.json); or two or
    /// more run folders of `track` or `predict` to set side by side in one report.
    pub runs: Vec<PathBuf>,
    /// Output folder (default for one run: the run folder itself, replaced as a whole
    /// once the new report is complete; required for several runs).
    pub out: Option<PathBuf>,
    /// Replace `--out` if it exists.
    pub overwrite: bool,
    /// Report ground-force excursions above the measurement larger than this (N).
    pub transient_threshold: f64,
}

/// Relative objective difference above which the re-evaluation does not reproduce the
/// run (the model, foot, phases or data changed since).
const OBJECTIVE_MISMATCH: f64 = 1e-6;

/// The solver's figures as the run recorded them in `summary.json`.
struct SolverRecord {
    status: SqpStatus,
    objective: f64,
    kkt: f64,
    seconds: f64,
    timings: SqpTimings,
    history: Vec<IterationRecord>,
    most_violated: Vec<Violation>,
}

fn read_record(run: &Path) -> anyhow::Result<SolverRecord> {
    let file = run.join("summary.json");
    if !file.is_file() {
        bail!("{}: not found (a track run folder has one; it holds the solver's figures the report carries over)", file.display());
    }
    let s = RunSummaryFile::read(&file)?;
    if s.command.as_deref() != Some("track") {
        bail!(
            "{}: field `command` is {}, expected \"track\" (footfall report rewrites track runs)",
            file.display(),
            s.command.map_or("missing".into(), |c| format!("{c:?}"))
        );
    }
    let need = |v: Option<f64>, field: &str| {
        v.ok_or_else(|| {
            anyhow!(
                "{}: field `{field}`: missing (a track run records it)",
                file.display()
            )
        })
    };
    Ok(SolverRecord {
        status: s.status.clone().ok_or_else(|| {
            anyhow!(
                "{}: field `status`: missing (a track run records it)",
                file.display()
            )
        })?,
        objective: need(s.objective, "objective")?,
        kkt: need(s.kkt, "kkt")?,
        seconds: need(s.seconds, "seconds")?,
        timings: s.timings,
        history: s.history,
        most_violated: s.most_violated,
    })
}

/// The arguments for re-writing one run.
struct OneRun {
    run: PathBuf,
    out: Option<PathBuf>,
    overwrite: bool,
    transient_threshold: f64,
}

/// `footfall report RUN_A RUN_B … --out DIR`: the runs' curves on the same plots and
/// their errors side by side, read from their files.
fn side_by_side(args: &ReportRequest, progress: &dyn Progress) -> anyhow::Result<()> {
    let Some(out) = &args.out else {
        bail!("--out: required with several runs (the side-by-side report gets its own folder; the run folders are left as they are)");
    };
    let mut runs = Vec::new();
    for r in &args.runs {
        if !r.is_dir() {
            bail!("{}: not a run folder (give folders that `footfall track` or `footfall predict` wrote)", r.display());
        }
        runs.push(crate::report::runs::RunCurves::read(r)?);
    }
    let folder = RunFolder::create(out, args.overwrite)?;
    let report = crate::report::runs::side_by_side(&runs);
    let listing = serde_json::json!({
        "command": "report",
        "runs": args.runs.iter().zip(&runs).map(|(p, r)| serde_json::json!({"path": p, "name": r.name, "verdict": r.verdict})).collect::<Vec<_>>(),
    });
    folder.write(
        "runs.json",
        serde_json::to_string_pretty(&listing)?.as_bytes(),
    )?;
    folder.write("report.html", report.to_html().as_bytes())?;
    let path = folder.commit()?;
    {
        note!(progress, "report: {}", path.join("report.html").display());
    }
    Ok(())
}

/// Run `report` as `args` describes, reporting to `progress`.
pub fn run(args: &ReportRequest, progress: &dyn Progress) -> anyhow::Result<()> {
    if args.runs.len() > 1 {
        return side_by_side(&args, progress);
    }
    let args = OneRun {
        run: args.runs[0].clone(),
        out: args.out.clone(),
        overwrite: args.overwrite,
        transient_threshold: args.transient_threshold,
    };
    if !args.run.is_dir() {
        bail!(
            "{}: not a run folder (give the folder a `footfall track` run wrote)",
            args.run.display()
        );
    }
    let setup = read_run_setup(&args.run)?;
    let solution = super::read_solution(&args.run)?;
    let record = read_record(&args.run)?;
    let mut prob = TrackingProblem::build(&setup, &[])?;
    prob.setup
        .start_from(&solution)
        .map_err(|e| anyhow!("{}: {e}", args.run.join("solution.json").display()))?;
    let (out, overwrite) = match &args.out {
        Some(o) => (o.clone(), args.overwrite),
        None => (args.run.clone(), true),
    };
    let folder = RunFolder::create(&out, overwrite)?;
    let base = crate::problems::diagnose::TrackingRunSetup {
        parameters: vec![],
        ..setup.clone()
    };
    let run = prob.with_transcription(|tr, cycle, w| {
        let ev = tr.evaluate(&w, true).context("evaluating the run's solution")?;
        let (lo, hi) = tr.constraint_bounds();
        let infeasibility = crate::sqp::violations(&ev.c, &lo, &hi).into_iter().fold(0.0, f64::max);
        let mismatch = (ev.f - record.objective).abs() / record.objective.abs().max(1e-12);
        if mismatch > OBJECTIVE_MISMATCH {
            bail!(
                "{}: the solution re-evaluates to J = {:.8} but the run recorded J = {:.8} (relative difference {mismatch:.1e}): the model, foot, phases or data changed since the run; re-run `footfall track` instead",
                args.run.display(),
                ev.f,
                record.objective
            );
        }
        let res = SqpResult {
            w,
            lambda: vec![],
            nu: vec![],
            objective: ev.f,
            infeasibility,
            kkt: record.kkt,
            status: record.status,
            history: record.history,
            most_violated: record.most_violated,
            seconds: record.seconds,
            timings: record.timings,
        };
        let provenance = format!("re-evaluated from {} by footfall report (J reproduced to {mismatch:.0e}); solver figures as the run recorded them", args.run.join("solution.json").display());
        prob.write_run(tr, cycle, res, RunWriting { base: &base, extra: &[], folder, transient_threshold: args.transient_threshold, progress: &super::WarningsOnly(progress), provenance: Some(provenance), check_sites: &prob.check_sites })
    })?;
    {
        result_note!(progress, "{}", run.output.table.to_markdown());
        if let Some(b) = &run.breakdown {
            let (share, normalised, windows) = crate::report::tracking::cost_tables(b);
            result_note!(
                progress,
                "{}\n{}\n{}",
                share.to_markdown(),
                normalised.to_markdown(),
                windows.to_markdown()
            );
        }
        if let Some(r) = &run.residuals {
            for t in &r.tables {
                result_note!(progress, "{}", t.to_markdown());
            }
        }
        note!(
            progress,
            "report: {}",
            run.output.path.join("report.html").display()
        );
    }
    Ok(())
}
