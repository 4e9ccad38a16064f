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

use super::checks::CheckValues;
use super::problem::{Block, Ocp};
use crate::sqp::EvalError;
use crate::integrate::{
    ControlShape, IntegrationStats, Integrator, IntegratorError, ShootingInterval,
};
use rayon::prelude::*;
use std::ops::Range;
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
    /// A user function failed.
    #[error("term '{term}': {reason}")]
    Term {
        /// Term name.
        term: String,
        /// Cause.
        reason: String,
    },
}

impl TranscriptionError {
    /// Whether another point may evaluate where this one failed: an integrator that cannot
    /// take a step, a model or user function outside its domain, a non-finite value. A
    /// malformed problem or invalid integrator settings fail everywhere.
    pub fn is_recoverable(&self) -> bool {
        match self {
            TranscriptionError::Invalid(_) => false,
            TranscriptionError::Term { .. } => true,
            TranscriptionError::Integrator { source, .. } => match source {
                IntegratorError::Failed { .. }
                | IntegratorError::Rhs { .. }
                | IntegratorError::NonFinite { .. }
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

/// Instants of the sample terms at one evaluation, per interval in transcription order
/// (`None`: the fixed ones only), and per sample term the gradient of its instant in θ
/// (s per unit; `None` where it does not move: not shifted, or held at its phase's ends).
type Placement = (Vec<Option<Instants>>, Vec<Option<Vec<f64>>>);

/// A shifted sample's instant is held at least this far (as a fraction of an interval)
/// after its phase's start, where CVODES can take a first step towards it.
const SHIFTED_PHASE_START: f64 = 1e-6;

/// A shifted instant closer than this (fraction of an interval) to an interval's start
/// is taken at the end of the interval before it (an instant moved by at most 1e-9 of an
/// interval, instead of a first CVODES step of that size).
const SHIFTED_SNAP: f64 = 1e-9;

/// Where a sample term at `(interval, τ)` of a phase of `intervals` intervals of length
/// `h` (s) falls when its instant is shifted by `shift` (s), as
/// [`SampleTerm::shift`](super::SampleTerm) places it: `(interval, τ, moves)`, held
/// inside the phase (`moves` false where it is held at either end, so the instant does
/// not move with the shift there). A zero shift leaves it exactly where it was.
pub fn shifted_instant(
    interval: usize,
    tau: f64,
    shift: f64,
    h: f64,
    intervals: usize,
) -> (usize, f64, bool) {
    // the instant in units of intervals from the phase's start
    let at = interval as f64 + tau + shift / h;
    if shift == 0.0 {
        (interval, tau, true)
    } else if at <= SHIFTED_PHASE_START {
        (0, SHIFTED_PHASE_START, false)
    } else if at >= intervals as f64 {
        (intervals - 1, 1.0, false)
    } else {
        let k = (at.ceil() as usize).saturating_sub(1).min(intervals - 1);
        let tau = (at - k as f64).min(1.0);
        if tau < SHIFTED_SNAP && k > 0 {
            (k - 1, 1.0, true)
        } else {
            (k, tau, true)
        }
    }
}

/// What an interval's sample terms add to the objective: their value, the gradient and the
/// Gauss–Newton block (upper triangle, row by row) over the interval's columns.
#[derive(Debug, Default)]
struct SampleSums {
    f: f64,
    grad: Vec<f64>,
    gauss_newton: Vec<f64>,
}

/// One interval's integration: end state, sensitivities, statistics, curvature block
/// (with multipliers) and what its sample terms add.
type IntervalResult = (
    Vec<f64>,
    Vec<f64>,
    IntegrationStats,
    Option<Vec<f64>>,
    Option<SampleSums>,
    Vec<CheckValues>,
);

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
}

impl<'o, 'a> Transcription<'o, 'a> {
    /// Integrator counters summed over every evaluation of this transcription so far
    /// (steps, right-hand sides, Newton iterations of states and sensitivities, ...): where
    /// a solve's integration time went.
    pub fn integration_totals(&self) -> IntegrationStats {
        self.totals.lock().map(|t| *t).unwrap_or_default()
    }

    /// Lay out variables and constraints and build the sparsity patterns.
    pub fn new(ocp: &'o Ocp<'a>) -> Result<Self, TranscriptionError> {
        let inv = |s: String| TranscriptionError::Invalid(s);
        if ocp.phases.is_empty() {
            return Err(inv("no phase".into()));
        }
        if ocp.transitions.len() + 1 != ocp.phases.len() {
            return Err(inv(format!(
                "{} transitions for {} phases (need one between each pair)",
                ocp.transitions.len(),
                ocp.phases.len()
            )));
        }
        let mut n = 0;
        let mut state_off = Vec::new();
        let mut control_off = Vec::new();
        let mut duration_off = Vec::new();
        for (j, ph) in ocp.phases.iter().enumerate() {
            let (nx, nu) = (ph.ode.nx(), ph.ode.nu());
            if ph.intervals == 0 {
                return Err(inv(format!("phase '{}' has zero intervals", ph.name)));
            }
            if ph.ode.ntheta() != ocp.ntheta {
                return Err(inv(format!(
                    "phase '{}': dynamics have {} parameters, problem has {}",
                    ph.name,
                    ph.ode.ntheta(),
                    ocp.ntheta
                )));
            }
            let nodes = ph.intervals + 1;
            let cn = ph.control_nodes();
            for (what, v, len, width) in [
                ("x_lb", &ph.x_lb, nodes, nx),
                ("x_ub", &ph.x_ub, nodes, nx),
                ("x_guess", &ph.x_guess, nodes, nx),
                ("u_lb", &ph.u_lb, cn, nu),
                ("u_ub", &ph.u_ub, cn, nu),
                ("u_guess", &ph.u_guess, cn, nu),
            ] {
                if v.len() != len || v.iter().any(|r| r.len() != width) {
                    return Err(inv(format!(
                        "phase '{}' ({j}): {what} must be {len} rows of {width}",
                        ph.name
                    )));
                }
            }
            let mut so = Vec::new();
            let mut co = Vec::new();
            for k in 0..nodes {
                so.push(n);
                n += nx;
                if k < cn {
                    co.push(n);
                    n += nu;
                }
            }
            state_off.push(so);
            control_off.push(co);
            duration_off.push(n);
            n += 1;
        }
        let theta_off = n;
        n += ocp.ntheta;

        let mut t = Self {
            ocp,
            n,
            state_off,
            control_off,
            duration_off,
            theta_off,
            m: 0,
            intervals: Vec::new(),
            terms: Vec::new(),
            jac_rows: Vec::new(),
            jac_cols: Vec::new(),
            gn_rows: Vec::new(),
            gn_cols: Vec::new(),
            pools: ocp.phases.iter().map(|_| Mutex::new(Vec::new())).collect(),
            labels: Vec::new(),
            shifted: Vec::new(),
            first_interval: Vec::new(),
            totals: Mutex::new(IntegrationStats::default()),
        };
        // sample terms, grouped by interval and τ
        let mut samples: Vec<Vec<Instants>> = ocp
            .phases
            .iter()
            .map(|p| vec![Vec::new(); p.intervals])
            .collect();
        for (si, st) in ocp.samples.iter().enumerate() {
            let Some(list) = samples
                .get_mut(st.phase)
                .and_then(|p| p.get_mut(st.interval))
            else {
                return Err(inv(format!(
                    "sample term '{}': phase {} has no interval {}",
                    st.name, st.phase, st.interval
                )));
            };
            if !(st.tau > 0.0 && st.tau <= 1.0) {
                return Err(inv(format!(
                    "sample term '{}': τ = {} is not in (0, 1]",
                    st.name, st.tau
                )));
            }
            if let Some(shift) = &st.shift {
                let ph = &ocp.phases[st.phase];
                if ph.duration.is_free() {
                    return Err(inv(format!("sample term '{}': a shifted instant needs phase '{}' to have a fixed duration", st.name, ph.name)));
                }
                if shift.dim() != 1 {
                    return Err(inv(format!(
                        "sample term '{}': its shift has dimension {}, not 1",
                        st.name,
                        shift.dim()
                    )));
                }
                t.shifted.push(si);
                continue;
            }
            add_instant(list, st.tau, si);
        }
        for list in samples.iter_mut().flatten() {
            list.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        let mut shifted_phase = vec![false; ocp.phases.len()];
        for &si in &t.shifted {
            shifted_phase[ocp.samples[si].phase] = true;
        }
        // continuity rows
        for (j, ph) in ocp.phases.iter().enumerate() {
            let nx = ph.ode.nx();
            t.first_interval.push(t.intervals.len());
            for k in 0..ph.intervals {
                let row = t.m;
                let fixed = std::mem::take(&mut samples[j][k]);
                let sample_block = shifted_phase[j] || !fixed.is_empty();
                t.intervals.push(IntervalRef {
                    phase: j,
                    k,
                    row,
                    samples: fixed,
                    sample_block,
                    checks: Vec::new(),
                });
                let cols = t.interval_cols(j, k);
                for i in 0..nx {
                    for &c in &cols {
                        t.jac_rows.push(row + i);
                        t.jac_cols.push(c);
                    }
                    t.jac_rows.push(row + i);
                    t.jac_cols.push(t.state_off[j][k + 1] + i);
                    t.labels.push(RowLabel {
                        phase: ph.name.clone(),
                        node: k,
                        name: format!("continuity[{i}]"),
                    });
                }
                t.m += nx;
            }
        }
        // transitions
        for (j, tr) in ocp.transitions.iter().enumerate() {
            let next = &ocp.phases[j + 1];
            let nx1 = next.ode.nx();
            let row = t.m;
            match tr {
                Some(term) => {
                    if term.f.dim() != nx1 {
                        return Err(inv(format!(
                            "transition '{}' has dimension {}, phase '{}' has {nx1} states",
                            term.name,
                            term.f.dim(),
                            next.name
                        )));
                    }
                    let cols = t.term_cols(&term.args)?;
                    t.terms.push(TermRef {
                        term: j,
                        kind: TermKind::Transition,
                        row,
                        cols: cols.clone(),
                    });
                    for i in 0..nx1 {
                        for &c in &cols {
                            t.jac_rows.push(row + i);
                            t.jac_cols.push(c);
                        }
                    }
                }
                None => {
                    let prev = &ocp.phases[j];
                    if prev.ode.nx() != nx1 {
                        return Err(inv(format!(
                            "phases '{}' and '{}' differ in state dimension and need a transition",
                            prev.name, next.name
                        )));
                    }
                    for i in 0..nx1 {
                        t.jac_rows.push(row + i);
                        t.jac_cols.push(t.state_off[j][prev.intervals] + i);
                    }
                }
            }
            for i in 0..nx1 {
                t.jac_rows.push(row + i);
                t.jac_cols.push(t.state_off[j + 1][0] + i);
                t.labels.push(RowLabel {
                    phase: next.name.clone(),
                    node: 0,
                    name: format!("transition[{i}]"),
                });
            }
            t.m += nx1;
        }
        // user constraints
        for (ci, con) in ocp.constraints.iter().enumerate() {
            let d = con.term.f.dim();
            if con.lb.len() != d || con.ub.len() != d {
                return Err(inv(format!(
                    "constraint '{}': bounds must have {d} entries",
                    con.term.name
                )));
            }
            let cols = t.term_cols(&con.term.args)?;
            let row = t.m;
            t.terms.push(TermRef {
                term: ci,
                kind: TermKind::Constraint,
                row,
                cols: cols.clone(),
            });
            let (phase, node) = t.locate(&con.term.args);
            for i in 0..d {
                for &c in &cols {
                    t.jac_rows.push(row + i);
                    t.jac_cols.push(c);
                }
                t.labels.push(RowLabel {
                    phase: phase.clone(),
                    node,
                    name: format!("{}[{i}]", con.term.name),
                });
            }
            t.m += d;
        }
        // check points: rows in interval order, by τ within an interval
        let mut per_interval: Vec<Vec<(f64, usize)>> = vec![Vec::new(); t.intervals.len()];
        for (ci, cp) in ocp.checks.iter().enumerate() {
            let Some(ph) = ocp
                .phases
                .get(cp.phase)
                .filter(|ph| cp.interval < ph.intervals)
            else {
                return Err(inv(format!(
                    "check point '{}': phase {} has no interval {}",
                    cp.name, cp.phase, cp.interval
                )));
            };
            if !(cp.tau > 0.0 && cp.tau < 1.0) {
                return Err(inv(format!(
                    "check point '{}' in phase '{}': τ = {} is not in (0, 1)",
                    cp.name, ph.name, cp.tau
                )));
            }
            let d = cp.f.dim();
            if cp.lb.len() != d || cp.ub.len() != d {
                return Err(inv(format!(
                    "check point '{}': bounds must have {d} entries",
                    cp.name
                )));
            }
            per_interval[t.first_interval[cp.phase] + cp.interval].push((cp.tau, ci));
        }
        for (i, mut list) in per_interval.into_iter().enumerate() {
            list.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let (j, k) = (t.intervals[i].phase, t.intervals[i].k);
            let cols = t.interval_cols(j, k);
            for (tau, ci) in list {
                let cp = &ocp.checks[ci];
                let row = t.m;
                t.intervals[i].checks.push((tau, ci, row));
                for r in 0..cp.f.dim() {
                    for &c in &cols {
                        t.jac_rows.push(row + r);
                        t.jac_cols.push(c);
                    }
                    t.labels.push(RowLabel {
                        phase: ocp.phases[j].name.clone(),
                        node: k,
                        name: format!("{}@τ={tau:.3}[{r}]", cp.name),
                    });
                }
                t.m += cp.f.dim();
            }
        }
        // costs
        for (li, ls) in ocp.least_squares.iter().enumerate() {
            let cols = t.term_cols(&ls.args)?;
            for (a, &ca) in cols.iter().enumerate() {
                for &cb in &cols[a..] {
                    t.gn_rows.push(ca.min(cb));
                    t.gn_cols.push(ca.max(cb));
                }
            }
            t.terms.push(TermRef {
                term: li,
                kind: TermKind::LeastSquares,
                row: 0,
                cols,
            });
        }
        // the sample terms' Gauss–Newton blocks, after the least-squares terms', in
        // interval order
        for iv in t.intervals.iter().filter(|iv| iv.sample_block) {
            let cols = t.interval_cols(iv.phase, iv.k);
            for (a, &ca) in cols.iter().enumerate() {
                for &cb in &cols[a..] {
                    t.gn_rows.push(ca.min(cb));
                    t.gn_cols.push(ca.max(cb));
                }
            }
        }
        for (gi, g) in ocp.costs.iter().enumerate() {
            if g.f.dim() != 1 {
                return Err(inv(format!("cost '{}' must be scalar", g.name)));
            }
            let cols = t.term_cols(&g.args)?;
            t.terms.push(TermRef {
                term: gi,
                kind: TermKind::Cost,
                row: 0,
                cols,
            });
        }
        Ok(t)
    }

    /// The columns an interval depends on: its start state, its control(s), its phase's
    /// duration and θ (the order of its sensitivity columns).
    fn interval_cols(&self, j: usize, k: usize) -> Vec<usize> {
        let ph = &self.ocp.phases[j];
        let mut cols: Vec<usize> = Vec::new();
        cols.extend(self.range(Block::State { phase: j, node: k }));
        cols.extend(self.range(Block::Control { phase: j, node: k }));
        if ph.controls == ControlShape::Linear {
            cols.extend(self.range(Block::Control {
                phase: j,
                node: k + 1,
            }));
        }
        cols.push(self.duration_off[j]);
        cols.extend(self.range(Block::Params));
        cols
    }

    fn locate(&self, args: &[Block]) -> (String, usize) {
        for b in args {
            match *b {
                Block::State { phase, node } | Block::Control { phase, node } => {
                    return (self.ocp.phases[phase].name.clone(), node)
                }
                Block::Duration { phase } => return (self.ocp.phases[phase].name.clone(), 0),
                Block::Params => {}
            }
        }
        ("problem".into(), 0)
    }

    fn term_cols(&self, args: &[Block]) -> Result<Vec<usize>, TranscriptionError> {
        let mut cols = Vec::new();
        for &b in args {
            self.check_block(b)?;
            cols.extend(self.range(b));
        }
        Ok(cols)
    }

    fn check_block(&self, b: Block) -> Result<(), TranscriptionError> {
        let ok = match b {
            Block::State { phase, node } => {
                phase < self.ocp.phases.len() && node <= self.ocp.phases[phase].intervals
            }
            Block::Control { phase, node } => {
                phase < self.ocp.phases.len() && node < self.ocp.phases[phase].control_nodes()
            }
            Block::Duration { phase } => phase < self.ocp.phases.len(),
            Block::Params => true,
        };
        if ok {
            Ok(())
        } else {
            Err(TranscriptionError::Invalid(format!(
                "block {b:?} does not exist"
            )))
        }
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

    /// Where the shifted sample terms fall at `w` ([`SampleTerm::shift`](super::SampleTerm)):
    /// the instant `(interval + τ) h + s(θ)` located in its phase's intervals (the node
    /// times are fixed: the phase's duration is), held inside the phase.
    fn place_shifted(&self, w: &[f64]) -> Result<Placement, TranscriptionError> {
        let mut lists: Vec<Option<Instants>> = vec![None; self.intervals.len()];
        let mut gradients = vec![None; self.ocp.samples.len()];
        let theta = &w[self.range(Block::Params)];
        for &si in &self.shifted {
            let st = &self.ocp.samples[si];
            let Some(shift) = &st.shift else { continue };
            let n = self.ocp.phases[st.phase].intervals;
            let h = w[self.duration_off[st.phase]] / n as f64;
            let mut s = [0.0];
            let mut g = vec![0.0; self.ocp.ntheta];
            shift
                .eval(theta, &mut s, Some(&mut g))
                .map_err(|reason| TranscriptionError::Term {
                    term: format!("{} (shift)", st.name),
                    reason,
                })?;
            if !s[0].is_finite() || g.iter().any(|v| !v.is_finite()) {
                return Err(TranscriptionError::Term {
                    term: format!("{} (shift)", st.name),
                    reason: format!("shift {} s is not finite", s[0]),
                });
            }
            let (k, tau, moves) = shifted_instant(st.interval, st.tau, s[0], h, n);
            if moves {
                gradients[si] = Some(g);
            }
            let i = self.first_interval[st.phase] + k;
            add_instant(
                lists[i].get_or_insert_with(|| self.intervals[i].samples.clone()),
                tau,
                si,
            );
        }
        for list in lists.iter_mut().flatten() {
            list.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        Ok((lists, gradients))
    }

    #[allow(clippy::too_many_arguments)]
    fn integrate_interval(
        &self,
        iv: &IntervalRef,
        list: &[(f64, Vec<usize>)],
        moves: &[Option<Vec<f64>>],
        w: &[f64],
        sens: bool,
        lambda: Option<&[f64]>,
    ) -> Result<IntervalResult, TranscriptionError> {
        let ph = &self.ocp.phases[iv.phase];
        let interval = ShootingInterval::new(ph.ode, ph.controls);
        let (nx, np) = (ph.ode.nx(), interval.np());
        let x0 = &w[self.range(Block::State {
            phase: iv.phase,
            node: iv.k,
        })];
        let u0 = &w[self.range(Block::Control {
            phase: iv.phase,
            node: iv.k,
        })];
        let u1 = match ph.controls {
            ControlShape::Linear => Some(
                &w[self.range(Block::Control {
                    phase: iv.phase,
                    node: iv.k + 1,
                })],
            ),
            ControlShape::Constant => None,
        };
        let h = w[self.duration_off[iv.phase]] / ph.intervals as f64;
        let theta = &w[self.range(Block::Params)];
        let err = |source| TranscriptionError::Integrator {
            phase: ph.name.clone(),
            interval: iv.k,
            source,
        };
        let mut p = Vec::with_capacity(np);
        interval
            .pack_params(u0, u1, h, theta, &mut p)
            .map_err(err)?;
        let pool = &self.pools[iv.phase];
        let taken = pool.lock().map(|mut v| v.pop()).unwrap_or(None);
        let mut integ = match taken {
            Some(i) => i,
            None => Integrator::new(nx, np, self.ocp.integrator.clone()).map_err(err)?,
        };
        let mut x1 = vec![0.0; nx];
        let mut s = Vec::new();
        let mut hess = None;
        // the sample terms' and check points' instants, with the interval's end for one
        // pass to all
        let mut taus: Vec<f64> = list.iter().map(|e| e.0).collect();
        if !iv.checks.is_empty() {
            taus.extend(iv.checks.iter().map(|c| c.0));
            taus.sort_by(f64::total_cmp);
            taus.dedup();
        }
        let mut times = taus.clone();
        if times.last().is_some_and(|&t| t < 1.0) {
            times.push(1.0);
        }
        let (mut xs, mut ss) = (Vec::new(), Vec::new());
        let res = if let Some(lam) = lambda {
            // continuity rows are s_{k+1} − x(1): their curvature is that of −λᵀx(1)
            s = vec![0.0; nx * (nx + np)];
            let weights: Vec<f64> = lam[iv.row..iv.row + nx].iter().map(|v| -v).collect();
            let mut h = vec![0.0; (nx + np) * (nx + np)];
            // the samples' and check points' states and sensitivities come from the same
            // pass, with the curvature of the check points' state dependence
            let interior: Vec<f64> = {
                let mut v: Vec<f64> = iv.checks.iter().map(|c| c.0).collect();
                v.dedup();
                v
            };
            let mut check_weights = |i: usize, x: &[f64]| {
                super::checks::state_weights(
                    self.ocp,
                    iv.phase,
                    &iv.checks,
                    interior[i],
                    &p,
                    x,
                    lam,
                )
                .map_err(|reason| IntegratorError::BadSettings {
                    field: "check point",
                    reason,
                })
            };
            match interval.integrate_with_hessian_interior(
                &mut integ,
                x0,
                &p,
                &weights,
                &mut x1,
                &mut s,
                &mut h,
                &taus,
                &mut xs,
                &mut ss,
                &interior,
                &mut check_weights,
            ) {
                Ok(true) => match super::checks::add_direct_curvature(
                    self.ocp, iv.phase, &iv.checks, &taus, &p, &xs, &ss, lam, &mut h,
                ) {
                    Ok(()) => {
                        hess = Some(h);
                        Ok(integ.stats_snapshot())
                    }
                    Err(reason) => Err(IntegratorError::BadSettings {
                        field: "check point",
                        reason,
                    }),
                },
                Ok(false) => Err(IntegratorError::BadSettings {
                    field: "hessian",
                    reason: format!(
                        "the dynamics of phase '{}' provide no second derivatives",
                        ph.name
                    ),
                }),
                Err(e) => Err(e),
            }
        } else if sens {
            s = vec![0.0; nx * (nx + np)];
            if taus.is_empty() {
                integ.integrate_with_sensitivities(&interval, 0.0, 1.0, x0, &p, &mut x1, &mut s)
            } else {
                integ
                    .integrate_with_sensitivities_dense(
                        &interval, 0.0, 1.0, x0, &p, &times, &mut xs, &mut ss,
                    )
                    .inspect(|_| {
                        let sz = nx * (nx + np);
                        x1.copy_from_slice(&xs[xs.len() - nx..]);
                        s.copy_from_slice(&ss[ss.len() - sz..]);
                    })
            }
        } else if taus.is_empty() {
            integ.integrate(&interval, 0.0, 1.0, x0, &p, &mut x1)
        } else {
            integ
                .integrate_dense(&interval, 0.0, 1.0, x0, &p, &times, &mut xs)
                .inspect(|_| x1.copy_from_slice(&xs[xs.len() - nx..]))
        };
        if let Ok(mut v) = pool.lock() {
            v.push(integ);
        }
        let stats = res.map_err(err)?;
        let derivs = sens || lambda.is_some();
        let checks = super::checks::check_values(
            self.ocp,
            iv.phase,
            &iv.checks,
            &taus,
            &p,
            &xs,
            derivs.then_some(&ss[..]),
        )?;
        let sums = if !iv.sample_block {
            None
        } else if iv.checks.is_empty() {
            Some(self.sample_sums(iv, list, moves, &p, &xs, derivs.then_some(&ss[..]))?)
        } else {
            // the samples' own rows of the merged instants
            let (xs, ss) = super::checks::rows_at(
                list.iter().map(|e| e.0),
                &taus,
                nx,
                nx * (nx + np),
                &xs,
                &ss,
                derivs,
            );
            Some(self.sample_sums(iv, list, moves, &p, &xs, derivs.then_some(&ss[..]))?)
        };
        Ok((x1, s, stats, hess, sums, checks))
    }

    /// The sample terms `list` of interval `iv` at its integrated states `xs` (nx per τ,
    /// in τ order) with, when `ss` is given, their sensitivities (nx·(nx+np) per τ):
    /// value, gradient and Gauss–Newton block over the interval's columns (x0, u0, [u1],
    /// T, θ), by the chain rule through `x(τ) = Φ(τ; x0, p)` and `u(τ)`; a term whose
    /// instant moves with θ (gradient in `moves`) adds `(∂r/∂x ẋ + ∂r/∂u u̇) ∂t/∂θ`.
    #[allow(clippy::too_many_arguments)]
    fn sample_sums(
        &self,
        iv: &IntervalRef,
        list: &[(f64, Vec<usize>)],
        moves: &[Option<Vec<f64>>],
        p: &[f64],
        xs: &[f64],
        ss: Option<&[f64]>,
    ) -> Result<SampleSums, TranscriptionError> {
        let ph = &self.ocp.phases[iv.phase];
        let interval = ShootingInterval::new(ph.ode, ph.controls);
        let (nx, nu, nt) = (ph.ode.nx(), ph.ode.nu(), self.ocp.ntheta);
        let ncols = nx + interval.np();
        let nz = nx + nu + nt;
        let theta = &p[interval.p_theta()];
        let u0 = &p[interval.p_u0()];
        let u1 = interval.p_u1().map(|r| &p[r]);
        let hscale = 1.0 / ph.intervals as f64;
        let mut out = SampleSums {
            f: 0.0,
            grad: Vec::new(),
            gauss_newton: Vec::new(),
        };
        if ss.is_some() {
            out.grad = vec![0.0; ncols];
            out.gauss_newton = vec![0.0; ncols * (ncols + 1) / 2];
        }
        for (q, (tau, terms)) in list.iter().enumerate() {
            let x = &xs[q * nx..(q + 1) * nx];
            let z = super::checks::instant_args(&interval, x, p, *tau);
            let u = &z[nx..nx + nu];
            for &si in terms {
                let term = &self.ocp.samples[si];
                let d = term.f.dim();
                let mut r = vec![0.0; d];
                let mut jz = vec![0.0; d * nz];
                term.f
                    .eval(&z, &mut r, ss.is_some().then_some(&mut jz[..]))
                    .map_err(|reason| TranscriptionError::Term {
                        term: term.name.clone(),
                        reason,
                    })?;
                out.f += r.iter().map(|v| v * v).sum::<f64>();
                let Some(ss) = ss else { continue };
                let s = &ss[q * nx * ncols..(q + 1) * nx * ncols];
                let mut jac =
                    super::checks::instant_jacobian(&interval, nx, nu, d, &jz, s, *tau, hscale);
                if let Some(g) = moves.get(si).and_then(Option::as_ref) {
                    // dr/dt along the trajectory (per second): ẋ = f(x, u, θ), u̇ = (u1 − u0)/h
                    let h = p[interval.p_duration()];
                    let mut xdot = vec![0.0; nx];
                    ph.ode
                        .f(x, &u, theta, &mut xdot)
                        .map_err(|e| TranscriptionError::Term {
                            term: term.name.clone(),
                            reason: e.to_string(),
                        })?;
                    let udot: Vec<f64> = match u1 {
                        Some(u1) => u0.iter().zip(u1).map(|(a, b)| (b - a) / h).collect(),
                        None => vec![0.0; nu],
                    };
                    for i in 0..d {
                        let rate = (0..nx).map(|k| jz[i + k * d] * xdot[k]).sum::<f64>()
                            + (0..nu).map(|k| jz[i + (nx + k) * d] * udot[k]).sum::<f64>();
                        for (k, c) in interval.p_theta().enumerate() {
                            jac[i + (nx + c) * d] += rate * g[k];
                        }
                    }
                }
                let mut at = 0;
                for a in 0..ncols {
                    let ja = &jac[a * d..(a + 1) * d];
                    out.grad[a] += 2.0 * ja.iter().zip(&r).map(|(j, v)| j * v).sum::<f64>();
                    for b in a..ncols {
                        out.gauss_newton[at] += 2.0
                            * ja.iter()
                                .zip(&jac[b * d..(b + 1) * d])
                                .map(|(x, y)| x * y)
                                .sum::<f64>();
                        at += 1;
                    }
                }
            }
        }
        Ok(out)
    }

    /// Evaluate objective and constraints, and with `derivs` their first derivatives
    /// and the Gauss–Newton Hessian.
    pub fn evaluate(&self, w: &[f64], derivs: bool) -> Result<Evaluation, TranscriptionError> {
        self.evaluate_inner(w, derivs, None).map(|(ev, _)| ev)
    }

    /// Evaluate with derivatives and the exact curvature `Σ λ_i ∇²c_i` of the continuity
    /// rows (from interval Hessians) and of the terms that provide it, as upper-triangle
    /// triplets `(rows, cols, vals)`.
    #[allow(clippy::type_complexity)]
    pub fn evaluate_with_hessian(
        &self,
        w: &[f64],
        lambda: &[f64],
    ) -> Result<(Evaluation, (Vec<usize>, Vec<usize>, Vec<f64>)), TranscriptionError> {
        let (ev, blocks) = self.evaluate_inner(w, true, Some(lambda))?;
        let (mut rows, mut cols, mut vals) =
            self.term_curvature(w, lambda, true)
                .map_err(|reason| TranscriptionError::Term {
                    term: "hessian".into(),
                    reason,
                })?;
        for (iv, h) in self.intervals.iter().zip(blocks) {
            let Some(h) = h else { continue };
            let ph = &self.ocp.phases[iv.phase];
            let interval = ShootingInterval::new(ph.ode, ph.controls);
            let nx = ph.ode.nx();
            let nz = nx + interval.np();
            // z order: x0, u0, [u1], h, θ  → NLP columns (h = T/N)
            let mut map: Vec<(usize, f64)> = self
                .range(Block::State {
                    phase: iv.phase,
                    node: iv.k,
                })
                .map(|c| (c, 1.0))
                .collect();
            map.extend(
                self.range(Block::Control {
                    phase: iv.phase,
                    node: iv.k,
                })
                .map(|c| (c, 1.0)),
            );
            if ph.controls == ControlShape::Linear {
                map.extend(
                    self.range(Block::Control {
                        phase: iv.phase,
                        node: iv.k + 1,
                    })
                    .map(|c| (c, 1.0)),
                );
            }
            map.push((self.duration_off[iv.phase], 1.0 / ph.intervals as f64));
            map.extend(self.range(Block::Params).map(|c| (c, 1.0)));
            debug_assert_eq!(map.len(), nz);
            for a in 0..nz {
                for b in a..nz {
                    let (ca, sa) = map[a];
                    let (cb, sb) = map[b];
                    let mut v = h[a + b * nz] * sa * sb;
                    if ca == cb && a != b {
                        v *= 2.0;
                    }
                    if v != 0.0 {
                        rows.push(ca.min(cb));
                        cols.push(ca.max(cb));
                        vals.push(v);
                    }
                }
            }
        }
        Ok((ev, (rows, cols, vals)))
    }

    #[allow(clippy::type_complexity)]
    fn evaluate_inner(
        &self,
        w: &[f64],
        derivs: bool,
        lambda: Option<&[f64]>,
    ) -> Result<(Evaluation, Vec<Option<Vec<f64>>>), TranscriptionError> {
        let (lists, moves) = self.place_shifted(w)?;
        let results: Vec<_> = self
            .intervals
            .par_iter()
            .zip(&lists)
            .map(|(iv, list)| {
                self.integrate_interval(
                    iv,
                    list.as_deref().unwrap_or(&iv.samples),
                    &moves,
                    w,
                    derivs,
                    lambda,
                )
            })
            .collect();
        let mut blocks = Vec::with_capacity(results.len());
        let mut sample_sums = Vec::new();
        let mut check_values = Vec::new();
        let mut ev = Evaluation {
            f: 0.0,
            c: vec![0.0; self.m],
            grad: if derivs {
                vec![0.0; self.n]
            } else {
                Vec::new()
            },
            jac: if derivs {
                Vec::with_capacity(self.jac_rows.len())
            } else {
                Vec::new()
            },
            gauss_newton: if derivs {
                Vec::with_capacity(self.gn_rows.len())
            } else {
                Vec::new()
            },
            stats: IntegrationStats::default(),
        };
        // continuity (Jacobian values in pattern order)
        for (iv, r) in self.intervals.iter().zip(results) {
            let (x1, s, st, hess, sums, checks) = r?;
            blocks.push(hess);
            check_values.extend(checks);
            if let Some(sums) = sums {
                sample_sums.push((iv, sums));
            }
            ev.stats += st;
            let ph = &self.ocp.phases[iv.phase];
            let nx = ph.ode.nx();
            let next = &w[self.range(Block::State {
                phase: iv.phase,
                node: iv.k + 1,
            })];
            for i in 0..nx {
                ev.c[iv.row + i] = next[i] - x1[i];
            }
            if derivs {
                let interval = ShootingInterval::new(ph.ode, ph.controls);
                let np = interval.np();
                let hscale = 1.0 / ph.intervals as f64;
                let dur = interval.p_duration();
                // sensitivity columns in pattern order: x0, u0, [u1], T, θ
                let mut order: Vec<(usize, f64)> = (0..nx).map(|c| (c, 1.0)).collect();
                order.extend(interval.p_u0().map(|c| (nx + c, 1.0)));
                if let Some(r) = interval.p_u1() {
                    order.extend(r.map(|c| (nx + c, 1.0)));
                }
                order.push((nx + dur, hscale));
                order.extend(interval.p_theta().map(|c| (nx + c, 1.0)));
                debug_assert_eq!(order.len(), nx + np);
                for i in 0..nx {
                    for &(c, sc) in &order {
                        ev.jac.push(-s[c * nx + i] * sc);
                    }
                    ev.jac.push(1.0);
                }
            }
        }
        // transitions, in pattern order
        for (j, tr) in self.ocp.transitions.iter().enumerate() {
            let next = &self.ocp.phases[j + 1];
            let nx1 = next.ode.nx();
            let x0: Vec<f64> = w[self.range(Block::State {
                phase: j + 1,
                node: 0,
            })]
            .to_vec();
            match tr {
                Some(term) => {
                    let t = self
                        .terms
                        .iter()
                        .find(|t| t.kind == TermKind::Transition && t.term == j)
                        .expect("transition term registered in new()");
                    let z = self.gather(w, &t.cols);
                    let mut v = vec![0.0; nx1];
                    let mut jac = vec![0.0; nx1 * z.len()];
                    term.f
                        .eval(&z, &mut v, derivs.then_some(&mut jac[..]))
                        .map_err(|reason| TranscriptionError::Term {
                            term: term.name.clone(),
                            reason,
                        })?;
                    for i in 0..nx1 {
                        ev.c[t.row + i] = x0[i] - v[i];
                    }
                    if derivs {
                        self.push_transition_jac(&mut ev.jac, t, nx1, &jac);
                    }
                }
                None => {
                    let prev = &self.ocp.phases[j];
                    let xe = &w[self.range(Block::State {
                        phase: j,
                        node: prev.intervals,
                    })];
                    let row = self.transition_row(j);
                    for i in 0..nx1 {
                        ev.c[row + i] = x0[i] - xe[i];
                    }
                    if derivs {
                        ev.jac.extend(std::iter::repeat(-1.0).take(nx1));
                        ev.jac.extend(std::iter::repeat(1.0).take(nx1));
                    }
                }
            }
        }
        // user constraints and costs, in term order
        for t in &self.terms {
            match t.kind {
                TermKind::Transition => {}
                TermKind::Constraint => {
                    let con = &self.ocp.constraints[t.term];
                    let d = con.term.f.dim();
                    let z = self.gather(w, &t.cols);
                    let mut jac = vec![0.0; d * z.len()];
                    con.term
                        .f
                        .eval(
                            &z,
                            &mut ev.c[t.row..t.row + d],
                            derivs.then_some(&mut jac[..]),
                        )
                        .map_err(|reason| TranscriptionError::Term {
                            term: con.term.name.clone(),
                            reason,
                        })?;
                    if derivs {
                        for i in 0..d {
                            for c in 0..z.len() {
                                ev.jac.push(jac[i + c * d]);
                            }
                        }
                    }
                }
                TermKind::LeastSquares => {
                    let term = &self.ocp.least_squares[t.term];
                    let d = term.f.dim();
                    let z = self.gather(w, &t.cols);
                    let mut r = vec![0.0; d];
                    let mut jac = vec![0.0; d * z.len()];
                    term.f
                        .eval(&z, &mut r, derivs.then_some(&mut jac[..]))
                        .map_err(|reason| TranscriptionError::Term {
                            term: term.name.clone(),
                            reason,
                        })?;
                    ev.f += r.iter().map(|v| v * v).sum::<f64>();
                    if derivs {
                        let nz = z.len();
                        for (a, &ca) in t.cols.iter().enumerate() {
                            ev.grad[ca] += 2.0 * (0..d).map(|i| jac[i + a * d] * r[i]).sum::<f64>();
                        }
                        for a in 0..nz {
                            for b in a..nz {
                                let mut v = 2.0
                                    * (0..d).map(|i| jac[i + a * d] * jac[i + b * d]).sum::<f64>();
                                if t.cols[a] == t.cols[b] && a != b {
                                    v *= 2.0;
                                }
                                ev.gauss_newton.push(v);
                            }
                        }
                    }
                }
                TermKind::Cost => {
                    let term = &self.ocp.costs[t.term];
                    let z = self.gather(w, &t.cols);
                    let mut v = [0.0];
                    let mut jac = vec![0.0; z.len()];
                    term.f
                        .eval(&z, &mut v, derivs.then_some(&mut jac[..]))
                        .map_err(|reason| TranscriptionError::Term {
                            term: term.name.clone(),
                            reason,
                        })?;
                    ev.f += v[0];
                    if derivs {
                        for (a, &ca) in t.cols.iter().enumerate() {
                            ev.grad[ca] += jac[a];
                        }
                    }
                }
            }
        }
        // check points, in row order (after the user constraints in the pattern)
        for cv in check_values {
            let d = cv.values.len();
            ev.c[cv.row..cv.row + d].copy_from_slice(&cv.values);
            if derivs {
                let ncols = cv.jac.len() / d.max(1);
                for i in 0..d {
                    ev.jac.extend((0..ncols).map(|c| cv.jac[i + c * d]));
                }
            }
        }
        // sample terms, in interval order (their Gauss–Newton blocks follow the
        // least-squares terms' in the pattern)
        for (iv, sums) in sample_sums {
            ev.f += sums.f;
            if derivs {
                let cols = self.interval_cols(iv.phase, iv.k);
                for (&c, g) in cols.iter().zip(&sums.grad) {
                    ev.grad[c] += g;
                }
                ev.gauss_newton.extend_from_slice(&sums.gauss_newton);
            }
        }
        if let Ok(mut t) = self.totals.lock() {
            *t += ev.stats;
        }
        Ok((ev, blocks))
    }

    /// Exact curvature of the terms that provide it, as upper-triangle triplets: of the
    /// constraints and transitions `Σ λ_i ∇²c_i`, and with `objective` also of the
    /// objective (`2 Σ r_i ∇²r_i` of least-squares terms, whose `2 JᵀJ` part is the
    /// Gauss–Newton matrix, and `∇²f` of general costs). Terms are evaluated in parallel
    /// and assembled in term order, so the result does not depend on the thread count.
    #[allow(clippy::type_complexity)]
    fn term_curvature(
        &self,
        w: &[f64],
        lambda: &[f64],
        objective: bool,
    ) -> Result<(Vec<usize>, Vec<usize>, Vec<f64>), String> {
        let blocks: Vec<Result<Option<(&TermRef, Vec<f64>)>, String>> = self
            .terms
            .par_iter()
            .map(|t| {
                let z = self.gather(w, &t.cols);
                // transitions are written x0 − ψ(z): their curvature enters with −λ
                let (f, name, weights): (&dyn super::NodeFunction, &str, Vec<f64>) = match t.kind {
                    TermKind::Transition => match &self.ocp.transitions[t.term] {
                        Some(term) => (
                            &*term.f,
                            &term.name,
                            (0..term.f.dim()).map(|i| -lambda[t.row + i]).collect(),
                        ),
                        None => return Ok(None),
                    },
                    TermKind::Constraint => {
                        let term = &self.ocp.constraints[t.term].term;
                        (
                            &*term.f,
                            &term.name,
                            (0..term.f.dim()).map(|i| lambda[t.row + i]).collect(),
                        )
                    }
                    TermKind::LeastSquares if objective => {
                        let term = &self.ocp.least_squares[t.term];
                        if !term.f.has_hessian() {
                            return Ok(None);
                        }
                        let mut r = vec![0.0; term.f.dim()];
                        term.f
                            .eval(&z, &mut r, None)
                            .map_err(|e| format!("term '{}': {e}", term.name))?;
                        (&*term.f, &term.name, r.iter().map(|v| 2.0 * v).collect())
                    }
                    TermKind::Cost if objective => {
                        let term = &self.ocp.costs[t.term];
                        (&*term.f, &term.name, vec![1.0])
                    }
                    _ => return Ok(None),
                };
                if !f.has_hessian() || weights.iter().all(|v| *v == 0.0) {
                    return Ok(None);
                }
                let nz = z.len();
                let mut hm = vec![0.0; nz * nz];
                f.weighted_hessian(&z, &weights, &mut hm)
                    .map_err(|e| format!("term '{name}': {e}"))?;
                Ok(Some((t, hm)))
            })
            .collect();
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        for b in blocks {
            let Some((t, hm)) = b? else { continue };
            let nz = t.cols.len();
            for a in 0..nz {
                for b in a..nz {
                    let mut v = hm[a + b * nz];
                    if v == 0.0 {
                        continue;
                    }
                    if t.cols[a] == t.cols[b] && a != b {
                        v *= 2.0;
                    }
                    rows.push(t.cols[a].min(t.cols[b]));
                    cols.push(t.cols[a].max(t.cols[b]));
                    vals.push(v);
                }
            }
        }
        Ok((rows, cols, vals))
    }

    fn transition_row(&self, j: usize) -> usize {
        let cont: usize = self
            .ocp
            .phases
            .iter()
            .map(|p| p.intervals * p.ode.nx())
            .sum();
        cont + (0..j)
            .map(|i| self.ocp.phases[i + 1].ode.nx())
            .sum::<usize>()
    }

    fn push_transition_jac(&self, jac_out: &mut Vec<f64>, t: &TermRef, nx1: usize, jac: &[f64]) {
        for i in 0..nx1 {
            for c in 0..t.cols.len() {
                jac_out.push(-jac[i + c * nx1]);
            }
        }
        for _ in 0..nx1 {
            jac_out.push(1.0);
        }
    }
}

impl crate::sqp::Nlp for Transcription<'_, '_> {
    fn n(&self) -> usize {
        self.n
    }
    fn m(&self) -> usize {
        self.m
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        let (wl, wu, _) = self.variable_bounds_and_guess();
        let (cl, cu) = self.constraint_bounds();
        (wl, wu, cl, cu)
    }
    fn jacobian_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        (self.jac_rows.clone(), self.jac_cols.clone())
    }
    fn gauss_newton_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        (self.gn_rows.clone(), self.gn_cols.clone())
    }
    fn hessian_blocks(&self) -> Vec<Vec<usize>> {
        Transcription::hessian_blocks(self)
    }
    fn evaluate(&self, w: &[f64], derivs: bool) -> Result<crate::sqp::NlpEval, EvalError> {
        let ev = Transcription::evaluate(self, w, derivs)?;
        Ok(crate::sqp::NlpEval {
            f: ev.f,
            c: ev.c,
            grad: ev.grad,
            jac: ev.jac,
            gn: ev.gauss_newton,
        })
    }
    fn elastic_weights(&self) -> Vec<f64> {
        let dynamics = self
            .ocp
            .phases
            .iter()
            .map(|p| p.intervals * p.ode.nx())
            .sum::<usize>()
            + self
                .ocp
                .phases
                .iter()
                .skip(1)
                .map(|p| p.ode.nx())
                .sum::<usize>();
        (0..self.m)
            .map(|i| if i < dynamics { 10.0 } else { 1.0 })
            .collect()
    }
    fn evaluate_with_hessian(
        &self,
        w: &[f64],
        lambda: &[f64],
    ) -> Result<(crate::sqp::NlpEval, (Vec<usize>, Vec<usize>, Vec<f64>)), EvalError> {
        let (ev, h) = Transcription::evaluate_with_hessian(self, w, lambda)?;
        Ok((
            crate::sqp::NlpEval {
                f: ev.f,
                c: ev.c,
                grad: ev.grad,
                jac: ev.jac,
                gn: ev.gauss_newton,
            },
            h,
        ))
    }
    fn rows_with_exact_hessian(&self) -> Vec<bool> {
        let mut rows = vec![false; self.m];
        for t in &self.terms {
            let (f, dim) = match t.kind {
                TermKind::Transition => match &self.ocp.transitions[t.term] {
                    Some(term) => (&term.f, term.f.dim()),
                    None => continue,
                },
                TermKind::Constraint => (
                    &self.ocp.constraints[t.term].term.f,
                    self.ocp.constraints[t.term].term.f.dim(),
                ),
                _ => continue,
            };
            if f.has_hessian() {
                rows[t.row..t.row + dim].iter_mut().for_each(|r| *r = true);
            }
        }
        rows
    }
    fn exact_hessian(
        &self,
        w: &[f64],
        lambda: &[f64],
    ) -> Result<(Vec<usize>, Vec<usize>, Vec<f64>), EvalError> {
        self.term_curvature(w, lambda, false)
            .map_err(EvalError::recoverable)
    }
    fn row_name(&self, i: usize) -> String {
        let l = &self.labels[i];
        format!("phase '{}', node {}, {}", l.phase, l.node, l.name)
    }
}
