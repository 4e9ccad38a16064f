//! `diagnose`'s statistics: on a trial with a hidden CoP offset, named as a candidate,
//! under the seed's cost the pelvis position is free and absorbs the offset, so the
//! candidate must be reported "not testable with this run's cost" (never scored 0 as if
//! absent), with the hint that makes it testable; the report (`summary.json`,
//! `diagnose.md`, `report.html`) shows for every candidate its testability, in-sample
//! statistic (with the variance inflation of correlated residuals), held-out figures and
//! verdict. On the real bundled trial, the MTG damping is confirmed on the other leg's
//! half cycle.

use footfall::runfolder::RunFolder;
use footfall::workflows::diagnose::DiagnoseRequest;
use footfall::workflows::track::{track, TrackRequest};
use footfall::workflows::Quiet;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read_json(p: &Path) -> Value {
    serde_json::from_str(
        &std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())),
    )
    .unwrap()
}

/// Track the hidden CoP-offset trial with the seed's cost (pelvis position free), from
/// its kept solution (tools/make-hidden-effect-baselines; `track` re-evaluates it and
/// iterates on only if it is not a KKT point of the current problem), into
/// `dir/cop_offset`.
fn seed_run(dir: &Path) -> PathBuf {
    let trial = root().join("tests/data/hidden/cop_offset");
    let out = dir.join("cop_offset");
    let mut req = TrackRequest::new("ellipse");
    req.check_points = false;
    req.run.data = Some(trial.join("synthetic.csv"));
    req.init = Some(trial.join("tracked_seed"));
    req.run.kinematics_cutoff = Some(10.0);
    let t = std::time::Instant::now();
    let run = track(&req, RunFolder::create(&out, false).unwrap(), &Quiet).unwrap();
    eprintln!(
        "track: {:.1} s, {} iterations, J {:.6}",
        t.elapsed().as_secs_f64(),
        run.result.history.len().saturating_sub(1),
        run.result.objective
    );
    assert!(run.converged, "{}", run.result.status);
    out
}

/// A diagnosis of `run` by `candidates`, with no verifying re-fit or held-out
/// validation: each test switches on what it checks.
fn request(run: &Path, candidates: &[&str]) -> DiagnoseRequest {
    DiagnoseRequest {
        verify: 0,
        candidates: candidates.iter().map(|c| c.to_string()).collect(),
        held_out: false,
        ..DiagnoseRequest::new(run.to_path_buf())
    }
}

/// Run `req` and read its `summary.json`.
fn diagnose_with(req: &DiagnoseRequest) -> Value {
    let t = std::time::Instant::now();
    footfall::workflows::diagnose::run(req, &Quiet).unwrap();
    eprintln!("diagnose: {:.1} s", t.elapsed().as_secs_f64());
    read_json(&PathBuf::from(format!(
        "{}-diagnose/summary.json",
        req.run.display()
    )))
}

/// `run` diagnosed by `candidates` with held-out validation, its solves (the held-out
/// track) started from the kept solutions in
/// tests/data/hidden/`starts` (written by tools/make-diagnosis-starts; each solve
/// re-evaluates its start and iterates on only if it is not a KKT point of the current
/// problem).
fn diagnose(run: &Path, candidates: &[&str], starts: &str) -> Value {
    let kept = root().join("tests/data/hidden").join(starts);
    diagnose_with(&DiagnoseRequest {
        held_out: true,
        starts: if kept.is_dir() {
            vec![kept]
        } else {
            Vec::new()
        },
        ..request(run, candidates)
    })
}

/// One line per candidate, for the record.
fn print_ranking(d: &Value) {
    for t in d["ranking"].as_array().unwrap() {
        eprintln!(
            "  {:<28} testable {:<5} statistic {:>8.2} (independent {:>8.2}, φ {:.2}) values {} sd {} held-out {} → {}",
            t["label"].as_str().unwrap(),
            t["testable"],
            t["statistic"].as_f64().unwrap(),
            t["statistic_independent"].as_f64().unwrap(),
            t["inflation"].as_f64().unwrap(),
            t["step_values"],
            t["identifiability"]["sd"],
            t["held_out"]
                .as_object()
                .map_or("—".into(), |h| format!("{:.4e} vs {:.4e}", h["change"].as_f64().unwrap(), h["band"].as_f64().unwrap())),
            t["verdict"].as_str().unwrap()
        );
    }
}

fn entry<'a>(d: &'a Value, kind: &str) -> &'a Value {
    d["ranking"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["effect"]["type"] == kind)
        .unwrap_or_else(|| panic!("{kind} not in the ranking"))
}

/// Every candidate carries testability, the in-sample statistic with its inflation and
/// threshold, a verdict, and held-out figures exactly when it was significant.
fn check_every_candidate(d: &Value) {
    let ranking = d["ranking"].as_array().unwrap();
    assert!(!ranking.is_empty());
    for t in ranking {
        let label = &t["label"];
        let testable = t["testable"].as_bool().unwrap();
        let stat = t["statistic"].as_f64().unwrap();
        let raw = t["statistic_independent"].as_f64().unwrap();
        let phi = t["inflation"].as_f64().unwrap();
        assert!(
            phi >= 1.0 && (stat * phi - raw).abs() <= 1e-9 * raw.max(1.0),
            "{label}"
        );
        assert!(t["threshold"].as_f64().unwrap() > 0.0);
        let id = &t["identifiability"];
        assert_eq!(id["testable"].as_bool(), Some(testable), "{label}");
        let verdict = t["verdict"].as_str().unwrap();
        let significant = t["significant"].as_bool().unwrap();
        assert!(
            !significant || testable,
            "{label}: untestable yet significant"
        );
        assert_eq!(
            t["held_out"].is_object(),
            significant,
            "{label}: held-out figures"
        );
        if let Some(h) = t["held_out"].as_object() {
            for k in ["change", "band", "objective", "beyond_noise", "stride"] {
                assert!(h.contains_key(k), "{label}: held_out.{k}");
            }
            assert_eq!(t["found"], h["beyond_noise"], "{label}");
        }
        let want = if !testable {
            "not testable with this run's cost"
        } else if !significant {
            "not significant"
        } else if t["found"] == true {
            "found"
        } else if t["held_out"]["reading"]["powered"] == false {
            "not validatable on the held-out half cycle"
        } else {
            "not confirmed on the held-out half cycle"
        };
        assert_eq!(verdict, want, "{label}");
    }
}

#[test]
fn a_cop_offset_is_untestable_under_the_seed_cost_and_says_what_makes_it_testable() {
    let dir = tempfile::tempdir().unwrap();
    let run = seed_run(dir.path());
    let d = diagnose(
        &run,
        &[
            "cop_offset",
            "force_plate_time_offset",
            "heel_pad_compliance",
        ],
        "cop_offset/starts_seed",
    );
    print_ranking(&d);
    check_every_candidate(&d);
    // the ellipse has no heel circle for a pad: named with the reason, the rest scored
    let pad: Vec<&str> = d["skipped"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|s| s.as_str())
        .filter(|s| s.starts_with("heel-pad compliance:"))
        .collect();
    assert!(
        pad.len() == 1 && pad[0].contains("no primitive 'heel'"),
        "{}",
        d["skipped"]
    );
    let cop = entry(&d, "cop_offset");
    assert_eq!(cop["testable"], false, "{cop:#}");
    assert_eq!(cop["significant"], false);
    assert_eq!(cop["found"], false);
    assert!(
        cop["hint"]
            .as_str()
            .unwrap()
            .contains("--track-pelvis-position"),
        "{}",
        cop["hint"]
    );
    // its sd, where there is one, is far beyond a quarter of the bound span
    let id = &cop["identifiability"];
    if let Some(sd) = id["sd"][0].as_f64() {
        assert!(sd > 0.25 * id["span"][0].as_f64().unwrap(), "{id:#}");
    }
    assert!(d["untestable"].as_u64().unwrap() >= 1);
    assert!(d["verdict"].as_str().unwrap().contains("Not testable"));
    // the channels' variance inflation
    let channels = d["variance_inflation"]["channels"].as_array().unwrap();
    assert_eq!(channels.len(), 7);
    for c in channels {
        assert!(c["inflation"].as_f64().is_none_or(|p| p >= 1.0), "{c}");
    }
    // the human report shows the same, and no 0.0 stands for an untestable candidate
    let out = PathBuf::from(format!("{}-diagnose", run.display()));
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    for s in [
        "testable",
        "held-out change",
        "not testable with this run&#39;s cost",
        "n/a",
        "φ",
    ] {
        assert!(
            html.contains(s) || html.contains(&s.replace("&#39;", "'")),
            "report.html lacks {s}"
        );
    }
    let md = std::fs::read_to_string(out.join("diagnose.md")).unwrap();
    let cop_row = md
        .lines()
        .find(|l| l.contains("| CoP offset"))
        .expect("CoP offset row");
    assert!(
        cop_row.contains("| NO ") && cop_row.contains("n/a"),
        "{cop_row}"
    );
}

/// Swapping the legs turns the bundled trial's half cycles from a right heel strike to
/// the next left one (0.624–1.252 and 1.858–2.467 s) into half cycles the phase graph
/// tracks (left heel strike to right), and swapping twice gives the trial back.
#[test]
fn swapping_the_legs_gives_the_other_legs_half_cycles() {
    use footfall::data::{detect_events, GaitData, DEFAULT_EVENT_FRACTION};
    use footfall::problems::track::half_cycles;
    let data = GaitData::bundled(&root()).unwrap();
    let ev = detect_events(&data, DEFAULT_EVENT_FRACTION).unwrap();
    let mut swapped = data.clone();
    swapped.swap_sides();
    let sev = detect_events(&swapped, DEFAULT_EVENT_FRACTION).unwrap();
    assert_eq!(sev.heel_strike[0], ev.heel_strike[1]);
    assert_eq!(sev.heel_strike[1], ev.heel_strike[0]);
    // the other leg's half cycles: right heel strike to the next left one
    let other: Vec<(f64, f64)> = ev.heel_strike[0]
        .iter()
        .filter_map(|&t0| {
            ev.heel_strike[1]
                .iter()
                .find(|&&t| t > t0)
                .map(|&t1| (t0, t1))
        })
        .collect();
    assert_eq!(half_cycles(&sev), other);
    assert_eq!(other.len(), 2, "{other:?}");
    assert_eq!(half_cycles(&ev).len(), 1);
    assert_eq!(swapped.q[3], data.q[6], "hip_r holds the left hip");
    assert_eq!(swapped.feet[0].fy, data.feet[1].fy);
    swapped.swap_sides();
    assert_eq!(swapped.q, data.q);
    assert_eq!(swapped.feet[0].cop_x.len(), data.feet[0].cop_x.len());
    for (a, b) in swapped.feet[1].cop_x.iter().zip(&data.feet[1].cop_x) {
        assert!(a == b || (a.is_nan() && b.is_nan()));
    }
}

/// The held-out validation `h` was made on the half cycle spanning `window` (s, to 20 ms;
/// `what` names it) and lowered its cost beyond the band.
fn confirmed_on(h: &Value, window: (f64, f64), what: &str) {
    let got = (
        h["window"][0].as_f64().unwrap(),
        h["window"][1].as_f64().unwrap(),
    );
    assert!(
        (got.0 - window.0).abs() < 0.02 && (got.1 - window.1).abs() < 0.02,
        "{what}: {got:?}"
    );
    assert!(
        h["change"].as_f64().unwrap() > h["band"].as_f64().unwrap(),
        "{h}"
    );
}

/// Held-out validation on the real bundled trial. Its kinematics hold one half cycle
/// from a left heel strike to a right one, which the run tracks, and the other leg's two
/// (mirrored), which held-out validation may use. Diagnosed by default (every candidate
/// of the catalog), the MTG damping ranks first: it is significant in-sample beyond what
/// it lowers on the model's own trial at the noise this trial shows (the model null: a free damping lowers
/// what the effort regularisation charges on any trial), and its fitted values, applied
/// to the other leg's half cycle before the run's (0.624–1.252 s), whose data the fit
/// never saw, lower that half cycle's cost beyond its band and that model null. Its
/// direction (less damping than the model's) is found; its value is reported as no
/// reading, since on the model's own trial a free damping runs to its bound too.
#[test]
fn the_real_trials_mtg_damping_is_confirmed_on_the_other_legs_half_cycle() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("untouched");
    let t = std::time::Instant::now();
    // from the kept solution of the bundled trial (contact constraints at the nodes only,
    // as it was made): the track re-evaluates it instead of iterating from the data
    let mut req = TrackRequest::new("ellipse");
    req.check_points = false;
    req.init = Some(root().join("tests/data/hidden/base"));
    let tracked = track(&req, RunFolder::create(&run, false).unwrap(), &Quiet).unwrap();
    eprintln!(
        "track: {:.1} s, J {:.6}",
        t.elapsed().as_secs_f64(),
        tracked.result.objective
    );
    assert!(tracked.converged, "{}", tracked.result.status);
    let d = diagnose(&run, &[], "base_starts");
    print_ranking(&d);
    let t = &d["ranking"][0];
    assert_eq!(t["effect"]["type"], "mtg_damping");
    assert_eq!(t["testable"], true);
    assert_eq!(t["significant"], true, "statistic {}", t["statistic"]);
    let h = &t["held_out"];
    assert_eq!(h["mirrored"], true, "{h}");
    confirmed_on(
        h,
        (0.624, 1.252),
        "the other leg's half cycle before the run's",
    );
    let verdict = t["verdict"].as_str().unwrap();
    assert!(verdict.starts_with("found"), "{verdict}");
    // its value is the cost's lean: on the model's own trial a free damping runs to its
    // bound as well
    assert!(verdict.contains("its value is not a reading"), "{verdict}");
    let model_null = t["model_null"]
        .as_f64()
        .expect("measured on the model's own trial");
    assert!(model_null > 0.0, "{t}");
    assert!(
        t["threshold"].as_f64().unwrap() > footfall::problems::distributions::chi2_999(1),
        "the threshold is the noncentral point: {t}"
    );
    assert!(
        t["step_values"][0].as_f64().unwrap() < 0.0,
        "less damping than the model's, as the effort regularisation prefers: {}",
        t["step_values"]
    );
}

/// Held-out validation on another recording of the same subject (`--held-out-data`). The
/// OpenCap subject's first walk holds one half cycle from a left heel strike to a right
/// one and none of the other leg, so it has no held-out half cycle of its own; its
/// second walk is another recording of the same subject. Diagnosed by default, the MTG
/// damping ranks first on the first walk, significant beyond what it lowers on the
/// model's own trial; applied with its fitted value to the second walk's first half
/// cycle, which the fit never saw, it lowers that cost beyond its band.
#[test]
fn a_candidate_is_validated_on_another_recording_of_the_same_subject() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("walk1");
    let mut req = TrackRequest::new("ellipse");
    req.run.data = Some(root().join("data/opencap_s4_walking1_sagittal.csv"));
    req.run.model = root().join("models/opencap_s4.json");
    let tracked = track(&req, RunFolder::create(&run, false).unwrap(), &Quiet).unwrap();
    assert!(tracked.converged, "{}", tracked.result.status);
    let walk2 = root().join("data/opencap_s4_walking2_sagittal.csv");
    let d = diagnose_with(&DiagnoseRequest {
        held_out: true,
        held_out_data: Some(walk2.clone()),
        ..request(&run, &[])
    });
    print_ranking(&d);
    let t = &d["ranking"][0];
    assert_eq!(t["effect"]["type"], "mtg_damping", "{t}");
    assert_eq!(t["significant"], true, "{t}");
    let h = &t["held_out"];
    assert_eq!(h["trial"].as_str().unwrap(), walk2.to_str().unwrap());
    confirmed_on(h, (0.533, 1.079), "the second walk's half cycle");
    assert!(t["verdict"].as_str().unwrap().starts_with("found"), "{t}");
}
