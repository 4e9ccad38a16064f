//! The hidden-effect trials made from the real measurements (`tools/make-real-
//! hidden-trials`, committed under `tests/data/real_hidden/`) hold what their truth says,
//! checked against the raw 600 Hz force record read by the library's own storage reader
//! (independently of the script): the kinematics are the bundled trial's, the edited
//! plate's forces are the raw ones moved in time, offset or scaled, the other plate's are
//! untouched, and a moved clock moves the force-threshold events with it. The same trials
//! with their forces at the raw 600 Hz (`tests/data/real_hidden_600hz/`, beside the
//! untouched trial in that form) are the raw record edited sample for sample.

use footfall::data::{detect_events, read_sagittal_csv, read_storage, GaitData};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The edited trials, in `tests/data/real_hidden` and `tests/data/real_hidden_600hz`.
const TRIALS: [&str; 5] = [
    "real_clock_r+25ms",
    "real_clock_l-20ms",
    "real_cop_r+25mm",
    "real_gain_l+6pct",
    "real_mass+5pct",
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn trial(name: &str) -> (GaitData, Value) {
    let dir = root().join("tests/data/real_hidden").join(name);
    let data = read_sagittal_csv(&dir.join("trial.csv")).unwrap();
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    (data, truth)
}

/// The raw force record's columns `fx, fy, px` of foot `side` (0 right, 1 left) and its
/// time column.
fn raw(side: usize) -> (Vec<f64>, [Vec<f64>; 3]) {
    let s =
        read_storage(&root().join("data/raw/opensim_subject01/subject01_walk1_grf.mot")).unwrap();
    let p = ["", "l_"][side];
    let col = |c: &str| s.column(&format!("{p}ground_force_{c}")).unwrap().to_vec();
    (s.time().to_vec(), [col("vx"), col("vy"), col("px")])
}

fn interp(t: &[f64], y: &[f64], at: f64) -> f64 {
    if at < t[0] || at > t[t.len() - 1] {
        return f64::NAN;
    }
    let k = t.partition_point(|&x| x <= at).clamp(1, t.len() - 1) - 1;
    let w = (at - t[k]) / (t[k + 1] - t[k]);
    (1.0 - w) * y[k] + w * y[k + 1]
}

/// The bundled trial as read from its CSV (the lab frame, as the edited trials are
/// stored; both move overground the same way when read).
fn bundled() -> GaitData {
    read_sagittal_csv(&GaitData::bundled_csv_path(&root())).unwrap()
}

/// Forces agree to the bundled CSV's converter (measured: 2.4 mN), CoP to 0.4 µm.
const FORCE_TOL: f64 = 5e-3;
const COP_TOL: f64 = 1e-6;

fn same_foot(a: &GaitData, b: &GaitData, side: usize, gain: f64, cop_offset: f64) {
    let (fa, fb) = (&a.feet[side], &b.feet[side]);
    for k in 0..a.time.len() {
        assert!(
            (fa.fx[k] - gain * fb.fx[k]).abs() < FORCE_TOL * gain,
            "fx[{k}]"
        );
        assert!(
            (fa.fy[k] - gain * fb.fy[k]).abs() < FORCE_TOL * gain,
            "fy[{k}]"
        );
        assert_eq!(
            fa.cop_x[k].is_nan(),
            fb.cop_x[k].is_nan(),
            "CoP defined at {k}"
        );
        if fa.cop_x[k].is_finite() {
            assert!(
                (fa.cop_x[k] - fb.cop_x[k] - cop_offset).abs() < COP_TOL,
                "cop[{k}]"
            );
        }
    }
}

#[test]
fn every_trial_keeps_the_kinematics_and_says_what_it_changed() {
    let b = bundled();
    for name in TRIALS {
        let (d, truth) = trial(name);
        assert_eq!(d.time, b.time, "{name}");
        assert_eq!(d.q, b.q, "{name}: kinematics copied");
        assert_eq!(d.belt_speed, b.belt_speed, "{name}: meta file beside it");
        assert_eq!(truth["trial"], name);
        // each foot: untouched, or changed exactly as the truth says
        for (side, key) in [(0, "r"), (1, "l")] {
            let gain = truth["gain"][key].as_f64().unwrap_or(1.0);
            let cop = truth["cop_offset_m"][key].as_f64().unwrap_or(0.0);
            if truth["clock_offset_s"][key].is_null() {
                same_foot(&d, &b, side, gain, cop);
            }
        }
    }
}

#[test]
fn a_moved_clock_is_the_raw_record_moved_and_moves_the_events() {
    let b = bundled();
    for (name, side, shift) in [
        ("real_clock_r+25ms", 0, 0.025),
        ("real_clock_l-20ms", 1, -0.020),
    ] {
        let (d, truth) = trial(name);
        let key = ["r", "l"][side];
        assert_eq!(truth["clock_offset_s"][key].as_f64(), Some(shift));
        let (t, [fx, fy, px]) = raw(side);
        let f = &d.feet[side];
        let mut compared = 0;
        for (k, &tk) in d.time.iter().enumerate() {
            let want = [interp(&t, &fx, tk - shift), interp(&t, &fy, tk - shift)];
            if want[1].is_nan() {
                // before the record starts: not measured
                assert!(f.fy[k].is_nan() && f.fx[k].is_nan(), "{name} at {tk}");
                continue;
            }
            assert!((f.fx[k] - want[0]).abs() < FORCE_TOL, "{name} fx at {tk}");
            assert!((f.fy[k] - want[1]).abs() < FORCE_TOL, "{name} fy at {tk}");
            if f.cop_x[k].is_finite() {
                let p = interp(&t, &px, tk - shift);
                assert!((f.cop_x[k] - p).abs() < COP_TOL, "{name} CoP at {tk}");
            }
            compared += 1;
        }
        assert!(compared > 140, "{name}: {compared} samples");
        // the other foot is the bundled trial's
        same_foot(&d, &b, 1 - side, 1.0, 0.0);
        // the edited foot's force-threshold events move by the offset (within a third of
        // a 60 Hz sample: the crossings are interpolated between samples); the other's
        // stay
        let (ea, eb) = (
            detect_events(&d, 0.05).unwrap(),
            detect_events(&b, 0.05).unwrap(),
        );
        let moved = |x: &[f64], y: &[f64]| -> Vec<f64> {
            x.iter()
                .filter_map(|&a| {
                    y.iter()
                        .map(|&b| a - b)
                        .min_by(|u, v| (u - shift).abs().total_cmp(&(v - shift).abs()))
                })
                .collect()
        };
        let hs = moved(&ea.heel_strike[side], &eb.heel_strike[side]);
        assert!(!hs.is_empty());
        for dt in &hs {
            assert!(
                (dt - shift).abs() < 6e-3,
                "{name}: heel strike moved {dt} s"
            );
        }
        let (other_a, other_b) = (&ea.heel_strike[1 - side], &eb.heel_strike[1 - side]);
        assert_eq!(other_a.len(), other_b.len());
        for (x, y) in other_a.iter().zip(other_b) {
            // (the threshold, 5 % of the trial's peak force, moves a little with the
            // shifted foot's samples)
            assert!(
                (x - y).abs() < 1e-4,
                "{name}: the other foot's heel strike {x} vs {y}"
            );
        }
    }
}

/// A trial of `tests/data/real_hidden_600hz` (forces at the raw record's rate).
fn trial_600(name: &str) -> (GaitData, Value) {
    let dir = root().join("tests/data/real_hidden_600hz").join(name);
    let data = read_sagittal_csv(&dir.join("trial.csv")).unwrap();
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    (data, truth)
}

/// Agreement of two values printed to 7 significant digits, NaN with NaN.
fn same_printed(a: f64, b: f64) -> bool {
    (a.is_nan() && b.is_nan()) || (a - b).abs() <= 2e-6 * a.abs().max(b.abs()) + 1e-9
}

#[test]
fn the_600_hz_trials_are_the_raw_record_edited_sample_for_sample() {
    let b = bundled();
    let (u, _) = trial_600("untouched");
    assert_eq!(u.time, b.time);
    assert_eq!(u.q, b.q, "kinematics copied");
    let rec = u.forces.as_ref().expect("forces at their own rate");
    assert_eq!(rec.time.len(), 1501, "0–2.5 s at 600 Hz");
    // (the kinematic rows keep the bundled CSV's times, printed to 7 digits)
    for (n, &t) in rec.time.iter().enumerate() {
        assert!((t - n as f64 / 600.0).abs() < 1e-6, "instant {n}: {t}");
    }
    // the untouched record is the raw one, sample for sample
    for side in 0..2 {
        let (_, [fx, fy, px]) = raw(side);
        let f = &rec.feet[side];
        for n in 0..rec.time.len() {
            assert!(same_printed(f.fx[n], fx[n]), "fx {side} {n}");
            assert!(same_printed(f.fy[n], fy[n]), "fy {side} {n}");
            if fy[n] >= 20.0 {
                assert!(same_printed(f.cop_x[n], px[n]), "cop {side} {n}");
            } else {
                assert!(f.cop_x[n].is_nan(), "no CoP below 20 N: {side} {n}");
            }
        }
    }
    for name in TRIALS {
        let (d, truth) = trial_600(name);
        assert_eq!(d.q, b.q, "{name}: kinematics copied");
        assert_eq!(truth, trial(name).1, "{name}: the same truth at both rates");
        let r = d.forces.as_ref().unwrap();
        assert_eq!(r.time, rec.time, "{name}");
        for (side, key) in [(0, "r"), (1, "l")] {
            let shift = truth["clock_offset_s"][key].as_f64().unwrap_or(0.0) * 600.0;
            let shift = shift.round() as i64;
            let gain = truth["gain"][key].as_f64().unwrap_or(1.0);
            let cop = truth["cop_offset_m"][key].as_f64().unwrap_or(0.0);
            let (f, g) = (&r.feet[side], &rec.feet[side]);
            for n in 0..r.time.len() as i64 {
                let m = n - shift;
                let i = n as usize;
                if m < 0 || m >= r.time.len() as i64 {
                    continue;
                }
                let m = m as usize;
                assert!(
                    same_printed(f.fx[i], gain * g.fx[m]),
                    "{name} fx {side} {n}"
                );
                assert!(
                    same_printed(f.fy[i], gain * g.fy[m]),
                    "{name} fy {side} {n}"
                );
                if f.cop_x[i].is_finite() || g.cop_x[m].is_finite() {
                    assert!(
                        (f.cop_x[i] - g.cop_x[m] - cop).abs() < 1e-6,
                        "{name} CoP {side} {n}"
                    );
                }
            }
        }
    }
}

#[test]
fn the_script_still_makes_the_committed_trials() {
    // regenerate into a copy of the needed tree and compare byte for byte (the script
    // needs only Python's standard library; skipped, and said, where there is no python3)
    let Ok(out) = std::process::Command::new("python3")
        .arg("--version")
        .output()
    else {
        eprintln!("no python3: the committed trials are not regenerated");
        return;
    };
    assert!(out.status.success());
    let tmp = tempfile::tempdir().unwrap();
    let copy = |rel: &str| {
        let to = tmp.path().join(rel);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(root().join(rel), &to).unwrap();
    };
    for rel in [
        "tools/make-real-hidden-trials",
        "data/opensim_subject01_sagittal.csv",
        "data/opensim_subject01_meta.json",
        "data/raw/opensim_subject01/subject01_walk1_grf.mot",
    ] {
        copy(rel);
    }
    let run = std::process::Command::new("python3")
        .arg(tmp.path().join("tools/make-real-hidden-trials"))
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let mut files = 0;
    for set in ["tests/data/real_hidden", "tests/data/real_hidden_600hz"] {
        let (made, committed) = (tmp.path().join(set), root().join(set));
        for entry in std::fs::read_dir(&committed).unwrap() {
            let dir = entry.unwrap().path();
            for f in ["trial.csv", "trial_meta.json", "truth.json"] {
                let name = dir.file_name().unwrap();
                let a = std::fs::read(dir.join(f)).unwrap();
                let b = std::fs::read(made.join(name).join(f)).unwrap();
                assert!(
                    a == b,
                    "{set}/{}/{f} differs from the script's",
                    Path::new(name).display()
                );
                files += 1;
            }
        }
    }
    // five edited trials at 60 Hz; the same and the untouched one at 600 Hz
    assert_eq!(files, 33);
}
