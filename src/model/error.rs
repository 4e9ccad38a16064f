//! Errors of model construction and evaluation.

use std::path::PathBuf;

/// Failure to read, validate or assemble a model, foot or phase file.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// A foot that is neither a bundled foot nor an existing file.
    #[error("foot {path}: no such file; a foot is `ellipse`, `double-circle`, a bundled foot file ({bundled}) or the path of a foot file (JSON)")]
    NoFoot {
        /// The foot as given.
        path: PathBuf,
        /// The bundled foot files, comma-separated.
        bundled: String,
    },
    /// The file is not valid JSON or does not match the schema.
    #[error("{path}: {message} (line {line}, column {column})")]
    Json {
        /// File.
        path: PathBuf,
        /// serde's description, naming the field where it can.
        message: String,
        /// Line of the problem.
        line: usize,
        /// Column of the problem.
        column: usize,
    },
    /// A value is physically or logically invalid.
    #[error("{path}: field '{field}': {reason}")]
    Invalid {
        /// File (or `<memory>`).
        path: PathBuf,
        /// Dotted path of the field.
        field: String,
        /// What is wrong and what would be valid.
        reason: String,
    },
}

impl ModelError {
    /// The error of a foot none of whose primitives reaches below the ankle (`lowest`: its
    /// lowest point above the ankle in the neutral pose, m).
    pub(crate) fn foot_above_ankle(path: &std::path::Path, lowest: f64) -> Self {
        ModelError::invalid(
            path,
            "primitives",
            format!(
                "no primitive reaches below the ankle (lowest point {lowest:.4} m above it in the neutral pose), \
                 so the foot cannot touch the ground; primitive positions are in the ankle frame, y up"
            ),
        )
    }

    pub(crate) fn invalid(
        path: &std::path::Path,
        field: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        ModelError::Invalid {
            path: path.to_path_buf(),
            field: field.into(),
            reason: reason.into(),
        }
    }
}

/// Failure of one dynamics evaluation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// The mass matrix is not positive definite (non-physical inertias or state).
    #[error("mass matrix not positive definite at pivot {pivot}")]
    MassMatrix {
        /// Pivot index.
        pivot: usize,
    },
    /// The active constraint rows are linearly dependent: the body is over-constrained.
    #[error(
        "constraint set '{set}' over-constrains the body (row {row} is dependent on the others)"
    )]
    OverConstrained {
        /// Constraint set name.
        set: String,
        /// Dependent row.
        row: usize,
    },
    /// A state or input value is not finite.
    #[error("non-finite {what}")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
}

/// Why a contact primitive's shape is refused ([`Shape::validate`]).
///
/// [`Shape::validate`]: crate::model::geometry::Shape::validate
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {reason}")]
pub struct ShapeError {
    /// The offending field: `radius`, `semi_axes`, `centre`, `angle` or `position`.
    pub field: &'static str,
    /// What is wrong and what would be valid.
    pub reason: String,
}

/// Why bodies do not form a kinematic tree ([`Tree::new`]).
///
/// [`Tree::new`]: crate::model::multibody::Tree::new
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TreeError {
    /// A body's parent does not come before it.
    #[error(
        "body '{body}' (index {index}) has parent index {parent}, which does not come before it"
    )]
    ParentOrder {
        /// The body's name.
        body: String,
        /// Its index.
        index: usize,
        /// Its parent's index.
        parent: usize,
    },
    /// A prismatic joint's axis is not a unit vector.
    #[error("body '{body}': prismatic axis must be a unit vector")]
    PrismaticAxis {
        /// The body's name.
        body: String,
        /// The axis as given (parent frame).
        axis: [f64; 2],
    },
}

/// Why de Leva's tables cannot be scaled to a subject ([`de_leva_planar`] and kin).
///
/// [`de_leva_planar`]: crate::model::anthropometry::de_leva_planar
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnthropometryError {
    /// The body mass is not finite and positive.
    #[error("body mass must be finite and > 0, got {mass_kg}")]
    Mass {
        /// The body mass (kg).
        mass_kg: f64,
    },
    /// The height is not finite and positive.
    #[error("height must be finite and > 0, got {height_m}")]
    Height {
        /// The height (m).
        height_m: f64,
    },
}

/// Why an effect parameter's value cannot be set ([`GaitModel::set_parameter_value`]).
///
/// [`GaitModel::set_parameter_value`]: crate::model::GaitModel::set_parameter_value
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParameterError {
    /// No effect of the model has a parameter of this name.
    #[error("the model has no parameter '{name}'")]
    Unknown {
        /// The name asked for.
        name: String,
    },
    /// The value is not finite or lies outside the parameter's bounds.
    #[error("parameter '{name}': {value} is outside its bounds [{lower}, {upper}]")]
    OutOfBounds {
        /// The parameter.
        name: String,
        /// The value asked for (in the parameter's unit).
        value: f64,
        /// Its lower bound.
        lower: f64,
        /// Its upper bound.
        upper: f64,
    },
}

/// Why a constraint set cannot be built from contact names ([`GaitModel::constraint_set`]).
///
/// [`GaitModel::constraint_set`]: crate::model::GaitModel::constraint_set
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContactSetError {
    /// The foot has no contact of this name.
    #[error("constraint set '{set}': unknown contact '{contact}' (this foot has: {})", known.join(", "))]
    UnknownContact {
        /// The constraint set's name.
        set: String,
        /// The contact asked for.
        contact: String,
        /// The model's contacts.
        known: Vec<String>,
    },
    /// The contact is volumetric: a force in every phase, never a constraint.
    #[error("constraint set '{set}': contact '{contact}' is volumetric: its force acts in every phase and it is never a constraint; leave it out of the phase file's contacts")]
    Volumetric {
        /// The constraint set's name.
        set: String,
        /// The contact.
        contact: String,
    },
    /// The contact is listed more than once.
    #[error("constraint set '{set}': contact '{contact}' is listed twice")]
    Repeated {
        /// The constraint set's name.
        set: String,
        /// The contact.
        contact: String,
    },
}

/// Why an effect entry cannot be read from its text or built for a model
/// ([`EffectSpec::parse_cli`], [`EffectSpec::build`]).
///
/// [`EffectSpec::parse_cli`]: crate::model::effects::EffectSpec::parse_cli
/// [`EffectSpec::build`]: crate::model::effects::EffectSpec::build
#[derive(Debug, thiserror::Error)]
pub enum EffectError {
    /// A field of the entry is invalid.
    #[error("{field}: {reason}")]
    Field {
        /// The entry's field (`joint`, `side`, `free`, a parameter).
        field: &'static str,
        /// What is wrong and what would be valid.
        reason: String,
    },
    /// The entry acts on the trunk but the model has no trunk body.
    #[error("the model has no trunk body 'hat'")]
    NoTrunk,
    /// The entry names a foot primitive the foot lacks.
    #[error("primitive: this foot has no primitive '{primitive}' (it has: {}); the pad goes under a heel circle", primitives.join(", "))]
    NoPrimitive {
        /// The primitive named.
        primitive: String,
        /// The foot's primitives.
        primitives: Vec<String>,
    },
    /// The entry names a joint whose coordinate the model lacks.
    #[error("joint: the model has no coordinate '{coordinate}'")]
    NoCoordinate {
        /// The coordinate looked for (e.g. `knee_r`).
        coordinate: String,
    },
    /// The contact law is freed but the foot has no volumetric primitive.
    #[error("volumetric_contact: the foot {foot} has no volumetric primitive (its primitives {} are rigid), so there is no contact law to free; use a volumetric foot, e.g. --foot models/feet/volumetric_ellipse.json, or give a primitive \"contact\": {{\"type\": \"volumetric\", …}} in the foot file", primitives.join(", "))]
    NoVolumetricPrimitive {
        /// The foot file.
        foot: String,
        /// The foot's (rigid) primitives.
        primitives: Vec<String>,
    },
    /// A volumetric primitive's law, as the foot file gives it, lies outside the bounds
    /// an identification may use.
    #[error("volumetric_contact: primitive '{primitive}' of the foot {foot} has {parameter} {value} (in the effect's units), outside the bounds [{lower}, {upper}] an identification may use; give a start value with {parameter}=…")]
    LawOutOfBounds {
        /// The primitive.
        primitive: String,
        /// The foot file.
        foot: String,
        /// `stiffness`, `damping` or `mu_dynamic`.
        parameter: &'static str,
        /// Its value (stiffness in the effect's unit, damping s/m, friction dimensionless).
        value: f64,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// The text names no known effect.
    #[error("'{name}' is not a known effect; use one of {}", crate::model::effects::EFFECT_KINDS.join(", "))]
    UnknownKind {
        /// The name given.
        name: String,
    },
    /// An item of the text is not `key=value`.
    #[error("'{item}' in '{text}' is not key=value")]
    NotKeyValue {
        /// The item.
        item: String,
        /// The whole text.
        text: String,
    },
    /// A key is given twice.
    #[error("'{key}' is given twice in '{text}'; give each parameter once")]
    RepeatedKey {
        /// The key.
        key: String,
        /// The whole text.
        text: String,
    },
    /// A parameter's value is not a number.
    #[error("effect '{text}': '{key}' must be a number (for example {key}=0.02), got '{value}'")]
    NotANumber {
        /// The whole text.
        text: String,
        /// The parameter.
        key: String,
        /// The value given.
        value: String,
    },
    /// The text does not describe an entry of this kind (an unknown parameter, a wrong type).
    #[error("effect '{text}': {source}")]
    Schema {
        /// The whole text.
        text: String,
        /// serde's description.
        source: serde_json::Error,
    },
    /// The text's entry is invalid.
    #[error("effect '{text}': {source}")]
    Entry {
        /// The whole text.
        text: String,
        /// What is invalid (an [`EffectError::Field`]).
        source: Box<EffectError>,
    },
    /// Two texts add the same effect.
    #[error("'{first}' and '{second}' both add the effect '{effect}'; give it once")]
    Twice {
        /// The first text.
        first: String,
        /// The second text.
        second: String,
        /// The effect both add.
        effect: String,
    },
}
