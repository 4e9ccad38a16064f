//! The candidates' tests: each score test at the run's solution (in parallel), with
//! its statistic against the noise of the largest model; the heel pad's re-fit; and
//! their ranking.

use super::super::track::TrackingProblem;
#[allow(unused_imports)]
use super::super::{note, warn_note, Progress};
use super::heldout;
use super::noise::{full_model_series, linearisation, residual_series, FullModel, Residuals};
use super::refit::{test_by_refit, Evidence};
use super::{Baseline, RunInputs};
use crate::model::effects::EffectSpec;
use crate::problems::diagnose::stats::candidate_identifiability_at;
use crate::problems::diagnose::{channel_means, score_test_from, ScoreTest, TrackingRunSetup};
use crate::problems::evaluation::GaitSolution;
use crate::sqp::linearised::GaussNewtonModel;
use anyhow::anyhow;
use rayon::prelude::*;
use std::sync::Arc;

/// Score test of candidate `effect` (its `k` parameters the last of θ); returns the test
/// and the point its truncated re-fit reached, where a verifying re-fit starts.
pub(super) fn test_candidate(
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
        let first = GaussNewtonModel::new(tr, &w, 1e-12)?;
        let first_step = first.step(None).map_err(Arc::new);
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
            None => residual_series(prob, tr, &cycle.continuous, &w1)?,
        };
        let phi = baseline.inflation_after(&after, &t.expected_channels);
        t.set_inflation(phi);
        // and so is the residual mean square
        t.set_mean_square(s2);
        let base = first_step.as_ref().map_err(|e| e.as_ref());
        let id = candidate_identifiability_at(tr, &first, base, names, s2, phi);
        t.set_identifiability(id, Some(hint));
        let mut solution = GaitSolution::from_nlp(tr, &w1, &cycle.continuous, prob.setup.window.0);
        // a plate's clock offset candidate moves the window's start with the events it gave
        prob.setup.place(&prob.model, &mut solution);
        Ok((t, solution))
    })
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

/// Whether the run's model already holds an effect that candidate `c` would duplicate.
pub(super) fn in_the_model(setup: &TrackingRunSetup, c: &EffectSpec) -> bool {
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
/// (in parallel), judged against what it lowers on the model's own trial (kept in
/// `null_dir`, [`super::model_null`]), a re-fit for the heel pad, and rank them.
pub(super) fn score_all(
    run: &RunInputs,
    base: &TrackingProblem,
    resid: &Residuals,
    phi_all: f64,
    candidates: &[EffectSpec],
    null_dir: &std::path::Path,
) -> anyhow::Result<Scores> {
    let (args, setup, progress) = (run.args, run.setup, run.progress);
    let pad = EffectSpec::parse_cli("heel_pad_compliance")?;
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
    // each score-tested candidate judged against what it lowers on the model's own data
    let (mut judged, evidence): (Vec<ScoreTest>, Vec<Evidence>) = tests.into_iter().unzip();
    super::model_null::judge_against_model_null(run, base, null_dir, &mut judged)?;
    let mut tests: Vec<(ScoreTest, Evidence)> = judged.into_iter().zip(evidence).collect();
    // testable candidates first, the untestable after them (their statistic says
    // nothing), and the significant before the rest; among them by how much each explains:
    // the decrease (its likelihood gain under the largest model's noise, which all share)
    // beyond what it lowers on the model's own trial (an actuator property relieves the
    // effort term on any trial; a damping standing in for a missing heel pad lowers more
    // than the pad, but less beyond its relief). The statistic's φ, weighted by the
    // channels a candidate improves, decides whether it explains more than the noise, not
    // which explains most
    tests.sort_by(|a, b| {
        b.0.testable
            .cmp(&a.0.testable)
            .then(b.0.significant.cmp(&a.0.significant))
            .then(
                b.0.decrease_beyond_model_null()
                    .total_cmp(&a.0.decrease_beyond_model_null()),
            )
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
