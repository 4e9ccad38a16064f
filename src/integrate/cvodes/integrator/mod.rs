//! The [`Integrator`]: creation, the calls that return the end point, and teardown; its
//! backward adjoints of stiff models in [`adjoint`].
#![allow(unsafe_code)]

mod adjoint;

pub use adjoint::{AdjointSweep, MAX_CELL_NODES};

use std::ffi::{c_int, c_long, c_void};
use std::ptr;

use sundials_sys as sys;

use super::callbacks::{
    all_finite, check_dim, check_interval, check_setup, null_error, nv_slice, nv_slice_mut,
    sens_rhs_callback, CallCtx, CallGuard, Shared,
};
use super::forward;
use super::settings::{IntegrationStats, IntegratorError, IntegratorSettings};
use crate::integrate::Ode;

/// A reusable CVODES instance for ODEs with `nx` states and `np` parameters.
///
/// Create one per worker thread and call it for many intervals; every call re-initialises
/// CVODES (`CVodeReInit`) and sets the stop time to `t1`, so no step goes past `t1` and the
/// result does not depend on earlier calls.  Outputs are written only on success.
pub struct Integrator {
    pub(super) nx: usize,
    pub(super) np: usize,
    pub(super) settings: IntegratorSettings,
    pub(super) ctx: sys::SUNContext,
    pub(super) mem: *mut c_void,
    pub(super) y: sys::N_Vector,
    /// `nx + np` sensitivity vectors.
    pub(super) ys: *mut sys::N_Vector,
    pub(super) ns: c_int,
    pub(super) mat: sys::SUNMatrix,
    pub(super) ls: sys::SUNLinearSolver,
    pub(super) shared: *mut Shared,
    /// Whether CVODES root finding is switched on (by the last call).
    pub(super) roots_on: bool,
    /// The adjoint pass's own CVODES objects, made by the first
    /// [`adjoints`](Self::adjoints) call.
    adjoint: Option<adjoint::Adjoint>,
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

        let shared = Box::into_raw(Box::new(Shared::new(nx, np)));
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
            adjoint: None,
        };
        // SAFETY: every call below receives pointers created in this function and checked
        // for null; `shared` is a live heap block that outlives the CVODES memory, and the
        // slots are the fresh value's null fields.
        unsafe {
            forward::create(
                forward::Slots {
                    ctx: &mut this.ctx,
                    mem: &mut this.mem,
                    y: &mut this.y,
                    mat: &mut this.mat,
                    ls: &mut this.ls,
                },
                (nx, n),
                &this.settings,
                shared,
                // the sensitivity vectors are cloned from `y`: CVODES then updates them all
                // in one pass per operation instead of one `N_VLinearSum` per vector
                forward::Options {
                    fused_ops: true,
                    initial_step: this.settings.initial_step,
                },
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

    /// Change the state tolerances (`rtol`, `atol`) and the sensitivities' own tolerance
    /// (`sens_tol`, when the integrator was created with one) for the following calls; the
    /// other settings stay. An inexact SQP tightens them as it nears an optimum.
    pub fn set_tolerances(
        &mut self,
        rtol: f64,
        atol: f64,
        sens_tol: Option<f64>,
    ) -> Result<(), IntegratorError> {
        let settings = IntegratorSettings {
            rtol,
            atol,
            sens_tol: sens_tol.filter(|_| self.settings.sens_tol.is_some()),
            ..self.settings.clone()
        };
        settings.validate()?;
        // SAFETY: `mem` is initialised (and its sensitivities, with `ns` of them) by `new`.
        unsafe {
            check_setup(
                "CVodeSStolerances",
                sys::CVodeSStolerances(self.mem, rtol, atol),
            )?;
            if let Some(t) = settings.sens_tol {
                let mut abs = vec![t; self.ns as usize];
                check_setup(
                    "CVodeSensSStolerances",
                    sys::CVodeSensSStolerances(self.mem, t, abs.as_mut_ptr()),
                )?;
            }
        }
        self.settings = settings;
        Ok(())
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
        let ctx = CallCtx::new(ode, p);
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
        let ctx = CallCtx::new(ode, p);
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
}

impl Integrator {
    /// Validate the inputs of a call and re-initialise CVODES at `(t0, x0)` with stop time
    /// `t1`, with sensitivities `S(t0) = [I | 0]` on or off.
    pub(super) fn start(
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
    pub(super) fn advance(&mut self, t_from: f64, tout: f64) -> Result<f64, IntegratorError> {
        self.advance_flag(t_from, tout).map(|(t, _)| t)
    }

    /// [`advance`](Self::advance), also returning CVODES's non-negative flag
    /// (`CV_ROOT_RETURN` when an event stopped it before `tout`).
    pub(super) fn advance_flag(
        &mut self,
        t_from: f64,
        tout: f64,
    ) -> Result<(f64, c_int), IntegratorError> {
        let mut tret = t_from;
        // SAFETY: `mem` is initialised by `start`; `y` has length nx; the call context is set.
        let flag = unsafe { sys::CVode(self.mem, tout, self.y, &mut tret, sys::CV_NORMAL) };
        if flag < 0 {
            return Err(self.failure(flag, tret));
        }
        Ok((tret, flag))
    }

    /// Turn a negative CVODES flag into an error, preferring the ODE's own fatal error.
    pub(super) fn failure(&mut self, flag: c_int, t: f64) -> IntegratorError {
        self.shared_mut().failure(flag, t)
    }

    pub(super) fn stats(&self, sensitivities: bool) -> IntegrationStats {
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

    pub(super) fn state(&self) -> &[f64] {
        // SAFETY: `y` is a serial vector of length nx owned by `self`.
        unsafe { nv_slice(self.y, self.nx) }
    }

    pub(super) fn sensitivity(&self, i: usize) -> &[f64] {
        assert!(i < self.ns as usize);
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
