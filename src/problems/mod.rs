//! Optimal control problems built from data and model files: the generic benchmark
//! problems (cart-pole swing-up, five-link biped) that prove the OCP engine knows
//! nothing about gait.

pub mod benchmark;

use crate::ocp::NodeFunction;

/// A [`NodeFunction`] from a closure `(z, value, jacobian)`.
pub struct FnTerm<F> {
    dim: usize,
    f: F,
}

impl<F> FnTerm<F>
where
    F: Fn(&[f64], &mut [f64], Option<&mut [f64]>) -> Result<(), String> + Send + Sync,
{
    /// Wrap `f` with output dimension `dim`.
    pub fn new(dim: usize, f: F) -> Self {
        Self { dim, f }
    }
}

impl<F> NodeFunction for FnTerm<F>
where
    F: Fn(&[f64], &mut [f64], Option<&mut [f64]>) -> Result<(), String> + Send + Sync,
{
    fn dim(&self) -> usize {
        self.dim
    }
    fn eval(&self, z: &[f64], value: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), String> {
        (self.f)(z, value, jac)
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
    fn eval(&self, z: &[f64], value: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), String> {
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
