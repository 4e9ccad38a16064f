//! The benchmark models (cart-pole, five-link biped) against the CasADi peer's check values
//! (an independent symbolic implementation), AD Jacobians against central differences,
//! energy conservation and power balance, and the defining properties of the heel-strike map
//! (plastic impact: new stance foot at rest, kinetic energy not increased, angular momentum
//! of Kelly's five sub-chains conserved).
//!
//! Tests that need the peer's `peer/problems/*.json` (`common::peer_dir`) print a note and
//! pass when it is absent.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

use footfall::integrate::{
    ControlShape, ControlledOde, Integrator, IntegratorSettings, Method, ShootingInterval,
};
use footfall::model::ad;
use footfall::problems::benchmarks::{read_problem_json, CartPole, FiveLinkBiped};
use num_dual::{Dual64, DualNum};
use serde_json::Value;

const FLIP: [usize; 5] = [4, 3, 2, 1, 0];

fn problem_path(name: &str) -> PathBuf {
    crate::common::peer_dir().join(format!("peer/problems/{name}.json"))
}

/// The peer file, or `None` with a note when it is not there.
fn peer(name: &str) -> Option<Value> {
    let p = problem_path(name);
    if !p.exists() {
        eprintln!("NOTE: {} not found: peer check skipped", p.display());
        return None;
    }
    Some(read_problem_json(&p).expect("peer JSON"))
}

fn vecf(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("not an array: {v}"))
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// max |a − b| / max |b| (vector max-norm relative error).
fn rel(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / scale
}

/// Largest per-entry relative error, entries below `floor` in magnitude compared absolutely.
fn rel_entry(a: &[f64], b: &[f64], floor: f64) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / y.abs().max(floor))
        .fold(0.0, f64::max)
}

/// Deterministic pseudo-random numbers (xorshift).
struct Rng(u64);
impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// Central-difference Jacobian (column-major) of `f` at `x`.
fn fd_jacobian(mut f: impl FnMut(&[f64]) -> Vec<f64>, x: &[f64]) -> Vec<f64> {
    let m = f(x).len();
    let mut jac = vec![0.0; m * x.len()];
    for j in 0..x.len() {
        let h = 1e-6 * x[j].abs().max(1.0);
        let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
        xp[j] += h;
        xm[j] -= h;
        let (fp, fm) = (f(&xp), f(&xm));
        for i in 0..m {
            jac[i + j * m] = (fp[i] - fm[i]) / (2.0 * h);
        }
    }
    jac
}

/// Max-norm difference of two Jacobians relative to max(1, |J|max).
fn jac_err(ad: &[f64], fd: &[f64]) -> f64 {
    let scale = fd.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    ad.iter()
        .zip(fd)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
        / scale
}

fn biped_f(b: &FiveLinkBiped, x: &[f64], u: &[f64]) -> Vec<f64> {
    let mut xdot = vec![0.0; 10];
    b.f(x, u, &[], &mut xdot).expect("f");
    xdot
}

// ---------------------------------------------------------------------------------------
// Loading
// ---------------------------------------------------------------------------------------

#[test]
fn loaders_match_defaults_and_name_missing_fields() {
    if let Some(p) = peer("cartpole_swingup") {
        let cp = CartPole::from_problem_json(&p).expect("cart-pole parameters");
        assert_eq!(cp, CartPole::default());
    }
    if let Some(p) = peer("five_link_biped") {
        let b = FiveLinkBiped::from_problem_json(&p).expect("biped parameters");
        assert_eq!(b, FiveLinkBiped::default());
    }
    let e = CartPole::from_problem_json(&serde_json::json!({"parameters": {"cart_mass": 1.0}}))
        .unwrap_err()
        .to_string();
    assert!(e.contains("parameters.pole_mass"), "{e}");
    let e = CartPole::from_problem_json(&serde_json::json!({}))
        .unwrap_err()
        .to_string();
    assert!(e.contains("`parameters`"), "{e}");
    let mut p = serde_json::json!({"parameters": {
        "m": [3.2, 6.8, 20.0, 6.8, 3.2], "I": [0.93, 1.08, 2.22, 1.08, 0.93],
        "l": [0.4, 0.4, 0.625, 0.4, 0.4], "c": [0.128, 0.163, 0.2, 0.163], "g": 9.81}});
    let e = FiveLinkBiped::from_problem_json(&p)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("parameters.c") && e.contains("array of 5"),
        "{e}"
    );
    p["parameters"]["c"] = serde_json::json!([0.128, 0.163, 0.2, 0.163, 0.128]);
    p["parameters"].as_object_mut().unwrap().remove("g");
    let e = FiveLinkBiped::from_problem_json(&p)
        .unwrap_err()
        .to_string();
    assert!(e.contains("parameters.g"), "{e}");
    p["parameters"]["g"] = serde_json::json!(9.81);
    assert_eq!(
        FiveLinkBiped::from_problem_json(&p).unwrap(),
        FiveLinkBiped::default()
    );
    p["parameters"]["m"][2] = serde_json::json!(-1.0);
    assert!(FiveLinkBiped::from_problem_json(&p)
        .unwrap_err()
        .to_string()
        .contains("every m"));
}

// ---------------------------------------------------------------------------------------
// Peer check values
// ---------------------------------------------------------------------------------------

#[test]
fn cartpole_reproduces_peer_check_values() {
    let Some(cv) = peer("check_values") else {
        return;
    };
    let cp = CartPole::default();
    for (k, case) in cv["cartpole_swingup"]["f"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
    {
        let (x, u, want) = (vecf(&case["x"]), vecf(&case["u"]), vecf(&case["xdot"]));
        let mut xdot = [0.0; 4];
        cp.f(&x, &u, &[], &mut xdot).unwrap();
        let e = rel(&xdot, &want);
        println!(
            "cart-pole f[{k}]: max-norm rel err {e:.2e}, per-entry {:.2e}",
            rel_entry(&xdot, &want, 1e-300)
        );
        assert!(e <= 1e-9, "cart-pole f[{k}] = {xdot:?}, peer {want:?}");
    }
}

#[test]
fn biped_reproduces_peer_check_values() {
    let Some(cv) = peer("check_values") else {
        return;
    };
    let cv = &cv["five_link_biped"];
    let b = FiveLinkBiped::default();
    let check = |what: &str, got: &[f64], want: &[f64]| {
        let e = rel(got, want);
        println!(
            "biped {what}: max-norm rel err {e:.2e}, per-entry (floor 1e-3) {:.2e}",
            rel_entry(got, want, 1e-3)
        );
        assert!(e <= 1e-9, "{what}: got {got:?}, peer {want:?}");
    };
    for (k, case) in cv["f"].as_array().unwrap().iter().enumerate() {
        let (x, u) = (vecf(&case["x"]), vecf(&case["u"]));
        check(
            &format!("f[{k}]"),
            &biped_f(&b, &x, &u),
            &vecf(&case["xdot"]),
        );
    }
    let x2 = vecf(&cv["impact"]["x_minus"]);
    let want_m: Vec<f64> = cv["mass_matrix_at_x2"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(vecf)
        .collect();
    check("M(x2)", &b.mass_matrix(&x2[..5]), &want_m);
    let hs = b.heel_strike_details(&x2);
    check("heel strike x+", &hs.x_plus, &vecf(&cv["impact"]["x_plus"]));
    check(
        "heel strike (Vec API)",
        &b.heel_strike(&x2),
        &vecf(&cv["impact"]["x_plus"]),
    );
    check(
        "ground impulse",
        &hs.impulse,
        &vecf(&cv["impact"]["ground_impulse_xy"]),
    );
    let foot = &cv["swing_foot_at_x2"];
    check("P5(x2)", &b.swing_foot(&x2[..5]), &vecf(&foot["P5"]));
    check(
        "dP5(x2)",
        &b.swing_foot_velocity(&x2[..5], &x2[5..]),
        &vecf(&foot["dP5"]),
    );

    // boundary constraints at the initial guess (order given by the peer file)
    let Some(prob) = peer("five_link_biped") else {
        return;
    };
    let q0 = vecf(&prob["initial_guess"]["q_start"]);
    let t = prob["horizon"]["T"].as_f64().unwrap();
    let d = prob["parameters"]["step_length"].as_f64().unwrap();
    let qf: Vec<f64> = FLIP.iter().map(|&k| q0[k]).collect();
    let dq: Vec<f64> = (0..5).map(|k| (qf[k] - q0[k]) / t).collect();
    let x0 = [q0.clone(), dq.clone()].concat();
    let xn = [qf.clone(), dq.clone()].concat();
    let xp = b.heel_strike(&xn);
    let mut g: Vec<f64> = (0..10).map(|k| x0[k] - xp[k]).collect();
    let p5n = b.swing_foot(&xn[..5]);
    g.push(p5n[0] - d);
    g.push(p5n[1]);
    g.push(b.swing_foot_velocity(&x0[..5], &x0[5..])[1]);
    g.push(b.swing_foot_velocity(&xn[..5], &xn[5..])[1]);
    check(
        "boundary constraints at guess",
        &g,
        &vecf(&cv["boundary_constraints_at_guess"]),
    );
}

// ---------------------------------------------------------------------------------------
// Jacobians
// ---------------------------------------------------------------------------------------

#[test]
fn cartpole_jacobian_matches_central_differences() {
    let cp = CartPole::default();
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut worst = 0.0f64;
    for _ in 0..20 {
        let x: Vec<f64> = [1.0, 3.0, 2.0, 5.0]
            .iter()
            .map(|s| rng.uniform(-s, *s))
            .collect();
        let u = [rng.uniform(-10.0, 10.0)];
        let (mut xdot, mut fx, mut fu) = ([0.0; 4], [0.0; 16], [0.0; 4]);
        cp.f_jac(&x, &u, &[], &mut xdot, &mut fx, &mut fu, &mut [])
            .unwrap();
        let mut plain = [0.0; 4];
        cp.f(&x, &u, &[], &mut plain).unwrap();
        assert_eq!(xdot, plain, "f_jac value differs from f");
        let xu = [x.clone(), u.to_vec()].concat();
        let fd = fd_jacobian(
            |z| {
                let mut v = vec![0.0; 4];
                cp.f(&z[..4], &z[4..], &[], &mut v).unwrap();
                v
            },
            &xu,
        );
        worst = worst.max(jac_err(&[fx.to_vec(), fu.to_vec()].concat(), &fd));
    }
    println!("cart-pole [fx fu] vs central differences: {worst:.2e}");
    assert!(worst <= 1e-6);
}

#[test]
fn biped_jacobians_match_central_differences() {
    let b = FiveLinkBiped::default();
    let mut rng = Rng(0x0bad_cafe_f00d_1234);
    let (mut e_f, mut e_hs, mut e_p5, mut e_v5) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for _ in 0..20 {
        let x: Vec<f64> = (0..10)
            .map(|k| {
                if k < 5 {
                    rng.uniform(-1.0, 1.0)
                } else {
                    rng.uniform(-3.0, 3.0)
                }
            })
            .collect();
        let u: Vec<f64> = (0..5).map(|_| rng.uniform(-50.0, 50.0)).collect();
        let (mut xdot, mut fx, mut fu) = ([0.0; 10], [0.0; 100], [0.0; 50]);
        b.f_jac(&x, &u, &[], &mut xdot, &mut fx, &mut fu, &mut [])
            .unwrap();
        assert!(
            rel(&xdot, &biped_f(&b, &x, &u)) < 1e-14,
            "f_jac value differs from f"
        );
        let xu = [x.clone(), u.clone()].concat();
        let fd = fd_jacobian(|z| biped_f(&b, &z[..10], &z[10..]), &xu);
        e_f = e_f.max(jac_err(&[fx.to_vec(), fu.to_vec()].concat(), &fd));

        let (v, j) = b.heel_strike_jacobian(&x);
        assert!(rel(&v, &b.heel_strike(&x)) < 1e-14);
        e_hs = e_hs.max(jac_err(&j, &fd_jacobian(|z| b.heel_strike(z), &x)));

        let (v, j) = b.swing_foot_jacobian(&x[..5]);
        assert!(rel(&v, &b.swing_foot(&x[..5])) < 1e-14);
        e_p5 = e_p5.max(jac_err(
            &j,
            &fd_jacobian(|z| b.swing_foot(z).to_vec(), &x[..5]),
        ));

        let (v, j) = b.swing_foot_velocity_jacobian(&x);
        assert!(rel(&v, &b.swing_foot_velocity(&x[..5], &x[5..])) < 1e-14);
        e_v5 = e_v5.max(jac_err(
            &j,
            &fd_jacobian(|z| b.swing_foot_velocity(&z[..5], &z[5..]).to_vec(), &x),
        ));
    }
    println!("biped vs central differences: [fx fu] {e_f:.2e}, heel strike {e_hs:.2e}, P5 {e_p5:.2e}, dP5 {e_v5:.2e}");
    for e in [e_f, e_hs, e_p5, e_v5] {
        assert!(e <= 1e-6);
    }
}

#[test]
fn biped_f_jac_equals_plain_ad_through_the_whole_rhs() {
    // f_jac differentiates M and r by AD and the solve by its derivative rule; compare with
    // AD straight through the generic rhs (Cholesky included), chunked and single-pass.
    let b = FiveLinkBiped::default();
    let mut rng = Rng(0x2468_1357_aaaa_5555);
    let mut worst = 0.0f64;
    for _ in 0..20 {
        let x: Vec<f64> = (0..10)
            .map(|k| {
                if k < 5 {
                    rng.uniform(-1.5, 1.5)
                } else {
                    rng.uniform(-5.0, 5.0)
                }
            })
            .collect();
        let u: Vec<f64> = (0..5).map(|_| rng.uniform(-100.0, 100.0)).collect();
        let (v1, fx, fu) = b.rhs_jacobian(&x, &u);
        let j1 = [fx.to_vec(), fu.to_vec()].concat();
        let (v2, j2) = chunked_biped_jacobian(&b, &x, &u);
        assert!(rel(&v1, &v2) < 1e-15);
        let xu: [f64; 15] = std::array::from_fn(|k| if k < 10 { x[k] } else { u[k - 10] });
        let mut j3 = [0.0; 150];
        lanes_jac::<15>(&b, &xu, &mut j3);
        worst = worst.max(rel(&j1, &j2)).max(rel(&j1, &j3));
    }
    println!("biped f_jac vs AD through the whole rhs: {worst:.2e}");
    assert!(worst < 1e-13);
}

fn chunked_biped_jacobian(b: &FiveLinkBiped, x: &[f64], u: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let xu = [x, u].concat();
    let (mut value, mut jac) = (vec![0.0; 10], vec![0.0; 150]);
    ad::jacobian::<()>(
        &xu,
        10,
        |z, out| {
            out.copy_from_slice(&b.rhs(&z[..10], &z[10..]));
            Ok(())
        },
        &mut value,
        &mut jac,
    )
    .unwrap();
    (value, jac)
}

// ---------------------------------------------------------------------------------------
// Physics
// ---------------------------------------------------------------------------------------

/// d/dt along ẋ of a scalar function g(x), by one dual-number pass.
fn time_derivative(g: impl Fn(&[Dual64]) -> Dual64, x: &[f64], xdot: &[f64]) -> f64 {
    let xs: Vec<Dual64> = x
        .iter()
        .zip(xdot)
        .map(|(&v, &d)| Dual64::new(v, d))
        .collect();
    g(&xs).eps
}

#[test]
fn power_balance() {
    // d/dt (T + V) = Qᵀ q̇ = Σ u_k × (relative joint rate); u = 0 for the cart-pole's pole.
    let b = FiveLinkBiped::default();
    let cp = CartPole::default();
    let mut rng = Rng(0x5eed_5eed_5eed_5eed);
    let (mut eb, mut ec) = (0.0f64, 0.0f64);
    for _ in 0..20 {
        let x: Vec<f64> = (0..10)
            .map(|k| {
                if k < 5 {
                    rng.uniform(-1.0, 1.0)
                } else {
                    rng.uniform(-3.0, 3.0)
                }
            })
            .collect();
        let u: Vec<f64> = (0..5).map(|_| rng.uniform(-50.0, 50.0)).collect();
        let xdot = biped_f(&b, &x, &u);
        let de = time_derivative(
            |z| {
                let (t, v) = b.energy(&z[..5], &z[5..]);
                t + v
            },
            &x,
            &xdot,
        );
        let rel_rate = [x[5], x[6] - x[5], x[7] - x[6], x[8] - x[7], x[9] - x[8]];
        let power: f64 = u.iter().zip(rel_rate).map(|(a, w)| a * w).sum();
        eb = eb.max((de - power).abs() / power.abs().max(1.0));

        let xc: Vec<f64> = [1.0, 3.0, 2.0, 5.0]
            .iter()
            .map(|s| rng.uniform(-s, *s))
            .collect();
        let uc = rng.uniform(-10.0, 10.0);
        let mut xdc = [0.0; 4];
        cp.f(&xc, &[uc], &[], &mut xdc).unwrap();
        let de = time_derivative(
            |z| {
                let (t, v) = cp.energy(&[z[0], z[1], z[2], z[3]]);
                t + v
            },
            &xc,
            &xdc,
        );
        ec = ec.max((de - uc * xc[2]).abs() / (uc * xc[2]).abs().max(1.0));
    }
    println!("power balance residual: biped {eb:.2e}, cart-pole {ec:.2e}");
    assert!(eb < 1e-11 && ec < 1e-11);
}

#[test]
fn mass_matrix_is_symmetric_positive_definite_and_energy_is_quadratic_form() {
    let b = FiveLinkBiped::default();
    let mut rng = Rng(0xfeed_beef_0123_4567);
    for _ in 0..20 {
        let q: Vec<f64> = (0..5).map(|_| rng.uniform(-3.0, 3.0)).collect();
        let m = b.mass_matrix(&q);
        for i in 0..5 {
            for j in 0..5 {
                assert_eq!(m[i * 5 + j], m[j * 5 + i]);
            }
        }
        let mut l = m;
        footfall::model::linalg::cholesky(&mut l, 5, 1e-12).expect("M positive definite");
        // kinetic energy from the explicit CoM velocities (independent of M)
        let dq: Vec<f64> = (0..5).map(|_| rng.uniform(-3.0, 3.0)).collect();
        let (t, _) = b.energy(&q, &dq);
        let qs: Vec<Dual64> = q
            .iter()
            .zip(&dq)
            .map(|(&v, &d)| Dual64::new(v, d))
            .collect();
        let (_, g) = b.points(&qs);
        let (mass, inertia) = (b.masses(), b.inertias());
        let t2: f64 = (0..5)
            .map(|k| {
                0.5 * mass[k] * (g[k][0].eps.powi(2) + g[k][1].eps.powi(2))
                    + 0.5 * inertia[k] * dq[k] * dq[k]
            })
            .sum();
        assert!((t - t2).abs() <= 1e-12 * t2.abs().max(1.0), "T {t} vs {t2}");
    }
}

#[test]
fn biped_conserves_energy_without_torques() {
    let b = FiveLinkBiped::default();
    let interval = ShootingInterval::new(&b, ControlShape::Constant);
    let settings = IntegratorSettings {
        rtol: 1e-10,
        atol: 1e-10,
        method: Method::Bdf,
        ..Default::default()
    };
    let mut integ = Integrator::new(10, interval.np(), settings).expect("integrator");
    // the peer's initial-guess node 0 (a falling, torque-free robot)
    let x0 = [
        -0.3,
        0.7,
        0.0,
        -0.5,
        -0.6,
        -3.0 / 7.0,
        -12.0 / 7.0,
        0.0,
        12.0 / 7.0,
        3.0 / 7.0,
    ];
    let e = |x: &[f64]| {
        let (t, v) = b.energy(&x[..5], &x[5..]);
        t + v
    };
    let (e0, (t0, _)) = (e(&x0), b.energy(&x0[..5], &x0[5..]));
    let mut p = Vec::new();
    let mut worst = 0.0f64;
    let mut x1 = [0.0; 10];
    for k in 1..=5 {
        let duration = 0.1 * k as f64;
        interval
            .pack_params(&[0.0; 5], None, duration, &[], &mut p)
            .unwrap();
        integ
            .integrate(&interval, 0.0, 1.0, &x0, &p, &mut x1)
            .expect("integration");
        worst = worst.max((e(&x1) - e0).abs() / e0.abs());
    }
    let (t1, _) = b.energy(&x1[..5], &x1[5..]);
    println!(
        "biped energy drift over 0.5 s (E0 = {e0:.6} J, T: {t0:.3} -> {t1:.3} J): {worst:.2e}"
    );
    assert!(t1 > 2.0 * t0, "the robot should have fallen and sped up");
    assert!(worst <= 1e-7);

    // cart-pole, same idea
    let cp = CartPole::default();
    let interval = ShootingInterval::new(&cp, ControlShape::Constant);
    let mut integ = Integrator::new(4, interval.np(), settings_1e10()).expect("integrator");
    let x0 = [0.0, 2.0, 0.5, -1.0];
    let e = |x: &[f64]| {
        let (t, v) = cp.energy(&[x[0], x[1], x[2], x[3]]);
        t + v
    };
    interval
        .pack_params(&[0.0], None, 2.0, &[], &mut p)
        .unwrap();
    let mut x1 = [0.0; 4];
    integ
        .integrate(&interval, 0.0, 1.0, &x0, &p, &mut x1)
        .expect("integration");
    let drift = (e(&x1) - e(&x0)).abs() / e(&x0).abs();
    println!("cart-pole energy drift over 2 s: {drift:.2e}");
    assert!(drift <= 1e-7);
}

fn settings_1e10() -> IntegratorSettings {
    IntegratorSettings {
        rtol: 1e-10,
        atol: 1e-10,
        ..Default::default()
    }
}

/// Angular momentum of `links` about `point`, from positions and velocities of the link
/// centres of mass computed here from the problem's kinematic definition (independently of
/// the model's coefficient form).
fn angular_momentum(
    b: &FiveLinkBiped,
    q: &[f64],
    dq: &[f64],
    links: &[usize],
    point: usize,
) -> f64 {
    let (l, c, m, inertia) = (b.lengths(), b.com_offsets(), b.masses(), b.inertias());
    let qs: Vec<Dual64> = q.iter().zip(dq).map(|(&v, &d)| Dual64::new(v, d)).collect();
    let e: Vec<[Dual64; 2]> = (0..5)
        .map(|k| {
            let (s, co) = qs[k].sin_cos();
            if k < 3 {
                [-s, co]
            } else {
                [s, -co]
            }
        })
        .collect();
    let ax = |p: [Dual64; 2], k: usize, a: f64| [p[0] + e[k][0] * a, p[1] + e[k][1] * a];
    let p0 = [Dual64::from(0.0), Dual64::from(0.0)];
    let p1 = ax(p0, 0, l[0]);
    let p2 = ax(p1, 1, l[1]);
    let p3 = ax(p2, 2, l[2]);
    let p4 = ax(p2, 3, l[3]);
    let p5 = ax(p4, 4, l[4]);
    let pts = [p0, p1, p2, p3, p4, p5];
    let g = [
        ax(p1, 0, -c[0]),
        ax(p2, 1, -c[1]),
        ax(p3, 2, -c[2]),
        ax(p2, 3, c[3]),
        ax(p4, 4, c[4]),
    ];
    let o = [pts[point][0].re, pts[point][1].re];
    links
        .iter()
        .map(|&k| {
            let r = [g[k][0].re - o[0], g[k][1].re - o[1]];
            let v = [g[k][0].eps, g[k][1].eps];
            m[k] * (r[0] * v[1] - r[1] * v[0]) + inertia[k] * dq[k]
        })
        .sum()
}

#[test]
fn heel_strike_is_a_plastic_impact() {
    let b = FiveLinkBiped::default();
    let mut rng = Rng(0x1357_9bdf_2468_ace0);
    let (mut e_stance, mut e_swing, mut e_pos, mut e_h, mut de_max) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64, f64::NEG_INFINITY);
    for trial in 0..30 {
        let mut x: Vec<f64> = (0..10)
            .map(|k| {
                if k < 5 {
                    rng.uniform(-1.0, 1.0)
                } else {
                    rng.uniform(-3.0, 3.0)
                }
            })
            .collect();
        if trial == 0 {
            x = vec![-0.25, 0.55, 0.1, -0.35, -0.5, 0.3, -0.2, 0.5, 1.0, -0.7];
        }
        let (q, dq) = x.split_at(5);
        let hs = b.heel_strike_details(&x);
        let (qp, dqp) = hs.x_plus.split_at(5);
        // the impacting foot (new stance foot) is at rest after impact:
        // v_old_stance + ∂P5/∂q q̇⁺ = 0
        let v = b.swing_foot_velocity(q, &hs.dq_plus_old_labels);
        let vb = hs.old_stance_foot_velocity;
        e_stance = e_stance.max((v[0] + vb[0]).abs().max((v[1] + vb[1]).abs()));
        // the new swing foot moves with the old stance foot's velocity
        let v_new = b.swing_foot_velocity(qp, dqp);
        e_swing = e_swing.max((v_new[0] - vb[0]).abs().max((v_new[1] - vb[1]).abs()));
        // and sits at −P5⁻ relative to the new stance foot
        let (p_old, p_new) = (b.swing_foot(q), b.swing_foot(qp));
        e_pos = e_pos.max((p_old[0] + p_new[0]).abs().max((p_old[1] + p_new[1]).abs()));
        // kinetic energy does not increase
        let (t_minus, v_minus) = b.energy(q, dq);
        let (t_plus, v_plus) = b.energy(qp, dqp);
        de_max = de_max.max((t_plus - t_minus) / t_minus);
        assert!(
            t_plus <= t_minus * (1.0 + 1e-12),
            "kinetic energy increased: {t_minus} -> {t_plus}"
        );
        // potential energy is continuous up to the height of the impact point (V⁺ measured
        // from the new stance foot, which is at height P5_y⁻)
        assert!((v_plus - (v_minus - b.total_mass() * b.gravity() * p_old[1])).abs() < 1e-9);
        // Kelly's angular-momentum conservation of the five sub-chains
        // (new {1..5} @ new stance foot, {2..5} @ new stance knee, {3,4,5} and {4,5} @ hip,
        // {5} @ new swing knee), in old labels on the left.
        for (old_links, old_pt, new_links, new_pt) in [
            (&[0, 1, 2, 3, 4][..], 5, &[0, 1, 2, 3, 4][..], 0),
            (&[0, 1, 2, 3][..], 4, &[1, 2, 3, 4][..], 1),
            (&[0, 1, 2][..], 2, &[2, 3, 4][..], 2),
            (&[0, 1][..], 2, &[3, 4][..], 2),
            (&[0][..], 1, &[4][..], 4),
        ] {
            let h_minus = angular_momentum(&b, q, dq, old_links, old_pt);
            let h_plus = angular_momentum(&b, qp, dqp, new_links, new_pt);
            e_h = e_h.max((h_plus - h_minus).abs() / h_minus.abs().max(1.0));
        }
    }
    println!(
        "heel strike: new stance foot speed {e_stance:.1e}, swing-foot velocity consistency {e_swing:.1e}, \
         position {e_pos:.1e}, angular momentum {e_h:.1e}, max relative KE change {de_max:.3}"
    );
    assert!(e_stance < 1e-12 && e_swing < 1e-12 && e_pos < 1e-14 && e_h < 1e-11);
}

#[test]
fn bad_input_gives_errors_not_panics() {
    use footfall::integrate::OdeError;
    let b = FiveLinkBiped::default();
    let cp = CartPole::default();
    let mut xd = [0.0; 10];
    let x = [0.1; 10];
    assert!(matches!(
        b.f(&x[..9], &[0.0; 5], &[], &mut xd),
        Err(OdeError::Fatal(_))
    ));
    assert!(matches!(
        b.f(&x, &[0.0; 5], &[1.0], &mut xd),
        Err(OdeError::Fatal(_))
    ));
    let (mut fx, mut fu) = ([0.0; 100], [0.0; 49]);
    assert!(matches!(
        b.f_jac(&x, &[0.0; 5], &[], &mut xd, &mut fx, &mut fu, &mut []),
        Err(OdeError::Fatal(_))
    ));
    let mut xn = x;
    xn[2] = f64::NAN;
    assert!(matches!(
        b.f(&xn, &[0.0; 5], &[], &mut xd),
        Err(OdeError::Recoverable(_))
    ));
    let mut fu = [0.0; 50];
    assert!(matches!(
        b.f_jac(&xn, &[0.0; 5], &[], &mut xd, &mut fx, &mut fu, &mut []),
        Err(OdeError::Recoverable(_))
    ));
    assert!(b.heel_strike(&xn).iter().all(|v| v.is_nan()));
    let mut xc = [0.0; 4];
    assert!(matches!(
        cp.f(&[0.0; 3], &[0.0], &[], &mut xc),
        Err(OdeError::Fatal(_))
    ));
    assert!(matches!(
        cp.f(&[f64::NAN; 4], &[0.0], &[], &mut xc),
        Err(OdeError::Recoverable(_))
    ));
}

#[test]
fn biped_interval_sensitivities_match_central_differences() {
    // f_jac as CVODES uses it: one shooting interval of the peer's grid (h = 0.7/40).
    let b = FiveLinkBiped::default();
    let interval = ShootingInterval::new(&b, ControlShape::Constant);
    let np = interval.np();
    let mut integ = Integrator::new(10, np, settings_1e10()).unwrap();
    let x0 = [-0.25, 0.55, 0.1, -0.35, -0.5, 0.3, -0.2, 0.5, 1.0, -0.7];
    let mut p = Vec::new();
    interval
        .pack_params(&[0.0, 10.0, -20.0, 5.0, 1.0], None, 0.0175, &[], &mut p)
        .unwrap();
    let (mut x1, mut s1) = (vec![0.0; 10], vec![0.0; 10 * (10 + np)]);
    integ
        .integrate_with_sensitivities(&interval, 0.0, 1.0, &x0, &p, &mut x1, &mut s1)
        .unwrap();
    let z0 = [&x0[..], &p[..]].concat();
    let fd = fd_jacobian(
        |z| {
            let mut out = vec![0.0; 10];
            integ
                .integrate(&interval, 0.0, 1.0, &z[..10], &z[10..], &mut out)
                .unwrap();
            out
        },
        &z0,
    );
    let e = jac_err(&s1, &fd);
    println!("biped interval sensitivities vs central differences: {e:.2e}");
    assert!(e < 1e-6);
}

// ---------------------------------------------------------------------------------------
// Timing (run with --nocapture to see the numbers)
// ---------------------------------------------------------------------------------------

/// Seconds per call: the best of 7 batches of `n` calls (robust to other load on the machine).
fn per_call(n: usize, mut body: impl FnMut(usize)) -> f64 {
    for i in 0..n / 10 {
        body(i);
    }
    (0..7)
        .map(|_| {
            let t = Instant::now();
            for i in 0..n {
                body(i);
            }
            t.elapsed().as_secs_f64() / n as f64
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn timing_of_f_and_f_jac() {
    let cp = CartPole::default();
    let xc = [0.1, 0.4, 0.2, -0.3];
    let (mut xd, mut fx, mut fu) = ([0.0; 4], [0.0; 16], [0.0; 4]);
    let n = 50_000;
    let t_cf = per_call(n, |i| {
        let u = [black_box(i as f64 * 1e-6)];
        cp.f(black_box(&xc), &u, &[], &mut xd).unwrap();
        black_box(&xd);
    });
    let t_cj = per_call(n, |i| {
        let u = [black_box(i as f64 * 1e-6)];
        cp.f_jac(black_box(&xc), &u, &[], &mut xd, &mut fx, &mut fu, &mut [])
            .unwrap();
        black_box((&xd, &fx, &fu));
    });
    let b = FiveLinkBiped::default();
    let x = [-0.25, 0.55, 0.1, -0.35, -0.5, 0.3, -0.2, 0.5, 1.0, -0.7];
    let (mut xd, mut fx, mut fu) = ([0.0; 10], [0.0; 100], [0.0; 50]);
    let n = 20_000;
    let t_bf = per_call(n, |i| {
        let u = [0.0, 10.0, -20.0, 5.0, black_box(i as f64 * 1e-6)];
        b.f(black_box(&x), &u, &[], &mut xd).unwrap();
        black_box(&xd);
    });
    let t_bj = per_call(n, |i| {
        let u = [0.0, 10.0, -20.0, 5.0, black_box(i as f64 * 1e-6)];
        b.f_jac(black_box(&x), &u, &[], &mut xd, &mut fx, &mut fu, &mut [])
            .unwrap();
        black_box((&xd, &fx, &fu));
    });
    let t_chunk = per_call(n / 2, |i| {
        let u = [0.0, 10.0, -20.0, 5.0, black_box(i as f64 * 1e-6)];
        black_box(chunked_biped_jacobian(&b, black_box(&x), &u));
    });
    let xu = [
        -0.25, 0.55, 0.1, -0.35, -0.5, 0.3, -0.2, 0.5, 1.0, -0.7, 0.0, 10.0, -20.0, 5.0, 1.0,
    ];
    let mut jac = [0.0; 150];
    let t_15 = per_call(n / 2, |_| {
        lanes_jac::<15>(&b, black_box(&xu), &mut jac);
        black_box(&jac);
    });
    let t_5 = per_call(n / 2, |_| {
        lanes_jac::<5>(&b, black_box(&xu), &mut jac);
        black_box(&jac);
    });
    let t_fd = per_call(n / 10, |i| {
        let u = [0.0, 10.0, -20.0, 5.0, black_box(i as f64 * 1e-6)];
        let xu = [&x[..], &u[..]].concat();
        black_box(fd_jacobian(|z| biped_f(&b, &z[..10], &z[10..]), &xu));
    });
    println!("per call (test profile, opt-level 2):");
    println!("  cart-pole f      {:8.1} ns", t_cf * 1e9);
    println!(
        "  cart-pole f_jac  {:8.1} ns  (one 5-lane dual pass)",
        t_cj * 1e9
    );
    println!("  biped f          {:8.1} ns", t_bf * 1e9);
    println!(
        "  biped f_jac      {:8.1} ns  (AD of M, r in 3 passes of 5 lanes + solve rule, used)",
        t_bj * 1e9
    );
    println!("  alternatives: AD through the whole rhs (Cholesky included)");
    println!("  - DualSVec64<15> {:8.1} ns  (1 pass)", t_15 * 1e9);
    println!(
        "  - ad::jacobian   {:8.1} ns  (2 passes of 8 lanes, allocating)",
        t_chunk * 1e9
    );
    println!("  - DualSVec64<5>  {:8.1} ns  (3 passes)", t_5 * 1e9);
    println!(
        "  biped central FD {:8.1} ns  (30 f calls + allocations, for comparison only)",
        t_fd * 1e9
    );
}

#[test]
fn timing_of_biped_sensitivity_sweep() {
    // The peer's measurement: 40 intervals of the initial guess, CVODES 1e-8, forward
    // sensitivities w.r.t. (x0, u) = 15 directions (here 16: + interval duration).
    let b = FiveLinkBiped::default();
    let interval = ShootingInterval::new(&b, ControlShape::Constant);
    let (n, t) = (40usize, 0.7);
    let q0 = [-0.3, 0.7, 0.0, -0.5, -0.6];
    let qf: Vec<f64> = FLIP.iter().map(|&k| q0[k]).collect();
    let dq: Vec<f64> = (0..5).map(|k| (qf[k] - q0[k]) / t).collect();
    let node = |k: usize| -> Vec<f64> {
        let s = k as f64 / n as f64;
        (0..10)
            .map(|i| {
                if i < 5 {
                    q0[i] + s * (qf[i] - q0[i])
                } else {
                    dq[i - 5]
                }
            })
            .collect()
    };
    for method in [Method::Bdf, Method::Adams] {
        let settings = IntegratorSettings {
            rtol: 1e-8,
            atol: 1e-8,
            method,
            ..Default::default()
        };
        let mut integ = Integrator::new(10, interval.np(), settings).unwrap();
        let mut p = Vec::new();
        let (mut x1, mut s1) = (vec![0.0; 10], vec![0.0; 10 * (10 + interval.np())]);
        let mut sweep = |sens: bool| {
            let start = Instant::now();
            let mut steps = 0;
            for k in 0..n {
                interval
                    .pack_params(&[0.0; 5], None, t / n as f64, &[], &mut p)
                    .unwrap();
                let st = if sens {
                    integ.integrate_with_sensitivities(
                        &interval,
                        0.0,
                        1.0,
                        &node(k),
                        &p,
                        &mut x1,
                        &mut s1,
                    )
                } else {
                    integ.integrate(&interval, 0.0, 1.0, &node(k), &p, &mut x1)
                }
                .unwrap();
                steps += st.steps;
            }
            (start.elapsed().as_secs_f64(), steps)
        };
        sweep(true);
        let (tp, sp) = sweep(false);
        let (ts, ss) = sweep(true);
        println!(
            "biped sweep {method:?} 1e-8: plain {:.2} ms ({sp} steps), with 16 forward sensitivities {:.2} ms ({ss} steps)",
            tp * 1e3,
            ts * 1e3
        );
    }
}

/// [fx fu] of the biped by AD straight through the generic `rhs` (Cholesky included), in
/// passes of `N` lanes (N = 15: a single pass).
fn lanes_jac<const N: usize>(b: &FiveLinkBiped, xu: &[f64; 15], jac: &mut [f64; 150]) {
    use num_dual::{Derivative, DualSVec64};
    let mut start = 0;
    while start < 15 {
        let z: [DualSVec64<N>; 15] = std::array::from_fn(|k| {
            let d = DualSVec64::<N>::from_re(xu[k]);
            if k >= start && k < start + N {
                d.derivative(k - start)
            } else {
                d
            }
        });
        let y = b.rhs(&z[..10], &z[10..]);
        for (i, yi) in y.iter().enumerate() {
            for l in 0..N.min(15 - start) {
                jac[i + (start + l) * 10] = match &yi.eps {
                    Derivative(Some(e)) => e[l],
                    Derivative(None) => 0.0,
                };
            }
        }
        start += N;
    }
}
