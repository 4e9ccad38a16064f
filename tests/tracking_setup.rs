//! The tracking problem built from the bundled trial: durations from the measured contact
//! sequence, a guess on the contact manifold, and a transcription that evaluates.

use crate::common;
use common::*;
use footfall::data::GaitData;
use footfall::integrate::IntegratorSettings;
use footfall::ocp::Transcription;
use footfall::phases::{Phase, PhaseSequence};
use footfall::problems::gait::GaitCycle;
use footfall::problems::track::TrackingSetup;

#[test]
fn tracking_problem_builds_from_the_bundled_trial_for_both_feet() {
    let data = GaitData::bundled(&root()).unwrap();
    for (foot, phases) in [
        ("ellipse.json", "phases/ellipse_walk.json"),
        ("double_circle.json", "phases/double_circle_walk.json"),
    ] {
        let m = model("opensim_subject01.json", foot);
        let p = path(phases);
        let seq = PhaseSequence::load(&p).unwrap();
        let sets = seq.resolve(&m, &p).unwrap();
        let setup = TrackingSetup::new(&m, &seq, &sets, &data).unwrap();
        let (t0, t1) = setup.window;
        // a left heel strike to the next right heel strike of the 5 % events
        assert!(setup.events.heel_strike[1]
            .iter()
            .any(|&t| (t - t0).abs() < 1e-12));
        assert!(setup.events.heel_strike[0]
            .iter()
            .any(|&t| (t - t1).abs() < 1e-12));
        let total: f64 = setup
            .seq
            .phases
            .iter()
            .map(|ph| match ph {
                Phase::Continuous { duration, .. } => duration.value(),
                Phase::Impact { .. } => 0.0,
            })
            .sum();
        assert!(
            (total - (t1 - t0)).abs() < 1e-9,
            "{foot}: phases last {total}, window {}",
            t1 - t0
        );
        // the guess lies on each phase's contact manifold
        let cycle = GaitCycle::new(&m, &setup.seq, &sets).unwrap();
        for (j, xs) in setup.guess.x.iter().enumerate() {
            let set = &sets[cycle.continuous[j]];
            for x in xs {
                for r in set
                    .rows
                    .iter()
                    .filter(|r| r.kind == footfall::model::RowKind::Normal)
                {
                    let (_, gap) = m.contact_point(r.contact, &x[..9], &[]);
                    assert!(gap.abs() < 1e-9, "{foot}: guess off the ground by {gap}");
                }
            }
        }
        let ocp = setup
            .ocp(&cycle, &m, &sets, IntegratorSettings::default())
            .unwrap();
        let tr = Transcription::new(&ocp).unwrap();
        let (_, _, w0) = tr.variable_bounds_and_guess();
        let ev = tr.evaluate(&w0, false).unwrap();
        assert!(ev.f.is_finite() && ev.f > 0.0 && ev.c.iter().all(|v| v.is_finite()));
        eprintln!(
            "{foot}: window {t0:.4}–{t1:.4} s, {} variables, initial tracking cost {:.3}",
            tr.n(),
            ev.f
        );
    }
}

/// The start from the inverse dynamics: at every node the model's joint torques with the
/// start's activations (muscle-torque generators) or controls (joint torques) equal the
/// trial's inverse-dynamics torques, except where the actuators cannot reach them (the
/// start reports those).
#[test]
fn the_inverse_dynamics_start_gives_the_trials_joint_torques() {
    use footfall::problems::check::balance::{inverse_dynamics, Body};
    use footfall::problems::check::signals::Signals;
    use footfall::problems::track::start::from_inverse_dynamics;
    let data = GaitData::bundled(&root()).unwrap();
    let signals = Signals::new(&data, 6.0, 0.0).unwrap();
    for file in ["opensim_subject01.json", "opensim_subject01_torque.json"] {
        let m = model(file, "ellipse.json");
        let p = path("phases/ellipse_walk.json");
        let seq = PhaseSequence::load(&p).unwrap();
        let sets = seq.resolve(&m, &p).unwrap();
        let mut started = TrackingSetup::new(&m, &seq, &sets, &data).unwrap();
        let report =
            from_inverse_dynamics(&m, &data, &started.node_times, &mut started.guess).unwrap();
        assert_eq!(report.set, report.nodes);
        let body = Body::of(&m).unwrap();
        let (mut exact, mut far, mut pairs) = (0, 0, 0);
        // the largest inverse-dynamics joint torque (N·m), against a joint-torque model's bound
        let mut largest: f64 = 0.0;
        let phases = started
            .node_times
            .iter()
            .zip(&started.guess.x)
            .zip(&started.guess.u);
        for ((times, xs), us) in phases {
            for ((&t, x), u) in times.iter().zip(xs).zip(us) {
                let want = inverse_dynamics(&body, &signals, &m, t).unwrap();
                let parts = m.generalized_force_parts(x, u, &m.theta0());
                for c in 3..9 {
                    let got =
                        parts.actuators[c] + parts.effects.iter().map(|e| e.1[c]).sum::<f64>();
                    largest = largest.max(want[c].abs());
                    let err = (got - want[c]).abs();
                    pairs += 1;
                    exact += usize::from(err <= 1e-6 * want[c].abs().max(1.0));
                    far += usize::from(err > 3.0);
                }
            }
        }
        eprintln!(
            "{file}: {exact} of {pairs} joint torques exact, {far} off by > 3 N·m, {} saturated",
            report.saturated
        );
        // a joint-torque model strong enough for every torque reaches each one exactly
        let spec = json(&root().join("models").join(file));
        if let Some(bound) = spec["actuators"]["max_torque"].as_f64() {
            assert!(largest < bound, "{file}: {largest} N·m against {bound}");
            assert_eq!(
                report.saturated, 0,
                "{file}: every torque is within {bound} N·m"
            );
        }
        assert!(
            far <= report.saturated,
            "{file}: {far} torques off by > 3 N·m, {} saturated",
            report.saturated
        );
        assert!(
            exact + report.saturated >= pairs,
            "{file}: only {exact} of {pairs} joint torques exact, {} saturated",
            report.saturated
        );
    }
}
