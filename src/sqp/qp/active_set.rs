//! The QP subproblem solved on a guessed active set: one sparse LDLᵀ instead of an
//! interior-point solve.
//!
//! Near a solution, and in every question asked at one (a score test's Gauss–Newton
//! steps, the identifiability probes), the bounds and inequality rows that hold at the
//! step are those that hold at the point; from one SQP iteration to the next, they are
//! mostly those the last QP held (its multipliers). The QP restricted to them is an
//! equality-constrained QP: one factorisation of its KKT matrix
//! $\begin{pmatrix} H & A^T \\ A & 0 \end{pmatrix}$, where Clarabel factorises a larger
//! one 10–25 times. The guess is corrected for a few rounds, in the manner of a
//! primal-dual active-set method (a violated bound or row joins the set, an active one
//! whose multiplier has the wrong sign leaves it), and the result is accepted only when
//! the QP's KKT conditions hold: primal feasibility, multipliers of the right sign, and
//! the reduced Hessian positive definite on the active set (the factorisation's
//! inertia). It is then the QP's solution (its only one when H is convex), to the
//! precision of the factorisation with iterative refinement. Otherwise the caller solves
//! the QP with Clarabel, so a wrong guess costs time, never a different answer.

use super::{ActiveHint, CscPattern, QpData, QpSolution};
use clarabel::qdldl::{QDLDLFactorisation, QDLDLSettings};

/// How a bound pair holds in the guess.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Held {
    /// Inactive.
    Free,
    /// At its lower bound.
    Lower,
    /// At its upper bound.
    Upper,
    /// An equality (lower and upper bound are one value).
    Fixed,
}

/// Rounds of corrections to the guessed active set before the interior-point solver
/// takes over.
const ROUNDS: usize = 4;
/// A bound or row counts as holding at the point when its distance to the bound is at
/// most this (relative to 1 + |bound|): the interior-point solver stops within about
/// 1e-10 of a bound it reaches.
const AT_BOUND: f64 = 1e-8;
/// Primal feasibility of the inactive bounds and rows (relative to 1 + |bound|).
const FEASIBLE: f64 = 1e-9;
/// A multiplier has the wrong sign beyond this fraction of the largest one.
const SIGN: f64 = 1e-9;
/// Static regularisations of the KKT matrix (relative to its largest entry), tried in
/// turn, removed by iterative refinement against the unregularised matrix. Each
/// refinement step shrinks the error by about δ / (δ + |λ|min(K)): an SQP's QP whose
/// reduced Hessian has curvature near the Hessian's own regularisation (a quasi-Newton
/// model along directions it has not yet seen) has |λ|min(K) near 1e-8, where δ = 1e-10
/// of the largest entry stalled the refinement and left most of the CasADi gait peer's
/// QPs to Clarabel; held rows that repeat each other (an equality row the other held
/// rows imply) leave pivots near −δ, whose growth at the smaller δ the larger one tames.
/// (A row whose variables held bounds all fix is kept out of the matrix.)
const REGULARISATIONS: [f64; 2] = [1e-13, 1e-10];
/// Iterative refinement steps at most, and the residual it must reach (relative to the
/// right-hand side and the products making up the matrix–vector product).
const REFINEMENTS: usize = 10;
const RESIDUAL: f64 = 1e-12;
/// A refinement that stops converging is accepted at this residual (relative as
/// [`RESIDUAL`]): Clarabel's own tolerances are 1e-10 on scaled residuals.
const STALLED: f64 = 1e-9;

/// A held row or bound is met when the step reaches it within a tolerance relative to
/// 1 + |bound| + the largest of the row's products `J_ij d_j`. Held rows that contradict
/// each other (an inconsistent linearisation) miss by about the constraint error; rows
/// that repeat each other stall the refinement at its round-off, a few 1e-9 on the
/// tracks' score tests. An SQP step meets its rows within `MET_STEP`: near convergence,
/// looser steps leave errors the line search's merit function sees (the five-link
/// biped's solve stops in its line search at 1e-8).
const MET_STEP: f64 = 1e-9;
/// A question asked at a solution (a Gauss–Newton step or probe) meets its rows within
/// `MET_QUESTION`, Clarabel's own feasibility tolerance.
const MET_QUESTION: f64 = 1e-8;

/// One held bound or row of the equality-constrained QP.
#[derive(Debug, Clone, Copy)]
enum Row {
    /// Constraint row `i` of the QP's Jacobian.
    Constraint(usize),
    /// Variable `j`'s bound.
    Variable(usize),
}

/// A multiplier of a previous QP counts as holding its bound beyond this fraction of the
/// largest one (an interior-point solution leaves the free ones near zero, not at it).
const HELD: f64 = 1e-8;

/// Where the first guess of the active set comes from.
#[derive(Debug, Clone, Copy)]
pub(super) enum Guess<'a> {
    /// The bounds and rows that hold at the point (a question asked at a solution).
    AtPoint,
    /// The bounds and rows a previous QP of the same shape held (its multipliers).
    Held(ActiveHint<'a>),
}

/// The QP `q` (not in elastic mode) on the active set guessed by `guess`, or `None` when
/// the guess does not settle on a KKT point within [`ROUNDS`] (the caller then solves it
/// with the interior-point solver). `jrows` holds the entries of each constraint row.
pub(super) fn solve(
    q: &QpData<'_>,
    jrows: &[Vec<(usize, f64)>],
    guess: Guess<'_>,
) -> Option<QpSolution> {
    let (n, m) = (q.g.len(), q.c.len());
    if q.elastic.is_some() {
        return None;
    }
    let met_within = match guess {
        Guess::AtPoint => MET_QUESTION,
        Guess::Held(_) => MET_STEP,
    };
    let (mut rows, mut vars) = match guess {
        Guess::AtPoint => held_at_point(q),
        Guess::Held(hint) if hint.lambda.len() == m && hint.nu.len() == n => {
            held_by_multipliers(q, hint)
        }
        Guess::Held(_) => return None,
    };
    let lo = |i: usize| q.c_lb[i] - q.c[i];
    let hi = |i: usize| q.c_ub[i] - q.c[i];
    // the Hessian's upper triangle, as Clarabel reads it
    let h: Vec<(usize, usize, f64)> = (0..q.h.vals.len())
        .filter(|&k| q.h.rows[k] <= q.h.cols[k])
        .map(|k| (q.h.rows[k], q.h.cols[k], q.h.vals[k]))
        .collect();
    let scale = h
        .iter()
        .map(|t| t.2.abs())
        .chain(q.jac.vals.iter().map(|v| v.abs()))
        .fold(1.0f64, f64::max);
    for _ in 0..ROUNDS {
        let held: Vec<(Row, f64)> = (0..m)
            .filter_map(|i| match rows[i] {
                Held::Free => None,
                Held::Upper => Some((Row::Constraint(i), hi(i))),
                Held::Lower | Held::Fixed => Some((Row::Constraint(i), lo(i))),
            })
            .chain((0..n).filter_map(|j| match vars[j] {
                Held::Free => None,
                Held::Upper => Some((Row::Variable(j), q.d_ub[j])),
                Held::Lower | Held::Fixed => Some((Row::Variable(j), q.d_lb[j])),
            }))
            .collect();
        // a held row whose variables the held bounds all fix repeats them (its value is
        // theirs): it stays out of the KKT matrix, which it would make singular, and is
        // checked with the others below
        let solved: Vec<(Row, f64)> = held
            .iter()
            .copied()
            .filter(|&(row, _)| match row {
                Row::Constraint(i) => jrows[i].iter().any(|&(j, _)| vars[j] == Held::Free),
                Row::Variable(_) => true,
            })
            .collect();
        let x = solve_equality_qp(q, jrows, &h, &solved, scale)?;
        let (d, y) = x.split_at(n);
        // the step on the rows, for the feasibility of the inactive ones
        let jd: Vec<f64> = jrows
            .iter()
            .map(|r| r.iter().map(|&(j, v)| v * d[j]).sum())
            .collect();
        // the held rows met: rows that contradict each other (an inconsistent
        // linearisation) leave a KKT matrix the refinement solves only relative to its huge
        // multipliers, and are the interior-point solver's to call infeasible
        let met = held.iter().all(|&(row, b)| {
            let (value, terms) = match row {
                Row::Constraint(i) => (jd[i], row_terms(&jrows[i], d)),
                Row::Variable(j) => (d[j], d[j].abs()),
            };
            (value - b).abs() <= met_within * (1.0 + b.abs() + terms)
        });
        if !met {
            return None;
        }
        // the multipliers by row and by variable (0 where nothing is held)
        let mut lambda = vec![0.0; m];
        let mut nu = vec![0.0; n];
        for (&(row, _), &y) in solved.iter().zip(y) {
            match row {
                Row::Constraint(i) => lambda[i] = y,
                Row::Variable(j) => nu[j] = y,
            }
        }
        let largest = y.iter().fold(1.0f64, |a, v| a.max(v.abs()));
        let mut changed = false;
        let mut update = |state: &mut Held, value: f64, lower: f64, upper: f64, y: f64| {
            let next = match *state {
                Held::Upper if y < -SIGN * largest => Held::Free,
                Held::Lower if y > SIGN * largest => Held::Free,
                Held::Free if value > upper + FEASIBLE * (1.0 + upper.abs()) => Held::Upper,
                Held::Free if value < lower - FEASIBLE * (1.0 + lower.abs()) => Held::Lower,
                s => s,
            };
            changed |= next != *state;
            *state = next;
        };
        for i in 0..m {
            update(&mut rows[i], jd[i], lo(i), hi(i), lambda[i]);
        }
        for j in 0..n {
            update(&mut vars[j], d[j], q.d_lb[j], q.d_ub[j], nu[j]);
        }
        if changed {
            continue;
        }
        // within FEASIBLE of its bounds: clamp, so that the point stays in the box
        let d = (0..n).map(|j| d[j].max(q.d_lb[j]).min(q.d_ub[j])).collect();
        return Some(QpSolution {
            d,
            lambda,
            nu,
            elastic_violation: 0.0,
            iterations: 0,
        });
    }
    None
}

/// The largest of the products `J_ij d_j` of a row with `entries` (the size of the terms
/// its value sums).
fn row_terms(entries: &[(usize, f64)], d: &[f64]) -> f64 {
    entries
        .iter()
        .fold(0.0f64, |a, &(j, v)| a.max((v * d[j]).abs()))
}

/// The rows and bounds of `q` that hold at the point (within [`AT_BOUND`]).
fn held_at_point(q: &QpData<'_>) -> (Vec<Held>, Vec<Held>) {
    let near = |distance: f64, bound: f64| distance.abs() <= AT_BOUND * (1.0 + bound.abs());
    // `lower`, `upper`: the distances to the bounds `l`, `u`
    let guess = |lower: f64, upper: f64, l: f64, u: f64| {
        if l == u {
            Held::Fixed
        } else if upper.is_finite() && near(upper, u) {
            Held::Upper
        } else if lower.is_finite() && near(lower, l) {
            Held::Lower
        } else {
            Held::Free
        }
    };
    let rows = (0..q.c.len())
        .map(|i| guess(q.c_lb[i] - q.c[i], q.c_ub[i] - q.c[i], q.c_lb[i], q.c_ub[i]))
        .collect();
    let vars = (0..q.g.len())
        .map(|j| guess(q.d_lb[j], q.d_ub[j], q.d_lb[j], q.d_ub[j]))
        .collect();
    (rows, vars)
}

/// The rows and bounds of `q` whose multipliers in `hint` hold them (beyond [`HELD`] of
/// the largest), on the side their sign gives; equalities always.
fn held_by_multipliers(q: &QpData<'_>, hint: ActiveHint<'_>) -> (Vec<Held>, Vec<Held>) {
    let largest = hint
        .lambda
        .iter()
        .chain(hint.nu)
        .fold(1.0f64, |a, v| a.max(v.abs()));
    let guess = |y: f64, l: f64, u: f64| {
        if l == u {
            Held::Fixed
        } else if y > HELD * largest && u.is_finite() {
            Held::Upper
        } else if y < -HELD * largest && l.is_finite() {
            Held::Lower
        } else {
            Held::Free
        }
    };
    let rows = (0..q.c.len())
        .map(|i| guess(hint.lambda[i], q.c_lb[i], q.c_ub[i]))
        .collect();
    let vars = (0..q.g.len())
        .map(|j| guess(hint.nu[j], q.d_lb[j], q.d_ub[j]))
        .collect();
    (rows, vars)
}

/// The solution `(d, y)` of `H d + Aᵀ y = −g`, `A d = b` for the held rows `held`
/// (`(row, b)`) at the first of [`REGULARISATIONS`] (times `scale`) that gives it, or
/// `None` when the reduced Hessian is not positive definite on them or the refinement
/// does not reach [`RESIDUAL`].
fn solve_equality_qp(
    q: &QpData<'_>,
    jrows: &[Vec<(usize, f64)>],
    h: &[(usize, usize, f64)],
    held: &[(Row, f64)],
    scale: f64,
) -> Option<Vec<f64>> {
    REGULARISATIONS
        .iter()
        .find_map(|&r| solve_regularised(q, jrows, h, held, r * scale))
}

/// [`solve_equality_qp`] with the static regularisation `delta`.
fn solve_regularised(
    q: &QpData<'_>,
    jrows: &[Vec<(usize, f64)>],
    h: &[(usize, usize, f64)],
    held: &[(Row, f64)],
    delta: f64,
) -> Option<Vec<f64>> {
    let n = q.g.len();
    let size = n + held.len();
    // the upper triangle of the regularised KKT matrix, as triplets
    let (mut r, mut c, mut v) = (Vec::new(), Vec::new(), Vec::new());
    let mut push = |i: usize, j: usize, x: f64| {
        r.push(i);
        c.push(j);
        v.push(x);
    };
    for &(i, j, x) in h {
        push(i, j, x);
    }
    for j in 0..n {
        push(j, j, delta);
    }
    let entries = |row: Row| -> Vec<(usize, f64)> {
        match row {
            Row::Constraint(i) => jrows[i].clone(),
            Row::Variable(j) => vec![(j, 1.0)],
        }
    };
    let a: Vec<Vec<(usize, f64)>> = held.iter().map(|&(row, _)| entries(row)).collect();
    for (k, row) in a.iter().enumerate() {
        for &(j, x) in row {
            push(j, n + k, x);
        }
        push(n + k, n + k, -delta);
    }
    let pattern = CscPattern::new(size, size, &r, &c);
    let mut nz = vec![0.0; pattern.nnz()];
    pattern.accumulate(&mut nz, &v, 1.0);
    let settings = QDLDLSettings {
        regularize_enable: false,
        ..Default::default()
    };
    let mut factor = QDLDLFactorisation::new(&pattern.matrix(nz), Some(settings)).ok()?;
    // n positive pivots (Sylvester's law of inertia, whatever the order): the Hessian is
    // positive definite on the null space of the held rows, and the point is a strict
    // local minimum of the QP on them
    if factor.positive_inertia() != n || !factor.D.iter().all(|d| d.is_finite() && *d != 0.0) {
        return None;
    }
    let mut rhs: Vec<f64> = q.g.iter().map(|g| -g).collect();
    rhs.extend(held.iter().map(|&(_, b)| b));
    // the unregularised product K x, and the size of its terms (for the tolerance)
    let product = |x: &[f64]| -> (Vec<f64>, f64) {
        let mut y = vec![0.0; size];
        let mut terms = 0.0f64;
        for &(i, j, v) in h {
            y[i] += v * x[j];
            terms = terms.max((v * x[j]).abs());
            if i != j {
                y[j] += v * x[i];
                terms = terms.max((v * x[i]).abs());
            }
        }
        for (k, row) in a.iter().enumerate() {
            for &(j, v) in row {
                y[j] += v * x[n + k];
                y[n + k] += v * x[j];
                terms = terms.max((v * x[n + k]).abs()).max((v * x[j]).abs());
            }
        }
        (y, terms)
    };
    let mut x = rhs.clone();
    factor.solve(&mut x);
    let size_of = |v: &[f64]| v.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let mut last = f64::INFINITY;
    for _ in 0..=REFINEMENTS {
        if !x.iter().all(|v| v.is_finite()) {
            return None;
        }
        let (kx, terms) = product(&x);
        let mut res: Vec<f64> = rhs.iter().zip(&kx).map(|(b, k)| b - k).collect();
        let (size, scale) = (size_of(&res), 1.0 + size_of(&rhs) + terms);
        // refined to the round-off, or stalled (rows held twice, e.g. an equality row
        // the other held rows imply, whose right-hand sides differ by the point's
        // constraint error) within what the interior-point solver would leave
        if size <= RESIDUAL * scale || (size > 0.5 * last && size <= STALLED * scale) {
            return Some(x);
        }
        last = size;
        factor.solve(&mut res);
        for (xi, ri) in x.iter_mut().zip(&res) {
            *xi += ri;
        }
    }
    None
}
