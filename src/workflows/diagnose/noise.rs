//! The noise a diagnosis measures every candidate against: the run's own residuals at
//! its solution (cost, count, the decrease a truncated re-fit still makes, each channel's
//! variance inflation) and the residuals of the largest model, every candidate at once.

use super::super::track::TrackingProblem;
#[allow(unused_imports)]
use super::super::{note, Progress};
use super::RunInputs;
use crate::model::effects::EffectSpec;
use crate::ocp::Transcription;
use crate::problems::diagnose::stats::variance_inflation;
use crate::problems::diagnose::{
    channel_series, gauss_newton_decrease, refit_point, TrackingRunSetup,
};
use crate::problems::evaluation::GaitSolution;
use anyhow::anyhow;

/// The decrease of a truncated re-fit of a problem started at the run's solution (the
/// baseline every candidate is measured against), its cost and its data residual count.
pub(super) fn decrease_at_solution(prob: &TrackingProblem) -> anyhow::Result<(f64, f64, usize)> {
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

/// `prob` for the Gauss–Newton linearisations of the score tests (the baseline, each
/// candidate and the largest model): the sensitivities are left out of CVODES's local
/// error test, so the steps follow the states' error only (an interval then takes about
/// two thirds of the steps and time). The costs that
/// decide a step are the states' (unchanged); the sensitivities only shape the
/// Gauss–Newton model, whose step is then checked on the cost. Full re-fits (the heel
/// pad's, the verifying ones) keep the run's settings: an SQP's convergence test needs
/// the sensitivities' error controlled.
pub(super) fn linearisation(mut prob: TrackingProblem) -> TrackingProblem {
    prob.integrator.sens_error_control = false;
    prob
}

/// The Table 3 channels' residual series at the nodes of `prob` at the point `w` of its
/// transcription `tr` (for their autocorrelation).
pub(super) fn residual_series(
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
/// largest model the diagnosis considers: every score-tested candidate but the actuator
/// properties at once (`candidates`: those the run's model accepts and does not already
/// hold), each kind once (each plate's instruments on their own rather than both plates
/// together), started from the run's solution. Its residuals are the diagnosis's
/// estimate of the noise: its mean square and autocorrelation are what every candidate's
/// decrease is measured against. `None` when fewer than two candidates are scored (each
/// candidate's own re-fit is then that model).
pub(super) fn full_model_series(
    setup: &TrackingRunSetup,
    solution: &GaitSolution,
    candidates: &[&EffectSpec],
) -> anyhow::Result<Option<FullModel>> {
    // the volumetric contact law is score-tested but left out of the largest model; so
    // are the actuator properties, which lower J on data that do not ask for them (they
    // relieve the effort term): in the largest model that relief would pass for a smaller
    // noise, and where one explains most of J (a free damping on a real track: 7.9 → 0.85)
    // every other candidate's decrease, measured alone and sharing part of its signature,
    // would read as a finding. Left out, a missing actuator property counts as noise and
    // can only hide another candidate, which shows once it is added to the model and the
    // re-fit is diagnosed.
    let mut order: Vec<&EffectSpec> = candidates
        .iter()
        .copied()
        .filter(|c| c.kind() != "volumetric_contact" && !c.is_actuator_property())
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
    /// The run's cost J.
    pub objective: f64,
    /// The Gauss–Newton decrease a truncated re-fit still makes at the solution.
    pub decrease: f64,
    /// The number of data residuals.
    pub rows: usize,
    /// The Table 3 channels' error series at the nodes.
    pub series: Vec<(String, Vec<f64>)>,
    /// Each channel's variance inflation `N/N_eff`.
    pub inflation: Vec<Option<f64>>,
}

impl Residuals {
    /// The variance inflation φ a candidate's decrease is judged with: that of the
    /// residual series `after` (by channel; the run's own where `after` lacks one),
    /// averaged over the channels weighted by how much the candidate improves each
    /// (`expected`: `(channel, unit, before, after)` mean errors), as the decrease's
    /// variance is that of the channels it comes from.
    pub(super) fn inflation_after(
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
    pub(super) fn mean_square(&self, noise: Option<&FullModel>) -> f64 {
        let objective = noise.map_or(self.objective, |f| f.objective.min(self.objective));
        objective / self.rows.max(1) as f64
    }
}

/// The run's own residuals at its solution (`base`): its cost, the decrease a
/// truncated re-fit still makes, and each channel's variance inflation; with the
/// inflation over all channels alike.
pub(super) fn baseline_residuals(
    run: &RunInputs,
    base: &TrackingProblem,
) -> anyhow::Result<(Residuals, f64)> {
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
