//! The multi-phase optimal control problem as the transcription sees it: phases with
//! dynamics, shooting grids, bounds and initial guesses; functions of node variables for
//! transitions, constraints and costs. Nothing here knows about gait.

use super::TermError;
use crate::integrate::{ControlShape, ControlledOde, IntegratorSettings};
use std::sync::Arc;

/// A block of decision variables a function may depend on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Block {
    /// State at a node of a phase (node 0 … intervals).
    State {
        /// Phase index.
        phase: usize,
        /// Node index.
        node: usize,
    },
    /// Control at a node (constant controls: interval index 0 … intervals−1; linear
    /// controls: node index 0 … intervals).
    Control {
        /// Phase index.
        phase: usize,
        /// Node or interval index.
        node: usize,
    },
    /// Duration of a phase (s).
    Duration {
        /// Phase index.
        phase: usize,
    },
    /// The free model parameters θ.
    Params,
}

/// A vector function of the concatenation `z` of its argument blocks, with an exact
/// Jacobian (`jac[i + j * dim] = ∂f_i/∂z_j`).
pub trait NodeFunction: Send + Sync {
    /// Output dimension.
    fn dim(&self) -> usize;
    /// Evaluate; fill `jac` when given.
    fn eval(&self, z: &[f64], value: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError>;
    /// Whether [`weighted_hessian`](Self::weighted_hessian) is provided.
    fn has_hessian(&self) -> bool {
        false
    }
    /// Exact curvature `Σ_i weights_i ∇²f_i(z)` (nz × nz, column-major), for the SQP's
    /// Hessian of the Lagrangian. Only called when [`has_hessian`](Self::has_hessian).
    fn weighted_hessian(
        &self,
        _z: &[f64],
        _weights: &[f64],
        _out: &mut [f64],
    ) -> Result<(), TermError> {
        Err(TermError::NoHessian)
    }
}

/// A function applied to specific variable blocks, with a name for reports.
#[derive(Clone)]
pub struct Term<'a> {
    /// Name (e.g. `periodicity`, `friction_cone`).
    pub name: String,
    /// Argument blocks, concatenated in this order.
    pub args: Vec<Block>,
    /// The function (may borrow the model for `'a`).
    pub f: Arc<dyn NodeFunction + 'a>,
}

impl std::fmt::Debug for Term<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Term")
            .field("name", &self.name)
            .field("args", &self.args)
            .finish()
    }
}

/// A least-squares residual at an instant inside a shooting interval,
/// `r(x(t), u(t), θ)`, where `x(t)` is the interval integrated from its start node to
/// `t = t_k + τ h` (CVODES dense output, with its forward sensitivities) and `u(t)` the
/// interval's control there. It lets a cost compare the model with measurements at the
/// instants they were taken instead of at the shooting nodes. Its curvature enters the
/// SQP as the Gauss–Newton term `2 JᵀJ` only, in every Hessian mode.
#[derive(Clone)]
pub struct SampleTerm<'a> {
    /// Name (e.g. `tracking sample`).
    pub name: String,
    /// Phase index.
    pub phase: usize,
    /// Interval index within the phase.
    pub interval: usize,
    /// Where in the interval, as a fraction of its length (0 < τ ≤ 1).
    pub tau: f64,
    /// The residual, a function of the concatenation `(x, u, θ)` (nx + nu + nθ).
    pub f: Arc<dyn NodeFunction + 'a>,
    /// A shift of the instant by `s(θ)` seconds (a scalar function of θ with its
    /// gradient), for a measurement taken on a clock offset from the model's: the model
    /// is compared at `(interval + τ) h + s(θ)`, in whichever interval of the phase that
    /// falls, so the data are never interpolated. The instant is held inside its phase
    /// (clamped to its ends, where the shift's derivative is zero), and the phase's
    /// duration must be fixed. `None`: the instant is fixed.
    pub shift: Option<Arc<dyn NodeFunction + 'a>>,
}

impl std::fmt::Debug for SampleTerm<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SampleTerm")
            .field("name", &self.name)
            .field("phase", &self.phase)
            .field("interval", &self.interval)
            .field("tau", &self.tau)
            .field("shifted", &self.shift.is_some())
            .finish()
    }
}

/// A path constraint at an instant inside a shooting interval,
/// `lb ≤ g(x(t), u(t), θ) ≤ ub` with `t = t_k + τ h`: `x(t)` from the interval's
/// integration (CVODES dense output, with its forward sensitivities, as for
/// [`SampleTerm`]). Node constraints hold only at the shooting nodes; check points hold a
/// constraint between them too (a ground that must not pull, a foot that must stay above
/// the floor). The constraint's curvature is left out of the SQP's Hessian (its first
/// derivatives are exact): it is active at few points, if any.
#[derive(Clone)]
pub struct CheckPoint<'a> {
    /// Name (e.g. `contact_forces`).
    pub name: String,
    /// Phase index.
    pub phase: usize,
    /// Interval index within the phase.
    pub interval: usize,
    /// Where in the interval, as a fraction of its length (0 < τ < 1).
    pub tau: f64,
    /// The constraint function of the concatenation `(x, u, θ)` (nx + nu + nθ).
    pub f: Arc<dyn NodeFunction + 'a>,
    /// Lower bounds (−∞ allowed).
    pub lb: Vec<f64>,
    /// Upper bounds (+∞ allowed).
    pub ub: Vec<f64>,
}

impl std::fmt::Debug for CheckPoint<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CheckPoint")
            .field("name", &self.name)
            .field("phase", &self.phase)
            .field("interval", &self.interval)
            .field("tau", &self.tau)
            .finish()
    }
}

/// A constraint `lb ≤ f(z) ≤ ub` (equal bounds for an equality).
#[derive(Debug, Clone)]
pub struct Constraint<'a> {
    /// The function and its arguments.
    pub term: Term<'a>,
    /// Lower bounds (−∞ allowed).
    pub lb: Vec<f64>,
    /// Upper bounds (+∞ allowed).
    pub ub: Vec<f64>,
}

/// Duration of a phase: fixed when `lb == ub`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseDuration {
    /// Initial guess (s).
    pub value: f64,
    /// Lower bound (s).
    pub lb: f64,
    /// Upper bound (s).
    pub ub: f64,
}

impl PhaseDuration {
    /// A fixed duration.
    pub fn fixed(v: f64) -> Self {
        Self {
            value: v,
            lb: v,
            ub: v,
        }
    }
    /// Whether the duration is a decision variable.
    pub fn is_free(&self) -> bool {
        self.lb < self.ub
    }
}

/// One continuous phase, discretised into equal shooting intervals.
pub struct Phase<'a> {
    /// Name, used in reports.
    pub name: String,
    /// Dynamics.
    pub ode: &'a dyn ControlledOde,
    /// Number of shooting intervals (≥ 1).
    pub intervals: usize,
    /// Duration.
    pub duration: PhaseDuration,
    /// Control parameterisation.
    pub controls: ControlShape,
    /// State bounds per node (`intervals + 1` rows of nx).
    pub x_lb: Vec<Vec<f64>>,
    /// State upper bounds per node.
    pub x_ub: Vec<Vec<f64>>,
    /// Control bounds per control node.
    pub u_lb: Vec<Vec<f64>>,
    /// Control upper bounds per control node.
    pub u_ub: Vec<Vec<f64>>,
    /// Initial guess of the node states.
    pub x_guess: Vec<Vec<f64>>,
    /// Initial guess of the controls.
    pub u_guess: Vec<Vec<f64>>,
}

impl Phase<'_> {
    /// Number of control nodes.
    pub fn control_nodes(&self) -> usize {
        match self.controls {
            ControlShape::Constant => self.intervals,
            ControlShape::Linear => self.intervals + 1,
        }
    }
}

/// A multi-phase optimal control problem
/// $$\min \sum \|r_i(z_i)\|^2 + \sum \phi_i(z_i)\quad\text{s.t. dynamics, transitions,}
///   \;lb \le g(z) \le ub,\; \text{bounds}.$$
pub struct Ocp<'a> {
    /// Continuous phases in order.
    pub phases: Vec<Phase<'a>>,
    /// State transition into phase `j + 1`: `x_{j+1,0} = ψ_j(args)`; `None` means
    /// continuity `x_{j+1,0} = x_{j,N}` (equal state dimensions required).
    pub transitions: Vec<Option<Term<'a>>>,
    /// Number of free parameters θ (shared by all phases' dynamics).
    pub ntheta: usize,
    /// θ initial guess and bounds.
    pub theta_guess: Vec<f64>,
    /// θ lower bounds.
    pub theta_lb: Vec<f64>,
    /// θ upper bounds.
    pub theta_ub: Vec<f64>,
    /// Path and boundary constraints.
    pub constraints: Vec<Constraint<'a>>,
    /// Least-squares cost terms: cost += ‖r(z)‖².
    pub least_squares: Vec<Term<'a>>,
    /// Least-squares residuals inside shooting intervals: cost += ‖r(x(t), u(t), θ)‖².
    pub samples: Vec<SampleTerm<'a>>,
    /// Path constraints at instants inside shooting intervals.
    pub checks: Vec<CheckPoint<'a>>,
    /// General scalar cost terms (dimension 1).
    pub costs: Vec<Term<'a>>,
    /// Integrator settings for the shooting intervals.
    pub integrator: IntegratorSettings,
}
