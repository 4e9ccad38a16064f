//! `footfall diagnose RUN`: which effect of the catalog is the model of a tracking run
//! missing? For every candidate: is it testable with the run's cost at all (reduced
//! Fisher information), its score test at the run's solution (a full re-fit for the
//! heel pad, which has no null value) with the statistic corrected for correlated
//! residuals; the significant ones are validated on another half cycle of the trial
//! (`diagnose/heldout.rs`) and the top found ones re-fitted for real (each written as a track run
//! folder, so `diff` and a second `diagnose` can start from it). The instruments and the
//! body are not among the candidates: the measurement stage (`footfall check`, the trial's
//! own Newton–Euler balance) reads them without a contact model, and its verdict is shown
//! first.

use super::track::{read_run_setup, TrackingProblem};
#[allow(unused_imports)]
use super::{note, warn_note, Progress};
use crate::model::effects::{catalog, EffectSpec};
use crate::model::GaitModel;
use crate::problems::diagnose::stats::{candidate_identifiability_at, variance_inflation};
use crate::problems::diagnose::{
    channel_means, channel_series, gauss_newton_decrease, refit_point, score_test_from, ScoreTest,
    TrackingRunSetup,
};

mod heldout;
mod output;
mod refit;
mod starts;
pub mod summary;
use crate::ocp::Transcription;
use crate::problems::evaluation::GaitSolution;
use crate::report::diff::RunSummary;
use crate::runfolder::RunFolder;
use crate::sqp::linearised::GaussNewtonModel;
use anyhow::anyhow;
use rayon::prelude::*;
use refit::{diff_with, refit, test_by_refit, Evidence, Verified};
use std::path::{Path, PathBuf};

/// The `--candidate` name that stands for the default candidates: the catalog, the heel
/// pad on a foot with a heel circle and the contact law on a volumetric foot.
pub const CATALOG: &str = "catalog";

/// What `diagnose` does: the arguments of `footfall diagnose`.
#[derive(Debug, Clone)]
pub struct DiagnoseRequest {
    /// A track run folder.
    pub run: PathBuf,
    /// Re-fit this many of the top significant candidates to verify them.
    pub verify: usize,
    /// Only these candidates (effect names or `NAME:key=value,…`; default: the catalog).
    /// [`CATALOG`] among them stands for the default set, so that others can be added to
    /// it (`catalog`, `foot_geometry`).
    pub candidates: Vec<String>,
    /// Output folder (default: `<RUN>-diagnose`); re-fits go to `<RUN>+<effect>`.
    pub out: Option<PathBuf>,
    /// Replace existing output folders.
    pub overwrite: bool,
    /// KKT tolerance of the re-fits.
    pub tol: f64,
    /// Iteration limit of the re-fits.
    pub max_iter: usize,
    /// Validate significant candidates on another half cycle of the trial (default on;
    /// off: they are reported "significant, not validated").
    pub held_out: bool,
    /// Kept solutions to start the diagnosis's own solves from (`--start`): run folders
    /// with `setup.json` and `solution.json` (an earlier re-fit `<RUN>+<effect>`), or
    /// folders of them (an earlier `<RUN>-diagnose`, whose `held_out` is its held-out
    /// track); each starts the solve
    /// of the same problem, which still iterates to the KKT tolerance from there.
    pub starts: Vec<PathBuf>,
}

impl DiagnoseRequest {
    /// A request with `footfall diagnose`'s defaults for the track run `run`: the default
    /// candidates, one verifying re-fit, held-out validation, re-fits to KKT 1e-5 within
    /// 200 iterations, the output beside the run (`<RUN>-diagnose`, not replaced); no
    /// kept starts.
    pub fn new(run: PathBuf) -> Self {
        DiagnoseRequest {
            run,
            verify: 1,
            candidates: Vec::new(),
            out: None,
            overwrite: false,
            tol: 1e-5,
            max_iter: 200,
            held_out: true,
            starts: Vec::new(),
        }
    }
}

/// The decrease of a truncated re-fit of a problem started at the run's solution (the
/// baseline every candidate is measured against), its cost and its data residual count.
fn decrease_at_solution(prob: &TrackingProblem) -> anyhow::Result<(f64, f64, usize)> {
    prob.with_transcription(|tr, cycle, w| {
        let (j, dec) = gauss_newton_decrease(tr, &w).map_err(|e| anyhow!(e))?;
        Ok((
            j,
            dec,
            prob.setup
                .data_rows(&prob.model, &prob.sets, &cycle.continuous),
        ))
    })
}

/// Score test of candidate `effect` (its `k` parameters the last of θ); returns the test
/// and the point its truncated re-fit reached, where a verifying re-fit starts.
fn test_candidate(
    prob: &TrackingProblem,
    effect: &EffectSpec,
    k: usize,
    baseline: &Residuals,
    noise: Option<&FullModel>,
    hint: String,
) -> anyhow::Result<(ScoreTest, GaitSolution)> {
    let rows = baseline.rows;
    prob.with_transcription(|tr, cycle, w| {
        let free = prob.model.free_parameters();
        let names: Vec<String> = free[free.len() - k..]
            .iter()
            .map(|&i| prob.model.parameters()[i].name.clone())
            .collect();
        // the Gauss–Newton model at the solution and its first step, shared by the score
        // test (its truncated re-fit's first step) and the identifiability probes
        let first = GaussNewtonModel::new(tr, &w, 1e-12).map_err(|e| anyhow!(e))?;
        let first_step = first.step(None);
        // the residual mean square every statistic is measured in
        let s2 = baseline.mean_square(noise);
        let (mut t, w1) = score_test_from(
            effect,
            names.clone(),
            tr,
            &first,
            first_step.clone(),
            baseline.decrease,
            rows,
            Some(s2),
        )
        .map_err(|e| anyhow!(e))?;
        let means = |w: &[f64]| {
            channel_means(
                tr,
                w,
                &cycle.continuous,
                prob.setup.window.0,
                &prob.model,
                &prob.sets,
                &prob.data,
            )
            .map_err(|e| anyhow!(e))
        };
        let (before, after) = (means(&w)?, means(&w1)?);
        t.expected_channels = before
            .into_iter()
            .zip(after)
            .map(|((c, u, b), (_, _, a))| (c, u, b, a))
            .collect();
        // the autocorrelation of the noise is that of the residuals under the largest
        // model (every candidate at once, [`full_model_series`]), as an F-test's variance
        // is the larger model's: at the plain model's solution a missing effect's
        // systematic misfit is itself a smooth, correlated residual, and so is a second
        // missing effect's after this candidate's re-fit; without that model, the
        // residuals after this candidate's own re-fit
        let after = match noise {
            Some(full) => full.series.clone(),
            None => residual_series(&prob, tr, &cycle.continuous, &w1)?,
        };
        let phi = baseline.inflation_after(&after, &t.expected_channels);
        t.set_inflation(phi);
        // and so is the residual mean square
        t.set_mean_square(s2);
        let id = candidate_identifiability_at(tr, &first, first_step.as_ref(), names, s2, phi)
            .map_err(|e| anyhow!(e))?;
        t.set_identifiability(id, Some(hint));
        let mut solution = GaitSolution::from_nlp(tr, &w1, &cycle.continuous, prob.setup.window.0);
        // a plate's clock offset candidate moves the window's start with the events it gave
        prob.setup.place(&prob.model, &mut solution);
        Ok((t, solution))
    })
}

/// `prob` for the Gauss–Newton linearisations of the score tests (the baseline, each
/// candidate and the largest model): the sensitivities are left out of CVODES's local
/// error test, so the steps follow the states' error only (an interval then takes about
/// two thirds of the steps and time). The costs that
/// decide a step are the states' (unchanged); the sensitivities only shape the
/// Gauss–Newton model, whose step is then checked on the cost. Full re-fits (the heel
/// pad's, the verifying ones) keep the run's settings: an SQP's convergence test needs
/// the sensitivities' error controlled.
fn linearisation(mut prob: TrackingProblem) -> TrackingProblem {
    prob.integrator.sens_error_control = false;
    prob
}

/// The Table 3 channels' residual series at the nodes of `prob` at the point `w` of its
/// transcription `tr` (for their autocorrelation).
fn residual_series(
    prob: &TrackingProblem,
    tr: &Transcription,
    continuous: &[usize],
    w: &[f64],
) -> anyhow::Result<Vec<(String, Vec<f64>)>> {
    channel_series(
        tr,
        w,
        continuous,
        prob.setup.window.0,
        &prob.model,
        &prob.sets,
        &prob.data,
    )
    .map_err(|e| anyhow!(e))
}

/// Whether `c` is an instrument effect of both plates together (one clock, CoP offset or
/// gain for both feet, or both plates' gains in one candidate), which the largest model
/// replaces by one per plate.
fn both_plates(c: &EffectSpec) -> bool {
    matches!(
        c,
        EffectSpec::ForcePlateTimeOffset { side, .. }
            | EffectSpec::CopOffset { side, .. }
            | EffectSpec::ForcePlateGain { side, .. } if side == "both" || side == "each"
    )
}

/// The Table 3 channels' residual series at the nodes after a truncated re-fit of the
/// largest model the diagnosis considers: every score-tested candidate at once
/// (`candidates`: those the run's model accepts and does not already hold), each kind
/// once (each plate's instruments on their own rather than both plates together),
/// started from the run's solution. Its residuals are the diagnosis's estimate of the
/// noise: its mean square and autocorrelation are what every candidate's decrease is
/// measured against. `None` when fewer than two candidates are scored (each candidate's
/// own re-fit is then that model).
fn full_model_series(
    setup: &TrackingRunSetup,
    solution: &GaitSolution,
    candidates: &[&EffectSpec],
) -> anyhow::Result<Option<FullModel>> {
    // the volumetric contact law is score-tested but left out of the largest model
    let mut order: Vec<&EffectSpec> = candidates
        .iter()
        .copied()
        .filter(|c| c.kind() != "volumetric_contact")
        .collect();
    order.sort_by_key(|c| both_plates(c));
    let mut chosen: Vec<EffectSpec> = Vec::new();
    for c in order {
        if !chosen.iter().any(|x| x.overlaps(c)) {
            chosen.push(c.clone());
        }
    }
    if chosen.len() < 2 {
        return Ok(None);
    }
    let mut prob = linearisation(TrackingProblem::build(setup, &chosen)?);
    prob.setup.start_from(solution).map_err(|e| anyhow!(e))?;
    let (objective, series) = prob.with_transcription(|tr, cycle, w| {
        let (j1, w1) = refit_point(tr, &w).map_err(|e| anyhow!(e))?;
        let series = residual_series(&prob, tr, &cycle.continuous, &w1)?;
        Ok((j1, series))
    })?;
    Ok(Some(FullModel {
        effects: chosen.iter().map(|c| c.label()).collect(),
        objective,
        series,
    }))
}

/// The largest model's truncated re-fit: the diagnosis's estimate of the noise.
pub(super) struct FullModel {
    /// Its effects' labels.
    pub effects: Vec<String>,
    /// Its cost after the re-fit.
    pub objective: f64,
    /// The Table 3 channels' residual series at the nodes.
    pub series: Vec<(String, Vec<f64>)>,
}

/// The run's residuals: cost, count, the truncated re-fit's leftover decrease and the
/// Table 3 channels' error series at the nodes (for their autocorrelation).
pub(super) struct Residuals {
    objective: f64,
    decrease: f64,
    rows: usize,
    series: Vec<(String, Vec<f64>)>,
    /// Each channel's variance inflation `N/N_eff`.
    inflation: Vec<Option<f64>>,
}

impl Residuals {
    /// The variance inflation φ a candidate's decrease is judged with: that of the
    /// residual series `after` (by channel; the run's own where `after` lacks one),
    /// averaged over the channels weighted by how much the candidate improves each
    /// (`expected`: `(channel, unit, before, after)` mean errors), as the decrease's
    /// variance is that of the channels it comes from.
    fn inflation_after(
        &self,
        after: &[(String, Vec<f64>)],
        expected: &[(String, String, f64, f64)],
    ) -> f64 {
        let weights: Vec<f64> = self
            .series
            .iter()
            .map(|(name, _)| {
                expected.iter().find(|c| &c.0 == name).map_or(0.0, |c| {
                    if c.2 > 0.0 {
                        (c.2 - c.3) / c.2
                    } else {
                        0.0
                    }
                })
            })
            .collect();
        let series: Vec<Vec<f64>> = self
            .series
            .iter()
            .map(|(name, own)| {
                after
                    .iter()
                    .find(|a| &a.0 == name)
                    .map_or_else(|| own.clone(), |a| a.1.clone())
            })
            .collect();
        variance_inflation(&series, &weights).1
    }

    /// The residual mean square every statistic is measured in: the largest model's
    /// (`noise`; an F-test's denominator), or the run's own without it.
    fn mean_square(&self, noise: Option<&FullModel>) -> f64 {
        let objective = noise.map_or(self.objective, |f| f.objective.min(self.objective));
        objective / self.rows.max(1) as f64
    }
}

/// The run being diagnosed: its solution, summary, cost and data residual count.
pub(super) struct Baseline<'a> {
    solution: &'a GaitSolution,
    summary: &'a RunSummary,
    objective: f64,
    rows: usize,
}

/// A score-tested candidate (one without a null value is tested by a re-fit instead):
/// its problem's build error (the model refuses it), or its test, the point its
/// truncated re-fit reached and the seconds it took.
enum Scored {
    Unbuilt(anyhow::Error),
    Tested(anyhow::Result<Box<(ScoreTest, GaitSolution, f64)>>),
}

/// One progress line per tested candidate: its (predicted or re-fit) decrease, the steps
/// or iterations it took, its statistic against the threshold.
fn print_progress(progress: &dyn Progress, t: &ScoreTest, converged: bool, seconds: f64) {
    let (what, steps) = if t.refit {
        ("re-fit decrease  ", "iterations")
    } else {
        ("expected decrease", "steps")
    };
    note!(progress,
        "  {:<32} {what} {:>10.3e} ({:>5.1} % of J, {} {steps}{}), statistic {:>9.1} (φ {:.1}) vs {:.1}{}  [{seconds:.1} s]",
        t.label,
        t.predicted_decrease,
        100.0 * t.predicted_fraction,
        t.steps,
        if converged { "" } else { ", not converged" },
        t.statistic,
        t.inflation,
        t.threshold,
        if !t.testable {
            format!("  NOT TESTABLE: {}", t.identifiability.as_ref().and_then(|i| i.reason.clone()).unwrap_or_default())
        } else if t.significant {
            "  significant".into()
        } else {
            String::new()
        },
    );
}

fn sibling(run: &Path, suffix: &str) -> PathBuf {
    let name = run
        .file_name()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "run".into());
    run.with_file_name(format!("{name}{suffix}"))
}

/// Why heel-pad compliance is not scored on a run with interpolated node targets, and
/// what to do instead (followed by the run).
///
/// The pad has no null value for a score test (the rigid heel is its limit of infinite
/// stiffness), so `diagnose` tests it by a full re-fit ([`refit_test`]). With Millard & Mombaur's
/// interpolated node targets that re-fit's decrease is no evidence: a free pad lowers J
/// on data *without* a pad too (the double-circle trial without a hidden effect: J
/// 0.3938 → 0.3696, a statistic of 34 against the χ²₂ 0.1 % point 13.8), even on
/// noise-free data, because at the nodes on the contact changes the targets average
/// across the jumps a rigid contact makes and a pad bends to meet them. With
/// `track --sample-targets` (every sample compared at its own instant) it does not, on
/// the 100 Hz noisy trials of tests/hidden_effects.rs; `docs/method.md` ("The heel pad") explains why.
const UNSCORABLE_PAD: &str = "not scored — it has no null value (the rigid heel is its limit of infinite stiffness), so it is tested by a re-fit, and on a run with interpolated node targets a re-fit's decrease is no evidence (a free pad lowers J on data without one too, from the node targets on the contact changes; see docs/method.md, \"The heel pad\"); track with `--sample-targets` (every sample compared at its own instant; 100 Hz tested) and diagnose that run, or re-fit it with `footfall track --foot … --effect heel_pad_compliance --init RUN` and judge the identified stiffness and damping and the per-channel errors with `footfall diff`";

/// The first stage: the run's trial checked against itself (whole-body Newton–Euler,
/// no model fitted), reported before the model stage. Returns its text (`None` where the
/// trial cannot be read so, which is said). Where it finds an instrument or body effect
/// the run's model lacks, the text says that the model stage reads the model against a
/// measurement not yet corrected, and how to correct it first.
fn measurement_stage(
    setup: &crate::problems::diagnose::TrackingRunSetup,
    progress: &dyn Progress,
) -> Option<String> {
    let req = super::check::CheckRequest {
        trial: super::trial::TrialFiles {
            data: setup.data.clone(),
            forces: setup.forces.clone(),
            plates: setup.plates.clone(),
            lab_axes: setup.lab_axes.clone(),
            belt_speed: setup.belt_speed,
            overground: setup.overground,
        },
        model: setup.model.clone(),
        out: None,
        overwrite: false,
        settings: crate::problems::check::CheckSettings::default(),
    };
    match super::check::read(&req) {
        Ok((_, check, _)) => {
            let mut text = format!(
                "stage 1, the measurement against itself (footfall check):\n{}",
                super::check::output::verdict_text(&check)
            );
            let missing: Vec<String> = super::check::effect_lines(&check)
                .into_iter()
                .filter(|line| !held_already(setup, line))
                .collect();
            if !missing.is_empty() {
                text += &format!(
                    "The model stage below reads the model against this measurement as it is: what the check found also moves the model's misfit. To read the model's physics alone, re-track the run with {} (or on the check's corrected trial, `footfall check TRIAL --out DIR` then `--data DIR/corrected/trial.csv`) and diagnose that run.\n",
                    missing
                        .iter()
                        .map(|l| format!("`--effect {l}`"))
                        .collect::<Vec<_>>()
                        .join(" ")
                );
            }
            progress.result(&text);
            Some(text)
        }
        Err(e) => {
            progress.note(&format!(
                "stage 1, the measurement against itself: not read ({e:#})"
            ));
            None
        }
    }
}

/// Whether the run's model already holds an effect of the kind `line` (an `--effect`
/// line of the check) adds.
fn held_already(setup: &crate::problems::diagnose::TrackingRunSetup, line: &str) -> bool {
    EffectSpec::parse_cli(line).is_ok_and(|spec| setup.effects.iter().any(|e| e.overlaps(&spec)))
}

/// What every step of a diagnosis reads: the request, the run's setup, solution and
/// summary, and where progress goes.
struct RunInputs<'a> {
    args: &'a DiagnoseRequest,
    setup: &'a TrackingRunSetup,
    solution: &'a GaitSolution,
    before: &'a RunSummary,
    progress: &'a dyn Progress,
}

/// Run `diagnose` as `args` describes, reporting to `progress`: the measurement stage
/// first, then the model stage.
pub fn run(args: &DiagnoseRequest, progress: &dyn Progress) -> anyhow::Result<()> {
    // a bad --start is named before any work
    starts::kept_solutions(&args.starts)?;
    let setup = read_run_setup(&args.run)?;
    let solution = super::read_solution(&args.run)?;
    let before = RunSummary::read(&args.run)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| sibling(&args.run, "-diagnose"));
    let folder = RunFolder::create(&out, args.overwrite)?;
    let measured = measurement_stage(&setup, progress);
    if let Some(text) = &measured {
        folder.write("measurement.md", text.as_bytes())?;
    }
    let run = RunInputs {
        args,
        setup: &setup,
        solution: &solution,
        before: &before,
        progress,
    };
    // the baseline: the run's own problem at its solution
    let mut base = linearisation(TrackingProblem::build(&setup, &[])?);
    base.setup
        .start_from(&solution)
        .map_err(|e| anyhow!("{}: {e}", args.run.display()))?;
    let (resid, phi_all) = baseline_residuals(&run, &base)?;
    let candidates = candidates_of(args, &base.model)?;
    let (mut tests, evidence, skipped, full) =
        score_all(&run, &base, &resid, phi_all, &candidates)?;
    let (held_out_note, held_base) = validate_held_out(&run, base.setup.window, &mut tests)?;
    for t in &mut tests {
        t.settle();
    }
    let verified = verify_found(&run, resid.objective, &tests, &evidence)?;
    let ctx = output::Outcome {
        args,
        before: &before,
        objective: resid.objective,
        rows: resid.rows,
        resid: &resid,
        phi: phi_all,
        noise: full.as_ref(),
        tests: &tests,
        evidence: &evidence,
        verified: &verified,
        skipped: &skipped,
        held_out_note: held_out_note.trim().to_string(),
        measurement: measured,
        held_out: held_base.as_ref().and_then(|b| b.as_ref().ok()),
        clock_moves_events: setup.sample_targets || setup.one_sided_targets,
    };
    output::write(&ctx, folder, progress)
}

/// The run's own residuals at its solution (`base`): its cost, the decrease a
/// truncated re-fit still makes, and each channel's variance inflation; with the
/// inflation over all channels alike.
fn baseline_residuals(run: &RunInputs, base: &TrackingProblem) -> anyhow::Result<(Residuals, f64)> {
    let (objective, base_decrease, rows) = decrease_at_solution(base)?;
    let series =
        base.with_transcription(|tr, cycle, w| residual_series(base, tr, &cycle.continuous, &w))?;
    let values: Vec<Vec<f64>> = series.iter().map(|s| s.1.clone()).collect();
    let (inflation, phi_all) = variance_inflation(&values, &[]);
    let resid = Residuals {
        objective,
        decrease: base_decrease,
        rows,
        series,
        inflation,
    };
    note!(run.progress,
        "diagnosing {}: J = {objective:.6} over {rows} data residuals (mean square {:.3e}); Gauss–Newton decrease left at the solution {base_decrease:.2e}; variance inflation of the correlated residuals {phi_all:.1} ({})",
        run.args.run.display(),
        objective / rows as f64,
        resid.series.iter().zip(&resid.inflation).map(|(s, p)| format!("{} {}", s.0, p.map_or("—".into(), |p| format!("{p:.1}")))).collect::<Vec<_>>().join(", ")
    );
    Ok((resid, phi_all))
}

/// The candidates to test: the named ones, and the default set (the catalog, the heel
/// pad on a foot with a heel circle, the contact law on a volumetric foot) when none is
/// named or [`CATALOG`] is among them.
fn candidates_of(args: &DiagnoseRequest, model: &GaitModel) -> anyhow::Result<Vec<EffectSpec>> {
    let with_catalog = args.candidates.is_empty() || args.candidates.iter().any(|c| c == CATALOG);
    let mut candidates: Vec<EffectSpec> = if with_catalog { catalog() } else { Vec::new() };
    for c in args.candidates.iter().filter(|c| *c != CATALOG) {
        let spec = EffectSpec::parse_cli(c).map_err(|e| anyhow!("--candidate: {e}"))?;
        if !candidates.contains(&spec) {
            candidates.push(spec);
        }
    }
    if !with_catalog {
        return Ok(candidates);
    }
    // the heel pad, tested by a re-fit on runs with sample or one-sided targets, named as
    // not scored on others
    let mut extra = Vec::new();
    if model.contacts.iter().any(|c| c.name.ends_with(".heel")) {
        extra.push("heel_pad_compliance");
    }
    // the volumetric contact law, its null value the foot file's law ("is the law the
    // one the forces ask for?")
    if model.has_volumetric_contacts() {
        extra.push("volumetric_contact");
    }
    for name in extra {
        let spec = EffectSpec::parse_cli(name).map_err(|e| anyhow!(e))?;
        if !candidates.contains(&spec) {
            candidates.push(spec);
        }
    }
    Ok(candidates)
}

/// Whether the run's model already holds an effect that candidate `c` would duplicate.
fn in_the_model(setup: &TrackingRunSetup, c: &EffectSpec) -> bool {
    setup
        .effects
        .iter()
        .any(|e| e.overlaps(c) && !e.composes_with(c))
}

/// The largest model's residuals (every accepted candidate at once), said in a line;
/// `None` with fewer than two, or where its re-fit failed (said as a warning).
fn largest_model(run: &RunInputs, accepted: &[&EffectSpec], objective: f64) -> Option<FullModel> {
    match full_model_series(run.setup, run.solution, accepted) {
        Ok(Some(full)) => {
            note!(run.progress,
                "the largest model ({} candidates at once: {}) lowers J from {objective:.6} to {:.6}; its residuals are the noise every statistic is measured against",
                full.effects.len(),
                full.effects.join(", "),
                full.objective
            );
            Some(full)
        }
        Ok(None) => None,
        Err(e) => {
            warn_note!(run.progress,
                "the largest model (every candidate at once) could not be re-fitted ({e:#}); each candidate's statistic is corrected with the residuals after its own re-fit"
            );
            None
        }
    }
}

/// Every candidate's test, in rank order, with the evidence each rests on; the
/// candidates not tested, and why; and the largest model's residuals.
type Scores = (
    Vec<ScoreTest>,
    Vec<Evidence>,
    Vec<String>,
    Option<FullModel>,
);

/// Test every candidate: a score test at the run's solution for each with a null value
/// (in parallel), a re-fit for the heel pad, and rank them.
fn score_all(
    run: &RunInputs,
    base: &TrackingProblem,
    resid: &Residuals,
    phi_all: f64,
    candidates: &[EffectSpec],
) -> anyhow::Result<Scores> {
    let (args, setup, progress) = (run.args, run.setup, run.progress);
    let pad = EffectSpec::parse_cli("heel_pad_compliance").map_err(|e| anyhow!(e))?;
    // each score-tested candidate's problem, built once (the model, phases and trial read
    // from their files): the largest model is made of those the model accepts, and each
    // is then score-tested
    let problems: Vec<Option<anyhow::Result<TrackingProblem>>> = candidates
        .iter()
        .map(|c| {
            (c.kind() != pad.kind() && !in_the_model(setup, c))
                .then(|| TrackingProblem::build(setup, std::slice::from_ref(c)))
        })
        .collect();
    let accepted: Vec<&EffectSpec> = candidates
        .iter()
        .zip(&problems)
        .filter(|(_, p)| matches!(p, Some(Ok(_))))
        .map(|(c, _)| c)
        .collect();
    let full = largest_model(run, &accepted, resid.objective);
    // the run every candidate's re-fit (the pad's) is measured against
    let baseline = Baseline {
        solution: run.solution,
        summary: run.before,
        objective: resid.objective,
        rows: resid.rows,
    };
    let scored_count = problems.iter().filter(|p| p.is_some()).count();
    if scored_count > 1 {
        note!(progress, "score-testing {scored_count} candidates");
    }
    let scored = score_tests(run, base, resid, full.as_ref(), candidates, problems);
    let mut tests = Vec::new();
    let mut skipped = Vec::new();
    for (c, scored) in candidates.iter().zip(scored) {
        if in_the_model(setup, c) {
            skipped.push(format!("{}: already in the model", c.label()));
            continue;
        }
        if c.kind() == pad.kind() {
            // a foot without a heel circle has no place for the pad: the candidate is
            // named with the model's reason, and the other candidates' scores stand
            if let Err(e) = TrackingProblem::build(setup, std::slice::from_ref(c)) {
                skipped.push(format!("{}: {e:#}", c.label()));
                continue;
            }
            if !(setup.one_sided_targets || setup.sample_targets) {
                skipped.push(format!(
                    "{}: {}",
                    c.label(),
                    UNSCORABLE_PAD.replace("RUN", &args.run.display().to_string())
                ));
                continue;
            }
            let t0 = std::time::Instant::now();
            let (mut t, refitted, diff) = test_by_refit(args, setup, c, &baseline, progress)?;
            t.set_inflation(phi_all);
            print_progress(progress, &t, refitted.converged, t0.elapsed().as_secs_f64());
            tests.push((t, Evidence::Refit(Box::new(refitted), diff)));
            continue;
        }
        // scored above for every candidate that gets here (neither in the model nor the pad)
        let Some(scored) = scored else { continue };
        let (t, start, seconds) = match scored {
            Scored::Unbuilt(e) => {
                skipped.push(format!("{}: {e:#}", c.label()));
                continue;
            }
            Scored::Tested(result) => *result?,
        };
        print_progress(progress, &t, true, seconds);
        tests.push((t, Evidence::Start(start)));
    }
    // testable candidates first, the untestable after them (their statistic says
    // nothing), and the significant before the rest; among them by how much each explains, the
    // decrease (its likelihood gain under the largest model's noise, which all share):
    // the statistic's φ, weighted by the channels a candidate improves, decides whether
    // it explains more than the noise, not which explains most
    tests.sort_by(|a, b| {
        b.0.testable
            .cmp(&a.0.testable)
            .then(b.0.significant.cmp(&a.0.significant))
            .then(b.0.predicted_decrease.total_cmp(&a.0.predicted_decrease))
    });
    let (tests, evidence): (Vec<ScoreTest>, Vec<Evidence>) = tests.into_iter().unzip();
    Ok((tests, evidence, skipped, full))
}

/// The score tests: each candidate's is independent of the others' (its own problem,
/// started at the run's solution), so they run at once, as many as rayon has threads;
/// each one's figures are the same whichever thread runs it and when, and they are
/// returned in the candidates' order (`None` for those not built: in the model, or the
/// pad).
fn score_tests(
    run: &RunInputs,
    base: &TrackingProblem,
    resid: &Residuals,
    full: Option<&FullModel>,
    candidates: &[EffectSpec],
    problems: Vec<Option<anyhow::Result<TrackingProblem>>>,
) -> Vec<Option<Scored>> {
    let (setup, solution) = (run.setup, run.solution);
    let base_theta = base.model.ntheta();
    candidates
        .par_iter()
        .zip(problems.into_par_iter())
        .map(|(c, built)| {
            Some(match built? {
                Err(e) => Scored::Unbuilt(e),
                Ok(p) => Scored::Tested((|| {
                    let mut prob = linearisation(p);
                    let k = prob.model.ntheta() - base_theta;
                    prob.setup.start_from(solution).map_err(|e| anyhow!(e))?;
                    let t0 = std::time::Instant::now();
                    let (t, start) =
                        test_candidate(&prob, c, k, resid, full, heldout::hint(c, setup))?;
                    Ok(Box::new((t, start, t0.elapsed().as_secs_f64())))
                })()),
            })
        })
        .collect()
}

/// The held-out half cycle's plain track, once (`None`: none was needed; `Err`: why the
/// trial has none).
type HeldOutTrack = Option<Result<heldout::HeldOutBase, String>>;

/// Validate the significant candidates of `tests` on another half cycle of the trial
/// than the run's (`window`, s): the note that says how it went, and that half cycle's
/// track.
fn validate_held_out(
    run: &RunInputs,
    window: (f64, f64),
    tests: &mut [ScoreTest],
) -> anyhow::Result<(String, HeldOutTrack)> {
    let (args, progress) = (run.args, run.progress);
    let validated = |t: &ScoreTest| t.significant && t.at_bound.is_empty() && !t.refit;
    let mut note: String = tests
        .iter()
        .filter(|t| t.significant && t.refit)
        .map(|t| format!(" {} is not validated on a held-out half cycle: it was tested by a full re-fit, which gives no reduced curvature to set its noise band.", t.label))
        .collect();
    if !tests.iter().any(validated) {
        return Ok((note, None));
    }
    if !args.held_out {
        note += " Held-out validation was not asked for (--no-held-out): significant candidates are not validated.";
        return Ok((note, None));
    }
    let held_base = heldout::held_out_base(args, run.setup, window, progress)?;
    let hb = match &held_base {
        Ok(hb) => hb,
        Err(why) => {
            note += &format!(" No held-out half cycle in this trial ({why}): significant candidates are not validated.");
            return Ok((note, Some(held_base)));
        }
    };
    note += &format!(
        " Held-out: each significant candidate, with the values fitted on this run's half cycle ({:.3}–{:.3} s), applied to {} ({:.3}–{:.3} s; the plain model tracked there: J = {:.6}, {} iterations{}) with the other variables re-fitted; it is found if it lowers that cost beyond its noise band (2 sd, inflated by φ, above the mean change a fit to noise makes, which is a rise). Each is applied at the opposite values too: the two changes give that half cycle's own curvature along the candidate, which sets its band, and its own reading of the candidate as a fraction of the fitted values (found: that reading lies beyond 2 sd). Where a true effect of the fitted size would not clear the band on average (the reading's sd above one half), that half cycle is too weakly informed to confirm or refute it: not validatable.",
        window.0,
        window.1,
        heldout::half_cycle_name(hb.stride, hb.mirrored),
        hb.window.0,
        hb.window.1,
        hb.objective,
        hb.iterations,
        if hb.converged { "" } else { ", NOT converged" }
    );
    for t in tests.iter_mut().filter(|t| validated(t)) {
        match heldout::validate(hb, t) {
            Ok(h) => {
                note!(
                    progress,
                    "  held-out {:<32} change {:>10.3e} ({:>5.1} % of J), noise band {:.3e}{}{}",
                    t.label,
                    h.change,
                    100.0 * h.change_fraction,
                    h.band,
                    reading_note(&h),
                    confirmed_note(&h)
                );
                t.held_out = Some(h);
            }
            Err(e) => {
                note += &format!(" {}: the held-out validation failed ({e:#}).", t.label);
            }
        }
    }
    Ok((note, Some(held_base)))
}

/// Re-fit the top `--verify` found candidates for real, each from where its test got to.
fn verify_found(
    run: &RunInputs,
    objective: f64,
    tests: &[ScoreTest],
    evidence: &[Evidence],
) -> anyhow::Result<Vec<Verified>> {
    let mut verified = Vec::new();
    for (t, e) in tests
        .iter()
        .zip(evidence)
        .filter(|(t, _)| t.found)
        .take(run.args.verify)
    {
        let v = match e {
            // the test was the re-fit
            Evidence::Refit(refitted, diff) => Verified::new(t, refitted, diff.clone(), objective),
            // from where the candidate's truncated re-fit got to (fewer SQP iterations
            // than from the run's solution)
            Evidence::Start(start) => {
                let refitted = refit(run.args, run.setup, &t.effect, start, run.progress)?;
                Verified::new(t, &refitted, diff_with(run.before, &refitted)?, objective)
            }
        };
        verified.push(v);
    }
    Ok(verified)
}

/// The progress line's reading of a held-out validation: `, reads 0.62 ± 0.41 of it`.
fn reading_note(h: &crate::problems::diagnose::HeldOut) -> String {
    h.reading
        .as_ref()
        .map_or(String::new(), |r| format!(", {}", r.text()))
}

/// The progress line's verdict of a held-out validation.
fn confirmed_note(h: &crate::problems::diagnose::HeldOut) -> &'static str {
    if h.beyond_noise {
        "  confirmed"
    } else if h.too_weakly_informed() {
        "  not validatable (too weakly informed there)"
    } else {
        "  not confirmed"
    }
}
