//! The tracking problem (Millard & Mombaur 2019, §3.4) assembled from measured data: the phase graph's
//! durations fixed to the measured contact sequence, node targets from splines of the
//! data, an initial guess from the data projected onto the contacts (activations 0.01,
//! excitations 0.025, their §3.6), and the node-wise least-squares residuals of eq. 18.

use super::gait::GaitGuess;
use super::tracking::{MeasuredLoads, NodeTarget, TrackingWeights};
use crate::data::{interp_linear, CubicSpline, Events, GaitData};
use crate::model::gait::COORDINATES;
use crate::model::{ConstraintSet, GaitModel, Side};
use crate::phases::{Duration, Phase, PhaseSequence};
use std::sync::Arc;

/// A measured half cycle from a left heel strike to the next right heel strike (the
/// span Millard & Mombaur's phase graphs describe: 1e*/1c* … 4e*/7c*).
pub fn half_cycle(events: &Events) -> Result<(f64, f64), String> {
    // keep a margin from the start of the recording, where splines are least reliable
    let earliest = events.span.0 + 0.05;
    for &t0 in events.heel_strike[1].iter().filter(|&&t| t >= earliest) {
        if let Some(&t1) = events.heel_strike[0].iter().find(|&&t| t > t0) {
            return Ok((t0, t1));
        }
    }
    Err("the data contain no left heel strike followed by a right heel strike".into())
}

/// Which feet can carry a ground force in a phase with constraint set `set`:
/// `[right, left]`. A foot with a volumetric primitive can in every phase.
pub fn loaded_feet(model: &GaitModel, set: &ConstraintSet) -> [bool; 2] {
    let side = |c: usize| usize::from(model.contacts[c].side != Side::Right);
    let mut f = [false; 2];
    for r in &set.rows {
        f[side(r.contact)] = true;
    }
    for c in (0..model.contacts.len()).filter(|&c| model.is_volumetric(c)) {
        f[side(c)] = true;
    }
    f
}

/// How the node targets are read from the samples.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum TargetSides {
    /// Splines through all the samples (Millard & Mombaur's). At a node on a contact change they
    /// average across the jump a rigid contact makes there (the force at heel strike,
    /// the velocities at an impact), whatever the sampling rate.
    #[default]
    Interpolated,
    /// Each phase's targets from its own samples only: the angles from those between
    /// the neighbouring impacts (where velocities jump), the forces from those strictly
    /// inside the phase (contact forces jump at every contact change), so a node on a
    /// contact change gets the limit from its phase's side. `cutoff_hz` low-passes the
    /// angles segment by segment (odd reflection at the segment's ends). Needs samples
    /// fast enough for every phase to hold [`MIN_SEGMENT_SAMPLES`]; the extrapolation to
    /// the event spans up to one sample interval, so it pays off with high-rate data
    /// (1 kHz, as force plates sample).
    OneSided {
        /// Kinematics low-pass cutoff (Hz), if any.
        cutoff_hz: Option<f64>,
    },
    /// No node targets: every sample inside the tracked window is compared with the model
    /// at its own instant (the shooting interval that holds it integrated to it, see
    /// [`SampleTerm`](crate::ocp::SampleTerm)): angles, and the forces and CoP of the feet
    /// the phase loads. A sample is always on one side of a contact change, so nothing is
    /// averaged across a jump, and there are no velocity targets (velocities are not
    /// measured). The excitation and activation regularisation stays at the nodes.
    Samples,
}

/// A measurement compared with the model inside a shooting interval
/// ([`TargetSides::Samples`]).
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

/// A sample's loads moved by the force plates' clock offset to the end of their phase are
/// evaluated this long (s) before it in cost breakdowns, where the solution is sampled
/// before the impact rather than after it.
const CLOCK_SHIFT_END: f64 = 1e-8;

/// Samples closer than this to a phase boundary (s) are left out of sample targets: on a
/// contact change the measurement belongs to neither side.
const SAMPLE_EDGE: f64 = 1e-9;

/// The fewest samples a phase (forces) or an impact-to-impact segment (angles) must hold
/// for one-sided targets.
pub const MIN_SEGMENT_SAMPLES: usize = 4;

/// Splines of `columns` through the samples strictly inside `(a, b)` (low-passed at
/// `cutoff_hz` first, if given); `what` names the span in errors.
fn segment_splines(
    data: &GaitData,
    columns: &[&[f64]],
    (a, b): (f64, f64),
    cutoff_hz: Option<f64>,
    what: &str,
) -> Result<Vec<CubicSpline>, String> {
    let idx: Vec<usize> = (0..data.time.len())
        .filter(|&k| data.time[k] > a + 1e-9 && data.time[k] < b - 1e-9)
        .collect();
    if idx.len() < MIN_SEGMENT_SAMPLES {
        return Err(format!(
            "one-sided targets: {what} ({a:.4}–{b:.4} s) holds {} samples, fewer than {MIN_SEGMENT_SAMPLES}; sample faster or use interpolated targets",
            idx.len()
        ));
    }
    let t: Vec<f64> = idx.iter().map(|&k| data.time[k]).collect();
    let fs = (t.len() - 1) as f64 / (t[t.len() - 1] - t[0]);
    columns
        .iter()
        .map(|col| {
            let y: Vec<f64> = idx.iter().map(|&k| col[k]).collect();
            let y = match cutoff_hz {
                Some(fc) => crate::data::filter::low_pass(&y, fs, fc),
                None => y,
            };
            CubicSpline::new(&t, &y).map_err(|e| format!("{what}: {e}"))
        })
        .collect()
}

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
fn sample_targets(
    model: &GaitModel,
    seq: &PhaseSequence,
    sets: &[ConstraintSet],
    data: &GaitData,
    t0: f64,
    load_offset: [f64; 2],
) -> Result<Vec<SampleTarget>, String> {
    let angles: Vec<&[f64]> = COORDINATES
        .iter()
        .map(|c| data.channel(c).ok_or_else(|| format!("no channel {c}")))
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

/// `seq` with the durations of its continuous phases fixed to the measured contact
/// sequence over `[t0, t1]`: consecutive phases with the same loaded feet share the
/// measured duration of that contact phase, in proportion to their initial durations.
pub fn fix_durations(
    seq: &PhaseSequence,
    model: &GaitModel,
    sets: &[ConstraintSet],
    events: &Events,
    t0: f64,
    t1: f64,
) -> Result<PhaseSequence, String> {
    let cont: Vec<usize> = seq.continuous_indices();
    if model.contacts.iter().all(|c| c.law.is_some()) {
        // compliant feet only: no contact changes to match; the continuous phases share
        // the window
        let mut out = seq.clone();
        share_span(&mut out, seq, &cont, t1 - t0);
        return Ok(out);
    }
    let measured = events.contact_phases(t0, t1);
    let mut groups: Vec<([bool; 2], Vec<usize>)> = Vec::new();
    for &i in &cont {
        let feet = loaded_feet(model, &sets[i]);
        match groups.last_mut() {
            Some((f, v)) if *f == feet => v.push(i),
            _ => groups.push((feet, vec![i])),
        }
    }
    let pattern = |f: [bool; 2]| match f {
        [true, true] => "double stance",
        [true, false] => "right stance",
        [false, true] => "left stance",
        [false, false] => "flight",
    };
    let g: Vec<&str> = groups.iter().map(|(f, _)| pattern(*f)).collect();
    let m: Vec<&str> = measured.iter().map(|p| pattern(p.contact)).collect();
    if g != m {
        return Err(format!(
            "phase graph '{}' ({}) does not match the measured contacts between {t0:.3} s and {t1:.3} s ({})",
            seq.name,
            g.join(" → "),
            m.join(" → ")
        ));
    }
    let mut out = seq.clone();
    for ((_, idx), mp) in groups.iter().zip(&measured) {
        share_span(&mut out, seq, idx, mp.duration());
    }
    Ok(out)
}

/// Fix the durations of the continuous phases `idx` (in `out`, a copy of `seq`) so that
/// they share `span` (s) in proportion to their initial durations in `seq`.
fn share_span(out: &mut PhaseSequence, seq: &PhaseSequence, idx: &[usize], span: f64) {
    let initial = |i: usize| match &seq.phases[i] {
        Phase::Continuous { duration, .. } => duration.value(),
        Phase::Impact { .. } => 0.0,
    };
    let total: f64 = idx.iter().map(|&i| initial(i)).sum();
    for &i in idx {
        if let Phase::Continuous { duration, .. } = &mut out.phases[i] {
            *duration = Duration::Fixed(span * initial(i) / total);
        }
    }
}

/// Everything the tracking OCP needs, built from data.
pub struct TrackingSetup {
    /// The phase file with durations fixed to the data.
    pub seq: PhaseSequence,
    /// Start and end of the tracked half cycle (s).
    pub window: (f64, f64),
    /// Node times per continuous phase (s).
    pub node_times: Vec<Vec<f64>>,
    /// Initial guess and bounds.
    pub guess: GaitGuess,
    /// Node targets per continuous phase.
    pub targets: Vec<Vec<NodeTarget>>,
    /// Cost weights.
    pub weights: TrackingWeights,
    /// Events detected in the data.
    pub events: Events,
    /// The measured loads as functions of time (for measurement effects).
    pub measured: Arc<MeasuredLoads>,
    /// Measurements compared inside the shooting intervals ([`TargetSides::Samples`]).
    pub samples: Vec<SampleTarget>,
    /// Where the events came from and what the data lack in the window (lines for the
    /// run's log; those starting `warning:` are warnings).
    pub notes: Vec<String>,
    /// How the window's instants move with the force plates' clock offsets.
    pub clock: PlateClock,
}

/// One foot's measured forces as splines over the measured stretch that overlaps the
/// tracked window most (all of the record when nothing is missing).
#[derive(Clone)]
struct ForceTrack {
    fx: CubicSpline,
    fy: CubicSpline,
    /// The stretch (s); node targets outside it have no force terms for this foot.
    stretch: (f64, f64),
}

impl ForceTrack {
    fn new(data: &GaitData, s: usize, (t0, t1): (f64, f64)) -> Result<Self, String> {
        let (time, feet) = data.force_record();
        let f = &feet[s];
        if f.fx.iter().chain(&f.fy).all(|v| v.is_finite()) {
            return Ok(Self {
                fx: CubicSpline::new(time, &f.fx).map_err(|e| e.to_string())?,
                fy: CubicSpline::new(time, &f.fy).map_err(|e| e.to_string())?,
                stretch: (f64::NEG_INFINITY, f64::INFINITY),
            });
        }
        let overlap = |(a, b): (f64, f64)| (b.min(t1) - a.max(t0)).max(0.0);
        let best = data
            .measured_stretches([Side::Right, Side::Left][s])
            .into_iter()
            .filter(|&(a, b)| {
                let k = time.iter().filter(|&&t| t >= a && t <= b).count();
                k >= 4 && b > a
            })
            .max_by(|x, y| overlap(*x).total_cmp(&overlap(*y)));
        let Some((a, b)) = best else {
            // never measured: zero splines that no target reads (every node is outside
            // the empty stretch)
            let z = vec![0.0; data.time.len()];
            let zs = CubicSpline::new(&data.time, &z).map_err(|e| e.to_string())?;
            return Ok(Self {
                fx: zs.clone(),
                fy: zs,
                stretch: (f64::INFINITY, f64::NEG_INFINITY),
            });
        };
        let idx: Vec<usize> = (0..time.len())
            .filter(|&k| time[k] >= a && time[k] <= b && f.fx[k].is_finite())
            .collect();
        let t: Vec<f64> = idx.iter().map(|&k| time[k]).collect();
        let pick = |v: &[f64]| idx.iter().map(|&k| v[k]).collect::<Vec<f64>>();
        Ok(Self {
            fx: CubicSpline::new(&t, &pick(&f.fx)).map_err(|e| e.to_string())?,
            fy: CubicSpline::new(&t, &pick(&f.fy)).map_err(|e| e.to_string())?,
            stretch: (t[0], t[t.len() - 1]),
        })
    }

    /// Whether `t` (s) lies in the measured stretch (to 1e-9 s).
    fn covers(&self, t: f64) -> bool {
        t >= self.stretch.0 - 1e-9 && t <= self.stretch.1 + 1e-9
    }
}

/// Largest distance (m) between the trial's force-plate surface and the model's ground
/// that a tracking accepts: the model's feet touch its ground, so a plate surface
/// elsewhere would be ignored.
pub const MAX_PLATE_GROUND_GAP: f64 = 0.01;

/// Refuse a trial whose force-plate surface (`force_plate_surface_y_m` of its meta file,
/// or the CoP height of its force file) is more than [`MAX_PLATE_GROUND_GAP`] from the
/// model's `contact.ground_height`.
fn check_plate_height(model: &GaitModel, data: &GaitData) -> Result<(), String> {
    let ground = model.contact_settings().ground_height;
    match data.force_plate_height {
        Some(h) if (h - ground).abs() > MAX_PLATE_GROUND_GAP => Err(format!(
            "the force-plate surface is at y = {} m (force_plate_surface_y_m of the meta file, or the force file's CoP height), but the model's ground (contact.ground_height) is at y = {} m; they may differ by at most {} mm: set the model's contact.ground_height to the plate surface",
            crate::limits::show(h),
            crate::limits::show(ground),
            MAX_PLATE_GROUND_GAP * 1e3
        )),
        _ => Ok(()),
    }
}

impl TrackingSetup {
    /// Build from `data` for `model` and the phase file `seq` (with its resolved
    /// constraint sets `sets`), with the events given with the data or else detected from
    /// the force threshold (5 % of peak).
    pub fn new(
        model: &GaitModel,
        seq: &PhaseSequence,
        sets: &[ConstraintSet],
        data: &GaitData,
    ) -> Result<Self, String> {
        Self::new_with_sides(model, seq, sets, data, TargetSides::Interpolated)
    }

    /// As [`new`](Self::new), with the node targets read as `sides` says. For
    /// [`TargetSides::OneSided`] `data` is the unfiltered trial (its cutoff filters each
    /// segment instead of the whole trial).
    pub fn new_with_sides(
        model: &GaitModel,
        seq: &PhaseSequence,
        sets: &[ConstraintSet],
        data: &GaitData,
        sides: TargetSides,
    ) -> Result<Self, String> {
        Self::for_window(model, seq, sets, data, sides, WindowChoice::First)
    }

    /// As [`new_with_sides`](Self::new_with_sides), tracking the half cycle `choice`
    /// selects, with the events of [`combined_events`] (the meta file's, else the force
    /// threshold's completed by kinematic events where a foot is off the plates).
    pub fn for_window(
        model: &GaitModel,
        seq: &PhaseSequence,
        sets: &[ConstraintSet],
        data: &GaitData,
        sides: TargetSides,
        choice: WindowChoice,
    ) -> Result<Self, String> {
        check_plate_height(model, data)?;
        let (offsets, moved) =
            clock::start_offsets(model, data, sides == TargetSides::Interpolated);
        let (events, mut notes) = window::combined_events_on_clocks(model, data, offsets)?;
        notes.extend(moved);
        let choice = if offsets == [0.0; 2] {
            choice
        } else {
            window::same_half_cycle(model, data, &events, offsets, choice)?
        };
        Self::build(model, seq, sets, data, events, sides, choice, notes)
    }

    /// As [`new`](Self::new), with the gait events given instead of detected from the
    /// force threshold (e.g. the exact events of a synthetic trial).
    pub fn with_events(
        model: &GaitModel,
        seq: &PhaseSequence,
        sets: &[ConstraintSet],
        data: &GaitData,
        events: Events,
    ) -> Result<Self, String> {
        Self::with_events_and_sides(model, seq, sets, data, events, TargetSides::Interpolated)
    }

    /// As [`with_events`](Self::with_events), with the node targets read as `sides` says.
    pub fn with_events_and_sides(
        model: &GaitModel,
        seq: &PhaseSequence,
        sets: &[ConstraintSet],
        data: &GaitData,
        events: Events,
        sides: TargetSides,
    ) -> Result<Self, String> {
        Self::build(
            model,
            seq,
            sets,
            data,
            events,
            sides,
            WindowChoice::First,
            Vec::new(),
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn build(
        model: &GaitModel,
        seq: &PhaseSequence,
        sets: &[ConstraintSet],
        data: &GaitData,
        events: Events,
        sides: TargetSides,
        choice: WindowChoice,
        mut notes: Vec<String>,
    ) -> Result<Self, String> {
        let ((t0, t1), gap) = choose_window(data, &events, choice)?;
        if let Some(g) = gap {
            notes.push(format!(
                "warning: {g}; those feet's force and CoP terms are left out there"
            ));
        }
        let seq = fix_durations(seq, model, sets, &events, t0, t1)?;
        let splines: Vec<CubicSpline> = COORDINATES
            .iter()
            .map(|c| data.spline(c).map_err(|e| e.to_string()))
            .collect::<Result<_, _>>()?;
        let tracks = [
            ForceTrack::new(data, 0, (t0, t1))?,
            ForceTrack::new(data, 1, (t0, t1))?,
        ];
        let [r, l] = tracks.clone();
        let (fx, fy) = ([r.fx, l.fx], [r.fy, l.fy]);
        let peak = data.peak_vertical_force();
        let (force_time, force_feet) = data.force_record();
        let cop_at = |s: usize, t: f64| -> Option<f64> {
            // linear interpolation of the measured CoP where the foot is loaded
            let v = interp_linear(&[t], force_time, &force_feet[s].cop_x)[0];
            v.is_finite().then_some(v)
        };
        let cop_gaps = data.cop_missing_while_loaded();
        for (s, gaps) in cop_gaps.iter().enumerate() {
            let inside: Vec<f64> = gaps
                .iter()
                .copied()
                .filter(|&t| t >= t0 && t <= t1)
                .collect();
            if let (Some(a), Some(b)) = (inside.first(), inside.last()) {
                notes.push(format!(
                    "warning: the {} foot is loaded but its CoP is missing at {} sample(s) between {a:.3} and {b:.3} s; there it tracks the forces only",
                    ["right", "left"][s],
                    inside.len()
                ));
            }
        }
        let (nq, na, nu) = (model.nq(), model.na(), model.nu());
        let theta = model.theta0();
        let mut node_times = Vec::new();
        let mut targets = Vec::new();
        let mut gx = Vec::new();
        let mut gu = Vec::new();
        let mut t = t0;
        let linear = seq
            .gait
            .as_ref()
            .is_none_or(|g| g.controls == crate::integrate::ControlShape::Linear);
        // the impacts' times (with the window's ends), where one-sided angle segments break
        let mut impacts = vec![t0];
        let mut at = t0;
        for ph in &seq.phases {
            match ph {
                Phase::Impact { .. } => impacts.push(at),
                Phase::Continuous { duration, .. } => at += duration.value(),
            }
        }
        impacts.push(t1);
        for (i, ph) in seq.phases.iter().enumerate() {
            let Phase::Continuous {
                name,
                duration,
                intervals,
                ..
            } = ph
            else {
                continue;
            };
            let h = duration.value() / *intervals as f64;
            let one_sided = match sides {
                TargetSides::Interpolated | TargetSides::Samples => None,
                TargetSides::OneSided { cutoff_hz } => {
                    if data.feet.iter().any(|f| f.fy.iter().any(|v| v.is_nan())) {
                        return Err("one-sided targets read the forces at the kinematic instants and need them measured throughout; where they are not, use interpolated or sample targets".into());
                    }
                    let end = t + duration.value();
                    let a = impacts
                        .iter()
                        .copied()
                        .filter(|&x| x <= t + 1e-9)
                        .fold(t0, f64::max);
                    let b = impacts
                        .iter()
                        .copied()
                        .filter(|&x| x >= end - 1e-9)
                        .fold(t1, f64::min);
                    let angles: Vec<&[f64]> = COORDINATES
                        .iter()
                        .map(|c| data.channel(c).ok_or_else(|| format!("no channel {c}")))
                        .collect::<Result<_, _>>()?;
                    let angles = segment_splines(
                        data,
                        &angles,
                        (a, b),
                        cutoff_hz,
                        &format!("the segment between the impacts around phase {name}"),
                    )?;
                    let (f, phase) = (&data.feet, format!("phase {name}"));
                    let fx = segment_splines(data, &[&f[0].fx, &f[1].fx], (t, end), None, &phase)?;
                    let fy = segment_splines(data, &[&f[0].fy, &f[1].fy], (t, end), None, &phase)?;
                    Some((angles, fx, fy))
                }
            };
            let untracked = NodeTarget {
                time: 0.0,
                q: vec![None; nq],
                qd: vec![None; nq],
                feet: [None, None],
            };
            let (splines, fx, fy): (&[CubicSpline], &[CubicSpline], &[CubicSpline]) =
                match &one_sided {
                    Some((a, x, y)) => (a, x, y),
                    None => (&splines, &fx, &fy),
                };
            let feet = loaded_feet(model, &sets[i]);
            let times: Vec<f64> = (0..=*intervals).map(|k| t + k as f64 * h).collect();
            let mut tg = Vec::new();
            let mut xs = Vec::new();
            for &tk in &times {
                let q: Vec<f64> = splines.iter().map(|s| s.eval(tk)).collect();
                let qd: Vec<f64> = splines.iter().map(|s| s.derivative(tk)).collect();
                let foot_target = |s: usize| {
                    // a foot whose force was not measured here loses its force terms
                    (feet[s] && tracks[s].covers(tk)).then(|| {
                        let fyv = fy[s].eval(tk);
                        (
                            fx[s].eval(tk),
                            fyv,
                            if fyv >= data.cop_threshold {
                                cop_at(s, tk)
                            } else {
                                None
                            },
                        )
                    })
                };
                tg.push(if sides == TargetSides::Samples {
                    NodeTarget {
                        time: tk,
                        ..untracked.clone()
                    }
                } else {
                    NodeTarget {
                        time: tk,
                        q: q.iter().map(|v| Some(*v)).collect(),
                        qd: qd.iter().map(|v| Some(*v)).collect(),
                        feet: [foot_target(0), foot_target(1)],
                    }
                });
                let (qp, qdp, _) = model
                    .project(&sets[i], &q, &qd, &theta)
                    .map_err(|e| format!("projecting the data at t = {tk:.3} s: {e}"))?;
                let mut x = qp;
                x.extend(qdp);
                x.extend(vec![0.01; na]);
                xs.push(x);
            }
            let cn = if linear { *intervals + 1 } else { *intervals };
            // excitations 0.025; joint torques and residual actuators 0
            let excitations = if model.na() > 0 {
                model.nu_actuators()
            } else {
                0
            };
            let mut u0 = vec![0.025; nu];
            u0[excitations..].iter_mut().for_each(|v| *v = 0.0);
            gu.push(vec![u0; cn]);
            gx.push(xs);
            targets.push(tg);
            node_times.push(times);
            t += duration.value();
        }
        // bounds: the data's range ± 1 (m, rad) and ± 1 (m/s, rad/s) beyond the measured
        // velocities (Millard & Mombaur 2019, §3.3); knee hyper-extension up to 0.1 rad; a, u in [0, 1]
        let (mut x_lb, mut x_ub) = (vec![0.0; model.nx()], vec![0.0; model.nx()]);
        for i in 0..nq {
            let (lo, hi) = data.q[i]
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
            let sp = &splines[i];
            let (dlo, dhi) = data
                .time
                .iter()
                .map(|&tt| sp.derivative(tt))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                });
            x_lb[i] = lo - 1.0;
            x_ub[i] = hi + 1.0;
            x_lb[nq + i] = dlo - 1.0;
            x_ub[nq + i] = dhi + 1.0;
        }
        for i in [4, 7] {
            x_ub[i] = 0.1;
        }
        for i in 2 * nq..model.nx() {
            x_lb[i] = 0.0;
            x_ub[i] = 1.0;
        }
        // excitations in [0, 1], joint torques in ±max_torque, residual actuators in [−1, 1]
        let (u_lb, u_ub) = model.control_bounds();
        let guess = GaitGuess {
            x: gx,
            u: gu,
            x_lb,
            x_ub,
            u_lb,
            u_ub,
        };

        let foot_length = 0.305;
        let weights = TrackingWeights::seed(nq, peak, foot_length);
        let measured = Arc::new(MeasuredLoads {
            fx,
            fy,
            time: force_time.to_vec(),
            cop_x: [force_feet[0].cop_x.clone(), force_feet[1].cop_x.clone()],
            belt_speed: if data.overground {
                data.belt_speed.unwrap_or(0.0)
            } else {
                0.0
            },
        });
        let samples = if sides == TargetSides::Samples {
            let offsets = clock::start_offsets(model, data, false).0;
            sample_targets(model, &seq, sets, data, t0, offsets)?
        } else {
            Vec::new()
        };
        let interpolated = sides == TargetSides::Interpolated;
        let (clock, warning) = clock::plate_clock(
            model,
            &seq,
            sets,
            data,
            &events,
            (t0, t1),
            splines,
            interpolated,
        );
        notes.extend(warning.map(String::from));
        Ok(Self {
            seq,
            window: (t0, t1),
            node_times,
            guess,
            targets,
            weights,
            events,
            measured,
            samples,
            notes,
            clock,
        })
    }

    /// Start from `solution` (a solution of the same phase graph, e.g. of a tracking run
    /// before an effect was added) instead of the data.
    pub fn start_from(&mut self, solution: &super::evaluation::GaitSolution) -> Result<(), String> {
        let cont: Vec<(&str, usize)> = self
            .seq
            .phases
            .iter()
            .filter_map(|p| match p {
                Phase::Continuous {
                    name, intervals, ..
                } => Some((name.as_str(), *intervals)),
                Phase::Impact { .. } => None,
            })
            .collect();
        if cont.len() != solution.phases.len() {
            return Err(format!(
                "the initial solution has {} continuous phases, the phase graph '{}' {}",
                solution.phases.len(),
                self.seq.name,
                cont.len()
            ));
        }
        for (((name, n), ph), gu) in cont.iter().zip(&solution.phases).zip(&self.guess.u) {
            if *name != ph.name || *n != ph.intervals() || ph.u.len() != gu.len() {
                return Err(format!("the initial solution's phase '{}' ({} intervals) does not match the phase graph's '{name}' ({n} intervals)", ph.name, ph.intervals()));
            }
        }
        let nu = self
            .guess
            .u
            .first()
            .and_then(|u| u.first())
            .map_or(0, Vec::len);
        if solution
            .phases
            .iter()
            .flat_map(|p| &p.u)
            .any(|u| u.len() > nu)
        {
            return Err(format!(
                "the initial solution has more controls than the model's {nu}"
            ));
        }
        self.guess.x = solution.phases.iter().map(|p| p.x.clone()).collect();
        // a solution without the residual actuators starts them at zero
        self.guess.u = solution
            .phases
            .iter()
            .zip(&self.guess.u)
            .map(|(p, g)| {
                p.u.iter()
                    .zip(g)
                    .map(|(u, gu)| {
                        u.iter()
                            .copied()
                            .chain(gu[u.len()..].iter().copied())
                            .collect()
                    })
                    .collect()
            })
            .collect();
        Ok(())
    }
}

mod breakdown;
mod clock;
mod residual;
pub mod start;
mod window;

pub use clock::{DurationClock, PlateClock};

pub use window::{
    choose_window, combined_events, half_cycles, kinematic_events, missing_forces, KinematicEvents,
    WindowChoice,
};

pub use breakdown::{CostBreakdown, NodeCost};
