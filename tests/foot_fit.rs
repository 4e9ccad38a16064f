//! Foot fitting: rolling without slipping against the analytic rolling circle, length
//! fixed, and the fit on the bundled trial lowering eq. 13 for both seed feet.

use crate::common;
use common::*;
use footfall::data::GaitData;
use footfall::model::spec::FootSpec;
use footfall::problems::foot_fit::{
    fit, fit_cost, foot_length, roll, stances_from_data, StanceSamples,
};

#[test]
fn a_rolling_circle_moves_its_centre_with_the_contact_and_turns_by_distance_over_radius() {
    let r = 0.05;
    let foot: FootSpec = serde_json::from_value(serde_json::json!({
        "name": "disc", "primitives": [ { "name": "c", "shape": { "type": "circle", "centre": [0.0, 0.0], "radius": r } } ]
    }))
    .unwrap();
    let n = 21;
    let cop: Vec<f64> = (0..n).map(|i| 0.3 + 0.01 * i as f64).collect();
    let st = StanceSamples {
        t: cop.clone(),
        ankle: vec![[0.0; 2]; n],
        angle: vec![0.2; n],
        cop: cop.clone(),
        weight: vec![1.0; n],
    };
    let (ankle, angle) = roll(&foot, &st, 0.0).unwrap();
    for i in 0..n {
        // the outline is a 720-gon: the centre may sit up to half an edge (2.2e-4 m) off
        assert!(
            (ankle[i][0] - cop[i]).abs() < 2.5e-4,
            "centre above the contact: {} vs {}",
            ankle[i][0],
            cop[i]
        );
        assert!((ankle[i][1] - r).abs() < 1e-5, "centre at radius height");
        if i + 1 < n {
            // rolling forward by d turns the disc clockwise by d / r
            let expect = (cop[n - 2] - cop[i]) / r;
            let got = angle[i] - angle[n - 2];
            let wrapped = (got - expect + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            assert!(wrapped.abs() < 0.01, "turn {got} vs {expect}");
        }
    }
}

#[test]
fn fitting_the_seed_feet_to_the_bundled_trial_lowers_the_cost_and_keeps_the_length() {
    let data = GaitData::bundled(&root()).unwrap();
    for foot_file in ["ellipse.json", "double_circle.json"] {
        let m = model("opensim_subject01.json", foot_file);
        let foot = FootSpec::load(&path(&format!("models/feet/{foot_file}"))).unwrap();
        let stances = stances_from_data(&m, &data).unwrap();
        assert!(stances.len() >= 2);
        let ground = m.contact_settings().ground_height;
        let before = fit_cost(&foot, &stances, ground).unwrap().0;
        let res = fit(&foot, &stances, ground, 1e-6, 4000).unwrap();
        eprintln!(
            "{foot_file}: eq. 13 {before:.3} → {:.3} in {} iterations",
            res.cost.1, res.iterations
        );
        assert!(res.cost.1 < 0.5 * before);
        assert!(
            (foot_length(&res.foot) - foot_length(&foot)).abs() < 1e-3,
            "length must stay fixed"
        );
    }
}

/// A third foot defined only in JSON (heel circle + forefoot ellipse, with its own phase
/// graph) is fitted and its tracking problem builds and evaluates end to end.
#[test]
fn a_third_foot_defined_only_in_json_is_fitted_and_tracked() {
    use footfall::integrate::IntegratorSettings;
    use footfall::ocp::Transcription;
    use footfall::phases::PhaseSequence;
    use footfall::problems::gait::GaitCycle;
    use footfall::problems::track::TrackingSetup;
    let data = GaitData::bundled(&root()).unwrap();
    let m = model(
        "opensim_subject01.json",
        "heel_circle_forefoot_ellipse.json",
    );
    let foot = FootSpec::load(&path("models/feet/heel_circle_forefoot_ellipse.json")).unwrap();
    let stances = stances_from_data(&m, &data).unwrap();
    let ground = m.contact_settings().ground_height;
    let res = fit(&foot, &stances, ground, 1e-6, 4000).unwrap();
    eprintln!("third foot: eq. 13 {:.3} → {:.3}", res.cost.0, res.cost.1);
    assert!(res.cost.1 < res.cost.0);
    // track with the fitted foot: the fitted JSON goes through the same loader
    let dir = tempfile::tempdir().unwrap();
    let fitted = dir.path().join("fitted.json");
    std::fs::write(&fitted, serde_json::to_string(&res.foot).unwrap()).unwrap();
    let m2 =
        footfall::model::GaitModel::load(&path("models/opensim_subject01.json"), &fitted).unwrap();
    let pp = path("phases/heel_circle_forefoot_ellipse_walk.json");
    let seq = PhaseSequence::load(&pp).unwrap();
    let sets = seq.resolve(&m2, &pp).unwrap();
    let setup = TrackingSetup::new(&m2, &seq, &sets, &data).unwrap();
    let cycle = GaitCycle::new(&m2, &setup.seq, &sets).unwrap();
    let ocp = setup
        .ocp(&cycle, &m2, &sets, IntegratorSettings::default())
        .unwrap();
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let ev = tr.evaluate(&w0, false).unwrap();
    assert!(ev.f.is_finite() && ev.c.iter().all(|v| v.is_finite()));
}
