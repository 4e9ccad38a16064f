//! Torque-driven tracking of the bundled trial: the actuation of the CasADi gait peer
//! (`peer_gait` in `common::peer_dir`), six joint torques of at most 500 N·m, on both feet, solved
//! from the data as `footfall track --model models/opensim_subject01_torque.json` does.
//!
//! Two faults once kept it from converging: the torques were bounded as excitations, to
//! [0, 1] N·m; and the swing foot's clearance row at the node it lifted off and at the node
//! it lands repeated rows the problem already held (the gap the Baumgarte rows keep at
//! zero, the landing row), so the QP's multipliers on them grew by 10³ per iteration until
//! Clarabel failed.

use crate::common;

use common::bundled_tracking_of;
use footfall::integrate::IntegratorSettings;
use footfall::ocp::Transcription;
use footfall::problems::evaluation::GaitSolution;
use footfall::problems::gait::GaitCycle;
use footfall::problems::track::TargetSides;
use footfall::sqp::{self, ExactConvexification, HessianMode, Silent, SqpSettings, SqpStatus};

/// Track the bundled trial with joint torques on `foot`; checks what a converged,
/// torque-driven fit must show.
fn tracks_with_torques(foot: &str, phases: &str) {
    let (m, sets, setup) = bundled_tracking_of(
        "opensim_subject01_torque.json",
        foot,
        phases,
        TargetSides::Interpolated,
    );
    let cycle = GaitCycle::new(&m, &setup.seq, &sets).unwrap();
    let ocp = setup
        .ocp(&cycle, &m, &sets, IntegratorSettings::default())
        .unwrap();
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    // footfall track's defaults
    let settings = SqpSettings {
        tol_kkt: 1e-5,
        max_iter: 200,
        hessian: HessianMode::Exact,
        exact_hessian_below: 1e-3,
        exact_convexification: ExactConvexification::InertiaCorrection,
        ..Default::default()
    };
    let res = sqp::solve(&tr, &w0, &settings, &mut Silent);
    eprintln!(
        "{foot}, joint torques: {:?}, {} iterations, {:.1} s, J = {:.6}, KKT {:.1e}",
        res.status,
        res.history.len() - 1,
        res.seconds,
        res.objective,
        res.kkt
    );
    assert_eq!(res.status, SqpStatus::Converged, "{foot}");
    assert!(res.kkt <= 1e-5);
    let sol = GaitSolution::from_nlp(&tr, &res.w, &cycle.continuous, setup.window.0);

    // the torques do the work: within ±500 N·m, and far beyond the old [0, 1] N·m box
    let unit = m.torque_unit().expect("torque-driven");
    let (lo, hi) = m.control_bounds();
    let mut peak = 0.0f64;
    for u in sol.phases.iter().flat_map(|p| &p.u) {
        for (k, v) in u.iter().enumerate() {
            assert!(
                *v >= lo[k] - 1e-9 && *v <= hi[k] + 1e-9,
                "{foot}: control {k} = {v}"
            );
            peak = peak.max((v * unit).abs());
        }
    }
    assert!(
        peak > 30.0 && peak <= 500.0 + 1e-6,
        "{foot}: peak joint torque {peak:.1} N·m"
    );
    let negative = sol
        .phases
        .iter()
        .flat_map(|p| &p.u)
        .any(|u| u[..m.nu_actuators()].iter().any(|v| *v < -0.1));
    assert!(negative, "{foot}: no joint torque below −10 N·m");

    // the first node has no on-ground rows of its own (the periodic landing implies
    // them): every foot on the ground there must still touch it
    let first = &sets[cycle.continuous[0]];
    let nq = m.nq();
    let q0 = &sol.phases[0].x[0][..nq];
    for row in &first.rows {
        let gap = m.gap(row.contact, q0, &sol.theta);
        assert!(
            gap.abs() < 1e-6,
            "{foot}: {} is {gap:.2e} m off the ground at the first node",
            m.contacts[row.contact].name
        );
    }
}

#[test]
fn torque_driven_tracking_converges_from_the_data_on_the_ellipse_foot() {
    tracks_with_torques("ellipse.json", "phases/ellipse_walk.json");
}

#[test]
fn torque_driven_tracking_converges_from_the_data_on_the_double_circle_foot() {
    tracks_with_torques("double_circle.json", "phases/double_circle_walk.json");
}
