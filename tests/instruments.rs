//! Instruments per force plate (clock offset, CoP offset and gain of each foot's plate, a
//! body-mass error) and actuator properties (MTG damping, strength, activation time
//! constants) as effects: each against closed-form truth, with exact parameter
//! derivatives checked against central differences; and a plate's clock offset moving
//! the contact events that plate's force threshold gave.

use crate::common;
use common::*;
use footfall::data::{read_sagittal_csv, CubicSpline, GaitData};
use footfall::model::effects::{catalog, measurement_effects, EffectSpec};
use footfall::model::GaitModel;
use footfall::ocp::NodeFunction;
use footfall::problems::track::{TargetSides, TrackingSetup};
use footfall::problems::tracking::{
    MeasuredLoads, NodeClock, NodeTarget, TrackingResidual, TrackingWeights,
};
use footfall::problems::AdTerm;
use std::sync::Arc;

fn state(m: &GaitModel, set: &footfall::model::ConstraintSet) -> Vec<f64> {
    let q = [1.6, 0.95, 0.11, 0.3, -0.2, 0.1, -0.3, -0.5, 0.05];
    let qd = [1.1, 0.1, 0.2, -1.0, 1.0, 0.3, 1.5, -0.8, 1.0];
    let (q, qd, _) = m.project(set, &q, &qd, &m.theta0()).unwrap();
    let mut x = q;
    x.extend(qd);
    x.extend(vec![0.2; m.na()]);
    x
}

/// Central-difference check of `f`'s Jacobian at `z` in the columns `cols`: the largest
/// absolute difference.
fn jacobian_error(f: &dyn NodeFunction, z: &[f64], cols: std::ops::Range<usize>) -> f64 {
    let d = f.dim();
    let mut v = vec![0.0; d];
    let mut jac = vec![0.0; d * z.len()];
    f.eval(z, &mut v, Some(&mut jac)).unwrap();
    let mut err = 0.0f64;
    for c in cols {
        let h = 1e-6 * z[c].abs().max(1.0);
        let (mut a, mut b) = (z.to_vec(), z.to_vec());
        a[c] += h;
        b[c] -= h;
        let (mut va, mut vb) = (vec![0.0; d], vec![0.0; d]);
        f.eval(&a, &mut va, None).unwrap();
        f.eval(&b, &mut vb, None).unwrap();
        for i in 0..d {
            err = err.max(((va[i] - vb[i]) / (2.0 * h) - jac[i + c * d]).abs());
        }
    }
    err
}

fn eval(f: &dyn NodeFunction, z: &[f64]) -> Vec<f64> {
    let mut v = vec![0.0; f.dim()];
    f.eval(z, &mut v, None).unwrap();
    v
}

/// In double stance, a clock offset of the right plate, a CoP offset of the left and a
/// gain of the left move only their own foot's rows; the measurement made by delaying
/// the right foot's loads, offsetting the left's CoP and scaling the left's forces is
/// matched exactly at the true values; the θ columns of the Jacobian match central
/// differences.
#[test]
fn per_plate_effects_touch_only_their_foot_and_have_exact_parameter_derivatives() {
    let effects = serde_json::json!([
        { "type": "force_plate_time_offset", "side": "right", "free": ["offset"] },
        { "type": "cop_offset", "side": "left", "free": ["offset"] },
        { "type": "force_plate_gain", "side": "left", "free": ["error"] }
    ]);
    let m = model_with_effects("opensim_subject01.json", "ellipse.json", effects);
    let names: Vec<&str> = m.parameters().iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "force_plate_time_offset.right.offset",
            "cop_offset.left.offset",
            "force_plate_gain.left.error"
        ]
    );
    let set = m
        .constraint_set("ds", &[("r.sole", true), ("l.sole", true)])
        .unwrap();
    let x = state(&m, &set);
    let u = vec![0.3; m.nu()];
    let loads = m
        .foot_loads_generic::<f64>(&set, &x, &u, &[0.0; 3])
        .unwrap();
    assert!(loads.iter().all(|l| l.1.abs() > 1.0), "both feet loaded");
    // truth: right plate 12 ms late, left CoP 20 mm forward, left forces 6 % high
    let (delay, dcop, gain, t_node) = (0.012, 0.02, 0.06, 0.5);
    let time: Vec<f64> = (0..200).map(|k| k as f64 * 0.005).collect();
    let shape = |t: f64, late: f64| 1.0 + 0.8 * (t - t_node - late);
    let spl = |v: f64, late: f64| {
        CubicSpline::new(
            &time,
            &time.iter().map(|&t| v * shape(t, late)).collect::<Vec<_>>(),
        )
        .unwrap()
    };
    let cop = |s: usize| loads[s].2 / loads[s].1;
    let measured = Arc::new(MeasuredLoads {
        fx: [spl(loads[0].0, delay), spl(loads[1].0 * (1.0 + gain), 0.0)],
        fy: [spl(loads[0].1, delay), spl(loads[1].1 * (1.0 + gain), 0.0)],
        time: time.clone(),
        cop_x: [
            time.iter()
                .map(|&t| cop(0) + 0.1 * (t - t_node - delay))
                .collect(),
            time.iter()
                .map(|&t| cop(1) + dcop + 0.1 * (t - t_node))
                .collect(),
        ],
        belt_speed: 0.0,
    });
    let nq = m.nq();
    let target = NodeTarget {
        time: t_node,
        q: x[..nq].iter().map(|v| Some(*v)).collect(),
        qd: x[nq..2 * nq].iter().map(|v| Some(*v)).collect(),
        // the values at the node (unused through the measured loads, but they mark the
        // rows)
        feet: [0, 1].map(|s| Some((loads[s].0, loads[s].1, Some(cop(s))))),
    };
    let mut w = TrackingWeights::seed(nq, 800.0, 0.305);
    w.excitation = 0.0;
    w.activation = 0.0;
    let r = AdTerm(TrackingResidual::new(
        &m,
        set.clone(),
        target,
        w,
        Some(measured),
    ));
    let z = |th: [f64; 3]| x.iter().chain(&u).copied().chain(th).collect::<Vec<f64>>();
    // rows: 7 angles, 7 velocities (pelvis x, y untracked), then per foot fx, fy, CoP
    let rows = |v: &[f64], s: usize| v[14 + 3 * s..17 + 3 * s].to_vec();
    let at_truth = eval(&r, &z([delay, dcop, gain]));
    for s in 0..2 {
        let worst = rows(&at_truth, s)
            .iter()
            .map(|v| v.abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "foot {s} at the truth: {worst:e}");
    }
    // each effect moves only its own foot's rows
    let base = eval(&r, &z([0.0; 3]));
    assert!(rows(&base, 0).iter().any(|v| v.abs() > 1e-4));
    let right_only = eval(&r, &z([delay, 0.0, 0.0]));
    assert_eq!(
        rows(&right_only, 1),
        rows(&base, 1),
        "right clock, left rows"
    );
    let left_only = eval(&r, &z([0.0, dcop, gain]));
    assert_eq!(
        rows(&left_only, 0),
        rows(&base, 0),
        "left CoP and gain, right rows"
    );
    // exact derivatives in θ (and in x, u) at a point away from the truth
    let zp = z([0.004, -0.01, 0.03]);
    let n = zp.len();
    let err = jacobian_error(&r, &zp, 0..n);
    assert!(err < 1e-5, "Jacobian vs central differences: {err:e}");
}

/// A node whose instant moves with the plates' clocks compares the model with the
/// kinematics at `t + c·δ` and with each foot's loads at `t + c·δ + δ_foot`: equal to a
/// fixed node built at the moved instant, with exact derivatives in δ.
#[test]
fn a_moving_node_reads_its_targets_at_the_moved_instant_with_exact_derivatives() {
    let effects = serde_json::json!([
        { "type": "force_plate_time_offset", "side": "right", "free": ["offset"] },
        { "type": "force_plate_time_offset", "side": "left", "free": ["offset"] }
    ]);
    let m = model_with_effects("opensim_subject01.json", "ellipse.json", effects);
    let set = m.constraint_set("ss", &[("r.sole", true)]).unwrap();
    let x = state(&m, &set);
    let u = vec![0.3; m.nu()];
    let nq = m.nq();
    let time: Vec<f64> = (0..120).map(|k| k as f64 / 60.0).collect();
    // smooth kinematics and loads, each its own function of time
    let kin: Vec<CubicSpline> = (0..nq)
        .map(|i| {
            let y: Vec<f64> = time
                .iter()
                .map(|&t| x[i] + 0.2 * (3.0 * t + i as f64).sin())
                .collect();
            CubicSpline::new(&time, &y).unwrap()
        })
        .collect();
    let force = |a: f64, f: f64| {
        CubicSpline::new(
            &time,
            &time
                .iter()
                .map(|&t| a * (1.0 + 0.3 * (f * t).cos()))
                .collect::<Vec<_>>(),
        )
        .unwrap()
    };
    let measured = Arc::new(MeasuredLoads {
        fx: [force(40.0, 2.0), force(0.0, 1.0)],
        fy: [force(700.0, 2.5), force(0.0, 1.0)],
        time: time.clone(),
        cop_x: [
            time.iter().map(|&t| 0.3 + 0.2 * t).collect(),
            vec![f64::NAN; time.len()],
        ],
        belt_speed: 0.0,
    });
    let mut w = TrackingWeights::seed(nq, 800.0, 0.305);
    w.excitation = 0.0;
    w.activation = 0.0;
    let t_node = 0.8;
    let target_at = |t: f64| NodeTarget {
        time: t,
        q: kin.iter().map(|s| Some(s.eval(t))).collect(),
        qd: kin.iter().map(|s| Some(s.derivative(t))).collect(),
        feet: [Some((0.0, 0.0, Some(0.5))), None],
    };
    let coeff = [-0.4, -1.0];
    let moving = AdTerm(
        TrackingResidual::new(
            &m,
            set.clone(),
            target_at(t_node),
            w.clone(),
            Some(measured.clone()),
        )
        .with_clock(NodeClock {
            coeff,
            kinematics: Arc::new(kin.clone()),
        }),
    );
    let delta = [0.015, -0.02];
    let moved = t_node + coeff[0] * delta[0] + coeff[1] * delta[1];
    // the same node fixed at the moved instant, its loads read at moved + δ_right through
    // the same clock effect (the left clock's own coefficient is what moves the node)
    let fixed = AdTerm(TrackingResidual::new(
        &m,
        set.clone(),
        target_at(moved),
        w,
        Some(measured),
    ));
    let z: Vec<f64> = x.iter().chain(&u).copied().chain(delta).collect();
    let a = eval(&moving, &z);
    let b = eval(&fixed, &z);
    assert!(
        rel_diff(&a, &b, 1e-9) < 1e-9,
        "moving node vs node built at the moved instant"
    );
    let n = z.len();
    let err = jacobian_error(&moving, &z, n - 2..n);
    assert!(err < 1e-6, "δ columns vs central differences: {err:e}");
}

fn trial(name: &str) -> GaitData {
    let d = read_sagittal_csv(
        &root()
            .join("tests/data/real_hidden")
            .join(name)
            .join("trial.csv"),
    )
    .unwrap();
    let v = d.belt_speed.unwrap();
    d.to_overground(v).unwrap()
}

fn setup_of(
    m: &GaitModel,
    data: &GaitData,
    sides: TargetSides,
) -> Result<TrackingSetup, footfall::problems::ProblemError> {
    let p = path("phases/ellipse_walk.json");
    let seq = footfall::phases::PhaseSequence::load(&p).unwrap();
    let sets = seq.resolve(m, &p).unwrap();
    TrackingSetup::new_with_sides(m, &seq, &sets, data, sides)
}

fn durations(s: &TrackingSetup) -> Vec<f64> {
    s.node_times.iter().map(|t| t[t.len() - 1] - t[0]).collect()
}

/// On the real trial whose right plate reports 25 ms late, the phase boundaries taken
/// from the right plate's threshold move by −δ_right: with the true offset the
/// durations and the window's start are the untouched trial's (to the 6 ms to which the
/// 60 Hz threshold crossings follow a moved clock); the left-early trial likewise moves
/// the window's start (a left heel strike). The OCP frees exactly the moving durations,
/// each held by an equality row; sample targets keep the measured events and say so.
#[test]
fn a_plates_clock_offset_moves_the_events_of_its_threshold() {
    let effects = serde_json::json!([
        { "type": "force_plate_time_offset", "side": "right", "free": ["offset"] },
        { "type": "force_plate_time_offset", "side": "left", "free": ["offset"] }
    ]);
    let m = model_with_effects("opensim_subject01.json", "ellipse.json", effects);
    let untouched = setup_of(
        &m,
        &GaitData::bundled(&root()).unwrap(),
        TargetSides::Interpolated,
    )
    .unwrap();
    let d0 = durations(&untouched);
    for (name, delta) in [
        ("real_clock_r+25ms", [0.025, 0.0]),
        ("real_clock_l-20ms", [0.0, -0.020]),
    ] {
        let s = setup_of(&m, &trial(name), TargetSides::Interpolated).unwrap();
        let c = &s.clock;
        assert!(c.moves(), "{name}");
        assert_eq!(
            c.start,
            [0.0, -1.0],
            "{name}: the window starts at a left heel strike"
        );
        let d = durations(&s);
        assert_eq!(d.len(), d0.len());
        // unmoved, the moving phases are off by the offset
        assert!(
            d.iter().zip(&d0).any(|(a, b)| (a - b).abs() > 0.015),
            "{name}: the measured durations already match"
        );
        for (j, (dj, cj)) in d.iter().zip(&c.durations).enumerate() {
            let moved = dj + cj[0] * delta[0] + cj[1] * delta[1];
            assert!(
                (moved - d0[j]).abs() < 6e-3,
                "{name} phase {j}: {dj:.4} s measured, {moved:.4} s moved, {:.4} s untouched",
                d0[j]
            );
        }
        let start = s.window.0 + c.start[0] * delta[0] + c.start[1] * delta[1];
        assert!(
            (start - untouched.window.0).abs() < 6e-3,
            "{name}: start {start} vs {}",
            untouched.window.0
        );
        // the node coefficients interpolate the boundaries' along each phase
        for (j, nodes) in c.nodes.iter().enumerate() {
            let n = nodes.len() - 1;
            for s in 0..2 {
                let gap = nodes[n][s] - nodes[0][s];
                assert!((gap - c.durations[j][s]).abs() < 1e-12);
            }
        }
        // the OCP: moving durations free and tied by one equality row each
        let p = path("phases/ellipse_walk.json");
        let seq = footfall::phases::PhaseSequence::load(&p).unwrap();
        let sets = seq.resolve(&m, &p).unwrap();
        let cycle = footfall::problems::gait::GaitCycle::new(&m, &s.seq, &sets).unwrap();
        let ocp = s.ocp(&cycle, &m, &sets, Default::default()).unwrap();
        let moving = c.durations.iter().filter(|d| **d != [0.0; 2]).count();
        // the double stance after the left heel strike (ended by the right toe off): the
        // left single stance runs from one right-plate event to another
        assert!(moving >= 1, "{name}: {moving} moving phases");
        assert_eq!(
            ocp.phases.iter().filter(|p| p.duration.is_free()).count(),
            moving
        );
        let rows: Vec<_> = ocp
            .constraints
            .iter()
            .filter(|c| c.term.name == "plate clock duration")
            .collect();
        assert_eq!(rows.len(), moving);
        for r in rows {
            // d − c·δ at (d, δ): exact Jacobian
            let z = [0.3, 0.01, -0.02];
            assert!(jacobian_error(r.term.f.as_ref(), &z, 0..3) < 1e-10);
        }
        // sample targets keep the events where the free offsets start (zero), and say so
        let samples = setup_of(&m, &trial(name), TargetSides::Samples).unwrap();
        assert!(!samples.clock_moves(&m));
        assert!(
            samples
                .notes
                .iter()
                .any(|n| n.contains("stay where the offset's start value puts them")),
            "{:?}",
            samples.notes
        );
        let ocp = samples.ocp(&cycle, &m, &sets, Default::default()).unwrap();
        assert!(ocp.phases.iter().all(|p| !p.duration.is_free()));
    }
    // without a clock effect nothing moves in the OCP
    let plain = model("opensim_subject01.json", "ellipse.json");
    let s = setup_of(
        &plain,
        &trial("real_clock_r+25ms"),
        TargetSides::Interpolated,
    )
    .unwrap();
    assert!(!s.clock_moves(&plain));
    // events given with the data belong to no plate
    let mut given = trial("real_clock_r+25ms");
    let ev = footfall::data::detect_events(&given, 0.05).unwrap();
    given.events = Some(ev);
    let s = setup_of(&m, &given, TargetSides::Interpolated).unwrap();
    assert!(!s.clock.moves(), "meta-file events do not move");
}

/// With sample targets (cut at fixed phase boundaries) a plate's clock offset moves the
/// events of its threshold by its value as the model starts it: held at the truth on the
/// real trial whose right plate reports 25 ms late, the window and the durations are the
/// untouched trial's (to the 6 ms to which the threshold crossings follow a moved clock);
/// a free offset moves them by its
/// start value and warns that they stay there. Interpolated targets move the events
/// with the offset itself (the OCP's duration rows), so their setup keeps the measured
/// ones.
#[test]
fn sample_targets_move_a_plates_events_by_its_held_clock_offset() {
    let clock = |offset: f64, free: bool| {
        let free: Vec<&str> = if free { vec!["offset"] } else { vec![] };
        model_with_effects(
            "opensim_subject01.json",
            "ellipse.json",
            serde_json::json!([{ "type": "force_plate_time_offset", "side": "right",
                                 "offset": offset, "free": free }]),
        )
    };
    let plain = model("opensim_subject01.json", "ellipse.json");
    let bundled = GaitData::bundled(&root()).unwrap();
    let untouched = setup_of(&plain, &bundled, TargetSides::Samples).unwrap();
    let late = trial("real_clock_r+25ms");
    let measured = setup_of(&plain, &late, TargetSides::Samples).unwrap();
    let off = |a: &TrackingSetup, b: &TrackingSetup| {
        let d = durations(a)
            .iter()
            .zip(durations(b))
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        (
            d,
            (a.window.0 - b.window.0).abs(),
            (a.window.1 - b.window.1).abs(),
        )
    };
    // the late plate's events, unmoved, are off by about the offset
    let (d, _, end) = off(&measured, &untouched);
    assert!(d > 0.015 && end > 0.015, "{d} {end}");
    for free in [false, true] {
        let m = clock(0.025, free);
        let s = setup_of(&m, &late, TargetSides::Samples).unwrap();
        let (d, start, end) = off(&s, &untouched);
        assert!(
            d < 6e-3 && start < 6e-3 && end < 6e-3,
            "free {free}: durations {d}, start {start}, end {end} s off the untouched trial's"
        );
        let said = if free {
            "warning: the contact events of the right plate's force threshold are moved by -25.0 ms, its free clock offset's start value"
        } else {
            "the contact events of the right plate's force threshold are moved by -25.0 ms, its held clock offset"
        };
        assert!(s.notes.iter().any(|n| n.starts_with(said)), "{:?}", s.notes);
        // interpolated targets keep the measured events (the OCP moves them)
        let i = setup_of(&m, &late, TargetSides::Interpolated).unwrap();
        let mi = setup_of(&plain, &late, TargetSides::Interpolated).unwrap();
        assert_eq!(durations(&i), durations(&mi));
        assert_eq!(i.window, mi.window);
    }
    // a held offset of zero moves nothing and warns of nothing
    let s = setup_of(&clock(0.0, false), &late, TargetSides::Samples).unwrap();
    assert_eq!(durations(&s), durations(&measured));
    assert!(
        !s.notes.iter().any(|n| n.contains("clock offset")),
        "{:?}",
        s.notes
    );
}

/// A held clock offset moves its plate's events but not which half cycle is tracked. On
/// the real right-clock trial the left plate's clock held at −66 ms moves the left heel
/// strikes 66 ms later, which turns an early one (before the data's first 0.05 s) into
/// the start of a half cycle at 0.070 s; chosen on the moved events, that half cycle
/// would have been tracked instead of the trial's own (1.252 s). The tracked half cycle
/// is the trial's own, its start moved by the offset.
#[test]
fn a_held_clock_offset_keeps_the_half_cycle_tracked() {
    let late = trial("real_clock_r+25ms");
    let plain = model("opensim_subject01.json", "ellipse.json");
    let own = setup_of(&plain, &late, TargetSides::Samples)
        .unwrap()
        .window;
    for offset in [-0.066, -0.04, 0.04] {
        let m = model_with_effects(
            "opensim_subject01.json",
            "ellipse.json",
            serde_json::json!([{ "type": "force_plate_time_offset", "side": "left",
                                 "offset": offset, "free": [] }]),
        );
        let w = setup_of(&m, &late, TargetSides::Samples).unwrap().window;
        assert!(
            (w.0 - (own.0 - offset)).abs() < 5e-3 && (w.1 - own.1).abs() < 5e-3,
            "left clock held at {offset} s: tracked {w:?} against the trial's {own:?} moved to start at {:.3}",
            own.0 - offset
        );
    }
}

/// A body-mass error scales every segment's mass and inertia: the generalised gravity
/// force and the mass matrix scale by 1 + ε exactly.
#[test]
fn a_body_mass_error_scales_the_whole_body() {
    let plain = model("opensim_subject01.json", "ellipse.json");
    let m = model_with_effects(
        "opensim_subject01.json",
        "ellipse.json",
        serde_json::json!([{ "type": "body_mass_error", "free": ["relative"] }]),
    );
    let q = [0.3, 0.95, 0.1, 0.3, -0.4, 0.1, -0.2, -0.3, 0.05];
    let qd = [1.0, 0.1, 0.2, -1.0, 1.0, 0.3, 1.5, -0.8, 1.0];
    let (m0, c0) = plain.mass_matrix_and_bias(&q, &qd, &[]);
    let eps = 0.05;
    let (m1, c1) = m.mass_matrix_and_bias(&q, &qd, &[eps]);
    for (a, b) in m0.iter().zip(&m1).chain(c0.iter().zip(&c1)) {
        assert!((b - (1.0 + eps) * a).abs() < 1e-9 * a.abs().max(1.0));
    }
}

/// The actuator effects: strength scales the actuators' torque (active and damping),
/// the damping change scales the damping alone (all activations zero: the torque is
/// −(1 + c) β ω exactly), the time change divides ȧ by 1 + c; each parameter's column of
/// the dynamics Jacobian matches central differences, and a free time change makes the
/// excitations curved inputs. A torque-driven model refuses them.
#[test]
fn actuator_properties_scale_the_mtgs_with_exact_derivatives() {
    use footfall::model::actuators::Joint;
    let effects = serde_json::json!([
        { "type": "mtg_strength", "free": ["change"] },
        { "type": "mtg_damping", "free": ["change"] },
        { "type": "activation_time_constants", "free": ["change"] }
    ]);
    let plain = model("opensim_subject01.json", "ellipse.json");
    let m = model_with_effects("opensim_subject01.json", "ellipse.json", effects.clone());
    let q = [0.3, 0.95, 0.1, 0.3, -0.4, 0.1, -0.2, -0.3, 0.05];
    let qd = [1.0, 0.1, 0.2, -1.0, 1.0, 0.3, 1.5, -0.8, 1.0];
    let mut x: Vec<f64> = q.iter().chain(&qd).copied().collect();
    x.extend((0..m.na()).map(|i| 0.1 + 0.05 * i as f64));
    let u: Vec<f64> = (0..m.nu()).map(|i| 0.6 - 0.04 * i as f64).collect();
    let th = [0.2, -0.5, 0.3];
    let p0 = plain.generalized_force_parts(&x, &u, &[]).actuators;
    let p1 = m
        .generalized_force_parts(&x, &u, &[0.2, 0.0, 0.0])
        .actuators;
    for (a, b) in p0.iter().zip(&p1) {
        assert!((b - 1.2 * a).abs() < 1e-9 * a.abs().max(1.0), "strength");
    }
    // damping alone: zero activations
    let mut x0 = x.clone();
    x0[18..].iter_mut().for_each(|v| *v = 0.0);
    let footfall::model::gait::Actuation::Mtg(set) = plain.actuation() else {
        panic!("MTG model")
    };
    let d = m
        .generalized_force_parts(&x0, &u, &[0.0, -0.5, 0.0])
        .actuators;
    for (c, joint) in [(3, Joint::Hip), (4, Joint::Knee), (5, Joint::Ankle)] {
        let want = -0.5 * set.damping(joint) * qd[c];
        assert!(
            (d[c] - want).abs() < 1e-9,
            "damping at {c}: {} vs {want}",
            d[c]
        );
    }
    // activation rate divided by 1 + change
    let s = m.constraint_set("flight", &[]).unwrap();
    let rate = |mm: &GaitModel, th: &[f64]| {
        let mut xdot = vec![0.0; mm.nx()];
        mm.dynamics::<f64>(&s, &x, &u, th, &mut xdot, &mut [], None)
            .unwrap();
        xdot[18..].to_vec()
    };
    for (a, b) in rate(&plain, &[]).iter().zip(rate(&m, &[0.0, 0.0, 0.3])) {
        assert!((b - a / 1.3).abs() < 1e-12, "activation rate");
    }
    // dynamics Jacobian columns of θ and u vs central differences
    let (nx, nu) = (m.nx(), m.nu());
    let mut xdot = vec![0.0; nx];
    let mut jac = vec![0.0; nx * (nx + nu + 3)];
    m.dynamics_jacobian(&s, &x, &u, &th, &mut xdot, &mut jac)
        .unwrap();
    let f = |uu: &[f64], tt: &[f64]| {
        let mut out = vec![0.0; nx];
        m.dynamics::<f64>(&s, &x, uu, tt, &mut out, &mut [], None)
            .unwrap();
        out
    };
    let mut err = 0.0f64;
    for k in 0..nu + 3 {
        let h = 1e-6;
        let (mut ua, mut ub, mut ta, mut tb) = (u.clone(), u.clone(), th.to_vec(), th.to_vec());
        if k < nu {
            ua[k] += h;
            ub[k] -= h;
        } else {
            ta[k - nu] += h;
            tb[k - nu] -= h;
        }
        let (a, b) = (f(&ua, &ta), f(&ub, &tb));
        for i in 0..nx {
            let fd = (a[i] - b[i]) / (2.0 * h);
            err = err.max((fd - jac[i + (nx + k) * nx]).abs() / fd.abs().max(1.0));
        }
    }
    assert!(
        err < 1e-6,
        "dynamics Jacobian (u, θ) vs central differences: {err:e}"
    );
    // a free time change makes the excitations curved; fixed, they stay affine
    let (curved, _) = m.curved_inputs();
    assert!((nx..nx + nu).all(|i| curved.contains(&i)));
    let (curved, _) = plain.curved_inputs();
    assert!((nx..nx + nu).all(|i| !curved.contains(&i)));
    // a torque-driven model refuses them, naming the effect
    let mp = root().join("models/opensim_subject01_torque.json");
    let fp = root().join("models/feet/ellipse.json");
    let mut spec = footfall::model::spec::ModelSpec::load(&mp).unwrap();
    spec.effects = serde_json::from_value(serde_json::json!([{ "type": "mtg_damping" }])).unwrap();
    let foot = footfall::model::spec::FootSpec::load(&fp).unwrap();
    let err = GaitModel::from_specs(&spec, &mp, &foot, &fp)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        err.contains("mtg_damping") && err.contains("joint torques"),
        "{err}"
    );
}

/// The command line names a plate by its foot; the measurement effects hold every
/// instrument per plate and the body mass, each at its null value; neither they nor the
/// actuator properties are default diagnosis candidates.
#[test]
fn per_plate_effects_parse_and_are_the_measurement_checks() {
    let e = EffectSpec::parse_cli("force_plate_time_offset:side=right").unwrap();
    assert_eq!(
        e,
        EffectSpec::ForcePlateTimeOffset {
            side: "right".into(),
            offset: 0.0,
            free: vec!["offset".into()]
        }
    );
    assert_eq!(e.label(), "force-plate time offset (right)");
    let e = EffectSpec::parse_cli("force_plate_gain:side=left,error=0.06,free=").unwrap();
    assert_eq!(
        e,
        EffectSpec::ForcePlateGain {
            side: "left".into(),
            error: 0.06,
            free: vec![]
        }
    );
    // a plate of one foot and the shared one overlap; the two feet's do not
    let r = EffectSpec::parse_cli("cop_offset:side=right").unwrap();
    let l = EffectSpec::parse_cli("cop_offset:side=left").unwrap();
    let both = EffectSpec::parse_cli("cop_offset").unwrap();
    assert!(!r.overlaps(&l) && r.overlaps(&both) && both.overlaps(&l));
    // both plates' gains in one candidate, each its own: it overlaps each plate's gain
    // and the shared one, and is a gain's side only
    let each = EffectSpec::parse_cli("force_plate_gain:side=each").unwrap();
    assert_eq!(each.label(), "force-plate gain (each plate)");
    for other in [
        "force_plate_gain:side=right",
        "force_plate_gain:side=left",
        "force_plate_gain",
    ] {
        assert!(
            each.overlaps(&EffectSpec::parse_cli(other).unwrap()),
            "{other}"
        );
    }
    assert!(!each.overlaps(&r));
    for (bad, needle) in [
        ("cop_offset:side=each", "side"),
        ("force_plate_time_offset:side=each", "side"),
        ("cop_offset:side=middle", "side"),
        ("force_plate_gain:error=0.5", "error"),
        ("mtg_damping:change=-1.5", "change"),
    ] {
        let err = EffectSpec::parse_cli(bad).unwrap_err().to_string();
        assert!(err.contains(needle), "{bad}: {err}");
    }
    let labels: Vec<String> = measurement_effects().iter().map(|e| e.label()).collect();
    let candidates: Vec<String> = catalog().iter().map(|e| e.label()).collect();
    for want in [
        "force-plate time offset (right)",
        "force-plate time offset (left)",
        "CoP offset (right)",
        "CoP offset (left)",
        "force-plate gain (right)",
        "force-plate gain (left)",
        "force-plate gain (each plate)",
        "body-mass error",
    ] {
        assert!(labels.iter().any(|l| l == want), "{want} not in {labels:?}");
        assert!(
            !candidates.contains(&want.to_string()),
            "{want} in {candidates:?}"
        );
    }
}

/// The measured CoP through a clock offset is continuous in time across the edge of the
/// loaded samples (NaN where the foot is unloaded): inside, linear interpolation; next to
/// and beyond the edge, the nearest loaded sample's value. Before, a node moved past the
/// edge fell back to its own fixed target, a jump the re-fit of a plate's clock stopped on.
#[test]
fn the_measured_cop_stays_continuous_across_the_edge_of_the_loaded_samples() {
    let time: Vec<f64> = (0..10).map(|k| k as f64 * 0.01).collect();
    // loaded on samples 2–5 (CoP 0.10, 0.12, 0.14, 0.16 m), unloaded elsewhere
    let cop: Vec<f64> = (0..10)
        .map(|k| {
            if (2..=5).contains(&k) {
                0.10 + 0.02 * (k - 2) as f64
            } else {
                f64::NAN
            }
        })
        .collect();
    let flat = CubicSpline::new(&time, &[0.0; 10]).unwrap();
    let m = MeasuredLoads {
        fx: [flat.clone(), flat.clone()],
        fy: [flat.clone(), flat],
        time,
        cop_x: [cop.clone(), cop],
        belt_speed: 0.0,
    };
    let at = |t: f64| m.cop::<f64>(0, t);
    assert!((at(0.035).unwrap() - 0.13).abs() < 1e-12);
    // on a fine sweep through both edges the value never jumps by more than the
    // interpolation's own slope allows (2 cm per 10 ms)
    let mut last = at(0.0).unwrap();
    assert_eq!(last, 0.10);
    for k in 1..900 {
        let t = k as f64 * 1e-4;
        let v = at(t).expect("defined next to loaded samples");
        assert!(
            (v - last).abs() <= 0.02 * 1e-4 / 0.01 + 1e-12,
            "jump at t = {t}: {last} → {v}"
        );
        last = v;
    }
    assert_eq!(at(0.09).unwrap(), 0.16);
    // outside the samples, or with no loaded sample at all: undefined
    assert!(at(0.2).is_none());
    let none = MeasuredLoads {
        cop_x: [vec![f64::NAN; 10], vec![f64::NAN; 10]],
        ..m
    };
    assert!(none.cop::<f64>(1, 0.03).is_none());
}
