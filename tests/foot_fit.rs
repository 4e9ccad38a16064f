//! Foot fitting: rolling without slipping against the analytic rolling circle, length
//! fixed, and the fit on the bundled trial lowering eq. 13 for both seed feet.

mod common;
use common::*;
use footfall::data::GaitData;
use footfall::model::spec::FootSpec;
use footfall::problems::foot_fit::{fit, fit_cost, foot_length, roll, stances_from_data, StanceSamples};

#[test]
fn a_rolling_circle_moves_its_centre_with_the_contact_and_turns_by_distance_over_radius() {
    let r = 0.05;
    let foot: FootSpec = serde_json::from_value(serde_json::json!({
        "name": "disc", "primitives": [ { "name": "c", "shape": { "type": "circle", "centre": [0.0, 0.0], "radius": r } } ]
    }))
    .unwrap();
    let n = 21;
    let cop: Vec<f64> = (0..n).map(|i| 0.3 + 0.01 * i as f64).collect();
    let st = StanceSamples { t: cop.clone(), ankle: vec![[0.0; 2]; n], angle: vec![0.2; n], cop: cop.clone(), weight: vec![1.0; n] };
    let (ankle, angle) = roll(&foot, &st, 0.0).unwrap();
    for i in 0..n {
        // the outline is a 720-gon: the centre may sit up to half an edge (2.2e-4 m) off
        assert!((ankle[i][0] - cop[i]).abs() < 2.5e-4, "centre above the contact: {} vs {}", ankle[i][0], cop[i]);
        assert!((ankle[i][1] - r).abs() < 1e-5, "centre at radius height");
        if i + 1 < n {
            // rolling forward by d turns the disc clockwise by d / r
            let expect = (cop[n - 2] - cop[i]) / r;
            let got = angle[i] - angle[n - 2];
            let wrapped = (got - expect + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
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
        eprintln!("{foot_file}: eq. 13 {before:.3} → {:.3} in {} iterations", res.cost.1, res.iterations);
        assert!(res.cost.1 < 0.5 * before);
        assert!((foot_length(&res.foot) - foot_length(&foot)).abs() < 1e-3, "length must stay fixed");
    }
}
