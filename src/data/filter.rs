//! Zero-phase low-pass filtering of uniformly sampled signals, as gait labs smooth
//! motion-capture kinematics before differentiating them (a velocity target from an
//! interpolating spline of raw samples amplifies measurement noise by about 1/Δt).
//!
//! A second-order Butterworth section designed by the bilinear transform with
//! pre-warping, run forwards and backwards (no phase lag; squared magnitude response
//! $|H(f)|^2 = 1/(1 + (\tan(\pi f/f_s)/\tan(\pi f_c/f_s))^4)$). The ends are padded by
//! odd reflection about the end values, so a line passes through unchanged.

/// Zero-phase second-order Butterworth low-pass of `x` sampled at `fs` Hz with cutoff
/// `fc` Hz (`0 < fc < fs/2`). Signals shorter than 3 samples are returned unchanged.
pub fn low_pass(x: &[f64], fs: f64, fc: f64) -> Vec<f64> {
    let n = x.len();
    if n < 3 {
        return x.to_vec();
    }
    let k = (std::f64::consts::PI * fc / fs).tan();
    let q = std::f64::consts::SQRT_2;
    let norm = 1.0 / (1.0 + q * k + k * k);
    let b = [k * k * norm, 2.0 * k * k * norm, k * k * norm];
    let a = [2.0 * (k * k - 1.0) * norm, (1.0 - q * k + k * k) * norm];
    // odd reflection about both ends (pad ≈ 3 time constants, at most the signal)
    let pad = ((3.0 * fs / fc).ceil() as usize).min(n - 1);
    let mut y: Vec<f64> = Vec::with_capacity(n + 2 * pad);
    y.extend((1..=pad).rev().map(|i| 2.0 * x[0] - x[i]));
    y.extend_from_slice(x);
    y.extend((1..=pad).map(|i| 2.0 * x[n - 1] - x[n - 1 - i]));
    let pass = |v: &mut Vec<f64>| {
        // start at rest on the first value (the steady state of a constant input)
        let (mut x1, mut x2, mut y1, mut y2) = (v[0], v[0], v[0], v[0]);
        for s in v.iter_mut() {
            let x0 = *s;
            let y0 = b[0] * x0 + b[1] * x1 + b[2] * x2 - a[0] * y1 - a[1] * y2;
            x2 = x1;
            x1 = x0;
            y2 = y1;
            y1 = y0;
            *s = y0;
        }
    };
    pass(&mut y);
    y.reverse();
    pass(&mut y);
    y.reverse();
    y[pad..pad + n].to_vec()
}
