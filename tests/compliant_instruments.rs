//! The hidden-effect trials made from the real measurements (`tools/make-real-hidden-trials`)
//! diagnosed against the untouched trial with the compliant foot, the volumetric ellipse,
//! instead of the rigid one.
//!
//! The rigid ellipse reads the untouched trial's right plate +25 ms late and its left
//! plate −38 ms early: its heel strike and push-off come at fixed contact events, so the
//! push-off plate's forces look late and the heel-strike plate's early. The compliant foot's force grows and fades with the foot's
//! sinking and has no such event; on the untouched trial it reads both clocks within a
//! few milliseconds of zero and finds nothing. Each trial is tracked as
//! `tools/make-compliant-real-tracks` tracked it (the seed's MTG damping, the
//! identification cost, CVODES at 1e-10), starting from the solution kept in
//! tests/data/real_compliant/<trial>; then `diagnose --verify 0 --no-held-out
//! --reference <the untouched trial's diagnosis>`.
//!
//! The kept solutions have KKT residuals of 1.2e-4 to 1.3e-3 and the tracks here stop at
//! 2e-3 (from the kept point the same track converges, 26 iterations to 1e-5). What the
//! score tests
//! assume, the Gauss–Newton decrease left at the solution, is below 1e-8 there (J is
//! 0.34–0.52).
//!
//! Each test takes several minutes (a diagnosis scores 15 candidates, each a truncated
//! re-fit of the compliant foot): beyond the CI's time, so they are ignored; run them
//! with `cargo test --test suite -- --ignored compliant_instruments::`.

use crate::common;
use common::*;
use footfall::runfolder::RunFolder;
use footfall::workflows::diagnose::DiagnoseRequest;
use footfall::workflows::track::track;
use footfall::workflows::Quiet;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Where every run of this file goes (kept for the process's lifetime).
fn scratch() -> &'static Path {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| tempfile::tempdir().unwrap()).path()
}

/// Track `trial` (`untouched`: the bundled trial) with the compliant foot from its kept
/// solution, into the scratch folder.
fn tracked(trial: &str) -> PathBuf {
    let out = scratch().join(trial);
    let mut req = compliant_identification_request();
    req.run.integrator_tol = 1e-10;
    if trial != "untouched" {
        req.run.data = Some(
            root()
                .join("tests/data/real_hidden")
                .join(trial)
                .join("trial.csv"),
        );
    }
    req.init = Some(root().join("tests/data/real_compliant").join(trial));
    req.sqp.tol_kkt = 2e-3;
    let t = std::time::Instant::now();
    let r = track(&req, RunFolder::create(&out, false).unwrap(), &Quiet)
        .unwrap_or_else(|e| panic!("track {trial}: {e:#}"));
    eprintln!(
        "{trial}: {} after {} iterations, J = {:.6}, KKT {:.1e} ({:.0} s)",
        r.result.status,
        r.result.history.len().saturating_sub(1),
        r.result.objective,
        r.result.kkt,
        t.elapsed().as_secs_f64()
    );
    assert!(r.converged, "{trial}: {}", r.result.status);
    out
}

/// Where `diagnose` writes the diagnosis of `run`.
fn diagnosis_folder(run: &Path) -> PathBuf {
    PathBuf::from(format!("{}-diagnose", run.display()))
}

/// `run` diagnosed with the catalog, no re-fit and no held-out half cycle, against
/// `reference` (a diagnosis folder) when given; its `summary.json`.
fn diagnosed(run: &Path, reference: Option<PathBuf>) -> Value {
    let req = DiagnoseRequest {
        verify: 0,
        held_out: false,
        reference,
        ..DiagnoseRequest::new(run.to_path_buf())
    };
    let t = std::time::Instant::now();
    footfall::workflows::diagnose::run(&req, &Quiet).unwrap();
    let folder = diagnosis_folder(run);
    eprintln!(
        "diagnose {}: {:.0} s",
        run.display(),
        t.elapsed().as_secs_f64()
    );
    eprintln!(
        "{}",
        std::fs::read_to_string(folder.join("diagnose.md")).unwrap()
    );
    json(&folder.join("summary.json"))
}

/// The untouched trial's diagnosis folder, made once per process.
fn reference() -> PathBuf {
    static REF: OnceLock<PathBuf> = OnceLock::new();
    REF.get_or_init(|| {
        let run = tracked("untouched");
        diagnosed(&run, None);
        diagnosis_folder(&run)
    })
    .clone()
}

/// The ranking entry of the candidate labelled `label`.
fn ranked<'a>(d: &'a Value, label: &str) -> &'a Value {
    d["ranking"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["label"] == label)
        .unwrap_or_else(|| panic!("{label} not in the ranking"))
}

/// Diagnose `trial` against the untouched trial and check that `parameter` (of the
/// candidate `label`) has the largest |difference|/sd of all and reads `truth` within
/// 20 % or 2 sd of the difference, whichever is larger; with `significant`, that its
/// difference also passes the comparison's threshold.
fn first_against_the_untouched_trial(
    trial: &str,
    label: &str,
    parameter: &str,
    truth: f64,
    significant: bool,
) {
    let reference = reference();
    let d = diagnosed(&tracked(trial), Some(reference));
    let c = &d["reference"];
    let first = &c["differences"][0];
    let (diff, sd) = (
        first["difference"].as_f64().unwrap(),
        first["sd"].as_f64().unwrap(),
    );
    eprintln!(
        "{trial}: first against the untouched trial {} {} {diff:+.4e} ± {sd:.2e} (z {:+.2}, threshold z² {:.1}), truth {truth:+e}",
        first["label"], first["parameter"], first["z"].as_f64().unwrap(), c["threshold"].as_f64().unwrap()
    );
    assert_eq!(first["label"], label, "{c}");
    assert_eq!(first["parameter"], parameter, "{c}");
    assert!(
        (diff - truth).abs() <= (0.2 * truth.abs()).max(2.0 * sd),
        "{parameter}: {diff} ± {sd} against the truth {truth}"
    );
    assert_eq!(first["significant"], significant, "{first}");
    // the true effect is testable in-sample too (its reading was compared, not skipped)
    let own = ranked(&d, label);
    assert_eq!(own["testable"], true, "{own}");
}

/// On the untouched trial the compliant foot reads each plate's clock within 10 ms of
/// zero (the rigid ellipse under the same model and cost: right +22.7 ms, left −31 ms)
/// and finds nothing. Measured: right −2.1 ± 2.8 ms, left
/// +5.7 ± 3.4 ms, the largest statistic the ground slope's, 6.3 against 10.8.
#[test]
#[ignore = "slow (a compliant-foot diagnosis, about 4 minutes); run with cargo test --test suite -- --ignored compliant_instruments::"]
fn the_untouched_trial_reads_both_clocks_near_zero_and_finds_nothing() {
    let d = json(&reference().join("summary.json"));
    assert_eq!(d["significant"], 0, "{}", d["verdict"]);
    for side in ["right", "left"] {
        let t = ranked(&d, &format!("force-plate time offset ({side})"));
        let offset = t["step_values"][0].as_f64().unwrap();
        assert!(offset.abs() < 0.010, "{side} clock {offset} s");
    }
}

/// The right plate's clock 25 ms late: first against the untouched trial and significant.
/// Measured: +24.7 ± 4.6 ms, z +5.3 against 3.9; in-sample +22.7 ± 3.7 ms,
/// third after two ghosts of the edit (trunk mass, ground slope) that the untouched
/// trial shares (same within noise against it).
#[test]
#[ignore = "slow (two compliant-foot diagnoses, about 8 minutes); run with cargo test --test suite -- --ignored compliant_instruments::"]
fn the_right_plates_clock_25_ms_late_is_read_first_against_the_untouched_trial() {
    first_against_the_untouched_trial(
        "real_clock_r+25ms",
        "force-plate time offset (right)",
        "force_plate_time_offset.right.offset",
        0.025,
        true,
    );
}

/// Every force 5 % high: the body-mass error first against the untouched trial and
/// significant. Measured: +4.95 ± 1.04 %, z +4.8.
#[test]
#[ignore = "slow (two compliant-foot diagnoses, about 8 minutes); run with cargo test --test suite -- --ignored compliant_instruments::"]
fn every_force_5_percent_high_is_read_first_as_a_body_mass_error() {
    first_against_the_untouched_trial(
        "real_mass+5pct",
        "body-mass error",
        "body_mass_error.relative",
        0.05,
        true,
    );
}

/// The right foot's CoP 25 mm forward: first against the untouched trial, within 2 sd,
/// but not significant. Measured: +27.0 ± 17.9 mm, z +1.5.
#[test]
#[ignore = "slow (two compliant-foot diagnoses, about 8 minutes); run with cargo test --test suite -- --ignored compliant_instruments::"]
fn the_right_cop_25_mm_forward_is_read_first_but_within_noise() {
    first_against_the_untouched_trial(
        "real_cop_r+25mm",
        "CoP offset (right)",
        "cop_offset.right.offset",
        0.025,
        false,
    );
}

/// The left plate 6 % high. Measured: first in-sample (+5.8 ± 1.0 %), but
/// against the untouched trial the body-mass error differs more (+5.2 %, z 5.0) than the
/// left gain (+6.0 ± 1.6 %, z 3.7, third): on this half cycle one plate's gain and the
/// whole body's mass scale much the same forces.
#[test]
#[ignore = "not found yet: against the untouched trial the body-mass error ranks first (z 5.0), the left gain third (+6.0 ± 1.6 %, z 3.7)"]
fn the_left_plate_6_percent_high_is_read_first_against_the_untouched_trial() {
    first_against_the_untouched_trial(
        "real_gain_l+6pct",
        "force-plate gain (left)",
        "force_plate_gain.left.error",
        0.06,
        false,
    );
}

/// The left plate's clock 20 ms early. Measured: the left clock reads
/// −9.7 ± 4.7 ms against the untouched trial (z −2.1, sixth); the right clock's +18.9 ms
/// (z 4.2) ranks first. The edit moves the half cycle's start (the left heel strike) 20
/// ms earlier, and the truncated re-fit from zero does not reach the left clock.
#[test]
#[ignore = "not found yet: the right clock ranks first (+18.9 ms, z 4.2), the left clock reads -9.7 +- 4.7 ms (truth -20 ms)"]
fn the_left_plates_clock_20_ms_early_is_read_first_against_the_untouched_trial() {
    first_against_the_untouched_trial(
        "real_clock_l-20ms",
        "force-plate time offset (left)",
        "force_plate_time_offset.left.offset",
        -0.020,
        false,
    );
}
