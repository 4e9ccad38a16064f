//! What the SQP's parts share while it iterates: the NLP's fixed structure, read once per
//! solve, and the current iterate.

use super::qp::Triplets;
use super::{Nlp, NlpEval, SqpSettings};

/// What the SQP reads from the NLP once per solve: sizes, bounds, sparsity patterns and
/// row weights.
#[derive(Debug, Clone, Default)]
pub(super) struct Structure {
    /// Number of variables.
    pub(super) n: usize,
    /// Number of constraints.
    pub(super) m: usize,
    /// Variable lower bounds.
    pub(super) w_lb: Vec<f64>,
    /// Variable upper bounds.
    pub(super) w_ub: Vec<f64>,
    /// Constraint lower bounds.
    pub(super) c_lb: Vec<f64>,
    /// Constraint upper bounds.
    pub(super) c_ub: Vec<f64>,
    /// Jacobian pattern rows.
    pub(super) jac_rows: Vec<usize>,
    /// Jacobian pattern columns.
    pub(super) jac_cols: Vec<usize>,
    /// Gauss–Newton Hessian pattern rows (upper triangle).
    pub(super) gn_rows: Vec<usize>,
    /// Gauss–Newton Hessian pattern columns.
    pub(super) gn_cols: Vec<usize>,
    /// Elastic-mode weights of the rows' violations.
    pub(super) elastic_weights: Vec<f64>,
    /// Rows whose exact curvature the quasi-Newton modes use
    /// ([`SqpSettings::exact_term_hessians`]); the BFGS update leaves them out.
    pub(super) exact_rows: Vec<bool>,
    /// Whether any row is in `exact_rows`.
    pub(super) any_exact: bool,
}

impl Structure {
    pub(super) fn new(nlp: &dyn Nlp, settings: &SqpSettings) -> Self {
        let (n, m) = (nlp.n(), nlp.m());
        let (w_lb, w_ub, c_lb, c_ub) = nlp.bounds();
        let (jac_rows, jac_cols) = nlp.jacobian_pattern();
        let elastic_weights = nlp.elastic_weights();
        let exact_rows = if settings.exact_term_hessians {
            nlp.rows_with_exact_hessian()
        } else {
            vec![false; m]
        };
        let any_exact = exact_rows.iter().any(|&r| r);
        let (gn_rows, gn_cols) = nlp.gauss_newton_pattern();
        Self {
            n,
            m,
            w_lb,
            w_ub,
            c_lb,
            c_ub,
            jac_rows,
            jac_cols,
            gn_rows,
            gn_cols,
            elastic_weights,
            exact_rows,
            any_exact,
        }
    }

    /// The Jacobian with values `vals` (in pattern order).
    pub(super) fn jacobian(&self, vals: &[f64]) -> Triplets {
        Triplets {
            rows: self.jac_rows.clone(),
            cols: self.jac_cols.clone(),
            vals: vals.to_vec(),
        }
    }
}

/// The current iterate.
pub(super) struct State {
    /// Variables.
    pub(super) w: Vec<f64>,
    /// Evaluation with derivatives at `w`.
    pub(super) ev: NlpEval,
    /// Exact constraint curvature at `w` (Exact mode).
    pub(super) hess: Option<Triplets>,
    /// Objective and l1 violation from a plain evaluation at `w`: the line search compares
    /// trial points (plain evaluations) with these, so that integrator noise, which differs
    /// between runs with and without sensitivity error control, cannot mislead it.
    pub(super) plain: (f64, f64),
}
