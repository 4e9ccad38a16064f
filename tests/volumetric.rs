//! The sagittal volumetric contact law (`model::volumetric`) against independent truth:
//! the penetrated area, its centroid and the plate CoP from a direct numerical
//! integration of the ellipse's vertical chords below the ground line, and the exact
//! derivatives (AD) against central differences, for circles and ellipses at several
//! depths and angles, down to first contact.

use footfall::model::volumetric::{disc_segment, penetration, VolumetricLaw};
use footfall::model::Scalar;
use num_dual::{Dual2_64, Dual64, DualNum};
use std::f64::consts::PI;

/// Area, centroid x and centroid y of the part of the ellipse (centre `c`, world angle
/// `alpha`, semi-axes `ab`) below `g`, by composite Simpson integration over x of the
/// vertical chord, from the ellipse's implicit equation (nothing of the affine-disc
/// formulas under test).
fn integrated(c: [f64; 2], alpha: f64, (a, b): (f64, f64), g: f64) -> (f64, f64, f64) {
    let (s, co) = alpha.sin_cos();
    // M⁻¹ = R diag(1/a², 1/b²) Rᵀ
    let q11 = co * co / (a * a) + s * s / (b * b);
    let q12 = s * co * (1.0 / (a * a) - 1.0 / (b * b));
    let q22 = s * s / (a * a) + co * co / (b * b);
    // half width of the ellipse in x
    let w = (a * a * co * co + b * b * s * s).sqrt();
    let chord = |x: f64| -> (f64, f64) {
        let dx = x - c[0];
        let disc = q12 * q12 * dx * dx - q22 * (q11 * dx * dx - 1.0);
        if disc <= 0.0 {
            return (0.0, 0.0);
        }
        let r = disc.sqrt();
        let lo = c[1] + (-q12 * dx - r) / q22;
        let hi = (c[1] + (-q12 * dx + r) / q22).min(g);
        if hi <= lo {
            (0.0, 0.0)
        } else {
            (hi - lo, 0.5 * (hi + lo))
        }
    };
    let n = 400_000; // even
    let h = 2.0 * w / n as f64;
    let (mut area, mut mx, mut my) = (0.0, 0.0, 0.0);
    for k in 0..=n {
        let x = c[0] - w + h * k as f64;
        let wt = if k == 0 || k == n {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let (len, mid) = chord(x);
        area += wt * len;
        mx += wt * len * x;
        my += wt * len * mid;
    }
    let f = h / 3.0;
    (area * f, mx / area, my / area)
}

/// The shapes tested: a circle and two ellipses (flat and tilted), each as (a, b, alpha).
const SHAPES: [(f64, f64, f64); 4] = [
    (0.0487, 0.0487, 0.3),
    (0.1525, 0.0403, 0.0),
    (0.1525, 0.0403, 0.25),
    (0.1525, 0.0403, -1.1),
];

fn half_height(a: f64, b: f64, alpha: f64) -> f64 {
    (a * a * alpha.sin().powi(2) + b * b * alpha.cos().powi(2)).sqrt()
}

#[test]
fn area_and_centroid_match_a_direct_integration_of_the_chords() {
    let g = -0.0075;
    for &(a, b, alpha) in &SHAPES {
        let h = half_height(a, b, alpha);
        // normalised depths from just after first contact to past the centre
        for s in [1e-3, 0.02, 0.1, 0.25, 0.5, 1.0, 1.4, 1.9] {
            let c = [0.31, g + h * (1.0 - s)];
            let p = penetration(c, alpha, (a, b), g).expect("penetrates");
            let (area, cx, cy) = integrated(c, alpha, (a, b), g);
            assert!(
                (p.area - area).abs() <= 2e-7 * area,
                "area {a} {b} {alpha} s={s}: formula {} vs integrated {area}",
                p.area
            );
            // centroid to 1e-7 m (a micrometre of a 30 cm foot is far below any CoP error)
            for (got, want, what) in [(p.centroid[0], cx, "x"), (p.centroid[1], cy, "y")] {
                assert!(
                    (got - want).abs() <= 1e-7,
                    "centroid {what} {a} {b} {alpha} s={s}: formula {got} vs integrated {want}"
                );
            }
            assert!((p.depth - s * h).abs() < 1e-15);
        }
    }
}

#[test]
fn clear_of_the_ground_there_is_no_contact_and_fully_sunk_is_the_whole_area() {
    let g = 0.0;
    let (a, b, alpha) = (0.1525, 0.0403, 0.2);
    let h = half_height(a, b, alpha);
    assert!(penetration([0.0, g + h + 1e-12], alpha, (a, b), g).is_none());
    assert!(penetration([0.0, g + h], alpha, (a, b), g).is_none());
    let sunk = penetration([0.0, g - h - 1e-3], alpha, (a, b), g).unwrap();
    assert!((sunk.area - PI * a * b).abs() < 1e-15);
    // the disc segment: half the disc at the centre, centroid 4/(3π) of the radius deep
    let (half, tau) = disc_segment(1.0);
    assert!((half - PI / 2.0).abs() < 1e-15);
    assert!((tau - 4.0 / (3.0 * PI)).abs() < 1e-15);
}

#[test]
fn first_contact_keeps_full_precision_and_finite_derivatives() {
    // near first contact the segment's area is (4√2/3) s^{3/2} (1 − 3s/20 + O(s²)) of the
    // unit disc and its centroid sits at the lowest point (τ → 1 − 3s/5 + …)
    for s in [1e-12, 1e-9, 1e-6, 1e-4] {
        let (area, tau) = disc_segment(s);
        let leading = 4.0 * 2f64.sqrt() / 3.0 * s.powf(1.5);
        let series = leading * (1.0 - 3.0 * s / 20.0);
        assert!(
            (area - series).abs() <= 1e-12 * series + 0.05 * leading * s * s,
            "s={s}: {area} vs {series}"
        );
        assert!(
            (tau - (1.0 - 0.6 * s)).abs() < 1e-9 + s * s,
            "s={s}: τ={tau}"
        );
        // first and second derivatives exist and are what the series says:
        // S' = 2√2 s^{1/2}(1 − …), S'' = √2 s^{−1/2}(1 − …)
        let d = disc_segment(Dual2_64::from_re(s).derivative()).0;
        let d1 = 2.0 * 2f64.sqrt() * s.sqrt();
        let d2 = 2f64.sqrt() / s.sqrt();
        assert!((d.v1 - d1).abs() <= 1e-3 * d1, "s={s}: S'={}", d.v1);
        assert!(
            (d.v2 - d2).abs() <= 1e-3 * d2,
            "s={s}: S''={} vs {d2}",
            d.v2
        );
    }
    // the force's derivative with respect to height vanishes as contact begins (C¹ onset)
    let law = law();
    let (a, b) = (0.1525, 0.0403);
    let depth_grad = |depth: f64| {
        let cy = Dual64::from_re(b - depth).derivative();
        let f = law
            .force(
                [Dual64::c(0.0), cy],
                Dual64::c(0.0),
                (a, b),
                [Dual64::c(0.0); 2],
                Dual64::c(0.0),
                Dual64::c(0.0),
            )
            .unwrap();
        assert!(f.force[1].re.is_finite() && f.force[1].eps.is_finite());
        f.force[1].eps
    };
    // dF/dδ = k ab S'(s)/h ∝ √δ: a thousandth of the depth, √1000 less steep
    let (g9, g6) = (depth_grad(1e-9), depth_grad(1e-6));
    assert!(
        (g9 / g6 - 1e-3f64.sqrt()).abs() < 1e-4,
        "dF/dy at onset: {g9} at 1 nm, {g6} at 1 µm"
    );
}

fn law() -> VolumetricLaw {
    VolumetricLaw {
        stiffness: 5e5,
        damping: 0.8,
        mu_dynamic: 0.5,
        mu_static: 0.8,
        transition_velocity: 0.1,
    }
}

#[test]
fn friction_is_odd_smooth_and_reaches_its_coefficients() {
    let law = law();
    for v in [1e-4f64, 0.01, 0.1, 0.5, 3.0] {
        let m = law.friction_coefficient(v);
        assert!((m + law.friction_coefficient(-v)).abs() < 1e-15);
        assert!(m > 0.0);
    }
    // at v_t: μ_d tanh 4 + (μ_s − μ_d); far beyond: μ_d
    let at_vt = law.friction_coefficient(0.1f64);
    assert!((at_vt - (0.5 * 4f64.tanh() + 0.3)).abs() < 1e-12);
    assert!((law.friction_coefficient(100.0f64) - 0.5).abs() < 1e-6);
    assert_eq!(law.friction_coefficient(0.0f64), 0.0);
    for bad in [
        VolumetricLaw {
            stiffness: -1.0,
            ..law
        },
        VolumetricLaw {
            mu_static: 0.1,
            ..law
        },
        VolumetricLaw {
            transition_velocity: 0.0,
            ..law
        },
        VolumetricLaw {
            damping: f64::NAN,
            ..law
        },
    ] {
        assert!(bad.check().is_err());
    }
    assert!(law.check().is_ok());
}

/// The force, point and CoP as one vector of the inputs
/// (cx, cy, α, vx, vy, ω).
fn outputs<S: Scalar>(law: &VolumetricLaw, ab: (f64, f64), g: f64, x: [S; 6]) -> [S; 5] {
    let f = law
        .force([x[0], x[1]], x[2], ab, [x[3], x[4]], x[5], S::c(g))
        .expect("in contact");
    [f.force[0], f.force[1], f.point[0], f.point[1], f.cop_x]
}

#[test]
fn force_centroid_and_cop_derivatives_match_central_differences() {
    let law = law();
    let g = -0.0075;
    for &(a, b, alpha) in &SHAPES {
        let h = half_height(a, b, alpha);
        for s in [1e-4, 0.05, 0.3, 1.2] {
            let x0 = [0.2, g + h * (1.0 - s), alpha, 0.03, -0.12, 0.7];
            for j in 0..6 {
                let xd: [Dual64; 6] = std::array::from_fn(|i| {
                    let v = Dual64::from_re(x0[i]);
                    if i == j {
                        v.derivative()
                    } else {
                        v
                    }
                });
                let ad = outputs(&law, (a, b), g, xd);
                // step small against the depth so that the difference stays in contact
                let e = match j {
                    1 => 1e-4 * s * h,
                    2 => 1e-4 * s.min(1.0) * 1e-2,
                    _ => 1e-6,
                };
                let mut xp = x0;
                let mut xm = x0;
                xp[j] += e;
                xm[j] -= e;
                let fp = outputs(&law, (a, b), g, xp);
                let fm = outputs(&law, (a, b), g, xm);
                for o in 0..5 {
                    let fd = (fp[o] - fm[o]) / (2.0 * e);
                    // truncation error of the difference, and its rounding error
                    let noise = 1e-13 * fp[o].abs().max(1.0) / e;
                    let scale = fd.abs().max(ad[o].eps.abs());
                    assert!(
                        (ad[o].eps - fd).abs() <= 1e-5 * scale + noise,
                        "shape ({a}, {b}, {alpha}) s={s}: d out{o}/d in{j}: AD {} vs FD {fd}",
                        ad[o].eps
                    );
                }
            }
            // the law itself: F_n = k A (1 + a_V v_cn), F_t = −μ(v) F_n, at the centroid
            let f = law
                .force([x0[0], x0[1]], x0[2], (a, b), [x0[3], x0[4]], x0[5], g)
                .unwrap();
            let p = f.penetration;
            let r = [p.centroid[0] - x0[0], p.centroid[1] - x0[1]];
            let v = [x0[3] - x0[5] * r[1], x0[4] + x0[5] * r[0]];
            let normal = law.stiffness * p.area * (1.0 - law.damping * v[1]);
            assert!((f.force[1] - normal).abs() <= 1e-12 * normal);
            assert!((f.force[0] + law.friction_coefficient(v[0]) * normal).abs() <= 1e-12 * normal);
            // plate CoP: no moment of the force about (cop_x, g)
            let m = (p.centroid[0] - f.cop_x) * f.force[1] - (p.centroid[1] - g) * f.force[0];
            assert!(m.abs() <= 1e-12 * normal, "moment about the CoP {m}");
        }
    }
}

/// A torque-driven body (no torques) on two volumetric circles (the double-circle foot's
/// heel and forefoot) with `damping` and no friction, dropped from the shipped step's
/// initial state: its samples and the model.
fn drop_on_circles(
    damping: f64,
) -> (
    footfall::model::GaitModel,
    footfall::simulate::SimulationResult,
) {
    use footfall::controls::ControlTable;
    use footfall::model::GaitModel;
    use footfall::phases::PhaseSequence;
    use footfall::simulate::{simulate, SimulationSettings};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let foot = dir.path().join("foot.json");
    let law = format!(
        r#"{{"type": "volumetric", "stiffness": 1e6, "damping": {damping}, "mu_dynamic": 0.0, "mu_static": 0.0, "transition_velocity": 0.1}}"#
    );
    std::fs::write(
        &foot,
        format!(
            r#"{{"name": "volumetric_circles", "primitives": [
                {{"name": "heel", "shape": {{"type": "circle", "centre": [-0.0619, -0.0664], "radius": 0.0487}}, "contact": {law}}},
                {{"name": "forefoot", "shape": {{"type": "circle", "centre": [0.1197, -0.0656], "radius": 0.0746}}, "contact": {law}}}
            ]}}"#
        ),
    )
    .unwrap();
    let model = GaitModel::load(&root.join("models/opensim_subject01_torque.json"), &foot).unwrap();
    let seq = PhaseSequence::load(&root.join("phases/sim_volumetric_ellipse_step.json")).unwrap();
    let sets = seq.resolve(&model, std::path::Path::new("<test>")).unwrap();
    let init = seq.initial_state.clone().unwrap();
    let mut x0 = init.q.clone();
    x0.extend(&init.qd);
    let controls = ControlTable::constant(model.control_names(), vec![0.0; model.nu()]);
    let mut settings = SimulationSettings::default();
    settings.integrator.rtol = 1e-11;
    settings.integrator.atol = 1e-11;
    let res = simulate(
        &model,
        &seq,
        &sets,
        &x0,
        &controls,
        &model.theta0(),
        &settings,
    )
    .unwrap();
    (model, res)
}

/// Elastic energy of a circle (centre `c`, radius `r`) pressed into the ground at `g`:
/// the Winkler foundation's $\frac{k}{2}\int d(x)^2\,dx$ over its vertical chords below the
/// ground, integrated numerically. For a circle the volumetric force (k·area, vertical,
/// through the centre's x) is this energy's gradient.
fn circle_energy(k: f64, c: [f64; 2], r: f64, g: f64) -> f64 {
    let n = 20_000;
    let h = 2.0 * r / n as f64;
    let mut sum = 0.0;
    for i in 0..=n {
        let x = -r + h * i as f64;
        let half = (r * r - x * x).max(0.0).sqrt();
        let d = (g.min(c[1] + half) - (c[1] - half)).max(0.0);
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        sum += w * d * d;
    }
    0.5 * k * sum * h / 3.0
}

/// Kinetic + gravitational + elastic energy of every sample.
fn energies(
    model: &footfall::model::GaitModel,
    res: &footfall::simulate::SimulationResult,
) -> Vec<f64> {
    let nq = model.nq();
    let theta = model.theta0();
    let g = -0.0075; // the torque model's ground height
    res.samples
        .iter()
        .map(|s| {
            let (q, qd) = (&s.x[..nq], &s.x[nq..2 * nq]);
            let (kinetic, potential) = model.energy(q, qd, &theta);
            let elastic: f64 = model
                .contacts
                .iter()
                .map(|c| match c.shape {
                    footfall::model::geometry::Shape::Circle { centre, radius } => {
                        circle_energy(1e6, model.body_point(c.body, centre, q), radius, g)
                    }
                    _ => unreachable!(),
                })
                .sum();
            kinetic + potential + elastic
        })
        .collect()
}

#[test]
fn volumetric_circles_without_damping_or_friction_conserve_energy_and_with_damping_dissipate() {
    let (model, res) = drop_on_circles(0.0);
    // the feet do land: some sample has a volumetric force of several hundred newtons
    let peak = res
        .samples
        .iter()
        .flat_map(|s| s.contact.volumetric.iter().map(|v| v.force[1]))
        .fold(0.0, f64::max);
    assert!(peak > 300.0, "peak volumetric force {peak} N");
    let e = energies(&model, &res);
    let drift = e.iter().map(|v| (v - e[0]).abs()).fold(0.0, f64::max);
    eprintln!(
        "energy {:.6} J, largest drift {drift:.3e} J, peak force {peak:.1} N",
        e[0]
    );
    assert!(drift < 1e-4, "energy drifts by {drift} J");

    // with damping the contact dissipates: the energy never rises (beyond the
    // integration noise measured above) and ends lower
    let (model, res) = drop_on_circles(0.9);
    let e = energies(&model, &res);
    for w in e.windows(2) {
        assert!(
            w[1] <= w[0] + 1e-4,
            "energy rises from {} to {} J",
            w[0],
            w[1]
        );
    }
    assert!(
        e[e.len() - 1] < e[0] - 1.0,
        "{} J → {} J",
        e[0],
        e[e.len() - 1]
    );
}

#[test]
fn a_bad_volumetric_foot_is_refused_naming_the_field() {
    use footfall::model::GaitModel;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let law = r#""contact": {"type": "volumetric", "stiffness": STIFF, "damping": 0.9, "mu_dynamic": 0.35, "mu_static": 0.4, "transition_velocity": 0.1}"#;
    let cases = [
        (
            r#"{"type": "point", "position": [0.0, -0.08]}"#,
            "1e6",
            "primitives[0].contact",
            "a point has no area",
        ),
        (
            r#"{"type": "circle", "centre": [0.0, -0.06], "radius": 0.05}"#,
            "-1e6",
            "primitives[0].contact.stiffness",
            "must be a positive number of N/m²",
        ),
    ];
    for (shape, stiffness, field, reason) in cases {
        let foot = dir.path().join("foot.json");
        std::fs::write(
            &foot,
            format!(
                r#"{{"name": "f", "primitives": [{{"name": "p", "shape": {shape}, {}}}]}}"#,
                law.replace("STIFF", stiffness)
            ),
        )
        .unwrap();
        let err = GaitModel::load(&root.join("models/opensim_subject01.json"), &foot)
            .unwrap_err()
            .to_string();
        assert!(err.contains(field) && err.contains(reason), "{err}");
        assert!(err.contains("foot.json"), "{err}");
    }
    // a volumetric primitive is never a constraint: a phase file that lists it is refused
    let model = GaitModel::load(
        &root.join("models/opensim_subject01.json"),
        &root.join("models/feet/volumetric_ellipse.json"),
    )
    .unwrap();
    let err = model
        .constraint_set("stance", &[("r.sole", true)])
        .unwrap_err()
        .to_string();
    assert!(err.contains("'r.sole' is volumetric"), "{err}");
}

/// Exact derivatives of the dynamics with the volumetric ellipse foot (the MTG model, both
/// feet pressing into the ground, one sliding): the state columns of the dynamics
/// Jacobian (forward AD) against central differences.
#[test]
fn volumetric_dynamics_jacobian_matches_central_differences() {
    use footfall::model::GaitModel;
    use footfall::phases::PhaseSequence;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let m = GaitModel::load(
        &root.join("models/opensim_subject01.json"),
        &root.join("models/feet/volumetric_ellipse.json"),
    )
    .unwrap();
    let seq = PhaseSequence::load(&root.join("phases/sim_volumetric_ellipse_step.json")).unwrap();
    let set = seq.resolve(&m, std::path::Path::new("<test>")).unwrap()[0].clone();
    let init = seq.initial_state.unwrap();
    let (nx, nu, nq) = (m.nx(), m.nu(), m.nq());
    let mut x = init.q.clone();
    x.extend(&init.qd);
    x.extend(vec![0.2; m.na()]);
    // lower the body until the left foot touches too
    x[1] -= 0.01;
    let theta = m.theta0();
    let u = vec![0.3; nu];
    let f = |x: &[f64]| {
        let mut xd = vec![0.0; nx];
        let mut lam = vec![0.0; set.rows.len()];
        let mut rep = footfall::model::ContactReport::default();
        m.dynamics::<f64>(&set, x, &u, &theta, &mut xd, &mut lam, Some(&mut rep))
            .unwrap();
        (xd, rep)
    };
    let (_, rep) = f(&x);
    assert!(
        rep.volumetric.iter().any(|v| v.force[1] > 100.0),
        "the feet press into the ground: {:?}",
        rep.volumetric
    );
    let mut xdot = vec![0.0; nx];
    let mut jac = vec![0.0; nx * (nx + nu + theta.len())];
    m.dynamics_jacobian(&set, &x, &u, &theta, &mut xdot, &mut jac)
        .unwrap();
    let mut worst = 0.0f64;
    for c in 0..2 * nq {
        let h = 1e-6;
        let (mut a, mut b) = (x.clone(), x.clone());
        a[c] += h;
        b[c] -= h;
        let (fa, fb) = (f(&a).0, f(&b).0);
        for r in 0..nx {
            let fd = (fa[r] - fb[r]) / (2.0 * h);
            worst = worst.max((fd - jac[c * nx + r]).abs() / (1.0 + fd.abs()));
        }
    }
    assert!(worst < 1e-5, "AD vs central differences: {worst:e}");
}

#[test]
fn sinking_whole_keeps_finite_derivatives() {
    // mirror image of first contact: the area lacks (4√2/3) ε^{3/2} of the disc at depth
    // 2 − ε, and its derivatives stay finite
    for eps in [1e-12, 1e-9, 1e-6, 1e-3] {
        let (area, tau) = disc_segment(2.0 - eps);
        let missing = 4.0 * 2f64.sqrt() / 3.0 * eps.powf(1.5) * (1.0 - 3.0 * eps / 20.0);
        assert!(
            (PI - area - missing).abs() <= 0.05 * missing * eps * eps + 4e-16,
            "ε={eps}: {area}"
        );
        assert!(tau.abs() < 1e-3 && tau.is_finite());
        let d = disc_segment(Dual2_64::from_re(2.0 - eps).derivative()).0;
        assert!(d.v1.is_finite() && d.v2.is_finite(), "ε={eps}: {d:?}");
        assert!((d.v1 - 2.0 * 2f64.sqrt() * eps.sqrt()).abs() <= 1e-3 * d.v1 + 1e-15);
    }
    // the two branches meet at the centre: half the disc, continuous derivative
    let below = disc_segment(Dual64::from_re(1.0 - 1e-12).derivative());
    let above = disc_segment(Dual64::from_re(1.0 + 1e-12).derivative());
    assert!((below.0.re - above.0.re).abs() < 1e-11);
    assert!((below.0.eps - 2.0).abs() < 1e-9 && (above.0.eps - 2.0).abs() < 1e-9);
}

/// The tracking problem of a foot whose primitives are all volumetric: one continuous
/// phase spans the measured half cycle (no contact changes to match), and both feet's
/// measured forces are targets at every node, the swing foot's (zero) included.
#[test]
fn a_compliant_foot_tracks_one_phase_over_the_half_cycle_with_both_feet_loaded() {
    use footfall::data::GaitData;
    use footfall::model::GaitModel;
    use footfall::phases::{Phase, PhaseSequence};
    use footfall::problems::track::TrackingSetup;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let data = GaitData::bundled(root).unwrap();
    let model = GaitModel::load(
        &root.join("models/opensim_subject01.json"),
        &root.join("models/feet/volumetric_ellipse.json"),
    )
    .unwrap();
    let p = root.join("phases/volumetric_ellipse_walk.json");
    let seq = PhaseSequence::load(&p).unwrap();
    let sets = seq.resolve(&model, &p).unwrap();
    assert!(sets.iter().all(|s| s.rows.is_empty()), "no constraint rows");
    let setup = TrackingSetup::new(&model, &seq, &sets, &data).unwrap();
    let (t0, t1) = setup.window;
    let Phase::Continuous { duration, .. } = &setup.seq.phases[0] else {
        panic!("one continuous phase")
    };
    assert!((duration.value() - (t1 - t0)).abs() < 1e-12);
    // the same half cycle as the rigid ellipse's (left to right heel strike)
    let rigid = GaitModel::load(
        &root.join("models/opensim_subject01.json"),
        &root.join("models/feet/ellipse.json"),
    )
    .unwrap();
    let rp = root.join("phases/ellipse_walk.json");
    let rseq = PhaseSequence::load(&rp).unwrap();
    let rsets = rseq.resolve(&rigid, &rp).unwrap();
    let r = TrackingSetup::new(&rigid, &rseq, &rsets, &data).unwrap();
    assert_eq!(setup.window, r.window);
    let targets = &setup.targets[0];
    assert_eq!(targets.len(), 26);
    let mut swing = 0;
    for t in targets {
        let (fx, fy) = (t.feet[0].unwrap(), t.feet[1].unwrap());
        assert!(fx.1.is_finite() && fy.1.is_finite());
        swing += usize::from(fx.1.abs() < 1.0 || fy.1.abs() < 1.0);
    }
    // the right foot swings through much of the half cycle: its target is zero there
    assert!(swing >= 10, "{swing} nodes with an unloaded foot");
}
