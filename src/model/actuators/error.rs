//! Why a set of muscle-torque generators is refused.

use super::{Joint, MuscleSide};

/// Why a muscle-torque-generator set is refused ([`JointActuatorSet::validate`],
/// [`MtgParams::validate`], [`ActivationDynamics::validate`]).
///
/// [`JointActuatorSet::validate`]: super::JointActuatorSet::validate
/// [`MtgParams::validate`]: super::MtgParams::validate
/// [`ActivationDynamics::validate`]: super::ActivationDynamics::validate
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ActuatorError {
    /// The set does not hold six MTGs (hip, knee, ankle × flexor, extensor).
    #[error("expected 6 MTGs, got {found}")]
    Count {
        /// Number of MTGs in the set.
        found: usize,
    },
    /// A joint's flexor or extensor MTG is missing or given more than once.
    #[error("expected exactly one {} {} MTG, found {found}", joint.name(), side.name())]
    MtgCount {
        /// The joint.
        joint: Joint,
        /// Flexor or extensor.
        side: MuscleSide,
        /// How many the set has.
        found: usize,
    },
    /// A parameter of one MTG that must be finite and positive is not.
    #[error("{} {}: {parameter} must be finite and > 0, got {value}", joint.name(), side.name())]
    NotPositive {
        /// The MTG's joint.
        joint: Joint,
        /// The MTG's side (flexor or extensor).
        side: MuscleSide,
        /// The parameter (`max_isometric_torque`, `omega_max`, the curve's width).
        parameter: &'static str,
        /// Its value (in the parameter's unit: N·m, rad/s, 1/rad or rad).
        value: f64,
    },
    /// One MTG's optimal angle is NaN or infinite.
    #[error("{} {}: optimal_angle must be finite", joint.name(), side.name())]
    OptimalAngle {
        /// The MTG's joint.
        joint: Joint,
        /// The MTG's side (flexor or extensor).
        side: MuscleSide,
    },
    /// A dimensionless torque–velocity parameter of one MTG lies outside its open range.
    #[error("{} {}: {parameter} must lie in ({low}, {high}), got {value}", joint.name(), side.name())]
    OutOfRange {
        /// The MTG's joint.
        joint: Joint,
        /// The MTG's side (flexor or extensor).
        side: MuscleSide,
        /// The parameter (`tv_at_half_omega_max`, `tv_max_eccentric`).
        parameter: &'static str,
        /// Its value (dimensionless).
        value: f64,
        /// Lower end of the open range.
        low: f64,
        /// Upper end of the open range.
        high: f64,
    },
    /// The damping factor η is negative or not finite.
    #[error("eta must be finite and >= 0, got {value}")]
    Eta {
        /// η (dimensionless).
        value: f64,
    },
    /// An activation time constant is not finite and positive.
    #[error("{parameter} must be finite and > 0, got {value}")]
    TimeConstant {
        /// `tau_activation` or `tau_deactivation`.
        parameter: &'static str,
        /// Its value (s).
        value: f64,
    },
}
