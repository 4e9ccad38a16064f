//! Readings of one candidate in several trials, pooled.
//!
//! Each trial's reading is $x_i$ with the window's own (Newey–West) standard deviation
//! $s_i$ and the check's total one $\sigma_i = \sqrt{s_i^2 + n^2}$, where $n$ is the
//! spread the body model's own error gives untouched trials. The pooled estimate is the
//! inverse-variance mean $\bar x = \sum w_i x_i / \sum w_i$ with $w_i = 1/s_i^2$. The body
//! model's error is the same in every trial of a subject, so it does not average out: it
//! is added once, $\sigma_{\bar x}^2 = 1/\sum w_i + n^2$ (with $n$ the largest of the
//! trials'). It is judged by its distance from what untouched trials read, $c$ (the
//! check's band centre): $z = (\bar x - c)/\sigma_{\bar x}$. Heterogeneity is Cochran's
//! $Q = \sum w_i (x_i - \bar x)^2$ on $k - 1$ degrees of freedom, its upper-tail
//! probability under $\chi^2_{k-1}$, and $I^2 = \max(0, (Q - (k-1))/Q)$.

use crate::problems::distributions::chi2_upper;
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
    /// What untouched trials read as the candidate: the centre of the check's band.
    pub centre: f64,
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
    /// What untouched trials read as the candidate (the check's band centre).
    pub centre: f64,
    /// `(estimate − centre) / sd`.
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

/// Pool `samples` (each with finite estimate and centre and positive finite
/// `sd_within`; others are left out). `None` when fewer than one sample is usable.
pub fn pool(samples: &[Sample]) -> Option<Pooled> {
    let ok: Vec<&Sample> = samples
        .iter()
        .filter(|s| {
            s.estimate.is_finite()
                && s.centre.is_finite()
                && s.sd_within.is_finite()
                && s.sd_within > 0.0
        })
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
    let centre = ok.iter().map(|s| s.centre).sum::<f64>() / ok.len() as f64;
    let df = ok.len() - 1;
    Some(Pooled {
        trials: ok.len(),
        estimate: mean,
        sd,
        sd_within,
        centre,
        z: (mean - centre) / sd,
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
