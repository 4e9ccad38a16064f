//! Fourier-series fits of periodic gait signals and the half-cycle shift that generates
//! the unmeasured leg from the measured one (Ezati et al. 2020, §3.3).
//!
//! A signal sampled at $t_j$ over one gait cycle of period $T_c$ is fitted by least
//! squares with
//! $$x(t) = a_0 + \sum_{i=1}^{m} a_i \cos(i\omega t) + b_i \sin(i\omega t), \qquad \omega = 2\pi/T_c,$$
//! i.e. $x = M(t)\,c$ with the basis matrix $M = [1\ \cos(i\omega t_j)\ \sin(i\omega t_j)]$
//! (Ezati et al. 2020, eq. 1) and $c = M^\dagger x$ by the SVD pseudo-inverse. The other leg is
//! $x_l(t_j) = M(t_j + T_{sh})\, M(t_j)^\dagger x_r$ (Ezati et al. 2020, eq. 2–3) with $T_{sh} = T_c/2$ for
//! a symmetric gait. Ezati et al. use $m = 5$ harmonics ([`SEED_FOURIER_ORDER`]).

use super::error::{memory_path, DataError};
use nalgebra::{DMatrix, DVector};

/// Number of harmonics of the fit (m = 5, Ezati et al. 2020, §3.3).
pub const SEED_FOURIER_ORDER: usize = 5;

/// A fitted truncated Fourier series of period `period`.
#[derive(Debug, Clone, PartialEq)]
pub struct FourierSeries {
    /// Period $T_c$ (s).
    pub period: f64,
    /// Mean $a_0$.
    pub a0: f64,
    /// Cosine coefficients $a_1 \dots a_m$.
    pub a: Vec<f64>,
    /// Sine coefficients $b_1 \dots b_m$.
    pub b: Vec<f64>,
}

impl FourierSeries {
    /// Least-squares fit of `order` harmonics to `(time, values)`.
    ///
    /// The samples should cover one cycle (a duplicated end point is harmless); if they
    /// cover more, the fit is the best periodic approximation of all of them. Needs at
    /// least `2·order + 1` samples, a finite positive period and finite values.
    pub fn fit(time: &[f64], values: &[f64], period: f64, order: usize) -> Result<Self, DataError> {
        let p = memory_path();
        if time.len() != values.len() {
            return Err(DataError::invalid(
                &p,
                "fourier",
                format!("{} times but {} values", time.len(), values.len()),
            ));
        }
        if !(period.is_finite() && period > 0.0) {
            return Err(DataError::invalid(
                &p,
                "period",
                format!("the period must be finite and positive, got {period}"),
            ));
        }
        let n = time.len();
        let ncoef = 2 * order + 1;
        if n < ncoef {
            return Err(DataError::invalid(
                &p,
                "fourier",
                format!("{n} samples cannot determine {order} harmonics (needs at least {ncoef})"),
            ));
        }
        if let Some(j) = (0..n).find(|&j| !time[j].is_finite() || !values[j].is_finite()) {
            return Err(DataError::invalid(
                &p,
                "fourier",
                format!(
                    "sample {j} is not finite (t = {}, value = {})",
                    time[j], values[j]
                ),
            ));
        }
        let w = 2.0 * std::f64::consts::PI / period;
        let m = basis(time, w, order);
        let svd = m.svd(true, true);
        let c = svd
            .solve(&DVector::from_column_slice(values), 1e-12)
            .map_err(|e| DataError::invalid(&p, "fourier", format!("least squares failed: {e}")))?;
        Ok(Self {
            period,
            a0: c[0],
            a: (0..order).map(|i| c[1 + 2 * i]).collect(),
            b: (0..order).map(|i| c[2 + 2 * i]).collect(),
        })
    }

    /// Number of harmonics $m$.
    pub fn order(&self) -> usize {
        self.a.len()
    }

    /// $x(t)$.
    pub fn eval(&self, t: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI / self.period;
        let mut x = self.a0;
        for i in 0..self.a.len() {
            let (s, c) = ((i + 1) as f64 * w * t).sin_cos();
            x += self.a[i] * c + self.b[i] * s;
        }
        x
    }
}

/// Ezati et al.'s basis matrix $[1\ \cos(i\omega t_j)\ \sin(i\omega t_j)]$, columns interleaved.
fn basis(time: &[f64], w: f64, order: usize) -> DMatrix<f64> {
    DMatrix::from_fn(time.len(), 2 * order + 1, |j, k| {
        if k == 0 {
            1.0
        } else {
            let i = k.div_ceil(2) as f64;
            let (s, c) = (i * w * time[j]).sin_cos();
            if k % 2 == 1 {
                c
            } else {
                s
            }
        }
    })
}

/// The values of the other leg: a [`SEED_FOURIER_ORDER`]-harmonic Fourier series fitted to
/// `values` at `time`, evaluated half a period later, $x(t_j + T_c/2)$ (Ezati et al. 2020, §3.3).
///
/// `time` should span one gait cycle of duration `period` (see [`FourierSeries::fit`]).
/// Exact for signals made of up to five harmonics of $1/T_c$; for real gait signals the
/// result is their five-harmonic approximation (sharp features such as heel-strike force
/// transients are smoothed, and a signal that is zero for part of the cycle, such as a
/// normal force in swing, ripples around zero). Use [`half_cycle_shift_order`] to choose
/// the number of harmonics.
///
/// Errors: see [`FourierSeries::fit`] (needs at least 11 samples).
///
/// # Example
/// ```
/// use footfall::data::half_cycle_shift;
/// let t: Vec<f64> = (0..50).map(|j| j as f64 * 0.02).collect();
/// let x: Vec<f64> = t.iter().map(|t| (std::f64::consts::TAU * t).sin()).collect();
/// let y = half_cycle_shift(&t, &x, 1.0).unwrap();
/// assert!((y[5] + x[5]).abs() < 1e-12); // sin(ωt + π) = −sin(ωt)
/// ```
pub fn half_cycle_shift(time: &[f64], values: &[f64], period: f64) -> Result<Vec<f64>, DataError> {
    half_cycle_shift_order(time, values, period, SEED_FOURIER_ORDER)
}

/// [`half_cycle_shift`] with `order` harmonics.
pub fn half_cycle_shift_order(
    time: &[f64],
    values: &[f64],
    period: f64,
    order: usize,
) -> Result<Vec<f64>, DataError> {
    let f = FourierSeries::fit(time, values, period, order)?;
    Ok(time.iter().map(|&t| f.eval(t + 0.5 * period)).collect())
}
