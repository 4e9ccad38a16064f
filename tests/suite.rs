//! footfall's integration tests, in one test binary.
//!
//! Each module is one file of `tests/` (they were once a binary each). One binary lets
//! the test harness keep both cores of a small machine busy across the whole suite: run
//! one binary after another, `cargo test` left a core idle through every single-test
//! binary and every binary's tail, and it compiled and linked the library's generic code
//! and the shared helpers 57 times. Run one module with a filter:
//! `cargo test --test suite hidden_effects::`.

mod common;

mod actuators;
mod bad_input;
mod benchmark_models;
mod c3d;
mod c3d_trial;
mod cli;
mod cli_exit_codes;
mod cli_solve;
mod contact_dynamics;
mod cost_breakdown;
mod data;
mod derivatives;
mod diagnose_stats;
mod diff;
mod effects;
mod eval_errors;
mod filter;
mod foot_fit;
mod foot_geometry;
mod fuzz;
mod gait_hessian;
mod gait_ocp;
mod hidden_effects;
mod instruments;
mod integrate;
mod layers;
mod linearised;
mod model_physics;
mod ocp_benchmarks;
mod ocp_engine;
mod ocp_lq;
mod ocp_samples;
mod opensim;
mod overground;
mod peer_gait;
mod qp_active_set;
mod qp_recovery;
mod real_hidden_refit;
mod real_hidden_trials;
mod reliability;
mod report;
mod report_gait;
mod run_anywhere;
mod simulate_sanity;
mod sqp_convexity;
mod sqp_warm_start;
mod synth;
mod torque_tracking;
mod track_third_foot;
mod tracking_recovery;
mod tracking_residual;
mod tracking_setup;
mod transient;
mod validity;
mod volumetric;
mod volumetric_identification;
