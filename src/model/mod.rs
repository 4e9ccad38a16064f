//! Planar multibody gait model: dynamics, contact, impacts, actuators and effects.
pub mod actuators;
pub mod ad;
pub mod anthropometry;
pub mod effects;
pub mod error;
pub mod gait;
pub mod geometry;
pub mod json;
pub mod linalg;
pub mod multibody;
pub mod scalar;
pub mod segments;
pub mod spec;
pub mod torso;
pub mod volumetric;

pub use actuators::ActuatorError;
pub use error::{
    AnthropometryError, ContactSetError, DynamicsError, EffectError, ModelError, ParameterError,
    ShapeError, TreeError,
};
pub use gait::{ConstraintSet, ContactReport, FootLoad, GaitModel, RowKind, Side};
pub use scalar::Scalar;
