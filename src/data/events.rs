//! Gait events from the force threshold: heel strike where a foot's normal force rises
//! above the threshold, toe off where it falls back below it.
//!
//! The threshold is a fraction of the peak normal force, $F_{thr} = f \max_{k,\,foot} F_y$
//! (one threshold for both feet; $f = 0.05$ by default, [`DEFAULT_EVENT_FRACTION`]). A
//! foot is loaded at sample $k$ when $F_y(t_k) > F_{thr}$; between a sample that is not
//! loaded and one that is (or vice versa) the crossing time is found by linear
//! interpolation,
//! $$t^* = t_k + \frac{F_{thr} - F_y(t_k)}{F_y(t_{k+1}) - F_y(t_k)}\,(t_{k+1}-t_k).$$
//! A foot that is loaded in the first sample has no heel strike there (the data start in
//! its stance). The events set the initial phase durations of the gait phase graphs
//! ([`Events::contact_phases`]).

use super::error::DataError;
use super::{side_index, GaitData};
use crate::model::Side;
use std::path::PathBuf;

/// Millard & Mombaur's event threshold: 5 % of the peak normal force.
pub const DEFAULT_EVENT_FRACTION: f64 = 0.05;

/// Heel strikes and toe offs of both feet (s), each list increasing.
#[derive(Debug, Clone, PartialEq)]
pub struct Events {
    /// Heel strikes: `[right, left]`.
    pub heel_strike: [Vec<f64>; 2],
    /// Toe offs: `[right, left]`.
    pub toe_off: [Vec<f64>; 2],
    /// Threshold used (N).
    pub threshold: f64,
    /// Whether each foot is loaded in the first sample: `[right, left]`.
    pub loaded_at_start: [bool; 2],
    /// Time span of the data the events come from (s).
    pub span: (f64, f64),
    /// File the data came from (for error messages).
    pub source: PathBuf,
}

/// One contact phase between two consecutive events.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPhase {
    /// Start (s).
    pub start: f64,
    /// End (s).
    pub end: f64,
    /// Whether each foot is on the ground: `[right, left]`.
    pub contact: [bool; 2],
}

impl ContactPhase {
    /// `end − start` (s).
    pub fn duration(&self) -> f64 {
        self.end - self.start
    }
}

/// Rising and falling crossings of `threshold` by `force` sampled at `time`, with linear
/// interpolation of the crossing instants: `(rises, falls)`.
///
/// A sample is "above" when `force > threshold`. A crossing is counted only between two
/// measured (finite) samples: where the force is `NaN` (the foot off the plates) nothing
/// is known, and the edge of a measured stretch is not an event.
/// `time` and `force` must have the same length (extra samples of the longer are ignored).
pub fn threshold_crossings(time: &[f64], force: &[f64], threshold: f64) -> (Vec<f64>, Vec<f64>) {
    let n = time.len().min(force.len());
    let above = |k: usize| force[k] > threshold;
    let (mut rises, mut falls) = (Vec::new(), Vec::new());
    for k in 0..n.saturating_sub(1) {
        let (a, b) = (above(k), above(k + 1));
        if a == b || force[k].is_nan() || force[k + 1].is_nan() {
            continue;
        }
        let (f0, f1) = (force[k], force[k + 1]);
        let t = if f0.is_finite() && f1.is_finite() && f1 != f0 {
            let s = ((threshold - f0) / (f1 - f0)).clamp(0.0, 1.0);
            time[k] + s * (time[k + 1] - time[k])
        } else {
            time[k + 1]
        };
        if b {
            rises.push(t);
        } else {
            falls.push(t);
        }
    }
    (rises, falls)
}

/// Heel strikes and toe offs of both feet, from the normal force threshold
/// `fraction × peak normal force` (see the module docs; Millard & Mombaur use
/// [`DEFAULT_EVENT_FRACTION`] = 0.05).
///
/// The forces are read at their own instants ([`GaitData::force_record`]). A foot has
/// events only where its normal force was measured (none where it is NaN, e.g. off the
/// plates; events there come from the meta file or the kinematics, see
/// `problems::track::combined_events`). Errors: data
/// that fail [`GaitData::validate`]; `fraction` outside (0, 1); [`DataError::NoStance`] when no normal force exceeds the
/// threshold (also when no force was measured at all or the peak is not positive);
/// [`DataError::TooShort`] when the forces were measured throughout and neither foot
/// has two heel strikes (less than one gait cycle). Detect events on the whole trial
/// before cutting it with [`GaitData::window`].
pub fn detect_events(data: &GaitData, fraction: f64) -> Result<Events, DataError> {
    data.validate()?;
    if !(fraction > 0.0 && fraction < 1.0) {
        return Err(DataError::invalid(
            &data.source,
            "fraction",
            format!("the event threshold must be a fraction of the peak force in (0, 1), got {fraction}"),
        ));
    }
    let (time, feet) = data.force_record();
    let peak = feet
        .iter()
        .flat_map(|f| f.fy.iter())
        .copied()
        .filter(|v| !v.is_nan())
        .fold(f64::NAN, f64::max);
    let threshold = fraction * peak;
    let stance = feet.iter().any(|f| f.fy.iter().any(|&v| v > threshold));
    if peak.is_nan() || peak <= 0.0 || !stance {
        return Err(DataError::NoStance {
            path: data.source.clone(),
            threshold,
            peak,
        });
    }
    let mut heel_strike = [Vec::new(), Vec::new()];
    let mut toe_off = [Vec::new(), Vec::new()];
    let mut loaded_at_start = [false; 2];
    for s in 0..2 {
        let fy = &feet[s].fy;
        let (hs, to) = threshold_crossings(time, fy, threshold);
        heel_strike[s] = hs;
        toe_off[s] = to;
        loaded_at_start[s] = fy.first().is_some_and(|&v| v > threshold);
    }
    let n = data.time.len();
    let span = (data.time[0], data.time[n - 1]);
    let measured_throughout = feet
        .iter()
        .zip(&data.sides)
        .all(|(f, &side)| side == super::SideSource::Missing || f.fy.iter().all(|v| v.is_finite()));
    if measured_throughout && heel_strike.iter().all(|h| h.len() < 2) {
        return Err(DataError::TooShort {
            path: data.source.clone(),
            reason: format!(
                "fewer than two heel strikes of either foot (right {}, left {}) at the threshold {:.1} N over {:.3}–{:.3} s",
                heel_strike[0].len(),
                heel_strike[1].len(),
                threshold,
                span.0,
                span.1
            ),
        });
    }
    Ok(Events {
        heel_strike,
        toe_off,
        threshold,
        loaded_at_start,
        span,
        source: data.source.clone(),
    })
}

/// The first complete gait cycle of `side`: from its first heel strike to its second
/// (s). Errors with [`DataError::TooShort`] if that foot has fewer than two heel strikes.
pub fn gait_cycle(events: &Events, side: Side) -> Result<(f64, f64), DataError> {
    events
        .gait_cycles(side)
        .first()
        .copied()
        .ok_or_else(|| DataError::TooShort {
            path: events.source.clone(),
            reason: format!(
                "{} heel strike(s) of the {side:?} foot; a gait cycle needs two",
                events.heel_strike[side_index(side)].len()
            ),
        })
}

impl Events {
    /// The events with the legs swapped ([`GaitData::swap_sides`](super::GaitData::swap_sides)).
    pub fn swap_sides(&mut self) {
        self.heel_strike.swap(0, 1);
        self.toe_off.swap(0, 1);
        self.loaded_at_start.swap(0, 1);
    }

    /// All complete cycles of `side`, heel strike to the next heel strike (s).
    pub fn gait_cycles(&self, side: Side) -> Vec<(f64, f64)> {
        self.heel_strike[side_index(side)]
            .windows(2)
            .map(|w| (w[0], w[1]))
            .collect()
    }

    /// Whether foot `s` (0 right, 1 left) is on the ground at `t` according to the events.
    fn contact_at(&self, s: usize, t: f64) -> bool {
        let last_hs = self.heel_strike[s].iter().rev().find(|&&e| e <= t);
        let last_to = self.toe_off[s].iter().rev().find(|&&e| e <= t);
        match (last_hs, last_to) {
            (Some(h), Some(o)) => h > o,
            (Some(_), None) => true,
            (None, Some(_)) => false,
            (None, None) => self.loaded_at_start[s],
        }
    }

    /// The sequence of contact phases between `t0` and `t1`, split at every event in
    /// between; each phase says which feet are on the ground. Over a right gait cycle
    /// this is double stance, right single stance, double stance, left single stance: the
    /// initial phase durations of a walking phase graph.
    pub fn contact_phases(&self, t0: f64, t1: f64) -> Vec<ContactPhase> {
        let mut cuts: Vec<f64> = self
            .heel_strike
            .iter()
            .chain(self.toe_off.iter())
            .flat_map(|v| v.iter().copied())
            .filter(|&e| e > t0 && e < t1)
            .collect();
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        let mut bounds = vec![t0];
        bounds.extend(cuts);
        bounds.push(t1);
        bounds
            .windows(2)
            .filter(|w| w[1] > w[0])
            .map(|w| {
                let mid = 0.5 * (w[0] + w[1]);
                ContactPhase {
                    start: w[0],
                    end: w[1],
                    contact: [self.contact_at(0, mid), self.contact_at(1, mid)],
                }
            })
            .collect()
    }
}
