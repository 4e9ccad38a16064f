//! The held-out validation of a candidate: fitted on the run's half cycle, applied with its
//! values fixed to another half cycle, and that half cycle's own reading of it.

use serde::{Deserialize, Serialize};

/// The verdict of a significant candidate that the held-out half cycle is too weakly
/// informed about to confirm or refute ([`HeldOutReading::powered`]).
pub const NOT_VALIDATABLE: &str = "not validatable on the held-out half cycle";

/// A candidate fitted on the run's half cycle, applied with its parameters fixed to
/// another half cycle of the trial and the other variables re-optimised there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOut {
    /// Which half cycle (`--stride`) was held out.
    pub stride: usize,
    /// Whether it is the other leg's half cycle, the legs swapped (`--mirror`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub mirrored: bool,
    /// Another recording of the subject whose first half cycle was held out
    /// (`--held-out-data`; `None`: a half cycle of the run's own trial).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trial: Option<std::path::PathBuf>,
    /// Its time span (s).
    pub window: (f64, f64),
    /// The parameter values fitted on the run's half cycle.
    pub values: Vec<f64>,
    /// The held-out cost of the plain model (its own tracking solution).
    pub objective: f64,
    /// Fall of the held-out cost with the candidate at `values` (cost units; negative:
    /// it got worse), after a truncated re-fit of the other variables and less that of
    /// the plain model.
    pub change: f64,
    /// `change` as a fraction of `objective`.
    pub change_fraction: f64,
    /// Upper edge of the noise band of `change` ([`stats::held_out_band`](super::stats::held_out_band)): two standard
    /// deviations above the mean change a candidate fitted on noise makes (which is
    /// negative).
    pub band: f64,
    /// Whether `change` exceeds `band`.
    pub beyond_noise: bool,
    /// The held-out half cycle's own reading of the candidate along its fitted values,
    /// from its changes at `θ` and `−θ`. `None` where `−θ` could not be applied.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reading: Option<HeldOutReading>,
}

/// What a held-out half cycle itself says about a candidate fitted elsewhere at `θ`.
/// Its cost along `θ` is a parabola `c(ρθ)`, `ρ` the fraction of `θ` it reads:
/// `Δ(θ) = q (ρ − ½)` and `Δ(−θ) = −q (ρ + ½)` (falls of the cost), so `q = −(Δ(θ) +
/// Δ(−θ))` is its curvature `θᵀH_hθ` and `ρ = (Δ(θ) − Δ(−θ)) / 2q`, with sd
/// `√(2 φ s² / q)` (the noise model of [`stats::held_out_band`](super::stats::held_out_band)). The candidate clears
/// the band at that curvature exactly when `ρ > 2 sd`: the held-out half cycle reads it,
/// in the same direction, beyond two sd. It can do so for a true effect (`ρ = 1`) only
/// when `sd < ½`; otherwise that half cycle is too weakly informed about this candidate
/// to confirm it or to refute it (`powered` false): a plate's gain fitted where that
/// foot is in stance, held out where it only pushes off, is one such case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutReading {
    /// The held-out cost's curvature along the fitted values, `q = θᵀH_hθ` (cost units).
    pub curvature: f64,
    /// The fraction `ρ` of the fitted values the held-out half cycle reads (1: the same
    /// values, 0: none of it, negative: the opposite way).
    pub fraction: f64,
    /// Its standard deviation, inflated by the candidate's `φ`.
    pub sd: f64,
    /// Whether a true effect of the fitted size would clear the band on average
    /// (`sd < ½`).
    pub powered: bool,
}

impl HeldOut {
    /// This validation with the held-out half cycle's own reading attached.
    pub fn with_reading(self, reading: HeldOutReading) -> Self {
        Self {
            reading: Some(reading),
            ..self
        }
    }

    /// Whether the held-out half cycle read the candidate too loosely to confirm or
    /// refute it ([`HeldOutReading::powered`] false; `false` where it was not read).
    pub fn too_weakly_informed(&self) -> bool {
        self.reading.as_ref().is_some_and(|r| !r.powered)
    }
}

impl HeldOutReading {
    /// The reading at curvature `curvature`: the fraction `fraction` of the fitted values,
    /// sd `sd`; powered when `sd < ½`.
    pub fn new(curvature: f64, fraction: f64, sd: f64) -> Self {
        Self {
            curvature,
            fraction,
            sd,
            powered: sd < 0.5,
        }
    }

    /// As the tables and progress lines print it: `reads 0.62 ± 0.41 of it`.
    pub fn text(&self) -> String {
        format!("reads {:.2} ± {:.2} of it", self.fraction, self.sd)
    }

    /// From the held-out cost's falls at `θ` (`up`) and at `−θ` (`down`), its residual
    /// mean square `s2` and the candidate's variance inflation `phi`; `None` when the
    /// cost does not curve along `θ` there (`q ≤ 0`: that half cycle does not inform
    /// the candidate at all).
    pub fn from_changes(up: f64, down: f64, s2: f64, phi: f64) -> Option<Self> {
        let q = -(up + down);
        (q > 0.0 && q.is_finite()).then(|| {
            Self::new(
                q,
                (up - down) / (2.0 * q),
                (2.0 * phi.max(1.0) * s2 / q).sqrt(),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::stats;
    use super::*;

    /// A held-out cost that is a parabola along the fitted values, `c(x) = a (x − x₀)²`
    /// in units of `θ = 0.06`: its falls at `θ` and `−θ` give back its curvature `2aθ²`
    /// and its own reading `x₀/θ` exactly; the candidate clears the band at that
    /// curvature ([`stats::held_out_band`]) exactly when that reading lies beyond 2 sd,
    /// and a true effect (`x₀ = θ`) clears it exactly when the reading's sd is below ½.
    #[test]
    fn a_held_out_parabola_reads_the_candidate_and_says_when_it_cannot_tell() {
        let (theta, s2, phi) = (0.06, 5e-4, 3.5);
        for a in [0.5, 1.6, 5.0, 20.0, 200.0] {
            for x0 in [-0.06, -0.01, 0.0, 0.02, 0.05, 0.06, 0.09, 0.2] {
                let c = |x: f64| a * (x - x0) * (x - x0);
                let (up, down) = (c(0.0) - c(theta), c(0.0) - c(-theta));
                let r = HeldOutReading::from_changes(up, down, s2, phi).unwrap();
                let q = 2.0 * a * theta * theta;
                assert!((r.curvature - q).abs() < 1e-12 * q, "a {a}");
                assert!((r.fraction - x0 / theta).abs() < 1e-9, "a {a} x0 {x0}");
                let sd = (2.0 * phi * s2 / q).sqrt();
                assert!((r.sd - sd).abs() < 1e-12 * sd);
                let band = stats::held_out_band(q, s2, phi);
                assert_eq!(up > band, r.fraction > 2.0 * r.sd, "a {a} x0 {x0}");
                let truth = q / 2.0; // the fall a true effect (x₀ = θ) makes
                assert_eq!(truth > band, r.powered, "a {a}");
            }
        }
        // a cost that does not curve along θ reads nothing
        assert!(HeldOutReading::from_changes(0.01, -0.01, s2, phi).is_none());
        assert!(HeldOutReading::from_changes(0.05, -0.02, s2, phi).is_none());
    }
}
