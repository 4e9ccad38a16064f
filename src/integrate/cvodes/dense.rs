//! Dense output: states (and sensitivities) at interior times from CVODES's own
//! interpolant, and integration that stops at an event.
#![allow(unsafe_code)]

use std::ffi::c_int;

use sundials_sys as sys;

use super::callbacks::{
    all_finite, check_interval, check_setup, root_callback, CallCtx, CallGuard,
};
use super::integrator::Integrator;
use super::settings::{IntegrationStats, IntegratorError};
use crate::integrate::Ode;

impl Integrator {
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
        let ctx = CallCtx::new(ode, p);
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
        check_output_times(t0, t1, times)?;
        self.start(ode, t0, t1, x0, p, false)?;
        let ctx = CallCtx::new(ode, p);
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
        check_output_times(t0, t1, times)?;
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
        let mut t_reached = t0;
        for &t in outputs_at_t0(t0, x0, times, out) {
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
        let mut t_reached = t0;
        for &t in outputs_at_t0(t0, x0, times, out) {
            t_reached = self.advance(t_reached, t)?;
            let y = self.state();
            if !all_finite(y) {
                return Err(IntegratorError::NonFinite { t });
            }
            out.extend_from_slice(y);
        }
        Ok(())
    }
}

/// Output times must increase strictly within `[t0, t1]`.
fn check_output_times(t0: f64, t1: f64, times: &[f64]) -> Result<(), IntegratorError> {
    let mut previous = f64::NEG_INFINITY;
    for (index, &t) in times.iter().enumerate() {
        // NaN fails every comparison and is rejected here too.
        if !(t >= t0 && t <= t1 && t > previous) {
            return Err(IntegratorError::BadOutputTime { index, t });
        }
        previous = t;
    }
    Ok(())
}

/// Append `x0` for the leading output times within a few ulp of `t0` and return the
/// others: CVODES refuses a first output time that close (CV_TOO_CLOSE), and the state
/// there is x0 to working precision.
fn outputs_at_t0<'t>(t0: f64, x0: &[f64], times: &'t [f64], out: &mut Vec<f64>) -> &'t [f64] {
    let k = times
        .iter()
        .take_while(|&&t| t - t0 <= 4.0 * f64::EPSILON * t0.abs().max(t.abs()))
        .count();
    for _ in 0..k {
        out.extend_from_slice(x0);
    }
    &times[k..]
}
