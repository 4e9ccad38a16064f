//! The tracking problem (Millard & Mombaur 2019, §3.4) assembled from measured data: the phase graph's
//! durations fixed to the measured contact sequence, node targets from splines of the
//! data, an initial guess from the data projected onto the contacts (activations 0.01,
//! excitations 0.025, their §3.6), and the node-wise least-squares residuals of eq. 18.

use super::error::{ProblemError, WindowError};
use super::gait::GaitGuess;
use super::tracking::{MeasuredLoads, NodeTarget, TrackingWeights};
use crate::data::{CubicSpline, Events, GaitData};
use crate::model::gait::COORDINATES;
use crate::model::{ConstraintSet, GaitModel, Side};
use crate::phases::{Duration, Phase, PhaseSequence};
use nodes::{ForceTrack, NodeSource};
use samples::sample_targets;
use std::sync::Arc;

/// A measured half cycle from a left heel strike to the next right heel strike (the
/// span Millard & Mombaur's phase graphs describe: 1e*/1c* … 4e*/7c*).
pub fn half_cycle(events: &Events) -> Result<(f64, f64), WindowError> {
    // keep a margin from the start of the recording, where splines are least reliable
    let earliest = events.span.0 + 0.05;
    for &t0 in events.heel_strike[1].iter().filter(|&&t| t >= earliest) {
        if let Some(&t1) = events.heel_strike[0].iter().find(|&&t| t > t0) {
            return Ok((t0, t1));
        }
    }
    Err(WindowError::NoHalfCycle {
        heel_strike: events.heel_strike.clone(),
    })
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

/// A sample's loads moved by the force plates' clock offset to the end of their phase are
/// evaluated this long (s) before it in cost breakdowns, where the solution is sampled
/// before the impact rather than after it.
const CLOCK_SHIFT_END: f64 = 1e-8;

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
) -> Result<PhaseSequence, ProblemError> {
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
    let g: Vec<[bool; 2]> = groups.iter().map(|(f, _)| *f).collect();
    let m: Vec<[bool; 2]> = measured.iter().map(|p| p.contact).collect();
    if g != m {
        return Err(ProblemError::ContactsMismatch {
            graph: seq.name.clone(),
            phases: g,
            measured: m,
            start: t0,
            end: t1,
        });
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

/// Largest distance (m) between the trial's force-plate surface and the model's ground
/// that a tracking accepts: the model's feet touch its ground, so a plate surface
/// elsewhere would be ignored.
pub const MAX_PLATE_GROUND_GAP: f64 = 0.01;

/// Refuse a trial whose force-plate surface (`force_plate_surface_y_m` of its meta file,
/// or the CoP height of its force file) is more than [`MAX_PLATE_GROUND_GAP`] from the
/// model's `contact.ground_height`.
fn check_plate_height(model: &GaitModel, data: &GaitData) -> Result<(), ProblemError> {
    let ground = model.contact_settings().ground_height;
    match data.force_plate_height {
        Some(h) if (h - ground).abs() > MAX_PLATE_GROUND_GAP => Err(ProblemError::PlateHeight {
            plate: h,
            ground,
            max_gap: MAX_PLATE_GROUND_GAP,
        }),
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
    ) -> Result<Self, ProblemError> {
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
    ) -> Result<Self, ProblemError> {
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
    ) -> Result<Self, ProblemError> {
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
    ) -> Result<Self, ProblemError> {
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
    ) -> Result<Self, ProblemError> {
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
    ) -> Result<Self, ProblemError> {
        let ((t0, t1), gap) = choose_window(data, &events, choice)?;
        if let Some(g) = gap {
            notes.push(format!(
                "warning: {g}; those feet's force and CoP terms are left out there"
            ));
        }
        let seq = fix_durations(seq, model, sets, &events, t0, t1)?;
        let splines: Vec<CubicSpline> = COORDINATES
            .iter()
            .map(|c| data.spline(c))
            .collect::<Result<_, _>>()?;
        let tracks = [
            ForceTrack::new(data, 0, (t0, t1))?,
            ForceTrack::new(data, 1, (t0, t1))?,
        ];
        let [r, l] = tracks.clone();
        let (fx, fy) = ([r.fx, l.fx], [r.fy, l.fy]);
        let peak = data.peak_vertical_force();
        let (force_time, force_feet) = data.force_record();
        notes.extend(nodes::cop_gap_notes(data, (t0, t1)));
        let nodes = NodeSource {
            model,
            sets,
            data,
            sides,
            window: (t0, t1),
            splines: &splines,
            tracks: &tracks,
            fx: &fx,
            fy: &fy,
            theta: model.theta0(),
        }
        .nodes(&seq)?;
        let (x_lb, x_ub) = nodes::state_bounds(model, data, &splines);
        // excitations in [0, 1], joint torques in ±max_torque, residual actuators in [−1, 1]
        let (u_lb, u_ub) = model.control_bounds();
        let guess = GaitGuess {
            x: nodes.x,
            u: nodes.u,
            x_lb,
            x_ub,
            u_lb,
            u_ub,
        };

        let foot_length = 0.305;
        let weights = TrackingWeights::seed(model.nq(), peak, foot_length);
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
            node_times: nodes.times,
            guess,
            targets: nodes.targets,
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
    pub fn start_from(
        &mut self,
        solution: &super::evaluation::GaitSolution,
    ) -> Result<(), ProblemError> {
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
            return Err(ProblemError::SolutionPhaseCount {
                found: solution.phases.len(),
                graph: self.seq.name.clone(),
                expected: cont.len(),
            });
        }
        for (((name, n), ph), gu) in cont.iter().zip(&solution.phases).zip(&self.guess.u) {
            if *name != ph.name || *n != ph.intervals() || ph.u.len() != gu.len() {
                return Err(ProblemError::SolutionPhase {
                    found: ph.name.clone(),
                    found_intervals: ph.intervals(),
                    expected: name.to_string(),
                    expected_intervals: *n,
                });
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
            return Err(ProblemError::SolutionControls { controls: nu });
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
mod nodes;
mod residual;
mod samples;
pub mod start;
mod window;

pub use nodes::MIN_SEGMENT_SAMPLES;
pub use samples::SampleTarget;

pub use clock::{DurationClock, PlateClock};

pub use window::{
    choose_window, combined_events, half_cycles, kinematic_events, missing_forces, KinematicEvents,
    WindowChoice,
};

pub use breakdown::{CostBreakdown, NodeCost};
