//! Time integration of ordinary differential equations with forward sensitivities.
//!
//! The integrator solves the initial-value problem
//! $$\dot x = f(t, x, p),\quad x(t_0) = x_0,$$
//! and, on request, the forward sensitivity equations
//! $$\dot S = f_x S + [0 \;|\; f_p],\quad S(t_0) = [I \;|\; 0],$$
//! so that $S(t_1) = \partial x(t_1) / \partial (x_0, p)$.  The Jacobians $f_x$ and $f_p$
//! come from the [`Ode`] implementation (exact: automatic differentiation or hand-derived),
//! never from difference quotients.
//!
//! [`ShootingInterval`] turns a control-affine-in-time model $f(x, u, \theta)$ into the
//! time-scaled ODE of one multiple-shooting interval, whose parameters are the interval's
//! control values, its duration and the free model parameters.

mod cvodes;
mod interval;
mod quadrature;

pub use cvodes::{
    AdjointSweep, IntegrationStats, Integrator, IntegratorError, IntegratorSettings, Method,
    MAX_CELL_NODES,
};
pub use interval::{ControlShape, ControlledOde, ShootingInterval};

/// Failure of an ODE right-hand side evaluation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OdeError {
    /// The state is outside the region where the model is defined, but a smaller step may
    /// avoid it (CVODES retries with a smaller step).
    #[error("recoverable right-hand-side failure: {0}")]
    Recoverable(String),
    /// The model cannot be evaluated; integration stops.
    #[error("{0}")]
    Fatal(String),
}

/// An ODE $\dot x = f(t, x, p)$ with exact first derivatives.
///
/// Matrices are dense and column-major: `fx[i + j * nx] = ∂f_i/∂x_j`,
/// `fp[i + k * nx] = ∂f_i/∂p_k`.
pub trait Ode: Sync {
    /// Number of states.
    fn nx(&self) -> usize;
    /// Number of parameters (the sensitivity parameters after the initial state).
    fn np(&self) -> usize;
    /// Right-hand side `xdot = f(t, x, p)`.
    fn rhs(&self, t: f64, x: &[f64], p: &[f64], xdot: &mut [f64]) -> Result<(), OdeError>;
    /// Right-hand side and its Jacobians with respect to `x` (nx × nx) and `p` (nx × np).
    fn jacobians(
        &self,
        t: f64,
        x: &[f64],
        p: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fp: &mut [f64],
    ) -> Result<(), OdeError>;
}
