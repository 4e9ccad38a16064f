//! Forward-mode AD plumbing, the crate's one home for it: the dual-number types the model
//! is evaluated with, and the Jacobian and Hessian drivers.
//!
//! A Jacobian of `f: ℝⁿ → ℝᵐ` is evaluated in chunks of [`CHUNK`] input directions with
//! the vector dual number [`AdChunk`], so one evaluation of the generic model code yields
//! [`CHUNK`] exact columns at once ([`jacobian`]); Hessians of a scalar come from nested
//! duals ([`hessian`], [`hessian_over`]). Small functions whose input size is known at
//! compile time (the benchmark models) use num-dual's own one-pass drivers through
//! [`dense_jacobian`] and [`dense_hessian`].

use nalgebra::SVector;
use num_dual::{Derivative, Dual2SVec64, DualSVec64, DualStruct};

/// Number of derivative directions carried by one [`AdChunk`]: the gait model's nine
/// coordinates, so that the dynamics' Jacobian in `(q, q̇)` takes two evaluations.
pub const CHUNK: usize = 9;

/// Dual number carrying [`CHUNK`] directional derivatives.
pub type AdChunk = DualSVec64<CHUNK>;

/// Number of inner directions of one [`AdNested`]. Narrower than [`CHUNK`]: the nested
/// number's cost per operation grows faster with the width than the number of
/// evaluations falls (knee-stiffness re-fit, evaluations: 20.5 s at 8, 18.3 s at 6,
/// 17.5 s at 4).
pub const HESSIAN_CHUNK: usize = 4;

/// The inner dual number of [`AdNested`].
pub type AdInner = DualSVec64<HESSIAN_CHUNK>;

/// A dual number over [`AdInner`]: one outer direction over [`HESSIAN_CHUNK`] inner directions,
/// for second derivatives (one Hessian column block per evaluation).
pub type AdNested = num_dual::Dual<AdInner>;

/// Hessian of a scalar function `f: ℝⁿ → ℝ` (column-major n × n) by nested forward AD.
/// Symmetry is used: outer direction `j` needs only the inner chunks up to `j`, so `f` is
/// evaluated about `n²/(2·HESSIAN_CHUNK) + n` times in [`AdNested`].
pub fn hessian<E>(
    x: &[f64],
    f: impl FnMut(&[AdNested]) -> Result<AdNested, E>,
    out: &mut [f64],
) -> Result<(), E> {
    let all: Vec<usize> = (0..x.len()).collect();
    hessian_over(x, &all, 0, f, out)
}

/// As [`hessian`], differentiating only in the inputs `curved` (distinct, any order):
/// the caller knows that every second derivative involving another input is zero (an
/// input that enters `f` affinely with constant coefficients), and those rows and
/// columns of `out` are set to zero. The first `affine_lead` of `curved` form a group in
/// which `f` is jointly affine (their second derivatives among themselves are zero, e.g.
/// activations that scale torques), so only their cross terms with the rest are
/// computed. Costs about `(k² − a²)/(2·HESSIAN_CHUNK) + k − a` evaluations for `k` curved inputs
/// of which `a` lead, instead of `n²/(2·HESSIAN_CHUNK) + n`.
pub fn hessian_over<E>(
    x: &[f64],
    curved: &[usize],
    affine_lead: usize,
    mut f: impl FnMut(&[AdNested]) -> Result<AdNested, E>,
    out: &mut [f64],
) -> Result<(), E> {
    let n = x.len();
    let k = curved.len();
    out.iter_mut().for_each(|v| *v = 0.0);
    // position of each input among the curved ones
    let mut slot = vec![usize::MAX; n];
    for (s, &i) in curved.iter().enumerate() {
        assert!(
            i < n && slot[i] == usize::MAX,
            "curved inputs out of range or repeated"
        );
        slot[i] = s;
    }
    let mut xs: Vec<AdNested> = Vec::with_capacity(n);
    // outer direction jj pairs with the inner ones up to jj: none outside the affine group
    // when jj lies in it
    for jj in affine_lead.min(k)..k {
        let mut start = 0;
        while start <= jj {
            xs.clear();
            for (i, &v) in x.iter().enumerate() {
                let s = slot[i];
                let mut inner = AdInner::from_re(v);
                if s != usize::MAX && s >= start && s < start + HESSIAN_CHUNK {
                    inner = inner.derivative(s - start);
                }
                let outer = if s == jj {
                    AdInner::from_re(1.0)
                } else {
                    AdInner::from_re(0.0)
                };
                xs.push(num_dual::Dual::new(inner, outer));
            }
            let y = f(&xs)?;
            let j = curved[jj];
            for c in 0..HESSIAN_CHUNK.min(k - start) {
                let ii = start + c;
                if ii > jj {
                    break;
                }
                let i = curved[ii];
                let v = eps(&y.eps, c);
                out[i + j * n] = v;
                out[j + i * n] = v;
            }
            start += HESSIAN_CHUNK;
        }
    }
    Ok(())
}

/// Seed `x` with unit directions for inputs `start..start+CHUNK`.
pub fn seed_chunk(x: &[f64], start: usize, out: &mut Vec<AdChunk>) {
    out.clear();
    for (i, &v) in x.iter().enumerate() {
        let d = AdChunk::from_re(v);
        if i >= start && i < start + CHUNK {
            out.push(d.derivative(i - start));
        } else {
            out.push(d);
        }
    }
}

/// `v` with derivative direction `k` of `N` seeded (a unit direction).
#[inline]
pub fn seed<const N: usize>(v: f64, k: usize) -> DualSVec64<N> {
    DualSVec64::<N>::from_re(v).derivative(k)
}

/// Value and column-major Jacobian (`jac[i + j * M]`) of `f: ℝᴺ → ℝᴹ` by one forward pass
/// with an `N`-lane vector dual number (num-dual's [`num_dual::jacobian`]).
pub fn dense_jacobian<const N: usize, const M: usize>(
    x: &[f64],
    f: impl FnOnce(&[DualSVec64<N>; N]) -> [DualSVec64<N>; M],
) -> (Vec<f64>, Vec<f64>) {
    assert_eq!(
        x.len(),
        N,
        "expected an input of length {N}, got {}",
        x.len()
    );
    let x = SVector::<f64, N>::from_column_slice(x);
    let (value, jac) = num_dual::jacobian(
        |xs: SVector<DualSVec64<N>, N>| SVector::from(f(&xs.into())),
        &x,
    );
    (value.as_slice().to_vec(), jac.as_slice().to_vec())
}

/// Hessian (column-major, `N × N`) of a scalar function of `N` variables by one
/// second-order forward pass (num-dual's [`num_dual::hessian`]).
pub fn dense_hessian<const N: usize>(
    z: &[f64],
    f: impl Fn(&[Dual2SVec64<N>]) -> Dual2SVec64<N>,
) -> Vec<f64> {
    let z = SVector::<f64, N>::from_column_slice(&z[..N]);
    let (_, _, h) = num_dual::hessian(|zs: SVector<Dual2SVec64<N>, N>| f(zs.as_slice()), &z);
    h.as_slice().to_vec()
}

/// Derivative part `k` of a vector dual number of any width (0 if the derivative is
/// structurally zero).
#[inline]
pub fn eps<const N: usize>(v: &DualSVec64<N>, k: usize) -> f64 {
    match &v.eps {
        Derivative(Some(m)) => m[k],
        Derivative(None) => 0.0,
    }
}

/// Value part.
#[inline]
pub fn re(v: &AdChunk) -> f64 {
    v.re()
}

/// Evaluate a Jacobian column-major (`jac[i + j*m] = ∂f_i/∂x_j`) and the value of `f`
/// by chunked forward-mode AD. `f` is called `ceil(n / CHUNK)` times.
pub fn jacobian<E>(
    x: &[f64],
    m: usize,
    mut f: impl FnMut(&[AdChunk], &mut [AdChunk]) -> Result<(), E>,
    value: &mut [f64],
    jac: &mut [f64],
) -> Result<(), E> {
    let n = x.len();
    assert_eq!(jac.len(), m * n);
    let mut xs = Vec::with_capacity(n);
    let mut ys = vec![AdChunk::from_re(0.0); m];
    let mut start = 0;
    loop {
        seed_chunk(x, start, &mut xs);
        f(&xs, &mut ys)?;
        if start == 0 {
            for (v, y) in value.iter_mut().zip(&ys) {
                *v = y.re;
            }
        }
        for k in 0..CHUNK.min(n.saturating_sub(start)) {
            let j = start + k;
            for (i, y) in ys.iter().enumerate() {
                jac[i + j * m] = eps(y, k);
            }
        }
        start += CHUNK;
        if start >= n {
            break;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::DualNum;

    /// `f = x0² x2 + sin(x2 x4) + 3 x1 − x3 + Σ x_i x_{i−5}²` (i = 5, 7, 9, 10) over 11 inputs, inputs 1 and 3
    /// affine with constant coefficients: the Hessian over the curved inputs equals the
    /// full one (zero rows and columns for 1 and 3), also with the inputs it is jointly
    /// affine in leading, and all match the analytic one.
    #[test]
    fn hessian_over_curved_inputs_matches_the_full_hessian() {
        let n = 11;
        let x: Vec<f64> = (0..n).map(|i| 0.3 + 0.17 * i as f64).collect();
        let f = |z: &[AdNested]| -> Result<AdNested, ()> {
            let mut y = z[0] * z[0] * z[2] + (z[2] * z[4]).sin() + z[1] * 3.0 - z[3];
            for i in [5, 7, 9, 10] {
                y += z[i] * z[i - 5] * z[i - 5];
            }
            Ok(y)
        };
        let (mut full, mut part) = (vec![f64::NAN; n * n], vec![f64::NAN; n * n]);
        hessian(&x, f, &mut full).unwrap();
        let curved: Vec<usize> = (0..n).filter(|&i| i != 1 && i != 3).collect();
        hessian_over(&x, &curved, 0, f, &mut part).unwrap();
        // f is jointly affine in (x7, x9, x10) and constant in (x6, x8): they lead, in any
        // order (x5 is not: x10 x5²)
        let mut lead = vec![f64::NAN; n * n];
        let order = [10, 7, 9, 6, 8, 5, 4, 0, 2];
        hessian_over(&x, &order, 5, f, &mut lead).unwrap();
        let mut exact = vec![0.0; n * n];
        let mut add = |i: usize, j: usize, v: f64| {
            exact[i + j * n] += v;
            if i != j {
                exact[j + i * n] += v;
            }
        };
        add(0, 0, 2.0 * x[2]);
        add(0, 2, 2.0 * x[0]);
        let s = -(x[2] * x[4]).sin();
        add(2, 2, s * x[4] * x[4]);
        add(4, 4, s * x[2] * x[2]);
        add(2, 4, s * x[2] * x[4] + (x[2] * x[4]).cos());
        for i in [5, 7, 9, 10] {
            add(i - 5, i - 5, 2.0 * x[i]);
            add(i, i - 5, 2.0 * x[i - 5]);
        }
        for k in 0..n * n {
            assert!(
                (full[k] - exact[k]).abs() < 1e-12,
                "full {k}: {} vs {}",
                full[k],
                exact[k]
            );
            assert_eq!(part[k], full[k], "entry {k}");
            assert_eq!(lead[k], full[k], "entry {k} with an affine lead");
        }
    }
}
