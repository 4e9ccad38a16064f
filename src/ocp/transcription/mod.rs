//! Direct multiple-shooting transcription of an [`Ocp`] into a sparse NLP
//! $$\min_w f(w)\quad\text{s.t.}\quad c_{lb} \le c(w) \le c_{ub},\; w_{lb} \le w \le w_{ub}.$$
//!
//! Variables, per phase in node order: $s_{j,0}, u_{j,0}, s_{j,1}, u_{j,1}, \dots, s_{j,N_j}$
//! (and $u_{j,N_j}$ for linear controls), then the phase duration $T_j$; θ last.
//! Constraints: continuity $s_{j,k+1} - \Phi(h_j; s_{j,k}, u_{j,k}[, u_{j,k+1}], \theta) = 0$
//! with $h_j = T_j/N_j$, from CVODES with forward sensitivities (every interval in
//! parallel, deterministic whatever the thread count); phase transitions; user terms.
//! The Jacobian is kept sparse: a fixed pattern built once, values refilled per
//! evaluation.
//!
//! One home per concept: `layout` (variables, rows and sparsity patterns), `sweep` (the
//! shooting intervals' integration and their sample terms), `evaluate` (assembling the
//! values and first derivatives), `curvature` (exact second derivatives), `nlp` (the
//! [`Nlp`](crate::sqp::Nlp) the SQP solves).

mod curvature;
mod evaluate;
mod layout;
mod nlp;
mod sweep;

pub use sweep::shifted_instant;

use super::problem::{Block, Ocp};
use super::TermError;
use crate::integrate::{IntegrationStats, Integrator, IntegratorError};
use crate::sqp::EvalError;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Failure of an NLP evaluation.
#[derive(Debug, thiserror::Error)]
pub enum TranscriptionError {
    /// The problem is malformed.
    #[error("invalid problem: {0}")]
    Invalid(String),
    /// Integration of a shooting interval failed.
    #[error("phase '{phase}', interval {interval}")]
    Integrator {
        /// Phase name.
        phase: String,
        /// Interval index.
        interval: usize,
        /// Cause.
        #[source]
        source: IntegratorError,
    },
    /// A function of the problem (a term, a check point, a sample term or its shift)
    /// failed at this point.
    #[error("term '{term}'")]
    Term {
        /// Term name (a shift's is its sample term's, with ` (shift)`).
        term: String,
        /// Cause.
        #[source]
        source: TermError,
    },
}

impl TranscriptionError {
    /// Whether another point may evaluate where this one failed: an integrator that cannot
    /// take a step, a model or user function outside its domain, a non-finite value. A
    /// malformed problem or invalid integrator settings fail everywhere.
    pub fn is_recoverable(&self) -> bool {
        match self {
            TranscriptionError::Invalid(_) => false,
            TranscriptionError::Term { source, .. } => source.is_recoverable(),
            TranscriptionError::Integrator { source, .. } => match source {
                IntegratorError::Failed { .. }
                | IntegratorError::Rhs { .. }
                | IntegratorError::NonFinite { .. }
                | IntegratorError::SingularTransition { .. }
                | IntegratorError::BadInterval { .. }
                | IntegratorError::BadOutputTime { .. } => true,
                // a check point's function failed at this point's states
                IntegratorError::BadSettings {
                    field: "check point",
                    ..
                } => true,
                IntegratorError::Setup { .. }
                | IntegratorError::Dimension { .. }
                | IntegratorError::BadSettings { .. } => false,
            },
        }
    }

    /// The failure of term `name` with its cause, for `map_err` (the name is copied only
    /// on failure).
    fn of_term(name: &str) -> impl FnOnce(TermError) -> TranscriptionError + '_ {
        move |source| TranscriptionError::Term {
            term: name.to_string(),
            source,
        }
    }
}

impl From<TranscriptionError> for EvalError {
    fn from(e: TranscriptionError) -> Self {
        if e.is_recoverable() {
            EvalError::Recoverable(Box::new(e))
        } else {
            EvalError::Fatal(Box::new(e))
        }
    }
}

/// Where a constraint row comes from, for reports of violated constraints.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RowLabel {
    /// Phase name (or `problem` for whole-problem terms).
    pub phase: String,
    /// Node or interval index within the phase.
    pub node: usize,
    /// Constraint name and component.
    pub name: String,
}

/// Sample terms of one interval: distinct τ ascending, each with its terms' indices.
type Instants = Vec<(f64, Vec<usize>)>;

/// Add sample term `si` at `tau` to `list` (beside the terms already at that instant; the
/// caller sorts the list by τ once it is complete).
fn add_instant(list: &mut Instants, tau: f64, si: usize) {
    match list.iter_mut().find(|(t, _)| *t == tau) {
        Some((_, v)) => v.push(si),
        None => list.push((tau, vec![si])),
    }
}

#[derive(Debug, Clone)]
struct IntervalRef {
    phase: usize,
    k: usize,
    row: usize,
    /// Sample terms inside the interval at fixed instants: distinct τ ascending, each
    /// with its terms.
    samples: Instants,
    /// Whether sample terms can fall in the interval (fixed ones, or its phase has
    /// shifted ones): it then has a Gauss–Newton block.
    sample_block: bool,
    /// Check points inside the interval, by τ: (τ, index in `Ocp::checks`, first row).
    checks: Vec<(f64, usize, usize)>,
}

#[derive(Debug, Clone)]
struct TermRef {
    term: usize,
    kind: TermKind,
    row: usize,
    cols: Vec<usize>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum TermKind {
    Transition,
    Constraint,
    LeastSquares,
    Cost,
}

/// Result of one evaluation.
#[derive(Debug, Clone, Default)]
pub struct Evaluation {
    /// Objective.
    pub f: f64,
    /// Constraint values.
    pub c: Vec<f64>,
    /// Objective gradient (when derivatives were requested).
    pub grad: Vec<f64>,
    /// Jacobian values in [`Transcription::jacobian_pattern`] order.
    pub jac: Vec<f64>,
    /// Gauss–Newton Hessian values `2 Σ J_rᵀ J_r` in
    /// [`Transcription::gauss_newton_pattern`] order (upper triangle).
    pub gauss_newton: Vec<f64>,
    /// Integrator counters of this evaluation.
    pub stats: IntegrationStats,
}

/// The transcribed NLP.
pub struct Transcription<'o, 'a> {
    ocp: &'o Ocp<'a>,
    n: usize,
    state_off: Vec<Vec<usize>>,
    control_off: Vec<Vec<usize>>,
    duration_off: Vec<usize>,
    theta_off: usize,
    m: usize,
    intervals: Vec<IntervalRef>,
    terms: Vec<TermRef>,
    jac_rows: Vec<usize>,
    jac_cols: Vec<usize>,
    gn_rows: Vec<usize>,
    gn_cols: Vec<usize>,
    pools: Vec<Mutex<Vec<Integrator>>>,
    labels: Vec<RowLabel>,
    /// Sample terms whose instant moves with θ ([`SampleTerm::shift`](super::SampleTerm)).
    shifted: Vec<usize>,
    /// Index in `intervals` of each phase's first interval.
    first_interval: Vec<usize>,
    /// Integrator counters summed over every evaluation so far.
    totals: Mutex<IntegrationStats>,
    /// The factor (≤ 1, as f64 bits) on the problem's integrator tolerances that the next
    /// evaluations use: an inexact SQP tightens it near an optimum
    /// ([`Nlp::set_integration_tolerance`](crate::sqp::Nlp::set_integration_tolerance)).
    tolerance_scale: AtomicU64,
}

impl<'o, 'a> Transcription<'o, 'a> {
    /// Integrator counters summed over every evaluation of this transcription so far
    /// (steps, right-hand sides, Newton iterations of states and sensitivities, ...): where
    /// a solve's integration time went.
    pub fn integration_totals(&self) -> IntegrationStats {
        self.totals.lock().map(|t| *t).unwrap_or_default()
    }

    /// The integrator tolerance (relative, of the states) the next evaluations use.
    pub fn integration_tolerance(&self) -> f64 {
        self.ocp.integrator.rtol * self.tolerance_scale()
    }

    /// Make the next evaluations integrate at relative tolerance `rtol` (the absolute and
    /// the sensitivities' tolerances scaled alike), at most the problem's own.
    pub fn set_integration_tolerance(&self, rtol: f64) {
        let scale = (rtol / self.ocp.integrator.rtol).min(1.0);
        if scale.is_finite() && scale > 0.0 {
            self.tolerance_scale
                .store(scale.to_bits(), Ordering::Relaxed);
        }
    }

    fn tolerance_scale(&self) -> f64 {
        f64::from_bits(self.tolerance_scale.load(Ordering::Relaxed))
    }

    /// Variable index range of a block.
    pub fn range(&self, b: Block) -> Range<usize> {
        match b {
            Block::State { phase, node } => {
                let o = self.state_off[phase][node];
                o..o + self.ocp.phases[phase].ode.nx()
            }
            Block::Control { phase, node } => {
                let o = self.control_off[phase][node];
                o..o + self.ocp.phases[phase].ode.nu()
            }
            Block::Duration { phase } => self.duration_off[phase]..self.duration_off[phase] + 1,
            Block::Params => self.theta_off..self.theta_off + self.ocp.ntheta,
        }
    }

    /// Number of variables.
    pub fn n(&self) -> usize {
        self.n
    }
    /// Number of constraints.
    pub fn m(&self) -> usize {
        self.m
    }
    /// The problem.
    pub fn ocp(&self) -> &Ocp<'a> {
        self.ocp
    }
    /// Row labels of the constraints.
    pub fn labels(&self) -> &[RowLabel] {
        &self.labels
    }
    /// Jacobian sparsity pattern as (rows, cols); duplicates are summed.
    pub fn jacobian_pattern(&self) -> (&[usize], &[usize]) {
        (&self.jac_rows, &self.jac_cols)
    }
    /// Gauss–Newton Hessian pattern (upper triangle, duplicates summed).
    pub fn gauss_newton_pattern(&self) -> (&[usize], &[usize]) {
        (&self.gn_rows, &self.gn_cols)
    }

    /// Variable blocks for block-wise quasi-Newton updates: one block per shooting node
    /// (state with its control), plus durations and θ.
    pub fn hessian_blocks(&self) -> Vec<Vec<usize>> {
        let mut blocks = Vec::new();
        for (j, ph) in self.ocp.phases.iter().enumerate() {
            for k in 0..=ph.intervals {
                let mut b: Vec<usize> = self.range(Block::State { phase: j, node: k }).collect();
                if k < ph.control_nodes() {
                    b.extend(self.range(Block::Control { phase: j, node: k }));
                }
                blocks.push(b);
            }
            blocks.push(vec![self.duration_off[j]]);
        }
        if self.ocp.ntheta > 0 {
            blocks.push(self.range(Block::Params).collect());
        }
        blocks
    }

    /// Variable bounds and initial guess.
    pub fn variable_bounds_and_guess(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let mut lb = vec![f64::NEG_INFINITY; self.n];
        let mut ub = vec![f64::INFINITY; self.n];
        let mut w = vec![0.0; self.n];
        for (j, ph) in self.ocp.phases.iter().enumerate() {
            for k in 0..=ph.intervals {
                let r = self.range(Block::State { phase: j, node: k });
                lb[r.clone()].copy_from_slice(&ph.x_lb[k]);
                ub[r.clone()].copy_from_slice(&ph.x_ub[k]);
                w[r].copy_from_slice(&ph.x_guess[k]);
            }
            for k in 0..ph.control_nodes() {
                let r = self.range(Block::Control { phase: j, node: k });
                lb[r.clone()].copy_from_slice(&ph.u_lb[k]);
                ub[r.clone()].copy_from_slice(&ph.u_ub[k]);
                w[r].copy_from_slice(&ph.u_guess[k]);
            }
            let d = self.duration_off[j];
            lb[d] = ph.duration.lb;
            ub[d] = ph.duration.ub;
            w[d] = ph.duration.value;
        }
        let r = self.range(Block::Params);
        lb[r.clone()].copy_from_slice(&self.ocp.theta_lb);
        ub[r.clone()].copy_from_slice(&self.ocp.theta_ub);
        w[r].copy_from_slice(&self.ocp.theta_guess);
        (lb, ub, w)
    }

    /// Constraint bounds.
    pub fn constraint_bounds(&self) -> (Vec<f64>, Vec<f64>) {
        let mut lb = vec![0.0; self.m];
        let mut ub = vec![0.0; self.m];
        for t in &self.terms {
            if t.kind == TermKind::Constraint {
                let con = &self.ocp.constraints[t.term];
                lb[t.row..t.row + con.lb.len()].copy_from_slice(&con.lb);
                ub[t.row..t.row + con.ub.len()].copy_from_slice(&con.ub);
            }
        }
        for &(_, ci, row) in self.intervals.iter().flat_map(|iv| &iv.checks) {
            let cp = &self.ocp.checks[ci];
            lb[row..row + cp.lb.len()].copy_from_slice(&cp.lb);
            ub[row..row + cp.ub.len()].copy_from_slice(&cp.ub);
        }
        (lb, ub)
    }

    fn gather(&self, w: &[f64], cols: &[usize]) -> Vec<f64> {
        cols.iter().map(|&c| w[c]).collect()
    }
}
