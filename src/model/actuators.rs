//! Muscle-torque generators (MTGs), activation dynamics and joint damping
//! (Millard & Mombaur 2019, "A Quick Turn of Foot", §2, eq. 9–12).
//!
//! # Model
//!
//! Each leg joint (hip, knee, ankle; both legs share the parameters) is driven by one
//! flexor and one extensor MTG (Millard & Mombaur 2019, eq. 9):
//!
//! ```text
//! τ^M = s · τ_o · a · f^A(θ) · f^V(ω)          s = ±1, see MuscleSide::torque_sign
//! ```
//!
//! with first-order activation dynamics in the C2 form of Millard & Mombaur 2019, eq. 10
//!
//! ```text
//! ȧ = (e − a) / (½ (τ_A + τ_D)),   τ_A = 15 ms, τ_D = 50 ms  (Thelen 2003, via Millard & Mombaur 2019)
//! ```
//!
//! and the net joint torque (Millard & Mombaur 2019, eq. 11–12)
//!
//! ```text
//! τ_i = τ^MF + τ^ME − β ω_i,   β = η (τ_o^MF + τ_o^ME) / (ω_max^MF + ω_max^ME),  η = 2.0
//! ```
//!
//! The passive parallel element is ignored, as Millard & Mombaur (2019) do.
//!
//! # Sign conventions (this crate)
//!
//! Joint angles are counter-clockwise positive seen from the subject's right, zero in the
//! neutral standing pose: hip `+` = flexion, knee `+` = extension (knee flexion is
//! negative), ankle `+` = dorsiflexion.
//!
//! Anderson et al. (2007) — and RBDL's `Millard2016TorqueMuscle`, whose reference figures
//! use Anderson's anatomical convention — measure hip flexion `+`, knee **flexion** `+`,
//! ankle dorsiflexion `+`, all zero in the anatomical neutral pose (thigh in line with
//! the trunk, knee straight, foot perpendicular to the shank). Hence
//!
//! ```text
//! θ_Anderson = s_θ · θ_model,   s_θ = +1 (hip), −1 (knee), +1 (ankle),   offset = 0
//! ```
//!
//! (evidence: RBDL `Millard2016TorqueMuscle.h` "Coordinate Mapping"; Millard, Sreenivasa &
//! Mombaur 2017 code `wholebodylifter2d_Model.cc::setupTorqueMuscles`, which maps a model
//! whose hip/ankle angles have the opposite sense and whose knee flexion is positive with
//! angle signs −1/+1/−1 and zero offsets).
//!
//! A flexor produces torque in the direction of flexion (hip flexion `+`, knee flexion
//! `−`, ankle dorsiflexion `+`); an extensor the opposite. "Ankle flexor" means
//! dorsiflexor (Anderson's "ankle flexion" = dorsiflexion, "ankle extension" = plantar
//! flexion). The **shortening (concentric) velocity** of an MTG is the joint angular
//! velocity projected on its torque direction, `ω_s = s · ω`; `f^V` is evaluated at
//! `ω_s / ω_max`, so the MTG's mechanical power `τ^M ω = τ_o a f^A f^V ω_s` is positive
//! when it shortens.
//!
//! # Smoothness
//!
//! All functions of `S: Scalar` are C∞ (no `abs`, `max`, or value branches). The
//! published curves have kinks; they are replaced by smooth approximations, each marked
//! `SMOOTHING:` below:
//! * Anderson's `cos(C2(θ−C3))` becomes negative away from the optimum → smooth positive
//!   part with width [`ACTIVE_ANGLE_EPS`], and a saturating angle map so the cosine cannot
//!   become positive again a period later.
//! * The torque–velocity curve has a slope discontinuity at ω = 0 in Anderson et al. and
//!   Hill/Katz → blended over a width set by [`TV_BLEND_REL`]; the concentric and
//!   eccentric branches are constructed with equal slopes at ω = 0 so the blend only
//!   smooths curvature.
//! * The Hill hyperbola becomes negative (the muscle would push) beyond ω_max → smooth
//!   positive part with width [`TV_FLOOR_EPS`].

mod error;
mod published;

pub use error::ActuatorError;
pub use published::{
    Anderson2007Coefficients, GymnastMtgRow, ANDERSON2007_YOUNG_FEMALE, ANDERSON2007_YOUNG_MALE,
    MILLARD2019_GYMNAST,
};

use serde::{Deserialize, Serialize};

use crate::model::scalar::Scalar;

/// Gravitational acceleration used to de-normalise Anderson et al.'s torques
/// (torque / (body mass · g · height)); 9.81 m/s² as in RBDL `Millard2016TorqueMuscle.cc`
/// (`const double gravity = 9.81; // Needed for the strength scaling used by Anderson`).
pub const ANDERSON_GRAVITY: f64 = 9.81;

/// The subject of Millard & Mombaur (2019, §3.1; data of Millard et al. 2017): 35-year-old
/// male, 81.7 kg.
pub const SEED_SUBJECT_MASS: f64 = 81.7;
/// Height of the subject of Millard & Mombaur (2019, §3.1): 1.72 m.
pub const SEED_SUBJECT_HEIGHT: f64 = 1.72;

/// Damping scale factor η of Millard & Mombaur 2019, eq. 12 ("We use a value of 2.0 for η").
///
/// Note: with any published MTG set found (Anderson 2007 scaled to the subject of Millard & Mombaur (2019):
/// hip 49.1, knee 14.8, ankle 12.2 N·m·s/rad; Millard 2019 gymnast: 36.6, 21.4, 11.8)
/// η = 2.0 does **not** give Millard & Mombaur's stated 2.7–7.3 N·m·s/rad; η = 0.4
/// (= 2 × [`MILLARD2017_CODE_ETA`]) with the gymnast set gives 2.37–7.32. See
/// `docs/parameters.md` §7.
pub const SEED_ETA: f64 = 2.0;

/// Normalised joint damping used in the published code of Millard, Sreenivasa & Mombaur
/// (2017) (`setupJointDamping`: `normDamping = 0.2`, same formula as Millard & Mombaur 2019, eq. 12; that
/// model also doubles the strength of the right-side MTGs because one planar limb stands
/// for two). Kept for comparison only; see `docs/parameters.md`.
pub const MILLARD2017_CODE_ETA: f64 = 0.2;

/// Activation time constant τ_A = 15 ms (Millard & Mombaur 2019, eq. 10, citing Thelen 2003).
pub const TAU_ACTIVATION: f64 = 0.015;
/// Deactivation time constant τ_D = 50 ms (Millard & Mombaur 2019, eq. 10, citing Thelen 2003).
pub const TAU_DEACTIVATION: f64 = 0.050;

/// SMOOTHING: width of the smooth positive part applied to Anderson's cosine
/// torque–angle curve: `f = ½(c + √(c² + ε²))`, normalised to peak 1. With ε = 0.05 the
/// curve is 0.025 at Anderson's zero crossing and < 0.0013 once the cosine is below −0.5;
/// RBDL's C2 Bézier version of the same curve likewise reaches 0 only at 1.05× Anderson's
/// half-width (`createAnderson2007ActiveTorqueAngleCurve`).
pub const ACTIVE_ANGLE_EPS: f64 = 0.05;

/// SMOOTHING: blend width between the concentric and eccentric branches of f^V at ω = 0,
/// relative to the branches' own curvature scales: δ = `TV_BLEND_REL` · min(k, b, 1) in
/// units of ω/ω_max (k: Hill curvature, b: eccentric hyperbola constant; see
/// [`torque_velocity`]). Because both branches have the same slope at ω = 0 the blend only
/// interpolates the curvature; the value at ω = 0 moves by ≈ s δ²/4·|1/k − 1/b| ≤ 0.1 %
/// before the exact renormalisation to 1.
pub const TV_BLEND_REL: f64 = 0.2;

/// SMOOTHING: width of the smooth positive part that keeps f^V ≥ 0 (a muscle cannot push)
/// beyond the maximum shortening velocity; f^V(ω_max) ≈ TV_FLOOR_EPS/2 instead of 0.
pub const TV_FLOOR_EPS: f64 = 0.02;

/// Cap on the torque–velocity value at half the maximum shortening velocity applied by
/// RBDL (`createAnderson2007ActiveTorqueVelocityCurve`: `tvMid = min(tvMid, 0.45)`);
/// Anderson's hip curves are almost linear (0.48–0.49) which a Hill hyperbola through
/// (0,1) and (ω_max,0) can only reach with an extremely flat curvature.
pub const TV_HALF_CAP: f64 = 0.45;

/// A leg joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Joint {
    /// Hip (pelvis–thigh).
    Hip,
    /// Knee (thigh–shank).
    Knee,
    /// Ankle (shank–foot).
    Ankle,
}

impl Joint {
    /// All leg joints, proximal to distal.
    pub const ALL: [Joint; 3] = [Joint::Hip, Joint::Knee, Joint::Ankle];

    /// `s_θ` in `θ_Anderson = s_θ · θ_model`: +1 hip (flexion +), −1 knee (Anderson's
    /// knee flexion is +, ours is −), +1 ankle (dorsiflexion + in both). Equal to the sign
    /// of the flexion (dorsiflexion) direction in model coordinates.
    pub fn anatomical_angle_sign(self) -> f64 {
        match self {
            Joint::Hip => 1.0,
            Joint::Knee => -1.0,
            Joint::Ankle => 1.0,
        }
    }

    /// snake_case name.
    pub fn name(self) -> &'static str {
        match self {
            Joint::Hip => "hip",
            Joint::Knee => "knee",
            Joint::Ankle => "ankle",
        }
    }
}

/// Which muscle group of a joint an MTG lumps.
///
/// Torque direction in model coordinates ([`MuscleSide::torque_sign`]):
///
/// | joint | flexor                 | extensor                  |
/// |-------|------------------------|---------------------------|
/// | hip   | + (hip flexion)        | − (hip extension)         |
/// | knee  | − (knee flexion)       | + (knee extension)        |
/// | ankle | + (dorsiflexion)       | − (plantar flexion)       |
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MuscleSide {
    /// Hip flexors, knee flexors, ankle dorsiflexors.
    Flexor,
    /// Hip extensors, knee extensors, ankle plantar flexors.
    Extensor,
}

impl MuscleSide {
    /// Sign of the torque this MTG applies to `joint` in model coordinates (table above).
    pub fn torque_sign(self, joint: Joint) -> f64 {
        match self {
            MuscleSide::Flexor => joint.anatomical_angle_sign(),
            MuscleSide::Extensor => -joint.anatomical_angle_sign(),
        }
    }

    /// snake_case name.
    pub fn name(self) -> &'static str {
        match self {
            MuscleSide::Flexor => "flexor",
            MuscleSide::Extensor => "extensor",
        }
    }
}

/// Shape of the normalised active torque–angle curve f^A (peak 1 at
/// [`MtgParams::optimal_angle`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum ActiveTorqueAngle {
    /// Anderson et al. (2007): `cos(C2 (θ_A − C3))`; `angle_scale` = C2 [1/rad]. The
    /// curve nominally reaches zero at `optimal_angle ± π/(2 C2)`.
    /// SMOOTHING: smooth positive part (see [`ACTIVE_ANGLE_EPS`]).
    Anderson2007Cosine {
        /// C2 [1/rad].
        angle_scale: f64,
    },
    /// Gaussian `exp(−(θ − θ_opt)² / (2 σ²))`, `std_dev` = σ [rad], as used for the
    /// whole-body gymnast MTGs of Millard et al. (2019) / RBDL
    /// (`createGaussianShapedActiveTorqueAngleCurve`). Already smooth and positive.
    Gaussian {
        /// σ [rad].
        std_dev: f64,
    },
}

/// Parameters of one muscle-torque generator.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MtgParams {
    /// Joint the MTG spans.
    pub joint: Joint,
    /// Flexor or extensor group.
    pub side: MuscleSide,
    /// Maximum active isometric torque τ_o^M [N·m] (positive magnitude).
    pub max_isometric_torque: f64,
    /// Maximum shortening angular velocity ω_max [rad/s] (positive magnitude): f^V ≈ 0
    /// when the joint moves at ω_max in this MTG's torque direction.
    pub omega_max: f64,
    /// Joint angle of peak active torque, model convention [rad].
    pub optimal_angle: f64,
    /// Active torque–angle curve shape.
    pub active_curve: ActiveTorqueAngle,
    /// f^V at half the maximum shortening velocity (sets the Hill curvature); in (0, 0.5).
    pub tv_at_half_omega_max: f64,
    /// f^V at a lengthening velocity of ω_max (eccentric plateau level); in (1, 2).
    pub tv_max_eccentric: f64,
}

impl MtgParams {
    /// Torque direction in model coordinates (±1); see [`MuscleSide::torque_sign`].
    pub fn torque_sign(&self) -> f64 {
        self.side.torque_sign(self.joint)
    }

    /// Shortening (concentric, > 0) velocity of this MTG for joint velocity `omega`.
    pub fn shortening_velocity<S: Scalar>(&self, omega: S) -> S {
        omega * self.torque_sign()
    }

    /// Check the parameter ranges the curves need.
    pub fn validate(&self) -> Result<(), ActuatorError> {
        let (joint, side) = (self.joint, self.side);
        let finite_pos = |value: f64, parameter: &'static str| -> Result<(), ActuatorError> {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ActuatorError::NotPositive {
                    joint,
                    side,
                    parameter,
                    value,
                })
            }
        };
        finite_pos(self.max_isometric_torque, "max_isometric_torque")?;
        finite_pos(self.omega_max, "omega_max")?;
        if !self.optimal_angle.is_finite() {
            return Err(ActuatorError::OptimalAngle { joint, side });
        }
        match self.active_curve {
            ActiveTorqueAngle::Anderson2007Cosine { angle_scale } => {
                finite_pos(angle_scale, "angle_scale (C2)")?
            }
            ActiveTorqueAngle::Gaussian { std_dev } => finite_pos(std_dev, "std_dev")?,
        }
        for (parameter, value, low, high) in [
            ("tv_at_half_omega_max", self.tv_at_half_omega_max, 0.0, 0.5),
            ("tv_max_eccentric", self.tv_max_eccentric, 1.0, 2.0),
        ] {
            if !(value.is_finite() && value > low && value < high) {
                return Err(ActuatorError::OutOfRange {
                    joint,
                    side,
                    parameter,
                    value,
                    low,
                    high,
                });
            }
        }
        Ok(())
    }
}

/// Smooth positive part `½(x + √(x² + ε²))` (C∞; → max(x, 0) as ε → 0).
#[inline]
fn smooth_pos<S: Scalar>(x: S, eps: f64) -> S {
    (x + (x * x + eps * eps).sqrt()) * 0.5
}

#[inline]
fn smooth_pos_f64(x: f64, eps: f64) -> f64 {
    0.5 * (x + (x * x + eps * eps).sqrt())
}

/// Active torque–angle multiplier f^A(θ) (dimensionless, peak exactly 1 at
/// `p.optimal_angle`, ≥ 0). `theta` is the joint angle in model convention [rad].
pub fn active_torque_angle<S: Scalar>(p: &MtgParams, theta: S) -> S {
    let d = theta - p.optimal_angle;
    match p.active_curve {
        ActiveTorqueAngle::Anderson2007Cosine { angle_scale } => {
            // f^A is even in (θ − θ_opt), so the sign map θ_A = s_θ θ only moves the peak
            // to s_θ·C3 (done in `to_mtg`).
            let u = d * angle_scale;
            // SMOOTHING: saturating angle map σ(u) = u / (1 + (u/π)^8)^(1/8): identity to
            // 8e-4 rad for |u| ≤ π/2, monotone, |σ| < π, so cos σ stays ≤ 0 beyond the
            // zero crossing instead of rising again one period later.
            let r = u * (1.0 / std::f64::consts::PI);
            let sigma = u * (r.powi(8) + 1.0).powf(-1.0 / 8.0);
            smooth_pos(sigma.cos(), ACTIVE_ANGLE_EPS)
                * (1.0 / smooth_pos_f64(1.0, ACTIVE_ANGLE_EPS))
        }
        ActiveTorqueAngle::Gaussian { std_dev } => (d * d * (-0.5 / (std_dev * std_dev))).exp(),
    }
}

/// Internal constants of the torque–velocity curve of one MTG.
struct TvShape {
    /// Hill curvature k: concentric branch (1 − x)·k/(k + x).
    k: f64,
    /// Eccentric increment f_ecc − 1.
    de: f64,
    /// Eccentric hyperbola constant b: 1 + de·(1 + b)·z/(b + z).
    b: f64,
    /// Blend width δ (units of ω/ω_max).
    delta: f64,
    /// Value of the un-normalised blend at ω = 0.
    f0: f64,
}

impl TvShape {
    fn new(p: &MtgParams) -> Self {
        let tv = p.tv_at_half_omega_max;
        // Hill hyperbola through (0,1), (½, tv), (1,0): k = ½ tv / (½ − tv).
        let k = 0.5 * tv / (0.5 - tv);
        let slope = 1.0 + 1.0 / k; // |df/dx| at x = 0⁺
        let de = p.tv_max_eccentric - 1.0;
        // Eccentric hyperbola with the same slope at 0 (C1 junction like RBDL's curve)
        // and value f_ecc at x = −1: slope = de (1+b)/b  ⇒  b = de / (slope − de).
        let b = de / (slope - de);
        let delta = TV_BLEND_REL * k.min(b).min(1.0);
        let h = 0.5 * delta; // ½(x + √(x²+δ²)) at x = 0
        let f0 = (1.0 - h) * k / (k + h) + de * (1.0 + b) * h / (b + h);
        TvShape {
            k,
            de,
            b,
            delta,
            f0,
        }
    }
}

/// Torque–angular-velocity multiplier f^V (dimensionless). `omega` is the **joint**
/// angular velocity in model convention [rad/s]; the curve is evaluated at the MTG's
/// normalised shortening velocity x = s·ω/ω_max:
/// * f^V(0) = 1 exactly;
/// * concentric (x > 0): Hill hyperbola (1 − x)k/(k + x) through f(½) =
///   `tv_at_half_omega_max`, ≈ 0 at x = 1 (≈ [`TV_FLOOR_EPS`]/2), never negative;
/// * eccentric (x < 0): hyperbola 1 + (f_ecc − 1)(1 + b)z/(b + z), z = −x, reaching
///   `tv_max_eccentric` at x = −1 and bounded by 1 + (f_ecc − 1)(1 + b) as x → −∞; its
///   slope at 0 equals the concentric slope (as in RBDL's curve).
///
/// SMOOTHING: the branches are joined by evaluating them at y = ½(x + √(x²+δ²)) ≥ 0 and
/// z = ½(−x + √(x²+δ²)) ≥ 0 (δ from [`TV_BLEND_REL`]; y, z ≥ 0 keeps both hyperbolas away
/// from their poles); the sum is floored by a smooth positive part ([`TV_FLOOR_EPS`]) and
/// normalised to exactly 1 at x = 0.
pub fn torque_velocity<S: Scalar>(p: &MtgParams, omega: S) -> S {
    let sh = TvShape::new(p);
    let x = p.shortening_velocity(omega) * (1.0 / p.omega_max);
    let root = (x * x + sh.delta * sh.delta).sqrt();
    let y = (root + x) * 0.5; // ≈ max(x, 0)
    let z = (root - x) * 0.5; // ≈ max(−x, 0)
    let conc = (-y + 1.0) * sh.k / (y + sh.k);
    let ecc = z * (sh.de * (1.0 + sh.b)) / (z + sh.b);
    let f = conc + ecc;
    smooth_pos(f, TV_FLOOR_EPS) * (1.0 / smooth_pos_f64(sh.f0, TV_FLOOR_EPS))
}

/// Signed torque of one MTG (Millard & Mombaur 2019, eq. 9): `s · τ_o · a · f^A(θ) · f^V(ω)` [N·m].
pub fn mtg_torque<S: Scalar>(p: &MtgParams, a: S, theta: S, omega: S) -> S {
    a * active_torque_angle(p, theta)
        * torque_velocity(p, omega)
        * (p.torque_sign() * p.max_isometric_torque)
}

/// Joint damping coefficient β of Millard & Mombaur 2019, eq. 12 [N·m·s/rad]:
/// `η (τ_o^F + τ_o^E) / (ω_max^F + ω_max^E)`.
pub fn damping_coefficient(flexor: &MtgParams, extensor: &MtgParams, eta: f64) -> f64 {
    eta * (flexor.max_isometric_torque + extensor.max_isometric_torque)
        / (flexor.omega_max + extensor.omega_max)
}

/// First-order activation dynamics in the C2 form of Millard & Mombaur 2019, eq. 10.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ActivationDynamics {
    /// τ_A [s] (seed: 15 ms).
    pub tau_activation: f64,
    /// τ_D [s] (seed: 50 ms).
    pub tau_deactivation: f64,
}

impl Default for ActivationDynamics {
    fn default() -> Self {
        ActivationDynamics {
            tau_activation: TAU_ACTIVATION,
            tau_deactivation: TAU_DEACTIVATION,
        }
    }
}

impl ActivationDynamics {
    /// Effective time constant ½(τ_A + τ_D) [s] (32.5 ms with the values of Millard & Mombaur (2019)).
    pub fn time_constant(&self) -> f64 {
        0.5 * (self.tau_activation + self.tau_deactivation)
    }

    /// ȧ = (e − a) / (½(τ_A + τ_D)) (Millard & Mombaur 2019, eq. 10).
    pub fn rate<S: Scalar>(&self, e: S, a: S) -> S {
        (e - a) * (1.0 / self.time_constant())
    }

    /// Positive, finite time constants.
    pub fn validate(&self) -> Result<(), ActuatorError> {
        for (value, parameter) in [
            (self.tau_activation, "tau_activation"),
            (self.tau_deactivation, "tau_deactivation"),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ActuatorError::TimeConstant { parameter, value });
            }
        }
        Ok(())
    }
}

/// The six MTGs of one leg (shared by both legs), the damping factor η and the
/// activation dynamics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointActuatorSet {
    /// Six MTGs: (hip, knee, ankle) × (flexor, extensor), any order.
    pub mtgs: Vec<MtgParams>,
    /// Damping factor η of Millard & Mombaur 2019, eq. 12.
    pub eta: f64,
    /// Activation dynamics shared by all MTGs.
    pub activation: ActivationDynamics,
}

impl JointActuatorSet {
    /// Anderson et al. (2007) young-male MTGs scaled (C1·m·g·h) to the subject of Millard & Mombaur (2019)
    /// (81.7 kg, 1.72 m), η = 2.0, τ_A = 15 ms, τ_D = 50 ms.
    pub fn anderson2007_young_male() -> Self {
        Self::anderson2007_young_male_for(SEED_SUBJECT_MASS, SEED_SUBJECT_HEIGHT)
    }

    /// Anderson et al. (2007) young-male MTGs for a subject of `mass` [kg], `height` [m].
    pub fn anderson2007_young_male_for(mass: f64, height: f64) -> Self {
        Self::from_anderson(&ANDERSON2007_YOUNG_MALE, mass, height)
    }

    /// Anderson et al. (2007) young-female MTGs for a subject of `mass` [kg], `height` [m].
    pub fn anderson2007_young_female_for(mass: f64, height: f64) -> Self {
        Self::from_anderson(&ANDERSON2007_YOUNG_FEMALE, mass, height)
    }

    fn from_anderson(
        table: &[(Joint, MuscleSide, Anderson2007Coefficients)],
        mass: f64,
        height: f64,
    ) -> Self {
        JointActuatorSet {
            mtgs: table
                .iter()
                .map(|(j, s, c)| c.to_mtg(*j, *s, mass, height))
                .collect(),
            eta: SEED_ETA,
            activation: ActivationDynamics::default(),
        }
    }

    /// Millard et al. (2019) gymnast MTGs (Jackson 2010 hip/knee, scaled Anderson ankle;
    /// 69.6 kg, 1.732 m subject, unscaled), η = 2.0, the activation constants of Millard & Mombaur (2019). Angles
    /// converted with the same sign map as Anderson's.
    pub fn millard2019_gymnast() -> Self {
        JointActuatorSet {
            mtgs: MILLARD2019_GYMNAST
                .iter()
                .map(|r| MtgParams {
                    joint: r.joint,
                    side: r.side,
                    max_isometric_torque: r.max_isometric_torque,
                    omega_max: r.omega_max,
                    optimal_angle: r.joint.anatomical_angle_sign() * r.peak_angle_anatomical,
                    active_curve: ActiveTorqueAngle::Gaussian { std_dev: r.std_dev },
                    tv_at_half_omega_max: r.tv_at_half_omega_max,
                    tv_max_eccentric: r.tv_max_eccentric,
                })
                .collect(),
            eta: SEED_ETA,
            activation: ActivationDynamics::default(),
        }
    }

    /// Strength scaling: every τ_o multiplied by `factor` (ω_max and curve shapes
    /// unchanged), so the damping β of eq. 12 scales by `factor` too. Typical factors:
    /// body-mass ratio m/m_ref for mass-normalised data, or (m·h)/(m_ref·h_ref) to move
    /// Anderson-based MTGs to another subject (their τ_o ∝ m·g·h).
    pub fn scaled(&self, factor: f64) -> Self {
        let mut out = self.clone();
        for m in &mut out.mtgs {
            m.max_isometric_torque *= factor;
        }
        out
    }

    /// Six valid MTGs, each (joint, side) exactly once; η ≥ 0 finite; positive time
    /// constants.
    pub fn validate(&self) -> Result<(), ActuatorError> {
        if self.mtgs.len() != 6 {
            return Err(ActuatorError::Count {
                found: self.mtgs.len(),
            });
        }
        for j in Joint::ALL {
            for s in [MuscleSide::Flexor, MuscleSide::Extensor] {
                let n = self
                    .mtgs
                    .iter()
                    .filter(|m| m.joint == j && m.side == s)
                    .count();
                if n != 1 {
                    return Err(ActuatorError::MtgCount {
                        joint: j,
                        side: s,
                        found: n,
                    });
                }
            }
        }
        for m in &self.mtgs {
            m.validate()?;
        }
        if !(self.eta.is_finite() && self.eta >= 0.0) {
            return Err(ActuatorError::Eta { value: self.eta });
        }
        self.activation.validate()
    }

    /// The MTG of `joint`/`side`, if present.
    pub fn mtg(&self, joint: Joint, side: MuscleSide) -> Option<&MtgParams> {
        self.mtgs
            .iter()
            .find(|m| m.joint == joint && m.side == side)
    }

    fn pair(&self, joint: Joint) -> (&MtgParams, &MtgParams) {
        let f = self
            .mtg(joint, MuscleSide::Flexor)
            .unwrap_or_else(|| panic!("no {} flexor MTG (call validate())", joint.name()));
        let e = self
            .mtg(joint, MuscleSide::Extensor)
            .unwrap_or_else(|| panic!("no {} extensor MTG (call validate())", joint.name()));
        (f, e)
    }

    /// Damping coefficient β of `joint` (Millard & Mombaur 2019, eq. 12) [N·m·s/rad].
    pub fn damping(&self, joint: Joint) -> f64 {
        let (f, e) = self.pair(joint);
        damping_coefficient(f, e, self.eta)
    }

    /// Net torque at one joint (eq. 11): flexor + extensor − β ω, given the two
    /// activations; `theta`, `omega` in model convention. Panics if the set lacks an MTG
    /// of `joint` (see [`validate`](Self::validate)).
    pub fn joint_torque<S: Scalar>(
        &self,
        joint: Joint,
        a_flexor: S,
        a_extensor: S,
        theta: S,
        omega: S,
    ) -> S {
        let (f, e) = self.pair(joint);
        mtg_torque(f, a_flexor, theta, omega) + mtg_torque(e, a_extensor, theta, omega)
            - omega * damping_coefficient(f, e, self.eta)
    }

    /// [`joint_torque`](Self::joint_torque) with every τ₀ scaled by `strength` and η by
    /// `damping` (the actuator effects' factors; β ∝ η τ₀ scales by both):
    /// `strength (τᶠ + τᵉ − damping β ω)`.
    #[allow(clippy::too_many_arguments)]
    pub fn joint_torque_scaled<S: Scalar>(
        &self,
        joint: Joint,
        a_flexor: S,
        a_extensor: S,
        theta: S,
        omega: S,
        strength: S,
        damping: S,
    ) -> S {
        let (f, e) = self.pair(joint);
        (mtg_torque(f, a_flexor, theta, omega) + mtg_torque(e, a_extensor, theta, omega)
            - omega * damping * damping_coefficient(f, e, self.eta))
            * strength
    }
}
