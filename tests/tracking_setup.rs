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
