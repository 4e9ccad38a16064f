//! Ground-force transients: short excursions of the model's force above the measured
//! force, found on a fine re-integration grid (Millard & Mombaur 2019, §4: the ellipse foot's ≈13 ms,
//! 6582.7 N spike in prediction, which falls between shooting nodes).
//!
//! A transient is a maximal run of samples where the excess `model − measured` exceeds a
//! threshold; its start and end are the threshold crossings, linearly interpolated
//! between samples, and its peak the largest excess in the run.

use super::evaluation::{Comparison, Reintegration};
use crate::model::ConstraintSet;
use serde::Serialize;

/// One run of a signal above a threshold.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Excursion {
    /// Threshold crossing upwards (s; the first sample if the signal starts above).
    pub start: f64,
    /// Threshold crossing downwards (s; the last sample if the signal ends above).
    pub end: f64,
    /// Time of the peak sample (s).
    pub t_peak: f64,
    /// Peak value.
    pub peak: f64,
    /// Index of the peak sample.
    pub index: usize,
}

impl Excursion {
    /// `end − start` (s).
    pub fn duration(&self) -> f64 {
        self.end - self.start
    }
}

/// Runs of `signal` (sampled at increasing `times`) strictly above `threshold`. NaN
/// samples count as below.
pub fn excursions(times: &[f64], signal: &[f64], threshold: f64) -> Vec<Excursion> {
    let n = times.len().min(signal.len());
    let above = |k: usize| signal[k] > threshold;
    let crossing = |k: usize| {
        // between samples k and k + 1, one above and one not
        let (f0, f1) = (signal[k], signal[k + 1]);
        if f0.is_finite() && f1.is_finite() && f1 != f0 {
            times[k] + ((threshold - f0) / (f1 - f0)).clamp(0.0, 1.0) * (times[k + 1] - times[k])
        } else {
            times[if above(k) { k } else { k + 1 }]
        }
    };
    let mut out = Vec::new();
    let mut k = 0;
    while k < n {
        if !above(k) {
            k += 1;
            continue;
        }
        let start = if k == 0 { times[0] } else { crossing(k - 1) };
        let mut best = k;
        let mut e = k;
        while e + 1 < n && above(e + 1) {
            e += 1;
            if signal[e] > signal[best] {
                best = e;
            }
        }
        let end = if e + 1 < n { crossing(e) } else { times[e] };
        out.push(Excursion {
            start,
            end,
            t_peak: times[best],
            peak: signal[best],
            index: best,
        });
        k = e + 1;
    }
    out
}

/// A ground-force transient of one foot.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub struct ForceTransient {
    /// `right` or `left`.
    pub foot: String,
    /// `normal` or `tangential`.
    pub component: String,
    /// Phase the peak falls in.
    pub phase: String,
    /// Time of the peak (s).
    pub t_peak: f64,
    /// Model force at the peak (N).
    pub peak_n: f64,
    /// Measured force at that instant (N).
    pub measured_n: f64,
    /// Excess over the measurement at the peak (N).
    pub excess_n: f64,
    /// Time above the threshold (s).
    pub duration_s: f64,
    /// Start and end of the time above the threshold (s).
    pub window_s: (f64, f64),
    /// Angular velocity of that foot's ankle at the peak (rad/s).
    pub ankle_velocity_rad_s: f64,
    /// Largest |Baumgarte force| within the window (N): small means not numerical.
    pub max_baumgarte_force_n: f64,
    /// Whether no shooting node falls inside the window (only the fine grid sees it).
    pub between_nodes: bool,
}

/// Transients of the normal and tangential ground forces of both feet on the fine grid
/// `fine` (held against the measurement in `cmp`, built from the same samples): runs of
/// excess over `threshold_n`, strongest first. `node_times` are the shooting nodes.
pub fn force_transients(
    fine: &Reintegration,
    cmp: &Comparison,
    sets: &[ConstraintSet],
    node_times: &[f64],
    nq: usize,
    threshold_n: f64,
) -> Vec<ForceTransient> {
    let samples = &fine.result.samples;
    let mut out = Vec::new();
    for (s, foot) in ["right", "left"].into_iter().enumerate() {
        for (c, component) in [(1usize, "normal"), (0, "tangential")] {
            let excess: Vec<f64> = (0..cmp.len())
                .map(|k| {
                    let m = cmp.model_feet[s][c][k];
                    let d = cmp.data_feet[s][c][k];
                    // tangential: excess of magnitude in the direction of the model force
                    if c == 0 {
                        (m - d) * m.signum()
                    } else {
                        m - d
                    }
                })
                .collect();
            for e in excursions(&cmp.times, &excess, threshold_n) {
                let k = e.index;
                let in_window = |t: f64| t >= e.start && t <= e.end;
                let baumgarte = samples
                    .iter()
                    .filter(|x| in_window(x.t))
                    .flat_map(|x| x.contact.baumgarte_force.iter().map(|v| v.abs()))
                    .fold(0.0, f64::max);
                out.push(ForceTransient {
                    foot: foot.to_string(),
                    component: component.to_string(),
                    phase: sets[samples[k].phase].name.clone(),
                    t_peak: e.t_peak,
                    peak_n: cmp.model_feet[s][c][k],
                    measured_n: cmp.data_feet[s][c][k],
                    excess_n: e.peak,
                    duration_s: e.duration(),
                    window_s: (e.start, e.end),
                    ankle_velocity_rad_s: samples[k].x[nq + 5 + 3 * s],
                    max_baumgarte_force_n: baumgarte,
                    between_nodes: !node_times.iter().any(|&t| in_window(t)),
                });
            }
        }
    }
    out.sort_by(|a, b| b.excess_n.total_cmp(&a.excess_n));
    out
}
