//! Small dense linear algebra generic over [`Scalar`], so that derivatives pass through
//! the solves of the contact KKT system by automatic differentiation.
//!
//! Matrices are row-major `n × n` slices; sizes here are at most a few dozen.

use super::Scalar;
use std::ops::{Div, Mul, SubAssign};

/// Failure of a factorisation: the matrix is not positive definite at `pivot`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NotPositiveDefinite {
    /// Index of the pivot that was not positive.
    pub pivot: usize,
    /// Its value.
    pub value: f64,
}

/// In-place Cholesky factorisation `A = L Lᵀ` of a symmetric positive-definite row-major
/// matrix; on return the lower triangle holds `L`. A pivot below `rel_tol · max|A_ii|`
/// is reported as rank deficiency (e.g. an over-constrained contact set).
pub fn cholesky<S: Scalar>(a: &mut [S], n: usize, rel_tol: f64) -> Result<(), NotPositiveDefinite> {
    assert_eq!(a.len(), n * n);
    let scale = (0..n)
        .map(|i| a[i * n + i].value().abs())
        .fold(0.0, f64::max)
        .max(1e-300);
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if !(d.value() > rel_tol * scale) {
            return Err(NotPositiveDefinite {
                pivot: j,
                value: d.value(),
            });
        }
        let l = d.sqrt();
        a[j * n + j] = l;
        let inv = l.recip();
        for i in (j + 1)..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s * inv;
        }
    }
    Ok(())
}

/// Solve `L Lᵀ x = b` in place with the factor from [`cholesky`]. The factor's entries
/// `F` may be real where `b` carries derivative parts (`F = f64`): each part is then
/// solved with the same factor.
pub fn cholesky_solve<F, S>(l: &[F], n: usize, b: &mut [S])
where
    F: Copy,
    S: Copy + SubAssign + Mul<F, Output = S> + Div<F, Output = S>,
{
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= b[k] * l[i * n + k];
        }
        b[i] = s / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in (i + 1)..n {
            s -= b[k] * l[k * n + i];
        }
        b[i] = s / l[i * n + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_spd_system() {
        let a0 = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0];
        let mut a = a0;
        cholesky(&mut a, 3, 1e-14).unwrap();
        let mut x = [1.0, 2.0, 3.0];
        cholesky_solve(&a, 3, &mut x);
        for i in 0..3 {
            let r: f64 = (0..3).map(|j| a0[i * 3 + j] * x[j]).sum();
            assert!((r - [1.0, 2.0, 3.0][i]).abs() < 1e-13);
        }
    }

    #[test]
    fn reports_singular_matrix() {
        let mut a = [1.0, 1.0, 1.0, 1.0];
        let e = cholesky(&mut a, 2, 1e-12).unwrap_err();
        assert_eq!(e.pivot, 1);
    }
}
