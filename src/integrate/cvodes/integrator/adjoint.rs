//! Backward adjoints of a stiff ODE by CVODES's adjoint module.
//!
//! The weights `μ(t)ᵀ = Σ_{t_j > t} w_jᵀ Ψ(t_j, t)` of an interval's curvature (the
//! second-order adjoint identity, `integrate/interval.rs`) solve the adjoint equation
//! `μ̇ = −f_xᵀ μ` backward from the instants `t_j`, where `μ` jumps by `w_j`. Found from the
//! forward transition matrix they need `Ψ(t)⁻¹`, which a compliant contact's damping makes
//! singular to working precision; integrated backward (BDF, Newton with `−f_xᵀ`), the fast
//! modes decay as they do forward, and nothing is inverted. The forward pass stores the
//! trajectory at every step (`CV_HERMITE` check points) for the backward one to interpolate.
#![allow(unsafe_code)]

use std::ffi::{c_int, c_long, c_void};
use std::ptr;

use sundials_sys as sys;

use super::super::callbacks::{
    all_finite, check_dim, check_interval, check_lin_setup, check_setup, null_error, nv_slice,
    nv_slice_mut, run_callback, CallCtx, CallGuard, Shared,
};
use super::super::settings::{IntegratorError, IntegratorSettings};
use super::super::{dense_lu, forward, vector_ops};
use super::Integrator;
use crate::integrate::{Ode, OdeError};

/// Forward steps between two check points. One interval of the gait model takes a few
/// hundred steps, so its trajectory is kept whole and the backward pass never re-integrates.
const CHECKPOINT_STEPS: c_long = 2000;

/// The CVODES objects of the adjoint pass: a forward problem of `nx` states without
/// sensitivities and one backward problem, with their own context, vectors and solvers.
pub(super) struct Adjoint {
    nx: usize,
    ctx: sys::SUNContext,
    mem: *mut c_void,
    y: sys::N_Vector,
    yb: sys::N_Vector,
    /// The backward problem's running moments (nx · MAX_CELL_NODES).
    qb: sys::N_Vector,
    mat: sys::SUNMatrix,
    ls: sys::SUNLinearSolver,
    mat_b: sys::SUNMatrix,
    ls_b: sys::SUNLinearSolver,
    shared: *mut Shared,
    /// Index of the backward problem (`CVodeCreateB`), once `CVodeInitB` has run.
    which: Option<c_int>,
}

// SAFETY: as for `Integrator`: every pointer is owned by this value and used through `&mut`.
unsafe impl Send for Adjoint {}

impl Adjoint {
    /// Allocate the forward problem for `nx` states and `np` parameters (the parameters
    /// only size the Jacobian cache) with the integrator's settings.
    fn new(nx: usize, np: usize, settings: &IntegratorSettings) -> Result<Self, IntegratorError> {
        let n = sys::sunindextype::try_from(nx).map_err(|_| IntegratorError::Dimension {
            what: "nx (must fit a SUNDIALS index)",
            expected: c_int::MAX as usize,
            found: nx,
        })?;
        let shared = Box::into_raw(Box::new(Shared::new(nx, np)));
        // From here on `Drop` frees whatever has been created.
        let mut this = Self {
            nx,
            ctx: ptr::null_mut(),
            mem: ptr::null_mut(),
            y: ptr::null_mut(),
            yb: ptr::null_mut(),
            qb: ptr::null_mut(),
            mat: ptr::null_mut(),
            ls: ptr::null_mut(),
            mat_b: ptr::null_mut(),
            ls_b: ptr::null_mut(),
            shared,
            which: None,
        };
        // SAFETY: every call receives pointers created here and checked for null; `shared`
        // is a live heap block that outlives the CVODES memory, and the slots are the fresh
        // value's null fields.
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
                settings,
                shared,
                forward::Options {
                    fused_ops: false,
                    initial_step: None,
                },
            )?;
            // the backward problem's state and moments, and its own Newton solver
            this.yb = sys::N_VNew_Serial(n, this.ctx);
            if this.yb.is_null() {
                return Err(null_error("N_VNew_Serial"));
            }
            vector_ops::install(this.yb);
            sys::N_VConst(0.0, this.yb);
            let nq = sys::sunindextype::try_from(nx * MAX_CELL_NODES).unwrap_or(n);
            this.qb = sys::N_VNew_Serial(nq, this.ctx);
            if this.qb.is_null() {
                return Err(null_error("N_VNew_Serial"));
            }
            vector_ops::install(this.qb);
            sys::N_VConst(0.0, this.qb);
            this.mat_b = sys::SUNDenseMatrix(n, n, this.ctx);
            if this.mat_b.is_null() {
                return Err(null_error("SUNDenseMatrix"));
            }
            this.ls_b = dense_lu::new(nx, this.ctx);
            if this.ls_b.is_null() {
                return Err(null_error("SUNLinSolNewEmpty"));
            }
            check_setup(
                "CVodeAdjInit",
                sys::CVodeAdjInit(this.mem, CHECKPOINT_STEPS, sys::CV_HERMITE),
            )?;
        }
        Ok(this)
    }

    fn shared_mut(&mut self) -> &mut Shared {
        // SAFETY: `shared` is owned by `self`; CVODES does not run while it is borrowed.
        unsafe { &mut *self.shared }
    }

    /// A CVODES failure as an error ([`Shared::failure`]).
    fn failure(&mut self, flag: c_int, t: f64) -> IntegratorError {
        self.shared_mut().failure(flag, t)
    }

    /// Start (or restart) the backward problem at `(t, μ)`, its moments at zero, with the
    /// tolerances `rtol` and `atol`.
    fn restart_backward(
        &mut self,
        t: f64,
        mu: &[f64],
        rtol: f64,
        atol: f64,
        max_steps: c_long,
    ) -> Result<c_int, IntegratorError> {
        // SAFETY: `yb` has length nx; `mem` holds a completed forward pass (`CVodeF`).
        unsafe {
            nv_slice_mut(self.yb, self.nx).copy_from_slice(mu);
            let which = match self.which {
                Some(which) => {
                    check_setup(
                        "CVodeReInitB",
                        sys::CVodeReInitB(self.mem, which, t, self.yb),
                    )?;
                    sys::N_VConst(0.0, self.qb);
                    check_setup(
                        "CVodeQuadReInitB",
                        sys::CVodeQuadReInitB(self.mem, which, self.qb),
                    )?;
                    which
                }
                None => {
                    let mut which: c_int = 0;
                    check_setup(
                        "CVodeCreateB",
                        sys::CVodeCreateB(self.mem, sys::CV_BDF, &mut which),
                    )?;
                    check_setup(
                        "CVodeInitB",
                        sys::CVodeInitB(self.mem, which, Some(adjoint_rhs_callback), t, self.yb),
                    )?;
                    check_setup(
                        "CVodeSetUserDataB",
                        sys::CVodeSetUserDataB(self.mem, which, self.shared.cast()),
                    )?;
                    check_setup(
                        "CVodeSetMaxNumStepsB",
                        sys::CVodeSetMaxNumStepsB(self.mem, which, max_steps),
                    )?;
                    check_lin_setup(
                        "CVodeSetLinearSolverB",
                        sys::CVodeSetLinearSolverB(self.mem, which, self.ls_b, self.mat_b),
                    )?;
                    check_lin_setup(
                        "CVodeSetJacFnB",
                        sys::CVodeSetJacFnB(self.mem, which, Some(adjoint_jac_callback)),
                    )?;
                    sys::N_VConst(0.0, self.qb);
                    check_setup(
                        "CVodeQuadInitB",
                        sys::CVodeQuadInitB(self.mem, which, Some(moments_rhs_callback), self.qb),
                    )?;
                    self.which = Some(which);
                    which
                }
            };
            check_setup(
                "CVodeSStolerancesB",
                sys::CVodeSStolerancesB(self.mem, which, rtol, atol),
            )?;
            check_setup(
                "CVodeSetQuadErrConB",
                sys::CVodeSetQuadErrConB(self.mem, which, 1),
            )?;
            check_setup(
                "CVodeQuadSStolerancesB",
                sys::CVodeQuadSStolerancesB(self.mem, which, rtol, atol),
            )?;
            Ok(which)
        }
    }
}

impl Drop for Adjoint {
    fn drop(&mut self) {
        // SAFETY: each pointer is null or owned by `self` and freed once, CVODES memory
        // (with its adjoint memory and backward problem) first.
        unsafe {
            if !self.mem.is_null() {
                sys::CVodeFree(&mut self.mem);
            }
            for ls in [self.ls, self.ls_b] {
                if !ls.is_null() {
                    sys::SUNLinSolFree(ls);
                }
            }
            for mat in [self.mat, self.mat_b] {
                if !mat.is_null() {
                    sys::SUNMatDestroy(mat);
                }
            }
            for v in [self.y, self.yb, self.qb] {
                if !v.is_null() {
                    sys::N_VDestroy(v);
                }
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

/// Nodes per cell of an [`AdjointSweep`] at most (the 4-point Gauss rule).
pub const MAX_CELL_NODES: usize = 4;

/// One backward sweep of [`Integrator::adjoints`]: the adjoint jumps by `w_j` at each of
/// the instants `jumps[j].0`, and its moments are wanted on the cells `[a, b]`.
#[derive(Debug, Clone, Default)]
pub struct AdjointSweep {
    /// `(t_j, w_j)`: where the adjoint jumps, by how much (nx each), in any order.
    pub jumps: Vec<(f64, Vec<f64>)>,
    /// `(a, b, nodes)`: disjoint cells `[a, b]` with 1 to [`MAX_CELL_NODES`] distinct
    /// nodes each; no jump lies strictly inside a cell.
    pub cells: Vec<(f64, f64, Vec<f64>)>,
}

impl Integrator {
    /// The moments `M_k = ∫_a^b L_k(t) μ(t) dt` of the adjoint
    /// `μ(t)ᵀ = Σ_{t_j > t} w_jᵀ Ψ(t_j, t)` of `ode` along the trajectory from `x(t0) = x0`,
    /// where `Ψ(t_j, t) = ∂x(t_j)/∂x(t)` and `L_k` is the Lagrange polynomial of a cell's
    /// node `k`: for each sweep, each of its cells (in the sweep's order) and each of the
    /// cell's nodes, nx values. A smooth `g` then has `∫_a^b g(t)ᵀμ(t) dt = Σ_k g(t_k)ᵀM_k`
    /// to the rule's order however fast `μ` changes (product integration: a stiff mode's
    /// boundary layer before each jump is integrated, not sampled). One forward pass
    /// without sensitivities stores the trajectory; each sweep integrates `μ̇ = −f_xᵀμ` and
    /// the moments backward from `t1` with the state tolerances (the absolute one relative
    /// to the largest jump). Jumps and cells lie in `(t0, t1]`, resp. `[t0, t1]`.
    pub fn adjoints(
        &mut self,
        ode: &dyn Ode,
        t0: f64,
        t1: f64,
        x0: &[f64],
        p: &[f64],
        sweeps: &[AdjointSweep],
    ) -> Result<Vec<Vec<Vec<Vec<f64>>>>, IntegratorError> {
        let nx = self.nx;
        check_dim("ode.nx()", nx, ode.nx())?;
        check_dim("ode.np()", self.np, ode.np())?;
        check_dim("x0", nx, x0.len())?;
        check_dim("p", self.np, p.len())?;
        check_interval(t0, t1)?;
        for sweep in sweeps {
            for (j, (t, w)) in sweep.jumps.iter().enumerate() {
                check_dim("adjoint jump", nx, w.len())?;
                if !(*t > t0 && *t <= t1 && all_finite(w)) {
                    return Err(IntegratorError::BadOutputTime { index: j, t: *t });
                }
            }
            for (c, (a, b, nodes)) in sweep.cells.iter().enumerate() {
                let inside = |t: f64| t >= *a && t <= *b;
                let valid = *a >= t0
                    && *b <= t1
                    && a < b
                    && (1..=MAX_CELL_NODES).contains(&nodes.len())
                    && nodes.iter().all(|&t| inside(t))
                    && nodes.windows(2).all(|p| p[0] < p[1])
                    && !sweep.jumps.iter().any(|(t, _)| *t > *a && *t < *b);
                if !valid {
                    return Err(IntegratorError::BadOutputTime { index: c, t: *a });
                }
            }
        }
        if !all_finite(x0) || !all_finite(p) {
            return Err(IntegratorError::NonFinite { t: t0 });
        }
        if self.adjoint.is_none() {
            self.adjoint = Some(Adjoint::new(nx, self.np, &self.settings)?);
        }
        let settings = self.settings.clone();
        let max_steps = c_long::try_from(settings.max_steps).unwrap_or(c_long::MAX);
        let adj = self.adjoint.as_mut().expect("created above");
        adj.shared_mut().reset();
        let ctx = CallCtx::new(ode, p);
        // SAFETY: `ctx` outlives the guard; `shared` is live.
        let guard = unsafe { CallGuard::new(adj.shared, &ctx) };
        // the forward pass, storing the trajectory
        // SAFETY: `y` has length nx; `mem` is initialised with its adjoint memory.
        unsafe {
            nv_slice_mut(adj.y, nx).copy_from_slice(x0);
            check_setup("CVodeReInit", sys::CVodeReInit(adj.mem, t0, adj.y))?;
            check_setup(
                "CVodeSStolerances",
                sys::CVodeSStolerances(adj.mem, settings.rtol, settings.atol),
            )?;
            check_setup("CVodeSetStopTime", sys::CVodeSetStopTime(adj.mem, t1))?;
            check_setup("CVodeAdjReInit", sys::CVodeAdjReInit(adj.mem))?;
            let (mut tret, mut ncheck) = (t0, 0 as c_int);
            let flag = sys::CVodeF(adj.mem, t1, adj.y, &mut tret, sys::CV_NORMAL, &mut ncheck);
            if flag < 0 {
                drop(guard);
                return Err(adj.failure(flag, tret));
            }
        }
        let mut out = Vec::with_capacity(sweeps.len());
        for sweep in sweeps {
            match backward_sweep(adj, sweep, &settings, max_steps) {
                Ok(mus) => out.push(mus),
                Err(e) => {
                    drop(guard);
                    return Err(e);
                }
            }
        }
        drop(guard);
        Ok(out)
    }
}

/// One sweep of [`Integrator::adjoints`] on a completed forward pass.
///
/// The backward problem carries the running moments `q_j(t) = ∫_t^{t_r} (t_r − s)^j μ(s) ds`
/// (`j < MAX_CELL_NODES`) from its last restart `t_r` (a jump), so that a cell's moments are
/// differences of them and no quadrature restarts inside a step.
fn backward_sweep(
    adj: &mut Adjoint,
    sweep: &AdjointSweep,
    settings: &IntegratorSettings,
    max_steps: c_long,
) -> Result<Vec<Vec<Vec<f64>>>, IntegratorError> {
    let nx = adj.nx;
    let nq = nx * MAX_CELL_NODES;
    // at one instant: cells starting there close, then jumps apply, then cells ending
    // there open (μ on a cell sums the jumps at and after its end)
    enum Event {
        Close(usize),
        Jump(usize),
        Open(usize),
    }
    let mut events: Vec<(f64, u8, Event)> = Vec::new();
    for (c, (a, b, _)) in sweep.cells.iter().enumerate() {
        events.push((*a, 0, Event::Close(c)));
        events.push((*b, 2, Event::Open(c)));
    }
    for (j, (t, _)) in sweep.jumps.iter().enumerate() {
        events.push((*t, 1, Event::Jump(j)));
    }
    events.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let scale = sweep
        .jumps
        .iter()
        .flat_map(|(_, w)| w.iter().map(|v| v.abs()))
        .fold(0.0f64, f64::max);
    let atol = settings.atol.max(f64::MIN_POSITIVE) * scale.max(f64::MIN_POSITIVE);
    let mut out: Vec<Vec<Vec<f64>>> = sweep
        .cells
        .iter()
        .map(|(_, _, nodes)| vec![vec![0.0; nx]; nodes.len()])
        .collect();
    // each open cell's running moments at its end and the restart they count from
    let mut opened: Vec<Option<(Vec<f64>, f64)>> = vec![None; sweep.cells.len()];
    let mut mu = vec![0.0; nx];
    let mut q = vec![0.0; nq];
    // the time the backward problem stands at; `None` while μ is zero (nothing to integrate)
    let mut at: Option<f64> = None;
    let mut restart = 0.0;
    for (t, _, event) in &events {
        if let Some(tb) = at {
            if *t < tb {
                let which = adj.which.expect("initialised by restart_backward");
                // SAFETY: the backward problem is initialised at `tb` > t ≥ t0; `yb` has
                // length nx and `qb` length nq.
                unsafe {
                    let flag = sys::CVodeB(adj.mem, *t, sys::CV_NORMAL);
                    if flag < 0 {
                        return Err(adj.failure(flag, *t));
                    }
                    let mut tret = *t;
                    let flag = sys::CVodeGetB(adj.mem, which, &mut tret, adj.yb);
                    if flag < 0 {
                        return Err(adj.failure(flag, *t));
                    }
                    mu.copy_from_slice(nv_slice(adj.yb, nx));
                    let flag = sys::CVodeGetQuadB(adj.mem, which, &mut tret, adj.qb);
                    if flag < 0 {
                        return Err(adj.failure(flag, *t));
                    }
                    q.copy_from_slice(nv_slice(adj.qb, nq));
                }
                if !all_finite(&mu) || !all_finite(&q) {
                    return Err(IntegratorError::NonFinite { t: *t });
                }
                at = Some(*t);
            }
        }
        match *event {
            Event::Close(c) => {
                if let (Some((q_end, t_r)), Some(_)) = (opened[c].take(), at) {
                    let nodes = &sweep.cells[c].2;
                    // L_k(s) = Σ_j coef[k][j] (t_r − s)^j; M_k = Σ_j coef[k][j] (q_j(a) − q_j(b))
                    // nodes too close to tell apart in floating point: as if repeated
                    let coef = lagrange_coefficients(nodes, t_r).ok_or(
                        IntegratorError::BadOutputTime {
                            index: c,
                            t: sweep.cells[c].0,
                        },
                    )?;
                    for (k, m) in out[c].iter_mut().enumerate() {
                        for (j, &ckj) in coef[k].iter().enumerate() {
                            for i in 0..nx {
                                m[i] += ckj * (q[j * nx + i] - q_end[j * nx + i]);
                            }
                        }
                    }
                }
            }
            Event::Jump(j) => {
                mu.iter_mut()
                    .zip(&sweep.jumps[j].1)
                    .for_each(|(m, w)| *m += w);
                at = if mu.iter().any(|&v| v != 0.0) {
                    q.fill(0.0);
                    restart = *t;
                    adj.shared_mut().restart = restart;
                    adj.restart_backward(*t, &mu, settings.rtol, atol, max_steps)?;
                    Some(*t)
                } else {
                    None
                };
            }
            Event::Open(c) => {
                if at.is_some() {
                    opened[c] = Some((q.clone(), restart));
                }
            }
        }
    }
    Ok(out)
}

/// The coefficients `c[k][j]` of the Lagrange polynomials of `nodes` in powers of
/// `(t_r − t)`: `L_k(t) = Σ_j c[k][j] (t_r − t)^j`, `L_k(nodes[i]) = δ_ki`; `None` when
/// their Vandermonde matrix cannot be inverted (nodes that coincide in floating point).
fn lagrange_coefficients(nodes: &[f64], t_r: f64) -> Option<Vec<Vec<f64>>> {
    let n = nodes.len();
    let s: Vec<f64> = nodes.iter().map(|&t| t_r - t).collect();
    // V[i][j] = s_i^j; the coefficients of L_k solve V c = e_k, i.e. c = column k of V⁻¹
    let v = nalgebra::DMatrix::from_fn(n, n, |i, j| s[i].powi(j as i32));
    let inv = v.try_inverse()?;
    let coef: Vec<Vec<f64>> = (0..n)
        .map(|k| (0..n).map(|j| inv[(j, k)]).collect())
        .collect();
    coef.iter().flatten().all(|c| c.is_finite()).then_some(coef)
}

/// `CVQuadRhsFnB`: the running moments' integrands `−(t_r − t)^j μ(t)` (backward in time,
/// so that `q_j(t) = ∫_t^{t_r} (t_r − s)^j μ(s) ds`).
unsafe extern "C" fn moments_rhs_callback(
    t: f64,
    _y: sys::N_Vector,
    yb: sys::N_Vector,
    qbdot: sys::N_Vector,
    user_data: *mut c_void,
) -> c_int {
    run_callback(user_data, t, |shared, _ctx| {
        let nx = shared.nx;
        // SAFETY: CVODES passes serial vectors of length nx (`yb`) and nx·MAX_CELL_NODES.
        let (yb, qbdot) = unsafe { (nv_slice(yb, nx), nv_slice_mut(qbdot, nx * MAX_CELL_NODES)) };
        let s = shared.restart - t;
        let mut power = 1.0;
        for j in 0..MAX_CELL_NODES {
            for i in 0..nx {
                qbdot[j * nx + i] = -power * yb[i];
            }
            power *= s;
        }
        Ok(())
    })
}

/// `CVRhsFnB`: the adjoint equation `μ̇ = −f_x(t, x(t))ᵀ μ` at the interpolated forward
/// state.
unsafe extern "C" fn adjoint_rhs_callback(
    t: f64,
    y: sys::N_Vector,
    yb: sys::N_Vector,
    ybdot: sys::N_Vector,
    user_data: *mut c_void,
) -> c_int {
    run_callback(user_data, t, |shared, ctx| {
        let nx = shared.nx;
        // SAFETY: CVODES passes distinct serial vectors of length nx.
        let (y, yb, ybdot) =
            unsafe { (nv_slice(y, nx), nv_slice(yb, nx), nv_slice_mut(ybdot, nx)) };
        shared.ensure_jacobians(ctx, t, y)?;
        for (i, d) in ybdot.iter_mut().enumerate() {
            let col = &shared.fx[i * nx..(i + 1) * nx];
            *d = -col.iter().zip(yb).map(|(a, b)| a * b).sum::<f64>();
        }
        if all_finite(ybdot) {
            Ok(())
        } else {
            Err(OdeError::Recoverable(
                "non-finite adjoint derivative".to_string(),
            ))
        }
    })
}

/// `CVLsJacFnB`: the backward Newton Jacobian `−f_xᵀ` (dense, column-major).
unsafe extern "C" fn adjoint_jac_callback(
    t: f64,
    y: sys::N_Vector,
    _yb: sys::N_Vector,
    _fyb: sys::N_Vector,
    jac: sys::SUNMatrix,
    user_data: *mut c_void,
    _tmp1: sys::N_Vector,
    _tmp2: sys::N_Vector,
    _tmp3: sys::N_Vector,
) -> c_int {
    run_callback(user_data, t, |shared, ctx| {
        let nx = shared.nx;
        // SAFETY: `y` is a serial vector of length nx; `jac` is the nx × nx dense matrix of
        // the backward problem, column-major in one block.
        let (y, jac) = unsafe {
            (
                nv_slice(y, nx),
                std::slice::from_raw_parts_mut(sys::SUNDenseMatrix_Data(jac), nx * nx),
            )
        };
        shared.ensure_jacobians(ctx, t, y)?;
        for c in 0..nx {
            for r in 0..nx {
                jac[r + c * nx] = -shared.fx[c + r * nx];
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::lagrange_coefficients;

    /// The Lagrange polynomials in powers of `t_r − t` are one at their own node and zero
    /// at the others; repeated nodes have none (never zeros in their place).
    #[test]
    fn lagrange_polynomials_interpolate_their_nodes_and_repeated_nodes_have_none() {
        let (nodes, t_r) = ([0.10, 0.13, 0.17, 0.2], 0.21);
        let coef = lagrange_coefficients(&nodes, t_r).unwrap();
        for (k, c) in coef.iter().enumerate() {
            for (i, &t) in nodes.iter().enumerate() {
                let l: f64 = c
                    .iter()
                    .enumerate()
                    .map(|(j, ckj)| ckj * (t_r - t).powi(j as i32))
                    .sum();
                let want = if i == k { 1.0 } else { 0.0 };
                assert!((l - want).abs() < 1e-9, "L_{k}({t}) = {l}");
            }
        }
        assert!(lagrange_coefficients(&[0.1, 0.1, 0.2], t_r).is_none());
    }
}
