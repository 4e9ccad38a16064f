//! One multiple-shooting interval as a parameterised ODE in normalised time.
//!
//! An interval of duration $T$ is mapped to $\tau \in [0, 1]$, so that the duration becomes a
//! parameter like the controls:
//! $$\frac{dx}{d\tau} = T\, f\bigl(x, u(\tau), \theta\bigr),\qquad
//! u(\tau) = \begin{cases} u_0 & \text{constant} \\ (1-\tau)\,u_0 + \tau\, u_1 & \text{linear}
//! \end{cases}$$
//! with parameter vector $p = [u_0,\ u_1\ (\text{linear only}),\ T,\ \theta]$.  Integrating
//! over $\tau$ from 0 to 1 with sensitivities gives $\partial x(1) / \partial (x_0, p)$, i.e.
//! the defect Jacobians of the shooting transcription in one pass.

use std::ops::Range;

use super::cvodes::IntegratorError;
use super::{Ode, OdeError};

/// A time-invariant controlled model ẋ = f(x, u, θ) with exact Jacobians.
pub trait ControlledOde: Sync {
    /// Number of states.
    fn nx(&self) -> usize;
    /// Number of controls.
    fn nu(&self) -> usize;
    /// Number of free model parameters θ.
    fn ntheta(&self) -> usize;
    /// Right-hand side `xdot = f(x, u, θ)` (state units per second).
    fn f(&self, x: &[f64], u: &[f64], theta: &[f64], xdot: &mut [f64]) -> Result<(), OdeError>;
    /// f and Jacobians fx (nx×nx), fu (nx×nu), ftheta (nx×nθ), column-major.
    #[allow(clippy::too_many_arguments)]
    fn f_jac(
        &self,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fu: &mut [f64],
        ftheta: &mut [f64],
    ) -> Result<(), OdeError>;
}

/// How the control varies over one shooting interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControlShape {
    /// Piecewise constant: u(τ) = u0.
    Constant,
    /// Piecewise linear: u(τ) = (1 − τ) u0 + τ u1.
    Linear,
}

/// Controls up to this size are interpolated in a stack buffer.
const STACK_NU: usize = 16;

/// Adapter from a [`ControlledOde`] to the [`Ode`] of one shooting interval over τ ∈ [0, 1].
///
/// See the module docs for the dynamics and the parameter layout; the layout helpers
/// ([`p_u0`](Self::p_u0), [`p_u1`](Self::p_u1), [`p_duration`](Self::p_duration),
/// [`p_theta`](Self::p_theta)) give the index ranges in `p` and in the sensitivity
/// columns after the first `nx`.
pub struct ShootingInterval<'a, O: ControlledOde + ?Sized> {
    model: &'a O,
    shape: ControlShape,
}

// Manual impls: derives would demand `O: Clone`/`O: Debug` although only `&O` is stored.
impl<O: ControlledOde + ?Sized> Clone for ShootingInterval<'_, O> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<O: ControlledOde + ?Sized> Copy for ShootingInterval<'_, O> {}

impl<O: ControlledOde + ?Sized> std::fmt::Debug for ShootingInterval<'_, O> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShootingInterval")
            .field("nx", &self.model.nx())
            .field("nu", &self.model.nu())
            .field("ntheta", &self.model.ntheta())
            .field("shape", &self.shape)
            .finish()
    }
}

impl<'a, O: ControlledOde + ?Sized> ShootingInterval<'a, O> {
    /// Wrap `model` with the given control shape.
    pub fn new(model: &'a O, shape: ControlShape) -> Self {
        Self { model, shape }
    }

    /// The wrapped model.
    pub fn model(&self) -> &'a O {
        self.model
    }

    /// The control shape.
    pub fn shape(&self) -> ControlShape {
        self.shape
    }

    /// Number of parameters: nu (+ nu for linear controls) + 1 + nθ.
    pub fn np(&self) -> usize {
        self.p_theta().end
    }

    /// Indices of u0 in `p`.
    pub fn p_u0(&self) -> Range<usize> {
        0..self.model.nu()
    }

    /// Indices of u1 in `p`; `None` for constant controls.
    pub fn p_u1(&self) -> Option<Range<usize>> {
        let nu = self.model.nu();
        match self.shape {
            ControlShape::Constant => None,
            ControlShape::Linear => Some(nu..2 * nu),
        }
    }

    /// Index of the duration T in `p`.
    pub fn p_duration(&self) -> usize {
        self.p_u1().map_or(self.model.nu(), |r| r.end)
    }

    /// Indices of θ in `p`.
    pub fn p_theta(&self) -> Range<usize> {
        let start = self.p_duration() + 1;
        start..start + self.model.ntheta()
    }

    /// Fill `p` (cleared first) with `[u0, u1, duration, θ]`.
    ///
    /// `u1` must be `Some` exactly for linear controls; lengths are checked against the model.
    pub fn pack_params(
        &self,
        u0: &[f64],
        u1: Option<&[f64]>,
        duration: f64,
        theta: &[f64],
        p: &mut Vec<f64>,
    ) -> Result<(), IntegratorError> {
        let nu = self.model.nu();
        let dim = |what, expected, found| {
            if expected == found {
                Ok(())
            } else {
                Err(IntegratorError::Dimension {
                    what,
                    expected,
                    found,
                })
            }
        };
        dim("u0", nu, u0.len())?;
        dim("theta", self.model.ntheta(), theta.len())?;
        match (self.shape, u1) {
            (ControlShape::Constant, Some(u1)) => {
                dim("u1 (constant controls take none)", 0, u1.len())?
            }
            (ControlShape::Linear, None) => dim("u1", nu, 0)?,
            (ControlShape::Linear, Some(u1)) => dim("u1", nu, u1.len())?,
            (ControlShape::Constant, None) => {}
        }
        p.clear();
        p.reserve(self.np());
        p.extend_from_slice(u0);
        if let (ControlShape::Linear, Some(u1)) = (self.shape, u1) {
            p.extend_from_slice(u1);
        }
        p.push(duration);
        p.extend_from_slice(theta);
        Ok(())
    }

    /// Reject buffers of the wrong length (the [`Ode`] methods must not panic).
    fn check_lengths(&self, x: &[f64], p: &[f64], xdot: &[f64]) -> Result<(), OdeError> {
        let (nx, np) = (self.model.nx(), ShootingInterval::np(self));
        if x.len() != nx || xdot.len() != nx || p.len() != np {
            return Err(OdeError::Fatal(format!(
                "shooting interval: expected x, xdot of length {nx} and p of length {np}, got {}, {}, {}",
                x.len(),
                xdot.len(),
                p.len()
            )));
        }
        Ok(())
    }

    /// Call `body` with u(τ): a sub-slice of `p` for constant controls, otherwise the
    /// interpolated value in a stack (or, for large nu, heap) buffer.
    fn with_control<R>(&self, tau: f64, p: &[f64], body: impl FnOnce(&[f64]) -> R) -> R {
        let u0 = &p[self.p_u0()];
        let Some(r1) = self.p_u1() else {
            return body(u0);
        };
        let u1 = &p[r1];
        let mut stack = [0.0; STACK_NU];
        let mut heap = Vec::new();
        let u = if u0.len() <= STACK_NU {
            &mut stack[..u0.len()]
        } else {
            heap.resize(u0.len(), 0.0);
            &mut heap[..]
        };
        for ((u, a), b) in u.iter_mut().zip(u0).zip(u1) {
            *u = (1.0 - tau) * a + tau * b;
        }
        body(u)
    }
}

impl<O: ControlledOde + ?Sized> Ode for ShootingInterval<'_, O> {
    fn nx(&self) -> usize {
        self.model.nx()
    }

    fn np(&self) -> usize {
        ShootingInterval::np(self)
    }

    fn rhs(&self, tau: f64, x: &[f64], p: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        self.check_lengths(x, p, xdot)?;
        let duration = p[self.p_duration()];
        let theta = &p[self.p_theta()];
        self.with_control(tau, p, |u| self.model.f(x, u, theta, xdot))?;
        xdot.iter_mut().for_each(|v| *v *= duration);
        Ok(())
    }

    fn jacobians(
        &self,
        tau: f64,
        x: &[f64],
        p: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fp: &mut [f64],
    ) -> Result<(), OdeError> {
        let nx = self.model.nx();
        self.check_lengths(x, p, xdot)?;
        if fx.len() != nx * nx || fp.len() != nx * p.len() {
            return Err(OdeError::Fatal(format!(
                "shooting interval: expected fx of length {} and fp of length {}, got {}, {}",
                nx * nx,
                nx * p.len(),
                fx.len(),
                fp.len()
            )));
        }
        let duration = p[self.p_duration()];
        let theta = &p[self.p_theta()];
        let cols = |r: Range<usize>| nx * r.start..nx * r.end;
        let (u_cols, rest) = fp.split_at_mut(self.p_duration() * nx);
        let (t_col, theta_cols) = rest.split_at_mut(nx);
        // fu goes straight into the u1 columns (linear) or the u0 columns (constant).
        let fu_range = match self.p_u1() {
            Some(r1) => cols(r1),
            None => cols(self.p_u0()),
        };
        self.with_control(tau, p, |u| {
            self.model.f_jac(
                x,
                u,
                theta,
                xdot,
                fx,
                &mut u_cols[fu_range.clone()],
                theta_cols,
            )
        })?;
        // ∂/∂T = f; then scale everything else by T.
        t_col.copy_from_slice(xdot);
        let scale = |v: &mut [f64], s: f64| v.iter_mut().for_each(|a| *a *= s);
        scale(xdot, duration);
        scale(fx, duration);
        scale(theta_cols, duration);
        if self.shape == ControlShape::Linear {
            // u_cols = [u0 | u1] with u1 = fu: u0 ← T(1−τ) fu, u1 ← Tτ fu.
            let (u0_cols, u1_cols) = u_cols.split_at_mut(fu_range.start);
            u0_cols.copy_from_slice(u1_cols);
            scale(u0_cols, duration * (1.0 - tau));
            scale(u1_cols, duration * tau);
        } else {
            scale(u_cols, duration);
        }
        Ok(())
    }
}
