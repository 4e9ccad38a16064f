//! Muscle-torque generators (seed eq. 9–12) and de Leva (1996) segment parameters.
//!
//! Run with `cargo test --test quick actuators:: -- --nocapture` to see the parameter tables
//! (peak torques, ω_max, damping coefficients, seed-subject segments).

use footfall::model::actuators::{
    self, damping_coefficient, mtg_torque, torque_velocity, ActivationDynamics, Joint,
    JointActuatorSet, MtgParams, MuscleSide, ANDERSON2007_YOUNG_FEMALE, ANDERSON2007_YOUNG_MALE,
    ANDERSON_GRAVITY, MILLARD2019_GYMNAST,
};
use footfall::model::anthropometry::{
    self, de_leva_hat_parts, de_leva_planar, de_leva_planar_using, RadiusColumn, Sex,
    DE_LEVA_FEMALE, DE_LEVA_MALE,
};
use footfall::model::Scalar;
use num_dual::{Dual2_64, Dual64, DualNum};

const SIDES: [MuscleSide; 2] = [MuscleSide::Flexor, MuscleSide::Extensor];

fn sets() -> Vec<(&'static str, JointActuatorSet)> {
    vec![
        (
            "anderson2007_young_male",
            JointActuatorSet::anderson2007_young_male(),
        ),
        (
            "anderson2007_young_female(60kg,1.65m)",
            JointActuatorSet::anderson2007_young_female_for(60.0, 1.65),
        ),
        (
            "millard2019_gymnast",
            JointActuatorSet::millard2019_gymnast(),
        ),
    ]
}

/// Derivative of a scalar function by forward-mode AD.
fn ad<F: Fn(Dual64) -> Dual64>(f: F, x: f64) -> f64 {
    f(Dual64::from_re(x).derivative()).eps
}

/// Second derivative by nested dual numbers.
fn ad2<F: Fn(Dual2_64) -> Dual2_64>(f: F, x: f64) -> f64 {
    f(Dual2_64::from_re(x).derivative()).v2
}

fn central_fd<F: Fn(f64) -> f64>(f: F, x: f64, h: f64) -> f64 {
    (f(x + h) - f(x - h)) / (2.0 * h)
}

fn assert_deriv(name: &str, ad: f64, fd: f64, rel: f64, abs_floor: f64) {
    let err = (ad - fd).abs();
    assert!(
        err <= rel * ad.abs().max(fd.abs()) + abs_floor,
        "{name}: AD {ad:.12e} vs FD {fd:.12e} (err {err:.3e})"
    );
}

fn angle_grid(p: &MtgParams) -> Vec<f64> {
    (-30..=30)
        .map(|i| p.optimal_angle + 0.05 * i as f64 + 0.0123)
        .collect()
}

fn omega_grid(p: &MtgParams) -> Vec<f64> {
    // −2 ω_max … 2 ω_max incl. points inside the ω = 0 blend and near ±ω_max
    let mut v: Vec<f64> = (-40..=40).map(|i| 0.05 * i as f64 + 0.0071).collect();
    v.extend([0.0, 1e-3, -1e-3, 0.02, -0.02, 0.99, -0.99, 1.0, -1.0]);
    v.into_iter().map(|x| x * p.omega_max).collect()
}

// ---------------------------------------------------------------------------------------
// Derivatives: AD == central finite differences; second derivatives exist (C2)
// ---------------------------------------------------------------------------------------

#[test]
fn curve_derivatives_match_finite_differences() {
    let mut checked = 0;
    for (_, set) in sets() {
        for p in &set.mtgs {
            for th in angle_grid(p) {
                let f = |x: f64| actuators::active_torque_angle(p, x);
                let d_ad = ad(|x| actuators::active_torque_angle(p, x), th);
                let d_fd = central_fd(f, th, 1e-6);
                assert_deriv("f^A'", d_ad, d_fd, 1e-7, 1e-9);
                // second derivative vs FD of the AD first derivative
                let d2_ad = ad2(|x| actuators::active_torque_angle(p, x), th);
                let d2_fd = central_fd(
                    |x| ad(|y| actuators::active_torque_angle(p, y), x),
                    th,
                    1e-6,
                );
                assert_deriv("f^A''", d2_ad, d2_fd, 1e-6, 1e-7);
                checked += 2;
            }
            for w in omega_grid(p) {
                let h = 1e-6 * p.omega_max;
                let d_ad = ad(|x| torque_velocity(p, x), w);
                let d_fd = central_fd(|x| torque_velocity(p, x), w, h);
                assert_deriv("f^V'", d_ad, d_fd, 1e-7, 1e-9 / p.omega_max);
                let d2_ad = ad2(|x| torque_velocity(p, x), w);
                let d2_fd = central_fd(|x| ad(|y| torque_velocity(p, y), x), w, h);
                assert_deriv(
                    "f^V''",
                    d2_ad,
                    d2_fd,
                    1e-5,
                    1e-7 / (p.omega_max * p.omega_max),
                );
                checked += 2;
            }
            // full MTG torque w.r.t. a, θ and ω at a few points
            for (a, th, w) in [
                (0.3, p.optimal_angle + 0.2, 0.1 * p.omega_max),
                (0.9, p.optimal_angle - 0.4, -0.3 * p.omega_max),
                (0.05, p.optimal_angle, 0.0),
            ] {
                let t = p.max_isometric_torque;
                let da = ad(|x| mtg_torque(p, x, Dual64::c(th), Dual64::c(w)), a);
                let dth = ad(|x| mtg_torque(p, Dual64::c(a), x, Dual64::c(w)), th);
                let dw = ad(|x| mtg_torque(p, Dual64::c(a), Dual64::c(th), x), w);
                assert_deriv(
                    "dτ/da",
                    da,
                    central_fd(|x| mtg_torque(p, x, th, w), a, 1e-6),
                    1e-7,
                    1e-9 * t,
                );
                assert_deriv(
                    "dτ/dθ",
                    dth,
                    central_fd(|x| mtg_torque(p, a, x, w), th, 1e-6),
                    1e-7,
                    1e-9 * t,
                );
                assert_deriv(
                    "dτ/dω",
                    dw,
                    central_fd(|x| mtg_torque(p, a, th, x), w, 1e-6 * p.omega_max),
                    1e-7,
                    1e-9 * t,
                );
                checked += 3;
            }
        }
        // net joint torque (eq. 11) w.r.t. ω includes the damping
        for j in Joint::ALL {
            let (af, ae, th, w) = (0.4, 0.6, 0.1, 1.3);
            let d_ad = ad(
                |x| set.joint_torque(j, Dual64::c(af), Dual64::c(ae), Dual64::c(th), x),
                w,
            );
            let d_fd = central_fd(|x| set.joint_torque(j, af, ae, th, x), w, 1e-6);
            assert_deriv("dτ_joint/dω", d_ad, d_fd, 1e-7, 1e-7);
            checked += 1;
        }
    }
    println!("derivative checks passed: {checked}");
}

// ---------------------------------------------------------------------------------------
// Curve properties
// ---------------------------------------------------------------------------------------

#[test]
fn active_torque_angle_peaks_at_one() {
    for (name, set) in sets() {
        for p in &set.mtgs {
            let f = |x: f64| actuators::active_torque_angle(p, x);
            assert!(
                (f(p.optimal_angle) - 1.0).abs() < 1e-14,
                "{name}: peak != 1"
            );
            assert!(ad(|x| actuators::active_torque_angle(p, x), p.optimal_angle).abs() < 1e-12);
            // scan ±4 rad: 0 <= f <= 1, unimodal
            let mut prev = f(p.optimal_angle);
            for i in 1..=4000 {
                let d = 1e-3 * i as f64;
                for s in [1.0, -1.0] {
                    let v = f(p.optimal_angle + s * d);
                    assert!((0.0..=1.0).contains(&v), "{name}: f^A out of [0,1]: {v}");
                }
                let v = f(p.optimal_angle + d);
                assert!(v <= prev + 1e-15, "{name}: f^A not unimodal");
                prev = v;
            }
            // Anderson's cosine: f^A follows cos(C2 Δθ) close to the optimum and is small
            // at the nominal zero crossing ±π/(2 C2) (smoothed kink)
            if let actuators::ActiveTorqueAngle::Anderson2007Cosine { angle_scale } = p.active_curve
            {
                for k in [0.1, 0.3, 0.5, 0.8] {
                    let d = k * std::f64::consts::FRAC_PI_2 / angle_scale;
                    let err = (f(p.optimal_angle + d) - (angle_scale * d).cos()).abs();
                    // smooth-positive-part offset ≈ ε²/(4 cos) dominates: 1.9e-3 at k = 0.8
                    assert!(
                        err < 2.5e-3,
                        "{name}: f^A deviates from cos by {err} at {k}"
                    );
                }
                let z = f(p.optimal_angle + std::f64::consts::FRAC_PI_2 / angle_scale);
                assert!(z > 0.0 && z < 0.03, "f^A at Anderson's zero crossing: {z}");
            }
        }
    }
}

#[test]
fn torque_velocity_shape() {
    for (name, set) in sets() {
        for p in &set.mtgs {
            let s = p.torque_sign();
            let fv = |x_norm: f64| torque_velocity(p, s * x_norm * p.omega_max); // x = shortening/ω_max
            assert!((fv(0.0) - 1.0).abs() < 1e-14, "{name}: f^V(0) != 1");
            let at_max = fv(1.0);
            assert!(
                (0.0..0.02).contains(&at_max),
                "{name}: f^V(ω_max) = {at_max}"
            );
            assert!(
                (fv(0.5) - p.tv_at_half_omega_max).abs() < 0.01,
                "{name}: f^V(ω_max/2) = {} vs {}",
                fv(0.5),
                p.tv_at_half_omega_max
            );
            assert!(
                (fv(-1.0) - p.tv_max_eccentric).abs() < 0.01,
                "{name}: f^V(−ω_max) = {} vs {}",
                fv(-1.0),
                p.tv_max_eccentric
            );
            // monotone decreasing in shortening velocity, > 1 eccentric, bounded, >= 0
            let plateau = fv(-1e6);
            assert!(plateau > p.tv_max_eccentric && plateau < p.tv_max_eccentric + 0.1);
            let mut prev = f64::INFINITY;
            for i in -3000..=3000 {
                let x = 1e-3 * i as f64;
                let v = fv(x);
                assert!(v <= prev + 1e-14, "{name}: f^V not monotone at x={x}");
                assert!(v >= 0.0);
                if x < 0.0 {
                    assert!(
                        v > 1.0 && v <= plateau + 1e-12,
                        "{name}: eccentric f^V = {v}"
                    );
                }
                prev = v;
            }
            // the concentric branch follows the Hill hyperbola through (½, tv_half)
            let tv = p.tv_at_half_omega_max;
            let k = 0.5 * tv / (0.5 - tv);
            for x in [0.2, 0.35, 0.5, 0.7, 0.9] {
                let hill = (1.0 - x) * k / (k + x);
                assert!(
                    (fv(x) - hill).abs() < 0.012,
                    "{name}: Hill deviation at {x}"
                );
            }
        }
    }
}

#[test]
fn anderson_concentric_factor_hits_c4_c5() {
    // the hyperbola of Anderson et al. passes through (C4, 0.75) and (C5, 0.5)
    for (_, _, c) in ANDERSON2007_YOUNG_MALE
        .iter()
        .chain(ANDERSON2007_YOUNG_FEMALE.iter())
    {
        assert!((c.concentric_factor(c.c4) - 0.75).abs() < 1e-12);
        assert!((c.concentric_factor(c.c5) - 0.5).abs() < 1e-12);
        assert!((c.concentric_factor(0.0) - 1.0).abs() < 1e-12);
    }
}

// ---------------------------------------------------------------------------------------
// Signs
// ---------------------------------------------------------------------------------------

#[test]
fn torque_signs_follow_model_convention() {
    let set = JointActuatorSet::anderson2007_young_male();
    let expect = [
        (Joint::Hip, 1.0),   // hip flexor: + (flexion +)
        (Joint::Knee, -1.0), // knee flexor: − (knee flexion is negative)
        (Joint::Ankle, 1.0), // dorsiflexor: +
    ];
    for (j, sgn) in expect {
        let f = set.mtg(j, MuscleSide::Flexor).unwrap();
        let e = set.mtg(j, MuscleSide::Extensor).unwrap();
        let th = f.optimal_angle;
        assert_eq!(mtg_torque(f, 1.0, th, 0.0).signum(), sgn);
        assert_eq!(mtg_torque(e, 1.0, th, 0.0).signum(), -sgn);
        assert_eq!(set.joint_torque(j, 1.0, 0.0, th, 0.0).signum(), sgn);
        assert_eq!(set.joint_torque(j, 0.0, 1.0, th, 0.0).signum(), -sgn);
        // damping opposes motion
        assert!(set.joint_torque(j, 0.0, 0.0, th, 2.0) < 0.0);
        assert!(set.joint_torque(j, 0.0, 0.0, th, -2.0) > 0.0);
        // moving in the flexor's direction is concentric for it: torque drops
        let conc = mtg_torque(f, 1.0, th, sgn * 0.5 * f.omega_max).abs();
        let ecc = mtg_torque(f, 1.0, th, -sgn * 0.5 * f.omega_max).abs();
        let iso = mtg_torque(f, 1.0, th, 0.0).abs();
        assert!(conc < iso && iso < ecc);
    }
    // optimal angles in model convention: knee angles are negative (flexed)
    for side in SIDES {
        assert!(set.mtg(Joint::Knee, side).unwrap().optimal_angle < 0.0);
    }
    assert!(
        set.mtg(Joint::Hip, MuscleSide::Extensor)
            .unwrap()
            .optimal_angle
            > 0.0
    ); // flexed hip
    assert!(
        set.mtg(Joint::Ankle, MuscleSide::Extensor)
            .unwrap()
            .optimal_angle
            > 0.0
    ); // dorsiflexed
    assert!(
        set.mtg(Joint::Ankle, MuscleSide::Flexor)
            .unwrap()
            .optimal_angle
            < 0.0
    ); // plantarflexed
}

// ---------------------------------------------------------------------------------------
// Published values
// ---------------------------------------------------------------------------------------

#[test]
fn peak_torques_match_anderson_and_cross_sources() {
    let (m, h) = (actuators::SEED_SUBJECT_MASS, actuators::SEED_SUBJECT_HEIGHT);
    let set = JointActuatorSet::anderson2007_young_male();
    set.validate().unwrap();
    println!(
        "\nAnderson et al. 2007, young male, seed subject {m} kg {h} m (m g h = {:.2} N·m)",
        m * ANDERSON_GRAVITY * h
    );
    println!(
        "joint  side      C1     τ_o[N·m]  θ_opt(model)[deg]  ω_max[rad/s]  tv(½ω_max) tv_ecc"
    );
    for (j, s, c) in ANDERSON2007_YOUNG_MALE.iter() {
        let p = set.mtg(*j, *s).unwrap();
        let expected = c.c1 * m * ANDERSON_GRAVITY * h;
        let peak = mtg_torque(p, 1.0, p.optimal_angle, 0.0).abs();
        assert!((peak - expected).abs() < 1e-9 * expected);
        assert!((p.max_isometric_torque - expected).abs() < 1e-12 * expected);
        // peak over a fine angle scan is at the optimal angle
        let best = (-2000..=2000)
            .map(|i| mtg_torque(p, 1.0, 1e-3 * i as f64 * 1.5, 0.0).abs())
            .fold(0.0, f64::max);
        assert!(best <= peak + 1e-9);
        println!(
            "{:5}  {:8}  {:.3}  {:8.2}  {:8.2}  {:8.3}  {:.3}  {:.3}",
            j.name(),
            s.name(),
            c.c1,
            p.max_isometric_torque,
            p.optimal_angle.to_degrees(),
            p.omega_max,
            p.tv_at_half_omega_max,
            p.tv_max_eccentric
        );
    }
    // Independent cross-check 1 (ω_max formula and angle convention): Millard et al. 2019
    // (gymnast set) took the ankle MTGs from Anderson et al.; their published ω_max and
    // angle of peak torque equal |2C4C5/(C5−3C4)| and C3 of the young-male rows.
    for (j, s, c) in ANDERSON2007_YOUNG_MALE
        .iter()
        .filter(|r| r.0 == Joint::Ankle)
    {
        let g = MILLARD2019_GYMNAST
            .iter()
            .find(|r| r.joint == *j && r.side == *s)
            .unwrap();
        assert!(
            (c.omega_max() - g.omega_max).abs() < 1e-4,
            "ω_max {} vs {}",
            c.omega_max(),
            g.omega_max
        );
        assert!((c.c3 - g.peak_angle_anatomical).abs() < 1e-12);
        // ... and their f^V parameters follow the same rules as ours:
        // tv(ω_max/2) from Anderson's hyperbola (capped at 0.45), tv_ecc = 1.1 + 0.2 C6
        assert!((c.tv_at_half_omega_max() - g.tv_at_half_omega_max).abs() < 1e-4);
        assert!((c.tv_max_eccentric() - g.tv_max_eccentric).abs() < 1e-9);
    }
    // Independent cross-check 2 (strength normalisation C1·m·g·h): the gymnast ankle
    // torques are Anderson's C1·m·g·h for the 69.6 kg / 1.732 m gymnast times one common
    // Jackson-to-Anderson ratio; with g = 9.81 the ratio is 1.1355 for both ankle MTGs.
    let ratios: Vec<f64> = ANDERSON2007_YOUNG_MALE
        .iter()
        .filter(|r| r.0 == Joint::Ankle)
        .map(|(j, s, c)| {
            let g = MILLARD2019_GYMNAST
                .iter()
                .find(|r| r.joint == *j && r.side == *s)
                .unwrap();
            g.max_isometric_torque / (c.c1 * 69.6 * ANDERSON_GRAVITY * 1.732)
        })
        .collect();
    println!("gymnast/Anderson ankle strength ratios: {ratios:?}");
    assert!((ratios[0] - ratios[1]).abs() < 1e-4);
    assert!((ratios[0] - 1.1355).abs() < 1e-3);
    // Plausibility: knee extensors strongest, ankle dorsiflexors weakest (Anderson Table 3)
    let tau = |j, s| set.mtg(j, s).unwrap().max_isometric_torque;
    assert!(tau(Joint::Knee, MuscleSide::Extensor) > tau(Joint::Hip, MuscleSide::Extensor));
    assert!(tau(Joint::Ankle, MuscleSide::Flexor) < tau(Joint::Knee, MuscleSide::Flexor));
}

#[test]
fn damping_coefficients_range() {
    // seed eq. 12 with η = 2.0; the seed reports 2.7–7.3 N·m·s/rad
    println!("\nβ = η (τF+τE)/(ωF+ωE)  [N·m·s/rad]");
    let mut all = vec![];
    for (name, set) in sets() {
        set.validate().unwrap();
        let b: Vec<f64> = Joint::ALL.iter().map(|j| set.damping(*j)).collect();
        println!(
            "{name:40} η={}: hip {:.2}  knee {:.2}  ankle {:.2}",
            set.eta, b[0], b[1], b[2]
        );
        // with η = 0.4 (Millard et al. 2017 code: 0.2 with doubled right-limb strength)
        let b4: Vec<f64> = Joint::ALL
            .iter()
            .map(|j| {
                let f = set.mtg(*j, MuscleSide::Flexor).unwrap();
                let e = set.mtg(*j, MuscleSide::Extensor).unwrap();
                damping_coefficient(f, e, 2.0 * actuators::MILLARD2017_CODE_ETA)
            })
            .collect();
        println!(
            "{name:40} η=0.4: hip {:.2}  knee {:.2}  ankle {:.2}",
            b4[0], b4[1], b4[2]
        );
        all.push((name, b, b4));
    }
    // Documented ranges (docs/parameters.md): Anderson young male, seed subject, η = 2:
    // hip 49.1, knee 14.8, ankle 12.2 — a factor 2–7 above the seed's 2.7–7.3.
    let (_, am, _) = &all[0];
    for (got, want) in am.iter().zip([49.13, 14.80, 12.16]) {
        assert!((got - want).abs() < 0.05, "β {got} vs documented {want}");
    }
    // Gymnast set with η = 0.4 reproduces the seed's upper bound (hip 7.32) and is close
    // to its lower bound (ankle 2.37 vs 2.7).
    let (_, _, g4) = &all[2];
    for (got, want) in g4.iter().zip([7.318, 4.289, 2.368]) {
        assert!((got - want).abs() < 0.005, "β(η=0.4) {got} vs {want}");
    }
    // β scales with strength
    let set = JointActuatorSet::anderson2007_young_male();
    let s2 = set.scaled(0.5);
    for j in Joint::ALL {
        assert!((s2.damping(j) - 0.5 * set.damping(j)).abs() < 1e-12);
    }
}

// ---------------------------------------------------------------------------------------
// Activation dynamics
// ---------------------------------------------------------------------------------------

#[test]
fn activation_relaxes_with_mean_time_constant() {
    let act = ActivationDynamics::default();
    assert_eq!(act.tau_activation, 0.015);
    assert_eq!(act.tau_deactivation, 0.050);
    let tc = act.time_constant();
    assert!((tc - 0.0325).abs() < 1e-15);
    for (a0, e) in [(0.0, 1.0), (1.0, 0.05), (0.3, 0.3), (0.8, 0.2)] {
        // RK4 with dt = 0.1 ms over 0.2 s (≈ 6 time constants)
        let dt = 1e-4;
        let mut a = a0;
        let mut t = 0.0;
        let mut max_err: f64 = 0.0;
        for _ in 0..2000 {
            let k1 = act.rate(e, a);
            let k2 = act.rate(e, a + 0.5 * dt * k1);
            let k3 = act.rate(e, a + 0.5 * dt * k2);
            let k4 = act.rate(e, a + dt * k3);
            a += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            t += dt;
            let exact = e + (a0 - e) * (-t / tc).exp();
            max_err = max_err.max((a - exact).abs());
        }
        assert!(max_err < 1e-12, "activation error {max_err}");
    }
    // symmetric in rise/fall (C2 form: one time constant)
    assert_eq!(act.rate(1.0, 0.0), -act.rate(0.0, 1.0));
    // derivative w.r.t. a is −1/T, w.r.t. e is +1/T
    let da = ad(|x| act.rate(Dual64::c(0.7), x), 0.2);
    let de = ad(|x| act.rate(x, Dual64::c(0.2)), 0.7);
    assert!((da + 1.0 / tc).abs() < 1e-12 && (de - 1.0 / tc).abs() < 1e-12);
}

// ---------------------------------------------------------------------------------------
// Validation and serde
// ---------------------------------------------------------------------------------------

#[test]
fn validation_and_serde() {
    for (_, set) in sets() {
        set.validate().unwrap();
        let js = serde_json::to_string(&set).unwrap();
        let back: JointActuatorSet = serde_json::from_str(&js).unwrap();
        assert_eq!(back, set);
    }
    let js = serde_json::to_string(&JointActuatorSet::anderson2007_young_male().mtgs[0]).unwrap();
    assert!(js.contains("\"joint\":\"hip\"") && js.contains("\"side\":\"extensor\""));
    assert!(js.contains("\"shape\":\"anderson2007_cosine\""));

    let good = JointActuatorSet::anderson2007_young_male();
    let mut bad = good.clone();
    bad.mtgs[2].max_isometric_torque = -1.0;
    assert!(bad.validate().is_err());
    let mut bad = good.clone();
    bad.mtgs[0].omega_max = f64::NAN;
    assert!(bad.validate().is_err());
    let mut bad = good.clone();
    bad.activation.tau_deactivation = 0.0;
    assert!(bad.validate().is_err());
    let mut bad = good.clone();
    bad.mtgs.pop();
    assert!(bad.validate().is_err());
    let mut bad = good.clone();
    bad.mtgs[1] = bad.mtgs[0];
    assert!(bad.validate().is_err());
    let mut bad = good.clone();
    bad.mtgs[3].tv_max_eccentric = 0.9;
    assert!(bad.validate().is_err());
    assert!(good.scaled(0.0).validate().is_err());
    let s = good.scaled(81.7 / 73.0);
    s.validate().unwrap();
    assert!(
        (s.mtgs[0].max_isometric_torque / good.mtgs[0].max_isometric_torque - 81.7 / 73.0).abs()
            < 1e-14
    );
}

// ---------------------------------------------------------------------------------------
// de Leva (1996)
// ---------------------------------------------------------------------------------------

#[test]
fn de_leva_fractions_and_table_consistency() {
    assert!((DE_LEVA_MALE.mass_pct_sum() - 100.0).abs() < 1e-9);
    assert!((DE_LEVA_FEMALE.mass_pct_sum() - 99.99).abs() < 1e-9); // as published
    for t in [&DE_LEVA_MALE, &DE_LEVA_FEMALE] {
        // the three trunk parts add up to the SUPR→MIDH trunk: 531.9 mm (M), 529.3 mm (F);
        // masses to 43.46 % (M), 42.57 % (F)
        let l = t.upper_trunk.length_mm + t.middle_trunk.length_mm + t.lower_trunk.length_mm;
        let m = t.upper_trunk.mass_pct + t.middle_trunk.mass_pct + t.lower_trunk.mass_pct;
        let (lw, mw) = if t.stature_mm == 1741.0 {
            (531.9, 43.46)
        } else {
            (529.3, 42.57)
        };
        assert!((l - lw).abs() < 1e-9 && (m - mw).abs() < 1e-9);
    }
    for sex in [Sex::Male, Sex::Female] {
        for (mass, height) in [(81.7, 1.72), (55.0, 1.60), (100.0, 1.95)] {
            let b = de_leva_planar(mass, height, sex).unwrap();
            assert!(
                (b.segment_mass_sum() - mass).abs() < 1e-12,
                "{sex:?} {mass}"
            );
            // fractions of body mass sum to 1
            let frac = b.segment_mass_sum() / b.total_mass;
            assert!((frac - 1.0).abs() < 1e-14);
        }
    }
    // HAT fraction: head 6.94 + trunk 43.46 + 2 × (2.71 + 1.62 + 0.61) = 60.28 % (male)
    let b = de_leva_planar(100.0, 1.741, Sex::Male).unwrap();
    assert!((b.hat.mass - 60.28).abs() < 1e-9);
    // reference stature: lengths equal the table
    assert!((b.thigh.length - 0.4222).abs() < 1e-12);
    assert!((b.shank.length - 0.4403).abs() < 1e-12);
    assert!((b.foot.length - 0.2581).abs() < 1e-12);
    // errors
    assert!(de_leva_planar(0.0, 1.7, Sex::Male).is_err());
    assert!(de_leva_planar(70.0, f64::NAN, Sex::Male).is_err());
}

#[test]
fn de_leva_seed_subject() {
    let (m, h) = (81.7, 1.72);
    let b = de_leva_planar(m, h, Sex::Male).unwrap();
    let s = h / 1.741;
    // hand-computed from Table 4 (male), transverse radii
    let thigh_l = 0.4222 * s;
    assert!((b.thigh.mass - 0.1416 * m).abs() < 1e-12);
    assert!((b.thigh.length - thigh_l).abs() < 1e-12);
    assert!((b.thigh.com_from_proximal - 0.4095 * thigh_l).abs() < 1e-12);
    assert!((b.thigh.inertia_com - 0.1416 * m * (0.329 * thigh_l).powi(2)).abs() < 1e-12);
    let shank_l = 0.4403 * s;
    assert!((b.shank.inertia_com - 0.0433 * m * (0.246 * shank_l).powi(2)).abs() < 1e-12);
    let foot_l = 0.2581 * s;
    assert!((b.foot.com_from_proximal - 0.4415 * foot_l).abs() < 1e-12);

    println!("\nde Leva (1996) planar segments, male {m} kg, {h} m (transverse radii):");
    println!("segment  mass[kg]  length[m]  com_from_prox[m]  I_com[kg m²]");
    for sp in [&b.hat, &b.thigh, &b.shank, &b.foot] {
        println!(
            "{:7}  {:8.4}  {:9.4}  {:16.4}  {:.5}",
            sp.name, sp.mass, sp.length, sp.com_from_proximal, sp.inertia_com
        );
    }
    let parts = de_leva_hat_parts(m, h, Sex::Male, RadiusColumn::Transverse).unwrap();
    println!("HAT parts (COM height above hip midpoint):");
    for p in &parts {
        println!(
            "  {:13} {:7.3} kg  {:7.4} m  I_own {:.5}",
            p.name, p.mass, p.com_height, p.inertia_com
        );
    }
    let alt = de_leva_planar_using(m, h, Sex::Male, RadiusColumn::Sagittal).unwrap();
    println!(
        "sagittal-column alternative: I_hat {:.4}  I_thigh {:.4}  I_shank {:.4}  I_foot {:.5}",
        alt.hat.inertia_com, alt.thigh.inertia_com, alt.shank.inertia_com, alt.foot.inertia_com
    );
    // plausibility of the lumped HAT: COM between lower and upper trunk COMs, inertia
    // larger than the sum of the parts' own inertia (parallel-axis terms)
    assert!((b.hat.mass - 0.6028 * m).abs() < 1e-9);
    assert!(b.hat.com_from_proximal > 0.2 && b.hat.com_from_proximal < 0.4);
    let own: f64 = parts.iter().map(|p| p.inertia_com).sum();
    assert!(b.hat.inertia_com > own);
    assert!(b.hat.length > 0.8 && b.hat.length < 0.9);
    // female tables work too
    let f = de_leva_planar(60.0, 1.65, Sex::Female).unwrap();
    assert!((f.segment_mass_sum() - 60.0).abs() < 1e-12);
    let _ = anthropometry::DeLevaTable::for_sex(Sex::Female);
}

#[test]
fn generic_over_scalar_types() {
    // the same code runs on f64, Dual64 and nested duals
    let set = JointActuatorSet::anderson2007_young_male();
    let t64 = set.joint_torque(Joint::Knee, 0.2, 0.7, -0.6, 1.5);
    let td = set.joint_torque(
        Joint::Knee,
        Dual64::c(0.2),
        Dual64::c(0.7),
        Dual64::c(-0.6),
        Dual64::from_re(1.5).derivative(),
    );
    assert!((td.re - t64).abs() < 1e-12 * t64.abs());
    assert!(td.eps.is_finite());
    let t2 = set.joint_torque(
        Joint::Knee,
        Dual2_64::c(0.2),
        Dual2_64::c(0.7),
        Dual2_64::from_re(-0.6).derivative(),
        Dual2_64::c(1.5),
    );
    assert!((t2.re - t64).abs() < 1e-12 && t2.v2.is_finite());
    let _ = Dual64::c(1.0).value();
    let _ = Dual64::c(1.0).sqrt();
}

#[test]
fn curves_vs_anderson_original() {
    // Compare the smooth f^V with Anderson et al.'s own concentric hyperbola (valid there)
    // and report the eccentric side (Anderson's eccentric branch is replaced, see docs).
    let set = JointActuatorSet::anderson2007_young_male();
    println!("\nf^V: ours vs Anderson (x = shortening velocity / ω_max)");
    println!("joint  side      x=-1.0(ours) x=0.25 ours/And  x=0.5 ours/And  x=0.75 ours/And");
    for (j, s, c) in ANDERSON2007_YOUNG_MALE.iter() {
        let p = set.mtg(*j, *s).unwrap();
        let fv = |x: f64| torque_velocity(p, p.torque_sign() * x * p.omega_max);
        let an = |x: f64| c.concentric_factor(x * p.omega_max);
        println!(
            "{:5}  {:8}  {:.3}        {:.3}/{:.3}    {:.3}/{:.3}    {:.3}/{:.3}",
            j.name(),
            s.name(),
            fv(-1.0),
            fv(0.25),
            an(0.25),
            fv(0.5),
            an(0.5),
            fv(0.75),
            an(0.75)
        );
        // where RBDL's cap (0.45) is inactive the concentric branch reproduces Anderson's
        // hyperbola at ω_max/2 (up to the smoothing)
        if c.concentric_factor(0.5 * c.omega_max()) < actuators::TV_HALF_CAP {
            assert!((fv(0.5) - an(0.5)).abs() < 0.005);
        }
    }
}
