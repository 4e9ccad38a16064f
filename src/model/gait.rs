//! The assembled planar gait model: 9-DoF body, two feet of contact primitives,
//! actuators and effects; forward dynamics with contact, and the impact map.
//!
//! Forward dynamics solve the index-reduced DAE (seed eq. 1–2)
//! $$\begin{bmatrix} M & G^T \\ G & 0\end{bmatrix}\begin{bmatrix}\ddot q \\ -\lambda\end{bmatrix}
//!   = \begin{bmatrix}\tau - c \\ b\end{bmatrix},$$
//! by Cholesky factors of $M$ and of $G M^{-1} G^T$ (a rank-deficient $G$, i.e. an
//! over-constrained foot, is reported, never silently regularised). Row $i$ of $G$ is
//! $e_i^T J_P$, the velocity of the foot's material point at the contact point $P$ along
//! the ground normal or tangent, and
//! $b_i = -\dot G_i\dot q - 2\alpha G_i\dot q - \beta^2\phi_i$ (normal) or
//! $b_i = -\dot G_i\dot q - \gamma G_i\dot q$ (tangential), with
//! $\dot G_i\dot q = e_i^T\big(a_P + \omega^2(\hat z\times d' + d)\big)$, where $a_P$ is the
//! material acceleration of $P$ at $\ddot q = 0$, $d(\psi)$ the offset of $P$ from the
//! primitive's centre and $d'$ its derivative in the foot angle (the contact point moves
//! over the foot surface while it rolls). $\lambda$ is the ground force on the foot at $P$
//! (N) along the row's direction.

use super::actuators::{Joint as MtgJoint, JointActuatorSet};
use super::ad::{self, AdChunk};
use super::anthropometry;
use super::effects::{
    DynEffect, EffectState, MeasurementAdjust, ModelAdjust, ModelScalar, ParamSpec,
};
use super::error::{DynamicsError, ModelError};
use super::geometry::Shape;
use super::linalg::{cholesky, cholesky_solve};
use super::multibody::{add, dot, lift, perp, scale, Body, Inertia, Joint, Kinematics, Tree, V2};
use super::spec::{self, ActuatorSpec, BodySpec, ContactSettings, FootSpec, ModelSpec, Segments};
use super::Scalar;
use crate::integrate::{ControlledOde, OdeError};
use num_dual::Dual;
use std::path::Path;

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

/// A contact primitive mounted on one foot.
#[derive(Debug, Clone, PartialEq)]
pub struct Contact {
    /// `r.NAME` or `l.NAME`.
    pub name: String,
    /// Which foot.
    pub side: Side,
    /// Body index of the foot it is fixed to.
    pub body: usize,
    /// Geometry in the foot frame.
    pub shape: Shape,
}

/// Direction of one constraint row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RowKind {
    /// Along the ground normal (contact): force λₙ, position error φ.
    Normal,
    /// Along the ground tangent (rolling without slipping): force λₜ.
    Tangential,
}

/// One active constraint row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ConstraintRow {
    /// Index into [`GaitModel::contacts`].
    pub contact: usize,
    /// Direction.
    pub kind: RowKind,
}

/// A set of active foot-ground constraints (one continuous phase's contact state).
#[derive(Debug, Clone, PartialEq)]
pub struct ConstraintSet {
    /// Name for messages.
    pub name: String,
    /// The rows, in multiplier order.
    pub rows: Vec<ConstraintRow>,
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
    params: Vec<ParamSpec>,
    free: Vec<usize>,
}

/// The generalised forces of the dynamics by source (N·m or N per coordinate).
#[derive(Debug, Clone, PartialEq)]
pub struct ForceParts {
    /// The actuators: muscle-torque generators with their passive damping, or the joint
    /// torques.
    pub actuators: Vec<f64>,
    /// The residual actuators (zero without them).
    pub residual: Vec<f64>,
    /// Each effect's, by its kind.
    pub effects: Vec<(String, Vec<f64>)>,
}

/// Quantities of one dynamics evaluation that reports need (f64 only).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct ContactReport {
    /// World contact point of each row's primitive (m).
    pub points: Vec<[f64; 2]>,
    /// Constraint force along each row (N).
    pub lambda: Vec<f64>,
    /// Normal position error φ of each row's primitive (m; meaningful on normal rows;
    /// 0 on a compliant contact's normal row, whose depth is its pad's compression).
    pub position_error: Vec<f64>,
    /// Velocity error `G q̇` of each row (m/s; 0 on a compliant contact's normal row).
    pub velocity_error: Vec<f64>,
    /// Part of λ caused by the Baumgarte terms (N).
    pub baumgarte_force: Vec<f64>,
}

/// Ground reaction force and centre of pressure of one foot.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct FootLoad {
    /// Tangential (forward +) force on the foot (N).
    pub fx: f64,
    /// Normal (up +) force on the foot (N).
    pub fy: f64,
    /// Centre of pressure x (m): normal-force-weighted mean of the contact points; NaN
    /// when the foot carries no normal force.
    pub cop_x: f64,
}

impl GaitModel {
    /// Build the model from a model file and a foot file.
    pub fn load(model_path: &Path, foot_path: &Path) -> Result<Self, ModelError> {
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
        let mut spec = ModelSpec::load(model_path)?;
        for e in extra {
            if let Some(j) = spec.effects.iter().position(|o| o.overlaps(e)) {
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
    pub fn set_parameter_value(&mut self, name: &str, value: f64) -> Result<(), String> {
        let p = self
            .params
            .iter_mut()
            .find(|p| p.name == name)
            .ok_or_else(|| format!("the model has no parameter '{name}'"))?;
        if !(value.is_finite() && value >= p.lower && value <= p.upper) {
            return Err(format!(
                "parameter '{name}': {value} is outside its bounds [{}, {}]",
                p.lower, p.upper
            ));
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
        let seg = match &spec.body {
            BodySpec::Explicit { segments } => segments.clone(),
            BodySpec::OpensimModel { file, lumbar } => {
                spec::opensim_segments(&spec::relative_to(model_path, file), *lumbar)?
            }
            BodySpec::DeLeva { mass, height, sex } => {
                let p = anthropometry::de_leva_planar(*mass, *height, *sex)
                    .map_err(|r| ModelError::invalid(model_path, "body", r))?;
                segments_from_de_leva(&p)
            }
        };
        let tree = Tree::new(build_bodies(&seg))
            .map_err(|r| ModelError::invalid(model_path, "body", r))?;
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
                });
            }
        }
        let actuation = match &spec.actuators {
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
                    _ => estimated_stature(&seg),
                });
                let mut set = JointActuatorSet::anderson2007_young_male_for(mass, height)
                    .scaled(*strength_scale);
                set.eta = *eta;
                set.activation.tau_activation = *tau_activation;
                set.activation.tau_deactivation = *tau_deactivation;
                set.validate()
                    .map_err(|r| ModelError::invalid(model_path, "actuators", r))?;
                Actuation::Mtg(set)
            }
            ActuatorSpec::JointTorques {
                max_torque,
                reference_torque,
            } => Actuation::Torques {
                max_torque: *max_torque,
                reference_torque: *reference_torque,
            },
        };
        let coords: Vec<String> = COORDINATES.iter().map(|s| s.to_string()).collect();
        let bodies: Vec<String> = tree.bodies().iter().map(|b| b.name.clone()).collect();
        let primitives: Vec<String> = foot.primitives.iter().map(|p| p.name.clone()).collect();
        let ctx = super::effects::BuildContext {
            coordinates: &coords,
            bodies: &bodies,
            primitives: &primitives,
        };
        let mut effects = Vec::new();
        for (i, e) in spec.effects.iter().enumerate() {
            effects.extend(
                e.build(&ctx)
                    .map_err(|r| ModelError::invalid(model_path, format!("effects[{i}]"), r))?,
            );
        }
        let mut params = Vec::new();
        let mut effect_offsets = Vec::new();
        for e in &effects {
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
        let compliant = contacts
            .iter()
            .map(|c| {
                effects.iter().position(|e| {
                    e.compliant_primitive()
                        .is_some_and(|p| c.name.split_once('.').is_some_and(|(_, n)| n == p))
                })
            })
            .collect();
        let model = Self {
            name: spec.name.clone(),
            tree,
            gravity: spec.gravity,
            contacts,
            foot_name: foot.name.clone(),
            actuation,
            contact_settings: spec.contact,
            effects,
            residuals: None,
            effect_offsets,
            compliant,
            params,
            free,
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
            return Err(ModelError::invalid(
                foot_path,
                "primitives",
                format!(
                    "no primitive reaches below the ankle (lowest point {lowest:.4} m above it in the neutral pose), \
                     so the foot cannot touch the ground; primitive positions are in the ankle frame, y up"
                ),
            ));
        }
        Ok(())
    }

    /// The multibody tree.
    pub fn tree(&self) -> &Tree {
        &self.tree
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

    /// Add residual actuators (seed 003's residual reduction): a generalised force on
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

    /// Index of a contact by name (`r.heel`).
    pub fn contact_index(&self, name: &str) -> Option<usize> {
        self.contacts.iter().position(|c| c.name == name)
    }

    /// Build a constraint set from `(contact name, rolling)` pairs: every listed contact
    /// gets a normal row, and a tangential (rolling) row where `rolling` is true.
    pub fn constraint_set(
        &self,
        name: &str,
        contacts: &[(&str, bool)],
    ) -> Result<ConstraintSet, String> {
        let mut rows = Vec::new();
        for (i, (c, rolling)) in contacts.iter().enumerate() {
            let idx = self.contact_index(c).ok_or_else(|| {
                let known: Vec<&str> = self.contacts.iter().map(|c| c.name.as_str()).collect();
                format!(
                    "constraint set '{name}': unknown contact '{c}' (this foot has: {})",
                    known.join(", ")
                )
            })?;
            if contacts[..i].iter().any(|(o, _)| o == c) {
                return Err(format!(
                    "constraint set '{name}': contact '{c}' is listed twice"
                ));
            }
            if *rolling {
                rows.push(ConstraintRow {
                    contact: idx,
                    kind: RowKind::Tangential,
                });
            }
            rows.push(ConstraintRow {
                contact: idx,
                kind: RowKind::Normal,
            });
        }
        Ok(ConstraintSet {
            name: name.to_string(),
            rows,
        })
    }

    /// Full parameter vector in scalar `S`: fixed values as constants, free ones from θ.
    fn full_params<S: Scalar>(&self, theta: &[S]) -> Vec<S> {
        debug_assert_eq!(
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

    fn effect_params<'a, S>(&self, p: &'a [S], e: usize) -> &'a [S] {
        let start = self.effect_offsets[e];
        &p[start..start + self.effects[e].parameters().len()]
    }

    /// How the measurements relate to the model under the measurement effects (zero
    /// offsets without any).
    pub fn measurement_adjust<S: ModelScalar>(&self, theta: &[S]) -> MeasurementAdjust<S> {
        let p = self.full_params(theta);
        let mut m = MeasurementAdjust {
            force_time_offset: S::c(0.0),
            cop_offset: S::c(0.0),
        };
        for e in 0..self.effects.len() {
            S::measurement(self.effects[e].as_ref(), self.effect_params(&p, e), &mut m);
        }
        m
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

    /// The generalised forces of [`dynamics`](Self::dynamics) split by source, at state
    /// `x = (q, q̇, a)`, controls `u` and free parameters `theta` (N·m or N per
    /// coordinate): the actuators (muscle-torque generators with their passive damping, or
    /// the joint torques), the residual actuators, and each effect by its kind.
    pub fn generalized_force_parts(&self, x: &[f64], u: &[f64], theta: &[f64]) -> ForceParts {
        let nq = self.nq();
        let (q, qd, a) = (&x[..nq], &x[nq..2 * nq], &x[2 * nq..]);
        let p = self.full_params(theta);
        let mut act = vec![0.0; nq];
        match &self.actuation {
            Actuation::Mtg(set) => {
                for (k, &(c, joint)) in LEG_JOINTS.iter().enumerate() {
                    act[c] += set.joint_torque(joint, a[2 * k], a[2 * k + 1], q[c], qd[c]);
                }
            }
            Actuation::Torques {
                reference_torque, ..
            } => {
                for (k, &(c, _)) in LEG_JOINTS.iter().enumerate() {
                    act[c] += u[k] * *reference_torque;
                }
            }
        }
        let mut residual = vec![0.0; nq];
        if let Some(scales) = &self.residuals {
            let base = self.nu_actuators();
            for (i, &sc) in scales.iter().enumerate() {
                residual[i] = u[base + i] * sc;
            }
        }
        let effects = (0..self.effects.len())
            .map(|e| {
                let mut tau = vec![0.0; nq];
                f64::forces(
                    self.effects[e].as_ref(),
                    self.effect_params(&p, e),
                    EffectState { q, qd },
                    &mut tau,
                );
                (self.effects[e].kind().to_string(), tau)
            })
            .collect();
        ForceParts {
            actuators: act,
            residual,
            effects,
        }
    }

    /// Generalised joint forces of the actuators (and passive damping) and effects.
    fn generalized_forces<S: ModelScalar>(
        &self,
        q: &[S],
        qd: &[S],
        a: &[S],
        u: &[S],
        p: &[S],
    ) -> Vec<S> {
        let mut tau = vec![S::c(0.0); self.nq()];
        match &self.actuation {
            Actuation::Mtg(set) => {
                for (k, &(c, joint)) in LEG_JOINTS.iter().enumerate() {
                    tau[c] += set.joint_torque(joint, a[2 * k], a[2 * k + 1], q[c], qd[c]);
                }
            }
            Actuation::Torques {
                reference_torque, ..
            } => {
                for (k, &(c, _)) in LEG_JOINTS.iter().enumerate() {
                    tau[c] += u[k] * S::c(*reference_torque);
                }
            }
        }
        if let Some(scales) = &self.residuals {
            let base = self.nu_actuators();
            for (i, &sc) in scales.iter().enumerate() {
                tau[i] += u[base + i] * sc;
            }
        }
        for e in 0..self.effects.len() {
            S::forces(
                self.effects[e].as_ref(),
                self.effect_params(p, e),
                EffectState { q, qd },
                &mut tau,
            );
        }
        tau
    }

    /// Contact point `P`, offset `d` and `d' = ∂d/∂ψ` of contact `c` (world).
    fn contact_geometry<S: Scalar>(
        &self,
        k: &Kinematics<S>,
        c: &Contact,
        n: V2<S>,
    ) -> (V2<S>, V2<S>, V2<S>) {
        let centre = self.tree.point(k, c.body, lift(c.shape.centre()));
        let psi = Dual::new(k.angle[c.body], S::c(1.0));
        let nd = [Dual::from_re(n[0]), Dual::from_re(n[1])];
        let dd = c.shape.contact_offset(psi, nd);
        let d = [dd[0].re, dd[1].re];
        let d1 = [dd[0].eps, dd[1].eps];
        (add(centre, d), d, d1)
    }

    /// Forward dynamics `ẋ = f(x, u, θ)` under constraint set `set`. Returns `ẋ` and
    /// the constraint forces λ (one per row). With `report`, also fills contact details.
    pub fn dynamics<S: ModelScalar>(
        &self,
        set: &ConstraintSet,
        x: &[S],
        u: &[S],
        theta: &[S],
        xdot: &mut [S],
        lambda: &mut [S],
        report: Option<&mut ContactReport>,
    ) -> Result<(), DynamicsError> {
        let nq = self.nq();
        let (q, rest) = x.split_at(nq);
        let (qd, a) = rest.split_at(nq);
        let p = self.full_params(theta);
        let (inertia, gravity, ground_h, n) = self.adjusted(&p);
        let k = self.tree.kinematics(q, qd);
        let mut m = vec![S::c(0.0); nq * nq];
        let mut c = vec![S::c(0.0); nq];
        self.tree
            .mass_matrix_and_bias(&k, &inertia, gravity, &mut m, &mut c);
        let tau = self.generalized_forces(q, qd, a, u, &p);
        cholesky(&mut m, nq, 1e-14).map_err(|e| DynamicsError::MassMatrix { pivot: e.pivot })?;
        let mut qdd: Vec<S> = tau.iter().zip(&c).map(|(t, c)| *t - *c).collect();
        cholesky_solve(&m, nq, &mut qdd);

        let nc = set.rows.len();
        if nc > 0 {
            let t = [n[1], -n[0]];
            let cs = &self.contact_settings;
            let mut g = vec![S::c(0.0); nc * nq];
            let mut b = vec![S::c(0.0); nc];
            let mut b_baum = vec![0.0; nc];
            let mut jp = vec![S::c(0.0); 2 * nq];
            let mut rep_rows = Vec::new();
            // geometry once per contact (a rolling contact has two rows)
            let mut geo: Vec<(usize, V2<S>, V2<S>)> = Vec::with_capacity(nc);
            // compliant normal rows: an explicit force, not a constraint
            let mut compliant_force = vec![S::c(0.0); nq];
            let mut rigid = Vec::with_capacity(nc);
            for (r, row) in set.rows.iter().enumerate() {
                let contact = &self.contacts[row.contact];
                let (pt, bias) = match geo.iter().find(|g| g.0 == row.contact) {
                    Some(&(_, pt, bias)) => (pt, bias),
                    None => {
                        let (pt, d, d1) = self.contact_geometry(&k, contact, n);
                        let (_, acc) = self.tree.point_motion(&k, contact.body, pt);
                        let w = k.omega[contact.body];
                        let bias = add(acc, scale(add(perp(d1), d), w * w));
                        geo.push((row.contact, pt, bias));
                        (pt, bias)
                    }
                };
                let gdot_qd_vec = bias;
                self.tree.point_jacobian(&k, contact.body, pt, &mut jp);
                let e = if row.kind == RowKind::Normal { n } else { t };
                for j in 0..nq {
                    g[r * nq + j] = e[0] * jp[j] + e[1] * jp[nq + j];
                }
                let gqd: S = (0..nq).map(|j| g[r * nq + j] * qd[j]).sum();
                let phi = dot(n, pt) - ground_h;
                rep_rows.push(([pt[0].value(), pt[1].value()], phi.value(), gqd.value()));
                if let (RowKind::Normal, Some(eff)) = (row.kind, self.compliant[row.contact]) {
                    // depth below the ground and its rate: the pad's compression
                    lambda[r] = S::normal_force(
                        self.effects[eff].as_ref(),
                        self.effect_params(&p, eff),
                        -phi,
                        -gqd,
                    );
                    for j in 0..nq {
                        compliant_force[j] += g[r * nq + j] * lambda[r];
                    }
                    continue;
                }
                let stab = match row.kind {
                    RowKind::Normal => {
                        gqd * (2.0 * cs.baumgarte_alpha)
                            + phi * (cs.baumgarte_beta * cs.baumgarte_beta)
                    }
                    RowKind::Tangential => gqd * cs.baumgarte_gamma,
                };
                b[r] = -dot(e, gdot_qd_vec) - stab;
                b_baum[r] = -stab.value();
                rigid.push(r);
            }
            if rigid.len() < nc {
                cholesky_solve(&m, nq, &mut compliant_force);
                for (a, f) in qdd.iter_mut().zip(&compliant_force) {
                    *a += *f;
                }
            }
            let nr = rigid.len();
            let mut b_baum_rigid = vec![0.0; nr];
            if nr > 0 {
                let g_rigid: Vec<S> = rigid
                    .iter()
                    .flat_map(|&r| g[r * nq..(r + 1) * nq].iter().copied())
                    .collect();
                let (y, amat, amat_f64) = schur_complement(&m, nq, &g_rigid, nr, &set.name)?;
                let mut lam_rigid: Vec<S> = rigid
                    .iter()
                    .enumerate()
                    .map(|(i, &r)| {
                        let gq: S = (0..nq).map(|l| g_rigid[i * nq + l] * qdd[l]).sum();
                        b[r] - gq
                    })
                    .collect();
                cholesky_solve(&amat, nr, &mut lam_rigid);
                for i in 0..nr {
                    for l in 0..nq {
                        qdd[l] += y[i * nq + l] * lam_rigid[i];
                    }
                    lambda[rigid[i]] = lam_rigid[i];
                }
                if report.is_some() {
                    let mut af = amat_f64;
                    b_baum_rigid = rigid.iter().map(|&r| b_baum[r]).collect();
                    if cholesky(&mut af, nr, 1e-10).is_ok() {
                        cholesky_solve(&af, nr, &mut b_baum_rigid);
                    }
                }
            }
            if let Some(rep) = report {
                let mut baum = vec![0.0; nc];
                for (i, &r) in rigid.iter().enumerate() {
                    baum[r] = b_baum_rigid[i];
                }
                // a compliant row's depth is its pad's compression, not a constraint error
                let rigid_or_zero = |r: usize, v: f64| {
                    if self.is_compliant_row(&set.rows[r]) {
                        0.0
                    } else {
                        v
                    }
                };
                rep.points = rep_rows.iter().map(|r| r.0).collect();
                rep.position_error = rep_rows
                    .iter()
                    .enumerate()
                    .map(|(r, x)| rigid_or_zero(r, x.1))
                    .collect();
                rep.velocity_error = rep_rows
                    .iter()
                    .enumerate()
                    .map(|(r, x)| rigid_or_zero(r, x.2))
                    .collect();
                rep.lambda = lambda.iter().map(|v| v.value()).collect();
                rep.baumgarte_force = baum;
            }
        } else if let Some(rep) = report {
            *rep = ContactReport::default();
        }

        xdot[..nq].copy_from_slice(qd);
        xdot[nq..2 * nq].copy_from_slice(&qdd);
        if let Actuation::Mtg(set) = &self.actuation {
            for i in 0..self.na() {
                xdot[2 * nq + i] = set.activation.rate(u[i], a[i]);
            }
        }
        Ok(())
    }

    /// Plastic impact map: post-impact velocities and impulses (N·s, one per row) for
    /// the constraint set active after the impact,
    /// $[M\;G^T;\,G\;0][\dot q^+; -\Lambda] = [M\dot q^-; 0]$.
    pub fn impact<S: ModelScalar>(
        &self,
        set_after: &ConstraintSet,
        q: &[S],
        qd_minus: &[S],
        theta: &[S],
    ) -> Result<(Vec<S>, Vec<S>), DynamicsError> {
        let nq = self.nq();
        let p = self.full_params(theta);
        let (inertia, gravity, _, n) = self.adjusted(&p);
        let k = self.tree.kinematics(q, qd_minus);
        let mut m = vec![S::c(0.0); nq * nq];
        let mut c = vec![S::c(0.0); nq];
        self.tree
            .mass_matrix_and_bias(&k, &inertia, gravity, &mut m, &mut c);
        cholesky(&mut m, nq, 1e-14).map_err(|e| DynamicsError::MassMatrix { pivot: e.pivot })?;
        // a compliant normal contact takes no impulse: its pad is compressed from here on
        let (rigid, idx) = self.rigid_rows(set_after);
        let g = self.constraint_jacobian(&k, &rigid, n);
        let nc = rigid.rows.len();
        let mut qd_plus = qd_minus.to_vec();
        let mut impulses = vec![S::c(0.0); set_after.rows.len()];
        if nc == 0 {
            return Ok((qd_plus, impulses));
        }
        let (y, amat, _) = schur_complement(&m, nq, &g, nc, &set_after.name)?;
        let mut imp: Vec<S> = (0..nc)
            .map(|i| -(0..nq).map(|l| g[i * nq + l] * qd_minus[l]).sum::<S>())
            .collect();
        cholesky_solve(&amat, nc, &mut imp);
        for i in 0..nc {
            for l in 0..nq {
                qd_plus[l] += y[i * nq + l] * imp[i];
            }
            impulses[idx[i]] = imp[i];
        }
        Ok((qd_plus, impulses))
    }

    /// The rows of `set` that are rigid constraints (all but the normal rows of compliant
    /// contacts), and each one's index in `set`.
    pub fn rigid_rows(&self, set: &ConstraintSet) -> (ConstraintSet, Vec<usize>) {
        let idx: Vec<usize> = (0..set.rows.len())
            .filter(|&r| !self.is_compliant_row(&set.rows[r]))
            .collect();
        (
            ConstraintSet {
                name: set.name.clone(),
                rows: idx.iter().map(|&r| set.rows[r]).collect(),
            },
            idx,
        )
    }

    /// Whether `row` is the normal row of a compliant contact (a force, not a constraint).
    pub fn is_compliant_row(&self, row: &ConstraintRow) -> bool {
        row.kind == RowKind::Normal && self.compliant[row.contact].is_some()
    }

    /// Whether contact `c` has a compliant normal contact.
    pub fn is_compliant(&self, c: usize) -> bool {
        self.compliant[c].is_some()
    }

    fn constraint_jacobian<S: Scalar>(
        &self,
        k: &Kinematics<S>,
        set: &ConstraintSet,
        n: V2<S>,
    ) -> Vec<S> {
        let nq = self.nq();
        let t = [n[1], -n[0]];
        let mut g = vec![S::c(0.0); set.rows.len() * nq];
        let mut jp = vec![S::c(0.0); 2 * nq];
        for (r, row) in set.rows.iter().enumerate() {
            let contact = &self.contacts[row.contact];
            let (pt, _, _) = self.contact_geometry(k, contact, n);
            self.tree.point_jacobian(k, contact.body, pt, &mut jp);
            let e = if row.kind == RowKind::Normal { n } else { t };
            for j in 0..nq {
                g[r * nq + j] = e[0] * jp[j] + e[1] * jp[nq + j];
            }
        }
        g
    }

    /// Index of a row of `set` that is linearly dependent on the rows before it, at a
    /// neutral standing pose (dependence of contact rows on one rigid foot does not change
    /// with the pose), or `None`.
    pub fn dependent_row(&self, set: &ConstraintSet) -> Option<usize> {
        let q = [0.0, 1.0, 0.0, 0.1, -0.2, 0.05, -0.1, -0.3, 0.1];
        let nq = self.nq();
        // only rigid rows constrain (a compliant contact's normal row is a force)
        let (set, idx) = &self.rigid_rows(set);
        let g = self.constraint_jacobian_at(set, &q[..nq.min(9)], &self.theta0());
        let nc = set.rows.len();
        let mut a = vec![0.0; nc * nc];
        for i in 0..nc {
            for j in 0..nc {
                a[i * nc + j] = (0..nq).map(|l| g[i * nq + l] * g[j * nq + l]).sum();
            }
        }
        cholesky(&mut a, nc, 1e-10).err().map(|e| idx[e.pivot])
    }

    /// Project a state onto the constraint manifold of `set` (seed §3.6: the initial
    /// guess is "polished to satisfy the foot-ground constraints"): positions by
    /// minimum-norm Gauss–Newton steps on the normal gaps φ = 0, velocities by the
    /// M-orthogonal projection onto `G q̇ = 0` (the plastic impact map). Returns the
    /// projected `(q, q̇)` and the largest remaining |φ| (m).
    pub fn project(
        &self,
        set: &ConstraintSet,
        q: &[f64],
        qd: &[f64],
        theta: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>, f64), DynamicsError> {
        let nq = self.nq();
        let mut q = q.to_vec();
        // compliant contacts are left where they are (their pad holds them, not a constraint)
        let normal: Vec<usize> = (0..set.rows.len())
            .filter(|&r| {
                set.rows[r].kind == RowKind::Normal && !self.is_compliant_row(&set.rows[r])
            })
            .collect();
        let nn = normal.len();
        let mut worst = 0.0;
        for _ in 0..50 {
            let g = self.constraint_jacobian_at(set, &q, theta);
            let phi: Vec<f64> = normal
                .iter()
                .map(|&r| self.contact_point(set.rows[r].contact, &q, theta).1)
                .collect();
            worst = phi.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if worst < 1e-12 || nn == 0 {
                break;
            }
            let mut a = vec![0.0; nn * nn];
            for (i, &ri) in normal.iter().enumerate() {
                for (j, &rj) in normal.iter().enumerate() {
                    a[i * nn + j] = (0..nq).map(|l| g[ri * nq + l] * g[rj * nq + l]).sum();
                }
            }
            cholesky(&mut a, nn, 1e-12).map_err(|e| DynamicsError::OverConstrained {
                set: set.name.clone(),
                row: e.pivot,
            })?;
            let mut y = phi.clone();
            cholesky_solve(&a, nn, &mut y);
            for (i, &ri) in normal.iter().enumerate() {
                for l in 0..nq {
                    q[l] -= g[ri * nq + l] * y[i];
                }
            }
        }
        let qd = if set.rows.is_empty() {
            qd.to_vec()
        } else {
            self.impact(set, &q, qd, theta)?.0
        };
        Ok((q, qd, worst))
    }

    /// Constraint Jacobian `G` (rows × nq, row-major) of `set` at `q` (f64).
    pub fn constraint_jacobian_at(
        &self,
        set: &ConstraintSet,
        q: &[f64],
        theta: &[f64],
    ) -> Vec<f64> {
        let p = self.full_params(theta);
        let (_, _, _, n) = self.adjusted(&p);
        let k = self.tree.kinematics(q, &vec![0.0; self.nq()]);
        self.constraint_jacobian(&k, set, n)
    }

    /// World contact point and normal gap φ (m) of contact `c` at `q`.
    pub fn contact_point(&self, c: usize, q: &[f64], theta: &[f64]) -> ([f64; 2], f64) {
        self.contact_point_generic(c, q, theta)
    }

    /// Normal gap φ (m) of contact `c` at `q`, over any model scalar (for exact
    /// derivatives of clearance and landing constraints).
    pub fn gap<S: ModelScalar>(&self, c: usize, q: &[S], theta: &[S]) -> S {
        self.contact_point_generic(c, q, theta).1
    }

    /// World contact point (m) and normal gap φ (m) of contact `c` at `q`, over any model
    /// scalar (for exact derivatives of a cost on the contact point).
    pub fn contact_point_generic<S: ModelScalar>(
        &self,
        c: usize,
        q: &[S],
        theta: &[S],
    ) -> (V2<S>, S) {
        let p = self.full_params(theta);
        let (_, _, h, n) = self.adjusted(&p);
        let k = self.tree.kinematics(q, &vec![S::c(0.0); self.nq()]);
        let (pt, _, _) = self.contact_geometry(&k, &self.contacts[c], n);
        (pt, dot(n, pt) - h)
    }

    /// Velocity `G q̇` (m/s) of every row of `set` at the state `x = (q, q̇, …)`: the
    /// tangential or normal velocity of each foot's material point at its contact point,
    /// which the Baumgarte rows drive to zero but do not hold (a state on the contact
    /// manifold needs `G q̇ = 0` as a constraint of its own).
    pub fn constraint_velocity<S: ModelScalar>(
        &self,
        set: &ConstraintSet,
        x: &[S],
        theta: &[S],
    ) -> Vec<S> {
        let nq = self.nq();
        let p = self.full_params(theta);
        let (_, _, _, n) = self.adjusted(&p);
        let k = self.tree.kinematics(&x[..nq], &vec![S::c(0.0); nq]);
        let g = self.constraint_jacobian(&k, set, n);
        (0..set.rows.len())
            .map(|r| (0..nq).map(|l| g[r * nq + l] * x[nq + l]).sum())
            .collect()
    }

    /// Mass matrix (row-major) and bias forces at `(q, q̇)`.
    pub fn mass_matrix_and_bias(
        &self,
        q: &[f64],
        qd: &[f64],
        theta: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        let nq = self.nq();
        let p = self.full_params(theta);
        let (inertia, gravity, _, _) = self.adjusted(&p);
        let k = self.tree.kinematics(q, qd);
        let mut m = vec![0.0; nq * nq];
        let mut c = vec![0.0; nq];
        self.tree
            .mass_matrix_and_bias(&k, &inertia, gravity, &mut m, &mut c);
        (m, c)
    }

    /// Kinetic and potential energy (J) at `(q, q̇)`.
    pub fn energy(&self, q: &[f64], qd: &[f64], theta: &[f64]) -> (f64, f64) {
        let p = self.full_params(theta);
        let (inertia, gravity, _, _) = self.adjusted(&p);
        let k = self.tree.kinematics(q, qd);
        self.tree.energy(&k, &inertia, gravity)
    }

    /// The ground at free parameters `theta` (a slope effect tilts it): its height h (m)
    /// and unit normal n, the ground being the points p with n·p = h.
    pub fn ground(&self, theta: &[f64]) -> (f64, [f64; 2]) {
        let p = self.full_params(theta);
        let (_, _, h, n) = self.adjusted(&p);
        (h, n)
    }

    /// World position of a point given in a body frame, at `q`.
    pub fn body_point(&self, body: usize, local: [f64; 2], q: &[f64]) -> [f64; 2] {
        let k = self.tree.kinematics(q, &vec![0.0; self.nq()]);
        self.tree.point(&k, body, local)
    }

    /// Per-foot ground reaction forces and centres of pressure from a report.
    pub fn foot_loads(&self, set: &ConstraintSet, rep: &ContactReport) -> [FootLoad; 2] {
        let mut out = [FootLoad::default(); 2];
        let mut moment = [0.0; 2];
        for (r, row) in set.rows.iter().enumerate() {
            let c = &self.contacts[row.contact];
            let s = if c.side == Side::Right { 0 } else { 1 };
            match row.kind {
                RowKind::Normal => {
                    out[s].fy += rep.lambda[r];
                    moment[s] += rep.lambda[r] * rep.points[r][0];
                }
                RowKind::Tangential => out[s].fx += rep.lambda[r],
            }
        }
        for s in 0..2 {
            out[s].cop_x = if out[s].fy.abs() > 1e-9 {
                moment[s] / out[s].fy
            } else {
                f64::NAN
            };
        }
        out
    }

    /// The inputs of `(x, u, θ)` that can appear in a second derivative of the dynamics
    /// or of anything computed from them (contact forces, ground loads), and how many of
    /// them lead as a group the dynamics are jointly affine in. All inputs can, except
    /// the excitations of muscle-torque generators without residual actuators: those
    /// enter only `ȧ = (e − a)/τ`, affinely with constant coefficients, so every second
    /// derivative involving them is exactly zero. The activations and the controls that
    /// remain (joint torques, residual actuators, excitations beside residuals) lead: the
    /// joint torques are linear in them at fixed (q, q̇, θ) (`s·τ₀·a·f^A(q)·f^V(q̇)`, or
    /// the control itself), the accelerations and contact forces are linear in the torques
    /// for a fixed contact set, and ȧ is linear in (e, a).
    pub fn curved_inputs(&self) -> (Vec<usize>, usize) {
        let (nq, nx, nu, nt) = (self.nq(), self.nx(), self.nu(), self.ntheta());
        let controls_affine =
            matches!(self.actuation, Actuation::Mtg(_)) && self.residuals.is_none();
        let mut order: Vec<usize> = (2 * nq..nx).collect();
        if !controls_affine {
            order.extend(nx..nx + nu);
        }
        let lead = order.len();
        order.extend(0..2 * nq);
        order.extend(nx + nu..nx + nu + nt);
        (order, lead)
    }

    /// Evaluate `ẋ` and its Jacobians with respect to `(x, u, θ)` by chunked forward AD;
    /// `jac` is nx × (nx + nu + nθ), column-major.
    pub fn dynamics_jacobian(
        &self,
        set: &ConstraintSet,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        xdot: &mut [f64],
        jac: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let (nx, nu, nt) = (self.nx(), self.nu(), theta.len());
        let mut lam = vec![AdChunk::from(0.0); set.rows.len()];
        match &self.actuation {
            // Excitations enter only the activation dynamics ȧ = rate(u, a): their columns
            // are diagonal and come from a scalar dual evaluation; AD runs over (x, θ) only
            // (residual actuators' controls enter the dynamics: the general path below).
            Actuation::Mtg(mtg) if self.residuals.is_none() => {
                let mut z = Vec::with_capacity(nx + nt);
                z.extend_from_slice(x);
                z.extend_from_slice(theta);
                let mut jz = vec![0.0; nx * (nx + nt)];
                let uc: Vec<AdChunk> = u.iter().map(|&v| AdChunk::from(v)).collect();
                ad::jacobian(
                    &z,
                    nx,
                    |zs, out| {
                        let (xs, ts) = zs.split_at(nx);
                        self.dynamics(set, xs, &uc, ts, out, &mut lam, None)
                    },
                    xdot,
                    &mut jz,
                )?;
                jac[..nx * nx].copy_from_slice(&jz[..nx * nx]);
                jac[nx * (nx + nu)..].copy_from_slice(&jz[nx * nx..]);
                let fu = &mut jac[nx * nx..nx * (nx + nu)];
                fu.iter_mut().for_each(|v| *v = 0.0);
                let a0 = 2 * self.nq();
                for i in 0..nu {
                    let e = num_dual::Dual64::new(u[i], 1.0);
                    let a = num_dual::Dual64::from(x[a0 + i]);
                    fu[i * nx + a0 + i] = mtg.activation.rate(e, a).eps;
                }
                Ok(())
            }
            _ => {
                let mut z = Vec::with_capacity(nx + nu + nt);
                z.extend_from_slice(x);
                z.extend_from_slice(u);
                z.extend_from_slice(theta);
                ad::jacobian(
                    &z,
                    nx,
                    |zs, out| {
                        let (xs, rest) = zs.split_at(nx);
                        let (us, ts) = rest.split_at(nu);
                        self.dynamics(set, xs, us, ts, out, &mut lam, None)
                    },
                    xdot,
                    jac,
                )
            }
        }
    }
}

impl GaitModel {
    /// Ground reaction force and CoP moment of each foot, generic in the scalar type:
    /// `[(fx, fy, m)]` for right and left, with `fx` the tangential and `fy` the normal
    /// force on the foot (N) and `m = Σ λₙ·x_P` (N·m) the normal-force moment about the
    /// origin, so that the centre of pressure is `m / fy` where `fy > 0`. Tracking costs use
    /// `m − x_cop·fy`, which weights the CoP error by the load and stays smooth at lift-off.
    pub fn foot_loads_generic<S: ModelScalar>(
        &self,
        set: &ConstraintSet,
        x: &[S],
        u: &[S],
        theta: &[S],
    ) -> Result<[(S, S, S); 2], DynamicsError> {
        let nq = self.nq();
        let mut xdot = vec![S::c(0.0); self.nx()];
        let mut lam = vec![S::c(0.0); set.rows.len()];
        self.dynamics(set, x, u, theta, &mut xdot, &mut lam, None)?;
        let p = self.full_params(theta);
        let (_, _, _, n) = self.adjusted(&p);
        let zeros = vec![S::c(0.0); nq];
        let k = self.tree.kinematics(&x[..nq], &zeros);
        let z = S::c(0.0);
        let mut out = [(z, z, z); 2];
        for (r, row) in set.rows.iter().enumerate() {
            let c = &self.contacts[row.contact];
            let s = if c.side == Side::Right { 0 } else { 1 };
            match row.kind {
                RowKind::Tangential => out[s].0 += lam[r],
                RowKind::Normal => {
                    let (pt, _, _) = self.contact_geometry(&k, c, n);
                    out[s].1 += lam[r];
                    out[s].2 += lam[r] * pt[0];
                }
            }
        }
        Ok(out)
    }
}

/// With the Cholesky factor of `M` and the constraint rows `G` (nc × nq, row-major):
/// `Y = M⁻¹Gᵀ` (row r of `y` = column r), the Cholesky factor of the Schur complement
/// `A = G M⁻¹ Gᵀ` and `A` itself in f64 (for reports). A dependent row of `G` is an
/// over-constrained contact set and is reported, never regularised.
#[allow(clippy::type_complexity)]
fn schur_complement<S: Scalar>(
    m_chol: &[S],
    nq: usize,
    g: &[S],
    nc: usize,
    set_name: &str,
) -> Result<(Vec<S>, Vec<S>, Vec<f64>), DynamicsError> {
    let mut y = g.to_vec();
    for r in 0..nc {
        cholesky_solve(m_chol, nq, &mut y[r * nq..(r + 1) * nq]);
    }
    let mut amat = vec![S::c(0.0); nc * nc];
    for i in 0..nc {
        for j in 0..nc {
            amat[i * nc + j] = (0..nq).map(|l| g[i * nq + l] * y[j * nq + l]).sum();
        }
    }
    let amat_f64: Vec<f64> = amat.iter().map(|v| v.value()).collect();
    cholesky(&mut amat, nc, 1e-10).map_err(|e| DynamicsError::OverConstrained {
        set: set_name.to_string(),
        row: e.pivot,
    })?;
    Ok((y, amat, amat_f64))
}

/// `ControlledOde` view of the model under one constraint set.
#[derive(Debug, Clone, Copy)]
pub struct GaitOde<'a> {
    /// The model.
    pub model: &'a GaitModel,
    /// Active constraints.
    pub set: &'a ConstraintSet,
}

fn ode_err(e: DynamicsError) -> OdeError {
    match e {
        DynamicsError::NonFinite { .. } => OdeError::Recoverable(e.to_string()),
        other => OdeError::Fatal(other.to_string()),
    }
}

impl ControlledOde for GaitOde<'_> {
    fn nx(&self) -> usize {
        self.model.nx()
    }
    fn nu(&self) -> usize {
        self.model.nu()
    }
    fn ntheta(&self) -> usize {
        self.model.ntheta()
    }
    fn f(&self, x: &[f64], u: &[f64], theta: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        let mut lam = vec![0.0; self.set.rows.len()];
        self.model
            .dynamics(self.set, x, u, theta, xdot, &mut lam, None)
            .map_err(ode_err)?;
        if xdot.iter().any(|v| !v.is_finite()) {
            return Err(OdeError::Recoverable("non-finite state derivative".into()));
        }
        Ok(())
    }
    fn weighted_hessian(
        &self,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        mu: &[f64],
        out: &mut [f64],
    ) -> Result<bool, OdeError> {
        let (nx, nu) = (self.model.nx(), self.model.nu());
        let mut xdot = vec![ad::AdNested::from(0.0); nx];
        let mut lam = vec![ad::AdNested::from(0.0); self.set.rows.len()];
        let z: Vec<f64> = x.iter().chain(u).chain(theta).copied().collect();
        let (curved, lead) = self.model.curved_inputs();
        ad::hessian_over(
            &z,
            &curved,
            lead,
            |zs| {
                let (xs, rest) = zs.split_at(nx);
                let (us, ts) = rest.split_at(nu);
                self.model
                    .dynamics(self.set, xs, us, ts, &mut xdot, &mut lam, None)?;
                Ok(xdot
                    .iter()
                    .zip(mu)
                    .fold(ad::AdNested::from(0.0), |acc, (f, m)| acc + *f * *m))
            },
            out,
        )
        .map_err(ode_err)?;
        if out.iter().any(|v| !v.is_finite()) {
            return Err(OdeError::Recoverable("non-finite Hessian".into()));
        }
        Ok(true)
    }
    fn f_jac(
        &self,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fu: &mut [f64],
        ftheta: &mut [f64],
    ) -> Result<(), OdeError> {
        let (nx, nu, nt) = (self.model.nx(), self.model.nu(), theta.len());
        let mut jac = vec![0.0; nx * (nx + nu + nt)];
        self.model
            .dynamics_jacobian(self.set, x, u, theta, xdot, &mut jac)
            .map_err(ode_err)?;
        fx.copy_from_slice(&jac[..nx * nx]);
        fu.copy_from_slice(&jac[nx * nx..nx * (nx + nu)]);
        ftheta.copy_from_slice(&jac[nx * (nx + nu)..]);
        if xdot.iter().chain(jac.iter()).any(|v| !v.is_finite()) {
            return Err(OdeError::Recoverable("non-finite derivative".into()));
        }
        Ok(())
    }
}

/// Stature (m) estimated from the hip→knee→ankle length with de Leva's (1996) male
/// reference proportions ((thigh + shank length) / stature = 862.5 / 1741 mm).
pub fn estimated_stature(s: &Segments) -> f64 {
    let len = |v: [f64; 2]| (v[0] * v[0] + v[1] * v[1]).sqrt();
    let t = &anthropometry::DE_LEVA_MALE;
    (len(s.knee_in_thigh) + len(s.ankle_in_shank)) * t.stature_mm
        / (t.thigh.length_mm + t.shank.length_mm)
}

/// The planar bodies of the 9-DoF model from segment parameters.
pub fn build_bodies(s: &Segments) -> Vec<Body> {
    let virt = |name: &str, parent: Option<usize>, axis: [f64; 2]| Body {
        name: name.into(),
        parent,
        joint: Joint::Prismatic { axis },
        joint_in_parent: [0.0, 0.0],
        mass: 0.0,
        com: [0.0, 0.0],
        izz: 0.0,
    };
    let seg = |name: String, parent: usize, at: [f64; 2], sp: &spec::SegmentSpec| Body {
        name,
        parent: Some(parent),
        joint: Joint::Revolute,
        joint_in_parent: at,
        mass: sp.mass,
        com: sp.com,
        izz: sp.izz,
    };
    let mut b = vec![
        virt("pelvis_x", None, [1.0, 0.0]),
        virt("pelvis_y", Some(0), [0.0, 1.0]),
    ];
    b.push(seg("hat".into(), 1, [0.0, 0.0], &s.hat));
    for side in ["r", "l"] {
        let base = b.len();
        b.push(seg(format!("thigh_{side}"), 2, s.hip_in_pelvis, &s.thigh));
        b.push(seg(
            format!("shank_{side}"),
            base,
            s.knee_in_thigh,
            &s.shank,
        ));
        b.push(seg(
            format!("foot_{side}"),
            base + 1,
            s.ankle_in_shank,
            &s.foot,
        ));
    }
    b
}

/// Horizontal distance heel → ankle as a fraction of foot length: 0.26, from the heel and
/// toe-tip markers of the OpenSim subject01 model (heel 0.075 m behind the ankle, toe tip
/// 0.216 m ahead of it, `data/opensim_subject01/model.json`).
pub const ANKLE_FROM_HEEL_FRACTION: f64 = 0.26;
/// Ankle height above the sole as a fraction of stature: 0.039 (Winter 2009,
/// *Biomechanics and Motor Control of Human Movement*, 4th ed., Fig. 4.1).
pub const ANKLE_HEIGHT_FRACTION: f64 = 0.039;

/// Segments of the planar model from de Leva (1996) parameters: HAT frame origin at the
/// hip midpoint, segments along their frames' −y axes; the foot's COM lies on the
/// heel→toe line at the documented height below the ankle.
pub fn segments_from_de_leva(p: &anthropometry::PlanarBodySegments) -> Segments {
    let down = |sp: &anthropometry::SegmentParams| spec::SegmentSpec {
        mass: sp.mass,
        com: [0.0, -sp.com_from_proximal],
        izz: sp.inertia_com,
    };
    let foot = &p.foot;
    // The ankle sits above the foot at a fixed fraction of the foot length from the heel.
    let ankle_from_heel = ANKLE_FROM_HEEL_FRACTION * foot.length;
    let ankle_height = ANKLE_HEIGHT_FRACTION * p.height;
    Segments {
        hat: spec::SegmentSpec {
            mass: p.hat.mass,
            com: [0.0, p.hat.com_from_proximal],
            izz: p.hat.inertia_com,
        },
        thigh: down(&p.thigh),
        shank: down(&p.shank),
        foot: spec::SegmentSpec {
            mass: foot.mass,
            com: [
                foot.com_from_proximal - ankle_from_heel,
                -0.5 * ankle_height,
            ],
            izz: foot.inertia_com,
        },
        hip_in_pelvis: [0.0, 0.0],
        knee_in_thigh: [0.0, -p.thigh.length],
        ankle_in_shank: [0.0, -p.shank.length],
    }
}
