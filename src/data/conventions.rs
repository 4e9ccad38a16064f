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

/// Slowest kinematic rate that counts as motion capture (Hz); times in milliseconds read
/// as a rate below 1 Hz.
pub const MIN_RATE_HZ: f64 = 10.0;
/// Fastest (Hz); times in minutes read as tens of kilohertz.
pub const MAX_RATE_HZ: f64 = 5000.0;
/// Highest pelvis above the ground that a walking adult reaches (m); millimetres read as
/// hundreds of metres.
pub const MAX_PELVIS_HEIGHT_M: f64 = 2.0;
/// Farthest a loaded foot's CoP lies from the pelvis horizontally (m): a step is under
/// 1 m, so 1.5 m is beyond any foot's reach; a CoP in millimetres reads as hundreds.
pub const MAX_COP_REACH_M: f64 = 1.5;

/// Smallest span (rad, 5.7°) of the widest-moving leg joint of a walk longer than
/// [`MIN_SPAN_DURATION`]: a knee spans about 60°, so joints that all stay within this
/// after a conversion from degrees were radians.
pub const MIN_LEG_SPAN_RAD: f64 = 0.1;

/// Shortest trial (s) on which [`MIN_LEG_SPAN_RAD`] is judged (about half a gait cycle).
pub const MIN_SPAN_DURATION: f64 = 0.5;

/// Normal force a loaded foot exceeds (N): a vertical force that never rises above it
/// while falling far below zero has its sign flipped.
const LOADED_N: f64 = 20.0;

impl GaitData {
    /// Check the trial's units and conventions (see the module doc). `overground`: the
    /// user asserts the trial is overground as it is (no belt speed needed).
    pub fn check_conventions(&self, overground: bool) -> Result<(), DataError> {
        self.check_scales()?;
        self.check_angles()?;
        self.check_knees_move()?;
        self.check_forces_measured()?;
        self.check_force_signs()?;
        if !overground {
            self.check_treadmill()?;
        }
        Ok(())
    }

    /// The leg joint that moves most, as (index into [`Q_NAMES`], span in rad, trial
    /// duration in s), when its span is below [`MIN_LEG_SPAN_RAD`] over at least
    /// [`MIN_SPAN_DURATION`]: the trial's angles, read as degrees, were radians.
    pub fn still_legs(&self) -> Option<(usize, f64, f64)> {
        let duration = self.long_enough_to_judge_spans()?;
        let span = |i: usize| Self::range(&self.q[i]).map_or(0.0, |(lo, hi)| hi - lo);
        let (widest, s) = (3..9)
            .map(|i| (i, span(i)))
            .fold((3, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
        (s < MIN_LEG_SPAN_RAD).then_some((widest, s, duration))
    }

    /// The trial's duration (s) when it lasts at least [`MIN_SPAN_DURATION`], long enough
    /// for a walking leg's joints to span their range.
    fn long_enough_to_judge_spans(&self) -> Option<f64> {
        let duration = self.time.last()? - self.time.first()?;
        (duration >= MIN_SPAN_DURATION).then_some(duration)
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

    /// Times in seconds, positions and CoP in metres, judged against walking.
    fn check_scales(&self) -> Result<(), DataError> {
        if let Some(h) = super::median_step(&self.time) {
            let rate = 1.0 / h;
            if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate) {
                return Err(DataError::invalid(
                    &self.source,
                    "time",
                    format!("samples {h:.4} apart, a rate of {rate:.3} Hz; motion capture runs at {MIN_RATE_HZ}–{MAX_RATE_HZ} Hz. footfall reads time in seconds: times in milliseconds read as a rate below 1 Hz"),
                ));
            }
        }
        if let Some((_, top)) = Self::range(&self.q[1]) {
            if top > MAX_PELVIS_HEIGHT_M {
                return Err(DataError::invalid(
                    &self.source,
                    "pelvis_y",
                    format!("reaches {top:.3}; a walking pelvis is under {MAX_PELVIS_HEIGHT_M} m above the ground. footfall reads positions in metres: millimetres read a thousand times too high"),
                ));
            }
        }
        for (s, side) in ["r", "l"].iter().enumerate() {
            let foot = &self.feet[s];
            for k in 0..self.time.len() {
                let (c, fy, px) = (foot.cop_x[k], foot.fy[k], self.q[0][k]);
                if c.is_finite() && fy > self.cop_threshold && (c - px).abs() > MAX_COP_REACH_M {
                    return Err(DataError::invalid(
                        &self.source,
                        format!("cop_x_{side}"),
                        format!("at {:.3} s the CoP lies {:.3} from the pelvis (x {px:.3}), beyond the {MAX_COP_REACH_M} m any foot reaches. footfall reads the CoP in metres in the same frame as pelvis_x: millimetres read a thousand times too far", self.time[k], c - px),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Some foot has a vertical force somewhere (NaN is a foot off the plates, and a
    /// trial whose every force is NaN has nothing to find its stances in).
    fn check_forces_measured(&self) -> Result<(), DataError> {
        let (t, feet) = self.force_record();
        if feet.iter().any(|f| f.fy.iter().any(|v| v.is_finite())) {
            return Ok(());
        }
        let side = if self.sides[0] == SideSource::Missing {
            "l"
        } else {
            "r"
        };
        Err(DataError::invalid(
            &self.source,
            format!("grf_y_{side}"),
            format!(
                "no foot's vertical ground force holds a number in the {} samples (all NaN): footfall finds the stances in the forces; give the forces of at least one foot",
                t.len()
            ),
        ))
    }

    /// Each measured knee bends over a walk of at least [`MIN_SPAN_DURATION`]: one that
    /// spans less than [`MIN_LEG_SPAN_RAD`] is a frozen or copied channel.
    fn check_knees_move(&self) -> Result<(), DataError> {
        let Some(duration) = self.long_enough_to_judge_spans() else {
            return Ok(());
        };
        for (s, i) in [(0, 4), (1, 7)] {
            if self.sides[s] != SideSource::Measured {
                continue;
            }
            let Some((lo, hi)) = Self::range(&self.q[i]) else {
                continue;
            };
            if hi - lo < MIN_LEG_SPAN_RAD {
                return Err(DataError::invalid(
                    &self.source,
                    Q_NAMES[i],
                    format!(
                        "spans only {:.4} rad ({:.2}°) in {duration:.2} s: a walking knee bends about 1 rad (60°) each stride, at least {MIN_LEG_SPAN_RAD} rad; the column looks frozen or filled with a constant",
                        hi - lo,
                        (hi - lo).to_degrees()
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
