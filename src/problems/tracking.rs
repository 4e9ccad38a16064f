//! Node-wise least-squares tracking residuals (Millard & Mombaur 2019, eq. 18, evaluated
//! at the shooting nodes as they do): joint and pelvis-tilt angles and angular velocities, ground
//! reaction forces and centre of pressure per foot, and the regularisation of excitations
//! and activations.
//!
//! Each term is `√w · (model − measurement)`, so the cost is `Σ w (model − measurement)²`.
//! The CoP term is written as the load-weighted moment error `(m − x_cop fᵧ) / (F_peak L)`
//! with `m = Σ λₙ x_P`: equal to `(fᵧ/F_peak)(CoP − x_cop)/L`, smooth when the foot unloads.

use super::GenericFunction;
use crate::data::CubicSpline;
use crate::model::effects::ModelScalar;
use crate::model::{ConstraintSet, GaitModel};
use std::sync::Arc;

/// The measured ground loads as functions of time, for measurement effects that move the
/// comparison in time (a force-plate clock offset) and need the targets' derivatives.
#[derive(Debug, Clone)]
pub struct MeasuredLoads {
    /// Tangential force splines (N), right and left.
    pub fx: [CubicSpline; 2],
    /// Normal force splines (N), right and left.
    pub fy: [CubicSpline; 2],
    /// Sample times of the CoP (s).
    pub time: Vec<f64>,
    /// Measured CoP x (m; NaN where the foot is unloaded), right and left.
    pub cop_x: [Vec<f64>; 2],
    /// The treadmill belt speed (m/s) whose displacement the overground CoP holds (at
    /// each sample's own instant, [`crate::data::GaitData::to_overground`]); 0 for a
    /// trial walked overground. A CoP sample compared at an instant a plate's clock
    /// offset moves it to then moves with the belt by the same time.
    pub belt_speed: f64,
}

impl MeasuredLoads {
    /// Tangential and normal force of foot `s` at time `t` (exact in `t`).
    pub fn forces<S: ModelScalar>(&self, s: usize, t: S) -> (S, S) {
        (self.fx[s].eval_generic(t), self.fy[s].eval_generic(t))
    }

    /// CoP of foot `s` at time `t`, linearly interpolated; next to an undefined sample (the
    /// foot unloaded) the value of the nearest defined sample, so that the target stays
    /// continuous in `t` as a clock offset moves a node across the edge of the loaded
    /// samples (it jumped to the node's own target there); `None` where no sample is
    /// defined or `t` is outside the samples.
    pub fn cop<S: ModelScalar>(&self, s: usize, t: S) -> Option<S> {
        let tv = t.value();
        let n = self.time.len();
        if n < 2 || tv < self.time[0] || tv > self.time[n - 1] {
            return None;
        }
        let i = (self.time.partition_point(|&v| v <= tv).max(1) - 1).min(n - 2);
        let (y0, y1) = (self.cop_x[s][i], self.cop_x[s][i + 1]);
        match (y0.is_finite(), y1.is_finite()) {
            (true, true) => {
                Some((t - self.time[i]) * ((y1 - y0) / (self.time[i + 1] - self.time[i])) + y0)
            }
            _ => {
                let left = (0..=i).rev().find(|&j| self.cop_x[s][j].is_finite());
                let right = (i + 1..n).find(|&j| self.cop_x[s][j].is_finite());
                let nearest = match (left, right) {
                    (Some(l), Some(r)) => {
                        if tv - self.time[l] <= self.time[r] - tv {
                            l
                        } else {
                            r
                        }
                    }
                    (Some(j), None) | (None, Some(j)) => j,
                    (None, None) => return None,
                };
                Some(S::c(self.cop_x[s][nearest]))
            }
        }
    }
}

/// What a node is compared with (`None` = not tracked at this node).
#[derive(Debug, Clone, Default)]
pub struct NodeTarget {
    /// Node time (s, on the data's clock).
    pub time: f64,
    /// Generalised positions (m, rad), one entry per coordinate.
    pub q: Vec<Option<f64>>,
    /// Generalised velocities (m/s, rad/s).
    pub qd: Vec<Option<f64>>,
    /// Per foot (right, left): tangential force, normal force (N) and CoP x (m; `None`
    /// while the measured foot is unloaded).
    pub feet: [Option<(f64, f64, Option<f64>)>; 2],
}

/// Weights of the tracking cost.
#[derive(Debug, Clone)]
pub struct TrackingWeights {
    /// Per coordinate weight of the angle error (1/rad² or 1/m²).
    pub angle: Vec<f64>,
    /// Per coordinate weight of the velocity error.
    pub velocity: Vec<f64>,
    /// Force errors are divided by this (N; seed: the peak measured normal force).
    pub force_scale: f64,
    /// Weight of the normalised force errors.
    pub force: f64,
    /// CoP errors are divided by this length (m; the foot length).
    pub cop_length: f64,
    /// Weight of the normalised CoP (moment) errors.
    pub cop: f64,
    /// Weight of the squared excitations (seed: 1e-3), or of the squared joint-torque
    /// controls, torques over the model's reference torque (the CasADi peer's 1e-3).
    pub excitation: f64,
    /// Weight of the squared activations (seed: 1e-3).
    pub activation: f64,
    /// Weight of the squared residual-actuator controls (if the model has them): 1e-2,
    /// so a residual of 10 N or N·m (control 0.1 at 100 per unit) costs at a node what a
    /// 0.5° angle error does.
    pub residual: f64,
}

impl TrackingWeights {
    /// Millard & Mombaur (2019), eq. 18: angles 1/(π/4), angular velocities 0.1/(π/4), ankles at 1/100 of
    /// these; pelvis translations untracked; forces and CoP normalised by the peak force
    /// (and the foot length); u², a² at 1e-3.
    pub fn seed(nq: usize, peak_force: f64, foot_length: f64) -> Self {
        let w = 1.0 / std::f64::consts::FRAC_PI_4;
        let mut angle = vec![w; nq];
        let mut velocity = vec![Self::SEED_VELOCITY * w; nq];
        for i in [0, 1] {
            angle[i] = 0.0;
            velocity[i] = 0.0;
        }
        for i in [5, 8] {
            angle[i] *= 0.01;
            velocity[i] *= 0.01;
        }
        Self {
            angle,
            velocity,
            force_scale: peak_force,
            force: 1.0,
            cop_length: foot_length,
            cop: 1.0,
            excitation: 1e-3,
            activation: 1e-3,
            residual: 1e-2,
        }
    }

    /// Millard & Mombaur's weight of the angular-velocity targets relative to the angles' (eq. 18).
    pub const SEED_VELOCITY: f64 = 0.1;

    /// These weights with the velocity targets weighted `relative` to the angles instead
    /// of Millard & Mombaur's [`SEED_VELOCITY`](Self::SEED_VELOCITY) (the ankles keeping their
    /// 1/100, untracked coordinates staying untracked); 0 drops the velocity targets,
    /// which come from differentiating the smoothed angles rather than from a measurement.
    pub fn with_velocity_weight(mut self, relative: f64) -> Self {
        self.velocity
            .iter_mut()
            .for_each(|v| *v *= relative / Self::SEED_VELOCITY);
        self
    }

    /// Weight of the pelvis position (x, y) errors when they are tracked: 1/(0.1 m), as
    /// Millard & Mombaur weight angles by 1/(π/4) and leave the translations untracked,
    /// which makes the model free to shift along the walkway — and a CoP offset of the
    /// force plates indistinguishable from such a shift.
    pub const PELVIS_POSITION: f64 = 10.0;

    /// These weights with every data channel weighted by the inverse variance of its
    /// measurement noise (`noise`: σ of the angles in rad, the pelvis position in m, the
    /// forces in N and the CoP in m), scaled so that the angles keep Millard & Mombaur's weight:
    /// the maximum-likelihood weighting for independent Gaussian noise, where Millard & Mombaur's
    /// weights count an angle's noise (0.5°) 3.8 times a force's (5 N, peak 995 N) and the
    /// ankles at 1/100. The CoP row, a load-weighted moment error, is weighted so that its
    /// noise counts fully at the peak force (these weights' `force_scale`, N). Untracked
    /// coordinates stay untracked (their velocities too); the velocity targets keep their
    /// weight relative to the angles.
    pub fn with_noise_weights(mut self, noise: &ChannelNoise) -> Self {
        let c = self.angle.iter().copied().fold(0.0, f64::max) * noise.angle_rad.powi(2);
        for (i, (a, v)) in self.angle.iter_mut().zip(&mut self.velocity).enumerate() {
            if *a > 0.0 {
                let relative = *v / *a;
                *a = c / if i < 2 {
                    noise.position_m
                } else {
                    noise.angle_rad
                }
                .powi(2);
                *v = relative * *a;
            } else {
                *v = 0.0;
            }
        }
        self.cop = c * (noise.force_n * self.cop_length / (self.force_scale * noise.cop_m)).powi(2);
        self.force = c;
        self.force_scale = noise.force_n;
        self
    }

    /// Also track the pelvis position (x, y) at [`PELVIS_POSITION`](Self::PELVIS_POSITION).
    pub fn with_pelvis_position(mut self) -> Self {
        self.angle[0] = Self::PELVIS_POSITION;
        self.angle[1] = Self::PELVIS_POSITION;
        self
    }
}

/// Standard deviations of the measurement noise per channel kind, for
/// [`TrackingWeights::with_noise_weights`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChannelNoise {
    /// Pelvis tilt and joint angles (rad).
    pub angle_rad: f64,
    /// Pelvis position (m).
    pub position_m: f64,
    /// Ground reaction forces (N).
    pub force_n: f64,
    /// Centre of pressure (m).
    pub cop_m: f64,
}

/// How a node's instant moves with the force plates' clock offsets when the phase
/// boundaries come from their force thresholds: the node is at
/// `time + coeff · (δ_right, δ_left)` on the motion capture's clock (δ the plates' clock
/// offsets of [`MeasurementAdjust`](crate::model::effects::MeasurementAdjust)), where
/// its angle targets are read from `kinematics`.
#[derive(Debug, Clone)]
pub struct NodeClock {
    /// The node time's derivative with respect to each plate's clock offset.
    pub coeff: [f64; 2],
    /// Splines of the measured coordinates, in the model's order.
    pub kinematics: Arc<Vec<CubicSpline>>,
}

/// The residual of one node.
pub struct TrackingResidual<'a> {
    model: &'a GaitModel,
    set: ConstraintSet,
    target: NodeTarget,
    weights: TrackingWeights,
    measured: Option<Arc<MeasuredLoads>>,
    regularised: bool,
    /// The loads are compared with the target's own values (the CoP offset still
    /// applied), never with the measured loads at a moved time.
    as_measured: bool,
    /// The node's instant moves with the plates' clock offsets.
    clock: Option<NodeClock>,
    dim: usize,
}

/// The shift (s) of a sample term's instant whose loads are read on one force plate's
/// clock: the sample taken at t is compared with the model at `t − force_time_offset(θ)`,
/// a function of θ ([`SampleTerm::shift`](crate::ocp::SampleTerm)), its term already
/// placed at `t − placed`, so shifted by `placed − force_time_offset(θ)`.
pub struct ForceClockShift<'a> {
    /// The model whose measurement effects give the offset.
    pub model: &'a GaitModel,
    /// The foot whose plate's clock it is (0 right, 1 left).
    pub side: usize,
    /// The offset (s) the term's place already applies: a held offset, or a free one's
    /// start value.
    pub placed: f64,
}

impl GenericFunction for ForceClockShift<'_> {
    fn dim(&self) -> usize {
        1
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), crate::ocp::TermError> {
        out[0] =
            S::from(self.placed) - self.model.measurement_adjust(z).force_time_offset[self.side];
        Ok(())
    }
    fn is_linear(&self) -> bool {
        true
    }
}

/// The cost breakdown's name for the actuators' effort rows: `excitations` of muscle
/// torque generators, or `joint torques` of a torque-driven model.
pub fn effort_channel(model: &GaitModel) -> &'static str {
    if model.na() > 0 {
        "excitations"
    } else {
        "joint torques"
    }
}

impl<'a> TrackingResidual<'a> {
    /// Residual of a node in a phase with constraint set `set`; its arguments are the
    /// node's state, its control and θ. With a model that has measurement effects, the
    /// force and CoP targets are taken from `measured` through them (the target's values
    /// otherwise).
    pub fn new(
        model: &'a GaitModel,
        set: ConstraintSet,
        target: NodeTarget,
        weights: TrackingWeights,
        measured: Option<Arc<MeasuredLoads>>,
    ) -> Self {
        let nq = model.nq();
        let mut dim = 0;
        for i in 0..nq {
            if target.q.get(i).copied().flatten().is_some() && weights.angle[i] > 0.0 {
                dim += 1;
            }
            if target.qd.get(i).copied().flatten().is_some() && weights.velocity[i] > 0.0 {
                dim += 1;
            }
        }
        for f in target.feet.iter().flatten() {
            dim += 2 + usize::from(f.2.is_some());
        }
        dim += model.nu() + model.na();
        let measured = measured.filter(|_| model.has_measurement_effects());
        Self {
            model,
            set,
            target,
            weights,
            measured,
            regularised: true,
            as_measured: false,
            clock: None,
            dim,
        }
    }

    /// The same residual at a node whose instant moves with the plates' clock offsets
    /// (its angle and velocity targets then read from `clock.kinematics` at the moved
    /// instant, its loads from the measured ones there plus each plate's offset).
    pub fn with_clock(mut self, clock: NodeClock) -> Self {
        if clock.coeff != [0.0, 0.0] {
            self.clock = Some(clock);
        }
        self
    }

    /// The same residual with the loads compared with the target's own values (the CoP
    /// offset still applied) rather than with the measured loads at the time the force
    /// plates' clock offset moves them to: for a sample term whose instant that offset
    /// moves instead ([`ForceClockShift`]), so that the measured forces, and their noise,
    /// are never interpolated.
    pub fn at_measured_values(mut self) -> Self {
        self.as_measured = true;
        self
    }

    /// The same residual without the regularisation rows (excitations, activations,
    /// residual actuators): the data rows only, for a measurement compared with the model
    /// at its own instant inside a shooting interval (the regularisation stays at the
    /// nodes).
    pub fn data_only(mut self) -> Self {
        if self.regularised {
            self.regularised = false;
            self.dim -= self.model.nu() + self.model.na();
        }
        self
    }

    /// The channel each residual row belongs to, in row order: the coordinate's name for
    /// positions and angles, `velocities`, `tangential GRF`, `normal GRF`, `CoP`,
    /// `excitations`, `activations` (for cost breakdowns).
    pub fn row_channels(&self) -> Vec<String> {
        let names = crate::model::gait::COORDINATES;
        let (nq, w) = (self.model.nq(), &self.weights);
        let mut out = Vec::with_capacity(self.dim);
        for i in 0..nq {
            if self.target.q.get(i).copied().flatten().is_some() && w.angle[i] > 0.0 {
                out.push(
                    names
                        .get(i)
                        .map_or_else(|| format!("q{i}"), |n| n.to_string()),
                );
            }
            if self.target.qd.get(i).copied().flatten().is_some() && w.velocity[i] > 0.0 {
                out.push("velocities".into());
            }
        }
        for f in self.target.feet.iter().flatten() {
            out.push("tangential GRF".into());
            out.push("normal GRF".into());
            if f.2.is_some() {
                out.push("CoP".into());
            }
        }
        if self.regularised {
            out.extend(std::iter::repeat_n(
                effort_channel(self.model).to_string(),
                self.model.nu_actuators(),
            ));
            out.extend(
                self.model
                    .control_names()
                    .into_iter()
                    .skip(self.model.nu_actuators()),
            );
            out.extend(std::iter::repeat_n(
                "activations".to_string(),
                self.model.na(),
            ));
        }
        out
    }

    fn residual<S: ModelScalar>(
        &self,
        x: &[S],
        u: &[S],
        th: &[S],
        out: &mut [S],
    ) -> Result<(), crate::ocp::TermError> {
        let (nq, w) = (self.model.nq(), &self.weights);
        // the node's instant on the motion capture's clock, moved with the plates' clocks
        let moved = self.clock.as_ref().map(|c| {
            let adj = self.model.measurement_adjust(th);
            let t = adj.force_time_offset[0] * c.coeff[0]
                + adj.force_time_offset[1] * c.coeff[1]
                + self.target.time;
            (c, t)
        });
        let mut o = 0;
        for i in 0..nq {
            if let Some(r) = self.target.q.get(i).copied().flatten() {
                if w.angle[i] > 0.0 {
                    let r = match &moved {
                        Some((c, t)) => c.kinematics[i].eval_generic(*t),
                        None => S::c(r),
                    };
                    out[o] = (x[i] - r) * w.angle[i].sqrt();
                    o += 1;
                }
            }
            if let Some(r) = self.target.qd.get(i).copied().flatten() {
                if w.velocity[i] > 0.0 {
                    let r = match &moved {
                        Some((c, t)) => c.kinematics[i].derivative_generic(*t),
                        None => S::c(r),
                    };
                    out[o] = (x[nq + i] - r) * w.velocity[i].sqrt();
                    o += 1;
                }
            }
        }
        if self.target.feet.iter().any(Option::is_some) {
            let loads = self.model.foot_loads_generic(&self.set, x, u, th)?;
            let adjust = self
                .measured
                .as_ref()
                .map(|m| (m, self.model.measurement_adjust(th)));
            let node_time = moved.as_ref().map_or(S::c(self.target.time), |(_, t)| *t);
            for (s, tgt) in self.target.feet.iter().enumerate() {
                let Some((fx, fy, cop)) = *tgt else { continue };
                // targets at the node time, or through the measurement effects
                let (tfx, tfy, tcop, cop_offset, gain) = match &adjust {
                    // the sample's own values; its overground CoP at the instant the
                    // plate's clock moves it to (t − δ): the belt moved by −δ·v more
                    Some((m, adj)) if self.as_measured => (
                        S::c(fx),
                        S::c(fy),
                        cop.map(|c| S::c(c) - adj.force_time_offset[s] * m.belt_speed),
                        adj.cop_offset[s],
                        adj.force_gain[s],
                    ),
                    Some((m, adj)) => {
                        let t = adj.force_time_offset[s] + node_time;
                        let (a, b) = m.forces(s, t);
                        // the overground CoP read δ later holds the belt's displacement
                        // δ·v further on: back to the node's instant
                        let c = cop.map(|c0| {
                            m.cop(s, t)
                                .map(|c| c - adj.force_time_offset[s] * m.belt_speed)
                                .unwrap_or(S::c(c0))
                        });
                        (a, b, c, adj.cop_offset[s], adj.force_gain[s])
                    }
                    None => (S::c(fx), S::c(fy), cop.map(S::c), S::c(0.0), S::c(1.0)),
                };
                let sc = w.force.sqrt() / w.force_scale;
                out[o] = (loads[s].0 * gain - tfx) * sc;
                out[o + 1] = (loads[s].1 * gain - tfy) * sc;
                o += 2;
                if let Some(xc) = tcop {
                    out[o] = (loads[s].2 + loads[s].1 * (cop_offset - xc))
                        * (w.cop.sqrt() / (w.force_scale * w.cop_length));
                    o += 1;
                }
            }
        }
        if !self.regularised {
            assert_eq!(o, self.dim);
            return Ok(());
        }
        let n_act = self.model.nu_actuators();
        for (k, v) in u.iter().enumerate() {
            let weight = if k < n_act { w.excitation } else { w.residual };
            out[o] = *v * weight.sqrt();
            o += 1;
        }
        for i in 0..self.model.na() {
            out[o] = x[2 * nq + i] * w.activation.sqrt();
            o += 1;
        }
        assert_eq!(o, self.dim);
        Ok(())
    }
}

/// Wrapped in [`AdTerm`](super::AdTerm) for the OCP: exact Jacobian and Hessian by AD.
impl GenericFunction for TrackingResidual<'_> {
    fn dim(&self) -> usize {
        self.dim
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), crate::ocp::TermError> {
        let (x, rest) = z.split_at(self.model.nx());
        let (u, th) = rest.split_at(self.model.nu());
        self.residual(x, u, th, out)
    }
    /// Only the ground-force and CoP rows are nonlinear, and the angle rows of a node
    /// that moves with the plates' clocks.
    fn is_linear(&self) -> bool {
        self.clock.is_none() && self.target.feet.iter().all(Option::is_none)
    }
    /// The controls enter only through the ground loads, that is through the dynamics.
    fn curved_inputs(&self) -> Option<(Vec<usize>, usize)> {
        Some(self.model.curved_inputs())
    }
}
