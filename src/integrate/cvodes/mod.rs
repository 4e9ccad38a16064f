//! Safe wrapper over SUNDIALS CVODES (version 6) for ODEs of fixed dimension.
//!
//! These files are the only place in the crate that touches `sundials_sys` or uses `unsafe`.
//! An [`Integrator`] owns every SUNDIALS object it creates (context, CVODES memory, state
//! and sensitivity vectors, dense Jacobian matrix and linear solver) and frees them in
//! `Drop`.  It is built once for a pair `(nx, np)` and re-initialised for every call, so the
//! allocation cost is paid once per worker thread.
//!
//! Both linear multistep families use a Newton iteration with a dense direct linear solver
//! and the exact Jacobian $f_x$ from [`Ode::jacobians`](super::Ode::jacobians).  Forward
//! sensitivities use the staggered corrector (`CV_STAGGERED`) with a user-supplied
//! sensitivity right-hand side $\dot S_i = f_x S_i + f_{p,i}$; CVODES never forms difference
//! quotients.
//!
//! One home per concept: `settings` (options, counters, errors), `callbacks` (the C
//! callbacks and the block they share with CVODES), `forward` (the forward problem both
//! create), `integrator` (creation, the end-point calls, teardown, and in
//! `integrator::adjoint` the backward adjoints of stiff models), `dense` (output at interior
//! times, events), `dense_lu` (the Newton systems' linear solver), `vector_ops` (the serial
//! vector kernels CVODES runs on).

mod callbacks;
mod dense;
mod dense_lu;
mod forward;
mod integrator;
mod settings;
mod vector_ops;

pub(crate) use callbacks::check_dim;
pub use integrator::{AdjointSweep, Integrator, MAX_CELL_NODES};
pub use settings::{IntegrationStats, IntegratorError, IntegratorSettings, Method};
