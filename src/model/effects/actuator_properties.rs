//! Actuator properties as effects: the muscle-torque generators' damping, strength and
//! activation time constants, each as a relative change of the model's own value (zero:
//! the model as it is), so that one catalog entry fits any MTG set.

use super::kinds::param;
use super::{ActuatorAdjust, Effect, ParamSpec};
use crate::model::Scalar;

/// The passive joint damping of Millard & Mombaur 2019, eq. 12, β = η (τ₀ᶠ + τ₀ᵉ)/(ω_maxᶠ + ω_maxᵉ), with
/// η scaled by `1 + change`. Millard & Mombaur (2019) state η = 2.0 but their damping figures need
/// η ≈ 0.4 (`docs/parameters.md` §7; `models/opensim_subject01_seed_damping.json`):
/// change = −0.8 from η = 2.0.
#[derive(Debug, Clone)]
pub struct MtgDampingScale {
    params: Vec<ParamSpec>,
}

impl MtgDampingScale {
    /// Bounds of the relative change (η between 2 % and 4× the model's).
    pub const BOUNDS: (f64, f64) = (-0.98, 3.0);

    /// Relative change `change` of η, parameter `mtg_damping.change`.
    pub fn new(change: f64, free: bool) -> Self {
        Self {
            params: vec![param(
                "mtg_damping.change".into(),
                change,
                Self::BOUNDS,
                "1",
                free,
            )],
        }
    }
}

impl Effect for MtgDampingScale {
    fn kind(&self) -> &'static str {
        "mtg_damping"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn adjust_actuators<S: Scalar>(&self, p: &[S], a: &mut ActuatorAdjust<S>) {
        a.damping *= p[0] + 1.0;
    }
    fn is_actuator(&self) -> bool {
        true
    }
}

/// Every MTG's maximum isometric torque τ₀ scaled by `1 + change` (the subject stronger
/// or weaker than the anthropometric scaling of the published MTGs); the damping β of
/// Millard & Mombaur 2019, eq. 12, proportional to τ₀, scales with it, as in
/// [`JointActuatorSet::scaled`](crate::model::actuators::JointActuatorSet::scaled).
#[derive(Debug, Clone)]
pub struct MtgStrengthScale {
    params: Vec<ParamSpec>,
}

impl MtgStrengthScale {
    /// Bounds of the relative change (τ₀ between 30 % and 3× the model's).
    pub const BOUNDS: (f64, f64) = (-0.7, 2.0);

    /// Relative change `change` of τ₀, parameter `mtg_strength.change`.
    pub fn new(change: f64, free: bool) -> Self {
        Self {
            params: vec![param(
                "mtg_strength.change".into(),
                change,
                Self::BOUNDS,
                "1",
                free,
            )],
        }
    }
}

impl Effect for MtgStrengthScale {
    fn kind(&self) -> &'static str {
        "mtg_strength"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn adjust_actuators<S: Scalar>(&self, p: &[S], a: &mut ActuatorAdjust<S>) {
        a.strength *= p[0] + 1.0;
    }
    fn is_actuator(&self) -> bool {
        true
    }
}

/// The activation and deactivation time constants τ_A, τ_D (Millard & Mombaur 2019, eq. 10) both scaled by
/// `1 + change`. Millard & Mombaur's C2 activation dynamics ȧ = (e − a)/(½(τ_A + τ_D)) depend on
/// their mean only, so one factor is all that tracking data can identify; a separate
/// τ_A and τ_D would make the information matrix singular.
#[derive(Debug, Clone)]
pub struct ActivationTimeConstants {
    params: Vec<ParamSpec>,
}

impl ActivationTimeConstants {
    /// Bounds of the relative change (time constants between 20 % and 5× the model's).
    pub const BOUNDS: (f64, f64) = (-0.8, 4.0);

    /// Relative change `change` of τ_A and τ_D, parameter
    /// `activation_time_constants.change`.
    pub fn new(change: f64, free: bool) -> Self {
        Self {
            params: vec![param(
                "activation_time_constants.change".into(),
                change,
                Self::BOUNDS,
                "1",
                free,
            )],
        }
    }
}

impl Effect for ActivationTimeConstants {
    fn kind(&self) -> &'static str {
        "activation_time_constants"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn adjust_actuators<S: Scalar>(&self, p: &[S], a: &mut ActuatorAdjust<S>) {
        a.time *= p[0] + 1.0;
    }
    fn is_actuator(&self) -> bool {
        true
    }
    fn scales_activation_time(&self) -> bool {
        // only a free change makes ȧ's excitation coefficient depend on θ; a fixed one
        // is a constant like the model's own time constants
        self.params[0].free
    }
}
