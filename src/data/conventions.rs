//! Units and conventions a trial must follow, checked before anything is fitted to it:
//! angles in radians, vertical ground forces positive (the ground pushes up), and a
//! treadmill trial's belt speed given. Each check catches a mistake that otherwise runs
//! to a nonsense result with exit 0 (a foot fitted to degrees, a threshold of −0 N, a
//! treadmill walk tracked as if the subject stood still); the message names the file,
//! the column and what would be valid.

use super::{DataError, GaitData, SideSource, Q_NAMES};

/// Largest span of a walking angle in radians within one trial: π (180°). A knee in
/// radians spans about 1.2 (1.4 running), so a span beyond π is degrees.
pub const MAX_ANGLE_SPAN_RAD: f64 = std::f64::consts::PI;

/// Slowest average forward speed of the pelvis that counts as walking overground (m/s):
/// slow walking is about 0.5 m/s, a treadmill trial's pelvis drifts by centimetres.
pub const MIN_OVERGROUND_SPEED: f64 = 0.15;

/// Shortest trial on which the pelvis speed is judged (s).
const MIN_JUDGED_DURATION: f64 = 0.5;

/// Normal force a loaded foot exceeds (N): a vertical force that never rises above it
/// while falling far below zero has its sign flipped.
const LOADED_N: f64 = 20.0;

impl GaitData {
    /// Check the trial's units and conventions (see the module doc). `overground`: the
    /// user asserts the trial is overground as it is (no belt speed needed).
    pub fn check_conventions(&self, overground: bool) -> Result<(), DataError> {
        self.check_angles()?;
        self.check_force_signs()?;
        if !overground {
            self.check_treadmill()?;
        }
        Ok(())
    }

    fn range(v: &[f64]) -> Option<(f64, f64)> {
        let (lo, hi) = v
            .iter()
            .filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        (lo <= hi).then_some((lo, hi))
    }

    fn check_angles(&self) -> Result<(), DataError> {
        for (i, name) in Q_NAMES.iter().enumerate().skip(2) {
            if i >= 3 && self.sides[(i - 3) / 3] == SideSource::Missing {
                continue;
            }
            let Some((lo, hi)) = Self::range(&self.q[i]) else {
                continue;
            };
            if hi - lo > MAX_ANGLE_SPAN_RAD || lo.abs().max(hi.abs()) > 2.0 * std::f64::consts::PI {
                return Err(DataError::invalid(
                    &self.source,
                    *name,
                    format!(
                        "spans {lo:.3} to {hi:.3}, more than π (180°) apart or beyond 2π, which an angle of walking in radians never is: this looks like degrees. footfall reads radians; convert the column, or declare \"units\": {{\"angles\": \"deg\"}} in the trial's meta file"
                    ),
                ));
            }
        }
        Ok(())
    }

    fn check_force_signs(&self) -> Result<(), DataError> {
        for (s, side) in ["r", "l"].iter().enumerate() {
            if self.sides[s] == SideSource::Missing {
                continue;
            }
            let Some((lo, hi)) = Self::range(&self.feet[s].fy) else {
                continue;
            };
            if hi < LOADED_N && lo < -5.0 * LOADED_N {
                return Err(DataError::invalid(
                    &self.source,
                    format!("grf_y_{side}"),
                    format!(
                        "is negative through stance (down to {lo:.1} N, never above {hi:.1} N): the ground pushes up on the foot, so footfall expects the vertical force positive; the sign looks flipped (negate the column)"
                    ),
                ));
            }
        }
        Ok(())
    }

    fn check_treadmill(&self) -> Result<(), DataError> {
        if self.overground || self.belt_speed.is_some() {
            return Ok(());
        }
        let (t0, t1) = (self.time[0], self.time[self.time.len() - 1]);
        let Some((lo, hi)) = Self::range(&self.q[0]) else {
            return Ok(());
        };
        let duration = t1 - t0;
        if duration >= MIN_JUDGED_DURATION && (hi - lo) / duration < MIN_OVERGROUND_SPEED {
            return Err(DataError::invalid(
                &self.source,
                "pelvis_x",
                format!(
                    "moves {:.3} m in {duration:.2} s ({:.3} m/s): a treadmill trial, and no belt speed is given. Give \"belt_speed_m_s\" in the trial's meta file (<name>_meta.json beside the CSV) or --belt-speed M/S, or pass --overground to take the trial as it is",
                    hi - lo,
                    (hi - lo) / duration
                ),
            ));
        }
        Ok(())
    }
}
