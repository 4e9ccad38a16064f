//! Published muscle-torque-generator parameters: the Anderson et al. (2007) torque
//! coefficients (scaled to a subject) and the Millard et al. (2019) gymnast table.

use super::{ActiveTorqueAngle, Joint, MtgParams, MuscleSide, ANDERSON_GRAVITY, TV_HALF_CAP};
use serde::{Deserialize, Serialize};

/// Anderson et al. (2007) Table 3 coefficients of one exertion (joint, direction).
///
/// Model (Anderson et al. 2007; the form is also documented in RBDL
/// `TorqueMuscleFunctionFactory.cc`):
///
/// ```text
/// T/(m g h) = C1 · cos(C2 (θ − C3)) · [2C4C5 + ω(C5 − 3C4)] / [2C4C5 + ω(2C5 − 4C4)]      ω ≥ 0
/// T/(m g h) = C1 · cos(C2 (θ − C3)) · (1 − C6 ω) [2C4C5 − ω(C5 − 3C4)] / [2C4C5 − ω(2C5 − 4C4)]   ω < 0
/// ```
///
/// θ in rad (Anderson's anatomical convention), ω in rad/s (+ = concentric). C1 is the
/// peak isometric torque normalised by body weight × height; the concentric factor is the
/// rectangular hyperbola through (0, 1), (C4, 0.75) and (C5, 0.5).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Anderson2007Coefficients {
    /// Peak isometric torque / (body mass · g · height) [–].
    pub c1: f64,
    /// Angle scale of the cosine [1/rad].
    pub c2: f64,
    /// Angle of peak torque, Anderson convention [rad].
    pub c3: f64,
    /// Shortening velocity at 75 % of isometric torque [rad/s].
    pub c4: f64,
    /// Shortening velocity at 50 % of isometric torque [rad/s].
    pub c5: f64,
    /// Eccentric slope factor [s/rad].
    pub c6: f64,
}

impl Anderson2007Coefficients {
    /// Anderson's concentric torque–velocity factor at shortening velocity `w` [rad/s].
    pub fn concentric_factor(&self, w: f64) -> f64 {
        let (c4, c5) = (self.c4, self.c5);
        (2.0 * c4 * c5 + w * (c5 - 3.0 * c4)) / (2.0 * c4 * c5 + w * (2.0 * c5 - 4.0 * c4))
    }

    /// ω_max = |2 C4 C5 / (C5 − 3 C4)| [rad/s]: the root of the numerator of Anderson's
    /// concentric factor. For most exertions this is the shortening velocity at which the
    /// torque vanishes. For the young-male (and young-female) ankle plantar flexors
    /// C5 > 3 C4, the hyperbola never reaches zero for ω > 0 (it tends to
    /// (C5−3C4)/(2C5−4C4) ≈ 0.19) and the root lies at negative ω; like RBDL
    /// (`omegaMax = abs(2.0*c4*c5/(c5-3.0*c4))`) we use its magnitude.
    pub fn omega_max(&self) -> f64 {
        (2.0 * self.c4 * self.c5 / (self.c5 - 3.0 * self.c4)).abs()
    }

    /// f^V at ω_max/2 from Anderson's concentric factor, capped at [`TV_HALF_CAP`] as in
    /// RBDL.
    pub fn tv_at_half_omega_max(&self) -> f64 {
        self.concentric_factor(0.5 * self.omega_max())
            .min(TV_HALF_CAP)
    }

    /// Eccentric plateau level used by RBDL for Anderson's data:
    /// `tvMaxEcc = 1.1 + 0.2 · C6` (`createAnderson2007ActiveTorqueVelocityCurve`); Anderson's
    /// own eccentric branch is only valid near ω = 0 (it turns negative for fast
    /// lengthening).
    pub fn tv_max_eccentric(&self) -> f64 {
        1.1 + 0.2 * self.c6
    }

    /// Build MTG parameters for a subject of `mass` [kg] and `height` [m]:
    /// `τ_o = C1 · mass · g · height`, optimal angle `s_θ · C3` (model convention).
    pub fn to_mtg(&self, joint: Joint, side: MuscleSide, mass: f64, height: f64) -> MtgParams {
        MtgParams {
            joint,
            side,
            max_isometric_torque: self.c1 * mass * ANDERSON_GRAVITY * height,
            omega_max: self.omega_max(),
            optimal_angle: joint.anatomical_angle_sign() * self.c3,
            active_curve: ActiveTorqueAngle::Anderson2007Cosine {
                angle_scale: self.c2,
            },
            tv_at_half_omega_max: self.tv_at_half_omega_max(),
            tv_max_eccentric: self.tv_max_eccentric(),
        }
    }
}

const fn coeffs(c1: f64, c2: f64, c3: f64, c4: f64, c5: f64, c6: f64) -> Anderson2007Coefficients {
    Anderson2007Coefficients {
        c1,
        c2,
        c3,
        c4,
        c5,
        c6,
    }
}

/// Anderson, Madigan & Nussbaum (2007), J Biomech 40:3105–3113, Table 3, mean
/// coefficients, **young (18–25) males**. Transcribed from RBDL
/// `addons/muscle/Millard2016TorqueMuscle.cc` (`Anderson2007Table3Mean`, rows
/// joint/direction/gender=0/age=0), which states it "is taken from Table 3 of Anderson et
/// al." The paper itself could not be retrieved through the search tools.
/// "Flexor" of the ankle = dorsiflexion ("AnkleFlexion"), extensor = plantar flexion.
pub const ANDERSON2007_YOUNG_MALE: [(Joint, MuscleSide, Anderson2007Coefficients); 6] = [
    (
        Joint::Hip,
        MuscleSide::Extensor,
        coeffs(0.161, 0.958, 0.932, 1.578, 3.190, 0.242),
    ),
    (
        Joint::Hip,
        MuscleSide::Flexor,
        coeffs(0.113, 0.738, -0.214, 2.095, 4.267, 0.218),
    ),
    (
        Joint::Knee,
        MuscleSide::Extensor,
        coeffs(0.163, 1.258, 1.133, 1.517, 3.952, 0.095),
    ),
    (
        Joint::Knee,
        MuscleSide::Flexor,
        coeffs(0.087, 0.869, 0.522, 2.008, 5.233, 0.304),
    ),
    (
        Joint::Ankle,
        MuscleSide::Extensor,
        coeffs(0.095, 1.391, 0.408, 0.987, 3.558, 0.295),
    ),
    (
        Joint::Ankle,
        MuscleSide::Flexor,
        coeffs(0.033, 1.510, -0.187, 0.699, 1.940, 0.828),
    ),
];

/// As [`ANDERSON2007_YOUNG_MALE`], **young (18–25) females** (same source rows with
/// gender = 1, age = 0).
pub const ANDERSON2007_YOUNG_FEMALE: [(Joint, MuscleSide, Anderson2007Coefficients); 6] = [
    (
        Joint::Hip,
        MuscleSide::Extensor,
        coeffs(0.181, 0.697, 1.242, 1.567, 3.164, 0.164),
    ),
    (
        Joint::Hip,
        MuscleSide::Flexor,
        coeffs(0.127, 0.650, -0.350, 2.136, 4.349, 0.156),
    ),
    (
        Joint::Knee,
        MuscleSide::Extensor,
        coeffs(0.159, 1.187, 1.274, 1.393, 3.623, 0.173),
    ),
    (
        Joint::Knee,
        MuscleSide::Flexor,
        coeffs(0.080, 0.873, 0.635, 1.698, 4.412, 0.175),
    ),
    (
        Joint::Ankle,
        MuscleSide::Extensor,
        coeffs(0.104, 1.399, 0.424, 0.862, 3.109, 0.189),
    ),
    (
        Joint::Ankle,
        MuscleSide::Flexor,
        coeffs(0.027, 1.079, -0.302, 0.864, 2.399, 0.771),
    ),
];

/// One row of the Millard et al. (2019) gymnast MTG table (see [`MILLARD2019_GYMNAST`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GymnastMtgRow {
    /// Joint.
    pub joint: Joint,
    /// Flexor / extensor.
    pub side: MuscleSide,
    /// Maximum active isometric torque [N·m].
    pub max_isometric_torque: f64,
    /// Maximum shortening velocity [rad/s].
    pub omega_max: f64,
    /// Angle of peak active torque, Anderson/RBDL-figure convention [rad].
    pub peak_angle_anatomical: f64,
    /// Standard deviation of the Gaussian torque–angle curve [rad].
    pub std_dev: f64,
    /// f^V at a lengthening velocity of ω_max.
    pub tv_max_eccentric: f64,
    /// f^V at ω_max/2 (shortening).
    pub tv_at_half_omega_max: f64,
}

#[allow(clippy::too_many_arguments)]
const fn gym(
    joint: Joint,
    side: MuscleSide,
    max_isometric_torque: f64,
    omega_max: f64,
    peak_angle_anatomical: f64,
    std_dev: f64,
    tv_max_eccentric: f64,
    tv_at_half_omega_max: f64,
) -> GymnastMtgRow {
    GymnastMtgRow {
        joint,
        side,
        max_isometric_torque,
        omega_max,
        peak_angle_anatomical,
        std_dev,
        tv_max_eccentric,
        tv_at_half_omega_max,
    }
}

/// Whole-body "gymnast" MTGs of Millard, Emonds, Harant & Mombaur (2019), J Biomech
/// 89:11–20 (hip and knee from Jackson 2010, ankle from Anderson et al. 2007 scaled by a
/// Jackson-to-Anderson strength ratio), young elite male gymnast 69.6 kg, 1.732 m; not
/// scaled to the subject. Values: RBDL `Millard2016TorqueMuscle.cc::GymnastWholeBody`
/// columns (τ_iso [N·m], ω_max [rad/s], angle at peak [rad, Anderson convention], Gaussian
/// σ [rad], f^V at −ω_max, f^V at ω_max/2); τ_iso and ω_max agree with
/// `mjhmilla/MillardEmondsHarantMombaur2019FiguresTables/curveTables/mtgNamesParameters.csv`.
pub const MILLARD2019_GYMNAST: [GymnastMtgRow; 6] = [
    gym(
        Joint::Hip,
        MuscleSide::Extensor,
        175.746,
        9.02335,
        1.06465,
        1.05941,
        1.1,
        0.163849,
    ),
    gym(
        Joint::Hip,
        MuscleSide::Flexor,
        157.293,
        9.18043,
        0.733038,
        1.21999,
        1.11905,
        0.25,
    ),
    gym(
        Joint::Knee,
        MuscleSide::Extensor,
        285.619,
        19.2161,
        0.942478,
        0.509636,
        1.13292,
        0.115304,
    ),
    gym(
        Joint::Knee,
        MuscleSide::Flexor,
        98.7579,
        16.633,
        1.02974,
        1.11003,
        1.12,
        0.19746,
    ),
    gym(
        Joint::Ankle,
        MuscleSide::Extensor,
        127.561,
        11.7646,
        0.408,
        0.660752,
        1.159,
        0.410591,
    ),
    gym(
        Joint::Ankle,
        MuscleSide::Flexor,
        44.3106,
        17.2746,
        -0.187,
        0.60868,
        1.2656,
        0.112303,
    ),
];
