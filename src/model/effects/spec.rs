//! Effects as written in a model JSON file or on the command line: what each kind's
//! parameters are, how they are checked and parsed, and how they build the model's effects.

use super::actuator_properties::{ActivationTimeConstants, MtgDampingScale, MtgStrengthScale};
use super::geometry::FootGeometry;
use super::instruments::{BodyMassError, ForcePlateGain};
use super::kinds::{
    CopOffset, ForcePlateTimeOffset, GroundSlope, HeelPadCompliance, PassiveJointStiffness,
    TrunkMass,
};
use super::volumetric::{VolumetricContact, VolumetricStart};
use super::DynEffect;
use crate::model::geometry::Shape;
use crate::model::volumetric::VolumetricLaw;
use serde::{Deserialize, Serialize};

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
    /// [`FootGeometry`]: the shape of every primitive of the foot, starting from the foot
    /// file's.
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

    /// The command-line form of the effect, `NAME:key=value,…,free=a+b`, that
    /// [`parse_cli`](Self::parse_cli) reads back as this entry: what a diagnosis tells
    /// the user to add with one line. `None` for an entry with a value the command line
    /// cannot carry (a list or an object).
    pub fn cli_text(&self) -> Option<String> {
        let v = serde_json::to_value(self).ok()?;
        let obj = v.as_object()?;
        let mut parts = Vec::new();
        // the values first, what is freed last, as people write it
        let free = obj.get("free").map(|f| ("free", f));
        for (k, x) in obj
            .iter()
            .filter(|(k, _)| *k != "free")
            .map(|(k, x)| (k.as_str(), x))
            .chain(free)
        {
            let text = match (k, x) {
                ("type", _) | (_, serde_json::Value::Null) => continue,
                ("free", serde_json::Value::Array(names)) => names
                    .iter()
                    .map(|n| n.as_str().map(String::from))
                    .collect::<Option<Vec<_>>>()?
                    .join("+"),
                (_, serde_json::Value::Number(n)) => n.as_f64()?.to_string(),
                (_, serde_json::Value::String(t)) => t.clone(),
                _ => return None,
            };
            parts.push(format!("{k}={text}"));
        }
        Some(format!("{}:{}", self.kind(), parts.join(",")))
    }

    /// Parse a command-line effect `NAME[:key=value,…]`, e.g. `ground_slope`,
    /// `passive_joint_stiffness:joint=knee`, `ground_slope:angle=0.03,free=`. Without a
    /// `free` key every parameter is freed ([`free_all`](Self::free_all)); `free=a+b`
    /// frees the listed ones, `free=` none.
    pub fn parse_cli(text: &str) -> Result<Self, String> {
        let (name, rest) = text.split_once(':').unwrap_or((text, ""));
        if !EFFECT_KINDS.contains(&name) {
            return Err(format!(
                "'{name}' is not a known effect; use one of {}",
                EFFECT_KINDS.join(", ")
            ));
        }
        let mut obj = serde_json::Map::new();
        obj.insert("type".into(), name.into());
        let mut free_given = false;
        for kv in rest.split(',').filter(|s| !s.is_empty()) {
            let (k, v) = kv
                .split_once('=')
                .ok_or_else(|| format!("'{kv}' in '{text}' is not key=value"))?;
            if obj.contains_key(k) {
                return Err(format!(
                    "'{k}' is given twice in '{text}'; give each parameter once"
                ));
            }
            let value = if k == "free" {
                free_given = true;
                serde_json::Value::from(v.split('+').filter(|s| !s.is_empty()).collect::<Vec<_>>())
            } else if let Ok(x) = v.parse::<f64>() {
                serde_json::Value::from(x)
            } else {
                serde_json::Value::from(v)
            };
            obj.insert(k.into(), value);
        }
        let mut spec: EffectSpec = serde_json::from_value(serde_json::Value::Object(obj.clone()))
            .map_err(|e| match not_a_number(&obj, &e.to_string()) {
            Some(k) => format!(
                "effect '{text}': '{k}' must be a number (for example {k}=0.02), got '{}'",
                obj[k].as_str().unwrap_or_default()
            ),
            None => format!("effect '{text}': {e}"),
        })?;
        if !free_given {
            spec.free_all();
        }
        spec.check()
            .map_err(|(f, r)| format!("effect '{text}': {f}: {r}"))?;
        Ok(spec)
    }

    /// Parse several `--effect` texts, refusing two that add the same effect (two sides
    /// of a held measurement effect compose, as in a model file).
    pub fn parse_cli_all(texts: &[String]) -> Result<Vec<Self>, String> {
        let specs = texts
            .iter()
            .map(|t| Self::parse_cli(t))
            .collect::<Result<Vec<_>, _>>()?;
        for (j, b) in specs.iter().enumerate() {
            if let Some(i) = (0..j).find(|&i| specs[i].overlaps(b) && !specs[i].composes_with(b)) {
                return Err(format!(
                    "'{}' and '{}' both add the effect '{}'; give it once",
                    texts[i],
                    texts[j],
                    b.label()
                ));
            }
        }
        Ok(specs)
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

    /// Build the effect instances for a model.
    pub fn build(&self, ctx: &BuildContext<'_>) -> Result<Vec<Box<dyn DynEffect>>, String> {
        self.check()
            .map_err(|(field, reason)| format!("{field}: {reason}"))?;
        Ok(match self {
            EffectSpec::PassiveJointStiffness {
                joint,
                side,
                stiffness,
                rest_angle,
                ..
            } => {
                let (sides, name): (&[&str], String) = match side.as_str() {
                    "right" => (&["r"], format!("{joint}_r")),
                    "left" => (&["l"], format!("{joint}_l")),
                    _ => (&["r", "l"], joint.clone()),
                };
                let mut coords = Vec::new();
                for s in sides {
                    let c = format!("{joint}_{s}");
                    coords.push(
                        ctx.coordinates
                            .iter()
                            .position(|x| *x == c)
                            .ok_or_else(|| format!("joint: the model has no coordinate '{c}'"))?,
                    );
                }
                vec![Box::new(PassiveJointStiffness::new(
                    coords,
                    &name,
                    *stiffness,
                    *rest_angle,
                    self.is_free("stiffness"),
                    self.is_free("rest_angle"),
                ))]
            }
            EffectSpec::GroundSlope { angle, .. } => {
                vec![Box::new(GroundSlope::new(*angle, self.is_free("angle")))]
            }
            EffectSpec::TrunkMass {
                added_mass,
                com_offset,
                ..
            } => {
                let body = ctx
                    .bodies
                    .iter()
                    .position(|b| b == "hat")
                    .ok_or("the model has no trunk body 'hat'")?;
                vec![Box::new(TrunkMass::new(
                    body,
                    *added_mass,
                    *com_offset,
                    self.is_free("added_mass"),
                    self.is_free("com_offset"),
                ))]
            }
            EffectSpec::ForcePlateTimeOffset { side, offset, .. } => {
                vec![Box::new(ForcePlateTimeOffset::on(
                    side_index(side),
                    *offset,
                    self.is_free("offset"),
                ))]
            }
            EffectSpec::CopOffset { side, offset, .. } => {
                vec![Box::new(CopOffset::on(
                    side_index(side),
                    *offset,
                    self.is_free("offset"),
                ))]
            }
            EffectSpec::ForcePlateGain { side, error, .. } if side == "each" => [0, 1]
                .map(|s| {
                    Box::new(ForcePlateGain::on(Some(s), *error, self.is_free("error")))
                        as Box<dyn DynEffect>
                })
                .into(),
            EffectSpec::ForcePlateGain { side, error, .. } => {
                vec![Box::new(ForcePlateGain::on(
                    side_index(side),
                    *error,
                    self.is_free("error"),
                ))]
            }
            EffectSpec::BodyMassError { relative, .. } => {
                vec![Box::new(BodyMassError::new(
                    *relative,
                    self.is_free("relative"),
                ))]
            }
            EffectSpec::MtgDamping { change, .. } => {
                vec![Box::new(MtgDampingScale::new(
                    *change,
                    self.is_free("change"),
                ))]
            }
            EffectSpec::MtgStrength { change, .. } => {
                vec![Box::new(MtgStrengthScale::new(
                    *change,
                    self.is_free("change"),
                ))]
            }
            EffectSpec::ActivationTimeConstants { change, .. } => {
                vec![Box::new(ActivationTimeConstants::new(
                    *change,
                    self.is_free("change"),
                ))]
            }
            EffectSpec::HeelPadCompliance {
                primitive,
                stiffness,
                damping,
                ..
            } => {
                if !ctx.primitives.contains(primitive) {
                    return Err(format!("primitive: this foot has no primitive '{primitive}' (it has: {}); the pad goes under a heel circle", ctx.primitives.join(", ")));
                }
                vec![Box::new(HeelPadCompliance::new(
                    primitive,
                    *stiffness,
                    *damping,
                    self.is_free("stiffness"),
                    self.is_free("damping"),
                ))]
            }
            EffectSpec::VolumetricContact {
                stiffness,
                damping,
                mu_dynamic,
                ..
            } => {
                let starts: Vec<(String, VolumetricStart)> = ctx
                    .primitives
                    .iter()
                    .zip(ctx.laws)
                    .filter_map(|(name, law)| {
                        let law = law.as_ref()?;
                        Some((
                            name.clone(),
                            VolumetricStart {
                                stiffness: stiffness.map_or(law.stiffness, |k| {
                                    k * VolumetricContact::STIFFNESS_UNIT
                                }),
                                damping: damping.unwrap_or(law.damping),
                                mu_dynamic: mu_dynamic.unwrap_or(law.mu_dynamic),
                            },
                        ))
                    })
                    .collect();
                if starts.is_empty() {
                    return Err(format!(
                        "volumetric_contact: the foot {} has no volumetric primitive (its primitives {} are rigid), so there is no contact law to free; use a volumetric foot, e.g. --foot models/feet/volumetric_ellipse.json, or give a primitive \"contact\": {{\"type\": \"volumetric\", …}} in the foot file",
                        ctx.foot,
                        ctx.primitives.join(", ")
                    ));
                }
                // a value outside the bounds from the foot file (the effect's own values
                // are checked above)
                for (name, s) in &starts {
                    let k = s.stiffness / VolumetricContact::STIFFNESS_UNIT;
                    for (field, v, (lo, hi)) in [
                        ("stiffness", k, VolumetricContact::STIFFNESS_BOUNDS),
                        ("damping", s.damping, VolumetricContact::DAMPING_BOUNDS),
                        ("mu_dynamic", s.mu_dynamic, VolumetricContact::MU_BOUNDS),
                    ] {
                        if !(lo..=hi).contains(&v) {
                            return Err(format!("volumetric_contact: primitive '{name}' of the foot {} has {field} {v} (in the effect's units), outside the bounds [{lo}, {hi}] an identification may use; give a start value with {field}=…", ctx.foot));
                        }
                    }
                }
                vec![Box::new(VolumetricContact::new(
                    &starts,
                    [
                        self.is_free("stiffness"),
                        self.is_free("damping"),
                        self.is_free("mu_dynamic"),
                    ],
                ))]
            }
            EffectSpec::FootGeometry { .. } => {
                let shapes: Vec<(String, Shape)> = ctx
                    .primitives
                    .iter()
                    .cloned()
                    .zip(ctx.shapes.iter().cloned())
                    .collect();
                vec![Box::new(FootGeometry::new(
                    &shapes,
                    [
                        self.is_free("centre"),
                        self.is_free("size"),
                        self.is_free("angle"),
                    ],
                ))]
            }
        })
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

/// The key of an effect's text whose value is not a number where serde's error `message`
/// says a number was expected (`invalid type: string "abc", expected f64`).
fn not_a_number<'a>(
    obj: &'a serde_json::Map<String, serde_json::Value>,
    message: &str,
) -> Option<&'a str> {
    if !message.contains("expected f64") {
        return None;
    }
    obj.iter()
        .filter(|(k, _)| k.as_str() != "type")
        .find(|(_, v)| {
            v.as_str()
                .is_some_and(|v| message.contains(&format!("string \"{v}\"")))
        })
        .map(|(k, _)| k.as_str())
}
