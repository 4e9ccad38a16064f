//! footfall: fit and predict human gait with rigid foot-ground contact models.
//!
//! Layers (see DESIGN.md): [`model`] (planar multibody dynamics, contact, impacts,
//! actuators, effects), [`integrate`] (CVODES with forward sensitivities), and on top the
//! phase sequences, forward simulation and run folders.
#![warn(missing_docs)]

pub mod controls;
pub mod data;
pub mod integrate;
pub mod limits;
pub mod model;
pub mod ocp;
pub mod phases;
pub mod problems;
pub mod report;
pub mod runfolder;
pub mod simulate;
pub mod sqp;
