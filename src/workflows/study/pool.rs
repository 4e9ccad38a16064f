//! Readings of one candidate in several trials, pooled.
//!
//! Each trial's reading is $x_i$ with the window's own (Newey–West) standard deviation
//! $s_i$ and the check's total one $\sigma_i = \sqrt{s_i^2 + n^2}$, where $n$ is the
//! spread the body model's own error gives untouched trials. The pooled estimate is the
//! inverse-variance mean $\bar x = \sum w_i x_i / \sum w_i$ with $w_i = 1/s_i^2$. The body
//! model's error is the same in every trial of a subject, so it does not average out: it
//! is added once, $\sigma_{\bar x}^2 = 1/\sum w_i + n^2$ (with $n$ the largest of the
//! trials'). Heterogeneity is Cochran's $Q = \sum w_i (x_i - \bar x)^2$ on $k - 1$ degrees
//! of freedom, its upper-tail probability under $\chi^2_{k-1}$, and
//! $I^2 = \max(0, (Q - (k-1))/Q)$.

use serde::Serialize;

/// One trial's reading of a candidate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Estimate (the candidate's unit).
    pub estimate: f64,
    /// The check's standard deviation: the window's own and the untouched trials' spread
    /// in quadrature.
    pub sd: f64,
    /// The window's own (Newey–West) standard deviation.
    pub sd_within: f64,
}

/// Several trials' readings of one candidate, pooled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pooled {
    /// Trials pooled.
    pub trials: usize,
    /// Inverse-variance weighted mean (the candidate's unit).
    pub estimate: f64,
    /// Its standard deviation, the body model's shared spread included.
    pub sd: f64,
    /// Its standard deviation from the trials' own noise alone, `1/√Σw`.
    pub sd_within: f64,
    /// `estimate / sd`.
    pub z: f64,
    /// Cochran's Q.
    pub q: f64,
    /// Its degrees of freedom, `trials − 1`.
    pub df: usize,
    /// `P(χ²_df > Q)`: a small value says the trials do not read the same effect.
    pub p_heterogeneity: f64,
    /// Share of the spread across trials beyond their own noise, `max(0, (Q − df)/Q)`.
    pub i2: f64,
}

/// Pool `samples` (each with finite estimate and positive finite `sd_within`; others
/// are left out). `None` when fewer than one sample is usable.
pub fn pool(samples: &[Sample]) -> Option<Pooled> {
    let ok: Vec<&Sample> = samples
        .iter()
        .filter(|s| s.estimate.is_finite() && s.sd_within.is_finite() && s.sd_within > 0.0)
        .collect();
    if ok.is_empty() {
        return None;
    }
    let w: Vec<f64> = ok
        .iter()
        .map(|s| 1.0 / (s.sd_within * s.sd_within))
        .collect();
    let sw: f64 = w.iter().sum();
    let mean = ok.iter().zip(&w).map(|(s, w)| w * s.estimate).sum::<f64>() / sw;
    let q: f64 = ok
        .iter()
        .zip(&w)
        .map(|(s, w)| w * (s.estimate - mean).powi(2))
        .sum();
    let shared = ok.iter().map(|s| shared_spread(s)).fold(0.0f64, f64::max);
    let sd_within = sw.recip().sqrt();
    let sd = sd_within.hypot(shared);
    let df = ok.len() - 1;
    Some(Pooled {
        trials: ok.len(),
        estimate: mean,
        sd,
        sd_within,
        z: mean / sd,
        q,
        df,
        p_heterogeneity: if df == 0 {
            1.0
        } else {
            chi2_upper(q, df as f64)
        },
        i2: if q > 0.0 {
            ((q - df as f64) / q).max(0.0)
        } else {
            0.0
        },
    })
}

/// The untouched trials' spread a reading carries, `√(σ² − s²)` (0 where not finite).
fn shared_spread(s: &Sample) -> f64 {
    let v = s.sd * s.sd - s.sd_within * s.sd_within;
    if v.is_finite() && v > 0.0 {
        v.sqrt()
    } else {
        0.0
    }
}

/// `P(χ²_k > x)`: the regularised upper incomplete gamma function `Q(k/2, x/2)`.
pub fn chi2_upper(x: f64, k: f64) -> f64 {
    if x.is_nan() || x <= 0.0 {
        return 1.0;
    }
    gamma_q(0.5 * k, 0.5 * x)
}

/// Regularised upper incomplete gamma `Q(a, x)` (series below `a + 1`, Lentz's continued
/// fraction above; Numerical Recipes §6.2), to about 1e-14.
fn gamma_q(a: f64, x: f64) -> f64 {
    let log_prefactor = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        let (mut sum, mut term, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..1000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (1.0 - sum * log_prefactor.exp()).clamp(0.0, 1.0)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (log_prefactor.exp() * h).clamp(0.0, 1.0)
    }
}

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7, nine terms; relative error below 1e-15).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}
