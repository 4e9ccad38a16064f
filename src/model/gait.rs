//! The assembled planar gait model: 9-DoF body, two feet of contact primitives,
//! actuators and effects, loaded from a model file and a foot file.
//!
//! [`GaitModel`] holds the model and its parameters; its methods live beside it by
//! concept: `gait/contact.rs` (constraint sets and constraint kinematics),
//! `gait/dynamics.rs` (forward dynamics with contact and the impact map) and
//! `gait/jacobians.rs` (derivatives by AD). The body is built in
//! [`anthropometry`](super::anthropometry); the integrator's view of the model is
//! `problems::GaitOde`, above this layer.

mod contact;
mod dynamics;
mod jacobians;
mod volumetric;

pub use contact::{ConstraintRow, ConstraintSet, Contact, ContactReport, FootLoad, RowKind};
pub use dynamics::ForceParts;
pub use volumetric::VolumetricReport;

use super::actuators::{Joint as MtgJoint, JointActuatorSet};
use super::anthropometry;
use super::effects::{
    ActuatorAdjust, DynEffect, MeasurementAdjust, ModelAdjust, ModelScalar, ParamSpec,
};
use super::error::{AnthropometryError, ModelError, ParameterError};
use super::geometry::{Shape, ShapeScalars};
use super::multibody::{Inertia, Tree, V2};
use super::segments::{build_bodies, estimated_stature, segments_from_de_leva};
use super::spec::{
    self, ActuatorSpec, BodySpec, ContactSettings, FootSpec, ModelSpec, OpensimSummary, Segments,
};
use super::torso::{self, Torso};
use super::Scalar;
use std::path::{Path, PathBuf};

/// Names of the generalised coordinates, in state order.
pub const COORDINATES: [&str; 9] = [
    "pelvis_x",
    "pelvis_y",
    "pelvis_tilt",
    "hip_r",
    "knee_r",
    "ankle_r",
    "hip_l",
    "knee_l",
    "ankle_l",
];

/// Leg side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// Right leg (prefix `r`).
    Right,
    /// Left leg (prefix `l`).
    Left,
}

impl Side {
    /// `r` or `l`.
    pub fn prefix(self) -> &'static str {
        match self {
            Side::Right => "r",
            Side::Left => "l",
        }
    }
}

/// How the joints are driven.
#[derive(Debug, Clone)]
pub enum Actuation {
    /// Flexor/extensor muscle-torque generators with activation dynamics.
    Mtg(JointActuatorSet),
    /// Joint torques as controls.
    Torques {
        /// Bound on each torque (N·m).
        max_torque: f64,
        /// A typical torque (N·m) that effort terms normalise by.
        reference_torque: f64,
    },
}

/// Leg joints in actuator order: (coordinate index, joint kind).
const LEG_JOINTS: [(usize, MtgJoint); 6] = [
    (3, MtgJoint::Hip),
    (4, MtgJoint::Knee),
    (5, MtgJoint::Ankle),
    (6, MtgJoint::Hip),
    (7, MtgJoint::Knee),
    (8, MtgJoint::Ankle),
];

/// The assembled model. State `x = (q, q̇, a)`, controls `u` (excitations or torques),
/// free parameters `θ` (the free effect parameters).
#[derive(Debug)]
pub struct GaitModel {
    /// Model name.
    pub name: String,
    /// The model file it was built from.
    source: PathBuf,
    tree: Tree,
    gravity: f64,
    /// Foot-ground contact primitives of both feet.
    pub contacts: Vec<Contact>,
    /// Name of the foot geometry.
    pub foot_name: String,
    actuation: Actuation,
    contact_settings: ContactSettings,
    effects: Vec<Box<dyn DynEffect>>,
    /// Residual actuators: force or torque per unit control on every coordinate.
    residuals: Option<Vec<f64>>,
    /// Offsets of each effect's parameters in [`GaitModel::parameters`].
    effect_offsets: Vec<usize>,
    /// Per contact: the effect that makes its normal contact compliant, if any.
    compliant: Vec<Option<usize>>,
    /// Per contact: the effect whose parameters replace its volumetric law, and the
    /// primitive's slot among that effect's (`volumetric_contact`), if any.
    volumetric_params: Vec<Option<(usize, usize)>>,
    /// Per contact: the effect whose parameters replace its geometry, and the offset of
    /// the primitive's among that effect's (`foot_geometry`), if any.
    geometry_params: Vec<Option<(usize, usize)>>,
    params: Vec<ParamSpec>,
    free: Vec<usize>,
    /// The HAT's trunk above the lumbar joint, where the body's source describes it.
    torso: Option<Torso>,
}

impl GaitModel {
    /// Build the model from a model file and a foot file.
    pub fn load(model_path: &Path, foot_path: &Path) -> Result<Self, ModelError> {
        // a bundled name missing from the current folder is read from footfall's copy
        let (model_path, foot_path) = (
            &crate::bundled::resolve(model_path),
            &crate::bundled::resolve(foot_path),
        );
        let spec = ModelSpec::load(model_path)?;
        let foot = FootSpec::load(foot_path)?;
        Self::from_specs(&spec, model_path, &foot, foot_path)
    }

    /// Build the model with `extra` effects added to those of the model file (e.g. from
    /// `--effect`); an extra effect that the file already has is refused.
    pub fn load_with_effects(
        model_path: &Path,
        foot_path: &Path,
        extra: &[super::effects::EffectSpec],
    ) -> Result<Self, ModelError> {
        // a bundled name missing from the current folder is read from footfall's copy
        let (model_path, foot_path) = (
            &crate::bundled::resolve(model_path),
            &crate::bundled::resolve(foot_path),
        );
        let mut spec = ModelSpec::load(model_path)?;
        for e in extra {
            if let Some(j) = spec
                .effects
                .iter()
                .position(|o| o.overlaps(e) && !o.composes_with(e))
            {
                return Err(ModelError::invalid(
                    model_path,
                    format!("effects[{j}]"),
                    format!("the model already has the effect '{}' that was asked for in addition; remove one of them", e.label()),
                ));
            }
            spec.effects.push(e.clone());
        }
        let foot = FootSpec::load(foot_path)?;
        Self::from_specs(&spec, model_path, &foot, foot_path)
    }

    /// Set the value of the effect parameter `name` (e.g. an identified value read back
    /// from a run), within its bounds.
    pub fn set_parameter_value(&mut self, name: &str, value: f64) -> Result<(), ParameterError> {
        let p = self
            .params
            .iter_mut()
            .find(|p| p.name == name)
            .ok_or_else(|| ParameterError::Unknown {
                name: name.to_string(),
            })?;
        if !(value.is_finite() && value >= p.lower && value <= p.upper) {
            return Err(ParameterError::OutOfBounds {
                name: name.to_string(),
                value,
                lower: p.lower,
                upper: p.upper,
            });
        }
        p.value = value;
        Ok(())
    }

    /// Assemble from parsed specifications (`model_path` resolves relative paths and
    /// names the file in errors).
    pub fn from_specs(
        spec: &ModelSpec,
        model_path: &Path,
        foot: &FootSpec,
        foot_path: &Path,
    ) -> Result<Self, ModelError> {
        spec.validate(model_path)?;
        foot.validate(foot_path)?;
        let (seg, torso) = body(spec, model_path)?;
        let tree = Tree::new(build_bodies(&seg))
            .map_err(|r| ModelError::invalid(model_path, "body", r.to_string()))?;
        let contacts = foot_contacts(&tree, foot);
        let actuation = actuation(spec, &seg, model_path)?;
        let effects = build_effects(spec, model_path, &tree, foot, foot_path)?;
        check_actuator_effects(&actuation, &effects, model_path)?;
        let EffectParameters {
            params,
            offsets: effect_offsets,
            free,
        } = effect_parameters(&effects, model_path)?;
        let slots = ContactSlots::new(&contacts, &effects);
        let model = Self {
            name: spec.name.clone(),
            source: model_path.to_path_buf(),
            tree,
            gravity: spec.gravity,
            contacts,
            foot_name: foot.name.clone(),
            actuation,
            contact_settings: spec.contact,
            effects,
            residuals: None,
            effect_offsets,
            compliant: slots.compliant,
            volumetric_params: slots.volumetric,
            geometry_params: slots.geometry,
            params,
            free,
            torso,
        };
        model.check_foot_reaches_ground(foot_path)?;
        Ok(model)
    }

    /// A foot must be able to touch the ground from a standing pose: its lowest point
    /// must lie below the ankle (a primitive entirely above the ankle cannot carry load).
    fn check_foot_reaches_ground(&self, foot_path: &Path) -> Result<(), ModelError> {
        let n = [0.0, 1.0];
        let lowest = self
            .contacts
            .iter()
            .filter(|c| c.side == Side::Right)
            .map(|c| c.shape.centre()[1] + c.shape.contact_offset::<f64>(0.0, n)[1])
            .fold(f64::INFINITY, f64::min);
        if !(lowest < 0.0) {
            return Err(ModelError::foot_above_ankle(foot_path, lowest));
        }
        Ok(())
    }

    /// The model file it was built from (as given, or footfall's copy of a bundled one).
    pub fn source(&self) -> &Path {
        &self.source
    }

    /// The multibody tree.
    pub fn tree(&self) -> &Tree {
        &self.tree
    }

    /// The HAT's trunk above the lumbar joint (part of the rigid HAT), where the body's
    /// source describes it: OpenSim models and de Leva's tables do, explicit segments
    /// do not.
    pub fn torso(&self) -> Option<&Torso> {
        self.torso.as_ref()
    }
    /// Gravitational acceleration of the model file (m/s², before any effect tilts it).
    pub fn gravity(&self) -> f64 {
        self.gravity
    }
    /// Number of generalised coordinates.
    pub fn nq(&self) -> usize {
        self.tree.nq()
    }
    /// Number of activation states.
    pub fn na(&self) -> usize {
        match self.actuation {
            Actuation::Mtg(_) => 2 * LEG_JOINTS.len(),
            Actuation::Torques { .. } => 0,
        }
    }
    /// State dimension `2 nq + na`.
    pub fn nx(&self) -> usize {
        2 * self.nq() + self.na()
    }
    /// Control dimension: the actuators' controls, then the residual actuators' (if any).
    pub fn nu(&self) -> usize {
        self.nu_actuators() + self.residuals.as_ref().map_or(0, Vec::len)
    }
    /// Number of controls of the actuators proper (excitations or joint torques).
    pub fn nu_actuators(&self) -> usize {
        match self.actuation {
            Actuation::Mtg(_) => 2 * LEG_JOINTS.len(),
            Actuation::Torques { .. } => LEG_JOINTS.len(),
        }
    }
    /// The effective time constant (s) of the activation dynamics; `None` without
    /// muscle-torque generators.
    pub fn activation_time_constant(&self) -> Option<f64> {
        match &self.actuation {
            Actuation::Mtg(set) => Some(set.activation.time_constant()),
            Actuation::Torques { .. } => None,
        }
    }
    /// Lower and upper bound of every control, in [`Self::control_names`] order:
    /// excitations in [0, 1], joint torques in ±`max_torque` (in units of
    /// [`Self::torque_unit`]), residual actuators in [−1, 1] (their scale is in the model).
    pub fn control_bounds(&self) -> (Vec<f64>, Vec<f64>) {
        let (lo, hi) = match self.actuation {
            Actuation::Mtg(_) => (0.0, 1.0),
            Actuation::Torques {
                max_torque,
                reference_torque,
            } => (
                -max_torque / reference_torque,
                max_torque / reference_torque,
            ),
        };
        let n = self.nu_actuators();
        let lb = (0..self.nu()).map(|i| if i < n { lo } else { -1.0 });
        let ub = (0..self.nu()).map(|i| if i < n { hi } else { 1.0 });
        (lb.collect(), ub.collect())
    }
    /// The torque (N·m) of a unit joint-torque control: controls are torques over the
    /// model's `reference_torque`, so they are of order one like excitations and the QP
    /// stays well scaled. `None` for muscle-torque generators (their controls are
    /// excitations).
    pub fn torque_unit(&self) -> Option<f64> {
        match self.actuation {
            Actuation::Mtg(_) => None,
            Actuation::Torques {
                reference_torque, ..
            } => Some(reference_torque),
        }
    }

    /// Add residual actuators (as in residual reduction of inverse dynamics): a generalised force on
    /// each pelvis translation of `force_n` newtons per unit control and a torque on the
    /// pelvis tilt and every joint of `torque_nm` newton-metres per unit control. Their
    /// controls follow the actuators' (names `<coordinate>_residual`), so a tracking
    /// problem can penalise them and show which residual the model needs, and when.
    pub fn with_residual_actuators(mut self, force_n: f64, torque_nm: f64) -> Self {
        self.residuals = Some(
            (0..self.nq())
                .map(|i| if i < 2 { force_n } else { torque_nm })
                .collect(),
        );
        self
    }

    /// Force or torque per unit control of each residual actuator (empty without them).
    pub fn residual_scales(&self) -> &[f64] {
        self.residuals.as_deref().unwrap_or(&[])
    }
    /// Number of free parameters θ.
    pub fn ntheta(&self) -> usize {
        self.free.len()
    }
    /// All effect parameters (fixed and free), in order.
    pub fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    /// Indices (into [`parameters`](Self::parameters)) of the free parameters, θ order.
    pub fn free_parameters(&self) -> &[usize] {
        &self.free
    }
    /// Current values of the free parameters.
    pub fn theta0(&self) -> Vec<f64> {
        self.free.iter().map(|&i| self.params[i].value).collect()
    }
    /// The actuation.
    pub fn actuation(&self) -> &Actuation {
        &self.actuation
    }
    /// Contact settings.
    pub fn contact_settings(&self) -> &ContactSettings {
        &self.contact_settings
    }
    /// Set Baumgarte gains (1/s).
    pub fn set_baumgarte(&mut self, alpha: f64, beta: f64, gamma: f64) {
        self.contact_settings.baumgarte_alpha = alpha;
        self.contact_settings.baumgarte_beta = beta;
        self.contact_settings.baumgarte_gamma = gamma;
    }
    /// Names of all state components.
    pub fn state_names(&self) -> Vec<String> {
        let mut v: Vec<String> = COORDINATES.iter().map(|s| s.to_string()).collect();
        v.extend(COORDINATES.iter().map(|s| format!("{s}_dot")));
        v.extend(
            self.control_names()
                .into_iter()
                .filter(|_| self.na() > 0)
                .map(|s| s.replace("_excitation", "_activation")),
        );
        v
    }
    /// Names of the controls.
    pub fn control_names(&self) -> Vec<String> {
        let mut v = Vec::new();
        for (c, _) in LEG_JOINTS {
            match self.actuation {
                Actuation::Mtg(_) => {
                    v.push(format!("{}_flexor_excitation", COORDINATES[c]));
                    v.push(format!("{}_extensor_excitation", COORDINATES[c]));
                }
                Actuation::Torques { .. } => v.push(format!("{}_torque", COORDINATES[c])),
            }
        }
        for i in 0..self.residual_scales().len() {
            v.push(format!("{}_residual", COORDINATES[i]));
        }
        v
    }

    /// Full parameter vector in scalar `S`: fixed values as constants, free ones from θ.
    fn full_params<S: Scalar>(&self, theta: &[S]) -> Vec<S> {
        assert_eq!(
            theta.len(),
            self.free.len(),
            "θ must hold the model's free parameters"
        );
        let mut p: Vec<S> = self.params.iter().map(|p| S::c(p.value)).collect();
        for (k, &i) in self.free.iter().enumerate() {
            p[i] = theta[k];
        }
        p
    }

    /// The shape of contact `c` with the free parameters at `theta`: the foot file's, or,
    /// under a `foot_geometry` effect, the one those parameters give (what a drawing of
    /// the fitted foot shows).
    pub fn contact_shape(&self, c: usize, theta: &[f64]) -> Shape {
        match self.shape_of(c, &self.full_params(theta)) {
            ShapeScalars::Point { position } => Shape::Point { position },
            ShapeScalars::Circle { centre, radius } => Shape::Circle { centre, radius },
            ShapeScalars::Ellipse {
                centre,
                angle,
                semi_axes,
            } => Shape::Ellipse {
                centre,
                angle,
                semi_axes,
            },
        }
    }

    /// The shape of contact `c` under the effect parameters `p` (all of them): the foot
    /// file's, or a `foot_geometry` effect's.
    fn shape_of<S: Scalar>(&self, c: usize, p: &[S]) -> ShapeScalars<S> {
        let contact = &self.contacts[c];
        let Some((e, offset)) = self.geometry_params[c] else {
            return contact.shape.scalars();
        };
        let q = &self.effect_params(p, e)[offset..];
        match contact.shape {
            Shape::Point { .. } => ShapeScalars::Point {
                position: [q[0], q[1]],
            },
            Shape::Circle { .. } => ShapeScalars::Circle {
                centre: [q[0], q[1]],
                radius: q[2],
            },
            Shape::Ellipse { .. } => ShapeScalars::Ellipse {
                centre: [q[0], q[1]],
                semi_axes: [q[2], q[3]],
                angle: q[4],
            },
        }
    }

    fn effect_params<'a, S>(&self, p: &'a [S], e: usize) -> &'a [S] {
        let start = self.effect_offsets[e];
        &p[start..start + self.effects[e].parameters().len()]
    }

    /// How the measurements relate to the model under the measurement effects (zero
    /// offsets without any).
    pub fn measurement_adjust<S: ModelScalar>(&self, theta: &[S]) -> MeasurementAdjust<S> {
        let p = self.full_params(theta);
        let mut m = MeasurementAdjust::identity();
        for e in 0..self.effects.len() {
            S::measurement(self.effects[e].as_ref(), self.effect_params(&p, e), &mut m);
        }
        m
    }

    /// The factors the actuator effects put on the muscle-torque generators' strength,
    /// damping and activation time constants (all one without any), from the full
    /// parameter vector `p`.
    pub(crate) fn actuator_adjust<S: ModelScalar>(&self, p: &[S]) -> ActuatorAdjust<S> {
        let mut a = ActuatorAdjust::identity();
        for e in 0..self.effects.len() {
            S::actuators(self.effects[e].as_ref(), self.effect_params(p, e), &mut a);
        }
        a
    }

    /// [`actuator_adjust`](Self::actuator_adjust) at free parameters `theta`.
    pub fn actuator_factors<S: ModelScalar>(&self, theta: &[S]) -> ActuatorAdjust<S> {
        self.actuator_adjust(&self.full_params(theta))
    }

    /// Whether a free parameter changes the activation time constants (the excitations
    /// then enter ȧ with a parameter-dependent coefficient).
    pub fn scales_activation_time(&self) -> bool {
        self.effects.iter().any(|e| e.scales_activation_time())
    }

    /// Whether any effect changes how the model is compared with the data.
    pub fn has_measurement_effects(&self) -> bool {
        self.effects.iter().any(|e| e.is_measurement())
    }

    /// Whether an effect moves the force plates' clock against the motion capture's.
    pub fn shifts_force_clock(&self) -> bool {
        self.effects.iter().any(|e| e.shifts_force_clock())
    }

    /// Model quantities after the effects' adjustments.
    fn adjusted<S: ModelScalar>(&self, p: &[S]) -> (Vec<Inertia<S>>, V2<S>, S, V2<S>) {
        let mut inertia = self.tree.inertias::<S>();
        let mut gravity = [S::c(0.0), S::c(-self.gravity)];
        let mut ground_height = S::c(self.contact_settings.ground_height);
        let mut ground_normal = [S::c(0.0), S::c(1.0)];
        for e in 0..self.effects.len() {
            let mut adj = ModelAdjust {
                inertia: &mut inertia,
                gravity: &mut gravity,
                ground_height: &mut ground_height,
                ground_normal: &mut ground_normal,
            };
            S::adjust(self.effects[e].as_ref(), self.effect_params(p, e), &mut adj);
        }
        (inertia, gravity, ground_height, ground_normal)
    }
}

/// The body's segments, and the HAT's trunk above the lumbar joint where the body's
/// source describes it: as given (no trunk), from an OpenSim model summary (its torso
/// body, if it has one), or from de Leva's tables.
fn body(spec: &ModelSpec, model_path: &Path) -> Result<(Segments, Option<Torso>), ModelError> {
    let de_leva = |r: AnthropometryError| ModelError::invalid(model_path, "body", r.to_string());
    Ok(match &spec.body {
        BodySpec::Explicit { segments } => (segments.clone(), None),
        BodySpec::OpensimModel { file, lumbar } => {
            let summary = OpensimSummary::load(&spec::relative_to(model_path, file))?;
            (
                spec::opensim_segments(&summary, *lumbar)?,
                torso::opensim_torso(&summary, *lumbar)?,
            )
        }
        BodySpec::DeLeva { mass, height, sex } => (
            segments_from_de_leva(
                &anthropometry::de_leva_planar(*mass, *height, *sex).map_err(de_leva)?,
            ),
            Some(torso::de_leva_torso(*mass, *height, *sex).map_err(de_leva)?),
        ),
    })
}

/// Each foot primitive on each side (right, then left), named `r.NAME` and `l.NAME`.
fn foot_contacts(tree: &Tree, foot: &FootSpec) -> Vec<Contact> {
    let mut contacts = Vec::new();
    for side in [Side::Right, Side::Left] {
        let body = tree
            .body_index(&format!("foot_{}", side.prefix()))
            .expect("foot body exists");
        for p in &foot.primitives {
            contacts.push(Contact {
                name: format!("{}.{}", side.prefix(), p.name),
                side,
                body,
                shape: p.shape.clone(),
                law: match p.contact {
                    spec::ContactLaw::Rigid => None,
                    spec::ContactLaw::Volumetric(law) => Some(law),
                },
            });
        }
    }
    contacts
}

/// The joints' drive: muscle-torque generators scaled to the subject (its mass and
/// stature default to the body's), or joint torques.
fn actuation(spec: &ModelSpec, seg: &Segments, model_path: &Path) -> Result<Actuation, ModelError> {
    Ok(match &spec.actuators {
        ActuatorSpec::MuscleTorqueGenerators {
            strength_scale,
            eta,
            tau_activation,
            tau_deactivation,
            subject_mass,
            subject_height,
        } => {
            let mass = subject_mass.unwrap_or_else(|| seg.total_mass());
            let height = subject_height.unwrap_or_else(|| match &spec.body {
                BodySpec::DeLeva { height, .. } => *height,
                _ => estimated_stature(seg),
            });
            let mut set =
                JointActuatorSet::anderson2007_young_male_for(mass, height).scaled(*strength_scale);
            set.eta = *eta;
            set.activation.tau_activation = *tau_activation;
            set.activation.tau_deactivation = *tau_deactivation;
            set.validate()
                .map_err(|r| ModelError::invalid(model_path, "actuators", r.to_string()))?;
            Actuation::Mtg(set)
        }
        ActuatorSpec::JointTorques {
            max_torque,
            reference_torque,
        } => Actuation::Torques {
            max_torque: *max_torque,
            reference_torque: *reference_torque,
        },
    })
}

/// The model file's effects, built for this body and foot; an error names the entry.
fn build_effects(
    spec: &ModelSpec,
    model_path: &Path,
    tree: &Tree,
    foot: &FootSpec,
    foot_path: &Path,
) -> Result<Vec<Box<dyn DynEffect>>, ModelError> {
    let coords: Vec<String> = COORDINATES.iter().map(|s| s.to_string()).collect();
    let bodies: Vec<String> = tree.bodies().iter().map(|b| b.name.clone()).collect();
    let primitives: Vec<String> = foot.primitives.iter().map(|p| p.name.clone()).collect();
    let laws: Vec<_> = foot
        .primitives
        .iter()
        .map(|p| match p.contact {
            spec::ContactLaw::Rigid => None,
            spec::ContactLaw::Volumetric(law) => Some(law),
        })
        .collect();
    let foot_file = foot_path.display().to_string();
    let shapes: Vec<Shape> = foot.primitives.iter().map(|p| p.shape.clone()).collect();
    let ctx = super::effects::BuildContext {
        coordinates: &coords,
        bodies: &bodies,
        primitives: &primitives,
        laws: &laws,
        shapes: &shapes,
        foot: &foot_file,
    };
    let mut effects = Vec::new();
    for (i, e) in spec.effects.iter().enumerate() {
        effects.extend(e.build(&ctx).map_err(|r| {
            ModelError::invalid(model_path, format!("effects[{i}]"), r.to_string())
        })?);
    }
    Ok(effects)
}

/// An effect on the muscle-torque generators needs a model driven by them.
fn check_actuator_effects(
    actuation: &Actuation,
    effects: &[Box<dyn DynEffect>],
    model_path: &Path,
) -> Result<(), ModelError> {
    if !matches!(actuation, Actuation::Mtg(_)) {
        if let Some(i) = effects.iter().position(|e| e.is_actuator()) {
            return Err(ModelError::invalid(
                model_path,
                format!("effects[{i}]"),
                format!(
                    "'{}' changes the muscle-torque generators, and this model is driven by joint torques; use a model with \"actuators\": {{\"type\": \"muscle_torque_generators\", …}}",
                    effects[i].kind()
                ),
            ));
        }
    }
    Ok(())
}

/// The effects' parameters in order.
struct EffectParameters {
    /// Every effect's parameters, effect by effect.
    params: Vec<ParamSpec>,
    /// The index of each effect's first parameter.
    offsets: Vec<usize>,
    /// The indices of the free parameters.
    free: Vec<usize>,
}

/// The effects' parameters; a name two effects define is an error.
fn effect_parameters(
    effects: &[Box<dyn DynEffect>],
    model_path: &Path,
) -> Result<EffectParameters, ModelError> {
    let mut params = Vec::new();
    let mut effect_offsets = Vec::new();
    for e in effects {
        effect_offsets.push(params.len());
        params.extend(e.parameters().iter().cloned());
    }
    for w in 0..params.len() {
        if params[..w].iter().any(|p| p.name == params[w].name) {
            return Err(ModelError::invalid(
                model_path,
                "effects",
                format!("parameter '{}' is defined by two effects", params[w].name),
            ));
        }
    }
    let free = params
        .iter()
        .enumerate()
        .filter(|(_, p)| p.free)
        .map(|(i, _)| i)
        .collect();
    Ok(EffectParameters {
        params,
        offsets: effect_offsets,
        free,
    })
}

/// Per contact, the effects that act on it (see the fields of [`GaitModel`] of the same
/// meaning).
struct ContactSlots {
    /// The effect that makes its normal contact compliant.
    compliant: Vec<Option<usize>>,
    /// The effect whose parameters replace its volumetric law, and the primitive's slot.
    volumetric: Vec<Option<(usize, usize)>>,
    /// The effect whose parameters replace its geometry, and the primitive's offset.
    geometry: Vec<Option<(usize, usize)>>,
}

impl ContactSlots {
    fn new(contacts: &[Contact], effects: &[Box<dyn DynEffect>]) -> Self {
        let compliant = contacts
            .iter()
            .map(|c| {
                effects.iter().position(|e| {
                    e.compliant_primitive()
                        .is_some_and(|p| c.name.split_once('.').is_some_and(|(_, n)| n == p))
                })
            })
            .collect();
        let volumetric = contacts
            .iter()
            .map(|c| {
                let (_, name) = c.name.split_once('.')?;
                effects.iter().enumerate().find_map(|(e, eff)| {
                    let slot = eff.volumetric_primitives().iter().position(|p| p == name)?;
                    Some((e, slot))
                })
            })
            .collect();
        let geometry = contacts
            .iter()
            .map(|c| {
                let (_, name) = c.name.split_once('.')?;
                effects.iter().enumerate().find_map(|(e, eff)| {
                    let &(_, offset) = eff.geometry_primitives().iter().find(|p| p.0 == name)?;
                    Some((e, offset))
                })
            })
            .collect();
        Self {
            compliant,
            volumetric,
            geometry,
        }
    }
}
