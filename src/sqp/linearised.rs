//! The Gauss–Newton model of a least-squares NLP at a point, for questions asked at a
//! solution rather than while solving: how far would the cost fall if some variables
//! were freed (a score test), and how uncertain are identified parameters.
//!
//! Both come from the QP of one Gauss–Newton SQP step,
//! $\min_d\ g^T d + \tfrac12 d^T H d$ s.t. the linearised constraints and bounds, with
//! $H = 2 J_r^T J_r$ for $f = \|r\|^2$.

use super::qp::{self, QpData, Triplets};
use super::{Nlp, NlpEval};

/// One Gauss–Newton step at a point.
#[derive(Debug, Clone)]
pub struct GaussNewtonStep {
    /// The step.
    pub d: Vec<f64>,
    /// Decrease of the quadratic model, $-(g^T d + \tfrac12 d^T H d)$.
    pub predicted_decrease: f64,
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
    pub fn new(nlp: &'a dyn Nlp, w: &[f64], regularization: f64) -> Result<Self, String> {
        let bounds = nlp.bounds();
        let w: Vec<f64> = w
            .iter()
            .zip(bounds.0.iter().zip(&bounds.1))
            .map(|(&v, (&l, &u))| v.max(l).min(u))
            .collect();
        let ev = nlp.evaluate(&w, true).map_err(|e| e.chain())?;
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
    pub fn step(&self, gradient_shift: Option<&[f64]>) -> Result<GaussNewtonStep, String> {
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
    ) -> Result<GaussNewtonStep, String> {
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
        let sol = qp::solve(&QpData {
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
        })
        .map_err(|e| e.to_string())?;
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
        })
    }
}
