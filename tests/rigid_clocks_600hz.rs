//! Issue 23, Done-means 1, for the left plate's clock with the rigid ellipse: the real
//! trial whose left plate runs 20 ms early, written at the plates' own 600 Hz
//! (`tests/data/real_hidden_600hz`, `tools/make-real-hidden-trials`), read against the
//! untouched trial by the two trials' clock profiles.
//!
//! At the identification cost (sample targets, the pelvis position tracked) the left
//! clock's profile on the edited trial is the untouched trial's moved by the edit's 20 ms
//! (stop 71, `docs/instruments.md`). On the edited trial a point of the profile lies
//! below the run and the re-fit held at its parabola's vertex is the candidate's test;
//! on the untouched trial none does, so its test is the score test's truncated re-fit,
//! another estimator. The comparison takes the two profiles' own readings, each the
//! vertex of its parabola with the run's cost among its points (stop 72).
//!
//! Each trial is tracked from its solution kept in `tests/data/real_hidden_600hz_kept`
//! (the rigid ellipse, the bundled model, `track --sample-targets
//! --track-pelvis-position`; the edited trial from the untouched one's solution), which
//! re-evaluates and stops there, and diagnosed with the left clock alone,
//! `--profile-clocks` (±20 and ±40 ms), no re-fit and no held-out half cycle. About a
//! minute a diagnosis on the faster two-core machines: ignored in the CI, whose time is
//! spent; run with `cargo test --test suite -- --ignored rigid_clocks_600hz::`.

use crate::common;
use common::*;
use footfall::runfolder::RunFolder;
use footfall::workflows::diagnose::DiagnoseRequest;
use footfall::workflows::track::{track, TrackRequest};
use footfall::workflows::Quiet;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Track `trial` (of tests/data/real_hidden_600hz) with the rigid ellipse at the
/// identification cost from its kept solution, into `dir`.
fn tracked(dir: &Path, trial: &str) -> PathBuf {
    let out = dir.join(trial);
    let mut req = TrackRequest::new("ellipse");
    req.run.sample_targets = true;
    req.run.track_pelvis_position = true;
    req.run.data = Some(
        root()
            .join("tests/data/real_hidden_600hz")
            .join(trial)
            .join("trial.csv"),
    );
    req.init = Some(root().join("tests/data/real_hidden_600hz_kept").join(trial));
    let r = track(&req, RunFolder::create(&out, false).unwrap(), &Quiet)
        .unwrap_or_else(|e| panic!("track {trial}: {e:#}"));
    eprintln!(
        "{trial}: {} after {} iterations, J = {:.6}",
        r.result.status,
        r.result.history.len().saturating_sub(1),
        r.result.objective
    );
    assert!(r.converged, "{trial}: {}", r.result.status);
    out
}

/// `run` diagnosed with the left clock alone and its profile, against `reference` when
/// given; the left clock's ranking entry and the whole summary.
fn left_clock(run: &Path, reference: Option<PathBuf>) -> (Value, Value) {
    let req = DiagnoseRequest {
        verify: 0,
        held_out: false,
        candidates: vec!["force_plate_time_offset:side=left".into()],
        profile_clocks: footfall::workflows::diagnose::profile::CLOCK_PROFILE.to_vec(),
        reference,
        ..DiagnoseRequest::new(run.to_path_buf())
    };
    let t = std::time::Instant::now();
    footfall::workflows::diagnose::run(&req, &Quiet).unwrap();
    let folder = PathBuf::from(format!("{}-diagnose", run.display()));
    eprintln!(
        "diagnose {}: {:.0} s\n{}",
        run.display(),
        t.elapsed().as_secs_f64(),
        std::fs::read_to_string(folder.join("diagnose.md")).unwrap()
    );
    let s = json(&folder.join("summary.json"));
    (s["ranking"][0].clone(), s)
}

/// The left clock 20 ms early, read against the untouched trial by the profiles'
/// vertices: within 20 % or 2 sd of −20 ms. Measured (stop 72, the full catalog):
/// the untouched trial's vertex −9.8 ± 7.1 ms (its score test −7.0 ± 5.0 ms, not
/// significant), the edited trial's re-fit held at −29.4 ms.
#[test]
#[ignore = "slow (two rigid diagnoses with a clock profile at 600 Hz, about 2 minutes); run with cargo test --test suite -- --ignored rigid_clocks_600hz::"]
fn the_left_clock_20_ms_early_is_read_against_the_untouched_trial_by_the_profiles() {
    let dir = tempfile::tempdir().unwrap();
    let untouched = tracked(dir.path(), "untouched");
    let (theirs, _) = left_clock(&untouched, None);
    let p = &theirs["profile"];
    // no point below the run: the score test stands, and the profile keeps its vertex
    assert_eq!(p["chosen"], false, "{theirs}");
    let v = p["vertex"]["offset"]
        .as_f64()
        .expect("the profile's vertex");
    assert!(p["vertex"]["sd"].as_f64().is_some(), "{p}");
    assert!(v.abs() < 0.02, "the untouched trial's vertex {v}");

    let edited = tracked(dir.path(), "real_clock_l-20ms");
    let reference = PathBuf::from(format!("{}-diagnose", untouched.display()));
    let (ours, s) = left_clock(&edited, Some(reference));
    assert_eq!(ours["profile"]["chosen"], true, "{ours}");
    let c = &s["reference"];
    let d = &c["differences"][0];
    eprintln!("{}", serde_json::to_string_pretty(c).unwrap());
    assert_eq!(d["label"], "force-plate time offset (left)", "{c}");
    assert_eq!(d["by_profiles"], true, "{d}");
    let (diff, sd) = (d["difference"].as_f64().unwrap(), d["sd"].as_f64().unwrap());
    let truth = -0.020;
    assert!(
        (diff - truth).abs() <= (0.2 * truth.abs()).max(2.0 * sd),
        "{diff} ± {sd} s against {truth} s"
    );
    // the reference's reading is its vertex, not its score test's
    assert_eq!(d["reference"].as_f64(), Some(v), "{d}");
}
