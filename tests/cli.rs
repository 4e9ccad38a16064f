//! The `footfall` binary end to end: a successful simulation writes a complete, finite run
//! folder; bad input exits with code 1 (an option value clap refuses with 2), prints
//! `error: …` naming the file, field or phase, and leaves no output folder (nor a hidden
//! staging folder) behind; an interrupted solve exits with 130 (tests/cli_exit_codes.rs
//! has the other codes).

use crate::common;
use common::{footfall, json, root, s, stderr};

use std::path::Path;
use std::process::{Command, Output};

/// Everything in `dir`, hidden entries included, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("read dir")
        .map(|e| {
            e.expect("dir entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    v.sort();
    v
}

/// A failed run: exit code 1, one `error:` report that names every item of `names`, no panic.
fn assert_user_error(o: &Output, names: &[&str]) -> String {
    let err = stderr(o);
    assert_eq!(
        o.status.code(),
        Some(1),
        "expected exit code 1, stderr: {err}"
    );
    assert!(
        err.starts_with("error: "),
        "stderr does not start with `error:`: {err}"
    );
    assert!(!err.contains("panicked"), "the binary panicked: {err}");
    for n in names {
        assert!(err.contains(n), "stderr does not name {n:?}: {err}");
    }
    err
}

const STEP: [&str; 6] = [
    "simulate",
    "--phase-set",
    "phases/sim_ellipse_step.json",
    "--controls",
    "phases/sim_controls_cocontraction.csv",
    "--quiet",
];

fn step_args<'a>(out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut a: Vec<&str> = STEP.to_vec();
    a.extend(["--out", out]);
    a.extend(extra);
    a
}

/// Every number in a JSON document is finite (serde_json writes NaN and ±inf as `null`).
fn assert_all_finite(v: &serde_json::Value, at: &str) {
    match v {
        serde_json::Value::Null => panic!("summary.json: null (a non-finite number?) at {at}"),
        serde_json::Value::Number(n) => {
            assert!(
                n.as_f64().is_some_and(f64::is_finite),
                "summary.json: {n} at {at}"
            )
        }
        serde_json::Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| assert_all_finite(x, &format!("{at}[{i}]"))),
        serde_json::Value::Object(m) => m
            .iter()
            .for_each(|(k, x)| assert_all_finite(x, &format!("{at}.{k}"))),
        _ => {}
    }
}

#[test]
fn simulate_writes_a_complete_finite_run_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let o = footfall(&step_args(s(&out), &[]));
    assert!(o.status.success(), "simulate failed: {}", stderr(&o));
    assert_eq!(entries(tmp.path()), ["run"], "staging folder left behind");
    assert_eq!(
        entries(&out),
        [".footfall-run", "summary.json", "timeseries.csv"]
    );

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
            .expect("summary.json is JSON");
    let samples = summary["samples"].as_u64().expect("summary.samples");
    assert!(samples > 0);
    assert_all_finite(&summary, "summary");

    let csv = std::fs::read_to_string(out.join("timeseries.csv")).unwrap();
    let lower = csv.to_ascii_lowercase();
    assert!(
        !lower.contains("nan") && !lower.contains("inf"),
        "timeseries.csv holds non-finite text"
    );
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    assert_eq!(header[..3], ["time", "phase", "pelvis_x"]);
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len() as u64, samples, "one row per sample");
    for (i, row) in rows.iter().enumerate() {
        let cells: Vec<&str> = row.split(',').collect();
        assert_eq!(
            cells.len(),
            header.len(),
            "row {} has {} cells",
            i + 2,
            cells.len()
        );
        for (c, cell) in cells.iter().enumerate().filter(|(c, _)| *c != 1) {
            // empty = not applicable (e.g. the centre of pressure of an unloaded foot)
            if !cell.is_empty() {
                let v: f64 = cell
                    .parse()
                    .unwrap_or_else(|_| panic!("row {}, `{}`: `{cell}`", i + 2, header[c]));
                assert!(v.is_finite());
            }
        }
    }
}

#[test]
fn bad_model_file_is_refused_without_output() {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("bad_model.json");
    let text = std::fs::read_to_string(root().join("models/opensim_subject01.json"))
        .unwrap()
        .replace("../data/", &format!("{}/data/", s(&root())))
        .replace("\"gravity\": 9.80665", "\"gravity\": -9.80665");
    std::fs::write(&model, text).unwrap();
    let out = tmp.path().join("run");
    let o = footfall(&step_args(s(&out), &["--model", s(&model)]));
    let err = assert_user_error(&o, &[s(&model), "'gravity'", "positive"]);
    eprintln!("{err}");
    assert!(!out.exists(), "an output folder was created");
    assert_eq!(
        entries(tmp.path()),
        ["bad_model.json"],
        "something was left behind"
    );

    // malformed JSON names the file, line and column
    std::fs::write(&model, "{ \"name\": \"x\",\n  \"body\": { ] }\n").unwrap();
    let o = footfall(&step_args(s(&out), &["--model", s(&model)]));
    let err = assert_user_error(&o, &[s(&model), "invalid JSON", "line 2"]);
    eprintln!("{err}");
    assert_eq!(entries(tmp.path()), ["bad_model.json"]);
}

#[test]
fn bad_foot_phase_and_control_files_are_refused_without_output() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");

    let foot = tmp.path().join("foot.json");
    std::fs::write(
        &foot,
        r#"{ "name": "f", "primitives": [ { "name": "sole", "shape": { "type": "circle", "centre": [0.0, -0.05], "radius": -0.03 } } ] }"#,
    )
    .unwrap();
    let o = footfall(&step_args(s(&out), &["--foot", s(&foot)]));
    eprintln!(
        "{}",
        assert_user_error(&o, &[s(&foot), "primitives[0].shape.radius"])
    );

    let phases = tmp.path().join("phases.json");
    let text = std::fs::read_to_string(root().join("phases/sim_ellipse_step.json")).unwrap();
    std::fs::write(&phases, text.replacen("\"r.sole\"", "\"r.heel\"", 1)).unwrap();
    let mut args = step_args(s(&out), &[]);
    args[2] = s(&phases);
    let o = footfall(&args);
    eprintln!(
        "{}",
        assert_user_error(
            &o,
            &[
                s(&phases),
                "phase 'single_stance_r'",
                "unknown contact 'r.heel'"
            ]
        )
    );

    let controls = tmp.path().join("controls.csv");
    let text =
        std::fs::read_to_string(root().join("phases/sim_controls_cocontraction.csv")).unwrap();
    std::fs::write(&controls, text.replace("\n0.4,", "\n-0.4,")).unwrap();
    let mut args = step_args(s(&out), &[]);
    args[4] = s(&controls);
    let o = footfall(&args);
    eprintln!(
        "{}",
        assert_user_error(&o, &[s(&controls), "line 3", "does not increase"])
    );

    let missing = tmp.path().join("no_such_phases.json");
    let mut args = step_args(s(&out), &[]);
    args[2] = s(&missing);
    let o = footfall(&args);
    eprintln!("{}", assert_user_error(&o, &[s(&missing), "cannot read"]));

    assert_eq!(
        entries(tmp.path()),
        ["controls.csv", "foot.json", "phases.json"],
        "something was left behind"
    );
}

#[test]
fn existing_output_folder_is_kept_without_overwrite() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("keep.txt"), "precious").unwrap();
    let o = footfall(&step_args(s(&out), &[]));
    // a folder of the user's own: --overwrite would not replace it either
    let err = assert_user_error(
        &o,
        &[
            s(&out),
            "was not written by footfall",
            "choose another --out",
        ],
    );
    eprintln!("{err}");
    assert_eq!(entries(tmp.path()), ["run"], "staging folder left behind");
    assert_eq!(entries(&out), ["keep.txt"]);
    assert_eq!(
        std::fs::read_to_string(out.join("keep.txt")).unwrap(),
        "precious"
    );

    // --overwrite does not replace a folder footfall did not write
    let o = footfall(&step_args(s(&out), &["--overwrite"]));
    assert_user_error(&o, &[s(&out), "was not written by footfall", "'keep.txt'"]);
    assert_eq!(entries(&out), ["keep.txt"]);
    assert_eq!(entries(tmp.path()), ["run"], "staging folder left behind");

    // an empty folder, or one footfall wrote, is replaced by a complete run
    std::fs::remove_file(out.join("keep.txt")).unwrap();
    for _ in 0..2 {
        let o = footfall(&step_args(s(&out), &["--overwrite"]));
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(
            entries(&out),
            [".footfall-run", "summary.json", "timeseries.csv"]
        );
        assert_eq!(entries(tmp.path()), ["run"]);
    }
}

#[test]
fn integrator_failure_names_the_phase_and_leaves_no_output() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    // a tolerance below the unit roundoff: CVODES refuses at the first step (CV_TOO_MUCH_ACC)
    let o = footfall(&step_args(s(&out), &["--tol", "1e-300"]));
    let err = assert_user_error(&o, &["phase 'single_stance_r'", "t = ", "CV_TOO_MUCH_ACC"]);
    eprintln!("{err}");
    assert!(
        entries(tmp.path()).is_empty(),
        "output left behind: {:?}",
        entries(tmp.path())
    );
}

#[test]
fn invalid_integrator_tolerance_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let o = footfall(&step_args(s(&out), &["--tol", "2"]));
    let err = assert_user_error(&o, &["rtol", "(0, 1)"]);
    eprintln!("{err}");
    assert!(entries(tmp.path()).is_empty());
    let o = footfall(&[
        "track",
        "--sensitivity-tol",
        "1.5",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_user_error(&o, &["--sensitivity-tol", "sens_tol", "(0, 1)", "1.5"]);
    assert!(entries(tmp.path()).is_empty());
}

/// Ctrl-C during `footfall track` stops the solve and still writes a complete run folder
/// from the last accepted iterate, with the stop reason saying so.
#[test]
fn track_interrupted_by_ctrl_c_writes_the_last_iterate() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let mut child = Command::new(env!("CARGO_BIN_EXE_footfall"))
        .current_dir(root())
        .args(["track", "--out", s(&out), "--max-iter", "50"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // wait for the first iteration line, then send SIGINT
    use std::io::{BufRead, BufReader};
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let mut log = String::new();
    for line in lines.by_ref() {
        let line = line.unwrap();
        log.push_str(&line);
        log.push('\n');
        if line.trim_start().starts_with("1 ") {
            break;
        }
    }
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    for line in lines {
        log.push_str(&line.unwrap());
        log.push('\n');
    }
    let code = child.wait().unwrap();
    assert_eq!(
        code.code(),
        Some(130),
        "an interrupted solve exits with 130:\n{log}"
    );
    assert!(log.contains("interrupted"), "{log}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "interrupted");
    assert!(summary["iterations"].as_u64().unwrap() >= 1);
    // the integrator's counters of the solve: every step takes at least one right-hand
    // side and one Newton iteration, the staggered sensitivity corrector iterates too,
    // and the Newton matrix is factored at most once per step
    let n = |k: &str| {
        summary["integration"][k]
            .as_u64()
            .unwrap_or_else(|| panic!("integration.{k}: {}", summary["integration"]))
    };
    assert!(n("steps") > 1000, "{}", summary["integration"]);
    assert!(n("rhs_evals") >= n("steps") && n("nonlinear_iters") >= n("steps"));
    assert!(n("sens_nonlinear_iters") > 0 && n("sens_rhs_evals") > 0);
    assert!(n("linear_setups") >= 1 && n("linear_setups") <= n("steps"));
    // written at once: the 1 ms re-integration (seconds to minutes on a fine mesh far
    // from a solution) is left to `footfall report`, which runs it
    assert!(summary["fine_grid"].is_null());
    let why = summary["fine_grid_error"].as_str().unwrap();
    assert!(
        why.contains("interrupted") && why.contains("footfall report"),
        "{why}"
    );
    let report = Command::new(env!("CARGO_BIN_EXE_footfall"))
        .current_dir(root())
        .args(["report", s(&out)])
        .output()
        .unwrap();
    assert!(report.status.success(), "{report:?}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "interrupted");
    assert!(
        summary["fine_grid"]["step_s"].is_number(),
        "{}",
        summary["fine_grid"]
    );
    assert_all_finite(&summary, "summary");
    for f in ["tracking.csv", "kinematics.sto", "table3.md", "report.html"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // the report says so: an amber box with the status and the infeasibility, and a
    // caution across every plot
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.contains(r#"<div class="summary warning" id="summary">"#),
        "not an amber box"
    );
    // ("interrupted", or "interrupted, physically invalid" when the last iterate breaks
    // physics between the nodes)
    assert!(html.contains(r#"<p class="status">interrupted"#));
    let inf = summary["infeasibility"].as_f64().unwrap();
    assert!(
        html.contains(&format!("<dt>infeasibility</dt><dd>{inf:.2e}</dd>")),
        "the infeasibility {inf:.2e} is not in the status box"
    );
    let plots = html.matches(">% of gait cycle").count();
    let notes = html.matches(r#"class="plot-note""#).count();
    assert!(
        plots >= 20 && notes == plots,
        "{notes} cautions on {plots} plots"
    );
    assert!(
        html.contains(">interrupted</text>")
            || html.contains(">interrupted, physically invalid</text>")
    );
    report_rewrites_a_track_run(&out, &summary);
}

/// `footfall report` re-evaluates a track run's solution without solving: the same
/// objective, errors and solver record, the where-it-fails section; bad input is named.
fn report_rewrites_a_track_run(run: &Path, summary: &serde_json::Value) {
    let dir = run.parent().unwrap();
    let again = dir.join("again");
    let o = footfall(&["report", s(run), "--out", s(&again), "--quiet"]);
    assert!(o.status.success(), "report: {}", stderr(&o));
    let rewritten: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(again.join("summary.json")).unwrap())
            .unwrap();
    assert_all_finite(&rewritten, "summary");
    for key in [
        "objective",
        "status",
        "iterations",
        "kkt",
        "errors",
        "errors_by_phase",
        "cost_breakdown",
        "history",
    ] {
        assert_eq!(
            rewritten[key], summary[key],
            "{key} differs after footfall report"
        );
    }
    let rel = (rewritten["infeasibility"].as_f64().unwrap()
        - summary["infeasibility"].as_f64().unwrap())
    .abs()
        / summary["infeasibility"].as_f64().unwrap();
    assert!(
        rel < 1e-3,
        "infeasibility {} against {}",
        rewritten["infeasibility"],
        summary["infeasibility"]
    );
    let html = std::fs::read_to_string(again.join("report.html")).unwrap();
    for text in [
        "Where the model fails",
        "Normalised error per channel and phase",
        "Data cost per shooting node",
        "re-evaluated from",
    ] {
        assert!(html.contains(text), "'{text}' not in the rewritten report");
    }
    // the output exists: refused without --overwrite
    let o = footfall(&["report", s(run), "--out", s(&again), "--quiet"]);
    assert_user_error(&o, &["again"]);
    // a run whose solution no longer reproduces its recorded objective
    let changed = dir.join("changed");
    std::fs::create_dir(&changed).unwrap();
    for f in ["setup.json", "solution.json"] {
        std::fs::copy(run.join(f), changed.join(f)).unwrap();
    }
    // with the inputs the run folder holds (setup.json names them inside it)
    for sub in std::fs::read_dir(run.join("inputs")).unwrap() {
        let sub = sub.unwrap().path();
        let to = changed.join("inputs").join(sub.file_name().unwrap());
        std::fs::create_dir_all(&to).unwrap();
        for f in std::fs::read_dir(&sub).unwrap() {
            let f = f.unwrap().path();
            std::fs::copy(&f, to.join(f.file_name().unwrap())).unwrap();
        }
    }
    let mut s2 = summary.clone();
    s2["objective"] = (summary["objective"].as_f64().unwrap() * 1.01).into();
    std::fs::write(changed.join("summary.json"), s2.to_string()).unwrap();
    let out = dir.join("out");
    let o = footfall(&["report", s(&changed), "--out", s(&out), "--quiet"]);
    assert_user_error(
        &o,
        &["changed", "re-evaluates to J", "re-run `footfall track`"],
    );
    // not a track run; no summary; not a folder
    s2["command"] = "predict".into();
    std::fs::write(changed.join("summary.json"), s2.to_string()).unwrap();
    let o = footfall(&["report", s(&changed), "--out", s(&out), "--quiet"]);
    assert_user_error(&o, &["summary.json", "`command`", "\"track\""]);
    std::fs::remove_file(changed.join("summary.json")).unwrap();
    let o = footfall(&["report", s(&changed), "--out", s(&out), "--quiet"]);
    assert_user_error(&o, &["summary.json"]);
    let o = footfall(&["report", "no/such/run", "--quiet"]);
    assert_user_error(&o, &["no/such/run", "not a run folder"]);
    assert!(!out.exists());
    assert!(
        entries(dir).iter().all(|e| !e.contains("partial")),
        "{:?}",
        entries(dir)
    );
}

#[test]
fn predict_and_compare_refuse_bad_arguments_before_solving() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p");
    // an initial solution that does not exist, or is not a solution
    let o = footfall(&[
        "predict",
        "--init",
        "no/such/run",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_user_error(&o, &["no/such/run", "no such run folder"]);
    let junk = dir.path().join("junk.json");
    std::fs::write(&junk, "{\"phases\": 3}").unwrap();
    let o = footfall(&["predict", "--init", s(&junk), "--out", s(&out), "--quiet"]);
    assert_user_error(&o, &["junk.json", "not a footfall solution"]);
    // a solution of another phase graph
    let sol = dir.path().join("other.json");
    std::fs::write(&sol, r#"{"phases": [{"name": "x", "set": 1, "t0": 0.0, "duration": 0.1, "controls": "linear", "x": [[0.0], [0.0]], "u": [[0.0], [0.0]]}], "theta": []}"#).unwrap();
    let o = footfall(&["predict", "--init", s(&sol), "--out", s(&out), "--quiet"]);
    assert_user_error(&o, &["phases/ellipse_walk.json", "continuous phases"]);
    let o = footfall(&["predict", "--speed=-1", "--out", s(&out), "--quiet"]);
    assert_user_error(&o, &["speed"]);
    assert!(!out.exists());
    // compare: one foot, an unknown expected foot, a malformed --init
    let o = footfall(&["compare", "--feet", "ellipse", "--out", s(&out), "--quiet"]);
    assert_user_error(&o, &["--feet", "at least two"]);
    let o = footfall(&[
        "compare",
        "--expect-transient",
        "banana",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_user_error(&o, &["--expect-transient banana"]);
    let o = footfall(&["compare", "--init", "ellipse", "--out", s(&out), "--quiet"]);
    assert_user_error(&o, &["--init ellipse", "FOOT=RUN"]);
    assert!(!out.exists());
    assert!(
        entries(dir.path()).iter().all(|e| !e.contains("partial")),
        "{:?}",
        entries(dir.path())
    );
}

/// A heel pad written in the model file (not only `--effect`) gets the integrator
/// tolerance its stiff dynamics need for the states while the sensitivities keep the
/// run's (with residual actuators both are tightened), and setup.json records both (so
/// `diagnose` re-fits and `report` rebuild the same problem; `report` reproduces the
/// run's objective bit for bit).
#[test]
fn track_tightens_the_integrator_for_a_pad_in_the_model_file() {
    let tmp = tempfile::tempdir().unwrap();
    let mut model: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("models/opensim_subject01.json")).unwrap(),
    )
    .unwrap();
    model["body"]["file"] = root()
        .join("data/opensim_subject01_model.json")
        .to_str()
        .unwrap()
        .into();
    model["effects"] =
        serde_json::json!([{ "type": "heel_pad_compliance", "stiffness": 150.0, "damping": 3.0 }]);
    let model_path = tmp.path().join("padded.json");
    std::fs::write(&model_path, model.to_string()).unwrap();
    let out = tmp.path().join("run");
    let o = Command::new(env!("CARGO_BIN_EXE_footfall"))
        .current_dir(root())
        .args([
            "track",
            "--model",
            s(&model_path),
            "--foot",
            "double-circle",
            "--init",
            "tests/data/hidden/double_circle_base",
            "--max-iter",
            "0",
            "--out",
            s(&out),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("integrator tolerance of the states 1e-8 → 1e-10"),
        "{err}"
    );
    assert!(err.contains("of the sensitivities 1e-8"), "{err}");
    let setup: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("setup.json")).unwrap()).unwrap();
    assert_eq!(setup["integrator_tol"], 1e-10, "{setup}");
    assert_eq!(setup["sensitivity_tol"], 1e-8, "{setup}");
    let o = Command::new(env!("CARGO_BIN_EXE_footfall"))
        .current_dir(root())
        .args(["report", s(&out), "--out", s(&tmp.path().join("report"))])
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "report of the padded run: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let html = std::fs::read_to_string(tmp.path().join("report/report.html")).unwrap();
    assert!(
        html.contains("J reproduced to 0e0"),
        "the padded run does not re-evaluate bit for bit from its setup.json"
    );
    // residual actuators keep the sensitivities at 1e-10 too (the KKT residual is
    // computed from them)
    let out = tmp.path().join("residuals");
    Command::new(env!("CARGO_BIN_EXE_footfall"))
        .current_dir(root())
        .args([
            "track",
            "--model",
            s(&model_path),
            "--foot",
            "double-circle",
            "--init",
            "tests/data/hidden/double_circle_base",
            "--residual-actuators",
            "--max-iter",
            "0",
            "--quiet",
            "--out",
            s(&out),
        ])
        .output()
        .unwrap();
    let setup: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("setup.json")).unwrap()).unwrap();
    assert_eq!(setup["integrator_tol"], 1e-10, "{setup}");
    assert!(setup.get("sensitivity_tol").is_none(), "{setup}");
}

/// A pad re-fit from where `diagnose`'s re-fit of a padded 100 Hz trial (noise seed 3)
/// once stalled at KKT 2.4e-5 converges to the same parameters. The stall was not the
/// loose sensitivities: the swing foot's clearance rows repeated, at the node after
/// lift-off and the node before landing, rows the problem already held, and their
/// multipliers grew without bound. Without them the first stage converges in 2
/// iterations; when a line search still fails, the solve goes on once with the
/// sensitivities at the states' tolerance.
#[test]
fn a_pad_fit_from_its_once_stalled_iterate_converges_to_the_same_parameters() {
    let tmp = tempfile::tempdir().unwrap();
    let trial = root().join("tests/data/hidden/heel_pad_compliance_seed3");
    let out = tmp.path().join("run");
    let o = footfall(&[
        "track",
        "--data",
        s(&trial.join("synthetic.csv")),
        "--init",
        s(&trial.join("stalled_refit")),
        "--foot",
        "double-circle",
        "--sample-targets",
        "--noise-weights",
        "angle=0.5,position=2,force=5,cop=5",
        "--effect",
        "heel_pad_compliance",
        "--hessian",
        "gauss-newton",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary = json(&out.join("summary.json"));
    assert_eq!(summary["status"], "converged", "{summary}");
    assert!(summary["kkt"].as_f64().unwrap() < 1e-5);
    let setup = json(&out.join("setup.json"));
    let start = json(&trial.join("stalled_refit/setup.json"));
    for (a, b) in setup["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .zip(start["parameters"].as_array().unwrap())
    {
        let (x, y) = (a["value"].as_f64().unwrap(), b["value"].as_f64().unwrap());
        assert!(
            (x - y).abs() < 1e-4 * y,
            "{}: {x} after, {y} at the stalled iterate",
            a["name"]
        );
    }
}

/// `--init` of a run that identified an effect's parameters starts free ones at its
/// values, but an `--effect` that holds a parameter fixed keeps the value it gives.
#[test]
fn track_holds_a_fixed_effect_parameter_at_its_given_value_despite_init() {
    let tmp = tempfile::tempdir().unwrap();
    let kept = root().join("tests/data/hidden/none/tracked_seed");
    let init = tmp.path().join("init");
    std::fs::create_dir(&init).unwrap();
    std::fs::copy(kept.join("solution.json"), init.join("solution.json")).unwrap();
    let mut setup: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(kept.join("setup.json")).unwrap()).unwrap();
    setup["parameters"] = serde_json::json!([{ "name": "ground_slope.angle", "value": 0.02, "unit": "rad", "free": true }]);
    std::fs::write(init.join("setup.json"), setup.to_string()).unwrap();
    let slope_after = |effect: &str, out: &str| {
        let out = tmp.path().join(out);
        Command::new(env!("CARGO_BIN_EXE_footfall"))
            .current_dir(root())
            .args([
                "track",
                "--data",
                "tests/data/hidden/none/synthetic.csv",
                "--kinematics-cutoff",
                "10",
                "--init",
                s(&init),
                "--effect",
                effect,
                "--max-iter",
                "0",
                "--quiet",
                "--out",
                s(&out),
            ])
            .output()
            .unwrap();
        let setup: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("setup.json")).unwrap())
                .unwrap();
        setup["parameters"][0]["value"].as_f64().unwrap()
    };
    assert_eq!(slope_after("ground_slope:angle=0.01,free=", "fixed"), 0.01);
    assert_eq!(slope_after("ground_slope", "free"), 0.02);
}

/// `--velocity-weight` scales the velocity targets' cost (0 drops them) at a given point
/// and is recorded in setup.json; a negative weight is refused before any output.
#[test]
fn track_velocity_weight_scales_the_velocity_targets_and_is_recorded() {
    let tmp = tempfile::tempdir().unwrap();
    let init = root().join("tests/data/hidden/none/tracked_seed");
    let run = |weight: Option<&str>, out: &str| {
        let out = tmp.path().join(out);
        let mut args = vec![
            "track",
            "--data",
            "tests/data/hidden/none/synthetic.csv",
            "--kinematics-cutoff",
            "10",
            "--init",
            s(&init),
            "--max-iter",
            "0",
            "--quiet",
            "--out",
            s(&out),
        ];
        if let Some(w) = weight {
            args.extend(["--velocity-weight", w]);
        }
        let o = Command::new(env!("CARGO_BIN_EXE_footfall"))
            .current_dir(root())
            .args(&args)
            .output()
            .unwrap();
        (o, out)
    };
    let (bad, bad_out) = run(Some("-1"), "bad");
    // refused by the option's parser: a usage error
    let err = stderr(&bad);
    assert_eq!(bad.status.code(), Some(2), "{err}");
    assert!(
        err.contains("'--velocity-weight <VELOCITY_WEIGHT>'") && err.contains("≥ 0"),
        "{err}"
    );
    assert!(!bad_out.exists());
    // (J, the velocity targets' share of it) at the kept solution
    let costs = |out: &Path| {
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let b = &summary["cost_breakdown"];
        let channels: Vec<&str> = b["channels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_str().unwrap())
            .collect();
        let velocities = channels.iter().position(|&c| c == "velocities").map(|i| {
            b["cost"][i]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .sum::<f64>()
        });
        (summary["objective"].as_f64().unwrap(), velocities)
    };
    let (j_seed, v_seed) = costs(&run(None, "seed").1);
    let (j_double, v_double) = costs(&run(Some("0.2"), "double").1);
    let (j_none, v_none) = costs(&run(Some("0"), "none").1);
    let v_seed = v_seed.expect("the seed's cost has velocity targets");
    assert!(
        v_seed > 0.01 * j_seed,
        "velocity targets {v_seed} of J {j_seed}"
    );
    assert!(
        (v_double.unwrap() - 2.0 * v_seed).abs() < 1e-9 * v_seed,
        "{v_double:?} vs 2 × {v_seed}"
    );
    assert!((j_double - j_seed - v_seed).abs() < 1e-9 * j_seed);
    assert_eq!(v_none, None, "weight 0 leaves no velocity channel");
    assert!(
        (j_none - (j_seed - v_seed)).abs() < 1e-9 * j_seed,
        "J {j_none} vs {j_seed} − {v_seed}"
    );
    let setup: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(tmp.path().join("double/setup.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(setup["velocity_weight"].as_f64(), Some(0.2));
}

/// `diagnose` says when the run it diagnoses stopped short of convergence (its score tests
/// assume the plain model's optimum), and only then: the kept solution of the no-effect
/// trial is a KKT point of the seed's cost but not of the cost with the velocity targets
/// doubled, where `track --max-iter 0` stops at the iteration limit.
#[test]
fn diagnose_cautions_on_a_run_that_did_not_converge() {
    let tmp = tempfile::tempdir().unwrap();
    let init = root().join("tests/data/hidden/none/tracked_seed");
    let verdict = |weight: &str| {
        let out = tmp.path().join(format!("w{weight}"));
        let args = [
            "track",
            "--data",
            "tests/data/hidden/none/synthetic.csv",
            "--kinematics-cutoff",
            "10",
            "--init",
            s(&init),
            "--max-iter",
            "0",
            "--velocity-weight",
            weight,
            "--quiet",
            "--out",
            s(&out),
        ];
        Command::new(env!("CARGO_BIN_EXE_footfall"))
            .current_dir(root())
            .args(args)
            .output()
            .unwrap();
        let status = serde_json::from_str::<serde_json::Value>(
            &std::fs::read_to_string(out.join("summary.json")).unwrap(),
        )
        .unwrap()["status"]
            .as_str()
            .unwrap()
            .to_string();
        let o = Command::new(env!("CARGO_BIN_EXE_footfall"))
            .current_dir(root())
            .args([
                "diagnose",
                s(&out),
                "--candidate",
                "ground_slope",
                "--verify",
                "0",
                "--quiet",
            ])
            .output()
            .unwrap();
        assert!(o.status.success(), "diagnose: {}", stderr(&o));
        let d: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(tmp.path().join(format!("w{weight}-diagnose/summary.json")))
                .unwrap(),
        )
        .unwrap();
        (status, d["verdict"].as_str().unwrap().to_string())
    };
    let (status, text) = verdict("0.1");
    assert_eq!(status, "converged");
    assert!(!text.contains("did not converge"), "{text}");
    let (status, text) = verdict("0.2");
    assert_eq!(status, "max_iterations");
    assert!(
        text.contains("Caution: the run did not converge (iteration limit reached)"),
        "{text}"
    );
}

/// `--one-sided-targets`: on a noise-free 1 kHz trial generated by the rigid
/// double-circle model, the cost at the generating solution has no force or velocity
/// error left, where the seed's interpolated targets average across the jumps a rigid
/// contact makes at the contact changes; `diagnose` tests the heel pad by a re-fit on
/// that run (its statistic the re-fit's decrease over the run's J/N, read back from the
/// two run folders) and names it as not scored on the interpolated one; a trial too
/// coarse for a phase is refused, naming the phase, before any output.
#[test]
fn one_sided_targets_match_the_generating_model_at_its_solution() {
    let tmp = tempfile::tempdir().unwrap();
    let base = root().join("tests/data/hidden/double_circle_base");
    let synth = |rate: &str, out: &str| {
        let out = tmp.path().join(out);
        let noise_free = [
            "--noise-angle-deg",
            "0",
            "--noise-position-mm",
            "0",
            "--noise-force-n",
            "0",
            "--noise-cop-mm",
            "0",
        ];
        let mut args = vec![
            "synth",
            "--from",
            s(&base),
            "--rate",
            rate,
            "--quiet",
            "--out",
            s(&out),
        ];
        args.extend(noise_free);
        let o = Command::new(env!("CARGO_BIN_EXE_footfall"))
            .current_dir(root())
            .args(&args)
            .output()
            .unwrap();
        assert!(o.status.success(), "synth: {}", stderr(&o));
        out.join("synthetic.csv")
    };
    let at_truth = |data: &Path, one_sided: bool, out: &str| {
        let out = tmp.path().join(out);
        let mut args = vec![
            "track",
            "--foot",
            "double-circle",
            "--data",
            s(data),
            "--init",
            s(&base),
            "--max-iter",
            "0",
            "--quiet",
            "--out",
            s(&out),
        ];
        if one_sided {
            args.push("--one-sided-targets");
        }
        (
            Command::new(env!("CARGO_BIN_EXE_footfall"))
                .current_dir(root())
                .args(&args)
                .output()
                .unwrap(),
            out,
        )
    };
    let channel_costs = |out: &Path| -> std::collections::HashMap<String, f64> {
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let b = &summary["cost_breakdown"];
        b["channels"]
            .as_array()
            .unwrap()
            .iter()
            .zip(b["cost"].as_array().unwrap())
            .map(|(c, v)| {
                (
                    c.as_str().unwrap().to_string(),
                    v.as_array()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_f64().unwrap())
                        .sum(),
                )
            })
            .collect()
    };
    let fast = synth("1000", "k");
    let interpolated = channel_costs(&at_truth(&fast, false, "interpolated").1);
    let (_, one_sided_out) = at_truth(&fast, true, "one_sided");
    let one_sided = channel_costs(&one_sided_out);
    eprintln!("at the truth, interpolated: {interpolated:?}\none-sided: {one_sided:?}");
    // the seed's targets: the left heel's force at heel strike averaged across its jump
    assert!(interpolated["normal GRF"] > 1e-3, "{interpolated:?}");
    for c in ["normal GRF", "tangential GRF"] {
        assert!(one_sided[c] < 1e-6, "{c}: {one_sided:?}");
    }
    assert!(
        one_sided["velocities"] < 1e-4
            && one_sided["velocities"] < 0.01 * interpolated["velocities"],
        "{one_sided:?}"
    );
    let setup: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(one_sided_out.join("setup.json")).unwrap())
            .unwrap();
    assert_eq!(setup["one_sided_targets"].as_bool(), Some(true));
    // diagnose tests the heel pad (no null value) by a full re-fit on a one-sided run …
    let read = |p: &Path| -> serde_json::Value {
        serde_json::from_str(
            &std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())),
        )
        .unwrap()
    };
    let diagnose = |run: &Path| {
        let o = Command::new(env!("CARGO_BIN_EXE_footfall"))
            .current_dir(root())
            .args([
                "diagnose",
                s(run),
                "--candidate",
                "heel_pad_compliance",
                "--max-iter",
                "2",
                "--quiet",
            ])
            .output()
            .unwrap();
        assert!(o.status.success(), "diagnose: {}", stderr(&o));
        read(&tmp.path().join(format!(
            "{}-diagnose/summary.json",
            run.file_name().unwrap().to_str().unwrap()
        )))
    };
    let d = diagnose(&one_sided_out);
    let t = &d["ranking"][0];
    assert_eq!(
        (
            t["effect"]["type"].as_str(),
            t["refit"].as_bool(),
            t["steps"].as_u64()
        ),
        (Some("heel_pad_compliance"), Some(true), Some(2)),
        "{t}"
    );
    let refit = tmp.path().join("one_sided+heel_pad_compliance");
    let (j, j_refit) = (
        read(&one_sided_out.join("summary.json"))["objective"]
            .as_f64()
            .unwrap(),
        read(&refit.join("summary.json"))["objective"]
            .as_f64()
            .unwrap(),
    );
    let rows = d["data_residuals"].as_f64().unwrap();
    // as if the residuals were independent, and divided by their variance inflation
    let independent = (j - j_refit).max(0.0) / (j / rows);
    assert!(
        (t["statistic_independent"].as_f64().unwrap() - independent).abs()
            <= 1e-9 * independent.max(1.0),
        "{t} against (J {j} − re-fit {j_refit}) / (J / {rows})"
    );
    let phi = t["inflation"].as_f64().unwrap();
    assert!(phi >= 1.0, "{t}");
    let statistic = independent / phi;
    assert!(
        (t["statistic"].as_f64().unwrap() - statistic).abs() <= 1e-9 * statistic.max(1.0),
        "{t}"
    );
    assert_eq!(
        t["significant"].as_bool(),
        Some(statistic > t["threshold"].as_f64().unwrap())
    );
    let refit_parameters: Vec<String> = read(&refit.join("setup.json"))["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(t["parameters"], serde_json::json!(refit_parameters));
    if let Some(v) = d["verified"].as_array().unwrap().first() {
        // a significant pad's verification is the same re-fit, not another
        assert_eq!(v["folder"].as_str(), refit.to_str());
    }
    // … and names it as not scored on a run with the seed's interpolated targets
    let d = diagnose(&tmp.path().join("interpolated"));
    assert!(d["ranking"].as_array().unwrap().is_empty());
    assert!(
        d["skipped"][0]
            .as_str()
            .unwrap()
            .starts_with("heel-pad compliance: not scored"),
        "{}",
        d["skipped"]
    );
    // at 50 Hz the 55 ms from heel strike to the forefoot's landing hold too few samples
    let coarse = synth("50", "coarse");
    let (o, out) = at_truth(&coarse, true, "coarse_run");
    assert_user_error(
        &o,
        &[
            "one-sided targets",
            "phase 2c",
            "fewer than 4",
            "sample faster",
        ],
    );
    assert!(!out.exists());
}

/// `--sample-targets`: every sample of a noise-free 100 Hz trial generated by the rigid
/// double-circle model is the model at its instant, so at the generating solution no data
/// cost is left (the integrator's tolerance), where the seed's interpolated node targets
/// keep the force steps at the contact changes; `--noise-weights` weights each channel by
/// its noise (the angles keeping the seed's weight: the ankles lose their 1/100, a force's
/// weight becomes σ_angle²/σ_force² of an angle's) and is recorded; bad noise weights are
/// refused before any output.
#[test]
fn sample_targets_match_the_generating_model_and_noise_weights_rescale_channels() {
    let tmp = tempfile::tempdir().unwrap();
    let base = root().join("tests/data/hidden/double_circle_base");
    let data = tmp.path().join("clean");
    let mut args = vec!["synth", "--from", s(&base), "--quiet", "--out", s(&data)];
    args.extend([
        "--noise-angle-deg",
        "0",
        "--noise-position-mm",
        "0",
        "--noise-force-n",
        "0",
        "--noise-cop-mm",
        "0",
    ]);
    let o = Command::new(env!("CARGO_BIN_EXE_footfall"))
        .current_dir(root())
        .args(&args)
        .output()
        .unwrap();
    assert!(o.status.success(), "synth: {}", stderr(&o));
    let data = data.join("synthetic.csv");
    let at_truth = |extra: &[&str], out: &str| {
        let out = tmp.path().join(out);
        let mut args = vec![
            "track",
            "--foot",
            "double-circle",
            "--data",
            s(&data),
            "--init",
            s(&base),
            "--max-iter",
            "0",
            "--quiet",
            "--out",
            s(&out),
        ];
        args.extend(extra);
        (
            Command::new(env!("CARGO_BIN_EXE_footfall"))
                .current_dir(root())
                .args(&args)
                .output()
                .unwrap(),
            out,
        )
    };
    let channel_costs = |out: &Path| -> std::collections::HashMap<String, f64> {
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let b = &summary["cost_breakdown"];
        b["channels"]
            .as_array()
            .unwrap()
            .iter()
            .zip(b["cost"].as_array().unwrap())
            .map(|(c, v)| {
                (
                    c.as_str().unwrap().to_string(),
                    v.as_array()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_f64().unwrap())
                        .sum(),
                )
            })
            .collect()
    };
    let interpolated = channel_costs(&at_truth(&[], "interpolated").1);
    let (_, samples_out) = at_truth(&["--sample-targets"], "samples");
    let samples = channel_costs(&samples_out);
    eprintln!("at the truth, interpolated: {interpolated:?}\nsamples: {samples:?}");
    assert!(interpolated["normal GRF"] > 1e-3, "{interpolated:?}");
    assert!(!samples.contains_key("velocities"), "{samples:?}");
    for (c, v) in &samples {
        if c != "excitations" && c != "activations" {
            assert!(*v < 1e-9, "{c}: {v} at the generating solution");
        }
    }
    let setup: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(samples_out.join("setup.json")).unwrap())
            .unwrap();
    assert_eq!(setup["sample_targets"].as_bool(), Some(true));
    // noise weights on the noisy trial without a hidden effect, at its kept solution
    let noisy = root().join("tests/data/hidden/double_circle_none/synthetic.csv");
    let init = root().join("tests/data/hidden/double_circle_none/tracked_samples");
    let on_noisy = |extra: &[&str], out: &str| {
        let out = tmp.path().join(out);
        let mut args = vec![
            "track",
            "--foot",
            "double-circle",
            "--sample-targets",
            "--data",
            s(&noisy),
            "--init",
            s(&init),
            "--max-iter",
            "0",
            "--quiet",
            "--out",
            s(&out),
        ];
        args.extend(extra);
        (
            Command::new(env!("CARGO_BIN_EXE_footfall"))
                .current_dir(root())
                .args(&args)
                .output()
                .unwrap(),
            out,
        )
    };
    let seed = channel_costs(&on_noisy(&[], "seed_weights").1);
    let (_, weighted_out) = on_noisy(
        &["--noise-weights", "angle=0.5,position=2,force=5,cop=5"],
        "noise_weights",
    );
    let weighted = channel_costs(&weighted_out);
    let peak = {
        let text = std::fs::read_to_string(&noisy).unwrap();
        let head: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let cols: Vec<usize> = head
            .iter()
            .enumerate()
            .filter(|(_, h)| h.starts_with("grf_y"))
            .map(|(i, _)| i)
            .collect();
        text.lines()
            .skip(1)
            .flat_map(|l| {
                let v: Vec<&str> = l.split(',').collect();
                cols.iter()
                    .map(move |&i| v[i].parse::<f64>().unwrap())
                    .collect::<Vec<_>>()
            })
            .fold(0.0, f64::max)
    };
    let ratio = |c: &str| weighted[c] / seed[c];
    // the seed weights an angle by 1/(π/4) per rad² and a force by 1/peak² per N²
    let force = (0.5f64.to_radians() / 5.0).powi(2) * peak * peak / std::f64::consts::FRAC_PI_4;
    for (c, expected) in [
        ("hip_r", 1.0),
        ("knee_l", 1.0),
        ("ankle_r", 100.0),
        ("normal GRF", force),
        ("tangential GRF", force),
    ] {
        assert!(
            (ratio(c) - expected).abs() < 1e-9 * expected,
            "{c}: cost ×{} with noise weights, expected ×{expected}",
            ratio(c)
        );
    }
    let setup: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(weighted_out.join("setup.json")).unwrap())
            .unwrap();
    assert!(
        (setup["noise_weights"]["force_n"].as_f64().unwrap() - 5.0).abs() < 1e-12,
        "{setup}"
    );
    for (bad, names) in [
        (
            "angle=0.5,force=5,cop=5",
            vec!["--noise-weights", "missing position"],
        ),
        (
            "angle=0.5,position=2,force=-5,cop=5",
            vec!["force", "positive"],
        ),
        (
            "angle=0.5,position=2,force=5,cop=5,speed=1",
            vec!["unknown key 'speed'"],
        ),
    ] {
        let (o, out) = on_noisy(&["--noise-weights", bad], "bad");
        assert_user_error(&o, &names);
        assert!(!out.exists());
    }
}
