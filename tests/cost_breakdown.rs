//! The cost breakdown of a tracking solution adds up to the objective the NLP evaluates,
//! and its worst windows do not overlap.

mod common;
use common::*;
use footfall::integrate::IntegratorSettings;
use footfall::ocp::Transcription;
use footfall::problems::evaluation::GaitSolution;
use footfall::problems::gait::GaitCycle;
use footfall::sqp::Nlp;

#[test]
fn cost_breakdown_adds_up_to_the_objective() {
    let (m, sets, setup) = bundled_tracking("ellipse.json", "phases/ellipse_walk.json");
    let cycle = GaitCycle::new(&m, &setup.seq, &sets).unwrap();
    let ocp = setup.ocp(&cycle, &m, &sets, IntegratorSettings::default()).unwrap();
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w) = tr.variable_bounds_and_guess();
    let f = Nlp::evaluate(&tr, &w, false).unwrap().f;
    let sol = GaitSolution::from_nlp(&tr, &w, &cycle.continuous, setup.window.0);
    let b = setup.cost_breakdown(&m, &sets, &cycle.continuous, &sol).unwrap();
    assert!((b.total() - f).abs() < 1e-9 * f, "breakdown {} vs objective {f}", b.total());
    for c in ["hip_r", "knee_l", "velocities", "normal GRF", "CoP", "excitations", "activations"] {
        assert!(b.channels.iter().any(|x| x == c), "{c} missing: {:?}", b.channels);
    }
    assert_eq!(b.phases.len(), 2, "the ellipse graph's two continuous phases");
    let rows = setup.data_rows(&m, &sets, &cycle.continuous);
    assert_eq!(b.nodes.len(), sol.phases.iter().map(|p| p.intervals()).sum::<usize>() + 1);
    assert!(rows > b.nodes.len() * 14, "{rows} data residuals");
    let win = b.worst_windows(5, 3);
    assert_eq!(win.len(), 3);
    for i in 0..3 {
        for j in 0..i {
            assert!(win[i].1 < win[j].0 || win[j].1 < win[i].0, "windows overlap: {win:?}");
        }
    }
    assert!(win[0].2 >= win[1].2 && win[1].2 >= win[2].2);
}
