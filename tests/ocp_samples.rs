//! Least-squares residuals inside shooting intervals (`Ocp::samples`): their value
//! against an independent RK4 integration of the interval, their gradient against central
//! differences, and their Gauss–Newton block against the directional derivative of the
//! residual.

use footfall::integrate::{ControlShape, ControlledOde, IntegratorSettings, OdeError};
use footfall::ocp::{
    Block, CheckPoint, NodeFunction, Ocp, Phase, PhaseDuration, SampleTerm, TermError,
    Transcription,
};
use std::sync::Arc;

/// A driven, damped pendulum with the stiffness as the free parameter θ:
/// ẋ₀ = x₁, ẋ₁ = −θ sin x₀ − 0.3 x₁ + u.
struct Pendulum;

impl Pendulum {
    fn rhs(x: &[f64], u: f64, theta: f64) -> [f64; 2] {
        [x[1], -theta * x[0].sin() - 0.3 * x[1] + u]
    }
}

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
        xdot.copy_from_slice(&Self::rhs(x, u[0], theta[0]));
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
        ft: &mut [f64],
    ) -> Result<(), OdeError> {
        self.f(x, u, theta, xdot)?;
        fx.copy_from_slice(&[0.0, -theta[0] * x[0].cos(), 1.0, -0.3]);
        fu.copy_from_slice(&[0.0, 1.0]);
        ft.copy_from_slice(&[0.0, -x[0].sin()]);
        Ok(())
    }
    fn weighted_hessian(
        &self,
        x: &[f64],
        _: &[f64],
        theta: &[f64],
        mu: &[f64],
        out: &mut [f64],
    ) -> Result<bool, OdeError> {
        // (x₀, x₁, u, θ): only f₁ = −θ sin x₀ … is curved
        out.iter_mut().for_each(|v| *v = 0.0);
        out[0] = mu[1] * theta[0] * x[0].sin();
        out[3] = -mu[1] * x[0].cos();
        out[12] = out[3];
        Ok(true)
    }
}

/// A positive scalar residual of `(x, u, θ)`: r = 2 + x₀² + sin(x₁)·u + θ·x₁ / 4 − 0.1 u.
struct Residual;

impl Residual {
    fn value(z: &[f64]) -> f64 {
        2.0 + z[0] * z[0] + z[1].sin() * z[2] + z[3] * z[1] / 4.0 - 0.1 * z[2]
    }
}

impl NodeFunction for Residual {
    fn dim(&self) -> usize {
        1
    }
    fn eval(&self, z: &[f64], v: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError> {
        v[0] = Self::value(z);
        if let Some(j) = jac {
            j.copy_from_slice(&[
                2.0 * z[0],
                z[1].cos() * z[2] + z[3] / 4.0,
                z[1].sin() - 0.1,
                z[1] / 4.0,
            ]);
        }
        Ok(())
    }
    fn has_hessian(&self) -> bool {
        true
    }
    fn weighted_hessian(
        &self,
        z: &[f64],
        weights: &[f64],
        out: &mut [f64],
    ) -> Result<(), TermError> {
        // z = (x₀, x₁, u, θ): ∂²/∂x₀² = 2, ∂²/∂x₁² = −sin(x₁) u, ∂²/∂x₁∂u = cos x₁, ∂²/∂x₁∂θ = 1/4
        let w = weights[0];
        out.iter_mut().for_each(|v| *v = 0.0);
        out[0] = 2.0 * w;
        out[1 + 4] = -z[1].sin() * z[2] * w;
        out[1 + 2 * 4] = z[1].cos() * w;
        out[2 + 4] = out[1 + 2 * 4];
        out[1 + 3 * 4] = 0.25 * w;
        out[3 + 4] = 0.25 * w;
        Ok(())
    }
}

const INTERVALS: usize = 3;
/// (interval, τ) of the sample terms; two share an instant.
const SAMPLES: [(usize, f64); 5] = [(0, 0.3), (0, 0.3), (1, 0.55), (1, 1.0), (2, 0.8)];

fn problem(ode: &Pendulum) -> Ocp<'_> {
    let inf = f64::INFINITY;
    let n = INTERVALS;
    let phase = Phase {
        name: "swing".into(),
        ode,
        intervals: n,
        duration: PhaseDuration {
            value: 0.9,
            lb: 0.5,
            ub: 2.0,
        },
        controls: ControlShape::Linear,
        x_lb: vec![vec![-inf; 2]; n + 1],
        x_ub: vec![vec![inf; 2]; n + 1],
        u_lb: vec![vec![-inf]; n + 1],
        u_ub: vec![vec![inf]; n + 1],
        x_guess: vec![vec![0.0; 2]; n + 1],
        u_guess: vec![vec![0.0]; n + 1],
    };
    let f: Arc<dyn NodeFunction> = Arc::new(Residual);
    Ocp {
        phases: vec![phase],
        transitions: vec![],
        ntheta: 1,
        theta_guess: vec![2.0],
        theta_lb: vec![0.0],
        theta_ub: vec![10.0],
        constraints: vec![],
        least_squares: vec![],
        samples: SAMPLES
            .iter()
            .map(|&(interval, tau)| SampleTerm {
                name: "sample".into(),
                phase: 0,
                interval,
                tau,
                f: f.clone(),
                shift: None,
            })
            .collect(),
        checks: vec![],
        costs: vec![],
        integrator: IntegratorSettings {
            rtol: 1e-12,
            atol: 1e-12,
            ..Default::default()
        },
    }
}

/// A point with distinct node states, controls, duration and θ.
fn point(tr: &Transcription) -> Vec<f64> {
    let mut w = vec![0.0; tr.n()];
    for k in 0..=INTERVALS {
        let r = tr.range(Block::State { phase: 0, node: k });
        w[r.start] = 0.4 - 0.2 * k as f64;
        w[r.start + 1] = 0.8 + 0.3 * k as f64;
        w[tr.range(Block::Control { phase: 0, node: k }).start] = 0.5 * (k as f64 - 1.2);
    }
    w[tr.range(Block::Duration { phase: 0 }).start] = 0.9;
    w[tr.range(Block::Params).start] = 2.3;
    w
}

/// RK4 of the interval from its node to τ (fine fixed steps), with the linear control.
fn rk4(x0: [f64; 2], u0: f64, u1: f64, h: f64, theta: f64, tau: f64) -> [f64; 2] {
    let steps = 4000;
    let dt = tau / steps as f64;
    let mut x = x0;
    let f = |s: f64, x: [f64; 2]| {
        let d = Pendulum::rhs(&x, (1.0 - s) * u0 + s * u1, theta);
        [h * d[0], h * d[1]]
    };
    for i in 0..steps {
        let s = i as f64 * dt;
        let k1 = f(s, x);
        let k2 = f(
            s + dt / 2.0,
            [x[0] + dt / 2.0 * k1[0], x[1] + dt / 2.0 * k1[1]],
        );
        let k3 = f(
            s + dt / 2.0,
            [x[0] + dt / 2.0 * k2[0], x[1] + dt / 2.0 * k2[1]],
        );
        let k4 = f(s + dt, [x[0] + dt * k3[0], x[1] + dt * k3[1]]);
        for j in 0..2 {
            x[j] += dt / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
        }
    }
    x
}

/// The objective of residuals at `(interval, τ)` instants, each interval integrated by
/// RK4 from its node at `w`.
fn rk4_objective<const N: usize>(
    tr: &Transcription,
    w: &[f64],
    instants: [(usize, f64); N],
) -> f64 {
    let theta = w[tr.range(Block::Params).start];
    let h = w[tr.range(Block::Duration { phase: 0 }).start] / INTERVALS as f64;
    let mut expected = 0.0;
    for (k, tau) in instants {
        let s = tr.range(Block::State { phase: 0, node: k });
        let u0 = w[tr.range(Block::Control { phase: 0, node: k }).start];
        let u1 = w[tr
            .range(Block::Control {
                phase: 0,
                node: k + 1,
            })
            .start];
        let x = rk4([w[s.start], w[s.start + 1]], u0, u1, h, theta, tau);
        let u = (1.0 - tau) * u0 + tau * u1;
        expected += Residual::value(&[x[0], x[1], u, theta]).powi(2);
    }
    expected
}

#[test]
fn sample_terms_match_an_independent_integration() {
    let ode = Pendulum;
    let ocp = problem(&ode);
    let tr = Transcription::new(&ocp).unwrap();
    let w = point(&tr);
    let expected = rk4_objective(&tr, &w, SAMPLES);
    for derivs in [false, true] {
        let ev = tr.evaluate(&w, derivs).unwrap();
        assert!(
            (ev.f - expected).abs() < 1e-9 * expected,
            "derivs {derivs}: objective {} against RK4's {expected}",
            ev.f
        );
    }
    // the end states are the same as without samples: the continuity rows agree
    let plain = Ocp {
        samples: vec![],
        ..problem(&ode)
    };
    let trp = Transcription::new(&plain).unwrap();
    let (a, b) = (
        tr.evaluate(&w, true).unwrap(),
        trp.evaluate(&w, true).unwrap(),
    );
    for (x, y) in a.c.iter().zip(&b.c) {
        assert!(
            (x - y).abs() < 1e-9,
            "continuity {x} with samples, {y} without"
        );
    }
    assert_eq!(b.f, 0.0);
}

#[test]
fn sample_gradient_and_gauss_newton_match_central_differences() {
    let ode = Pendulum;
    let ocp = problem(&ode);
    let tr = Transcription::new(&ocp).unwrap();
    let w = point(&tr);
    let ev = tr.evaluate(&w, true).unwrap();
    let f = |w: &[f64]| tr.evaluate(w, false).unwrap().f;
    let eps = 1e-6;
    for i in 0..tr.n() {
        let (mut wp, mut wm) = (w.clone(), w.clone());
        wp[i] += eps;
        wm[i] -= eps;
        let fd = (f(&wp) - f(&wm)) / (2.0 * eps);
        assert!(
            (ev.grad[i] - fd).abs() < 1e-6 * (1.0 + fd.abs()),
            "∂f/∂w[{i}]: {} against {fd}",
            ev.grad[i]
        );
    }
    // one sample term alone: r = √f (r > 0), so dᵀ GN d = 2 (∂r/∂d)²
    let one = Ocp {
        samples: problem(&ode).samples.into_iter().skip(2).take(1).collect(),
        ..problem(&ode)
    };
    assert_gauss_newton_is_the_residuals_derivative(&Transcription::new(&one).unwrap(), &w, None);
}

/// For a problem with one positive sample residual (r = √f), `dᵀ GN d = 2 (∂r/∂d)²` along
/// a few directions (central differences), the variable `fixed` (if any) held.
fn assert_gauss_newton_is_the_residuals_derivative(
    tr: &Transcription,
    w: &[f64],
    fixed: Option<usize>,
) {
    let eps = 1e-6;
    let ev = tr.evaluate(w, true).unwrap();
    let (rows, cols) = tr.gauss_newton_pattern();
    let r = |w: &[f64]| tr.evaluate(w, false).unwrap().f.sqrt();
    for seed in 0..4 {
        let d: Vec<f64> = (0..tr.n())
            .map(|i| {
                if Some(i) == fixed {
                    0.0
                } else {
                    ((i * 7 + seed * 13) % 11) as f64 / 11.0 - 0.45
                }
            })
            .collect();
        let mut quad = 0.0;
        for ((&a, &b), &v) in rows.iter().zip(cols).zip(&ev.gauss_newton) {
            quad += if a == b {
                v * d[a] * d[a]
            } else {
                2.0 * v * d[a] * d[b]
            };
        }
        let wp: Vec<f64> = w.iter().zip(&d).map(|(x, y)| x + eps * y).collect();
        let wm: Vec<f64> = w.iter().zip(&d).map(|(x, y)| x - eps * y).collect();
        let dr = (r(&wp) - r(&wm)) / (2.0 * eps);
        assert!(
            (quad - 2.0 * dr * dr).abs() < 1e-6 * (1.0 + quad.abs()),
            "direction {seed}: dᵀ GN d = {quad}, 2 (∂r/∂d)² = {}",
            2.0 * dr * dr
        );
    }
}

/// The exact-Hessian path (with multipliers) gives the same objective, gradient and
/// Gauss–Newton block as the plain evaluation.
fn assert_exact_hessian_path_agrees(tr: &Transcription, w: &[f64]) {
    let lambda: Vec<f64> = (0..tr.m()).map(|i| 0.3 - 0.1 * i as f64).collect();
    let (a, _) = tr.evaluate_with_hessian(w, &lambda).unwrap();
    let b = tr.evaluate(w, true).unwrap();
    assert!((a.f - b.f).abs() < 1e-10 * b.f, "{} against {}", a.f, b.f);
    for (x, y) in a
        .grad
        .iter()
        .zip(&b.grad)
        .chain(a.gauss_newton.iter().zip(&b.gauss_newton))
    {
        assert!((x - y).abs() < 1e-8 * (1.0 + y.abs()), "{x} against {y}");
    }
}

/// With multipliers (the exact-Hessian path) the samples come from the interval's
/// curvature pass: the same objective, gradient and Gauss–Newton block as without.
#[test]
fn sample_terms_are_the_same_on_the_exact_hessian_path() {
    let ode = Pendulum;
    let ocp = problem(&ode);
    let tr = Transcription::new(&ocp).unwrap();
    assert_exact_hessian_path_agrees(&tr, &point(&tr));
}

#[test]
fn a_sample_outside_its_interval_is_refused() {
    let ode = Pendulum;
    for (interval, tau) in [(0, 0.0), (0, 1.5), (3, 0.5), (0, f64::NAN)] {
        let mut ocp = problem(&ode);
        ocp.samples[0].interval = interval;
        ocp.samples[0].tau = tau;
        let e = Transcription::new(&ocp)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("sample term 'sample'"),
            "interval {interval}, τ {tau}: {e}"
        );
    }
}

/// A shift of a sample's instant linear in θ: `s(θ) = c + 0.05 (θ − 2)` seconds.
struct Shift(f64);

impl NodeFunction for Shift {
    fn dim(&self) -> usize {
        1
    }
    fn eval(&self, z: &[f64], v: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError> {
        v[0] = self.0 + 0.05 * (z[0] - 2.0);
        if let Some(j) = jac {
            j[0] = 0.05;
        }
        Ok(())
    }
}

/// (interval, τ, c) of shifted sample terms on a fixed 0.9 s phase (h = 0.3 s), and the
/// (interval, τ) each lands in at θ = 2.3 (shift c + 0.015 s): within its interval, two
/// intervals on, one back, held at the phase's end and at its start.
const SHIFTED: [(usize, f64, f64, usize, f64); 5] = [
    (0, 0.3, 0.1, 0, 0.205 / 0.3),
    (1, 0.55, 0.2, 2, 0.68 / 0.3 - 2.0),
    (2, 0.8, -0.35, 1, 0.505 / 0.3 - 1.0),
    (1, 0.5, 0.8, 2, 1.0),
    (0, 0.5, -0.5, 0, 1e-6),
];

fn shifted_problem<'a>(ode: &'a Pendulum, which: &[usize]) -> Ocp<'a> {
    let mut ocp = problem(ode);
    ocp.phases[0].duration = PhaseDuration::fixed(0.9);
    let f: Arc<dyn NodeFunction> = Arc::new(Residual);
    ocp.samples = which
        .iter()
        .map(|&i| {
            let (interval, tau, c, ..) = SHIFTED[i];
            SampleTerm {
                name: "shifted".into(),
                phase: 0,
                interval,
                tau,
                f: f.clone(),
                shift: Some(Arc::new(Shift(c))),
            }
        })
        .collect();
    ocp
}

/// Shifted sample terms are the model at the moved instant, wherever in the phase it
/// falls (an independent RK4 from the node of the interval it lands in), with their
/// gradient matching central differences (every variable but the fixed duration) and
/// their Gauss–Newton block the directional derivative of the residual.
#[test]
fn shifted_sample_terms_are_the_model_at_the_moved_instant_with_exact_derivatives() {
    let ode = Pendulum;
    let all: Vec<usize> = (0..SHIFTED.len()).collect();
    let ocp = shifted_problem(&ode, &all);
    let tr = Transcription::new(&ocp).unwrap();
    let w = point(&tr);
    let expected = rk4_objective(&tr, &w, SHIFTED.map(|(.., k, tau)| (k, tau)));
    let ev = tr.evaluate(&w, true).unwrap();
    assert!(
        (ev.f - expected).abs() < 1e-9 * expected,
        "objective {} against RK4's {expected}",
        ev.f
    );
    let f = |w: &[f64]| tr.evaluate(w, false).unwrap().f;
    let eps = 1e-6;
    let duration = tr.range(Block::Duration { phase: 0 }).start;
    for i in (0..tr.n()).filter(|&i| i != duration) {
        let (mut wp, mut wm) = (w.clone(), w.clone());
        wp[i] += eps;
        wm[i] -= eps;
        let fd = (f(&wp) - f(&wm)) / (2.0 * eps);
        assert!(
            (ev.grad[i] - fd).abs() < 1e-6 * (1.0 + fd.abs()),
            "∂f/∂w[{i}]: {} against {fd}",
            ev.grad[i]
        );
    }
    // one term that moved two intervals on: its Gauss–Newton block
    assert_gauss_newton_is_the_residuals_derivative(
        &Transcription::new(&shifted_problem(&ode, &[1])).unwrap(),
        &w,
        Some(duration),
    );
    // the exact-Hessian path places them the same
    assert_exact_hessian_path_agrees(&tr, &w);
}

/// A shift that is zero (and constant) leaves a sample term where it was: the same
/// objective and gradient as the unshifted term, bit for bit.
#[test]
fn a_zero_shift_leaves_the_sample_where_it_was() {
    let ode = Pendulum;
    let mut fixed = problem(&ode);
    fixed.phases[0].duration = PhaseDuration::fixed(0.9);
    let mut zero = problem(&ode);
    zero.phases[0].duration = PhaseDuration::fixed(0.9);
    struct Zero;
    impl NodeFunction for Zero {
        fn dim(&self) -> usize {
            1
        }
        fn eval(&self, _: &[f64], v: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError> {
            v[0] = 0.0;
            if let Some(j) = jac {
                j[0] = 0.0;
            }
            Ok(())
        }
    }
    zero.samples
        .iter_mut()
        .for_each(|s| s.shift = Some(Arc::new(Zero)));
    let (ta, tb) = (
        Transcription::new(&fixed).unwrap(),
        Transcription::new(&zero).unwrap(),
    );
    let w = point(&ta);
    let (a, b) = (
        ta.evaluate(&w, true).unwrap(),
        tb.evaluate(&w, true).unwrap(),
    );
    assert_eq!(a.f, b.f);
    assert_eq!(a.grad, b.grad);
}

#[test]
fn a_shifted_sample_in_a_phase_of_free_duration_is_refused() {
    let ode = Pendulum;
    let mut ocp = shifted_problem(&ode, &[0]);
    ocp.phases[0].duration = PhaseDuration {
        value: 0.9,
        lb: 0.5,
        ub: 2.0,
    };
    let e = Transcription::new(&ocp)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        e.contains("sample term 'shifted'") && e.contains("fixed duration"),
        "{e}"
    );
}

// ---------------------------------------------------------------------------------------
// Check points: path constraints inside intervals (`Ocp::checks`)

/// (interval, τ) of the check points; one shares its instant with a sample term, two
/// share an instant with each other.
const CHECKS: [(usize, f64); 4] = [(0, 0.3), (0, 0.65), (0, 0.65), (2, 0.4)];

fn checked_problem(ode: &Pendulum) -> Ocp<'_> {
    let f: Arc<dyn NodeFunction> = Arc::new(Residual);
    Ocp {
        checks: CHECKS
            .iter()
            .map(|&(interval, tau)| CheckPoint {
                name: "check".into(),
                phase: 0,
                interval,
                tau,
                f: f.clone(),
                lb: vec![2.5],
                ub: vec![f64::INFINITY],
            })
            .collect(),
        ..problem(ode)
    }
}

#[test]
fn check_points_match_an_independent_integration_with_exact_jacobians() {
    let ode = Pendulum;
    let ocp = checked_problem(&ode);
    let tr = Transcription::new(&ocp).unwrap();
    let plain_ocp = problem(&ode);
    let plain = Transcription::new(&plain_ocp).unwrap();
    assert_eq!(tr.m(), plain.m() + CHECKS.len());
    let w = point(&tr);
    let (lb, _) = tr.constraint_bounds();
    let ev = tr.evaluate(&w, true).unwrap();
    let evp = plain.evaluate(&w, true).unwrap();
    // the check rows follow the others, in interval and τ order, with their bounds
    let rows = plain.m()..tr.m();
    assert!(lb[rows.clone()].iter().all(|&v| v == 2.5));
    assert!(
        tr.labels()[rows.start].name.starts_with("check@τ=0.300"),
        "{:?}",
        tr.labels()[rows.start]
    );
    // each value is the function at the RK4 state of its instant
    for (row, (k, tau)) in rows.clone().zip(CHECKS) {
        let expected = rk4_objective(&tr, &w, [(k, tau)]).sqrt();
        assert!(
            (ev.c[row] - expected).abs() < 1e-8,
            "check at ({k}, {tau}): {} against RK4's {expected}",
            ev.c[row]
        );
    }
    // the rest of the NLP is the same as without them (the samples share the pass)
    assert!(
        (ev.f - evp.f).abs() < 1e-10 * evp.f.abs(),
        "{} against {}",
        ev.f,
        evp.f
    );
    for i in 0..plain.m() {
        assert!(
            (ev.c[i] - evp.c[i]).abs() < 1e-10,
            "row {i}: {} against {}",
            ev.c[i],
            evp.c[i]
        );
    }
    // the Jacobian rows against central differences of the values
    let (jr, jc) = tr.jacobian_pattern();
    let eps = 1e-6;
    for i in 0..tr.n() {
        let (mut wp, mut wm) = (w.clone(), w.clone());
        wp[i] += eps;
        wm[i] -= eps;
        let (cp, cm) = (
            tr.evaluate(&wp, false).unwrap().c,
            tr.evaluate(&wm, false).unwrap().c,
        );
        for row in rows.clone() {
            let fd = (cp[row] - cm[row]) / (2.0 * eps);
            let exact: f64 = (0..jr.len())
                .filter(|&e| jr[e] == row && jc[e] == i)
                .map(|e| ev.jac[e])
                .sum();
            assert!(
                (exact - fd).abs() < 1e-6 * (1.0 + fd.abs()),
                "∂c[{row}]/∂w[{i}]: {exact} against {fd}"
            );
        }
    }
    // and on the exact-Hessian path
    let lambda = vec![0.1; tr.m()];
    let (evh, _) = tr.evaluate_with_hessian(&w, &lambda).unwrap();
    for row in rows {
        assert!((evh.c[row] - ev.c[row]).abs() < 1e-10);
    }
    assert_eq!(evh.jac.len(), ev.jac.len());
}

#[test]
fn a_check_point_at_a_node_or_outside_its_phase_is_refused() {
    let ode = Pendulum;
    for (interval, tau, words) in [
        (0, 1.0, "not in (0, 1)"),
        (0, 0.0, "not in (0, 1)"),
        (7, 0.5, "has no interval 7"),
    ] {
        let f: Arc<dyn NodeFunction> = Arc::new(Residual);
        let ocp = Ocp {
            checks: vec![CheckPoint {
                name: "c".into(),
                phase: 0,
                interval,
                tau,
                f,
                lb: vec![0.0],
                ub: vec![1.0],
            }],
            ..problem(&ode)
        };
        let err = Transcription::new(&ocp).err().expect("refused").to_string();
        assert!(err.contains(words), "{err}");
    }
}

/// ẍ = u on a fixed horizon: a double integrator.
struct DoubleIntegrator;

impl ControlledOde for DoubleIntegrator {
    fn nx(&self) -> usize {
        2
    }
    fn nu(&self) -> usize {
        1
    }
    fn ntheta(&self) -> usize {
        0
    }
    fn f(&self, x: &[f64], u: &[f64], _: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        xdot.copy_from_slice(&[x[1], u[0]]);
        Ok(())
    }
    fn f_jac(
        &self,
        x: &[f64],
        u: &[f64],
        t: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fu: &mut [f64],
        _: &mut [f64],
    ) -> Result<(), OdeError> {
        self.f(x, u, t, xdot)?;
        fx.copy_from_slice(&[0.0, 0.0, 1.0, 0.0]);
        fu.copy_from_slice(&[0.0, 1.0]);
        Ok(())
    }
}

/// `scale · (x₀ − target)`, or with `target` NaN the position itself: of `(x, u)` or
/// `(x)` (the control, when given, has no effect).
struct Position {
    target: f64,
    scale: f64,
}

impl NodeFunction for Position {
    fn dim(&self) -> usize {
        1
    }
    fn eval(&self, z: &[f64], v: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError> {
        let t = if self.target.is_nan() {
            0.0
        } else {
            self.target
        };
        v[0] = self.scale * (z[0] - t);
        if let Some(j) = jac {
            j.iter_mut().for_each(|e| *e = 0.0);
            j[0] = self.scale;
        }
        Ok(())
    }
}

#[test]
fn check_points_remove_a_violation_between_the_nodes() {
    // a cost that pulls the position to −1 in the middle of the second interval, against
    // x ≥ 0 at the nodes: the optimum keeps the nodes on x = 0 and dips below it between
    use footfall::sqp::{solve, Silent, SqpSettings, SqpStatus};
    let ode = DoubleIntegrator;
    let n = 4;
    let inf = f64::INFINITY;
    let mut x_lb = vec![vec![0.0, -inf]; n + 1];
    let mut x_ub = vec![vec![inf, inf]; n + 1];
    // start and end at rest at x = 1
    x_lb[0] = vec![1.0, 0.0];
    x_ub[0] = vec![1.0, 0.0];
    x_lb[n] = vec![1.0, 0.0];
    x_ub[n] = vec![1.0, 0.0];
    let phase = |checks: bool| Phase {
        name: if checks {
            "checked".into()
        } else {
            "plain".into()
        },
        ode: &ode,
        intervals: n,
        duration: PhaseDuration::fixed(4.0),
        controls: ControlShape::Constant,
        x_lb: x_lb.clone(),
        x_ub: x_ub.clone(),
        u_lb: vec![vec![-10.0]; n],
        u_ub: vec![vec![10.0]; n],
        x_guess: vec![vec![1.0, 0.0]; n + 1],
        u_guess: vec![vec![0.0]; n],
    };
    let pull: Arc<dyn NodeFunction> = Arc::new(Position {
        target: -1.0,
        scale: 1.0,
    });
    let position: Arc<dyn NodeFunction> = Arc::new(Position {
        target: f64::NAN,
        scale: 1.0,
    });
    let build = |checks: Vec<(usize, f64)>| Ocp {
        phases: vec![phase(!checks.is_empty())],
        transitions: vec![],
        ntheta: 0,
        theta_guess: vec![],
        theta_lb: vec![],
        theta_ub: vec![],
        constraints: vec![],
        least_squares: vec![],
        samples: vec![SampleTerm {
            name: "pull".into(),
            phase: 0,
            interval: 1,
            tau: 0.5,
            f: pull.clone(),
            shift: None,
        }],
        checks: checks
            .into_iter()
            .map(|(interval, tau)| CheckPoint {
                name: "x ≥ 0".into(),
                phase: 0,
                interval,
                tau,
                f: position.clone(),
                lb: vec![0.0],
                ub: vec![inf],
            })
            .collect(),
        costs: vec![],
        integrator: IntegratorSettings {
            rtol: 1e-10,
            atol: 1e-10,
            ..Default::default()
        },
    };
    // the smallest position on a fine grid of each interval, from an RK-free closed form:
    // x(t) = x_k + v_k t + u_k t²/2 within interval k
    let lowest = |tr: &Transcription, w: &[f64]| -> (f64, usize, f64) {
        let mut worst = (f64::INFINITY, 0, 0.0);
        for k in 0..n {
            let s = tr.range(Block::State { phase: 0, node: k });
            let u = w[tr.range(Block::Control { phase: 0, node: k }).start];
            for i in 1..200 {
                let t = i as f64 / 200.0;
                let x = w[s.start] + w[s.start + 1] * t + u * t * t / 2.0;
                if x < worst.0 {
                    worst = (x, k, t);
                }
            }
        }
        worst
    };
    let settings = SqpSettings {
        tol_kkt: 1e-8,
        ..Default::default()
    };
    let plain = build(vec![]);
    let tr = Transcription::new(&plain).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let res = solve(&tr, &w0, &settings, &mut Silent);
    assert_eq!(res.status, SqpStatus::Converged);
    let (low, k, tau) = lowest(&tr, &res.w);
    // every node satisfies x ≥ 0, yet the trajectory dips below it between them
    for node in 0..=n {
        assert!(res.w[tr.range(Block::State { phase: 0, node }).start] >= -1e-8);
    }
    assert!(
        low < -0.05,
        "no violation between the nodes to remove: lowest x {low}"
    );
    eprintln!("without check points: lowest x {low:.4} at τ = {tau:.3} of interval {k}");
    // refine: a check point where the fine grid is lowest in each violating interval,
    // warm-started, until nothing on the fine grid is below −1e-6
    let mut checks: Vec<(usize, f64)> = vec![(k, tau)];
    let mut w = res.w.clone();
    for round in 0..5 {
        let ocp = build(checks.clone());
        let tr = Transcription::new(&ocp).unwrap();
        let res = solve(&tr, &w, &settings, &mut Silent);
        assert_eq!(res.status, SqpStatus::Converged, "round {round}");
        w = res.w;
        let (low, k, tau) = lowest(&tr, &w);
        if low >= -1e-6 {
            eprintln!(
                "{} check point(s), {} round(s); lowest x between the nodes {low:.2e}",
                checks.len(),
                round + 1
            );
            assert!(round <= 3, "took {} rounds", round + 1);
            return;
        }
        checks.push((k, tau));
    }
    panic!("the check points did not remove the violation: {checks:?}");
}

#[test]
fn check_point_curvature_matches_central_differences_of_the_gradient() {
    // Σ ν ∇²c over the check rows alone: the exact Hessian with multipliers on the check
    // rows less the one without, against central differences of Jᵀν
    let ode = Pendulum;
    let ocp = checked_problem(&ode);
    let tr = Transcription::new(&ocp).unwrap();
    let plain_ocp = problem(&ode);
    let first_check = Transcription::new(&plain_ocp).unwrap().m();
    let w = point(&tr);
    let mut nu = vec![0.0; tr.m()];
    for (i, v) in nu[first_check..].iter_mut().enumerate() {
        *v = 0.7 - 0.45 * i as f64;
    }
    let dense = |lam: &[f64]| {
        let (_, (r, c, v)) = tr.evaluate_with_hessian(&w, lam).unwrap();
        let mut h = vec![0.0; tr.n() * tr.n()];
        for k in 0..r.len() {
            h[r[k] + c[k] * tr.n()] += v[k];
            if r[k] != c[k] {
                h[c[k] + r[k] * tr.n()] += v[k];
            }
        }
        h
    };
    let (with, without) = (dense(&nu), dense(&vec![0.0; tr.m()]));
    let (jr, jc) = tr.jacobian_pattern();
    let jt_nu = |w: &[f64]| {
        let ev = tr.evaluate(w, true).unwrap();
        let mut g = vec![0.0; tr.n()];
        for k in 0..jr.len() {
            g[jc[k]] += ev.jac[k] * nu[jr[k]];
        }
        g
    };
    let eps = 1e-5;
    let mut largest = 0.0f64;
    for j in 0..tr.n() {
        let (mut wp, mut wm) = (w.clone(), w.clone());
        wp[j] += eps;
        wm[j] -= eps;
        let (gp, gm) = (jt_nu(&wp), jt_nu(&wm));
        for i in 0..tr.n() {
            let fd = (gp[i] - gm[i]) / (2.0 * eps);
            let exact = with[i + j * tr.n()] - without[i + j * tr.n()];
            largest = largest.max(fd.abs());
            assert!(
                (exact - fd).abs() < 1e-5 * (1.0 + fd.abs()),
                "∂²(νᵀc)/∂w[{i}]∂w[{j}]: {exact} against {fd}"
            );
        }
    }
    assert!(
        largest > 0.1,
        "the check points' curvature is not exercised: {largest}"
    );
}
