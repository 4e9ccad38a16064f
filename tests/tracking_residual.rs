//! Tracking residuals: zero at the model's own motion and forces, exact Jacobians, and
//! generic foot loads equal to the reported ground reaction forces and CoP.

use crate::common;
use common::*;
use footfall::model::gait::ContactReport;
use footfall::ocp::NodeFunction;
use footfall::problems::tracking::{NodeTarget, TrackingResidual, TrackingWeights};
use footfall::problems::AdTerm;

fn state(m: &footfall::model::GaitModel, set: &footfall::model::ConstraintSet) -> Vec<f64> {
    let q = [1.6, 0.95, 0.11, 0.3, -0.2, 0.1, -0.3, -0.5, 0.05];
    let qd = [1.1, 0.1, 0.2, -1.0, 1.0, 0.3, 1.5, -0.8, 1.0];
    let (q, qd, _) = m.project(set, &q, &qd, &m.theta0()).unwrap();
    let mut x = q;
    x.extend(qd);
    x.extend(vec![0.2; m.na()]);
    x
}

#[test]
fn residual_vanishes_at_the_models_own_motion_and_has_exact_jacobian() {
    for (foot, contacts) in [
        ("ellipse.json", vec![("r.sole", true), ("l.sole", true)]),
        (
            "double_circle.json",
            vec![("r.heel", true), ("r.forefoot", false)],
        ),
    ] {
        let m = model("opensim_subject01.json", foot);
        let set = m.constraint_set("s", &contacts).unwrap();
        let x = state(&m, &set);
        let u = vec![0.3; m.nu()];
        // the model's own forces and CoP, from the f64 report path
        let mut xdot = vec![0.0; m.nx()];
        let mut lam = vec![0.0; set.rows.len()];
        let mut rep = ContactReport::default();
        m.dynamics(&set, &x, &u, &[], &mut xdot, &mut lam, Some(&mut rep))
            .unwrap();
        let loads = m.foot_loads(&set, &rep);
        let generic = m.foot_loads_generic::<f64>(&set, &x, &u, &[]).unwrap();
        for s in 0..2 {
            assert!(
                (generic[s].0 - loads[s].fx).abs() < 1e-9
                    && (generic[s].1 - loads[s].fy).abs() < 1e-9
            );
            if loads[s].fy.abs() > 1e-6 {
                assert!(
                    (generic[s].2 / generic[s].1 - loads[s].cop_x).abs() < 1e-9,
                    "CoP"
                );
            }
        }
        let nq = m.nq();
        let target = NodeTarget {
            time: 0.0,
            q: x[..nq].iter().map(|v| Some(*v)).collect(),
            qd: x[nq..2 * nq].iter().map(|v| Some(*v)).collect(),
            feet: [0, 1].map(|s| {
                Some((
                    loads[s].fx,
                    loads[s].fy,
                    if loads[s].fy > 1.0 {
                        Some(loads[s].cop_x)
                    } else {
                        None
                    },
                ))
            }),
        };
        let mut w = TrackingWeights::seed(nq, 800.0, 0.305);
        w.excitation = 0.0;
        w.activation = 0.0;
        let r = AdTerm(TrackingResidual::new(&m, set.clone(), target, w, None));
        let z: Vec<f64> = x.iter().chain(&u).copied().collect();
        let mut v = vec![0.0; r.dim()];
        let mut jac = vec![0.0; r.dim() * z.len()];
        r.eval(&z, &mut v, Some(&mut jac)).unwrap();
        let worst = v.iter().map(|a| a.abs()).fold(0.0, f64::max);
        assert!(
            worst < 1e-9,
            "{foot}: residual at the model's own motion {worst:e}"
        );
        // Jacobian vs central differences (perturbed point so all terms are active)
        let mut zp = z.clone();
        let mut rng = Rng::new(4);
        for v in zp.iter_mut() {
            *v += rng.uniform(-0.01, 0.01);
        }
        r.eval(&zp, &mut v, Some(&mut jac)).unwrap();
        let d = r.dim();
        let mut err = 0.0f64;
        for c in 0..zp.len() {
            let h = 1e-6 * zp[c].abs().max(1.0);
            let (mut a, mut b) = (zp.clone(), zp.clone());
            a[c] += h;
            b[c] -= h;
            let (mut va, mut vb) = (vec![0.0; d], vec![0.0; d]);
            r.eval(&a, &mut va, None).unwrap();
            r.eval(&b, &mut vb, None).unwrap();
            for i in 0..d {
                err = err.max(((va[i] - vb[i]) / (2.0 * h) - jac[i + c * d]).abs());
            }
        }
        assert!(err < 1e-5, "{foot}: Jacobian vs FD {err:e}");
    }
}

/// Measurement effects: a force-plate clock offset compares the model with the measured
/// loads at t + δ, a CoP offset moves the measured CoP. At zero offsets the residual
/// equals the plain one; its derivatives in the offsets (free parameters θ) match central
/// differences; a clock offset equal to the shift of a shifted measurement and a CoP
/// offset equal to the added offset zero the load residuals.
#[test]
fn measurement_effects_shift_the_targets_with_exact_parameter_derivatives() {
    use footfall::data::CubicSpline;
    use footfall::problems::tracking::MeasuredLoads;
    use std::sync::Arc;
    let effects = serde_json::json!([
        { "type": "force_plate_time_offset", "free": ["offset"] },
        { "type": "cop_offset", "free": ["offset"] }
    ]);
    let m = model_with_effects("opensim_subject01.json", "ellipse.json", effects);
    let plain = model("opensim_subject01.json", "ellipse.json");
    assert_eq!(m.ntheta(), 2);
    assert!(m.has_measurement_effects() && !plain.has_measurement_effects());
    let set = m.constraint_set("s", &[("r.sole", true)]).unwrap();
    let x = state(&m, &set);
    let u = vec![0.3; m.nu()];
    let loads = m
        .foot_loads_generic::<f64>(&set, &x, &u, &[0.0, 0.0])
        .unwrap();
    let (fx, fy, mom) = loads[0];
    let cop = mom / fy;
    // a measurement that is the model's loads at t = 0.5 s, varying linearly in time, and
    // recorded with a clock offset of 0.012 s and a CoP offset of 0.02 m
    let (delay, dcop, t_node) = (0.012, 0.02, 0.5);
    let time: Vec<f64> = (0..200).map(|k| k as f64 * 0.005).collect();
    let shape = |t: f64| 1.0 + 0.8 * (t - t_node - delay);
    let spl = |v: f64| {
        CubicSpline::new(
            &time,
            &time.iter().map(|&t| v * shape(t)).collect::<Vec<_>>(),
        )
        .unwrap()
    };
    let zero = CubicSpline::new(&time, &vec![0.0; time.len()]).unwrap();
    let cop_series: Vec<f64> = time
        .iter()
        .map(|&t| cop + dcop + 0.1 * (t - t_node - delay))
        .collect();
    let measured = Arc::new(MeasuredLoads {
        fx: [spl(fx), zero.clone()],
        fy: [spl(fy), zero],
        time: time.clone(),
        cop_x: [cop_series, vec![f64::NAN; time.len()]],
        belt_speed: 0.0,
    });
    let nq = m.nq();
    let target = NodeTarget {
        time: t_node,
        q: x[..nq].iter().map(|v| Some(*v)).collect(),
        qd: x[nq..2 * nq].iter().map(|v| Some(*v)).collect(),
        feet: [
            Some((
                fx * shape(t_node),
                fy * shape(t_node),
                Some(cop + dcop - 0.1 * delay),
            )),
            None,
        ],
    };
    let mut w = TrackingWeights::seed(nq, 800.0, 0.305);
    w.excitation = 0.0;
    w.activation = 0.0;
    let with = AdTerm(TrackingResidual::new(
        &m,
        set.clone(),
        target.clone(),
        w.clone(),
        Some(measured),
    ));
    let without = AdTerm(TrackingResidual::new(&plain, set.clone(), target, w, None));
    let z0: Vec<f64> = x.iter().chain(&u).copied().collect();
    let d = with.dim();
    let eval = |r: &AdTerm<TrackingResidual>, z: &[f64]| {
        let mut v = vec![0.0; d];
        r.eval(z, &mut v, None).unwrap();
        v
    };
    let at = |th: [f64; 2]| z0.iter().copied().chain(th).collect::<Vec<f64>>();
    let a = eval(&with, &at([0.0, 0.0]));
    let b = eval(&without, &z0);
    assert!(
        rel_diff(&a, &b, 1e-12) < 1e-10,
        "zero offsets change nothing"
    );
    assert!(
        a.iter().map(|v| v.abs()).fold(0.0, f64::max) > 1e-3,
        "the shifted measurement is not matched at zero offsets"
    );
    let fit = eval(&with, &at([delay, dcop]));
    let worst = fit.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(
        worst < 1e-9,
        "the true offsets explain the measurement: worst residual {worst:e}"
    );
    // θ derivatives vs central differences at a point off the truth
    let zp = at([0.004, -0.01]);
    let mut jac = vec![0.0; d * zp.len()];
    let mut v = vec![0.0; d];
    with.eval(&zp, &mut v, Some(&mut jac)).unwrap();
    let n = zp.len();
    let mut err = 0.0f64;
    let mut any = 0.0f64;
    for c in [n - 2, n - 1] {
        let h = 1e-6;
        let (mut p, mut q) = (zp.clone(), zp.clone());
        p[c] += h;
        q[c] -= h;
        let (vp, vq) = (eval(&with, &p), eval(&with, &q));
        for i in 0..d {
            let fd = (vp[i] - vq[i]) / (2.0 * h);
            err = err.max((fd - jac[i + c * d]).abs());
            any = any.max(fd.abs());
        }
    }
    assert!(any > 1e-2, "the offsets move the residual");
    assert!(err < 1e-6 * any.max(1.0), "θ Jacobian vs FD {err:e}");
}

/// The residual actuators' figures of a solution: RMS, peak and the share of nodes on the
/// bound, against values worked out by hand; the model's own actuators do not count.
#[test]
fn residual_use_reports_rms_peak_and_saturation() {
    use footfall::integrate::ControlShape;
    use footfall::problems::evaluation::{residual_use, GaitSolution, PhaseSolution};
    let m = model("opensim_subject01.json", "ellipse.json").with_residual_actuators(100.0, 50.0);
    assert!(residual_use(
        &model("opensim_subject01.json", "ellipse.json"),
        &GaitSolution {
            phases: vec![],
            theta: vec![]
        }
    )
    .is_empty());
    let (base, nr) = (m.nu_actuators(), m.residual_scales().len());
    assert_eq!(nr, 9);
    // four nodes: pelvis_x residual at controls 1, −1, 0.5, 0 (two of four on the bound);
    // the hip_r torque at 0.2 throughout; actuators at 1 (must not count as saturation)
    let u = |c: f64| {
        let mut u = vec![1.0; base + nr];
        u[base..].iter_mut().for_each(|v| *v = 0.0);
        u[base] = c;
        u[base + 3] = 0.2;
        u
    };
    let phase = PhaseSolution {
        name: "p".into(),
        set: 0,
        t0: 0.5,
        duration: 0.4,
        controls: ControlShape::Constant,
        x: vec![vec![0.0; m.nx()]; 5],
        u: vec![u(1.0), u(-1.0), u(0.5), u(0.0)],
    };
    let uses = residual_use(
        &m,
        &GaitSolution {
            phases: vec![phase],
            theta: vec![],
        },
    );
    assert_eq!(uses.len(), 9);
    let px = &uses[0];
    assert_eq!(
        (px.name.as_str(), px.unit, px.bound),
        ("pelvis_x_residual", "N", 100.0)
    );
    let rms = ((100.0f64.powi(2) * 2.0 + 50.0f64.powi(2)) / 4.0).sqrt();
    assert!(
        (px.rms - rms).abs() < 1e-12 && px.peak == 100.0 && px.at_bound_fraction == 0.5,
        "{px:?}"
    );
    assert_eq!(px.times, vec![0.5, 0.6, 0.7, 0.8]);
    let hip = &uses[3];
    assert_eq!(
        (hip.name.as_str(), hip.unit, hip.bound),
        ("hip_r_residual", "N·m", 50.0)
    );
    assert!(
        (hip.rms - 10.0).abs() < 1e-12
            && (hip.peak - 10.0).abs() < 1e-12
            && hip.at_bound_fraction == 0.0,
        "{hip:?}"
    );
    assert!(uses[1].rms == 0.0 && uses[1].at_bound_fraction == 0.0);
}

/// A CoP sample compared at the instant a plate's clock offset moves it to (a sample
/// target, [`TrackingResidual::at_measured_values`]) on a treadmill trial moved
/// overground: its overground CoP holds the belt's displacement at its own instant, so
/// compared δ earlier it is `v·δ` further back. Without the correction a left plate 20 ms
/// early on the bundled trial's 1.13 m/s belt held at its true offset compared its CoP
/// 23 mm off.
#[test]
fn a_moved_cop_sample_moves_with_the_treadmill_belt() {
    use footfall::data::CubicSpline;
    use footfall::problems::tracking::MeasuredLoads;
    use std::sync::Arc;
    let effects = serde_json::json!([{ "type": "force_plate_time_offset", "free": ["offset"] }]);
    let m = model_with_effects("opensim_subject01.json", "ellipse.json", effects);
    let set = m.constraint_set("s", &[("r.sole", true)]).unwrap();
    let x = state(&m, &set);
    let u = vec![0.3; m.nu()];
    let (fx, fy, mom) = m.foot_loads_generic::<f64>(&set, &x, &u, &[0.0]).unwrap()[0];
    let time: Vec<f64> = (0..20).map(|k| k as f64 * 0.05).collect();
    let flat = |v: f64| CubicSpline::new(&time, &vec![v; time.len()]).unwrap();
    let measured = |belt_speed: f64| {
        Arc::new(MeasuredLoads {
            fx: [flat(fx), flat(0.0)],
            fy: [flat(fy), flat(0.0)],
            time: time.clone(),
            cop_x: [vec![mom / fy; time.len()], vec![f64::NAN; time.len()]],
            belt_speed,
        })
    };
    let nq = m.nq();
    let target = |cop: f64| NodeTarget {
        time: 0.5,
        q: vec![None; nq],
        qd: vec![None; nq],
        feet: [Some((fx, fy, Some(cop))), None],
    };
    let w = TrackingWeights::seed(nq, 800.0, 0.305);
    let residual = |cop: f64, belt: f64| {
        AdTerm(
            TrackingResidual::new(
                &m,
                set.clone(),
                target(cop),
                w.clone(),
                Some(measured(belt)),
            )
            .data_only()
            .at_measured_values(),
        )
    };
    let eval = |r: &AdTerm<TrackingResidual>, theta: f64| {
        let z: Vec<f64> = x.iter().chain(&u).copied().chain([theta]).collect();
        let mut v = vec![0.0; r.dim()];
        r.eval(&z, &mut v, None).unwrap();
        v
    };
    let (v, delta, cop) = (1.1322, -0.020, mom / fy + 0.01);
    // the model's own loads with the CoP 1 cm off: the CoP row alone is nonzero
    let plain = eval(&residual(cop, 0.0), delta);
    assert!(plain[2].abs() > 1e-3 && plain[..2].iter().all(|r| r.abs() < 1e-12));
    // on the belt, compared δ earlier: as the CoP v·δ further back on a still floor
    let moved = eval(&residual(cop, v), delta);
    let still = eval(&residual(cop - v * delta, 0.0), delta);
    assert!(
        rel_diff(&moved, &still, 1e-12) < 1e-12,
        "{moved:?} against {still:?}"
    );
    assert!((moved[2] - plain[2]).abs() > 0.1 * plain[2].abs());
    // with no offset the belt changes nothing
    assert_eq!(eval(&residual(cop, v), 0.0), eval(&residual(cop, 0.0), 0.0));
}
