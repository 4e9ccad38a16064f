//! Held-out validation of `diagnose`'s significant candidates.
//!
//! A candidate significant on the run's half cycle is fitted there (its truncated
//! re-fit's values); those values, fixed, are then applied to another half cycle of the
//! same trial that the fit did not see: the next one, or one before, or else the other
//! leg's half cycle with the legs swapped (`mirror`; a side-bound candidate, e.g. the
//! right plate's clock, then applies to the swapped side, whose data it was fitted on).
//! The bundled trial holds one half cycle from a left heel strike to a right one
//! (1.252–1.858 s) and two the other way round (0.624–1.252, 1.858–2.467 s). There the
//! plain model is tracked once; each candidate's change
//! of that cost, after a truncated re-fit of the other variables, must exceed its noise
//! band ([`crate::problems::diagnose::stats::held_out_band`]) for the candidate to be
//! "found".

use super::super::track::TrackingProblem;
#[allow(unused_imports)]
use super::super::{note, Progress};
use super::DiagnoseRequest;
use crate::model::effects::EffectSpec;
use crate::problems::diagnose::stats::{curvature_along, held_out_band};
use crate::problems::diagnose::{
    truncated_refit, HeldOut, HeldOutReading, ScoreTest, TrackingRunSetup, MAX_STEPS, REL_STOP,
};
use crate::problems::evaluation::GaitSolution;
use anyhow::anyhow;

/// The plain model tracked on a held-out half cycle.
pub(super) struct HeldOutBase {
    /// The run's setup with the held-out half cycle (`stride`).
    setup: TrackingRunSetup,
    /// Which half cycle.
    pub stride: usize,
    /// Whether it is the other leg's (legs swapped against the run's).
    pub mirrored: bool,
    /// Another recording of the subject, whose first half cycle it is (`None`: the run's
    /// own trial).
    pub trial: Option<std::path::PathBuf>,
    /// Its span (s).
    pub window: (f64, f64),
    /// The plain model's solution there.
    solution: GaitSolution,
    /// Its cost.
    pub objective: f64,
    /// The truncated re-fit's decrease left at that solution (subtracted from each
    /// candidate's, as in the score test).
    leftover: f64,
    /// Residual mean square `J/N` there.
    pub s2: f64,
    /// SQP iterations of its solve and whether it converged.
    pub iterations: usize,
    pub converged: bool,
}

/// A half cycle tried as held-out and passed over.
#[derive(Debug, thiserror::Error)]
pub(super) enum PassedOver {
    /// Its problem cannot be built (the trial does not hold it, or its data are unusable).
    #[error("{name}: {source:#}")]
    Unusable {
        /// The half cycle ([`half_cycle_name`]).
        name: String,
        /// Why its problem cannot be built.
        source: anyhow::Error,
    },
    /// It is the run's own half cycle.
    #[error("{name} is the run's own")]
    RunsOwn {
        /// The half cycle ([`half_cycle_name`]).
        name: String,
    },
}

/// Why a trial has no held-out half cycle: each half cycle tried, in order, and why it
/// was passed over.
#[derive(Debug, thiserror::Error)]
#[error("{}", passed_over.iter().map(ToString::to_string).collect::<Vec<_>>().join("; "))]
pub(super) struct NoHeldOut {
    /// The half cycles tried.
    pub passed_over: Vec<PassedOver>,
}

/// The half cycles tried as held-out, in order, as (stride, legs swapped against the
/// run's): the next one, the ones before, then the other leg's (the first three), then
/// the one after next.
fn strides(run: &TrackingRunSetup) -> Vec<(usize, bool)> {
    let own = run.stride.unwrap_or(1);
    let mut s = vec![(own + 1, false)];
    s.extend((1..own).rev().map(|k| (k, false)));
    s.extend((1..=3).map(|k| (k, true)));
    s.push((own + 2, false));
    s
}

/// Track the plain model on the held-out half cycle: the first of another recording of
/// the subject where the request names one (`--held-out-data`), else the first half cycle
/// of the trial other than the run's (`run_window`) that the trial holds; `None` (with
/// why) when there is none.
pub(super) fn held_out_base(
    args: &DiagnoseRequest,
    run: &TrackingRunSetup,
    run_window: (f64, f64),
    progress: &dyn Progress,
) -> anyhow::Result<Result<HeldOutBase, NoHeldOut>> {
    if let Some(data) = &args.held_out_data {
        let setup = TrackingRunSetup {
            data: Some(data.clone()),
            forces: None,
            plates: Vec::new(),
            lab_axes: None,
            belt_speed: None,
            stride: None,
            window: None,
            check_points: vec![],
            guess: Default::default(),
            ..run.clone()
        };
        let prob = TrackingProblem::build(&setup, &[])
            .map_err(|e| anyhow!("--held-out-data {}: {e:#}", data.display()))?;
        let mut base = track_base(args, setup, prob, 1, false, progress)?;
        base.trial = Some(data.clone());
        return Ok(Ok(base));
    }
    let mut passed_over = Vec::new();
    for (stride, mirrored) in strides(run) {
        let name = half_cycle_name(stride, mirrored);
        let (setup, prob) = match half_cycle(run, stride, mirrored) {
            Ok(p) => p,
            Err(source) => {
                passed_over.push(PassedOver::Unusable { name, source });
                continue;
            }
        };
        if !mirrored && (prob.setup.window.0 - run_window.0).abs() < 1e-6 {
            passed_over.push(PassedOver::RunsOwn { name });
            continue;
        }
        return track_base(args, setup, prob, stride, mirrored, progress).map(Ok);
    }
    Ok(Err(NoHeldOut { passed_over }))
}

/// The setup and the plain problem of `run`'s half cycle `stride` (legs swapped against
/// the run's own when `mirrored`).
fn half_cycle(
    run: &TrackingRunSetup,
    stride: usize,
    mirrored: bool,
) -> anyhow::Result<(TrackingRunSetup, TrackingProblem)> {
    let setup = TrackingRunSetup {
        stride: Some(stride),
        mirror: run.mirror != mirrored,
        window: None,
        check_points: vec![],
        ..run.clone()
    };
    let prob = TrackingProblem::build(&setup, &[])?;
    Ok((setup, prob))
}

/// Solve the plain problem `prob` of half cycle `stride` in full, and its Gauss–Newton
/// decrease left at the solution.
fn track_base(
    args: &DiagnoseRequest,
    setup: TrackingRunSetup,
    prob: TrackingProblem,
    stride: usize,
    mirrored: bool,
    progress: &dyn Progress,
) -> anyhow::Result<HeldOutBase> {
    let window = prob.setup.window;
    {
        note!(
            progress,
            "held-out {} ({:.3}–{:.3} s): tracking the plain model there",
            args.held_out_data
                .as_deref()
                .map_or_else(|| half_cycle_name(stride, mirrored), other_recording_name),
            window.0,
            window.1
        );
    }
    let mut prob = prob;
    // a kept track of this half cycle (`--start`, an earlier diagnosis's `held_out`)
    // starts the solve instead of the data, when it fits
    super::starts::start_from_kept(
        args,
        &setup,
        &mut prob,
        || TrackingProblem::build(&setup, &[]),
        "starting from the data",
        progress,
    )?;
    let settings = super::refit::full_solve_settings(args, &prob);
    let (res, solution) = prob.solve(&settings, &super::super::Quiet)?;
    let mut at = TrackingProblem::build(&setup, &[])?;
    at.setup.start_from(&solution).map_err(|e| anyhow!(e))?;
    let (objective, leftover, rows) = super::noise::decrease_at_solution(&at)?;
    {
        note!(
            progress,
            "  held-out J = {objective:.6} ({} iterations{}), Gauss–Newton decrease left {leftover:.2e}",
            res.history.len().saturating_sub(1),
            if res.status == crate::sqp::SqpStatus::Converged { "" } else { ", not converged" }
        );
    }
    Ok(HeldOutBase {
        stride,
        mirrored,
        trial: None,
        window,
        objective,
        leftover,
        s2: objective / rows.max(1) as f64,
        iterations: res.history.len().saturating_sub(1),
        converged: res.status == crate::sqp::SqpStatus::Converged,
        solution,
        setup,
    })
}

impl HeldOutBase {
    /// Keep the plain model's track of the half cycle in `dir` (`setup.json`,
    /// `solution.json`), so that a later diagnosis of the run can start from it
    /// (`--start`).
    pub(super) fn write_into(&self, dir: &std::path::Path) -> anyhow::Result<()> {
        super::starts::keep(dir, &self.setup, &self.solution)
    }

    /// How this held-out half cycle is named ([`half_cycle_name`],
    /// [`other_recording_name`]).
    pub(super) fn name(&self) -> String {
        match &self.trial {
            Some(data) => other_recording_name(data),
            None => half_cycle_name(self.stride, self.mirrored),
        }
    }
}

/// How the first half cycle of another recording is named.
pub(super) fn other_recording_name(data: &std::path::Path) -> String {
    format!("the first half cycle of {}", data.display())
}

/// How a held-out half cycle is named: `half cycle 2`, or `half cycle 1 of the other
/// leg (mirrored)`.
pub(super) fn half_cycle_name(stride: usize, mirrored: bool) -> String {
    if mirrored {
        format!("half cycle {stride} of the other leg (mirrored)")
    } else {
        format!("half cycle {stride}")
    }
}

/// `effect` with its parameters `names` (qualified, `kind.name`) fixed at `values`; on
/// the other leg's half cycle (`mirrored`) a one-sided effect moves to the other side,
/// where the data it was fitted on now are. Both plates' gains read jointly (`each`)
/// become one fixed gain per plate, each at its own value.
pub(super) fn fixed_at(
    effect: &EffectSpec,
    names: &[String],
    values: &[f64],
    mirrored: bool,
) -> anyhow::Result<Vec<EffectSpec>> {
    let swap = |side: &str| -> String {
        match side {
            "right" if mirrored => "left",
            "left" if mirrored => "right",
            s => s,
        }
        .to_string()
    };
    // both plates' gains in one candidate: each plate's gain fixed at its own value
    if matches!(effect, EffectSpec::ForcePlateGain { side, .. } if side == "each") {
        return Ok(names
            .iter()
            .zip(values)
            .map(|(n, &error)| EffectSpec::ForcePlateGain {
                side: swap(if n.contains(".right.") {
                    "right"
                } else {
                    "left"
                }),
                error,
                free: Vec::new(),
            })
            .collect());
    }
    let mut v = serde_json::to_value(effect.fixed())?;
    for (n, x) in names.iter().zip(values) {
        let key = n.rsplit('.').next().unwrap_or(n);
        v[key] = (*x).into();
    }
    if let Some(side) = v["side"].as_str() {
        v["side"] = swap(side).into();
    }
    Ok(vec![serde_json::from_value(v).map_err(|e| {
        anyhow!("{}: fixing its parameters: {e}", effect.label())
    })?])
}

/// The fall of the held-out cost with candidate `t` fixed at `values`, the other
/// variables re-fitted by a truncated re-fit (as the score test's), less the plain
/// model's own truncated decrease there.
fn change_at(base: &HeldOutBase, t: &ScoreTest, values: &[f64]) -> anyhow::Result<f64> {
    let specs = fixed_at(&t.effect, &t.parameters, values, base.mirrored)?;
    let mut prob = TrackingProblem::build(&base.setup, &specs)?;
    prob.setup
        .start_from(&base.solution)
        .map_err(|e| anyhow!(e))?;
    let after = prob.with_transcription(|tr, _, w| {
        let (j, dec, _, _) =
            truncated_refit(tr, &w, MAX_STEPS, REL_STOP).map_err(|e| anyhow!(e))?;
        Ok(j - dec)
    })?;
    Ok(base.objective - base.leftover - after)
}

/// Apply candidate `t` (fitted on the run's half cycle) to the held-out half cycle at
/// its values `θ`, and at `−θ` for that half cycle's own curvature along them
/// ([`HeldOutReading`]): the band is the one at that curvature, not the run's, since a
/// half cycle can be far less informed about a candidate than the run's (a plate whose
/// foot is in stance in one and only pushes off in the other). Where `−θ` cannot be
/// applied (the effect refuses it), the run's curvature sets the band, as for a held
/// clock.
pub(super) fn validate(base: &HeldOutBase, t: &ScoreTest) -> anyhow::Result<HeldOut> {
    let up = change_at(base, t, &t.step_values)?;
    let reading = change_at(base, t, &opposite(t).step_values)
        .ok()
        .and_then(|down| HeldOutReading::from_changes(up, down, base.s2, t.inflation));
    Ok(match reading {
        Some(r) => judged_at(base, t, up, r.curvature).with_reading(r),
        // `−θ` refused, or the two changes do not make a parabola (a body-mass error on
        // the mass trial: +4.5 % lowers the held-out cost by 5.9e-2, −4.5 % raises it by
        // only 2.1e-2): the run's curvature sets the band, and nothing is read
        None => judged(base, t, up),
    })
}

/// The held-out validation of candidate `t` whose values lowered the held-out cost by
/// `change` (negative: it rose), judged against its noise band. The band's curvature is
/// the run's reduced curvature along the fitted values (the score test's).
fn judged(base: &HeldOutBase, t: &ScoreTest, change: f64) -> HeldOut {
    judged_at(base, t, change, band(t, base.s2).0)
}

/// [`judged`] with the band at curvature `q` along the fitted values (the held-out half
/// cycle's own, where it was measured; without curvature, `q = 0`, nothing is found).
fn judged_at(base: &HeldOutBase, t: &ScoreTest, change: f64, q: f64) -> HeldOut {
    // what the candidate lowers on the model's own data, it lowers here too without the
    // data asking for it
    let band = held_out_band(q, base.s2, t.inflation) + t.model_null.unwrap_or(0.0);
    HeldOut {
        stride: base.stride,
        mirrored: base.mirrored,
        trial: base.trial.clone(),
        window: base.window,
        values: t.step_values.clone(),
        objective: base.objective,
        change,
        change_fraction: change / base.objective,
        band,
        // a candidate without curvature here (q = 0) has no band: it must lower the cost
        beyond_noise: change > band.max(0.0) && q > 0.0,
        reading: None,
    }
}

/// `t` with its values negated, for the held-out half cycle's own curvature along them.
fn opposite(t: &ScoreTest) -> ScoreTest {
    ScoreTest {
        step_values: t.step_values.iter().map(|v| -v).collect(),
        ..t.clone()
    }
}

/// `q = θᵀHθ` along candidate `t`'s fitted values θ (0 without a reduced curvature) and
/// the upper edge of its held-out noise band at the held-out residual mean square `s2`.
fn band(t: &ScoreTest, s2: f64) -> (f64, f64) {
    let q = t
        .identifiability
        .as_ref()
        .and_then(|id| curvature_along(&id.reduced_inverse_hessian, &t.step_values))
        .unwrap_or(0.0);
    (q, held_out_band(q, s2, t.inflation))
}

/// Whether re-tracking with the pelvis position makes candidate `effect` testable: the
/// CoP offset moves the measured CoP, which the free pelvis position follows unless it
/// is tracked.
pub(super) fn hint(effect: &EffectSpec, run: &TrackingRunSetup) -> String {
    if effect.kind().contains("cop") && !run.track_pelvis_position {
        "the free pelvis position absorbs it: track the pelvis position too (`footfall track --track-pelvis-position`)".into()
    } else if !run.sample_targets {
        "the other variables (most likely the actuators) absorb it under this cost: compare every sample at its own instant (`footfall track --sample-targets`), or fit it on a second trial of the same subject".into()
    } else {
        "the other variables (most likely the actuators) absorb it under this cost: fit it on a second trial of the same subject, or fix what trades off with it".into()
    }
}

#[cfg(test)]
mod tests {
    use super::band;
    use crate::model::effects::EffectSpec;
    use crate::problems::diagnose::refit_test;
    use crate::problems::diagnose::stats::identifiability;

    /// A right-plate clock read with the curvature `a` of the bundled trial's size, at
    /// residual mean square `s2` and variance inflation `phi`.
    const A: f64 = 600.6;
    const S2: f64 = 0.3994 / 456.0;
    const PHI: f64 = 5.2;

    fn right_clock() -> (String, EffectSpec) {
        (
            "force_plate_time_offset.right.offset".to_string(),
            EffectSpec::ForcePlateTimeOffset {
                side: "right".into(),
                offset: 0.0,
                free: vec!["offset".into()],
            },
        )
    }

    /// A reading on a cost `J ≈ J* + a (δ − δ*)²` applied to held-out data with the same
    /// offset lowers that cost by about `a δ*²`. That clears the held-out band exactly
    /// when the reading lies more than 2 sd from zero, the sd being the one the reading
    /// reports (`√(φ s²/a)`): the band and the reading's sd are one noise model.
    #[test]
    fn a_reading_clears_its_held_out_band_beyond_two_sd() {
        let (a, s2, phi) = (A, S2, PHI);
        let (name, clock) = right_clock();
        let sd = (phi * s2 / a).sqrt();
        for k in [0.5, 1.5, 1.95, 2.05, 3.0, 6.0] {
            let v = k * sd;
            let mut t = refit_test(&clock, vec![name.clone()], vec![v], 1.7, 1.6, 456, 9);
            t.set_inflation(phi);
            let id = identifiability(vec![name.clone()], vec![vec![0.5 / a]], vec![0.1], s2, phi);
            assert!(
                (id.sd[0].unwrap() - sd).abs() < 1e-12 * sd,
                "{:?} against {sd}",
                id.sd
            );
            t.set_identifiability(id, None);
            let (q, edge) = band(&t, s2);
            assert!((q - 2.0 * a * v * v).abs() < 1e-9 * q, "q {q}");
            let true_change = a * v * v;
            assert_eq!(
                true_change > edge,
                k > 2.0,
                "k {k}: change {true_change}, band {edge}"
            );
        }
    }

    /// Both plates' gains read jointly are applied as one fixed gain per plate at its own
    /// value; on the other leg's half cycle each value moves to the other plate.
    #[test]
    fn joint_gains_are_fixed_one_plate_each() {
        let each = EffectSpec::parse_cli("force_plate_gain:side=each").unwrap();
        let names = [
            "force_plate_gain.right.error",
            "force_plate_gain.left.error",
        ]
        .map(String::from);
        let fixed = super::fixed_at(&each, &names, &[0.02, 0.06], false).unwrap();
        let plate = |s: &EffectSpec| match s {
            EffectSpec::ForcePlateGain { side, error, free } => {
                assert!(free.is_empty());
                (side.clone(), *error)
            }
            other => panic!("{other:?}"),
        };
        let got: Vec<_> = fixed.iter().map(plate).collect();
        assert_eq!(
            got,
            [("right".to_string(), 0.02), ("left".to_string(), 0.06)]
        );
        let mirrored: Vec<_> = super::fixed_at(&each, &names, &[0.02, 0.06], true)
            .unwrap()
            .iter()
            .map(plate)
            .collect();
        assert_eq!(
            mirrored,
            [("left".to_string(), 0.02), ("right".to_string(), 0.06)]
        );
        // a one-plate gain keeps its one spec, moved to the other plate when mirrored
        let left = EffectSpec::parse_cli("force_plate_gain:side=left").unwrap();
        let one = super::fixed_at(&left, &names[1..], &[0.06], true).unwrap();
        assert_eq!(
            one.iter().map(plate).collect::<Vec<_>>(),
            [("right".to_string(), 0.06)]
        );
    }
}
