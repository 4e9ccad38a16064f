//! JSON specifications of models and feet, with validation on load.
//!
//! A model file (`models/*.json`) names the body parameters (a preset or explicit
//! segments), the actuators, the contact settings and optional effects. A foot file
//! (`models/feet/*.json`) lists contact primitives in the ankle (foot) frame; the same
//! foot is mirrored onto both legs (planar model: left and right feet are identical).

use super::effects::EffectSpec;
use super::error::ModelError;
use super::geometry::Shape;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Standard gravity (m/s²).
pub const STANDARD_GRAVITY: f64 = 9.80665;

fn default_gravity() -> f64 {
    STANDARD_GRAVITY
}
fn one() -> f64 {
    1.0
}

/// A gait model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSpec {
    /// Model name.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Magnitude of gravity (m/s², default 9.80665).
    #[serde(default = "default_gravity")]
    pub gravity: f64,
    /// Body-segment parameters.
    pub body: BodySpec,
    /// How the joints are driven.
    pub actuators: ActuatorSpec,
    /// Ground and constraint stabilisation.
    #[serde(default)]
    pub contact: ContactSettings,
    /// Optional effects, one entry each.
    #[serde(default)]
    pub effects: Vec<EffectSpec>,
}

/// Where the body-segment parameters come from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "preset", rename_all = "snake_case", deny_unknown_fields)]
pub enum BodySpec {
    /// Zatsiorsky–de Leva regressions scaled to body mass and height (de Leva 1996).
    DeLeva {
        /// Body mass (kg).
        mass: f64,
        /// Stature (m).
        height: f64,
        /// `male` or `female`.
        sex: super::anthropometry::Sex,
    },
    /// The derived 9-DoF segments of an OpenSim model summary JSON (as shipped in
    /// `data/opensim_subject01/`); the path is relative to the model file.
    OpensimModel {
        /// Path of the model summary JSON.
        file: PathBuf,
        /// Frozen lumbar angle for the rigid HAT: `trial_mean` (default) or `zero`.
        #[serde(default)]
        lumbar: LumbarChoice,
    },
    /// Segments given explicitly.
    Explicit {
        /// The segments.
        segments: Segments,
    },
}

/// Which frozen lumbar angle the rigid HAT of an OpenSim model uses.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LumbarChoice {
    /// The trial's mean lumbar extension (HAT COM over the hips).
    #[default]
    TrialMean,
    /// Lumbar extension 0 (the model's neutral).
    Zero,
}

/// Inertial parameters of one segment in its own frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentSpec {
    /// Mass (kg, > 0).
    pub mass: f64,
    /// Centre of mass in the segment frame (m).
    pub com: [f64; 2],
    /// Moment of inertia about the centre of mass (kg·m², > 0).
    pub izz: f64,
}

/// The seven segments of the planar body and its joint locations.
///
/// Frames: the HAT (pelvis) frame has its origin at the pelvis reference point; the
/// thigh frame at the hip, the shank frame at the knee, the foot (ankle) frame at the
/// ankle. All frames coincide in orientation with their parent at zero joint angle;
/// x forward, y up in the neutral standing pose.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Segments {
    /// Head, arms and trunk with the pelvis, in the pelvis frame.
    pub hat: SegmentSpec,
    /// Thigh, in the thigh frame.
    pub thigh: SegmentSpec,
    /// Shank, in the shank frame.
    pub shank: SegmentSpec,
    /// Foot, in the ankle frame.
    pub foot: SegmentSpec,
    /// Hip joint centre in the pelvis frame (m).
    pub hip_in_pelvis: [f64; 2],
    /// Knee joint centre in the thigh frame (m).
    pub knee_in_thigh: [f64; 2],
    /// Ankle joint centre in the shank frame (m).
    pub ankle_in_shank: [f64; 2],
}

/// Ground plane and Baumgarte stabilisation.
///
/// Normal rows: $G_n\ddot q + \dot G_n\dot q + 2\alpha G_n\dot q + \beta^2\phi = 0$;
/// tangential (rolling) rows: $G_t\ddot q + \dot G_t\dot q + \gamma G_t\dot q = 0$.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ContactSettings {
    /// Height of the (horizontal) ground plane (m, default 0).
    pub ground_height: f64,
    /// Velocity gain α of the normal rows (1/s, default 20).
    pub baumgarte_alpha: f64,
    /// Position gain β of the normal rows (1/s, default 20).
    pub baumgarte_beta: f64,
    /// Velocity gain γ of the tangential rows (1/s, default 20).
    pub baumgarte_gamma: f64,
}

impl Default for ContactSettings {
    fn default() -> Self {
        Self { ground_height: 0.0, baumgarte_alpha: 20.0, baumgarte_beta: 20.0, baumgarte_gamma: 20.0 }
    }
}

/// How the six leg joints are driven.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ActuatorSpec {
    /// A flexor and an extensor muscle-torque generator per joint (seed eq. 9–12) with
    /// activation dynamics; controls are the 12 excitations in [0, 1].
    MuscleTorqueGenerators {
        /// Multiplies every maximum isometric torque (default 1).
        #[serde(default = "one")]
        strength_scale: f64,
        /// Passive damping scale η of seed eq. 12 (default 2.0).
        #[serde(default = "default_eta")]
        eta: f64,
        /// Activation time constant (s, default 0.015).
        #[serde(default = "default_tau_a")]
        tau_activation: f64,
        /// Deactivation time constant (s, default 0.050).
        #[serde(default = "default_tau_d")]
        tau_deactivation: f64,
        /// Body mass the Anderson et al. (2007) torques are scaled with (kg); default: the
        /// body's total segment mass.
        #[serde(default)]
        subject_mass: Option<f64>,
        /// Stature the torques are scaled with (m); default: the de Leva preset's height,
        /// else estimated from hip→ankle length with de Leva's (1996) male proportions.
        #[serde(default)]
        subject_height: Option<f64>,
    },
    /// Plain joint torques (N·m) as controls, no activation states.
    JointTorques {
        /// Bound on each torque (N·m, default 500), used by optimal control problems.
        #[serde(default = "default_max_torque")]
        max_torque: f64,
    },
}

fn default_eta() -> f64 {
    2.0
}
fn default_tau_a() -> f64 {
    0.015
}
fn default_tau_d() -> f64 {
    0.050
}
fn default_max_torque() -> f64 {
    500.0
}

/// A foot file: named contact primitives in the ankle frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FootSpec {
    /// Foot name.
    pub name: String,
    /// Free text (e.g. where the parameters come from).
    #[serde(default)]
    pub description: String,
    /// Contact primitives; names must be unique.
    pub primitives: Vec<PrimitiveSpec>,
}

/// One named primitive of a foot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrimitiveSpec {
    /// Name, used by constraint sets as `r.NAME` / `l.NAME`.
    pub name: String,
    /// Geometry.
    pub shape: Shape,
}

/// Read and parse a JSON file, mapping errors to [`ModelError`] with line and column.
pub fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T, ModelError> {
    let text = std::fs::read_to_string(path).map_err(|source| ModelError::Io { path: path.to_path_buf(), source })?;
    parse_json(&text, path)
}

/// Parse JSON text that came from `path`.
///
/// The error names the dotted path of the offending field (`body.segments.thigh.mass`,
/// `primitives[0].shape`), found from serde's line and column.
pub fn parse_json<T: DeserializeOwned>(text: &str, path: &Path) -> Result<T, ModelError> {
    serde_json::from_str(text).map_err(|e| {
        let what = e.to_string();
        let what = match what.rfind(" at line ") {
            Some(k) if e.line() > 0 => what[..k].to_string(),
            _ => what,
        };
        let mut field = if e.line() > 0 { json_path_at(text, e.line(), e.column()) } else { String::new() };
        // serde names the unknown or missing field itself; the position is its parent object.
        for prefix in ["unknown field `", "missing field `"] {
            if let Some(name) = what.strip_prefix(prefix).and_then(|r| r.split('`').next()) {
                field = if field.is_empty() { name.to_string() } else { format!("{field}.{name}") };
            }
        }
        let message = match e.classify() {
            serde_json::error::Category::Syntax | serde_json::error::Category::Eof => {
                if field.is_empty() {
                    format!("invalid JSON: {what}")
                } else {
                    format!("invalid JSON: {what} (inside `{field}`)")
                }
            }
            _ if field.is_empty() => what,
            _ => format!("field `{field}`: {what}"),
        };
        ModelError::Json { path: path.to_path_buf(), message, line: e.line(), column: e.column() }
    })
}

/// Dotted path of the JSON value being read just before `line`:`column` (1-based, as
/// serde_json reports them; the character at the position itself is excluded). Object keys
/// become `.key`, array elements `[i]`; inside an unfinished key the path is its object's.
fn json_path_at(text: &str, line: usize, column: usize) -> String {
    enum Frame {
        Object { key: Option<String> },
        Array { index: usize },
    }
    let line_start: usize = text.split_inclusive('\n').take(line.saturating_sub(1)).map(str::len).sum();
    let mut end = (line_start + column.saturating_sub(1)).min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let mut stack: Vec<Frame> = Vec::new();
    let mut chars = text[..end].chars();
    while let Some(c) = chars.next() {
        match c {
            '{' => stack.push(Frame::Object { key: None }),
            '[' => stack.push(Frame::Array { index: 0 }),
            '}' | ']' => {
                stack.pop();
            }
            ',' => match stack.last_mut() {
                Some(Frame::Array { index }) => *index += 1,
                Some(Frame::Object { key }) => *key = None,
                None => {}
            },
            '"' => {
                let mut s = String::new();
                let mut closed = false;
                while let Some(d) = chars.next() {
                    match d {
                        '"' => {
                            closed = true;
                            break;
                        }
                        '\\' => {
                            if let Some(x) = chars.next() {
                                s.push(x);
                            }
                        }
                        _ => s.push(d),
                    }
                }
                if let Some(Frame::Object { key }) = stack.last_mut() {
                    if key.is_none() && closed {
                        *key = Some(s);
                    }
                }
            }
            _ => {}
        }
    }
    let mut out = String::new();
    for f in &stack {
        match f {
            Frame::Object { key: Some(k) } => {
                if !out.is_empty() {
                    out.push('.');
                }
                out.push_str(k);
            }
            Frame::Object { key: None } => break,
            Frame::Array { index } => out.push_str(&format!("[{index}]")),
        }
    }
    out
}

fn check_positive(path: &Path, field: &str, v: f64, unit: &str) -> Result<(), ModelError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ModelError::invalid(path, field, format!("must be a positive finite number ({unit}), got {v}")))
    }
}

fn check_finite(path: &Path, field: &str, v: &[f64]) -> Result<(), ModelError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(ModelError::invalid(path, field, format!("must be finite, got {v:?}")))
    }
}

impl SegmentSpec {
    fn validate(&self, path: &Path, field: &str) -> Result<(), ModelError> {
        check_positive(path, &format!("{field}.mass"), self.mass, "kg")?;
        check_positive(path, &format!("{field}.izz"), self.izz, "kg·m²")?;
        check_finite(path, &format!("{field}.com"), &self.com)
    }
}

impl Segments {
    /// Check every mass, inertia and position.
    pub fn validate(&self, path: &Path) -> Result<(), ModelError> {
        self.hat.validate(path, "body.segments.hat")?;
        self.thigh.validate(path, "body.segments.thigh")?;
        self.shank.validate(path, "body.segments.shank")?;
        self.foot.validate(path, "body.segments.foot")?;
        check_finite(path, "body.segments.hip_in_pelvis", &self.hip_in_pelvis)?;
        check_finite(path, "body.segments.knee_in_thigh", &self.knee_in_thigh)?;
        check_finite(path, "body.segments.ankle_in_shank", &self.ankle_in_shank)
    }

    /// Total body mass (kg): HAT plus two legs.
    pub fn total_mass(&self) -> f64 {
        self.hat.mass + 2.0 * (self.thigh.mass + self.shank.mass + self.foot.mass)
    }
}

impl ModelSpec {
    /// Read and validate a model file.
    pub fn load(path: &Path) -> Result<Self, ModelError> {
        let spec: ModelSpec = read_json(path)?;
        spec.validate(path)?;
        Ok(spec)
    }

    /// Check values that serde cannot.
    pub fn validate(&self, path: &Path) -> Result<(), ModelError> {
        check_positive(path, "gravity", self.gravity, "m/s²")?;
        match &self.body {
            BodySpec::DeLeva { mass, height, .. } => {
                check_positive(path, "body.mass", *mass, "kg")?;
                check_positive(path, "body.height", *height, "m")?;
            }
            BodySpec::Explicit { segments } => segments.validate(path)?,
            BodySpec::OpensimModel { file, .. } => {
                let target = relative_to(path, file);
                if let Err(e) = std::fs::metadata(&target) {
                    return Err(ModelError::Io {
                        path: target,
                        source: std::io::Error::new(
                            e.kind(),
                            format!("{e} (the OpenSim model named by field 'body.file' of {})", path.display()),
                        ),
                    });
                }
            }
        }
        match &self.actuators {
            ActuatorSpec::MuscleTorqueGenerators {
                strength_scale,
                eta,
                tau_activation,
                tau_deactivation,
                subject_mass,
                subject_height,
            } => {
                if let Some(m) = subject_mass {
                    check_positive(path, "actuators.subject_mass", *m, "kg")?;
                }
                if let Some(h) = subject_height {
                    check_positive(path, "actuators.subject_height", *h, "m")?;
                }
                check_positive(path, "actuators.strength_scale", *strength_scale, "dimensionless")?;
                if !(eta.is_finite() && *eta >= 0.0) {
                    return Err(ModelError::invalid(path, "actuators.eta", format!("must be finite and ≥ 0, got {eta}")));
                }
                check_positive(path, "actuators.tau_activation", *tau_activation, "s")?;
                check_positive(path, "actuators.tau_deactivation", *tau_deactivation, "s")?;
            }
            ActuatorSpec::JointTorques { max_torque } => check_positive(path, "actuators.max_torque", *max_torque, "N·m")?,
        }
        let c = &self.contact;
        check_finite(path, "contact.ground_height", &[c.ground_height])?;
        for (f, v) in [
            ("contact.baumgarte_alpha", c.baumgarte_alpha),
            ("contact.baumgarte_beta", c.baumgarte_beta),
            ("contact.baumgarte_gamma", c.baumgarte_gamma),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ModelError::invalid(path, f, format!("must be finite and ≥ 0 (1/s), got {v}")));
            }
        }
        let mut springs: Vec<(usize, &str, &str)> = Vec::new();
        for (i, e) in self.effects.iter().enumerate() {
            e.check().map_err(|(f, r)| ModelError::invalid(path, format!("effects[{i}].{f}"), r))?;
            match e {
                EffectSpec::PassiveJointStiffness { joint, side, .. } => {
                    let sides: &[&str] = match side.as_str() {
                        "right" => &["right"],
                        "left" => &["left"],
                        _ => &["right", "left"],
                    };
                    for s in sides {
                        if let Some((j, _, _)) = springs.iter().find(|(_, jj, ss)| jj == joint && ss == s) {
                            return Err(ModelError::invalid(
                                path,
                                format!("effects[{i}].joint"),
                                format!("the {s} {joint} already has a passive_joint_stiffness (effects[{j}]); give each joint one entry"),
                            ));
                        }
                        springs.push((i, joint, s));
                    }
                }
            }
        }
        Ok(())
    }
}

impl FootSpec {
    /// Read and validate a foot file.
    pub fn load(path: &Path) -> Result<Self, ModelError> {
        let spec: FootSpec = read_json(path)?;
        spec.validate(path)?;
        Ok(spec)
    }

    /// Check that the foot has primitives with unique names and valid geometry.
    pub fn validate(&self, path: &Path) -> Result<(), ModelError> {
        if self.primitives.is_empty() {
            return Err(ModelError::invalid(
                path,
                "primitives",
                "the foot has no contact primitive, so it can never touch the ground; add a circle, ellipse or point",
            ));
        }
        for (i, p) in self.primitives.iter().enumerate() {
            if p.name.is_empty() || p.name.contains('.') {
                return Err(ModelError::invalid(
                    path,
                    format!("primitives[{i}].name"),
                    "must be a non-empty name without '.'",
                ));
            }
            if self.primitives[..i].iter().any(|q| q.name == p.name) {
                return Err(ModelError::invalid(path, format!("primitives[{i}].name"), format!("'{}' is used twice", p.name)));
            }
            p.shape.check().map_err(|(f, r)| ModelError::invalid(path, format!("primitives[{i}].shape.{f}"), r))?;
        }
        // Planar model, foot frame at the ankle with y up in the neutral pose: a primitive
        // whose lowest point is not below the ankle can never carry the body's weight.
        let lowest = self.primitives.iter().filter_map(|p| p.shape.lowest_y()).fold(f64::INFINITY, f64::min);
        if !(lowest < 0.0) {
            return Err(ModelError::invalid(
                path,
                "primitives",
                format!(
                    "no primitive reaches below the ankle (lowest point {lowest:.4} m above it in the neutral pose), \
                     so the foot cannot touch the ground; primitive positions are in the ankle frame, y up"
                ),
            ));
        }
        Ok(())
    }
}

/// Resolve a path given in a file relative to that file's directory.
pub fn relative_to(file: &Path, p: &Path) -> PathBuf {
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        file.parent().unwrap_or(Path::new(".")).join(p)
    }
}

/// Read the derived 9-DoF segments from an OpenSim model summary JSON.
pub fn opensim_segments(path: &Path, lumbar: LumbarChoice) -> Result<Segments, ModelError> {
    let v: serde_json::Value = read_json(path)?;
    let get = |ptr: &str| -> Result<f64, ModelError> {
        v.pointer(ptr).and_then(|x| x.as_f64()).ok_or_else(|| {
            ModelError::invalid(path, ptr.trim_start_matches('/').replace('/', "."), "missing or not a number")
        })
    };
    let pair = |ptr: &str| -> Result<[f64; 2], ModelError> { Ok([get(&format!("{ptr}/0"))?, get(&format!("{ptr}/1"))?]) };
    let hat = match lumbar {
        LumbarChoice::TrialMean => "/nine_dof_mapping/HAT_at_trial_mean_lumbar",
        LumbarChoice::Zero => "/nine_dof_mapping/HAT_at_default_lumbar_0",
    };
    let seg = Segments {
        hat: SegmentSpec {
            mass: get(&format!("{hat}/mass_kg"))?,
            com: pair(&format!("{hat}/com_in_pelvis_frame_m"))?,
            izz: get(&format!("{hat}/inertia_about_com_in_pelvis_frame_kg_m2/zz"))?,
        },
        thigh: SegmentSpec {
            mass: get("/bodies/femur_r/mass_kg")?,
            com: pair("/bodies/femur_r/com_in_body_m")?,
            izz: get("/bodies/femur_r/inertia_about_com_kg_m2/zz")?,
        },
        shank: SegmentSpec {
            mass: get("/bodies/tibia_r/mass_kg")?,
            com: pair("/bodies/tibia_r/com_in_body_m")?,
            izz: get("/bodies/tibia_r/inertia_about_com_kg_m2/zz")?,
        },
        foot: SegmentSpec {
            mass: get("/nine_dof_mapping/foot_r/mass_kg")?,
            com: pair("/nine_dof_mapping/foot_r/com_in_talus_frame_m")?,
            izz: get("/nine_dof_mapping/foot_r/inertia_about_com_in_talus_frame_kg_m2/zz")?,
        },
        hip_in_pelvis: pair("/derived_planar/hip_centre_in_pelvis_frame_m")?,
        knee_in_thigh: pair("/derived_planar/thigh_hip_to_knee_m/vector_in_femur_frame_at_knee_angle_0_m")?,
        ankle_in_shank: pair("/derived_planar/shank_vector_in_tibia_frame_m")?,
    };
    seg.validate(path)?;
    Ok(seg)
}
