//! Interpolating cubic splines with not-a-knot end conditions.
//!
//! Given knots $t_0 < t_1 < \dots < t_{n-1}$ and values $y_i$, the spline $s$ is a cubic
//! polynomial on each interval, twice continuously differentiable, with $s(t_i) = y_i$.
//! The two missing conditions are **not-a-knot**: $s'''$ is continuous at $t_1$ and at
//! $t_{n-2}$ (the first two and the last two pieces are one cubic each). Unlike the
//! natural spline ($s'' = 0$ at the ends), this reproduces any cubic polynomial exactly,
//! and its end derivatives are not biased towards zero curvature, which matters for
//! tracked joint angles whose accelerations feed the dynamics.
//!
//! The slopes $s_i = s'(t_i)$ solve the tridiagonal system (de Boor 1978, ch. IV)
//! $$h_i s_{i-1} + 2(h_{i-1}+h_i) s_i + h_{i-1} s_{i+1} = 3(h_i d_{i-1} + h_{i-1} d_i),$$
//! $h_i = t_{i+1}-t_i$, $d_i = (y_{i+1}-y_i)/h_i$, with the not-a-knot rows
//! $h_1 s_0 + (h_0+h_1) s_1 = \big((h_0 + 2(h_0+h_1)) h_1 d_0 + h_0^2 d_1\big)/(h_0+h_1)$ and
//! its mirror image at the end. Two knots give the straight line, three the parabola.
//! Outside $[t_0, t_{n-1}]$ the end pieces are extended (cubic extrapolation).

use super::error::{memory_path, DataError};

/// A $C^2$ piecewise-cubic interpolant with not-a-knot end conditions (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct CubicSpline {
    /// Knots (strictly increasing).
    t: Vec<f64>,
    /// `coef[i] = [c0, c1, c2, c3]`: on piece `i`, `s(t) = c0 + c1 τ + c2 τ² + c3 τ³` with `τ = t − t_i`.
    coef: Vec<[f64; 4]>,
}

impl CubicSpline {
    /// The interpolating spline through `(t[i], y[i])`.
    ///
    /// Errors: fewer than two knots, lengths that differ, knots that are not finite and
    /// strictly increasing, values that are not finite.
    ///
    /// # Example
    /// ```
    /// use footfall::data::CubicSpline;
    /// let t = [0.0, 0.3, 1.0, 1.2, 2.0];
    /// let y: Vec<f64> = t.iter().map(|x| x * x * x - x).collect();
    /// let s = CubicSpline::new(&t, &y).unwrap();
    /// assert!((s.eval(0.5) - (0.125 - 0.5)).abs() < 1e-12);
    /// assert!((s.derivative(0.5) - (3.0 * 0.25 - 1.0)).abs() < 1e-12);
    /// ```
    pub fn new(t: &[f64], y: &[f64]) -> Result<Self, DataError> {
        let p = memory_path();
        let n = t.len();
        if y.len() != n {
            return Err(DataError::invalid(
                &p,
                "spline",
                format!("{} knots but {} values", n, y.len()),
            ));
        }
        if n < 2 {
            return Err(DataError::invalid(
                &p,
                "spline",
                format!("{n} knot(s); a spline needs at least 2"),
            ));
        }
        for i in 0..n {
            if !t[i].is_finite() {
                return Err(DataError::invalid(
                    &p,
                    "spline",
                    format!("knot {i} is {}", t[i]),
                ));
            }
            if !y[i].is_finite() {
                return Err(DataError::invalid(
                    &p,
                    "spline",
                    format!("value {i} (t = {}) is {}", t[i], y[i]),
                ));
            }
            if i > 0 && t[i] <= t[i - 1] {
                return Err(DataError::invalid(
                    &p,
                    "spline",
                    format!(
                        "knots must increase strictly: t[{i}] = {} after t[{}] = {}",
                        t[i],
                        i - 1,
                        t[i - 1]
                    ),
                ));
            }
        }
        let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let d: Vec<f64> = (0..n - 1).map(|i| (y[i + 1] - y[i]) / h[i]).collect();
        let s = match n {
            2 => vec![d[0], d[0]],
            3 => {
                // The parabola through the three points.
                let c2 = (d[1] - d[0]) / (t[2] - t[0]);
                vec![d[0] - c2 * h[0], d[0] + c2 * h[0], d[1] + c2 * h[1]]
            }
            _ => not_a_knot_slopes(&h, &d),
        };
        let coef = (0..n - 1)
            .map(|i| {
                let c2 = (3.0 * d[i] - 2.0 * s[i] - s[i + 1]) / h[i];
                let c3 = (s[i] + s[i + 1] - 2.0 * d[i]) / (h[i] * h[i]);
                [y[i], s[i], c2, c3]
            })
            .collect();
        Ok(Self {
            t: t.to_vec(),
            coef,
        })
    }

    /// The knots.
    pub fn knots(&self) -> &[f64] {
        &self.t
    }

    /// The interval `[t_0, t_{n-1}]` spanned by the knots.
    pub fn range(&self) -> (f64, f64) {
        (self.t[0], self.t[self.t.len() - 1])
    }

    fn piece(&self, x: f64) -> (usize, f64) {
        let m = self.coef.len();
        // Index of the last knot <= x, clamped to the pieces.
        let i = match self.t.partition_point(|&k| k <= x) {
            0 => 0,
            k => (k - 1).min(m - 1),
        };
        (i, x - self.t[i])
    }

    /// $s(t)$.
    pub fn eval(&self, t: f64) -> f64 {
        let (i, x) = self.piece(t);
        let c = &self.coef[i];
        c[0] + x * (c[1] + x * (c[2] + x * c[3]))
    }

    /// $s(t)$ at a dual number: the piece is chosen by the value of `t`, and the
    /// polynomial is evaluated in `t`'s scalar type, so derivatives with respect to `t`
    /// are exact (used to identify a measurement's time offset).
    pub fn eval_generic<S: crate::model::Scalar>(&self, t: S) -> S {
        let (i, _) = self.piece(t.value());
        let c = &self.coef[i];
        let x = t - self.t[i];
        x * (x * (x * c[3] + c[2]) + c[1]) + c[0]
    }

    /// $s'(t)$.
    pub fn derivative(&self, t: f64) -> f64 {
        let (i, x) = self.piece(t);
        let c = &self.coef[i];
        c[1] + x * (2.0 * c[2] + x * 3.0 * c[3])
    }

    /// $s'(t)$ at a dual number (as [`eval_generic`](Self::eval_generic)): exact
    /// derivatives with respect to `t` (a node's instant moved by a clock offset).
    pub fn derivative_generic<S: crate::model::Scalar>(&self, t: S) -> S {
        let (i, _) = self.piece(t.value());
        let c = &self.coef[i];
        let x = t - self.t[i];
        x * (x * (3.0 * c[3]) + 2.0 * c[2]) + c[1]
    }

    /// $s''(t)$ (continuous; piecewise linear).
    pub fn second_derivative(&self, t: f64) -> f64 {
        let (i, x) = self.piece(t);
        let c = &self.coef[i];
        2.0 * c[2] + 6.0 * c[3] * x
    }
}

/// Slopes of the not-a-knot spline for `n >= 4` knots (tridiagonal solve, Thomas algorithm).
fn not_a_knot_slopes(h: &[f64], d: &[f64]) -> Vec<f64> {
    let n = h.len() + 1;
    // Row i: sub[i] s_{i-1} + diag[i] s_i + sup[i] s_{i+1} = rhs[i].
    let mut sub = vec![0.0; n];
    let mut diag = vec![0.0; n];
    let mut sup = vec![0.0; n];
    let mut rhs = vec![0.0; n];
    let w0 = h[0] + h[1];
    diag[0] = h[1];
    sup[0] = w0;
    rhs[0] = ((h[0] + 2.0 * w0) * h[1] * d[0] + h[0] * h[0] * d[1]) / w0;
    for i in 1..n - 1 {
        sub[i] = h[i];
        diag[i] = 2.0 * (h[i - 1] + h[i]);
        sup[i] = h[i - 1];
        rhs[i] = 3.0 * (h[i] * d[i - 1] + h[i - 1] * d[i]);
    }
    let (a, b) = (h[n - 3], h[n - 2]);
    let w1 = a + b;
    sub[n - 1] = w1;
    diag[n - 1] = a;
    rhs[n - 1] = (b * b * d[n - 3] + (2.0 * w1 + b) * a * d[n - 2]) / w1;
    // Forward elimination.
    for i in 1..n {
        let m = sub[i] / diag[i - 1];
        diag[i] -= m * sup[i - 1];
        rhs[i] -= m * rhs[i - 1];
    }
    let mut s = vec![0.0; n];
    s[n - 1] = rhs[n - 1] / diag[n - 1];
    for i in (0..n - 1).rev() {
        s[i] = (rhs[i] - sup[i] * s[i + 1]) / diag[i];
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parabola_and_line() {
        let s = CubicSpline::new(&[0.0, 1.0, 3.0], &[1.0, 2.0, 10.0]).unwrap();
        // y = 1 + 0 t + t^2 ... check: 1, 2, 10 -> y = t^2 + 1 at 0,1,3 gives 1,2,10.
        for &x in &[-1.0, 0.5, 2.0, 4.0] {
            assert!((s.eval(x) - (x * x + 1.0)).abs() < 1e-12);
        }
        let l = CubicSpline::new(&[0.0, 2.0], &[1.0, 5.0]).unwrap();
        assert!((l.eval(1.0) - 3.0).abs() < 1e-15);
        assert!((l.derivative(7.0) - 2.0).abs() < 1e-15);
    }
}
