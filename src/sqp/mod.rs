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

//!
//! One home per concept: `driver` (the iteration), `step` (the QP subproblem, elastic
//! mode and the rescue of a failed QP), `line_search` (the filter and the second-order
//! correction), `kkt` (the convergence test), `evaluator` (timed NLP and QP calls),
//! `iterate` (the NLP's structure and the current iterate, which these share), `qp` (the
//! QP subproblem's data and its solvers: Clarabel, and `qp::active_set` for a QP asked at
//! a solution, solved on its guessed active set).

pub mod checkpoint;
mod driver;
mod eval_error;
mod evaluator;
pub mod hessian;
mod iterate;
mod kkt;
mod line_search;
pub mod linearised;
pub mod qp;
mod step;

use checkpoint::SqpCheckpoint;
pub use eval_error::{Cause, EvalError};
use serde::{Deserialize, Serialize};

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
    /// Whether the exact curvature costs several evaluations (a stiff model's, integrated
    /// backward), so that the exact mode computes it only where a step uses it, not at
    /// every accepted point (default: false; the path then stays bit for bit what it was).
    fn curvature_on_demand(&self) -> bool {
        false
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
    /// The relative integrator tolerance the next evaluations use, when evaluating
    /// integrates (default: None, it does not).
    fn integration_tolerance(&self) -> Option<f64> {
        None
    }
    /// Integrate the next evaluations at relative tolerance `rtol`, never looser than the
    /// problem's own (default: nothing to change). The SQP tightens it as the KKT residual
    /// falls ([`SqpSettings::inexact_integration`]).
    fn set_integration_tolerance(&self, _rtol: f64) {}
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

/// When the exact mode's Gauss–Newton steps count as stalled
/// ([`SqpSettings::exact_hessian_on_stall`]): over `iterations` consecutive iterations, all
/// at a violation of at most `below`, the objective never fell below the lowest one of the
/// points before them with such a violation by more than `relative_decrease` of it. Once
/// stalled, the curvature stays in use.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StallSwitch {
    /// Largest constraint violation of the stalled iterations.
    pub below: f64,
    /// How many iterations without progress make a stall.
    pub iterations: usize,
    /// Progress: a decrease of the objective by more than this fraction of it.
    pub relative_decrease: f64,
}

impl StallSwitch {
    /// The first iteration (an index into `history`) after which the Gauss–Newton steps
    /// had stalled, if they had.
    pub fn stalled_at(&self, history: &[IterationRecord]) -> Option<usize> {
        let k = self.iterations.max(1);
        (k..history.len()).find(|&i| {
            let window = &history[i - k + 1..=i];
            // the best objective before the window among the points with a violation
            // within the bound (a cycle that dips and rises sets no new best)
            let best = history[..=i - k]
                .iter()
                .filter(|r| r.infeasibility <= self.below)
                .map(|r| r.objective)
                .reduce(f64::min);
            best.is_some_and(|best| {
                window.iter().all(|r| {
                    r.infeasibility <= self.below
                        && r.objective >= best - self.relative_decrease * best.abs()
                })
            })
        })
    }
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
    /// The inertia correction until its shifted steps stall ([`SHIFTED_STALL`] iterations
    /// in a row with a shift, near feasibility, without halving the smallest KKT residual
    /// before them), then, for the rest of the solve, the exact Hessian where it is convex
    /// on the null space of the equality and active rows (the same LDLᵀ test, δ = 0) and
    /// the Gauss–Newton Hessian of the least-squares objective where it is not. For
    /// tracking problems, whose objective is a sum of squares. Where a small shift makes
    /// the Hessian convex the shifted step is nearly Newton's and converges; where the
    /// constraints' curvature needs a large one, on directions the data barely determine,
    /// the shifted steps creep (on a second subject's recordings: δ of 1 to 300, the KKT
    /// residual near 1e-3 for hundreds of iterations, the objective falling in its seventh
    /// digit), and the Gauss–Newton steps cross that region.
    InertiaCorrectionThenGaussNewton,
}

/// Shifted exact steps in a row without progress that make
/// [`ExactConvexification::InertiaCorrectionThenGaussNewton`] switch.
pub const SHIFTED_STALL: usize = 10;

/// Whether the last [`SHIFTED_STALL`] iterations all took a shifted exact Hessian at a
/// violation of at most `below`, and none halved the smallest KKT residual before them.
pub fn shifted_steps_stalled(history: &[IterationRecord], below: f64) -> bool {
    let k = SHIFTED_STALL;
    if history.len() <= k {
        return false;
    }
    let (before, window) = history.split_at(history.len() - k);
    let best_before = before.iter().map(|r| r.kkt).fold(f64::INFINITY, f64::min);
    window.iter().all(|r| {
        r.hessian_shift.is_some_and(|d| d > 0.0)
            && r.infeasibility <= below
            && r.kkt > 0.5 * best_before
    })
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
    /// Exact mode: use the constraint curvature also above `exact_hessian_below`, from the
    /// iteration on where the Gauss–Newton steps stalled (None, the default: never). A
    /// volumetric foot's identification started at another problem's solution (violation
    /// 8e-9) crawled with the curvature from its first step (J 0.3151 → 0.2434 in 56
    /// iterations, far from converged), while its Gauss–Newton steps reached J 0.2165 in 14
    /// and then cycled at violations of 2e-3 to 1e-2, above any fixed switch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exact_hessian_on_stall: Option<StallSwitch>,
    /// Exact mode: once a step has used the constraint curvature, the next uses it too
    /// while the violation is at most this multiple of `exact_hessian_below` (default:
    /// 10). A full exact step near the switch can raise the violation just above it; a
    /// Gauss–Newton step in reply throws away the curvature's local convergence, and the
    /// steps alternate between the two Hessians.
    pub exact_hessian_hold: f64,
    /// How the exact mode keeps its QPs convex (default: augmented).
    pub exact_convexification: ExactConvexification,
    /// Use the exact curvature of constraint terms that provide it (convexified per
    /// block) in the quasi-Newton modes (default: false; on the five-link biped it
    /// converged more slowly: J = 470.11354 vs 470.11126 after 150 iterations).
    pub exact_term_hessians: bool,
    /// Inexact SQP: once the KKT residual is `r`, later evaluations integrate at relative
    /// tolerance `inexact_integration · r` when that is tighter than the current one (down
    /// to 1e-12; 0: never tightened). Integration error of the size of the tolerance makes
    /// the KKT residual itself noisy, and near an optimum that noise stalls the iterations
    /// (a ground-slope re-fit: 23 iterations at a fixed 1e-8, its KKT residual jumping
    /// between 1e-5 and 4e-4 for the last 14; 8 iterations at 1e-10, quadratically to
    /// 3.4e-7). Loose integration stays where the residual is large (default: 1e-5).
    pub inexact_integration: f64,
    /// Cap on the violation a line search accepts, as a multiple of the violation where the
    /// solve starts: θ_max = max(1, k·θ₀) (l1 norms) instead of max(10⁴, 1.2·θ₀) (None,
    /// the default). From a point near feasibility the loose cap lets a full step that
    /// lowers the objective leave the region where the linearised constraints hold: a
    /// prediction of the volumetric foot from its tracking solution (θ₀ = 0.11) took a
    /// first step to J = 0.048 and a violation of 12.9, lifted both feet off the ground
    /// (where the compliant contact has no force and no gradient) and ended infeasible;
    /// with k = 10 it backtracks and reaches a feasible point valid on the 1 ms grid.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub violation_growth: Option<f64>,
    /// Exact mode with the curvature on demand ([`Nlp::curvature_on_demand`]): at a
    /// point evaluated without the curvature where a step would use it, first solve the
    /// Gauss–Newton QP, and stop there if its multipliers show a KKT point (default:
    /// false). A KKT point is one whatever QP gave its multipliers; this saves the
    /// curvature, most of a compliant foot's evaluation (the gain trial at 600 Hz: 3.4 s
    /// of 4.5 s), where a solve starts at a kept solution of its own problem, as a
    /// diagnosis's clock-profile points do from an earlier diagnosis's (`diagnose
    /// --start`). Off where a solve is judged at a looser tolerance and then goes on to a
    /// tighter one (check-point rounds, `workflows::refine`): there the Gauss–Newton
    /// multipliers' residual often meets the loose tolerance and not the tight one (the
    /// gain trial's kept track: 2.9e-5 against the exact QP's 4.7e-6), and the solve then
    /// needs the curvature anyway.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub gauss_newton_check: bool,
    /// A KKT tolerance looser than `tol_kkt` at which the solve asks its observer
    /// ([`Observer::milestone`]) whether to go on (default: none). A solve whose solution
    /// is checked elsewhere (the check-point rounds, `workflows::refine`) ends there when
    /// the check adds constraints, and otherwise goes on in place to `tol_kkt`: a restart
    /// would transcribe and evaluate its start point again.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub milestone_tol: Option<f64>,
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
            exact_hessian_on_stall: None,
            exact_hessian_hold: 10.0,
            exact_convexification: ExactConvexification::Augmented,
            inexact_integration: 1e-5,
            violation_growth: None,
            gauss_newton_check: false,
            milestone_tol: None,
            inject_qp_failures: Vec::new(),
        }
    }
}

impl SqpSettings {
    /// The stopping rules a command takes within the ranges of [`crate::limits`]: the KKT
    /// tolerance, the iteration limit and the time limit. A KKT tolerance of 1e300 would
    /// call any start converged, however far it is from its constraints.
    pub fn check_limits(&self) -> Result<(), crate::limits::OutOfRange> {
        crate::limits::kkt_tolerance(self.tol_kkt)?;
        crate::limits::iteration_limit(self.max_iter)?;
        if let Some(t) = self.max_time {
            crate::limits::time_limit(t)?;
        }
        Ok(())
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

impl SqpStatus {
    /// The outcome in one of three words, without commas (the `status` column of a run's
    /// CSV files): `converged`, `interrupted` or `not converged`.
    pub fn outcome(&self) -> &'static str {
        match self {
            SqpStatus::Converged => "converged",
            SqpStatus::Interrupted => "interrupted",
            _ => "not converged",
        }
    }
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
    /// The relative integrator tolerance of the evaluations that follow this iteration
    /// (None: the NLP does not integrate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub integration_tol: Option<f64>,
    /// The shift δ added to the exact Hessian's diagonal to make the QP convex (inertia
    /// correction; 0 under the augmented convexification, which adds ρJₑᵀJₑ instead;
    /// None when the step did not use the exact curvature). A δ that stays above zero near
    /// the optimum turns Newton's quadratic convergence into a linear one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hessian_shift: Option<f64>,
    /// Which QP gave the step (None for records from before this field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub qp_route: Option<QpRoute>,
}

/// Which quadratic program gave an SQP step: the subproblem as built, or one of the
/// fall-backs when that could not be solved. Every fall-back but the elastic QP on an
/// inconsistent linearisation changes the curvature, so a solve that keeps using one
/// converges linearly at best.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum QpRoute {
    /// The subproblem's own QP.
    Direct,
    /// The exact-Hessian QP failed; its Hessian projected block by block onto the PSD cone.
    Convexified,
    /// The elastic QP (constraints relaxed with a penalty), with the convexified Hessian
    /// in the exact mode.
    Elastic,
    /// A proximal shift of the Hessian after the elastic QP failed too.
    Proximal,
}

impl QpRoute {
    /// A short word for logs.
    pub fn word(self) -> &'static str {
        match self {
            QpRoute::Direct => "qp",
            QpRoute::Convexified => "convex",
            QpRoute::Elastic => "elastic",
            QpRoute::Proximal => "proximal",
        }
    }
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

impl IterationRecord {
    /// The head of the iteration table whose rows are [`table_row`](Self::table_row).
    pub fn table_head() -> String {
        format!(
            "{:>5} {:>16} {:>10} {:>10} {:>8} {:>8} {:>8} {:>8}",
            "iter", "objective", "infeas", "kkt", "step", "seconds", "shift", "qp"
        )
    }

    /// This iteration as a row of the iteration table.
    pub fn table_row(&self) -> String {
        let shift = self
            .hessian_shift
            .map_or("-".to_string(), |d| format!("{d:.1e}"));
        let route = self.qp_route.map_or("-", QpRoute::word);
        format!(
            "{:>5} {:>16.9e} {:>10.3e} {:>10.3e} {:>8.2e} {:>8.2} {:>8} {:>8}",
            self.iter,
            self.objective,
            self.infeasibility,
            self.kkt,
            self.step,
            self.seconds,
            shift,
            route
        )
    }
}

impl SqpResult {
    /// `J = …, KKT …` with the objective to `digits` decimals, or, when the solve stopped
    /// before its start could be evaluated (no finite objective), says so instead of
    /// printing NaN.
    pub fn objective_and_kkt(&self, digits: usize) -> String {
        if self.evaluated() {
            format!("J = {:.digits$}, KKT {:.2e}", self.objective, self.kkt)
        } else {
            "J and KKT not evaluated (the start could not be evaluated)".to_string()
        }
    }

    /// `J = …` with the objective to `digits` decimals, or `J not evaluated` (as
    /// [`objective_and_kkt`](Self::objective_and_kkt), for a table's cell).
    pub fn objective_text(&self, digits: usize) -> String {
        if self.evaluated() {
            format!("J = {:.digits$}", self.objective)
        } else {
            "J not evaluated".to_string()
        }
    }

    /// Whether the solve evaluated its start: a finite objective and KKT residual.
    fn evaluated(&self) -> bool {
        self.objective.is_finite() && self.kkt.is_finite()
    }

    /// One result of two solves, `second` started where this one stopped: the second's
    /// point and status, the iteration history of both (the second's numbered on, without
    /// its repeated initial point), their times added up. A second solve that stopped
    /// before its start was evaluated (no history) leaves this one's point, values and
    /// history standing, with its own stop reason.
    pub fn followed_by(self, second: SqpResult) -> SqpResult {
        let mut timings = self.timings;
        timings += second.timings;
        let seconds = self.seconds + second.seconds;
        if second.history.is_empty() {
            return SqpResult {
                status: second.status,
                timings,
                seconds,
                ..self
            };
        }
        let (used, elapsed) = (self.history.len().saturating_sub(1), self.seconds);
        let mut history = self.history;
        history.extend(second.history.iter().skip(1).map(|r| IterationRecord {
            iter: r.iter + used,
            seconds: r.seconds + elapsed,
            ..r.clone()
        }));
        SqpResult {
            history,
            timings,
            seconds,
            ..second
        }
    }
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
    /// A turn in the solve worth telling the user (e.g. that the Gauss–Newton steps
    /// stalled and the exact Hessian took over), before the iteration it affects.
    fn note(&mut self, _text: &str) {}
    /// Called with the iterate at an iteration whose KKT residual is within
    /// [`SqpSettings::milestone_tol`] (at every such iteration until it returns `true`):
    /// whether the solve goes on to `tol_kkt`; `false` ends it there, converged at the
    /// milestone's tolerance.
    fn milestone(&mut self, _w: &[f64]) -> bool {
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

/// Solve `nlp` from `w0` (clipped into the bounds).
pub fn solve(
    nlp: &dyn Nlp,
    w0: &[f64],
    settings: &SqpSettings,
    observer: &mut dyn Observer,
) -> SqpResult {
    driver::run(nlp, w0, None, settings, observer, None)
}

/// Multipliers a solve of a problem starts from, e.g. those of the same problem solved
/// just before at a looser integrator tolerance. Either slice is ignored when its length
/// is not the problem's (or a value is not finite), and that part starts at zero.
#[derive(Clone, Copy, Debug)]
pub struct WarmStart<'a> {
    /// Constraint multipliers, one per constraint row: the first iteration's Hessian of
    /// the Lagrangian gets the constraints' curvature, not the objective's alone.
    pub lambda: &'a [f64],
    /// Bound multipliers, one per variable: a variable with a nonzero one that sits at
    /// its bound is held there by the first iteration's inertia correction, as by every
    /// later one, instead of counting as a free direction.
    pub nu: &'a [f64],
}

impl<'a> WarmStart<'a> {
    /// Constraint multipliers alone (the bound multipliers start at zero).
    pub fn constraints(lambda: &'a [f64]) -> Self {
        Self { lambda, nu: &[] }
    }
}

/// [`solve`] from the multipliers `warm`: the same problem solved again from its own
/// solution (a tighter tolerance) starts with its curvature and its active bounds, not
/// the objective's curvature alone.
pub fn solve_warm(
    nlp: &dyn Nlp,
    w0: &[f64],
    warm: WarmStart<'_>,
    settings: &SqpSettings,
    observer: &mut dyn Observer,
) -> SqpResult {
    driver::run(nlp, w0, Some(warm), settings, observer, None)
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
    driver::run(nlp, &from.w.values(), None, settings, observer, Some(from))
}
