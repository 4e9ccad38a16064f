//! A force plate's clock offset moves what it touches: the compared forces and CoP of
//! that plate, and the contact events taken from that plate's force threshold.
//!
//! A plate whose clock runs δ behind the motion capture's reports a force event at
//! `t_event + δ`; on the motion capture's clock (the model's) the event is at
//! `t_measured − δ`. The tracked window and the contact phases are cut at events, so
//! with δ a free parameter every phase boundary taken from that plate moves by −δ: the
//! window's start, the phase durations, and with them every shooting node's instant
//! (where its angle targets are read). All of these are affine in the plates' offsets
//! `(δ_right, δ_left)`; [`PlateClock`] holds the coefficients. Events given with the data
//! (a meta file's `events_s`, or a synthetic trial's exact events) or taken from the
//! kinematics belong to no plate and do not move.

use super::loaded_feet;
use crate::data::{detect_events, CubicSpline, Events, GaitData, DEFAULT_EVENT_FRACTION};
use crate::model::effects::ModelScalar;
use crate::model::{ConstraintSet, GaitModel};
use crate::phases::{Phase, PhaseSequence};
use crate::problems::GenericFunction;
use std::sync::Arc;

/// How the tracked window moves with the plates' clock offsets δ = (δ_right, δ_left):
/// each instant is its measured value plus `coefficients · δ`.
#[derive(Debug, Clone)]
pub struct PlateClock {
    /// Of the window's start (the first node).
    pub start: [f64; 2],
    /// Of each continuous phase's duration (OCP phase order).
    pub durations: Vec<[f64; 2]>,
    /// Of each node of each continuous phase.
    pub nodes: Vec<Vec<[f64; 2]>>,
    /// Splines of the measured coordinates (the angle targets at a moved node).
    pub kinematics: Arc<Vec<CubicSpline>>,
    /// Whether the node targets are interpolated from splines (the only targets that can
    /// follow a moving node; one-sided and sample targets are cut at fixed boundaries).
    pub interpolated: bool,
}

impl PlateClock {
    /// Whether any instant moves with a plate's clock.
    pub fn moves(&self) -> bool {
        self.start != [0.0; 2] || self.durations.iter().any(|d| *d != [0.0; 2])
    }

    /// `coefficients · δ` for the plates' offsets `delta`.
    pub fn shift(c: [f64; 2], delta: [f64; 2]) -> f64 {
        c[0] * delta[0] + c[1] * delta[1]
    }
}

/// The plate (0 right, 1 left) whose force threshold gave the event at `t`, if any:
/// `plate[s]` are the events detected on plate `s` (exact times).
fn plate_of(t: f64, plate: &[Vec<f64>; 2]) -> Option<usize> {
    (0..2).find(|&s| plate[s].iter().any(|&e| e == t))
}

/// Why one-sided and sample targets keep the events of a plate whose clock is offset.
pub(super) const FIXED_EVENTS: &str = "warning: a free force-plate clock offset in the model moves the contact events taken from that plate's force threshold only with interpolated node targets (the default); with one-sided or sample targets, cut at fixed phase boundaries, the events stay where the offset's start value puts them while it moves";

/// Whether a plate's clock offset is a free parameter of `model`.
fn free_clock(model: &GaitModel) -> bool {
    model
        .parameters()
        .iter()
        .any(|p| p.free && p.name.starts_with("force_plate_time_offset"))
}

/// The offsets (s; right, left) by which, with one-sided or sample targets (cut at fixed
/// phase boundaries), the events of each plate's force threshold are moved to the motion
/// capture's clock (`t − δ`, as its loads are read at `t + δ`): each plate's clock offset
/// as the model starts it. A held offset
/// (`--effect force_plate_time_offset:offset=0.02,free=`) so moves everything derived from
/// its plate; a free one moves the events by its start value only ([`FIXED_EVENTS`]).
/// Zero with interpolated node targets, which move the events with the offset itself
/// ([`PlateClock`]), and for events given with the data, which belong to no plate. With
/// the lines for the run's log.
pub(super) fn start_offsets(
    model: &GaitModel,
    data: &GaitData,
    interpolated: bool,
) -> ([f64; 2], Vec<String>) {
    if interpolated || data.events.is_some() || !model.shifts_force_clock() {
        return ([0.0; 2], Vec::new());
    }
    let delta = model.measurement_adjust(&model.theta0()).force_time_offset;
    let free = free_clock(model);
    let notes = (0..2)
        .filter(|&s| delta[s] != 0.0)
        .map(|s| {
            let side = ["right", "left"][s];
            if free {
                format!(
                    "warning: the contact events of the {side} plate's force threshold are moved by {:+.1} ms, its free clock offset's start value, and stay there while the offset moves (one-sided and sample targets are cut at fixed phase boundaries)",
                    -1e3 * delta[s]
                )
            } else {
                format!(
                    "the contact events of the {side} plate's force threshold are moved by {:+.1} ms, its held clock offset",
                    -1e3 * delta[s]
                )
            }
        })
        .collect();
    (delta, notes)
}

/// The coefficients of every instant of the tracked window `(t0, t1)` of `seq` (its
/// durations already fixed to `events`) in the plates' clock offsets; `kinematics` are
/// the coordinate splines; with the warning [`FIXED_EVENTS`] when the model's clock
/// effects would move them but the targets cannot follow.
#[allow(clippy::too_many_arguments)]
pub(super) fn plate_clock(
    model: &GaitModel,
    seq: &PhaseSequence,
    sets: &[ConstraintSet],
    data: &GaitData,
    events: &Events,
    (t0, t1): (f64, f64),
    kinematics: Vec<CubicSpline>,
    interpolated: bool,
) -> (PlateClock, Option<&'static str>) {
    // the events each plate's force threshold gives (none when the data bring their own)
    let plate: [Vec<f64>; 2] = match (&data.events, detect_events(data, DEFAULT_EVENT_FRACTION)) {
        (None, Ok(d)) => [0, 1].map(|s| {
            d.heel_strike[s]
                .iter()
                .chain(&d.toe_off[s])
                .copied()
                .filter(|e| events.heel_strike[s].contains(e) || events.toe_off[s].contains(e))
                .collect()
        }),
        _ => [Vec::new(), Vec::new()],
    };
    let coeff = |t: f64| -> [f64; 2] {
        let mut c = [0.0; 2];
        if let Some(s) = plate_of(t, &plate) {
            c[s] = -1.0;
        }
        c
    };
    let cont = seq.continuous_indices();
    let fixed = |i: usize| match &seq.phases[i] {
        Phase::Continuous { duration, .. } => duration.value(),
        Phase::Impact { .. } => 0.0,
    };
    // the groups of consecutive phases with the same loaded feet share one measured
    // contact phase (as `fix_durations` cut them): its bounds' coefficients
    let mut groups: Vec<([bool; 2], Vec<usize>)> = Vec::new();
    for (j, &i) in cont.iter().enumerate() {
        let feet = loaded_feet(model, &sets[i]);
        match groups.last_mut() {
            Some((f, v)) if *f == feet => v.push(j),
            _ => groups.push((feet, vec![j])),
        }
    }
    let compliant_only = model.contacts.iter().all(|c| c.law.is_some());
    let bounds: Vec<[f64; 2]> = if compliant_only {
        groups = vec![([true, true], (0..cont.len()).collect())];
        vec![coeff(t0), coeff(t1)]
    } else {
        let measured = events.contact_phases(t0, t1);
        let mut b: Vec<[f64; 2]> = measured.iter().map(|p| coeff(p.start)).collect();
        b.push(coeff(t1));
        if b.len() != groups.len() + 1 {
            // fix_durations matched them; without a match nothing moves
            b = vec![[0.0; 2]; groups.len() + 1];
        }
        b
    };
    let mut durations = vec![[0.0; 2]; cont.len()];
    for (g, (_, members)) in groups.iter().enumerate() {
        let span: f64 = members.iter().map(|&j| fixed(cont[j])).sum();
        for &j in members {
            let w = if span > 0.0 {
                fixed(cont[j]) / span
            } else {
                0.0
            };
            for s in 0..2 {
                durations[j][s] = w * (bounds[g + 1][s] - bounds[g][s]);
            }
        }
    }
    let start = bounds[0];
    let mut nodes = Vec::with_capacity(cont.len());
    let mut at = start;
    for (j, &i) in cont.iter().enumerate() {
        let n = match &seq.phases[i] {
            Phase::Continuous { intervals, .. } => *intervals,
            Phase::Impact { .. } => 0,
        };
        nodes.push(
            (0..=n)
                .map(|k| {
                    let f = k as f64 / n as f64;
                    [0, 1].map(|s| at[s] + f * durations[j][s])
                })
                .collect(),
        );
        for s in 0..2 {
            at[s] += durations[j][s];
        }
    }
    let clock = PlateClock {
        start,
        durations,
        nodes,
        kinematics: Arc::new(kinematics),
        interpolated,
    };
    let warning = (free_clock(model) && clock.moves() && !interpolated).then_some(FIXED_EVENTS);
    (clock, warning)
}

/// The constraint row `d − c · δ(θ)` of a phase whose duration `d` moves with the plates'
/// clock offsets (`c` its coefficients), held at the measured duration: a function of
/// `(d, θ)`.
pub struct DurationClock<'a> {
    /// The model whose measurement effects give the offsets.
    pub model: &'a GaitModel,
    /// The duration's coefficients in (δ_right, δ_left).
    pub coeff: [f64; 2],
}

impl GenericFunction for DurationClock<'_> {
    fn dim(&self) -> usize {
        1
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), crate::ocp::TermError> {
        let d = self.model.measurement_adjust(&z[1..]).force_time_offset;
        out[0] = z[0] - d[0] * self.coeff[0] - d[1] * self.coeff[1];
        Ok(())
    }
    fn is_linear(&self) -> bool {
        true
    }
}

impl super::TrackingSetup {
    /// Whether the model's clock offsets move this window's instants (a plate clock
    /// effect, events taken from that plate's force threshold, and interpolated node
    /// targets: one-sided and sample targets are cut at fixed phase boundaries, and with
    /// them the events stay where the measured forces put them, as a warning in
    /// [`notes`](Self::notes) says).
    pub fn clock_moves(&self, model: &GaitModel) -> bool {
        model.shifts_force_clock() && self.clock.moves() && self.clock.interpolated
    }

    /// The residual of node `k` of continuous phase `j` (`target` its target): as
    /// [`residual`](Self::residual) with the measured loads, its instant moving with the
    /// plates' clocks where [`clock_moves`](Self::clock_moves).
    pub(super) fn node_residual<'m>(
        &self,
        model: &'m GaitModel,
        set: &ConstraintSet,
        (j, k): (usize, usize),
        target: crate::problems::tracking::NodeTarget,
    ) -> crate::problems::tracking::TrackingResidual<'m> {
        let r = self.residual(model, set, target, true);
        match self.clock.nodes.get(j).and_then(|n| n.get(k)) {
            Some(&coeff) if self.clock_moves(model) => {
                r.with_clock(crate::problems::tracking::NodeClock {
                    coeff,
                    kinematics: self.clock.kinematics.clone(),
                })
            }
            _ => r,
        }
    }

    /// The instant (s, motion capture's clock) the first node is at for free parameters
    /// `theta`: the window's start moved by the plates' clock offsets.
    pub fn start_time(&self, model: &GaitModel, theta: &[f64]) -> f64 {
        let t0 = self.window.0;
        if !self.clock_moves(model) {
            return t0;
        }
        let d = model.measurement_adjust(theta).force_time_offset;
        t0 + PlateClock::shift(self.clock.start, d)
    }

    /// Make the durations that move with the plates' clocks free in `ocp`, each held by
    /// an equality row at its measured value plus its coefficients times the offsets
    /// ([`DurationClock`]), started where the model's initial offsets put them.
    pub(super) fn free_moving_durations<'c>(
        &self,
        model: &'c GaitModel,
        ocp: &mut crate::ocp::Ocp<'c>,
    ) {
        if !self.clock_moves(model) {
            return;
        }
        let d0 = model.measurement_adjust(&model.theta0()).force_time_offset;
        for (j, &c) in self.clock.durations.iter().enumerate() {
            if c == [0.0; 2] {
                continue;
            }
            let ph = &mut ocp.phases[j];
            let measured = ph.duration.value;
            // room for the offsets' bounds (±100 ms each, so ±200 ms between two plates)
            ph.duration = crate::ocp::PhaseDuration {
                value: measured + PlateClock::shift(c, d0),
                lb: (measured - 0.25).max(0.2 * measured),
                ub: measured + 0.25,
            };
            ocp.constraints.push(crate::ocp::Constraint {
                term: crate::ocp::Term {
                    name: "plate clock duration".into(),
                    args: vec![
                        crate::ocp::Block::Duration { phase: j },
                        crate::ocp::Block::Params,
                    ],
                    f: Arc::new(crate::problems::AdTerm(DurationClock { model, coeff: c })),
                },
                lb: vec![measured],
                ub: vec![measured],
            });
        }
    }

    /// Move `solution`'s phases to the instants its parameters' clock offsets put them at
    /// (a solution read from the NLP starts at the window's measured start).
    pub fn place(
        &self,
        model: &GaitModel,
        solution: &mut crate::problems::evaluation::GaitSolution,
    ) {
        let dt = self.start_time(model, &solution.theta) - self.window.0;
        if dt != 0.0 {
            for p in &mut solution.phases {
                p.t0 += dt;
            }
        }
    }
}
