//! Integrated Lagrange terms as quadrature states.
//!
//! [`WithQuadrature`] appends states $\ell$ with $\dot\ell = L(x, u, \theta)$ to a model,
//! so that $\int L\,dt$ over a phase is the growth of $\ell$, integrated by CVODES with the
//! dynamics (error-controlled, with sensitivities and curvature like every other state).
//! Give $\ell$ the bounds $[0, 0]$ at the first node and put the final value into the
//! objective (see [`quadrature_cost`]).

use super::problem::{Block, NodeFunction, Term};
use super::term_error::with_causes;
use super::TermError;
use crate::integrate::{ControlledOde, OdeError};
use std::sync::Arc;

/// An integrand `L(x, u, θ)` with exact derivatives.
pub trait Integrand: Send + Sync {
    /// Number of integrated quantities.
    fn dim(&self) -> usize;
    /// `L` and, when given, its Jacobian with respect to `(x, u, θ)` (dim × (nx+nu+nθ),
    /// column-major).
    fn eval(
        &self,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        value: &mut [f64],
        jac: Option<&mut [f64]>,
    ) -> Result<(), TermError>;
    /// `Σ_i w_i ∇²L_i` with respect to `(x, u, θ)`; `Ok(false)` if not provided.
    fn weighted_hessian(
        &self,
        _x: &[f64],
        _u: &[f64],
        _theta: &[f64],
        _w: &[f64],
        _out: &mut [f64],
    ) -> Result<bool, TermError> {
        Ok(false)
    }
}

/// A model extended by quadrature states.
pub struct WithQuadrature<'a> {
    /// The model.
    pub ode: &'a dyn ControlledOde,
    /// The integrand.
    pub integrand: &'a dyn Integrand,
}

impl ControlledOde for WithQuadrature<'_> {
    fn nx(&self) -> usize {
        self.ode.nx() + self.integrand.dim()
    }
    fn nu(&self) -> usize {
        self.ode.nu()
    }
    fn ntheta(&self) -> usize {
        self.ode.ntheta()
    }
    /// The model's: the quadrature states add no stiffness (their rows of ∂f/∂x are
    /// zero), but the model's own stiff transition needs the chained pass all the same.
    fn stiff_transition(&self) -> bool {
        self.ode.stiff_transition()
    }
    fn fast_curvature_layers(&self) -> bool {
        self.ode.fast_curvature_layers()
    }
    fn f(&self, x: &[f64], u: &[f64], theta: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        let n = self.ode.nx();
        self.ode.f(&x[..n], u, theta, &mut xdot[..n])?;
        self.integrand
            .eval(&x[..n], u, theta, &mut xdot[n..], None)
            .map_err(|e| OdeError::Fatal(with_causes(&e)))
    }
    fn f_jac(
        &self,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fu: &mut [f64],
        ftheta: &mut [f64],
    ) -> Result<(), OdeError> {
        let (n, nl, nu, nt) = (
            self.ode.nx(),
            self.integrand.dim(),
            self.ode.nu(),
            self.ode.ntheta(),
        );
        let na = n + nl;
        let (mut gx, mut gu, mut gt) = (vec![0.0; n * n], vec![0.0; n * nu], vec![0.0; n * nt]);
        self.ode
            .f_jac(&x[..n], u, theta, &mut xdot[..n], &mut gx, &mut gu, &mut gt)?;
        let mut lj = vec![0.0; nl * (n + nu + nt)];
        self.integrand
            .eval(&x[..n], u, theta, &mut xdot[n..], Some(&mut lj))
            .map_err(|e| OdeError::Fatal(with_causes(&e)))?;
        fx.iter_mut().for_each(|v| *v = 0.0);
        for c in 0..n {
            fx[c * na..c * na + n].copy_from_slice(&gx[c * n..(c + 1) * n]);
            for i in 0..nl {
                fx[c * na + n + i] = lj[i + c * nl];
            }
        }
        for c in 0..nu {
            fu[c * na..c * na + n].copy_from_slice(&gu[c * n..(c + 1) * n]);
            for i in 0..nl {
                fu[c * na + n + i] = lj[i + (n + c) * nl];
            }
        }
        for c in 0..nt {
            ftheta[c * na..c * na + n].copy_from_slice(&gt[c * n..(c + 1) * n]);
            for i in 0..nl {
                ftheta[c * na + n + i] = lj[i + (n + nu + c) * nl];
            }
        }
        Ok(())
    }
    fn weighted_hessian(
        &self,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        mu: &[f64],
        out: &mut [f64],
    ) -> Result<bool, OdeError> {
        let (n, nl, nu, nt) = (
            self.ode.nx(),
            self.integrand.dim(),
            self.ode.nu(),
            self.ode.ntheta(),
        );
        let nw = n + nu + nt;
        let mut hm = vec![0.0; nw * nw];
        if !self
            .ode
            .weighted_hessian(&x[..n], u, theta, &mu[..n], &mut hm)?
        {
            return Ok(false);
        }
        let mut hl = vec![0.0; nw * nw];
        if !self
            .integrand
            .weighted_hessian(&x[..n], u, theta, &mu[n..n + nl], &mut hl)
            .map_err(|e| OdeError::Fatal(with_causes(&e)))?
        {
            return Ok(false);
        }
        // variables of the extended model: (x, ℓ, u, θ); ℓ enters nothing nonlinearly
        let na = n + nl;
        let nwa = na + nu + nt;
        let map = |k: usize| if k < n { k } else { k + nl };
        out.iter_mut().for_each(|v| *v = 0.0);
        for a in 0..nw {
            for b in 0..nw {
                out[map(a) + map(b) * nwa] = hm[a + b * nw] + hl[a + b * nw];
            }
        }
        Ok(true)
    }
}

/// The scalar cost `Σ_i ℓ_i` at the final node of `phase` (linear, so its curvature is
/// zero), for `nl` quadrature states at offset `offset` of the node state.
pub fn quadrature_cost<'a>(phase: usize, node: usize, offset: usize, nl: usize) -> Term<'a> {
    struct Sum {
        range: std::ops::Range<usize>,
    }
    impl NodeFunction for Sum {
        fn dim(&self) -> usize {
            1
        }
        fn eval(&self, z: &[f64], v: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError> {
            v[0] = z[self.range.clone()].iter().sum();
            if let Some(j) = jac {
                j.iter_mut().for_each(|x| *x = 0.0);
                for i in self.range.clone() {
                    j[i] = 1.0;
                }
            }
            Ok(())
        }
        fn has_hessian(&self) -> bool {
            true
        }
        fn weighted_hessian(
            &self,
            _z: &[f64],
            _w: &[f64],
            out: &mut [f64],
        ) -> Result<(), TermError> {
            out.iter_mut().for_each(|v| *v = 0.0);
            Ok(())
        }
    }
    Term {
        name: "integrated_cost".into(),
        args: vec![Block::State { phase, node }],
        f: Arc::new(Sum {
            range: offset..offset + nl,
        }),
    }
}
