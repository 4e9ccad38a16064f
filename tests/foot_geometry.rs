//! The `foot_geometry` effect: the foot's primitives' centres, sizes and orientation as
//! free parameters, with exact sensitivities. The θ columns of the dynamics Jacobian (rigid
//! ellipse in single stance: the constraint rows, their bias and forces; volumetric
//! ellipse: the penetrated area) and the derivatives of the contact gap against central
//! differences.

use footfall::model::effects::EffectSpec;
use footfall::model::{ConstraintSet, GaitModel};
use footfall::phases::PhaseSequence;
use num_dual::Dual64;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn model(foot: &str, effect: &str) -> GaitModel {
    GaitModel::load_with_effects(
        &root().join("models/opensim_subject01.json"),
        &root().join(foot),
        &[EffectSpec::parse_cli(effect).unwrap()],
    )
    .unwrap()
}

#[test]
fn every_primitive_gets_its_centre_size_and_angle_within_bounds_of_the_files() {
    let m = model("models/feet/ellipse.json", "foot_geometry");
    let p = m.parameters();
    let names: Vec<&str> = p.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names
            .iter()
            .map(|n| n.rsplit('.').next().unwrap())
            .collect::<Vec<_>>(),
        ["x", "y", "a", "b", "angle"]
    );
    assert!(names[0].starts_with("foot_geometry."));
    assert_eq!(m.ntheta(), 5);
    // the file's shape: centre (4.30, −8.11) cm, semi-axes 15.25 × 4.03 cm (Millard & Mombaur 2019)
    let foot: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("models/feet/ellipse.json")).unwrap(),
    )
    .unwrap();
    let shape = &foot["primitives"][0]["shape"];
    let want = [
        shape["centre"][0].as_f64().unwrap(),
        shape["centre"][1].as_f64().unwrap(),
        shape["semi_axes"][0].as_f64().unwrap(),
        shape["semi_axes"][1].as_f64().unwrap(),
        shape["angle"].as_f64().unwrap(),
    ];
    for (q, w) in p.iter().zip(want) {
        assert_eq!(q.value, w, "{}", q.name);
        assert!(q.lower < w && w < q.upper, "{}", q.name);
    }
    assert!((p[2].upper / p[2].value - 1.3).abs() < 1e-12);
    assert!((p[0].upper - p[0].value - 0.03).abs() < 1e-12);
    // two circles: x, y, radius each; only the sizes free
    let m = model("models/feet/double_circle.json", "foot_geometry:free=size");
    assert_eq!(m.parameters().len(), 6);
    assert_eq!(m.ntheta(), 2);
    assert!(m
        .free_parameters()
        .iter()
        .all(|&i| m.parameters()[i].name.ends_with(".radius")));
    let e = EffectSpec::parse_cli("foot_geometry:free=width")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("width") && e.contains("centre, size, angle"),
        "{e}"
    );
}

/// The report draws the foot the run identified: the body drawing's primitives are the
/// shapes the free parameters give (the file's at the file's values, a 10 % longer
/// ellipse turned by 0.1 rad and moved 1 cm forward at those), for both feet.
#[test]
fn the_body_drawing_shows_the_identified_shape() {
    use footfall::model::geometry::Shape;
    use footfall::report::body::{Outline, Pose};
    let m = model("models/feet/ellipse.json", "foot_geometry");
    let file: Vec<f64> = m.parameters().iter().map(|p| p.value).collect();
    let (x, a, angle) = (file[0] + 0.01, 1.1 * file[2], file[4] + 0.1);
    let theta = [x, file[1], a, file[3], angle];
    let q = vec![0.0; m.nq()];
    for (values, want) in [
        (file.clone(), [file[0], file[2], file[4]]),
        (theta.to_vec(), [x, a, angle]),
    ] {
        let pose = Pose::of_model(&m, &q, &values);
        assert_eq!(pose.outlines.len(), m.contacts.len());
        for (i, (_, outline)) in pose.outlines.iter().enumerate() {
            let Shape::Ellipse {
                centre,
                angle,
                semi_axes,
            } = m.contact_shape(i, &values)
            else {
                panic!("the ellipse foot's primitive is an ellipse");
            };
            assert_eq!([centre[0], semi_axes[0], angle], want);
            let Outline::Ellipse {
                semi_axes: drawn, ..
            } = outline
            else {
                panic!("an ellipse is drawn as one");
            };
            assert_eq!(*drawn, semi_axes);
        }
    }
}

/// The initial state of a simulation phase file, projected onto its first phase's set.
fn state(m: &GaitModel, phases: &str, lower: f64) -> (ConstraintSet, Vec<f64>, Vec<f64>) {
    let seq = PhaseSequence::load(&root().join(phases)).unwrap();
    let set = seq.resolve(m, Path::new("<test>")).unwrap()[0].clone();
    let init = seq.initial_state.unwrap();
    let mut q = init.q.clone();
    q[1] -= lower;
    let (q, qd, _) = m.project(&set, &q, &init.qd, &m.theta0()).unwrap();
    let mut x = q;
    x.extend(qd);
    x.extend(vec![0.2; m.na()]);
    (set, x, vec![0.3; m.nu()])
}

/// θ columns of the dynamics Jacobian against central differences of the dynamics; `theta`
/// away from the file's values.
fn check_dynamics(m: &GaitModel, set: &ConstraintSet, x: &[f64], u: &[f64], theta: &[f64]) {
    let (nx, nu) = (m.nx(), m.nu());
    let f = |theta: &[f64]| {
        let mut xd = vec![0.0; nx];
        let mut lam = vec![0.0; set.rows.len()];
        m.dynamics::<f64>(set, x, u, theta, &mut xd, &mut lam, None)
            .unwrap();
        xd
    };
    let mut xdot = vec![0.0; nx];
    let mut jac = vec![0.0; nx * (nx + nu + theta.len())];
    m.dynamics_jacobian(set, x, u, theta, &mut xdot, &mut jac)
        .unwrap();
    for i in 0..theta.len() {
        let h = 1e-6;
        let (mut a, mut b) = (theta.to_vec(), theta.to_vec());
        a[i] += h;
        b[i] -= h;
        let (fa, fb) = (f(&a), f(&b));
        let col = nx + nu + i;
        let (mut worst, mut largest) = (0.0f64, 0.0f64);
        for r in 0..nx {
            let fd = (fa[r] - fb[r]) / (2.0 * h);
            largest = largest.max(fd.abs());
            worst = worst.max((fd - jac[col * nx + r]).abs() / (1.0 + fd.abs()));
        }
        let name = &m.parameters()[m.free_parameters()[i]].name;
        eprintln!("{name}: largest |∂ẋ/∂θ| {largest:.3e}, worst relative AD error {worst:.1e}");
        assert!(largest > 1e-3, "{name} does not move the dynamics");
        assert!(worst < 1e-5, "{name}: AD vs central differences {worst:e}");
    }
}

#[test]
fn rigid_ellipse_in_stance_dynamics_and_gap_derivatives_match_central_differences() {
    let m = model("models/feet/ellipse.json", "foot_geometry");
    let (set, x, u) = state(&m, "phases/sim_ellipse_step.json", 0.0);
    assert!(!set.rows.is_empty(), "a stance phase with constraint rows");
    let theta: Vec<f64> = m
        .theta0()
        .iter()
        .zip([0.004, -0.003, 0.01, -0.004, 0.05])
        .map(|(v, d)| v + d)
        .collect();
    check_dynamics(&m, &set, &x, &u, &theta);
    // the gap of the left foot's ellipse (in the air) over θ, by forward AD
    let nq = m.nq();
    let c = m.contacts.iter().position(|c| c.name == "l.sole").unwrap();
    let q: Vec<Dual64> = x[..nq].iter().map(|&v| Dual64::from_re(v)).collect();
    let mut d = vec![0.0; theta.len()];
    for i in 0..theta.len() {
        let th: Vec<Dual64> = theta
            .iter()
            .enumerate()
            .map(|(j, &v)| {
                if i == j {
                    Dual64::from_re(v).derivative()
                } else {
                    Dual64::from_re(v)
                }
            })
            .collect();
        let ad = m.gap(c, &q, &th).eps;
        let h = 1e-6;
        let (mut a, mut b) = (theta.clone(), theta.clone());
        a[i] += h;
        b[i] -= h;
        let fd =
            (m.contact_point(c, &x[..nq], &a).1 - m.contact_point(c, &x[..nq], &b).1) / (2.0 * h);
        assert!(
            (ad - fd).abs() < 1e-7,
            "θ{i}: AD {ad}, central differences {fd}"
        );
        d[i] = ad;
    }
    // moving the centre in the foot frame moves the lowest point with it: the gradient of
    // the gap over (x, y) is the ground normal seen in the turned foot frame, a unit vector
    assert!(
        (d[0].hypot(d[1]) - 1.0).abs() < 1e-9,
        "∂φ/∂(x, y) = {:?}",
        &d[..2]
    );
}

#[test]
fn volumetric_ellipse_dynamics_derivatives_in_the_geometry_match_central_differences() {
    let m = model("models/feet/volumetric_ellipse.json", "foot_geometry");
    let seq = PhaseSequence::load(&root().join("phases/sim_volumetric_ellipse_step.json")).unwrap();
    let set = seq.resolve(&m, Path::new("<test>")).unwrap()[0].clone();
    let init = seq.initial_state.unwrap();
    let mut x = init.q.clone();
    x.extend(&init.qd);
    x.extend(vec![0.2; m.na()]);
    x[1] -= 0.01;
    let u = vec![0.3; m.nu()];
    let theta: Vec<f64> = m
        .theta0()
        .iter()
        .zip([0.004, -0.003, 0.01, -0.004, 0.05])
        .map(|(v, d)| v + d)
        .collect();
    check_dynamics(&m, &set, &x, &u, &theta);
}

/// The ellipse foot of the file with its first semi-axis 10 % longer (the hidden shape).
fn hidden_foot() -> String {
    let mut foot: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("models/feet/ellipse.json")).unwrap(),
    )
    .unwrap();
    foot["name"] = "ellipse_hidden".into();
    foot["description"] = "tests/foot_geometry.rs: the ellipse of models/feet/ellipse.json with its first semi-axis 10 % longer".into();
    let a = foot["primitives"][0]["shape"]["semi_axes"][0]
        .as_f64()
        .unwrap();
    foot["primitives"][0]["shape"]["semi_axes"][0] = (1.1 * a).into();
    serde_json::to_string_pretty(&foot).unwrap()
}

/// The first semi-axis of a foot file (m).
fn semi_axis(path: &Path) -> f64 {
    let foot: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    foot["primitives"][0]["shape"]["semi_axes"][0]
        .as_f64()
        .unwrap()
}

/// A synthetic trial from the rigid ellipse with its first semi-axis 10 % longer than the
/// file's, tracked with the file's ellipse and `--effect foot_geometry:free=size`, started
/// from the file-shaped ellipse's converged fit of the bundled trial
/// (tests/data/hidden/base): the identified semi-axis moves from the file's towards the
/// hidden one and ends within 20 % of it.
///
/// Measured: 25 iterations, J 34.88 → 27.01, a = 0.1817 m against the hidden 0.1678 m
/// (file 0.1525 m; 8.3 % off), while b ran from 0.0403 m to its upper bound 0.0524 m
/// (+30 %): with both semi-axes free the two trade off, so the size is identified only
/// roughly.
#[test]
fn freeing_the_size_recovers_a_longer_ellipse() {
    use footfall::sqp::HessianMode;
    use footfall::workflows::track::{tracking_sqp_settings, TrackRequest, TrackingProblem};
    let dir = root().join("tests/data/hidden/foot_geometry");
    let truth = semi_axis(&dir.join("hidden_foot.json"));
    let file = semi_axis(&root().join("models/feet/ellipse.json"));
    assert!((truth / file - 1.1).abs() < 1e-12);
    let mut run = TrackRequest::new("ellipse").run;
    run.model = root().join("models/opensim_subject01.json");
    run.foot = root()
        .join("models/feet/ellipse.json")
        .to_str()
        .unwrap()
        .into();
    run.phases = root().join("phases/ellipse_walk.json");
    run.data = Some(dir.join("synthetic.csv"));
    let mut prob = TrackingProblem::build(
        &run,
        &[EffectSpec::parse_cli("foot_geometry:free=size").unwrap()],
    )
    .unwrap();
    prob.refine = false;
    let start: footfall::problems::evaluation::GaitSolution = serde_json::from_str(
        &std::fs::read_to_string(root().join("tests/data/hidden/base/solution.json")).unwrap(),
    )
    .unwrap();
    prob.setup.start_from(&start).unwrap();
    let t = std::time::Instant::now();
    let settings = tracking_sqp_settings(1e-4, 40, None, HessianMode::Exact, None);
    let (res, sol) = prob.solve(&settings, &crate::common::printed()).unwrap();
    eprintln!(
        "{} iterations, {:.0} s, J {:.6} → {:.6}, KKT {:.1e}, {}; a {:.5} m (file {file:.5}, hidden {truth:.5}), b {:.5} m",
        res.history.len() - 1,
        t.elapsed().as_secs_f64(),
        res.history[0].objective,
        res.objective,
        res.kkt,
        res.status,
        sol.theta[0],
        sol.theta[1],
    );
    let a = sol.theta[0];
    assert!(
        a > file && (a / truth - 1.0).abs() < 0.2,
        "a: identified {a}, hidden {truth}, file {file}"
    );
}

/// Regenerates tests/data/hidden/foot_geometry (minutes): the bundled trial tracked with
/// the hidden foot ([`hidden_foot`], kept as `hidden_foot.json`) from the file-shaped
/// ellipse's fit (tests/data/hidden/base), 40 SQP iterations — the truth need only be a
/// walk of that model, not the optimum of the bundled trial; then `synth` from it (100 Hz,
/// the default noise, seed 1).
#[test]
#[ignore = "regenerates test data (minutes): cargo test --test suite -- --ignored foot_geometry::"]
fn make_foot_geometry_trial() {
    use footfall::runfolder::RunFolder;
    use footfall::sqp::HessianMode;
    use footfall::workflows::{self, track::tracking_sqp_settings};
    std::env::set_current_dir(root()).unwrap();
    let dest = root().join("tests/data/hidden/foot_geometry");
    std::fs::create_dir_all(&dest).unwrap();
    let foot = dest.join("hidden_foot.json");
    std::fs::write(&foot, hidden_foot()).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let progress = crate::common::printed();
    let truth = tmp.path().join("truth");
    let mut req = workflows::track::TrackRequest::new(foot.to_str().unwrap());
    req.run.phases = PathBuf::from("phases/ellipse_walk.json");
    req.init = Some(root().join("tests/data/hidden/base/solution.json"));
    req.check_points = false;
    req.sqp = tracking_sqp_settings(1e-4, 40, None, HessianMode::Exact, None);
    workflows::track::track(&req, RunFolder::create(&truth, false).unwrap(), &progress).unwrap();
    let out = tmp.path().join("synth");
    workflows::synth::run(
        &workflows::synth::SynthRequest::new(truth.clone(), out.clone()),
        &progress,
    )
    .unwrap();
    for f in ["synthetic.csv", "synthetic_meta.json", "truth.json"] {
        std::fs::copy(out.join(f), dest.join(f)).unwrap();
    }
    std::fs::copy(
        truth.join("solution.json"),
        dest.join("truth_solution.json"),
    )
    .unwrap();
}
