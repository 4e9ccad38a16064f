//! footfall's integration tests that take seconds: parsers, the model's
//! physics and derivatives piece by piece, the QP and SQP pieces, the report's files.
//! The tests that run whole solves are in `suite.rs`.
//!
//! Two test crates, not one, so that they compile side by side after the library (each
//! in few codegen units, Cargo.toml) and `cargo test` runs the short ones first: the
//! harness leaves a core idle only for seconds at this crate's end. Run one module with
//! a filter: `cargo test --test quick fuzz::`.

mod common;

mod actuators;
mod benchmark_models;
mod c3d;
mod c3d_damaged;
mod check;
mod check_torques;
mod check_trunk;
mod cli_exit_codes;
mod cli_solve;
mod contact_dynamics;
mod cost_breakdown;
mod data;
mod diff;
mod effects;
mod eval_errors;
mod filter;
mod foot_fit;
mod front_door;
mod fuzz;
mod gait_ocp;
mod implausible_input;
mod integrate;
mod layers;
mod linearised;
mod model_physics;
mod ocp_engine;
mod ocp_lq;
mod ocp_samples;
mod qp_active_set;
mod real_hidden_trials;
mod report;
mod simulate_sanity;
mod sqp_convexity;
mod sqp_warm_start;
mod study;
mod tracking_setup;
mod transient;
mod volumetric;
