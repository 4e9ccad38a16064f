//! Optimal control problems built from data and model files: the generic benchmark
//! problems (cart-pole swing-up, five-link biped) that prove the OCP engine knows
//! nothing about gait.

pub mod benchmarks;
pub mod check;
pub mod diagnose;
pub mod distributions;
pub mod error;
pub mod errors;
pub mod evaluation;
pub mod foot_fit;
pub mod gait;
pub mod gait_ode;
pub mod peer_gait;
pub mod predict;
pub mod synth;
pub mod track;
pub mod tracking;
pub mod transient;
pub mod validity;

pub use error::{
    DiagnoseError, FieldError, FootFitError, PeerGaitError, ProblemError, SampleSpan, WindowError,
};
pub use gait_ode::GaitOde;

use crate::model::ad::{self, AdChunk, AdNested};
use crate::model::effects::ModelScalar;
use crate::ocp::{NodeFunction, TermError};

/// A vector function written once over any model scalar, so that its value, its exact
/// Jacobian (chunked forward AD) and its exact weighted Hessian (nested forward AD) all
/// come from the same code. Wrap it in [`AdTerm`] to use it as a [`NodeFunction`].
pub trait GenericFunction: Send + Sync {
    /// Output dimension.
    fn dim(&self) -> usize;
    /// Evaluate at `z` into `out`.
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), TermError>;
    /// Whether the function is affine in `z` (zero Hessian, no AD pass needed).
    fn is_linear(&self) -> bool {
        false
    }
    /// The inputs that can appear in a second derivative (`None`: all) and how many of
    /// them lead as a group the function is jointly affine in, as for
    /// [`ad::hessian_over`]. Every second derivative involving another input must be
    /// exactly zero (an input absent from `eval`, or entering it affinely with constant
    /// coefficients); the Hessian then skips those inputs.
    fn curved_inputs(&self) -> Option<(Vec<usize>, usize)> {
        None
    }
}

/// [`NodeFunction`] view of a [`GenericFunction`], with exact Jacobian and Hessian.
pub struct AdTerm<T>(pub T);

impl<T: GenericFunction> NodeFunction for AdTerm<T> {
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn eval(&self, z: &[f64], value: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError> {
        match jac {
            None => self.0.eval(z, value),
            Some(j) => ad::jacobian(
                z,
                self.0.dim(),
                |zs: &[AdChunk], out: &mut [AdChunk]| self.0.eval(zs, out),
                value,
                j,
            ),
        }
    }
    fn has_hessian(&self) -> bool {
        true
    }
    fn weighted_hessian(
        &self,
        z: &[f64],
        weights: &[f64],
        out: &mut [f64],
    ) -> Result<(), TermError> {
        if self.0.is_linear() || weights.iter().all(|w| *w == 0.0) {
            out.iter_mut().for_each(|v| *v = 0.0);
            return Ok(());
        }
        let mut y = vec![AdNested::from(0.0); self.0.dim()];
        let (curved, lead) = self
            .0
            .curved_inputs()
            .unwrap_or_else(|| ((0..z.len()).collect(), 0));
        ad::hessian_over(
            z,
            &curved,
            lead,
            |zs| {
                self.0.eval(zs, &mut y)?;
                Ok(y.iter()
                    .zip(weights)
                    .fold(AdNested::from(0.0), |acc, (v, w)| acc + *v * *w))
            },
            out,
        )
    }
}

/// Callback computing `Σ w_i ∇²f_i(z)` (nz × nz column-major) for an [`FnTerm`].
pub type HessianFn = Box<dyn Fn(&[f64], &[f64], &mut [f64]) -> Result<(), TermError> + Send + Sync>;

/// A [`NodeFunction`] from a closure `(z, value, jacobian)`, optionally with an exact
/// weighted Hessian.
pub struct FnTerm<F> {
    dim: usize,
    f: F,
    hessian: Option<HessianFn>,
}

impl<F> FnTerm<F>
where
    F: Fn(&[f64], &mut [f64], Option<&mut [f64]>) -> Result<(), TermError> + Send + Sync,
{
    /// Wrap `f` with output dimension `dim`.
    pub fn new(dim: usize, f: F) -> Self {
        Self {
            dim,
            f,
            hessian: None,
        }
    }

    /// Attach the exact weighted Hessian.
    pub fn with_hessian(mut self, h: HessianFn) -> Self {
        self.hessian = Some(h);
        self
    }
}

impl<F> NodeFunction for FnTerm<F>
where
    F: Fn(&[f64], &mut [f64], Option<&mut [f64]>) -> Result<(), TermError> + Send + Sync,
{
    fn dim(&self) -> usize {
        self.dim
    }
    fn eval(&self, z: &[f64], value: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError> {
        (self.f)(z, value, jac)
    }
    fn has_hessian(&self) -> bool {
        self.hessian.is_some()
    }
    fn weighted_hessian(
        &self,
        z: &[f64],
        weights: &[f64],
        out: &mut [f64],
    ) -> Result<(), TermError> {
        match &self.hessian {
            Some(h) => h(z, weights, out),
            None => Err(TermError::NoHessian),
        }
    }
}

/// A linear function `A z` (A given row-major, `dim × nz`).
pub struct Linear {
    a: Vec<f64>,
    dim: usize,
    nz: usize,
}

impl Linear {
    /// `A` row-major with `dim` rows.
    pub fn new(a: Vec<f64>, dim: usize) -> Self {
        let nz = if dim == 0 { 0 } else { a.len() / dim };
        Self { a, dim, nz }
    }
}

impl NodeFunction for Linear {
    fn dim(&self) -> usize {
        self.dim
    }
    fn has_hessian(&self) -> bool {
        true
    }
    fn weighted_hessian(
        &self,
        _z: &[f64],
        _weights: &[f64],
        out: &mut [f64],
    ) -> Result<(), TermError> {
        out.iter_mut().for_each(|v| *v = 0.0);
        Ok(())
    }
    fn eval(&self, z: &[f64], value: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError> {
        for i in 0..self.dim {
            value[i] = (0..self.nz).map(|j| self.a[i * self.nz + j] * z[j]).sum();
        }
        if let Some(jac) = jac {
            for i in 0..self.dim {
                for j in 0..self.nz {
                    jac[i + j * self.dim] = self.a[i * self.nz + j];
                }
            }
        }
        Ok(())
    }
}
