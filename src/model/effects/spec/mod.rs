//! Effects as written in a model JSON file or on the command line: what each kind's
//! parameters are, how they are checked and parsed, and how they build the model's effects.

use super::actuator_properties::{ActivationTimeConstants, MtgDampingScale, MtgStrengthScale};
use super::instruments::{BodyMassError, ForcePlateGain};
use super::kinds::{
    CopOffset, ForcePlateTimeOffset, GroundSlope, HeelPadCompliance, PassiveJointStiffness,
    TrunkMass,
};
use super::volumetric::VolumetricContact;
use crate::model::geometry::Shape;
use crate::model::volumetric::VolumetricLaw;
use serde::{Deserialize, Serialize};

mod build;
mod cli;

/// What an effect needs to know about the model it is built for.
#[derive(Debug, Clone, Copy)]
pub struct BuildContext<'a> {
    /// Generalised coordinate names, in order.
    pub coordinates: &'a [String],
    /// Body names, in order.
    pub bodies: &'a [String],
    /// Names of the foot's contact primitives (without the side prefix).
    pub primitives: &'a [String],
    /// Each primitive's volumetric law (`None`: rigid), parallel to `primitives`.
    pub laws: &'a [Option<VolumetricLaw>],
    /// Each primitive's shape, parallel to `primitives`.
    pub shapes: &'a [Shape],
    /// The foot file, for errors.
    pub foot: &'a str,
}

/// An effect as written in a model JSON file (`{"type": "ground_slope", "angle": 0.02}`).
/// Parameters not listed in `free` are fixed at their values; listed ones are identified
/// by the OCP within the effect's bounds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum EffectSpec {
    /// [`PassiveJointStiffness`] on one joint, on one leg or on both with one shared
    /// stiffness and rest angle.
    PassiveJointStiffness {
        /// `hip`, `knee` or `ankle`.
        joint: String,
        /// `both` (default), `right` or `left`.
        #[serde(default = "both")]
        side: String,
        /// Stiffness (N·m/rad, ≥ 0).
        #[serde(default)]
        stiffness: f64,
        /// Rest angle (rad).
        #[serde(default)]
        rest_angle: f64,
        /// Names of the parameters to free: `stiffness`, `rest_angle`.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`GroundSlope`].
    GroundSlope {
        /// Slope (rad, positive uphill).
        #[serde(default)]
        angle: f64,
        /// `angle` to identify it.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`TrunkMass`].
    TrunkMass {
        /// Mass added to the trunk (kg).
        #[serde(default)]
        added_mass: f64,
        /// Shift of the trunk's centre of mass along its x axis (m).
        #[serde(default)]
        com_offset: f64,
        /// Any of `added_mass`, `com_offset`.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`ForcePlateTimeOffset`]: one foot's plate or both.
    ForcePlateTimeOffset {
        /// `both` (default: one shared offset), `right` or `left` (that foot's plate).
        #[serde(default = "both")]
        side: String,
        /// Clock offset of the force plate(s) (s; positive: the plate reports late).
        #[serde(default)]
        offset: f64,
        /// `offset` to identify it.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`CopOffset`]: one foot's plate or both.
    CopOffset {
        /// `both` (default), `right` or `left`.
        #[serde(default = "both")]
        side: String,
        /// Offset of the measured centre of pressure (m; reported minus true).
        #[serde(default)]
        offset: f64,
        /// `offset` to identify it.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`ForcePlateGain`]: one foot's plate, both with one shared error, or each plate
    /// its own error in one effect (`each`: two parameters, read jointly).
    ForcePlateGain {
        /// `both` (default), `right`, `left`, or `each` (the right plate's and the left
        /// plate's gain, `force_plate_gain.right.error` and `.left.error`, both starting
        /// at `error` and freed by `error`).
        #[serde(default = "both")]
        side: String,
        /// Reported over true force, minus one (0.06: the plate reads 6 % high).
        #[serde(default)]
        error: f64,
        /// `error` to identify it.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`BodyMassError`].
    BodyMassError {
        /// The subject's mass over the model's, minus one.
        #[serde(default)]
        relative: f64,
        /// `relative` to identify it.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`MtgDampingScale`]: η × (1 + change).
    MtgDamping {
        /// Relative change of the damping factor η.
        #[serde(default)]
        change: f64,
        /// `change` to identify it.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`MtgStrengthScale`]: τ₀ × (1 + change).
    MtgStrength {
        /// Relative change of every MTG's maximum isometric torque.
        #[serde(default)]
        change: f64,
        /// `change` to identify it.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`ActivationTimeConstants`]: τ_A, τ_D × (1 + change).
    ActivationTimeConstants {
        /// Relative change of the activation and deactivation time constants.
        #[serde(default)]
        change: f64,
        /// `change` to identify it.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`HeelPadCompliance`].
    HeelPadCompliance {
        /// The foot's primitive the pad is under (default `heel`).
        #[serde(default = "heel")]
        primitive: String,
        /// Pad stiffness (N/mm; default 1000, nearly rigid: 0.7 mm under body weight).
        #[serde(default = "default_pad_stiffness")]
        stiffness: f64,
        /// Pad damping (N·s/mm; default 1).
        #[serde(default = "default_pad_damping")]
        damping: f64,
        /// Any of `stiffness`, `damping`.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`VolumetricContact`]: the law of every volumetric primitive of the foot.
    VolumetricContact {
        /// Area stiffness (N/mm², 1 N/mm² = 10⁶ N/m²; default: each primitive's own from
        /// the foot file).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        stiffness: Option<f64>,
        /// Damping (s/m; default: the foot file's).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        damping: Option<f64>,
        /// Dynamic friction coefficient (default: the foot file's; the static one keeps
        /// the file's margin above it).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mu_dynamic: Option<f64>,
        /// Any of `stiffness`, `damping`, `mu_dynamic`.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`FootGeometry`](super::FootGeometry): the shape of every primitive of the foot,
    /// starting from the foot file's.
    FootGeometry {
        /// Any of `centre` (x and y of every primitive), `size` (radii and semi-axes),
        /// `angle` (ellipses' orientation).
        #[serde(default)]
        free: Vec<String>,
    },
}

fn heel() -> String {
    "heel".into()
}

fn default_pad_stiffness() -> f64 {
    1000.0
}

fn default_pad_damping() -> f64 {
    1.0
}

fn both() -> String {
    "both".into()
}

/// The names that may appear on the command line: `--effect NAME[:key=value,…]`.
pub const EFFECT_KINDS: [&str; 13] = [
    "ground_slope",
    "trunk_mass",
    "passive_joint_stiffness",
    "force_plate_time_offset",
    "cop_offset",
    "heel_pad_compliance",
    "force_plate_gain",
    "body_mass_error",
    "mtg_damping",
    "mtg_strength",
    "activation_time_constants",
    "volumetric_contact",
    "foot_geometry",
];

/// A measurement effect's foot: `None` for `both`, `Some(0)` right, `Some(1)` left.
fn side_index(side: &str) -> Option<usize> {
    match side {
        "right" => Some(0),
        "left" => Some(1),
        _ => None,
    }
}

/// ` (right)`, ` (left)` or nothing for `both`.
fn side_suffix(side: &str) -> String {
    if side == "both" {
        String::new()
    } else {
        format!(" ({side})")
    }
}

impl EffectSpec {
    /// Kind name as in JSON.
    pub fn kind(&self) -> &'static str {
        match self {
            EffectSpec::PassiveJointStiffness { .. } => "passive_joint_stiffness",
            EffectSpec::GroundSlope { .. } => "ground_slope",
            EffectSpec::TrunkMass { .. } => "trunk_mass",
            EffectSpec::ForcePlateTimeOffset { .. } => "force_plate_time_offset",
            EffectSpec::CopOffset { .. } => "cop_offset",
            EffectSpec::HeelPadCompliance { .. } => "heel_pad_compliance",
            EffectSpec::ForcePlateGain { .. } => "force_plate_gain",
            EffectSpec::BodyMassError { .. } => "body_mass_error",
            EffectSpec::MtgDamping { .. } => "mtg_damping",
            EffectSpec::MtgStrength { .. } => "mtg_strength",
            EffectSpec::ActivationTimeConstants { .. } => "activation_time_constants",
            EffectSpec::VolumetricContact { .. } => "volumetric_contact",
            EffectSpec::FootGeometry { .. } => "foot_geometry",
        }
    }

    /// A short human label, e.g. `passive joint stiffness (knee)`.
    pub fn label(&self) -> String {
        match self {
            EffectSpec::PassiveJointStiffness { joint, side, .. } if side == "both" => {
                format!("passive {joint} stiffness")
            }
            EffectSpec::PassiveJointStiffness { joint, side, .. } => {
                format!("passive {joint} stiffness ({side})")
            }
            EffectSpec::GroundSlope { .. } => "ground slope".into(),
            EffectSpec::TrunkMass { .. } => "trunk mass and COM offset".into(),
            EffectSpec::ForcePlateTimeOffset { side, .. } => {
                format!("force-plate time offset{}", side_suffix(side))
            }
            EffectSpec::CopOffset { side, .. } => format!("CoP offset{}", side_suffix(side)),
            EffectSpec::HeelPadCompliance { .. } => "heel-pad compliance".into(),
            EffectSpec::ForcePlateGain { side, .. } if side == "each" => {
                "force-plate gain (each plate)".into()
            }
            EffectSpec::ForcePlateGain { side, .. } => {
                format!("force-plate gain{}", side_suffix(side))
            }
            EffectSpec::BodyMassError { .. } => "body-mass error".into(),
            EffectSpec::MtgDamping { .. } => "MTG damping (η)".into(),
            EffectSpec::MtgStrength { .. } => "MTG strength".into(),
            EffectSpec::ActivationTimeConstants { .. } => {
                "activation/deactivation time constants".into()
            }
            EffectSpec::VolumetricContact { .. } => "volumetric contact law".into(),
            EffectSpec::FootGeometry { .. } => "foot geometry".into(),
        }
    }

    /// Names of the parameters that `free` may list, with each one's value (`None`: taken
    /// from the model when built) and bounds.
    fn parameter_values(&self) -> Vec<(&'static str, Option<f64>, (f64, f64))> {
        let pi = std::f64::consts::PI;
        match self {
            EffectSpec::PassiveJointStiffness {
                stiffness,
                rest_angle,
                ..
            } => {
                vec![
                    (
                        "stiffness",
                        Some(*stiffness),
                        PassiveJointStiffness::STIFFNESS_BOUNDS,
                    ),
                    ("rest_angle", Some(*rest_angle), (-pi, pi)),
                ]
            }
            EffectSpec::GroundSlope { angle, .. } => {
                vec![("angle", Some(*angle), GroundSlope::BOUNDS)]
            }
            EffectSpec::TrunkMass {
                added_mass,
                com_offset,
                ..
            } => {
                vec![
                    ("added_mass", Some(*added_mass), TrunkMass::MASS_BOUNDS),
                    ("com_offset", Some(*com_offset), TrunkMass::OFFSET_BOUNDS),
                ]
            }
            EffectSpec::ForcePlateTimeOffset { offset, .. } => {
                vec![("offset", Some(*offset), ForcePlateTimeOffset::BOUNDS)]
            }
            EffectSpec::CopOffset { offset, .. } => {
                vec![("offset", Some(*offset), CopOffset::BOUNDS)]
            }
            EffectSpec::ForcePlateGain { error, .. } => {
                vec![("error", Some(*error), ForcePlateGain::BOUNDS)]
            }
            EffectSpec::BodyMassError { relative, .. } => {
                vec![("relative", Some(*relative), BodyMassError::BOUNDS)]
            }
            EffectSpec::MtgDamping { change, .. } => {
                vec![("change", Some(*change), MtgDampingScale::BOUNDS)]
            }
            EffectSpec::MtgStrength { change, .. } => {
                vec![("change", Some(*change), MtgStrengthScale::BOUNDS)]
            }
            EffectSpec::ActivationTimeConstants { change, .. } => {
                vec![("change", Some(*change), ActivationTimeConstants::BOUNDS)]
            }
            EffectSpec::HeelPadCompliance {
                stiffness, damping, ..
            } => {
                vec![
                    (
                        "stiffness",
                        Some(*stiffness),
                        HeelPadCompliance::STIFFNESS_BOUNDS,
                    ),
                    ("damping", Some(*damping), HeelPadCompliance::DAMPING_BOUNDS),
                ]
            }
            EffectSpec::VolumetricContact {
                stiffness,
                damping,
                mu_dynamic,
                ..
            } => vec![
                ("stiffness", *stiffness, VolumetricContact::STIFFNESS_BOUNDS),
                ("damping", *damping, VolumetricContact::DAMPING_BOUNDS),
                ("mu_dynamic", *mu_dynamic, VolumetricContact::MU_BOUNDS),
            ],
            // bounds relative to the foot file's shape (checked when built)
            EffectSpec::FootGeometry { .. } => vec![
                ("centre", None, (f64::NEG_INFINITY, f64::INFINITY)),
                ("size", None, (0.0, f64::INFINITY)),
                ("angle", None, (f64::NEG_INFINITY, f64::INFINITY)),
            ],
        }
    }

    fn free(&self) -> &[String] {
        match self {
            EffectSpec::PassiveJointStiffness { free, .. }
            | EffectSpec::GroundSlope { free, .. }
            | EffectSpec::TrunkMass { free, .. }
            | EffectSpec::ForcePlateTimeOffset { free, .. }
            | EffectSpec::CopOffset { free, .. }
            | EffectSpec::HeelPadCompliance { free, .. }
            | EffectSpec::ForcePlateGain { free, .. }
            | EffectSpec::BodyMassError { free, .. }
            | EffectSpec::MtgDamping { free, .. }
            | EffectSpec::MtgStrength { free, .. }
            | EffectSpec::ActivationTimeConstants { free, .. }
            | EffectSpec::VolumetricContact { free, .. }
            | EffectSpec::FootGeometry { free } => free,
        }
    }

    fn free_mut(&mut self) -> &mut Vec<String> {
        match self {
            EffectSpec::PassiveJointStiffness { free, .. }
            | EffectSpec::GroundSlope { free, .. }
            | EffectSpec::TrunkMass { free, .. }
            | EffectSpec::ForcePlateTimeOffset { free, .. }
            | EffectSpec::CopOffset { free, .. }
            | EffectSpec::HeelPadCompliance { free, .. }
            | EffectSpec::ForcePlateGain { free, .. }
            | EffectSpec::BodyMassError { free, .. }
            | EffectSpec::MtgDamping { free, .. }
            | EffectSpec::MtgStrength { free, .. }
            | EffectSpec::ActivationTimeConstants { free, .. }
            | EffectSpec::VolumetricContact { free, .. }
            | EffectSpec::FootGeometry { free } => free,
        }
    }

    fn is_free(&self, name: &str) -> bool {
        self.free().iter().any(|f| f == name)
    }

    /// Free every parameter except a passive spring's rest angle (a spring identified
    /// from its null value, stiffness 0, has no information about its rest angle).
    pub fn free_all(&mut self) {
        let names: Vec<String> = self
            .parameter_values()
            .iter()
            .map(|p| p.0)
            .filter(|n| {
                !(matches!(self, EffectSpec::PassiveJointStiffness { .. }) && *n == "rest_angle")
            })
            .map(String::from)
            .collect();
        *self.free_mut() = names;
    }

    /// The effect with every parameter fixed at its value.
    pub fn fixed(&self) -> Self {
        let mut e = self.clone();
        e.free_mut().clear();
        e
    }

    /// Check the entry without a model; the error names the offending field and what is
    /// wrong.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        if let EffectSpec::PassiveJointStiffness { joint, side, .. } = self {
            if !["hip", "knee", "ankle"].contains(&joint.as_str()) {
                return Err((
                    "joint",
                    format!("'{joint}' is not a joint of the model; use one of hip, knee, ankle"),
                ));
            }
            if !["both", "right", "left"].contains(&side.as_str()) {
                return Err(("side", format!("'{side}' is not one of both, right, left")));
            }
        }
        if let EffectSpec::ForcePlateGain { side, .. } = self {
            if !["both", "right", "left", "each"].contains(&side.as_str()) {
                return Err((
                    "side",
                    format!("'{side}' is not one of both, right, left (the foot whose force plate it is), each (both plates, each its own gain)"),
                ));
            }
        }
        if let EffectSpec::ForcePlateTimeOffset { side, .. } | EffectSpec::CopOffset { side, .. } =
            self
        {
            if !["both", "right", "left"].contains(&side.as_str()) {
                return Err((
                    "side",
                    format!("'{side}' is not one of both, right, left (the foot whose force plate it is)"),
                ));
            }
        }
        let params = self.parameter_values();
        for &(name, value, (lo, hi)) in &params {
            let Some(value) = value else { continue };
            if !(value.is_finite() && value >= lo && value <= hi) {
                return Err((
                    name,
                    format!("must be a finite number in [{lo}, {hi}], got {value}"),
                ));
            }
        }
        let free = self.free();
        for (k, f) in free.iter().enumerate() {
            if !params.iter().any(|p| p.0 == f) {
                let names: Vec<&str> = params.iter().map(|p| p.0).collect();
                return Err((
                    "free",
                    format!("entry {k} '{f}' is not one of {}", names.join(", ")),
                ));
            }
            if free[..k].contains(f) {
                return Err(("free", format!("'{f}' is listed twice")));
            }
        }
        Ok(())
    }

    /// Whether the effect is a property of the actuators (the MTGs' damping or strength,
    /// the activation time constants): it changes what the effort regularisation charges,
    /// so freeing it lowers a track's cost on data that do not ask for it.
    pub fn is_actuator_property(&self) -> bool {
        matches!(
            self,
            EffectSpec::MtgDamping { .. }
                | EffectSpec::MtgStrength { .. }
                | EffectSpec::ActivationTimeConstants { .. }
        )
    }

    /// Whether `other`, an instrument effect of this held one's kind (no free parameter)
    /// on another side, adds to it in one model: clock and CoP offsets add, gains
    /// multiply, and their parameters are named by side. So a correction held for both
    /// plates (a shared clock a diagnosis found) leaves one plate's further error a
    /// candidate.
    pub fn composes_with(&self, other: &EffectSpec) -> bool {
        let side = |e: &EffectSpec| match e {
            EffectSpec::ForcePlateTimeOffset { side, .. }
            | EffectSpec::CopOffset { side, .. }
            | EffectSpec::ForcePlateGain { side, .. } => Some(side.clone()),
            _ => None,
        };
        match (side(self), side(other)) {
            (Some(a), Some(b)) => self.kind() == other.kind() && a != b && self.free().is_empty(),
            _ => false,
        }
    }

    /// Whether `other` describes the same effect slot (same kind, and for passive
    /// stiffness an overlapping joint and side), so a model cannot hold both.
    pub fn overlaps(&self, other: &EffectSpec) -> bool {
        match (self, other) {
            (
                EffectSpec::PassiveJointStiffness {
                    joint: a, side: sa, ..
                },
                EffectSpec::PassiveJointStiffness {
                    joint: b, side: sb, ..
                },
            ) => a == b && (sa == sb || sa == "both" || sb == "both"),
            (
                EffectSpec::ForcePlateTimeOffset { side: sa, .. }
                | EffectSpec::CopOffset { side: sa, .. }
                | EffectSpec::ForcePlateGain { side: sa, .. },
                EffectSpec::ForcePlateTimeOffset { side: sb, .. }
                | EffectSpec::CopOffset { side: sb, .. }
                | EffectSpec::ForcePlateGain { side: sb, .. },
            ) => {
                // `each` is both plates' gains, each its own
                let whole = |s: &str| s == "both" || s == "each";
                self.kind() == other.kind() && (sa == sb || whole(sa) || whole(sb))
            }
            _ => self.kind() == other.kind(),
        }
    }
}
