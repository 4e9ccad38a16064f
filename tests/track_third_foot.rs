//! A foot no code knows — a heel circle plus a forefoot ellipse, with its own phase
//! graph, defined only in `models/feet/` and `phases/` — is fitted by `fit-foot` and then
//! tracked end to end by `track --foot FILE --phases FILE` from the command line.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_footfall"))
        .current_dir(root())
        .arg("--quiet")
        .args(args)
        .output()
        .unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn third_foot_is_fitted_then_tracked_from_json_files_only() {
    let dir = tempfile::tempdir().unwrap();
    let fit_dir = dir.path().join("fit");
    let o = run(&[
        "fit-foot",
        "--foot",
        "models/feet/heel_circle_forefoot_ellipse.json",
        "--out",
        s(&fit_dir),
    ]);
    assert!(
        o.status.success(),
        "fit-foot: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let fitted = fit_dir.join("heel_circle_forefoot_ellipse_fitted.json");
    assert!(fitted.is_file());

    let track_dir = dir.path().join("track");
    let o = run(&[
        "track",
        "--foot",
        s(&fitted),
        "--phases",
        "phases/heel_circle_forefoot_ellipse_walk.json",
        "--out",
        s(&track_dir),
    ]);
    assert!(
        o.status.success(),
        "track: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(track_dir.join("summary.json")).unwrap())
            .unwrap();
    eprintln!(
        "third foot tracked: {} iterations, {:.1} s, J = {}, KKT {}",
        summary["iterations"],
        summary["seconds"].as_f64().unwrap(),
        summary["objective"],
        summary["kkt"]
    );
    assert_eq!(summary["status"], "converged");
    assert!(summary["kkt"].as_f64().unwrap() <= 1e-5);
    assert_eq!(summary["foot"], "heel_circle_forefoot_ellipse_fitted");

    // the model follows the measurement: errors of the size the bundled feet reach
    let err = |name: &str| -> f64 {
        summary["errors"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["channel"] == name)
            .unwrap_or_else(|| panic!("no channel {name}"))["stats"]["mean"]
            .as_f64()
            .unwrap()
    };
    for (name, limit) in [
        ("hip angle", 5.0),
        ("knee angle", 8.0),
        ("normal GRF", 80.0),
        ("CoP", 8.0),
    ] {
        let e = err(name);
        eprintln!("  {name}: mean |error| {e:.2}");
        assert!(e < limit, "{name}: mean error {e} ≥ {limit}");
    }
    // errors by phase name every phase of the foot's own phase graph
    let phases: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("phases/heel_circle_forefoot_ellipse_walk.json"))
            .unwrap(),
    )
    .unwrap();
    let hip = summary["errors_by_phase"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["channel"] == "hip angle")
        .unwrap();
    let listed: Vec<&str> = hip["phases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["phase"].as_str().unwrap())
        .collect();
    for p in phases["phases"].as_array().unwrap() {
        let name = p["name"].as_str().unwrap();
        let continuous = p["type"] == "continuous";
        assert_eq!(
            listed.contains(&name),
            continuous,
            "phase {name} in errors_by_phase: {listed:?}"
        );
    }
    // the 1 ms re-integration: finite figures, Baumgarte forces small next to body weight
    let fine = &summary["fine_grid"];
    let bw = 72.6 * 9.81;
    let peak = fine["peak_normal_force_n"][0].as_f64().unwrap();
    assert!(
        peak > 0.8 * bw && peak < 3.0 * bw,
        "peak normal force {peak}"
    );
    assert!(
        fine["max_baumgarte_force_n"].as_f64().unwrap() < 0.05 * bw,
        "{fine}"
    );
    for f in [
        "tracking.csv",
        "fine_grid.csv",
        "kinematics.sto",
        "table3.md",
        "solution.json",
        "report.html",
    ] {
        assert!(track_dir.join(f).is_file(), "{f} missing");
    }
    // the run's own report renders in headless Chromium with every plot: the angles and
    // the velocities (pelvis x, y, tilt, and hip, knee, ankle with both legs overlaid),
    // normal force, tangential force and CoP (both feet overlaid), the actuators' torques,
    // activations and excitations per joint, the data cost per node of "Where the model
    // fails", the body animation, and the film strip with its three panels
    let url = format!("file://{}", track_dir.join("report.html").display());
    let dom = String::from_utf8(common::chromium(
        &["--dump-dom".into(), url],
        std::time::Duration::from_secs(90),
    ))
    .unwrap();
    assert_eq!(
        dom.matches("<svg").count(),
        6 + 6 + 3 + 9 + 1 + 1 + 4,
        "plots in the rendered report"
    );
    for title in [
        "knee angle",
        "ankle angular velocity",
        "normal GRF",
        "CoP",
        "hip excitations",
        "heel strike (left)",
        "Tracking errors by phase",
        "Ground-force transients",
        "Where the model fails",
        "Data cost per shooting node",
    ] {
        assert!(dom.contains(title), "{title} not in the rendered report");
    }
}
