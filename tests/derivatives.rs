//! Exact derivatives against finite differences: the AD Jacobian of the dynamics, and
//! CVODES forward sensitivities of a shooting interval (initial state, piecewise-linear
//! controls, duration and a free effect parameter) for both feet and every constraint set.

use crate::common;
use common::*;
use footfall::integrate::{ControlShape, Integrator, IntegratorSettings, Ode, ShootingInterval};
use footfall::model::GaitModel;
use footfall::problems::GaitOde;

fn stiff_model(foot: &str) -> GaitModel {
    model_with_effects(
        "opensim_subject01.json",
        foot,
        serde_json::json!([{ "type": "passive_joint_stiffness", "joint": "knee", "stiffness": 20.0, "rest_angle": -0.2, "free": ["stiffness"] }]),
    )
}

fn random_state(m: &GaitModel, rng: &mut Rng, contact: Option<&str>) -> Vec<f64> {
    let j = [
        rng.uniform(0.0, 0.2),
        rng.uniform(-0.4, 0.4),
        rng.uniform(-0.6, 0.0),
        rng.uniform(-0.2, 0.2),
        rng.uniform(-0.4, 0.4),
        rng.uniform(-0.6, 0.0),
        rng.uniform(-0.2, 0.2),
    ];
    let mut x = match contact {
        Some(c) => pose_on_ground(m, j, c),
        None => vec![0.0, 1.0, j[0], j[1], j[2], j[3], j[4], j[5], j[6]],
    };
    for _ in 0..9 {
        x.push(rng.uniform(-0.5, 0.5));
    }
    for _ in 0..m.na() {
        x.push(rng.uniform(0.05, 0.9));
    }
    x
}

#[test]
fn dynamics_jacobian_matches_central_differences() {
    let mut rng = Rng::new(3);
    for foot in ["ellipse.json", "double_circle.json"] {
        let m = stiff_model(foot);
        assert_eq!(
            m.ntheta(),
            1,
            "one knee stiffness shared by both legs is free"
        );
        jacobian_matches_central_differences(&m, foot, &mut rng, 5);
    }
}

/// The torque-driven model (the CasADi gait peer's actuation): its torque columns come
/// from the accelerations' response to a unit torque, not from AD.
#[test]
fn torque_driven_dynamics_jacobian_matches_central_differences() {
    let mut rng = Rng::new(5);
    for foot in ["ellipse.json", "double_circle.json"] {
        let m = model_with_effects("opensim_subject01_torque.json", foot, serde_json::json!([]));
        assert_eq!(m.na(), 0, "no activations");
        jacobian_matches_central_differences(&m, foot, &mut rng, 2);
    }
}

/// `draws` random states, controls and parameters in every constraint set of `foot`:
/// each column of the dynamics Jacobian against fourth-order central differences.
fn jacobian_matches_central_differences(m: &GaitModel, foot: &str, rng: &mut Rng, draws: usize) {
    let (nx, nu, nt) = (m.nx(), m.nu(), m.ntheta());
    for (name, contacts) in constraint_sets(foot) {
        let set = m.constraint_set(name, &contacts).unwrap();
        for _ in 0..draws {
            let x = random_state(m, rng, contacts.first().map(|c| c.0));
            let u: Vec<f64> = (0..nu).map(|_| rng.uniform(0.0, 1.0)).collect();
            let th: Vec<f64> = (0..nt).map(|_| rng.uniform(5.0, 50.0)).collect();
            let mut f0 = vec![0.0; nx];
            let mut jac = vec![0.0; nx * (nx + nu + nt)];
            m.dynamics_jacobian(&set, &x, &u, &th, &mut f0, &mut jac)
                .unwrap();
            let mut z: Vec<f64> = x.iter().chain(&u).chain(&th).copied().collect();
            let eval = |z: &[f64]| {
                let mut f = vec![0.0; nx];
                let mut lam = vec![0.0; set.rows.len()];
                m.dynamics(
                    &set,
                    &z[..nx],
                    &z[nx..nx + nu],
                    &z[nx + nu..],
                    &mut f,
                    &mut lam,
                    None,
                )
                .unwrap();
                f
            };
            for j in 0..z.len() {
                // fourth-order central differences: truncation O(h⁴), round-off ~ ε|f|/h
                let h = 1e-4 * z[j].abs().max(1.0);
                let z0 = z[j];
                let mut at = |k: f64| {
                    z[j] = z0 + k * h;
                    let f = eval(&z);
                    z[j] = z0;
                    f
                };
                let (f2, f1, m1, m2) = (at(2.0), at(1.0), at(-1.0), at(-2.0));
                let fd: Vec<f64> = (0..nx)
                    .map(|i| (-f2[i] + 8.0 * f1[i] - 8.0 * m1[i] + m2[i]) / (12.0 * h))
                    .collect();
                let col = &jac[j * nx..(j + 1) * nx];
                // FD round-off grows with |f|/h: scale the floor with the function's size
                let fscale = f0.iter().map(|v| v.abs()).fold(1.0, f64::max);
                let err = rel_diff(col, &fd, (1e-3 * fscale).max(1.0));
                assert!(
                    err < 1e-6,
                    "{foot}/{name}: column {j} differs from FD by {err:e}"
                );
            }
        }
    }
}

/// CVODES sensitivities (exact RHS derivatives) vs central
/// differences of the integrated end state, both at tolerance 1e-12, to 1e-5 relative.
#[test]
fn cvodes_sensitivities_match_finite_differences_for_every_constraint_set() {
    let mut rng = Rng::new(17);
    let tight = IntegratorSettings {
        rtol: 1e-12,
        atol: 1e-12,
        ..Default::default()
    };
    for foot in ["ellipse.json", "double_circle.json"] {
        let m = stiff_model(foot);
        for (name, contacts) in constraint_sets(foot) {
            let set = m.constraint_set(name, &contacts).unwrap();
            let ode = GaitOde {
                model: &m,
                set: &set,
            };
            let interval = ShootingInterval::new(&ode, ControlShape::Linear);
            let nx = m.nx();
            let np = interval.np();
            let mut integ = Integrator::new(nx, np, tight.clone()).unwrap();
            let x0 = random_state(&m, &mut rng, contacts.first().map(|c| c.0));
            let u0: Vec<f64> = (0..m.nu()).map(|_| rng.uniform(0.0, 1.0)).collect();
            let u1: Vec<f64> = (0..m.nu()).map(|_| rng.uniform(0.0, 1.0)).collect();
            let dur = rng.uniform(0.02, 0.04);
            let th = vec![rng.uniform(5.0, 50.0)];
            let mut p = Vec::new();
            interval
                .pack_params(&u0, Some(&u1), dur, &th, &mut p)
                .unwrap();
            let mut x1 = vec![0.0; nx];
            let mut s1 = vec![0.0; nx * (nx + np)];
            integ
                .integrate_with_sensitivities(&interval, 0.0, 1.0, &x0, &p, &mut x1, &mut s1)
                .unwrap();
            let mut end = |x0: &[f64], p: &[f64]| {
                let mut x1 = vec![0.0; nx];
                integ
                    .integrate(&interval, 0.0, 1.0, x0, p, &mut x1)
                    .unwrap();
                x1
            };
            let mut worst = (0.0f64, 0usize);
            for j in 0..nx + np {
                // fourth-order central differences at two step sizes: truncation O(h⁴)
                // dominates the larger step, integration noise (~tol/h) the smaller one; the
                // sensitivity must agree with the better of the two estimates.
                let v = if j < nx { x0[j] } else { p[j - nx] };
                let floor = if j == nx + interval.p_duration() {
                    0.0
                } else {
                    0.1
                };
                let col = &s1[j * nx..(j + 1) * nx];
                let mut best: Option<(f64, Vec<f64>)> = None;
                for eps in [1e-2, 1e-3] {
                    let h = eps * v.abs().max(floor);
                    let mut at = |k: f64| {
                        let (mut xa, mut pa) = (x0.clone(), p.clone());
                        if j < nx {
                            xa[j] += k * h;
                        } else {
                            pa[j - nx] += k * h;
                        }
                        end(&xa, &pa)
                    };
                    let (f2, f1, m1, m2) = (at(2.0), at(1.0), at(-1.0), at(-2.0));
                    let fd: Vec<f64> = (0..nx)
                        .map(|i| (-f2[i] + 8.0 * f1[i] - 8.0 * m1[i] + m2[i]) / (12.0 * h))
                        .collect();
                    let e = rel_diff(col, &fd, 1e-3);
                    if best.as_ref().is_none_or(|(be, _)| e < *be) {
                        best = Some((e, fd));
                    }
                }
                let (err, fd) = best.expect("two estimates");
                let abs = s1[j * nx..(j + 1) * nx]
                    .iter()
                    .zip(&fd)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                let norm = fd.iter().map(|v| v.abs()).fold(0.0, f64::max);
                if err > 1e-6 {
                    eprintln!("  col {j}: rel {err:.2e} abs {abs:.2e} |fd| {norm:.2e}");
                }
                if err > worst.0 {
                    worst = (err, j);
                }
            }
            eprintln!(
                "{foot}/{name}: worst column {} relative error {:.2e} ({} sensitivity columns)",
                worst.1,
                worst.0,
                nx + np
            );
            assert!(
                worst.0 < 1e-5,
                "{foot}/{name}: sensitivity column {} differs from FD by {:e}",
                worst.1,
                worst.0
            );
            let _ = interval.nx();
        }
    }
}

/// Exact second derivatives of the gait dynamics, `∇²(μᵀf)` over (x, u, θ) by nested AD,
/// against central differences of the exact AD Jacobian: muscle-torque generators (AD
/// over the states and θ only, the activations leading), the same with residual
/// actuators (their controls lead beside the activations) and joint torques.
#[test]
fn dynamics_second_derivatives_match_finite_differences() {
    use footfall::integrate::ControlledOde;
    let mut rng = Rng::new(21);
    let knee = serde_json::json!([{ "type": "passive_joint_stiffness", "joint": "knee", "stiffness": 20.0, "rest_angle": -0.2, "free": ["stiffness"] }]);
    // the generators' parameters scale the torques the activations make: the Hessian's
    // (activation, parameter) block
    let actuators = serde_json::json!([
        { "type": "mtg_strength", "free": ["change"] },
        { "type": "mtg_damping", "free": ["change"] },
    ]);
    for (m, foot, contacts) in [
        (
            stiff_model("ellipse.json"),
            "ellipse.json",
            vec![("r.sole", true)],
        ),
        (
            stiff_model("double_circle.json"),
            "double_circle.json",
            vec![("r.heel", true), ("r.forefoot", false)],
        ),
        (
            stiff_model("ellipse.json").with_residual_actuators(100.0, 50.0),
            "ellipse.json with residual actuators",
            vec![("r.sole", true)],
        ),
        (
            model_with_effects("opensim_subject01_torque.json", "ellipse.json", knee),
            "ellipse.json, joint torques",
            vec![("r.sole", true)],
        ),
        (
            model_with_effects("opensim_subject01.json", "double_circle.json", actuators),
            "double_circle.json, free generator strength and damping",
            vec![("r.heel", true), ("r.forefoot", false)],
        ),
    ] {
        let set = m.constraint_set("s", &contacts).unwrap();
        let ode = GaitOde {
            model: &m,
            set: &set,
        };
        let (nx, nu, nt) = (m.nx(), m.nu(), m.ntheta());
        let nw = nx + nu + nt;
        let x = random_state(&m, &mut rng, Some(contacts[0].0));
        let u: Vec<f64> = (0..nu).map(|_| rng.uniform(0.0, 1.0)).collect();
        let th: Vec<f64> = if nt == 1 { vec![25.0] } else { vec![0.1, 0.3] };
        let mu: Vec<f64> = (0..nx).map(|_| rng.uniform(-1.0, 1.0)).collect();
        let mut h = vec![0.0; nw * nw];
        assert!(ode.weighted_hessian(&x, &u, &th, &mu, &mut h).unwrap());
        let z: Vec<f64> = x.iter().chain(&u).chain(&th).copied().collect();
        let (worst, scale) = weighted_hessian_fd_error(&m, &set, &z, &mu, &h, 1e-5);
        eprintln!("{foot}: ∇²(μᵀf) vs FD of the exact Jacobian: {worst:.2e} (scale {scale:.2e})");
        assert!(worst < 1e-6, "{foot}: Hessian differs from FD by {worst:e}");
    }
}
