//! Derivatives of the gait dynamics: which inputs can appear in a second derivative,
//! and the Jacobian of `ẋ` with respect to `(x, u, θ)` by chunked forward AD.

use super::{Actuation, ConstraintSet, GaitModel};
use crate::model::ad::{self, AdChunk};
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
            // Excitations enter only the activation dynamics ȧ = rate(u, a): their columns
            // are diagonal and come from a scalar dual evaluation; AD runs over (x, θ) only
            // (residual actuators' controls enter the dynamics: the general path below).
            Actuation::Mtg(mtg) if self.residuals.is_none() => {
                let mut z = Vec::with_capacity(nx + nt);
                z.extend_from_slice(x);
                z.extend_from_slice(theta);
                let mut jz = vec![0.0; nx * (nx + nt)];
                let uc: Vec<AdChunk> = u.iter().map(|&v| AdChunk::from(v)).collect();
                ad::jacobian(
                    &z,
                    nx,
                    |zs, out| {
                        let (xs, ts) = zs.split_at(nx);
                        self.dynamics(set, xs, &uc, ts, out, &mut lam, None)
                    },
                    xdot,
                    &mut jz,
                )?;
                jac[..nx * nx].copy_from_slice(&jz[..nx * nx]);
                jac[nx * (nx + nu)..].copy_from_slice(&jz[nx * nx..]);
                let fu = &mut jac[nx * nx..nx * (nx + nu)];
                fu.iter_mut().for_each(|v| *v = 0.0);
                let a0 = 2 * self.nq();
                // the activation time constants' factor (an effect's) divides the rate
                let time = self.actuator_factors(theta).time;
                for i in 0..nu {
                    let e = num_dual::Dual64::new(u[i], 1.0);
                    let a = num_dual::Dual64::from(x[a0 + i]);
                    fu[i * nx + a0 + i] = mtg.activation.rate(e, a).eps / time;
                }
                Ok(())
            }
            _ => {
                let mut z = Vec::with_capacity(nx + nu + nt);
                z.extend_from_slice(x);
                z.extend_from_slice(u);
                z.extend_from_slice(theta);
                ad::jacobian(
                    &z,
                    nx,
                    |zs, out| {
                        let (xs, rest) = zs.split_at(nx);
                        let (us, ts) = rest.split_at(nu);
                        self.dynamics(set, xs, us, ts, out, &mut lam, None)
                    },
                    xdot,
                    jac,
                )
            }
        }
    }
}
