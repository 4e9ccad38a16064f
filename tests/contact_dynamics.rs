//! Conservation and constraint behaviour over time: energy in free flight, and rolling
//! contact with and without Baumgarte stabilisation.

use crate::common;
use common::*;
use footfall::controls::ControlTable;
use footfall::integrate::IntegratorSettings;
use footfall::model::{ConstraintSet, GaitModel, RowKind};
use footfall::phases::{ContactUse, Duration, Phase, PhaseSequence};
use footfall::simulate::{simulate, SimulationResult, SimulationSettings};

fn one_phase(name: &str, contacts: &[&str], duration: f64) -> PhaseSequence {
    PhaseSequence {
        name: name.into(),
        description: String::new(),
        initial_state: None,
        gait: None,
        phases: vec![Phase::Continuous {
            name: name.into(),
            contacts: contacts
                .iter()
                .map(|c| ContactUse {
                    contact: c.to_string(),
                    rolling: true,
                })
                .collect(),
            duration: Duration::Fixed(duration),
            intervals: 1,
            end: None,
        }],
    }
}

fn run(
    m: &GaitModel,
    seq: &PhaseSequence,
    x0: &[f64],
    tol: f64,
) -> (SimulationResult, Vec<ConstraintSet>) {
    let sets = seq.resolve(m, std::path::Path::new("<test>")).unwrap();
    let controls = ControlTable::constant(m.control_names(), vec![0.0; m.nu()]);
    let settings = SimulationSettings {
        output_step: 1e-3,
        integrator: IntegratorSettings {
            rtol: tol,
            atol: tol,
            ..Default::default()
        },
    };
    let res = simulate(m, seq, &sets, x0, &controls, &[], &settings).unwrap();
    (res, sets)
}

/// With actuators and damping off (zero joint torques) and no contact, total energy is
/// conserved to the integrator tolerance over 1 s.
#[test]
fn energy_is_conserved_in_flight_without_actuation() {
    let m = model("opensim_subject01_torque.json", "ellipse.json");
    let mut x0 = vec![0.0, 1.0, 0.1, 0.4, -0.6, 0.2, -0.3, -0.2, -0.1];
    x0.extend([1.2, 0.5, 0.8, -2.0, 3.0, -4.0, 2.5, 1.0, 3.0]);
    for tol in [1e-8, 1e-10] {
        let (res, _) = run(&m, &one_phase("flight", &[], 1.0), &x0, tol);
        let e0 = {
            let (k, p) = m.energy(&x0[..9], &x0[9..], &[]);
            k + p
        };
        let scale = m.energy(&x0[..9], &x0[9..], &[]).0.max(1.0);
        let worst = res
            .samples
            .iter()
            .map(|s| {
                let (k, p) = m.energy(&s.x[..9], &s.x[9..18], &[]);
                (k + p - e0).abs() / scale
            })
            .fold(0.0, f64::max);
        eprintln!(
            "tol {tol:e}: relative energy drift over 1 s {worst:.2e} ({} samples)",
            res.samples.len()
        );
        assert!(res.samples.last().unwrap().t > 0.999);
        assert!(
            worst < 50.0 * tol,
            "energy drift {worst:e} at tolerance {tol:e}"
        );
    }
}

fn springs() -> serde_json::Value {
    serde_json::json!([
        { "type": "passive_joint_stiffness", "joint": "hip", "stiffness": 300.0, "rest_angle": 0.0 },
        { "type": "passive_joint_stiffness", "joint": "knee", "stiffness": 300.0, "rest_angle": -0.3 },
        { "type": "passive_joint_stiffness", "joint": "ankle", "stiffness": 300.0, "rest_angle": 0.0 }
    ])
}

fn stance_start(m: &GaitModel, contact: &str, lift: f64, slip: f64) -> Vec<f64> {
    let mut q = pose_on_ground(m, [0.1, 0.3, -0.2, -0.1, -0.4, -0.6, 0.1], contact);
    let set = m.constraint_set("s", &[(contact, true)]).unwrap();
    let qd_raw = [1.0, -0.05, 0.1, -0.5, 0.2, 0.8, 0.5, -0.5, 0.2];
    // project velocities onto the constraint manifold (plastic impact map = M-orthogonal
    // projection), then perturb position and tangential velocity as requested
    let (mut qd, _) = m.impact(&set, &q, &qd_raw, &[]).unwrap();
    q[1] += lift;
    qd[0] += slip;
    q.extend(qd);
    q
}

fn max_abs(
    res: &SimulationResult,
    sets: &[ConstraintSet],
    kind: RowKind,
    pos: bool,
    from: f64,
) -> f64 {
    res.samples
        .iter()
        .filter(|s| s.t >= from)
        .flat_map(|s| {
            sets[s.phase]
                .rows
                .iter()
                .enumerate()
                .filter(move |(_, r)| r.kind == kind)
                .map(move |(i, _)| {
                    if pos {
                        s.contact.position_error[i].abs()
                    } else {
                        s.contact.velocity_error[i].abs()
                    }
                })
        })
        .fold(0.0, f64::max)
}

/// During rolling the contact point's material velocity stays below 1e-6 m/s and the
/// position drift stays bounded with Baumgarte on, for both feet.
#[test]
fn rolling_contact_point_stays_still_with_baumgarte() {
    for (foot, contact) in [
        ("ellipse.json", "r.sole"),
        ("double_circle.json", "r.forefoot"),
        ("double_circle.json", "r.heel"),
    ] {
        // passive joint springs keep the unactuated body in shape, so it rolls over the foot
        let m = model_with_effects("opensim_subject01_torque.json", foot, springs());
        let x0 = stance_start(&m, contact, 0.0, 0.0);
        let (res, sets) = run(&m, &one_phase("stance", &[contact], 0.3), &x0, 1e-8);
        let vt = max_abs(&res, &sets, RowKind::Tangential, false, 0.0);
        let vn = max_abs(&res, &sets, RowKind::Normal, false, 0.0);
        let drift = max_abs(&res, &sets, RowKind::Normal, true, 0.0);
        let foot_body = m.contacts[m.contact_index(contact).unwrap()].body;
        let rot = |x: &[f64]| -> f64 {
            m.tree()
                .ancestors(foot_body)
                .iter()
                .filter(|&&j| j >= 2)
                .map(|&j| x[j])
                .sum()
        };
        let rolled = (rot(&res.samples.last().unwrap().x) - rot(&x0)).abs();
        eprintln!("{foot} {contact}: |v_t| ≤ {vt:.2e} m/s, |v_n| ≤ {vn:.2e} m/s, |φ| ≤ {drift:.2e} m, foot rotated {rolled:.3} rad");
        assert!(rolled > 0.05, "the foot must actually roll in this test");
        assert!(
            vt < 1e-6 && vn < 1e-6,
            "contact point velocity {vt:e} / {vn:e} m/s"
        );
        assert!(drift < 1e-6, "position drift {drift:e} m");
    }
}

/// From a perturbed start (1 mm gap, 1 cm/s slip) Baumgarte drives the errors to zero;
/// without it the position error grows.
#[test]
fn drift_decays_with_baumgarte_and_grows_without() {
    let contact = "r.sole";
    let mut on = model("opensim_subject01_torque.json", "ellipse.json");
    let x0 = stance_start(&on, contact, 1e-3, 0.01);
    let (res_on, sets) = run(&on, &one_phase("stance", &[contact], 0.4), &x0, 1e-8);
    on.set_baumgarte(0.0, 0.0, 0.0);
    let off = on;
    let (res_off, _) = run(&off, &one_phase("stance", &[contact], 0.4), &x0, 1e-8);
    let end_on = max_abs(&res_on, &sets, RowKind::Normal, true, 0.35);
    let end_off = max_abs(&res_off, &sets, RowKind::Normal, true, 0.35);
    let slip_on = max_abs(&res_on, &sets, RowKind::Tangential, false, 0.35);
    let slip_off = max_abs(&res_off, &sets, RowKind::Tangential, false, 0.35);
    eprintln!("after 0.35 s: gap {end_on:.2e} m (Baumgarte) vs {end_off:.2e} m (none); slip {slip_on:.2e} vs {slip_off:.2e} m/s");
    assert!(
        end_on < 1e-5,
        "Baumgarte must remove the 1 mm gap, left {end_on:e}"
    );
    // tangential errors decay as e^{-γt}: 0.01 m/s · e^{-20·0.35} = 9.1e-6 m/s
    assert!(
        slip_on < 1.2 * 0.01 * (-20.0f64 * 0.35).exp(),
        "slip {slip_on:e}"
    );
    assert!(
        end_off > 0.9e-3,
        "without stabilisation the gap must persist: {end_off:e}"
    );
    assert!(
        (slip_off - 0.01).abs() < 1e-3,
        "without stabilisation the slip persists: {slip_off:e}"
    );
    assert!(end_off > 100.0 * end_on);
}

/// From a consistent start, numerical drift accumulates without Baumgarte and stays
/// bounded with it.
#[test]
fn numerical_drift_grows_without_baumgarte() {
    let contact = "r.sole";
    let mut m = model_with_effects("opensim_subject01_torque.json", "ellipse.json", springs());
    let x0 = stance_start(&m, contact, 0.0, 0.0);
    let seq = one_phase("stance", &[contact], 1.0);
    let (on, _) = run(&m, &seq, &x0, 1e-6);
    m.set_baumgarte(0.0, 0.0, 0.0);
    let (off, _) = run(&m, &seq, &x0, 1e-6);
    let window = |r: &SimulationResult, a: f64, b: f64| {
        r.samples
            .iter()
            .filter(|s| s.t >= a && s.t <= b)
            .map(|s| s.contact.position_error[1].abs())
            .fold(0.0, f64::max)
    };
    let (on_early, on_late) = (window(&on, 0.0, 0.1), window(&on, 0.9, 1.0));
    let (off_early, off_late) = (window(&off, 0.0, 0.1), window(&off, 0.9, 1.0));
    eprintln!("drift |φ| at tol 1e-6: Baumgarte {on_early:.2e} → {on_late:.2e} m; none {off_early:.2e} → {off_late:.2e} m");
    assert!(
        off_late > 3.0 * off_early,
        "drift without Baumgarte should grow"
    );
    assert!(
        off_late > 10.0 * on_late,
        "Baumgarte should keep drift smaller"
    );
    assert!(on_late < 1e-6);
}
