//! The SQP subproblem as a Clarabel QP.
//!
//! $$\min_d \tfrac12 d^T H d + g^T d \quad\text{s.t.}\quad
//!   c_{lb} - c \le J d \le c_{ub} - c,\qquad w_{lb} - w \le d \le w_{ub} - w,$$
//! mapped to Clarabel's form $A d + s = b$, $s \in \mathcal{K}$: equality rows (and fixed
//! variables) in the zero cone, each finite inequality bound as one row of the
//! nonnegative cone. In elastic mode every constraint row gets a pair of non-negative
//! slacks $p, n$ penalised by $\rho \sum (p + n)$, so the QP is always feasible (used when
//! the linearised constraints are inconsistent). A QP asked at a solution, or given the
//! multipliers of a previous QP of the same shape, is solved on its guessed active set
//! first ([`active_set`]).

mod active_set;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolution, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

/// Sparse matrix as triplets (duplicates are summed).
#[derive(Debug, Clone, Default)]
pub struct Triplets {
    /// Row indices.
    pub rows: Vec<usize>,
    /// Column indices.
    pub cols: Vec<usize>,
    /// Values.
    pub vals: Vec<f64>,
}

impl Triplets {
    /// Add one entry.
    pub fn push(&mut self, r: usize, c: usize, v: f64) {
        self.rows.push(r);
        self.cols.push(c);
        self.vals.push(v);
    }

    /// Append `scale · other`.
    pub fn extend_scaled(&mut self, other: &Triplets, scale: f64) {
        self.rows.extend_from_slice(&other.rows);
        self.cols.extend_from_slice(&other.cols);
        self.vals.extend(other.vals.iter().map(|v| scale * v));
    }
}

/// The compressed-sparse-column pattern of a list of triplet positions: where each
/// triplet's value goes (duplicates share one entry). Built by a counting sort over the
/// columns and a sort of each column's rows, so a pattern of a million entries takes
/// milliseconds; matrices with the same positions and other values reuse it.
#[derive(Debug, Clone)]
pub struct CscPattern {
    m: usize,
    n: usize,
    colptr: Vec<usize>,
    rowval: Vec<usize>,
    /// For each triplet, the index of its entry in `rowval`.
    slot: Vec<usize>,
}

impl CscPattern {
    /// The pattern of the positions `(rows[k], cols[k])` in an `m × n` matrix.
    pub fn new(m: usize, n: usize, rows: &[usize], cols: &[usize]) -> Self {
        // counting sort of the triplets by column (stable: equal positions keep their order)
        let mut start = vec![0usize; n + 1];
        for &c in cols {
            start[c + 1] += 1;
        }
        for c in 0..n {
            start[c + 1] += start[c];
        }
        let mut order = vec![0usize; cols.len()];
        let mut next = start.clone();
        for (k, &c) in cols.iter().enumerate() {
            order[next[c]] = k;
            next[c] += 1;
        }
        let mut colptr = vec![0usize; n + 1];
        let mut rowval = Vec::with_capacity(cols.len());
        let mut slot = vec![0usize; cols.len()];
        for c in 0..n {
            let col = &mut order[start[c]..start[c + 1]];
            col.sort_unstable_by_key(|&k| (rows[k], k));
            let mut last = None;
            for &k in col.iter() {
                if last != Some(rows[k]) {
                    rowval.push(rows[k]);
                    last = Some(rows[k]);
                }
                slot[k] = rowval.len() - 1;
            }
            colptr[c + 1] = rowval.len();
        }
        Self {
            m,
            n,
            colptr,
            rowval,
            slot,
        }
    }

    /// Number of distinct entries.
    pub fn nnz(&self) -> usize {
        self.rowval.len()
    }

    /// The entry of triplet `k`.
    pub fn slot(&self, k: usize) -> usize {
        self.slot[k]
    }

    /// Add `scale · vals[k]` to the entry of each triplet `k` (duplicates are summed, in
    /// triplet order).
    pub fn accumulate(&self, nz: &mut [f64], vals: &[f64], scale: f64) {
        for (k, v) in vals.iter().enumerate() {
            nz[self.slot[k]] += scale * v;
        }
    }

    /// The matrix with the entries `nz`.
    pub fn matrix(&self, nz: Vec<f64>) -> CscMatrix<f64> {
        CscMatrix::new(self.m, self.n, self.colptr.clone(), self.rowval.clone(), nz)
    }
}

/// Compressed sparse column matrix from triplets, summing duplicates.
pub fn csc(m: usize, n: usize, t: &Triplets) -> CscMatrix<f64> {
    let pattern = CscPattern::new(m, n, &t.rows, &t.cols);
    let mut nz = vec![0.0; pattern.nnz()];
    pattern.accumulate(&mut nz, &t.vals, 1.0);
    pattern.matrix(nz)
}

/// Data of one QP subproblem.
pub struct QpData<'a> {
    /// Hessian (upper triangle entries; lower ones are ignored).
    pub h: &'a Triplets,
    /// Objective gradient.
    pub g: &'a [f64],
    /// Constraint Jacobian.
    pub jac: &'a Triplets,
    /// Constraint values at the current point.
    pub c: &'a [f64],
    /// Constraint bounds.
    pub c_lb: &'a [f64],
    /// Constraint upper bounds.
    pub c_ub: &'a [f64],
    /// Step bounds `w_lb − w`.
    pub d_lb: &'a [f64],
    /// Step upper bounds `w_ub − w`.
    pub d_ub: &'a [f64],
    /// Elastic penalty ρ (None = plain QP).
    pub elastic: Option<f64>,
    /// Per-row multipliers of ρ in elastic mode.
    pub elastic_weights: &'a [f64],
    /// The multipliers (λ of the rows, ν of the bounds) of a previous QP of the same
    /// shape, the last SQP iteration's: the rows and bounds they hold are the first guess
    /// of this QP's active set ([`solve`]).
    pub hint: Option<ActiveHint<'a>>,
}

/// The multipliers of a previous QP of the same shape (Lagrangian `f + λᵀc + νᵀw`): a
/// row or bound with a positive multiplier held its upper bound, with a negative one its
/// lower bound.
#[derive(Debug, Clone, Copy)]
pub struct ActiveHint<'a> {
    /// Constraint multipliers λ.
    pub lambda: &'a [f64],
    /// Bound multipliers ν.
    pub nu: &'a [f64],
}

/// Solution of a QP subproblem.
#[derive(Debug, Clone)]
pub struct QpSolution {
    /// Step.
    pub d: Vec<f64>,
    /// Constraint multipliers λ (Lagrangian `f + λᵀc + νᵀw`).
    pub lambda: Vec<f64>,
    /// Bound multipliers ν.
    pub nu: Vec<f64>,
    /// Linearised l1 violation after the step (elastic slacks), 0 for a plain QP.
    pub elastic_violation: f64,
    /// Clarabel iterations (0: solved on the guessed active set, without Clarabel).
    pub iterations: u32,
}

/// QP failure.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum QpError {
    /// The linearised constraints are inconsistent.
    #[error("QP subproblem infeasible")]
    Infeasible,
    /// Clarabel stopped without a solution.
    #[error("QP solver stopped with status {0}")]
    Failed(String),
}

enum RowMap {
    /// constraint row i, sign
    Con(usize, f64),
    /// variable j, sign
    Var(usize, f64),
    /// slack variable column
    Slack,
}

/// Solve a QP subproblem: given a [`QpData::hint`], first on the active set the previous
/// QP held (one sparse LDLᵀ, `sqp::qp::active_set`; across SQP iterations the active
/// set mostly stays), else with Clarabel.
pub fn solve(q: &QpData<'_>) -> Result<QpSolution, QpError> {
    let jrows = rows_of(q);
    let guessed = q
        .hint
        .and_then(|hint| active_set::solve(q, &jrows, active_set::Guess::Held(hint)));
    match guessed {
        Some(sol) => Ok(sol),
        None => interior_point(q, &jrows),
    }
}

/// Solve a QP subproblem asked at a solution (a Gauss–Newton model's steps and probes):
/// first on the active set guessed from the bounds and rows that hold at the point (one
/// sparse LDLᵀ, `sqp::qp::active_set`), which settles on the QP's KKT point
/// in a few corrections when the point is a solution of a nearby problem; else with
/// Clarabel. Inside the SQP's iterations this guess rarely holds (a step moves the
/// point off the rows it reaches); there [`solve`] guesses from the last QP's multipliers.
pub fn solve_near_solution(q: &QpData<'_>) -> Result<QpSolution, QpError> {
    let jrows = rows_of(q);
    match active_set::solve(q, &jrows, active_set::Guess::AtPoint) {
        Some(sol) => Ok(sol),
        None => interior_point(q, &jrows),
    }
}

/// The entries of J by constraint row.
fn rows_of(q: &QpData<'_>) -> Vec<Vec<(usize, f64)>> {
    let mut jrows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); q.c.len()];
    for k in 0..q.jac.vals.len() {
        jrows[q.jac.rows[k]].push((q.jac.cols[k], q.jac.vals[k]));
    }
    jrows
}

/// Solve a QP subproblem with Clarabel (`jrows`: the entries of J by row).
fn interior_point(q: &QpData<'_>, jrows: &[Vec<(usize, f64)>]) -> Result<QpSolution, QpError> {
    let rows = ConeRows::new(q, jrows);
    let sol = rows.solve(q)?;
    Ok(rows.solution(q, &sol))
}

/// The QP's rows in Clarabel's form `A d + s = b`: equality rows (and fixed variables) in
/// the zero cone, each finite inequality bound as one row of the nonnegative cone, and in
/// elastic mode the slacks' own rows; each with the multiplier it gives.
struct ConeRows {
    /// Number of variables.
    n: usize,
    /// Number of constraints.
    m: usize,
    /// Number of elastic slacks (two per constraint in elastic mode, else none).
    ns: usize,
    eq: Triplets,
    eq_b: Vec<f64>,
    eq_map: Vec<RowMap>,
    ineq: Triplets,
    ineq_b: Vec<f64>,
    ineq_map: Vec<RowMap>,
}

impl ConeRows {
    /// The rows of `q` (`jrows`: the entries of J by row).
    fn new(q: &QpData<'_>, jrows: &[Vec<(usize, f64)>]) -> Self {
        let n = q.g.len();
        let m = q.c.len();
        let ns = if q.elastic.is_some() { 2 * m } else { 0 };
        let mut rows = Self {
            n,
            m,
            ns,
            eq: Triplets::default(),
            eq_b: Vec::new(),
            eq_map: Vec::new(),
            ineq: Triplets::default(),
            ineq_b: Vec::new(),
            ineq_map: Vec::new(),
        };
        rows.add_constraints(q, jrows);
        rows.add_bounds(q);
        for s in 0..ns {
            let r = rows.ineq_b.len();
            rows.ineq.push(r, n + s, -1.0);
            rows.ineq_b.push(0.0);
            rows.ineq_map.push(RowMap::Slack);
        }
        rows
    }

    /// The constraint rows `c_lb − c ≤ J d ≤ c_ub − c`, in elastic mode with their slacks.
    fn add_constraints(&mut self, q: &QpData<'_>, jrows: &[Vec<(usize, f64)>]) {
        let n = self.n;
        for i in 0..self.m {
            let (lo, hi) = (q.c_lb[i] - q.c[i], q.c_ub[i] - q.c[i]);
            let slack = |t: &mut Triplets, r: usize| {
                if q.elastic.is_some() {
                    // J d − p + n
                    t.push(r, n + 2 * i, -1.0);
                    t.push(r, n + 2 * i + 1, 1.0);
                }
            };
            if q.c_lb[i] == q.c_ub[i] {
                let r = self.eq_b.len();
                for &(c, v) in &jrows[i] {
                    self.eq.push(r, c, v);
                }
                slack(&mut self.eq, r);
                self.eq_b.push(lo);
                self.eq_map.push(RowMap::Con(i, 1.0));
            } else {
                if hi.is_finite() {
                    let r = self.ineq_b.len();
                    for &(c, v) in &jrows[i] {
                        self.ineq.push(r, c, v);
                    }
                    slack(&mut self.ineq, r);
                    self.ineq_b.push(hi);
                    self.ineq_map.push(RowMap::Con(i, 1.0));
                }
                if lo.is_finite() {
                    let r = self.ineq_b.len();
                    for &(c, v) in &jrows[i] {
                        self.ineq.push(r, c, -v);
                    }
                    if q.elastic.is_some() {
                        self.ineq.push(r, n + 2 * i, 1.0);
                        self.ineq.push(r, n + 2 * i + 1, -1.0);
                    }
                    self.ineq_b.push(-lo);
                    self.ineq_map.push(RowMap::Con(i, -1.0));
                }
            }
        }
    }

    /// The variable bound rows `d_lb ≤ d ≤ d_ub` (a fixed variable as an equality).
    fn add_bounds(&mut self, q: &QpData<'_>) {
        for j in 0..self.n {
            if q.d_lb[j] == q.d_ub[j] {
                let r = self.eq_b.len();
                self.eq.push(r, j, 1.0);
                self.eq_b.push(q.d_lb[j]);
                self.eq_map.push(RowMap::Var(j, 1.0));
            } else {
                if q.d_ub[j].is_finite() {
                    let r = self.ineq_b.len();
                    self.ineq.push(r, j, 1.0);
                    self.ineq_b.push(q.d_ub[j]);
                    self.ineq_map.push(RowMap::Var(j, 1.0));
                }
                if q.d_lb[j].is_finite() {
                    let r = self.ineq_b.len();
                    self.ineq.push(r, j, -1.0);
                    self.ineq_b.push(-q.d_lb[j]);
                    self.ineq_map.push(RowMap::Var(j, -1.0));
                }
            }
        }
    }

    /// Clarabel's solution of the QP `q` on these rows: tight tolerances first (the SQP's
    /// KKT test needs accurate multipliers), Clarabel's defaults as a fallback when it
    /// stalls, then a robust attempt.
    fn solve(&self, q: &QpData<'_>) -> Result<DefaultSolution<f64>, QpError> {
        let (n, m, ns) = (self.n, self.m, self.ns);
        let nt = n + ns;
        let (neq, nin) = (self.eq_b.len(), self.ineq_b.len());
        let mut a = self.eq.clone();
        for k in 0..self.ineq.vals.len() {
            a.push(
                self.ineq.rows[k] + neq,
                self.ineq.cols[k],
                self.ineq.vals[k],
            );
        }
        let mut b = self.eq_b.clone();
        b.extend(self.ineq_b.iter().copied());
        let mut p = Triplets::default();
        for k in 0..q.h.vals.len() {
            let (r, c) = (q.h.rows[k], q.h.cols[k]);
            if r <= c {
                p.push(r, c, q.h.vals[k]);
            }
        }
        let mut qv = q.g.to_vec();
        if let Some(rho) = q.elastic {
            for i in 0..m {
                let w = q.elastic_weights.get(i).copied().unwrap_or(1.0);
                qv.push(rho * w);
                qv.push(rho * w);
            }
        }
        let pm = csc(nt, nt, &p);
        let am = csc(neq + nin, nt, &a);
        let cones = [
            SupportedConeT::ZeroConeT(neq),
            SupportedConeT::NonnegativeConeT(nin),
        ];
        // tight tolerances first (the SQP's KKT test needs accurate multipliers); Clarabel's
        // defaults as a fallback when it stalls
        let mut last = String::new();
        // a third attempt for ill-conditioned QPs: stronger static regularisation of the KKT
        // factorisation, more iterative refinement and more iterations
        for (tol, robust) in [(1e-10, false), (1e-8, false), (1e-8, true)] {
            let mut solver = DefaultSolver::new(&pm, &qv, &am, &b, &cones, settings(tol, robust))
                .map_err(|e| QpError::Failed(e.to_string()))?;
            // a solve asked to stop ends the QP at its next iteration
            solver.set_termination_callback(|_| crate::interrupt::stop_now());
            solver.solve();
            let sol = solver.solution;
            match sol.status {
                SolverStatus::CallbackTerminated => {
                    return Err(QpError::Failed(crate::interrupt::STOPPED.into()))
                }
                SolverStatus::Solved | SolverStatus::AlmostSolved => {
                    return Ok(sol);
                }
                SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                    return Err(QpError::Infeasible)
                }
                SolverStatus::InsufficientProgress
                | SolverStatus::MaxIterations
                | SolverStatus::NumericalError
                    if sol.r_prim < 1e-7 && sol.r_dual < 1e-7 =>
                {
                    return Ok(sol);
                }
                other => {
                    last = format!(
                        "{other:?} (primal residual {:.1e}, dual residual {:.1e})",
                        sol.r_prim, sol.r_dual
                    )
                }
            }
        }
        Err(QpError::Failed(last))
    }

    /// The step and the multipliers of `q` from Clarabel's solution `sol` on these rows.
    fn solution(&self, q: &QpData<'_>, sol: &DefaultSolution<f64>) -> QpSolution {
        let (n, m, ns) = (self.n, self.m, self.ns);
        let mut lambda = vec![0.0; m];
        let mut nu = vec![0.0; n];
        for (r, map) in self.eq_map.iter().chain(self.ineq_map.iter()).enumerate() {
            let z = sol.z[r];
            match *map {
                RowMap::Con(i, s) => lambda[i] += s * z,
                RowMap::Var(j, s) => nu[j] += s * z,
                RowMap::Slack => {}
            }
        }
        let elastic_violation = (0..ns)
            .map(|s| sol.x[n + s].max(0.0) * q.elastic_weights.get(s / 2).copied().unwrap_or(1.0))
            .sum();
        QpSolution {
            d: sol.x[..n].to_vec(),
            lambda,
            nu,
            elastic_violation,
            iterations: sol.iterations,
        }
    }
}

/// Clarabel's settings for an attempt at tolerance `tol`; `robust`: stronger static
/// regularisation of the KKT factorisation, more iterative refinement and more iterations.
fn settings(tol: f64, robust: bool) -> DefaultSettings<f64> {
    let base = DefaultSettings::<f64>::default();
    DefaultSettings {
        verbose: false,
        max_threads: 1,
        tol_gap_abs: tol,
        tol_gap_rel: tol,
        tol_feas: tol,
        max_iter: if robust { 500 } else { 200 },
        presolve_enable: false,
        static_regularization_constant: if robust {
            1e-6
        } else {
            base.static_regularization_constant
        },
        iterative_refinement_max_iter: if robust {
            50
        } else {
            base.iterative_refinement_max_iter
        },
        ..base
    }
}
