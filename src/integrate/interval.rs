//! One multiple-shooting interval as a parameterised ODE in normalised time.
//!
//! An interval of duration $T$ is mapped to $\tau \in [0, 1]$, so that the duration becomes a
//! parameter like the controls:
//! $$\frac{dx}{d\tau} = T\, f\bigl(x, u(\tau), \theta\bigr),\qquad
//! u(\tau) = \begin{cases} u_0 & \text{constant} \\ (1-\tau)\,u_0 + \tau\, u_1 & \text{linear}
//! \end{cases}$$
//! with parameter vector $p = [u_0,\ u_1\ (\text{linear only}),\ T,\ \theta]$.  Integrating
//! over $\tau$ from 0 to 1 with sensitivities gives $\partial x(1) / \partial (x_0, p)$, i.e.
//! the defect Jacobians of the shooting transcription in one pass.

use std::ops::Range;

use super::cvodes::IntegratorError;
use super::quadrature::{flatten, grade_start, piece_cells, span_cells, Cell, STIFF_SPLIT};
use super::{AdjointSweep, Ode, OdeError};

/// A time-invariant controlled model ẋ = f(x, u, θ) with exact Jacobians.
pub trait ControlledOde: Sync {
    /// Number of states.
    fn nx(&self) -> usize;
    /// Number of controls.
    fn nu(&self) -> usize;
    /// Number of free model parameters θ.
    fn ntheta(&self) -> usize;
    /// Right-hand side `xdot = f(x, u, θ)` (state units per second).
    fn f(&self, x: &[f64], u: &[f64], theta: &[f64], xdot: &mut [f64]) -> Result<(), OdeError>;
    /// f and Jacobians fx (nx×nx), fu (nx×nu), ftheta (nx×nθ), column-major.
    #[allow(clippy::too_many_arguments)]
    fn f_jac(
        &self,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fu: &mut [f64],
        ftheta: &mut [f64],
    ) -> Result<(), OdeError>;

    /// Exact curvature of the weighted dynamics: `∇²_{(x,u,θ)} (μᵀ f(x, u, θ))`
    /// ((nx+nu+nθ)², column-major) into `out`. Returns `Ok(false)` when the model does not
    /// provide second derivatives (the default).
    fn weighted_hessian(
        &self,
        _x: &[f64],
        _u: &[f64],
        _theta: &[f64],
        _mu: &[f64],
        _out: &mut [f64],
    ) -> Result<bool, OdeError> {
        Ok(false)
    }

    /// Whether the dynamics can be so stiff that a shooting interval's state transition
    /// matrix Ψ(τ) becomes singular to working precision (a compliant contact's damping:
    /// eigenvalues of ∂f/∂x near −1e5 1/s; a swing foot's small inertia against its
    /// actuators' damping). The interval curvature then integrates its
    /// adjoint backward instead of inverting Ψ(τ), and with it the adjoint's moments over
    /// each cell of the rule, so that the fast mode's boundary layers before the jumps are
    /// integrated, not sampled ([`Integrator::adjoints`](super::Integrator::adjoints)),
    /// and the rule takes twice the nodes ([`STIFF_SPLIT`]) (default: false, the single
    /// pass).
    fn stiff_transition(&self) -> bool {
        false
    }
    /// Whether, besides, the curvature's integrand has a layer of microseconds at the
    /// interval's start, where the sensitivities leave `[I | 0]` along a mode that fast (a
    /// compliant contact): the rule's first cell then shrinks toward the start
    /// (`quadrature::grade_start`). Only with [`stiff_transition`](Self::stiff_transition)
    /// (default: false).
    fn fast_curvature_layers(&self) -> bool {
        false
    }
}

/// How the control varies over one shooting interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControlShape {
    /// Piecewise constant: u(τ) = u0.
    Constant,
    /// Piecewise linear: u(τ) = (1 − τ) u0 + τ u1.
    Linear,
}

/// Controls up to this size are interpolated in a stack buffer.
const STACK_NU: usize = 16;

/// Adapter from a [`ControlledOde`] to the [`Ode`] of one shooting interval over τ ∈ [0, 1].
///
/// See the module docs for the dynamics and the parameter layout; the layout helpers
/// ([`p_u0`](Self::p_u0), [`p_u1`](Self::p_u1), [`p_duration`](Self::p_duration),
/// [`p_theta`](Self::p_theta)) give the index ranges in `p` and in the sensitivity
/// columns after the first `nx`.
pub struct ShootingInterval<'a, O: ControlledOde + ?Sized> {
    model: &'a O,
    shape: ControlShape,
}

// Manual impls: derives would demand `O: Clone`/`O: Debug` although only `&O` is stored.
impl<O: ControlledOde + ?Sized> Clone for ShootingInterval<'_, O> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<O: ControlledOde + ?Sized> Copy for ShootingInterval<'_, O> {}

impl<O: ControlledOde + ?Sized> std::fmt::Debug for ShootingInterval<'_, O> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShootingInterval")
            .field("nx", &self.model.nx())
            .field("nu", &self.model.nu())
            .field("ntheta", &self.model.ntheta())
            .field("shape", &self.shape)
            .finish()
    }
}

impl<'a, O: ControlledOde + ?Sized> ShootingInterval<'a, O> {
    /// Wrap `model` with the given control shape.
    pub fn new(model: &'a O, shape: ControlShape) -> Self {
        Self { model, shape }
    }

    /// The wrapped model.
    pub fn model(&self) -> &'a O {
        self.model
    }

    /// The control shape.
    pub fn shape(&self) -> ControlShape {
        self.shape
    }

    /// Number of parameters: nu (+ nu for linear controls) + 1 + nθ.
    pub fn np(&self) -> usize {
        self.p_theta().end
    }

    /// Indices of u0 in `p`.
    pub fn p_u0(&self) -> Range<usize> {
        0..self.model.nu()
    }

    /// Indices of u1 in `p`; `None` for constant controls.
    pub fn p_u1(&self) -> Option<Range<usize>> {
        let nu = self.model.nu();
        match self.shape {
            ControlShape::Constant => None,
            ControlShape::Linear => Some(nu..2 * nu),
        }
    }

    /// Index of the duration T in `p`.
    pub fn p_duration(&self) -> usize {
        self.p_u1().map_or(self.model.nu(), |r| r.end)
    }

    /// Indices of θ in `p`.
    pub fn p_theta(&self) -> Range<usize> {
        let start = self.p_duration() + 1;
        start..start + self.model.ntheta()
    }

    /// Fill `p` (cleared first) with `[u0, u1, duration, θ]`.
    ///
    /// `u1` must be `Some` exactly for linear controls; lengths are checked against the model.
    pub fn pack_params(
        &self,
        u0: &[f64],
        u1: Option<&[f64]>,
        duration: f64,
        theta: &[f64],
        p: &mut Vec<f64>,
    ) -> Result<(), IntegratorError> {
        let nu = self.model.nu();
        let dim = super::cvodes::check_dim;
        dim("u0", nu, u0.len())?;
        dim("theta", self.model.ntheta(), theta.len())?;
        match (self.shape, u1) {
            (ControlShape::Constant, Some(u1)) => {
                dim("u1 (constant controls take none)", 0, u1.len())?
            }
            (ControlShape::Linear, None) => dim("u1", nu, 0)?,
            (ControlShape::Linear, Some(u1)) => dim("u1", nu, u1.len())?,
            (ControlShape::Constant, None) => {}
        }
        p.clear();
        p.reserve(self.np());
        p.extend_from_slice(u0);
        if let (ControlShape::Linear, Some(u1)) = (self.shape, u1) {
            p.extend_from_slice(u1);
        }
        p.push(duration);
        p.extend_from_slice(theta);
        Ok(())
    }

    /// Reject buffers of the wrong length (the [`Ode`] methods must not panic).
    fn check_lengths(&self, x: &[f64], p: &[f64], xdot: &[f64]) -> Result<(), OdeError> {
        let (nx, np) = (self.model.nx(), ShootingInterval::np(self));
        if x.len() != nx || xdot.len() != nx || p.len() != np {
            return Err(OdeError::Fatal(format!(
                "shooting interval: expected x, xdot of length {nx} and p of length {np}, got {}, {}, {}",
                x.len(),
                xdot.len(),
                p.len()
            )));
        }
        Ok(())
    }

    /// Call `body` with u(τ): a sub-slice of `p` for constant controls, otherwise the
    /// interpolated value in a stack (or, for large nu, heap) buffer.
    fn with_control<R>(&self, tau: f64, p: &[f64], body: impl FnOnce(&[f64]) -> R) -> R {
        let u0 = &p[self.p_u0()];
        let Some(r1) = self.p_u1() else {
            return body(u0);
        };
        let u1 = &p[r1];
        let mut stack = [0.0; STACK_NU];
        let mut heap = Vec::new();
        let u = if u0.len() <= STACK_NU {
            &mut stack[..u0.len()]
        } else {
            heap.resize(u0.len(), 0.0);
            &mut heap[..]
        };
        for ((u, a), b) in u.iter_mut().zip(u0).zip(u1) {
            *u = (1.0 - tau) * a + tau * b;
        }
        body(u)
    }
}

impl<O: ControlledOde + ?Sized> Ode for ShootingInterval<'_, O> {
    fn nx(&self) -> usize {
        self.model.nx()
    }

    fn np(&self) -> usize {
        ShootingInterval::np(self)
    }

    fn rhs(&self, tau: f64, x: &[f64], p: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        self.check_lengths(x, p, xdot)?;
        let duration = p[self.p_duration()];
        let theta = &p[self.p_theta()];
        self.with_control(tau, p, |u| self.model.f(x, u, theta, xdot))?;
        xdot.iter_mut().for_each(|v| *v *= duration);
        Ok(())
    }

    fn jacobians(
        &self,
        tau: f64,
        x: &[f64],
        p: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fp: &mut [f64],
    ) -> Result<(), OdeError> {
        let nx = self.model.nx();
        self.check_lengths(x, p, xdot)?;
        if fx.len() != nx * nx || fp.len() != nx * p.len() {
            return Err(OdeError::Fatal(format!(
                "shooting interval: expected fx of length {} and fp of length {}, got {}, {}",
                nx * nx,
                nx * p.len(),
                fx.len(),
                fp.len()
            )));
        }
        let duration = p[self.p_duration()];
        let theta = &p[self.p_theta()];
        let cols = |r: Range<usize>| nx * r.start..nx * r.end;
        let (u_cols, rest) = fp.split_at_mut(self.p_duration() * nx);
        let (t_col, theta_cols) = rest.split_at_mut(nx);
        // fu goes straight into the u1 columns (linear) or the u0 columns (constant).
        let fu_range = match self.p_u1() {
            Some(r1) => cols(r1),
            None => cols(self.p_u0()),
        };
        self.with_control(tau, p, |u| {
            self.model.f_jac(
                x,
                u,
                theta,
                xdot,
                fx,
                &mut u_cols[fu_range.clone()],
                theta_cols,
            )
        })?;
        // ∂/∂T = f; then scale everything else by T.
        t_col.copy_from_slice(xdot);
        let scale = |v: &mut [f64], s: f64| v.iter_mut().for_each(|a| *a *= s);
        scale(xdot, duration);
        scale(fx, duration);
        scale(theta_cols, duration);
        if self.shape == ControlShape::Linear {
            // u_cols = [u0 | u1] with u1 = fu: u0 ← T(1−τ) fu, u1 ← Tτ fu.
            let (u0_cols, u1_cols) = u_cols.split_at_mut(fu_range.start);
            u0_cols.copy_from_slice(u1_cols);
            scale(u0_cols, duration * (1.0 - tau));
            scale(u1_cols, duration * tau);
        } else {
            scale(u_cols, duration);
        }
        Ok(())
    }
}

/// How the adjoint weights μ(τ) at the quadrature nodes are found.
enum SpanAdjoint {
    /// From `c = Σ Ψ(t_end)ᵀw_end` of each piece (by its end), by solving with Ψ(τ) at
    /// each node (the single pass).
    Inverse(Vec<(f64, Vec<f64>)>),
    /// A stiff model's, integrated backward: per node its moment `∫ L_q(τ) μ(τ) dτ` over
    /// its cell ([`Integrator::adjoints`](super::Integrator::adjoints)), which stands for
    /// `w_q μ(τ_q)` in the rule and also integrates the stiff mode's boundary layers.
    Moments(Vec<Vec<f64>>),
}

impl<O: ControlledOde + ?Sized> ShootingInterval<'_, O> {
    /// End state, sensitivities and the exact curvature of `λᵀ x(1)` with respect to
    /// `z = (x0, p)` ((nx+np)², column-major), by the second-order adjoint identity
    /// $$\nabla^2_z\,\lambda^T x(1) = \int_0^1 \begin{bmatrix}S\\P\end{bmatrix}^T
    ///   \nabla^2_{(x,p)}\big(\mu^T F\big)\begin{bmatrix}S\\P\end{bmatrix} d\tau,\qquad
    ///   \mu(\tau)^T = \lambda^T\Psi(1)\Psi(\tau)^{-1},$$
    /// with $S = \partial x/\partial z$ and $\Psi = \partial x/\partial x_0$ from the forward
    /// sensitivities at 4 Gauss–Legendre nodes (CVODES dense output; a stiff model's
    /// interval in parts of 4 nodes each, `integrate/quadrature.rs`, with μ from a backward
    /// adjoint pass, [`ControlledOde::stiff_transition`]), $P = [0\;|\;I]$ and
    /// $F = T f(x, u(\tau), \theta)$. Second derivatives of $f$ come from the model
    /// ([`ControlledOde::weighted_hessian`]); no finite differences.
    /// Returns `Ok(false)` when the model has no second derivatives.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_with_hessian(
        &self,
        integ: &mut super::Integrator,
        x0: &[f64],
        p: &[f64],
        lambda: &[f64],
        x1: &mut [f64],
        s1: &mut [f64],
        hess: &mut [f64],
    ) -> Result<bool, IntegratorError> {
        self.integrate_with_hessian_and_outputs(
            integ,
            x0,
            p,
            lambda,
            x1,
            s1,
            hess,
            &[],
            &mut Vec::new(),
            &mut Vec::new(),
        )
    }

    /// As [`integrate_with_hessian`](Self::integrate_with_hessian), and in the same pass
    /// the states and sensitivities at the strictly increasing `outputs ⊂ (0, 1]`,
    /// appended to `xs` and `ss` as by
    /// [`Integrator::integrate_with_sensitivities_dense`](super::Integrator::integrate_with_sensitivities_dense).
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_with_hessian_and_outputs(
        &self,
        integ: &mut super::Integrator,
        x0: &[f64],
        p: &[f64],
        lambda: &[f64],
        x1: &mut [f64],
        s1: &mut [f64],
        hess: &mut [f64],
        outputs: &[f64],
        xs_out: &mut Vec<f64>,
        ss_out: &mut Vec<f64>,
    ) -> Result<bool, IntegratorError> {
        self.integrate_with_hessian_interior(
            integ,
            x0,
            p,
            lambda,
            x1,
            s1,
            hess,
            outputs,
            xs_out,
            ss_out,
            &[],
            &[],
            &mut |_, _| Ok(Vec::new()),
        )
    }

    /// As [`integrate_with_hessian_and_outputs`](Self::integrate_with_hessian_and_outputs),
    /// with the curvature of `w_iᵀ x(τ_i)` added for every interior instant `τ_i` of
    /// `interior` (increasing, each one of `outputs`): the same identity over `[0, τ_i]`
    /// with `μ_i(τ)ᵀ = w_iᵀΨ(τ_i)Ψ(τ)⁻¹`, in the same pass. Where `own_span[i]`, on 4
    /// Gauss–Legendre nodes of that span of its own (a check point); otherwise folded into
    /// the interval's own rule, which is then split at those instants into pieces on which
    /// the summed adjoint is smooth ([`piece_nodes`]; the samples of a high-rate trial:
    /// one node per millisecond instead of four per sample). `weights(i, x(τ_i))` gives
    /// `w_i` (nx) once the state there is known (e.g. the multipliers of a constraint on
    /// `x(τ_i)` times its gradient).
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_with_hessian_interior(
        &self,
        integ: &mut super::Integrator,
        x0: &[f64],
        p: &[f64],
        lambda: &[f64],
        x1: &mut [f64],
        s1: &mut [f64],
        hess: &mut [f64],
        outputs: &[f64],
        xs_out: &mut Vec<f64>,
        ss_out: &mut Vec<f64>,
        interior: &[f64],
        own_span: &[bool],
        weights: &mut dyn FnMut(usize, &[f64]) -> Result<Vec<f64>, IntegratorError>,
    ) -> Result<bool, IntegratorError> {
        let m = self.model;
        let nx = m.nx();
        let np = self.np();
        let nz = nx + np;
        // the quadrature nodes of the pieces between the interior instants, the outputs
        // and the end, in time order
        let own = |i: usize| own_span.get(i).copied().unwrap_or(false);
        let folded: Vec<f64> = (0..interior.len())
            .filter(|&i| !own(i))
            .map(|i| interior[i])
            .collect();
        // a stiff model's transients need finer pieces (STIFF_SPLIT), a compliant
        // contact's also cells shrinking toward the start
        let split = if m.stiff_transition() { STIFF_SPLIT } else { 1 };
        let layers = m.stiff_transition() && m.fast_curvature_layers();
        let mut cells = piece_cells(&folded, split);
        if layers {
            grade_start(&mut cells);
        }
        let nodes = flatten(&cells);
        // the spans of their own: 4 nodes on [0, τ_i] (on each of its parts), all in the
        // piece ending at τ_i
        let own_cells: Vec<Vec<Cell>> = (0..interior.len())
            .filter(|&i| own(i))
            .map(|i| {
                let mut cells = span_cells(interior[i], split);
                if layers {
                    grade_start(&mut cells);
                }
                cells
            })
            .collect();
        let own_nodes: Vec<Vec<(f64, f64, f64)>> = own_cells.iter().map(|c| flatten(c)).collect();
        let mut times: Vec<f64> = nodes
            .iter()
            .chain(own_nodes.iter().flatten())
            .map(|n| n.0)
            .chain(outputs.iter().copied())
            .chain([1.0])
            .collect();
        times.sort_by(f64::total_cmp);
        times.dedup();
        let at = |t: f64| times.partition_point(|&v| v < t);
        let (mut xs, mut ss) = (Vec::new(), Vec::new());
        integ
            .integrate_with_sensitivities_dense(self, 0.0, 1.0, x0, p, &times, &mut xs, &mut ss)?;
        let sz = nx * nz;
        let end = times.len() - 1;
        x1.copy_from_slice(&xs[end * nx..(end + 1) * nx]);
        s1.copy_from_slice(&ss[end * sz..(end + 1) * sz]);
        for &t in outputs {
            let i = at(t);
            xs_out.extend_from_slice(&xs[i * nx..(i + 1) * nx]);
            ss_out.extend_from_slice(&ss[i * sz..(i + 1) * sz]);
        }
        hess.iter_mut().for_each(|v| *v = 0.0);
        // (end instant, weights on the state there): λ at 1, then each w_i at τ_i
        let mut spans: Vec<(f64, Vec<f64>)> = vec![(1.0, lambda.to_vec())];
        let mut own_spans: Vec<(f64, Vec<f64>)> = Vec::new();
        for (i, &ti) in interior.iter().enumerate() {
            let q = at(ti);
            let w = weights(i, &xs[q * nx..(q + 1) * nx])?;
            if own(i) {
                own_spans.push((ti, w));
            } else {
                spans.push((ti, w));
            }
        }
        // a stiff model's adjoint moments on the cells, by backward integration: one
        // sweep for the folded spans, one for each span of its own
        let backward: Option<Vec<Vec<Vec<f64>>>> = if m.stiff_transition() {
            let sweep = |spans: &[(f64, Vec<f64>)], cells: &[Cell]| AdjointSweep {
                jumps: spans.to_vec(),
                cells: cells
                    .iter()
                    .map(|c| (c.a, c.b, c.nodes.iter().map(|n| n.0).collect()))
                    .collect(),
            };
            let sweeps: Vec<AdjointSweep> = std::iter::once(sweep(&spans, &cells))
                .chain(
                    own_spans
                        .iter()
                        .zip(&own_cells)
                        .map(|(span, cells)| sweep(std::slice::from_ref(span), cells)),
                )
                .collect();
            let moments = integ.adjoints(self, 0.0, 1.0, x0, p, &sweeps)?;
            // per node, in the nodes' order (cells in time order, nodes in cell order)
            Some(
                moments
                    .into_iter()
                    .map(|sweep| sweep.into_iter().flatten().collect())
                    .collect(),
            )
        } else {
            None
        };
        let mut given = backward.map(|b| b.into_iter());
        if !self.add_spans_curvature(
            p,
            &xs,
            &ss,
            &times,
            given.as_mut().and_then(|g| g.next()),
            &nodes,
            &spans,
            hess,
        )? {
            return Ok(false);
        }
        for (span, nodes) in own_spans.iter().zip(&own_nodes) {
            let spans = std::slice::from_ref(span);
            let mus = given.as_mut().and_then(|g| g.next());
            if !self.add_spans_curvature(p, &xs, &ss, &times, mus, nodes, spans, hess)? {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Add the curvature of `Σ w_endᵀ x(t_end)` over `spans` by the quadrature `nodes`
    /// (`(τ, weight, end of τ's piece)`): on the piece ending at b, μ(τ) sums the
    /// adjoints of the spans `[0, t_end]` with `t_end ≥ b`.
    #[allow(clippy::too_many_arguments)]
    fn add_spans_curvature(
        &self,
        p: &[f64],
        xs: &[f64],
        ss: &[f64],
        times: &[f64],
        backward: Option<Vec<Vec<f64>>>,
        nodes: &[(f64, f64, f64)],
        spans: &[(f64, Vec<f64>)],
        hess: &mut [f64],
    ) -> Result<bool, IntegratorError> {
        let nx = self.model.nx();
        let sz = nx * (nx + self.np());
        let at = |t: f64| times.partition_point(|&v| v < t);
        // μ(τ)ᵀ = Σ w_endᵀΨ(t_end, τ)
        let adjoint = match backward {
            // the moments on the nodes' cells, integrated backward
            Some(moments) => SpanAdjoint::Moments(moments),
            // Σ w_endᵀΨ(t_end), per piece end
            None => {
                let mut per_end: Vec<(f64, Vec<f64>)> = Vec::new();
                for &(_, _, b) in nodes {
                    if per_end.last().is_some_and(|e| e.0 == b) {
                        continue;
                    }
                    let mut c = vec![0.0; nx];
                    for (t_end, w_end) in spans.iter().filter(|sp| sp.0 >= b) {
                        let q_end = at(*t_end);
                        let s_end = &ss[q_end * sz..(q_end + 1) * sz];
                        for (j, cj) in c.iter_mut().enumerate() {
                            *cj += (0..nx).map(|i| w_end[i] * s_end[i + j * nx]).sum::<f64>();
                        }
                    }
                    per_end.push((b, c));
                }
                SpanAdjoint::Inverse(per_end)
            }
        };
        self.add_node_curvature(p, xs, ss, times, nodes, &adjoint, hess)
    }

    /// Add `∇²_z w_endᵀ x(t_end)` to `hess` by Gauss–Legendre quadrature over `[0, t_end]`
    /// from the states and sensitivities `xs`, `ss` at `times`, with the span's adjoint
    /// weights found as `adjoint` says.
    /// Returns `Ok(false)` when the model has no second derivatives.
    #[allow(clippy::too_many_arguments)]
    fn add_node_curvature(
        &self,
        p: &[f64],
        xs: &[f64],
        ss: &[f64],
        times: &[f64],
        nodes: &[(f64, f64, f64)],
        adjoint: &SpanAdjoint,
        hess: &mut [f64],
    ) -> Result<bool, IntegratorError> {
        let m = self.model;
        let (nx, nu, nt) = (m.nx(), m.nu(), m.ntheta());
        let np = self.np();
        let nz = nx + np;
        let nw = nx + nu + nt;
        let sz = nx * nz;
        let at = |t: f64| times.partition_point(|&v| v < t);
        let dur = p[self.p_duration()];
        let theta = &p[self.p_theta()];
        let mut u = vec![0.0; nu];
        let mut h = vec![0.0; nw * nw];
        let mut xdot = vec![0.0; nx];
        let (mut fx, mut fu, mut ft) = (vec![0.0; nx * nx], vec![0.0; nx * nu], vec![0.0; nx * nt]);
        for (node, &(tau, wq, piece_end)) in nodes.iter().enumerate() {
            let q = at(tau);
            let x = &xs[q * nx..(q + 1) * nx];
            let s = &ss[q * sz..(q + 1) * sz];
            let (wq, mu): (f64, Vec<f64>) = match adjoint {
                SpanAdjoint::Moments(moments) => (1.0, moments[node].clone()),
                SpanAdjoint::Inverse(per_end) => {
                    // μ(τ)ᵀ = cᵀΨ(τ)⁻¹ with c = Σ Ψ(t_end)ᵀw_end of the piece: solve
                    // Ψ(τ)ᵀ μ = c
                    let c = &per_end
                        .iter()
                        .find(|e| e.0 == piece_end)
                        .expect("every piece end has its weights")
                        .1;
                    let psi = nalgebra::DMatrix::from_column_slice(nx, nx, &s[..nx * nx]);
                    let rhs = nalgebra::DVector::from_column_slice(c);
                    let mu = psi
                        .transpose()
                        .lu()
                        .solve(&rhs)
                        .ok_or(IntegratorError::SingularTransition { t: tau })?;
                    (wq, mu.iter().copied().collect())
                }
            };
            let u0 = &p[self.p_u0()];
            match self.p_u1() {
                Some(r) => {
                    let u1 = &p[r];
                    for i in 0..nu {
                        u[i] = (1.0 - tau) * u0[i] + tau * u1[i];
                    }
                }
                None => u.copy_from_slice(u0),
            }
            let rhs_err = |e: OdeError| IntegratorError::Rhs { t: tau, source: e };
            if !m
                .weighted_hessian(x, &u, theta, &mu, &mut h)
                .map_err(rhs_err)?
            {
                return Ok(false);
            }
            m.f_jac(x, &u, theta, &mut xdot, &mut fx, &mut fu, &mut ft)
                .map_err(rhs_err)?;
            // gradient of h = μᵀf with respect to (x, u, θ)
            let grad_w: Vec<f64> = (0..nw)
                .map(|c| {
                    let col = if c < nx {
                        &fx[c * nx..(c + 1) * nx]
                    } else if c < nx + nu {
                        &fu[(c - nx) * nx..(c - nx + 1) * nx]
                    } else {
                        &ft[(c - nx - nu) * nx..(c - nx - nu + 1) * nx]
                    };
                    col.iter().zip(&mu).map(|(a, b)| a * b).sum()
                })
                .collect();
            // D = ∂(x, u, θ)/∂z (nw × nz) and the T-derivative column handled explicitly
            let mut d = vec![0.0; nw * nz];
            for c in 0..nz {
                for r in 0..nx {
                    d[r + c * nw] = s[r + c * nx];
                }
            }
            for i in 0..nu {
                d[nx + i + (nx + self.p_u0().start + i) * nw] = if self.p_u1().is_some() {
                    1.0 - tau
                } else {
                    1.0
                };
                if let Some(r) = self.p_u1() {
                    d[nx + i + (nx + r.start + i) * nw] = tau;
                }
            }
            for (k, c) in self.p_theta().enumerate() {
                d[nx + nu + k + (nx + c) * nw] = 1.0;
            }
            // H += w · [ T · Dᵀ h_ww D + (e_T ⊗ (Dᵀ∇h)) + ((Dᵀ∇h) ⊗ e_T) ]
            let hd: Vec<f64> = (0..nz)
                .flat_map(|c| {
                    let h = &h;
                    let d = &d;
                    (0..nw)
                        .map(move |r| (0..nw).map(|k| h[r + k * nw] * d[k + c * nw]).sum::<f64>())
                })
                .collect();
            let t_col = nx + self.p_duration();
            let dg: Vec<f64> = (0..nz)
                .map(|c| (0..nw).map(|r| d[r + c * nw] * grad_w[r]).sum())
                .collect();
            for a in 0..nz {
                for b in 0..nz {
                    let mut v = dur * (0..nw).map(|r| d[r + a * nw] * hd[r + b * nw]).sum::<f64>();
                    if a == t_col {
                        v += dg[b];
                    }
                    if b == t_col {
                        v += dg[a];
                    }
                    hess[a + b * nz] += wq * v;
                }
            }
        }
        Ok(true)
    }
}
