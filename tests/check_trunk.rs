//! The measurement check with the trunk following the trial's lumbar angle
//! (`footfall check --lumbar`): the moved trunk's balance against finite differences of
//! the body's own positions and momenta, what it does to the bundled trial's residual,
//! and the refusals when the trunk's angle or description is missing.

use crate::check::{bundled_600_signals, BUNDLED_600};
use crate::common::{footfall, json, root, stderr};
use footfall::problems::check::balance::{Body, NPARAM};
use footfall::problems::check::signals::Signals;
use std::path::Path;

/// The bundled 600 Hz trial's signals and its body with the trunk moving.
fn moving_trunk() -> (Signals, Body) {
    let model = crate::common::model("opensim_subject01.json", "ellipse.json");
    let signals = bundled_600_signals(&model);
    let body = Body::with_torso(&model)
        .expect("the OpenSim summary describes its torso")
        .expect("body");
    assert!(body.moves_trunk(&signals));
    (signals, body)
}

#[test]
fn a_moving_trunks_balance_is_the_rate_of_the_bodys_momentum() {
    // Σ m (a − g) is M c̈ − M g, with c the centre of mass from the bodies' positions
    // alone; the moment about c is dH_c/dt (gravity has no moment about the centre of
    // mass). Both by central differences of positions and momenta, which share no
    // acceleration with the balance.
    let (signals, body) = moving_trunk();
    let (m, g) = (body.mass(), body.gravity());
    let zero = [0.0; NPARAM];
    let h = 2e-4;
    for &t in signals.instants.iter().step_by(131) {
        let at = body.instant(&signals, t);
        let req = body.required(&at, &zero);
        let (up, down) = (body.instant(&signals, t + h), body.instant(&signals, t - h));
        for i in 0..2 {
            let acc = (up.com[i] - 2.0 * at.com[i] + down.com[i]) / (h * h);
            let expected = m * acc + if i == 1 { m * g } else { 0.0 };
            assert!(
                (req[i] - expected).abs() < 0.5,
                "t {t}, force {i}: balance {} N, M c̈ − M g {expected} N",
                req[i]
            );
        }
        let dh = (body.momentum(&up)[2] - body.momentum(&down)[2]) / (2.0 * h);
        assert!(
            (req[2] - dh).abs() < 0.05,
            "t {t}: balance moment {} N·m, dH_c/dt {dh} N·m",
            req[2]
        );
    }
}

/// `footfall check TRIAL --model MODEL --out OUT`, with `extra` arguments.
fn run_check(trial: &str, model: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "check",
        trial,
        "--model",
        model,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    footfall(&args)
}

/// `footfall check` of the bundled 600 Hz trial, with `extra` arguments: its summary.
fn bundled_check(extra: &[&str]) -> serde_json::Value {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("check");
    let o = run_check(BUNDLED_600, "models/opensim_subject01.json", &out, extra);
    assert!(o.status.success(), "{}", stderr(&o));
    json(&out.join("summary.json"))
}

#[test]
fn the_bundled_trunks_rocking_carries_most_of_the_rigid_hats_horizontal_residual() {
    // The bundled kinematics were made consistent with the ground forces by OpenSim's
    // residual reduction on a model whose trunk moves on the pelvis: freezing the trunk
    // leaves its rocking as residual, following it takes that away.
    let rigid = bundled_check(&[]);
    let moving = bundled_check(&["--lumbar"]);
    assert_eq!(moving["settings"]["lumbar"], true);
    let rms = |s: &serde_json::Value, i: usize| {
        s["thresholds"]["as_measured"]["rms_force"][i]
            .as_f64()
            .unwrap()
    };
    let peak = |s: &serde_json::Value| {
        s["thresholds"]["as_measured"]["peak_force"]
            .as_f64()
            .unwrap()
    };
    assert!(
        rms(&moving, 0) < 0.5 * rms(&rigid, 0),
        "horizontal residual {} N moving, {} N rigid",
        rms(&moving, 0),
        rms(&rigid, 0)
    );
    assert!(peak(&moving) < peak(&rigid));
    // the rigid run says what the moving trunk would leave, and the moving run what the
    // frozen one leaves
    for run in [&rigid, &moving] {
        let t = &run["trunk_rocking"];
        assert_eq!(
            t["frozen"]["rms_force"][0].as_f64().unwrap(),
            rms(&rigid, 0)
        );
        assert_eq!(
            t["moving"]["rms_force"][0].as_f64().unwrap(),
            rms(&moving, 0)
        );
    }
    // the shipped bands are the rigid HAT's: the run says its verdicts are approximate
    let warned = moving["warnings"].as_array().unwrap();
    assert!(warned
        .iter()
        .any(|w| w.as_str().unwrap().contains("rigid HAT")));
}

#[test]
fn lumbar_needs_the_trials_lumbar_angle_and_a_body_that_describes_its_trunk() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c");
    let refused = dir.path().join("refused");
    let (d123, d123_model) = (
        "data/pig_c3dorg_D123_sagittal.csv",
        "models/pig_c3dorg_D123.json",
    );
    let o = run_check(d123, d123_model, &out, &["--lumbar"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("pig_c3dorg_D123_sagittal.csv") && e.contains("'lumbar_extension'"),
        "{e}"
    );
    assert!(!out.exists());
    // without --lumbar the same trial is checked, and nothing is said of its trunk
    let o = run_check(d123, d123_model, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(json(&out.join("summary.json"))["trunk_rocking"].is_null());
    // a body of explicit segments has no trunk above a lumbar joint
    let model = dir.path().join("explicit.json");
    let text = std::fs::read_to_string(root().join("models/opensim_subject01.json")).unwrap();
    let mut spec: serde_json::Value = serde_json::from_str(&text).unwrap();
    spec["body"] = serde_json::json!({"preset": "explicit", "segments": {
        "hat": {"mass": 44.4, "com": [-0.03, 0.31], "izz": 3.2},
        "thigh": {"mass": 9.3, "com": [0.0, -0.17], "izz": 0.13},
        "shank": {"mass": 3.7, "com": [0.0, -0.19], "izz": 0.05},
        "foot": {"mass": 1.25, "com": [0.06, -0.03], "izz": 0.005},
        "hip_in_pelvis": [-0.072, -0.068],
        "knee_in_thigh": [0.0, -0.40],
        "ankle_in_shank": [0.0, -0.43]}});
    std::fs::write(&model, spec.to_string()).unwrap();
    let o = run_check(
        BUNDLED_600,
        model.to_str().unwrap(),
        &refused,
        &["--lumbar"],
    );
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("explicit.json") && e.contains("trunk above the lumbar joint"),
        "{e}"
    );
}
