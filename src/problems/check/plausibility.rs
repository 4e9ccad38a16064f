//! Whether the forces can be right: the forward force's sign in each stance (braking,
//! then propulsion), checked where every trial is read for every command
//! ([`check_forward_force_sign`]); and, in the measurement check, against the body by
//! the whole-body balance: the body mass they imply against the model's, and the
//! horizontal force's run against the body's acceleration ([`check_balance`]); the body
//! against the trial is judged by its geometry ([`footing`](super::footing)). Units
//! (times in seconds, positions and CoP in metres, angles in radians) and the vertical
//! force's sign are checked where every trial is read as well
//! ([`GaitData::check_conventions`]).

use super::{CheckError, Implausible};
use crate::data::{median_step, DataError, FootData, GaitData, SideSource};

/// How far the mass the forces imply may lie from the model's before the trial is
/// refused (fraction): beyond 25 % the forces, their unit or the model belong to
/// someone else.
pub const MASS_REFUSED: f64 = 0.25;
/// Beyond this (fraction) the check warns.
pub const MASS_WARNED: f64 = 0.10;

/// What the balance says of the forces against the body: the mass they imply against
/// the model's, and the horizontal force's sign. `Err` where the data cannot be right,
/// else warnings (possibly none).
pub fn check_balance(
    data: &GaitData,
    model_mass: f64,
    implied_mass: f64,
    horizontal_correlation: f64,
) -> Result<Vec<String>, CheckError> {
    let path = &data.source;
    let ratio = implied_mass / model_mass;
    if !ratio.is_finite() || (ratio - 1.0).abs() > MASS_REFUSED {
        return Err(Implausible::Mass {
            path: path.clone(),
            implied_kg: implied_mass,
            model_kg: model_mass,
        }
        .into());
    }
    if horizontal_correlation < -0.5 {
        return Err(Implausible::HorizontalSign {
            path: path.clone(),
            correlation: horizontal_correlation,
        }
        .into());
    }
    let mut warnings = Vec::new();
    if (ratio - 1.0).abs() > MASS_WARNED {
        warnings.push(format!(
            "the vertical forces imply a body of {implied_mass:.1} kg, {:+.0} % from the model's {model_mass:.1} kg",
            100.0 * (ratio - 1.0)
        ));
    }
    Ok(warnings)
}

/// Share of a foot's vertical impulse over its stances that the forward impulse of each
/// half of stance must exceed, against the walking direction, before the forward force
/// is refused as flipped. A walking stance brakes with about 4 % of its vertical impulse
/// in its first half and propels with as much in its second; a flipped column shows the
/// reverse in both halves.
pub const FLIPPED_FORWARD_SHARE: f64 = 0.01;
/// Shortest stance judged (s): a running stance lasts about 0.2 s, a walking one 0.5 s
/// or more; shorter loaded stretches are a foot's brush of the plate.
pub const MIN_STANCE_S: f64 = 0.1;
/// Normal force (N) that a loaded foot exceeds (the usual CoP threshold).
pub const LOADED_N: f64 = 20.0;
/// Share of the foot's peak normal force that a loaded foot exceeds.
pub const LOADED_SHARE: f64 = 0.05;

/// The forward impulses of a foot's complete stances (loaded between two unloaded
/// samples, with no gap): the first halves' and the second halves' sums along the
/// walking direction `forward` (±1), the vertical impulse, and the stance count (N·s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StanceImpulses {
    /// Forward impulse of the first halves of stance (braking: negative).
    pub first_half: f64,
    /// Forward impulse of the second halves (propulsion: positive).
    pub second_half: f64,
    /// Vertical impulse over the stances.
    pub vertical: f64,
    /// Complete stances found.
    pub stances: usize,
}

/// The normal force (N) above which foot `foot` counts as loaded: [`LOADED_N`], or
/// [`LOADED_SHARE`] of the foot's peak where that is more.
pub fn loaded_threshold(foot: &FootData) -> f64 {
    let peak = foot
        .fy
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    LOADED_N.max(LOADED_SHARE * peak)
}

/// The complete stances of foot `foot` sampled at `t`: index ranges `(a, b)` from the
/// last unloaded sample before each loaded run ([`loaded_threshold`]) to the first
/// unloaded one after it, with nothing missing in between.
pub fn complete_stances(t: &[f64], foot: &FootData) -> Vec<(usize, usize)> {
    let n = t.len().min(foot.fy.len());
    let threshold = loaded_threshold(foot);
    let gap = median_step(&t[..n]).map_or(f64::INFINITY, |m| 1.5 * m);
    let unloaded = |k: usize| foot.fy[k].is_finite() && foot.fy[k] <= threshold;
    let mut out = Vec::new();
    let mut k = 1;
    while k < n {
        if !(unloaded(k - 1) && foot.fy[k] > threshold) {
            k += 1;
            continue;
        }
        let mut j = k;
        while j < n && foot.fy[j] > threshold && t[j] - t[j - 1] <= gap {
            j += 1;
        }
        if j < n && unloaded(j) && t[j] - t[j - 1] <= gap {
            out.push((k - 1, j));
        }
        k = j.max(k + 1);
    }
    out
}

impl StanceImpulses {
    /// The impulses of foot `foot` sampled at `t`, along `forward`.
    pub fn of(t: &[f64], foot: &FootData, forward: f64) -> Self {
        let mut out = Self::default();
        for (a, b) in complete_stances(t, foot) {
            if b < foot.fx.len() {
                out.add(&t[a..=b], &foot.fx[a..=b], &foot.fy[a..=b], forward);
            }
        }
        out
    }

    /// Add one stance's samples (trapezoids, each in the half its middle falls in).
    fn add(&mut self, t: &[f64], fx: &[f64], fy: &[f64], forward: f64) {
        let (t0, t1) = (t[0], t[t.len() - 1]);
        if t1 - t0 < MIN_STANCE_S || fx.iter().any(|v| !v.is_finite()) {
            return;
        }
        let mid = 0.5 * (t0 + t1);
        let (mut first, mut second, mut vertical) = (0.0, 0.0, 0.0);
        for i in 1..t.len() {
            let h = t[i] - t[i - 1];
            let f = forward * 0.5 * h * (fx[i] + fx[i - 1]);
            if 0.5 * (t[i] + t[i - 1]) < mid {
                first += f;
            } else {
                second += f;
            }
            vertical += 0.5 * h * (fy[i] + fy[i - 1]);
        }
        self.first_half += first;
        self.second_half += second;
        self.vertical += vertical;
        self.stances += 1;
    }

    /// Whether the forward force pushes forward in the first halves and backward in the
    /// second, each by more than [`FLIPPED_FORWARD_SHARE`] of the vertical impulse.
    pub fn flipped(&self) -> bool {
        let least = FLIPPED_FORWARD_SHARE * self.vertical;
        self.stances > 0 && self.first_half > least && self.second_half < -least
    }
}

/// The walking direction along x: the sign of the pelvis's travel when it moves at least
/// [`MIN_OVERGROUND_SPEED`](crate::data::conventions::MIN_OVERGROUND_SPEED) on average,
/// else +x (footfall's forward; a treadmill trial taken as it is).
fn walking_direction(data: &GaitData) -> f64 {
    let x: Vec<(f64, f64)> = data
        .time
        .iter()
        .zip(&data.q[0])
        .filter(|(_, x)| x.is_finite())
        .map(|(&t, &x)| (t, x))
        .collect();
    match (x.first(), x.last()) {
        (Some(a), Some(b))
            if b.0 > a.0
                && ((b.1 - a.1) / (b.0 - a.0)).abs()
                    >= crate::data::conventions::MIN_OVERGROUND_SPEED =>
        {
            (b.1 - a.1).signum()
        }
        _ => 1.0,
    }
}

/// The forward ground force of each measured foot brakes, then propels: over the foot's
/// complete stances it points against the walking direction in the first half of stance
/// and along it in the second. A column that shows the reverse in both halves, each by
/// more than [`FLIPPED_FORWARD_SHARE`] of the vertical impulse, has its sign flipped
/// (the lab's forward axis is footfall's backward) and is refused, naming it.
pub fn check_forward_force_sign(data: &GaitData) -> Result<(), DataError> {
    let forward = walking_direction(data);
    let (t, feet) = data.force_record();
    for (s, side) in ["r", "l"].iter().enumerate() {
        if data.sides[s] != SideSource::Measured {
            continue;
        }
        let imp = StanceImpulses::of(t, &feet[s], forward);
        if !imp.flipped() {
            continue;
        }
        let dir = if forward > 0.0 { "+x" } else { "-x" };
        return Err(DataError::invalid(
            &data.source,
            format!("grf_x_{side}"),
            format!(
                "over the foot's {} complete {} the forward force pushes the foot forward in the first half ({:+.1} N·s along the walking direction, {dir}) and back in the second ({:+.1} N·s), {:.1} % and {:.1} % of the vertical impulse; a walking foot brakes first and then propels (first half backward, second half forward). footfall reads grf_x as the ground's force on the foot, + forward: the sign looks flipped (negate the column)",
                imp.stances,
                if imp.stances == 1 { "stance" } else { "stances" },
                imp.first_half,
                imp.second_half,
                100.0 * imp.first_half / imp.vertical,
                100.0 * imp.second_half.abs() / imp.vertical,
            ),
        ));
    }
    Ok(())
}
