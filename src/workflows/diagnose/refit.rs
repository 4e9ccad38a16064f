//! The re-fits of `diagnose`: a candidate's verifying re-fit written as a track run
//! folder, the heel pad's test by a full re-fit (it has no null value) and what a re-fit
//! changed, channel by channel, in one sentence.

use super::{note, sibling, Baseline, DiagnoseRequest, Progress};
use crate::model::effects::EffectSpec;
use crate::problems::diagnose::{refit_test, IdentifiedParameter, ScoreTest, TrackingRunSetup};
use crate::problems::evaluation::GaitSolution;
use crate::report::diff::{RunDiff, RunSummary};
use crate::runfolder::RunFolder;
use crate::sqp::HessianMode;
use crate::workflows::track::{tracking_sqp_settings, TrackedRun, TrackingProblem};
use anyhow::anyhow;
use std::path::PathBuf;

/// A verified candidate: its re-fit run and what changed.
pub(super) struct Verified {
    pub(super) test: ScoreTest,
    pub(super) folder: PathBuf,
    pub(super) converged: bool,
    pub(super) objective_before: f64,
    pub(super) objective_after: f64,
    pub(super) parameters: Vec<(String, f64, Option<f64>, String)>,
    pub(super) diff: RunDiff,
    pub(super) sentence: String,
}

/// Per-channel errors of the run `before` against its re-fit `run`.
pub(super) fn diff_with(before: &RunSummary, run: &TrackedRun) -> anyhow::Result<RunDiff> {
    Ok(RunDiff::new(
        before,
        &RunSummary::read(&run.output.path)?,
        5.0,
    ))
}

impl Verified {
    /// What the re-fit `run` of candidate `test` changed (`diff`) against the run before
    /// it (cost `objective`).
    pub(super) fn new(test: &ScoreTest, run: &TrackedRun, diff: RunDiff, objective: f64) -> Self {
        let parameters = run
            .record
            .parameters
            .iter()
            .filter(|p| test.parameters.contains(&p.name))
            .map(|p| (p.name.clone(), p.value, p.sd, p.unit.clone()))
            .collect();
        Verified {
            sentence: sentence(&test.label, &diff),
            test: test.clone(),
            folder: run.output.path.clone(),
            converged: run.converged,
            objective_before: objective,
            objective_after: run.result.objective,
            parameters,
            diff,
        }
    }
}

/// What a candidate's test left: the point of its truncated re-fit (where a verifying
/// re-fit starts), or the full re-fit of a candidate without a null value with its
/// per-channel errors against the run.
pub(super) enum Evidence {
    Start(GaitSolution),
    Refit(Box<TrackedRun>, RunDiff),
}

/// The run's re-fit with `effect` added, from `start` (the run's solution, the effect's
/// parameters at their initial values, or a truncated re-fit's point), written to
/// `<RUN>+<effect>`.
pub(super) fn refit(
    args: &DiagnoseRequest,
    setup: &TrackingRunSetup,
    effect: &EffectSpec,
    start: &GaitSolution,
    progress: &dyn Progress,
) -> anyhow::Result<TrackedRun> {
    let dir = sibling(&args.run, &format!("+{}", effect.kind()));
    refit_into(args, setup, effect, start, dir, progress)
}

/// [`refit`] into the run folder `dir`.
fn refit_into(
    args: &DiagnoseRequest,
    setup: &TrackingRunSetup,
    effect: &EffectSpec,
    start: &GaitSolution,
    dir: PathBuf,
    progress: &dyn Progress,
) -> anyhow::Result<TrackedRun> {
    {
        note!(
            progress,
            "re-fitting with {} → {}",
            effect.label(),
            dir.display()
        );
    }
    solve_into(
        args,
        setup,
        std::slice::from_ref(effect),
        start,
        dir,
        progress,
    )
}

/// Track `setup` with `effects` added, from `start`, into the run folder `dir` (a
/// candidate's re-fit).
pub(super) fn solve_into(
    args: &DiagnoseRequest,
    setup: &TrackingRunSetup,
    effects: &[EffectSpec],
    start: &GaitSolution,
    dir: PathBuf,
    progress: &dyn Progress,
) -> anyhow::Result<TrackedRun> {
    let mut prob = TrackingProblem::build(setup, effects)?;
    // a kept solution of this problem (`--start`) starts it instead, when it fits
    let want = TrackingRunSetup {
        effects: setup.effects.iter().chain(effects).cloned().collect(),
        ..setup.clone()
    };
    let started = super::starts::start_from_kept(
        args,
        &want,
        &mut prob,
        || TrackingProblem::build(setup, effects),
        "starting where the diagnosis got to",
        progress,
    )?;
    if !started {
        prob.start_at(start)
            .map_err(|e| anyhow!("{}: {e:#}", args.run.display()))?;
    }
    let settings = full_solve_settings(args, &prob);
    let rf = RunFolder::create(&dir, args.overwrite)?;
    prob.solve_and_write(
        setup,
        effects,
        &settings,
        rf,
        crate::workflows::run_folder::DEFAULT_TRANSIENT_THRESHOLD_N,
        progress,
    )
}

/// Sample targets per shooting interval above which the diagnosis's own solves use the
/// Gauss–Newton Hessian ([`solve_hessian`]).
pub(super) const GAUSS_NEWTON_SAMPLES_PER_INTERVAL: f64 = 3.0;

/// The settings of a full solve of `prob` in a diagnosis: its tolerance and iteration
/// limit, the Hessian [`solve_hessian`] picks, and the default switch to the exact one.
pub(super) fn full_solve_settings(
    args: &DiagnoseRequest,
    prob: &TrackingProblem,
) -> crate::sqp::SqpSettings {
    tracking_sqp_settings(args.tol, args.max_iter, None, solve_hessian(prob), None)
}

/// The Hessian of the diagnosis's own solves (re-fits, held-out half cycles). The exact Hessian converges in fewer iterations, but with sample targets its
/// curvature is integrated piece by piece between an interval's samples, so an iteration
/// costs more the more samples an interval holds; Gauss–Newton's costs the same. Measured
/// on the double-circle heel pad's re-fit (release build, `diagnose --candidate
/// heel_pad_compliance`): on the 100 Hz trial without a hidden effect (about one sample per
/// interval) exact takes 22 iterations (47 s) against Gauss–Newton's 49 (67 s), to the same
/// J and pad to six digits; on the 1 kHz pad trial (about ten) exact takes 17 (116 s)
/// against 18 (51 s; both with another job beside). So exact, unless the samples outnumber
/// the intervals [`GAUSS_NEWTON_SAMPLES_PER_INTERVAL`] times and the foot is rigid. A
/// compliant foot's solves take the exact mode's Gauss–Newton steps until they stall and
/// its curvature after (integrated backward), where Gauss–Newton alone can stop at its
/// iteration limit with the constraints still violated.
pub(super) fn solve_hessian(prob: &TrackingProblem) -> HessianMode {
    if prob.model.has_volumetric_contacts() {
        return HessianMode::Exact;
    }
    let intervals: usize = prob
        .setup
        .node_times
        .iter()
        .map(|t| t.len().saturating_sub(1))
        .sum();
    let per_interval = prob.setup.samples.len() as f64 / intervals.max(1) as f64;
    if per_interval > GAUSS_NEWTON_SAMPLES_PER_INTERVAL {
        HessianMode::GaussNewton
    } else {
        HessianMode::Exact
    }
}

/// Test of the heel pad by a full re-fit ([`refit_test`]); its channel errors before and
/// after are the re-fit's (returned too, for its verification).
pub(super) fn test_by_refit(
    args: &DiagnoseRequest,
    setup: &TrackingRunSetup,
    effect: &EffectSpec,
    base: &Baseline<'_>,
    progress: &dyn Progress,
) -> anyhow::Result<(ScoreTest, TrackedRun, RunDiff)> {
    let Baseline {
        solution,
        summary: before,
        objective,
        rows,
    } = *base;
    let run = refit(args, setup, effect, solution, progress)?;
    let added: Vec<&IdentifiedParameter> = run
        .record
        .parameters
        .iter()
        .filter(|p| p.free && p.name.starts_with(&format!("{}.", effect.kind())))
        .collect();
    let names = added.iter().map(|p| p.name.clone()).collect();
    let values = added.iter().map(|p| p.value).collect();
    let mut t = refit_test(
        effect,
        names,
        values,
        objective,
        run.result.objective,
        rows,
        run.result.history.len().saturating_sub(1),
    );
    let diff = diff_with(before, &run)?;
    t.expected_channels = channel_changes(&diff);
    Ok((t, run, diff))
}

/// Each channel's mean error before and after a re-fit, from its diff against the run:
/// `(channel, unit, before, after)`, as a test's `expected_channels`.
fn channel_changes(diff: &RunDiff) -> Vec<(String, String, f64, f64)> {
    diff.channels
        .iter()
        .filter_map(|c| {
            Some((
                c.channel.clone(),
                c.unit.clone(),
                c.a.as_ref()?.mean,
                c.b.as_ref()?.mean,
            ))
        })
        .collect()
}

/// "ground slope explains 71 % of the tangential GRF error (…), most in phase 2e (…)".
pub(super) fn sentence(label: &str, diff: &RunDiff) -> String {
    let best = diff
        .channels
        .iter()
        .filter_map(|c| Some((c, c.a.as_ref()?.mean, c.b.as_ref()?.mean)))
        .filter(|(_, a, b)| *a > 0.0 && b < a)
        .max_by(|x, y| ((x.1 - x.2) / x.1).total_cmp(&((y.1 - y.2) / y.1)));
    let Some((c, a, b)) = best else {
        return format!("{label} does not reduce the mean error of any channel");
    };
    let mut s = format!(
        "{label} explains {:.0} % of the {} error ({a:.3} → {b:.3} {})",
        100.0 * (a - b) / a,
        c.channel,
        c.unit
    );
    let phase = c
        .phases
        .iter()
        .filter_map(|p| Some((p, p.mean_a?, p.mean_b?)))
        .filter(|(_, a, b)| *a > 0.0 && b < a)
        .max_by(|x, y| ((x.1 - x.2) / x.1).total_cmp(&((y.1 - y.2) / y.1)));
    if let Some((p, pa, pb)) = phase {
        s += &format!(
            ", {:.0} % in phase {} ({pa:.3} → {pb:.3})",
            100.0 * (pa - pb) / pa,
            p.phase
        );
    }
    s
}
