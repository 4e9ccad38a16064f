//! Input that reads without error but cannot be right (a flipped axis, a unit off by a
//! thousand, an option outside its range) is refused by the command line before any
//! solve, with exit code 1 and a message that names the file, the column or field, what
//! was found and what would be valid.

use crate::common::{assert_exit, edited_json, footfall, root, s, stderr};
use std::path::{Path, PathBuf};
use std::process::Output;

/// The bundled sagittal CSV with `edit` applied to the cells of `columns` (NaN cells
/// left as they are), written as `dir/trial.csv` beside the bundled meta file.
fn edited_csv(dir: &Path, columns: &[&str], edit: impl Fn(f64) -> f64) -> PathBuf {
    let text = std::fs::read_to_string(root().join("data/opensim_subject01_sagittal.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let idx: Vec<usize> = header
        .split(',')
        .enumerate()
        .filter(|(_, c)| columns.contains(c))
        .map(|(i, _)| i)
        .collect();
    assert_eq!(idx.len(), columns.len(), "{columns:?} in {header}");
    let mut out = format!("{header}\n");
    for line in lines.filter(|l| !l.is_empty()) {
        let row: Vec<String> = line
            .split(',')
            .enumerate()
            .map(|(i, v)| match v.parse::<f64>() {
                Ok(x) if idx.contains(&i) && x.is_finite() => format!("{:.12e}", edit(x)),
                _ => v.to_string(),
            })
            .collect();
        out += &(row.join(",") + "\n");
    }
    let p = dir.join("trial.csv");
    std::fs::write(&p, out).unwrap();
    std::fs::copy(
        root().join("data/opensim_subject01_meta.json"),
        dir.join("trial_meta.json"),
    )
    .unwrap();
    p
}

/// The bundled OpenSim external loads with `edit` applied to the columns whose names end
/// in `suffix`, written as `dir/grf.mot`.
fn edited_grf(dir: &Path, suffix: &str, edit: impl Fn(f64) -> f64) -> PathBuf {
    let src = root().join("data/raw/opensim_subject01/subject01_walk1_grf.mot");
    let text = std::fs::read_to_string(src).unwrap();
    let mut out = String::new();
    let mut idx: Option<Vec<usize>> = None;
    let mut header_done = false;
    for line in text.lines() {
        let cells: Vec<&str> = line.split('\t').collect();
        if !header_done {
            header_done = line.trim() == "endheader";
            out += &format!("{line}\n");
            continue;
        }
        let Some(cols) = &idx else {
            idx = Some(
                (0..cells.len())
                    .filter(|&i| cells[i].trim().ends_with(suffix))
                    .collect(),
            );
            out += &format!("{line}\n");
            continue;
        };
        let row: Vec<String> = cells
            .iter()
            .enumerate()
            .map(|(i, v)| match v.trim().parse::<f64>() {
                Ok(x) if cols.contains(&i) => format!("{}", edit(x)),
                _ => v.to_string(),
            })
            .collect();
        out += &(row.join("\t") + "\n");
    }
    assert!(idx.is_some_and(|c| c.len() == 2), "two {suffix} columns");
    let p = dir.join("grf.mot");
    std::fs::write(&p, out).unwrap();
    p
}

/// `footfall track` on `data` (and `forces`, with the bundled trial's belt speed) with one
/// iteration at most, into `dir/run`; the run folder must not exist afterwards.
fn track(dir: &Path, data: &Path, forces: Option<&Path>) -> Output {
    let out = dir.join("run");
    let mut args = vec!["track", "--data", s(data), "--out", s(&out), "--quiet"];
    args.extend(["--max-iter", "1"]);
    if let Some(f) = forces {
        args.extend(["--forces", s(f), "--belt-speed", "1.1322"]);
    }
    let o = footfall(&args);
    assert!(!out.exists(), "{}", stderr(&o));
    o
}

fn ik() -> PathBuf {
    root().join("data/raw/opensim_subject01/subject01_walk1_ik.mot")
}

#[test]
fn a_flipped_forward_force_is_refused_with_the_braking_and_propulsion_it_shows() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = edited_csv(tmp.path(), &["grf_x_r", "grf_x_l"], |v| -v);
    for cmd in ["track", "check"] {
        let o = if cmd == "track" {
            track(tmp.path(), &csv, None)
        } else {
            let out = tmp.path().join("check");
            footfall(&["check", s(&csv), "--out", s(&out)])
        };
        assert_exit(
            &o,
            1,
            &[
                "trial.csv: grf_x_r:",
                "pushes the foot forward in the first half (+20.1 N·s",
                "back in the second (-21.2 N·s)",
                "brakes first and then propels",
                "sign looks flipped",
            ],
        );
    }
    // one plate's axis alone is named too
    let csv = edited_csv(tmp.path(), &["grf_x_l"], |v| -v);
    assert_exit(
        &track(tmp.path(), &csv, None),
        1,
        &["trial.csv: grf_x_l:", "2 complete stances"],
    );
}

#[test]
fn an_opensim_forward_force_flipped_is_refused_naming_the_force_file_and_column() {
    let tmp = tempfile::tempdir().unwrap();
    let grf = edited_grf(tmp.path(), "ground_force_vx", |v| -v);
    let err = assert_exit(
        &track(tmp.path(), &ik(), Some(&grf)),
        1,
        &["grf.mot: ground_force_vx:", "sign looks flipped"],
    );
    assert!(!err.contains("grf_x_r"), "{err}");
}

#[test]
fn an_opensim_cop_in_millimetres_is_refused_naming_the_force_file_and_column() {
    let tmp = tempfile::tempdir().unwrap();
    let grf = edited_grf(tmp.path(), "ground_force_px", |v| 1e3 * v);
    let err = assert_exit(
        &track(tmp.path(), &ik(), Some(&grf)),
        1,
        &[
            "grf.mot: ground_force_px:",
            "beyond the 1.5 m any foot reaches",
            "millimetres",
        ],
    );
    assert!(!err.contains("ik.mot"), "{err}");
}

#[test]
fn a_kkt_tolerance_that_calls_any_start_converged_is_refused_by_the_library_before_solving() {
    use footfall::limits::OutOfRange;
    use footfall::workflows::{track::TrackRequest, Quiet};
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let expected = "--tol 1e300: expected a KKT tolerance > 0 and ≤ 0.01";
    let mut req = TrackRequest::new("ellipse");
    req.sqp.tol_kkt = 1e300;
    let folder = footfall::runfolder::RunFolder::create(&out, false).unwrap();
    let Err(e) = footfall::workflows::track::track(&req, folder, &Quiet) else {
        panic!("a KKT tolerance of 1e300 was accepted");
    };
    let typed = e.downcast_ref::<OutOfRange>().expect("an OutOfRange error");
    assert_eq!((typed.option, typed.value), ("--tol", 1e300));
    assert!(e.to_string().contains(expected), "{e}");
    assert!(!out.exists());
    let solve = footfall::workflows::solve::SolveRequest {
        problem: Some(root().join("problems/cartpole_swingup.json")),
        out: out.clone(),
        overwrite: false,
        warm_start: None,
        tol: 1e300,
        max_iter: 1,
        max_time: None,
        integrator: None,
        hessian: None,
    };
    let e = footfall::workflows::solve::run(&solve, &Quiet).unwrap_err();
    assert!(e.downcast_ref::<OutOfRange>().is_some(), "{e}");
    assert!(e.to_string().contains(expected), "{e}");
    assert!(!out.exists());
    // the command line refuses it as a usage error, naming the option
    let o = footfall(&["track", "--tol", "1e300", "--out", s(&out)]);
    assert_exit(
        &o,
        2,
        &["'--tol <TOL>'", "expected a KKT tolerance > 0 and ≤ 0.01"],
    );
}

#[test]
fn a_trunk_angle_with_gaps_is_read_as_it_is_because_the_model_does_not_use_it() {
    // lower-body Plug-in Gait output has no trunk: lumbar_extension NaN in all rows or
    // in some; the bundled models freeze the trunk at their own angle
    let tmp = tempfile::tempdir().unwrap();
    let csv = edited_csv(tmp.path(), &["lumbar_extension"], |_| f64::NAN);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut gaps = String::new();
    for (k, line) in text.lines().enumerate() {
        let keep = k == 0 || k % 3 == 0;
        let row = match line.rsplit_once(',') {
            Some((head, _)) if !keep => format!("{head},NaN"),
            Some((head, v)) if k > 0 => format!("{head},{}", if v == "NaN" { "-0.4" } else { v }),
            _ => line.to_string(),
        };
        gaps += &(row + "\n");
    }
    assert!(text.lines().next().unwrap().ends_with(",lumbar_extension"));
    for (name, body) in [("all_nan.csv", text.clone()), ("gaps.csv", gaps)] {
        let p = tmp.path().join(name);
        std::fs::write(&p, body).unwrap();
        std::fs::copy(
            root().join("data/opensim_subject01_meta.json"),
            tmp.path().join(name.replace(".csv", "_meta.json")),
        )
        .unwrap();
        let trial = footfall::workflows::trial::load_trial(
            &footfall::workflows::trial::TrialFiles::csv(Some(p.clone()), false),
        )
        .unwrap_or_else(|e| panic!("{name}: {e}"));
        let lumbar = trial.data.extra.get("lumbar_extension");
        assert_eq!(lumbar.is_some(), name == "gaps.csv", "{name}");
        let out = tmp.path().join("run");
        let o = footfall(&[
            "track",
            "--data",
            s(&p),
            "--max-iter",
            "0",
            "--no-check-points",
            "--out",
            s(&out),
            "--quiet",
        ]);
        assert_exit(&o, 3, &["iteration limit reached"]);
        std::fs::remove_dir_all(&out).unwrap();
    }
    // a gap in a coordinate is still refused, naming the line and the column
    let csv = edited_csv(
        tmp.path(),
        &["hip_r"],
        |v| if v > 0.2 { f64::NAN } else { v },
    );
    assert_exit(
        &track(tmp.path(), &csv, None),
        1,
        &["trial.csv: line", "column 'hip_r': value is NaN"],
    );
}

#[test]
fn a_checkpoint_holding_nan_in_its_filter_or_constants_is_refused_naming_the_entry() {
    use footfall::sqp::checkpoint::{CheckpointError, ExactVec, SqpCheckpoint, CHECKPOINT_VERSION};
    let cp = |scalars: [f64; 7], filter: [f64; 4]| SqpCheckpoint {
        version: CHECKPOINT_VERSION,
        n: 2,
        m: 1,
        next_iter: 0,
        w: ExactVec::new(&[1.0, 2.0]),
        lambda: ExactVec::new(&[0.5]),
        nu: ExactVec::new(&[0.0, 0.0]),
        scalars: ExactVec::new(&scalars),
        filter: ExactVec::new(&filter),
        bfgs: vec![],
        history: vec![],
        timings: Default::default(),
    };
    let nan = f64::NAN;
    // θ_max before the first line search, the filter's first entry and the integrator
    // tolerance of an NLP that does not integrate are not numbers a solve must have
    let good = cp(
        [1.0, 1.0, 0.0, f64::INFINITY, 0.5, 3.0, nan],
        [1e4, f64::NEG_INFINITY, 1.0, 2.0],
    );
    good.check(2, 1).unwrap();
    for (bad, what) in [
        (
            cp([nan, 1.0, 0.0, 1e4, 0.5, 3.0, nan], [1e4, 0.0, 1.0, 2.0]),
            "scalars[0] is NaN",
        ),
        (
            cp([1.0, 1.0, 0.0, 1e4, 0.5, 3.0, nan], [1e4, 0.0, nan, 2.0]),
            "filter[2] is NaN",
        ),
    ] {
        let e = bad.check(2, 1).unwrap_err();
        assert!(matches!(e, CheckpointError::NonFinite { .. }), "{e}");
        assert!(e.to_string().contains(what), "{e}");
    }
}

/// Replace the meta file `edited_csv` wrote beside `dir/trial.csv` by the bundled one
/// with `edit` applied.
fn edit_meta(dir: &Path, edit: impl Fn(&mut serde_json::Value)) -> PathBuf {
    edited_json(
        "data/opensim_subject01_meta.json",
        &dir.join("trial_meta.json"),
        edit,
    )
}

#[test]
fn csv_times_in_milliseconds_are_refused_with_the_rate_they_imply() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = edited_csv(tmp.path(), &["time"], |t| 1e3 * t);
    assert_exit(
        &track(tmp.path(), &csv, None),
        1,
        &[
            "trial.csv: time:",
            "a rate of 0.060 Hz",
            "10–5000 Hz",
            "milliseconds",
        ],
    );
}

#[test]
fn csv_positions_in_millimetres_are_refused_naming_the_pelvis_height() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = edited_csv(tmp.path(), &["pelvis_x", "pelvis_y"], |x| 1e3 * x);
    assert_exit(
        &track(tmp.path(), &csv, None),
        1,
        &["trial.csv: pelvis_y:", "under 2 m", "millimetres"],
    );
}

#[test]
fn a_csv_cop_in_millimetres_is_refused_naming_the_column() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = edited_csv(tmp.path(), &["cop_x_r", "cop_x_l"], |x| 1e3 * x);
    assert_exit(
        &track(tmp.path(), &csv, None),
        1,
        &["trial.csv: cop_x_r:", "beyond the 1.5 m", "millimetres"],
    );
}

#[test]
fn a_meta_file_declaring_degrees_over_radians_is_refused_naming_the_meta_file() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = edited_csv(tmp.path(), &[], |x| x);
    edit_meta(tmp.path(), |m| m["units"]["angles"] = "deg".into());
    assert_exit(
        &track(tmp.path(), &csv, None),
        1,
        &[
            "trial_meta.json: units.angles:",
            "knee_r",
            "look like radians",
        ],
    );
}

#[test]
fn a_constant_knee_angle_is_refused_naming_the_column() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = edited_csv(tmp.path(), &["knee_r", "knee_l"], |_| -0.2);
    assert_exit(
        &track(tmp.path(), &csv, None),
        1,
        &["trial.csv: knee_r:", "at least 0.1 rad", "frozen"],
    );
}

#[test]
fn a_negative_belt_speed_in_a_meta_file_is_refused_naming_the_field() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = edited_csv(tmp.path(), &[], |x| x);
    edit_meta(tmp.path(), |m| m["belt_speed_m_s"] = (-1.1322).into());
    assert_exit(
        &track(tmp.path(), &csv, None),
        1,
        &[
            "trial_meta.json: belt_speed_m_s:",
            "> 0 and ≤ 12 m/s",
            "got -1.1322",
        ],
    );
}

#[test]
fn forces_that_imply_another_body_are_refused_by_track_as_by_check() {
    // the vertical forces × 1.5: the balance reads a body half as heavy again as the model's
    let tmp = tempfile::tempdir().unwrap();
    let csv = edited_csv(tmp.path(), &["grf_y_r", "grf_y_l"], |v| 1.5 * v);
    let checked = footfall(&["check", s(&csv), "--out", s(&tmp.path().join("check"))]);
    let tracked = track(tmp.path(), &csv, None);
    for o in [&checked, &tracked] {
        assert_exit(
            o,
            1,
            &[
                "trial.csv: the vertical forces imply a body of",
                "the model's is",
                "(+50 %)",
                "give the subject's model with --model",
            ],
        );
    }
}

#[test]
fn forces_a_sixth_off_the_models_body_are_tracked_with_a_note() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = edited_csv(tmp.path(), &["grf_y_r", "grf_y_l"], |v| 1.15 * v);
    let out = tmp.path().join("run");
    let o = footfall(&[
        "track",
        "--data",
        s(&csv),
        "--out",
        s(&out),
        "--max-iter",
        "1",
    ]);
    // the iteration limit (exit 3), with the mass named before the solve
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("trial.csv: the vertical forces imply a body of")
            && err.contains("+15 % from the model's"),
        "{err}"
    );
}

#[test]
fn opensim_forces_shorter_than_the_motion_are_refused_naming_both_spans() {
    // the bundled external loads cut at 1.0 s, the kinematics left whole
    let tmp = tempfile::tempdir().unwrap();
    let src = root().join("data/raw/opensim_subject01/subject01_walk1_grf.mot");
    let text = std::fs::read_to_string(src).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let end = lines.iter().position(|l| l.trim() == "endheader").unwrap();
    let rows: Vec<&str> = lines[end + 2..]
        .iter()
        .copied()
        .filter(|l| l.split('\t').next().unwrap().trim().parse::<f64>().unwrap() <= 1.0)
        .collect();
    let mut out = String::new();
    for l in &lines[..end + 2] {
        let l = if l.starts_with("datarows") {
            format!("datarows {}", rows.len())
        } else if l.starts_with("range") {
            "range 0.000000 1.000000".to_string()
        } else {
            l.to_string()
        };
        out += &format!("{l}\n");
    }
    for l in rows {
        out += &format!("{l}\n");
    }
    let grf = tmp.path().join("grf.mot");
    std::fs::write(&grf, out).unwrap();
    let check = tmp.path().join("check");
    for o in [
        footfall(&[
            "check",
            "--data",
            s(&ik()),
            "--forces",
            s(&grf),
            "--belt-speed",
            "1.1322",
            "--out",
            s(&check),
        ]),
        track(tmp.path(), &ik(), Some(&grf)),
    ] {
        assert_exit(&o, 1, &["grf.mot", "the forces cover", "the kinematics"]);
    }
}
