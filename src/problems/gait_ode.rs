//! The gait model under one constraint set as a [`ControlledOde`], the view the
//! multiple-shooting transcription integrates (CVODES with forward sensitivities) and
//! differentiates. It lives here, above the integrator, so that the model does not depend
//! on the layers that use it.

use crate::integrate::{ControlledOde, OdeError};
use crate::model::{ConstraintSet, DynamicsError, GaitModel};

/// `ControlledOde` view of the model under one constraint set.
#[derive(Debug, Clone, Copy)]
pub struct GaitOde<'a> {
    /// The model.
    pub model: &'a GaitModel,
    /// Active constraints.
    pub set: &'a ConstraintSet,
}

fn ode_err(e: DynamicsError) -> OdeError {
    match e {
        DynamicsError::NonFinite { .. } => OdeError::Recoverable(e.to_string()),
        other => OdeError::Fatal(other.to_string()),
    }
}

impl ControlledOde for GaitOde<'_> {
    fn nx(&self) -> usize {
        self.model.nx()
    }
    fn nu(&self) -> usize {
        self.model.nu()
    }
    fn ntheta(&self) -> usize {
        self.model.ntheta()
    }
    fn f(&self, x: &[f64], u: &[f64], theta: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        let mut lam = vec![0.0; self.set.rows.len()];
        self.model
            .dynamics(self.set, x, u, theta, xdot, &mut lam, None)
            .map_err(ode_err)?;
        if xdot.iter().any(|v| !v.is_finite()) {
            return Err(OdeError::Recoverable("non-finite state derivative".into()));
        }
        Ok(())
    }
    /// With a compliant contact (its damping), and with muscle-torque generators: a swing
    /// foot's small inertia against the generators' damping decays within milliseconds,
    /// so Ψ(τ) is ill-conditioned on rigid feet too (condition numbers up to 1e12 on the
    /// bundled model, 1e21 on OpenCap subject 4), and the adjoint from its inverse was
    /// wrong by up to 37 % of the Hessian's largest entry (`gait_hessian::`). A
    /// torque-driven model keeps the single pass.
    fn stiff_transition(&self) -> bool {
        self.model.has_volumetric_contacts()
            || matches!(
                self.model.actuation(),
                crate::model::gait::Actuation::Mtg(_)
            )
    }
    /// A compliant contact's fast mode decays within microseconds from the interval's
    /// start. The generators' slower one does not need the graded cells: on the bundled
    /// model and on OpenCap subject 4 the assembled Hessian matches the finite
    /// differences as closely without them (`gait_hessian::`), with 8 nodes per
    /// interval instead of 18.
    fn fast_curvature_layers(&self) -> bool {
        self.model.has_volumetric_contacts()
    }
    fn weighted_hessian(
        &self,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        mu: &[f64],
        out: &mut [f64],
    ) -> Result<bool, OdeError> {
        self.model
            .weighted_dynamics_hessian(self.set, (x, u, theta), mu, out)
            .map_err(ode_err)?;
        if out.iter().any(|v| !v.is_finite()) {
            return Err(OdeError::Recoverable("non-finite Hessian".into()));
        }
        Ok(true)
    }
    fn f_jac(
        &self,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fu: &mut [f64],
        ftheta: &mut [f64],
    ) -> Result<(), OdeError> {
        let (nx, nu, nt) = (self.model.nx(), self.model.nu(), theta.len());
        let mut jac = vec![0.0; nx * (nx + nu + nt)];
        self.model
            .dynamics_jacobian(self.set, x, u, theta, xdot, &mut jac)
            .map_err(ode_err)?;
        fx.copy_from_slice(&jac[..nx * nx]);
        fu.copy_from_slice(&jac[nx * nx..nx * (nx + nu)]);
        ftheta.copy_from_slice(&jac[nx * (nx + nu)..]);
        if xdot.iter().chain(jac.iter()).any(|v| !v.is_finite()) {
            return Err(OdeError::Recoverable("non-finite derivative".into()));
        }
        Ok(())
    }
}
