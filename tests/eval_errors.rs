//! Typed evaluation failures: a recoverable one (an integrator that cannot take a step) at
//! a trial point makes the line search shorten the step, and the solve still converges; a
//! fatal one (a specification error) stops the solve at once and names its cause. The
//! transcription classifies real failures: CVODES stopped by a model outside its domain is
//! recoverable, invalid integrator settings are fatal.

use footfall::integrate::{ControlShape, ControlledOde, IntegratorSettings, OdeError};
use footfall::ocp::{
    Block, NodeFunction, Ocp, Phase, PhaseDuration, Term, TermError, Transcription,
    TranscriptionError,
};
use footfall::sqp::{self, EvalError, HessianMode, Nlp, NlpEval, Silent, SqpSettings, SqpStatus};
use std::cell::RefCell;
use std::sync::Arc;

/// What the test NLPs here share: w = (w₀, w₁) within ±`bound`, one constraint row
/// "w1": w₁ = 0, and a diagonal Gauss–Newton pattern, one Hessian block per variable.
macro_rules! two_variables_on_a_line {
    ($bound:expr) => {
        fn n(&self) -> usize {
            2
        }
        fn m(&self) -> usize {
            1
        }
        fn bounds(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
            (vec![-$bound; 2], vec![$bound; 2], vec![0.0], vec![0.0])
        }
        fn jacobian_pattern(&self) -> (Vec<usize>, Vec<usize>) {
            (vec![0], vec![1])
        }
        fn gauss_newton_pattern(&self) -> (Vec<usize>, Vec<usize>) {
            (vec![0, 1], vec![0, 1])
        }
        fn hessian_blocks(&self) -> Vec<Vec<usize>> {
            vec![vec![0], vec![1]]
        }
        fn row_name(&self, _i: usize) -> String {
            "w1".into()
        }
    };
}

/// f(w) = (w₀ − 1)² with the constraint w₁ = 0, whose Gauss–Newton Hessian is a quarter
/// of the true one: from w₀ = 0 the full step lands at w₀ = 4, beyond the domain w₀ ≤ 3,
/// and half of it at w₀ = 2 does not decrease f; a quarter reaches the optimum.
struct OutsideTheDomain {
    fatal: bool,
    evaluated: RefCell<Vec<(f64, bool)>>,
}

impl Nlp for OutsideTheDomain {
    two_variables_on_a_line!(10.0);
    fn evaluate(&self, w: &[f64], derivs: bool) -> Result<NlpEval, EvalError> {
        let outside = w[0] > 3.0;
        self.evaluated.borrow_mut().push((w[0], outside));
        if outside {
            let cause = format!(
                "CVODES failed at t = 0.1: the model is undefined at w₀ = {}",
                w[0]
            );
            return Err(if self.fatal {
                EvalError::fatal(format!(
                    "specification: phase 'swing' names no dynamics ({cause})"
                ))
            } else {
                EvalError::recoverable(cause)
            });
        }
        let mut ev = NlpEval {
            f: (w[0] - 1.0).powi(2),
            c: vec![w[1]],
            ..Default::default()
        };
        if derivs {
            ev.grad = vec![2.0 * (w[0] - 1.0), 0.0];
            ev.jac = vec![1.0];
            ev.gn = vec![0.5, 1.0];
        }
        Ok(ev)
    }
}

fn settings() -> SqpSettings {
    SqpSettings {
        tol_kkt: 1e-10,
        max_iter: 20,
        hessian: HessianMode::GaussNewton,
        regularization: 0.0,
        ..Default::default()
    }
}

#[test]
fn a_recoverable_failure_at_a_trial_point_shortens_the_step() {
    let nlp = OutsideTheDomain {
        fatal: false,
        evaluated: RefCell::new(Vec::new()),
    };
    let res = sqp::solve(&nlp, &[0.0, 0.0], &settings(), &mut Silent);
    assert_eq!(res.status, SqpStatus::Converged, "{res:?}");
    assert!((res.w[0] - 1.0).abs() < 1e-9, "{:?}", res.w);
    let evaluated = nlp.evaluated.borrow();
    // the full step was tried, failed, and the search went on to shorter steps
    let failed = evaluated
        .iter()
        .position(|e| e.1)
        .expect("the full step failed");
    assert!((evaluated[failed].0 - 4.0).abs() < 1e-9, "{evaluated:?}");
    assert!(
        evaluated[failed + 1..]
            .iter()
            .any(|e| (e.0 - 1.0).abs() < 1e-9),
        "{evaluated:?}"
    );
}

#[test]
fn a_fatal_failure_at_a_trial_point_stops_the_solve_with_its_cause() {
    let nlp = OutsideTheDomain {
        fatal: true,
        evaluated: RefCell::new(Vec::new()),
    };
    let res = sqp::solve(&nlp, &[0.0, 0.0], &settings(), &mut Silent);
    let SqpStatus::EvaluationFailure(why) = &res.status else {
        panic!("expected an evaluation failure, got {:?}", res.status);
    };
    assert!(
        why.contains("cannot be evaluated") && why.contains("names no dynamics"),
        "{why}"
    );
    // no shorter step was tried after it, and the result is the last good iterate
    let evaluated = nlp.evaluated.borrow();
    assert!(evaluated.last().unwrap().1, "{evaluated:?}");
    assert_eq!(evaluated.iter().filter(|e| e.1).count(), 1);
    assert_eq!(res.w[0], 0.0);
}

/// A solve whose start lies outside the domain has no objective to report: its stop line
/// says so instead of printing NaN.
#[test]
fn a_start_that_cannot_be_evaluated_reports_no_objective() {
    let nlp = OutsideTheDomain {
        fatal: false,
        evaluated: RefCell::new(Vec::new()),
    };
    let res = sqp::solve(&nlp, &[5.0, 0.0], &settings(), &mut Silent);
    assert!(
        matches!(res.status, SqpStatus::EvaluationFailure(_)),
        "{:?}",
        res.status
    );
    assert!(!res.objective.is_finite(), "{}", res.objective);
    let line = res.objective_and_kkt(6);
    assert!(
        line.contains("not evaluated") && !line.contains("NaN"),
        "{line}"
    );
    // a solve that evaluated its start reports both
    let ok = sqp::solve(&nlp, &[0.0, 0.0], &settings(), &mut Silent);
    assert!(
        ok.objective_and_kkt(6).starts_with("J = 0.000000, KKT "),
        "{}",
        ok.objective_and_kkt(6)
    );
}

/// f(w) = (w₀ − 10)² with the constraint w₁ = 0 and a Gauss–Newton Hessian twice the true
/// one, so every step goes half-way to the optimum: the first from w₀ = 0 to w₀ = 5,
/// where the plain evaluation succeeds but the derivatives fail (as sensitivities can
/// fail where the states alone integrate), recoverably, on 4 < w₀ < 6.
struct DerivativesFailOnAnIsland {
    derivatives_at: RefCell<Vec<(f64, bool)>>,
}

impl Nlp for DerivativesFailOnAnIsland {
    two_variables_on_a_line!(20.0);
    fn evaluate(&self, w: &[f64], derivs: bool) -> Result<NlpEval, EvalError> {
        let mut ev = NlpEval {
            f: (w[0] - 10.0).powi(2),
            c: vec![w[1]],
            ..Default::default()
        };
        if derivs {
            let island = w[0] > 4.0 && w[0] < 6.0;
            self.derivatives_at.borrow_mut().push((w[0], island));
            if island {
                return Err(EvalError::recoverable(format!(
                    "the sensitivities do not integrate at w₀ = {}",
                    w[0]
                )));
            }
            ev.grad = vec![2.0 * (w[0] - 10.0), 0.0];
            ev.jac = vec![1.0];
            ev.gn = vec![4.0, 1.0];
        }
        Ok(ev)
    }
}

#[test]
fn a_recoverable_failure_of_the_derivatives_at_an_accepted_point_shortens_the_step() {
    let nlp = DerivativesFailOnAnIsland {
        derivatives_at: RefCell::new(Vec::new()),
    };
    let settings = SqpSettings {
        tol_kkt: 1e-8,
        max_iter: 80,
        ..settings()
    };
    let res = sqp::solve(&nlp, &[0.0, 0.0], &settings, &mut Silent);
    assert_eq!(res.status, SqpStatus::Converged, "{res:?}");
    assert!((res.w[0] - 10.0).abs() < 1e-6, "{:?}", res.w);
    let at = nlp.derivatives_at.borrow();
    // the first step's point (w₀ = 5) failed; the search was repeated with half the step
    // and took w₀ = 2.5, from where the next step jumps over the island
    let failed = at.iter().position(|e| e.1).expect("the island was hit");
    assert!((at[failed].0 - 5.0).abs() < 1e-9, "{at:?}");
    assert!((at[failed + 1].0 - 2.5).abs() < 1e-9, "{at:?}");
    assert!(!at[failed + 1].1);
}

/// ẋ = u, defined only for x ≤ 1 (a fatal right-hand-side error beyond it, which stops
/// CVODES).
struct Bounded;
impl ControlledOde for Bounded {
    fn nx(&self) -> usize {
        1
    }
    fn nu(&self) -> usize {
        1
    }
    fn ntheta(&self) -> usize {
        0
    }
    fn f(&self, x: &[f64], u: &[f64], _: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        if x[0] > 1.0 {
            return Err(OdeError::Fatal(format!("x = {} is beyond 1", x[0])));
        }
        xdot[0] = u[0];
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
        fx[0] = 0.0;
        fu[0] = 1.0;
        Ok(())
    }
}

struct Identity;
impl NodeFunction for Identity {
    fn dim(&self) -> usize {
        1
    }
    fn eval(&self, z: &[f64], v: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError> {
        v[0] = z[0];
        if let Some(j) = jac {
            j[0] = 1.0;
        }
        Ok(())
    }
}

fn ocp(ode: &Bounded, integrator: IntegratorSettings) -> Ocp<'_> {
    let n = 4;
    Ocp {
        phases: vec![Phase {
            name: "bounded".into(),
            ode,
            intervals: n,
            duration: PhaseDuration::fixed(1.0),
            controls: ControlShape::Constant,
            x_lb: vec![vec![-10.0]; n + 1],
            x_ub: vec![vec![10.0]; n + 1],
            u_lb: vec![vec![-100.0]; n],
            u_ub: vec![vec![100.0]; n],
            x_guess: vec![vec![0.0]; n + 1],
            u_guess: vec![vec![0.0]; n],
        }],
        transitions: vec![],
        ntheta: 0,
        theta_guess: vec![],
        theta_lb: vec![],
        theta_ub: vec![],
        constraints: vec![],
        least_squares: vec![Term {
            name: "end".into(),
            args: vec![Block::State { phase: 0, node: n }],
            f: Arc::new(Identity),
        }],
        samples: Vec::new(),
        checks: Vec::new(),
        costs: vec![],
        integrator,
    }
}

#[test]
fn the_transcription_tells_an_integrator_failure_from_a_specification_error() {
    let ode = Bounded;
    let good = ocp(&ode, IntegratorSettings::default());
    let tr = Transcription::new(&good).unwrap();
    let (_, _, mut w) = tr.variable_bounds_and_guess();
    assert!(Nlp::evaluate(&tr, &w, true).is_ok());
    // a control that drives the state beyond its domain inside the first interval
    w[tr.range(Block::Control { phase: 0, node: 0 })][0] = 50.0;
    let e = Nlp::evaluate(&tr, &w, true).expect_err("CVODES stops");
    assert!(e.is_recoverable(), "{}", e.chain());
    assert!(e.chain().contains("beyond 1"), "{}", e.chain());

    // the same point with a relative tolerance that no integrator accepts
    let bad = ocp(
        &ode,
        IntegratorSettings {
            rtol: -1.0,
            ..Default::default()
        },
    );
    let tr = Transcription::new(&bad).unwrap();
    let (_, _, w) = tr.variable_bounds_and_guess();
    let e = Nlp::evaluate(&tr, &w, false).expect_err("invalid settings");
    assert!(!e.is_recoverable(), "{}", e.chain());
    assert!(e.chain().contains("rtol"), "{}", e.chain());
    // and the solve stops on it before any iteration, naming it
    let res = sqp::solve(&tr, &w, &settings(), &mut Silent);
    match &res.status {
        SqpStatus::EvaluationFailure(why) => assert!(why.contains("rtol"), "{why}"),
        s => panic!("expected an evaluation failure, got {s:?}"),
    }
}

/// z ↦ z, defined only for z ≤ 5: a function of the user's that fails with its own
/// error beyond it.
struct IdentityUpToFive;
impl NodeFunction for IdentityUpToFive {
    fn dim(&self) -> usize {
        1
    }
    fn eval(&self, z: &[f64], v: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError> {
        if z[0] > 5.0 {
            return Err(TermError::external(format!("z = {} is beyond 5", z[0])));
        }
        Identity.eval(z, v, jac)
    }
}

/// A term that fails at a point is a recoverable failure of that point, typed: the
/// transcription's error names the term and holds the function's own error as its cause,
/// and the solver's error reads both.
#[test]
fn a_term_failure_is_recoverable_and_names_the_term_and_its_cause() {
    let ode = Bounded;
    let mut problem = ocp(&ode, IntegratorSettings::default());
    problem.least_squares[0].f = Arc::new(IdentityUpToFive);
    let tr = Transcription::new(&problem).unwrap();
    let (_, _, mut w) = tr.variable_bounds_and_guess();
    assert!(Nlp::evaluate(&tr, &w, true).is_ok());
    // the last node's state, which only the term and the last continuity row read
    w[tr.range(Block::State { phase: 0, node: 4 })][0] = 6.0;
    let e = tr.evaluate(&w, false).expect_err("the term fails");
    match &e {
        TranscriptionError::Term {
            term,
            source: TermError::External(cause),
        } => {
            assert_eq!(term, "end");
            assert_eq!(cause.to_string(), "z = 6 is beyond 5");
        }
        other => panic!("expected the term's failure, got {other:?}"),
    }
    assert!(e.is_recoverable());
    let e = EvalError::from(e);
    assert!(e.is_recoverable(), "{}", e.chain());
    assert_eq!(
        e.chain(),
        "the evaluation failed at this point: term 'end': z = 6 is beyond 5"
    );
}

/// f(w) = (w₀ − 1)² with the constraint w₁ = 0, whose gradient carries an error of the
/// size of its "integrator tolerance" (as sensitivities integrated at that tolerance
/// do): `tol · cos(10⁵ w₀ + 1)`. The values are exact.
struct NoisyGradient {
    base: f64,
    tol: std::cell::Cell<f64>,
}

impl Nlp for NoisyGradient {
    two_variables_on_a_line!(10.0);
    fn evaluate(&self, w: &[f64], derivs: bool) -> Result<NlpEval, EvalError> {
        let mut ev = NlpEval {
            f: (w[0] - 1.0).powi(2),
            c: vec![w[1]],
            ..Default::default()
        };
        if derivs {
            let noise = self.tol.get() * (1e5 * w[0] + 1.0).cos();
            ev.grad = vec![2.0 * (w[0] - 1.0) + noise, 0.0];
            ev.jac = vec![1.0];
            ev.gn = vec![2.0, 1.0];
        }
        Ok(ev)
    }
    fn integration_tolerance(&self) -> Option<f64> {
        Some(self.tol.get())
    }
    fn set_integration_tolerance(&self, rtol: f64) {
        self.tol.set(rtol.min(self.base));
    }
}

/// The inexact SQP: at a fixed tolerance of 1e-4 the gradient's error keeps the KKT
/// residual near 1e-4 and the solve cannot certify 1e-10; with the tolerance following
/// the residual (`inexact_integration`), it tightens, step by step, and converges.
#[test]
fn the_integrator_tolerance_follows_the_kkt_residual_until_the_solve_converges() {
    let solve = |inexact: f64| {
        let nlp = NoisyGradient {
            base: 1e-4,
            tol: std::cell::Cell::new(1e-4),
        };
        let settings = SqpSettings {
            inexact_integration: inexact,
            ..settings()
        };
        (
            sqp::solve(&nlp, &[0.0, 0.0], &settings, &mut Silent),
            nlp.tol.get(),
        )
    };
    let (fixed, tol) = solve(0.0);
    assert_ne!(fixed.status, SqpStatus::Converged, "{fixed:?}");
    assert!(fixed.kkt > 1e-7, "{}", fixed.kkt);
    assert_eq!(tol, 1e-4);
    let (res, tol) = solve(1e-2);
    assert_eq!(res.status, SqpStatus::Converged, "{res:?}");
    assert!(
        res.kkt <= 1e-10 && (res.w[0] - 1.0).abs() < 1e-10,
        "{res:?}"
    );
    // tightened as the residual fell, never loosened, and recorded with each iteration
    let tols: Vec<f64> = res
        .history
        .iter()
        .map(|r| r.integration_tol.expect("recorded"))
        .collect();
    assert!(tols.windows(2).all(|p| p[1] <= p[0]), "{tols:?}");
    assert!(tols[0] == 1e-4 && tol < 1e-8, "{tols:?}");
    assert_eq!(*tols.last().unwrap(), tol);
}
