//! footfall's integration tests, in one test binary.
//!
//! Each module below was its own binary (`tests/<name>.rs`) until stop 46. One binary
//! links once instead of 56 times, and libtest's two threads then share the whole
//! suite: a module with one long test no longer leaves a core idle while the next
//! module waits. Run one module with `cargo test --test suite <module>::`, e.g.
//! `cargo test --test suite hidden_effects::`.

mod actuators;
mod bad_input;
mod benchmark_models;
mod c3d;
mod c3d_trial;
mod cli;
mod cli_exit_codes;
mod cli_solve;
mod common;
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
mod qp_recovery;
mod real_hidden_refit;
mod real_hidden_trials;
mod reliability;
mod report;
mod report_gait;
mod run_anywhere;
mod simulate_sanity;
mod sqp_convexity;
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
