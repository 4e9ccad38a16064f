//! Which physical effect is the model missing? Score tests of candidate effects at a
//! tracking solution, and the uncertainty of identified effect parameters.
//!
//! A candidate effect enters the model at its null value (no effect) with its parameters
//! free. Gauss–Newton steps of the enlarged tracking problem from the solution — the
//! first is the score test, a few more follow a cost that is strongly nonlinear in the
//! parameter ([`truncated_refit`]) — estimate how far the cost would fall if it were
//! added and re-fitted; the decrease of the problem without the candidate is
//! subtracted, so a solution that is not exactly stationary does not credit every
//! candidate with the same leftover decrease.
//!
//! Significance: with `N` data residuals whose mean square at the solution is `s² =
//! J/N`, the decrease in units of `s²` is approximately χ² with `k` degrees of freedom
//! (`k` = the candidate's free parameters) when the candidate explains only noise (the
//! extra-sum-of-squares test) — if the residuals were independent. They are not (real
//! residuals are smooth in time), so the decrease is divided by the variance inflation
//! `φ = N/N_eff` of the channels it comes from, measured on the residuals left after the
//! candidate's re-fit ([`stats::variance_inflation`]), before it is compared with the
//! χ²ₖ 0.1 % point.
//!
//! Identifiability comes first: a candidate whose reduced Fisher information (the
//! Hessian of the cost w.r.t. its parameters with everything else optimised out) is
//! rank deficient, or whose standard deviations exceed a quarter of their bound span, is
//! "not testable with this run's cost" — its score (often exactly 0, as the free
//! variables absorb it) says nothing about its absence ([`stats::identifiability`]).
//! A significant candidate is "found" only if, fitted here and applied with its values
//! fixed to another half cycle of the trial, it lowers that cost beyond its noise band
//! ([`HeldOut`], [`stats::held_out_band`]).

mod held_out;
mod run_setup;
pub mod stats;

pub use held_out::{HeldOut, HeldOutReading, NOT_VALIDATABLE};
pub use run_setup::TrackingRunSetup;

use super::distributions::{chi2_999, noncentral_chi2_point};
use super::error::DiagnoseError;
use crate::model::effects::EffectSpec;
use crate::ocp::{Block, Transcription};
use crate::sqp::linearised::{GaussNewtonModel, GaussNewtonStep};
use serde::{Deserialize, Serialize};

/// An effect parameter at a solution.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct IdentifiedParameter {
    /// Qualified name, e.g. `ground_slope.angle`.
    pub name: String,
    /// Value at the solution.
    pub value: f64,
    /// Approximate standard deviation (`None` for a fixed parameter or one at a bound).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sd: Option<f64>,
    /// Unit.
    pub unit: String,
    /// Whether it was identified.
    pub free: bool,
}

/// The verdict of a candidate whose decrease clears the χ²ₖ point but not what it lowers
/// on the model's own trial: not told apart from that, which is not evidence of absence.
pub const BELOW_MODEL_NULL: &str = "not told apart from what it lowers on the model's own trial";

/// What a candidate's truncated re-fit reads on the model's own trial (all empty: not
/// measured).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct ModelNullReading {
    /// The values it reaches.
    #[serde(
        rename = "model_null_values",
        default,
        skip_serializing_if = "Vec::is_empty"
    )]
    pub values: Vec<f64>,
    /// Its null values, where it starts (the truth there).
    #[serde(rename = "null_values", default, skip_serializing_if = "Vec::is_empty")]
    pub start: Vec<f64>,
    /// Each value's sd there, in that trial's own noise (`None` where the information
    /// is not positive; empty: not measured).
    #[serde(
        rename = "model_null_sd",
        default,
        skip_serializing_if = "Vec::is_empty"
    )]
    pub sd: Vec<Option<f64>>,
    /// Whether some value lies at a bound of its range.
    #[serde(
        rename = "model_null_at_bound",
        default,
        skip_serializing_if = "std::ops::Not::not"
    )]
    pub at_bound: bool,
}

/// Result of a score test of one candidate.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ScoreTest {
    /// The candidate (null value, parameters free).
    pub effect: EffectSpec,
    /// Human label.
    pub label: String,
    /// Names of its free parameters.
    pub parameters: Vec<String>,
    /// Their values after the Gauss–Newton step.
    pub step_values: Vec<f64>,
    /// The parameters whose value lies at a bound of its admissible range: a limit the
    /// data pushed against, not a reading.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub at_bound: Vec<String>,
    /// Fall of the tracking cost over the truncated re-fit (cost units), less that of
    /// the problem without the candidate.
    pub predicted_decrease: f64,
    /// As a fraction of the cost at the solution.
    pub predicted_fraction: f64,
    /// Predicted decrease in units of the residual mean square `J/N`.
    pub statistic: f64,
    /// The 0.1 % point it is compared with: of the χ²ₖ distribution, or of the noncentral
    /// χ²ₖ(λ) where the candidate lowers the cost on the model's own data too
    /// (`noncentrality`).
    pub threshold: f64,
    /// The residual mean square the statistic is measured in (cost units per residual).
    #[serde(default)]
    pub mean_square: f64,
    /// How far the candidate, freed the same way, lowers the cost of a trial the run's own
    /// model made from the run's solution at the trial's noise (cost units; `None`: not
    /// measured): the decrease it makes with nothing missing, by relieving the effort
    /// regularisation or the targets' interpolation, which no data ask for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_null: Option<f64>,
    /// What its truncated re-fit reads on that trial, where its true values are its null
    /// values.
    #[serde(flatten)]
    pub model_null_reading: ModelNullReading,
    /// `model_null` in the statistic's units (`model_null / (mean_square φ)`): the
    /// noncentrality λ of the statistic's distribution when the model lacks nothing.
    #[serde(default)]
    pub noncentrality: f64,
    /// Whether the statistic exceeds the threshold.
    pub significant: bool,
    /// Gauss–Newton steps taken ([`truncated_refit`]), or the SQP iterations of a full
    /// re-fit.
    pub steps: usize,
    /// Whether the decrease is a full re-fit's ([`refit_test`]: an effect without a null
    /// value) rather than the truncated re-fit's prediction.
    pub refit: bool,
    /// Mean error per Table 3 channel at the solution and after the steps:
    /// `(channel, unit, before, after)` — the expected change channel by channel.
    pub expected_channels: Vec<(String, String, f64, f64)>,
    /// The statistic as if the residuals were independent (`decrease / (J/N)`); the
    /// `statistic` divides this by `inflation`.
    pub statistic_independent: f64,
    /// Variance inflation `φ = N/N_eff` of the correlated residuals the decrease comes
    /// from ([`stats::variance_inflation`]; 1 = independent).
    pub inflation: f64,
    /// Whether the candidate's parameters are identifiable under the run's cost
    /// (`None`: not checked, e.g. a re-fit test).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub identifiability: Option<stats::Identifiability>,
    /// Whether it can be tested with this run's cost at all; an untestable candidate is
    /// never significant, and its statistic says nothing about the effect's absence.
    pub testable: bool,
    /// What would make an untestable candidate testable.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hint: Option<String>,
    /// The held-out validation of a significant candidate (`None`: not run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub held_out: Option<HeldOut>,
    /// Significant in-sample and validated on the held-out half cycle (or significant
    /// where the trial has no other half cycle: see `held_out`).
    pub found: bool,
    /// One of `not testable with this run's cost`, [`BELOW_MODEL_NULL`], `not
    /// significant`, `significant at
    /// its bound, not a reading`, `not confirmed on the held-out half cycle`,
    /// [`NOT_VALIDATABLE`], `found`, `significant, not validated`.
    pub verdict: String,
}

/// Mean error per Table 3 channel of the tracking solution in `w` against `data`.
pub fn channel_means(
    tr: &Transcription,
    w: &[f64],
    continuous: &[usize],
    t0: f64,
    model: &crate::model::GaitModel,
    sets: &[crate::model::ConstraintSet],
    data: &crate::data::GaitData,
) -> Result<Vec<(String, String, f64)>, DiagnoseError> {
    use super::evaluation::{channel_errors, Comparison, GaitSolution};
    let sol = GaitSolution::from_nlp(tr, w, continuous, t0);
    let nodes = sol.node_samples(model, sets)?;
    let cmp = Comparison::through_model(&nodes, data, model, &sol.theta)?;
    let channels = cmp.table_channels();
    Ok(channel_errors(&channels, &cmp, None)
        .into_iter()
        .filter_map(|c| c.runs[0].map(|s| (c.name.clone(), c.unit.clone(), s.mean)))
        .collect())
}

/// The parameters θ of a transcription's variable vector.
pub fn theta_of(tr: &Transcription, w: &[f64]) -> Vec<f64> {
    w[tr.range(Block::Params)].to_vec()
}

/// At most this many Gauss–Newton steps per candidate.
pub const MAX_STEPS: usize = 5;
/// A candidate's steps stop when one adds less than this fraction of its decrease.
pub const REL_STOP: f64 = 0.05;
/// A candidate's steps also stop when one adds less than this fraction of the
/// significance threshold to its statistic (in units of the residual mean square before
/// the variance inflation, which only shrinks it): such a step cannot change the verdict.
/// The clock-offset candidates on trials without a clock error took all [`MAX_STEPS`]
/// steps to gain a statistic of 0.1 against 10.8.
pub const STEP_STOP_OF_THRESHOLD: f64 = 0.01;

/// Cost decrease of the truncated re-fit from `w` ([`truncated_refit`]) and the cost.
pub fn gauss_newton_decrease(tr: &Transcription, w: &[f64]) -> Result<(f64, f64), DiagnoseError> {
    let (j, dec, _, _) = truncated_refit(tr, w, MAX_STEPS, REL_STOP)?;
    Ok((j, dec))
}

/// The point the truncated re-fit from `w` reaches ([`truncated_refit`] with the
/// diagnosis's step limit and stopping rule) and the cost there.
pub fn refit_point(tr: &Transcription, w: &[f64]) -> Result<(f64, Vec<f64>), DiagnoseError> {
    truncated_refit(tr, w, MAX_STEPS, REL_STOP).map(|(j, dec, w1, _)| (j - dec, w1))
}

/// A truncated re-fit from `w`: Gauss–Newton steps (each one QP on the linearised
/// constraints, backtracked on the cost) until a step adds less than `rel_stop` of the
/// decrease so far, or `max_steps`. The first step is the score test proper; the next
/// ones follow the cost where it is strongly nonlinear in the new parameters (a clock
/// offset moves sharp impact transients). Returns the cost at `w`, its total decrease,
/// the point reached and the number of steps.
pub fn truncated_refit(
    tr: &Transcription,
    w: &[f64],
    max_steps: usize,
    rel_stop: f64,
) -> Result<(f64, f64, Vec<f64>, usize), DiagnoseError> {
    let first = GaussNewtonModel::new(tr, w, 1e-12)?;
    let step = first.step(None);
    truncated_refit_from(tr, &first, step, max_steps, rel_stop, 0.0)
}

/// [`truncated_refit`] from the Gauss–Newton model `first` at the start and its first
/// step (or the error computing it), computed once by a caller that also asks the model
/// other questions (the identifiability probes start from the same model and step). The
/// steps also stop after one that lowers the cost by less than `abs_stop`.
pub fn truncated_refit_from(
    tr: &dyn crate::sqp::Nlp,
    first: &GaussNewtonModel<'_>,
    first_step: Result<GaussNewtonStep, impl Into<DiagnoseError>>,
    max_steps: usize,
    rel_stop: f64,
    abs_stop: f64,
) -> Result<(f64, f64, Vec<f64>, usize), DiagnoseError> {
    let cost = |w: &[f64]| tr.evaluate(w, false).map(|e| e.f);
    let j0 = first.objective();
    let mut w = first.point().to_vec();
    let mut pending = Some(first_step);
    let (mut f, mut total, mut steps) = (j0, 0.0, 0);
    while steps < max_steps {
        let s = match pending.take() {
            Some(s) => s.map_err(Into::into)?,
            None => GaussNewtonModel::new(tr, &w, 1e-12).and_then(|m| m.step(None))?,
        };
        if !(s.predicted_decrease > 0.0) {
            break;
        }
        let mut alpha = 1.0;
        let mut accepted = None;
        while alpha >= 1.0 / 16.0 {
            let trial: Vec<f64> = w.iter().zip(&s.d).map(|(a, b)| a + alpha * b).collect();
            if let Ok(ft) = cost(&trial) {
                if ft < f {
                    accepted = Some((trial, ft));
                    break;
                }
            }
            alpha *= 0.5;
        }
        let Some((trial, ft)) = accepted else { break };
        let dec = f - ft;
        total += dec;
        w = trial;
        f = ft;
        steps += 1;
        if dec < rel_stop * total || dec < abs_stop {
            break;
        }
    }
    Ok((j0, total, w, steps))
}

/// Score test of a candidate: `tr` is the tracking problem of the model with the
/// candidate added last (its parameters the last `k` of θ, at their null values in `w`),
/// `baseline_decrease` the Gauss–Newton decrease of the problem without it, `data_rows`
/// the number of data residuals.
/// Returns the test and the point after the step.
pub fn score_test(
    effect: &EffectSpec,
    parameters: Vec<String>,
    tr: &Transcription,
    w: &[f64],
    baseline_decrease: f64,
    data_rows: usize,
) -> Result<(ScoreTest, Vec<f64>), DiagnoseError> {
    let first = GaussNewtonModel::new(tr, w, 1e-12)?;
    let step = first.step(None);
    score_test_from(
        effect,
        parameters,
        tr,
        &first,
        step,
        baseline_decrease,
        data_rows,
        None,
    )
}

/// [`score_test`] from the Gauss–Newton model at the run's solution and its first step,
/// computed once for the score test and the identifiability probes. With the residual
/// mean square the statistic will be measured in (`mean_square`), the steps stop after
/// one that adds less than [`STEP_STOP_OF_THRESHOLD`] of the threshold to it.
#[allow(clippy::too_many_arguments)]
pub fn score_test_from(
    effect: &EffectSpec,
    parameters: Vec<String>,
    tr: &Transcription,
    first: &GaussNewtonModel<'_>,
    first_step: Result<GaussNewtonStep, impl Into<DiagnoseError>>,
    baseline_decrease: f64,
    data_rows: usize,
    mean_square: Option<f64>,
) -> Result<(ScoreTest, Vec<f64>), DiagnoseError> {
    let k = parameters.len();
    let abs_stop = mean_square
        .filter(|s2| s2.is_finite() && *s2 > 0.0)
        .map_or(0.0, |s2| STEP_STOP_OF_THRESHOLD * chi2_999(k) * s2);
    let (objective, decrease, w1, steps) =
        truncated_refit_from(tr, first, first_step, MAX_STEPS, REL_STOP, abs_stop)?;
    let theta = theta_of(tr, &w1);
    let values = theta[theta.len() - k..].to_vec();
    let at_bound = parameters_at_bound(tr, &parameters, &values);
    let test = ScoreTest {
        steps,
        at_bound,
        ..ScoreTest::from_decrease(
            effect,
            parameters,
            values,
            decrease - baseline_decrease,
            objective,
            data_rows,
        )
    };
    Ok((test, w1))
}

/// A ground-slope candidate read at 0.01 rad by a re-fit (J 2.0 → 1.0 over 20 rows),
/// testable and significant (statistic 20 against 10.8), not yet validated held out: the
/// verdict tests' fixture.
#[cfg(test)]
pub(crate) fn significant_slope() -> ScoreTest {
    let slope = EffectSpec::GroundSlope {
        angle: 0.0,
        free: vec!["angle".into()],
    };
    let mut t = refit_test(
        &slope,
        vec!["ground_slope.angle".into()],
        vec![0.01],
        2.0,
        1.0,
        20,
        3,
    );
    t.testable = true;
    t.statistic = 20.0;
    t.threshold = 10.8;
    t.significant = true;
    t
}

/// Which of `names`, the last parameters of θ in `tr` with `values`, lie within 1e-6 of
/// their bound span of a bound.
fn parameters_at_bound(tr: &Transcription, names: &[String], values: &[f64]) -> Vec<String> {
    let (w_lb, w_ub, _, _) = crate::sqp::Nlp::bounds(tr);
    let end = tr.range(Block::Params).end;
    let first = end - names.len();
    names
        .iter()
        .zip(values)
        .enumerate()
        .filter(|&(j, (_, &v))| {
            let (lo, hi) = (w_lb[first + j], w_ub[first + j]);
            let span = hi - lo;
            span.is_finite() && (v - lo <= 1e-6 * span || hi - v <= 1e-6 * span)
        })
        .map(|(_, (n, _))| n.clone())
        .collect()
}

/// The test of a candidate without a null value (the heel pad, whose limit of infinite
/// stiffness is the rigid heel): the decrease of a full re-fit with the candidate from
/// the solution, `objective` → `refit_objective`, in units of the residual mean square
/// `objective / data_rows`, against the χ²ₖ 0.1 % point as a score test's. The null
/// lies on the boundary and one parameter (the damping) has no meaning there, so the
/// χ²ₖ reference is an approximation; `diagnose` offers it only where the pad was shown
/// not to gain on data without one (sample targets, one-sided node targets).
pub fn refit_test(
    effect: &EffectSpec,
    parameters: Vec<String>,
    values: Vec<f64>,
    objective: f64,
    refit_objective: f64,
    data_rows: usize,
    iterations: usize,
) -> ScoreTest {
    ScoreTest {
        steps: iterations,
        refit: true,
        ..ScoreTest::from_decrease(
            effect,
            parameters,
            values,
            objective - refit_objective,
            objective,
            data_rows,
        )
    }
}

impl ScoreTest {
    /// The test of a candidate whose parameters (at `values` after its re-fit) lower the
    /// cost `objective` by `decrease` (a negative one counts as none): the decrease in
    /// units of the residual mean square `objective / data_rows` against the χ²ₖ 0.1 %
    /// point, `k` the number of parameters. No steps, not a full re-fit.
    fn from_decrease(
        effect: &EffectSpec,
        parameters: Vec<String>,
        values: Vec<f64>,
        decrease: f64,
        objective: f64,
        data_rows: usize,
    ) -> Self {
        let decrease = decrease.max(0.0);
        let statistic = decrease / (objective / data_rows.max(1) as f64);
        let threshold = chi2_999(parameters.len());
        ScoreTest {
            label: effect.label(),
            effect: effect.clone(),
            parameters,
            step_values: values,
            at_bound: Vec::new(),
            predicted_decrease: decrease,
            predicted_fraction: decrease / objective,
            statistic,
            threshold,
            mean_square: objective / data_rows.max(1) as f64,
            model_null: None,
            model_null_reading: ModelNullReading::default(),
            noncentrality: 0.0,
            significant: statistic > threshold,
            expected_channels: Vec::new(),
            steps: 0,
            refit: false,
            statistic_independent: statistic,
            inflation: 1.0,
            identifiability: None,
            testable: true,
            hint: None,
            held_out: None,
            found: false,
            verdict: String::new(),
        }
    }

    /// Measure the decrease in units of the residual mean square `mean_square` (the
    /// largest model's, as an F-test's denominator) instead of the run's own, keeping the
    /// variance inflation, and judge it again.
    pub fn set_mean_square(&mut self, mean_square: f64) {
        if mean_square > 0.0 && mean_square.is_finite() {
            self.mean_square = mean_square;
            self.statistic_independent = self.predicted_decrease / mean_square;
            self.set_inflation(self.inflation);
        }
    }

    /// Divide the statistic by the variance inflation `phi` of correlated residuals
    /// (≥ 1) and judge it again.
    pub fn set_inflation(&mut self, phi: f64) {
        self.inflation = phi.max(1.0);
        self.statistic = self.statistic_independent / self.inflation;
        self.judge();
    }

    /// Record whether the candidate is identifiable; an untestable one is not
    /// significant whatever its statistic.
    pub fn set_identifiability(&mut self, id: stats::Identifiability, hint: Option<String>) {
        self.testable = id.testable;
        self.identifiability = Some(id);
        self.hint = if self.testable { None } else { hint };
        self.judge();
    }

    /// Record the candidate's decrease on the model's own trial (cost units) and what its
    /// truncated re-fit reads there: its statistic is then judged against the noncentral
    /// χ²ₖ(λ), λ that decrease in the statistic's units. With noise, the statistic of a
    /// candidate whose fitted values relieve the cost by a decrease `d₀` is
    /// `(√(d₀/σ²φ) + z)²`-like: noncentral χ².
    pub fn set_model_null(&mut self, decrease: f64, reading: ModelNullReading) {
        self.model_null = Some(decrease.max(0.0));
        self.model_null_reading = reading;
        self.judge();
    }

    /// The decrease the candidate explains beyond what it lowers on the model's own trial
    /// (cost units): what the data ask of it, without the relief it gives on any trial.
    pub fn decrease_beyond_model_null(&self) -> f64 {
        self.predicted_decrease - self.model_null.unwrap_or(0.0)
    }

    /// Whether the candidate's reading is biased: on the model's own trial, where its true
    /// values are its null values, some parameter reads away from its null value by more
    /// than 20 % of the run's reading (both measured from the null value), and by more
    /// than 2 sd (its sd there, in that trial's noise; the run's where that is unknown) or
    /// as far as a bound of its range.
    pub fn reading_biased(&self) -> bool {
        let reading = &self.model_null_reading;
        let run_sd = self.identifiability.as_ref().map(|i| i.sd.clone());
        (0..reading.values.len().min(reading.start.len())).any(|i| {
            let null = reading.values[i] - reading.start[i];
            let run = self
                .step_values
                .get(i)
                .map_or(0.0, |v| v - reading.start[i]);
            let sd = reading
                .sd
                .get(i)
                .copied()
                .flatten()
                .or_else(|| run_sd.as_ref().and_then(|s| s.get(i).copied().flatten()));
            let beyond_noise = reading.at_bound || null.abs() > 2.0 * sd.unwrap_or(0.0);
            null.abs() > 0.2 * run.abs() && beyond_noise
        })
    }

    /// What the candidate reads on the model's own trial: `where it is 0.0000, it reads
    /// -0.9800`.
    pub fn model_null_text(&self) -> String {
        let list = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{x:.4}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        format!(
            "where it is {}, it reads {}",
            list(&self.model_null_reading.start),
            list(&self.model_null_reading.values)
        )
    }

    /// Whether the statistic clears the central χ²ₖ point but not the model null's.
    fn beyond_central_only(&self) -> bool {
        self.model_null.is_some() && self.statistic > chi2_999(self.parameters.len())
    }

    /// The threshold at the noncentrality the model null gives, and the verdict on it.
    fn judge(&mut self) {
        let k = self.parameters.len();
        self.noncentrality = match self.model_null {
            Some(d0) if self.mean_square > 0.0 => d0 / (self.mean_square * self.inflation),
            _ => 0.0,
        };
        self.threshold = if self.noncentrality > 0.0 {
            noncentral_chi2_point(k, self.noncentrality, 0.001)
        } else {
            chi2_999(k)
        };
        self.significant = self.testable && self.statistic > self.threshold;
    }

    /// Settle `found` and `verdict` from the tests so far.
    pub fn settle(&mut self) {
        let (found, verdict) = if !self.testable {
            (false, "not testable with this run's cost".to_string())
        } else if !self.significant && self.beyond_central_only() {
            (false, BELOW_MODEL_NULL.into())
        } else if !self.significant {
            (false, "not significant".into())
        } else if !self.at_bound.is_empty() {
            // the data want more than the admissible range: a misfit of the model, which
            // the candidate only leans against, more likely than this effect
            (false, "significant at its bound, not a reading".into())
        } else {
            match &self.held_out {
                Some(h) if h.beyond_noise => (true, "found".into()),
                // too weakly informed there to confirm or refute it
                Some(h) if h.too_weakly_informed() => (false, NOT_VALIDATABLE.into()),
                Some(_) => (false, "not confirmed on the held-out half cycle".into()),
                // no other half cycle, validation off, or a candidate tested by a full
                // re-fit (no reduced curvature to set its band): the diagnosis says why
                None => (true, "significant, not validated".into()),
            }
        };
        self.found = found;
        self.verdict = verdict;
        if self.significant && self.at_bound.is_empty() && self.reading_biased() {
            self.verdict += &format!(
                "; its value is not a reading (on the model's own trial, {})",
                self.model_null_text()
            );
        }
    }
}

/// The signed error series of each Table 3 channel of the solution in `w` against
/// `data` at the nodes, the right leg's then the left's with a NaN between (so the two
/// legs are separate segments for [`stats::effective_sample_size`]).
pub fn channel_series(
    tr: &Transcription,
    w: &[f64],
    continuous: &[usize],
    t0: f64,
    model: &crate::model::GaitModel,
    sets: &[crate::model::ConstraintSet],
    data: &crate::data::GaitData,
) -> Result<Vec<(String, Vec<f64>)>, DiagnoseError> {
    use super::evaluation::{Comparison, GaitSolution};
    let sol = GaitSolution::from_nlp(tr, w, continuous, t0);
    let nodes = sol.node_samples(model, sets)?;
    let cmp = Comparison::through_model(&nodes, data, model, &sol.theta)?;
    let n = cmp.len();
    Ok(cmp
        .table_channels()
        .into_iter()
        .map(|c| {
            let mut e = c.errors;
            if e.len() == 2 * n {
                e.insert(n, f64::NAN);
            }
            (c.name, e)
        })
        .collect())
}

/// Approximate standard deviations of the free parameters θ at a least-squares solution
/// `w`: `sd_j = √(2 s² (H⁻¹)_jj)` with `H` the Gauss–Newton Hessian reduced to the
/// linearised constraints and `s² = J/(N − p)` (`N` data residuals, `p` = number of θ).
/// `(H⁻¹)_jj` comes from the Gauss–Newton step's equality-constrained QP on its active
/// constraints ([`GaussNewtonModel::reduced_inverse`]). A parameter at a bound gets
/// `None`.
pub fn parameter_sd(
    tr: &Transcription,
    w: &[f64],
    data_rows: usize,
) -> Result<Vec<Option<f64>>, DiagnoseError> {
    let cols: Vec<usize> = tr.range(Block::Params).collect();
    let (w_lb, w_ub, _, _) = crate::sqp::Nlp::bounds(tr);
    let m = GaussNewtonModel::new(tr, w, 0.0)?;
    let base = m.step(None)?;
    let p = cols.len();
    let s2 = m.objective() / (data_rows.saturating_sub(p)).max(1) as f64;
    let at_bound = |col: usize| {
        let span = w_ub[col] - w_lb[col];
        w[col] - w_lb[col] < 1e-9 * span || w_ub[col] - w[col] < 1e-9 * span
    };
    // (H⁻¹)_jj from the equality-constrained QPs of the step's active set; should one
    // fail, from the full QP's response to a shifted gradient, parameter by parameter
    let diagonal: Vec<Option<f64>> = match m.reduced_inverse(&base, &cols) {
        Ok(inv) => (0..p).map(|j| Some(inv[j][j])).collect(),
        Err(_) => cols
            .iter()
            .map(|&col| {
                if at_bound(col) {
                    Ok(None)
                } else {
                    probed_inverse_diagonal(tr.n(), &m, &base, col, w_ub[col] - w_lb[col]).map(Some)
                }
            })
            .collect::<Result<_, DiagnoseError>>()?,
    };
    Ok(cols
        .iter()
        .zip(diagonal)
        .map(|(&col, v)| {
            v.filter(|&v| v > 0.0 && !at_bound(col))
                .map(|v| (2.0 * s2 * v).sqrt())
        })
        .collect())
}

/// `(H⁻¹)_jj` of variable `col` (of `n`, bound span `span`) as the Gauss–Newton step's
/// response to a gradient shift in it, the shift aimed at a response of about 1e-3 of the
/// span (QP accuracy limits small steps; large ones change the active set).
fn probed_inverse_diagonal(
    n: usize,
    m: &GaussNewtonModel<'_>,
    base: &GaussNewtonStep,
    col: usize,
    span: f64,
) -> Result<f64, DiagnoseError> {
    let target = 1e-3 * span;
    let mut eps = 1.0;
    let mut inv = f64::NAN;
    for _ in 0..4 {
        let mut shift = vec![0.0; n];
        shift[col] = eps;
        let dtheta = base.d[col] - m.step(Some(&shift))?.d[col];
        inv = dtheta / eps;
        let ratio = dtheta.abs() / target;
        if inv <= 0.0 || (0.1..=10.0).contains(&ratio) {
            break;
        }
        eps = target / inv;
    }
    Ok(inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A significant candidate that the held-out half cycle cannot tell about is neither
    /// found nor "not confirmed": it is not validatable there.
    #[test]
    fn a_weakly_informed_held_out_half_cycle_leaves_the_candidate_not_validatable() {
        let mut t = significant_slope();
        let held = |reading: Option<HeldOutReading>, beyond: bool| HeldOut {
            stride: 1,
            mirrored: true,
            trial: None,
            window: (0.6, 1.2),
            values: vec![0.01],
            objective: 1.0,
            change: 0.0,
            change_fraction: 0.0,
            band: 0.01,
            beyond_noise: beyond,
            reading,
        };
        let weak = HeldOutReading::from_changes(0.0, -0.004, 5e-4, 3.5).unwrap();
        assert!(!weak.powered, "{weak:?}");
        let strong = HeldOutReading::from_changes(0.0, -0.4, 5e-4, 3.5).unwrap();
        assert!(strong.powered, "{strong:?}");
        for (h, verdict, found) in [
            (held(Some(weak.clone()), false), NOT_VALIDATABLE, false),
            (
                held(Some(strong), false),
                "not confirmed on the held-out half cycle",
                false,
            ),
            (
                held(None, false),
                "not confirmed on the held-out half cycle",
                false,
            ),
            (held(Some(weak), true), "found", true),
        ] {
            t.held_out = Some(h);
            t.settle();
            assert_eq!((t.verdict.as_str(), t.found), (verdict, found));
        }
    }
}
