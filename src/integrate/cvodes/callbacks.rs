//! Callback plumbing between CVODES and Rust.
//!
//! CVODES 6 captures the user-data pointer for the sensitivity right-hand side once, in
//! `CVodeSensInit`, and `CVodeSensReInit` does not refresh it.  The callbacks therefore
//! receive a heap-allocated [`Shared`] block whose address never changes; the borrowed ODE
//! and parameter vector of the current call are stored in it for the duration of the call
//! only (see [`CallGuard`]).  Panics stop at the C boundary ([`run_callback`]).
#![allow(unsafe_code)]

use std::ffi::{c_char, c_int, c_long, c_void, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::ptr;

use sundials_sys as sys;

use super::settings::IntegratorError;
use crate::integrate::{Ode, OdeError};

/// The borrowed inputs of one call, on the caller's stack.
pub(super) struct CallCtx<'a> {
    pub(super) ode: &'a dyn Ode,
    pub(super) p: &'a [f64],
    /// Event function `g(t, x)` of a call with root finding.
    pub(super) event: Option<&'a dyn Fn(f64, &[f64]) -> f64>,
}

impl<'a> CallCtx<'a> {
    /// The context of a call without root finding.
    pub(super) fn new(ode: &'a dyn Ode, p: &'a [f64]) -> Self {
        CallCtx {
            ode,
            p,
            event: None,
        }
    }
}

/// Heap block shared with the C callbacks through CVODES's user-data and error-handler
/// pointers.  Its address is fixed for the integrator's lifetime.
pub(super) struct Shared {
    pub(super) nx: usize,
    pub(super) np: usize,
    /// Points to the current call's [`CallCtx`]; null outside a call.
    pub(super) call: *const c_void,
    /// First fatal ODE error of the current call, with its time.
    pub(super) fatal: Option<(f64, OdeError)>,
    /// Last recoverable ODE error of the current call, with its time.
    pub(super) recoverable: Option<(f64, OdeError)>,
    /// Last CVODES error message of the current call.
    pub(super) cvodes_error: Option<String>,
    /// Last CVODES warning of the current call.
    pub(super) cvodes_warning: Option<String>,
    /// Whether `cache_*`, `fx`, `fp` hold the Jacobians at (`cache_t`, `cache_y`).
    pub(super) cache_valid: bool,
    pub(super) cache_t: f64,
    pub(super) cache_y: Vec<f64>,
    pub(super) fx: Vec<f64>,
    pub(super) fp: Vec<f64>,
    pub(super) xdot: Vec<f64>,
    /// The adjoint pass's last restart time, where its running moments start.
    pub(super) restart: f64,
}

impl Shared {
    /// A fresh block for `nx` states and `np` parameters, outside any call.
    pub(super) fn new(nx: usize, np: usize) -> Self {
        Shared {
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
            restart: 0.0,
        }
    }

    /// A failed CVODES call (`flag`, at `t`) as an error, preferring the ODE's own fatal
    /// error, with CVODES's message and the last recoverable ODE failure.
    pub(super) fn failure(&mut self, flag: c_int, t: f64) -> IntegratorError {
        if let Some((t, source)) = self.fatal.take() {
            return IntegratorError::Rhs { t, source };
        }
        let mut message = self
            .cvodes_error
            .take()
            .or_else(|| self.cvodes_warning.take())
            .unwrap_or_default();
        if let Some((tr, e)) = self.recoverable.take() {
            message.push_str(&format!("; last recoverable ODE failure at t = {tr}: {e}"));
        }
        IntegratorError::Failed {
            flag,
            flag_name: flag_name(flag),
            t,
            message,
        }
    }

    pub(super) fn reset(&mut self) {
        self.fatal = None;
        self.recoverable = None;
        self.cvodes_error = None;
        self.cvodes_warning = None;
        self.cache_valid = false;
    }

    /// Evaluate `fx`, `fp` at `(t, y)` unless the cache already holds exactly that point.
    pub(super) fn ensure_jacobians(
        &mut self,
        ctx: &CallCtx<'_>,
        t: f64,
        y: &[f64],
    ) -> Result<(), OdeError> {
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
pub(super) struct CallGuard(*mut Shared);

impl CallGuard {
    /// # Safety
    /// `shared` must be valid for the guard's lifetime and `ctx` must outlive the guard.
    pub(super) unsafe fn new(shared: *mut Shared, ctx: &CallCtx<'_>) -> Self {
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

pub(super) fn all_finite(v: &[f64]) -> bool {
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
/// A solve asked to stop ([`crate::interrupt::stop_now`]) fails the call at once.
///
/// # Safety
/// `user_data` must be null or the integrator's `Shared` block, whose `call` is null or
/// points to a live `CallCtx`.
pub(super) unsafe fn run_callback(
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
    // a solve asked to stop: the integration ends at this step
    if crate::interrupt::stop_now() {
        if shared.fatal.is_none() {
            shared.fatal = Some((t, OdeError::Fatal(crate::interrupt::STOPPED.into())));
        }
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
pub(super) unsafe fn nv_slice<'a>(v: sys::N_Vector, n: usize) -> &'a [f64] {
    std::slice::from_raw_parts(sys::N_VGetArrayPointer(v), n)
}

/// # Safety
/// `v` must be a serial N_Vector of length at least `n`, not aliased during the borrow.
pub(super) unsafe fn nv_slice_mut<'a>(v: sys::N_Vector, n: usize) -> &'a mut [f64] {
    std::slice::from_raw_parts_mut(sys::N_VGetArrayPointer(v), n)
}

/// `CVRhsFn`: ẏ = f(t, y, p).  Non-finite output is reported as recoverable so that CVODES
/// retries with a smaller step.
pub(super) unsafe extern "C" fn rhs_callback(
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
pub(super) unsafe extern "C" fn jac_callback(
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
pub(super) unsafe extern "C" fn sens_rhs_callback(
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
pub(super) unsafe extern "C" fn root_callback(
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
pub(super) unsafe extern "C" fn error_handler(
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
pub(super) fn flag_name(flag: c_int) -> String {
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

pub(super) fn check_setup(function: &'static str, flag: c_int) -> Result<(), IntegratorError> {
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

pub(super) fn check_lin_setup(function: &'static str, flag: c_int) -> Result<(), IntegratorError> {
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

pub(super) fn null_error(function: &'static str) -> IntegratorError {
    IntegratorError::Setup {
        function,
        flag: sys::CV_MEM_FAIL,
        flag_name: flag_name(sys::CV_MEM_FAIL),
    }
}

/// A [`IntegratorError::Dimension`] when a buffer `what` has `found` entries, not `expected`.
pub(crate) fn check_dim(
    what: &'static str,
    expected: usize,
    found: usize,
) -> Result<(), IntegratorError> {
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

pub(super) fn check_interval(t0: f64, t1: f64) -> Result<(), IntegratorError> {
    if t0.is_finite() && t1.is_finite() && t1 > t0 {
        Ok(())
    } else {
        Err(IntegratorError::BadInterval { t0, t1 })
    }
}
