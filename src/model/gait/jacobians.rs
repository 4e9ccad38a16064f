//! Derivatives of the gait dynamics: which inputs can appear in a second derivative,
//! and the Jacobian of `ẋ` with respect to `(x, u, θ)` by chunked forward AD through
//! the implicit derivatives of the dynamics (`GaitModel::dynamics_tangent`).

use super::{Actuation, ConstraintSet, GaitModel, LEG_JOINTS};
use crate::model::ad::{self, AdChunk, AdNested};
use crate::model::error::DynamicsError;

impl GaitModel {
    /// The inputs of `(x, u, θ)` that can appear in a second derivative of the dynamics
    /// or of anything computed from them (contact forces, ground loads), and how many of
    /// them lead as a group the dynamics are jointly affine in. All inputs can, except
    /// the excitations of muscle-torque generators without residual actuators and without
    /// a free factor on the activation time constants: those
    /// enter only `ȧ = (e − a)/τ`, affinely with constant coefficients, so every second
    /// derivative involving them is exactly zero. The activations and the controls that
    /// remain (joint torques, residual actuators, excitations beside residuals) lead: the
    /// joint torques are linear in them at fixed (q, q̇, θ) (`s·τ₀·a·f^A(q)·f^V(q̇)`, or
    /// the control itself), the accelerations and contact forces are linear in the torques
    /// for a fixed contact set, and ȧ is linear in (e, a).
    pub fn curved_inputs(&self) -> (Vec<usize>, usize) {
        let (nq, nx, nu, nt) = (self.nq(), self.nx(), self.nu(), self.ntheta());
        // a free factor on the activation time constants multiplies the excitations in ȧ
        let controls_affine = matches!(self.actuation, Actuation::Mtg(_))
            && self.residuals.is_none()
            && !self.scales_activation_time();
        let mut order: Vec<usize> = (2 * nq..nx).collect();
        if !controls_affine {
            order.extend(nx..nx + nu);
        }
        let lead = order.len();
        order.extend(0..2 * nq);
        order.extend(nx + nu..nx + nu + nt);
        (order, lead)
    }

    /// `∂τ/∂a` (nq × na, column-major, N·m per unit activation): how the joint torques
    /// of the actuators, damping and effects at `(x, u, θ)` move with each activation.
    fn torque_activation_jacobian(&self, x: &[f64], u: &[f64], theta: &[f64]) -> Vec<f64> {
        let (nq, a0) = (self.nq(), 2 * self.nq());
        let na = x.len() - a0;
        let c = |v: &[f64]| -> Vec<AdChunk> { v.iter().map(|&w| AdChunk::from(w)).collect() };
        let (q, qd, uc) = (c(&x[..nq]), c(&x[nq..a0]), c(u));
        let p = self.full_params(&c(theta));
        let mut out = vec![0.0; nq * na];
        let mut a = Vec::with_capacity(na);
        for start in (0..na).step_by(ad::CHUNK) {
            ad::seed_chunk(&x[a0..], start, &mut a);
            let tau = self.generalized_forces(&q, &qd, &a, &uc, &p);
            for k in 0..ad::CHUNK.min(na - start) {
                for (j, t) in tau.iter().enumerate() {
                    out[j + (start + k) * nq] = ad::eps(t, k);
                }
            }
        }
        out
    }

    /// Per control, the coordinate it pushes and its force per unit control (N·m or N)
    /// if it enters the dynamics only so: the joint torques and the residual actuators;
    /// `None` for the excitations of muscle-torque generators.
    fn control_pushes(&self) -> Vec<Option<(usize, f64)>> {
        let mut pushes = vec![None; self.nu()];
        if let Actuation::Torques {
            reference_torque, ..
        } = &self.actuation
        {
            for (k, &(c, _)) in LEG_JOINTS.iter().enumerate() {
                pushes[k] = Some((c, *reference_torque));
            }
        }
        if let Some(scales) = &self.residuals {
            let base = self.nu_actuators();
            for (i, &sc) in scales.iter().enumerate() {
                pushes[base + i] = Some((i, sc));
            }
        }
        pushes
    }

    /// `Σ μ_i ∇²ẋ_i` over `(x, u, θ)` (column-major, nz × nz) by nested forward AD.
    /// With muscle-torque generators (no residual actuators, activation time not free)
    /// the activations act only through the joint torques, linearly: the accelerations
    /// are differentiated along the joints' torques instead of the twelve activations
    /// (`H[a_i, w] = Σ_j ∂τ_j/∂a_i H[τ_j, w] + Σ_j γ_j ∂²τ_j/∂a_i∂w` with
    /// `γ_j = μ_q · ∂q̈/∂τ_j`), and ȧ, affine in (e, a) with constant coefficients,
    /// adds nothing.
    pub fn weighted_dynamics_hessian(
        &self,
        set: &ConstraintSet,
        (x, u, theta): (&[f64], &[f64], &[f64]),
        mu: &[f64],
        out: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let (nx, nu, nt) = (self.nx(), self.nu(), theta.len());
        let nz = nx + nu + nt;
        let mut lam = vec![AdNested::from(0.0); set.rows.len()];
        let mut xdot = vec![AdNested::from(0.0); nx];
        let weighted = |xdot: &[AdNested]| {
            xdot.iter()
                .zip(mu)
                .fold(AdNested::from(0.0), |acc, (f, m)| acc + *f * *m)
        };
        let through_torques = matches!(self.actuation, Actuation::Mtg(_))
            && self.residuals.is_none()
            && !self.scales_activation_time();
        if !through_torques {
            let z: Vec<f64> = x.iter().chain(u).chain(theta).copied().collect();
            let (curved, lead) = self.curved_inputs();
            return ad::hessian_over(
                &z,
                &curved,
                lead,
                |zs| {
                    let (xs, rest) = zs.split_at(nx);
                    let (us, ts) = rest.split_at(nu);
                    self.dynamics(set, xs, us, ts, &mut xdot, &mut lam, None)?;
                    Ok(weighted(&xdot))
                },
                out,
            );
        }
        let (nq, a0) = (self.nq(), 2 * self.nq());
        let na = nx - a0;
        let dtau_da = self.torque_activation_jacobian(x, u, theta);
        let joints = moved_joints(&dtau_da, nq);
        let nj = joints.len();
        let uc: Vec<AdNested> = u.iter().map(|&v| AdNested::from(v)).collect();
        let ac: Vec<AdNested> = x[a0..].iter().map(|&v| AdNested::from(v)).collect();
        // over (q, q̇, δτ, θ): the activations held, torques δτ added at the joints
        let mut z = x[..a0].to_vec();
        z.extend(std::iter::repeat_n(0.0, nj));
        z.extend_from_slice(theta);
        let nzt = z.len();
        let curved = lead_first(a0..a0 + nj, nzt);
        let mut ht = vec![0.0; nzt * nzt];
        let mut xs = Vec::with_capacity(nx);
        let mut extra = Vec::with_capacity(nj);
        ad::hessian_over(
            &z,
            &curved,
            nj,
            |zs| {
                let (qs, rest) = zs.split_at(a0);
                let (taus, ts) = rest.split_at(nj);
                xs.clear();
                xs.extend_from_slice(qs);
                xs.extend_from_slice(&ac);
                extra.clear();
                extra.extend(joints.iter().copied().zip(taus.iter().copied()));
                self.forward(set, (&xs, &uc, ts), &extra, &mut xdot, &mut lam, None)?;
                Ok(weighted(&xdot))
            },
            &mut ht,
        )?;
        // γ_j, and Σ_j γ_j (τ_j(w, a) − τ_j(w, a*)) over (q, q̇, a, θ): its (a, w) block
        let mut xd = vec![0.0; nx];
        let at = self.solution(set, (x, u, theta), &mut xd)?;
        let gamma: Vec<f64> = joints
            .iter()
            .map(|&j| {
                let r = at.unit_torque_response(j);
                r.iter().zip(&mu[nq..a0]).map(|(r, m)| r * m).sum()
            })
            .collect();
        let zw: Vec<f64> = x.iter().chain(theta).copied().collect();
        let nzw = zw.len();
        let curved_w = lead_first(a0..nx, nzw);
        let mut hw = vec![0.0; nzw * nzw];
        ad::hessian_over(
            &zw,
            &curved_w,
            na,
            |zs| {
                let (w, ts) = zs.split_at(nx);
                let (q, rest) = w.split_at(nq);
                let (qd, a) = rest.split_at(nq);
                let p = self.full_params(ts);
                let tau = self.generalized_forces(q, qd, a, &uc, &p);
                let tau0 = self.generalized_forces(q, qd, &ac, &uc, &p);
                Ok(joints
                    .iter()
                    .zip(&gamma)
                    .fold(AdNested::from(0.0), |acc, (&j, g)| {
                        acc + (tau[j] - tau0[j]) * *g
                    }))
            },
            &mut hw,
        )?;
        // assembled over (x, u, θ): w = (q, q̇, θ) rows and columns from `ht`, the
        // activations' from the chain rule
        out.iter_mut().for_each(|v| *v = 0.0);
        // w's entries as (index in zw, in z, in the output)
        let ws: Vec<(usize, usize, usize)> = (0..a0 + nt)
            .map(|k| match k.checked_sub(a0) {
                None => (k, k, k),
                Some(t) => (nx + t, a0 + nj + t, nx + nu + t),
            })
            .collect();
        for &(_, tr, or) in &ws {
            for &(_, tc, oc) in &ws {
                out[or + oc * nz] = ht[tr + tc * nzt];
            }
        }
        for i in 0..na {
            let oa = a0 + i;
            for &(wi, tw, ow) in &ws {
                let mut v = hw[(a0 + i) + wi * nzw];
                for (k, &j) in joints.iter().enumerate() {
                    v += dtau_da[j + i * nq] * ht[(a0 + k) + tw * nzt];
                }
                out[oa + ow * nz] = v;
                out[ow + oa * nz] = v;
            }
        }
        Ok(())
    }

    /// Evaluate `ẋ` and its Jacobians with respect to `(x, u, θ)` by chunked forward AD;
    /// `jac` is nx × (nx + nu + nθ), column-major.
    pub fn dynamics_jacobian(
        &self,
        set: &ConstraintSet,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        xdot: &mut [f64],
        jac: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let (nx, nu, nt) = (self.nx(), self.nu(), theta.len());
        let mut lam = vec![AdChunk::from(0.0); set.rows.len()];
        match &self.actuation {
            // Excitations enter only the activation dynamics ȧ = rate(u, a), and the
            // activations only that and the joint torques τ(q, q̇, a): AD runs over
            // (q, q̇, θ), and the activation and excitation columns follow by the chain
            // rule from ∂τ/∂a, the accelerations' response to a unit torque (one real
            // solve with the dynamics' factors) and the rate's scalar derivatives
            // (residual actuators' controls enter the dynamics: the general path below).
            Actuation::Mtg(mtg) if self.residuals.is_none() => {
                let (nq, a0) = (self.nq(), 2 * self.nq());
                let na = nx - a0;
                let at = self.solution(set, (x, u, theta), xdot)?;
                let dtau_da = self.torque_activation_jacobian(x, u, theta);
                let mut z = Vec::with_capacity(a0 + nt);
                z.extend_from_slice(&x[..a0]);
                z.extend_from_slice(theta);
                let mut jz = vec![0.0; nx * z.len()];
                let uc: Vec<AdChunk> = u.iter().map(|&v| AdChunk::from(v)).collect();
                let ac: Vec<AdChunk> = x[a0..].iter().map(|&v| AdChunk::from(v)).collect();
                let mut xs = Vec::with_capacity(nx);
                ad::jacobian(
                    &z,
                    nx,
                    |zs, out| {
                        let (qs, ts) = zs.split_at(a0);
                        xs.clear();
                        xs.extend_from_slice(qs);
                        xs.extend_from_slice(&ac);
                        self.dynamics_tangent(set, (&xs, &uc, ts), &at, out, &mut lam);
                        Ok::<(), DynamicsError>(())
                    },
                    xdot,
                    &mut jz,
                )?;
                // (q, q̇) and θ columns as computed
                jac[..nx * a0].copy_from_slice(&jz[..nx * a0]);
                jac[nx * (nx + nu)..].copy_from_slice(&jz[nx * a0..]);
                // activation columns: Σ_j ∂q̈/∂τ_j ∂τ_j/∂a_i, and the rate's own
                let time = self.actuator_factors(theta).time;
                let joints = moved_joints(&dtau_da, nq);
                let responses: Vec<Vec<f64>> =
                    joints.iter().map(|&j| at.unit_torque_response(j)).collect();
                for i in 0..na {
                    let col = &mut jac[nx * (a0 + i)..nx * (a0 + i + 1)];
                    col.iter_mut().for_each(|v| *v = 0.0);
                    for (&j, r) in joints.iter().zip(&responses) {
                        let d = dtau_da[j + i * nq];
                        if d != 0.0 {
                            col[nq..a0].iter_mut().zip(r).for_each(|(c, v)| *c += d * v);
                        }
                    }
                    let e = num_dual::Dual64::from(u[i]);
                    let a = num_dual::Dual64::new(x[a0 + i], 1.0);
                    col[a0 + i] += mtg.activation.rate(e, a).eps / time;
                }
                let fu = &mut jac[nx * nx..nx * (nx + nu)];
                fu.iter_mut().for_each(|v| *v = 0.0);
                for i in 0..nu {
                    let e = num_dual::Dual64::new(u[i], 1.0);
                    let a = num_dual::Dual64::from(x[a0 + i]);
                    fu[i * nx + a0 + i] = mtg.activation.rate(e, a).eps / time;
                }
                Ok(())
            }
            // the controls that push one coordinate with a constant factor (joint
            // torques, residual actuators) by the accelerations' response to a unit
            // force; AD over (x, θ) and the other controls (excitations)
            _ => {
                let (nq, a0) = (self.nq(), 2 * self.nq());
                let at = self.solution(set, (x, u, theta), xdot)?;
                let pushes = self.control_pushes();
                let free: Vec<usize> = (0..nu).filter(|&k| pushes[k].is_none()).collect();
                let mut z = Vec::with_capacity(nx + free.len() + nt);
                z.extend_from_slice(x);
                z.extend(free.iter().map(|&k| u[k]));
                z.extend_from_slice(theta);
                let mut jz = vec![0.0; nx * z.len()];
                let mut us: Vec<AdChunk> = u.iter().map(|&v| AdChunk::from(v)).collect();
                ad::jacobian(
                    &z,
                    nx,
                    |zs, out| {
                        let (xs, rest) = zs.split_at(nx);
                        let (fs, ts) = rest.split_at(free.len());
                        for (&k, v) in free.iter().zip(fs) {
                            us[k] = *v;
                        }
                        self.dynamics_tangent(set, (xs, &us, ts), &at, out, &mut lam);
                        Ok::<(), DynamicsError>(())
                    },
                    xdot,
                    &mut jz,
                )?;
                jac[..nx * nx].copy_from_slice(&jz[..nx * nx]);
                jac[nx * (nx + nu)..].copy_from_slice(&jz[nx * (nx + free.len())..]);
                let mut next_free = 0;
                for (k, push) in pushes.iter().enumerate() {
                    let col = &mut jac[nx * (nx + k)..nx * (nx + k + 1)];
                    match push {
                        Some((c, factor)) => {
                            col.iter_mut().for_each(|v| *v = 0.0);
                            let r = at.unit_torque_response(*c);
                            col[nq..a0]
                                .iter_mut()
                                .zip(&r)
                                .for_each(|(o, v)| *o = factor * v);
                        }
                        None => {
                            let j = nx + next_free;
                            col.copy_from_slice(&jz[nx * j..nx * (j + 1)]);
                            next_free += 1;
                        }
                    }
                }
                Ok(())
            }
        }
    }
}

/// The joints whose torque some activation moves, from `∂τ/∂a` (nq × na, column-major).
fn moved_joints(dtau_da: &[f64], nq: usize) -> Vec<usize> {
    (0..nq)
        .filter(|&j| dtau_da.chunks_exact(nq).any(|col| col[j] != 0.0))
        .collect()
}

/// All of `0..n` with the inputs of `lead` first: the order [`ad::hessian_over`] takes
/// an affine leading group in.
fn lead_first(lead: std::ops::Range<usize>, n: usize) -> Vec<usize> {
    lead.clone()
        .chain((0..n).filter(|i| !lead.contains(i)))
        .collect()
}
