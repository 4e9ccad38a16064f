//! Sample targets: every measured sample inside the tracked window compared with the model
//! at its own instant, in the shooting interval that holds it.

use super::loaded_feet;
use crate::data::GaitData;
use crate::model::gait::COORDINATES;
use crate::model::{ConstraintSet, GaitModel};
use crate::phases::{Phase, PhaseSequence};
use crate::problems::error::ProblemError;
use crate::problems::tracking::NodeTarget;

/// A measurement compared with the model inside a shooting interval
/// ([`TargetSides::Samples`](super::TargetSides::Samples)).
#[derive(Debug, Clone)]
pub struct SampleTarget {
    /// Continuous phase (OCP phase index).
    pub phase: usize,
    /// Shooting interval within the phase.
    pub interval: usize,
    /// Position in the interval (0 < τ ≤ 1).
    pub tau: f64,
    /// The sample (its time, angles and loads; no velocities).
    pub target: NodeTarget,
    /// Factor on the weights of this sample's force and CoP rows: the force record's
    /// sample period over the kinematics' (the mean steps of their instants inside the
    /// tracked span; 1 when the forces are sampled with the kinematics). Forces at 600 Hz
    /// beside kinematics at 60 Hz then count per second as they would at 60 Hz, so a
    /// faster plate does not outweigh the angles.
    pub load_weight: f64,
    /// Where each foot's loads are compared: (continuous phase, interval, τ) of the
    /// sample's instant moved by that foot's plate clock offset as the model starts it
    /// ([`Self::load_offset`]); the sample's own place where the offset is zero.
    pub loads_at: [(usize, usize, f64); 2],
    /// The plate clock offsets (s; right, left) the loads' places already apply: a held
    /// offset in full (so the model's loads are compared where the measured ones belong,
    /// in the phase that holds that instant, as the events were moved alike), a free
    /// one by its start value; the OCP shifts the loads by the offset's change from it.
    pub load_offset: [f64; 2],
}

impl SampleTarget {
    /// Where a residual part of this sample is compared: (continuous phase, interval, τ)
    /// of the loads of foot `side` ([`Self::loads_at`]), or the sample's own place for its
    /// angles (`None`).
    pub fn place_of(&self, side: Option<usize>) -> (usize, usize, f64) {
        match side {
            Some(side) => self.loads_at[side],
            None => (self.phase, self.interval, self.tau),
        }
    }
}

/// Samples closer than this to a phase boundary (s) are left out of sample targets: on a
/// contact change the measurement belongs to neither side.
const SAMPLE_EDGE: f64 = 1e-9;

/// Every sample of `data` inside the continuous phases of `seq` (durations fixed, the
/// first starting at `t0`), located in its shooting interval, with the angles and the
/// loads of the feet its phase loads (the CoP where the normal force reaches the data's
/// CoP threshold); samples on a phase boundary are left out. Forces sampled apart from
/// the kinematics ([`GaitData::forces`]) give their own samples at their own instants,
/// weighted by their sample period over the kinematics' ([`SampleTarget::load_weight`]);
/// unmeasured (`NaN`) forces and CoP give no terms. Each foot's loads are placed at the
/// instant its plate's clock offset `load_offset` (s; right, left: a held offset, or a
/// free one's start value) moves them to, in the phase that holds that instant, as the
/// events were moved: a plate 20 ms early held at −20 ms compares its loads where the
/// untouched trial compares them (not held at their timestamp's phase's end).
pub(super) fn sample_targets(
    model: &GaitModel,
    seq: &PhaseSequence,
    sets: &[ConstraintSet],
    data: &GaitData,
    t0: f64,
    load_offset: [f64; 2],
) -> Result<Vec<SampleTarget>, ProblemError> {
    let angles: Vec<&[f64]> = COORDINATES
        .iter()
        .map(|&c| {
            data.channel(c)
                .ok_or(ProblemError::NoChannel { channel: c })
        })
        .collect::<Result<_, _>>()?;
    let nq = angles.len();
    // each channel at its own instants: (time, kinematic row, force row)
    let (force_time, force_feet) = data.force_record();
    let instants: Vec<(f64, Option<usize>, Option<usize>)> = if data.forces.is_some() {
        let mut v: Vec<_> = (0..data.time.len())
            .map(|n| (data.time[n], Some(n), None))
            .chain((0..force_time.len()).map(|n| (force_time[n], None, Some(n))))
            .collect();
        v.sort_by(|x, y| x.0.total_cmp(&y.0));
        v
    } else {
        (0..data.time.len())
            .map(|n| (data.time[n], Some(n), Some(n)))
            .collect()
    };
    // each continuous phase: (OCP phase, start, end, interval length, intervals, the
    // feet it loads)
    let mut phases = Vec::new();
    let (mut a, mut j) = (t0, 0);
    for (i, ph) in seq.phases.iter().enumerate() {
        let Phase::Continuous {
            duration,
            intervals,
            ..
        } = ph
        else {
            continue;
        };
        let b = a + duration.value();
        let h = duration.value() / *intervals as f64;
        phases.push((j, a, b, h, *intervals, loaded_feet(model, &sets[i])));
        a = b;
        j += 1;
    }
    // the force record's sample period over the kinematics', each the mean step of its
    // instants inside the tracked span [t0, a] (robust to times printed to few digits)
    let step = |t: &[f64]| {
        let inside: Vec<f64> = t.iter().copied().filter(|&x| x >= t0 && x <= a).collect();
        (inside.len() >= 2)
            .then(|| (inside[inside.len() - 1] - inside[0]) / (inside.len() - 1) as f64)
    };
    let load_weight = match (data.forces.is_some(), step(force_time), step(&data.time)) {
        (true, Some(f), Some(k)) => f / k,
        _ => 1.0,
    };
    // where an instant falls: (phase, interval, τ, the feet that phase loads); none on a
    // phase boundary or outside the window
    let place = |t: f64| {
        phases.iter().find_map(|&(j, a, b, h, intervals, feet)| {
            if !(t > a + SAMPLE_EDGE && t < b - SAMPLE_EDGE) {
                return None;
            }
            let s = (t - a) / h;
            let mut k = (s.floor() as usize).min(intervals - 1);
            let mut tau = (s - k as f64).min(1.0);
            if tau < 1e-12 {
                // on an inner node: the end of the interval before it
                k -= 1;
                tau = 1.0;
            }
            Some((j, k, tau, feet))
        })
    };
    let mut out = Vec::new();
    for &(t, kin, frc) in &instants {
        // the angles at the sample's instant, each foot's loads at the instant its
        // plate's held clock moves them to (the events were moved alike)
        let angles_at = kin.and_then(|_| place(t));
        let loads_at: [_; 2] = std::array::from_fn(|f| {
            frc.and_then(|_| place(t - load_offset[f]))
                .filter(|p| p.3[f])
        });
        // the loads of the feet their phase loads, where measured (a NaN force is not
        // measured: no force terms; a NaN CoP of a loaded foot: no CoP term)
        let load = |f: usize| {
            let n = frc?;
            loads_at[f]?;
            let fd = &force_feet[f];
            (fd.fx[n].is_finite() && fd.fy[n].is_finite()).then(|| {
                (
                    fd.fx[n],
                    fd.fy[n],
                    (fd.fy[n] >= data.cop_threshold && fd.cop_x[n].is_finite())
                        .then_some(fd.cop_x[n]),
                )
            })
        };
        let q = match (kin, angles_at) {
            (Some(n), Some(_)) => angles
                .iter()
                .map(|c| c[n].is_finite().then_some(c[n]))
                .collect(),
            _ => vec![None; nq],
        };
        let target = NodeTarget {
            time: t,
            q,
            qd: vec![None; nq],
            feet: [load(0), load(1)],
        };
        let has_angles = target.q.iter().any(Option::is_some);
        if !has_angles && target.feet.iter().all(Option::is_none) {
            continue;
        }
        // the sample's own place: its angles', or else its first loaded foot's
        let own = if has_angles {
            angles_at
        } else {
            (0..2)
                .find(|&f| target.feet[f].is_some())
                .and_then(|f| loads_at[f])
        };
        let Some((j, k, tau, _)) = own else {
            continue;
        };
        let loads = std::array::from_fn(|f| loads_at[f].map_or((j, k, tau), |p| (p.0, p.1, p.2)));
        out.push(SampleTarget {
            phase: j,
            interval: k,
            tau,
            target,
            load_weight,
            loads_at: loads,
            load_offset,
        });
    }
    Ok(out)
}
