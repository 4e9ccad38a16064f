//! OpenSim files in and out: a trial given as the raw OpenSim pair (inverse kinematics and
//! external loads, `data/raw/opensim_subject01/`) is tracked and foot-fitted through the
//! command line, gives the same targets and costs as the sagittal CSV converted from it,
//! and the run's `kinematics.sto` carries OpenSim's coordinate names. Bad OpenSim input
//! (unknown extension, missing forces, unknown or ambiguous plates, degrees said to be
//! radians, a flipped vertical force, a treadmill trial without a belt speed) is refused
//! with a message that names the file, the column and what would be valid.

use crate::common;
use common::{csv_columns, footfall, grf, ik, json, raw, root, s, stderr};

use footfall::data::{
    parse_storage, read_sagittal_csv, read_storage, storage_text, OPENSIM_COORDINATES,
};
use footfall::workflows::trial::{load_trial, TrialFiles};
use std::path::{Path, PathBuf};

/// The belt speed of the bundled treadmill trial (its meta file's `belt_speed_m_s`).
const BELT_SPEED: &str = "1.1322";

/// The 2-D kinematics the bundled CSV was converted from (`data/convert_opensim_subject01.py`).
fn states() -> PathBuf {
    raw("walk_gait1018_state_reference.mot")
}

fn column<'a>(cols: &'a [(String, Vec<f64>)], name: &str) -> &'a [f64] {
    &cols
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no column {name}"))
        .1
}

fn files(data: &Path, forces: Option<&Path>) -> TrialFiles {
    TrialFiles {
        data: Some(data.to_path_buf()),
        forces: forces.map(Path::to_path_buf),
        ..Default::default()
    }
}

/// The message of a refused trial, checked to name every item of `words`.
fn refused(t: &TrialFiles, words: &[&str]) -> String {
    let e = match load_trial(t) {
        Ok(_) => panic!("{t:?} was accepted"),
        Err(e) => format!("{e:#}"),
    };
    for w in words {
        assert!(e.contains(w), "the message does not name {w:?}: {e}");
    }
    e
}

/// Linear interpolation of (t, v) at x (inside the range).
fn lerp(t: &[f64], v: &[f64], x: f64) -> f64 {
    let k = t.partition_point(|&a| a <= x).clamp(1, t.len() - 1);
    let w = (x - t[k - 1]) / (t[k] - t[k - 1]);
    v[k - 1] + w * (v[k] - v[k - 1])
}

#[test]
fn track_reads_the_raw_opensim_pair_and_writes_opensim_coordinate_names() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = footfall(&[
        "track",
        "--data",
        s(&ik()),
        "--forces",
        s(&grf()),
        "--belt-speed",
        BELT_SPEED,
        "--max-iter",
        "0",
        "--no-check-points",
        "--out",
        s(&out),
    ]);
    let err = stderr(&o);
    // no iteration: stopped at the iteration limit (exit 3), the run folder written
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("right foot ground_force_vx/vy/px (detected), left foot l_ground_force_vx/vy/px (detected)"),
        "the plate choice is not said: {err}"
    );
    // the run folder holds a copy of the forces file, which setup.json names
    let setup = json(&out.join("setup.json"));
    assert_eq!(
        setup["forces"].as_str(),
        Some("inputs/forces/subject01_walk1_grf.mot")
    );
    assert_eq!(
        std::fs::read(out.join("inputs/forces/subject01_walk1_grf.mot")).unwrap(),
        std::fs::read(grf()).unwrap()
    );
    assert_eq!(setup["belt_speed"].as_f64(), Some(1.1322));

    // kinematics.sto: OpenSim's coordinate names, radians stated, the model's coordinates
    let text = std::fs::read_to_string(out.join("kinematics.sto")).unwrap();
    let sto = parse_storage(&text, &out.join("kinematics.sto")).unwrap();
    let mut expected = vec!["time".to_string()];
    expected.extend(OPENSIM_COORDINATES.iter().map(|c| c.to_string()));
    assert_eq!(sto.columns, expected);
    assert!(text.contains("\ninDegrees=no\n") && !sto.in_degrees);
    // the 1 ms grid of fine_grid.csv, an impact's repeated instant once
    let fine = csv_columns(&out.join("fine_grid.csv"));
    let ft = column(&fine, "time");
    let keep: Vec<usize> = (0..ft.len())
        .filter(|&k| k == 0 || ft[k] > ft[k - 1])
        .collect();
    assert!(keep.len() < ft.len(), "no impact on the fine grid");
    assert_eq!(sto.len(), keep.len());
    let ours = footfall::model::gait::COORDINATES;
    for (o, c) in std::iter::once((&"time", "time")).chain(OPENSIM_COORDINATES.iter().zip(ours)) {
        let a = sto.column(o).unwrap();
        let b = column(
            &fine,
            &if c == "time" {
                c.to_string()
            } else {
                format!("model_{c}")
            },
        )
        .to_vec();
        assert!(a.iter().all(|x| x.is_finite()), "{o} not finite");
        // both written as {:.9e}
        assert!(
            keep.iter().zip(a).all(|(&k, x)| *x == b[k]),
            "{o} ≠ model_{c}"
        );
    }
    let knee = sto.column("knee_angle_r").unwrap();
    assert!(
        knee.iter().all(|k| (-1.6..0.3).contains(k)),
        "knee not in radians"
    );

    // the run's targets are the raw IK in radians, pelvis moved overground by the belt
    let raw = read_storage(&ik()).unwrap();
    let t_raw = raw.time();
    let nodes = csv_columns(&out.join("tracking.csv"));
    let times = column(&nodes, "time");
    assert!(times.len() > 20);
    for (o, c) in OPENSIM_COORDINATES.iter().zip(ours).skip(2) {
        let deg = raw.column(o).unwrap();
        let rad: Vec<f64> = deg.iter().map(|d| d.to_radians()).collect();
        let data = column(&nodes, &format!("data_{c}"));
        for (k, &t) in times.iter().enumerate() {
            let want = lerp(t_raw, &rad, t);
            // the targets are splines of the 60 Hz samples: within a few mrad of the chords
            assert!(
                (data[k] - want).abs() < 5e-3,
                "{c} at t = {t}: target {} but the raw IK gives {want}",
                data[k]
            );
        }
    }
    let px = raw.column("pelvis_tx").unwrap();
    let data = column(&nodes, "data_pelvis_x");
    for (k, &t) in times.iter().enumerate() {
        let want = lerp(t_raw, px, t) + 1.1322 * t;
        assert!(
            (data[k] - want).abs() < 2e-3,
            "pelvis_x at {t}: {} vs {want}",
            data[k]
        );
    }
}

#[test]
fn the_opensim_pair_gives_the_converted_csv_trials_targets_and_starting_cost() {
    // the bundled CSV is walk_gait1018_state_reference.mot with the GRF resampled at its
    // instants (7 significant digits): tracking either gives the same problem
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["track", "--max-iter", "0", "--no-check-points", "--quiet"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", s(&out)]);
        let o = footfall(&args);
        assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
        out
    };
    let a = run(
        "opensim",
        &[
            "--data",
            s(&states()),
            "--forces",
            s(&grf()),
            "--belt-speed",
            BELT_SPEED,
        ],
    );
    let b = run("csv", &[]);
    let j = |d: &Path| {
        json(&d.join("summary.json"))["history"][0]["objective"]
            .as_f64()
            .unwrap()
    };
    // the pair's forces are used at their own 600 Hz instants (the spline targets pass
    // through ten times the samples of the CSV's 60 Hz copy), so the costs agree to the
    // difference that makes: 0.09 % when measured
    let (ja, jb) = (j(&a), j(&b));
    assert!(
        (ja - jb).abs() < 2e-3 * jb,
        "starting cost {ja} (OpenSim pair) vs {jb} (CSV)"
    );
    // the tracked half cycle starts and ends at the same heel strikes, found on the
    // 600 Hz forces (the pair) and on their 60 Hz copy (the CSV, whose threshold crossings
    // are interpolated between samples 16.7 ms apart): within a quarter of a kinematic
    // sample (measured: 1.7 ms)
    let (na, nb) = (
        csv_columns(&a.join("tracking.csv")),
        csv_columns(&b.join("tracking.csv")),
    );
    for (x, y) in column(&na, "time").iter().zip(column(&nb, "time")) {
        assert!((x - y).abs() < 0.25 / 60.0, "node time {x} vs {y}");
    }
    // and at the kinematic instants the two trials are the same: the CSV is the pair
    // rounded to 7 digits
    let pair = load_trial(&TrialFiles {
        data: Some(states()),
        forces: Some(grf()),
        belt_speed: Some(1.1322),
        ..Default::default()
    })
    .unwrap()
    .data;
    let csv = load_trial(&TrialFiles::default()).unwrap().data;
    assert_eq!(pair.time.len(), csv.time.len());
    for (c, (qa, qb)) in pair.q.iter().zip(&csv.q).enumerate() {
        for (x, y) in qa.iter().zip(qb) {
            assert!((x - y).abs() < 1e-5, "coordinate {c}: {x} vs {y}");
        }
    }
    for (f, (fa, fb)) in pair.feet.iter().zip(&csv.feet).enumerate() {
        for (va, vb, what) in [(&fa.fx, &fb.fx, "fx"), (&fa.fy, &fb.fy, "fy")] {
            for (x, y) in va.iter().zip(vb) {
                assert!((x - y).abs() < 5e-3, "foot {f} {what}: {x} vs {y}");
            }
        }
        for (x, y) in fa.cop_x.iter().zip(&fb.cop_x) {
            assert!(
                (x.is_nan() && y.is_nan()) || (x - y).abs() < 1e-5,
                "foot {f} CoP: {x} vs {y}"
            );
        }
    }
}

#[test]
fn fit_foot_reads_the_opensim_pair() {
    let dir = tempfile::tempdir().unwrap();
    let fit = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["fit-foot", "--max-iter", "20", "--quiet"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", s(&out)]);
        let o = footfall(&args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        json(&out.join("summary.json"))
    };
    let raw = fit(
        "ik",
        &[
            "--data",
            s(&ik()),
            "--forces",
            s(&grf()),
            "--belt-speed",
            BELT_SPEED,
        ],
    );
    assert_eq!(raw["forces"].as_str(), Some(s(&grf())));
    assert!(raw["stances"].as_u64().unwrap() >= 4, "{raw}");
    assert!(raw["cost_fitted"].as_f64().unwrap() < raw["cost_initial"].as_f64().unwrap());
    // the 2-D pair and the CSV converted from it: the same stances, the same cost
    let a = fit(
        "states",
        &[
            "--data",
            s(&states()),
            "--forces",
            s(&grf()),
            "--belt-speed",
            BELT_SPEED,
        ],
    );
    let b = fit("csv", &[]);
    assert_eq!(a["samples"], b["samples"]);
    let (ca, cb) = (
        a["cost_initial"].as_f64().unwrap(),
        b["cost_initial"].as_f64().unwrap(),
    );
    // the forces at their own 600 Hz instants against the CSV's 60 Hz copy: 0.1 % apart
    assert!((ca - cb).abs() < 2e-3 * cb, "eq. 13 cost {ca} vs {cb}");
}

#[test]
fn the_opensim_pair_reads_as_the_csv_through_the_library() {
    let t = TrialFiles {
        belt_speed: Some(1.1322),
        ..files(&states(), Some(&grf()))
    };
    let d = load_trial(&t).unwrap();
    assert!(d.notes[0].contains("(detected)"), "{:?}", d.notes);
    let d = d.data;
    let csv = footfall::data::GaitData::bundled(&root()).unwrap();
    assert!(d.overground && d.belt_speed == Some(1.1322));
    for i in 0..9 {
        for (x, y) in d.q[i].iter().zip(&csv.q[i]) {
            assert!((x - y).abs() < 1e-6 * (1.0 + y.abs()), "q[{i}] {x} vs {y}");
        }
    }
    for s in 0..2 {
        for (x, y) in d.feet[s].fy.iter().zip(&csv.feet[s].fy) {
            assert!((x - y).abs() < 1e-3, "fy {x} vs {y}");
        }
    }
    // a CSV may take the belt speed from the command line only if it agrees with its meta
    let csv_path = root().join("data/opensim_subject01_sagittal.csv");
    let mut t = files(&csv_path, None);
    t.belt_speed = Some(1.1322);
    load_trial(&t).unwrap();
    t.belt_speed = Some(1.3);
    refused(
        &t,
        &[
            "opensim_subject01_sagittal.csv",
            "belt_speed_m_s",
            "1.1322",
            "1.3",
        ],
    );
    let _ = read_sagittal_csv(&csv_path).unwrap();
}

#[test]
fn unknown_extensions_and_missing_or_misplaced_forces_are_refused() {
    let readme = root().join("data/README.md");
    refused(
        &files(&readme, None),
        &["README.md", "--data", "'.md'", ".csv", ".mot or .sto"],
    );
    refused(
        &files(&ik(), None),
        &["subject01_walk1_ik.mot", "--forces GRF.mot"],
    );
    let csv = root().join("data/opensim_subject01_sagittal.csv");
    refused(
        &files(&csv, Some(&grf())),
        &[
            "--forces",
            "subject01_walk1_grf.mot",
            "holds its own forces",
        ],
    );
    refused(
        &files(&ik(), Some(&csv)),
        &["--forces", "opensim_subject01_sagittal.csv", ".mot or .sto"],
    );
    let mut t = files(&ik(), Some(&grf()));
    t.overground = true;
    t.belt_speed = Some(1.0);
    refused(&t, &["--belt-speed", "--overground"]);
    // and on the command line: exit 1, an `error:` line, no run folder
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never");
    let o = footfall(&["fit-foot", "--data", s(&readme), "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).starts_with("error: ") && stderr(&o).contains("'.md'"));
    assert!(!out.exists());
}

/// The GRF storage with its columns renamed by `rename` and the column `negate` negated.
fn edited_grf(dir: &Path, rename: impl Fn(&str) -> String, negate: Option<&str>) -> PathBuf {
    let g = read_storage(&grf()).unwrap();
    let names: Vec<String> = g.columns[1..].iter().map(|c| rename(c)).collect();
    let data: Vec<Vec<f64>> = g.columns[1..]
        .iter()
        .zip(&g.data[1..])
        .map(|(c, v)| {
            if Some(c.as_str()) == negate {
                v.iter().map(|x| -x).collect()
            } else {
                v.clone()
            }
        })
        .collect();
    let cols: Vec<(&str, &[f64])> = names
        .iter()
        .zip(&data)
        .map(|(n, v)| (n.as_str(), v.as_slice()))
        .collect();
    let p = dir.join("grf_edited.mot");
    std::fs::write(&p, storage_text("edited", g.time(), &cols)).unwrap();
    p
}

#[test]
fn kinematics_and_forces_given_the_wrong_way_round_are_named_as_swapped() {
    let e = refused(
        &files(&grf(), Some(&ik())),
        &[
            "--data",
            "subject01_walk1_grf.mot holds ground forces",
            "subject01_walk1_ik.mot holds kinematics",
            "swapped",
        ],
    );
    assert!(!e.contains("inDegrees"), "{e}");
}

#[test]
fn plates_are_detected_or_named_and_unknown_ones_refused() {
    let dir = tempfile::tempdir().unwrap();
    let numbered = edited_grf(
        dir.path(),
        |c| match c.strip_prefix("l_") {
            Some(rest) => format!("2_{rest}"),
            None => format!("1_{c}"),
        },
        None,
    );
    let mut t = files(&ik(), Some(&numbered));
    t.belt_speed = Some(1.1322);
    refused(
        &t,
        &[
            "grf_edited.mot",
            "right foot",
            "'1_'",
            "'2_'",
            "--plate r=PREFIX",
        ],
    );
    t.plates = vec!["r=1_".into(), "l=2_".into()];
    let d = load_trial(&t).unwrap();
    assert!(
        d.notes[0].contains("right foot 1_ground_force_vx/vy/px (--plate)"),
        "{:?}",
        d.notes
    );
    let mut plain = files(&ik(), Some(&grf()));
    plain.belt_speed = Some(1.1322);
    let p = load_trial(&plain).unwrap().data;
    assert_eq!(d.data.feet[0].fy, p.feet[0].fy);
    assert_eq!(d.data.feet[1].cop_x.len(), p.feet[1].cop_x.len());
    // crossed plates: the right foot reads the left plate
    plain.plates = vec!["r=l_".into(), "l=".into()];
    let x = load_trial(&plain).unwrap().data;
    assert_eq!(x.feet[0].fy, p.feet[1].fy);
    plain.plates = vec!["r=3_".into()];
    refused(
        &plain,
        &[
            "subject01_walk1_grf.mot",
            "3_ground_force_vy",
            "--plate r=3_",
            "'l_'",
        ],
    );
    plain.plates = vec!["x=1_".into()];
    refused(&plain, &["--plate x=1_", "neither r (right) nor l (left)"]);
    plain.plates = vec!["r1_".into()];
    refused(&plain, &["--plate r1_", "FOOT=PREFIX"]);
    plain.plates = vec!["l=".into()];
    refused(&plain, &["both feet", "ground_force_vy"]);
}

#[test]
fn degrees_said_to_be_radians_are_refused_naming_file_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(ik()).unwrap();
    assert!(text.contains("Angles are in degrees."));
    let p = dir.path().join("ik_radians.mot");
    std::fs::write(
        &p,
        text.replace("Angles are in degrees.", "Angles are in radians."),
    )
    .unwrap();
    let mut t = files(&p, Some(&grf()));
    t.belt_speed = Some(1.1322);
    refused(
        &t,
        &[
            "ik_radians.mot",
            "pelvis_tilt",
            "looks like degrees",
            "inDegrees=yes",
        ],
    );
    // a header that states no unit: say which line to add
    let p = dir.path().join("ik_unstated.mot");
    std::fs::write(&p, text.replace("Angles are in degrees.", "")).unwrap();
    t.data = Some(p);
    refused(
        &t,
        &[
            "ik_unstated.mot",
            "inDegrees",
            "add the line 'inDegrees=yes'",
        ],
    );
}

#[test]
fn radians_said_to_be_degrees_are_refused_naming_file_and_column() {
    // the 2-D kinematics in radians under a header that says degrees
    let dir = tempfile::tempdir().unwrap();
    let k = read_storage(&states()).unwrap();
    assert!(k.in_degrees);
    let rotational = |c: &str| !matches!(c, "pelvis_tx" | "pelvis_ty");
    let data: Vec<Vec<f64>> = k.columns[1..]
        .iter()
        .zip(&k.data[1..])
        .map(|(c, v)| {
            v.iter()
                .map(|x| if rotational(c) { x.to_radians() } else { *x })
                .collect()
        })
        .collect();
    let cols: Vec<(&str, &[f64])> = k.columns[1..]
        .iter()
        .zip(&data)
        .map(|(n, v)| (n.as_str(), v.as_slice()))
        .collect();
    let text = storage_text("radians", k.time(), &cols);
    let p = dir.path().join("states_in_radians.mot");
    std::fs::write(&p, text.replace("inDegrees=no", "inDegrees=yes")).unwrap();
    let mut t = files(&p, Some(&grf()));
    t.belt_speed = Some(1.1322);
    refused(
        &t,
        &[
            "states_in_radians.mot",
            "knee_angle",
            "look like radians",
            "inDegrees=no",
        ],
    );
    // the same numbers under a header that says radians are the bundled trial
    std::fs::write(&p, text).unwrap();
    let d = load_trial(&t).unwrap().data;
    let csv = footfall::data::GaitData::bundled(&root()).unwrap();
    assert!((d.q[4][10] - csv.q[4][10]).abs() < 1e-6);
}

#[test]
fn a_flipped_vertical_force_is_refused_naming_the_force_file_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let flipped = edited_grf(dir.path(), str::to_string, Some("l_ground_force_vy"));
    let mut t = files(&ik(), Some(&flipped));
    t.belt_speed = Some(1.1322);
    let e = refused(
        &t,
        &[
            "grf_edited.mot",
            "l_ground_force_vy",
            "negative through stance",
            "sign looks flipped",
        ],
    );
    assert!(!e.contains("grf_y_l"), "{e}");
}

#[test]
fn a_treadmill_pair_needs_a_belt_speed_or_overground() {
    let t = files(&ik(), Some(&grf()));
    refused(
        &t,
        &[
            "subject01_walk1_ik.mot",
            "pelvis_tx",
            "treadmill",
            "--belt-speed",
            "--overground",
        ],
    );
    let d = load_trial(&TrialFiles {
        overground: true,
        ..t.clone()
    })
    .unwrap()
    .data;
    assert!(!d.overground && d.belt_speed.is_none());
    let v = load_trial(&TrialFiles {
        belt_speed: Some(1.1322),
        ..t
    })
    .unwrap()
    .data;
    // moved by belt_speed · t
    let k = v.time.len() - 1;
    assert!((v.q[0][k] - d.q[0][k] - 1.1322 * v.time[k]).abs() < 1e-12);
}

/// A kinematics file and a forces file of the same name (from two folders) both keep
/// their copy in the run folder: the forces have a folder of their own.
#[test]
fn kinematics_and_forces_of_one_name_are_both_copied_into_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("ik"), dir.path().join("grf"));
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    std::fs::copy(ik(), a.join("walk.mot")).unwrap();
    std::fs::copy(grf(), b.join("walk.mot")).unwrap();
    let out = dir.path().join("run");
    let o = footfall(&[
        "track",
        "--data",
        s(&a.join("walk.mot")),
        "--forces",
        s(&b.join("walk.mot")),
        "--belt-speed",
        BELT_SPEED,
        "--max-iter",
        "0",
        "--no-check-points",
        "--quiet",
        "--out",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let setup = json(&out.join("setup.json"));
    assert_eq!(setup["data"].as_str(), Some("inputs/data/walk.mot"));
    assert_eq!(setup["forces"].as_str(), Some("inputs/forces/walk.mot"));
    let read = |p: &str| std::fs::read(out.join(p)).unwrap();
    assert_eq!(read("inputs/data/walk.mot"), std::fs::read(ik()).unwrap());
    assert_eq!(
        read("inputs/forces/walk.mot"),
        std::fs::read(grf()).unwrap()
    );
}
