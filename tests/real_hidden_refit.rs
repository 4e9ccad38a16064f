//! The re-fits of the hidden-effect trials: on each trial made from the
//! real measurements (`tools/make-real-hidden-trials`), a track with the default settings
//! re-fitted with the true effect identifies it within 20 % or 2 sd of the truth
//! (whichever is larger) and brings every channel's mean error back near the untouched
//! trial's. The clock offsets move the contact events of their plate's threshold; the
//! CoP offset needs the pelvis position tracked (the default cost leaves it untracked,
//! and the model then shifts along the walkway instead), so its trial and the untouched
//! reference it is compared with are both tracked with `--track-pelvis-position`.
//!
//! A clock or CoP offset is judged relative to the untouched trial: re-fitted with the
//! same effect, the untouched measurement itself reads a few milliseconds (its
//! force-threshold events against a rigid-contact model's contact changes) or
//! millimetres (the ellipse's CoP against the real foot's), and the hidden offset is what
//! the edit added to that. The gain and the body mass are judged as identified.
//!
//! Each trial's track starts from the untouched trial's solution (same problem, fewer
//! iterations than from the data); its re-fit from the trial's own solution.

use crate::common;
use common::*;
use footfall::model::effects::EffectSpec;
use footfall::runfolder::RunFolder;
use footfall::workflows::track::{track, TrackRequest};
use footfall::workflows::Quiet;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Where every run of this file goes (kept for the test's lifetime).
fn scratch() -> &'static Path {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| tempfile::tempdir().unwrap()).path()
}

/// Track `data` (None: the bundled trial) with `effects` from `init`, into `name`.
fn run(
    name: &str,
    data: Option<PathBuf>,
    effects: &[&str],
    init: Option<&Path>,
    pelvis: bool,
) -> (PathBuf, footfall::workflows::track::TrackedRun) {
    let out = scratch().join(name);
    let mut req = TrackRequest::new("ellipse");
    req.run.data = data;
    req.run.track_pelvis_position = pelvis;
    req.effects = effects
        .iter()
        .map(|e| EffectSpec::parse_cli(e).unwrap())
        .collect();
    req.init = init.map(Path::to_path_buf);
    let t = std::time::Instant::now();
    let folder = RunFolder::create(&out, false).unwrap();
    let r = track(&req, folder, &Quiet).unwrap_or_else(|e| panic!("track {name}: {e:#}"));
    eprintln!(
        "{name}: {} after {} iterations, J = {:.4} ({:.0} s)",
        r.result.status,
        r.result.history.len().saturating_sub(1),
        r.result.objective,
        t.elapsed().as_secs_f64()
    );
    assert!(r.converged, "{name}: {}", r.result.status);
    (out, r)
}

/// The untouched bundled trial, tracked once per process (with or without the pelvis
/// position).
fn untouched(pelvis: bool) -> &'static Path {
    static PLAIN: OnceLock<PathBuf> = OnceLock::new();
    static PELVIS: OnceLock<PathBuf> = OnceLock::new();
    let (cell, name) = if pelvis {
        (&PELVIS, "untouched_pelvis")
    } else {
        (&PLAIN, "untouched")
    };
    cell.get_or_init(|| run(name, None, &[], None, pelvis).0)
}

fn channel_means(run: &Path) -> Vec<(String, f64)> {
    json(&run.join("summary.json"))["errors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            (
                c["channel"].as_str().unwrap().to_string(),
                c["stats"]["mean"].as_f64().unwrap(),
            )
        })
        .collect()
}

/// The value and standard deviation of `parameter` when the untouched trial is re-fitted
/// with `effect`: what the model reads in the real measurement before anything was
/// hidden in it (the threshold events of a rigid-contact model, for instance, lag or
/// lead its contact changes a little).
fn untouched_value(effect: &str, parameter: &str, pelvis: bool) -> (f64, f64) {
    let (_, r) = run(
        &format!("untouched_{}", effect.replace([':', '='], "_")),
        None,
        &[effect],
        Some(untouched(pelvis)),
        pelvis,
    );
    let p = r
        .record
        .parameters
        .iter()
        .find(|p| p.name == parameter)
        .unwrap();
    (p.value, p.sd.unwrap_or(0.0))
}

/// Track trial `name`, re-fit it with `effect` and check the identified `parameter`
/// against `truth` and each channel's mean error against the untouched trial's (within
/// 15 %: the channels a hidden effect spoils must come back, those it does not touch
/// must not get worse). With `relative`, the truth is compared with the value on the
/// trial less the value on the untouched trial ([`untouched_value`]), their standard
/// deviations combined.
fn refit_finds(
    name: &str,
    effect: &str,
    parameter: &str,
    truth: f64,
    pelvis: bool,
    relative: bool,
) {
    let reference = untouched(pelvis);
    let data = root()
        .join("tests/data/real_hidden")
        .join(name)
        .join("trial.csv");
    let (base, _) = run(name, Some(data.clone()), &[], Some(reference), pelvis);
    let (refit, r) = run(
        &format!("{name}_refit"),
        Some(data),
        &[effect],
        Some(&base),
        pelvis,
    );
    let p = r
        .record
        .parameters
        .iter()
        .find(|p| p.name == parameter)
        .unwrap_or_else(|| panic!("{name}: no parameter {parameter}"));
    let mut sd = p.sd.unwrap_or(f64::NAN);
    let mut value = p.value;
    if relative {
        let (v0, sd0) = untouched_value(effect, parameter, pelvis);
        eprintln!(
            "{name}: {parameter} = {:.5} ± {sd:.2e} on the trial, {v0:.5} ± {sd0:.2e} on the untouched trial",
            p.value
        );
        value -= v0;
        sd = sd.hypot(sd0);
    }
    let allowed = (0.2 * truth.abs()).max(2.0 * sd);
    eprintln!(
        "{name}: {parameter} = {value:.5} ± {sd:.2e}{} (truth {truth}; {:.1} % off, allowed ±{allowed:.2e})",
        if relative { " relative to the untouched trial" } else { "" },
        100.0 * (value - truth).abs() / truth.abs()
    );
    assert!(
        (value - truth).abs() <= allowed,
        "{name}: {parameter} = {value} ± {sd}, truth {truth}"
    );
    let (u, b, a) = (
        channel_means(reference),
        channel_means(&base),
        channel_means(&refit),
    );
    let mut bad = Vec::new();
    for (((c, eu), (_, eb)), (_, ea)) in u.iter().zip(&b).zip(&a) {
        eprintln!("  {c}: untouched {eu:.4}, tracked {eb:.4}, re-fit {ea:.4}");
        if *ea > 1.15 * eu + 0.02 * eu.max(1e-9) {
            bad.push(format!("{c} {ea:.4} vs untouched {eu:.4}"));
        }
    }
    assert!(
        bad.is_empty(),
        "{name}: after the re-fit {}",
        bad.join("; ")
    );
}

#[test]
#[ignore = "not found yet: the re-fit stops at -4.4 ± 1.4 ms (truth +25 ms), and the untouched trial's re-fit with the right clock ends in a failed line search"]
fn right_plate_clock_late_25_ms() {
    refit_finds(
        "real_clock_r+25ms",
        "force_plate_time_offset:side=right",
        "force_plate_time_offset.right.offset",
        0.025,
        false,
        true,
    );
}

#[test]
#[ignore = "slow (each test tracks the real trial 2–4 times: about 9 minutes together in the test profile), beyond the CI's time budget; run with cargo test --test suite -- --ignored real_hidden_refit::"]
fn left_plate_clock_early_20_ms() {
    refit_finds(
        "real_clock_l-20ms",
        "force_plate_time_offset:side=left",
        "force_plate_time_offset.left.offset",
        -0.020,
        false,
        true,
    );
}

#[test]
#[ignore = "slow (each test tracks the real trial 2–4 times: about 9 minutes together in the test profile), beyond the CI's time budget; run with cargo test --test suite -- --ignored real_hidden_refit::"]
fn left_plate_gain_6_percent() {
    refit_finds(
        "real_gain_l+6pct",
        "force_plate_gain:side=left",
        "force_plate_gain.left.error",
        0.06,
        false,
        false,
    );
}

#[test]
#[ignore = "slow (each test tracks the real trial 2–4 times: about 9 minutes together in the test profile), beyond the CI's time budget; run with cargo test --test suite -- --ignored real_hidden_refit::"]
fn every_force_5_percent_high_as_a_body_mass_error() {
    refit_finds(
        "real_mass+5pct",
        "body_mass_error",
        "body_mass_error.relative",
        0.05,
        false,
        false,
    );
}

#[test]
#[ignore = "not found yet: with the pelvis position tracked the re-fit reads -78.9 ± 26.4 mm (truth +25 mm)"]
fn right_cop_25_mm_forward_with_the_pelvis_position_tracked() {
    refit_finds(
        "real_cop_r+25mm",
        "cop_offset:side=right",
        "cop_offset.right.offset",
        0.025,
        true,
        true,
    );
}

/// The untouched trial re-fitted with the MTG damping free: the largest real
/// mismatch (tracking with the seed's stated damping, η = 0.4 instead of 2.0, lowers J
/// from 7.90 to 1.63). The identified η, η₀ (1 + change) with η₀ = 2.0, is printed
/// beside the seed's stated damping; the re-fit must lower J by more than half and move η
/// below 2.0.
#[test]
#[ignore = "slow (each test tracks the real trial 2–4 times: about 9 minutes together in the test profile), beyond the CI's time budget; run with cargo test --test suite -- --ignored real_hidden_refit::"]
fn the_untouched_trial_refits_a_lower_mtg_damping() {
    let reference = untouched(false);
    let before = json(&reference.join("summary.json"))["objective"]
        .as_f64()
        .unwrap();
    let (_, r) = run(
        "untouched_mtg_damping",
        None,
        &["mtg_damping"],
        Some(reference),
        false,
    );
    let p = r
        .record
        .parameters
        .iter()
        .find(|p| p.name == "mtg_damping.change")
        .unwrap();
    let eta = 2.0 * (1.0 + p.value);
    eprintln!(
        "MTG damping: change {:.4} ± {:?} → η = {eta:.3} (seed's stated damping needs η ≈ 0.4); J {before:.4} → {:.4}",
        p.value, p.sd, r.result.objective
    );
    assert!(eta < 2.0, "η = {eta}");
    assert!(
        r.result.objective < 0.5 * before,
        "J {before} → {}",
        r.result.objective
    );
}
