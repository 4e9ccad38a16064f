//! footfall runs from any folder, and its run folders carry their inputs:
//! started in a temporary folder outside the repository, `track` finds the bundled
//! model, foot, phases and trial; the run folder holds copies of them under `inputs/`
//! that `setup.json` names relative to the folder; `report`, `diagnose`, `synth` and
//! `diff` work on it from that folder, and on a copy of it at another path, from yet
//! another folder. One cheap run (started at a converged solution, one iteration) serves
//! every check.

use crate::common;
use common::stderr;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Run `footfall ARGS` in `dir`.
fn footfall(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_footfall"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run the footfall binary")
}

fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Copy the folder `from` to `to`, recursively.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}

#[test]
fn runs_from_anywhere_and_run_folders_carry_their_inputs() {
    let tmp = tempfile::tempdir().unwrap();
    let here = tmp.path().join("work");
    std::fs::create_dir_all(&here).unwrap();
    assert!(
        !here.join("models").exists() && !tmp.path().starts_with(root()),
        "the test folder must not be the repository"
    );
    // a converged run of the bundled defaults (its setup.json records the paths as typed,
    // as run folders did before they carried their inputs)
    let init = root().join("tests/data/hidden/base");
    let o = footfall(
        &here,
        &[
            "track",
            "--init",
            init.to_str().unwrap(),
            "--max-iter",
            "1",
            "--no-check-points",
            "--quiet",
            "--out",
            "run",
        ],
    );
    let run = here.join("run");
    assert!(
        run.join("summary.json").is_file(),
        "track from {} wrote no run: {}",
        here.display(),
        stderr(&o)
    );
    assert!(
        !stderr(&o).contains("cannot read") && !stderr(&o).contains("No such file"),
        "{}",
        stderr(&o)
    );
    let summary = json(&run.join("summary.json"));
    let objective = summary["objective"].as_f64().unwrap();
    assert!(objective.is_finite() && objective > 0.0, "J = {objective}");

    // the inputs are in the run folder, byte for byte the bundled files (the model's
    // OpenSim model beside it, named by its file name), and setup.json names them
    // relative to the folder
    let setup = json(&run.join("setup.json"));
    let expect = [
        ("model", "inputs/model/opensim_subject01.json"),
        ("foot", "inputs/foot/ellipse.json"),
        ("phases", "inputs/phases/ellipse_walk.json"),
        ("data", "inputs/data/opensim_subject01_sagittal.csv"),
    ];
    for (field, path) in expect {
        assert_eq!(setup[field], path, "setup.json field {field}");
        assert!(run.join(path).is_file(), "{path} missing");
    }
    for (copy, original) in [
        ("inputs/foot/ellipse.json", "models/feet/ellipse.json"),
        (
            "inputs/phases/ellipse_walk.json",
            "phases/ellipse_walk.json",
        ),
        (
            "inputs/data/opensim_subject01_sagittal.csv",
            "data/opensim_subject01_sagittal.csv",
        ),
        (
            "inputs/data/opensim_subject01_meta.json",
            "data/opensim_subject01_meta.json",
        ),
        (
            "inputs/model/opensim_subject01_model.json",
            "data/opensim_subject01_model.json",
        ),
    ] {
        assert_eq!(
            std::fs::read(run.join(copy)).unwrap(),
            std::fs::read(root().join(original)).unwrap(),
            "{copy} is not {original}"
        );
    }
    let model = json(&run.join("inputs/model/opensim_subject01.json"));
    assert_eq!(model["body"]["file"], "opensim_subject01_model.json");
    assert_eq!(summary["phases"], "inputs/phases/ellipse_walk.json");
    assert_eq!(summary["setup"]["model"], setup["model"]);

    // the run folder copied elsewhere, and every command run from a third folder
    let moved = tmp.path().join("elsewhere/moved");
    copy_dir(&run, &moved);
    let other = tmp.path().join("other");
    std::fs::create_dir_all(&other).unwrap();

    // report rewrites the copy from its own inputs: the objective is reproduced
    let o = footfall(
        &other,
        &[
            "report",
            moved.to_str().unwrap(),
            "--out",
            "reported",
            "--quiet",
        ],
    );
    assert!(o.status.success(), "report: {}", stderr(&o));
    let reported = other.join("reported");
    let again = json(&reported.join("summary.json"));
    let j = again["objective"].as_f64().unwrap();
    assert!(
        (j - objective).abs() <= 1e-6 * objective,
        "report re-evaluates J = {j}, the run had {objective}"
    );
    assert!(reported
        .join("inputs/model/opensim_subject01.json")
        .is_file());
    assert_eq!(json(&reported.join("setup.json"))["model"], setup["model"]);

    // the run and its re-report side by side, from their files
    let o = footfall(
        &other,
        &[
            "report",
            moved.to_str().unwrap(),
            "reported",
            "--out",
            "side",
            "--quiet",
        ],
    );
    assert!(o.status.success(), "side by side: {}", stderr(&o));
    assert!(other.join("side/report.html").is_file());

    // a broken setup.json is named with its field; a missing input by its path in the
    // run folder
    let broken = tmp.path().join("broken");
    copy_dir(&moved, &broken);
    let mut bad = setup.clone();
    bad["integrator_tol"] = "tight".into();
    std::fs::write(broken.join("setup.json"), bad.to_string()).unwrap();
    let o = footfall(&other, &["report", broken.to_str().unwrap(), "--out", "b1"]);
    assert!(!o.status.success());
    for want in [
        "setup.json",
        "`integrator_tol`",
        "expected a number",
        "\"tight\"",
    ] {
        assert!(stderr(&o).contains(want), "{want} not in: {}", stderr(&o));
    }
    std::fs::write(broken.join("setup.json"), setup.to_string()).unwrap();
    std::fs::remove_file(broken.join("inputs/phases/ellipse_walk.json")).unwrap();
    let o = footfall(&other, &["report", broken.to_str().unwrap(), "--out", "b2"]);
    assert!(!o.status.success());
    let missing = broken.join("inputs/phases/ellipse_walk.json");
    assert!(
        stderr(&o).contains(missing.to_str().unwrap()),
        "{}",
        stderr(&o)
    );
    assert!(!other.join("b1").exists() && !other.join("b2").exists());

    // report in place, from the run's own folder's parent
    let o = footfall(&here, &["report", "run", "--quiet"]);
    assert!(o.status.success(), "report in place: {}", stderr(&o));

    // diff of the run and its re-report: the same errors
    let o = footfall(
        &other,
        &[
            "diff",
            moved.to_str().unwrap(),
            "reported",
            "--out",
            "diffed",
            "--quiet",
        ],
    );
    assert!(o.status.success(), "diff: {}", stderr(&o));
    let d = json(&other.join("diffed/summary.json"));
    assert_eq!(d["command"], "diff");
    assert!(
        d["counts"]["unchanged"].as_u64().unwrap() > 0
            && d["counts"]["better"] == 0
            && d["counts"]["worse"] == 0,
        "{}",
        d["counts"]
    );

    // diagnose the copy: one candidate by its score test, no re-fit
    let o = footfall(
        &other,
        &[
            "diagnose",
            moved.to_str().unwrap(),
            "--candidate",
            "ground_slope",
            "--verify",
            "0",
            "--out",
            "diagnosed",
            "--quiet",
        ],
    );
    assert!(o.status.success(), "diagnose: {}", stderr(&o));
    assert!(other.join("diagnosed/summary.json").is_file());

    // synth from the copy: a synthetic trial of the run's model, foot and phases
    let o = footfall(
        &other,
        &[
            "synth",
            "--from",
            moved.to_str().unwrap(),
            "--seed",
            "1",
            "--out",
            "synthetic",
            "--quiet",
        ],
    );
    assert!(o.status.success(), "synth: {}", stderr(&o));
    assert!(std::fs::read_dir(other.join("synthetic")).unwrap().count() > 0);

    // a path the user types is still read from the current folder, and named
    let o = footfall(
        &other,
        &[
            "track",
            "--model",
            "models/no_such_model.json",
            "--out",
            "never",
            "--quiet",
        ],
    );
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("models/no_such_model.json"),
        "{}",
        stderr(&o)
    );
    assert!(!other.join("never").exists());
}
