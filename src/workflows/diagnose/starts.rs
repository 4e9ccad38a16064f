//! Kept starting points for a diagnosis's own solves (`diagnose --start DIR`).
//!
//! A diagnosis solves whole problems: a candidate's verifying re-fit, the heel pad's test
//! by a re-fit, the held-out half cycle's plain track. Each
//! starts where the diagnosis has got to (the run's solution, a truncated re-fit's point,
//! the data of the held-out half cycle), and takes 5–25 SQP iterations from there. An
//! earlier diagnosis of the same run has already solved the same problems: its re-fit run
//! folders (`<RUN>+<effect>`) and its held-out track (`<RUN>-diagnose/held_out`) are
//! solutions of them. Given with `--start`, each starts the solve of the same problem
//! instead. A start never decides the answer: the solve re-evaluates it and iterates
//! until the KKT tolerance is met, as from any other point, so a kept solution of the
//! current code's problem converges at its first evaluation and one of an older problem
//! is iterated on.
//!
//! Which problem a kept solution solves is read from its `setup.json`: the effects added
//! to the model (with their initial values and free parameters), which half cycle, and the
//! cost's options (`KEY_FIELDS`); input paths are not compared, so give starts of the
//! same trial.

use super::super::track::TrackingProblem;
use super::super::{note, warn_note, Progress};
use super::DiagnoseRequest;
use crate::problems::diagnose::TrackingRunSetup;
use crate::problems::evaluation::GaitSolution;
use anyhow::{anyhow, bail, Context};
use std::path::{Path, PathBuf};

/// The fields of a run's `setup.json` that say which problem it solves beyond its input
/// files: two setups equal in these have the same variables and cost.
const KEY_FIELDS: [&str; 11] = [
    "effects",
    "stride",
    "mirror",
    "track_pelvis_position",
    "residual_actuators",
    "regularisation",
    "one_sided_targets",
    "sample_targets",
    "noise_weights",
    "velocity_weight",
    "kinematics_cutoff",
];

/// The problem a setup describes, as the values of [`KEY_FIELDS`].
fn key(setup: &TrackingRunSetup) -> anyhow::Result<serde_json::Value> {
    let all = serde_json::to_value(setup).context("recording a setup")?;
    Ok(serde_json::Value::Object(
        KEY_FIELDS
            .iter()
            .map(|k| {
                (
                    k.to_string(),
                    all.get(*k).cloned().unwrap_or(serde_json::Value::Null),
                )
            })
            .collect(),
    ))
}

/// Whether `dir` holds a kept solution (`setup.json` and `solution.json`).
fn holds_solution(dir: &Path) -> bool {
    dir.join("setup.json").is_file() && dir.join("solution.json").is_file()
}

/// The kept solutions the `--start` folders give: each folder that holds one, and the
/// folders one level inside it that do (a diagnosis folder's `held_out`, a folder of
/// re-fits). A folder that does not exist or gives none is an error naming it.
pub(super) fn kept_solutions(starts: &[PathBuf]) -> anyhow::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for dir in starts {
        if !dir.is_dir() {
            bail!(
                "--start {}: no such folder (give a run folder with setup.json and solution.json, e.g. an earlier re-fit <RUN>+<effect>, or a folder of them, e.g. an earlier <RUN>-diagnose)",
                dir.display()
            );
        }
        let before = out.len();
        if holds_solution(dir) {
            out.push(dir.clone());
        }
        let mut inside: Vec<PathBuf> = std::fs::read_dir(dir)
            .with_context(|| format!("--start {}: reading the folder", dir.display()))?
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.is_dir() && holds_solution(p))
            .collect();
        // in name order, so that the first match is the same on every file system
        inside.sort();
        out.extend(inside);
        if out.len() == before {
            bail!(
                "--start {}: holds no solution (neither it nor a folder inside it has setup.json and solution.json)",
                dir.display()
            );
        }
    }
    Ok(out)
}

/// The first kept solution among `args.starts` of the problem `want` (the run's setup
/// with the solve's effects added and its half cycle), with its folder.
fn find(
    args: &DiagnoseRequest,
    want: &TrackingRunSetup,
) -> anyhow::Result<Option<(PathBuf, GaitSolution)>> {
    let Some(dir) = find_folder(&args.starts, want)? else {
        return Ok(None);
    };
    let solution =
        super::super::read_solution(&dir).with_context(|| format!("--start {}", dir.display()))?;
    Ok(Some((dir, solution)))
}

/// The first folder among the kept solutions of `starts` that solves `want`: the same
/// effects, half cycle and cost; never another's.
fn find_folder(starts: &[PathBuf], want: &TrackingRunSetup) -> anyhow::Result<Option<PathBuf>> {
    if starts.is_empty() {
        return Ok(None);
    }
    let exact = key(want)?;
    for dir in kept_solutions(starts)? {
        let setup = TrackingRunSetup::read(&dir.join("setup.json"))
            .map_err(|e| anyhow!("--start {}: {e}", dir.display()))?;
        if key(&setup)? == exact {
            return Ok(Some(dir));
        }
    }
    Ok(None)
}

/// Keep `solution` of the problem `setup` in `dir` (`setup.json`, `solution.json`), so
/// that a later diagnosis of the run can start that solve from it (`--start`).
pub(super) fn keep(
    dir: &Path,
    setup: &TrackingRunSetup,
    solution: &GaitSolution,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| anyhow!("{}: {e}", dir.display()))?;
    let setup = serde_json::to_string_pretty(setup)?;
    let solution = serde_json::to_string_pretty(solution)?;
    crate::runfolder::write_atomic(dir, "setup.json", setup.as_bytes())?;
    crate::runfolder::write_atomic(dir, "solution.json", solution.as_bytes())?;
    Ok(())
}

/// Start `prob`, the problem `want`, from its kept solution among `args.starts` when there
/// is one and it fits. A kept solution that does not fit (its variables are another
/// problem's) is named in a warning and `prob` is made afresh by `rebuild`, to be started
/// where the caller says (`otherwise`, e.g. "starting from the data"). Whether `prob`
/// now starts at a kept solution.
pub(super) fn start_from_kept(
    args: &DiagnoseRequest,
    want: &TrackingRunSetup,
    prob: &mut TrackingProblem,
    rebuild: impl FnOnce() -> anyhow::Result<TrackingProblem>,
    otherwise: &str,
    progress: &dyn Progress,
) -> anyhow::Result<bool> {
    let Some((dir, kept)) = find(args, want)? else {
        return Ok(false);
    };
    match prob.start_at(&kept) {
        Ok(()) => {
            note!(
                progress,
                "  starting from the kept solution {}",
                dir.display()
            );
            Ok(true)
        }
        Err(e) => {
            warn_note!(
                progress,
                "  the kept solution {} does not fit this problem ({e:#}); {otherwise}",
                dir.display()
            );
            *prob = rebuild()?;
            Ok(false)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::effects::EffectSpec;

    fn setup(effects: &[&str], stride: Option<usize>) -> TrackingRunSetup {
        let mut s: TrackingRunSetup = serde_json::from_value(serde_json::json!({
            "model": "models/opensim_subject01.json",
            "foot": "ellipse",
            "phases": "phases/ellipse_walk.json",
            "integrator_tol": 1e-8,
            "effects": [],
            "parameters": []
        }))
        .unwrap();
        s.effects = effects
            .iter()
            .map(|e| EffectSpec::parse_cli(e).unwrap())
            .collect();
        s.stride = stride;
        s
    }

    fn keep(dir: &Path, s: &TrackingRunSetup) {
        std::fs::create_dir_all(dir).unwrap();
        std::fs::write(dir.join("setup.json"), serde_json::to_string(s).unwrap()).unwrap();
        std::fs::write(dir.join("solution.json"), "{}").unwrap();
    }

    /// A start is the problem's by its effects, half cycle and cost, whatever its paths;
    /// a folder of starts is searched one level deep; a bad `--start` is named.
    #[test]
    fn a_start_matches_by_effects_half_cycle_and_cost_not_by_paths() {
        let tmp = tempfile::tempdir().unwrap();
        let knee = setup(&["passive_joint_stiffness:joint=knee"], None);
        let mut moved = knee.clone();
        moved.model = "elsewhere/model.json".into();
        keep(&tmp.path().join("kept/refit_knee"), &moved);
        keep(&tmp.path().join("kept/held_out"), &setup(&[], Some(2)));
        let found = kept_solutions(&[tmp.path().join("kept")]).unwrap();
        assert_eq!(found.len(), 2);
        assert_eq!(key(&knee).unwrap(), key(&moved).unwrap());
        assert_ne!(
            key(&knee).unwrap(),
            key(&setup(&["passive_joint_stiffness:joint=hip"], None)).unwrap()
        );
        assert_ne!(
            key(&setup(&[], Some(2))).unwrap(),
            key(&setup(&[], None)).unwrap()
        );
        let mut pelvis = setup(&[], Some(2));
        pelvis.track_pelvis_position = true;
        assert_ne!(key(&pelvis).unwrap(), key(&setup(&[], Some(2))).unwrap());
        let e = kept_solutions(&[tmp.path().join("none")])
            .unwrap_err()
            .to_string();
        assert!(e.contains("none") && e.contains("no such folder"), "{e}");
        std::fs::create_dir(tmp.path().join("empty")).unwrap();
        let e = kept_solutions(&[tmp.path().join("empty")])
            .unwrap_err()
            .to_string();
        assert!(e.contains("holds no solution"), "{e}");
    }
}
