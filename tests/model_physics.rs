//! Physics of the gait model against independent truth: the CasADi peer's check values
//! (an independent symbolic implementation), symmetry and definiteness of M, brute-force
//! geometry, and the defining properties of the plastic impact map.

use crate::common;
use common::*;
use footfall::model::geometry::Shape;
use footfall::model::{GaitModel, RowKind};

fn peer_model() -> GaitModel {
    model("opensim_subject01_torque.json", "peer_ellipse.json")
}

#[test]
fn mass_matrix_and_bias_match_peer_check_values() {
    if !have_shared() {
        eprintln!("shared/ not present: skipped");
        return;
    }
    let p = peer_gait_problem();
    let cv = &p["check_values"];
    let m = peer_model();
    let q = vecf(&cv["q"]);
    let qd = vecf(&cv["qd"]);
    let (mm, c) = m.mass_matrix_and_bias(&q, &qd, &[]);
    let want: Vec<f64> = cv["M"].as_array().unwrap().iter().flat_map(vecf).collect();
    assert!(
        rel_diff(&mm, &want, 1.0) < 1e-7,
        "M differs: {:e}",
        rel_diff(&mm, &want, 1.0)
    );
    assert!(rel_diff(&c, &vecf(&cv["bias"]), 1.0) < 1e-7, "bias differs");
    let (ke, pe) = m.energy(&q, &qd, &[]);
    // the peer's potential energy reference is y = 0 like ours
    assert!(
        (ke + pe - cv["energy"].as_f64().unwrap()).abs() < 1e-6,
        "energy {} vs {}",
        ke + pe,
        cv["energy"]
    );
}

#[test]
fn contact_points_jacobians_and_gaps_match_peer() {
    if !have_shared() {
        return;
    }
    let p = peer_gait_problem();
    let cv = &p["check_values"];
    let m = peer_model();
    let q = vecf(&cv["q"]);
    for (side, cp, gk, phik) in [("r", "cp_r", "G_r", "phi_r"), ("l", "cp_l", "G_l", "phi_l")] {
        let c = m.contact_index(&format!("{side}.sole")).unwrap();
        let (pt, phi) = m.contact_point(c, &q, &[]);
        assert!(rel_diff(&pt, &vecf(&cv[cp]), 1.0) < 1e-9, "{cp}: {pt:?}");
        assert!(
            (phi - cv[phik].as_f64().unwrap()).abs() < 1e-9,
            "{phik}: {phi}"
        );
        let set = m
            .constraint_set("x", &[(&format!("{side}.sole"), true)])
            .unwrap();
        let g = m.constraint_jacobian_at(&set, &q, &[]);
        // our rows: tangential then normal, like the peer's [G_t; G_n]
        let want: Vec<f64> = cv[gk].as_array().unwrap().iter().flat_map(vecf).collect();
        assert!(rel_diff(&g, &want, 1.0) < 1e-9, "{gk}");
    }
}

#[test]
fn forward_dynamics_match_peer_for_every_contact_set() {
    if !have_shared() {
        return;
    }
    let p = peer_gait_problem();
    let cv = &p["check_values"];
    let m = peer_model();
    let q = vecf(&cv["q"]);
    let qd = vecf(&cv["qd"]);
    // the controls are the peer's torques (N·m) in the model's torque unit
    let unit = m.torque_unit().expect("a torque-driven model");
    let u: Vec<f64> = vecf(&cv["tau"]).iter().map(|t| t / unit).collect();
    let mut x = q.clone();
    x.extend(&qd);
    for (key, contacts) in [
        ("forward_dynamics_rl", vec!["r.sole", "l.sole"]),
        ("forward_dynamics_r", vec!["r.sole"]),
        ("forward_dynamics_l", vec!["l.sole"]),
        ("forward_dynamics_flight", vec![]),
    ] {
        let list: Vec<(&str, bool)> = contacts.iter().map(|c| (*c, true)).collect();
        let set = m.constraint_set(key, &list).unwrap();
        let mut xdot = vec![0.0; 18];
        let mut lam = vec![0.0; set.rows.len()];
        m.dynamics(&set, &x, &u, &[], &mut xdot, &mut lam, None)
            .unwrap();
        let want_qdd = vecf(&cv[key]["qdd"]);
        assert!(
            rel_diff(&xdot[9..], &want_qdd, 1.0) < 1e-7,
            "{key} qdd: {:?}",
            &xdot[9..]
        );
        // peer order per foot: [fx, fy]; ours: [tangential, normal]
        let want_lam = vecf(&cv[key]["lam"]);
        assert!(
            rel_diff(&lam, &want_lam, 1.0) < 1e-7,
            "{key} lambda: {lam:?} vs {want_lam:?}"
        );
    }
}

#[test]
fn impact_map_matches_peer() {
    if !have_shared() {
        return;
    }
    let p = peer_gait_problem();
    let cv = &p["check_values"];
    let m = peer_model();
    let q = vecf(&cv["q"]);
    let qd = vecf(&cv["qd"]);
    let set = m
        .constraint_set("both", &[("r.sole", true), ("l.sole", true)])
        .unwrap();
    let (qd_plus, imp) = m.impact(&set, &q, &qd, &[]).unwrap();
    assert!(rel_diff(&qd_plus, &vecf(&cv["impact_rl"]["qd_plus"]), 1.0) < 1e-8);
    assert!(
        rel_diff(&imp, &vecf(&cv["impact_rl"]["Lam"]), 1.0) < 1e-8,
        "{imp:?}"
    );
}

#[test]
fn mass_matrix_symmetric_positive_definite_over_random_configurations() {
    let mut rng = Rng::new(7);
    for (mf, ff) in [
        ("gait9dof.json", "ellipse.json"),
        ("opensim_subject01.json", "double_circle.json"),
    ] {
        let m = model(mf, ff);
        for _ in 0..500 {
            let q: Vec<f64> = (0..9)
                .map(|i| {
                    if i < 2 {
                        rng.uniform(-3.0, 3.0)
                    } else {
                        rng.uniform(-3.2, 3.2)
                    }
                })
                .collect();
            let (mm, _) = m.mass_matrix_and_bias(&q, &[0.0; 9], &[]);
            let n = 9;
            for i in 0..n {
                for j in 0..n {
                    assert!(
                        (mm[i * n + j] - mm[j * n + i]).abs() < 1e-12 * (1.0 + mm[i * n + j].abs())
                    );
                }
            }
            // Cholesky must succeed and the smallest Gershgorin-free test: xᵀMx > 0 for random x
            let mut a = mm.clone();
            footfall::model::linalg::cholesky(&mut a, n, 1e-14).expect("M positive definite");
            for _ in 0..5 {
                let v: Vec<f64> = (0..n).map(|_| rng.uniform(-1.0, 1.0)).collect();
                let quad: f64 = (0..n)
                    .map(|i| (0..n).map(|j| v[i] * mm[i * n + j] * v[j]).sum::<f64>())
                    .sum();
                assert!(quad > 0.0);
            }
        }
    }
}

#[test]
fn ellipse_lowest_point_agrees_with_brute_force_sampling() {
    let mut rng = Rng::new(11);
    for _ in 0..20 {
        let (a, b) = (rng.uniform(0.02, 0.2), rng.uniform(0.02, 0.2));
        let angle = rng.uniform(-3.0, 3.0);
        let psi = rng.uniform(-1.5, 1.5);
        let shape = Shape::Ellipse {
            centre: [0.0, 0.0],
            angle,
            semi_axes: [a, b],
        };
        let d = shape.contact_offset::<f64>(psi, [0.0, 1.0]);
        // brute force over 1e5 boundary points (parametric), world frame
        let (s, c) = (psi + angle).sin_cos();
        let mut best = f64::INFINITY;
        let mut best_pt = [0.0; 2];
        for k in 0..100_000 {
            let t = k as f64 * std::f64::consts::TAU / 100_000.0;
            let p = [a * t.cos(), b * t.sin()];
            let w = [c * p[0] - s * p[1], s * p[0] + c * p[1]];
            if w[1] < best {
                best = w[1];
                best_pt = w;
            }
        }
        assert!(
            d[1] <= best + 1e-15,
            "found point is not lowest: {} vs {best}",
            d[1]
        );
        assert!(
            best - d[1] < 1e-8,
            "height differs from brute force by {}",
            best - d[1]
        );
        let dist = ((d[0] - best_pt[0]).powi(2) + (d[1] - best_pt[1]).powi(2)).sqrt();
        assert!(
            dist < 2.0 * std::f64::consts::TAU / 100_000.0 * a.max(b),
            "point differs by {dist}"
        );
        // and it lies on the ellipse, to rounding
        let e = [c * d[0] + s * d[1], -s * d[0] + c * d[1]];
        let on = (e[0] / a).powi(2) + (e[1] / b).powi(2);
        assert!((on - 1.0).abs() < 1e-12, "off the ellipse: {on}");
    }
}

#[test]
fn impact_zeroes_constraint_velocities_with_nonnegative_impulse_and_no_energy_gain() {
    let mut rng = Rng::new(5);
    for foot in ["ellipse.json", "double_circle.json"] {
        let m = model("opensim_subject01.json", foot);
        let sets: Vec<Vec<(&str, bool)>> = if foot == "ellipse.json" {
            vec![
                vec![("r.sole", true)],
                vec![("r.sole", true), ("l.sole", true)],
            ]
        } else {
            vec![
                vec![("l.heel", true)],
                vec![("r.forefoot", true), ("l.heel", true)],
                vec![("l.heel", true), ("l.forefoot", false)],
            ]
        };
        for contacts in &sets {
            let set = m.constraint_set("impact", contacts).unwrap();
            for _ in 0..50 {
                let q: Vec<f64> = (0..9)
                    .map(|i| {
                        if i < 2 {
                            [1.0, 0.9][i]
                        } else {
                            rng.uniform(-0.5, 0.5)
                        }
                    })
                    .collect();
                // approaching the ground: downward pelvis velocity so normal impulses are compressive
                let mut qd: Vec<f64> = (0..9).map(|_| rng.uniform(-1.0, 1.0)).collect();
                qd[1] = -rng.uniform(0.5, 1.5);
                qd[0] = rng.uniform(0.0, 0.5);
                let (qd_plus, imp) = m.impact(&set, &q, &qd, &[]).unwrap();
                let g = m.constraint_jacobian_at(&set, &q, &[]);
                for r in 0..set.rows.len() {
                    let v: f64 = (0..9).map(|j| g[r * 9 + j] * qd_plus[j]).sum();
                    assert!(v.abs() < 1e-10, "post-impact constraint velocity {v}");
                }
                let (ke_minus, _) = m.energy(&q, &qd, &[]);
                let (ke_plus, _) = m.energy(&q, &qd_plus, &[]);
                assert!(
                    ke_plus <= ke_minus + 1e-10,
                    "kinetic energy grew: {ke_minus} -> {ke_plus}"
                );
                // a frictionless landing (normal row only) always gets a compressive impulse
                let ni = set
                    .rows
                    .iter()
                    .position(|r| r.kind == RowKind::Normal)
                    .unwrap();
                let pre: f64 = (0..9).map(|j| g[ni * 9 + j] * qd[j]).sum();
                if contacts.len() == 1 {
                    let normal_only = m.constraint_set("n", &[(contacts[0].0, false)]).unwrap();
                    let (_, imp_n) = m.impact(&normal_only, &q, &qd, &[]).unwrap();
                    if pre < 0.0 {
                        assert!(
                            imp_n[0] > 0.0,
                            "normal impulse {} for approach velocity {pre}",
                            imp_n[0]
                        );
                    }
                }
                let _ = imp;
            }
        }
    }
}

/// With sticking (rolling) rows the sign of the normal impulse depends on the state (the
/// optimal control problems constrain it); for a body dropping straight onto one foot it
/// must be compressive and equal the momentum stopped.
#[test]
fn vertical_drop_onto_one_foot_gives_compressive_impulse() {
    for (foot, c) in [("ellipse.json", "r.sole"), ("double_circle.json", "r.heel")] {
        let m = model("opensim_subject01.json", foot);
        let set = m.constraint_set("land", &[(c, true)]).unwrap();
        let q = [0.0, 0.95, 0.0, 0.1, -0.05, 0.0, -0.2, -0.3, 0.1];
        let mut qd = [0.0; 9];
        qd[1] = -0.8;
        let (qd_plus, imp) = m.impact(&set, &q, &qd, &[]).unwrap();
        let ni = set
            .rows
            .iter()
            .position(|r| r.kind == RowKind::Normal)
            .unwrap();
        assert!(imp[ni] > 0.0, "{foot}: normal impulse {}", imp[ni]);
        assert!(
            imp[ni] < 72.6 * 0.8 + 1e-9,
            "{foot}: impulse larger than the body's momentum"
        );
        let (k0, _) = m.energy(&q, &qd, &[]);
        let (k1, _) = m.energy(&q, &qd_plus, &[]);
        assert!(k1 < k0);
    }
}

#[test]
fn over_constrained_set_is_reported() {
    let m = model("opensim_subject01.json", "double_circle.json");
    // both circles with rolling rows: 4 rows on one rigid foot in the plane is fine only
    // if independent; heel + forefoot both rolling makes the two tangential rows dependent.
    let set = m
        .constraint_set("both_rolling", &[("r.heel", true), ("r.forefoot", true)])
        .unwrap();
    let mut x = vec![0.0; m.nx()];
    x[1] = 0.95;
    let u = vec![0.0; m.nu()];
    let mut xdot = vec![0.0; m.nx()];
    let mut lam = vec![0.0; set.rows.len()];
    let e = m
        .dynamics(&set, &x, &u, &[], &mut xdot, &mut lam, None)
        .unwrap_err();
    assert!(e.to_string().contains("over-constrains"), "{e}");
}
