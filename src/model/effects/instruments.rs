//! Instrument effects beyond the clock and CoP offsets of [`super::kinds`]: a force
//! plate's gain, and an error of the body mass the model was scaled to.

use super::kinds::{param, side_mask};
use super::{Effect, MeasurementAdjust, ModelAdjust, ParamSpec};
use crate::model::Scalar;

/// A force plate's gain is off: it reports `1 + error` times the true forces (a
/// calibration error of its load cells). The CoP, a ratio of moment and force, is
/// unchanged. On one foot's plate (`right`, `left`) or on both with one shared error.
///
/// A gain error on both plates and a body-mass error ([`BodyMassError`]) both scale the
/// measured forces against the kinematics; they differ in what the actuators must
/// supply (a heavier body needs more joint torque for the same motion, a miscalibrated
/// plate does not).
#[derive(Debug, Clone)]
pub struct ForcePlateGain {
    sides: [bool; 2],
    params: Vec<ParamSpec>,
}

impl ForcePlateGain {
    /// Bounds of the relative gain error (−30 … +30 %).
    pub const BOUNDS: (f64, f64) = (-0.3, 0.3);

    /// Gain error `error` (reported over true force, minus one) of foot `side`'s plate
    /// (0 right, 1 left; `None` both), parameter `force_plate_gain.[right.|left.]error`.
    pub fn on(side: Option<usize>, error: f64, free: bool) -> Self {
        let (sides, infix) = side_mask(side);
        Self {
            sides,
            params: vec![param(
                format!("force_plate_gain.{infix}error"),
                error,
                Self::BOUNDS,
                "1",
                free,
            )],
        }
    }
}

impl Effect for ForcePlateGain {
    fn kind(&self) -> &'static str {
        "force_plate_gain"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn adjust_measurement<S: Scalar>(&self, p: &[S], m: &mut MeasurementAdjust<S>) {
        for s in (0..2).filter(|&s| self.sides[s]) {
            m.force_gain[s] *= p[0] + 1.0;
        }
    }
    fn is_measurement(&self) -> bool {
        true
    }
}

/// The subject's body mass is `1 + relative` times the mass the model was scaled to (a
/// wrong scale reading or a subject's clothing and markers): every segment's mass and
/// moment of inertia scale by that factor, centres of mass and lengths stay.
///
/// This is a model effect, not a measurement one: a heavier body needs proportionally
/// larger ground forces *and* joint torques for the same motion (the equations of motion
/// are linear in the inertial parameters), while scaling the measured forces alone
/// ([`ForcePlateGain`] on both plates) leaves the torques as they were. Both explain
/// forces that are uniformly too high; only the torques, through the actuators' effort,
/// tell them apart.
#[derive(Debug, Clone)]
pub struct BodyMassError {
    params: Vec<ParamSpec>,
}

impl BodyMassError {
    /// Bounds of the relative error (−30 … +30 %).
    pub const BOUNDS: (f64, f64) = (-0.3, 0.3);

    /// Relative mass error `relative`, parameter `body_mass_error.relative`.
    pub fn new(relative: f64, free: bool) -> Self {
        Self {
            params: vec![param(
                "body_mass_error.relative".into(),
                relative,
                Self::BOUNDS,
                "1",
                free,
            )],
        }
    }
}

impl Effect for BodyMassError {
    fn kind(&self) -> &'static str {
        "body_mass_error"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn adjust_model<S: Scalar>(&self, p: &[S], m: &mut ModelAdjust<'_, S>) {
        let f = p[0] + 1.0;
        for b in m.inertia.iter_mut() {
            b.mass *= f;
            b.izz *= f;
        }
    }
}
