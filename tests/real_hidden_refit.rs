//! Issue 23, Done-means 1 (the re-fit half): on each hidden-effect trial made from the
//! real measurements (`tools/make-real-hidden-trials`), a track with the default settings
//! re-fitted with the true effect identifies it within 20 % or 2 sd of the truth
//! (whichever is larger) and brings every channel's mean error back near the untouched
//! trial's. The clock offsets move the contact events of their plate's threshold; the
//! CoP offset needs the pelvis position tracked (the default cost leaves it untracked,
//! and the model then shifts along the walkway instead), so its trial and the untouched
//! reference it is compared with are both tracked with `--track-pelvis-position`.
//!
//! Each trial's track starts from the untouched trial's solution (same problem, fewer
//! iterations than from the data); its re-fit from the trial's own solution.

mod common;
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

/// Track trial `name`, re-fit it with `effect` and check the identified `parameter`
/// against `truth` and each channel's mean error against the untouched trial's: within
/// `factor` of it plus `slack` of the channel's untouched error before the re-fit moved
/// it (the channels a hidden effect spoils must come back; those it does not touch must
/// not get worse).
fn refit_finds(name: &str, effect: &str, parameter: &str, truth: f64, pelvis: bool) {
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
    let sd = p.sd.unwrap_or(f64::NAN);
    let allowed = (0.2 * truth.abs()).max(2.0 * sd);
    eprintln!(
        "{name}: {parameter} = {:.5} ± {sd:.2e} (truth {truth}; {:.1} % off, allowed ±{allowed:.2e})",
        p.value,
        100.0 * (p.value - truth).abs() / truth.abs()
    );
    assert!(
        (p.value - truth).abs() <= allowed,
        "{name}: {parameter} = {} ± {sd}, truth {truth}",
        p.value
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
fn right_plate_clock_late_25_ms() {
    refit_finds(
        "real_clock_r+25ms",
        "force_plate_time_offset:side=right",
        "force_plate_time_offset.right.offset",
        0.025,
        false,
    );
}

#[test]
fn left_plate_clock_early_20_ms() {
    refit_finds(
        "real_clock_l-20ms",
        "force_plate_time_offset:side=left",
        "force_plate_time_offset.left.offset",
        -0.020,
        false,
    );
}

#[test]
fn left_plate_gain_6_percent() {
    refit_finds(
        "real_gain_l+6pct",
        "force_plate_gain:side=left",
        "force_plate_gain.left.error",
        0.06,
        false,
    );
}

#[test]
fn every_force_5_percent_high_as_a_body_mass_error() {
    refit_finds(
        "real_mass+5pct",
        "body_mass_error",
        "body_mass_error.relative",
        0.05,
        false,
    );
}

#[test]
fn right_cop_25_mm_forward_with_the_pelvis_position_tracked() {
    refit_finds(
        "real_cop_r+25mm",
        "cop_offset:side=right",
        "cop_offset.right.offset",
        0.025,
        true,
    );
}
