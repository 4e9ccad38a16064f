//! Effects as written in a model JSON file or on the command line, and the catalog of
//! candidate effects `footfall diagnose` tries.

use super::kinds::{
    CopOffset, ForcePlateTimeOffset, GroundSlope, HeelPadCompliance, PassiveJointStiffness,
    TrunkMass,
};
use super::DynEffect;
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
    /// [`ForcePlateTimeOffset`].
    ForcePlateTimeOffset {
        /// Clock offset of the force plates (s).
        #[serde(default)]
        offset: f64,
        /// `offset` to identify it.
        #[serde(default)]
        free: Vec<String>,
    },
    /// [`CopOffset`].
    CopOffset {
        /// Offset of the measured centre of pressure (m).
        #[serde(default)]
        offset: f64,
        /// `offset` to identify it.
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
pub const EFFECT_KINDS: [&str; 6] = [
    "ground_slope",
    "trunk_mass",
    "passive_joint_stiffness",
    "force_plate_time_offset",
    "cop_offset",
    "heel_pad_compliance",
];

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
            EffectSpec::ForcePlateTimeOffset { .. } => "force-plate time offset".into(),
            EffectSpec::CopOffset { .. } => "CoP offset".into(),
            EffectSpec::HeelPadCompliance { .. } => "heel-pad compliance".into(),
        }
    }

    /// Names of the parameters that `free` may list, with each one's value and bounds.
    fn parameter_values(&self) -> Vec<(&'static str, f64, (f64, f64))> {
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
                        *stiffness,
                        PassiveJointStiffness::STIFFNESS_BOUNDS,
                    ),
                    ("rest_angle", *rest_angle, (-pi, pi)),
                ]
            }
            EffectSpec::GroundSlope { angle, .. } => vec![("angle", *angle, GroundSlope::BOUNDS)],
            EffectSpec::TrunkMass {
                added_mass,
                com_offset,
                ..
            } => {
                vec![
                    ("added_mass", *added_mass, TrunkMass::MASS_BOUNDS),
                    ("com_offset", *com_offset, TrunkMass::OFFSET_BOUNDS),
                ]
            }
            EffectSpec::ForcePlateTimeOffset { offset, .. } => {
                vec![("offset", *offset, ForcePlateTimeOffset::BOUNDS)]
            }
            EffectSpec::CopOffset { offset, .. } => vec![("offset", *offset, CopOffset::BOUNDS)],
            EffectSpec::HeelPadCompliance {
                stiffness, damping, ..
            } => {
                vec![
                    ("stiffness", *stiffness, HeelPadCompliance::STIFFNESS_BOUNDS),
                    ("damping", *damping, HeelPadCompliance::DAMPING_BOUNDS),
                ]
            }
        }
    }

    fn free(&self) -> &[String] {
        match self {
            EffectSpec::PassiveJointStiffness { free, .. }
            | EffectSpec::GroundSlope { free, .. }
            | EffectSpec::TrunkMass { free, .. }
            | EffectSpec::ForcePlateTimeOffset { free, .. }
            | EffectSpec::CopOffset { free, .. }
            | EffectSpec::HeelPadCompliance { free, .. } => free,
        }
    }

    fn free_mut(&mut self) -> &mut Vec<String> {
        match self {
            EffectSpec::PassiveJointStiffness { free, .. }
            | EffectSpec::GroundSlope { free, .. }
            | EffectSpec::TrunkMass { free, .. }
            | EffectSpec::ForcePlateTimeOffset { free, .. }
            | EffectSpec::CopOffset { free, .. }
            | EffectSpec::HeelPadCompliance { free, .. } => free,
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
        let mut spec: EffectSpec = serde_json::from_value(serde_json::Value::Object(obj))
            .map_err(|e| format!("effect '{text}': {e}"))?;
        if !free_given {
            spec.free_all();
        }
        spec.check()
            .map_err(|(f, r)| format!("effect '{text}': {f}: {r}"))?;
        Ok(spec)
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
        let params = self.parameter_values();
        for &(name, value, (lo, hi)) in &params {
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
            EffectSpec::ForcePlateTimeOffset { offset, .. } => {
                vec![Box::new(ForcePlateTimeOffset::new(
                    *offset,
                    self.is_free("offset"),
                ))]
            }
            EffectSpec::CopOffset { offset, .. } => {
                vec![Box::new(CopOffset::new(*offset, self.is_free("offset")))]
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
        })
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
            _ => self.kind() == other.kind(),
        }
    }
}

/// The candidate effects `footfall diagnose` tries, each at its null value (no effect)
/// with its identifiable parameters free: ground slope, trunk mass and COM offset, passive
/// stiffness of hip, knee and ankle (both legs, rest angle 0), force-plate time offset and
/// CoP offset.
pub fn catalog() -> Vec<EffectSpec> {
    let mut out = vec![
        EffectSpec::GroundSlope {
            angle: 0.0,
            free: vec![],
        },
        EffectSpec::TrunkMass {
            added_mass: 0.0,
            com_offset: 0.0,
            free: vec![],
        },
    ];
    for joint in ["hip", "knee", "ankle"] {
        out.push(EffectSpec::PassiveJointStiffness {
            joint: joint.into(),
            side: "both".into(),
            stiffness: 0.0,
            rest_angle: 0.0,
            free: vec![],
        });
    }
    out.push(EffectSpec::ForcePlateTimeOffset {
        offset: 0.0,
        free: vec![],
    });
    out.push(EffectSpec::CopOffset {
        offset: 0.0,
        free: vec![],
    });
    for e in &mut out {
        e.free_all();
    }
    out
}
