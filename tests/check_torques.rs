//! The check's inverse dynamics (`joint_torques.csv`, `joint_powers.csv`): each leg
//! joint's torque against the principle of virtual work evaluated from the bodies'
//! positions alone, the generalised forces' power against the rate of the body's energy,
//! and the run folder's files against the library's figures.

use crate::check::{bundled_600_signals, check_to, BUNDLED_600};
use footfall::model::gait::COORDINATES;
use footfall::problems::check::balance::{inverse_dynamics, Body};
use footfall::problems::check::signals::Signals;

/// Each massive body's centre of mass and world angle at `q` (m, rad).
fn pose(body: &Body, q: &[f64; 9]) -> Vec<([f64; 2], f64)> {
    let tree = body.tree();
    let k = tree.kinematics::<f64>(q, &[0.0; 9]);
    tree.inertias::<f64>()
        .iter()
        .enumerate()
        .map(|(b, i)| (tree.point(&k, b, i.com), k.angle[b]))
        .collect()
}

/// The world position at `q` of the material point of body `b` that lies at `p` at `q0`.
fn carried(body: &Body, b: usize, p: [f64; 2], q0: &[f64; 9], q: &[f64; 9]) -> [f64; 2] {
    let tree = body.tree();
    let k0 = tree.kinematics::<f64>(q0, &[0.0; 9]);
    let (c, s) = k0.cs[b];
    let d = [p[0] - k0.origin[b][0], p[1] - k0.origin[b][1]];
    let local = [c * d[0] + s * d[1], -s * d[0] + c * d[1]];
    tree.point(&tree.kinematics::<f64>(q, &[0.0; 9]), b, local)
}

/// Foot `s`'s body, its measured load `[Fx, Fy]` at `t` and the point the load acts at
/// with the body at `q`: where its line of action crosses the floor, or the ankle (the
/// foot's origin) for an unloaded foot's few newtons, as the inverse dynamics applies it.
fn load_at(
    body: &Body,
    signals: &Signals,
    q: &[f64; 9],
    s: usize,
    t: f64,
) -> (usize, [f64; 2], [f64; 2]) {
    let tree = body.tree();
    let b = tree.body_index(["foot_r", "foot_l"][s]).expect("foot");
    let [fx, fy, mz] = signals.load(s, t, 0.0_f64).expect("load");
    let p = if fy.abs() > 1.0 {
        [mz / fy, 0.0]
    } else {
        tree.kinematics::<f64>(q, &[0.0; 9]).origin[b]
    };
    (b, [fx, fy], p)
}

#[test]
fn joint_torques_do_the_virtual_work_of_the_bodies_motion_and_the_measured_loads() {
    // τ_j = Σ_i [m_i (c̈_i + g ŷ)·∂c_i/∂q_j + I_i θ̈_i ∂θ_i/∂q_j] − Σ_feet F·∂p/∂q_j, with
    // each body's accelerations by central differences in time of its positions and the
    // virtual displacements by central differences in each coordinate: no mass matrix and
    // no bias forces, which the inverse dynamics uses.
    let model = crate::common::model("opensim_subject01.json", "ellipse.json");
    let signals = bundled_600_signals(&model);
    let body = Body::of(&model).expect("body");
    let inertia = body.tree().inertias::<f64>();
    let g = model.gravity();
    let (h, e) = (2e-4, 1e-6);
    let mut checked = 0;
    for &t in signals.instants.iter().step_by(97) {
        let tau = inverse_dynamics(&body, &signals, &model, t).expect("loads at t");
        let q = |t: f64| signals.motion(t).0;
        let q0 = q(t);
        let (down, at, up) = (
            pose(&body, &q(t - h)),
            pose(&body, &q0),
            pose(&body, &q(t + h)),
        );
        for j in 3..9 {
            let (mut qa, mut qb) = (q0, q0);
            qa[j] += e;
            qb[j] -= e;
            let (pa, pb) = (pose(&body, &qa), pose(&body, &qb));
            let mut work = 0.0;
            for (b, i) in inertia.iter().enumerate() {
                let acc = |k: usize| (up[b].0[k] - 2.0 * at[b].0[k] + down[b].0[k]) / (h * h);
                let alpha = (up[b].1 - 2.0 * at[b].1 + down[b].1) / (h * h);
                let dc = |k: usize| (pa[b].0[k] - pb[b].0[k]) / (2.0 * e);
                let dtheta = (pa[b].1 - pb[b].1) / (2.0 * e);
                work += i.mass * (acc(0) * dc(0) + (acc(1) + g) * dc(1)) + i.izz * alpha * dtheta;
            }
            for s in 0..2 {
                let (b, [fx, fy], p) = load_at(&body, &signals, &q0, s, t);
                let (a, bb) = (
                    carried(&body, b, p, &q0, &qa),
                    carried(&body, b, p, &q0, &qb),
                );
                work -= fx * (a[0] - bb[0]) / (2.0 * e) + fy * (a[1] - bb[1]) / (2.0 * e);
            }
            assert!(
                (tau[j] - work).abs() < 0.05 + 1e-3 * work.abs(),
                "t {t}, {}: inverse dynamics {} N·m, virtual work {work} N·m",
                COORDINATES[j],
                tau[j]
            );
            checked += 1;
        }
    }
    assert!(checked >= 60, "{checked} torques checked");
}

#[test]
fn the_generalised_forces_power_with_the_loads_is_the_rate_of_the_bodys_energy() {
    // Σ τ_j q̇_j over every coordinate (the leg joints' powers and the pelvis rows', the
    // residual's) and the measured loads' power F·v at their points make d(KE + PE)/dt,
    // the body's energy differenced centrally in time: no mass matrix, no bias forces.
    let model = crate::common::model("opensim_subject01.json", "ellipse.json");
    let signals = bundled_600_signals(&model);
    let body = Body::of(&model).expect("body");
    let tree = body.tree();
    let inertia = tree.inertias::<f64>();
    let gravity = [0.0, -model.gravity()];
    let energy = |t: f64| {
        let (q, qd, _) = signals.motion(t);
        let (ke, pe) = tree.energy(&tree.kinematics::<f64>(&q, &qd), &inertia, gravity);
        ke + pe
    };
    let h = 2e-4;
    let mut checked = 0;
    for &t in signals.instants.iter().step_by(97) {
        let tau = inverse_dynamics(&body, &signals, &model, t).expect("loads at t");
        let (q, qd, _) = signals.motion(t);
        let k = tree.kinematics::<f64>(&q, &qd);
        let generalised: f64 = (0..9).map(|j| tau[j] * qd[j]).sum();
        let mut loads = 0.0;
        for s in 0..2 {
            let (b, [fx, fy], p) = load_at(&body, &signals, &q, s, t);
            let (v, _) = tree.point_motion(&k, b, p);
            loads += fx * v[0] + fy * v[1];
        }
        let rate = (energy(t + h) - energy(t - h)) / (2.0 * h);
        assert!(
            (generalised + loads - rate).abs() < 0.1 + 1e-3 * rate.abs(),
            "t {t}: Σ τ q̇ {generalised} W and the loads' {loads} W against dE/dt {rate} W"
        );
        checked += 1;
    }
    assert!(checked >= 10, "{checked} instants checked");
}

#[test]
fn the_check_writes_the_trials_joint_torques() {
    // The run folder's joint_torques.csv holds the library's inverse dynamics at the
    // check's instants, every leg joint, every value finite.
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("check");
    check_to(BUNDLED_600, "models/opensim_subject01.json", &out);
    let text = std::fs::read_to_string(out.join("joint_torques.csv")).expect("joint_torques.csv");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("time,hip_r_Nm,knee_r_Nm,ankle_r_Nm,hip_l_Nm,knee_l_Nm,ankle_l_Nm")
    );
    let model = crate::common::model("opensim_subject01.json", "ellipse.json");
    let signals = bundled_600_signals(&model);
    let body = Body::of(&model).expect("body");
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().expect("a number")).collect())
        .collect();
    assert!(rows.len() > 1000, "{} rows", rows.len());
    for row in rows.iter().step_by(101) {
        let want = inverse_dynamics(&body, &signals, &model, row[0]).expect("loads");
        for j in 0..6 {
            assert!(row[1 + j].is_finite());
            assert!(
                (row[1 + j] - want[3 + j]).abs() < 1e-9 * (1.0 + want[3 + j].abs()),
                "t {}: {} {} against {}",
                row[0],
                COORDINATES[3 + j],
                row[1 + j],
                want[3 + j]
            );
        }
    }
    // the powers are the torques times the joints' angular velocities
    let powers = std::fs::read_to_string(out.join("joint_powers.csv")).expect("joint_powers.csv");
    let mut lines = powers.lines();
    assert_eq!(
        lines.next(),
        Some("time,hip_r_W,knee_r_W,ankle_r_W,hip_l_W,knee_l_W,ankle_l_W")
    );
    for (line, row) in lines.zip(&rows).step_by(101) {
        let p: Vec<f64> = line
            .split(',')
            .map(|v| v.parse().expect("a number"))
            .collect();
        let (_, qd, _) = signals.motion(row[0]);
        assert_eq!(p[0], row[0]);
        for j in 0..6 {
            let want = row[1 + j] * qd[3 + j];
            assert!(
                (p[1 + j] - want).abs() < 1e-9 * (1.0 + want.abs()),
                "{}",
                COORDINATES[3 + j]
            );
        }
    }
    // the stance ankle's plantarflexor peak of a 72.6 kg walker: 1.2–2 N·m/kg
    let peak = rows.iter().map(|r| -r[3]).fold(f64::MIN, f64::max);
    assert!((1.2..2.0).contains(&(peak / 72.6)), "ankle peak {peak} N·m");
}
