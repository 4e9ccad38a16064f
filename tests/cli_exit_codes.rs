//! Exit codes of the `footfall` binary (`docs/commands.md`, "Exit codes"): option values outside
//! their range are usage errors (2, clap's), bad files are bad input (1), a solve stopped
//! by its iteration limit exits 3 and an infeasible one 4, both with the run folder
//! written. Success (0) is in tests/cli_solve.rs, interruption (130) in tests/cli.rs.

use crate::common::{assert_exit, edited_json, footfall, root, s};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[test]
fn out_of_range_option_values_are_usage_errors_naming_the_option() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let finite_positive = "expected a finite number > 0";
    let kkt = "expected a KKT tolerance > 0 and ≤ 0.01";
    let cases: &[(&[&str], &str, &str)] = &[
        (&["track", "--tol", "NaN"], "'--tol <TOL>'", kkt),
        (&["track", "--tol=-1"], "'--tol <TOL>'", kkt),
        (&["track", "--tol", "-1"], "'--tol <TOL>'", kkt),
        (&["track", "--tol", "1e300"], "'--tol <TOL>'", kkt),
        (&["predict", "--tol", "0.5"], "'--tol <TOL>'", kkt),
        (
            &["track", "--max-time", "-5"],
            "'--max-time <MAX_TIME>'",
            finite_positive,
        ),
        (
            &["track", "--integrator-tol", "0"],
            "'--integrator-tol <INTEGRATOR_TOL>'",
            finite_positive,
        ),
        (
            &["track", "--sensitivity-tol", "inf"],
            "'--sensitivity-tol <SENSITIVITY_TOL>'",
            finite_positive,
        ),
        (
            &["track", "--exact-below", "NaN"],
            "'--exact-below <EXACT_BELOW>'",
            "≥ 0 (or inf)",
        ),
        (
            &["track", "--max-iter", "1000000"],
            "'--max-iter <MAX_ITER>'",
            "from 0 to 100000",
        ),
        (
            &["track", "--regularisation=-1e-3"],
            "'--regularisation <REGULARISATION>'",
            "finite number ≥ 0",
        ),
        (
            &["track", "--transient-threshold", "0"],
            "'--transient-threshold <TRANSIENT_THRESHOLD>'",
            finite_positive,
        ),
        (
            &["track", "--kinematics-cutoff", "NaN"],
            "'--kinematics-cutoff <KINEMATICS_CUTOFF>'",
            finite_positive,
        ),
        (
            &["track", "--window", "1.6,0.5"],
            "'--window <T0,T1>'",
            "must be before",
        ),
        (
            &["track", "--window", "0.5"],
            "'--window <T0,T1>'",
            "expected T0,T1",
        ),
        (&["track", "--stride", "0"], "'--stride <N>'", "not in 1.."),
        (
            &["track", "--plate", "x"],
            "'--plate <FOOT=PREFIX|FOOT=N>'",
            "expected FOOT=PREFIX",
        ),
        (
            &["predict", "--plate", "q=2"],
            "'--plate <FOOT=PREFIX|FOOT=N>'",
            "foot 'q' is neither r (right) nor l (left)",
        ),
        (
            &["track", "--effect", "bogus"],
            "'--effect <NAME[:key=value,…]>'",
            "'bogus' is not a known effect; use one of ground_slope",
        ),
        (
            &["track", "--effect", "trunk_mass:added_mass=4,added_mass=5"],
            "'--effect <NAME[:key=value,…]>'",
            "'added_mass' is given twice",
        ),
        (
            &[
                "solve",
                "--problem",
                "problems/cartpole_swingup.json",
                "--tol",
                "NaN",
            ],
            "'--tol <TOL>'",
            kkt,
        ),
        (
            &[
                "solve",
                "--problem",
                "problems/cartpole_swingup.json",
                "--max-time",
                "0",
            ],
            "'--max-time <MAX_TIME>'",
            finite_positive,
        ),
        (
            &["predict", "--impulse-weight=-1"],
            "'--impulse-weight <IMPULSE_WEIGHT>'",
            "finite number ≥ 0",
        ),
        (
            &["predict", "--ankle-velocity-limit", "0"],
            "'--ankle-velocity-limit <ANKLE_VELOCITY_LIMIT>'",
            finite_positive,
        ),
        (
            &["predict", "--max-violation-growth=-2"],
            "'--max-violation-growth <MAX_VIOLATION_GROWTH>'",
            "number ≥ 0 (or inf)",
        ),
        (
            &["compare", "--expect-ratio", "inf"],
            "'--expect-ratio <EXPECT_RATIO>'",
            finite_positive,
        ),
        (
            &[
                "simulate",
                "--phase-set",
                "phases/sim_ellipse_step.json",
                "--dt",
                "0",
            ],
            "'--dt <DT>'",
            finite_positive,
        ),
        (
            &["fit-foot", "--tol", "NaN"],
            "'--tol <TOL>'",
            finite_positive,
        ),
        (
            &["diagnose", "runs/x", "--max-iter=-1"],
            "'--max-iter <MAX_ITER>'",
            "from 0 to 100000",
        ),
        (
            &["synth", "--from", "runs/x", "--noise-force-n=-5"],
            "'--noise-force-n <NOISE_FORCE_N>'",
            "finite number ≥ 0",
        ),
        (
            &["synth", "--from", "runs/x", "--rate", "0"],
            "'--rate <RATE>'",
            finite_positive,
        ),
        (
            &["diff", "a", "b", "--threshold-pct", "NaN"],
            "'--threshold-pct <THRESHOLD_PCT>'",
            "finite number ≥ 0",
        ),
        (
            &["report", "runs/x", "--transient-threshold=-1"],
            "'--transient-threshold <TRANSIENT_THRESHOLD>'",
            finite_positive,
        ),
    ];
    for (args, option, valid) in cases {
        let mut a = args.to_vec();
        a.extend(["--out", s(&out), "--quiet"]);
        assert_exit(&footfall(&a), 2, &[option, valid]);
    }
    assert!(!out.exists());
}

#[test]
fn an_absurd_phase_file_is_bad_input() {
    let tmp = tempfile::tempdir().unwrap();
    let (o, out) = simulate_edited_phases(tmp.path(), |v| {
        v["phases"][0]["intervals"] = 1_000_000.into()
    });
    assert_exit(
        &o,
        1,
        &[
            "p.json",
            "phases[0] ('single_stance_r').intervals",
            "1 to 1000",
            "got 1000000",
        ],
    );
    assert!(!out.exists());
}

/// `simulate` of the bundled step with its phase file edited by `edit` (written to
/// `dir/p.json`): the result, and the run folder it was asked for (`dir/run`).
fn simulate_edited_phases(
    dir: &Path,
    edit: impl FnOnce(&mut serde_json::Value),
) -> (Output, PathBuf) {
    let p = edited_json("phases/sim_ellipse_step.json", &dir.join("p.json"), edit);
    let out = dir.join("run");
    let o = footfall(&[
        "simulate",
        "--phase-set",
        s(&p),
        "--out",
        s(&out),
        "--quiet",
    ]);
    (o, out)
}

#[test]
fn a_phase_sequence_of_too_many_intervals_in_all_is_bad_input() {
    let tmp = tempfile::tempdir().unwrap();
    let (o, out) = simulate_edited_phases(tmp.path(), |v| {
        v["phases"][0]["intervals"] = 600.into();
        v["phases"][2]["intervals"] = 600.into();
    });
    let err = assert_exit(
        &o,
        1,
        &["p.json", "phases[*].intervals", "at most 1000", "got 1200"],
    );
    assert!(err.len() < 300, "{err}");
    assert!(!out.exists());
}

#[test]
fn a_phase_of_a_billion_seconds_is_bad_input() {
    let tmp = tempfile::tempdir().unwrap();
    let (o, out) = simulate_edited_phases(tmp.path(), |v| v["phases"][0]["duration"] = 1e9.into());
    let err = assert_exit(
        &o,
        1,
        &[
            "p.json",
            "phases[0] ('single_stance_r').duration",
            "positive number of seconds, at most 60",
            "got 1e9",
        ],
    );
    assert!(err.len() < 300, "{err}");
    // each phase within the limit, the sequence beyond it
    let (o, _) = simulate_edited_phases(tmp.path(), |v| {
        v["phases"][0]["duration"] = 40.0.into();
        v["phases"][2]["duration"] = 40.0.into();
    });
    assert_exit(&o, 1, &["phases[*].duration", "at most 60 s", "got 80 s"]);
    assert!(!out.exists());
}

/// A foot file of `n` circles named `p0`, `p1`, …
fn foot_of_circles(path: &Path, n: usize) {
    let prims: Vec<String> = (0..n)
        .map(|k| {
            format!(
                r#"{{"name":"p{k}","shape":{{"type":"circle","centre":[0.0,-0.08],"radius":0.03}}}}"#
            )
        })
        .collect();
    let text = format!(r#"{{"name":"many","primitives":[{}]}}"#, prims.join(","));
    std::fs::write(path, text).unwrap();
}

#[test]
fn a_foot_of_300000_primitives_is_refused_at_once_in_a_short_message() {
    let tmp = tempfile::tempdir().unwrap();
    let foot = tmp.path().join("many.json");
    let out = tmp.path().join("run");
    foot_of_circles(&foot, 300_000);
    let start = std::time::Instant::now();
    let sim = |foot: &Path| {
        footfall(&[
            "simulate",
            "--foot",
            s(foot),
            "--phase-set",
            "phases/sim_ellipse_step.json",
            "--out",
            s(&out),
            "--quiet",
        ])
    };
    let o = sim(&foot);
    let err = assert_exit(
        &o,
        1,
        &["many.json", "primitives", "1 to 100", "got 300000"],
    );
    assert!(err.len() < 300, "{err}");
    assert!(start.elapsed().as_secs() < 20, "took {:?}", start.elapsed());
    // at the limit the foot is read, and a phase file naming a contact it lacks lists a
    // few of its 200 contacts and counts the rest
    foot_of_circles(&foot, 100);
    let err = assert_exit(
        &sim(&foot),
        1,
        &["unknown contact 'r.sole'", "r.p0, r.p1", "and 195 more"],
    );
    assert!(err.len() < 400, "{err}");
    assert!(!out.exists());
}

#[test]
fn an_absurd_gravity_is_bad_input_naming_the_field() {
    let tmp = tempfile::tempdir().unwrap();
    let m = edited_json(
        "models/gait9dof.json",
        &tmp.path().join("model.json"),
        |v| v["gravity"] = 1e308.into(),
    );
    let out = tmp.path().join("run");
    let o = footfall(&[
        "simulate",
        "--model",
        s(&m),
        "--phase-set",
        "phases/sim_ellipse_step.json",
        "--out",
        s(&out),
        "--quiet",
    ]);
    let err = assert_exit(
        &o,
        1,
        &[
            "model.json",
            "field 'gravity'",
            "1e308 m/s²",
            "(0, 100] m/s²",
        ],
    );
    assert!(err.len() < 300, "{err}");
    assert!(!out.exists());
}

#[test]
fn an_iteration_limit_exits_3_with_the_run_written() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("limited");
    let o = footfall(&[
        "solve",
        "--problem",
        "problems/cartpole_swingup.json",
        "--max-iter",
        "1",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_exit(&o, 3, &["iteration limit reached", "results written to"]);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "max_iterations");
}

#[test]
fn an_infeasible_problem_exits_4_with_the_run_written() {
    // the cart-pole cannot swing up with |u| ≤ 1 mN: the solver finds a stationary point
    // of the constraint violation (9 iterations on 10 intervals)
    let tmp = tempfile::tempdir().unwrap();
    let p = edited_json(
        "problems/cartpole_swingup.json",
        &tmp.path().join("weak.json"),
        |v| {
            v["bounds"]["u_lb"] = serde_json::json!([-0.001]);
            v["bounds"]["u_ub"] = serde_json::json!([0.001]);
            v["discretization"]["N"] = 10.into();
        },
    );
    let out = tmp.path().join("weak");
    let o = footfall(&["solve", "--problem", s(&p), "--out", s(&out), "--quiet"]);
    assert_exit(&o, 4, &["infeasible"]);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "infeasible");
}

#[test]
fn help_lists_the_exit_codes() {
    let o = footfall(&["--help"]);
    assert!(o.status.success());
    let help = String::from_utf8_lossy(&o.stdout);
    for line in [
        "Exit codes:",
        "  1    bad input",
        "  2    usage error",
        "  3    solved but not converged",
        "  4    infeasible",
        "  5    converged but physically invalid",
        "  130  interrupted",
    ] {
        assert!(help.contains(line), "{line:?} missing: {help}");
    }
}

#[test]
fn a_window_without_a_half_cycle_is_bad_input_listing_the_half_cycles() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let o = footfall(&["track", "--window", "0.0,0.4", "--out", s(&out), "--quiet"]);
    let err = assert_exit(&o, 1, &["no half cycle", "0–0.4 s", "1: "]);
    assert!(!out.join("summary.json").exists(), "{err}");
    let o = footfall(&["track", "--stride", "9", "--out", s(&out), "--quiet"]);
    assert_exit(&o, 1, &["stride 9 does not exist", "half cycle(s)"]);
}

#[test]
fn compare_contact_checks_every_foot_before_solving_anything() {
    // the rigid run would solve first; the missing volumetric foot is found before it, and
    // nothing is written
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cmp");
    let missing = tmp.path().join("no_such_foot.json");
    let o = footfall(&[
        "compare-contact",
        "--volumetric-foot",
        s(&missing),
        "--out",
        s(&out),
    ]);
    assert_exit(&o, 1, &["no_such_foot.json", "volumetric"]);
    assert!(
        !out.exists(),
        "a refused comparison wrote {}",
        out.display()
    );
}

#[test]
fn a_missing_foot_is_bad_input_listing_the_bundled_feet() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let o = footfall(&["track", "--foot", "nonexistent", "--out", s(&out)]);
    assert_exit(
        &o,
        1,
        &[
            "foot nonexistent: no such file",
            "`ellipse`, `double-circle`",
            "models/feet/volumetric_ellipse.json",
        ],
    );
    assert!(!out.exists());
}

#[test]
fn a_prediction_target_outside_human_gait_is_refused_before_solving() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let cases: &[(&[&str], &[&str])] = &[
        (
            &["--step-length", "-0.5"],
            &[
                "step length -0.5 m",
                "> 0 and ≤ 2.5 m",
                "the subject's: 0.687 m",
            ],
        ),
        (&["--step-length=0"], &["step length 0 m", "≤ 2.5 m"]),
        (
            &["--speed", "1e6"],
            &[
                "speed 1000000 m/s",
                "> 0 and ≤ 12 m/s",
                "the subject's: 1.133 m/s",
            ],
        ),
    ];
    for (extra, names) in cases {
        let mut a = vec!["predict", "--out", s(&out), "--quiet"];
        a.extend(*extra);
        assert_exit(&footfall(&a), 1, names);
        assert!(!out.exists());
    }
}

/// The cart-pole problem file with `edit` applied, written into `dir`.
fn edited_cartpole(dir: &Path, edit: impl Fn(&mut serde_json::Value)) -> PathBuf {
    edited_json(
        "problems/cartpole_swingup.json",
        &dir.join("edited.json"),
        edit,
    )
}

#[test]
fn a_problem_without_a_positive_horizon_or_with_crossed_bounds_is_refused_before_solving() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    type Edit = fn(&mut serde_json::Value);
    let cases: &[(Edit, &[&str])] = &[
        (
            |v| v["horizon"]["T"] = (-2.0).into(),
            &["field 'horizon.T'", "> 0 and ≤ 10000 s", "got -2"],
        ),
        (
            |v| v["horizon"]["T"] = 0.into(),
            &["field 'horizon.T'", "got 0"],
        ),
        (
            |v| {
                v["bounds"]["u_lb"] = serde_json::json!([10.0]);
                v["bounds"]["u_ub"] = serde_json::json!([-10.0]);
            },
            &[
                "field 'bounds.u_ub[0]' (-10) is below 'bounds.u_lb[0]' (10)",
                "at most the upper one",
            ],
        ),
    ];
    for (edit, names) in cases {
        let p = edited_cartpole(tmp.path(), edit);
        let o = footfall(&["solve", "--problem", s(&p), "--out", s(&out), "--quiet"]);
        let err = assert_exit(&o, 1, names);
        assert!(err.contains("edited.json"), "{err}");
        assert!(!out.exists(), "{err}");
    }
}

#[test]
fn an_effect_added_twice_is_a_usage_error_naming_both_items() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let o = footfall(&[
        "track",
        "--effect",
        "trunk_mass",
        "--effect",
        "trunk_mass:added_mass=2",
        "--out",
        s(&out),
    ]);
    let err = assert_exit(
        &o,
        2,
        &[
            "--effect: 'trunk_mass' and 'trunk_mass:added_mass=2' both add the effect 'trunk mass and COM offset'",
            "give it once",
        ],
    );
    assert!(!err.contains("models/"), "{err}");
    assert!(!out.exists());
}

#[test]
fn a_force_plate_surface_away_from_the_models_ground_is_refused_before_solving() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("trial_sagittal.csv");
    std::fs::copy(root().join("data/opensim_subject01_sagittal.csv"), &csv).unwrap();
    edited_json(
        "data/opensim_subject01_meta.json",
        &tmp.path().join("trial_meta.json"),
        |meta| meta["force_plate_surface_y_m"] = 0.05.into(),
    );
    let out = tmp.path().join("run");
    let o = footfall(&["track", "--data", s(&csv), "--out", s(&out), "--quiet"]);
    assert_exit(
        &o,
        1,
        &[
            "trial_sagittal.csv",
            "force-plate surface is at y = 0.05 m",
            "force_plate_surface_y_m",
            "contact.ground_height) is at y = -0.0075 m",
            "at most 10 mm",
        ],
    );
    assert!(!out.join("summary.json").exists());
}

#[test]
fn an_unconverged_runs_table_and_motion_say_so_in_their_first_line() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let o = footfall(&["track", "--max-iter", "0", "--out", s(&out), "--quiet"]);
    assert_exit(&o, 3, &["iteration limit reached", "results written to"]);
    let first = |name: &str| {
        let text = std::fs::read_to_string(out.join(name)).unwrap();
        text.lines().next().unwrap_or_default().to_string()
    };
    let table = first("table3.md");
    assert!(table.starts_with("**not converged"), "{table}");
    let sto = first("kinematics.sto");
    assert!(sto.starts_with("footfall_tracking: not converged"), "{sto}");
    for line in [table, sto] {
        assert!(
            line.contains("(iteration limit reached): the last iterate, not a solution"),
            "{line}"
        );
    }
}

#[test]
fn compare_checks_every_foot_and_phase_file_before_solving_anything() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cmp");
    let o = footfall(&["compare", "--feet", "ellipse,nonexistent", "--out", s(&out)]);
    assert_exit(
        &o,
        1,
        &["--feet nonexistent", "no such file", "`double-circle`"],
    );
    let phases = tmp.path().join("no_phases.json");
    let feet = format!("ellipse,models/feet/double_circle.json:{}", s(&phases));
    let o = footfall(&["compare", "--feet", &feet, "--out", s(&out)]);
    assert_exit(
        &o,
        1,
        &["--feet models/feet/double_circle.json:", "no_phases.json"],
    );
    assert!(
        !out.exists(),
        "a refused comparison wrote {}",
        out.display()
    );
}

#[test]
fn an_output_that_cannot_be_replaced_is_refused_without_a_hint_at_overwrite() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("notes.txt");
    std::fs::write(&file, "notes").unwrap();
    let problem = root().join("problems/cartpole_swingup.json");
    for (out, says) in [
        (".", "is the current folder or one of its parents"),
        ("/", "is the current folder or one of its parents"),
        (s(&file), "exists and is not a folder"),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_footfall"))
            .args(["solve", "--problem", s(&problem), "--out", out, "--quiet"])
            .current_dir(tmp.path())
            .output()
            .unwrap();
        let err = assert_exit(&o, 1, &[says, "choose another --out"]);
        assert!(!err.contains("pass --overwrite"), "{err}");
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "notes");
}

/// A trial whose forces never load a foot is refused naming its file once, with the
/// threshold and the peak force it found.
#[test]
fn a_trial_without_a_stance_names_its_file_once() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = std::fs::read_to_string(root().join("data/opensim_subject01_sagittal.csv")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    let forces: Vec<usize> = header
        .split(',')
        .enumerate()
        .filter(|(_, c)| c.starts_with("grf_"))
        .map(|(i, _)| i)
        .collect();
    let mut text = format!("{header}\n");
    for line in lines {
        let row: Vec<String> = line
            .split(',')
            .enumerate()
            .map(|(i, v)| {
                if forces.contains(&i) {
                    "0".into()
                } else {
                    v.to_string()
                }
            })
            .collect();
        text += &(row.join(",") + "\n");
    }
    let trial = tmp.path().join("unloaded.csv");
    std::fs::write(&trial, text).unwrap();
    std::fs::copy(
        root().join("data/opensim_subject01_meta.json"),
        tmp.path().join("unloaded_meta.json"),
    )
    .unwrap();
    let out = tmp.path().join("run");
    let o = footfall(&["track", "--data", s(&trial), "--out", s(&out)]);
    let err = assert_exit(&o, 1, &["unloaded.csv", "no stance phase"]);
    assert_eq!(err.matches("unloaded.csv").count(), 1, "{err}");
    assert!(!out.exists());
}
