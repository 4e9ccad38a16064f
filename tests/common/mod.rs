//! Shared helpers for the integration tests.
#![allow(dead_code)]

pub mod docs;
pub mod study;

use footfall::model::GaitModel;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Project root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Load a model file and a foot file from `models/`.
pub fn model(model: &str, foot: &str) -> GaitModel {
    let r = root();
    GaitModel::load(
        &r.join("models").join(model),
        &r.join("models/feet").join(foot),
    )
    .unwrap_or_else(|e| panic!("loading {model} + {foot}: {e}"))
}

/// Deterministic pseudo-random numbers (xorshift), so tests need no seed handling.
pub struct Rng(u64);
impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E3779B97F4A7C15) | 1)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// The CasADi peers' folder (their problem files, check values and results), which is not
/// part of the repository: `FOOTFALL_PEER_DIR`, else the folder `shared` beside the
/// repository's own. The tests that read it print a note and pass when it is absent.
pub fn peer_dir() -> PathBuf {
    match std::env::var_os("FOOTFALL_PEER_DIR") {
        Some(d) => PathBuf::from(d),
        None => root()
            .parent()
            .map(|p| p.join("shared"))
            .unwrap_or_default(),
    }
}

/// Peer problem file with check values.
pub fn peer_gait_problem() -> serde_json::Value {
    let p = peer_dir().join("peer_gait/problem/gait_track_ellipse.json");
    let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&text).expect("peer problem JSON")
}

/// Whether the peers' folder ([`peer_dir`]) is present.
pub fn have_shared() -> bool {
    peer_dir()
        .join("peer_gait/problem/gait_track_ellipse.json")
        .exists()
}

/// Vector from a JSON array.
pub fn vecf(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// Max-norm relative difference with a floor on the scale.
pub fn rel_diff(a: &[f64], b: &[f64], floor: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().map(|x| x.abs()).fold(floor, f64::max);
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / scale
}

pub fn path(p: &str) -> PathBuf {
    root().join(p)
}

pub fn exists(p: &Path) -> bool {
    p.exists()
}

/// A model from `models/MODEL` and `models/feet/FOOT` with extra effects (JSON values).
pub fn model_with_effects(model_file: &str, foot: &str, effects: serde_json::Value) -> GaitModel {
    use footfall::model::spec::{FootSpec, ModelSpec};
    let mp = root().join("models").join(model_file);
    let fp = root().join("models/feet").join(foot);
    let mut spec = ModelSpec::load(&mp).unwrap();
    spec.effects = serde_json::from_value(effects).expect("effects JSON");
    let foot_spec = FootSpec::load(&fp).unwrap();
    GaitModel::from_specs(&spec, &mp, &foot_spec, &fp).unwrap()
}

/// Generalised positions with the joint angles given and pelvis height chosen so that
/// contact `c` touches the ground.
pub fn pose_on_ground(m: &GaitModel, joints: [f64; 7], contact: &str) -> Vec<f64> {
    let mut q = vec![
        0.0, 1.0, joints[0], joints[1], joints[2], joints[3], joints[4], joints[5], joints[6],
    ];
    let c = m.contact_index(contact).expect("contact");
    let (_, gap) = m.contact_point(c, &q, &m.theta0());
    q[1] -= gap;
    q
}

/// The constraint sets exercised by derivative and drift tests, per foot file.
pub fn constraint_sets(foot: &str) -> Vec<(&'static str, Vec<(&'static str, bool)>)> {
    match foot {
        "ellipse.json" => vec![
            ("flight", vec![]),
            ("single_stance", vec![("r.sole", true)]),
            ("double_stance", vec![("r.sole", true), ("l.sole", true)]),
        ],
        _ => vec![
            ("heel", vec![("r.heel", true)]),
            ("forefoot", vec![("r.forefoot", true)]),
            (
                "both_circles",
                vec![("r.heel", true), ("r.forefoot", false)],
            ),
            (
                "double_stance",
                vec![("r.forefoot", true), ("l.heel", true)],
            ),
            (
                "three_circles",
                vec![
                    ("r.forefoot", true),
                    ("l.heel", true),
                    ("l.forefoot", false),
                ],
            ),
        ],
    }
}

pub const CHROMIUM: &str = "/usr/bin/chromium";

/// Run headless Chromium on `args` (after the flags that keep it off the network) with a
/// fresh profile; returns stdout. Panics on a time-out or a failure.
pub fn chromium(args: &[String], timeout: Duration) -> Vec<u8> {
    assert!(
        Path::new(CHROMIUM).exists(),
        "{CHROMIUM} not found: run tools/setup, which installs Debian's chromium for this test"
    );
    let profile = tempfile::tempdir().unwrap();
    let mut child = Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start chromium");
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let out_t = std::thread::spawn(move || {
        let mut v = Vec::new();
        out.read_to_end(&mut v).ok();
        v
    });
    let err_t = std::thread::spawn(move || {
        let mut v = Vec::new();
        err.read_to_end(&mut v).ok();
        v
    });
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait for chromium") {
            break s;
        }
        if start.elapsed() > timeout {
            child.kill().ok();
            child.wait().ok();
            panic!("chromium {args:?} did not finish within {timeout:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let stdout = out_t.join().unwrap();
    let stderr = err_t.join().unwrap();
    assert!(
        status.success(),
        "chromium {args:?} failed ({status}): {}",
        String::from_utf8_lossy(&stderr)
    );
    stdout
}

/// The tracking problem of the bundled trial for the model `opensim_subject01.json`, foot
/// file `foot` and phase file `phases`: the model, the phase file's constraint sets and
/// the tracking setup.
#[allow(dead_code)]
pub fn bundled_tracking(
    foot: &str,
    phases: &str,
) -> (
    GaitModel,
    Vec<footfall::model::ConstraintSet>,
    footfall::problems::track::TrackingSetup,
) {
    bundled_tracking_with(
        foot,
        phases,
        footfall::problems::track::TargetSides::Interpolated,
    )
}

/// The compliant foot's identification track of the bundled trial, as
/// `tools/make-compliant-real-tracks` runs it: the volumetric ellipse with its file's law,
/// the seed's MTG damping, sample targets and the pelvis position tracked (the integrator
/// and the solver at their defaults).
pub fn compliant_identification_request() -> footfall::workflows::track::TrackRequest {
    let foot = root().join("models/feet/volumetric_ellipse.json");
    let mut req = footfall::workflows::track::TrackRequest::new(foot.to_str().unwrap());
    req.run.model = root().join("models/opensim_subject01_seed_damping.json");
    req.run.phases = root().join("phases/volumetric_ellipse_walk.json");
    req.run.sample_targets = true;
    req.run.track_pelvis_position = true;
    req
}

/// As [`bundled_tracking`], with the targets read as `sides` says.
#[allow(dead_code)]
pub fn bundled_tracking_with(
    foot: &str,
    phases: &str,
    sides: footfall::problems::track::TargetSides,
) -> (
    GaitModel,
    Vec<footfall::model::ConstraintSet>,
    footfall::problems::track::TrackingSetup,
) {
    bundled_tracking_of("opensim_subject01.json", foot, phases, sides)
}

/// As [`bundled_tracking_with`], for the model file `model_file` in `models/`.
#[allow(dead_code)]
pub fn bundled_tracking_of(
    model_file: &str,
    foot: &str,
    phases: &str,
    sides: footfall::problems::track::TargetSides,
) -> (
    GaitModel,
    Vec<footfall::model::ConstraintSet>,
    footfall::problems::track::TrackingSetup,
) {
    let data = footfall::data::GaitData::bundled(&root()).unwrap();
    let m = model(model_file, foot);
    let p = path(phases);
    let seq = footfall::phases::PhaseSequence::load(&p).unwrap();
    let sets = seq.resolve(&m, &p).unwrap();
    let setup =
        footfall::problems::track::TrackingSetup::new_with_sides(&m, &seq, &sets, &data, sides)
            .unwrap();
    (m, sets, setup)
}

/// Run `footfall ARGS` in the crate root.
pub fn footfall(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_footfall"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("run the footfall binary")
}

/// A process's standard error as text.
pub fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Exit code `code`, one `error:` report naming every item of `names`, no panic; the
/// report.
pub fn assert_exit(o: &std::process::Output, code: i32, names: &[&str]) -> String {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(code), "stderr: {err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in names {
        assert!(err.contains(n), "stderr does not name {n:?}: {err}");
    }
    err
}

/// A JSON file, read.
pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("read JSON")).expect("JSON")
}

/// The repository's JSON file `from` (relative to its root) with `edit` applied, written
/// to `to`; returns `to`.
pub fn edited_json(from: &str, to: &Path, edit: impl FnOnce(&mut serde_json::Value)) -> PathBuf {
    let mut v = json(&root().join(from));
    edit(&mut v);
    std::fs::write(to, v.to_string()).expect("write the edited JSON");
    to.to_path_buf()
}

/// The columns of a CSV written by a run: header names and numbers (NaN for empty cells).
pub fn csv_columns(path: &Path) -> Vec<(String, Vec<f64>)> {
    let text = std::fs::read_to_string(path).expect("read CSV");
    let mut lines = text.lines();
    let mut cols: Vec<(String, Vec<f64>)> = lines
        .next()
        .expect("header")
        .split(',')
        .map(|n| (n.to_string(), vec![]))
        .collect();
    for l in lines {
        for (c, f) in cols.iter_mut().zip(l.split(',')) {
            c.1.push(f.parse().unwrap_or(f64::NAN));
        }
    }
    cols
}

/// A path as the `&str` a command line takes.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// A raw file of the bundled OpenSim trial (`data/raw/opensim_subject01/`).
pub fn raw(name: &str) -> PathBuf {
    root().join("data/raw/opensim_subject01").join(name)
}

/// The bundled trial's 3-D inverse kinematics (60 Hz).
pub fn ik() -> PathBuf {
    raw("subject01_walk1_ik.mot")
}

/// The bundled trial's ground reaction forces (600 Hz).
pub fn grf() -> PathBuf {
    raw("subject01_walk1_grf.mot")
}

/// The largest difference between `h` (∇²(μᵀf) over z = (x, u, θ), column-major, from
/// [`ControlledOde::weighted_hessian`](footfall::integrate::ControlledOde::weighted_hessian))
/// and central differences of the model's exact AD Jacobian weighted by `mu`, relative
/// to the largest entry of `h`; with that entry.
pub fn weighted_hessian_fd_error(
    m: &GaitModel,
    set: &footfall::model::ConstraintSet,
    z: &[f64],
    mu: &[f64],
    h: &[f64],
    step: f64,
) -> (f64, f64) {
    let (nx, nu) = (m.nx(), m.nu());
    let nw = z.len();
    let grad = |z: &[f64]| {
        let mut xdot = vec![0.0; nx];
        let mut jac = vec![0.0; nx * nw];
        m.dynamics_jacobian(
            set,
            &z[..nx],
            &z[nx..nx + nu],
            &z[nx + nu..],
            &mut xdot,
            &mut jac,
        )
        .unwrap();
        (0..nw)
            .map(|c| (0..nx).map(|i| mu[i] * jac[i + c * nx]).sum::<f64>())
            .collect::<Vec<f64>>()
    };
    let scale = h.iter().map(|v| v.abs()).fold(1.0, f64::max);
    let mut worst = 0.0f64;
    for c in 0..nw {
        let e = step * z[c].abs().max(1.0);
        let (mut a, mut b) = (z.to_vec(), z.to_vec());
        a[c] += e;
        b[c] -= e;
        let (ga, gb) = (grad(&a), grad(&b));
        for r in 0..nw {
            worst = worst.max(((ga[r] - gb[r]) / (2.0 * e) - h[r + c * nw]).abs() / scale);
        }
    }
    (worst, scale)
}

/// The interval curvature ∇²_z λᵀx(1) of `iv` from `x0` with parameters `p` (z = (x0, p),
/// integrated at `settings`) against central differences of the exact gradient `Sᵀλ`:
/// the largest difference relative to the largest curvature entry (at least 1e-3), that
/// entry, and where the difference is (row, column, difference quotient, curvature).
/// `step` is relative to max(|z_c|, 1), or to max(|z_c|, 0.01) for the duration column.
pub fn interval_curvature_fd_error(
    iv: &footfall::integrate::ShootingInterval<'_, dyn footfall::integrate::ControlledOde + '_>,
    x0: &[f64],
    p: &[f64],
    lambda: &[f64],
    settings: footfall::integrate::IntegratorSettings,
    step: f64,
) -> (f64, f64, (usize, usize, f64, f64)) {
    let (nx, np) = (x0.len(), p.len());
    let nz = nx + np;
    let mut integ = footfall::integrate::Integrator::new(nx, np, settings).unwrap();
    let (mut x1, mut s1, mut hs) = (vec![0.0; nx], vec![0.0; nx * nz], vec![0.0; nz * nz]);
    assert!(iv
        .integrate_with_hessian(&mut integ, x0, p, lambda, &mut x1, &mut s1, &mut hs)
        .unwrap());
    let mut grad = |z: &[f64]| {
        let (mut x, mut s) = (vec![0.0; nx], vec![0.0; nx * nz]);
        integ
            .integrate_with_sensitivities(iv, 0.0, 1.0, &z[..nx], &z[nx..], &mut x, &mut s)
            .unwrap();
        (0..nz)
            .map(|c| (0..nx).map(|i| lambda[i] * s[i + c * nx]).sum::<f64>())
            .collect::<Vec<f64>>()
    };
    let z0: Vec<f64> = x0.iter().chain(p).copied().collect();
    let t_col = nx + iv.p_duration();
    let scale = hs.iter().map(|v| v.abs()).fold(1e-3, f64::max);
    let mut worst = (0.0f64, (0, 0, 0.0, 0.0));
    for c in 0..nz {
        let e = step * z0[c].abs().max(if c == t_col { 0.01 } else { 1.0 });
        let (mut zp, mut zm) = (z0.clone(), z0.clone());
        zp[c] += e;
        zm[c] -= e;
        let (gp, gm) = (grad(&zp), grad(&zm));
        for r in 0..nz {
            let fd = (gp[r] - gm[r]) / (2.0 * e);
            let d = (fd - hs[r + c * nz]).abs() / scale;
            if d > worst.0 {
                worst = (d, (r, c, fd, hs[r + c * nz]));
            }
        }
    }
    (worst.0, scale, worst.1)
}

/// Progress shown as the command line shows it, for a test whose solve is worth watching
/// with `--nocapture`.
pub fn printed() -> footfall::workflows::TextProgress {
    fn write(_: footfall::workflows::Stream, text: &str) {
        eprintln!("{text}");
    }
    footfall::workflows::TextProgress {
        quiet: false,
        write,
    }
}
