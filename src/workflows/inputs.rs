//! The inputs of a run, copied into its folder: `inputs/model/` (the model file and the
//! OpenSim model it names), `inputs/foot/`, `inputs/phases/`, `inputs/data/` (the
//! trial and its meta file; the bundled trial when the run used it) and `inputs/forces/`
//! (the forces file of a trial given as kinematics and forces). `setup.json` names
//! these copies relative to the run folder, so `report`, `diagnose`, `synth` and `diff`
//! rebuild the run's problem from any folder, also after the run folder was moved or
//! copied to another machine.

use crate::runfolder::RunFolder;
use anyhow::Context;
use std::path::{Path, PathBuf};

/// The subfolder of a run folder holding the run's inputs.
pub const INPUTS: &str = "inputs";

pub use crate::report::run_summary::RunInputs;

/// The file name of `path` (for messages and copies).
fn file_name(path: &Path) -> anyhow::Result<String> {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .with_context(|| format!("{}: not a file name", path.display()))
}

/// Copy the file `source` into the staging folder as `inputs/<what>/<name>` (`name`: its
/// own file name unless given); returns the path relative to the run folder.
fn copy(
    folder: &RunFolder,
    what: &str,
    source: &Path,
    name: Option<&str>,
) -> anyhow::Result<PathBuf> {
    let bytes = std::fs::read(source)
        .with_context(|| format!("copying the run's {what} file {}", source.display()))?;
    let name = match name {
        Some(n) => n.to_string(),
        None => file_name(source)?,
    };
    let rel = Path::new(INPUTS).join(what).join(name);
    folder.write(&rel.to_string_lossy(), &bytes)?;
    Ok(rel)
}

/// Copy the model file and the OpenSim model it names (`body.file`, written beside it
/// and named by its file name in the copy).
fn copy_model(folder: &RunFolder, model: &Path) -> anyhow::Result<PathBuf> {
    let source = crate::bundled::resolve(model);
    let text = std::fs::read_to_string(&source)
        .with_context(|| format!("copying the run's model file {}", source.display()))?;
    let mut spec: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("{}: not valid JSON", source.display()))?;
    let name = file_name(&source)?;
    let body_file = spec
        .pointer("/body/file")
        .and_then(|f| f.as_str())
        .map(PathBuf::from);
    let text = match body_file {
        Some(body) => {
            let body_source = crate::model::spec::relative_to(&source, &body);
            let mut body_name = file_name(&body_source)?;
            if body_name == name {
                body_name = format!("body_{body_name}");
            }
            copy(folder, "model", &body_source, Some(&body_name))?;
            spec["body"]["file"] = body_name.into();
            serde_json::to_string_pretty(&spec)? + "\n"
        }
        None => text,
    };
    let rel = Path::new(INPUTS).join("model").join(&name);
    folder.write(&rel.to_string_lossy(), text.as_bytes())?;
    Ok(rel)
}

/// Copy a model file (with the OpenSim model it names), a foot (`ellipse`,
/// `double-circle` or a foot file) and a phase file into `folder`'s `inputs/`; returns
/// their paths relative to the run folder. Bundled names missing from the current
/// folder are copied from footfall's own copies, as they were read.
pub fn copy_model_inputs(
    folder: &RunFolder,
    model: &Path,
    foot: &str,
    phases: &Path,
) -> anyhow::Result<(PathBuf, PathBuf, PathBuf)> {
    let model = copy_model(folder, model)?;
    let foot = copy(
        folder,
        "foot",
        &crate::bundled::resolve(&super::foot_path(foot)),
        None,
    )?;
    let phases = copy(folder, "phases", &crate::bundled::resolve(phases), None)?;
    Ok((model, foot, phases))
}

/// Copy a run's model, foot, phase file ([`copy_model_inputs`]) and trial (`None`: the
/// bundled trial; its meta file beside it; and its forces file, if given apart, in
/// `inputs/forces/`) into
/// `folder`'s `inputs/`.
pub fn copy_inputs(
    folder: &RunFolder,
    model: &Path,
    foot: &str,
    phases: &Path,
    data: Option<&Path>,
    forces: Option<&Path>,
) -> anyhow::Result<RunInputs> {
    let (model, foot, phases) = copy_model_inputs(folder, model, foot, phases)?;
    let csv = match data {
        Some(p) => p.to_path_buf(),
        None => {
            crate::bundled::path_of(&format!("data/{}_sagittal.csv", crate::data::BUNDLED_TRIAL))?
        }
    };
    let data = copy(folder, "data", &csv, None)?;
    if let Some(meta) = crate::data::sibling_meta_path(&csv) {
        copy(folder, "data", &meta, None)?;
    }
    // a folder of its own: kinematics and forces files may share a name
    let forces = forces
        .map(|f| copy(folder, "forces", f, None))
        .transpose()?;
    Ok(RunInputs {
        model,
        foot,
        phases,
        data,
        forces,
    })
}

/// `path` as read for the run in `folder`: a relative path under `inputs/` names an
/// input copied into the run folder and is taken from there (also when it is missing, so
/// that the error names the run folder's file, unless the current folder has it); any
/// other path as it is (older run folders recorded the paths as typed, relative to the
/// current folder).
pub fn in_run(folder: &Path, path: &Path) -> PathBuf {
    let inside = folder.join(path);
    if path.is_relative() && path.starts_with(INPUTS) && (inside.is_file() || !path.exists()) {
        inside
    } else {
        path.to_path_buf()
    }
}

/// Read a run's `setup.json` (`run`: the run folder or the file). The inputs it names
/// inside the run folder (`inputs/…`) are returned as paths to read from here; older
/// run folders' paths, recorded as typed, are returned as they are.
pub fn read_run_setup(
    run: &std::path::Path,
) -> anyhow::Result<crate::problems::diagnose::TrackingRunSetup> {
    let (file, folder) = if run.is_dir() {
        (run.join("setup.json"), run.to_path_buf())
    } else {
        let parent = run.parent().unwrap_or(std::path::Path::new(""));
        (run.to_path_buf(), parent.to_path_buf())
    };
    if !file.is_file() {
        anyhow::bail!(
            "{}: not found (a track run folder has one; it says how the run was set up)",
            file.display()
        );
    }
    let mut setup = crate::problems::diagnose::TrackingRunSetup::read(&file)?;
    let inside = |p: &std::path::Path| in_run(&folder, p);
    setup.model = inside(&setup.model);
    setup.phases = inside(&setup.phases);
    setup.data = setup.data.as_deref().map(inside);
    setup.forces = setup.forces.as_deref().map(inside);
    setup.foot = inside(std::path::Path::new(&setup.foot))
        .to_string_lossy()
        .into_owned();
    Ok(setup)
}
