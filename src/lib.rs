//! footfall: fit and predict human gait with foot-ground contact models, by multi-phase
//! direct multiple shooting (CVODES with forward sensitivities for every shooting
//! interval, an SQP with sparse QPs solved by Clarabel).
//!
//! # The layers
//!
//! Top to bottom; a module uses only modules below it, and any module may use the bottom
//! row (the binary's `cli` sits on top, parsing arguments into the workflows' request
//! structs, printing their progress and mapping their errors to exit codes). The `use
//! crate::…` lines of each module show it.
//!
//! | layer | owns | may use |
//! |---|---|---|
//! | [`workflows`] | track, predict, compare, synth, diagnose, report as library calls: a request in, a result out, progress through an observer; run folders written by one writer | everything below |
//! | [`report`] | tables, SVG plots, the HTML report, comparisons of runs | problems, simulate, phases, sqp, data, model |
//! | [`problems`] | tracking, prediction, foot fitting, diagnosis statistics, validity, the benchmark problems: costs and constraints built from data | ocp, sqp, integrate, simulate, phases, data, controls, model |
//! | [`simulate`], [`phases`] | forward simulation through a phase sequence; phase sequences in JSON | phases (simulate), integrate, controls, model |
//! | [`ocp`] | the phase graph as a multiple-shooting NLP: variables, constraints, sparsity, parallel interval evaluation | integrate, sqp |
//! | [`sqp`] | SQP iterations, Hessian approximations, filter line search, KKT test, typed evaluation errors | — |
//! | [`integrate`] | the safe wrapper over CVODES (the only module with `unsafe`): integrators, forward sensitivities, dense output | — |
//! | [`data`], [`controls`] | measured gait data (CSV, OpenSim storage files) and control tables | model, limits |
//! | [`model`] | planar multibody dynamics, contact sets, impact maps, actuators, effects, JSON model specs | limits |
//! | [`limits`], [`runfolder`], [`bundled`], [`interrupt`] | limits of plausible input; run folders that are complete or absent, their `setup.json` and `summary.json`; the files footfall ships with, compiled in; the request to stop that the long loops read | — |
//!
//! `ocp`, `sqp` and `integrate` know nothing of gait: they solve the cart-pole and the
//! five-link biped as well ([`problems`]' benchmark problems).
#![warn(missing_docs)]
#![deny(unsafe_code)]

pub mod bundled;
pub mod controls;
pub mod data;
pub mod integrate;
pub mod interrupt;
pub mod limits;
pub mod model;
pub mod ocp;
pub mod phases;
pub mod problems;
pub mod report;
pub mod runfolder;
pub mod simulate;
pub mod sqp;
pub mod workflows;
