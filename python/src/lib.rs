//! `import footfall`: the library's workflows from Python, results as numpy arrays.
//!
//! ```python
//! import footfall
//! run = footfall.track(foot="ellipse", out="runs/py_track")
//! print(run["status"], run["objective"], run["states"].shape)
//! table = footfall.study("tests/data/study/clock_edit.csv", out="runs/py_study")
//! checked = footfall.check(out="runs/py_check")
//! print(checked["found"], checked["joint_torques"].shape)
//! ```
//!
//! Paths are relative to the working folder (the repository root for the bundled model
//! and trial), as for the command line.

use footfall::problems::check::{CheckSettings, JointKinetics};
use footfall::runfolder::RunFolder;
use footfall::workflows::check::{self as check_workflow, CheckRequest};
use footfall::workflows::study::{self as study_workflow, StudyRequest, StudySettings};
use footfall::workflows::track::{track as track_workflow, TrackRequest};
use footfall::workflows::trial::TrialFiles;
use footfall::workflows::{Stream, TextProgress};
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

/// The binding's progress, as a terminal shows it: results on standard output, news, the
/// iteration table and warnings on standard error (only warnings if `quiet`).
fn printed(quiet: bool) -> TextProgress {
    fn write(stream: Stream, text: &str) {
        match stream {
            Stream::Results => println!("{text}"),
            Stream::Messages => eprintln!("{text}"),
        }
    }
    TextProgress { quiet, write }
}

/// Track measured walking with the model and write the run folder `out`.
///
/// Returns a dict: `status`, `converged`, `physically_valid`, `objective`, `kkt`,
/// `iterations`, `seconds`, `run_folder`, and at the shooting nodes `time` (s, n),
/// `states` (n × states: q, q̇, activations) and `state_names`, and `parameters` (the
/// model's effect parameters by name).
#[pyfunction]
#[pyo3(signature = (foot="ellipse", out="runs/py_track", data=None, init=None, model=None, phases=None, max_iter=200, tol=1e-5, check_points=true, overwrite=true, quiet=false))]
#[allow(clippy::too_many_arguments)]
fn track<'py>(
    py: Python<'py>,
    foot: &str,
    out: &str,
    data: Option<PathBuf>,
    init: Option<PathBuf>,
    model: Option<PathBuf>,
    phases: Option<PathBuf>,
    max_iter: usize,
    tol: f64,
    check_points: bool,
    overwrite: bool,
    quiet: bool,
) -> PyResult<Bound<'py, PyDict>> {
    if !(tol.is_finite() && tol > 0.0) {
        return Err(PyValueError::new_err(format!(
            "tol = {tol}: expected a positive KKT tolerance"
        )));
    }
    let mut req = TrackRequest::new(foot);
    req.run.data = data;
    if let Some(m) = model {
        req.run.model = m;
    }
    if let Some(p) = phases {
        req.run.phases = p;
    }
    req.init = init;
    req.check_points = check_points;
    req.sqp.max_iter = max_iter;
    req.sqp.tol_kkt = tol;
    let out = PathBuf::from(out);
    let run = py
        .detach(|| -> anyhow::Result<_> {
            let folder = RunFolder::create(&out, overwrite)?;
            Ok(track_workflow(&req, folder, &printed(quiet))?)
        })
        .map_err(|e| PyRuntimeError::new_err(format!("{e:#}")))?;
    let solution = &run.solution;
    let mut time = Vec::new();
    let mut states: Vec<Vec<f64>> = Vec::new();
    for (j, p) in solution.phases.iter().enumerate() {
        // a phase's first node is the previous phase's last one (after an impact, the
        // post-impact state): every node once, the later phase's
        for k in 0..p.x.len() {
            let t = p.node_time(k);
            if j > 0 && k == 0 {
                time.pop();
                states.pop();
            }
            time.push(t);
            states.push(p.x[k].clone());
        }
    }
    let names = run.state_names.clone();
    let d = PyDict::new(py);
    d.set_item("status", run.result.status.to_string())?;
    d.set_item("converged", run.converged)?;
    d.set_item(
        "physically_valid",
        run.output.validity.as_ref().map(|v| v.is_valid()),
    )?;
    d.set_item("objective", run.result.objective)?;
    d.set_item("kkt", run.result.kkt)?;
    d.set_item("iterations", run.result.history.len().saturating_sub(1))?;
    d.set_item("seconds", run.result.seconds)?;
    d.set_item("run_folder", run.output.path.display().to_string())?;
    d.set_item("time", PyArray1::from_vec(py, time))?;
    d.set_item(
        "states",
        PyArray2::from_vec2(py, &states).map_err(|e| PyValueError::new_err(e.to_string()))?,
    )?;
    d.set_item("state_names", names)?;
    let parameters = PyDict::new(py);
    for p in &run.record.parameters {
        parameters.set_item(&p.name, p.value)?;
    }
    d.set_item("parameters", parameters)?;
    Ok(d)
}

/// Check the measurement against itself (as `footfall check`): the trial's whole-body
/// balance read for instrument and body effects, written to the run folder `out`.
///
/// Returns a dict: `found` (effect names), `readings` (one dict per candidate: `effect`,
/// `label`, `estimate`, `sd`, `z`, `threshold`, `smallest_found` in SI units, NaN where
/// not read, and `verdict`), `add_effects` (the `--effect` lines for `track`),
/// `run_folder`, and at the instants read `time` (s, n), `residual` and
/// `residual_corrected` (n × 3: Fx, Fy in N, moment about the COM in N·m) and
/// `joint_torques` (n × 6, N·m, the inverse dynamics as recorded) and `joint_powers`
/// (n × 6, W) at `torque_time`, with `joint_names`.
#[pyfunction]
#[pyo3(signature = (trial=None, model="models/opensim_subject01.json", out="runs/py_check", forces=None, plates=vec![], overground=false, cutoff=6.0, level=0.05, lumbar=false, overwrite=true, quiet=false))]
#[allow(clippy::too_many_arguments)]
fn check<'py>(
    py: Python<'py>,
    trial: Option<PathBuf>,
    model: &str,
    out: &str,
    forces: Option<PathBuf>,
    plates: Vec<String>,
    overground: bool,
    cutoff: f64,
    level: f64,
    lumbar: bool,
    overwrite: bool,
    quiet: bool,
) -> PyResult<Bound<'py, PyDict>> {
    for (name, v) in [("cutoff", cutoff), ("level", level)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(PyValueError::new_err(format!(
                "{name} = {v}: expected a positive number"
            )));
        }
    }
    let req = CheckRequest {
        trial: TrialFiles {
            data: trial,
            forces,
            plates,
            overground,
            ..TrialFiles::default()
        },
        model: PathBuf::from(model),
        out: Some(PathBuf::from(out)),
        overwrite,
        settings: CheckSettings {
            cutoff_hz: cutoff,
            level,
            lumbar,
            ..CheckSettings::default()
        },
    };
    let outcome = py
        .detach(|| check_workflow::run(&req, &printed(quiet)))
        .map_err(|e| PyRuntimeError::new_err(format!("{e:#}")))?;
    let c = &outcome.check;
    let d = PyDict::new(py);
    let found: Vec<&str> = c.found().map(|r| r.param.name()).collect();
    d.set_item("found", found)?;
    let readings = PyList::empty(py);
    for r in &c.readings {
        let e = PyDict::new(py);
        e.set_item("effect", r.param.name())?;
        e.set_item("label", r.param.label())?;
        e.set_item("estimate", r.estimate)?;
        e.set_item("sd", r.sd)?;
        e.set_item("z", r.z)?;
        e.set_item("threshold", r.threshold)?;
        e.set_item("smallest_found", r.smallest_found())?;
        e.set_item("verdict", r.verdict.text())?;
        readings.append(e)?;
    }
    d.set_item("readings", readings)?;
    d.set_item("add_effects", check_workflow::effect_lines(c))?;
    d.set_item(
        "run_folder",
        outcome.folder.as_ref().map(|f| f.display().to_string()),
    )?;
    let rows = |v: &[[f64; 3]]| v.iter().map(|r| r.to_vec()).collect::<Vec<_>>();
    let matrix = |m: Vec<Vec<f64>>| {
        PyArray2::from_vec2(py, &m).map_err(|e| PyValueError::new_err(e.to_string()))
    };
    d.set_item("time", PyArray1::from_vec(py, c.time.clone()))?;
    d.set_item("residual", matrix(rows(&c.before))?)?;
    d.set_item("residual_corrected", matrix(rows(&c.after))?)?;
    d.set_item(
        "torque_time",
        PyArray1::from_vec(py, c.joints.iter().map(|k| k.t).collect()),
    )?;
    d.set_item(
        "joint_torques",
        matrix(c.joints.iter().map(|k| k.torque.to_vec()).collect())?,
    )?;
    d.set_item(
        "joint_powers",
        matrix(c.joints.iter().map(|k| k.power.to_vec()).collect())?,
    )?;
    d.set_item("joint_names", JointKinetics::names().to_vec())?;
    Ok(d)
}

/// Run the study of a manifest into `out` (as `footfall study`) and return its table,
/// one row per trial: a pandas DataFrame where pandas is installed, else a dict of
/// columns (numbers as numpy arrays, NaN where absent; text as lists). The columns are
/// those of `study.csv`.
#[pyfunction]
#[pyo3(signature = (manifest, out="runs/study", track=false, diagnose=false, max_iter=200, cutoff=6.0, level=0.05, jobs=None, quiet=false))]
#[allow(clippy::too_many_arguments)]
fn study<'py>(
    py: Python<'py>,
    manifest: PathBuf,
    out: &str,
    track: bool,
    diagnose: bool,
    max_iter: usize,
    cutoff: f64,
    level: f64,
    jobs: Option<usize>,
    quiet: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let manifest = manifest
        .canonicalize()
        .map_err(|e| PyValueError::new_err(format!("manifest {}: {e}", manifest.display())))?;
    let req = StudyRequest {
        settings: StudySettings {
            manifest,
            track,
            diagnose,
            max_iter,
            cutoff_hz: cutoff,
            level,
        },
        out: std::path::absolute(out).unwrap_or_else(|_| PathBuf::from(out)),
        jobs: jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
        only_row: None,
    };
    let outcome = py
        .detach(|| study_workflow::run(&req, &printed(quiet)))
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let table = outcome
        .table
        .ok_or_else(|| PyRuntimeError::new_err("the study wrote no table"))?;
    let csv = study_workflow::report::csv(&table);
    let columns = PyDict::new(py);
    let mut lines = csv.lines().map(footfall::report::table::csv_fields);
    let header = lines.next().unwrap_or_default();
    let rows: Vec<Vec<String>> = lines.collect();
    for (i, name) in header.iter().enumerate() {
        let cells: Vec<&str> = rows
            .iter()
            .map(|r| r.get(i).map_or("", String::as_str))
            .collect();
        let numbers: Option<Vec<f64>> = cells
            .iter()
            .map(|c| {
                if c.is_empty() {
                    Some(f64::NAN)
                } else {
                    c.parse().ok()
                }
            })
            .collect();
        match numbers.filter(|n| n.iter().any(|x| x.is_finite())) {
            Some(n) => columns.set_item(name, PyArray1::from_vec(py, n))?,
            None => columns.set_item(name, cells)?,
        }
    }
    match py.import("pandas") {
        Ok(pd) => pd.call_method1("DataFrame", (columns,)),
        Err(_) => Ok(columns.into_any()),
    }
}

/// footfall: fit and predict human gait with foot-ground contact models.
#[pymodule]
#[pyo3(name = "footfall")]
fn footfall_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(track, m)?)?;
    m.add_function(wrap_pyfunction!(study, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    Ok(())
}
