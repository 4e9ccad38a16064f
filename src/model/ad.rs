//! Forward-mode AD plumbing: the dual-number types the model is evaluated with, and the
//! chunked Jacobian driver.
//!
//! A Jacobian of `f: ℝⁿ → ℝᵐ` is evaluated in chunks of [`CHUNK`] input directions with
//! the vector dual number [`AdChunk`], so one evaluation of the generic model code yields
//! [`CHUNK`] exact columns at once.

use num_dual::{Derivative, DualSVec64, DualStruct};

/// Number of derivative directions carried by one [`AdChunk`].
pub const CHUNK: usize = 8;

/// Dual number carrying [`CHUNK`] directional derivatives.
pub type AdChunk = DualSVec64<CHUNK>;

/// A dual number over [`AdChunk`]: one outer direction over [`CHUNK`] inner directions,
/// for second derivatives (one Hessian column block per evaluation).
pub type AdNested = num_dual::Dual<AdChunk>;

/// Hessian of a scalar function `f: ℝⁿ → ℝ` (column-major n × n) by nested forward AD.
/// Symmetry is used: outer direction `j` needs only the inner chunks up to `j`, so `f` is
/// evaluated about `n²/(2·CHUNK) + n` times in [`AdNested`].
pub fn hessian<E>(
    x: &[f64],
    mut f: impl FnMut(&[AdNested]) -> Result<AdNested, E>,
    out: &mut [f64],
) -> Result<(), E> {
    let n = x.len();
    let mut xs: Vec<AdNested> = Vec::with_capacity(n);
    for j in 0..n {
        let mut start = 0;
        while start <= j {
            xs.clear();
            for (i, &v) in x.iter().enumerate() {
                let mut inner = AdChunk::from_re(v);
                if i >= start && i < start + CHUNK {
                    inner = inner.derivative(i - start);
                }
                let outer = if i == j {
                    AdChunk::from_re(1.0)
                } else {
                    AdChunk::from_re(0.0)
                };
                xs.push(num_dual::Dual::new(inner, outer));
            }
            let y = f(&xs)?;
            for k in 0..CHUNK.min(n - start) {
                let i = start + k;
                if i > j {
                    break;
                }
                let v = eps(&y.eps, k);
                out[i + j * n] = v;
                out[j + i * n] = v;
            }
            start += CHUNK;
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

/// Derivative part `k` of `v` (0 if the derivative is structurally zero).
#[inline]
pub fn eps(v: &AdChunk, k: usize) -> f64 {
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
    debug_assert_eq!(jac.len(), m * n);
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
