//! The residual thresholds gait labs use to accept a dynamically consistent trial (Hicks,
//! Uchida, Seth, Rajagopal and Delp 2015, "Is my model good enough? Best practices for
//! verification and validation of musculoskeletal models and simulations of movement"):
//! the peak residual force below 5 % of the peak ground force, and the RMS residual
//! moment below 1 % of the centre of mass's height times the peak ground force.

use super::balance::{self, NPARAM};
use super::fit::Problem;

/// The thresholds, read from one residual.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Thresholds {
    /// Peak residual force magnitude (N).
    pub peak_force: f64,
    /// Its limit: 5 % of the peak ground force magnitude (N).
    pub force_limit: f64,
    /// RMS residual moment about the centre of mass (N·m).
    pub rms_moment: f64,
    /// Its limit: 1 % of the centre of mass's mean height times the peak ground force (N·m).
    pub moment_limit: f64,
    /// RMS residual force, horizontal and vertical (N).
    pub rms_force: [f64; 2],
}

impl Thresholds {
    /// The thresholds of residual `r` at the instants of `p`.
    pub fn of(r: &[[f64; 3]], p: &Problem) -> Self {
        let zero = [0.0; NPARAM];
        let mut peak_ground: f64 = 0.0;
        let mut height = 0.0;
        for at in p.instants {
            if let Some(m) = balance::measured::<f64>(p.signals, at, &zero) {
                peak_ground = peak_ground.max(m[0].hypot(m[1]));
            }
            height += at.com[1];
        }
        height /= p.instants.len().max(1) as f64;
        let finite: Vec<&[f64; 3]> = r.iter().filter(|r| r[0].is_finite()).collect();
        let n = finite.len().max(1) as f64;
        let rms = |i: usize| (finite.iter().map(|r| r[i] * r[i]).sum::<f64>() / n).sqrt();
        Self {
            peak_force: finite.iter().map(|r| r[0].hypot(r[1])).fold(0.0, f64::max),
            force_limit: 0.05 * peak_ground,
            rms_moment: rms(2),
            moment_limit: 0.01 * height * peak_ground,
            rms_force: [rms(0), rms(1)],
        }
    }

    /// Whether the peak residual force is within its limit.
    pub fn force_passes(&self) -> bool {
        self.peak_force <= self.force_limit
    }

    /// Whether the RMS residual moment is within its limit.
    pub fn moment_passes(&self) -> bool {
        self.rms_moment <= self.moment_limit
    }
}
