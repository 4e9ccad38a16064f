//! A QP that fails mid-solve is never fatal the first time: the SQP re-solves it in
//! elastic mode and then with a growing proximal shift δI, and the solve goes on to the
//! optimum it reaches without the failure. The failures are injected
//! (`SqpSettings::inject_qp_failures`: those QP solves report Clarabel's numerical error
//! without being attempted), so the test does not depend on finding a QP that Clarabel
//! happens to fail on.

use footfall::integrate::{IntegratorSettings, Method};
use footfall::ocp::Transcription;
use footfall::problems::benchmarks::{read_problem_json, Benchmark};
use footfall::sqp::{self, HessianMode, Silent, SqpResult, SqpSettings, SqpStatus};
use std::path::PathBuf;

fn solve_biped(inject: Vec<usize>) -> SqpResult {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("problems/five_link_biped.json");
    let bench = Benchmark::from_json(read_problem_json(&p).unwrap()).unwrap();
    let ocp = bench
        .ocp(IntegratorSettings {
            method: Method::Adams,
            ..Default::default()
        })
        .unwrap();
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let settings = SqpSettings {
        tol_kkt: 1e-6,
        hessian: HessianMode::Exact,
        max_iter: 100,
        inject_qp_failures: inject,
        ..Default::default()
    };
    sqp::solve(&tr, &w0, &settings, &mut Silent)
}

#[test]
fn injected_qp_failures_mid_solve_are_recovered_and_the_solve_converges() {
    let clean = solve_biped(Vec::new());
    assert_eq!(clean.status, SqpStatus::Converged);
    let solves = clean.timings.qp_solves;
    assert!(solves >= 6, "{solves} QP solves");
    // mid-solve: one failure; then three in a row, which fail an iteration's QP, its
    // elastic re-solve and the first proximal shift (or, where they straddle
    // iterations, the QPs of two iterations)
    let mid = solves / 2;
    for inject in [vec![mid], vec![mid, mid + 1, mid + 2]] {
        let r = solve_biped(inject.clone());
        eprintln!(
            "QP failures at solves {inject:?}: {:?} after {} iterations ({} without), J = {:.10} ({:.10} without), {} QP solves ({solves} without)",
            r.status,
            r.history.len() - 1,
            clean.history.len() - 1,
            r.objective,
            clean.objective,
            r.timings.qp_solves
        );
        assert_eq!(r.status, SqpStatus::Converged, "{inject:?}");
        assert!(r.kkt <= 1e-6);
        assert!(
            (r.objective - clean.objective).abs() < 1e-6 * clean.objective,
            "{inject:?}: J = {} against {}",
            r.objective,
            clean.objective
        );
        // the failed solves were made and answered by further ones
        assert!(r.timings.qp_solves > solves, "{inject:?}");
    }
    // every QP failing from there on: fatal once an iteration's QP, its elastic
    // re-solve and every proximal shift have failed, and the stop says why
    let r = solve_biped((mid..mid + 100).collect());
    eprintln!("every QP failing from solve {mid} on: {:?}", r.status);
    assert!(
        matches!(&r.status, SqpStatus::QpFailure(m) if m.contains("injected")),
        "{:?}",
        r.status
    );
}
