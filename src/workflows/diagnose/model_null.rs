//! The model null: how far each candidate lowers the cost when the model lacks nothing.
//!
//! A candidate can lower a track's cost on data that do not ask for it. An actuator
//! property changes what the effort regularisation charges (a lower MTG damping needs
//! less excitation for the same motion, and following noisy targets takes fast motion),
//! and any freed parameter gives the fit room to trade effort for tracking. That
//! decrease is no evidence, and it is not only noise either: it is there on every trial,
//! and it grows with the data's noise (a free MTG damping on the bundled trial's model
//! lowers the cost of its own trial by 0.12 without noise, 1.3 with 0.25° of angle noise
//! and 5.4 with 0.5°). So the diagnosis measures it. The run's own model drives a trial
//! made from the run's solution, at the run's sampling rate, with the noise the run's
//! trial shows ([`measured_noise`]); the plain model is tracked on it with the run's
//! cost; and each candidate is freed there as in its score test. Its decrease `d₀` there
//! is what the candidate gives with nothing missing. On the run, the statistic of such a
//! candidate is then a noncentral χ²ₖ with noncentrality `λ = d₀/(s²φ)` (the run's
//! residual mean square and variance inflation), and it is judged against that
//! distribution's 0.1 % point ([`ScoreTest::set_model_null`]). The held-out validation
//! asks the same margin again (`heldout::validate`).
//!
//! The same trial checks the candidate's reading: there its true value is the model's
//! (the null value), so where its re-fit reads it away from that by more than 20 % of the
//! run's reading, and by more than 2 sd or as far as a bound, the run's value is biased
//! the same way (a free MTG damping runs towards zero on any trial: the muscles can
//! cancel any damping, and only the effort term, which always prefers less, tells values
//! apart). Such a candidate's value is reported as not a reading.
//!
//! The trial and its track are kept in the diagnosis folder (`model_null/`).

use super::super::track::TrackingProblem;
#[allow(unused_imports)]
use super::super::{note, warn_note, Progress};
use super::noise::{decrease_at_solution, linearisation};
use super::RunInputs;
use crate::data::write_sagittal_csv;
use crate::integrate::IntegratorSettings;
use crate::problems::diagnose::stats::candidate_identifiability_at;
use crate::problems::diagnose::{
    score_test_from, theta_of, ModelNullReading, ScoreTest, TrackingRunSetup,
};
use crate::problems::evaluation::GaitSolution;
use crate::problems::synth::{synthesize, MeasurementOffsets, NoiseModel, SynthSettings};
use crate::sqp::linearised::GaussNewtonModel;
use anyhow::anyhow;
use rayon::prelude::*;
use std::path::Path;
use std::sync::Arc;

/// Length of the model's trial in half cycles of the run's solution: the half cycle the
/// track reads, with room for the event search on both sides.
const HALF_CYCLES: f64 = 3.0;

/// The plain model tracked on the trial its own solution makes.
struct NullTrack {
    /// The run's setup on the model's trial.
    setup: TrackingRunSetup,
    /// The plain model's solution there.
    solution: GaitSolution,
    /// The noise its trial was made with.
    noise: NoiseModel,
    /// Its cost and SQP iterations.
    objective: f64,
    iterations: usize,
}

/// Measure every candidate of `tests` that a score test found significant against the
/// central χ² (not one tested by a full re-fit) on the model's own trial, kept in `dir`,
/// and judge it again against its model null. Where the trial cannot be made or
/// tracked, says why and leaves the tests against the central χ².
pub(super) fn judge_against_model_null(
    run: &RunInputs,
    base: &TrackingProblem,
    dir: &Path,
    tests: &mut [ScoreTest],
) -> anyhow::Result<()> {
    // the noncentral point lies above the central one, so only a candidate significant
    // against the central χ² can change its verdict
    let judged = |t: &ScoreTest| t.significant && !t.refit;
    if !tests.iter().any(judged) {
        return Ok(());
    }
    let progress = run.progress;
    let null = match track_model_trial(run, base, dir) {
        Ok(null) => null,
        Err(e) => {
            warn_note!(
                progress,
                "the model's own trial could not be made or tracked ({e:#}): the candidates are judged against the central χ², without what they lower on data that lack nothing"
            );
            return Ok(());
        }
    };
    note!(
        progress,
        "the model's own trial (its solution, the trial's noise: {:.2}°, {:.1} mm, {:.1} N, CoP {:.1} mm): the plain model tracked there, J = {:.6} ({} iterations)",
        null.noise.angle_rad.to_degrees(),
        1e3 * null.noise.position_m,
        null.noise.force_n,
        1e3 * null.noise.cop_m,
        null.objective,
        null.iterations
    );
    let leftover = {
        let mut at = TrackingProblem::build(&null.setup, &[])?;
        at.setup
            .start_from(&null.solution)
            .map_err(|e| anyhow!(e))?;
        decrease_at_solution(&linearisation(at))?.1
    };
    let decreases: Vec<anyhow::Result<(f64, ModelNullReading)>> = tests
        .par_iter()
        .map(|t| {
            if !judged(t) {
                return Ok((0.0, ModelNullReading::default()));
            }
            let mut prob = linearisation(TrackingProblem::build(
                &null.setup,
                std::slice::from_ref(&t.effect),
            )?);
            prob.setup
                .start_from(&null.solution)
                .map_err(|e| anyhow!(e))?;
            let k = t.parameters.len();
            prob.with_transcription(|tr, cycle, w| {
                let first = GaussNewtonModel::new(tr, &w, 1e-12).map_err(|e| anyhow!(e))?;
                let step = first.step(None).map_err(Arc::new);
                let rows = prob
                    .setup
                    .data_rows(&prob.model, &prob.sets, &cycle.continuous);
                // each parameter's sd there, in that trial's own noise, which tells a
                // reading the cost leans to from one that noise gives
                let s2 = first.objective() / rows.max(1) as f64;
                let names = t.parameters.clone();
                let base = step.as_ref().map_err(|e| e.as_ref());
                let sd = candidate_identifiability_at(tr, &first, base, names, s2, t.inflation).sd;
                // the candidate's truncated re-fit there from its null values, as in its
                // score test: its decrease beyond the plain model's leftover, its values
                let (there, _) = score_test_from(
                    &t.effect,
                    t.parameters.clone(),
                    tr,
                    &first,
                    step,
                    leftover,
                    rows,
                    None,
                )
                .map_err(|e| anyhow!(e))?;
                let theta = theta_of(tr, &w);
                let reading = ModelNullReading {
                    start: theta[theta.len() - k..].to_vec(),
                    values: there.step_values,
                    sd,
                    at_bound: !there.at_bound.is_empty(),
                };
                Ok((there.predicted_decrease, reading))
            })
        })
        .collect();
    for (t, d) in tests.iter_mut().zip(decreases) {
        if !judged(t) {
            continue;
        }
        match d {
            Ok((d0, reading)) => {
                t.set_model_null(d0, reading);
                note!(
                    progress,
                    "  {:<32} on the model's own trial  {:>10.3e} (λ {:.1}): threshold {:.1}, statistic {:.1}{}{}",
                    t.label,
                    d0.max(0.0),
                    t.noncentrality,
                    t.threshold,
                    t.statistic,
                    if t.significant { "  significant" } else { "" },
                    if t.reading_biased() { "; its value there is not the model's: not a reading" } else { "" }
                );
            }
            Err(e) => warn_note!(
                progress,
                "  {}: not measured on the model's own trial ({e:#}); judged against the central χ²",
                t.label
            ),
        }
    }
    Ok(())
}

/// Make the trial the run's model gives from its solution (at the run's sampling rate,
/// with the noise the run's trial shows: [`measured_noise`]), keep it in `dir`, and
/// track the plain model on it with the run's cost, from the run's solution.
fn track_model_trial(
    run: &RunInputs,
    base: &TrackingProblem,
    dir: &Path,
) -> anyhow::Result<NullTrack> {
    let mut truth = run.solution.clone();
    let t0 = truth.phases[0].t0;
    truth.phases.iter_mut().for_each(|p| p.t0 -= t0);
    let half = truth.span().1;
    // the noise of the samples as read, before the run's kinematics cutoff (the model's
    // trial is filtered as the run's was)
    let raw = super::super::trial::load_trial(&run.setup.into())?.data;
    let noise = measured_noise(&raw);
    let settings = SynthSettings {
        rate_hz: sampling_rate(&base.data.time)?,
        start_s: -0.5 * half,
        duration_s: HALF_CYCLES * half,
        noise,
        integrator: IntegratorSettings {
            rtol: 1e-10,
            atol: 1e-10,
            ..Default::default()
        },
        measurement: MeasurementOffsets::default(),
    };
    let (data, _) = synthesize(&base.model, &base.sets, &truth, &settings, "model_null")
        .map_err(|e| anyhow!("making the trial: {e}"))?;
    std::fs::create_dir_all(dir).map_err(|e| anyhow!("{}: {e}", dir.display()))?;
    let (csv, meta) = write_sagittal_csv(&data);
    crate::runfolder::write_atomic(dir, "trial.csv", csv.as_bytes())?;
    crate::runfolder::write_atomic(dir, "trial_meta.json", meta.as_bytes())?;
    let setup = TrackingRunSetup {
        data: Some(dir.join("trial.csv")),
        overground: false,
        forces: None,
        plates: Vec::new(),
        lab_axes: None,
        belt_speed: None,
        window: None,
        stride: None,
        mirror: false,
        guess: Default::default(),
        ..run.setup.clone()
    };
    let mut prob = TrackingProblem::build(&setup, &[])?;
    prob.setup
        .start_from(run.solution)
        .map_err(|e| anyhow!(e))?;
    let settings = super::refit::full_solve_settings(run.args, &prob);
    let (res, solution) = prob.solve(&settings, &super::super::Quiet)?;
    if res.status != crate::sqp::SqpStatus::Converged {
        return Err(anyhow!("its track stopped: {}", res.status));
    }
    super::starts::keep(dir, &setup, &solution)?;
    Ok(NullTrack {
        setup,
        noise,
        objective: res.objective,
        iterations: res.history.len().saturating_sub(1),
        solution,
    })
}

/// The white noise a trial's samples show, per kind of channel: each channel's standard
/// deviation from its second differences (`Δ²x = x₊ − 2x + x₋` has variance 6σ² for
/// white noise), robustly (1.4826 × the median absolute value, so impacts and gaps do
/// not count), the median over the channels of a kind. The signal's own curvature counts
/// too, so this is an upper bound: at 60–100 Hz a joint angle's curvature alone gives
/// about 0.1°.
pub(super) fn measured_noise(data: &crate::data::GaitData) -> NoiseModel {
    let (force_feet, cop_feet) = match &data.forces {
        Some(f) => (&f.feet, &f.feet),
        None => (&data.feet, &data.feet),
    };
    let kind = |channels: Vec<&Vec<f64>>| {
        let mut sds: Vec<f64> = channels
            .into_iter()
            .filter_map(|x| white_noise_sd(x))
            .collect();
        sds.sort_by(f64::total_cmp);
        if sds.is_empty() {
            0.0
        } else {
            sds[sds.len() / 2]
        }
    };
    NoiseModel {
        position_m: kind(data.q[..2].iter().collect()),
        angle_rad: kind(data.q[2..].iter().collect()),
        force_n: kind(force_feet.iter().flat_map(|f| [&f.fx, &f.fy]).collect()),
        cop_m: kind(cop_feet.iter().map(|f| &f.cop_x).collect()),
        seed: 1,
    }
}

/// The white-noise standard deviation of one channel from its second differences
/// (robust; `None` with fewer than ten finite ones).
fn white_noise_sd(x: &[f64]) -> Option<f64> {
    let mut d2: Vec<f64> = x
        .windows(3)
        .map(|w| (w[2] - 2.0 * w[1] + w[0]).abs())
        .filter(|v| v.is_finite())
        .collect();
    if d2.len() < 10 {
        return None;
    }
    d2.sort_by(f64::total_cmp);
    Some(1.4826 * d2[d2.len() / 2] / 6f64.sqrt())
}

/// The sampling rate (Hz) of a trial's time column: samples over span.
fn sampling_rate(time: &[f64]) -> anyhow::Result<f64> {
    let (Some(first), Some(last)) = (time.first(), time.last()) else {
        return Err(anyhow!("the trial has no samples"));
    };
    let span = last - first;
    if !(span > 0.0) || time.len() < 2 {
        return Err(anyhow!("the trial spans no time"));
    }
    Ok((time.len() - 1) as f64 / span)
}

#[cfg(test)]
mod tests {
    use super::white_noise_sd;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// White noise of a known standard deviation on a gait-like signal (a joint angle's
    /// swing at 1 Hz, sampled at 100 Hz) is read back from the second differences within
    /// 10 %, whatever the signal's amplitude; a few impact-like jumps do not move it; and
    /// the smooth signal alone reads far below the noise (the bound the curvature sets).
    #[test]
    fn white_noise_is_read_back_from_the_second_differences() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let n = 2000;
        let signal: Vec<f64> = (0..n)
            .map(|i| 0.5 * (2.0 * std::f64::consts::PI * i as f64 / 100.0).sin())
            .collect();
        for sigma in [0.002, 0.01] {
            let noise = Normal::new(0.0, sigma).unwrap();
            let mut x: Vec<f64> = signal.iter().map(|s| s + noise.sample(&mut rng)).collect();
            for k in (100..n).step_by(400) {
                x[k] += 50.0 * sigma;
            }
            let got = white_noise_sd(&x).unwrap();
            assert!((got / sigma - 1.0).abs() < 0.1, "σ {sigma}: read {got}");
        }
        let smooth = white_noise_sd(&signal).unwrap();
        assert!(smooth < 1e-3, "the signal alone reads {smooth}");
        assert!(white_noise_sd(&[0.0; 9]).is_none());
    }
}
