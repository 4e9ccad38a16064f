//! Multi-phase optimal control problems and their direct multiple-shooting transcription.
//!
//! An [`Ocp`] lists continuous phases (dynamics as a
//! [`ControlledOde`](crate::integrate::ControlledOde), a shooting grid, bounds, an initial
//! guess), transitions between phases (e.g. impact maps), constraints and cost terms as
//! functions of node variables. [`Transcription`] turns it into a sparse NLP whose
//! continuity constraints come from CVODES forward sensitivities.
mod checks;
pub mod problem;
pub mod quadrature;
mod term_error;
pub mod transcription;

pub use problem::{
    Block, CheckPoint, Constraint, NodeFunction, Ocp, Phase, PhaseDuration, SampleTerm, Term,
};
pub use quadrature::{quadrature_cost, Integrand, WithQuadrature};
pub use term_error::{ExternalCause, TermError};
pub use transcription::{shifted_instant, Evaluation, RowLabel, Transcription, TranscriptionError};
