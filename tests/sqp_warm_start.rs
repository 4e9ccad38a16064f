//! A solve started with the multipliers of the problem it continues (`sqp::solve_warm`,
//! used when a solve goes on at a tighter integrator tolerance) starts with the curvature
//! of the Lagrangian, not the objective's alone, and holds the bounds the problem held.
//! A solve asked at its milestone (`SqpSettings::milestone_tol`, where a round of check
//! points is judged) ends there when told to, and otherwise goes on in place as if it had
//! not been asked.
//!
//! The problem: minimise −x − y on the circle x² + y² = 2, whose solution is (1, 1) with
//! the multiplier λ = ½. The objective is linear, so its Hessian is zero; the Lagrangian's
//! is 2λ·I = I. Started on the circle a little away from the solution, the exact SQP with
//! λ = ½ takes Newton steps on the circle and is done in a few iterations; with λ = 0 its
//! first QP sees no curvature along the circle, and it needs more.

use footfall::sqp::{
    self, EvalError, ExactConvexification, HessianMode, IterationRecord, Nlp, NlpEval, Observer,
    Silent, SqpSettings, SqpStatus, WarmStart,
};

/// A linear objective on a curve of two variables, one equality row.
#[derive(Clone, Copy)]
enum OnA {
    /// Minimise −x − y on the circle x² + y² = 2 (the module's problem).
    Circle,
    /// Maximise x² on the parabola y = x² with x ≤ 1: minimise −y subject to y − x² = 0,
    /// x ∈ [−1, 1]. The solution is (1, 1) with λ = 1 and x held at its upper bound. The
    /// Lagrangian −y + λ(y − x²) curves by −2λ along x, so the only direction the
    /// parabola leaves free, (1, 2x), is negatively curved: only the bound makes the
    /// point a minimum.
    Parabola,
}

impl Nlp for OnA {
    fn n(&self) -> usize {
        2
    }
    fn m(&self) -> usize {
        1
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        match self {
            OnA::Circle => (vec![-10.0; 2], vec![10.0; 2], vec![0.0], vec![0.0]),
            OnA::Parabola => (vec![-1.0, -10.0], vec![1.0, 10.0], vec![0.0], vec![0.0]),
        }
    }
    fn jacobian_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        (vec![0, 0], vec![0, 1])
    }
    fn gauss_newton_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        (Vec::new(), Vec::new())
    }
    fn hessian_blocks(&self) -> Vec<Vec<usize>> {
        vec![vec![0, 1]]
    }
    fn row_name(&self, _i: usize) -> String {
        "curve".into()
    }
    fn evaluate(&self, w: &[f64], derivs: bool) -> Result<NlpEval, EvalError> {
        let (f, c, grad, jac) = match self {
            OnA::Circle => (
                -w[0] - w[1],
                w[0] * w[0] + w[1] * w[1] - 2.0,
                vec![-1.0, -1.0],
                vec![2.0 * w[0], 2.0 * w[1]],
            ),
            OnA::Parabola => (
                -w[1],
                w[1] - w[0] * w[0],
                vec![0.0, -1.0],
                vec![-2.0 * w[0], 1.0],
            ),
        };
        let mut ev = NlpEval {
            f,
            c: vec![c],
            ..Default::default()
        };
        if derivs {
            (ev.grad, ev.jac) = (grad, jac);
        }
        Ok(ev)
    }
    fn rows_with_exact_hessian(&self) -> Vec<bool> {
        vec![true]
    }
    fn exact_hessian(
        &self,
        _w: &[f64],
        lambda: &[f64],
    ) -> Result<(Vec<usize>, Vec<usize>, Vec<f64>), EvalError> {
        Ok(match self {
            OnA::Circle => (vec![0, 1], vec![0, 1], vec![2.0 * lambda[0]; 2]),
            OnA::Parabola => (vec![0], vec![0], vec![-2.0 * lambda[0]]),
        })
    }
}

fn settings() -> SqpSettings {
    SqpSettings {
        tol_kkt: 1e-10,
        max_iter: 60,
        hessian: HessianMode::Exact,
        exact_convexification: ExactConvexification::InertiaCorrection,
        ..Default::default()
    }
}

#[test]
fn the_multipliers_of_the_problem_a_solve_continues_give_it_newton_steps() {
    let angle = std::f64::consts::FRAC_PI_4 + 0.05;
    let w0 = [2f64.sqrt() * angle.cos(), 2f64.sqrt() * angle.sin()];
    let warm = sqp::solve_warm(
        &OnA::Circle,
        &w0,
        WarmStart::constraints(&[0.5]),
        &settings(),
        &mut Silent,
    );
    let cold = sqp::solve(&OnA::Circle, &w0, &settings(), &mut Silent);
    for (what, res) in [("warm", &warm), ("cold", &cold)] {
        assert_eq!(res.status, SqpStatus::Converged, "{what}: {res:?}");
        assert!(
            (res.w[0] - 1.0).abs() < 1e-8 && (res.w[1] - 1.0).abs() < 1e-8,
            "{what}: {:?}",
            res.w
        );
        assert!(
            (res.lambda[0] - 0.5).abs() < 1e-8,
            "{what}: λ = {:?}",
            res.lambda
        );
    }
    let iterations = |r: &sqp::SqpResult| r.history.len() - 1;
    // Newton on the circle: the error squares at each step (0.05 → 1e-3 → 1e-6 → 1e-12)
    assert!(
        iterations(&warm) <= 4,
        "warm: {} iterations",
        iterations(&warm)
    );
    assert!(
        iterations(&warm) < iterations(&cold),
        "warm {} against cold {} iterations",
        iterations(&warm),
        iterations(&cold)
    );
    eprintln!(
        "warm: {} iterations, cold: {}",
        iterations(&warm),
        iterations(&cold)
    );
    // multipliers of the wrong length are ignored: the same as the cold solve
    let ignored = sqp::solve_warm(
        &OnA::Circle,
        &w0,
        WarmStart::constraints(&[0.5, 0.5]),
        &settings(),
        &mut Silent,
    );
    assert_eq!(ignored.w, cold.w);
    assert_eq!(iterations(&ignored), iterations(&cold));
}

/// Collects what the solve tells its observer.
#[derive(Default)]
struct Told(Vec<String>);

impl sqp::Observer for Told {
    fn iteration(&mut self, _rec: &sqp::IterationRecord) -> bool {
        true
    }
    fn note(&mut self, text: &str) {
        self.0.push(text.to_string());
    }
}

/// When the exact Hessian comes in because the Gauss–Newton steps stalled, above the
/// violation that would bring it in anyway, the solve says so once; a solve without the
/// switch says nothing. The rule here trips after any one iteration (a decrease of 1000 %
/// is never reached) at any violation, so the step from iteration 2 (the first with an
/// iteration before it) uses the curvature; it never comes in by violation.
#[test]
fn the_solve_tells_when_stalled_steps_bring_in_the_exact_hessian() {
    let w0 = [1.2, 1.0];
    let stalling = SqpSettings {
        exact_hessian_below: 0.0,
        exact_hessian_on_stall: Some(sqp::StallSwitch {
            below: f64::INFINITY,
            iterations: 1,
            relative_decrease: 10.0,
        }),
        ..settings()
    };
    let mut told = Told::default();
    let res = sqp::solve(&OnA::Circle, &w0, &stalling, &mut told);
    assert_eq!(res.status, SqpStatus::Converged, "{res:?}");
    assert_eq!(told.0.len(), 1, "{:?}", told.0);
    assert!(
        told.0[0].starts_with("the steps from iteration 2 on use the exact Hessian"),
        "{}",
        told.0[0]
    );
    let mut quiet = Told::default();
    let fixed = SqpSettings {
        exact_hessian_below: 0.0,
        ..settings()
    };
    sqp::solve(&OnA::Circle, &w0, &fixed, &mut quiet);
    assert!(quiet.0.is_empty(), "{:?}", quiet.0);
}

/// A solve that goes on from another's multipliers (a tracking round that finishes the
/// last one's problem, or the second stage at a tighter integrator tolerance) also takes
/// its bound multipliers: the variable the first solve held at its bound is held by the
/// first iteration's inertia correction too, which then needs no shift (its smallest,
/// 2e-12). With the constraint multipliers alone the bound's variable counts as free, the
/// Lagrangian is not convex along the parabola, and the first QP's Hessian is shifted.
#[test]
fn the_bound_multipliers_of_the_problem_a_solve_continues_hold_its_bounds() {
    let first = sqp::solve(&OnA::Parabola, &[0.9, 0.5], &settings(), &mut Silent);
    assert_eq!(first.status, SqpStatus::Converged, "{first:?}");
    assert!(
        (first.w[0] - 1.0).abs() < 1e-9 && (first.w[1] - 1.0).abs() < 1e-8,
        "{:?}",
        first.w
    );
    assert!(
        (first.lambda[0] - 1.0).abs() < 1e-8,
        "λ = {:?}",
        first.lambda
    );
    assert!(first.nu[0] != 0.0, "ν = {:?}", first.nu);
    // the constraint violated, x at its bound: what a tighter integrator would leave
    let w0 = [1.0, 0.9];
    let shifts = |r: &sqp::SqpResult| -> Vec<Option<f64>> {
        r.history.iter().map(|h| h.hessian_shift).collect()
    };
    let both = sqp::solve_warm(
        &OnA::Parabola,
        &w0,
        WarmStart {
            lambda: &first.lambda,
            nu: &first.nu,
        },
        &settings(),
        &mut Silent,
    );
    let lambda_only = sqp::solve_warm(
        &OnA::Parabola,
        &w0,
        WarmStart::constraints(&first.lambda),
        &settings(),
        &mut Silent,
    );
    for (what, res) in [("λ and ν", &both), ("λ alone", &lambda_only)] {
        assert_eq!(res.status, SqpStatus::Converged, "{what}: {res:?}");
        assert!((res.w[1] - 1.0).abs() < 1e-8, "{what}: {:?}", res.w);
    }
    eprintln!(
        "shifts with λ and ν: {:?}; with λ alone: {:?}",
        shifts(&both),
        shifts(&lambda_only)
    );
    // at most the test's smallest shift (1e-12 of the Hessian's largest entry, here 2),
    // against one of the Lagrangian's curvature's size
    assert!(
        both.history[0].hessian_shift.is_some_and(|d| d < 1e-10),
        "{:?}",
        shifts(&both)
    );
    assert!(
        lambda_only.history[0]
            .hessian_shift
            .is_some_and(|d| d > 0.5),
        "{:?}",
        shifts(&lambda_only)
    );
    assert!(both.history.len() <= lambda_only.history.len());
    // bound multipliers of the wrong length are ignored: the same as λ alone
    let ignored = sqp::solve_warm(
        &OnA::Parabola,
        &w0,
        WarmStart {
            lambda: &first.lambda,
            nu: &[1.0],
        },
        &settings(),
        &mut Silent,
    );
    assert_eq!(ignored.w, lambda_only.w);
    assert_eq!(ignored.history.len(), lambda_only.history.len());
}

/// A problem that cannot be evaluated anywhere (as a round whose start the integrator
/// cannot cross): the circle's structure, every evaluation failing.
struct Unevaluable;

impl Nlp for Unevaluable {
    fn n(&self) -> usize {
        OnA::Circle.n()
    }
    fn m(&self) -> usize {
        OnA::Circle.m()
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        OnA::Circle.bounds()
    }
    fn jacobian_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        OnA::Circle.jacobian_pattern()
    }
    fn gauss_newton_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        OnA::Circle.gauss_newton_pattern()
    }
    fn hessian_blocks(&self) -> Vec<Vec<usize>> {
        OnA::Circle.hessian_blocks()
    }
    fn row_name(&self, i: usize) -> String {
        OnA::Circle.row_name(i)
    }
    fn evaluate(&self, _w: &[f64], _derivs: bool) -> Result<NlpEval, EvalError> {
        Err(EvalError::recoverable("non-finite value"))
    }
}

/// Work a solve finished is kept when the solve that continues it fails before its start
/// is evaluated: the joined result holds the first solve's point, objective, violation
/// and iterations, and the second's stop reason.
#[test]
fn a_continuation_that_fails_at_its_start_keeps_the_first_solves_point() {
    let first = sqp::solve(
        &OnA::Circle,
        &[1.2, 0.6],
        &SqpSettings {
            max_iter: 3,
            ..settings()
        },
        &mut Silent,
    );
    assert_eq!(first.status, SqpStatus::MaxIterations);
    assert!(first.objective.is_finite() && first.history.len() == 4);
    let second = sqp::solve(&Unevaluable, &first.w, &settings(), &mut Silent);
    assert!(second.history.is_empty() && second.objective.is_nan());
    let (w, objective, kkt) = (first.w.clone(), first.objective, first.kkt);
    let joined = first.followed_by(second);
    assert!(
        matches!(&joined.status, SqpStatus::EvaluationFailure(why) if why.contains("non-finite value")),
        "{:?}",
        joined.status
    );
    assert_eq!(joined.w, w);
    assert_eq!(joined.objective.to_bits(), objective.to_bits());
    assert_eq!(joined.kkt.to_bits(), kkt.to_bits());
    assert_eq!(joined.history.len(), 4);
}

/// An observer that answers `go_on` at the milestone and keeps the iterates it was asked
/// about.
struct Judge {
    go_on: bool,
    asked: Vec<Vec<f64>>,
}

impl Observer for Judge {
    fn iteration(&mut self, _: &IterationRecord) -> bool {
        true
    }
    fn milestone(&mut self, w: &[f64]) -> bool {
        self.asked.push(w.to_vec());
        self.go_on
    }
}

impl Judge {
    fn answering(go_on: bool) -> Self {
        Self {
            go_on,
            asked: Vec::new(),
        }
    }
}

/// A start on the circle far enough from the solution to take several iterations.
fn far_start() -> [f64; 2] {
    let angle = std::f64::consts::FRAC_PI_4 + 0.6;
    [2f64.sqrt() * angle.cos(), 2f64.sqrt() * angle.sin()]
}

/// The circle's solve from [`far_start`], with a milestone at a KKT residual of 1e-3 and
/// `judge` as its observer.
fn solve_with_milestone(judge: &mut Judge) -> sqp::SqpResult {
    let settings = SqpSettings {
        milestone_tol: Some(1e-3),
        ..settings()
    };
    sqp::solve(&OnA::Circle, &far_start(), &settings, judge)
}

#[test]
fn a_solve_told_to_end_at_its_milestone_ends_there_converged_to_its_tolerance() {
    let mut judge = Judge::answering(false);
    let res = solve_with_milestone(&mut judge);
    assert_eq!(res.status, SqpStatus::Converged, "{res:?}");
    assert!(res.kkt <= 1e-3 && res.kkt > 1e-10, "KKT {:e}", res.kkt);
    assert_eq!(
        judge.asked,
        vec![res.w.clone()],
        "asked once, at the point it ends at"
    );
    // the KKT residual was above the milestone at every earlier iteration
    let history = &res.history;
    assert!(
        history.len() >= 3,
        "{} iterations: {history:?}",
        history.len() - 1
    );
    assert!(history[..history.len() - 1].iter().all(|r| r.kkt > 1e-3));
}

#[test]
fn a_solve_told_to_go_on_at_its_milestone_follows_the_iterates_of_one_not_asked() {
    let mut judge = Judge::answering(true);
    let res = solve_with_milestone(&mut judge);
    let plain = sqp::solve(&OnA::Circle, &far_start(), &settings(), &mut Silent);
    assert_eq!(res.status, SqpStatus::Converged, "{res:?}");
    assert!(res.kkt <= 1e-10, "KKT {:e}", res.kkt);
    assert_eq!(judge.asked.len(), 1, "asked once, then not again");
    let asked_at = res
        .history
        .iter()
        .position(|r| r.kkt <= 1e-3)
        .expect("an iteration within the milestone");
    assert!(
        asked_at < res.history.len() - 1,
        "the milestone before the end"
    );
    assert_eq!(res.w, plain.w, "the same solution, bit for bit");
    assert_eq!(res.history.len(), plain.history.len());
    for (a, b) in res.history.iter().zip(&plain.history) {
        assert_eq!(a.kkt.to_bits(), b.kkt.to_bits(), "iteration {}", a.iter);
    }
}
