//! The forward problem that the [`Integrator`](super::Integrator) and the adjoint pass both
//! create: a context, CVODES memory with footfall's error handler and shared block, a state
//! vector, the tolerances and step limits, and the dense Newton solver with the exact
//! Jacobian. Each owner adds its own: the sensitivities, or the backward problem.
#![allow(unsafe_code)]

use std::ffi::{c_long, c_void};

use sundials_sys as sys;

use super::callbacks::{
    check_lin_setup, check_setup, error_handler, jac_callback, null_error, rhs_callback, Shared,
};
use super::settings::{IntegratorError, IntegratorSettings};
use super::{dense_lu, vector_ops};

/// The owner's fields that [`create`] fills, each as soon as its object exists, so that
/// the owner's `Drop` frees whatever was made before a failure.
pub(super) struct Slots<'a> {
    pub(super) ctx: &'a mut sys::SUNContext,
    pub(super) mem: &'a mut *mut c_void,
    pub(super) y: &'a mut sys::N_Vector,
    pub(super) mat: &'a mut sys::SUNMatrix,
    pub(super) ls: &'a mut sys::SUNLinearSolver,
}

/// How the two forward problems differ.
pub(super) struct Options {
    /// Fused vector kernels on `y`, which vectors cloned from it inherit (the
    /// integrator's sensitivities: one pass per operation over all of them).
    pub(super) fused_ops: bool,
    /// CVODES's first step (s); `None` lets it choose.
    pub(super) initial_step: Option<f64>,
}

/// Create the forward problem of `nx` states (`n`, the same as a SUNDIALS index) with
/// `settings`, its callbacks reading the block `shared`, into `slots`.
///
/// # Safety
/// `shared` must be a live heap block that outlives the CVODES memory, and every slot
/// null (the owner frees what is put there).
pub(super) unsafe fn create(
    slots: Slots<'_>,
    (nx, n): (usize, sys::sunindextype),
    settings: &IntegratorSettings,
    shared: *mut Shared,
    options: Options,
) -> Result<(), IntegratorError> {
    let Slots {
        ctx,
        mem,
        y,
        mat,
        ls,
    } = slots;
    // SAFETY: every call receives pointers created here and checked for null; `shared`
    // outlives the CVODES memory (the caller's contract).
    unsafe {
        check_setup(
            "SUNContext_Create",
            sys::SUNContext_Create(std::ptr::null_mut(), ctx),
        )?;
        if ctx.is_null() {
            return Err(null_error("SUNContext_Create"));
        }
        *mem = sys::CVodeCreate(settings.method.lmm(), *ctx);
        if mem.is_null() {
            return Err(null_error("CVodeCreate"));
        }
        check_setup(
            "CVodeSetErrHandlerFn",
            sys::CVodeSetErrHandlerFn(*mem, Some(error_handler), shared.cast()),
        )?;
        *y = sys::N_VNew_Serial(n, *ctx);
        if y.is_null() {
            return Err(null_error("N_VNew_Serial"));
        }
        if options.fused_ops {
            check_setup(
                "N_VEnableFusedOps_Serial",
                sys::N_VEnableFusedOps_Serial(*y, 1),
            )?;
        }
        // footfall's optimised kernels in place of the serial library's (vector_ops.rs),
        // inherited by the clones
        vector_ops::install(*y);
        sys::N_VConst(0.0, *y);
        check_setup(
            "CVodeInit",
            sys::CVodeInit(*mem, Some(rhs_callback), 0.0, *y),
        )?;
        check_setup(
            "CVodeSStolerances",
            sys::CVodeSStolerances(*mem, settings.rtol, settings.atol),
        )?;
        check_setup(
            "CVodeSetUserData",
            sys::CVodeSetUserData(*mem, shared.cast()),
        )?;
        // validated positive by `IntegratorSettings::validate`
        let max_steps = c_long::try_from(settings.max_steps).unwrap_or(c_long::MAX);
        check_setup(
            "CVodeSetMaxNumSteps",
            sys::CVodeSetMaxNumSteps(*mem, max_steps),
        )?;
        if let Some(order) = settings.max_order {
            check_setup("CVodeSetMaxOrd", sys::CVodeSetMaxOrd(*mem, order))?;
        }
        if let Some(h) = options.initial_step {
            check_setup("CVodeSetInitStep", sys::CVodeSetInitStep(*mem, h))?;
        }
        *mat = sys::SUNDenseMatrix(n, n, *ctx);
        if mat.is_null() {
            return Err(null_error("SUNDenseMatrix"));
        }
        *ls = dense_lu::new(nx, *ctx);
        if ls.is_null() {
            return Err(null_error("SUNLinSolNewEmpty"));
        }
        check_lin_setup(
            "CVodeSetLinearSolver",
            sys::CVodeSetLinearSolver(*mem, *ls, *mat),
        )?;
        check_lin_setup(
            "CVodeSetJacFn",
            sys::CVodeSetJacFn(*mem, Some(jac_callback)),
        )?;
    }
    Ok(())
}
