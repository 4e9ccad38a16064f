//! Held-out validation of `diagnose`'s significant candidates, and the re-track that
//! makes untestable candidates testable (`--make-testable`).
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

use super::super::track::{TrackedRun, TrackingProblem};
#[allow(unused_imports)]
use super::super::{note, Progress};
use super::{sibling, DiagnoseRequest};
use crate::model::effects::EffectSpec;
use crate::problems::diagnose::stats::{curvature_along, held_out_band};
use crate::problems::diagnose::{
    truncated_refit, HeldOut, ScoreTest, TrackingRunSetup, MAX_STEPS, REL_STOP,
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

/// Track the plain model on the first half cycle of the trial other than the run's
/// (`run_window`) that the trial holds; `None` (with why) when there is none.
pub(super) fn held_out_base(
    args: &DiagnoseRequest,
    run: &TrackingRunSetup,
    run_window: (f64, f64),
    progress: &dyn Progress,
) -> anyhow::Result<Result<HeldOutBase, String>> {
    let mut why = Vec::new();
    for (stride, mirrored) in strides(run) {
        let setup = TrackingRunSetup {
            stride: Some(stride),
            mirror: run.mirror != mirrored,
            window: None,
            check_points: vec![],
            ..run.clone()
        };
        let name = half_cycle_name(stride, mirrored);
        let prob = match TrackingProblem::build(&setup, &[]) {
            Ok(p) => p,
            Err(e) => {
                why.push(format!("{name}: {e:#}"));
                continue;
            }
        };
        let window = prob.setup.window;
        if !mirrored && (window.0 - run_window.0).abs() < 1e-6 {
            why.push(format!("{name} is the run's own"));
            continue;
        }
        {
            note!(
                progress,
                "held-out {name} ({:.3}–{:.3} s): tracking the plain model there",
                window.0,
                window.1
            );
        }
        let settings = super::refit::full_solve_settings(args, &prob);
        let (res, solution) = prob.solve(&settings, &super::super::Quiet)?;
        let mut at = TrackingProblem::build(&setup, &[])?;
        at.setup.start_from(&solution).map_err(|e| anyhow!(e))?;
        let (objective, leftover, rows) = super::decrease_at_solution(&at)?;
        {
            note!(
                progress,
                "  held-out J = {objective:.6} ({} iterations{}), Gauss–Newton decrease left {leftover:.2e}",
                res.history.len().saturating_sub(1),
                if res.status == crate::sqp::SqpStatus::Converged { "" } else { ", not converged" }
            );
        }
        return Ok(Ok(HeldOutBase {
            stride,
            mirrored,
            window,
            objective,
            leftover,
            s2: objective / rows.max(1) as f64,
            iterations: res.history.len().saturating_sub(1),
            converged: res.status == crate::sqp::SqpStatus::Converged,
            solution,
            setup,
        }));
    }
    Ok(Err(why.join("; ")))
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
/// where the data it was fitted on now are.
pub(super) fn fixed_at(
    effect: &EffectSpec,
    names: &[String],
    values: &[f64],
    mirrored: bool,
) -> anyhow::Result<EffectSpec> {
    let mut v = serde_json::to_value(effect.fixed())?;
    for (n, x) in names.iter().zip(values) {
        let key = n.rsplit('.').next().unwrap_or(n);
        v[key] = (*x).into();
    }
    if mirrored {
        let other = match v["side"].as_str() {
            Some("right") => Some("left"),
            Some("left") => Some("right"),
            _ => None,
        };
        if let Some(o) = other {
            v["side"] = o.into();
        }
    }
    serde_json::from_value(v).map_err(|e| anyhow!("{}: fixing its parameters: {e}", effect.label()))
}

/// Apply candidate `t` (fitted on the run's half cycle) to the held-out half cycle,
/// the other variables re-fitted by a truncated re-fit (as the score test's).
fn validate(base: &HeldOutBase, t: &ScoreTest) -> anyhow::Result<HeldOut> {
    let spec = fixed_at(&t.effect, &t.parameters, &t.step_values, base.mirrored)?;
    let mut prob = TrackingProblem::build(&base.setup, std::slice::from_ref(&spec))?;
    prob.setup
        .start_from(&base.solution)
        .map_err(|e| anyhow!(e))?;
    let after = prob.with_transcription(|tr, _, w| {
        let (j, dec, _, _) =
            truncated_refit(tr, &w, MAX_STEPS, REL_STOP).map_err(|e| anyhow!(e))?;
        Ok(j - dec)
    })?;
    Ok(judged(base, t, base.objective - base.leftover - after))
}

/// Apply a plate's clock read from its profile (`t`, a re-fit held at the profile's
/// vertex) to the held-out half cycle, held there too, and solve that half cycle in
/// full. A truncated re-fit would not do: the held offset moves the plate's events (with
/// sample or one-sided targets), so the phases no longer sit where the plain model's
/// solution put them, and a few Gauss–Newton steps from there understate the change.
/// Returns the validation and whether the solve converged.
fn validate_held_clock(
    args: &DiagnoseRequest,
    base: &HeldOutBase,
    t: &ScoreTest,
) -> anyhow::Result<(HeldOut, bool)> {
    let spec = fixed_at(&t.effect, &t.parameters, &t.step_values, base.mirrored)?;
    let mut prob = TrackingProblem::build(&base.setup, std::slice::from_ref(&spec))?;
    prob.start_at(&base.solution)?;
    let settings = super::refit::full_solve_settings(args, &prob);
    let (res, _) = prob.solve(&settings, &super::super::Quiet)?;
    if !res.objective.is_finite() {
        return Err(anyhow!(
            "the held-out solve ended without a finite cost ({})",
            res.status
        ));
    }
    let converged = res.status == crate::sqp::SqpStatus::Converged;
    Ok((judged(base, t, base.objective - res.objective), converged))
}

/// Whether test `t` is a plate's clock read from its refined profile (a re-fit held at
/// the vertex): validated by a full solve with the clock held, its band from the
/// parabola's curvature. Other full re-fits (the heel pad, a free profile re-fit) have no
/// reduced curvature and are not validated.
pub(super) fn held_clock(t: &ScoreTest) -> bool {
    t.refit && t.profile.as_ref().is_some_and(|p| p.refined)
}

/// Validate candidate `t` (at its `step_values`) on the held-out half cycle: a clock read
/// from its refined profile by a full solve with it held ([`validate_held_clock`]), any
/// other by a truncated re-fit ([`validate`]). A held-out solve that did not converge is
/// said in `note`.
pub(super) fn check(
    args: &DiagnoseRequest,
    base: &HeldOutBase,
    t: &ScoreTest,
    note: &mut String,
) -> anyhow::Result<HeldOut> {
    if held_clock(t) {
        let (h, converged) = validate_held_clock(args, base, t)?;
        if !converged {
            *note += &format!(
                " {}: its held-out solve did not converge; its change is that of the last iterate.",
                t.label
            );
        }
        Ok(h)
    } else {
        validate(base, t)
    }
}

/// The held-out validation of candidate `t` whose values lowered the held-out cost by
/// `change` (negative: it rose), judged against its noise band. The band's curvature is
/// the run's reduced curvature along the fitted values (the score test's, or a clock
/// profile's parabola).
fn judged(base: &HeldOutBase, t: &ScoreTest, change: f64) -> HeldOut {
    let (q, band) = band(t, base.s2);
    HeldOut {
        stride: base.stride,
        mirrored: base.mirrored,
        window: base.window,
        values: t.step_values.clone(),
        objective: base.objective,
        change,
        change_fraction: change / base.objective,
        band,
        // a candidate without curvature here (q = 0) has no band: it must lower the cost
        beyond_noise: change > band.max(0.0) && q > 0.0,
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
        "the free pelvis position absorbs it: track the pelvis position too (`footfall track --track-pelvis-position`, or `diagnose --make-testable`, which re-tracks the run so)".into()
    } else if !run.sample_targets {
        "the other variables (most likely the actuators) absorb it under this cost: compare every sample at its own instant (`footfall track --sample-targets`), or fit it on a second trial of the same subject".into()
    } else {
        "the other variables (most likely the actuators) absorb it under this cost: fit it on a second trial of the same subject, or fix what trades off with it".into()
    }
}

/// Re-track the run with the pelvis position tracked, from its solution, into
/// `<RUN>+pelvis-position` (`--make-testable`).
pub(super) fn retrack_with_pelvis(
    args: &DiagnoseRequest,
    run: &TrackingRunSetup,
    solution: &GaitSolution,
    progress: &dyn Progress,
) -> anyhow::Result<TrackedRun> {
    let setup = TrackingRunSetup {
        track_pelvis_position: true,
        ..run.clone()
    };
    let dir = sibling(&args.run, "+pelvis-position");
    {
        note!(
            progress,
            "--make-testable: re-tracking with the pelvis position tracked → {}",
            dir.display()
        );
    }
    super::refit::solve_into(args, &setup, &[], solution, dir, progress)
}

#[cfg(test)]
mod tests {
    use super::band;
    use crate::model::effects::EffectSpec;
    use crate::problems::diagnose::refit_test;
    use crate::problems::diagnose::stats::identifiability;

    /// A clock read from its profile's parabola `J ≈ J* + a (δ − δ*)²` and applied to
    /// held-out data with the same offset lowers that cost by about `a δ*²`. That clears
    /// the held-out band exactly when the reading lies more than 2 sd from zero, the sd
    /// being the one the profile reports (`√(φ s²/a)`): the band and the profile's sd
    /// are one noise model.
    #[test]
    fn a_profile_reading_clears_its_held_out_band_beyond_two_sd() {
        let (a, s2, phi): (f64, f64, f64) = (600.6, 0.3994 / 456.0, 5.2);
        let name = "force_plate_time_offset.right.offset".to_string();
        let clock = EffectSpec::ForcePlateTimeOffset {
            side: "right".into(),
            offset: 0.0,
            free: vec!["offset".into()],
        };
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
}
