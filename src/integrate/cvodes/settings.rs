//! Options, work counters and errors of the CVODES integrator.

use std::ffi::{c_int, c_long};

use serde::{Deserialize, Serialize};
use sundials_sys as sys;

use crate::integrate::OdeError;

/// Linear multistep family used by CVODES.
///
/// Both use Newton iteration with the dense direct linear solver and the exact Jacobian.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Backward differentiation formulas, orders 1–5: for stiff problems (contact dynamics).
    #[default]
    Bdf,
    /// Adams–Moulton formulas, orders 1–12: for smooth, non-stiff problems.
    Adams,
}

impl Method {
    /// Highest order CVODES supports for the method.
    fn max_order(self) -> i32 {
        match self {
            Method::Bdf => 5,
            Method::Adams => 12,
        }
    }

    /// CVODES's constant for the method (`CV_BDF`, `CV_ADAMS`).
    pub(super) fn lmm(self) -> c_int {
        match self {
            Method::Bdf => sys::CV_BDF,
            Method::Adams => sys::CV_ADAMS,
        }
    }
}

/// Options of the CVODES integrator; fixed when the [`Integrator`](super::Integrator) is
/// created.
///
/// The sensitivities use the same tolerances as the states (CVODES's estimated error
/// tolerances, `CVodeSensEEtolerances`) unless [`sens_tol`](Self::sens_tol) sets their
/// own.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IntegratorSettings {
    /// Linear multistep family (default: `bdf`).
    pub method: Method,
    /// Relative local error tolerance, dimensionless, in (0, 1) (default: 1e-8).
    pub rtol: f64,
    /// Absolute local error tolerance, in state units, > 0 (default: 1e-8).
    pub atol: f64,
    /// Maximum number of internal steps per CVODES call, i.e. per output time (default: 100000).
    pub max_steps: i64,
    /// Include the sensitivities in the local error test (default: true).
    pub sens_error_control: bool,
    /// Relative and absolute local error tolerance of the forward sensitivities, in (0, 1)
    /// (`CVodeSensSStolerances`); `None` = the states' tolerances (default). A looser one
    /// than the states' keeps the function values precise (what a line search compares)
    /// at fewer steps; but an optimality test computed from the derivatives inherits
    /// their error.
    pub sens_tol: Option<f64>,
    /// Maximum method order, 1–5 for BDF and 1–12 for Adams; `None` = method maximum (default: None).
    pub max_order: Option<i32>,
    /// First internal step size in time units, > 0; `None` = CVODES estimate (default: None).
    pub initial_step: Option<f64>,
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        Self {
            method: Method::Bdf,
            rtol: 1e-8,
            atol: 1e-8,
            max_steps: 100_000,
            sens_error_control: true,
            sens_tol: None,
            max_order: None,
            initial_step: None,
        }
    }
}

impl IntegratorSettings {
    /// These settings with the sensitivities at a tenth of the KKT tolerance `tol_kkt` a
    /// solve is held to, never tighter than the states: the KKT residual is computed from
    /// the sensitivities, the function values a line search compares from the states, and
    /// looser sensitivities take fewer steps.
    pub fn sensitivities_for_kkt_tol(self, tol_kkt: f64) -> Self {
        let want = 0.1 * tol_kkt;
        Self {
            sens_tol: (want > self.rtol).then_some(want),
            ..self
        }
    }

    /// Check every option; [`Integrator::new`](super::Integrator::new) calls this.
    pub fn validate(&self) -> Result<(), IntegratorError> {
        let bad = |field: &'static str, reason: String| {
            Err(IntegratorError::BadSettings { field, reason })
        };
        if !(self.rtol.is_finite() && self.rtol > 0.0 && self.rtol < 1.0) {
            return bad(
                "rtol",
                format!("must be finite and in (0, 1), got {}", self.rtol),
            );
        }
        if !(self.atol.is_finite() && self.atol > 0.0) {
            return bad(
                "atol",
                format!("must be finite and positive, got {}", self.atol),
            );
        }
        if let Some(t) = self.sens_tol {
            if !(t.is_finite() && t > 0.0 && t < 1.0) {
                return bad("sens_tol", format!("must be finite and in (0, 1), got {t}"));
            }
        }
        if self.max_steps <= 0 || c_long::try_from(self.max_steps).is_err() {
            return bad(
                "max_steps",
                format!("must be positive and fit a C long, got {}", self.max_steps),
            );
        }
        if let Some(order) = self.max_order {
            let max = self.method.max_order();
            if !(1..=max).contains(&order) {
                return bad(
                    "max_order",
                    format!("must be in 1..={max} for {:?}, got {order}", self.method),
                );
            }
        }
        if let Some(h) = self.initial_step {
            if !(h.is_finite() && h > 0.0) {
                return bad(
                    "initial_step",
                    format!("must be finite and positive, got {h}"),
                );
            }
        }
        Ok(())
    }
}

/// Work counters of one integration call, read from CVODES after the call.
///
/// The names follow the CVODES getters (`CVodeGetNumSteps`, `CVodeGetNumRhsEvals`, ...).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct IntegrationStats {
    /// Internal steps taken (`nst`).
    pub steps: u64,
    /// Right-hand side evaluations (`nfe`).
    pub rhs_evals: u64,
    /// Jacobian evaluations for the Newton matrix (`nje`).
    pub jac_evals: u64,
    /// Calls of the all-at-once sensitivity right-hand side (`nfSe`); 0 without sensitivities.
    pub sens_rhs_evals: u64,
    /// Local error test failures of the state (`netf`).
    pub error_test_failures: u64,
    /// Nonlinear (Newton) convergence failures of the state corrector (`ncfn`).
    pub nonlinear_conv_failures: u64,
    /// Newton iterations of the state corrector (`nni`).
    pub nonlinear_iters: u64,
    /// Newton iterations of the staggered sensitivity corrector, all columns at once
    /// (`nniS`); each solves one linear system per sensitivity column.
    pub sens_nonlinear_iters: u64,
    /// Newton-matrix factorisations (`nsetups`).
    pub linear_setups: u64,
}

impl std::ops::AddAssign for IntegrationStats {
    fn add_assign(&mut self, other: Self) {
        self.steps += other.steps;
        self.rhs_evals += other.rhs_evals;
        self.jac_evals += other.jac_evals;
        self.sens_rhs_evals += other.sens_rhs_evals;
        self.error_test_failures += other.error_test_failures;
        self.nonlinear_conv_failures += other.nonlinear_conv_failures;
        self.nonlinear_iters += other.nonlinear_iters;
        self.sens_nonlinear_iters += other.sens_nonlinear_iters;
        self.linear_setups += other.linear_setups;
    }
}

/// Failure of the integrator or of its input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IntegratorError {
    /// A CVODES setup function (create, init, option setter) returned an error flag.
    #[error("CVODES setup call {function} failed with {flag_name} ({flag})")]
    Setup {
        /// The SUNDIALS function that failed.
        function: &'static str,
        /// Its return flag.
        flag: i32,
        /// The flag's CVODES name.
        flag_name: String,
    },
    /// CVODES stopped before reaching the requested time.
    #[error("CVODES failed at t = {t} with {flag_name} ({flag}): {message}")]
    Failed {
        /// The CVODES return flag, e.g. `CV_TOO_MUCH_WORK` or `CV_CONV_FAILURE`.
        flag: i32,
        /// The flag's CVODES name.
        flag_name: String,
        /// Time reached when CVODES gave up.
        t: f64,
        /// CVODES's own error message (and the last recoverable ODE failure, if any).
        message: String,
    },
    /// The ODE reported a fatal error or panicked.
    #[error("ODE evaluation failed at t = {t}")]
    Rhs {
        /// Time of the failed evaluation.
        t: f64,
        /// The ODE's error.
        #[source]
        source: OdeError,
    },
    /// An argument has the wrong length.
    #[error("dimension mismatch for {what}: expected {expected}, found {found}")]
    Dimension {
        /// Which argument.
        what: &'static str,
        /// Required length.
        expected: usize,
        /// Given length.
        found: usize,
    },
    /// An [`IntegratorSettings`] field is invalid.
    #[error("invalid integrator setting `{field}`: {reason}")]
    BadSettings {
        /// Field name.
        field: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// The interval is empty, reversed or not finite (`t1 > t0` is required).
    #[error("invalid integration interval [{t0}, {t1}]: need finite t0 < t1")]
    BadInterval {
        /// Start time.
        t0: f64,
        /// End time.
        t1: f64,
    },
    /// A dense-output time is outside `[t0, t1]`, not finite, or not strictly increasing.
    #[error("output time times[{index}] = {t} is outside the interval or not increasing")]
    BadOutputTime {
        /// Index into `times`.
        index: usize,
        /// The offending time.
        t: f64,
    },
    /// NaN or infinity in the initial state or parameters (at `t0`) or in the result.
    #[error("non-finite value at t = {t}")]
    NonFinite {
        /// Time of the offending value.
        t: f64,
    },
    /// The state transition matrix `Ψ(t) = ∂x(t)/∂x(t0)` is singular at `t`, so an adjoint
    /// cannot be found from its inverse.
    #[error("the state transition matrix is singular at t = {t}")]
    SingularTransition {
        /// Time (within the interval's normalised time).
        t: f64,
    },
}
