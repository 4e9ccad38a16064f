//! The gait OCP's functions of the state: contact-force rows, gaps, impact impulses,
//! the impact map and periodicity, each a [`GenericFunction`] differentiated by AD.

use crate::model::effects::ModelScalar;
use crate::model::{ConstraintSet, GaitModel};
use crate::ocp::TermError;
use crate::problems::GenericFunction;

/// Constraint forces of a contact set combined row-wise (`Σ_r c_r λ_r` per output):
/// unilateral normal forces and the friction cone. Arguments: `(x, u, θ)`.
pub(super) struct ContactForceRows<'a> {
    pub(super) model: &'a GaitModel,
    pub(super) set: ConstraintSet,
    pub(super) rows: Vec<Vec<(usize, f64)>>,
}

impl GenericFunction for ContactForceRows<'_> {
    fn dim(&self) -> usize {
        self.rows.len()
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), TermError> {
        let (nx, nu) = (self.model.nx(), self.model.nu());
        let (x, rest) = z.split_at(nx);
        let (u, th) = rest.split_at(nu);
        let mut xdot = vec![S::c(0.0); nx];
        let mut lam = vec![S::c(0.0); self.set.rows.len()];
        self.model
            .dynamics(&self.set, x, u, th, &mut xdot, &mut lam, None)?;
        for (o, row) in self.rows.iter().enumerate() {
            out[o] = row.iter().fold(S::c(0.0), |acc, &(r, c)| acc + lam[r] * c);
        }
        Ok(())
    }
    fn curved_inputs(&self) -> Option<(Vec<usize>, usize)> {
        Some(self.model.curved_inputs())
    }
}

/// Normal gap of one contact primitive as a function of `(x, u, θ)` (the control has no
/// effect), for check points.
pub(super) struct GapOfState<'a> {
    pub(super) model: &'a GaitModel,
    pub(super) contact: usize,
}

impl GenericFunction for GapOfState<'_> {
    fn dim(&self) -> usize {
        1
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), TermError> {
        let (nx, nu, nq) = (self.model.nx(), self.model.nu(), self.model.nq());
        out[0] = self.model.gap(self.contact, &z[..nq], &z[nx + nu..]);
        Ok(())
    }
    /// The positions and θ.
    fn curved_inputs(&self) -> Option<(Vec<usize>, usize)> {
        let (nx, nu, nq) = (self.model.nx(), self.model.nu(), self.model.nq());
        let curved = (0..nq).chain(nx + nu..nx + nu + self.model.ntheta());
        Some((curved.collect(), 0))
    }
}

/// Combinations `Σ c_r Λ_r` of the impulses (N·s) of the plastic impact into `set` from the
/// pre-impact state: the impulses themselves scaled for a cost, or the friction cone of a
/// landing foot's impulse. Arguments: `(x, θ)`.
pub(crate) struct ImpulseRows<'a> {
    pub(super) model: &'a GaitModel,
    pub(super) set: ConstraintSet,
    pub(super) rows: Vec<Vec<(usize, f64)>>,
}

impl<'a> ImpulseRows<'a> {
    /// The combinations `rows` (each a list of (row of `set`, coefficient)).
    pub(crate) fn new(
        model: &'a GaitModel,
        set: &ConstraintSet,
        rows: Vec<Vec<(usize, f64)>>,
    ) -> Self {
        Self {
            model,
            set: set.clone(),
            rows,
        }
    }
    /// `scale · Λ`, every impulse of `set`.
    pub(crate) fn scaled(model: &'a GaitModel, set: &ConstraintSet, scale: f64) -> Self {
        let rows = (0..set.rows.len()).map(|r| vec![(r, scale)]).collect();
        Self::new(model, set, rows)
    }
}

impl GenericFunction for ImpulseRows<'_> {
    fn dim(&self) -> usize {
        self.rows.len()
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), TermError> {
        let (nx, nq) = (self.model.nx(), self.model.nq());
        let (x, th) = z.split_at(nx);
        let (_, imp) = self.model.impact(&self.set, &x[..nq], &x[nq..2 * nq], th)?;
        for (o, row) in self.rows.iter().enumerate() {
            out[o] = row.iter().fold(S::c(0.0), |acc, &(r, c)| acc + imp[r] * c);
        }
        Ok(())
    }
}

/// Post-impact state `(q, q̇⁺, a)` of the plastic impact with the contacts of `set`.
/// Arguments: `(x, θ)`.
pub(super) struct ImpactMap<'a> {
    pub(super) model: &'a GaitModel,
    pub(super) set: ConstraintSet,
}

impl GenericFunction for ImpactMap<'_> {
    fn dim(&self) -> usize {
        self.model.nx()
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), TermError> {
        let (nx, nq) = (self.model.nx(), self.model.nq());
        let (x, th) = z.split_at(nx);
        let (qd_plus, _) = self.model.impact(&self.set, &x[..nq], &x[nq..2 * nq], th)?;
        out.copy_from_slice(x);
        out[nq..2 * nq].copy_from_slice(&qd_plus);
        Ok(())
    }
}

/// Periodicity through the left/right mirror: `x_first − mirror(ψ(x_last))` without the
/// forward position, with ψ the trailing impact map (identity without one). Arguments:
/// `(x_first, x_last, θ)`.
pub(super) struct Periodicity<'a> {
    pub(super) model: &'a GaitModel,
    pub(super) impact: Option<ConstraintSet>,
    pub(super) xmap: Vec<usize>,
    pub(super) skip: usize,
}

impl GenericFunction for Periodicity<'_> {
    fn dim(&self) -> usize {
        self.model.nx() - 1
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), TermError> {
        let (nx, nq) = (self.model.nx(), self.model.nq());
        let (x0, rest) = z.split_at(nx);
        let (xe, th) = rest.split_at(nx);
        let mut xp = xe.to_vec();
        if let Some(set) = &self.impact {
            let (qd_plus, _) = self.model.impact(set, &xe[..nq], &xe[nq..2 * nq], th)?;
            xp[nq..2 * nq].copy_from_slice(&qd_plus);
        }
        for (o, i) in (0..nx).filter(|&i| i != self.skip).enumerate() {
            out[o] = x0[i] - xp[self.xmap[i]];
        }
        Ok(())
    }
}

/// Normal gap of one contact primitive. Arguments: `(x, θ)`.
pub(super) struct Gap<'a> {
    pub(super) model: &'a GaitModel,
    pub(super) contact: usize,
}

impl GenericFunction for Gap<'_> {
    fn dim(&self) -> usize {
        1
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), TermError> {
        let (nx, nq) = (self.model.nx(), self.model.nq());
        out[0] = self.model.gap(self.contact, &z[..nq], &z[nx..]);
        Ok(())
    }
    /// The positions and θ.
    fn curved_inputs(&self) -> Option<(Vec<usize>, usize)> {
        let (nx, nq) = (self.model.nx(), self.model.nq());
        Some(((0..nq).chain(nx..nx + self.model.ntheta()).collect(), 0))
    }
}
