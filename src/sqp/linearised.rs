//! The Gauss–Newton model of a least-squares NLP at a point, for questions asked at a
//! solution rather than while solving: how far would the cost fall if some variables
//! were freed (a score test), and how uncertain are identified parameters.
//!
//! Both come from the QP of one Gauss–Newton SQP step,
//! $\min_d\ g^T d + \tfrac12 d^T H d$ s.t. the linearised constraints and bounds, with
//! $H = 2 J_r^T J_r$ for $f = \|r\|^2$: the step itself, and the inverse of $H$ reduced
//! to the constraints active at the step, from equality-constrained QPs on those
//! constraints.

use super::qp::{self, QpData, QpError, Triplets};
use super::{EvalError, Nlp, NlpEval};

/// Why the Gauss–Newton model cannot be built or asked.
#[derive(Debug, thiserror::Error)]
pub enum LinearisedError {
    /// The NLP cannot be evaluated at the point.
    #[error("{}", .0.chain())]
    Evaluation(#[source] EvalError),
    /// A QP of the model (a step or a column of the reduced inverse) failed.
    #[error(transparent)]
    Qp(#[from] QpError),
    /// The step given is not one of this model (its sizes differ from the model's).
    #[error("the step is not one of this model")]
    ForeignStep,
    /// A column asked for is not a variable of the NLP.
    #[error("column {column} is not a variable (n = {n})")]
    Column {
        /// The column asked for.
        column: usize,
        /// Number of variables.
        n: usize,
    },
}

/// One Gauss–Newton step at a point.
#[derive(Debug, Clone)]
pub struct GaussNewtonStep {
    /// The step.
    pub d: Vec<f64>,
    /// Decrease of the quadratic model, $-(g^T d + \tfrac12 d^T H d)$.
    pub predicted_decrease: f64,
    /// The QP's constraint multipliers (one per NLP constraint).
    pub lambda: Vec<f64>,
    /// The QP's bound multipliers (one per variable).
    pub nu: Vec<f64>,
}

/// The Gauss–Newton model at `w` (evaluated once, with derivatives).
pub struct GaussNewtonModel<'a> {
    nlp: &'a dyn Nlp,
    w: Vec<f64>,
    ev: NlpEval,
    h: Triplets,
    jac: Triplets,
    bounds: (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>),
}

impl<'a> GaussNewtonModel<'a> {
    /// Evaluate `nlp` at `w` (clamped into its bounds). `regularization` (≥ 0) is added
    /// to the diagonal of H, relative to its largest entry, so variables the cost does not
    /// see (e.g. a parameter with no effect) stay put instead of making the QP singular.
    pub fn new(nlp: &'a dyn Nlp, w: &[f64], regularization: f64) -> Result<Self, LinearisedError> {
        let bounds = nlp.bounds();
        let w: Vec<f64> = w
            .iter()
            .zip(bounds.0.iter().zip(&bounds.1))
            .map(|(&v, (&l, &u))| v.max(l).min(u))
            .collect();
        let ev = nlp
            .evaluate(&w, true)
            .map_err(LinearisedError::Evaluation)?;
        let (hr, hc) = nlp.gauss_newton_pattern();
        let mut h = Triplets {
            rows: hr,
            cols: hc,
            vals: ev.gn.clone(),
        };
        let hmax = h.vals.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-12);
        for i in 0..nlp.n() {
            h.push(i, i, regularization * hmax);
        }
        let (jr, jc) = nlp.jacobian_pattern();
        let jac = Triplets {
            rows: jr,
            cols: jc,
            vals: ev.jac.clone(),
        };
        Ok(Self {
            nlp,
            w,
            ev,
            h,
            jac,
            bounds,
        })
    }

    /// Objective at the point.
    pub fn objective(&self) -> f64 {
        self.ev.f
    }

    /// The point (clamped into the bounds).
    pub fn point(&self) -> &[f64] {
        &self.w
    }

    /// The step from the point with the objective gradient plus `gradient_shift` (if
    /// any). The shift probes the inverse of the reduced Hessian: with `ε e_j` the step
    /// changes by `−ε (H⁻¹)_{·j}` while the active set stays.
    pub fn step(&self, gradient_shift: Option<&[f64]>) -> Result<GaussNewtonStep, LinearisedError> {
        self.step_with(gradient_shift, &[])
    }

    /// [`step`](Self::step) with the bounds of the variables `unbounded` lifted: the
    /// curvature of the cost along a parameter is a property of the data, not of the
    /// range it is allowed, and a probe of it must not be stopped by a bound the step
    /// reaches (the response to a gradient shift is then nil and the parameter looks
    /// perfectly known).
    pub fn step_with(
        &self,
        gradient_shift: Option<&[f64]>,
        unbounded: &[usize],
    ) -> Result<GaussNewtonStep, LinearisedError> {
        let n = self.nlp.n();
        let g: Vec<f64> = match gradient_shift {
            Some(s) => self.ev.grad.iter().zip(s).map(|(a, b)| a + b).collect(),
            None => self.ev.grad.clone(),
        };
        let (w_lb, w_ub, c_lb, c_ub) = &self.bounds;
        let mut d_lb: Vec<f64> = (0..n).map(|i| w_lb[i] - self.w[i]).collect();
        let mut d_ub: Vec<f64> = (0..n).map(|i| w_ub[i] - self.w[i]).collect();
        for &i in unbounded {
            d_lb[i] = f64::NEG_INFINITY;
            d_ub[i] = f64::INFINITY;
        }
        let weights = vec![1.0; self.nlp.m()];
        let sol = qp::solve_near_solution(&QpData {
            h: &self.h,
            g: &g,
            jac: &self.jac,
            c: &self.ev.c,
            c_lb,
            c_ub,
            d_lb: &d_lb,
            d_ub: &d_ub,
            elastic: None,
            elastic_weights: &weights,
            hint: None,
        })?;
        let mut hd = vec![0.0; n];
        for ((&r, &c), &v) in self.h.rows.iter().zip(&self.h.cols).zip(&self.h.vals) {
            hd[r] += v * sol.d[c];
            if r != c {
                hd[c] += v * sol.d[r];
            }
        }
        let gd: f64 = self.ev.grad.iter().zip(&sol.d).map(|(a, b)| a * b).sum();
        let dhd: f64 = hd.iter().zip(&sol.d).map(|(a, b)| a * b).sum();
        Ok(GaussNewtonStep {
            predicted_decrease: -(gd + 0.5 * dhd),
            d: sol.d,
            lambda: sol.lambda,
            nu: sol.nu,
        })
    }

    /// Rows and columns `cols` of the inverse of H reduced to the constraints active at
    /// `step` (a step of this model): `Z (ZᵀHZ)⁻¹ Zᵀ` for Z spanning the directions that
    /// keep the linearised equality rows, the inequality rows and the variable bounds
    /// active there, except the bounds of `cols` themselves (a parameter's information is
    /// the cost's curvature along it, not the range it is allowed). Column j is the step's
    /// response to a unit decrease of `∂f/∂w_j` while the active set stays, which is what
    /// a probe with a shifted gradient measures; here it is the step of the QP with the
    /// gradient `e_j` and only those constraints, as equalities: with no inequality the
    /// response is linear in the gradient, at any size, and one solve per column replaces
    /// the probes' search for a shift that keeps the active set.
    pub fn reduced_inverse(
        &self,
        step: &GaussNewtonStep,
        cols: &[usize],
    ) -> Result<Vec<Vec<f64>>, LinearisedError> {
        let n = self.nlp.n();
        let (w_lb, w_ub, c_lb, c_ub) = &self.bounds;
        if step.d.len() != n || step.nu.len() != n || step.lambda.len() != c_lb.len() {
            return Err(LinearisedError::ForeignStep);
        }
        let mut free = vec![false; n];
        for &c in cols {
            if c >= n {
                return Err(LinearisedError::Column { column: c, n });
            }
            free[c] = true;
        }
        // a multiplier counts as nonzero above 1e-8 of the largest: the interior-point
        // QP leaves ~tolerance-sized multipliers on inactive rows
        let scale = step
            .lambda
            .iter()
            .chain(&step.nu)
            .fold(1.0f64, |m, v| m.max(v.abs()));
        let held = |value: f64, lb: f64, ub: f64, multiplier: f64| {
            let near = |b: f64| b.is_finite() && (value - b).abs() <= 1e-7 * (1.0 + b.abs());
            lb == ub || (multiplier.abs() > 1e-8 * scale && (near(lb) || near(ub)))
        };
        // the linearised constraint values at the step
        let mut lin = self.ev.c.clone();
        for ((&r, &c), &v) in self.jac.rows.iter().zip(&self.jac.cols).zip(&self.jac.vals) {
            lin[r] += v * step.d[c];
        }
        // the active rows as equalities, the others dropped; the variables the active
        // bounds hold fixed: an equality-constrained QP, linear in its gradient
        let m = c_lb.len();
        let mut a_lb = vec![f64::NEG_INFINITY; m];
        let mut a_ub = vec![f64::INFINITY; m];
        for i in 0..m {
            if held(lin[i], c_lb[i], c_ub[i], step.lambda[i]) {
                (a_lb[i], a_ub[i]) = (0.0, 0.0);
            }
        }
        let mut d_lb = vec![f64::NEG_INFINITY; n];
        let mut d_ub = vec![f64::INFINITY; n];
        for j in 0..n {
            let at = self.w[j] + step.d[j];
            if !free[j] && held(at, w_lb[j], w_ub[j], step.nu[j]) {
                (d_lb[j], d_ub[j]) = (0.0, 0.0);
            }
        }
        let zeros = vec![0.0; m];
        let weights = vec![1.0; m];
        let mut out = vec![vec![0.0; cols.len()]; cols.len()];
        for (j, &col) in cols.iter().enumerate() {
            let mut g = vec![0.0; n];
            g[col] = 1.0;
            let sol = qp::solve_near_solution(&QpData {
                h: &self.h,
                g: &g,
                jac: &self.jac,
                c: &zeros,
                c_lb: &a_lb,
                c_ub: &a_ub,
                d_lb: &d_lb,
                d_ub: &d_ub,
                elastic: None,
                elastic_weights: &weights,
                hint: None,
            })?;
            for (i, &ci) in cols.iter().enumerate() {
                out[i][j] = -sol.d[ci];
            }
        }
        Ok(out)
    }
}
