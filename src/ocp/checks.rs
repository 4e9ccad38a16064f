//! Check points ([`CheckPoint`](super::CheckPoint)): path constraints at instants inside
//! shooting intervals, and the chain rule they share with sample terms.

use super::problem::Ocp;
use super::term_error::{with_causes, TermError};
use super::transcription::TranscriptionError;
use crate::integrate::{IntegratorError, ShootingInterval};

/// A check point's values and, with derivatives, its Jacobian over the interval's columns
/// (d × ncols, column-major), with its first constraint row.
pub(super) struct CheckValues {
    pub row: usize,
    pub values: Vec<f64>,
    pub jac: Vec<f64>,
}

/// Jacobian (d × ncols, column-major) over an interval's columns `(x0, u0, [u1], T, θ)`
/// of a function `g(x(τ), u(τ), θ)` with Jacobian `jz` (d × (nx + nu + nθ)) at the
/// interval's state `x(τ)`, whose sensitivities `s` (nx × ncols) are those of the
/// time-scaled interval (the duration column enters through h = T/N, `hscale` = 1/N):
/// `J = ∂g/∂x · S` plus the direct control and θ terms.
#[allow(clippy::too_many_arguments)]
pub(super) fn instant_jacobian<O: crate::integrate::ControlledOde + ?Sized>(
    interval: &ShootingInterval<'_, O>,
    nx: usize,
    nu: usize,
    d: usize,
    jz: &[f64],
    s: &[f64],
    tau: f64,
    hscale: f64,
) -> Vec<f64> {
    let ncols = nx + interval.np();
    let duration_col = nx + interval.p_duration();
    let mut jac = vec![0.0; d * ncols];
    for c in 0..ncols {
        let sc = if c == duration_col { hscale } else { 1.0 };
        let sc_col = &s[c * nx..(c + 1) * nx];
        for i in 0..d {
            jac[i + c * d] = sc * (0..nx).map(|k| jz[i + k * d] * sc_col[k]).sum::<f64>();
        }
    }
    for k in 0..nu {
        let direct = |c: usize, f: f64, jac: &mut [f64]| {
            (0..d).for_each(|i| jac[i + c * d] += f * jz[i + (nx + k) * d])
        };
        match interval.p_u1() {
            Some(r1) => {
                direct(nx + interval.p_u0().start + k, 1.0 - tau, &mut jac);
                direct(nx + r1.start + k, tau, &mut jac);
            }
            None => direct(nx + interval.p_u0().start + k, 1.0, &mut jac),
        }
    }
    for (k, c) in interval.p_theta().enumerate() {
        for i in 0..d {
            jac[i + (nx + c) * d] += jz[i + (nx + nu + k) * d];
        }
    }
    jac
}

/// The rows of `xs` (`nx` per instant) and `ss` (`ns` per instant, when `derivs`) at the
/// instants `wanted`, each one of `taus` (the instants the interval was integrated to).
pub(super) fn rows_at(
    wanted: impl Iterator<Item = f64>,
    taus: &[f64],
    nx: usize,
    ns: usize,
    xs: &[f64],
    ss: &[f64],
    derivs: bool,
) -> (Vec<f64>, Vec<f64>) {
    let (mut xo, mut so) = (Vec::new(), Vec::new());
    for tau in wanted {
        let q = taus
            .iter()
            .position(|&t| t == tau)
            .expect("every instant was integrated to");
        xo.extend_from_slice(&xs[q * nx..(q + 1) * nx]);
        if derivs {
            so.extend_from_slice(&ss[q * ns..(q + 1) * ns]);
        }
    }
    (xo, so)
}

/// Values (and with `ss`, Jacobians) of the check points `checks` of an interval of phase
/// `phase`, from its states `xs` at `taus` (nx per instant) and their sensitivities `ss`
/// (nx · ncols per instant), with the interval's packed parameters `p`.
#[allow(clippy::too_many_arguments)]
pub(super) fn check_values(
    ocp: &Ocp<'_>,
    phase: usize,
    checks: &[(f64, usize, usize)],
    taus: &[f64],
    p: &[f64],
    xs: &[f64],
    ss: Option<&[f64]>,
) -> Result<Vec<CheckValues>, TranscriptionError> {
    if checks.is_empty() {
        return Ok(Vec::new());
    }
    let ph = &ocp.phases[phase];
    let interval = ShootingInterval::new(ph.ode, ph.controls);
    let (nx, nu, nt) = (ph.ode.nx(), ph.ode.nu(), ocp.ntheta);
    let ncols = nx + interval.np();
    let nz = nx + nu + nt;
    let hscale = 1.0 / ph.intervals as f64;
    let mut out = Vec::with_capacity(checks.len());
    for &(tau, ci, row) in checks {
        let cp = &ocp.checks[ci];
        let q = taus
            .iter()
            .position(|&t| t == tau)
            .expect("every check point was integrated to");
        let z = instant_args(&interval, &xs[q * nx..(q + 1) * nx], p, tau);
        let d = cp.f.dim();
        let mut values = vec![0.0; d];
        let mut jz = vec![0.0; d * nz];
        cp.f.eval(&z, &mut values, ss.is_some().then_some(&mut jz[..]))
            .map_err(|source| TranscriptionError::Term {
                term: cp.name.clone(),
                source,
            })?;
        let jac = match ss {
            Some(ss) => instant_jacobian(
                &interval,
                nx,
                nu,
                d,
                &jz,
                &ss[q * nx * ncols..(q + 1) * nx * ncols],
                tau,
                hscale,
            ),
            None => Vec::new(),
        };
        out.push(CheckValues { row, values, jac });
    }
    Ok(out)
}

/// `(x(τ), u(τ), θ)` of an interval at `x` and τ, from its packed parameters `p` (the
/// argument of sample terms and check points).
pub(super) fn instant_args<O: crate::integrate::ControlledOde + ?Sized>(
    interval: &ShootingInterval<'_, O>,
    x: &[f64],
    p: &[f64],
    tau: f64,
) -> Vec<f64> {
    let u0 = &p[interval.p_u0()];
    let u: Vec<f64> = match interval.p_u1().map(|r| &p[r]) {
        Some(u1) => u0
            .iter()
            .zip(u1)
            .map(|(a, b)| (1.0 - tau) * a + tau * b)
            .collect(),
        None => u0.to_vec(),
    };
    x.iter()
        .chain(&u)
        .chain(&p[interval.p_theta()])
        .copied()
        .collect()
}

/// The weights `Σ_c Σ_r ν_r ∂g_r/∂x` (nx) on the state at `tau` of the check points of an
/// interval there, with their multipliers `lambda` (the NLP's, by row): the state part of
/// the checks' curvature comes from the interval's second-order pass with these weights.
/// A check point's failure is the integrator's, as the pass asks for the weights.
pub(super) fn state_weights(
    ocp: &Ocp<'_>,
    phase: usize,
    checks: &[(f64, usize, usize)],
    tau: f64,
    p: &[f64],
    x: &[f64],
    lambda: &[f64],
) -> Result<Vec<f64>, IntegratorError> {
    let ph = &ocp.phases[phase];
    let interval = ShootingInterval::new(ph.ode, ph.controls);
    let nx = ph.ode.nx();
    let z = instant_args(&interval, x, p, tau);
    let nz = z.len();
    let mut w = vec![0.0; nx];
    for &(_, ci, row) in checks.iter().filter(|c| c.0 == tau) {
        let cp = &ocp.checks[ci];
        let d = cp.f.dim();
        let mut v = vec![0.0; d];
        let mut jz = vec![0.0; d * nz];
        cp.f.eval(&z, &mut v, Some(&mut jz))
            .map_err(|e| check_point_failure(&cp.name, &e))?;
        for (k, wk) in w.iter_mut().enumerate() {
            *wk += (0..d).map(|i| lambda[row + i] * jz[i + k * d]).sum::<f64>();
        }
    }
    Ok(w)
}

/// Add the direct part of the check points' curvature, `Dᵀ (Σ ν ∇²g) D` with
/// `D = ∂(x(τ), u(τ), θ)/∂(x0, p)`, to an interval's Hessian `hess` ((nx+np)²,
/// column-major), from the states `xs` and sensitivities `ss` at `taus`. Functions without
/// second derivatives add nothing; a check point's failure is the integrator's, as for
/// [`state_weights`].
#[allow(clippy::too_many_arguments)]
pub(super) fn add_direct_curvature(
    ocp: &Ocp<'_>,
    phase: usize,
    checks: &[(f64, usize, usize)],
    taus: &[f64],
    p: &[f64],
    xs: &[f64],
    ss: &[f64],
    lambda: &[f64],
    hess: &mut [f64],
) -> Result<(), IntegratorError> {
    let ph = &ocp.phases[phase];
    let interval = ShootingInterval::new(ph.ode, ph.controls);
    let (nx, nu, nt) = (ph.ode.nx(), ph.ode.nu(), ocp.ntheta);
    let ncols = nx + interval.np();
    let nw = nx + nu + nt;
    for &(tau, ci, row) in checks {
        let cp = &ocp.checks[ci];
        let d = cp.f.dim();
        let weights = &lambda[row..row + d];
        if !cp.f.has_hessian() || weights.iter().all(|v| *v == 0.0) {
            continue;
        }
        let q = taus
            .iter()
            .position(|&t| t == tau)
            .expect("every check point was integrated to");
        let z = instant_args(&interval, &xs[q * nx..(q + 1) * nx], p, tau);
        let mut g = vec![0.0; nw * nw];
        cp.f.weighted_hessian(&z, weights, &mut g)
            .map_err(|e| check_point_failure(&cp.name, &e))?;
        let s = &ss[q * nx * ncols..(q + 1) * nx * ncols];
        add_instant_curvature(&interval, (nx, nu, nt), tau, s, &g, hess);
    }
    Ok(())
}

/// The integrator's error for check point `name`, whose function failed with `e` in the
/// interval's curvature pass: a failure at this point's states, which the transcription
/// takes as recoverable (the integrator's errors hold their reason as text).
fn check_point_failure(name: &str, e: &TermError) -> IntegratorError {
    IntegratorError::BadSettings {
        field: "check point",
        reason: format!("check point '{name}': {}", with_causes(e)),
    }
}

/// Add `Dᵀ g D` to an interval's Hessian `hess` ((nx+np)², column-major, over the
/// interval's own columns `(x0, u0, [u1], h, θ)`), where `g` ((nx+nu+nθ)², column-major) is
/// the curvature of a function of `(x(τ), u(τ), θ)` and `D = ∂(x(τ), u(τ), θ)/∂(x0, p)`:
/// the state rows are the sensitivities `s` (nx × (nx+np)) at τ, the control and θ rows
/// direct.
pub(super) fn add_instant_curvature<O: crate::integrate::ControlledOde + ?Sized>(
    interval: &ShootingInterval<'_, O>,
    (nx, nu, nt): (usize, usize, usize),
    tau: f64,
    s: &[f64],
    g: &[f64],
    hess: &mut [f64],
) {
    let ncols = nx + interval.np();
    let nw = nx + nu + nt;
    let mut dm = vec![0.0; nw * ncols];
    for c in 0..ncols {
        dm[c * nw..c * nw + nx].copy_from_slice(&s[c * nx..(c + 1) * nx]);
    }
    for k in 0..nu {
        match interval.p_u1() {
            Some(r1) => {
                dm[nx + k + (nx + interval.p_u0().start + k) * nw] = 1.0 - tau;
                dm[nx + k + (nx + r1.start + k) * nw] = tau;
            }
            None => dm[nx + k + (nx + interval.p_u0().start + k) * nw] = 1.0,
        }
    }
    for (k, c) in interval.p_theta().enumerate() {
        dm[nx + nu + k + (nx + c) * nw] = 1.0;
    }
    let gd: Vec<f64> = (0..ncols)
        .flat_map(|c| {
            let dm = &dm;
            (0..nw).map(move |r| (0..nw).map(|k| g[r + k * nw] * dm[k + c * nw]).sum::<f64>())
        })
        .collect();
    for a in 0..ncols {
        for b in 0..ncols {
            hess[a + b * ncols] += (0..nw)
                .map(|r| dm[r + a * nw] * gd[r + b * nw])
                .sum::<f64>();
        }
    }
}
