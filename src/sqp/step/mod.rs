//! The step: the QP subproblem at the current iterate and its solution.
//!
//! The QP's Hessian follows [`HessianMode`]: Gauss–Newton, block BFGS, the structured
//! mix, or the exact Hessian of the Lagrangian made convex ([`ExactConvexification`]).
//! When the QP fails, the exact mode retries with its block-convexified Hessian; an
//! inconsistent (or stalled) QP is solved in elastic mode, with every row's violation
//! penalised; when that fails too, a growing proximal shift `δ I` gives a
//! better-conditioned QP with a shorter step.

mod exact;

use super::evaluator::Evaluator;
use super::hessian::BlockBfgs;
use super::iterate::{State, Structure};
use super::qp::{ActiveHint, QpData, QpError, QpSolution, Triplets};
use super::{
    ExactConvexification, HessianMode, IterationRecord, Nlp, QpRoute, SqpSettings, SqpStatus,
};
use exact::{exact_qp_hessian, row_gram, sparse_rows, ExactQpContext};

/// What the step computation carries from one iteration to the next (and in
/// checkpoints).
#[derive(Debug, Clone, Copy)]
pub(super) struct StepMemory {
    /// Size of the multipliers of the last consistent QP: the elastic penalty exceeds it.
    pub(super) lam_est: f64,
    /// ρ of the exact mode's augmentation or convexity test is this times max|H|
    /// (raised when a QP fails).
    pub(super) test_rho_scale: f64,
    /// Inertia-correction shift of the exact mode's QP Hessian (last value).
    pub(super) shift: f64,
    /// Whether the shifted steps stalled, so that the exact mode now takes the
    /// Gauss–Newton Hessian where the exact one is not convex
    /// ([`ExactConvexification::InertiaCorrectionThenGaussNewton`]).
    pub(super) shift_stalled: bool,
    /// Whether the exact mode's last QP took the Gauss–Newton Hessian.
    pub(super) gauss_newton: bool,
}

impl Default for StepMemory {
    fn default() -> Self {
        Self {
            lam_est: 1.0,
            test_rho_scale: 1.0,
            shift: 0.0,
            shift_stalled: false,
            gauss_newton: false,
        }
    }
}

/// The QP subproblem at one iterate.
pub(super) struct Subproblem<'a> {
    s: &'a Structure,
    /// The QP Hessian (upper triangle, regularised).
    h: Triplets,
    /// Exact mode: the block-convexified Hessian, for elastic QPs and when the QP fails.
    h_elastic: Option<Triplets>,
    /// Augmentation ρ of the exact mode's QP ([`ExactConvexification::Augmented`]).
    aug_rho: f64,
    /// The equality rows of the Jacobian, when augmented.
    eq_rows: Vec<Vec<(usize, f64)>>,
    jac: Triplets,
    g: &'a [f64],
    c: &'a [f64],
    d_lb: Vec<f64>,
    d_ub: Vec<f64>,
    /// The multipliers of the last QP (λ, ν): its active set is the first guess of this
    /// one's (`None`: no guess, straight to Clarabel).
    last: Option<(Vec<f64>, Vec<f64>)>,
}

impl Subproblem<'_> {
    /// Solve the QP without a guess of its active set: straight to Clarabel.
    pub(super) fn without_guess(&mut self) {
        self.last = None;
    }

    /// The QP; in elastic mode (penalty ρ) with the convexified Hessian if there is one.
    pub(super) fn data(&self, elastic: Option<f64>) -> QpData<'_> {
        QpData {
            h: if elastic.is_some() {
                self.h_elastic.as_ref().unwrap_or(&self.h)
            } else {
                &self.h
            },
            g: self.g,
            jac: &self.jac,
            c: self.c,
            c_lb: &self.s.c_lb,
            c_ub: &self.s.c_ub,
            d_lb: &self.d_lb,
            d_ub: &self.d_ub,
            elastic,
            elastic_weights: &self.s.elastic_weights,
            hint: self
                .last
                .as_ref()
                .map(|(lambda, nu)| ActiveHint { lambda, nu }),
        }
    }
}

/// A solved subproblem.
#[derive(Debug)]
pub(super) struct Step {
    /// Step and multipliers (the equality multipliers corrected for the augmentation).
    pub(super) sol: QpSolution,
    /// Whether it came from the elastic QP.
    pub(super) elastic: bool,
    /// Which QP gave it.
    pub(super) route: QpRoute,
}

/// Whether the exact mode uses the constraint curvature at an iterate of largest violation
/// `infeas` after the iterations `history`: far from feasibility the multipliers (and so
/// the curvature) are unreliable, so only below `exact_hessian_below`, or once the
/// Gauss–Newton steps have stalled ([`SqpSettings::exact_hessian_on_stall`]); after a
/// step that used it, up to [`SqpSettings::exact_hessian_hold`] times that violation.
pub(super) fn curvature_in_use(
    settings: &SqpSettings,
    infeas: f64,
    history: &[IterationRecord],
) -> bool {
    infeas <= settings.exact_hessian_below
        || (history.last().is_some_and(|r| r.hessian_shift.is_some())
            && infeas <= settings.exact_hessian_hold * settings.exact_hessian_below)
        || settings
            .exact_hessian_on_stall
            .is_some_and(|rule| rule.stalled_at(history).is_some())
}

/// Whether iteration `iter`'s QP is tried first on the active set the last QP's
/// multipliers hold: unless the last two QPs both left it to Clarabel (far from a
/// solution, where the active set changes more between iterations than a few corrections
/// mend), and then every third iteration. A miss costs a few sparse factorisations.
pub(super) fn guess_active_set(iter: usize, history: &[IterationRecord]) -> bool {
    let missed = history
        .iter()
        .rev()
        .take(2)
        .filter(|r| r.qp_iterations > 0)
        .count();
    missed < 2 || iter % 3 == 0
}

/// Build the QP at `st` with multipliers `lambda`, `nu` of the last QP; `curvature`: whether
/// the exact mode uses the constraint curvature at `st` ([`curvature_in_use`]).
/// `zero_blocks` is the Hessian's block structure with zero matrices (convexification
/// block by block). An error is the solve's status.
#[allow(clippy::too_many_arguments)]
pub(super) fn subproblem<'a>(
    nlp: &dyn Nlp,
    settings: &SqpSettings,
    s: &'a Structure,
    st: &'a State,
    (lambda, nu): (&[f64], &[f64]),
    curvature: bool,
    (bfgs, zero_blocks): (&BlockBfgs, &BlockBfgs),
    mem: &mut StepMemory,
) -> Result<Subproblem<'a>, SqpStatus> {
    let (n, m) = (s.n, s.m);
    let mut h = Triplets::default();
    let mut h_elastic: Option<Triplets> = None;
    let mut aug_rho = 0.0;
    let mut eq_rows: Vec<Vec<(usize, f64)>> = Vec::new();
    match settings.hessian {
        HessianMode::GaussNewton => h = gauss_newton(s, st),
        HessianMode::Bfgs if !s.any_exact => bfgs.push_upper(&mut h),
        HessianMode::Bfgs => {}
        HessianMode::Exact => {
            let mut ex = gauss_newton(s, st);
            let use_curvature = curvature && st.hess.is_some();
            if let (Some(hx), true) = (&st.hess, use_curvature) {
                ex.rows.extend_from_slice(&hx.rows);
                ex.cols.extend_from_slice(&hx.cols);
                ex.vals.extend_from_slice(&hx.vals);
            }
            // block-convexified copy: for elastic QPs and when a QP fails
            let mut conv = Triplets::default();
            zero_blocks.convexify_into(&mut ex.clone(), &mut conv);
            for i in 0..n {
                conv.push(i, i, settings.regularization);
            }
            h_elastic = Some(conv);
            if settings.exact_convexification == ExactConvexification::Augmented {
                let hmax = ex.vals.iter().map(|v| v.abs()).fold(1.0, f64::max);
                aug_rho = mem.test_rho_scale * hmax;
                eq_rows = sparse_rows(m, &s.jac_rows, &s.jac_cols, &st.ev.jac, |i| {
                    s.c_lb[i] == s.c_ub[i]
                });
                ex.extend_scaled(&row_gram(&eq_rows), aug_rho);
            } else if use_curvature {
                let shift = exact_qp_hessian(
                    &mut ex,
                    !mem.shift_stalled,
                    &ExactQpContext {
                        n,
                        w: &st.w,
                        w_lb: &s.w_lb,
                        w_ub: &s.w_ub,
                        nu,
                        c: &st.ev.c,
                        c_lb: &s.c_lb,
                        c_ub: &s.c_ub,
                        lambda,
                        jac_rows: &s.jac_rows,
                        jac_cols: &s.jac_cols,
                        jac: &st.ev.jac,
                        test_rho_scale: mem.test_rho_scale,
                        previous_shift: mem.shift,
                    },
                );
                mem.gauss_newton = shift.is_none();
                mem.shift = shift.unwrap_or(0.0);
                if mem.gauss_newton {
                    ex = gauss_newton(s, st);
                }
            }
            h = ex;
        }
        HessianMode::GaussNewtonBfgs => {
            h = gauss_newton(s, st);
            if !s.any_exact {
                bfgs.push_upper(&mut h);
            }
        }
    }
    if s.any_exact
        && matches!(
            settings.hessian,
            HessianMode::Bfgs | HessianMode::GaussNewtonBfgs
        )
    {
        match nlp.exact_hessian(&st.w, lambda) {
            Ok((r, c, v)) => {
                let mut ex = Triplets {
                    rows: r,
                    cols: c,
                    vals: v,
                };
                bfgs.convexify_into(&mut ex, &mut h);
            }
            Err(e) => return Err(SqpStatus::EvaluationFailure(e.chain())),
        }
    }
    for i in 0..n {
        h.push(i, i, settings.regularization);
    }
    Ok(Subproblem {
        s,
        h,
        h_elastic,
        aug_rho,
        eq_rows,
        jac: s.jacobian(&st.ev.jac),
        g: &st.ev.grad,
        c: &st.ev.c,
        d_lb: (0..n).map(|i| s.w_lb[i] - st.w[i]).collect(),
        d_ub: (0..n).map(|i| s.w_ub[i] - st.w[i]).collect(),
        last: Some((lambda.to_vec(), nu.to_vec())),
    })
}

/// Solve the subproblem: the QP; in the exact mode after a failure its block-convexified
/// version (and a larger ρ from now on); if inconsistent or failed, the elastic QP with
/// penalty `clamp(10 λ_est, 10³, 10⁸)`; if that fails, the proximal rescue. An error is
/// the solve's status ([`SqpStatus::QpFailure`] with the elastic QP's error).
pub(super) fn solve(
    eval: &Evaluator<'_>,
    sub: &Subproblem<'_>,
    mem: &mut StepMemory,
) -> Result<Step, SqpStatus> {
    let rho = (10.0 * mem.lam_est).clamp(1e3, 1e8);
    let mut aug_rho = sub.aug_rho;
    let mut route = QpRoute::Direct;
    let mut first = eval.qp(&sub.data(None));
    if let (Err(QpError::Failed(_)), Some(hc)) = (&first, sub.h_elastic.as_ref()) {
        route = QpRoute::Convexified;
        // exact mode: the QP was not solved with the exact curvature; test convexity
        // with a larger ρ from now on and solve this one with the block-convexified Hessian
        mem.test_rho_scale *= 10.0;
        aug_rho = 0.0;
        first = eval.qp(&QpData {
            h: hc,
            ..sub.data(None)
        });
    }
    let (mut sol, elastic) = match first {
        Ok(s) => (s, false),
        // inconsistent linearisation (or a stalled, nearly inconsistent one): elastic mode
        Err(QpError::Infeasible | QpError::Failed(_)) => match eval.qp(&sub.data(Some(rho))) {
            Ok(s) => {
                route = QpRoute::Elastic;
                (s, true)
            }
            Err(e) => match rescue(eval, sub) {
                Some(s) => {
                    route = QpRoute::Proximal;
                    (s, false)
                }
                None => return Err(SqpStatus::QpFailure(e.to_string())),
            },
        },
    };
    if aug_rho > 0.0 && !elastic {
        // ρ JₑᵀJₑ moves the QP's equality multipliers by −ρ·(Jₑ d)
        for (i, row) in sub.eq_rows.iter().enumerate() {
            sol.lambda[i] += aug_rho * row.iter().map(|&(c, v)| v * sol.d[c]).sum::<f64>();
        }
    }
    if !elastic {
        mem.lam_est = sol.lambda.iter().map(|v| v.abs()).fold(1.0, f64::max);
    }
    Ok(Step {
        sol,
        elastic,
        route,
    })
}

/// The Gauss–Newton Hessian of the least-squares objective at the current point, as
/// upper-triangle triplets.
fn gauss_newton(s: &Structure, st: &State) -> Triplets {
    Triplets {
        rows: s.gn_rows.clone(),
        cols: s.gn_cols.clone(),
        vals: st.ev.gn.clone(),
    }
}

/// The interior-point solver lost accuracy on this QP: a proximal shift δI (growing,
/// δ = (10⁻⁶, 10⁻⁴, 10⁻², 1) · max(1, max|H|)) gives a better-conditioned QP with a
/// shorter step; the first that solves.
fn rescue(eval: &Evaluator<'_>, sub: &Subproblem<'_>) -> Option<QpSolution> {
    let hmax = sub.h.vals.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    for delta in [1e-6, 1e-4, 1e-2, 1.0] {
        let mut hs = sub.h.clone();
        for i in 0..sub.s.n {
            hs.push(i, i, delta * hmax);
        }
        if let Ok(s) = eval.qp(&QpData {
            h: &hs,
            ..sub.data(None)
        }) {
            return Some(s);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sqp::{EvalError, NlpEval, StallSwitch};

    /// An NLP the step never evaluates (the subproblems below are built by hand).
    struct Unused;

    impl Nlp for Unused {
        fn n(&self) -> usize {
            unreachable!()
        }
        fn m(&self) -> usize {
            unreachable!()
        }
        fn bounds(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
            unreachable!()
        }
        fn jacobian_pattern(&self) -> (Vec<usize>, Vec<usize>) {
            unreachable!()
        }
        fn gauss_newton_pattern(&self) -> (Vec<usize>, Vec<usize>) {
            unreachable!()
        }
        fn hessian_blocks(&self) -> Vec<Vec<usize>> {
            unreachable!()
        }
        fn evaluate(&self, _: &[f64], _: bool) -> Result<NlpEval, EvalError> {
            unreachable!()
        }
        fn row_name(&self, i: usize) -> String {
            format!("row {i}")
        }
    }

    fn settings(inject: &[usize]) -> SqpSettings {
        SqpSettings {
            inject_qp_failures: inject.to_vec(),
            ..SqpSettings::default()
        }
    }

    /// Equality rows `c_i = 0` with a dense Jacobian pattern (row by row), variable
    /// bounds ±10, elastic weights `weights`.
    fn structure(n: usize, weights: &[f64]) -> Structure {
        let m = weights.len();
        Structure {
            n,
            m,
            w_lb: vec![-10.0; n],
            w_ub: vec![10.0; n],
            c_lb: vec![0.0; m],
            c_ub: vec![0.0; m],
            jac_rows: (0..m * n).map(|k| k / n).collect(),
            jac_cols: (0..m * n).map(|k| k % n).collect(),
            elastic_weights: weights.to_vec(),
            exact_rows: vec![false; m],
            ..Structure::default()
        }
    }

    fn diagonal(d: &[f64]) -> Triplets {
        let mut t = Triplets::default();
        for (i, &v) in d.iter().enumerate() {
            t.push(i, i, v);
        }
        t
    }

    fn subproblem<'a>(
        s: &'a Structure,
        h: Triplets,
        jac: &[f64],
        g: &'a [f64],
        c: &'a [f64],
    ) -> Subproblem<'a> {
        Subproblem {
            s,
            h,
            h_elastic: None,
            aug_rho: 0.0,
            eq_rows: Vec::new(),
            jac: s.jacobian(jac),
            g,
            c,
            d_lb: s.w_lb.clone(),
            d_ub: s.w_ub.clone(),
            last: Some((vec![0.0; s.m], vec![0.0; s.n])),
        }
    }

    /// x − 1 = 0 (weight 10) and x + 1 = 0 (weight 1) at x = 0: the linearisation asks
    /// for d = 1 and d = −1 at once. The elastic QP (penalty 10³) keeps the heavier row:
    /// min ½d² + 10³(10|d − 1| + |d + 1|) is at d = 1.
    #[test]
    fn an_inconsistent_linearisation_is_solved_in_elastic_mode() {
        let s = structure(1, &[10.0, 1.0]);
        let sub = subproblem(&s, diagonal(&[1.0]), &[1.0, 1.0], &[0.0], &[-1.0, 1.0]);
        let settings = settings(&[]);
        let eval = Evaluator::new(&Unused, &settings, Default::default());
        let mut mem = StepMemory::default();
        let step = solve(&eval, &sub, &mut mem).expect("elastic QP");
        assert!(step.elastic);
        assert!((step.sol.d[0] - 1.0).abs() < 1e-6, "{:?}", step.sol.d);
        // the estimate of the multipliers' size is kept from consistent QPs only
        assert_eq!(mem.lam_est, 1.0);
        assert_eq!(eval.timings().qp_solves, 2);
    }

    /// min d² − 2d (d = 1) when the QP and its elastic version fail: the proximal rescue
    /// solves with H + 10⁻⁶·max|H|·I = 2 + 2·10⁻⁶, d = 1/(1 + 10⁻⁶); when every
    /// shift fails too, the solve stops with the elastic QP's error.
    #[test]
    fn a_failed_qp_is_rescued_by_a_proximal_shift() {
        let s = structure(1, &[]);
        let sub = subproblem(&s, diagonal(&[2.0]), &[], &[-2.0], &[]);
        let settings = settings(&[0, 1]);
        let eval = Evaluator::new(&Unused, &settings, Default::default());
        let step = solve(&eval, &sub, &mut StepMemory::default()).expect("rescued");
        assert!(!step.elastic);
        let want = 1.0 / (1.0 + 1e-6);
        assert!((step.sol.d[0] - want).abs() < 1e-9, "{:?}", step.sol.d);
        assert_eq!(eval.timings().qp_solves, 3);

        let settings = self::settings(&[0, 1, 2, 3, 4, 5]);
        let eval = Evaluator::new(&Unused, &settings, Default::default());
        match solve(&eval, &sub, &mut StepMemory::default()) {
            Err(SqpStatus::QpFailure(e)) => assert!(e.contains("injected"), "{e}"),
            other => panic!("{other:?}"),
        }
        assert_eq!(eval.timings().qp_solves, 6);
    }

    /// min ½|d|² s.t. d₁ + d₂ = 1 (c = −1): d = (½, ½), λ = −½ (Lagrangian f + λc).
    /// With the augmentation ρ JᵀJ (ρ = 10) the QP's multiplier is −½ − ρ; the step
    /// corrects it back to −½. When the QP fails, the exact mode solves with its
    /// convexified Hessian instead, raises the test's ρ scale tenfold and corrects
    /// nothing.
    #[test]
    fn the_augmented_qp_returns_the_lagrangian_multipliers() {
        let s = structure(2, &[1.0]);
        let mut sub = subproblem(&s, diagonal(&[1.0, 1.0]), &[1.0, 1.0], &[0.0, 0.0], &[-1.0]);
        sub.aug_rho = 10.0;
        sub.eq_rows = sparse_rows(1, &s.jac_rows, &s.jac_cols, &[1.0, 1.0], |_| true);
        sub.h.extend_scaled(&row_gram(&sub.eq_rows), sub.aug_rho);
        let settings = settings(&[]);
        let eval = Evaluator::new(&Unused, &settings, Default::default());
        let step = solve(&eval, &sub, &mut StepMemory::default()).expect("QP");
        assert!((step.sol.d[0] - 0.5).abs() < 1e-7 && (step.sol.d[1] - 0.5).abs() < 1e-7);
        assert!(
            (step.sol.lambda[0] + 0.5).abs() < 1e-6,
            "{:?}",
            step.sol.lambda
        );

        sub.h_elastic = Some(diagonal(&[2.0, 2.0]));
        let settings = self::settings(&[0]);
        let eval = Evaluator::new(&Unused, &settings, Default::default());
        let mut mem = StepMemory::default();
        let step = solve(&eval, &sub, &mut mem).expect("convexified QP");
        assert_eq!(mem.test_rho_scale, 10.0);
        // H = 2I: d = (½, ½), λ = −1, uncorrected
        assert!(
            (step.sol.lambda[0] + 1.0).abs() < 1e-6,
            "{:?}",
            step.sol.lambda
        );
        assert_eq!(mem.lam_est, step.sol.lambda[0].abs().max(1.0));
    }

    /// The Gauss–Newton subproblem: the Gauss–Newton values plus the regularisation on
    /// the diagonal, the step bounds w_lb − w and w_ub − w.
    #[test]
    fn the_gauss_newton_subproblem_is_the_gauss_newton_matrix_regularised() {
        let mut s = structure(2, &[1.0]);
        s.gn_rows = vec![0, 0, 1];
        s.gn_cols = vec![0, 1, 1];
        let st = State {
            w: vec![1.0, -2.0],
            ev: NlpEval {
                f: 0.0,
                c: vec![0.5],
                grad: vec![1.0, 2.0],
                jac: vec![1.0, 1.0],
                gn: vec![4.0, 1.0, 3.0],
            },
            hess: None,
            plain: (0.0, 0.5),
        };
        let settings = settings(&[]);
        let blocks = BlockBfgs::new(vec![vec![0], vec![1]], settings.bfgs_update);
        let sub = subproblem_of(&settings, &s, &st, &blocks);
        assert_eq!(sub.h.rows, vec![0, 0, 1, 0, 1]);
        assert_eq!(sub.h.cols, vec![0, 1, 1, 0, 1]);
        assert_eq!(sub.h.vals, vec![4.0, 1.0, 3.0, 1e-9, 1e-9]);
        assert_eq!(
            (sub.d_lb.clone(), sub.d_ub.clone()),
            (vec![-11.0, -8.0], vec![9.0, 12.0])
        );
        assert_eq!(sub.data(None).g, &[1.0, 2.0]);
    }

    fn subproblem_of<'a>(
        settings: &SqpSettings,
        s: &'a Structure,
        st: &'a State,
        blocks: &BlockBfgs,
    ) -> Subproblem<'a> {
        let (lambda, nu) = (vec![0.0; s.m], vec![0.0; s.n]);
        let Ok(sub) = super::subproblem(
            &Unused,
            settings,
            s,
            st,
            (&lambda, &nu),
            curvature_in_use(settings, 0.5, &[]),
            (blocks, blocks),
            &mut StepMemory::default(),
        ) else {
            panic!("subproblem")
        };
        sub
    }

    /// A history of `(objective, violation)` per iteration.
    fn history(points: &[(f64, f64)]) -> Vec<IterationRecord> {
        points
            .iter()
            .enumerate()
            .map(|(iter, &(objective, infeasibility))| IterationRecord {
                iter,
                objective,
                infeasibility,
                kkt: 1.0,
                step: 1.0,
                seconds: 0.0,
                qp_iterations: 0,
                integration_tol: None,
                hessian_shift: None,
                qp_route: None,
            })
            .collect()
    }

    /// The shifted steps' stall: ten shifted steps near feasibility that do not halve the
    /// smallest KKT residual before them; not when one of them halves it, one is unshifted,
    /// one is far from feasible, or there is nothing before them to compare with.
    #[test]
    fn shifted_steps_stall_when_ten_in_a_row_do_not_halve_the_residual() {
        let tail = |kkt: &[f64], shift: Option<f64>, infeasibility: f64| {
            let mut h = history(&vec![(1.0, infeasibility); kkt.len() + 1]);
            h[0].kkt = 1e-3;
            h[0].infeasibility = 1e-6;
            for (r, &k) in h[1..].iter_mut().zip(kkt) {
                r.kkt = k;
                r.hessian_shift = shift;
            }
            h
        };
        let flat = [8e-4; super::super::SHIFTED_STALL];
        let stalled = |h: &[IterationRecord]| super::super::shifted_steps_stalled(h, 1e-3);
        assert!(stalled(&tail(&flat, Some(5.0), 1e-6)));
        let mut halved = flat;
        halved[6] = 4e-4;
        assert!(!stalled(&tail(&halved, Some(5.0), 1e-6)));
        assert!(!stalled(&tail(&flat, Some(0.0), 1e-6)));
        assert!(!stalled(&tail(&flat, None, 1e-6)));
        assert!(!stalled(&tail(&flat, Some(5.0), 1e-2)));
        assert!(!stalled(&tail(&flat, Some(5.0), 1e-6)[1..]));
    }

    /// The stall switch: steady progress never trips it; a cycle that dips and rises
    /// without a new best (by more than 0.1 %) trips it after three iterations; a violation
    /// above its bound in the window, or a lower objective at an infeasible point before
    /// the window, does not count; once tripped, the curvature stays in use above the
    /// violation switch.
    #[test]
    fn the_curvature_comes_in_when_the_steps_stall_below_the_violation() {
        let rule = StallSwitch {
            below: 0.1,
            iterations: 3,
            relative_decrease: 1e-3,
        };
        let steady: Vec<(f64, f64)> = (0..10).map(|i| (1.0 - 0.01 * i as f64, 1e-2)).collect();
        assert_eq!(rule.stalled_at(&history(&steady)), None);
        // the best feasible point is 0.5 at iteration 1; iterations 2–4 never beat it by
        // 0.1 % (0.4996 is within), though 3 is below its predecessor 2
        let cycle = [
            (0.6, 1e-2),
            (0.5, 1e-2),
            (0.52, 5e-3),
            (0.4996, 8e-3),
            (0.51, 1e-2),
        ];
        assert_eq!(rule.stalled_at(&history(&cycle)), Some(4));
        assert_eq!(rule.stalled_at(&history(&cycle[..4])), None);
        // a new best beyond the tolerance in the window: progress
        let mut better = cycle;
        better[3].0 = 0.49;
        assert_eq!(rule.stalled_at(&history(&better)), None);
        // a window point above the violation bound: not a stall of these steps
        let mut far = cycle;
        far[3].1 = 0.2;
        assert_eq!(rule.stalled_at(&history(&far)), None);
        // a lower objective at an infeasible point (violation 5) is no best to beat: the
        // windows are measured from the feasible points before them, and go down from them
        let infeasible_low = [
            (0.3, 5.0),
            (0.6, 1e-2),
            (0.55, 1e-2),
            (0.5, 1e-2),
            (0.45, 1e-2),
        ];
        assert_eq!(rule.stalled_at(&history(&infeasible_low)), None);
        // and with no feasible point before the window there is nothing to stall against
        let flat_from_far = [(0.3, 5.0), (0.5, 1e-2), (0.5, 1e-2), (0.5, 1e-2)];
        assert_eq!(rule.stalled_at(&history(&flat_from_far)), None);

        let mut settings = SqpSettings {
            hessian: HessianMode::Exact,
            exact_hessian_below: 1e-3,
            ..SqpSettings::default()
        };
        let h = history(&cycle);
        assert!(
            !curvature_in_use(&settings, 1e-2, &h),
            "no rule: the violation decides"
        );
        assert!(curvature_in_use(&settings, 1e-4, &h));
        settings.exact_hessian_on_stall = Some(rule);
        assert!(curvature_in_use(&settings, 1e-2, &h));
        // sticky: still in use at a violation above the rule's bound after the stall
        assert!(curvature_in_use(&settings, 0.5, &h));
        assert!(!curvature_in_use(&settings, 1e-2, &h[..4]));

        // held after a step that used it: up to exact_hessian_hold × the switch
        settings.exact_hessian_on_stall = None;
        let mut after_exact = history(&[(1.0, 1e-4)]);
        assert!(!curvature_in_use(&settings, 5e-3, &after_exact));
        after_exact[0].hessian_shift = Some(0.0);
        assert!(curvature_in_use(&settings, 5e-3, &after_exact));
        assert!(!curvature_in_use(&settings, 2e-2, &after_exact));
        settings.exact_hessian_hold = 1.0;
        assert!(!curvature_in_use(&settings, 5e-3, &after_exact));
    }
}
