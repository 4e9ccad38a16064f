//! JSON specifications of models and feet, with validation on load.
//!
//! A model file (`models/*.json`) names the body parameters (a preset or explicit
//! segments), the actuators, the contact settings and optional effects. A foot file
//! (`models/feet/*.json`) lists contact primitives in the ankle (foot) frame; the same
//! foot is mirrored onto both legs (planar model: left and right feet are identical).

use super::effects::EffectSpec;
use super::error::ModelError;
use super::geometry::Shape;
use crate::limits::{
    show, MAX_BAUMGARTE, MAX_ETA, MAX_GRAVITY, MAX_GROUND_HEIGHT, MAX_HEIGHT, MAX_INERTIA,
    MAX_MASS, MAX_SEGMENT_EXTENT, MIN_HEIGHT,
};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub use super::json::{parse_json, read_json};

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
        Self {
            ground_height: 0.0,
            baumgarte_alpha: 20.0,
            baumgarte_beta: 20.0,
            baumgarte_gamma: 20.0,
        }
    }
}

/// How the six leg joints are driven.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ActuatorSpec {
    /// A flexor and an extensor muscle-torque generator per joint (Millard & Mombaur 2019, eq. 9–12) with
    /// activation dynamics; controls are the 12 excitations in [0, 1].
    MuscleTorqueGenerators {
        /// Multiplies every maximum isometric torque (default 1).
        #[serde(default = "one")]
        strength_scale: f64,
        /// Passive damping scale η of Millard & Mombaur 2019, eq. 12 (default 2.0).
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
        /// A typical torque (N·m, default 100, as the CasADi gait peer): the unit of the
        /// torque controls, so that `u = τ/τ_ref` is of order one like an excitation and
        /// an effort term `u²` is the peer's `(τ/τ_ref)²`.
        #[serde(default = "default_reference_torque")]
        reference_torque: f64,
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
fn default_reference_torque() -> f64 {
    100.0
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
    /// How it meets the ground (default: rigid, held by the phases' contact constraints).
    #[serde(default)]
    pub contact: ContactLaw,
}

/// How a primitive meets the ground.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ContactLaw {
    /// A rigid contact: the phase file's constraint sets hold it on the ground (rolling
    /// without slipping), with impacts where it lands.
    #[default]
    Rigid,
    /// A compliant volumetric contact ([`crate::model::volumetric`]): a force from the
    /// penetrated area in every phase, never a constraint; the phase file leaves it out of
    /// its contact sets.
    Volumetric(crate::model::volumetric::VolumetricLaw),
}

fn check_positive(path: &Path, field: &str, v: f64, unit: &str) -> Result<(), ModelError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ModelError::invalid(
            path,
            field,
            format!("must be a positive finite number ({unit}), got {}", show(v)),
        ))
    }
}

/// `v` must be in (0, `max`]: beyond it a value is physically absurd.
fn check_at_most(path: &Path, field: &str, v: f64, max: f64, unit: &str) -> Result<(), ModelError> {
    check_positive(path, field, v, unit)?;
    if v <= max {
        Ok(())
    } else {
        Err(ModelError::invalid(
            path,
            field,
            format!(
                "{} {unit} is beyond the sensible limit; expected a value in (0, {}] {unit}",
                show(v),
                show(max)
            ),
        ))
    }
}

/// A stature (m) in [`MIN_HEIGHT`], [`MAX_HEIGHT`].
fn check_stature(path: &Path, field: &str, v: f64) -> Result<(), ModelError> {
    check_at_most(path, field, v, MAX_HEIGHT, "m")?;
    if v >= MIN_HEIGHT {
        return Ok(());
    }
    Err(ModelError::invalid(
        path,
        field,
        format!(
            "a stature of {} m is below any human's; expected a value in [{}, {}] m",
            show(v),
            show(MIN_HEIGHT),
            show(MAX_HEIGHT)
        ),
    ))
}

fn check_finite(path: &Path, field: &str, v: &[f64]) -> Result<(), ModelError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(ModelError::invalid(
            path,
            field,
            format!("must be finite, got {v:?}"),
        ))
    }
}

/// A position in a segment frame: finite and within [`MAX_SEGMENT_EXTENT`] of the origin.
fn check_position(path: &Path, field: &str, v: &[f64; 2]) -> Result<(), ModelError> {
    check_finite(path, field, v)?;
    if v.iter().all(|x| x.abs() <= MAX_SEGMENT_EXTENT) {
        Ok(())
    } else {
        Err(ModelError::invalid(
            path,
            field,
            format!("[{}, {}] m is beyond the sensible limit; expected coordinates within ±{MAX_SEGMENT_EXTENT} m of the frame's origin", show(v[0]), show(v[1])),
        ))
    }
}

impl SegmentSpec {
    fn validate(&self, path: &Path, field: &str) -> Result<(), ModelError> {
        check_at_most(path, &format!("{field}.mass"), self.mass, MAX_MASS, "kg")?;
        check_at_most(
            path,
            &format!("{field}.izz"),
            self.izz,
            MAX_INERTIA,
            "kg·m²",
        )?;
        check_position(path, &format!("{field}.com"), &self.com)
    }
}

impl Segments {
    /// Check every mass, inertia and position.
    pub fn validate(&self, path: &Path) -> Result<(), ModelError> {
        self.hat.validate(path, "body.segments.hat")?;
        self.thigh.validate(path, "body.segments.thigh")?;
        self.shank.validate(path, "body.segments.shank")?;
        self.foot.validate(path, "body.segments.foot")?;
        check_position(path, "body.segments.hip_in_pelvis", &self.hip_in_pelvis)?;
        check_position(path, "body.segments.knee_in_thigh", &self.knee_in_thigh)?;
        check_position(path, "body.segments.ankle_in_shank", &self.ankle_in_shank)
    }

    /// Total body mass (kg): HAT plus two legs.
    pub fn total_mass(&self) -> f64 {
        self.hat.mass + 2.0 * (self.thigh.mass + self.shank.mass + self.foot.mass)
    }
}

impl ModelSpec {
    /// Read and validate a model file.
    pub fn load(path: &Path) -> Result<Self, ModelError> {
        let path = &crate::bundled::resolve(path);
        let spec: ModelSpec = read_json(path)?;
        spec.validate(path)?;
        Ok(spec)
    }

    /// Check values that serde cannot.
    pub fn validate(&self, path: &Path) -> Result<(), ModelError> {
        check_at_most(path, "gravity", self.gravity, MAX_GRAVITY, "m/s²")?;
        match &self.body {
            BodySpec::DeLeva { mass, height, .. } => {
                check_at_most(path, "body.mass", *mass, MAX_MASS, "kg")?;
                check_stature(path, "body.height", *height)?;
            }
            BodySpec::Explicit { segments } => segments.validate(path)?,
            BodySpec::OpensimModel { file, .. } => {
                let target = relative_to(path, file);
                if let Err(e) = std::fs::metadata(&target) {
                    return Err(ModelError::Io {
                        path: target,
                        source: std::io::Error::new(
                            e.kind(),
                            format!(
                                "{e} (the OpenSim model named by field 'body.file' of {})",
                                path.display()
                            ),
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
                    check_at_most(path, "actuators.subject_mass", *m, MAX_MASS, "kg")?;
                }
                if let Some(h) = subject_height {
                    check_stature(path, "actuators.subject_height", *h)?;
                }
                check_positive(
                    path,
                    "actuators.strength_scale",
                    *strength_scale,
                    "dimensionless",
                )?;
                if !(eta.is_finite() && (0.0..=MAX_ETA).contains(eta)) {
                    return Err(ModelError::invalid(
                        path,
                        "actuators.eta",
                        format!(
                            "must be in [0, {}] (Millard & Mombaur 2019 use 0.4 to 2), got {}",
                            show(MAX_ETA),
                            show(*eta)
                        ),
                    ));
                }
                check_positive(path, "actuators.tau_activation", *tau_activation, "s")?;
                check_positive(path, "actuators.tau_deactivation", *tau_deactivation, "s")?;
            }
            ActuatorSpec::JointTorques {
                max_torque,
                reference_torque,
            } => {
                check_positive(path, "actuators.max_torque", *max_torque, "N·m")?;
                check_positive(path, "actuators.reference_torque", *reference_torque, "N·m")?
            }
        }
        let c = &self.contact;
        check_finite(path, "contact.ground_height", &[c.ground_height])?;
        if c.ground_height.abs() > MAX_GROUND_HEIGHT {
            return Err(ModelError::invalid(
                path,
                "contact.ground_height",
                format!("{} m is beyond the sensible limit; expected a height within ±{} m of the model's origin", show(c.ground_height), show(MAX_GROUND_HEIGHT)),
            ));
        }
        for (f, v) in [
            ("contact.baumgarte_alpha", c.baumgarte_alpha),
            ("contact.baumgarte_beta", c.baumgarte_beta),
            ("contact.baumgarte_gamma", c.baumgarte_gamma),
        ] {
            if !(v.is_finite() && (0.0..=MAX_BAUMGARTE).contains(&v)) {
                return Err(ModelError::invalid(
                    path,
                    f,
                    format!(
                        "must be in [0, {}] 1/s, got {}",
                        show(MAX_BAUMGARTE),
                        show(v)
                    ),
                ));
            }
        }
        for (i, e) in self.effects.iter().enumerate() {
            e.check()
                .map_err(|(f, r)| ModelError::invalid(path, format!("effects[{i}].{f}"), r))?;
            if let Some(j) = self.effects[..i]
                .iter()
                .position(|o| o.overlaps(e) && !o.composes_with(e))
            {
                let (field, what) = match e {
                    EffectSpec::PassiveJointStiffness { joint, side, .. } => {
                        let which = match (side.as_str(), &self.effects[j]) {
                            ("both", EffectSpec::PassiveJointStiffness { side: s, .. }) if s != "both" => s.clone(),
                            (s, _) => s.to_string(),
                        };
                        ("joint", format!("the {which} {joint} already has a passive_joint_stiffness (effects[{j}]); give each joint one entry"))
                    }
                    _ => ("type", format!("'{}' is already an effect of the model (effects[{j}]); give each effect one entry", e.kind())),
                };
                return Err(ModelError::invalid(
                    path,
                    format!("effects[{i}].{field}"),
                    what,
                ));
            }
        }
        Ok(())
    }
}

impl FootSpec {
    /// Read and validate a foot file.
    pub fn load(path: &Path) -> Result<Self, ModelError> {
        let path = &crate::bundled::resolve(path);
        if !path.exists() {
            return Err(ModelError::NoFoot {
                path: path.clone(),
                bundled: crate::bundled::feet().join(", "),
            });
        }
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
        if self.primitives.len() > crate::limits::MAX_PRIMITIVES {
            return Err(ModelError::invalid(
                path,
                "primitives",
                format!(
                    "must list 1 to {} contact primitives, got {}",
                    crate::limits::MAX_PRIMITIVES,
                    self.primitives.len()
                ),
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
                return Err(ModelError::invalid(
                    path,
                    format!("primitives[{i}].name"),
                    format!("'{}' is used twice", p.name),
                ));
            }
            p.shape.check().map_err(|(f, r)| {
                ModelError::invalid(path, format!("primitives[{i}].shape.{f}"), r)
            })?;
            if let ContactLaw::Volumetric(law) = &p.contact {
                if matches!(p.shape, Shape::Point { .. }) {
                    return Err(ModelError::invalid(
                        path,
                        format!("primitives[{i}].contact"),
                        "a point has no area to penetrate the ground; a volumetric contact needs a circle or an ellipse",
                    ));
                }
                law.check().map_err(|(f, r)| {
                    ModelError::invalid(path, format!("primitives[{i}].contact.{f}"), r)
                })?;
            }
            if p.shape.lowest_y().is_none() {
                return Err(ModelError::invalid(
                    path,
                    format!("primitives[{i}].shape"),
                    "its lowest point evaluates to a non-finite number; use sizes and positions in metres of a foot's scale",
                ));
            }
        }
        // Planar model, foot frame at the ankle with y up in the neutral pose: a primitive
        // whose lowest point is not below the ankle can never carry the body's weight.
        let lowest = self
            .primitives
            .iter()
            .filter_map(|p| p.shape.lowest_y())
            .fold(f64::INFINITY, f64::min);
        if lowest >= 0.0 {
            return Err(ModelError::foot_above_ankle(path, lowest));
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

/// An OpenSim model summary JSON (as shipped in `data/`), read once: its numbers by JSON
/// pointer, an error naming the file and the field where one is missing.
#[derive(Debug, Clone)]
pub struct OpensimSummary {
    path: PathBuf,
    value: serde_json::Value,
}

impl OpensimSummary {
    /// Read the summary at `path`.
    pub fn load(path: &Path) -> Result<Self, ModelError> {
        Ok(Self {
            path: path.to_path_buf(),
            value: read_json(path)?,
        })
    }

    /// The file it was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whether the summary has an entry at `ptr` (a JSON pointer).
    pub fn has(&self, ptr: &str) -> bool {
        self.value.pointer(ptr).is_some()
    }

    /// The number at `ptr` (a JSON pointer).
    pub fn number(&self, ptr: &str) -> Result<f64, ModelError> {
        self.value
            .pointer(ptr)
            .and_then(|x| x.as_f64())
            .ok_or_else(|| {
                ModelError::invalid(
                    &self.path,
                    ptr.trim_start_matches('/').replace('/', "."),
                    "missing or not a number",
                )
            })
    }

    /// The first two numbers of the array at `ptr` (a JSON pointer).
    pub fn pair(&self, ptr: &str) -> Result<[f64; 2], ModelError> {
        Ok([
            self.number(&format!("{ptr}/0"))?,
            self.number(&format!("{ptr}/1"))?,
        ])
    }
}

/// The derived 9-DoF segments of an OpenSim model summary.
pub fn opensim_segments(
    summary: &OpensimSummary,
    lumbar: LumbarChoice,
) -> Result<Segments, ModelError> {
    let get = |ptr: &str| summary.number(ptr);
    let pair = |ptr: &str| summary.pair(ptr);
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
        knee_in_thigh: pair(
            "/derived_planar/thigh_hip_to_knee_m/vector_in_femur_frame_at_knee_angle_0_m",
        )?,
        ankle_in_shank: pair("/derived_planar/shank_vector_in_tibia_frame_m")?,
    };
    seg.validate(summary.path())?;
    Ok(seg)
}
