//! Issue 23, Done-means 1 (the re-fit half): on each hidden-effect trial made from the
//! real measurements (`tools/make-real-hidden-trials`), a track with the default settings
//! re-fitted with the true effect identifies it within 20 % or 2 sd of the truth
//! (whichever is larger) and brings every channel's mean error back near the untouched
//! trial's. The clock offsets move the contact events of their plate's threshold; the
//! CoP offset needs the pelvis position tracked (the default cost leaves it untracked,
//! and the model then shifts along the walkway instead), so its trial and the untouched
//! reference it is compared with are both tracked with `--track-pelvis-position`.
//!
//! A clock offset is judged relative to the untouched trial: re-fitted with the same
//! effect, the untouched measurement itself reads a few milliseconds (its force-threshold
//! events against a rigid-contact model's contact changes), and the hidden offset is what
//! the edit added to that.
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


#[test]
fn tmp_untouched_cop_value() {
    let (v, sd) = untouched_value("cop_offset:side=right", "cop_offset.right.offset", true);
    eprintln!("UNTOUCHED cop_offset.right.offset = {v:.5} ± {sd:.2e}");
}
