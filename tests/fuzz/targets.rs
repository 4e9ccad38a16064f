//! The library loaders under fuzzing. Each target reads one mutated file (its siblings
//! unmutated) from a scratch folder and checks the outcome: `Ok`, or an error whose
//! message is non-empty and names a file in the scratch folder; after a successful load
//! the loaded object is used once (dynamics, unit conversion, transcription).

use footfall::controls::ControlTable;
use footfall::data::{read_sagittal_csv, read_storage, GaitData, StorageMap};
use footfall::integrate::{ControlledOde, IntegratorSettings};
use footfall::model::spec::{FootSpec, ModelSpec};
use footfall::model::GaitModel;
use footfall::phases::PhaseSequence;
use footfall::problems::benchmarks::Benchmark;
use footfall::problems::GaitOde;
use footfall::report::diff::RunSummary;
use std::path::{Path, PathBuf};

/// The corpus folder.
pub fn corpus() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz")
}

/// Read a corpus file.
pub fn seed(rel: &str) -> Vec<u8> {
    std::fs::read(corpus().join(rel)).unwrap_or_else(|e| panic!("corpus file {rel}: {e}"))
}

/// How a loader answered an input that broke no property.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Loaded (and the loaded object worked).
    Accepted,
    /// Refused with an error naming the file.
    Refused,
    /// Loaded, but the first use of the object failed with an error (message kept).
    UseFailed(String),
}

/// A fuzz target: a name, its seed files (relative to the corpus) and its check.
pub struct Target {
    /// Name (also the folder of its regression inputs).
    pub name: &'static str,
    /// Seed files, relative to [`corpus`].
    pub seeds: &'static [&'static str],
    /// Check one mutated input: `dir` is a scratch folder, `seed` the seed's index,
    /// `bytes` the mutated file. `Err` describes a violated property.
    pub check: fn(dir: &Path, seed: usize, bytes: &[u8]) -> Result<Outcome, String>,
}

/// Every library target.
pub const TARGETS: &[Target] = &[
    Target {
        name: "model",
        seeds: &[
            "model/opensim_subject01.json",
            "model/gait9dof.json",
            "model/opensim_subject01_torque.json",
            "model/opensim_subject01_seed_damping.json",
        ],
        check: check_model,
    },
    Target {
        name: "foot",
        seeds: &[
            "foot/ellipse.json",
            "foot/double_circle.json",
            "foot/heel_circle_forefoot_ellipse.json",
            "foot/peer_ellipse.json",
        ],
        check: check_foot,
    },
    Target {
        name: "phases",
        seeds: &[
            "phases/sim_ellipse_step.json",
            "phases/sim_double_circle_step.json",
            "phases/ellipse_walk.json",
            "phases/double_circle_walk.json",
            "phases/heel_circle_forefoot_ellipse_walk.json",
        ],
        check: check_phases,
    },
    Target {
        name: "csv",
        seeds: &[
            "csv/opensim_subject01_sagittal.csv",
            "csv/opensim_subject01_meta.json",
        ],
        check: check_csv,
    },
    Target {
        name: "storage",
        seeds: &[
            "storage/subject01_walk1_ik.mot",
            "storage/subject01_walk1_grf.mot",
            "storage/walk_gait1018_state_reference.sto",
        ],
        check: check_storage,
    },
    Target {
        name: "problem",
        seeds: &[
            "problem/cartpole_swingup.json",
            "problem/five_link_biped.json",
        ],
        check: check_problem,
    },
    Target {
        name: "summary",
        seeds: &["summary/run_a.json", "summary/run_b.json"],
        check: check_summary,
    },
    Target {
        name: "controls",
        seeds: &["controls/sim_controls_cocontraction.csv"],
        check: check_controls,
    },
];

/// Write `bytes` to `dir/rel` (creating folders) and return the path.
fn put(dir: &Path, rel: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(rel);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    std::fs::write(&p, bytes).unwrap_or_else(|e| panic!("writing {}: {e}", p.display()));
    p
}

/// A refused input: the message must be non-empty and name a file in `dir`.
fn refused(dir: &Path, what: &str, msg: String) -> Result<Outcome, String> {
    if msg.trim().is_empty() {
        return Err(format!("{what}: empty error message"));
    }
    if !msg.contains(&dir.display().to_string()) {
        return Err(format!("{what}: error does not name the file: {msg}"));
    }
    Ok(Outcome::Refused)
}

/// Model, foot and phase file in `dir` (the OpenSim summary beside them, as in the
/// repository), with `mutated` (0 model, 1 foot, 2 phases) replaced by `bytes`.
fn gait_case(
    dir: &Path,
    files: [&str; 3],
    mutated: usize,
    bytes: &[u8],
) -> Result<Outcome, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    put(
        dir,
        "data/opensim_subject01_model.json",
        &std::fs::read(root.join("data/opensim_subject01_model.json")).unwrap(),
    );
    let rel = [
        "models/model.json",
        "models/feet/foot.json",
        "phases/phases.json",
    ];
    let paths: Vec<PathBuf> = (0..3)
        .map(|i| {
            if i == mutated {
                put(dir, rel[i], bytes)
            } else {
                put(dir, rel[i], &seed(files[i]))
            }
        })
        .collect();
    let r = (|| {
        let spec = ModelSpec::load(&paths[0])?;
        let foot = FootSpec::load(&paths[1])?;
        let model = GaitModel::from_specs(&spec, &paths[0], &foot, &paths[1])?;
        let seq = PhaseSequence::load(&paths[2])?;
        let sets = seq.resolve(&model, &paths[2])?;
        Ok::<_, footfall::model::ModelError>((model, seq, sets))
    })();
    let (model, seq, sets) = match r {
        Ok(x) => x,
        Err(e) => return refused(dir, "gait files", e.to_string()),
    };
    evaluate(&model, &seq, &sets[0])
}

/// One right-hand side evaluation at the phase file's initial state (or a standing pose):
/// `Ok` with a finite derivative or an error with a message.
fn evaluate(
    model: &GaitModel,
    seq: &PhaseSequence,
    set: &footfall::model::ConstraintSet,
) -> Result<Outcome, String> {
    let nq = model.nq();
    let (q, qd, a) = match &seq.initial_state {
        Some(s) => (
            s.q.clone(),
            s.qd.clone(),
            s.a.clone().unwrap_or_else(|| vec![0.01; model.na()]),
        ),
        None => {
            let mut q = vec![0.0; nq];
            q[1] = 1.0;
            (q, vec![0.0; nq], vec![0.01; model.na()])
        }
    };
    let mut x = q;
    x.extend(qd);
    x.extend(a);
    let u = vec![if model.na() > 0 { 0.025 } else { 0.0 }; model.nu()];
    let mut xdot = vec![0.0; model.nx()];
    match (GaitOde { model, set }).f(&x, &u, &model.theta0(), &mut xdot) {
        Ok(()) if xdot.iter().all(|v| v.is_finite()) => Ok(Outcome::Accepted),
        Ok(()) => Err(format!(
            "dynamics returned a non-finite derivative silently: {xdot:?}"
        )),
        Err(e) if e.to_string().trim().is_empty() => {
            Err("dynamics error with an empty message".into())
        }
        Err(e) => Ok(Outcome::UseFailed(e.to_string())),
    }
}

const GAIT_PAIRS: [(&str, &str); 3] = [
    ("foot/ellipse.json", "phases/sim_ellipse_step.json"),
    (
        "foot/double_circle.json",
        "phases/sim_double_circle_step.json",
    ),
    (
        "foot/heel_circle_forefoot_ellipse.json",
        "phases/heel_circle_forefoot_ellipse_walk.json",
    ),
];

fn check_model(dir: &Path, s: usize, bytes: &[u8]) -> Result<Outcome, String> {
    let (foot, phases) = GAIT_PAIRS[s % 2];
    gait_case(dir, [TARGETS[0].seeds[s], foot, phases], 0, bytes)
}

fn check_foot(dir: &Path, s: usize, bytes: &[u8]) -> Result<Outcome, String> {
    let phases = match s {
        1 => GAIT_PAIRS[1].1,
        2 => GAIT_PAIRS[2].1,
        _ => GAIT_PAIRS[0].1,
    };
    gait_case(
        dir,
        ["model/opensim_subject01.json", TARGETS[1].seeds[s], phases],
        1,
        bytes,
    )
}

fn check_phases(dir: &Path, s: usize, bytes: &[u8]) -> Result<Outcome, String> {
    let foot = match s {
        1 | 3 => GAIT_PAIRS[1].0,
        4 => GAIT_PAIRS[2].0,
        _ => GAIT_PAIRS[0].0,
    };
    gait_case(
        dir,
        ["model/opensim_subject01.json", foot, TARGETS[2].seeds[s]],
        2,
        bytes,
    )
}

/// The sagittal CSV with its sibling meta file, one of them mutated; on success the
/// checks and the treadmill-to-overground conversion the CLI applies.
fn check_csv(dir: &Path, s: usize, bytes: &[u8]) -> Result<Outcome, String> {
    let names = ["trial_sagittal.csv", "trial_meta.json"];
    for (i, n) in names.iter().enumerate() {
        put(
            dir,
            n,
            &if i == s {
                bytes.to_vec()
            } else {
                seed(TARGETS[3].seeds[i])
            },
        );
    }
    let r = read_sagittal_csv(&dir.join(names[0])).and_then(|d| {
        d.validate()?;
        match d.belt_speed {
            Some(v) if !d.overground => d.to_overground(v).and_then(|o| o.validate()),
            _ => Ok(()),
        }
    });
    r.map(|()| Outcome::Accepted)
        .or_else(|e| refused(dir, "sagittal CSV", e.to_string()))
}

/// A storage file; the kinematics and forces are combined into gait data as
/// `GaitData::from_storage` does.
fn check_storage(dir: &Path, s: usize, bytes: &[u8]) -> Result<Outcome, String> {
    let seeds = TARGETS[4].seeds;
    let p = put(dir, seeds[s].rsplit('/').next().unwrap(), bytes);
    let r = read_storage(&p).and_then(|st| {
        st.validate()?;
        let map = StorageMap::gait10dof18musc();
        match s {
            0 => {
                let grf = read_storage(&corpus().join(seeds[1]))?;
                GaitData::from_storage(&st, Some(&grf), &map)
            }
            1 => {
                let ik = read_storage(&corpus().join(seeds[0]))?;
                GaitData::from_storage(&ik, Some(&st), &map)
            }
            _ => GaitData::from_storage(&st, None, &map),
        }
        .and_then(|d| d.validate())
    });
    r.map(|()| Outcome::Accepted)
        .or_else(|e| refused(dir, "storage", e.to_string()))
}

/// A problem file of `footfall solve`, and its optimal control problem.
fn check_problem(dir: &Path, _s: usize, bytes: &[u8]) -> Result<Outcome, String> {
    let p = put(dir, "problem.json", bytes);
    match Benchmark::load(&p) {
        Err(e) => refused(dir, "problem", e.to_string()),
        // `load` checks the OCP's fields, so building it cannot fail
        Ok(b) => match b.ocp(IntegratorSettings::default()) {
            Ok(_) => Ok(Outcome::Accepted),
            Err(e) => Err(format!("problem: loaded, but its OCP is refused: {e}")),
        },
    }
}

/// A run summary as `footfall diff` reads it.
fn check_summary(dir: &Path, _s: usize, bytes: &[u8]) -> Result<Outcome, String> {
    put(dir, "run/summary.json", bytes);
    match RunSummary::read(&dir.join("run")) {
        Ok(_) => Ok(Outcome::Accepted),
        Err(e) => refused(dir, "run summary", e.to_string()),
    }
}

/// A control table for the bundled model's controls.
fn check_controls(dir: &Path, _s: usize, bytes: &[u8]) -> Result<Outcome, String> {
    let p = put(dir, "controls.csv", bytes);
    static NAMES: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    let names = NAMES.get_or_init(|| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        GaitModel::load(
            &root.join("models/opensim_subject01.json"),
            &root.join("models/feet/ellipse.json"),
        )
        .unwrap()
        .control_names()
    });
    match ControlTable::load_csv(&p, names) {
        Err(e) => refused(dir, "controls", e.to_string()),
        Ok(c) => {
            let mut u = vec![0.0; names.len()];
            for t in [-1.0, 0.0, 0.2, 1e9] {
                c.at(t, &mut u);
                if !u.iter().all(|v| v.is_finite()) {
                    return Err(format!("controls at t = {t} are not finite: {u:?}"));
                }
            }
            Ok(Outcome::Accepted)
        }
    }
}
