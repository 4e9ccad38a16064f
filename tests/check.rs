//! The measurement check (`footfall check`): the whole-body balance's exact derivatives
//! against finite differences, edits of real recordings read against the untouched
//! recording with the truth kept beside them (tests/data/check/trials, made by
//! tools/make-check-trials), the untouched recordings' half cycles against the stated
//! level, and the refusals of data that cannot be right as declared.

use crate::common::{footfall, json, root, stderr};
use footfall::problems::check::balance::{residual, Body, Param, NPARAM};
use footfall::problems::check::signals::Signals;
use footfall::workflows::check::hips_on_measured_centres;
use footfall::workflows::trial::{load_trial, TrialFiles};
use std::path::{Path, PathBuf};

pub(crate) const BUNDLED_600: &str = "tests/data/check/opensim_subject01_600hz.csv";

fn model_of(recording: &str) -> &'static str {
    if recording.starts_with("opencap") {
        "models/opencap_s4.json"
    } else {
        "models/opensim_subject01.json"
    }
}

fn untouched_of(recording: &str) -> String {
    if recording.starts_with("opencap") {
        format!("data/{recording}_sagittal.csv")
    } else {
        BUNDLED_600.into()
    }
}

/// `footfall check TRIAL --model MODEL --out OUT`, which must succeed.
pub(crate) fn check_to(trial: &str, model: &str, out: &Path) {
    let o = footfall(&[
        "--quiet",
        "check",
        trial,
        "--model",
        model,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "check {trial}: {}", stderr(&o));
}

/// `footfall check TRIAL --model MODEL` into a fresh folder; its summary.json.
fn check(trial: &str, model: &str) -> serde_json::Value {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("check");
    check_to(trial, model, &out);
    json(&out.join("summary.json"))
}

fn candidate<'a>(summary: &'a serde_json::Value, effect: &str) -> &'a serde_json::Value {
    summary["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["effect"] == effect)
        .unwrap_or_else(|| panic!("no candidate {effect}"))
}

/// The bundled 600 Hz trial's signals as the check reads them (6 Hz, 60 ms margin), its
/// hips on the centres it measures for `model`.
pub(crate) fn bundled_600_signals(model: &footfall::model::GaitModel) -> Signals {
    let loaded = load_trial(&TrialFiles {
        data: Some(root().join(BUNDLED_600)),
        ..TrialFiles::default()
    })
    .expect("trial");
    let data = hips_on_measured_centres(loaded.data, model);
    Signals::new(&data, 6.0, 0.06).expect("signals")
}

#[test]
fn the_residuals_exact_jacobian_matches_central_differences() {
    let model = crate::common::model("opensim_subject01.json", "ellipse.json");
    let signals = bundled_600_signals(&model);
    let body = Body::of(&model).expect("body");
    let theta = [
        0.004, -0.003, 0.002, 0.02, -0.03, 0.01, -0.02, 0.03, 0.02, 1.5, 0.02,
    ];
    for &t in signals.instants.iter().step_by(97) {
        let at = body.instant(&signals, t);
        for p in Param::ALL {
            let k = p.index();
            let mut dual = [num_dual::Dual64::from(0.0); NPARAM];
            for (j, v) in theta.iter().enumerate() {
                dual[j] = num_dual::Dual64::from(*v);
            }
            dual[k] = num_dual::Dual64::from(theta[k]).derivative();
            let exact = residual(&body, &signals, &at, &dual).expect("inside");
            let h = 1e-6 * theta[k].abs().max(1e-3);
            let (mut up, mut down) = (theta, theta);
            up[k] += h;
            down[k] -= h;
            let fu = residual(&body, &signals, &at, &up).expect("inside");
            let fd = residual(&body, &signals, &at, &down).expect("inside");
            for i in 0..3 {
                let numeric = (fu[i] - fd[i]) / (2.0 * h);
                let e = exact[i].eps;
                assert!(
                    (e - numeric).abs() <= 1e-5 * numeric.abs().max(1.0),
                    "t {t}, {p:?}, component {i}: exact {e}, central difference {numeric}"
                );
            }
        }
    }
}

/// The edits the check must call found on each recording (and read within 20 % or 2 sd
/// of the truth against the untouched recording).
const READ_EDITS: [(&str, &[&str]); 3] = [
    (
        "opensim_subject01",
        &[
            "clock_both+20ms",
            "clock_both-20ms",
            "clock_l-10ms",
            "clock_l-20ms",
            "clock_l-40ms",
            "clock_r+20ms",
            "clock_r+40ms",
            "gain_l-7pct",
            "gain_r+3pct",
            "gain_r+7pct",
            "mass+5pct",
            "mass-5pct",
        ],
    ),
    (
        "opencap_s4_walking1",
        &[
            "clock_both+20ms",
            "clock_both-20ms",
            "clock_l-10ms",
            "clock_l-20ms",
            "clock_l-40ms",
            "clock_r+10ms",
            "clock_r+20ms",
            "clock_r+40ms",
            "gain_l-7pct",
            "gain_r+3pct",
            "gain_r+7pct",
            "mass+5pct",
            "mass-5pct",
        ],
    ),
    (
        "opencap_s4_walking2",
        &[
            "clock_both+20ms",
            "clock_both-20ms",
            "clock_l-10ms",
            "clock_l-20ms",
            "clock_l-40ms",
            "clock_r+10ms",
            "clock_r+20ms",
            "clock_r+40ms",
            "gain_l-7pct",
            "gain_r+3pct",
            "gain_r+7pct",
            "mass+5pct",
            "mass-5pct",
        ],
    ),
];

/// Every edit of one recording, sorted: its folder name and truth (effect, value).
fn edits_of(recording: &str) -> Vec<(String, String, f64)> {
    let dir = root().join("tests/data/check/trials").join(recording);
    let mut edits: Vec<(String, String, f64)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| {
            let name = e.unwrap().file_name().to_string_lossy().into_owned();
            let truth = json(&dir.join(&name).join("truth.json"));
            let effect = truth["effect"].as_str().unwrap().to_string();
            (name, effect, truth["value"].as_f64().unwrap())
        })
        .collect();
    edits.sort_by(|a, b| a.0.cmp(&b.0));
    edits
}

/// Each edit of the three recordings is checked as a user checks a trial. Those of
/// [`READ_EDITS`] are found; every edit found is read within 20 % or 2 sd of its truth
/// against the untouched recording; and every edit missed is one the check says it could
/// not have seen: not testable, or smaller than 1.25 times the smallest effect it states
/// it would have found.
#[test]
fn edits_of_real_recordings_are_found_and_read_against_the_untouched_recording() {
    let mut misses = Vec::new();
    for (recording, must_find) in READ_EDITS {
        let model = model_of(recording);
        let base = check(&untouched_of(recording), model);
        let edits = edits_of(recording);
        for name in must_find {
            assert!(
                edits.iter().any(|(n, ..)| n == name),
                "{recording}/{name} is not among the edits"
            );
        }
        for (edit, effect, value) in &edits {
            let dir: PathBuf = Path::new("tests/data/check/trials")
                .join(recording)
                .join(edit);
            let s = check(dir.join("trial.csv").to_str().unwrap(), model);
            let c = candidate(&s, effect);
            if c["verdict"] != "found" {
                let verdict = c["verdict"].as_str().unwrap();
                let least = c["smallest_found"].as_f64().unwrap_or(f64::NAN);
                if must_find.contains(&edit.as_str()) {
                    misses.push(format!("{recording}/{edit}: {effect} is {verdict}"));
                } else if !(verdict.starts_with("not testable") || 1.25 * least >= value.abs()) {
                    misses.push(format!(
                        "{recording}/{edit}: {effect} of {value} is {verdict}, though the check says it finds {least} and more"
                    ));
                }
                continue;
            }
            let reading = c["estimate"].as_f64().unwrap()
                - candidate(&base, effect)["estimate"].as_f64().unwrap();
            let sd = c["sd"].as_f64().unwrap();
            if (reading - value).abs() > (0.2 * value.abs()).max(2.0 * sd) {
                misses.push(format!(
                    "{recording}/{edit}: read {reading} ± {sd} against the untouched recording, truth {value}"
                ));
            }
            assert!(
                !s["add_effects"].as_array().unwrap().is_empty(),
                "{recording}/{edit}: no --effect line"
            );
        }
    }
    assert!(misses.is_empty(), "{}", misses.join("\n"));
}

const UNTOUCHED: [(&str, &str); 4] = [
    (BUNDLED_600, "models/opensim_subject01.json"),
    (
        "data/opencap_s4_walking1_sagittal.csv",
        "models/opencap_s4.json",
    ),
    (
        "data/opencap_s4_walking2_sagittal.csv",
        "models/opencap_s4.json",
    ),
    (
        "data/pig_c3dorg_D123_sagittal.csv",
        "models/pig_c3dorg_D123.json",
    ),
];

/// The loosest within-window sd at which each candidate counts as testable, as the check
/// and `tools/calibrate-check` use it.
fn testable(effect: &str) -> f64 {
    match effect {
        e if e.contains("clock") => 0.02,
        e if e.contains("gain") || e == "body_mass" => 0.2,
        e if e.contains("cop") || e == "trunk_com_offset" => 0.05,
        "trunk_mass" => 10.0,
        _ => 0.1,
    }
}

/// Each candidate's band over the half cycles of `summaries`, as `tools/calibrate-check`
/// computes it: centred on zero but for both plates' clock (the mean of each recording's
/// mean reading), the spread the root mean square of the readings alone about the centre.
fn null_band(summaries: &[&serde_json::Value]) -> serde_json::Map<String, serde_json::Value> {
    // per candidate, per recording: its half-cycle readings
    let mut readings: std::collections::BTreeMap<String, Vec<Vec<f64>>> = Default::default();
    for s in summaries {
        let mut own: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
        for h in s["half_cycles"].as_array().unwrap() {
            for r in h["alone"].as_array().into_iter().flatten() {
                let (Some(e), Some(w)) = (r["estimate"].as_f64(), r["sd_within"].as_f64()) else {
                    continue;
                };
                let name = r["effect"].as_str().unwrap().to_string();
                if w <= testable(&name) {
                    own.entry(name).or_default().push(e);
                }
            }
        }
        for (k, v) in own {
            readings.entry(k).or_default().push(v);
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    readings
        .into_iter()
        .map(|(k, per)| {
            let centre = if k == "shared_clock" {
                mean(&per.iter().map(|r| mean(r)).collect::<Vec<_>>())
            } else {
                0.0
            };
            let all: Vec<f64> = per.into_iter().flatten().collect();
            let spread =
                (all.iter().map(|e| (e - centre).powi(2)).sum::<f64>() / all.len() as f64).sqrt();
            let band = serde_json::json!({"mean": centre, "sd": spread});
            (k, band)
        })
        .collect()
}

#[test]
fn untouched_half_cycles_checked_out_of_sample_find_no_more_than_the_level_allows() {
    // each recording checked with the spread of the other recordings only, so that no
    // half cycle is judged by a calibration it took part in
    let all: Vec<serde_json::Value> = UNTOUCHED.iter().map(|(t, m)| check(t, m)).collect();
    let (mut found, mut half_cycles) = (Vec::new(), 0);
    for (k, (trial, model)) in UNTOUCHED.iter().enumerate() {
        let others: Vec<&serde_json::Value> = all
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != k)
            .map(|(_, s)| s)
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let null = dir.path().join("null.json");
        std::fs::write(
            &null,
            serde_json::Value::Object(null_band(&others)).to_string(),
        )
        .unwrap();
        let out = dir.path().join("check");
        let o = footfall(&[
            "--quiet",
            "check",
            trial,
            "--model",
            model,
            "--null",
            null.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        for h in json(&out.join("summary.json"))["half_cycles"]
            .as_array()
            .unwrap()
        {
            if let Some(f) = h["found"].as_array() {
                half_cycles += 1;
                found.extend(f.iter().map(|e| format!("{trial} {}: {e}", h["span_s"])));
            }
        }
    }
    // family-wise 5 % per half cycle: 0.4 half cycles with a finding expected in 8
    assert!(half_cycles >= 8, "{half_cycles} half cycles read");
    assert!(
        found.len() <= 1,
        "found in {half_cycles} untouched half cycles:\n{}",
        found.join("\n")
    );
}

/// The bundled 600 Hz trial with `edit` applied to every data row's cells, written to a
/// temporary folder with its meta file.
fn edited(edit: impl Fn(&str, &mut f64)) -> (tempfile::TempDir, String) {
    rewritten(|header, cells| {
        cells
            .iter()
            .zip(header)
            .map(|(c, h)| {
                let mut v: f64 = c.parse().unwrap();
                edit(h, &mut v);
                if v.is_nan() {
                    "NaN".into()
                } else {
                    v.to_string()
                }
            })
            .collect()
    })
}

/// The bundled 600 Hz trial with each data row's cells replaced by `row(header, cells)`,
/// written to a temporary folder with its meta file.
fn rewritten(row: impl Fn(&[&str], &[&str]) -> Vec<String>) -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().expect("temp dir");
    let text = std::fs::read_to_string(root().join(BUNDLED_600)).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut out = header.join(",") + "\n";
    for l in lines {
        let cells: Vec<&str> = l.split(',').collect();
        out += &(row(&header, &cells).join(",") + "\n");
    }
    let path = dir.path().join("trial.csv");
    std::fs::write(&path, out).unwrap();
    std::fs::copy(
        root().join("tests/data/check/opensim_subject01_600hz_meta.json"),
        dir.path().join("trial_meta.json"),
    )
    .unwrap();
    let p = path.to_str().unwrap().to_string();
    (dir, p)
}

fn refused(trial: &str, words: &[&str]) {
    let out = tempfile::tempdir().unwrap();
    let o = footfall(&[
        "check",
        trial,
        "--out",
        out.path().join("c").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("trial.csv"), "no file named: {e}");
    for w in words {
        assert!(e.contains(w), "'{w}' missing from: {e}");
    }
    assert!(!e.contains("panicked"), "{e}");
}

#[test]
fn data_that_cannot_be_right_as_declared_are_refused_with_what_was_found() {
    let (_d, t) = edited(|h, v| {
        if h == "time" {
            *v *= 1000.0
        }
    });
    refused(&t, &["time", "milliseconds"]);
    let (_d, t) = edited(|h, v| {
        if h == "pelvis_y" {
            *v *= 1000.0
        }
    });
    refused(&t, &["pelvis_y", "millimetres"]);
    let (_d, t) = edited(|h, v| {
        if h.starts_with("grf_") {
            *v *= 1.5
        }
    });
    refused(&t, &["imply a body of", "72.6 kg"]);
    let (_d, t) = edited(|h, v| {
        if h.starts_with("grf_x") {
            *v = -*v
        }
    });
    refused(&t, &["grf_x", "flipped"]);
}

#[test]
fn a_trial_without_one_foots_forces_or_too_short_is_refused_clearly() {
    let (_d, t) = edited(|h, v| {
        if h.ends_with("_l") && (h.starts_with("grf") || h.starts_with("cop")) {
            *v = f64::NAN
        }
    });
    refused(&t, &["left foot has no measured load"]);
    let (_d, t) = edited(|h, v| {
        if h.ends_with("_r") && (h.starts_with("grf") || h.starts_with("cop")) && *v != 0.0 {
            *v = f64::NAN
        }
    });
    refused(&t, &["right foot has no measured load"]);
    // both feet's loads known over the first 0.1 s only: too few instants to read
    let row_time = std::cell::Cell::new(0.0);
    let (_d, t) = edited(|h, v| {
        if h == "time" {
            row_time.set(*v);
        } else if (h.starts_with("grf") || h.starts_with("cop")) && row_time.get() > 0.1 {
            *v = f64::NAN
        }
    });
    refused(
        &t,
        &[
            "force samples",
            "have both feet's loads known",
            "are needed",
        ],
    );
}

#[test]
fn forces_that_stop_before_the_motion_are_read_where_known_and_the_check_says_where() {
    // every force and CoP unknown after 1.5 s of the bundled trial's 2.5 s
    let row_time = std::cell::Cell::new(0.0);
    let (_d, t) = edited(|h, v| {
        if h == "time" {
            row_time.set(*v);
        } else if (h.starts_with("grf") || h.starts_with("cop")) && row_time.get() > 1.5 {
            *v = f64::NAN
        }
    });
    let motion_end: f64 = std::fs::read_to_string(root().join(BUNDLED_600))
        .unwrap()
        .lines()
        .filter(|l| !l.is_empty())
        .last()
        .and_then(|l| l.split(',').next()?.parse().ok())
        .unwrap();
    let out = tempfile::tempdir().unwrap();
    let o = footfall(&["check", &t, "--out", out.path().join("c").to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    let line = stdout
        .lines()
        .find(|l| l.starts_with("read over "))
        .unwrap_or_else(|| panic!("no coverage line: {stdout}"));
    // "read over A–B s (N force samples …) of the motion's C–D s"
    let numbers: Vec<f64> = line
        .split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .filter_map(|w| w.parse().ok())
        .collect();
    let (last, end) = (numbers[1], numbers[4]);
    assert!(last <= 1.5, "read past the forces' end: {line}");
    assert!(
        (end - motion_end).abs() < 1e-3,
        "motion's end {motion_end}: {line}"
    );
}

#[test]
fn a_check_writes_its_run_folder_and_says_how_to_add_what_it_found() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("check");
    let trial = "tests/data/check/trials/opencap_s4_walking1/clock_r+40ms/trial.csv";
    let o = footfall(&[
        "check",
        trial,
        "--model",
        "models/opencap_s4.json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("--effect force_plate_time_offset:offset=0.04"),
        "{stdout}"
    );
    for f in [
        "summary.json",
        "readings.md",
        "readings.csv",
        "half_cycles.csv",
        "residual.csv",
        "residual.svg",
        "momentum.svg",
        "effects.txt",
        "report.html",
        "corrected/trial.csv",
        "corrected/trial_meta.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // the corrected trial reads back and no longer carries the clock
    let again = check(
        out.join("corrected/trial.csv").to_str().unwrap(),
        "models/opencap_s4.json",
    );
    let clock = candidate(&again, "clock_right");
    assert_ne!(clock["verdict"], "found", "{clock}");
}

#[test]
fn a_treadmill_plates_clock_is_read_on_its_plate_with_the_other_plates_named_as_its_look_alike() {
    // the bundled walk is a treadmill trial: its plate moments are read in the plates'
    // frame, so the right plate made 20 ms late shifts what that plate measured and not
    // the belt's travel; in double support the left plate early by as much looks alike,
    // and the check must say so
    let s = check(
        "tests/data/check/trials/opensim_subject01/clock_r+20ms/trial.csv",
        "models/opensim_subject01.json",
    );
    let right = candidate(&s, "clock_right");
    assert_eq!(right["verdict"], "found", "{right}");
    let alternatives = right["alternatives"]
        .as_array()
        .expect("alternatives listed");
    assert!(
        alternatives
            .iter()
            .any(|a| a["effect"] == "clock_left" && a["estimate"].as_f64().unwrap() < 0.0),
        "{right}"
    );
}

/// The hidden value of `field` in a model-made trial's `truth.json` (tests/data/hidden).
fn hidden(trial: &str, field: &str) -> f64 {
    let truth = json(
        &root()
            .join("tests/data/hidden")
            .join(trial)
            .join("truth.json"),
    );
    truth["hidden_effects"]
        .as_array()
        .unwrap()
        .iter()
        .find_map(|e| e[field].as_f64())
        .unwrap_or_else(|| panic!("{trial}: no hidden {field}"))
}

/// A ground slope hidden in a model-made trial (`synth` of the bundled trial's solution,
/// 100 Hz with synth's noise) is found by the whole-body balance and read within 20 % or
/// 2 sd of the truth.
#[test]
fn a_slope_hidden_in_a_model_made_trial_is_found_and_read() {
    let trial = root().join("tests/data/hidden/ground_slope/synthetic.csv");
    let s = check(trial.to_str().unwrap(), "models/opensim_subject01.json");
    let truth = hidden("ground_slope", "angle");
    let c = candidate(&s, "ground_slope");
    assert_eq!(c["verdict"], "found", "{c}");
    let (est, sd) = (c["estimate"].as_f64().unwrap(), c["sd"].as_f64().unwrap());
    assert!(
        (est - truth).abs() <= (0.2 * truth).max(2.0 * sd),
        "slope {est} ± {sd} rad against {truth}"
    );
}

/// Mass added to the trunk of a model-made trial scales the ground forces against the
/// body the model weighs: the balance reads it as a scale of its two sides (the body's
/// mass, or both plates' gains alike, which it names as look-alikes), each found
/// reading within 20 % or 2 sd of the added mass's share of the body's, and never all
/// three scales at once (scaled together they would fit the balance to zero).
#[test]
fn mass_added_to_a_model_made_trials_trunk_is_read_as_the_balances_scale() {
    let trial = root().join("tests/data/hidden/trunk_mass/synthetic.csv");
    let s = check(trial.to_str().unwrap(), "models/opensim_subject01.json");
    let share = hidden("trunk_mass", "added_mass") / s["mass_kg"]["model"].as_f64().unwrap();
    let scales = ["body_mass", "gain_right", "gain_left"];
    let found: Vec<&serde_json::Value> = s["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["verdict"] == "found")
        .collect();
    assert!(!found.is_empty(), "nothing found: {s}");
    assert!(found.len() <= 2, "{found:?}");
    for c in &found {
        let effect = c["effect"].as_str().unwrap();
        assert!(scales.contains(&effect), "{effect} found");
        let (est, sd) = (c["estimate"].as_f64().unwrap(), c["sd"].as_f64().unwrap());
        // a gain reads the forces high (reported over true), a mass error the body heavy
        assert!(
            (est - share).abs() <= (0.2 * share).max(2.0 * sd),
            "{effect} {est} ± {sd} against {share}"
        );
    }
}

/// Each shipped recording with the model of its subject (data/README.md, models/): the
/// untouched recordings the check is calibrated on, and the bundled one at its 60 Hz too.
fn shipped() -> impl Iterator<Item = (&'static str, &'static str)> {
    UNTOUCHED.into_iter().chain([(
        "data/opensim_subject01_sagittal.csv",
        "models/opensim_subject01.json",
    )])
}

/// The library's verdict on `trial` (a file under the repository) checked with `model`.
fn checked_in_library(
    trial: &str,
    model: &str,
) -> Result<footfall::problems::check::MeasurementCheck, footfall::problems::check::CheckError> {
    use footfall::problems::check::{check, CheckSettings};
    let loaded = load_trial(&TrialFiles {
        data: Some(root().join(trial)),
        ..TrialFiles::default()
    })
    .expect("trial");
    let model = crate::common::model(model.trim_start_matches("models/"), "ellipse.json");
    let data = hips_on_measured_centres(loaded.data, &model);
    check(&data, &model, &CheckSettings::default(), None)
}

/// A body file of another subject whose mass the forces pass (within 25 %) is refused:
/// posed by the trial's coordinates, its legs do not stand the loaded feet on the floor.
/// The refusal is typed, and its message names the trial, the model and the ankle
/// height measured; each shipped recording with its own model passes, with no warning
/// about the body.
#[test]
fn a_body_file_of_another_subject_is_refused_naming_both_files() {
    use footfall::problems::check::footing::{ANKLE_REFUSED, ANKLE_WARNED};
    use footfall::problems::check::{CheckError, Implausible};
    let wrong = [
        (
            "data/opensim_subject01_sagittal.csv",
            "models/opencap_s4.json",
        ),
        (
            "data/opencap_s4_walking1_sagittal.csv",
            "models/opensim_subject01.json",
        ),
    ];
    for (trial, model) in wrong {
        let height = match checked_in_library(trial, model) {
            Err(CheckError::Implausible(Implausible::Footing {
                path,
                model: file,
                ankle_height,
                ..
            })) => {
                assert!(
                    path.ends_with(trial) && file.ends_with(model),
                    "{path:?} {file:?}"
                );
                ankle_height
            }
            other => panic!("{trial} with {model}: not refused for its footing: {other:?}"),
        };
        assert!(
            !(ANKLE_REFUSED.0..=ANKLE_REFUSED.1).contains(&height),
            "{trial} with {model}: ankle {height} m"
        );
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("check");
        let o = footfall(&[
            "check",
            trial,
            "--model",
            model,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        let e = stderr(&o);
        for w in [
            trial,
            model,
            &format!("ankle lies {:.1} cm above the floor", 100.0 * height),
            "does not match this trial's subject",
        ] {
            assert!(e.contains(w), "'{w}' missing from: {e}");
        }
        assert!(!out.exists(), "{trial} with {model}: a folder written");
    }
    for (trial, model) in shipped() {
        let s = check(trial, model);
        let warnings = s["warnings"].as_array().expect("warnings listed");
        assert!(
            warnings
                .iter()
                .all(|w| !w.as_str().unwrap().contains("ankle")),
            "{trial} with {model}: {warnings:?}"
        );
        let c = checked_in_library(trial, model).expect("not refused");
        assert!(
            c.warnings.iter().all(|w| !w.contains("ankle")),
            "{:?}",
            c.warnings
        );
    }
    assert!(ANKLE_REFUSED.0 < ANKLE_WARNED.0 && ANKLE_WARNED.1 < ANKLE_REFUSED.1);
}

/// The bundled 600 Hz trial with the right and left force columns swapped: each loaded
/// foot then swings above the floor while the other stands on it, and the refusal names
/// the swap as a cause besides the body file.
#[test]
fn loads_of_the_other_foot_are_named_as_a_cause_when_the_loaded_foot_stands_off_the_floor() {
    // the column of the other foot's force or CoP of the same name
    let other = |header: &[&str], h: &str| {
        let (stem, side) = h.rsplit_once('_')?;
        let swapped = match side {
            "r" => "l",
            "l" => "r",
            _ => return None,
        };
        let partner = format!("{stem}_{swapped}");
        (h.starts_with("grf_") || h.starts_with("cop_"))
            .then(|| header.iter().position(|c| *c == partner))
            .flatten()
    };
    let (_dir, trial) = rewritten(|header, cells| {
        (0..cells.len())
            .map(|i| {
                other(header, header[i])
                    .map_or(cells[i], |j| cells[j])
                    .to_string()
            })
            .collect()
    });
    refused(
        &trial,
        &[
            "models/opensim_subject01.json",
            "above the swinging foot's",
            "swapped",
        ],
    );
}
