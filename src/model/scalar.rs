//! The scalar type all model code is generic over.
//!
//! Model functions are written once for any `S: Scalar`. With `S = f64` they evaluate the
//! model; with the dual numbers of `num-dual` they return exact derivatives by forward-mode
//! automatic differentiation (no finite differences anywhere in the solver path).

use num_dual::DualNum;

/// A real number or a (possibly nested) dual number over `f64`.
pub trait Scalar: DualNum<Primitive = f64> + Copy + Send + Sync {
    /// The value part (`f64` for plain numbers).
    #[inline]
    fn value(&self) -> f64 {
        self.re()
    }
    /// A constant (zero derivative parts).
    #[inline]
    fn c(v: f64) -> Self {
        Self::from(v)
    }
}

impl<T: DualNum<Primitive = f64> + Copy + Send + Sync> Scalar for T {}
