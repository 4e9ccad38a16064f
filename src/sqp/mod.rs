//! Sequential quadratic programming for sparse NLPs
//! $$\min_w f(w)\ \text{s.t.}\ c_{lb} \le c(w) \le c_{ub},\ w_{lb} \le w \le w_{ub}.$$
//!
//! Each iteration solves a sparse QP (Clarabel) with a Gauss–Newton, block-wise BFGS or
//! structured (Gauss–Newton + BFGS) Hessian and globalises with a filter line search
//! (Wächter & Biegler 2006) on the objective and the l1 constraint violation, with a
//! second-order correction when the full step is rejected. When the linearised
//! constraints are inconsistent the QP is solved in elastic mode; if the violation then
//! cannot be reduced the solver stops with [`SqpStatus::Infeasible`] and names the most
//! violated constraints.
//!
//! Convergence is declared when the KKT residual, the largest of the scaled
//! stationarity $\|\nabla f + J^T\lambda + \nu\|_\infty / s_d$ (IPOPT's scaling,
//! $s_d = \max(1, \|(\lambda,\nu)\|_1/((m+n)\,100))$), the constraint violation and the
//! complementarity, falls below the tolerance.

pub mod checkpoint;
mod eval_error;
pub mod hessian;
pub mod linearised;
pub mod qp;

pub use eval_error::{Cause, EvalError};
use checkpoint::{ExactRecord, ExactVec, SqpCheckpoint, CHECKPOINT_VERSION};
use hessian::BlockBfgs;
use qp::{QpData, QpError, Triplets};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// A sparse NLP as the SQP sees it.
pub trait Nlp {
    /// Number of variables.
    fn n(&self) -> usize;
    /// Number of constraints.
    fn m(&self) -> usize;
    /// `(w_lb, w_ub, c_lb, c_ub)`.
    fn bounds(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);
    /// Jacobian pattern (rows, cols).
    fn jacobian_pattern(&self) -> (Vec<usize>, Vec<usize>);
    /// Gauss–Newton Hessian pattern (upper triangle).
    fn gauss_newton_pattern(&self) -> (Vec<usize>, Vec<usize>);
    /// Variable groups for block-wise quasi-Newton updates.
    fn hessian_blocks(&self) -> Vec<Vec<usize>>;
    /// Evaluate at `w`; with `derivs` also gradient, Jacobian values and Gauss–Newton
    /// Hessian values (in pattern order). A [recoverable](EvalError::Recoverable) failure
    /// at a trial point shortens the step; a [fatal](EvalError::Fatal) one stops the solve.
    fn evaluate(&self, w: &[f64], derivs: bool) -> Result<NlpEval, EvalError>;
    /// Human-readable name of constraint row `i`.
    fn row_name(&self, i: usize) -> String;
    /// Relative weights of the rows' violations in elastic mode (default all 1). A
    /// larger weight makes the solver keep that row satisfied at the expense of others,
    /// so an infeasible problem reports the constraints that really conflict (e.g. a
    /// transcription weights its continuity rows above user constraints).
    fn elastic_weights(&self) -> Vec<f64> {
        vec![1.0; self.m()]
    }
    /// Evaluate with derivatives and the exact Lagrangian curvature of the constraints
    /// `Σ λ_i ∇²c_i` (upper-triangle triplets), for [`HessianMode::Exact`]. Default:
    /// [`evaluate`](Self::evaluate) plus [`exact_hessian`](Self::exact_hessian).
    #[allow(clippy::type_complexity)]
    fn evaluate_with_hessian(
        &self,
        w: &[f64],
        lambda: &[f64],
    ) -> Result<(NlpEval, (Vec<usize>, Vec<usize>, Vec<f64>)), EvalError> {
        Ok((self.evaluate(w, true)?, self.exact_hessian(w, lambda)?))
    }
    /// Rows whose curvature [`exact_hessian`](Self::exact_hessian) provides (the
    /// quasi-Newton update leaves them out). Default: none.
    fn rows_with_exact_hessian(&self) -> Vec<bool> {
        vec![false; self.m()]
    }
    /// Exact curvature `Σ λ_i ∇²c_i` of those rows at `w`, as upper-triangle triplets.
    fn exact_hessian(
        &self,
        _w: &[f64],
        _lambda: &[f64],
    ) -> Result<(Vec<usize>, Vec<usize>, Vec<f64>), EvalError> {
        Ok((Vec::new(), Vec::new(), Vec::new()))
    }
}

/// Keep the first fatal evaluation failure of a line search; recoverable ones only
/// shorten the step.
fn keep_fatal(slot: &mut Option<EvalError>, e: EvalError) {
    if !e.is_recoverable() && slot.is_none() {
        *slot = Some(e);
    }
}

/// An NLP evaluation.
#[derive(Debug, Clone, Default)]
pub struct NlpEval {
    /// Objective.
    pub f: f64,
    /// Constraints.
    pub c: Vec<f64>,
    /// Gradient.
    pub grad: Vec<f64>,
    /// Jacobian values.
    pub jac: Vec<f64>,
    /// Gauss–Newton Hessian values.
    pub gn: Vec<f64>,
}

/// Hessian approximation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HessianMode {
    /// `2 Σ J_rᵀ J_r` of the least-squares terms (tracking problems).
    GaussNewton,
    /// Block-diagonal BFGS of the Lagrangian Hessian (general objectives).
    Bfgs,
    /// Exact Hessian of the Lagrangian: Gauss–Newton of the least-squares objective plus
    /// the exact curvature of the objective (`2Σ rᵢ∇²rᵢ`), of the constraint terms and of
    /// the intervals (second-order sensitivities). Multiple-shooting Hessians are
    /// indefinite; [`ExactConvexification`] says how the QP is kept convex. Elastic QPs
    /// use the Hessian with each node block projected onto the PSD cone instead.
    Exact,
    /// Gauss–Newton for the least-squares objective plus a block-diagonal BFGS
    /// approximation of the constraint curvature `∇²(λᵀc)` (structured quasi-Newton):
    /// exact where the objective is quadratic, superlinear where the dynamics bend.
    GaussNewtonBfgs,
}

/// How [`HessianMode::Exact`] turns the indefinite Hessian of the Lagrangian into a
/// QP Clarabel can solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExactConvexification {
    /// Add `ρ JₑᵀJₑ` of the equality rows (ρ = max|H|; constant on `Jₑd = −c`, so the
    /// step is unchanged) and remove its effect `ρ Jₑd` from the equality multipliers.
    /// Measured: biped 8–9 iterations, cart-pole 24; on the gait tracking problem the
    /// multipliers corrected this way grow without bound once ρ must be large.
    Augmented,
    /// Inertia correction: variables held at a bound get a diagonal, and `h + δI` with
    /// the smallest δ for which the Hessian is convex on the null space of the equality
    /// and active rows (tested by a sparse LDLᵀ of the augmented matrix); the QP gets no
    /// ρ term, so its multipliers are the Lagrangian's. Measured: converges the gait
    /// tracking problems; the cart-pole needs δ > 0 near its solution and stalls.
    InertiaCorrection,
}

/// SQP settings.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SqpSettings {
    /// KKT tolerance (default: 1e-5).
    pub tol_kkt: f64,
    /// Iteration limit (default: 200).
    pub max_iter: usize,
    /// Wall-time limit in seconds (default: none).
    pub max_time: Option<f64>,
    /// Hessian approximation (default: gauss_newton).
    pub hessian: HessianMode,
    /// Armijo constant of the line search (default: 1e-4).
    pub line_search_armijo: f64,
    /// Smallest step length before the line search fails (default: 1e-10).
    pub line_search_min_step: f64,
    /// Diagonal regularisation added to the QP Hessian (default: 1e-9).
    pub regularization: f64,
    /// BFGS rule for non-convex steps (default: skip_nonconvex).
    pub bfgs_update: hessian::BfgsUpdate,
    /// Exact mode: use the constraint curvature only when the largest constraint violation
    /// is at most this (Gauss–Newton steps before; default: infinity, always).
    pub exact_hessian_below: f64,
    /// How the exact mode keeps its QPs convex (default: augmented).
    pub exact_convexification: ExactConvexification,
    /// Use the exact curvature of constraint terms that provide it (convexified per
    /// block) in the quasi-Newton modes (default: false; on the five-link biped it
    /// converged more slowly: J = 470.11354 vs 470.11126 after 150 iterations).
    pub exact_term_hessians: bool,
    /// Fault injection for tests: the QP solves (numbered from 0 over the whole solve,
    /// elastic and second-order-correction QPs included) that fail as if Clarabel had
    /// stopped with a numerical error, so that the recovery path can be shown to work.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub inject_qp_failures: Vec<usize>,
}

impl Default for SqpSettings {
    fn default() -> Self {
        Self {
            tol_kkt: 1e-5,
            max_iter: 200,
            max_time: None,
            hessian: HessianMode::GaussNewton,
            line_search_armijo: 1e-4,
            line_search_min_step: 1e-10,
            regularization: 1e-9,
            bfgs_update: hessian::BfgsUpdate::SkipNonconvex,
            exact_term_hessians: false,
            exact_hessian_below: f64::INFINITY,
            exact_convexification: ExactConvexification::Augmented,
            inject_qp_failures: Vec::new(),
        }
    }
}

/// Why the SQP stopped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SqpStatus {
    /// KKT residual below tolerance.
    Converged,
    /// Iteration limit.
    MaxIterations,
    /// Time limit.
    MaxTime,
    /// No acceptable step along the search direction.
    LineSearchFailure,
    /// The QP solver failed.
    QpFailure(String),
    /// The constraints cannot be satisfied: a stationary point of the violation with
    /// positive violation was reached.
    Infeasible,
    /// A function evaluation failed at the initial point or repeatedly.
    EvaluationFailure(String),
    /// Stopped by the caller's callback (e.g. Ctrl-C).
    Interrupted,
}

impl std::fmt::Display for SqpStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SqpStatus::Converged => write!(f, "converged (KKT tolerance reached)"),
            SqpStatus::MaxIterations => write!(f, "iteration limit reached"),
            SqpStatus::MaxTime => write!(f, "time limit reached"),
            SqpStatus::LineSearchFailure => write!(f, "line search failed"),
            SqpStatus::QpFailure(s) => write!(f, "QP subproblem failed: {s}"),
            SqpStatus::Infeasible => write!(f, "infeasible: the constraints cannot be satisfied"),
            SqpStatus::EvaluationFailure(s) => write!(f, "evaluation failed: {s}"),
            SqpStatus::Interrupted => write!(f, "interrupted"),
        }
    }
}

/// One iteration's figures.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct IterationRecord {
    /// Iteration number (0 = initial point).
    pub iter: usize,
    /// Objective.
    pub objective: f64,
    /// Largest constraint violation.
    pub infeasibility: f64,
    /// KKT residual at this point.
    pub kkt: f64,
    /// Accepted step length (0 at the last record).
    pub step: f64,
    /// Elapsed seconds.
    pub seconds: f64,
    /// QP solver iterations.
    pub qp_iterations: u32,
}

/// A violated constraint at the final point.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Violation {
    /// Row name.
    pub name: String,
    /// Amount of violation.
    pub amount: f64,
}

/// Where the time of a solve went.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
pub struct SqpTimings {
    /// Seconds in NLP evaluations (integration, sensitivities, Hessians).
    pub evaluation_s: f64,
    /// Number of NLP evaluations.
    pub evaluations: usize,
    /// Seconds in QP solves (assembly and Clarabel).
    pub qp_s: f64,
    /// Number of QP solves (including elastic and second-order-correction QPs).
    pub qp_solves: usize,
}

/// Two solves' time splits added up (a solve continued from where another stopped).
impl std::ops::AddAssign for SqpTimings {
    fn add_assign(&mut self, other: Self) {
        self.evaluation_s += other.evaluation_s;
        self.evaluations += other.evaluations;
        self.qp_s += other.qp_s;
        self.qp_solves += other.qp_solves;
    }
}

/// Result of a solve.
#[derive(Debug, Clone, Serialize)]
pub struct SqpResult {
    /// Final variables.
    pub w: Vec<f64>,
    /// Constraint multipliers.
    pub lambda: Vec<f64>,
    /// Bound multipliers.
    pub nu: Vec<f64>,
    /// Objective.
    pub objective: f64,
    /// Largest constraint violation.
    pub infeasibility: f64,
    /// KKT residual.
    pub kkt: f64,
    /// Stop reason.
    pub status: SqpStatus,
    /// Iteration history.
    pub history: Vec<IterationRecord>,
    /// The most violated constraints (up to 10), largest first.
    pub most_violated: Vec<Violation>,
    /// Wall time (s).
    pub seconds: f64,
    /// Time split.
    pub timings: SqpTimings,
}

/// Receives iteration records; return `false` to stop.
pub trait Observer {
    /// Called after every iteration.
    fn iteration(&mut self, rec: &IterationRecord) -> bool;
    /// Whether [`checkpoint`](Self::checkpoint) should be called (building a checkpoint
    /// copies the iterate and the history).
    fn wants_checkpoints(&self) -> bool {
        false
    }
    /// Called after every accepted step with the state a solve can continue from
    /// ([`solve_resumed`]), e.g. to write it to disk.
    fn checkpoint(&mut self, _state: &SqpCheckpoint) {}
}

/// An observer that prints one line per iteration to stderr.
pub struct StderrLog;

impl Observer for StderrLog {
    fn iteration(&mut self, r: &IterationRecord) -> bool {
        if r.iter == 0 {
            eprintln!(
                "{:>5} {:>16} {:>10} {:>10} {:>8} {:>8}",
                "iter", "objective", "infeas", "kkt", "step", "seconds"
            );
        }
        eprintln!(
            "{:>5} {:>16.9e} {:>10.3e} {:>10.3e} {:>8.2e} {:>8.2}",
            r.iter, r.objective, r.infeasibility, r.kkt, r.step, r.seconds
        );
        true
    }
}

/// An observer that does nothing.
pub struct Silent;
impl Observer for Silent {
    fn iteration(&mut self, _: &IterationRecord) -> bool {
        true
    }
}

/// Violation of each constraint value `c` of its bounds `[lb, ub]` (0 when satisfied).
pub fn violations(c: &[f64], lb: &[f64], ub: &[f64]) -> Vec<f64> {
    c.iter()
        .zip(lb.iter().zip(ub))
        .map(|(&v, (&l, &u))| (l - v).max(v - u).max(0.0))
        .collect()
}

struct State {
    w: Vec<f64>,
    ev: NlpEval,
    /// Exact constraint curvature at `w` (Exact mode).
    hess: Option<Triplets>,
    /// Objective and l1 violation from a plain evaluation at `w`: the line search compares
    /// trial points (plain evaluations) with these, so that integrator noise, which differs
    /// between runs with and without sensitivity error control, cannot mislead it.
    plain: (f64, f64),
}

/// Solve `nlp` from `w0` (clipped into the bounds).
pub fn solve(
    nlp: &dyn Nlp,
    w0: &[f64],
    settings: &SqpSettings,
    observer: &mut dyn Observer,
) -> SqpResult {
    solve_impl(nlp, w0, settings, observer, None)
}

/// Continue a solve of `nlp` from a checkpoint its observer received: with the same
/// settings it follows the same iterates, bit for bit, as the solve that wrote it, and
/// its result holds the whole history. The checkpoint must pass
/// [`SqpCheckpoint::check`] for this NLP (a mismatch is an evaluation failure).
pub fn solve_resumed(
    nlp: &dyn Nlp,
    from: &SqpCheckpoint,
    settings: &SqpSettings,
    observer: &mut dyn Observer,
) -> SqpResult {
    solve_impl(nlp, &from.w.values(), settings, observer, Some(from))
}

fn solve_impl(
    nlp: &dyn Nlp,
    w0: &[f64],
    settings: &SqpSettings,
    observer: &mut dyn Observer,
    resume: Option<&SqpCheckpoint>,
) -> SqpResult {
    let elapsed_before =
        resume.map_or(0.0, |cp| cp.scalars.values().get(5).copied().unwrap_or(0.0));
    let start = Instant::now()
        .checked_sub(std::time::Duration::from_secs_f64(elapsed_before.max(0.0)))
        .unwrap_or_else(Instant::now);
    let (n, m) = (nlp.n(), nlp.m());
    let (w_lb, w_ub, c_lb, c_ub) = nlp.bounds();
    let (jr, jc) = nlp.jacobian_pattern();
    let elastic_weights = nlp.elastic_weights();
    let exact_rows = if settings.exact_term_hessians {
        nlp.rows_with_exact_hessian()
    } else {
        vec![false; m]
    };
    let any_exact = exact_rows.iter().any(|&r| r);
    let (hr, hc) = nlp.gauss_newton_pattern();
    let mut bfgs = BlockBfgs::new(nlp.hessian_blocks(), settings.bfgs_update);
    if settings.hessian == HessianMode::GaussNewtonBfgs {
        bfgs.scale(1e-4);
    }
    let w: Vec<f64> = w0
        .iter()
        .zip(w_lb.iter().zip(&w_ub))
        .map(|(&v, (&l, &u))| v.max(l).min(u))
        .collect();
    let fail = |status: SqpStatus, w: Vec<f64>| SqpResult {
        lambda: vec![0.0; m],
        nu: vec![0.0; n],
        objective: f64::NAN,
        infeasibility: f64::NAN,
        kkt: f64::NAN,
        status,
        history: Vec::new(),
        most_violated: Vec::new(),
        seconds: start.elapsed().as_secs_f64(),
        timings: SqpTimings::default(),
        w,
    };
    if let Some(cp) = resume {
        if let Err(e) = cp.check(n, m) {
            return fail(SqpStatus::EvaluationFailure(e.to_string()), w);
        }
        if !bfgs.restore(cp.bfgs.iter().map(|(b, s)| (b.values(), *s)).collect()) {
            return fail(
                SqpStatus::EvaluationFailure(
                    "the checkpoint's BFGS blocks do not fit this problem".into(),
                ),
                w,
            );
        }
    }
    let timings = std::cell::Cell::new(resume.map_or_else(SqpTimings::default, |cp| cp.timings));
    let timed = |eval: bool, f: &mut dyn FnMut()| {
        let t = Instant::now();
        f();
        let mut tm = timings.get();
        if eval {
            tm.evaluation_s += t.elapsed().as_secs_f64();
            tm.evaluations += 1;
        } else {
            tm.qp_s += t.elapsed().as_secs_f64();
            tm.qp_solves += 1;
        }
        timings.set(tm);
    };
    let eval_plain = |w: &[f64]| {
        let mut r = Err(EvalError::fatal("not evaluated"));
        timed(true, &mut || r = nlp.evaluate(w, false));
        r
    };
    let solve_qp = |d: &QpData<'_>| {
        let mut r = Err(QpError::Failed(String::new()));
        if settings
            .inject_qp_failures
            .contains(&timings.get().qp_solves)
        {
            timed(false, &mut || {
                r = Err(QpError::Failed("NumericalError (injected)".into()))
            });
            return r;
        }
        timed(false, &mut || r = qp::solve(d));
        r
    };
    let exact = settings.hessian == HessianMode::Exact;
    // derivatives at a point; in Exact mode with the curvature for multipliers `lam`
    let eval_derivs = |w: &[f64], lam: &[f64]| -> Result<(NlpEval, Option<Triplets>), EvalError> {
        let mut out = Err(EvalError::fatal("not evaluated"));
        timed(true, &mut || {
            out = if exact {
                nlp.evaluate_with_hessian(w, lam).map(|(ev, (r, c, v))| {
                    (
                        ev,
                        Some(Triplets {
                            rows: r,
                            cols: c,
                            vals: v,
                        }),
                    )
                })
            } else {
                nlp.evaluate(w, true).map(|ev| (ev, None))
            }
        });
        out
    };
    let lambda0 = resume.map_or_else(|| vec![0.0; m], |cp| cp.lambda.values());
    let (ev, hess) = match eval_derivs(&w, &lambda0) {
        Ok(r) => r,
        Err(e) => return fail(SqpStatus::EvaluationFailure(e.chain()), w),
    };
    let plain = match eval_plain(&w) {
        Ok(p) => (p.f, violations(&p.c, &c_lb, &c_ub).iter().sum::<f64>()),
        Err(e) => return fail(SqpStatus::EvaluationFailure(e.chain()), w),
    };
    let mut st = State { w, ev, hess, plain };
    let mut zero_blocks = BlockBfgs::new(nlp.hessian_blocks(), settings.bfgs_update);
    // ρ of the exact mode's augmentation or convexity test is test_rho_scale · max|H|
    // (raised when a QP fails)
    let mut test_rho_scale: f64 = 1.0;
    // inertia-correction shift of the exact mode's QP Hessian (last value)
    let mut shift: f64 = 0.0;
    zero_blocks.scale(0.0);
    let mut lambda = lambda0;
    let mut nu = vec![0.0; n];
    // size of the multipliers of the last consistent QP: the elastic penalty exceeds it
    let mut lam_est: f64 = 1.0;
    let mut filter: Vec<(f64, f64)> = Vec::new();
    let mut theta_max = f64::INFINITY;
    let mut history = Vec::new();
    let mut status = SqpStatus::MaxIterations;
    let mut kkt = f64::INFINITY;
    let mut last_step = 0.0;
    let mut qp_iters;
    let mut first_iter = 0;
    if let Some(cp) = resume {
        nu = cp.nu.values();
        let sc = cp.scalars.values();
        (lam_est, test_rho_scale, shift, theta_max, last_step) =
            (sc[0], sc[1], sc[2], sc[3], sc[4]);
        filter = cp
            .filter
            .values()
            .chunks_exact(2)
            .map(|p| (p[0], p[1]))
            .collect();
        history = cp.records();
        first_iter = cp.next_iter;
    }
    let jt = |vals: &[f64]| Triplets {
        rows: jr.clone(),
        cols: jc.clone(),
        vals: vals.to_vec(),
    };
    for iter in first_iter..=settings.max_iter {
        // --- QP subproblem at the current point
        let infeas0 = violations(&st.ev.c, &c_lb, &c_ub)
            .iter()
            .copied()
            .fold(0.0, f64::max);
        let mut h = Triplets::default();
        let mut h_elastic: Option<Triplets> = None;
        // augmentation ρ of the exact mode's QP (ExactConvexification::Augmented)
        let mut aug_rho = 0.0;
        let mut eq_rows: Vec<Vec<(usize, f64)>> = Vec::new();
        match settings.hessian {
            HessianMode::GaussNewton => {
                h.rows.clone_from(&hr);
                h.cols.clone_from(&hc);
                h.vals.clone_from(&st.ev.gn);
            }
            HessianMode::Bfgs if !any_exact => bfgs.push_upper(&mut h),
            HessianMode::Bfgs => {}
            HessianMode::Exact => {
                let mut ex = Triplets {
                    rows: hr.clone(),
                    cols: hc.clone(),
                    vals: st.ev.gn.clone(),
                };
                // far from feasibility the multipliers (and so the curvature) are unreliable:
                // use the curvature only once the violation is below `exact_hessian_below`
                let use_curvature = infeas0 <= settings.exact_hessian_below && st.hess.is_some();
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
                    aug_rho = test_rho_scale * hmax;
                    eq_rows = sparse_rows(m, &jr, &jc, &st.ev.jac, |i| c_lb[i] == c_ub[i]);
                    ex.extend_scaled(&row_gram(&eq_rows), aug_rho);
                } else if use_curvature {
                    shift = exact_qp_hessian(
                        &mut ex,
                        &ExactQpContext {
                            n,
                            w: &st.w,
                            w_lb: &w_lb,
                            w_ub: &w_ub,
                            nu: &nu,
                            c: &st.ev.c,
                            c_lb: &c_lb,
                            c_ub: &c_ub,
                            lambda: &lambda,
                            jac_rows: &jr,
                            jac_cols: &jc,
                            jac: &st.ev.jac,
                            test_rho_scale,
                            previous_shift: shift,
                        },
                    );
                }
                h = ex;
            }
            HessianMode::GaussNewtonBfgs => {
                h.rows.clone_from(&hr);
                h.cols.clone_from(&hc);
                h.vals.clone_from(&st.ev.gn);
                if !any_exact {
                    bfgs.push_upper(&mut h);
                }
            }
        }
        if any_exact
            && matches!(
                settings.hessian,
                HessianMode::Bfgs | HessianMode::GaussNewtonBfgs
            )
        {
            match nlp.exact_hessian(&st.w, &lambda) {
                Ok((r, c, v)) => {
                    let mut ex = Triplets {
                        rows: r,
                        cols: c,
                        vals: v,
                    };
                    bfgs.convexify_into(&mut ex, &mut h);
                }
                Err(e) => {
                    status = SqpStatus::EvaluationFailure(e.chain());
                    break;
                }
            }
        }
        for i in 0..n {
            h.push(i, i, settings.regularization);
        }
        let jac = jt(&st.ev.jac);
        let d_lb: Vec<f64> = (0..n).map(|i| w_lb[i] - st.w[i]).collect();
        let d_ub: Vec<f64> = (0..n).map(|i| w_ub[i] - st.w[i]).collect();
        let viol = violations(&st.ev.c, &c_lb, &c_ub);
        let infeas = viol.iter().copied().fold(0.0, f64::max);
        let data = |elastic: Option<f64>| QpData {
            h: if elastic.is_some() {
                h_elastic.as_ref().unwrap_or(&h)
            } else {
                &h
            },
            g: &st.ev.grad,
            jac: &jac,
            c: &st.ev.c,
            c_lb: &c_lb,
            c_ub: &c_ub,
            d_lb: &d_lb,
            d_ub: &d_ub,
            elastic,
            elastic_weights: &elastic_weights,
        };
        let rho = (10.0 * lam_est).clamp(1e3, 1e8);
        let mut first = solve_qp(&data(None));
        if let (Err(QpError::Failed(_)), Some(hc)) = (&first, h_elastic.as_ref()) {
            // exact mode: the QP was not solved with the exact curvature; test convexity
            // with a larger ρ from now on and solve this one with the block-convexified Hessian
            test_rho_scale *= 10.0;
            aug_rho = 0.0;
            first = solve_qp(&QpData {
                h: hc,
                ..data(None)
            });
        }
        let (sol, elastic) = match first {
            Ok(s) => (s, false),
            // inconsistent linearisation (or a stalled, nearly inconsistent one): elastic mode
            Err(QpError::Infeasible | QpError::Failed(_)) => match solve_qp(&data(Some(rho))) {
                Ok(s) => (s, true),
                Err(e) => {
                    // the interior-point solver lost accuracy on this QP: a proximal shift
                    // δI (growing) gives a better-conditioned QP with a shorter step
                    let hmax = h.vals.iter().fold(1.0f64, |m, v| m.max(v.abs()));
                    let mut rescued = None;
                    for delta in [1e-6, 1e-4, 1e-2, 1.0] {
                        let mut hs = h.clone();
                        for i in 0..n {
                            hs.push(i, i, delta * hmax);
                        }
                        if let Ok(s) = solve_qp(&QpData {
                            h: &hs,
                            ..data(None)
                        }) {
                            rescued = Some(s);
                            break;
                        }
                    }
                    match rescued {
                        Some(s) => (s, false),
                        None => {
                            status = SqpStatus::QpFailure(e.to_string());
                            break;
                        }
                    }
                }
            },
        };
        let mut sol = sol;
        if aug_rho > 0.0 && !elastic {
            // ρ JₑᵀJₑ moves the QP's equality multipliers by −ρ·(Jₑ d)
            for (i, row) in eq_rows.iter().enumerate() {
                sol.lambda[i] += aug_rho * row.iter().map(|&(c, v)| v * sol.d[c]).sum::<f64>();
            }
        }
        qp_iters = sol.iterations;
        if !elastic {
            lam_est = sol.lambda.iter().map(|v| v.abs()).fold(1.0, f64::max);
        }
        // --- KKT residual at the current point with the QP multipliers
        let mut stat = st.ev.grad.clone();
        for k in 0..jr.len() {
            stat[jc[k]] += st.ev.jac[k] * sol.lambda[jr[k]];
        }
        for i in 0..n {
            stat[i] += sol.nu[i];
        }
        let mult_l1: f64 = sol.lambda.iter().chain(&sol.nu).map(|v| v.abs()).sum();
        let sd = (mult_l1 / ((m + n) as f64 * 100.0)).max(1.0);
        let stat_inf = stat.iter().map(|v| v.abs()).fold(0.0, f64::max) / sd;
        let compl = (0..m)
            .map(|i| {
                let (c, l, u) = (st.ev.c[i], c_lb[i], c_ub[i]);
                if l == u {
                    0.0
                } else if sol.lambda[i] > 0.0 {
                    (sol.lambda[i] * (u - c)).abs()
                } else {
                    (sol.lambda[i] * (c - l)).abs()
                }
            })
            .fold(0.0, f64::max);
        kkt = stat_inf.max(infeas).max(compl / sd);
        let rec = IterationRecord {
            iter,
            objective: st.ev.f,
            infeasibility: infeas,
            kkt,
            step: last_step,
            seconds: start.elapsed().as_secs_f64(),
            qp_iterations: qp_iters,
        };
        let go_on = observer.iteration(&rec);
        history.push(rec);
        lambda.clone_from(&sol.lambda);
        nu.clone_from(&sol.nu);
        if kkt <= settings.tol_kkt && !elastic {
            status = SqpStatus::Converged;
            break;
        }
        if !go_on {
            status = SqpStatus::Interrupted;
            break;
        }
        if iter == settings.max_iter {
            status = SqpStatus::MaxIterations;
            break;
        }
        if settings
            .max_time
            .is_some_and(|t| start.elapsed().as_secs_f64() > t)
        {
            status = SqpStatus::MaxTime;
            break;
        }
        let dnorm = sol.d.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let wnorm = st.w.iter().map(|v| v.abs()).fold(1.0, f64::max);
        if elastic && dnorm <= 1e-10 * wnorm && infeas > settings.tol_kkt {
            status = SqpStatus::Infeasible;
            break;
        }
        // --- filter line search (Wächter & Biegler 2006): accept a trial point that
        // sufficiently reduces the objective (when the step is a descent direction and
        // the infeasibility is small) or the infeasibility, and is not dominated by the
        // filter of earlier (infeasibility, objective) pairs
        let grad_d: f64 = st.ev.grad.iter().zip(&sol.d).map(|(a, b)| a * b).sum();
        let theta0 = st.plain.1;
        if filter.is_empty() {
            theta_max = (1e4f64).max(1.2 * theta0);
            filter.push((theta_max, f64::NEG_INFINITY));
        }
        let (gamma_t, gamma_f, eta, delta, s_t, s_f) =
            (1e-5, 1e-5, settings.line_search_armijo, 1.0, 1.1, 2.3);
        let f0 = st.plain.0;
        let acceptable = |ev: &NlpEval, a: f64, filter: &[(f64, f64)]| -> Option<bool> {
            let th = violations(&ev.c, &c_lb, &c_ub).iter().sum::<f64>();
            if !ev.f.is_finite() || !th.is_finite() || th > theta_max {
                return None;
            }
            if filter.iter().any(|&(ft, ff)| th >= ft && ev.f >= ff) {
                return None;
            }
            let switching = grad_d < 0.0 && a * (-grad_d).powf(s_f) > delta * theta0.powf(s_t);
            if switching && theta0 <= 1e-4 * theta_max.max(1.0) {
                // f-type step: Armijo on the objective, the filter is not augmented
                (ev.f <= f0 + eta * a * grad_d).then_some(false)
            } else if th <= (1.0 - gamma_t) * theta0 || ev.f <= f0 - gamma_f * theta0 {
                Some(true)
            } else {
                None
            }
        };
        let trial = |a: f64, dir: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| (st.w[i] + a * dir[i]).max(w_lb[i]).min(w_ub[i]))
                .collect()
        };
        // trial points are evaluated without derivatives (a plain sweep); derivatives and
        // curvature are computed once, at the accepted point
        let mut alpha = 1.0;
        let mut found: Option<(Vec<f64>, bool, (f64, f64))> = None;
        let summary = |ev: &NlpEval| (ev.f, violations(&ev.c, &c_lb, &c_ub).iter().sum::<f64>());
        // a recoverable failure at a trial point shortens the step; a fatal one stops
        let mut fatal: Option<EvalError> = None;
        let w1 = trial(1.0, &sol.d);
        match eval_plain(&w1) {
            Ok(ev1) => match acceptable(&ev1, 1.0, &filter) {
                Some(aug) => found = Some((w1, aug, summary(&ev1))),
                None => {
                    // second-order correction: re-solve with the constraint values at w + d
                    let mut jd = vec![0.0; m];
                    for k in 0..jr.len() {
                        jd[jr[k]] += st.ev.jac[k] * sol.d[jc[k]];
                    }
                    let c_soc: Vec<f64> = (0..m).map(|i| ev1.c[i] - jd[i]).collect();
                    let soc = QpData {
                        c: &c_soc,
                        ..data(None)
                    };
                    if let Ok(s2) = solve_qp(&soc) {
                        let w2 = trial(1.0, &s2.d);
                        match eval_plain(&w2) {
                            Ok(ev2) => {
                                if let Some(aug) = acceptable(&ev2, 1.0, &filter) {
                                    found = Some((w2, aug, summary(&ev2)));
                                }
                            }
                            Err(e) => keep_fatal(&mut fatal, e),
                        }
                    }
                    alpha = 0.5;
                }
            },
            Err(e) => {
                keep_fatal(&mut fatal, e);
                alpha = 0.5;
            }
        }
        while found.is_none() && fatal.is_none() && alpha >= settings.line_search_min_step {
            let wa = trial(alpha, &sol.d);
            match eval_plain(&wa) {
                Ok(eva) => {
                    if let Some(aug) = acceptable(&eva, alpha, &filter) {
                        found = Some((wa, aug, summary(&eva)));
                        break;
                    }
                }
                Err(e) => keep_fatal(&mut fatal, e),
            }
            alpha *= 0.5;
        }
        if let Some(e) = fatal {
            status = SqpStatus::EvaluationFailure(e.chain());
            break;
        }
        let mut accepted: Option<(Vec<f64>, NlpEval, Option<Triplets>, bool)> = None;
        let mut plain_new = (0.0, 0.0);
        if let Some((wa, aug, pl)) = found {
            plain_new = pl;
            match eval_derivs(&wa, &sol.lambda) {
                Ok((ev, hw)) => accepted = Some((wa, ev, hw, aug)),
                Err(e) => status = SqpStatus::EvaluationFailure(e.chain()),
            }
        }
        let accepted = accepted.map(|(w, ev, hw, aug)| {
            if aug {
                filter.push(((1.0 - gamma_t) * theta0, f0 - gamma_f * theta0));
            }
            (w, ev, hw)
        });
        let Some((w_new, ev_new, hess_new)) = accepted else {
            if !matches!(status, SqpStatus::EvaluationFailure(_)) {
                status = if elastic {
                    SqpStatus::Infeasible
                } else {
                    SqpStatus::LineSearchFailure
                };
            }
            break;
        };
        last_step = alpha;
        // --- quasi-Newton update with the new multipliers
        if settings.hessian == HessianMode::Bfgs || settings.hessian == HessianMode::GaussNewtonBfgs
        {
            // full Lagrangian gradient for BFGS, constraint part only for the structured mode
            let structured = settings.hessian == HessianMode::GaussNewtonBfgs;
            let mut gl_new = if structured {
                vec![0.0; n]
            } else {
                ev_new.grad.clone()
            };
            let mut gl_old = if structured {
                vec![0.0; n]
            } else {
                st.ev.grad.clone()
            };
            for k in 0..jr.len() {
                if exact_rows[jr[k]] {
                    continue;
                }
                gl_new[jc[k]] += ev_new.jac[k] * sol.lambda[jr[k]];
                gl_old[jc[k]] += st.ev.jac[k] * sol.lambda[jr[k]];
            }
            let s: Vec<f64> = (0..n).map(|i| w_new[i] - st.w[i]).collect();
            let y: Vec<f64> = (0..n).map(|i| gl_new[i] - gl_old[i]).collect();
            bfgs.update(&s, &y);
        }
        st = State {
            w: w_new,
            ev: ev_new,
            hess: hess_new,
            plain: plain_new,
        };
        if observer.wants_checkpoints() {
            observer.checkpoint(&SqpCheckpoint {
                version: CHECKPOINT_VERSION,
                n,
                m,
                next_iter: iter + 1,
                w: ExactVec::new(&st.w),
                lambda: ExactVec::new(&lambda),
                nu: ExactVec::new(&nu),
                scalars: ExactVec::new(&[
                    lam_est,
                    test_rho_scale,
                    shift,
                    theta_max,
                    last_step,
                    start.elapsed().as_secs_f64(),
                ]),
                filter: ExactVec::new(
                    &filter
                        .iter()
                        .flat_map(|&(a, b)| [a, b])
                        .collect::<Vec<f64>>(),
                ),
                bfgs: bfgs
                    .state()
                    .into_iter()
                    .map(|(b, s)| (ExactVec::new(&b), s))
                    .collect(),
                history: history.iter().map(ExactRecord::from).collect(),
                timings: timings.get(),
            });
        }
    }
    let viol = violations(&st.ev.c, &c_lb, &c_ub);
    let mut order: Vec<usize> = (0..m).filter(|&i| viol[i] > settings.tol_kkt).collect();
    order.sort_by(|&a, &b| viol[b].total_cmp(&viol[a]));
    let most_violated = order
        .iter()
        .take(10)
        .map(|&i| Violation {
            name: nlp.row_name(i),
            amount: viol[i],
        })
        .collect();
    SqpResult {
        objective: st.ev.f,
        infeasibility: viol.iter().copied().fold(0.0, f64::max),
        kkt,
        status,
        history,
        most_violated,
        seconds: start.elapsed().as_secs_f64(),
        timings: timings.get(),
        w: st.w,
        lambda,
        nu,
    }
}

/// What [`exact_qp_hessian`] needs to know about the current iterate.
struct ExactQpContext<'a> {
    n: usize,
    w: &'a [f64],
    w_lb: &'a [f64],
    w_ub: &'a [f64],
    /// Bound multipliers of the last QP.
    nu: &'a [f64],
    c: &'a [f64],
    c_lb: &'a [f64],
    c_ub: &'a [f64],
    /// Constraint multipliers of the last QP.
    lambda: &'a [f64],
    jac_rows: &'a [usize],
    jac_cols: &'a [usize],
    jac: &'a [f64],
    test_rho_scale: f64,
    previous_shift: f64,
}

/// Make the exact Hessian of the Lagrangian `h` usable in a convex QP without changing
/// the Newton step where that is possible; returns the shift δ applied.
///
/// Multiple-shooting Hessians are indefinite; what matters is the curvature on the
/// directions the linearised active constraints leave free. (1) Variables held at a bound
/// (at it, with a bound multiplier in the last QP) get a diagonal of the Hessian's size,
/// which costs nothing while they stay there. (2) Convexity on the null space of the
/// equalities and active inequalities is tested by a sparse LDLᵀ of `h + ρ Σ J_iᵀJ_i` over
/// those rows for ρ = (1, 10², 10⁴) · max|h| (Finsler: positive definite for some ρ iff the
/// reduced Hessian is); where it fails, δI is added, δ the smallest of a geometric
/// sequence that passes (the inertia correction of Wächter & Biegler 2006, §3.1). The QP
/// itself gets `h + δI` without the ρ term, so its multipliers are the Lagrangian's.
fn exact_qp_hessian(h: &mut Triplets, cx: &ExactQpContext<'_>) -> f64 {
    let n = cx.n;
    let hmax = h.vals.iter().map(|v| v.abs()).fold(1.0, f64::max);
    for i in 0..n {
        let tol = 1e-9 * (1.0 + cx.w[i].abs());
        if (cx.w[i] - cx.w_lb[i] <= tol || cx.w_ub[i] - cx.w[i] <= tol) && cx.nu[i] != 0.0 {
            h.push(i, i, hmax);
        }
    }
    // the rows of the test: equalities and inequalities active in the last QP
    let lam_max = cx.lambda.iter().fold(1.0f64, |a, v| a.max(v.abs()));
    let tested: Vec<bool> = (0..cx.c.len())
        .map(|i| {
            let tol = 1e-6 * (1.0 + cx.c[i].abs());
            let active = (cx.c[i] - cx.c_lb[i]).abs() <= tol || (cx.c_ub[i] - cx.c[i]).abs() <= tol;
            cx.c_lb[i] == cx.c_ub[i] || (active && cx.lambda[i].abs() > 1e-8 * lam_max)
        })
        .collect();
    let jtj = row_gram(&sparse_rows(
        cx.c.len(),
        cx.jac_rows,
        cx.jac_cols,
        cx.jac,
        |i| tested[i],
    ));
    let mut best: Option<f64> = None;
    let mut test = hessian::ConvexityTest::new(n, h, &jtj);
    for f in [1.0, 1e2, 1e4] {
        let rho = cx.test_rho_scale * hmax * f;
        if let Some(d) = test.shift(rho, cx.previous_shift, 1e-12 * hmax, 1e2 * hmax) {
            if best.is_none_or(|b| d < b) {
                best = Some(d);
            }
            if d == 0.0 {
                break;
            }
        }
    }
    let delta = best.unwrap_or(1e2 * hmax);
    if delta > 0.0 {
        for i in 0..n {
            h.push(i, i, delta);
        }
    }
    delta
}

/// The rows `i` of a sparse Jacobian (triplets in pattern order) with `keep(i)`, each as
/// `(column, value)` pairs; the other rows empty.
fn sparse_rows(
    m: usize,
    rows: &[usize],
    cols: &[usize],
    vals: &[f64],
    keep: impl Fn(usize) -> bool,
) -> Vec<Vec<(usize, f64)>> {
    let mut out: Vec<Vec<(usize, f64)>> = vec![Vec::new(); m];
    for k in 0..rows.len() {
        if keep(rows[k]) {
            out[rows[k]].push((cols[k], vals[k]));
        }
    }
    out
}

/// `Σ_i J_iᵀJ_i` over the given sparse rows, as upper-triangle triplets.
fn row_gram(rows: &[Vec<(usize, f64)>]) -> Triplets {
    let mut t = Triplets::default();
    for row in rows {
        for a in 0..row.len() {
            for b in a..row.len() {
                let ((ca, va), (cb, vb)) = (row[a], row[b]);
                let v = if ca == cb && a != b {
                    2.0 * va * vb
                } else {
                    va * vb
                };
                t.push(ca.min(cb), ca.max(cb), v);
            }
        }
    }
    t
}
