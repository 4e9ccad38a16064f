//! The shooting intervals at one point: where the shifted sample terms fall, each
//! interval's integration (with sensitivities and curvature on request), and what its
//! sample terms add to the objective.

use super::{add_instant, Instants, IntervalRef, Transcription, TranscriptionError};
use crate::integrate::{
    ControlShape, ControlledOde, IntegrationStats, Integrator, IntegratorError, ShootingInterval,
};
use crate::ocp::checks::{self, CheckValues};
use crate::ocp::problem::Block;
use crate::ocp::term_error::with_causes;
use crate::ocp::TermError;
use std::sync::Mutex;

/// Instants of the sample terms at one evaluation, per interval in transcription order
/// (`None`: the fixed ones only), and per sample term the gradient of its instant in θ
/// (s per unit; `None` where it does not move: not shifted, or held at its phase's ends).
type Placement = (Vec<Option<Instants>>, Vec<Option<Vec<f64>>>);

/// A shifted sample's instant is held at least this far (as a fraction of an interval)
/// after its phase's start, where CVODES can take a first step towards it.
const SHIFTED_PHASE_START: f64 = 1e-6;

/// A shifted instant closer than this (fraction of an interval) to an interval's start
/// is taken at the end of the interval before it (an instant moved by at most 1e-9 of an
/// interval, instead of a first CVODES step of that size).
const SHIFTED_SNAP: f64 = 1e-9;

/// Where a sample term at `(interval, τ)` of a phase of `intervals` intervals of length
/// `h` (s) falls when its instant is shifted by `shift` (s), as
/// [`SampleTerm::shift`](crate::ocp::SampleTerm) places it: `(interval, τ, moves)`, held
/// inside the phase (`moves` false where it is held at either end, so the instant does
/// not move with the shift there). A zero shift leaves it exactly where it was.
pub fn shifted_instant(
    interval: usize,
    tau: f64,
    shift: f64,
    h: f64,
    intervals: usize,
) -> (usize, f64, bool) {
    // the instant in units of intervals from the phase's start
    let at = interval as f64 + tau + shift / h;
    if shift == 0.0 {
        (interval, tau, true)
    } else if at <= SHIFTED_PHASE_START {
        (0, SHIFTED_PHASE_START, false)
    } else if at >= intervals as f64 {
        (intervals - 1, 1.0, false)
    } else {
        let k = (at.ceil() as usize).saturating_sub(1).min(intervals - 1);
        let tau = (at - k as f64).min(1.0);
        if tau < SHIFTED_SNAP && k > 0 {
            (k - 1, 1.0, true)
        } else {
            (k, tau, true)
        }
    }
}

/// What an interval's sample terms add to the objective: their value, the gradient and the
/// Gauss–Newton block (upper triangle, row by row) over the interval's columns.
#[derive(Debug, Default)]
pub(super) struct SampleSums {
    pub(super) f: f64,
    pub(super) grad: Vec<f64>,
    pub(super) gauss_newton: Vec<f64>,
}

/// One interval's integration: end state, sensitivities, statistics, curvature block
/// (with multipliers) and what its sample terms add.
pub(super) type IntervalResult = (
    Vec<f64>,
    Vec<f64>,
    IntegrationStats,
    Option<Vec<f64>>,
    Option<SampleSums>,
    Vec<CheckValues>,
);

impl<'o, 'a> Transcription<'o, 'a> {
    /// Where the shifted sample terms fall at `w` ([`SampleTerm::shift`](crate::ocp::SampleTerm)):
    /// the instant `(interval + τ) h + s(θ)` located in its phase's intervals (the node
    /// times are fixed: the phase's duration is), held inside the phase.
    pub(super) fn place_shifted(&self, w: &[f64]) -> Result<Placement, TranscriptionError> {
        let mut lists: Vec<Option<Instants>> = vec![None; self.intervals.len()];
        let mut gradients = vec![None; self.ocp.samples.len()];
        let theta = &w[self.range(Block::Params)];
        for &si in &self.shifted {
            let st = &self.ocp.samples[si];
            let Some(shift) = &st.shift else { continue };
            let n = self.ocp.phases[st.phase].intervals;
            let h = w[self.duration_off[st.phase]] / n as f64;
            let mut s = [0.0];
            let mut g = vec![0.0; self.ocp.ntheta];
            shift
                .eval(theta, &mut s, Some(&mut g))
                .map_err(|source| TranscriptionError::Term {
                    term: format!("{} (shift)", st.name),
                    source,
                })?;
            if !s[0].is_finite() || g.iter().any(|v| !v.is_finite()) {
                return Err(TranscriptionError::Term {
                    term: format!("{} (shift)", st.name),
                    source: TermError::NonFiniteShift { shift: s[0] },
                });
            }
            let (k, tau, moves) = shifted_instant(st.interval, st.tau, s[0], h, n);
            if moves {
                gradients[si] = Some(g);
            }
            let i = self.first_interval[st.phase] + k;
            add_instant(
                lists[i].get_or_insert_with(|| self.intervals[i].samples.clone()),
                tau,
                si,
            );
        }
        for list in lists.iter_mut().flatten() {
            list.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        Ok((lists, gradients))
    }

    /// Integrate interval `iv` at `w` with its sample terms at the instants `list` (τ
    /// ascending, each with its terms; `moves`: per sample term the gradient of its instant
    /// in θ, where it moves): with `sens` the sensitivities, with the multipliers `lambda`
    /// also the curvature block.
    pub(super) fn integrate_interval(
        &self,
        iv: &IntervalRef,
        list: &[(f64, Vec<usize>)],
        moves: &[Option<Vec<f64>>],
        w: &[f64],
        sens: bool,
        lambda: Option<&[f64]>,
    ) -> Result<IntervalResult, TranscriptionError> {
        let ph = &self.ocp.phases[iv.phase];
        let interval = ShootingInterval::new(ph.ode, ph.controls);
        let (nx, np) = (ph.ode.nx(), interval.np());
        let x0 = &w[self.range(Block::State {
            phase: iv.phase,
            node: iv.k,
        })];
        let u0 = &w[self.range(Block::Control {
            phase: iv.phase,
            node: iv.k,
        })];
        let u1 = match ph.controls {
            ControlShape::Linear => Some(
                &w[self.range(Block::Control {
                    phase: iv.phase,
                    node: iv.k + 1,
                })],
            ),
            ControlShape::Constant => None,
        };
        let h = w[self.duration_off[iv.phase]] / ph.intervals as f64;
        let theta = &w[self.range(Block::Params)];
        let err = |source| TranscriptionError::Integrator {
            phase: ph.name.clone(),
            interval: iv.k,
            source,
        };
        let mut p = Vec::with_capacity(np);
        interval
            .pack_params(u0, u1, h, theta, &mut p)
            .map_err(err)?;
        let pool = &self.pools[iv.phase];
        let mut integ = self.pooled_integrator(pool, (nx, np)).map_err(err)?;
        // the sample terms' and check points' instants, with the interval's end for one
        // pass to all
        let mut taus: Vec<f64> = list.iter().map(|e| e.0).collect();
        if !iv.checks.is_empty() {
            taus.extend(iv.checks.iter().map(|c| c.0));
            taus.sort_by(f64::total_cmp);
            taus.dedup();
        }
        let mut times = taus.clone();
        if times.last().is_some_and(|&t| t < 1.0) {
            times.push(1.0);
        }
        let run = IntervalRun {
            iv,
            list,
            interval,
            nx,
            np,
            x0,
            p,
            taus,
            times,
        };
        let mut out = Pass {
            x1: vec![0.0; nx],
            s: Vec::new(),
            hess: None,
            xs: Vec::new(),
            ss: Vec::new(),
        };
        let res = if let Some(lam) = lambda {
            self.integrate_with_curvature(&run, &mut integ, lam, &mut out)
        } else {
            run.integrate(&mut integ, sens, &mut out)
        };
        if let Ok(mut v) = pool.lock() {
            v.push(integ);
        }
        let stats = res.map_err(err)?;
        let derivs = sens || lambda.is_some();
        let checks = checks::check_values(
            self.ocp,
            iv.phase,
            &iv.checks,
            &run.taus,
            &run.p,
            &out.xs,
            derivs.then_some(&out.ss[..]),
        )?;
        let sums = if !iv.sample_block {
            None
        } else {
            Some(self.interval_sample_sums(&run, moves, derivs, &mut out)?)
        };
        Ok((out.x1, out.s, stats, out.hess, sums, checks))
    }

    /// An integrator from the phase's `pool` (or a new one for `nx` states and `np`
    /// parameters), at the tolerances the transcription's scale asks for.
    fn pooled_integrator(
        &self,
        pool: &Mutex<Vec<Integrator>>,
        (nx, np): (usize, usize),
    ) -> Result<Integrator, IntegratorError> {
        let taken = pool.lock().map(|mut v| v.pop()).unwrap_or(None);
        let mut integ = match taken {
            Some(i) => i,
            None => Integrator::new(nx, np, self.ocp.integrator.clone())?,
        };
        let base = &self.ocp.integrator;
        let scale = self.tolerance_scale();
        if integ.settings().rtol != base.rtol * scale {
            integ.set_tolerances(
                base.rtol * scale,
                base.atol * scale,
                base.sens_tol.map(|t| t * scale),
            )?;
        }
        Ok(integ)
    }

    /// The interval's pass with the curvature of `−λᵀx(1)` (`lam`: the multipliers of all
    /// rows), of its check points' state dependence and of its sample terms' residuals,
    /// with the states and sensitivities at the instants.
    fn integrate_with_curvature<O: ControlledOde + ?Sized>(
        &self,
        run: &IntervalRun<'_, O>,
        integ: &mut Integrator,
        lam: &[f64],
        out: &mut Pass,
    ) -> Result<IntegrationStats, IntegratorError> {
        let (iv, list, interval, p) = (run.iv, run.list, &run.interval, &run.p[..]);
        let (nx, np) = (run.nx, run.np);
        // continuity rows are s_{k+1} − x(1): their curvature is that of −λᵀx(1)
        out.s = vec![0.0; nx * (nx + np)];
        let weights: Vec<f64> = lam[iv.row..iv.row + nx].iter().map(|v| -v).collect();
        let mut h = vec![0.0; (nx + np) * (nx + np)];
        // the samples' and check points' states and sensitivities come from the same
        // pass, with the curvature of the check points' state dependence
        // and of the sample terms' residuals (their weight 2 r ∂r/∂x on x(τ))
        let sample_taus: &[(f64, Vec<usize>)] = if iv.sample_block { list } else { &[] };
        let interior: Vec<f64> = {
            let mut v: Vec<f64> = iv.checks.iter().map(|c| c.0).collect();
            v.extend(sample_taus.iter().map(|e| e.0));
            v.sort_by(f64::total_cmp);
            v.dedup();
            v
        };
        // a check point's own span, as before samples had curvature (a check point
        // that is also a sample instant is folded in with it)
        let own_span: Vec<bool> = interior
            .iter()
            .map(|t| !sample_taus.iter().any(|e| e.0 == *t))
            .collect();
        let mut check_weights = |i: usize, x: &[f64]| {
            let tau = interior[i];
            // zero where no check point is at τ
            let mut w = checks::state_weights(self.ocp, iv.phase, &iv.checks, tau, p, x, lam)?;
            if let Some((_, terms)) = sample_taus.iter().find(|e| e.0 == tau) {
                self.sample_state_weights(interval, terms, tau, p, x, &mut w)
                    .map_err(|e| IntegratorError::BadSettings {
                        field: "sample term",
                        reason: with_causes(&e),
                    })?;
            }
            Ok(w)
        };
        match interval.integrate_with_hessian_interior(
            integ,
            run.x0,
            p,
            &weights,
            &mut out.x1,
            &mut out.s,
            &mut h,
            &run.taus,
            &mut out.xs,
            &mut out.ss,
            &interior,
            &own_span,
            &mut check_weights,
        ) {
            Ok(true) => {
                checks::add_direct_curvature(
                    self.ocp, iv.phase, &iv.checks, &run.taus, p, &out.xs, &out.ss, lam, &mut h,
                )?;
                out.hess = Some(h);
                Ok(integ.stats_snapshot())
            }
            Ok(false) => Err(IntegratorError::BadSettings {
                field: "hessian",
                reason: format!(
                    "the dynamics of phase '{}' provide no second derivatives",
                    self.ocp.phases[iv.phase].name
                ),
            }),
            Err(e) => Err(e),
        }
    }

    /// What the interval's sample terms add, read at their own rows of the pass's merged
    /// instants (`derivs`: whether the pass has sensitivities); their curvature goes into
    /// the pass's block, where it has one.
    fn interval_sample_sums<O: ControlledOde + ?Sized>(
        &self,
        run: &IntervalRun<'_, O>,
        moves: &[Option<Vec<f64>>],
        derivs: bool,
        out: &mut Pass,
    ) -> Result<SampleSums, TranscriptionError> {
        let (iv, list, nx, np) = (run.iv, run.list, run.nx, run.np);
        // the samples' own rows of the merged instants
        let rows;
        let (xs, ss) = if iv.checks.is_empty() {
            (&out.xs[..], &out.ss[..])
        } else {
            rows = checks::rows_at(
                list.iter().map(|e| e.0),
                &run.taus,
                nx,
                nx * (nx + np),
                &out.xs,
                &out.ss,
                derivs,
            );
            (&rows.0[..], &rows.1[..])
        };
        let ss = derivs.then_some(ss);
        self.sample_sums(iv, list, moves, &run.p, xs, ss, out.hess.as_deref_mut())
    }

    /// Add the sample terms' `2 Σ_j r_j ∂r_j/∂x` at the state `x` of instant `tau` to `w`
    /// (nx): the weight of their residuals on the state's second-order sensitivity.
    fn sample_state_weights<O: crate::integrate::ControlledOde + ?Sized>(
        &self,
        interval: &ShootingInterval<'_, O>,
        terms: &[usize],
        tau: f64,
        p: &[f64],
        x: &[f64],
        w: &mut [f64],
    ) -> Result<(), TranscriptionError> {
        let nx = x.len();
        let z = checks::instant_args(interval, x, p, tau);
        for &si in terms {
            let (r, jz) = self.eval_sample(si, &z, true)?;
            let d = r.len();
            for (k, wk) in w.iter_mut().enumerate().take(nx) {
                *wk += (0..d).map(|i| 2.0 * r[i] * jz[i + k * d]).sum::<f64>();
            }
        }
        Ok(())
    }

    /// Sample term `si` at `z = (x(τ), u(τ), θ)`: its residuals and, with `jac`, their
    /// Jacobian (d × nz, column-major; empty without).
    fn eval_sample(
        &self,
        si: usize,
        z: &[f64],
        jac: bool,
    ) -> Result<(Vec<f64>, Vec<f64>), TranscriptionError> {
        let term = &self.ocp.samples[si];
        let d = term.f.dim();
        let mut r = vec![0.0; d];
        let mut jz = if jac {
            vec![0.0; d * z.len()]
        } else {
            Vec::new()
        };
        term.f
            .eval(z, &mut r, jac.then_some(&mut jz[..]))
            .map_err(|source| TranscriptionError::Term {
                term: term.name.clone(),
                source,
            })?;
        Ok((r, jz))
    }

    /// The sample terms `list` of interval `iv` at its integrated states `xs` (nx per τ,
    /// in τ order) with, when `ss` is given, their sensitivities (nx·(nx+np) per τ):
    /// value, gradient and Gauss–Newton block over the interval's columns (x0, u0, [u1],
    /// T, θ), by the chain rule through `x(τ) = Φ(τ; x0, p)` and `u(τ)`; a term whose
    /// instant moves with θ (gradient in `moves`) adds `(∂r/∂x ẋ + ∂r/∂u u̇) ∂t/∂θ`.
    ///
    /// With `hess` (the interval's curvature block, when the exact Hessian is wanted) the
    /// direct part of the residuals' own curvature, `Dᵀ (2 Σ r_i ∇²_{(x,u,θ)} r_i) D`, is
    /// added to it; their weight on the state's second-order sensitivity comes from
    /// [`sample_state_weights`](Self::sample_state_weights) in the integration pass.
    /// Without both the exact Hessian of a sample-target problem is Gauss–Newton in its
    /// data terms, and a weakly determined parameter whose force depends on the state (the
    /// heel pad's stiffness times its compression) converges linearly (rate 0.91 per
    /// iteration on the heel-pad re-fit of tests/hidden_effects.rs). Left out, as in
    /// Gauss–Newton: the curvature of an instant that moves with θ (a plate's clock).
    #[allow(clippy::too_many_arguments)]
    fn sample_sums(
        &self,
        iv: &IntervalRef,
        list: &[(f64, Vec<usize>)],
        moves: &[Option<Vec<f64>>],
        p: &[f64],
        xs: &[f64],
        ss: Option<&[f64]>,
        mut hess: Option<&mut [f64]>,
    ) -> Result<SampleSums, TranscriptionError> {
        let ph = &self.ocp.phases[iv.phase];
        let interval = ShootingInterval::new(ph.ode, ph.controls);
        let (nx, nu, nt) = (ph.ode.nx(), ph.ode.nu(), self.ocp.ntheta);
        let ncols = nx + interval.np();
        let nz = nx + nu + nt;
        let theta = &p[interval.p_theta()];
        let u0 = &p[interval.p_u0()];
        let u1 = interval.p_u1().map(|r| &p[r]);
        let hscale = 1.0 / ph.intervals as f64;
        let mut out = SampleSums {
            f: 0.0,
            grad: Vec::new(),
            gauss_newton: Vec::new(),
        };
        if ss.is_some() {
            out.grad = vec![0.0; ncols];
            out.gauss_newton = vec![0.0; ncols * (ncols + 1) / 2];
        }
        for (q, (tau, terms)) in list.iter().enumerate() {
            let x = &xs[q * nx..(q + 1) * nx];
            let z = checks::instant_args(&interval, x, p, *tau);
            let u = &z[nx..nx + nu];
            for &si in terms {
                let term = &self.ocp.samples[si];
                let (r, jz) = self.eval_sample(si, &z, ss.is_some())?;
                let d = r.len();
                out.f += r.iter().map(|v| v * v).sum::<f64>();
                let Some(ss) = ss else { continue };
                let s = &ss[q * nx * ncols..(q + 1) * nx * ncols];
                if let Some(h) = hess.as_deref_mut() {
                    if term.f.has_hessian() {
                        let weights: Vec<f64> = r.iter().map(|v| 2.0 * v).collect();
                        let mut g = vec![0.0; nz * nz];
                        term.f
                            .weighted_hessian(&z, &weights, &mut g)
                            .map_err(|source| TranscriptionError::Term {
                                term: term.name.clone(),
                                source,
                            })?;
                        checks::add_instant_curvature(&interval, (nx, nu, nt), *tau, s, &g, h);
                    }
                }
                let mut jac = checks::instant_jacobian(&interval, nx, nu, d, &jz, s, *tau, hscale);
                if let Some(g) = moves.get(si).and_then(Option::as_ref) {
                    // dr/dt along the trajectory (per second): ẋ = f(x, u, θ), u̇ = (u1 − u0)/h
                    let h = p[interval.p_duration()];
                    let mut xdot = vec![0.0; nx];
                    ph.ode
                        .f(x, &u, theta, &mut xdot)
                        .map_err(|e| TranscriptionError::Term {
                            term: term.name.clone(),
                            source: TermError::Ode(e),
                        })?;
                    let udot: Vec<f64> = match u1 {
                        Some(u1) => u0.iter().zip(u1).map(|(a, b)| (b - a) / h).collect(),
                        None => vec![0.0; nu],
                    };
                    for i in 0..d {
                        let rate = (0..nx).map(|k| jz[i + k * d] * xdot[k]).sum::<f64>()
                            + (0..nu).map(|k| jz[i + (nx + k) * d] * udot[k]).sum::<f64>();
                        for (k, c) in interval.p_theta().enumerate() {
                            jac[i + (nx + c) * d] += rate * g[k];
                        }
                    }
                }
                let mut at = 0;
                for a in 0..ncols {
                    let ja = &jac[a * d..(a + 1) * d];
                    out.grad[a] += 2.0 * ja.iter().zip(&r).map(|(j, v)| j * v).sum::<f64>();
                    for b in a..ncols {
                        out.gauss_newton[at] += 2.0
                            * ja.iter()
                                .zip(&jac[b * d..(b + 1) * d])
                                .map(|(x, y)| x * y)
                                .sum::<f64>();
                        at += 1;
                    }
                }
            }
        }
        Ok(out)
    }
}

/// One interval's integration at one point: the interval, where it starts, its
/// parameters and the instants it reports.
struct IntervalRun<'r, O: ControlledOde + ?Sized> {
    iv: &'r IntervalRef,
    /// The sample terms' instants (τ ascending, each with its terms).
    list: &'r [(f64, Vec<usize>)],
    interval: ShootingInterval<'r, O>,
    nx: usize,
    /// Number of the integrator's parameters.
    np: usize,
    /// The start state.
    x0: &'r [f64],
    /// The integrator's parameters (controls, interval length, θ).
    p: Vec<f64>,
    /// The sample terms' and check points' instants (τ ascending).
    taus: Vec<f64>,
    /// `taus` with the interval's end.
    times: Vec<f64>,
}

/// What an interval's integration gives: the end state, with derivatives its
/// sensitivities (nx·(nx+np)), with multipliers the curvature block, and the states (nx per
/// instant) and sensitivities at the reported instants.
struct Pass {
    x1: Vec<f64>,
    s: Vec<f64>,
    hess: Option<Vec<f64>>,
    xs: Vec<f64>,
    ss: Vec<f64>,
}

impl<O: ControlledOde + ?Sized> IntervalRun<'_, O> {
    /// The interval's pass without curvature: with `sens` the sensitivities; the states
    /// (and sensitivities) at the instants where there are any.
    fn integrate(
        &self,
        integ: &mut Integrator,
        sens: bool,
        out: &mut Pass,
    ) -> Result<IntegrationStats, IntegratorError> {
        let (interval, x0, p, times) = (&self.interval, self.x0, &self.p[..], &self.times[..]);
        let (nx, np) = (self.nx, self.np);
        if sens {
            out.s = vec![0.0; nx * (nx + np)];
            if self.taus.is_empty() {
                integ.integrate_with_sensitivities(
                    interval,
                    0.0,
                    1.0,
                    x0,
                    p,
                    &mut out.x1,
                    &mut out.s,
                )
            } else {
                integ
                    .integrate_with_sensitivities_dense(
                        interval,
                        0.0,
                        1.0,
                        x0,
                        p,
                        times,
                        &mut out.xs,
                        &mut out.ss,
                    )
                    .inspect(|_| {
                        let sz = nx * (nx + np);
                        out.x1.copy_from_slice(&out.xs[out.xs.len() - nx..]);
                        out.s.copy_from_slice(&out.ss[out.ss.len() - sz..]);
                    })
            }
        } else if self.taus.is_empty() {
            integ.integrate(interval, 0.0, 1.0, x0, p, &mut out.x1)
        } else {
            integ
                .integrate_dense(interval, 0.0, 1.0, x0, p, times, &mut out.xs)
                .inspect(|_| out.x1.copy_from_slice(&out.xs[out.xs.len() - nx..]))
        }
    }
}
