//! Tests of the CVODES wrapper and the shooting-interval adapter against independent truth:
//! closed-form solutions of a linear ODE, central finite differences of the integrated map,
//! and the un-normalised time-domain model.

use footfall::integrate::{
    ControlShape, ControlledOde, IntegrationStats, Integrator, IntegratorError, IntegratorSettings,
    Method, Ode, OdeError, ShootingInterval,
};
use nalgebra::{Matrix2, Vector2};

fn settings(tol: f64, method: Method) -> IntegratorSettings {
    IntegratorSettings {
        method,
        rtol: tol,
        atol: tol,
        ..IntegratorSettings::default()
    }
}

/// max |a − b| / max(max |b|, floor): a norm-wise relative error that tolerates tiny entries.
fn rel_err(a: &[f64], b: &[f64], floor: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let scale = b.iter().map(|y| y.abs()).fold(floor, f64::max);
    diff / scale
}

/// Per-column version of [`rel_err`] for column-major nx × m matrices.
fn max_col_rel_err(a: &[f64], b: &[f64], nx: usize, floor: f64) -> f64 {
    a.chunks(nx)
        .zip(b.chunks(nx))
        .map(|(ca, cb)| rel_err(ca, cb, floor))
        .fold(0.0, f64::max)
}

// ---------------------------------------------------------------------------------------
// 1. Linear ODE with closed-form solution
// ---------------------------------------------------------------------------------------

/// Damped oscillator ẋ = A x + B p with A = [[0, 1], [−k, −c]], B = [[0, 0], [1, 0.5]].
///
/// With α = c/2, β = √(k − α²):  e^{At} = e^{−αt} (cos βt I + sin βt / β (A + αI)),
/// x(t) = e^{A(t−t0)} x0 + A⁻¹ (e^{A(t−t0)} − I) B p.
struct Oscillator;

const K: f64 = 4.0;
const C: f64 = 0.6;

impl Oscillator {
    fn a() -> Matrix2<f64> {
        Matrix2::new(0.0, 1.0, -K, -C)
    }
    fn b() -> Matrix2<f64> {
        Matrix2::new(0.0, 0.0, 1.0, 0.5)
    }
    fn expm(t: f64) -> Matrix2<f64> {
        let alpha = C / 2.0;
        let beta = (K - alpha * alpha).sqrt();
        (-alpha * t).exp()
            * ((beta * t).cos() * Matrix2::identity()
                + (beta * t).sin() / beta * (Self::a() + alpha * Matrix2::identity()))
    }
    /// Exact x(t1) and S(t1) = [∂x/∂x0 | ∂x/∂p] (column-major, 2 × 4).
    fn exact(t0: f64, t1: f64, x0: &[f64], p: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let e = Self::expm(t1 - t0);
        let a_inv = Self::a().try_inverse().expect("A is invertible");
        let g = a_inv * (e - Matrix2::identity()) * Self::b();
        let x = e * Vector2::new(x0[0], x0[1]) + g * Vector2::new(p[0], p[1]);
        let mut s = Vec::new();
        s.extend_from_slice(e.as_slice());
        s.extend_from_slice(g.as_slice());
        (x.as_slice().to_vec(), s)
    }
}

impl Ode for Oscillator {
    fn nx(&self) -> usize {
        2
    }
    fn np(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, x: &[f64], p: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        xdot[0] = x[1];
        xdot[1] = -K * x[0] - C * x[1] + p[0] + 0.5 * p[1];
        Ok(())
    }
    fn jacobians(
        &self,
        t: f64,
        x: &[f64],
        p: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fp: &mut [f64],
    ) -> Result<(), OdeError> {
        self.rhs(t, x, p, xdot)?;
        fx.copy_from_slice(Self::a().as_slice());
        fp.copy_from_slice(Self::b().as_slice());
        Ok(())
    }
}

const OSC_X0: [f64; 2] = [1.0, -0.4];
const OSC_P: [f64; 2] = [0.7, -1.3];

fn check_linear_against_closed_form(method: Method) {
    let mut integrator = Integrator::new(2, 2, settings(1e-10, method)).expect("integrator");
    let (t0, t1) = (0.3, 2.8);
    let (x_exact, s_exact) = Oscillator::exact(t0, t1, &OSC_X0, &OSC_P);

    let mut x1 = [0.0; 2];
    let mut s1 = [0.0; 8];
    let stats = integrator
        .integrate_with_sensitivities(&Oscillator, t0, t1, &OSC_X0, &OSC_P, &mut x1, &mut s1)
        .expect("integration with sensitivities");
    assert!(
        rel_err(&x1, &x_exact, 1e-12) < 1e-7,
        "{method:?}: x1 {x1:?} vs {x_exact:?}"
    );
    let e = max_col_rel_err(&s1, &s_exact, 2, 1e-12);
    assert!(e < 1e-7, "{method:?}: S rel err {e:e}\n{s1:?}\n{s_exact:?}");
    assert!(stats.steps > 0 && stats.rhs_evals > 0 && stats.sens_rhs_evals > 0);
    assert!(
        stats.jac_evals > 0,
        "exact Jacobian must be used: {stats:?}"
    );

    let mut x_plain = [0.0; 2];
    let stats = integrator
        .integrate(&Oscillator, t0, t1, &OSC_X0, &OSC_P, &mut x_plain)
        .expect("plain");
    assert!(
        rel_err(&x_plain, &x_exact, 1e-12) < 1e-7,
        "{method:?}: {x_plain:?}"
    );
    assert_eq!(stats.sens_rhs_evals, 0);
}

#[test]
fn linear_ode_matches_matrix_exponential_bdf() {
    check_linear_against_closed_form(Method::Bdf);
}

#[test]
fn linear_ode_matches_matrix_exponential_adams() {
    check_linear_against_closed_form(Method::Adams);
}

// ---------------------------------------------------------------------------------------
// 2. Nonlinear ODE: sensitivities vs central finite differences
// ---------------------------------------------------------------------------------------

/// Forced Van der Pol oscillator: ẋ1 = x2, ẋ2 = μ (1 − x1²) x2 − x1 + b, p = [μ, b].
struct VanDerPol;

impl Ode for VanDerPol {
    fn nx(&self) -> usize {
        2
    }
    fn np(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, x: &[f64], p: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        xdot[0] = x[1];
        xdot[1] = p[0] * (1.0 - x[0] * x[0]) * x[1] - x[0] + p[1];
        Ok(())
    }
    fn jacobians(
        &self,
        t: f64,
        x: &[f64],
        p: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fp: &mut [f64],
    ) -> Result<(), OdeError> {
        self.rhs(t, x, p, xdot)?;
        fx.copy_from_slice(&[
            0.0,
            -2.0 * p[0] * x[0] * x[1] - 1.0,
            1.0,
            p[0] * (1.0 - x[0] * x[0]),
        ]);
        fp.copy_from_slice(&[0.0, (1.0 - x[0] * x[0]) * x[1], 0.0, 1.0]);
        Ok(())
    }
}

/// Central differences of the end state with respect to (x0, p), column-major nx × (nx + np).
fn finite_difference_sensitivities(
    integrator: &mut Integrator,
    ode: &dyn Ode,
    t0: f64,
    t1: f64,
    x0: &[f64],
    p: &[f64],
    h: f64,
) -> Vec<f64> {
    let (nx, np) = (x0.len(), p.len());
    let mut s = Vec::with_capacity(nx * (nx + np));
    let mut plus = vec![0.0; nx];
    let mut minus = vec![0.0; nx];
    for j in 0..nx + np {
        let (mut xp, mut xm, mut pp, mut pm) = (x0.to_vec(), x0.to_vec(), p.to_vec(), p.to_vec());
        if j < nx {
            xp[j] += h;
            xm[j] -= h;
        } else {
            pp[j - nx] += h;
            pm[j - nx] -= h;
        }
        integrator
            .integrate(ode, t0, t1, &xp, &pp, &mut plus)
            .expect("FD plus");
        integrator
            .integrate(ode, t0, t1, &xm, &pm, &mut minus)
            .expect("FD minus");
        s.extend(plus.iter().zip(&minus).map(|(a, b)| (a - b) / (2.0 * h)));
    }
    s
}

#[test]
fn van_der_pol_sensitivities_match_finite_differences() {
    let mut integrator = Integrator::new(2, 2, settings(1e-12, Method::Bdf)).expect("integrator");
    let (x0, p) = ([1.5, -0.5], [1.2, 0.3]);
    let (t0, t1) = (0.0, 3.0);
    let mut x1 = [0.0; 2];
    let mut s1 = [0.0; 8];
    integrator
        .integrate_with_sensitivities(&VanDerPol, t0, t1, &x0, &p, &mut x1, &mut s1)
        .expect("sensitivities");
    let fd = finite_difference_sensitivities(&mut integrator, &VanDerPol, t0, t1, &x0, &p, 1e-6);
    let e = rel_err(&s1, &fd, 1e-8);
    assert!(e < 1e-5, "rel err {e:e}\nCVODES {s1:?}\nFD     {fd:?}");
    // Guard against a vacuous comparison: the sensitivities are far from [I | 0].
    assert!(s1.iter().map(|v| v.abs()).fold(0.0, f64::max) > 0.1);
}

/// A looser sensitivity tolerance (`sens_tol`) keeps the states at their own tolerance,
/// gives sensitivities accurate to the looser one, and takes fewer steps than
/// sensitivities held to the states' tolerance.
#[test]
fn looser_sensitivity_tolerance_keeps_the_states_and_costs_fewer_steps() {
    let (x0, p) = ([1.5, -0.5], [1.2, 0.3]);
    let (t0, t1) = (0.0, 3.0);
    let run = |s: IntegratorSettings| {
        let mut integrator = Integrator::new(2, 2, s).expect("integrator");
        let (mut x1, mut s1) = ([0.0; 2], [0.0; 8]);
        let stats = integrator
            .integrate_with_sensitivities(&VanDerPol, t0, t1, &x0, &p, &mut x1, &mut s1)
            .expect("sensitivities");
        (x1, s1, stats)
    };
    let (x_tight, _, tight) = run(settings(1e-10, Method::Bdf));
    let (x_loose, s_loose, loose) = run(IntegratorSettings {
        sens_tol: Some(1e-6),
        ..settings(1e-10, Method::Bdf)
    });
    let mut reference = Integrator::new(2, 2, settings(1e-12, Method::Bdf)).expect("integrator");
    let fd = finite_difference_sensitivities(&mut reference, &VanDerPol, t0, t1, &x0, &p, 1e-6);
    let e = rel_err(&x_loose, &x_tight, 1e-8);
    assert!(
        e < 1e-8,
        "states: rel err {e:e} between {x_loose:?} and {x_tight:?}"
    );
    let e = rel_err(&s_loose, &fd, 1e-8);
    assert!(
        e < 1e-4,
        "sensitivities at 1e-6: rel err {e:e}\nCVODES {s_loose:?}\nFD     {fd:?}"
    );
    assert!(
        loose.steps < tight.steps,
        "steps: sensitivities at 1e-6 {loose:?}, at 1e-10 {tight:?}"
    );
}

// ---------------------------------------------------------------------------------------
// 3. ShootingInterval
// ---------------------------------------------------------------------------------------

/// Pendulum with damping 0.2, gravity parameter θ and a torque u acting through cos x1:
/// ẋ1 = x2, ẋ2 = −θ sin x1 − 0.2 x2 + u cos x1.
struct Pendulum;

impl ControlledOde for Pendulum {
    fn nx(&self) -> usize {
        2
    }
    fn nu(&self) -> usize {
        1
    }
    fn ntheta(&self) -> usize {
        1
    }
    fn f(&self, x: &[f64], u: &[f64], theta: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        xdot[0] = x[1];
        xdot[1] = -theta[0] * x[0].sin() - 0.2 * x[1] + u[0] * x[0].cos();
        Ok(())
    }
    fn f_jac(
        &self,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fu: &mut [f64],
        ftheta: &mut [f64],
    ) -> Result<(), OdeError> {
        self.f(x, u, theta, xdot)?;
        let (s, c) = x[0].sin_cos();
        fx.copy_from_slice(&[0.0, -theta[0] * c - u[0] * s, 1.0, -0.2]);
        fu.copy_from_slice(&[0.0, c]);
        ftheta.copy_from_slice(&[0.0, -s]);
        Ok(())
    }
}

/// The same model in physical time t ∈ [0, T] with u(t) = u0 + (u1 − u0) t / T: an
/// independent check of the time normalisation.  p = [u0, u1, T, θ].
struct PhysicalTime;

impl Ode for PhysicalTime {
    fn nx(&self) -> usize {
        2
    }
    fn np(&self) -> usize {
        4
    }
    fn rhs(&self, t: f64, x: &[f64], p: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        let u = p[0] + (p[1] - p[0]) * t / p[2];
        Pendulum.f(x, &[u], &p[3..], xdot)
    }
    fn jacobians(
        &self,
        t: f64,
        x: &[f64],
        p: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fp: &mut [f64],
    ) -> Result<(), OdeError> {
        // Only fx is needed for the Newton matrix of a plain integration.
        let u = p[0] + (p[1] - p[0]) * t / p[2];
        let (mut fu, mut ft) = ([0.0; 2], [0.0; 2]);
        Pendulum.f_jac(x, &[u], &p[3..], xdot, fx, &mut fu, &mut ft)?;
        fp.fill(0.0);
        Ok(())
    }
}

fn check_shooting_interval(shape: ControlShape) {
    let interval = ShootingInterval::new(&Pendulum, shape);
    let u1 = [-0.4];
    let u1_arg = (shape == ControlShape::Linear).then_some(&u1[..]);
    let mut p = Vec::new();
    interval
        .pack_params(&[0.9], u1_arg, 1.7, &[9.0], &mut p)
        .expect("pack");
    let np = interval.np();
    assert_eq!(p.len(), np);
    assert_eq!(np, if shape == ControlShape::Linear { 4 } else { 3 });
    assert_eq!(p[interval.p_duration()], 1.7);
    assert_eq!(&p[interval.p_theta()], &[9.0]);
    assert_eq!(&p[interval.p_u0()], &[0.9]);
    if let Some(r) = interval.p_u1() {
        assert_eq!(&p[r], &u1);
    }

    let x0 = [0.6, -0.3];
    let mut integrator = Integrator::new(2, np, settings(1e-12, Method::Bdf)).expect("integrator");
    let mut x1 = [0.0; 2];
    let mut s1 = vec![0.0; 2 * (2 + np)];
    integrator
        .integrate_with_sensitivities(&interval, 0.0, 1.0, &x0, &p, &mut x1, &mut s1)
        .expect("sensitivities");
    let fd = finite_difference_sensitivities(&mut integrator, &interval, 0.0, 1.0, &x0, &p, 1e-6);
    let e = max_col_rel_err(&s1, &fd, 2, 1e-6);
    assert!(
        e < 1e-5,
        "{shape:?}: rel err {e:e}\nCVODES {s1:?}\nFD     {fd:?}"
    );
    // ∂x(1)/∂T must be non-trivial and ∂/∂u1 must be present for linear controls.
    assert!(s1[2 * (2 + interval.p_duration())..][..2]
        .iter()
        .any(|v| v.abs() > 1e-2));

    // Same end state as the model integrated in physical time over [0, T].
    let u1_phys = if shape == ControlShape::Linear {
        u1[0]
    } else {
        0.9
    };
    let p_phys = [0.9, u1_phys, 1.7, 9.0];
    let mut physical = Integrator::new(2, 4, settings(1e-12, Method::Bdf)).expect("integrator");
    let mut x_phys = [0.0; 2];
    physical
        .integrate(&PhysicalTime, 0.0, 1.7, &x0, &p_phys, &mut x_phys)
        .expect("physical");
    assert!(
        rel_err(&x1, &x_phys, 1e-12) < 1e-8,
        "{shape:?}: {x1:?} vs {x_phys:?}"
    );
}

#[test]
fn shooting_interval_constant_controls() {
    check_shooting_interval(ControlShape::Constant);
}

#[test]
fn shooting_interval_linear_controls() {
    check_shooting_interval(ControlShape::Linear);
}

#[test]
fn shooting_interval_rejects_bad_parameter_packing() {
    let constant = ShootingInterval::new(&Pendulum, ControlShape::Constant);
    let linear = ShootingInterval::new(&Pendulum, ControlShape::Linear);
    let mut p = Vec::new();
    assert!(matches!(
        constant.pack_params(&[1.0, 2.0], None, 1.0, &[9.0], &mut p),
        Err(IntegratorError::Dimension {
            what: "u0",
            expected: 1,
            found: 2
        })
    ));
    assert!(constant
        .pack_params(&[1.0], Some(&[1.0]), 1.0, &[9.0], &mut p)
        .is_err());
    assert!(linear
        .pack_params(&[1.0], None, 1.0, &[9.0], &mut p)
        .is_err());
    assert!(linear
        .pack_params(&[1.0], Some(&[1.0]), 1.0, &[], &mut p)
        .is_err());
}

// ---------------------------------------------------------------------------------------
// 4. Reuse
// ---------------------------------------------------------------------------------------

#[test]
fn reused_integrator_is_bit_reproducible() {
    let (x0, p) = ([1.5, -0.5], [1.2, 0.3]);
    let run = |integrator: &mut Integrator, with_sens: bool| -> (Vec<f64>, IntegrationStats) {
        let mut x1 = [0.0; 2];
        let mut s1 = [0.0; 8];
        let stats = if with_sens {
            integrator.integrate_with_sensitivities(&VanDerPol, 0.0, 2.5, &x0, &p, &mut x1, &mut s1)
        } else {
            integrator.integrate(&VanDerPol, 0.0, 2.5, &x0, &p, &mut x1)
        }
        .expect("integration");
        let mut all = x1.to_vec();
        all.extend_from_slice(&s1);
        (all, stats)
    };
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();

    let mut fresh_plain = Integrator::new(2, 2, IntegratorSettings::default()).expect("new");
    let mut fresh_sens = Integrator::new(2, 2, IntegratorSettings::default()).expect("new");
    let (plain_ref, plain_stats) = run(&mut fresh_plain, false);
    let (sens_ref, sens_stats) = run(&mut fresh_sens, true);

    let mut reused = Integrator::new(2, 2, IntegratorSettings::default()).expect("new");
    for round in 0..3 {
        let (plain, stats) = run(&mut reused, false);
        assert_eq!(bits(&plain), bits(&plain_ref), "plain, round {round}");
        assert_eq!(stats, plain_stats, "plain stats, round {round}");
        let (sens, stats) = run(&mut reused, true);
        assert_eq!(bits(&sens), bits(&sens_ref), "sensitivities, round {round}");
        assert_eq!(stats, sens_stats, "sensitivity stats, round {round}");
    }
    // A failed call in between must not change later results.
    let mut x1 = [0.0; 2];
    assert!(reused
        .integrate(&VanDerPol, 0.0, 2.5, &[f64::NAN, 0.0], &p, &mut x1)
        .is_err());
    assert!(reused
        .integrate(&FailsAfter(0.5), 0.0, 2.5, &[1.0, 0.0], &p, &mut x1)
        .is_err());
    assert_eq!(bits(&run(&mut reused, true).0), bits(&sens_ref));
    assert_eq!(bits(&run(&mut reused, false).0), bits(&plain_ref));
}

#[test]
fn integrator_moves_across_threads() {
    fn assert_send<T: Send>() {}
    assert_send::<Integrator>();
    let mut integrator = Integrator::new(2, 2, IntegratorSettings::default()).expect("new");
    let handle = std::thread::spawn(move || {
        let mut x1 = [0.0; 2];
        integrator
            .integrate(&Oscillator, 0.0, 1.0, &OSC_X0, &OSC_P, &mut x1)
            .map(|_| x1)
    });
    let x1 = handle.join().expect("thread").expect("integration");
    let (exact, _) = Oscillator::exact(0.0, 1.0, &OSC_X0, &OSC_P);
    assert!(rel_err(&x1, &exact, 1e-12) < 1e-6);
}

// ---------------------------------------------------------------------------------------
// 5. Dense output
// ---------------------------------------------------------------------------------------

#[test]
fn dense_output_matches_point_integrations_and_closed_form() {
    let mut integrator = Integrator::new(2, 2, settings(1e-10, Method::Bdf)).expect("integrator");
    let (t0, t1) = (0.3, 2.8);
    let times = [0.3, 0.31, 0.75, 1.2, 2.0, 2.8];
    let mut out = vec![-1.0]; // existing content must be kept
    integrator
        .integrate_dense(&Oscillator, t0, t1, &OSC_X0, &OSC_P, &times, &mut out)
        .expect("dense");
    assert_eq!(out.len(), 1 + 2 * times.len());
    assert_eq!(out[0], -1.0);
    for (k, &t) in times.iter().enumerate() {
        let row = &out[1 + 2 * k..3 + 2 * k];
        let (exact, _) = Oscillator::exact(t0, t, &OSC_X0, &OSC_P);
        assert!(
            rel_err(row, &exact, 1e-12) < 1e-7,
            "t = {t}: {row:?} vs {exact:?}"
        );
        if t > t0 {
            let mut x = [0.0; 2];
            integrator
                .integrate(&Oscillator, t0, t, &OSC_X0, &OSC_P, &mut x)
                .expect("point");
            assert!(rel_err(row, &x, 1e-12) < 1e-7, "t = {t}: {row:?} vs {x:?}");
        } else {
            assert_eq!(row, &OSC_X0[..]);
        }
    }
}

#[test]
fn dense_output_rejects_bad_times_and_leaves_output_untouched() {
    let mut integrator = Integrator::new(2, 2, IntegratorSettings::default()).expect("new");
    let mut out = vec![7.0];
    let cases: [(&[f64], usize); 4] = [
        (&[0.5, 0.5], 1),
        (&[0.5, 0.2], 1),
        (&[-0.1], 0),
        (&[0.5, 1.5], 1),
    ];
    for (times, bad_index) in cases {
        let err = integrator
            .integrate_dense(&Oscillator, 0.0, 1.0, &OSC_X0, &OSC_P, times, &mut out)
            .expect_err("bad times");
        assert!(
            matches!(err, IntegratorError::BadOutputTime { index, .. } if index == bad_index),
            "{times:?}: {err:?}"
        );
    }
    let err = integrator
        .integrate_dense(
            &FailsAfter(0.5),
            0.0,
            1.0,
            &[1.0, 0.0],
            &OSC_P,
            &[0.2, 0.9],
            &mut out,
        )
        .expect_err("fatal ODE");
    assert!(matches!(err, IntegratorError::Rhs { .. }), "{err:?}");
    assert_eq!(out, vec![7.0]);
}

// ---------------------------------------------------------------------------------------
// 6. Errors
// ---------------------------------------------------------------------------------------

/// ẋ = −x, failing fatally for t > t_fail.
struct FailsAfter(f64);

impl Ode for FailsAfter {
    fn nx(&self) -> usize {
        2
    }
    fn np(&self) -> usize {
        2
    }
    fn rhs(&self, t: f64, x: &[f64], _p: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        if t > self.0 {
            return Err(OdeError::Fatal(format!("model undefined at t = {t}")));
        }
        xdot[0] = -x[0];
        xdot[1] = -x[1];
        Ok(())
    }
    fn jacobians(
        &self,
        t: f64,
        x: &[f64],
        p: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fp: &mut [f64],
    ) -> Result<(), OdeError> {
        self.rhs(t, x, p, xdot)?;
        fx.copy_from_slice(&[-1.0, 0.0, 0.0, -1.0]);
        fp.fill(0.0);
        Ok(())
    }
}

/// ẋ = x² (blows up at t = 1/x0), with an optional panic or recoverable failure mode.
struct Scalar {
    mode: ScalarMode,
}

#[derive(PartialEq)]
enum ScalarMode {
    Square,
    PanicAfter(f64),
    AlwaysRecoverable,
}

impl Ode for Scalar {
    fn nx(&self) -> usize {
        1
    }
    fn np(&self) -> usize {
        0
    }
    fn rhs(&self, t: f64, x: &[f64], _p: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        match self.mode {
            ScalarMode::PanicAfter(tp) if t > tp => panic!("test panic in rhs"),
            ScalarMode::AlwaysRecoverable => {
                return Err(OdeError::Recoverable("outside model domain".into()))
            }
            _ => {}
        }
        xdot[0] = x[0] * x[0];
        Ok(())
    }
    fn jacobians(
        &self,
        t: f64,
        x: &[f64],
        p: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        _fp: &mut [f64],
    ) -> Result<(), OdeError> {
        self.rhs(t, x, p, xdot)?;
        fx[0] = 2.0 * x[0];
        Ok(())
    }
}

#[test]
fn fatal_rhs_error_reports_its_time() {
    let mut integrator = Integrator::new(2, 2, IntegratorSettings::default()).expect("new");
    let mut x1 = [0.0; 2];
    let mut s1 = [0.0; 8];
    let before = x1;
    let err = integrator
        .integrate(&FailsAfter(0.7), 0.0, 2.0, &[1.0, 2.0], &OSC_P, &mut x1)
        .expect_err("must fail");
    match &err {
        IntegratorError::Rhs {
            t,
            source: OdeError::Fatal(msg),
        } => {
            assert!(*t > 0.7 && *t < 0.9, "t = {t}");
            assert!(msg.contains("model undefined"), "{msg}");
        }
        other => panic!("expected Rhs, got {other:?}"),
    }
    assert!(err.to_string().contains("t = "), "{err}");
    assert_eq!(x1, before, "outputs must be untouched on error");

    let err = integrator
        .integrate_with_sensitivities(
            &FailsAfter(0.7),
            0.0,
            2.0,
            &[1.0, 2.0],
            &OSC_P,
            &mut x1,
            &mut s1,
        )
        .expect_err("must fail");
    assert!(
        matches!(err, IntegratorError::Rhs { t, .. } if t > 0.7 && t < 0.9),
        "{err:?}"
    );
}

/// ẋ = −x whose Jacobians fail fatally for t > 0.4 (the right-hand side never fails).
struct JacobianFailsAfter;

impl Ode for JacobianFailsAfter {
    fn nx(&self) -> usize {
        1
    }
    fn np(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, x: &[f64], p: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        xdot[0] = -p[0] * x[0];
        Ok(())
    }
    fn jacobians(
        &self,
        t: f64,
        x: &[f64],
        p: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fp: &mut [f64],
    ) -> Result<(), OdeError> {
        if t > 0.4 {
            return Err(OdeError::Fatal("no Jacobian".into()));
        }
        self.rhs(t, x, p, xdot)?;
        fx[0] = -p[0];
        fp[0] = -x[0];
        Ok(())
    }
}

#[test]
fn fatal_jacobian_error_in_sensitivity_rhs_is_reported() {
    let mut integrator = Integrator::new(1, 1, IntegratorSettings::default()).expect("new");
    let (mut x1, mut s1) = ([0.0], [0.0; 2]);
    let err = integrator
        .integrate_with_sensitivities(
            &JacobianFailsAfter,
            0.0,
            1.0,
            &[1.0],
            &[1.0],
            &mut x1,
            &mut s1,
        )
        .expect_err("must fail");
    match err {
        IntegratorError::Rhs { t, source } => {
            assert!(t > 0.4 && t < 0.6, "t = {t}");
            assert_eq!(source, OdeError::Fatal("no Jacobian".into()));
        }
        other => panic!("expected Rhs, got {other:?}"),
    }
}

#[test]
fn shooting_interval_rejects_wrong_lengths_without_panicking() {
    let interval = ShootingInterval::new(&Pendulum, ControlShape::Linear);
    let mut xdot = [0.0; 2];
    let err = interval
        .rhs(0.5, &[0.0, 0.0], &[1.0, 2.0], &mut xdot)
        .expect_err("short p");
    assert!(matches!(err, OdeError::Fatal(_)), "{err:?}");
    let (mut fx, mut fp) = ([0.0; 4], [0.0; 6]);
    let p = [1.0, 2.0, 1.0, 9.0];
    let err = interval
        .jacobians(0.5, &[0.0, 0.0], &p, &mut xdot, &mut fx, &mut fp)
        .expect_err("short fp");
    assert!(matches!(err, OdeError::Fatal(_)), "{err:?}");
}

#[test]
fn panic_in_rhs_becomes_an_error() {
    let mut integrator = Integrator::new(1, 0, IntegratorSettings::default()).expect("new");
    let mut x1 = [0.0];
    let ode = Scalar {
        mode: ScalarMode::PanicAfter(0.2),
    };
    let err = integrator
        .integrate(&ode, 0.0, 0.5, &[0.5], &[], &mut x1)
        .expect_err("panic");
    match err {
        IntegratorError::Rhs {
            t,
            source: OdeError::Fatal(msg),
        } => {
            assert!(t > 0.2 && t < 0.5, "t = {t}");
            assert!(msg.contains("test panic in rhs"), "{msg}");
        }
        other => panic!("expected Rhs, got {other:?}"),
    }
    // The integrator is still usable afterwards: ẋ = x², x(0) = 0.5 → x(0.5) = 0.5 / 0.75.
    let ode = Scalar {
        mode: ScalarMode::Square,
    };
    integrator
        .integrate(&ode, 0.0, 0.5, &[0.5], &[], &mut x1)
        .expect("after panic");
    assert!((x1[0] - 0.5 / 0.75).abs() < 1e-6, "{}", x1[0]);
}

#[test]
fn persistent_recoverable_error_fails_with_cvodes_flag() {
    let mut integrator = Integrator::new(1, 0, IntegratorSettings::default()).expect("new");
    let mut x1 = [0.0];
    let ode = Scalar {
        mode: ScalarMode::AlwaysRecoverable,
    };
    let err = integrator
        .integrate(&ode, 0.0, 1.0, &[0.5], &[], &mut x1)
        .expect_err("fails");
    match err {
        IntegratorError::Failed {
            flag,
            flag_name,
            message,
            ..
        } => {
            assert!(flag < 0);
            assert!(flag_name.starts_with("CV_"), "{flag_name}");
            assert!(message.contains("outside model domain"), "{message}");
        }
        other => panic!("expected Failed, got {other:?}"),
    }
}

#[test]
fn blow_up_is_an_error_not_a_panic() {
    let mut integrator = Integrator::new(1, 0, IntegratorSettings::default()).expect("new");
    let mut x1 = [0.0];
    let ode = Scalar {
        mode: ScalarMode::Square,
    };
    let err = integrator
        .integrate(&ode, 0.0, 2.0, &[1.0], &[], &mut x1)
        .expect_err("blow-up");
    match &err {
        IntegratorError::Failed {
            t,
            flag_name,
            message,
            ..
        } => {
            assert!(*t > 0.99 && *t <= 1.0 + 1e-6, "t = {t}");
            assert!(!flag_name.is_empty() && !message.is_empty(), "{err:?}");
        }
        IntegratorError::NonFinite { .. } => {}
        other => panic!("expected Failed or NonFinite, got {other:?}"),
    }
    assert_eq!(x1, [0.0]);
    let mut s1 = [0.0];
    let err = integrator
        .integrate_with_sensitivities(&ode, 0.0, 2.0, &[1.0], &[], &mut x1, &mut s1)
        .expect_err("blow-up");
    assert!(
        matches!(
            err,
            IntegratorError::Failed { .. } | IntegratorError::NonFinite { .. }
        ),
        "{err:?}"
    );
}

#[test]
fn invalid_inputs_are_rejected() {
    let mut integrator = Integrator::new(2, 2, IntegratorSettings::default()).expect("new");
    let mut x1 = [0.0; 2];
    let mut s1 = [0.0; 8];
    let ode = &Oscillator;

    for (t0, t1) in [
        (1.0, 1.0),
        (1.0, 0.5),
        (0.0, f64::NAN),
        (f64::NEG_INFINITY, 1.0),
    ] {
        let err = integrator
            .integrate(ode, t0, t1, &OSC_X0, &OSC_P, &mut x1)
            .expect_err("interval");
        assert!(
            matches!(err, IntegratorError::BadInterval { .. }),
            "{err:?}"
        );
    }
    let err = integrator
        .integrate(ode, 0.0, 1.0, &[1.0], &OSC_P, &mut x1)
        .expect_err("x0");
    assert_eq!(
        err,
        IntegratorError::Dimension {
            what: "x0",
            expected: 2,
            found: 1
        }
    );
    let err = integrator
        .integrate(ode, 0.0, 1.0, &OSC_X0, &[1.0], &mut x1)
        .expect_err("p");
    assert!(
        matches!(err, IntegratorError::Dimension { what: "p", .. }),
        "{err:?}"
    );
    let err = integrator
        .integrate_with_sensitivities(ode, 0.0, 1.0, &OSC_X0, &OSC_P, &mut x1, &mut s1[..6])
        .expect_err("s1");
    assert!(
        matches!(
            err,
            IntegratorError::Dimension {
                expected: 8,
                found: 6,
                ..
            }
        ),
        "{err:?}"
    );
    let scalar = Scalar {
        mode: ScalarMode::Square,
    };
    let err = integrator
        .integrate(&scalar, 0.0, 1.0, &OSC_X0, &OSC_P, &mut x1)
        .expect_err("nx");
    assert!(matches!(err, IntegratorError::Dimension { .. }), "{err:?}");

    let err = integrator
        .integrate(ode, 0.0, 1.0, &[f64::NAN, 0.0], &OSC_P, &mut x1)
        .expect_err("NaN x0");
    assert_eq!(err, IntegratorError::NonFinite { t: 0.0 });
    let err = integrator
        .integrate(ode, 0.0, 1.0, &OSC_X0, &[0.0, f64::INFINITY], &mut x1)
        .expect_err("inf p");
    assert_eq!(err, IntegratorError::NonFinite { t: 0.0 });
    assert_eq!(x1, [0.0; 2]);

    assert!(matches!(
        Integrator::new(0, 1, IntegratorSettings::default()),
        Err(IntegratorError::Dimension { .. })
    ));
}

#[test]
fn bad_settings_are_rejected() {
    let bad = [
        (
            "rtol",
            IntegratorSettings {
                rtol: -1e-6,
                ..Default::default()
            },
        ),
        (
            "rtol",
            IntegratorSettings {
                rtol: f64::NAN,
                ..Default::default()
            },
        ),
        (
            "atol",
            IntegratorSettings {
                atol: 0.0,
                ..Default::default()
            },
        ),
        (
            "max_steps",
            IntegratorSettings {
                max_steps: 0,
                ..Default::default()
            },
        ),
        (
            "max_order",
            IntegratorSettings {
                max_order: Some(6),
                ..Default::default()
            },
        ),
        (
            "initial_step",
            IntegratorSettings {
                initial_step: Some(-0.1),
                ..Default::default()
            },
        ),
        (
            "sens_tol",
            IntegratorSettings {
                sens_tol: Some(0.0),
                ..Default::default()
            },
        ),
        (
            "sens_tol",
            IntegratorSettings {
                sens_tol: Some(f64::INFINITY),
                ..Default::default()
            },
        ),
    ];
    for (name, s) in bad {
        match Integrator::new(2, 0, s) {
            Err(IntegratorError::BadSettings { field, .. }) => assert_eq!(field, name),
            other => panic!("{name}: expected BadSettings, got {other:?}"),
        }
    }
    let adams_order_12 = IntegratorSettings {
        method: Method::Adams,
        max_order: Some(12),
        ..Default::default()
    };
    assert!(Integrator::new(2, 0, adams_order_12).is_ok());
}

#[test]
fn settings_deserialize_with_defaults_and_reject_unknown_fields() {
    let s: IntegratorSettings =
        serde_json::from_str(r#"{"rtol": 1e-6, "method": "adams"}"#).expect("partial json");
    assert_eq!(s.rtol, 1e-6);
    assert_eq!(s.method, Method::Adams);
    assert_eq!(s.atol, IntegratorSettings::default().atol);
    assert!(serde_json::from_str::<IntegratorSettings>(r#"{"rtoll": 1e-6}"#).is_err());
}

/// The first time after `t0` at which `g(exact x(t))` falls through zero, by bisection on
/// the closed form (scanning in 1e-3 steps for the bracket).
fn closed_form_fall(t0: f64, g: impl Fn(&[f64]) -> f64) -> f64 {
    let x = |t: f64| Oscillator::exact(t0, t, &OSC_X0, &OSC_P).0;
    let mut lo = t0;
    while !(g(&x(lo)) > 0.0 && g(&x(lo + 1e-3)) <= 0.0) {
        lo += 1e-3;
        assert!(lo < t0 + 20.0, "no fall");
    }
    let mut hi = lo + 1e-3;
    for _ in 0..200 {
        let m = 0.5 * (lo + hi);
        if g(&x(m)) > 0.0 {
            lo = m;
        } else {
            hi = m;
        }
    }
    hi
}

/// Root finding stops at the first fall of the event through zero (rises are ignored),
/// returns the state there, and is switched off again for the next call.
#[test]
fn dense_output_until_an_event_stops_at_its_first_fall() {
    let mut integrator = Integrator::new(2, 2, settings(1e-10, Method::Bdf)).expect("integrator");
    let (t0, t1) = (0.3, 8.0);
    let times: Vec<f64> = (1..=77)
        .map(|k| t0 + 0.1 * k as f64)
        .filter(|&t| t <= t1)
        .collect();
    // x₀ falls through zero first; −x₀ starts negative, rises with that fall, and falls
    // when x₀ rises through zero
    let events: [(&str, fn(&[f64]) -> f64); 2] = [("x0", |x| x[0]), ("-x0", |x| -x[0])];
    for (name, g) in events {
        let truth = closed_form_fall(t0, g);
        let mut out = vec![-1.0];
        let event = move |_t: f64, x: &[f64]| g(x);
        let (_, root) = integrator
            .integrate_dense_until(
                &Oscillator,
                t0,
                t1,
                &OSC_X0,
                &OSC_P,
                &times,
                &event,
                &mut out,
            )
            .expect("until");
        let tr = root.expect("a root");
        assert!((tr - truth).abs() < 1e-8, "{name}: root {tr} vs {truth}");
        let before = times.iter().filter(|&&t| t < tr).count();
        assert_eq!(out.len(), 1 + 2 * (before + 1), "{name}");
        let last = &out[out.len() - 2..];
        let (exact, _) = Oscillator::exact(t0, tr, &OSC_X0, &OSC_P);
        assert!(
            rel_err(last, &exact, 1e-3) < 1e-7,
            "{name}: {last:?} vs {exact:?}"
        );
        assert!(g(last) <= 1e-12, "{name}: event {} at the root", g(last));
        eprintln!("{name}: root {tr:.12} (closed form {truth:.12}), {before} outputs before it");
    }
    // the next plain call has no root function: all outputs
    let mut out = Vec::new();
    integrator
        .integrate_dense(&Oscillator, t0, t1, &OSC_X0, &OSC_P, &times, &mut out)
        .expect("dense");
    assert_eq!(out.len(), 2 * times.len());
    // no fall within the interval: every output and no root
    let mut out = Vec::new();
    let never = |_t: f64, _x: &[f64]| 1.0;
    let (_, root) = integrator
        .integrate_dense_until(
            &Oscillator,
            t0,
            t1,
            &OSC_X0,
            &OSC_P,
            &times,
            &never,
            &mut out,
        )
        .expect("until");
    assert_eq!((root, out.len()), (None, 2 * times.len()));
}

/// `set_tolerances` re-tolerances a live integrator (as the inexact SQP does near an
/// optimum): against the closed form, the state and sensitivity errors at 1e-4 shrink by
/// orders of magnitude at 1e-10, with more steps, and back at 1e-4 the integrator gives
/// the bits of a fresh one at 1e-4.
#[test]
fn tightened_tolerances_shrink_the_error_against_the_closed_form() {
    let (t0, t1) = (0.3, 2.8);
    let (x_exact, s_exact) = Oscillator::exact(t0, t1, &OSC_X0, &OSC_P);
    let run = |integ: &mut Integrator| {
        let (mut x1, mut s1) = ([0.0; 2], [0.0; 8]);
        let stats = integ
            .integrate_with_sensitivities(&Oscillator, t0, t1, &OSC_X0, &OSC_P, &mut x1, &mut s1)
            .expect("integration");
        (
            rel_err(&x1, &x_exact, 1e-12),
            max_col_rel_err(&s1, &s_exact, 2, 1e-12),
            stats.steps,
            x1,
        )
    };
    let mut integ = Integrator::new(2, 2, settings(1e-4, Method::Bdf)).expect("integrator");
    let (ex_loose, es_loose, steps_loose, x_loose) = run(&mut integ);
    integ.set_tolerances(1e-10, 1e-10, None).expect("tighten");
    assert_eq!(integ.settings().rtol, 1e-10);
    let (ex_tight, es_tight, steps_tight, _) = run(&mut integ);
    assert!(
        ex_tight < 1e-3 * ex_loose && es_tight < 1e-3 * es_loose,
        "states {ex_loose:e} → {ex_tight:e}, sensitivities {es_loose:e} → {es_tight:e}"
    );
    assert!(
        ex_tight < 1e-7 && es_tight < 1e-7,
        "{ex_tight:e} {es_tight:e}"
    );
    assert!(
        steps_tight > 2 * steps_loose,
        "{steps_loose} → {steps_tight} steps"
    );
    integ.set_tolerances(1e-4, 1e-4, None).expect("loosen");
    let (_, _, _, x_again) = run(&mut integ);
    assert_eq!(x_again, x_loose);
    // invalid tolerances are refused and change nothing
    assert!(integ.set_tolerances(0.0, 1e-4, None).is_err());
    assert_eq!(integ.settings().rtol, 1e-4);
}

// ---------------------------------------------------------------------------------------
// 5. Backward adjoints and their moments (the stiff curvature's weights)
// ---------------------------------------------------------------------------------------

/// A stiff linear ODE ẋ = A x with A = [[−1, 1], [0, −λ]], λ = 1e5: a slow mode and one
/// decaying within 10 µs, like a compliant contact's damping.
struct StiffPair;

const STIFF: f64 = 1e5;

impl StiffPair {
    /// e^{A s}, closed form (upper triangular).
    fn expm(s: f64) -> Matrix2<f64> {
        let (e1, e2) = ((-s).exp(), (-STIFF * s).exp());
        Matrix2::new(e1, (e1 - e2) / (STIFF - 1.0), 0.0, e2)
    }
}

impl Ode for StiffPair {
    fn nx(&self) -> usize {
        2
    }
    fn np(&self) -> usize {
        0
    }
    fn rhs(&self, _t: f64, x: &[f64], _p: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        xdot[0] = -x[0] + x[1];
        xdot[1] = -STIFF * x[1];
        Ok(())
    }
    fn jacobians(
        &self,
        t: f64,
        x: &[f64],
        p: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        _fp: &mut [f64],
    ) -> Result<(), OdeError> {
        self.rhs(t, x, p, xdot)?;
        fx.copy_from_slice(&[-1.0, 0.0, 1.0, -STIFF]);
        Ok(())
    }
}

/// Lagrange polynomial `k` of `nodes` at `t`.
fn lagrange(nodes: &[f64], k: usize, t: f64) -> f64 {
    nodes
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != k)
        .map(|(_, &s)| (t - s) / (nodes[k] - s))
        .product()
}

/// `∫_a^b L_k(t) μ(t) dt` by the 4-point Gauss rule on `n` equal parts (brute force).
fn brute_moment(
    mu: &dyn Fn(f64) -> Vector2<f64>,
    nodes: &[f64],
    k: usize,
    a: f64,
    b: f64,
    n: usize,
) -> Vector2<f64> {
    const G: [(f64, f64); 4] = [
        (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
        (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
        (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
        (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
    ];
    let h = (b - a) / n as f64;
    let mut sum = Vector2::zeros();
    for part in 0..n {
        for &(g, w) in &G {
            let t = a + h * (part as f64 + g);
            sum += mu(t) * (lagrange(nodes, k, t) * w * h);
        }
    }
    sum
}

/// The adjoint moments of a stiff linear ODE against the closed form
/// `μ(t) = Σ_{t_j > t} e^{Aᵀ(t_j − t)} w_j` integrated by brute force (200,000 parts per
/// cell): on cells of 1, 2 and 4 nodes, with jumps at the end, inside the range (at cell
/// ends) and in a second sweep of its own, each component against its own size. Sampling
/// `μ` at the nodes instead (the rule `Σ_k w_k μ(t_k)`) misses the fast mode's 10 µs
/// boundary layer before each jump; the integrated moments agree to 1e-6 at the
/// integrator's tolerance 1e-12 (about 1e-5 at 1e-10: the error follows the tolerance).
#[test]
fn adjoint_moments_of_a_stiff_linear_ode_match_the_closed_form() {
    use footfall::integrate::AdjointSweep;
    let mut integrator = Integrator::new(2, 0, settings(1e-12, Method::Bdf)).expect("integrator");
    let jumps = vec![(1.0, vec![1.0, 2.0]), (0.5, vec![-0.5, 3.0])];
    let gauss2 = |a: f64, b: f64| {
        let h = b - a;
        vec![
            a + h * 0.211_324_865_405_187_1,
            a + h * 0.788_675_134_594_812_9,
        ]
    };
    let cells = vec![
        (0.0, 0.25, gauss2(0.0, 0.25)),
        (0.25, 0.5, vec![0.375]),
        (0.5, 1.0, vec![0.55, 0.7, 0.85, 0.97]),
    ];
    let own = AdjointSweep {
        jumps: vec![(0.5, vec![0.25, -1.0])],
        cells: vec![(0.3, 0.5, gauss2(0.3, 0.5))],
    };
    let sweeps = [
        AdjointSweep {
            jumps: jumps.clone(),
            cells: cells.clone(),
        },
        own.clone(),
    ];
    let x0 = [1.0, 0.5];
    let moments = integrator
        .adjoints(&StiffPair, 0.0, 1.0, &x0, &[], &sweeps)
        .expect("adjoints");
    let adjoint = |jumps: &[(f64, Vec<f64>)], t: f64| -> Vector2<f64> {
        jumps
            .iter()
            .filter(|(tj, _)| *tj > t)
            .map(|(tj, w)| StiffPair::expm(tj - t).transpose() * Vector2::new(w[0], w[1]))
            .sum()
    };
    let mut worst = 0.0f64;
    let mut sampled_worst = 0.0f64;
    for (sweep, got) in sweeps.iter().zip(&moments) {
        assert_eq!(got.len(), sweep.cells.len());
        for ((a, b, nodes), cell) in sweep.cells.iter().zip(got) {
            assert_eq!(cell.len(), nodes.len());
            for (k, m) in cell.iter().enumerate() {
                let mu = |t: f64| adjoint(&sweep.jumps, t);
                let truth = brute_moment(&mu, nodes, k, *a, *b, 200_000);
                // each component against its own size: the fast one is 1e-5 of the slow one
                let rel = |v: Vector2<f64>| {
                    (0..2)
                        .map(|i| (v[i] - truth[i]).abs() / truth[i].abs())
                        .fold(0.0, f64::max)
                };
                let err = rel(Vector2::new(m[0], m[1]));
                worst = worst.max(err);
                // the sampled rule: weight of node k (∫ L_k) times μ at the node
                let weight = brute_moment(&|_| Vector2::new(1.0, 0.0), nodes, k, *a, *b, 1)[0];
                let sampled = mu(nodes[k]) * weight;
                sampled_worst = sampled_worst.max(rel(sampled));
            }
        }
    }
    eprintln!(
        "adjoint moments vs closed form: {worst:.2e}; sampled at the nodes: {sampled_worst:.2e}"
    );
    assert!(
        worst < 1e-6,
        "moments differ from the closed form by {worst:e}"
    );
    assert!(
        sampled_worst > 0.5,
        "the boundary layer should matter: {sampled_worst:e}"
    );
}

/// On a nonlinear ODE the adjoint follows `f_x` along the stored trajectory: the moments of
/// the Van der Pol adjoint agree with `μ(t)ᵀ = wᵀ S(1) S(t)⁻¹` from the forward
/// sensitivities (non-stiff, so the inverse is safe), integrated by a fine Gauss rule.
#[test]
fn adjoint_moments_follow_the_trajectory_of_a_nonlinear_ode() {
    use footfall::integrate::AdjointSweep;
    let mut integrator = Integrator::new(2, 2, settings(1e-11, Method::Bdf)).expect("integrator");
    let (x0, p) = ([1.5, -0.3], [1.2, 0.4]);
    let w = vec![0.8, -1.1];
    let nodes = vec![0.3, 0.45, 0.6];
    let sweep = AdjointSweep {
        jumps: vec![(2.0, w.clone())],
        cells: vec![(0.2, 0.7, nodes.clone())],
    };
    let got = integrator
        .adjoints(&VanDerPol, 0.0, 2.0, &x0, &p, std::slice::from_ref(&sweep))
        .expect("adjoints");
    // μ(t) from the forward sensitivities on a fine grid of Gauss points over the cell
    let parts = 400;
    let mut times = Vec::new();
    let g4 = [
        0.069_431_844_202_973_71,
        0.330_009_478_207_571_87,
        0.669_990_521_792_428_1,
        0.930_568_155_797_026_3,
    ];
    let h = 0.5 / parts as f64;
    for part in 0..parts {
        for g in g4 {
            times.push(0.2 + h * (part as f64 + g));
        }
    }
    times.push(2.0);
    let (mut xs, mut ss) = (Vec::new(), Vec::new());
    integrator
        .integrate_with_sensitivities_dense(&VanDerPol, 0.0, 2.0, &x0, &p, &times, &mut xs, &mut ss)
        .expect("forward");
    let psi = |i: usize| Matrix2::from_column_slice(&ss[i * 8..i * 8 + 4]);
    let end = psi(times.len() - 1);
    let wv = Vector2::new(w[0], w[1]);
    let g4w = [
        0.173_927_422_568_726_93,
        0.326_072_577_431_273_07,
        0.326_072_577_431_273_07,
        0.173_927_422_568_726_93,
    ];
    for (k, m) in got[0][0].iter().enumerate() {
        let mut truth = Vector2::zeros();
        for (i, &t) in times[..times.len() - 1].iter().enumerate() {
            let transition = end * psi(i).try_inverse().expect("non-stiff");
            truth += transition.transpose() * wv * (lagrange(&nodes, k, t) * g4w[i % 4] * h);
        }
        let err = (Vector2::new(m[0], m[1]) - truth).amax() / truth.amax();
        eprintln!("node {k}: moment {m:?}, from the sensitivities {truth:?}, error {err:.2e}");
        assert!(err < 1e-6, "node {k}: {err:e}");
    }
}

/// Bad sweeps are errors, not panics: a jump inside a cell, a cell outside the range, a
/// wrong jump length, too many nodes.
#[test]
fn adjoint_sweeps_are_validated() {
    use footfall::integrate::{AdjointSweep, MAX_CELL_NODES};
    let mut integrator = Integrator::new(2, 0, settings(1e-8, Method::Bdf)).expect("integrator");
    let x0 = [1.0, 0.5];
    let bad = [
        AdjointSweep {
            jumps: vec![(0.5, vec![1.0, 0.0])],
            cells: vec![(0.2, 0.8, vec![0.5])],
        },
        AdjointSweep {
            jumps: vec![(1.0, vec![1.0, 0.0])],
            cells: vec![(0.5, 1.5, vec![0.7])],
        },
        AdjointSweep {
            jumps: vec![(1.0, vec![1.0])],
            cells: vec![(0.5, 1.0, vec![0.7])],
        },
        AdjointSweep {
            jumps: vec![(1.0, vec![1.0, 0.0])],
            cells: vec![(
                0.0,
                1.0,
                (0..=MAX_CELL_NODES).map(|i| 0.1 + 0.1 * i as f64).collect(),
            )],
        },
    ];
    for sweep in &bad {
        let r = integrator.adjoints(&StiffPair, 0.0, 1.0, &x0, &[], std::slice::from_ref(sweep));
        assert!(r.is_err(), "{sweep:?} accepted");
    }
    // and the integrator still works after them
    let ok = AdjointSweep {
        jumps: vec![(1.0, vec![1.0, 0.0])],
        cells: vec![(0.5, 1.0, vec![0.75])],
    };
    integrator
        .adjoints(&StiffPair, 0.0, 1.0, &x0, &[], &[ok])
        .expect("a valid sweep after the bad ones");
}
