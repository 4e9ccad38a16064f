//! Safe wrapper over SUNDIALS CVODES (version 6) for ODEs of fixed dimension.
//!
//! This module is the only place in the crate that touches `sundials_sys` or uses `unsafe`.
//! An [`Integrator`] owns every SUNDIALS object it creates (context, CVODES memory, state
//! and sensitivity vectors, dense Jacobian matrix and linear solver) and frees them in
//! `Drop`.  It is built once for a pair `(nx, np)` and re-initialised for every call, so the
//! allocation cost is paid once per worker thread.
//!
//! Both linear multistep families use a Newton iteration with a dense direct linear solver
//! and the exact Jacobian $f_x$ from [`Ode::jacobians`].  Forward sensitivities use the
//! staggered corrector (`CV_STAGGERED`) with a user-supplied sensitivity right-hand side
//! $\dot S_i = f_x S_i + f_{p,i}$; CVODES never forms difference quotients.
//!
//! # Callback data
//!
//! CVODES 6 captures the user-data pointer for the sensitivity right-hand side once, in
//! `CVodeSensInit`, and `CVodeSensReInit` does not refresh it.  The callbacks therefore
//! receive a heap-allocated [`Shared`] block whose address never changes; the borrowed ODE
//! and parameter vector of the current call are stored in it for the duration of the call
//! only (see [`CallGuard`]).

use std::ffi::{c_char, c_int, c_long, c_void, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::ptr;

use serde::{Deserialize, Serialize};
use sundials_sys as sys;

use super::{Ode, OdeError};

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

    fn lmm(self) -> c_int {
        match self {
            Method::Bdf => sys::CV_BDF,
            Method::Adams => sys::CV_ADAMS,
        }
    }
}

/// Options of the CVODES integrator; fixed when the [`Integrator`] is created.
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
    /// Check every option; [`Integrator::new`] calls this.
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
}

// ---------------------------------------------------------------------------------------
// Callback plumbing
// ---------------------------------------------------------------------------------------

/// The borrowed inputs of one call, on the caller's stack.
struct CallCtx<'a> {
    ode: &'a dyn Ode,
    p: &'a [f64],
    /// Event function `g(t, x)` of a call with root finding.
    event: Option<&'a dyn Fn(f64, &[f64]) -> f64>,
}

/// Heap block shared with the C callbacks through CVODES's user-data and error-handler
/// pointers.  Its address is fixed for the integrator's lifetime.
struct Shared {
    nx: usize,
    np: usize,
    /// Points to the current call's [`CallCtx`]; null outside a call.
    call: *const c_void,
    /// First fatal ODE error of the current call, with its time.
    fatal: Option<(f64, OdeError)>,
    /// Last recoverable ODE error of the current call, with its time.
    recoverable: Option<(f64, OdeError)>,
    /// Last CVODES error message of the current call.
    cvodes_error: Option<String>,
    /// Last CVODES warning of the current call.
    cvodes_warning: Option<String>,
    /// Whether `cache_*`, `fx`, `fp` hold the Jacobians at (`cache_t`, `cache_y`).
    cache_valid: bool,
    cache_t: f64,
    cache_y: Vec<f64>,
    fx: Vec<f64>,
    fp: Vec<f64>,
    xdot: Vec<f64>,
}

impl Shared {
    fn reset(&mut self) {
        self.fatal = None;
        self.recoverable = None;
        self.cvodes_error = None;
        self.cvodes_warning = None;
        self.cache_valid = false;
    }

    /// Evaluate `fx`, `fp` at `(t, y)` unless the cache already holds exactly that point.
    fn ensure_jacobians(&mut self, ctx: &CallCtx<'_>, t: f64, y: &[f64]) -> Result<(), OdeError> {
        if self.cache_valid
            && self.cache_t.to_bits() == t.to_bits()
            && self
                .cache_y
                .iter()
                .zip(y)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        {
            return Ok(());
        }
        self.cache_valid = false;
        ctx.ode
            .jacobians(t, y, ctx.p, &mut self.xdot, &mut self.fx, &mut self.fp)?;
        if !all_finite(&self.fx) || !all_finite(&self.fp) {
            return Err(OdeError::Recoverable(
                "non-finite Jacobian entries".to_string(),
            ));
        }
        self.cache_t = t;
        self.cache_y.copy_from_slice(y);
        self.cache_valid = true;
        Ok(())
    }
}

/// Sets [`Shared::call`] for one call and clears it again on every exit path.
struct CallGuard(*mut Shared);

impl CallGuard {
    /// # Safety
    /// `shared` must be valid for the guard's lifetime and `ctx` must outlive the guard.
    unsafe fn new(shared: *mut Shared, ctx: &CallCtx<'_>) -> Self {
        (*shared).call = (ctx as *const CallCtx<'_>).cast();
        Self(shared)
    }
}

impl Drop for CallGuard {
    fn drop(&mut self) {
        // SAFETY: the guard is created from the integrator's live `Shared` block and dropped
        // before the integrator; no callback runs concurrently (CVODES is not running).
        unsafe { (*self.0).call = ptr::null() };
    }
}

fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic payload".to_string()
    }
}

/// Run one callback body with the current call's context, translate its result into the
/// CVODES convention (0 ok, >0 recoverable, <0 fatal) and stop panics at the C boundary.
///
/// # Safety
/// `user_data` must be null or the integrator's `Shared` block, whose `call` is null or
/// points to a live `CallCtx`.
unsafe fn run_callback(
    user_data: *mut c_void,
    t: f64,
    body: impl FnOnce(&mut Shared, &CallCtx<'_>) -> Result<(), OdeError>,
) -> c_int {
    if user_data.is_null() {
        return -1;
    }
    let shared = &mut *user_data.cast::<Shared>();
    if shared.call.is_null() {
        return -1;
    }
    let ctx = &*shared.call.cast::<CallCtx<'_>>();
    let outcome = catch_unwind(AssertUnwindSafe(|| body(&mut *shared, ctx)));
    let error = match outcome {
        Ok(Ok(())) => return 0,
        Ok(Err(e)) => e,
        Err(payload) => OdeError::Fatal(format!(
            "panic in ODE callback: {}",
            panic_message(payload.as_ref())
        )),
    };
    match error {
        OdeError::Recoverable(_) => {
            shared.recoverable = Some((t, error));
            1
        }
        OdeError::Fatal(_) => {
            if shared.fatal.is_none() {
                shared.fatal = Some((t, error));
            }
            -1
        }
    }
}

/// # Safety
/// `v` must be a serial N_Vector of length at least `n`.
unsafe fn nv_slice<'a>(v: sys::N_Vector, n: usize) -> &'a [f64] {
    std::slice::from_raw_parts(sys::N_VGetArrayPointer(v), n)
}

/// # Safety
/// `v` must be a serial N_Vector of length at least `n`, not aliased during the borrow.
unsafe fn nv_slice_mut<'a>(v: sys::N_Vector, n: usize) -> &'a mut [f64] {
    std::slice::from_raw_parts_mut(sys::N_VGetArrayPointer(v), n)
}

/// `CVRhsFn`: ẏ = f(t, y, p).  Non-finite output is reported as recoverable so that CVODES
/// retries with a smaller step.
unsafe extern "C" fn rhs_callback(
    t: f64,
    y: sys::N_Vector,
    ydot: sys::N_Vector,
    user_data: *mut c_void,
) -> c_int {
    run_callback(user_data, t, |shared, ctx| {
        let nx = shared.nx;
        // SAFETY: CVODES passes distinct serial vectors of length nx.
        let (y, ydot) = unsafe { (nv_slice(y, nx), nv_slice_mut(ydot, nx)) };
        ctx.ode.rhs(t, y, ctx.p, ydot)?;
        if all_finite(ydot) {
            Ok(())
        } else {
            Err(OdeError::Recoverable(
                "non-finite right-hand side".to_string(),
            ))
        }
    })
}

/// `CVLsJacFn`: fills the dense (column-major) Newton Jacobian with `fx`.
unsafe extern "C" fn jac_callback(
    t: f64,
    y: sys::N_Vector,
    _fy: sys::N_Vector,
    jac: sys::SUNMatrix,
    user_data: *mut c_void,
    _tmp1: sys::N_Vector,
    _tmp2: sys::N_Vector,
    _tmp3: sys::N_Vector,
) -> c_int {
    run_callback(user_data, t, |shared, ctx| {
        let nx = shared.nx;
        // SAFETY: `y` is a serial vector of length nx; `jac` is our nx × nx dense matrix,
        // stored column-major in one contiguous block.
        let (y, jac) = unsafe {
            (
                nv_slice(y, nx),
                std::slice::from_raw_parts_mut(sys::SUNDenseMatrix_Data(jac), nx * nx),
            )
        };
        shared.ensure_jacobians(ctx, t, y)?;
        jac.copy_from_slice(&shared.fx);
        Ok(())
    })
}

/// `CVSensRhsFn` (all sensitivities at once): Ṡ_i = fx S_i, plus fp_(i−nx) for the
/// parameter columns.
unsafe extern "C" fn sens_rhs_callback(
    ns: c_int,
    t: f64,
    y: sys::N_Vector,
    _ydot: sys::N_Vector,
    ys: *mut sys::N_Vector,
    ysdot: *mut sys::N_Vector,
    user_data: *mut c_void,
    _tmp1: sys::N_Vector,
    _tmp2: sys::N_Vector,
) -> c_int {
    run_callback(user_data, t, |shared, ctx| {
        let (nx, np) = (shared.nx, shared.np);
        if usize::try_from(ns).ok() != Some(nx + np) {
            return Err(OdeError::Fatal(format!(
                "internal error: CVODES passed {ns} sensitivities, expected {}",
                nx + np
            )));
        }
        // SAFETY: `y` is a serial vector of length nx.
        let y = unsafe { nv_slice(y, nx) };
        shared.ensure_jacobians(ctx, t, y)?;
        for i in 0..nx + np {
            // SAFETY: CVODES passes two arrays of `ns` distinct serial vectors of length nx.
            let (si, di) = unsafe { (nv_slice(*ys.add(i), nx), nv_slice_mut(*ysdot.add(i), nx)) };
            match i.checked_sub(nx) {
                Some(k) => di.copy_from_slice(&shared.fp[k * nx..(k + 1) * nx]),
                None => di.fill(0.0),
            }
            for (col, &s) in shared.fx.chunks_exact(nx).zip(si) {
                if s != 0.0 {
                    for (d, &a) in di.iter_mut().zip(col) {
                        *d += a * s;
                    }
                }
            }
        }
        Ok(())
    })
}

/// `CVRootFn` (one function): gout[0] = g(t, y) of the call's event.
unsafe extern "C" fn root_callback(
    t: f64,
    y: sys::N_Vector,
    gout: *mut f64,
    user_data: *mut c_void,
) -> c_int {
    run_callback(user_data, t, |shared, ctx| {
        let nx = shared.nx;
        let event = ctx.event.ok_or_else(|| {
            OdeError::Fatal("internal error: root function called without an event".to_string())
        })?;
        // SAFETY: `y` is a serial vector of length nx; `gout` holds the one root function.
        let (y, g) = unsafe { (nv_slice(y, nx), &mut *gout) };
        *g = event(t, y);
        if g.is_finite() {
            Ok(())
        } else {
            Err(OdeError::Fatal(format!(
                "non-finite event function value at t = {t}"
            )))
        }
    })
}

/// `CVErrHandlerFn`: keeps CVODES messages off stderr and stores them for the error value.
unsafe extern "C" fn error_handler(
    error_code: c_int,
    _module: *const c_char,
    function: *const c_char,
    msg: *mut c_char,
    eh_data: *mut c_void,
) {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        if eh_data.is_null() {
            return;
        }
        let text = |p: *const c_char| {
            if p.is_null() {
                String::new()
            } else {
                // SAFETY: CVODES passes NUL-terminated strings valid for the call.
                unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
            }
        };
        let message = format!("{}: {}", text(function), text(msg));
        // SAFETY: `eh_data` is the integrator's `Shared` block; no Rust reference to it is
        // live while CVODES runs outside our callbacks.
        let shared = unsafe { &mut *eh_data.cast::<Shared>() };
        if error_code == sys::CV_WARNING {
            shared.cvodes_warning = Some(message);
        } else {
            shared.cvodes_error = Some(message);
        }
    }));
}

extern "C" {
    /// C `free`, for the string returned by `CVodeGetReturnFlagName`.
    fn free(p: *mut c_void);
}

/// CVODES's name for a return flag (`CV_TOO_MUCH_WORK`, ...).
fn flag_name(flag: c_int) -> String {
    // SAFETY: CVodeGetReturnFlagName returns a malloc'd NUL-terminated string (or NULL)
    // that the caller owns.
    unsafe {
        let p = sys::CVodeGetReturnFlagName(c_long::from(flag));
        if p.is_null() {
            return format!("flag {flag}");
        }
        let name = CStr::from_ptr(p).to_string_lossy().into_owned();
        free(p.cast());
        name
    }
}

/// Name of a CVLS (linear solver interface) flag.
fn lin_flag_name(flag: c_int) -> String {
    // SAFETY: as for `flag_name`.
    unsafe {
        let p = sys::CVodeGetLinReturnFlagName(c_long::from(flag));
        if p.is_null() {
            return format!("flag {flag}");
        }
        let name = CStr::from_ptr(p).to_string_lossy().into_owned();
        free(p.cast());
        name
    }
}

fn check_setup(function: &'static str, flag: c_int) -> Result<(), IntegratorError> {
    if flag < 0 {
        Err(IntegratorError::Setup {
            function,
            flag,
            flag_name: flag_name(flag),
        })
    } else {
        Ok(())
    }
}

fn check_lin_setup(function: &'static str, flag: c_int) -> Result<(), IntegratorError> {
    if flag < 0 {
        Err(IntegratorError::Setup {
            function,
            flag,
            flag_name: lin_flag_name(flag),
        })
    } else {
        Ok(())
    }
}

fn null_error(function: &'static str) -> IntegratorError {
    IntegratorError::Setup {
        function,
        flag: sys::CV_MEM_FAIL,
        flag_name: flag_name(sys::CV_MEM_FAIL),
    }
}

fn check_dim(what: &'static str, expected: usize, found: usize) -> Result<(), IntegratorError> {
    if expected == found {
        Ok(())
    } else {
        Err(IntegratorError::Dimension {
            what,
            expected,
            found,
        })
    }
}

fn check_interval(t0: f64, t1: f64) -> Result<(), IntegratorError> {
    if t0.is_finite() && t1.is_finite() && t1 > t0 {
        Ok(())
    } else {
        Err(IntegratorError::BadInterval { t0, t1 })
    }
}

// ---------------------------------------------------------------------------------------
// Integrator
// ---------------------------------------------------------------------------------------

/// A reusable CVODES instance for ODEs with `nx` states and `np` parameters.
///
/// Create one per worker thread and call it for many intervals; every call re-initialises
/// CVODES (`CVodeReInit`) and sets the stop time to `t1`, so no step goes past `t1` and the
/// result does not depend on earlier calls.  Outputs are written only on success.
pub struct Integrator {
    nx: usize,
    np: usize,
    settings: IntegratorSettings,
    ctx: sys::SUNContext,
    mem: *mut c_void,
    y: sys::N_Vector,
    /// `nx + np` sensitivity vectors.
    ys: *mut sys::N_Vector,
    ns: c_int,
    mat: sys::SUNMatrix,
    ls: sys::SUNLinearSolver,
    shared: *mut Shared,
    /// Whether CVODES root finding is switched on (by the last call).
    roots_on: bool,
}

// SAFETY: every pointer is exclusively owned by this value (nothing is shared with other
// integrators), SUNDIALS serial objects have no thread affinity, and all access goes through
// `&mut self`, so moving the integrator to another thread is sound.  It is not `Sync`.
unsafe impl Send for Integrator {}

impl std::fmt::Debug for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Integrator")
            .field("nx", &self.nx)
            .field("np", &self.np)
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

impl Integrator {
    /// Allocate CVODES for `nx ≥ 1` states and `np ≥ 0` parameters with validated settings.
    pub fn new(
        nx: usize,
        np: usize,
        settings: IntegratorSettings,
    ) -> Result<Self, IntegratorError> {
        settings.validate()?;
        if nx == 0 {
            return Err(IntegratorError::Dimension {
                what: "nx (at least 1)",
                expected: 1,
                found: 0,
            });
        }
        let too_large = |found| IntegratorError::Dimension {
            what: "nx + np (must fit a C int)",
            expected: c_int::MAX as usize,
            found,
        };
        let ntot = nx.checked_add(np).ok_or(too_large(usize::MAX))?;
        let ns = c_int::try_from(ntot).map_err(|_| too_large(ntot))?;
        let n = sys::sunindextype::try_from(nx).map_err(|_| too_large(nx))?;
        // Overflow guard for the nx × nx and nx × np buffers.
        nx.checked_mul(ntot).ok_or(too_large(ntot))?;

        let shared = Box::into_raw(Box::new(Shared {
            nx,
            np,
            call: ptr::null(),
            fatal: None,
            recoverable: None,
            cvodes_error: None,
            cvodes_warning: None,
            cache_valid: false,
            cache_t: 0.0,
            cache_y: vec![0.0; nx],
            fx: vec![0.0; nx * nx],
            fp: vec![0.0; nx * np],
            xdot: vec![0.0; nx],
        }));
        // From here on `Drop` frees whatever has been created.
        let mut this = Self {
            nx,
            np,
            settings,
            ctx: ptr::null_mut(),
            mem: ptr::null_mut(),
            y: ptr::null_mut(),
            ys: ptr::null_mut(),
            ns,
            mat: ptr::null_mut(),
            ls: ptr::null_mut(),
            shared,
            roots_on: false,
        };
        // SAFETY: every call below receives pointers created in this function and checked
        // for null; `shared` is a live heap block that outlives the CVODES memory.
        unsafe {
            check_setup(
                "SUNContext_Create",
                sys::SUNContext_Create(ptr::null_mut(), &mut this.ctx),
            )?;
            if this.ctx.is_null() {
                return Err(null_error("SUNContext_Create"));
            }
            this.mem = sys::CVodeCreate(this.settings.method.lmm(), this.ctx);
            if this.mem.is_null() {
                return Err(null_error("CVodeCreate"));
            }
            let eh_data: *mut c_void = shared.cast();
            check_setup(
                "CVodeSetErrHandlerFn",
                sys::CVodeSetErrHandlerFn(this.mem, Some(error_handler), eh_data),
            )?;
            this.y = sys::N_VNew_Serial(n, this.ctx);
            if this.y.is_null() {
                return Err(null_error("N_VNew_Serial"));
            }
            sys::N_VConst(0.0, this.y);
            check_setup(
                "CVodeInit",
                sys::CVodeInit(this.mem, Some(rhs_callback), 0.0, this.y),
            )?;
            let s = &this.settings;
            check_setup(
                "CVodeSStolerances",
                sys::CVodeSStolerances(this.mem, s.rtol, s.atol),
            )?;
            check_setup(
                "CVodeSetUserData",
                sys::CVodeSetUserData(this.mem, shared.cast()),
            )?;
            // Validated positive and within c_long in `validate`.
            let max_steps = c_long::try_from(s.max_steps).unwrap_or(c_long::MAX);
            check_setup(
                "CVodeSetMaxNumSteps",
                sys::CVodeSetMaxNumSteps(this.mem, max_steps),
            )?;
            if let Some(order) = s.max_order {
                check_setup("CVodeSetMaxOrd", sys::CVodeSetMaxOrd(this.mem, order))?;
            }
            if let Some(h) = s.initial_step {
                check_setup("CVodeSetInitStep", sys::CVodeSetInitStep(this.mem, h))?;
            }

            this.mat = sys::SUNDenseMatrix(n, n, this.ctx);
            if this.mat.is_null() {
                return Err(null_error("SUNDenseMatrix"));
            }
            this.ls = dense_lu::new(nx, this.ctx);
            if this.ls.is_null() {
                return Err(null_error("SUNLinSolNewEmpty"));
            }
            check_lin_setup(
                "CVodeSetLinearSolver",
                sys::CVodeSetLinearSolver(this.mem, this.ls, this.mat),
            )?;
            check_lin_setup(
                "CVodeSetJacFn",
                sys::CVodeSetJacFn(this.mem, Some(jac_callback)),
            )?;

            this.ys = sys::N_VCloneVectorArray(ns, this.y);
            if this.ys.is_null() {
                return Err(null_error("N_VCloneVectorArray"));
            }
            this.reset_sensitivities();
            check_setup(
                "CVodeSensInit",
                sys::CVodeSensInit(
                    this.mem,
                    ns,
                    sys::CV_STAGGERED,
                    Some(sens_rhs_callback),
                    this.ys,
                ),
            )?;
            match this.settings.sens_tol {
                Some(t) => {
                    // CVODES copies the absolute tolerances (one per sensitivity)
                    let mut abs = vec![t; ntot];
                    check_setup(
                        "CVodeSensSStolerances",
                        sys::CVodeSensSStolerances(this.mem, t, abs.as_mut_ptr()),
                    )?;
                }
                None => check_setup(
                    "CVodeSensEEtolerances",
                    sys::CVodeSensEEtolerances(this.mem),
                )?,
            }
            check_setup(
                "CVodeSetSensErrCon",
                sys::CVodeSetSensErrCon(this.mem, c_int::from(this.settings.sens_error_control)),
            )?;
            check_setup("CVodeSensToggleOff", sys::CVodeSensToggleOff(this.mem))?;
        }
        Ok(this)
    }

    /// Number of states.
    pub fn nx(&self) -> usize {
        self.nx
    }

    /// Number of parameters.
    pub fn np(&self) -> usize {
        self.np
    }

    /// The settings the integrator was created with.
    pub fn settings(&self) -> &IntegratorSettings {
        &self.settings
    }

    /// Counters of the last call (with sensitivities).
    pub fn stats_snapshot(&self) -> IntegrationStats {
        self.stats(true)
    }

    /// Integrate from `x(t0) = x0` to `t1` and write the end state into `x1` (length nx).
    pub fn integrate(
        &mut self,
        ode: &dyn Ode,
        t0: f64,
        t1: f64,
        x0: &[f64],
        p: &[f64],
        x1: &mut [f64],
    ) -> Result<IntegrationStats, IntegratorError> {
        check_dim("x1", self.nx, x1.len())?;
        self.start(ode, t0, t1, x0, p, false)?;
        let ctx = CallCtx {
            ode,
            p,
            event: None,
        };
        // SAFETY: `ctx` outlives the guard; `shared` is live.
        let guard = unsafe { CallGuard::new(self.shared, &ctx) };
        self.advance(t0, t1)?;
        drop(guard);
        let y = self.state();
        if !all_finite(y) {
            return Err(IntegratorError::NonFinite { t: t1 });
        }
        x1.copy_from_slice(y);
        Ok(self.stats(false))
    }

    /// Integrate with forward sensitivities.
    ///
    /// Writes the end state into `x1` (length nx) and `S(t1) = ∂x(t1)/∂(x0, p)` into `s1`
    /// (nx × (nx + np), column-major: first the nx columns ∂x(t1)/∂x0, then the np columns
    /// ∂x(t1)/∂p), starting from `S(t0) = [I | 0]`.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_with_sensitivities(
        &mut self,
        ode: &dyn Ode,
        t0: f64,
        t1: f64,
        x0: &[f64],
        p: &[f64],
        x1: &mut [f64],
        s1: &mut [f64],
    ) -> Result<IntegrationStats, IntegratorError> {
        check_dim("x1", self.nx, x1.len())?;
        check_dim(
            "s1 (nx * (nx + np))",
            self.nx * (self.nx + self.np),
            s1.len(),
        )?;
        self.start(ode, t0, t1, x0, p, true)?;
        let ctx = CallCtx {
            ode,
            p,
            event: None,
        };
        // SAFETY: `ctx` outlives the guard; `shared` is live.
        let guard = unsafe { CallGuard::new(self.shared, &ctx) };
        self.advance(t0, t1)?;
        drop(guard);
        let mut tret = t1;
        // SAFETY: sensitivities are enabled and `ys` holds `ns` vectors.
        let flag = unsafe { sys::CVodeGetSens(self.mem, &mut tret, self.ys) };
        if flag < 0 {
            return Err(self.failure(flag, t1));
        }
        let nx = self.nx;
        let finite = all_finite(self.state())
            && (0..self.ns as usize).all(|i| all_finite(self.sensitivity(i)));
        if !finite {
            return Err(IntegratorError::NonFinite { t: t1 });
        }
        x1.copy_from_slice(self.state());
        for (i, col) in s1.chunks_exact_mut(nx).enumerate() {
            col.copy_from_slice(self.sensitivity(i));
        }
        Ok(self.stats(true))
    }

    /// States and forward sensitivities at the strictly increasing output times
    /// `times ⊂ (t0, t1]` (the integrator's own interpolant, like
    /// [`integrate_dense`](Self::integrate_dense)). Appends nx values per time to `xs` and
    /// nx·(nx + np) values per time (column-major `S(t)`, as in
    /// [`integrate_with_sensitivities`](Self::integrate_with_sensitivities)) to `ss`.
    /// Used for quadratures along the trajectory, e.g. exact second derivatives.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_with_sensitivities_dense(
        &mut self,
        ode: &dyn Ode,
        t0: f64,
        t1: f64,
        x0: &[f64],
        p: &[f64],
        times: &[f64],
        xs: &mut Vec<f64>,
        ss: &mut Vec<f64>,
    ) -> Result<IntegrationStats, IntegratorError> {
        check_interval(t0, t1)?;
        let mut previous = t0;
        for (index, &t) in times.iter().enumerate() {
            if !(t > previous && t <= t1) {
                return Err(IntegratorError::BadOutputTime { index, t });
            }
            previous = t;
        }
        self.start(ode, t0, t1, x0, p, true)?;
        let ctx = CallCtx {
            ode,
            p,
            event: None,
        };
        // SAFETY: `ctx` outlives the guard; `shared` is live.
        let guard = unsafe { CallGuard::new(self.shared, &ctx) };
        let (lx, ls) = (xs.len(), ss.len());
        let mut result = Ok(());
        let mut t_reached = t0;
        for &t in times {
            match self.advance(t_reached, t) {
                Ok(tr) => t_reached = tr,
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
            let mut tret = t;
            // SAFETY: sensitivities are enabled and `ys` holds `ns` vectors.
            let flag = unsafe { sys::CVodeGetSens(self.mem, &mut tret, self.ys) };
            if flag < 0 {
                result = Err(self.failure(flag, t));
                break;
            }
            let finite = all_finite(self.state())
                && (0..self.ns as usize).all(|i| all_finite(self.sensitivity(i)));
            if !finite {
                result = Err(IntegratorError::NonFinite { t });
                break;
            }
            xs.extend_from_slice(self.state());
            for i in 0..self.ns as usize {
                ss.extend_from_slice(self.sensitivity(i));
            }
        }
        drop(guard);
        if result.is_err() {
            xs.truncate(lx);
            ss.truncate(ls);
        }
        result.map(|()| self.stats(true))
    }

    /// States at the strictly increasing output times `times ⊂ [t0, t1]`.
    ///
    /// Values come from CVODES's own interpolating polynomial (one integration, no extra
    /// steps); `nx` values per time are appended to `out`, row `k` = `x(times[k])`.  On error
    /// `out` is left as it was.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_dense(
        &mut self,
        ode: &dyn Ode,
        t0: f64,
        t1: f64,
        x0: &[f64],
        p: &[f64],
        times: &[f64],
        out: &mut Vec<f64>,
    ) -> Result<IntegrationStats, IntegratorError> {
        check_interval(t0, t1)?;
        let mut previous = f64::NEG_INFINITY;
        for (index, &t) in times.iter().enumerate() {
            // NaN fails every comparison and is rejected here too.
            if !(t >= t0 && t <= t1 && t > previous) {
                return Err(IntegratorError::BadOutputTime { index, t });
            }
            previous = t;
        }
        self.start(ode, t0, t1, x0, p, false)?;
        let ctx = CallCtx {
            ode,
            p,
            event: None,
        };
        // SAFETY: `ctx` outlives the guard; `shared` is live.
        let guard = unsafe { CallGuard::new(self.shared, &ctx) };
        let len = out.len();
        let result = self.dense_outputs(t0, x0, times, out);
        drop(guard);
        if result.is_err() {
            out.truncate(len);
        }
        result.map(|()| self.stats(false))
    }

    /// States at the strictly increasing output times `times ⊂ [t0, t1]`, as
    /// [`integrate_dense`](Self::integrate_dense), stopping early at the first time
    /// `t* ∈ (t0, t1]` where `event(t, x)` falls through zero (from positive to zero or
    /// negative; CVODES root finding on each step's interpolating polynomial, located to a
    /// few ulp of t). Appends the states at the output times before `t*`, then the state
    /// at `t*`, and returns `Some(t*)`; without a root, all output states and `None`. A
    /// root exactly at t0 does not count (the event must first be positive). On error
    /// `out` is left as it was.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_dense_until(
        &mut self,
        ode: &dyn Ode,
        t0: f64,
        t1: f64,
        x0: &[f64],
        p: &[f64],
        times: &[f64],
        event: &dyn Fn(f64, &[f64]) -> f64,
        out: &mut Vec<f64>,
    ) -> Result<(IntegrationStats, Option<f64>), IntegratorError> {
        check_interval(t0, t1)?;
        let mut previous = f64::NEG_INFINITY;
        for (index, &t) in times.iter().enumerate() {
            if !(t >= t0 && t <= t1 && t > previous) {
                return Err(IntegratorError::BadOutputTime { index, t });
            }
            previous = t;
        }
        self.start(ode, t0, t1, x0, p, false)?;
        let mut direction: [c_int; 1] = [-1];
        // SAFETY: `mem` is initialised; one root function; `direction` has one entry and
        // CVODES copies it.
        unsafe {
            check_setup(
                "CVodeRootInit",
                sys::CVodeRootInit(self.mem, 1, Some(root_callback)),
            )?;
            self.roots_on = true;
            check_setup(
                "CVodeSetRootDirection",
                sys::CVodeSetRootDirection(self.mem, direction.as_mut_ptr()),
            )?;
            check_setup(
                "CVodeSetNoInactiveRootWarn",
                sys::CVodeSetNoInactiveRootWarn(self.mem),
            )?;
        }
        let ctx = CallCtx {
            ode,
            p,
            event: Some(event),
        };
        // SAFETY: `ctx` outlives the guard; `shared` is live.
        let guard = unsafe { CallGuard::new(self.shared, &ctx) };
        let len = out.len();
        let result = self.dense_outputs_until(t0, x0, times, out);
        drop(guard);
        if result.is_err() {
            out.truncate(len);
        }
        result.map(|root| (self.stats(false), root))
    }

    fn dense_outputs_until(
        &mut self,
        t0: f64,
        x0: &[f64],
        times: &[f64],
        out: &mut Vec<f64>,
    ) -> Result<Option<f64>, IntegratorError> {
        let mut started = false;
        let mut t_reached = t0;
        for &t in times {
            if !started && t - t0 <= 4.0 * f64::EPSILON * t0.abs().max(t.abs()) {
                out.extend_from_slice(x0);
                continue;
            }
            started = true;
            let (tr, flag) = self.advance_flag(t_reached, t)?;
            t_reached = tr;
            let y = self.state();
            if !all_finite(y) {
                return Err(IntegratorError::NonFinite { t: tr });
            }
            out.extend_from_slice(y);
            if flag == sys::CV_ROOT_RETURN {
                return Ok(Some(tr));
            }
        }
        Ok(None)
    }

    fn dense_outputs(
        &mut self,
        t0: f64,
        x0: &[f64],
        times: &[f64],
        out: &mut Vec<f64>,
    ) -> Result<(), IntegratorError> {
        out.reserve(times.len() * self.nx);
        let mut started = false;
        let mut t_reached = t0;
        for &t in times {
            // CVODES refuses a first output time within a few ulp of t0 (CV_TOO_CLOSE);
            // the state there is x0 to working precision.
            if !started && t - t0 <= 4.0 * f64::EPSILON * t0.abs().max(t.abs()) {
                out.extend_from_slice(x0);
                continue;
            }
            started = true;
            t_reached = self.advance(t_reached, t)?;
            let y = self.state();
            if !all_finite(y) {
                return Err(IntegratorError::NonFinite { t });
            }
            out.extend_from_slice(y);
        }
        Ok(())
    }

    /// Validate the inputs of a call and re-initialise CVODES at `(t0, x0)` with stop time
    /// `t1`, with sensitivities `S(t0) = [I | 0]` on or off.
    fn start(
        &mut self,
        ode: &dyn Ode,
        t0: f64,
        t1: f64,
        x0: &[f64],
        p: &[f64],
        sensitivities: bool,
    ) -> Result<(), IntegratorError> {
        check_dim("ode.nx()", self.nx, ode.nx())?;
        check_dim("ode.np()", self.np, ode.np())?;
        check_dim("x0", self.nx, x0.len())?;
        check_dim("p", self.np, p.len())?;
        check_interval(t0, t1)?;
        if !all_finite(x0) || !all_finite(p) {
            return Err(IntegratorError::NonFinite { t: t0 });
        }
        self.shared_mut().reset();
        // SAFETY: `y` has length nx; `mem` is initialised; `ys` holds `ns` vectors.
        unsafe {
            nv_slice_mut(self.y, self.nx).copy_from_slice(x0);
            check_setup("CVodeReInit", sys::CVodeReInit(self.mem, t0, self.y))?;
            check_setup("CVodeSetStopTime", sys::CVodeSetStopTime(self.mem, t1))?;
            if self.roots_on {
                check_setup("CVodeRootInit", sys::CVodeRootInit(self.mem, 0, None))?;
                self.roots_on = false;
            }
            if sensitivities {
                self.reset_sensitivities();
                check_setup(
                    "CVodeSensReInit",
                    sys::CVodeSensReInit(self.mem, sys::CV_STAGGERED, self.ys),
                )?;
            } else {
                check_setup("CVodeSensToggleOff", sys::CVodeSensToggleOff(self.mem))?;
            }
        }
        Ok(())
    }

    /// Advance to `tout` (CV_NORMAL, interpolating inside the last step); returns the
    /// reached time.  `t_from` is reported if CVODES fails before taking a step.
    fn advance(&mut self, t_from: f64, tout: f64) -> Result<f64, IntegratorError> {
        self.advance_flag(t_from, tout).map(|(t, _)| t)
    }

    /// [`advance`](Self::advance), also returning CVODES's non-negative flag
    /// (`CV_ROOT_RETURN` when an event stopped it before `tout`).
    fn advance_flag(&mut self, t_from: f64, tout: f64) -> Result<(f64, c_int), IntegratorError> {
        let mut tret = t_from;
        // SAFETY: `mem` is initialised by `start`; `y` has length nx; the call context is set.
        let flag = unsafe { sys::CVode(self.mem, tout, self.y, &mut tret, sys::CV_NORMAL) };
        if flag < 0 {
            return Err(self.failure(flag, tret));
        }
        Ok((tret, flag))
    }

    /// Turn a negative CVODES flag into an error, preferring the ODE's own fatal error.
    fn failure(&mut self, flag: c_int, t: f64) -> IntegratorError {
        let shared = self.shared_mut();
        if let Some((t, source)) = shared.fatal.take() {
            return IntegratorError::Rhs { t, source };
        }
        let mut message = shared
            .cvodes_error
            .take()
            .or_else(|| shared.cvodes_warning.take())
            .unwrap_or_default();
        if let Some((tr, e)) = shared.recoverable.take() {
            message.push_str(&format!("; last recoverable ODE failure at t = {tr}: {e}"));
        }
        IntegratorError::Failed {
            flag,
            flag_name: flag_name(flag),
            t,
            message,
        }
    }

    fn stats(&self, sensitivities: bool) -> IntegrationStats {
        type Getter = unsafe extern "C" fn(*mut c_void, *mut c_long) -> c_int;
        let read = |getter: Getter| {
            let mut n: c_long = 0;
            // SAFETY: `mem` is a live CVODES memory block; the getter writes one long.
            let flag = unsafe { getter(self.mem, &mut n) };
            if flag < 0 {
                0
            } else {
                u64::try_from(n).unwrap_or(0)
            }
        };
        IntegrationStats {
            steps: read(sys::CVodeGetNumSteps),
            rhs_evals: read(sys::CVodeGetNumRhsEvals),
            jac_evals: read(sys::CVodeGetNumJacEvals),
            sens_rhs_evals: if sensitivities {
                read(sys::CVodeGetSensNumRhsEvals)
            } else {
                0
            },
            error_test_failures: read(sys::CVodeGetNumErrTestFails),
            nonlinear_conv_failures: read(sys::CVodeGetNumNonlinSolvConvFails),
            nonlinear_iters: read(sys::CVodeGetNumNonlinSolvIters),
            sens_nonlinear_iters: if sensitivities {
                read(sys::CVodeGetSensNumNonlinSolvIters)
            } else {
                0
            },
            linear_setups: read(sys::CVodeGetNumLinSolvSetups),
        }
    }

    /// Set the sensitivity vectors to `[I | 0]`.
    fn reset_sensitivities(&mut self) {
        for i in 0..self.ns as usize {
            // SAFETY: `ys` holds `ns` serial vectors of length nx.
            let col = unsafe { nv_slice_mut(*self.ys.add(i), self.nx) };
            col.fill(0.0);
            if i < self.nx {
                col[i] = 1.0;
            }
        }
    }

    fn state(&self) -> &[f64] {
        // SAFETY: `y` is a serial vector of length nx owned by `self`.
        unsafe { nv_slice(self.y, self.nx) }
    }

    fn sensitivity(&self, i: usize) -> &[f64] {
        debug_assert!(i < self.ns as usize);
        // SAFETY: `ys` holds `ns` serial vectors of length nx owned by `self`.
        unsafe { nv_slice(*self.ys.add(i), self.nx) }
    }

    fn shared_mut(&mut self) -> &mut Shared {
        // SAFETY: `shared` is a live heap block owned by `self`; CVODES does not run while
        // `&mut self` is borrowed here, so no callback holds a reference to it.
        unsafe { &mut *self.shared }
    }
}

impl Drop for Integrator {
    fn drop(&mut self) {
        // SAFETY: each pointer is either null or owned by `self`, and is freed exactly once,
        // CVODES memory first (it refers to the vectors, matrix and solver).
        unsafe {
            if !self.mem.is_null() {
                sys::CVodeFree(&mut self.mem);
            }
            if !self.ls.is_null() {
                sys::SUNLinSolFree(self.ls);
            }
            if !self.mat.is_null() {
                sys::SUNMatDestroy(self.mat);
            }
            if !self.ys.is_null() {
                sys::N_VDestroyVectorArray(self.ys, self.ns);
            }
            if !self.y.is_null() {
                sys::N_VDestroy(self.y);
            }
            if !self.ctx.is_null() {
                sys::SUNContext_Free(&mut self.ctx);
            }
            if !self.shared.is_null() {
                drop(Box::from_raw(self.shared));
            }
        }
    }
}

/// A dense LU linear solver for CVODES's Newton systems, in Rust.
///
/// CVODES's staggered corrector solves the Newton system once per sensitivity column
/// and iteration: about 19,000 solves of a 30 × 30 system in one 40 ms interval of the
/// gait model with 55 columns. SUNDIALS's own dense solver (`SUNDlsMat_denseGETRS`)
/// spent a third of the interval's time there; this one factors with partial pivoting
/// into one contiguous column-major block and substitutes over contiguous columns.
mod dense_lu {
    use super::sys;
    use std::ffi::c_int;

    /// Factors of the last setup.
    struct Content {
        n: usize,
        /// L (unit lower, below the diagonal) and U, column-major.
        lu: Vec<f64>,
        /// Row exchanged with row k at step k.
        pivots: Vec<usize>,
        /// 0, or the 1-based column of a zero pivot found by the last setup.
        last_flag: i64,
    }

    /// A new solver for `n × n` dense matrices; null if SUNDIALS cannot allocate it.
    ///
    /// # Safety
    /// `ctx` is a live SUNDIALS context.
    pub(super) unsafe fn new(n: usize, ctx: sys::SUNContext) -> sys::SUNLinearSolver {
        // SAFETY: `ctx` is live (caller); the returned solver has allocated, zeroed ops.
        let s = unsafe { sys::SUNLinSolNewEmpty(ctx) };
        if s.is_null() {
            return s;
        }
        let content = Box::new(Content {
            n,
            lu: vec![0.0; n * n],
            pivots: vec![0; n],
            last_flag: 0,
        });
        // SAFETY: `s` and its ops were just allocated by SUNDIALS and are ours to fill.
        unsafe {
            (*s).content = Box::into_raw(content).cast();
            let ops = &mut *(*s).ops;
            ops.gettype = Some(get_type);
            ops.setup = Some(setup);
            ops.solve = Some(solve);
            ops.lastflag = Some(last_flag);
            ops.free = Some(free);
        }
        s
    }

    /// # Safety
    /// `s` was made by [`new`] and not freed.
    unsafe fn content<'a>(s: sys::SUNLinearSolver) -> &'a mut Content {
        // SAFETY: `content` holds the boxed `Content` of `new` until `free`.
        unsafe { &mut *(*s).content.cast::<Content>() }
    }

    unsafe extern "C" fn get_type(_s: sys::SUNLinearSolver) -> sys::SUNLinearSolver_Type {
        sys::SUNLinearSolver_Type_SUNLINEARSOLVER_DIRECT
    }

    unsafe extern "C" fn last_flag(s: sys::SUNLinearSolver) -> sys::sunindextype {
        // SAFETY: CVODES passes the solver it was given.
        unsafe { content(s).last_flag as sys::sunindextype }
    }

    /// LU with partial pivoting of the dense matrix `a`; a zero pivot is a recoverable
    /// failure (CVODES retries with a smaller step), as in SUNDIALS's dense solver.
    unsafe extern "C" fn setup(s: sys::SUNLinearSolver, a: sys::SUNMatrix) -> c_int {
        // SAFETY: CVODES passes our solver and the n × n dense matrix it was built with,
        // stored column-major in one contiguous block.
        let (c, data) = unsafe {
            let c = content(s);
            let n = c.n;
            (
                c,
                std::slice::from_raw_parts(sys::SUNDenseMatrix_Data(a), n * n),
            )
        };
        c.lu.copy_from_slice(data);
        c.last_flag = factor(c.n, &mut c.lu, &mut c.pivots);
        if c.last_flag == 0 {
            0
        } else {
            sys::SUNLS_LUFACT_FAIL as c_int
        }
    }

    /// x = A⁻¹ b from the factors of the last setup.
    unsafe extern "C" fn solve(
        s: sys::SUNLinearSolver,
        _a: sys::SUNMatrix,
        x: sys::N_Vector,
        b: sys::N_Vector,
        _tol: f64,
    ) -> c_int {
        // SAFETY: our solver; `x` and `b` are serial vectors of length n (possibly the
        // same vector), read before `x` is written.
        unsafe {
            let c = content(s);
            let n = c.n;
            let bp = sys::N_VGetArrayPointer(b);
            let xp = sys::N_VGetArrayPointer(x);
            if bp != xp {
                std::ptr::copy_nonoverlapping(bp, xp, n);
            }
            substitute(n, &c.lu, &c.pivots, std::slice::from_raw_parts_mut(xp, n));
        }
        0
    }

    unsafe extern "C" fn free(s: sys::SUNLinearSolver) -> c_int {
        if s.is_null() {
            return 0;
        }
        // SAFETY: `content` is the box of `new` (or null after a previous free); the rest
        // is freed by SUNDIALS's own routine for a solver made by SUNLinSolNewEmpty.
        unsafe {
            let c = (*s).content.cast::<Content>();
            if !c.is_null() {
                drop(Box::from_raw(c));
                (*s).content = std::ptr::null_mut();
            }
            sys::SUNLinSolFreeEmpty(s);
        }
        0
    }

    /// In-place LU with partial pivoting of the column-major `n × n` matrix `a`
    /// (`PA = LU`, L unit lower); 0, or the 1-based column of a zero pivot.
    pub(super) fn factor(n: usize, a: &mut [f64], pivots: &mut [usize]) -> i64 {
        for k in 0..n {
            let col = &a[k * n..(k + 1) * n];
            let mut p = k;
            for i in k + 1..n {
                if col[i].abs() > col[p].abs() {
                    p = i;
                }
            }
            pivots[k] = p;
            if a[k * n + p] == 0.0 {
                return k as i64 + 1;
            }
            if p != k {
                for j in 0..n {
                    a.swap(j * n + k, j * n + p);
                }
            }
            let inv = 1.0 / a[k * n + k];
            for v in &mut a[k * n + k + 1..(k + 1) * n] {
                *v *= inv;
            }
            let (left, right) = a.split_at_mut((k + 1) * n);
            let lk = &left[k * n + k + 1..(k + 1) * n];
            for j in 0..n - k - 1 {
                let colj = &mut right[j * n..(j + 1) * n];
                let akj = colj[k];
                if akj != 0.0 {
                    for (v, l) in colj[k + 1..].iter_mut().zip(lk) {
                        *v -= l * akj;
                    }
                }
            }
        }
        0
    }

    /// Solve `LU x = P b` in place (`x` holds b on entry).
    pub(super) fn substitute(n: usize, lu: &[f64], pivots: &[usize], x: &mut [f64]) {
        for k in 0..n {
            x.swap(k, pivots[k]);
        }
        for k in 0..n {
            let xk = x[k];
            if xk != 0.0 {
                for (v, l) in x[k + 1..].iter_mut().zip(&lu[k * n + k + 1..(k + 1) * n]) {
                    *v -= l * xk;
                }
            }
        }
        for k in (0..n).rev() {
            x[k] /= lu[k * n + k];
            let xk = x[k];
            for (v, u) in x[..k].iter_mut().zip(&lu[k * n..k * n + k]) {
                *v -= u * xk;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::dense_lu::{factor, substitute};

    /// The LU solve against nalgebra's on matrices that need pivoting, and a singular
    /// matrix reported by the column of its zero pivot.
    #[test]
    fn dense_lu_solves_like_nalgebra_and_reports_a_zero_pivot() {
        let n = 30;
        let mut seed = 12345u64;
        let mut rand = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for trial in 0..5 {
            // small diagonal: every column needs a row exchange somewhere
            let a =
                nalgebra::DMatrix::from_fn(
                    n,
                    n,
                    |i, j| if i == j { 1e-3 * trial as f64 } else { rand() },
                );
            let b = nalgebra::DVector::from_fn(n, |_, _| rand());
            let mut lu: Vec<f64> = a.as_slice().to_vec();
            let mut piv = vec![0; n];
            assert_eq!(factor(n, &mut lu, &mut piv), 0);
            let mut x = b.as_slice().to_vec();
            substitute(n, &lu, &piv, &mut x);
            let want = a.clone().lu().solve(&b).unwrap();
            let err = (nalgebra::DVector::from_vec(x) - &want).amax() / want.amax();
            assert!(err < 1e-12, "trial {trial}: relative error {err}");
        }
        // column 3 a combination of columns 0 and 1: the third pivot is zero
        let mut a = nalgebra::DMatrix::<f64>::identity(4, 4);
        a[(0, 2)] = 1.0;
        a[(1, 2)] = 2.0;
        a[(2, 2)] = 0.0;
        let mut lu = a.as_slice().to_vec();
        assert_eq!(factor(4, &mut lu, &mut [0; 4]), 3);
    }
}
