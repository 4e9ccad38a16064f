//! footfall's integration tests that run whole solves (tracks, predictions,
//! diagnoses), and the bad-input checks (here to even out the two test crates' compile
//! times); the other ones that take seconds are in `quick.rs`.
//!
//! Each module is one file of `tests/` (they were once a binary each). One binary lets
//! the test harness keep both cores of a small machine busy across these tests: run
//! one binary after another, `cargo test` left a core idle through every single-test
//! binary and every binary's tail, and it compiled and linked the library's generic code
//! and the shared helpers once per file. Run one module with a filter:
//! `cargo test --test suite hidden_effects::`.

mod common;

mod bad_input;
mod c3d_trial;
mod cli;
mod derivatives;
mod diagnose_stats;
mod documented_commands;
mod every_recording;
mod foot_geometry;
mod gait_hessian;
mod hidden_effects;
mod instruments;
mod ocp_benchmarks;
mod opensim;
mod overground;
mod peer_gait;
mod qp_recovery;
mod real_hidden_refit;
mod reliability;
mod report_gait;
mod run_anywhere;
mod study_runs;
mod synth;
mod torque_tracking;
mod track_third_foot;
mod tracking_recovery;
mod tracking_residual;
mod validity;
mod volumetric_identification;
