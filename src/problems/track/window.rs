//! Which half cycle of a trial is tracked, and the gait events it is cut by when the
//! forces were measured only in places (overground trials: one stance per foot on a
//! force plate, the forces `NaN` elsewhere).
//!
//! Events come, in this order, from the meta file's `events_s` ([`GaitData::events`]),
//! else from the force threshold where a foot's force was measured
//! ([`detect_events`]), completed where a foot is off the plates by events from the
//! kinematics ([`kinematic_events`]): the coordinate-based criterion of Zeni, Richards &
//! Higginson (2008, Gait & Posture 27:710–714) with the model's forward kinematics —
//! heel strike where the foot's rearmost contact point is furthest ahead of the pelvis,
//! toe off where its foremost contact point is furthest behind it — moved by the mean
//! offset from the force events of the same kind where both are known.

use crate::data::{detect_events, Events, GaitData, DEFAULT_EVENT_FRACTION};
use crate::model::{GaitModel, Side};
use crate::problems::error::WindowError;

/// Which half cycle (a left heel strike to the next right heel strike) is tracked.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum WindowChoice {
    /// The first one in which every foot a phase loads has its force measured
    /// throughout that phase (with full force coverage: the first half cycle).
    #[default]
    First,
    /// The first one inside `[t0, t1]` (s).
    Within(f64, f64),
    /// The `n`-th one (1-based) of the trial, counting every half cycle the events give.
    Stride(usize),
}

/// Kinematic events closer than this (s) to a force event of the same kind and foot are
/// the same event (and calibrate the kinematic criterion's offset).
const SAME_EVENT_S: f64 = 0.15;

/// Half-width (s) of the neighbourhood in which a kinematic extremum must be the largest.
const EXTREMUM_HALF_WIDTH_S: f64 = 0.2;

/// Events of one kind from the kinematics, `[right, left]` (s).
#[derive(Debug, Clone, PartialEq)]
pub struct KinematicEvents {
    /// Heel strikes: maxima of (rearmost contact point x − pelvis x), refined by a
    /// parabola through the three samples around each.
    pub heel_strike: [Vec<f64>; 2],
    /// Toe offs: minima of (foremost contact point x − pelvis x).
    pub toe_off: [Vec<f64>; 2],
}

/// Extrema of `y` sampled at `t`: interior samples that are the largest (`max`) or
/// smallest in a ±[`EXTREMUM_HALF_WIDTH_S`] neighbourhood, at the vertex of the parabola
/// through their two neighbours.
fn extrema(t: &[f64], y: &[f64], max: bool) -> Vec<f64> {
    let n = t.len();
    let sign = if max { 1.0 } else { -1.0 };
    let mut out = Vec::new();
    for k in 1..n.saturating_sub(1) {
        let v = sign * y[k];
        let best = (0..n)
            .filter(|&j| j != k && (t[j] - t[k]).abs() <= EXTREMUM_HALF_WIDTH_S)
            .all(|j| sign * y[j] < v);
        if !best {
            continue;
        }
        let (a, b, c) = (y[k - 1], y[k], y[k + 1]);
        let den = a - 2.0 * b + c;
        let h = 0.5 * (t[k + 1] - t[k - 1]);
        let s = if den.abs() > 0.0 {
            (0.5 * (a - c) / den).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        out.push(t[k] + s * h);
    }
    out
}

/// Heel strikes and toe offs of both feet from the kinematics alone (see the module
/// docs), without the offset calibration. A side whose angles are not all finite (a
/// missing side) has none.
pub fn kinematic_events(model: &GaitModel, data: &GaitData) -> KinematicEvents {
    let theta = model.theta0();
    let n = data.time.len();
    let mut heel_strike = [Vec::new(), Vec::new()];
    let mut toe_off = [Vec::new(), Vec::new()];
    for (s, side) in [Side::Right, Side::Left].into_iter().enumerate() {
        let contacts: Vec<usize> = (0..model.contacts.len())
            .filter(|&c| model.contacts[c].side == side)
            .collect();
        if contacts.is_empty() || data.q.iter().any(|q| q.iter().any(|v| !v.is_finite())) {
            continue;
        }
        let (mut heel, mut toe) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for k in 0..n {
            let q: Vec<f64> = data.q.iter().map(|c| c[k]).collect();
            let xs: Vec<f64> = contacts
                .iter()
                .map(|&c| model.contact_point(c, &q, &theta).0[0])
                .collect();
            let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            heel.push(lo - q[0]);
            toe.push(hi - q[0]);
        }
        heel_strike[s] = extrema(&data.time, &heel, true);
        toe_off[s] = extrema(&data.time, &toe, false);
    }
    KinematicEvents {
        heel_strike,
        toe_off,
    }
}

/// Mean of (force event − kinematic event) over the pairs of the same foot closer than
/// [`SAME_EVENT_S`] (0 without pairs) and the number of pairs.
fn calibration(force: &[Vec<f64>; 2], kin: &[Vec<f64>; 2]) -> (f64, usize) {
    let mut d = Vec::new();
    for s in 0..2 {
        for &g in &kin[s] {
            if let Some(&f) = force[s].iter().find(|&&f| (f - g).abs() < SAME_EVENT_S) {
                d.push(f - g);
            }
        }
    }
    let m = if d.is_empty() {
        0.0
    } else {
        d.iter().sum::<f64>() / d.len() as f64
    };
    (m, d.len())
}

/// The events tracking uses (see the module docs) and notes on where they came from
/// (for the run's log). With the forces measured throughout, or events in the meta file,
/// these are exactly [`detect_events`]'s or the meta file's.
pub fn combined_events(
    model: &GaitModel,
    data: &GaitData,
) -> Result<(Events, Vec<String>), WindowError> {
    combined_events_on_clocks(model, data, [0.0; 2])
}

/// As [`combined_events`], with the events of each plate's force threshold moved to the
/// motion capture's clock by that plate's clock offset `offsets[s]` (s, positive when the
/// plate runs late: `t − δ`) before the kinematic events are calibrated against them.
pub(super) fn combined_events_on_clocks(
    model: &GaitModel,
    data: &GaitData,
    offsets: [f64; 2],
) -> Result<(Events, Vec<String>), WindowError> {
    if let Some(e) = &data.events {
        return Ok((e.clone(), Vec::new()));
    }
    let mut ev = detect_events(data, DEFAULT_EVENT_FRACTION)?;
    for (s, &d) in offsets.iter().enumerate().filter(|(_, &d)| d != 0.0) {
        for e in ev.heel_strike[s].iter_mut().chain(ev.toe_off[s].iter_mut()) {
            *e -= d;
        }
    }
    let (_, feet) = data.force_record();
    let partial: Vec<usize> = (0..2)
        .filter(|&s| feet[s].fy.iter().any(|v| v.is_nan()))
        .collect();
    if partial.is_empty() {
        return Ok((ev, Vec::new()));
    }
    let kin = kinematic_events(model, data);
    let (hs_off, hs_pairs) = calibration(&ev.heel_strike, &kin.heel_strike);
    let (to_off, to_pairs) = calibration(&ev.toe_off, &kin.toe_off);
    let mut notes = vec![format!(
        "forces not measured throughout ({}): events off the plates from the kinematics, moved by {:+.1} ms (heel strike, {hs_pairs} pair(s)) and {:+.1} ms (toe off, {to_pairs} pair(s)) to match the force events",
        partial
            .iter()
            .map(|&s| ["right", "left"][s])
            .collect::<Vec<_>>()
            .join(", "),
        1e3 * hs_off,
        1e3 * to_off
    )];
    for &s in &partial {
        let side = [Side::Right, Side::Left][s];
        let stretches = data.measured_stretches(side);
        let inside = |t: f64| {
            stretches
                .iter()
                .any(|&(a, b)| t > a + 0.5 * SAME_EVENT_S && t < b - 0.5 * SAME_EVENT_S)
        };
        let mut added = Vec::new();
        for (kind, force, k, off) in [
            (
                "heel strike",
                &mut ev.heel_strike[s],
                &kin.heel_strike[s],
                hs_off,
            ),
            ("toe off", &mut ev.toe_off[s], &kin.toe_off[s], to_off),
        ] {
            for &g in k {
                let t = g + off;
                if inside(t) || force.iter().any(|&f| (f - t).abs() < SAME_EVENT_S) {
                    continue;
                }
                force.push(t);
                added.push(format!("{kind} {t:.3} s"));
            }
            force.sort_by(f64::total_cmp);
        }
        if data.force_record().1[s]
            .fy
            .first()
            .is_none_or(|v| v.is_nan())
        {
            // unknown at the start: loaded if the foot's first event is a toe off
            let first_hs = ev.heel_strike[s].first().copied().unwrap_or(f64::INFINITY);
            let first_to = ev.toe_off[s].first().copied().unwrap_or(f64::INFINITY);
            ev.loaded_at_start[s] = first_to < first_hs;
        }
        if !added.is_empty() {
            notes.push(format!(
                "{} foot, from the kinematics: {}",
                ["right", "left"][s],
                added.join(", ")
            ));
        }
    }
    Ok((ev, notes))
}

/// The half cycle `choice` selects on the plates' own clocks, found again among the
/// half cycles of `moved` (the events with each plate's clock offset `offsets` applied,
/// [`combined_events_on_clocks`]): the one whose start lies nearest that half cycle's
/// start moved by the left plate's offset (a half cycle starts at a left heel strike).
/// Choosing on the moved events instead would let a held offset change which half cycle
/// is tracked: on the real right-clock trial the left plate's clock held at −66 ms made
/// a half cycle at 0.070 s the first one whose forces are known, and the profile compared
/// costs of different half cycles.
pub(super) fn same_half_cycle(
    model: &GaitModel,
    data: &GaitData,
    moved: &Events,
    offsets: [f64; 2],
    choice: WindowChoice,
) -> Result<WindowChoice, WindowError> {
    let (plain, _) = combined_events_on_clocks(model, data, [0.0; 2])?;
    let ((t0, t1), _) = choose_window(data, &plain, choice)?;
    let target = t0 - offsets[1];
    let all = half_cycles(moved);
    all.iter()
        .enumerate()
        .min_by(|a, b| (a.1 .0 - target).abs().total_cmp(&(b.1 .0 - target).abs()))
        .filter(|(_, w)| (w.0 - target).abs() < SAME_EVENT_S)
        .map(|(i, _)| WindowChoice::Stride(i + 1))
        .ok_or_else(|| WindowError::NoCounterpart {
            window: (t0, t1),
            offsets,
            target,
            half_cycles: all.clone(),
        })
}

/// Every half cycle of `events` (a left heel strike at least 0.05 s into the data
/// followed by the next right heel strike), in time order.
pub fn half_cycles(events: &Events) -> Vec<(f64, f64)> {
    let earliest = events.span.0 + 0.05;
    events.heel_strike[1]
        .iter()
        .filter(|&&t| t >= earliest)
        .filter_map(|&t0| {
            events.heel_strike[0]
                .iter()
                .find(|&&t| t > t0)
                .map(|&t1| (t0, t1))
        })
        .filter(|&(_, t1)| t1 <= events.span.1 + 1e-9)
        .collect()
}

/// Why the forces of `[t0, t1]` are not fully known: the phases in which a foot the
/// phase graph loads has no measured force (`None` if every loaded foot's force is).
/// (The measured contact phases stand for the phase graph's: the durations are fixed to
/// them.)
pub fn missing_forces(data: &GaitData, events: &Events, (t0, t1): (f64, f64)) -> Option<String> {
    let mut gaps = Vec::new();
    for ph in events.contact_phases(t0, t1) {
        for (s, side) in [Side::Right, Side::Left].into_iter().enumerate() {
            if ph.contact[s] && !data.forces_known(side, ph.start, ph.end) {
                gaps.push(format!(
                    "{side:?} foot loaded {:.3}–{:.3} s",
                    ph.start, ph.end
                ));
            }
        }
    }
    (!gaps.is_empty()).then(|| {
        let stretches = |side| {
            let v: Vec<String> = data
                .measured_stretches(side)
                .iter()
                .map(|(a, b)| format!("{a:.3}–{b:.3} s"))
                .collect();
            if v.is_empty() {
                "nowhere".to_string()
            } else {
                v.join(", ")
            }
        };
        format!(
            "forces not measured while {} (right forces measured {}, left {})",
            gaps.join(", "),
            stretches(Side::Right),
            stretches(Side::Left)
        )
    })
}

/// The half cycle `choice` selects, and a warning when its loaded feet's forces are not
/// all known (an explicit choice may track such a window: those force and CoP terms
/// are left out). The default ([`WindowChoice::First`]) takes only a fully known one and
/// otherwise says why each half cycle fails.
pub fn choose_window(
    data: &GaitData,
    events: &Events,
    choice: WindowChoice,
) -> Result<((f64, f64), Option<String>), WindowError> {
    let all = half_cycles(events);
    if all.is_empty() {
        return Err(WindowError::NoHalfCycle {
            heel_strike: events.heel_strike.clone(),
        });
    }
    let check = |w: (f64, f64)| missing_forces(data, events, w);
    match choice {
        WindowChoice::First => {
            let mut gaps = Vec::new();
            for &w in &all {
                match check(w) {
                    None => return Ok((w, None)),
                    Some(m) => gaps.push((w, m)),
                }
            }
            Err(WindowError::NoMeasuredHalfCycle { gaps })
        }
        WindowChoice::Within(a, b) => {
            let w = all
                .iter()
                .copied()
                .find(|&(t0, t1)| t0 >= a - 1e-9 && t1 <= b + 1e-9)
                .ok_or_else(|| WindowError::NotInWindow {
                    start: a,
                    end: b,
                    half_cycles: all.clone(),
                })?;
            Ok((w, check(w)))
        }
        WindowChoice::Stride(n) => {
            let w = n
                .checked_sub(1)
                .and_then(|i| all.get(i).copied())
                .ok_or_else(|| WindowError::NoStride {
                    stride: n,
                    half_cycles: all.clone(),
                })?;
            Ok((w, check(w)))
        }
    }
}
