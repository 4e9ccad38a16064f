//! The effect catalog: each effect's physics against closed-form truth, the command-line
//! form, and the catalog `diagnose` draws from.

use crate::common;
use common::*;
use footfall::model::effects::{catalog, measurement_effects, EffectSpec};

const G: f64 = 9.80665;

/// Generalised gravity force at rest: the bias `c` of `M q̈ + c = τ` at q̇ = 0 is the
/// negative generalised gravity force. Its pelvis-x and pelvis-y entries are the total
/// weight's components, whatever the posture.
fn gravity_bias(m: &footfall::model::GaitModel, theta: &[f64]) -> Vec<f64> {
    let q = [0.3, 0.95, 0.1, 0.3, -0.4, 0.1, -0.2, -0.3, 0.05];
    m.mass_matrix_and_bias(&q, &[0.0; 9], theta).1
}

#[test]
fn ground_slope_tilts_gravity_by_its_angle() {
    let plain = model("opensim_subject01.json", "ellipse.json");
    let m = model_with_effects(
        "opensim_subject01.json",
        "ellipse.json",
        serde_json::json!([{ "type": "ground_slope", "free": ["angle"] }]),
    );
    let c0 = gravity_bias(&plain, &[]);
    let total = c0[1] / G;
    assert!(
        (total - 72.6).abs() < 1.0,
        "the subject's mass from the weight: {total}"
    );
    assert!(c0[0].abs() < 1e-9);
    for alpha in [-0.1, 0.03, 0.15] {
        let c = gravity_bias(&m, &[alpha]);
        assert!(
            (c[0] - total * G * alpha.sin()).abs() < 1e-9,
            "along the walkway: {}",
            c[0]
        );
        assert!(
            (c[1] - total * G * alpha.cos()).abs() < 1e-9,
            "normal to it: {}",
            c[1]
        );
    }
    assert_eq!(gravity_bias(&m, &[0.0]), c0, "zero slope is no effect");
}

#[test]
fn trunk_mass_adds_weight_and_moves_the_trunk_centre_of_mass() {
    let plain = model("opensim_subject01.json", "ellipse.json");
    let m = model_with_effects(
        "opensim_subject01.json",
        "ellipse.json",
        serde_json::json!([{ "type": "trunk_mass", "free": ["added_mass", "com_offset"] }]),
    );
    let c0 = gravity_bias(&plain, &[]);
    assert_eq!(gravity_bias(&m, &[0.0, 0.0]), c0);
    let c = gravity_bias(&m, &[5.0, 0.0]);
    assert!((c[1] - c0[1] - 5.0 * G).abs() < 1e-9, "5 kg more weight");
    // the trunk's own coordinate (index 2, its angle 0.1 rad): moving its COM by δ along
    // its x axis changes the gravity moment about the hip by (m_hat) g δ cos(0.1)
    let delta = 0.02;
    let c = gravity_bias(&m, &[0.0, delta]);
    let dm = (c[2] - c0[2]).abs() / (G * delta * 0.1f64.cos());
    assert!(
        dm > 20.0 && dm < 60.0,
        "the moment change is the trunk's weight times the offset: {dm} kg"
    );
    // and is linear in δ with no change of the total weight
    let c2 = gravity_bias(&m, &[0.0, 2.0 * delta]);
    assert!(((c2[2] - c0[2]) - 2.0 * (c[2] - c0[2])).abs() < 1e-9);
    assert!((c2[1] - c0[1]).abs() < 1e-9);
}

#[test]
fn command_line_effects_parse_free_their_parameters_and_refuse_mistakes() {
    let e = EffectSpec::parse_cli("ground_slope").unwrap();
    assert_eq!(
        e,
        EffectSpec::GroundSlope {
            angle: 0.0,
            free: vec!["angle".into()]
        }
    );
    let e = EffectSpec::parse_cli("passive_joint_stiffness:joint=knee,stiffness=40").unwrap();
    assert_eq!(
        e,
        EffectSpec::PassiveJointStiffness {
            joint: "knee".into(),
            side: "both".into(),
            stiffness: 40.0,
            rest_angle: 0.0,
            free: vec!["stiffness".into()]
        }
    );
    let e = EffectSpec::parse_cli("trunk_mass:added_mass=3,free=").unwrap();
    assert_eq!(
        e,
        EffectSpec::TrunkMass {
            added_mass: 3.0,
            com_offset: 0.0,
            free: vec![]
        }
    );
    for (bad, needle) in [
        ("tendon_slack", "not a known effect"),
        ("ground_slope:angle=1.0", "angle"),
        ("ground_slope:angel=0.1", "angel"),
        ("passive_joint_stiffness:joint=elbow", "elbow"),
        ("cop_offset:free=offset+offset", "twice"),
        ("cop_offset:offset", "key=value"),
        ("trunk_mass:added_mass=abc", "'added_mass' must be a number"),
    ] {
        let err = EffectSpec::parse_cli(bad).unwrap_err().to_string();
        assert!(err.contains(needle), "{bad}: {err}");
    }
}

#[test]
fn the_catalog_builds_into_the_model_with_free_parameters_at_their_null_values() {
    let cat: Vec<EffectSpec> = catalog().into_iter().chain(measurement_effects()).collect();
    let kinds: Vec<&str> = cat.iter().map(|e| e.kind()).collect();
    for k in [
        "ground_slope",
        "trunk_mass",
        "passive_joint_stiffness",
        "force_plate_time_offset",
        "cop_offset",
    ] {
        assert!(kinds.contains(&k), "{k} missing from the catalog");
    }
    // the model's physics are the diagnosis's candidates; the instruments and the body
    // are the measurement check's
    let physics = [
        "passive_joint_stiffness",
        "mtg_damping",
        "mtg_strength",
        "activation_time_constants",
    ];
    assert!(catalog().iter().all(|e| physics.contains(&e.kind())));
    for k in physics {
        assert!(
            catalog().iter().any(|e| e.kind() == k),
            "{k} not a candidate"
        );
    }
    for e in &cat {
        let m = model_with_effects(
            "opensim_subject01.json",
            "ellipse.json",
            serde_json::to_value(vec![e]).unwrap(),
        );
        assert!(m.ntheta() >= 1, "{}: nothing free", e.label());
        assert!(
            m.theta0().iter().all(|v| *v == 0.0),
            "{}: not at its null value",
            e.label()
        );
        let plain = model("opensim_subject01.json", "ellipse.json");
        assert_eq!(
            gravity_bias(&m, &m.theta0()),
            gravity_bias(&plain, &[]),
            "{}: the null value changes the model",
            e.label()
        );
    }
}

/// Residual actuators: controls after the actuators' that add `scale × u` to each
/// generalised force; in flight M Δq̈ equals the added force exactly.
#[test]
fn residual_actuators_add_generalised_forces_per_unit_control() {
    let m = model("opensim_subject01.json", "ellipse.json").with_residual_actuators(100.0, 50.0);
    let base = m.nu_actuators();
    assert_eq!(m.nu(), base + 9);
    assert_eq!(m.control_names()[base], "pelvis_x_residual");
    assert_eq!(m.control_names()[base + 4], "knee_r_residual");
    let set = m.constraint_set("flight", &[]).unwrap();
    let q = [0.3, 1.2, 0.1, 0.3, -0.4, 0.1, -0.2, -0.3, 0.05];
    let qd = [1.0, 0.1, 0.2, -1.0, 1.0, 0.3, 1.5, -0.8, 1.0];
    let mut x: Vec<f64> = q.iter().chain(&qd).copied().collect();
    x.extend(vec![0.2; m.na()]);
    let (mass, _) = m.mass_matrix_and_bias(&q, &qd, &[]);
    let qdd = |u: &[f64]| {
        let mut xdot = vec![0.0; m.nx()];
        m.dynamics::<f64>(&set, &x, u, &[], &mut xdot, &mut [], None)
            .unwrap();
        xdot[9..18].to_vec()
    };
    let u0 = vec![0.3; m.nu()];
    let a0 = qdd(&{
        let mut u = u0.clone();
        u[base..].iter_mut().for_each(|v| *v = 0.0);
        u
    });
    for (i, scale) in [(0, 100.0), (2, 50.0), (7, 50.0)] {
        let mut u = u0.clone();
        u[base..].iter_mut().for_each(|v| *v = 0.0);
        u[base + i] = 0.5;
        let a = qdd(&u);
        for r in 0..9 {
            let f: f64 = (0..9).map(|c| mass[r * 9 + c] * (a[c] - a0[c])).sum();
            let expect = if r == i { 0.5 * scale } else { 0.0 };
            assert!(
                (f - expect).abs() < 1e-8 * scale,
                "residual {i}, row {r}: {f} vs {expect}"
            );
        }
    }
}

/// The dynamics Jacobian of a model with residual actuators has the residual controls'
/// columns (central differences).
#[test]
fn residual_actuator_columns_of_the_dynamics_jacobian_match_finite_differences() {
    let m = model("opensim_subject01.json", "ellipse.json").with_residual_actuators(100.0, 100.0);
    let set = m.constraint_set("s", &[("r.sole", true)]).unwrap();
    let q = [1.6, 0.95, 0.11, 0.3, -0.2, 0.1, -0.3, -0.5, 0.05];
    let qd = [1.1, 0.1, 0.2, -1.0, 1.0, 0.3, 1.5, -0.8, 1.0];
    let (q, qd, _) = m.project(&set, &q, &qd, &[]).unwrap();
    let mut x: Vec<f64> = q.iter().chain(&qd).copied().collect();
    x.extend(vec![0.2; m.na()]);
    let (nx, nu) = (m.nx(), m.nu());
    let u: Vec<f64> = (0..nu)
        .map(|i| {
            if i < m.nu_actuators() {
                0.3
            } else {
                0.05 * i as f64 - 0.4
            }
        })
        .collect();
    let mut xdot = vec![0.0; nx];
    let mut jac = vec![0.0; nx * (nx + nu)];
    m.dynamics_jacobian(&set, &x, &u, &[], &mut xdot, &mut jac)
        .unwrap();
    let f = |u: &[f64]| {
        let mut xd = vec![0.0; nx];
        let mut lam = vec![0.0; set.rows.len()];
        m.dynamics::<f64>(&set, &x, u, &[], &mut xd, &mut lam, None)
            .unwrap();
        xd
    };
    let mut worst = 0.0f64;
    for c in 0..nu {
        let h = 1e-6;
        let (mut a, mut b) = (u.clone(), u.clone());
        a[c] += h;
        b[c] -= h;
        let (fa, fb) = (f(&a), f(&b));
        for r in 0..nx {
            worst = worst.max(((fa[r] - fb[r]) / (2.0 * h) - jac[nx * nx + c * nx + r]).abs());
        }
    }
    assert!(worst < 1e-5, "control columns vs FD: {worst:e}");
}

/// A double-circle model with a heel pad of 150 N/mm and 1 N·s/mm (both free), torque
/// driven (u = 0: no actuator forces).
fn padded() -> footfall::model::GaitModel {
    model_with_effects(
        "opensim_subject01_torque.json",
        "double_circle.json",
        serde_json::json!([{ "type": "heel_pad_compliance", "stiffness": 150.0, "damping": 1.0, "free": ["stiffness", "damping"] }]),
    )
}

/// A state with the left heel 3 mm into the ground and moving down, the left forefoot
/// near the ground: `(set, x)` with the heel rolling and the forefoot in contact.
fn heel_strike_state(m: &footfall::model::GaitModel) -> (footfall::model::ConstraintSet, Vec<f64>) {
    let set = m
        .constraint_set(
            "heel_and_forefoot",
            &[("l.heel", true), ("l.forefoot", false)],
        )
        .unwrap();
    let mut q = pose_on_ground(m, [0.05, 0.3, -0.2, 0.05, -0.1, -0.05, 0.02], "l.heel");
    q[1] -= 0.003;
    let qd = vec![1.1, -0.08, 0.1, -0.4, 0.6, 0.3, 0.9, -0.3, 0.4];
    let mut x: Vec<f64> = q.iter().chain(&qd).copied().collect();
    x.extend(vec![0.0; m.na()]);
    (set, x)
}

/// The pad's normal force is k·d + c·ḋ of the heel circle's depth below the ground (its
/// gap and the gap's rate by central differences along q̇, independent of the dynamics'
/// own geometry), it takes part in the equations of motion M q̈ + c = Gᵀλ, and the rigid
/// rows (the heel's rolling, the forefoot's contact) keep their Baumgarte-stabilised
/// acceleration constraints.
#[test]
fn heel_pad_pushes_with_spring_and_damper_while_the_rigid_rows_hold() {
    let m = padded();
    let (set, x) = heel_strike_state(&m);
    let theta = [150.0, 1.0];
    let (q, qd) = (&x[..9], &x[9..18]);
    let heel = m.contact_index("l.heel").unwrap();
    let gap = |q: &[f64]| m.contact_point(heel, q, &theta).1;
    let h = 1e-6;
    let shifted = |s: f64| {
        q.iter()
            .zip(qd)
            .map(|(a, v)| a + s * v)
            .collect::<Vec<f64>>()
    };
    let depth = -gap(q);
    let rate = -(gap(&shifted(h)) - gap(&shifted(-h))) / (2.0 * h);
    assert!(
        depth > 0.0029 && depth < 0.0031,
        "the heel is 3 mm in: {depth}"
    );
    assert!(rate > 0.0, "and moving down: {rate}");
    let mut xdot = vec![0.0; m.nx()];
    let mut lam = vec![0.0; set.rows.len()];
    m.dynamics::<f64>(
        &set,
        &x,
        &vec![0.0; m.nu()],
        &theta,
        &mut xdot,
        &mut lam,
        None,
    )
    .unwrap();
    let normal = set
        .rows
        .iter()
        .position(|r| r.contact == heel && r.kind == footfall::model::RowKind::Normal)
        .unwrap();
    let expect = 150e3 * depth + 1e3 * rate;
    assert!(
        (lam[normal] - expect).abs() < 1e-6 * expect,
        "pad force {} N, k·d + c·ḋ = {expect} N",
        lam[normal]
    );

    // equations of motion with every row's force
    let qdd = &xdot[9..18];
    let (mass, bias) = m.mass_matrix_and_bias(q, qd, &theta);
    let g = m.constraint_jacobian_at(&set, q, &theta);
    for r in 0..9 {
        let lhs: f64 = (0..9).map(|c| mass[r * 9 + c] * qdd[c]).sum::<f64>() + bias[r];
        let rhs: f64 = (0..set.rows.len()).map(|i| g[i * 9 + r] * lam[i]).sum();
        assert!(
            (lhs - rhs).abs() < 1e-8 * (1.0 + rhs.abs()),
            "row {r}: M q̈ + c = {lhs}, Gᵀλ = {rhs}"
        );
    }

    // rigid rows: d/dt(G q̇) = −γ G q̇ (rolling), −2α G q̇ − β² φ (forefoot contact)
    let cs = m.contact_settings();
    let w = |s: f64| {
        let qs: Vec<f64> = q.iter().zip(qd).map(|(a, v)| a + s * v).collect();
        let vs: Vec<f64> = qd.iter().zip(qdd).map(|(v, a)| v + s * a).collect();
        let g = m.constraint_jacobian_at(&set, &qs, &theta);
        (0..set.rows.len())
            .map(|i| (0..9).map(|c| g[i * 9 + c] * vs[c]).sum::<f64>())
            .collect::<Vec<f64>>()
    };
    let (wp, wm, w0) = (w(h), w(-h), w(0.0));
    for (i, row) in set.rows.iter().enumerate() {
        let dw = (wp[i] - wm[i]) / (2.0 * h);
        let expect = match row.kind {
            _ if i == normal => continue,
            footfall::model::RowKind::Tangential => -cs.baumgarte_gamma * w0[i],
            footfall::model::RowKind::Normal => {
                let phi = m.contact_point(row.contact, q, &theta).1;
                -2.0 * cs.baumgarte_alpha * w0[i] - cs.baumgarte_beta * cs.baumgarte_beta * phi
            }
        };
        assert!(
            (dw - expect).abs() < 1e-4 * (1.0 + expect.abs()),
            "row {i} ({:?}): d/dt(G q̇) = {dw}, expected {expect}",
            row.kind
        );
    }
}

/// Exact derivatives of the padded dynamics: the state and parameter columns of the
/// dynamics Jacobian (forward AD) against central differences.
#[test]
fn heel_pad_dynamics_jacobian_matches_finite_differences() {
    let m = padded();
    let (set, x) = heel_strike_state(&m);
    let theta = vec![150.0, 1.0];
    let (nx, nu) = (m.nx(), m.nu());
    let u = vec![0.0; nu];
    let mut xdot = vec![0.0; nx];
    let mut jac = vec![0.0; nx * (nx + nu + 2)];
    m.dynamics_jacobian(&set, &x, &u, &theta, &mut xdot, &mut jac)
        .unwrap();
    let f = |x: &[f64], th: &[f64]| {
        let mut xd = vec![0.0; nx];
        let mut lam = vec![0.0; set.rows.len()];
        m.dynamics::<f64>(&set, x, &u, th, &mut xd, &mut lam, None)
            .unwrap();
        xd
    };
    // worst relative error of Jacobian column `col` against a central difference of
    // `perturbed(±h)`
    let column_error = |col: usize, h: f64, perturbed: &dyn Fn(f64) -> Vec<f64>| {
        let (fa, fb) = (perturbed(h), perturbed(-h));
        (0..nx)
            .map(|r| (fa[r] - fb[r]) / (2.0 * h))
            .enumerate()
            .map(|(r, fd)| (fd - jac[col * nx + r]).abs() / (1.0 + fd.abs()))
            .fold(0.0f64, f64::max)
    };
    let mut worst = 0.0f64;
    for c in 0..18 {
        let along = |h: f64| {
            let mut a = x.clone();
            a[c] += h;
            f(&a, &theta)
        };
        worst = worst.max(column_error(c, 1e-6, &along));
    }
    for k in 0..2 {
        let along = |h: f64| {
            let mut a = theta.clone();
            a[k] += h;
            f(&x, &a)
        };
        worst = worst.max(column_error(
            nx + nu + k,
            1e-4 * theta[k].abs().max(1.0),
            &along,
        ));
    }
    assert!(worst < 1e-5, "AD vs central differences: {worst:e}");
}

/// At heel strike the pad takes no impulse: only the heel's rolling row is impulsive —
/// momentum changes by G_tᵀΛ_t alone, the heel stops slipping, its normal velocity is
/// not set to zero (the pad takes it up) — where the rigid heel stops dead.
#[test]
fn heel_pad_takes_no_impulse_at_heel_strike() {
    let m = padded();
    let (_, x) = heel_strike_state(&m);
    let set = m.constraint_set("heel", &[("l.heel", true)]).unwrap();
    let theta = [150.0, 1.0];
    let (q, qd) = (&x[..9], &x[9..18]);
    let (qd_plus, imp) = m.impact::<f64>(&set, q, qd, &theta).unwrap();
    let g = m.constraint_jacobian_at(&set, q, &theta);
    let (mass, _) = m.mass_matrix_and_bias(q, qd, &theta);
    for r in 0..9 {
        let dp: f64 = (0..9).map(|c| mass[r * 9 + c] * (qd_plus[c] - qd[c])).sum();
        let gl: f64 = (0..set.rows.len()).map(|i| g[i * 9 + r] * imp[i]).sum();
        assert!(
            (dp - gl).abs() < 1e-9 * (1.0 + gl.abs()),
            "momentum row {r}: {dp} vs {gl}"
        );
    }
    let normal = set
        .rows
        .iter()
        .position(|r| r.kind == footfall::model::RowKind::Normal)
        .unwrap();
    for (i, row) in set.rows.iter().enumerate() {
        let v: f64 = (0..9).map(|c| g[i * 9 + c] * qd_plus[c]).sum();
        match row.kind {
            footfall::model::RowKind::Normal => {
                assert_eq!(imp[i], 0.0, "no impulse through the pad");
                assert!(
                    v.abs() > 0.01,
                    "the heel's normal velocity is left to the pad: {v} m/s"
                );
            }
            footfall::model::RowKind::Tangential => {
                assert!(imp[i].abs() > 1e-3, "the rolling constraint is impulsive");
                assert!(v.abs() < 1e-10, "no slip after the impact: {v}");
            }
        }
    }
    // the rigid heel stops dead
    let rigid = model("opensim_subject01_torque.json", "double_circle.json");
    let (qd_rigid, _) = rigid.impact::<f64>(&set, q, qd, &[]).unwrap();
    let v: f64 = (0..9).map(|c| g[normal * 9 + c] * qd_rigid[c]).sum();
    assert!(v.abs() < 1e-10, "rigid heel: {v}");
}

#[test]
fn heel_pad_needs_a_heel_primitive_and_sane_values() {
    use footfall::model::spec::{FootSpec, ModelSpec};
    let mp = root().join("models/opensim_subject01.json");
    let fp = root().join("models/feet/ellipse.json");
    let mut spec = ModelSpec::load(&mp).unwrap();
    spec.effects = vec![EffectSpec::parse_cli("heel_pad_compliance").unwrap()];
    let err =
        footfall::model::GaitModel::from_specs(&spec, &mp, &FootSpec::load(&fp).unwrap(), &fp)
            .unwrap_err()
            .to_string();
    assert!(
        err.contains("primitive") && err.contains("'heel'") && err.contains("sole"),
        "{err}"
    );
    let e = EffectSpec::parse_cli("heel_pad_compliance:stiffness=200").unwrap();
    assert_eq!(
        e,
        EffectSpec::HeelPadCompliance {
            primitive: "heel".into(),
            stiffness: 200.0,
            damping: 1.0,
            free: vec!["stiffness".into(), "damping".into()]
        }
    );
    for (bad, needle) in [
        ("heel_pad_compliance:stiffness=0", "stiffness"),
        ("heel_pad_compliance:damping=-1", "damping"),
    ] {
        let err = EffectSpec::parse_cli(bad).unwrap_err().to_string();
        assert!(err.contains(needle), "{bad}: {err}");
    }
}

/// The command-line form a diagnosis prints to add an effect reads back as the same
/// entry: every catalog and measurement effect with all parameters freed, with none freed, and a clock
/// held at a reading (`force_plate_time_offset:offset=0.0236,free=`, side `both`).
#[test]
fn an_effects_command_line_form_reads_back_as_the_same_entry() {
    let mut entries = Vec::new();
    for e in catalog().into_iter().chain(measurement_effects()) {
        let mut free = e.clone();
        free.free_all();
        entries.push(free);
        entries.push(e.fixed());
    }
    entries.push(EffectSpec::ForcePlateTimeOffset {
        side: "both".into(),
        offset: 0.0236,
        free: vec![],
    });
    for e in entries {
        let text = e
            .cli_text()
            .unwrap_or_else(|| panic!("{e:?} has no command-line form"));
        let back = EffectSpec::parse_cli(&text).unwrap_or_else(|err| panic!("{text}: {err}"));
        assert_eq!(
            serde_json::to_value(&back).unwrap(),
            serde_json::to_value(&e).unwrap(),
            "{text}"
        );
    }
    let held = EffectSpec::parse_cli("force_plate_time_offset:offset=0.0236,free=").unwrap();
    assert_eq!(
        held.cli_text().unwrap(),
        "force_plate_time_offset:offset=0.0236,side=both,free="
    );
}

/// A clock held for both plates (the correction a diagnosis found) and one plate's
/// further clock error are one model: the second is added in addition to the first, its
/// parameter named by its side, and that plate's offset is their sum, the other plate's
/// the held one alone. Two free clocks of overlapping plates, or two of one side, are
/// refused.
#[test]
fn a_held_shared_clock_and_one_plates_clock_add_up() {
    use footfall::model::GaitModel;
    let r = root();
    let (m, f) = (
        r.join("models/opensim_subject01.json"),
        r.join("models/feet/ellipse.json"),
    );
    let held = EffectSpec::parse_cli("force_plate_time_offset:offset=0.02,free=").unwrap();
    let left = EffectSpec::parse_cli("force_plate_time_offset:side=left").unwrap();
    assert!(held.composes_with(&left) && !left.composes_with(&held));
    let model = GaitModel::load_with_effects(&m, &f, &[held.clone(), left.clone()]).unwrap();
    assert_eq!(model.ntheta(), 1);
    let names: Vec<&str> = model.parameters().iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "force_plate_time_offset.offset",
            "force_plate_time_offset.left.offset"
        ]
    );
    let adj = model.measurement_adjust(&[-0.005]);
    // sides: 0 right, 1 left
    assert!((adj.force_time_offset[0] - 0.02).abs() < 1e-15);
    assert!((adj.force_time_offset[1] - 0.015).abs() < 1e-15);
    let mut shared = held.clone();
    shared.free_all();
    assert!(GaitModel::load_with_effects(&m, &f, &[shared, left.clone()]).is_err());
    let held_left =
        EffectSpec::parse_cli("force_plate_time_offset:side=left,offset=0.01,free=").unwrap();
    assert!(GaitModel::load_with_effects(&m, &f, &[held_left, left]).is_err());
}
