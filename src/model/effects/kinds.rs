//! The effect types of the catalog. Each is one small type implementing [`Effect`]; its
//! parameters are named `<kind>.<parameter>` (per joint for passive stiffness) and carry
//! the bounds an identification may use.

use super::{Effect, EffectState, MeasurementAdjust, ModelAdjust, ParamSpec};
use crate::model::Scalar;

pub(super) fn param(
    name: String,
    value: f64,
    (lower, upper): (f64, f64),
    unit: &str,
    free: bool,
) -> ParamSpec {
    ParamSpec {
        name,
        value,
        lower,
        upper,
        unit: unit.into(),
        free,
    }
}

/// A linear torsional spring at a joint: τ = −k (θ − θ₀), at one coordinate or with one
/// shared stiffness and rest angle at the same joint of both legs (a symmetric subject,
/// as the half-cycle problems with their left↔right periodicity assume).
///
/// Models the passive elastic torque of ligaments, joint capsule and stretched muscle
/// that the muscle-torque generators leave out (Millard & Mombaur 2019, §2 ignores it).
#[derive(Debug, Clone)]
pub struct PassiveJointStiffness {
    coordinates: Vec<usize>,
    params: Vec<ParamSpec>,
}

impl PassiveJointStiffness {
    /// Bounds of the stiffness (N·m/rad).
    pub const STIFFNESS_BOUNDS: (f64, f64) = (0.0, 500.0);

    /// Spring at coordinate indices `coordinates` (named `name`, e.g. `knee_r` or `knee`
    /// for both legs) with stiffness `stiffness` (N·m/rad) and rest angle `rest_angle` (rad).
    pub fn new(
        coordinates: Vec<usize>,
        coordinate_name: &str,
        stiffness: f64,
        rest_angle: f64,
        free_stiffness: bool,
        free_rest_angle: bool,
    ) -> Self {
        let base = format!("passive_joint_stiffness.{coordinate_name}");
        let pi = std::f64::consts::PI;
        Self {
            coordinates,
            params: vec![
                param(
                    format!("{base}.stiffness"),
                    stiffness,
                    Self::STIFFNESS_BOUNDS,
                    "N·m/rad",
                    free_stiffness,
                ),
                param(
                    format!("{base}.rest_angle"),
                    rest_angle,
                    (-pi, pi),
                    "rad",
                    free_rest_angle,
                ),
            ],
        }
    }
}

impl Effect for PassiveJointStiffness {
    fn kind(&self) -> &'static str {
        "passive_joint_stiffness"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn generalized_forces<S: Scalar>(&self, p: &[S], x: EffectState<'_, S>, tau: &mut [S]) {
        let (k, rest) = (p[0], p[1]);
        for &c in &self.coordinates {
            tau[c] -= k * (x.q[c] - rest);
        }
    }
}

/// The walkway is inclined by an angle α (rad, positive uphill in the walking direction)
/// to the horizontal. The model's frame is the walkway's (as the motion-capture and
/// force-plate frames are when aligned with it), so gravity is tilted by α:
/// g = |g| (−sin α, −cos α).
#[derive(Debug, Clone)]
pub struct GroundSlope {
    params: Vec<ParamSpec>,
}

impl GroundSlope {
    /// Bounds of the slope (rad; ±11.5°).
    pub const BOUNDS: (f64, f64) = (-0.2, 0.2);

    /// Slope `angle` (rad).
    pub fn new(angle: f64, free: bool) -> Self {
        Self {
            params: vec![param(
                "ground_slope.angle".into(),
                angle,
                Self::BOUNDS,
                "rad",
                free,
            )],
        }
    }
}

impl Effect for GroundSlope {
    fn kind(&self) -> &'static str {
        "ground_slope"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn adjust_model<S: Scalar>(&self, p: &[S], m: &mut ModelAdjust<'_, S>) {
        let g = (m.gravity[0] * m.gravity[0] + m.gravity[1] * m.gravity[1]).sqrt();
        let (s, c) = (p[0].sin(), p[0].cos());
        *m.gravity = [-g * s, -g * c];
    }
}

/// The trunk (head-arms-trunk body) is heavier or lighter than the anthropometric
/// estimate by `added_mass` (kg) and its centre of mass lies `com_offset` (m) further
/// along the body's x axis (anterior when upright). The moment of inertia about the
/// centre of mass scales with the mass.
#[derive(Debug, Clone)]
pub struct TrunkMass {
    body: usize,
    params: Vec<ParamSpec>,
}

impl TrunkMass {
    /// Bounds of the added mass (kg).
    pub const MASS_BOUNDS: (f64, f64) = (-20.0, 20.0);
    /// Bounds of the COM offset (m).
    pub const OFFSET_BOUNDS: (f64, f64) = (-0.15, 0.15);

    /// Trunk body index `body`; `added_mass` (kg), `com_offset` (m).
    pub fn new(
        body: usize,
        added_mass: f64,
        com_offset: f64,
        free_mass: bool,
        free_offset: bool,
    ) -> Self {
        Self {
            body,
            params: vec![
                param(
                    "trunk_mass.added_mass".into(),
                    added_mass,
                    Self::MASS_BOUNDS,
                    "kg",
                    free_mass,
                ),
                param(
                    "trunk_mass.com_offset".into(),
                    com_offset,
                    Self::OFFSET_BOUNDS,
                    "m",
                    free_offset,
                ),
            ],
        }
    }
}

impl Effect for TrunkMass {
    fn kind(&self) -> &'static str {
        "trunk_mass"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn adjust_model<S: Scalar>(&self, p: &[S], m: &mut ModelAdjust<'_, S>) {
        let b = &mut m.inertia[self.body];
        let scale = (b.mass + p[0]) / b.mass;
        b.mass += p[0];
        b.izz *= scale;
        b.com[0] += p[1];
    }
}

/// A force plate's clock is offset from the motion capture's by `offset` (s): the
/// model's ground forces at time t are compared with the measured forces at t + offset.
/// On one foot's plate (`right`, `left`; each foot's stance is on its own plate) or on
/// both with one shared offset. The contact events taken from that plate's force
/// threshold move with it (see `problems::track`).
#[derive(Debug, Clone)]
pub struct ForcePlateTimeOffset {
    sides: [bool; 2],
    params: Vec<ParamSpec>,
}

/// `[right, left]` from a foot index (`None`: both), and the parameter name's infix.
pub(super) fn side_mask(side: Option<usize>) -> ([bool; 2], &'static str) {
    match side {
        Some(0) => ([true, false], "right."),
        Some(_) => ([false, true], "left."),
        None => ([true, true], ""),
    }
}

impl ForcePlateTimeOffset {
    /// Bounds of the offset (s): an instrument's error plus the model's own bias. At the
    /// identification cost the rigid ellipse reads the untouched real trial's right clock
    /// at +25 ms, so a +25 ms edit put the reading at the old ±50 ms bound.
    pub const BOUNDS: (f64, f64) = (-0.1, 0.1);

    /// Clock offset `offset` (s) of both plates.
    pub fn new(offset: f64, free: bool) -> Self {
        Self::on(None, offset, free)
    }

    /// Clock offset `offset` (s) of foot `side`'s plate (0 right, 1 left; `None` both),
    /// parameter `force_plate_time_offset.[right.|left.]offset`.
    pub fn on(side: Option<usize>, offset: f64, free: bool) -> Self {
        let (sides, infix) = side_mask(side);
        Self {
            sides,
            params: vec![param(
                format!("force_plate_time_offset.{infix}offset"),
                offset,
                Self::BOUNDS,
                "s",
                free,
            )],
        }
    }
}

impl Effect for ForcePlateTimeOffset {
    fn kind(&self) -> &'static str {
        "force_plate_time_offset"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn adjust_measurement<S: Scalar>(&self, p: &[S], m: &mut MeasurementAdjust<S>) {
        for s in (0..2).filter(|&s| self.sides[s]) {
            m.force_time_offset[s] += p[0];
        }
    }
    fn is_measurement(&self) -> bool {
        true
    }
    fn shifts_force_clock(&self) -> bool {
        true
    }
}

/// A force plate reports the centre of pressure `offset` (m) further along the walkway
/// than it is (a calibration error of the plate origin): one foot's plate or both.
#[derive(Debug, Clone)]
pub struct CopOffset {
    sides: [bool; 2],
    params: Vec<ParamSpec>,
}

impl CopOffset {
    /// Bounds of the offset (m).
    pub const BOUNDS: (f64, f64) = (-0.1, 0.1);

    /// CoP offset `offset` (m) of both plates.
    pub fn new(offset: f64, free: bool) -> Self {
        Self::on(None, offset, free)
    }

    /// CoP offset `offset` (m) of foot `side`'s plate (0 right, 1 left; `None` both),
    /// parameter `cop_offset.[right.|left.]offset`.
    pub fn on(side: Option<usize>, offset: f64, free: bool) -> Self {
        let (sides, infix) = side_mask(side);
        Self {
            sides,
            params: vec![param(
                format!("cop_offset.{infix}offset"),
                offset,
                Self::BOUNDS,
                "m",
                free,
            )],
        }
    }
}

impl Effect for CopOffset {
    fn kind(&self) -> &'static str {
        "cop_offset"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn adjust_measurement<S: Scalar>(&self, p: &[S], m: &mut MeasurementAdjust<S>) {
        for s in (0..2).filter(|&s| self.sides[s]) {
            m.cop_offset[s] += p[0];
        }
    }
    fn is_measurement(&self) -> bool {
        true
    }
}

/// A compliant heel pad: the named contact primitive of each foot (the heel circle) no
/// longer holds the ground rigidly along the normal but through a linear spring and
/// damper in parallel (Kelvin–Voigt), F = k·d + c·ḋ, with d the depth of the rigid circle
/// below the ground — the pad's compression, the pad itself massless — while its rolling
/// (tangential) constraint stays rigid.
///
/// The fat pad under the calcaneus compresses by several millimetres under body weight
/// and dissipates part of the heel-strike energy; a rigid heel circle leaves both out, so
/// its normal force rises too fast at heel strike and cannot show the impact peak's
/// shape. The rigid heel is the limit k → ∞; there is no finite null value, so `diagnose`
/// cannot score this effect from a rigid run (see `footfall track --effect`).
#[derive(Debug, Clone)]
pub struct HeelPadCompliance {
    primitive: String,
    params: Vec<ParamSpec>,
}

impl HeelPadCompliance {
    /// Bounds of the stiffness (N/mm).
    pub const STIFFNESS_BOUNDS: (f64, f64) = (10.0, 5000.0);
    /// Bounds of the damping (N·s/mm).
    pub const DAMPING_BOUNDS: (f64, f64) = (0.0, 20.0);

    /// Pad under primitive `primitive` of both feet with stiffness `stiffness` (N/mm) and
    /// damping `damping` (N·s/mm).
    pub fn new(
        primitive: &str,
        stiffness: f64,
        damping: f64,
        free_stiffness: bool,
        free_damping: bool,
    ) -> Self {
        Self {
            primitive: primitive.to_string(),
            params: vec![
                param(
                    "heel_pad_compliance.stiffness".into(),
                    stiffness,
                    Self::STIFFNESS_BOUNDS,
                    "N/mm",
                    free_stiffness,
                ),
                param(
                    "heel_pad_compliance.damping".into(),
                    damping,
                    Self::DAMPING_BOUNDS,
                    "N·s/mm",
                    free_damping,
                ),
            ],
        }
    }
}

impl Effect for HeelPadCompliance {
    fn kind(&self) -> &'static str {
        "heel_pad_compliance"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn compliant_primitive(&self) -> Option<&str> {
        Some(&self.primitive)
    }
    fn normal_force<S: Scalar>(&self, p: &[S], depth: S, rate: S) -> S {
        // N/mm and N·s/mm to SI
        (p[0] * depth + p[1] * rate) * 1000.0
    }
}
