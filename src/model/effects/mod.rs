//! Optional physical effects: model components with named parameters an optimiser may free.
//!
//! An effect is one type implementing [`Effect`]. Its hooks are generic over the scalar
//! type, so parameter sensitivities come from the same automatic differentiation as the
//! rest of the model. The blanket implementation of [`DynEffect`] makes every [`Effect`]
//! usable as a trait object; [`ModelScalar`] routes generic model code to it.
//!
//! Three kinds of hooks exist: *model* hooks change the dynamics (inertia, gravity, ground,
//! generalised forces, a compliant contact), *actuator* hooks change the muscle-torque
//! generators (strength, damping, activation time constants), and *measurement* hooks
//! change how the model is compared with the data, per force plate (a plate's clock
//! offset, which also moves the contact events taken from its force threshold, an
//! offset of its centre of pressure, its gain).
//!
//! A user adds an effect with one entry in the model JSON (`"effects": [{"type": …}]`)
//! or `--effect NAME` on the command line; [`EffectSpec`] lists the known kinds and
//! [`catalog`] the candidates `footfall diagnose` tries; [`measurement_effects`] the
//! instrument and body effects the measurement check reads.

mod actuator_properties;
mod catalog;
mod geometry;
mod instruments;
mod kinds;
mod spec;
mod volumetric;

pub use actuator_properties::{ActivationTimeConstants, MtgDampingScale, MtgStrengthScale};
pub use catalog::{catalog, measurement_effects};
pub use geometry::FootGeometry;
pub use instruments::{BodyMassError, ForcePlateGain};
pub use kinds::{
    CopOffset, ForcePlateTimeOffset, GroundSlope, HeelPadCompliance, PassiveJointStiffness,
    TrunkMass,
};
pub(crate) use spec::EFFECT_KINDS;
pub use spec::{BuildContext, EffectSpec};
pub use volumetric::{VolumetricContact, VolumetricStart};

use super::ad::{AdChunk, AdNested};
use super::multibody::{Inertia, V2};
use super::Scalar;
use num_dual::Dual64;
use serde::{Deserialize, Serialize};

/// One named parameter of an effect.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamSpec {
    /// Fully qualified name, e.g. `passive_joint_stiffness.knee_r.stiffness`.
    pub name: String,
    /// Current (or initial) value.
    pub value: f64,
    /// Lower bound for identification.
    pub lower: f64,
    /// Upper bound for identification.
    pub upper: f64,
    /// Unit, for reports.
    pub unit: String,
    /// Whether the parameter is free (a sensitivity parameter θ of the model).
    pub free: bool,
}

/// Model quantities an effect may change before the dynamics are evaluated.
#[derive(Debug)]
pub struct ModelAdjust<'a, S> {
    /// Inertial parameters of each body.
    pub inertia: &'a mut [Inertia<S>],
    /// Gravity vector in the world frame (m/s²).
    pub gravity: &'a mut V2<S>,
    /// Ground plane height along its normal (m).
    pub ground_height: &'a mut S,
    /// Ground plane unit normal (world).
    pub ground_normal: &'a mut V2<S>,
}

/// How the measurements relate to the model, changed by measurement effects, per foot
/// (`[right, left]`: each foot's stance is on its own force plate, so each foot's loads
/// are one instrument). With no such effect the offsets are zero and the gains one: the
/// model is compared with the data at the same instant, position and scale.
#[derive(Debug, Clone, Copy)]
pub struct MeasurementAdjust<S> {
    /// The model's ground forces and CoP of foot `s` at time `t` are compared with the
    /// measured ones at `t + force_time_offset[s]` (s; positive when that plate's clock
    /// runs behind the motion capture's). The force-threshold events of that plate move
    /// with it (see `problems::track`).
    pub force_time_offset: [S; 2],
    /// The measured CoP of foot `s` is the model's plus this (m, along the walkway).
    pub cop_offset: [S; 2],
    /// The measured forces of foot `s` are the model's times this (reported over true;
    /// the CoP, a ratio of moment and force, is unchanged).
    pub force_gain: [S; 2],
}

impl<S: Scalar> MeasurementAdjust<S> {
    /// No measurement effect: zero offsets, unit gains.
    pub fn identity() -> Self {
        Self {
            force_time_offset: [S::c(0.0), S::c(0.0)],
            cop_offset: [S::c(0.0), S::c(0.0)],
            force_gain: [S::c(1.0), S::c(1.0)],
        }
    }
}

/// Actuator properties changed by actuator effects, as factors of the model's own
/// (all one without such an effect). Only muscle-torque generators have them.
#[derive(Debug, Clone, Copy)]
pub struct ActuatorAdjust<S> {
    /// Factor on every MTG's maximum isometric torque τ₀ (and so, by Millard & Mombaur 2019, eq. 12, on the
    /// passive damping β, which is proportional to τ₀).
    pub strength: S,
    /// Factor on the damping factor η of Millard & Mombaur 2019, eq. 12 (β ∝ η).
    pub damping: S,
    /// Factor on the activation and deactivation time constants τ_A, τ_D (Millard & Mombaur 2019, eq. 10).
    pub time: S,
}

impl<S: Scalar> ActuatorAdjust<S> {
    /// No actuator effect: every factor one.
    pub fn identity() -> Self {
        Self {
            strength: S::c(1.0),
            damping: S::c(1.0),
            time: S::c(1.0),
        }
    }
}

/// Read-only state seen by an effect's generalised forces.
#[derive(Debug, Clone, Copy)]
pub struct EffectState<'a, S> {
    /// Generalised positions.
    pub q: &'a [S],
    /// Generalised velocities.
    pub qd: &'a [S],
}

/// A physical effect, written once for any scalar type.
pub trait Effect: std::fmt::Debug + Send + Sync {
    /// Kind name as used in JSON (`"type"`).
    fn kind(&self) -> &'static str;
    /// The effect's parameters (values, bounds, whether free), in a fixed order.
    fn parameters(&self) -> &[ParamSpec];
    /// Change inertial parameters, gravity or ground (default: nothing).
    fn adjust_model<S: Scalar>(&self, _p: &[S], _m: &mut ModelAdjust<'_, S>) {}
    /// Add generalised forces (N or N·m) to `tau` (default: nothing).
    fn generalized_forces<S: Scalar>(&self, _p: &[S], _x: EffectState<'_, S>, _tau: &mut [S]) {}
    /// Change how the measurements are compared with the model (default: nothing).
    fn adjust_measurement<S: Scalar>(&self, _p: &[S], _m: &mut MeasurementAdjust<S>) {}
    /// Change the muscle-torque generators' properties (default: nothing).
    fn adjust_actuators<S: Scalar>(&self, _p: &[S], _a: &mut ActuatorAdjust<S>) {}
    /// Whether the effect has an actuator hook (a model without muscle-torque generators
    /// refuses it).
    fn is_actuator(&self) -> bool {
        false
    }
    /// Whether the effect changes the activation time constants: the excitations then
    /// enter `ȧ = (e − a)/τ(θ)` with a parameter-dependent coefficient.
    fn scales_activation_time(&self) -> bool {
        false
    }
    /// Whether the effect has a measurement hook (the tracking residual then evaluates
    /// its targets through it).
    fn is_measurement(&self) -> bool {
        false
    }
    /// Whether the effect moves the force plates' clock against the motion capture's
    /// (`MeasurementAdjust::force_time_offset`): a tracking cost that compares every
    /// sample at its own instant then moves the model's instant rather than
    /// interpolating the measured forces, whose noise an interpolation would smooth.
    fn shifts_force_clock(&self) -> bool {
        false
    }
    /// Name of the contact primitive (on both feet, e.g. `heel`) whose normal contact
    /// this effect makes compliant: its normal row is then no rigid constraint but the
    /// force [`normal_force`](Self::normal_force) (default: none).
    fn compliant_primitive(&self) -> Option<&str> {
        None
    }
    /// Normal force (N) of a compliant contact at penetration `depth` (m, > 0 into the
    /// ground) and penetration rate `rate` (m/s).
    fn normal_force<S: Scalar>(&self, _p: &[S], _depth: S, _rate: S) -> S {
        S::c(0.0)
    }
    /// Names of the volumetric primitives (on both feet) whose law this effect's
    /// parameters replace: primitive `i` takes parameters `3i..3i+3`, its area stiffness
    /// (N/mm²), damping (s/m) and dynamic friction coefficient (default: none).
    fn volumetric_primitives(&self) -> &[String] {
        &[]
    }
    /// The primitives (on both feet) whose geometry this effect's parameters replace, each
    /// with the offset of its parameters: centre x, y (m), then a circle's radius or an
    /// ellipse's semi-axes a, b (m) and angle (rad), a point nothing more (default: none).
    fn geometry_primitives(&self) -> &[(String, usize)] {
        &[]
    }
}

/// Object-safe form of [`Effect`], implemented for every effect. The methods are
/// monomorphic copies of the generic hooks, one per scalar type the model uses.
#[allow(missing_docs)]
pub trait DynEffect: std::fmt::Debug + Send + Sync {
    fn kind(&self) -> &'static str;
    fn parameters(&self) -> &[ParamSpec];
    fn adjust_f64(&self, p: &[f64], m: &mut ModelAdjust<'_, f64>);
    fn adjust_dual(&self, p: &[Dual64], m: &mut ModelAdjust<'_, Dual64>);
    fn adjust_chunk(&self, p: &[AdChunk], m: &mut ModelAdjust<'_, AdChunk>);
    fn adjust_nested(&self, p: &[AdNested], m: &mut ModelAdjust<'_, AdNested>);
    fn forces_f64(&self, p: &[f64], x: EffectState<'_, f64>, tau: &mut [f64]);
    fn forces_dual(&self, p: &[Dual64], x: EffectState<'_, Dual64>, tau: &mut [Dual64]);
    fn forces_chunk(&self, p: &[AdChunk], x: EffectState<'_, AdChunk>, tau: &mut [AdChunk]);
    fn forces_nested(&self, p: &[AdNested], x: EffectState<'_, AdNested>, tau: &mut [AdNested]);
    fn measurement_f64(&self, p: &[f64], m: &mut MeasurementAdjust<f64>);
    fn measurement_dual(&self, p: &[Dual64], m: &mut MeasurementAdjust<Dual64>);
    fn measurement_chunk(&self, p: &[AdChunk], m: &mut MeasurementAdjust<AdChunk>);
    fn measurement_nested(&self, p: &[AdNested], m: &mut MeasurementAdjust<AdNested>);
    fn actuators_f64(&self, p: &[f64], a: &mut ActuatorAdjust<f64>);
    fn actuators_dual(&self, p: &[Dual64], a: &mut ActuatorAdjust<Dual64>);
    fn actuators_chunk(&self, p: &[AdChunk], a: &mut ActuatorAdjust<AdChunk>);
    fn actuators_nested(&self, p: &[AdNested], a: &mut ActuatorAdjust<AdNested>);
    fn is_actuator(&self) -> bool;
    fn scales_activation_time(&self) -> bool;
    fn is_measurement(&self) -> bool;
    fn shifts_force_clock(&self) -> bool;
    fn compliant_primitive(&self) -> Option<&str>;
    fn volumetric_primitives(&self) -> &[String];
    fn geometry_primitives(&self) -> &[(String, usize)];
    fn normal_force_f64(&self, p: &[f64], depth: f64, rate: f64) -> f64;
    fn normal_force_dual(&self, p: &[Dual64], depth: Dual64, rate: Dual64) -> Dual64;
    fn normal_force_chunk(&self, p: &[AdChunk], depth: AdChunk, rate: AdChunk) -> AdChunk;
    fn normal_force_nested(&self, p: &[AdNested], depth: AdNested, rate: AdNested) -> AdNested;
}

impl<E: Effect> DynEffect for E {
    fn kind(&self) -> &'static str {
        Effect::kind(self)
    }
    fn parameters(&self) -> &[ParamSpec] {
        Effect::parameters(self)
    }
    fn adjust_f64(&self, p: &[f64], m: &mut ModelAdjust<'_, f64>) {
        self.adjust_model(p, m)
    }
    fn adjust_dual(&self, p: &[Dual64], m: &mut ModelAdjust<'_, Dual64>) {
        self.adjust_model(p, m)
    }
    fn adjust_chunk(&self, p: &[AdChunk], m: &mut ModelAdjust<'_, AdChunk>) {
        self.adjust_model(p, m)
    }
    fn adjust_nested(&self, p: &[AdNested], m: &mut ModelAdjust<'_, AdNested>) {
        self.adjust_model(p, m)
    }
    fn forces_f64(&self, p: &[f64], x: EffectState<'_, f64>, tau: &mut [f64]) {
        self.generalized_forces(p, x, tau)
    }
    fn forces_dual(&self, p: &[Dual64], x: EffectState<'_, Dual64>, tau: &mut [Dual64]) {
        self.generalized_forces(p, x, tau)
    }
    fn forces_chunk(&self, p: &[AdChunk], x: EffectState<'_, AdChunk>, tau: &mut [AdChunk]) {
        self.generalized_forces(p, x, tau)
    }
    fn forces_nested(&self, p: &[AdNested], x: EffectState<'_, AdNested>, tau: &mut [AdNested]) {
        self.generalized_forces(p, x, tau)
    }
    fn measurement_f64(&self, p: &[f64], m: &mut MeasurementAdjust<f64>) {
        self.adjust_measurement(p, m)
    }
    fn measurement_dual(&self, p: &[Dual64], m: &mut MeasurementAdjust<Dual64>) {
        self.adjust_measurement(p, m)
    }
    fn measurement_chunk(&self, p: &[AdChunk], m: &mut MeasurementAdjust<AdChunk>) {
        self.adjust_measurement(p, m)
    }
    fn measurement_nested(&self, p: &[AdNested], m: &mut MeasurementAdjust<AdNested>) {
        self.adjust_measurement(p, m)
    }
    fn actuators_f64(&self, p: &[f64], a: &mut ActuatorAdjust<f64>) {
        self.adjust_actuators(p, a)
    }
    fn actuators_dual(&self, p: &[Dual64], a: &mut ActuatorAdjust<Dual64>) {
        self.adjust_actuators(p, a)
    }
    fn actuators_chunk(&self, p: &[AdChunk], a: &mut ActuatorAdjust<AdChunk>) {
        self.adjust_actuators(p, a)
    }
    fn actuators_nested(&self, p: &[AdNested], a: &mut ActuatorAdjust<AdNested>) {
        self.adjust_actuators(p, a)
    }
    fn is_actuator(&self) -> bool {
        Effect::is_actuator(self)
    }
    fn scales_activation_time(&self) -> bool {
        Effect::scales_activation_time(self)
    }
    fn is_measurement(&self) -> bool {
        Effect::is_measurement(self)
    }
    fn shifts_force_clock(&self) -> bool {
        Effect::shifts_force_clock(self)
    }
    fn compliant_primitive(&self) -> Option<&str> {
        Effect::compliant_primitive(self)
    }
    fn volumetric_primitives(&self) -> &[String] {
        Effect::volumetric_primitives(self)
    }
    fn geometry_primitives(&self) -> &[(String, usize)] {
        Effect::geometry_primitives(self)
    }
    fn normal_force_f64(&self, p: &[f64], depth: f64, rate: f64) -> f64 {
        self.normal_force(p, depth, rate)
    }
    fn normal_force_dual(&self, p: &[Dual64], depth: Dual64, rate: Dual64) -> Dual64 {
        self.normal_force(p, depth, rate)
    }
    fn normal_force_chunk(&self, p: &[AdChunk], depth: AdChunk, rate: AdChunk) -> AdChunk {
        self.normal_force(p, depth, rate)
    }
    fn normal_force_nested(&self, p: &[AdNested], depth: AdNested, rate: AdNested) -> AdNested {
        self.normal_force(p, depth, rate)
    }
}

/// The scalar types the model's dynamics can be evaluated in (those [`DynEffect`] has a
/// method for).
pub trait ModelScalar: Scalar {
    /// Route to the effect's model adjustment for this scalar type.
    fn adjust(e: &dyn DynEffect, p: &[Self], m: &mut ModelAdjust<'_, Self>);
    /// Route to the effect's generalised forces for this scalar type.
    fn forces(e: &dyn DynEffect, p: &[Self], x: EffectState<'_, Self>, tau: &mut [Self]);
    /// Route to the effect's measurement adjustment for this scalar type.
    fn measurement(e: &dyn DynEffect, p: &[Self], m: &mut MeasurementAdjust<Self>);
    /// Route to the effect's compliant normal force for this scalar type.
    fn normal_force(e: &dyn DynEffect, p: &[Self], depth: Self, rate: Self) -> Self;
    /// Route to the effect's actuator adjustment for this scalar type.
    fn actuators(e: &dyn DynEffect, p: &[Self], a: &mut ActuatorAdjust<Self>);
}

macro_rules! model_scalar {
    ($t:ty, $adj:ident, $frc:ident, $mea:ident, $nf:ident, $act:ident) => {
        impl ModelScalar for $t {
            fn adjust(e: &dyn DynEffect, p: &[Self], m: &mut ModelAdjust<'_, Self>) {
                e.$adj(p, m)
            }
            fn forces(e: &dyn DynEffect, p: &[Self], x: EffectState<'_, Self>, tau: &mut [Self]) {
                e.$frc(p, x, tau)
            }
            fn measurement(e: &dyn DynEffect, p: &[Self], m: &mut MeasurementAdjust<Self>) {
                e.$mea(p, m)
            }
            fn normal_force(e: &dyn DynEffect, p: &[Self], depth: Self, rate: Self) -> Self {
                e.$nf(p, depth, rate)
            }
            fn actuators(e: &dyn DynEffect, p: &[Self], a: &mut ActuatorAdjust<Self>) {
                e.$act(p, a)
            }
        }
    };
}
model_scalar!(
    f64,
    adjust_f64,
    forces_f64,
    measurement_f64,
    normal_force_f64,
    actuators_f64
);
model_scalar!(
    Dual64,
    adjust_dual,
    forces_dual,
    measurement_dual,
    normal_force_dual,
    actuators_dual
);
model_scalar!(
    AdChunk,
    adjust_chunk,
    forces_chunk,
    measurement_chunk,
    normal_force_chunk,
    actuators_chunk
);
model_scalar!(
    AdNested,
    adjust_nested,
    forces_nested,
    measurement_nested,
    normal_force_nested,
    actuators_nested
);
