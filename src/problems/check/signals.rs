//! The measured trial as smooth functions of time, for the whole-body balance: the nine
//! coordinates and each plate's loads low-pass filtered at one cutoff (zero-phase
//! Butterworth, [`low_pass`]) and interpolated by $C^2$ cubic splines, so that velocities
//! and accelerations are analytic and a plate's loads can be read at any shifted instant.
//!
//! Kinematics and forces are filtered at the same cutoff: filtering them differently
//! puts a spurious residual at every heel strike (Kristianslund, Krosshaug and van den
//! Bogert 2012, "Effect of low pass filtering on joint moments from inverse dynamics").
//!
//! A plate's moment about the world origin, $M_s = x_{cop} F_y - y_{cop} F_x$, is filtered
//! rather than its CoP, in the plate's own frame: on a treadmill the belt's travel
//! $v t$ that moves the trial overground is taken out before filtering and put back at
//! the kinematics' instant, so that a plate's clock shifts what the plate measured and
//! not the belt's travel. The moment is smooth where the CoP jumps or is undefined (below
//! the CoP threshold the nearest defined CoP of the stretch is held; the moment there is
//! under 20 N times a lever arm).

use super::CheckError;
use crate::data::filter::low_pass;
use crate::data::{stretch_indices, CubicSpline, FootData, GaitData};

/// One foot's plate loads over one measured stretch: force (N) and moment about the
/// world origin (N·m), filtered and splined.
#[derive(Debug, Clone)]
pub struct LoadStretch {
    /// First and last instant (s).
    pub span: (f64, f64),
    fx: CubicSpline,
    fy: CubicSpline,
    mz: CubicSpline,
}

impl LoadStretch {
    /// `[fx, fy, mz]` at `t` (generic, so that a clock offset carries its derivative).
    pub fn eval<S: crate::model::Scalar>(&self, t: S) -> [S; 3] {
        [
            self.fx.eval_generic(t),
            self.fy.eval_generic(t),
            self.mz.eval_generic(t),
        ]
    }
}

/// The trial's smoothed coordinates and plate loads.
#[derive(Debug, Clone)]
pub struct Signals {
    q: Vec<CubicSpline>,
    /// The trunk's angle on the pelvis (`lumbar_extension`, rad) and its mean over the
    /// trial, where the trial has it at every kinematic instant.
    lumbar: Option<(CubicSpline, f64)>,
    /// `[right, left]` measured stretches of each foot's loads.
    pub loads: [Vec<LoadStretch>; 2],
    /// The force record's instants (s) at which the balance can be read: inside the
    /// kinematics, and with both feet's loads known from `margin` before to `margin` after.
    pub instants: Vec<f64>,
    /// Sample rate of the force record (Hz).
    pub force_rate: f64,
    /// Sample rate of the kinematics (Hz).
    pub kinematic_rate: f64,
    /// Belt speed (m/s) the trial was moved overground with; 0 overground.
    belt_speed: f64,
}

/// Median sample rate (Hz) of increasing instants `t`.
pub fn median_rate(t: &[f64]) -> f64 {
    crate::data::median_step(t).map_or(f64::NAN, |h| 1.0 / h)
}

impl Signals {
    /// Filter and spline `data` at `cutoff_hz`; keep the force instants whose loads are
    /// known within `margin` (s) on either side and that lie `margin` inside the
    /// kinematics (the filter's end effects and any clock shift up to `margin` stay
    /// outside).
    pub fn new(data: &GaitData, cutoff_hz: f64, margin: f64) -> Result<Self, CheckError> {
        let kinematic_rate = median_rate(&data.time);
        let nyquist = 0.5 * kinematic_rate;
        if !(cutoff_hz > 0.0 && cutoff_hz < 0.8 * nyquist) {
            return Err(CheckError::Cutoff {
                cutoff_hz,
                limit_hz: 0.8 * nyquist,
            });
        }
        let mut q = Vec::with_capacity(9);
        for (i, c) in data.q.iter().enumerate() {
            if c.iter().any(|v| !v.is_finite()) {
                return Err(CheckError::Kinematics {
                    coordinate: crate::data::Q_NAMES[i],
                });
            }
            q.push(CubicSpline::new(
                &data.time,
                &low_pass(c, kinematic_rate, cutoff_hz),
            )?);
        }
        let lumbar = match data.extra.get("lumbar_extension") {
            Some(l) if l.len() == data.time.len() && l.iter().all(|v| v.is_finite()) => {
                let mean = l.iter().sum::<f64>() / l.len() as f64;
                Some((
                    CubicSpline::new(&data.time, &low_pass(l, kinematic_rate, cutoff_hz))?,
                    mean,
                ))
            }
            _ => None,
        };
        let (ft, feet) = data.force_record();
        let force_rate = median_rate(ft);
        let belt_speed = data.belt_speed.unwrap_or(0.0);
        let plate = Plate {
            height: data.force_plate_height.unwrap_or(0.0),
            belt_speed,
            rate: force_rate,
        };
        let mut loads: [Vec<LoadStretch>; 2] = [vec![], vec![]];
        for s in 0..2 {
            loads[s] = foot_stretches(ft, &feet[s], &plate, cutoff_hz)?;
        }
        let (k0, k1) = (
            data.time[0] + margin,
            data.time[data.time.len() - 1] - margin,
        );
        let known = |s: usize, t: f64| {
            loads[s]
                .iter()
                .any(|l| l.span.0 <= t - margin && l.span.1 >= t + margin)
        };
        let instants = ft
            .iter()
            .copied()
            .filter(|&t| t >= k0 && t <= k1 && known(0, t) && known(1, t))
            .collect();
        Ok(Self {
            q,
            lumbar,
            loads,
            instants,
            force_rate,
            kinematic_rate,
            belt_speed,
        })
    }

    /// Coordinates, velocities and accelerations at `t` (m, rad; /s; /s²).
    pub fn motion(&self, t: f64) -> ([f64; 9], [f64; 9], [f64; 9]) {
        let mut q = [0.0; 9];
        let mut qd = [0.0; 9];
        let mut qdd = [0.0; 9];
        for (i, s) in self.q.iter().enumerate() {
            q[i] = s.eval(t);
            qd[i] = s.derivative(t);
            qdd[i] = s.second_derivative(t);
        }
        (q, qd, qdd)
    }

    /// The trunk's angle on the pelvis at `t` less `frozen` (the trial's mean when
    /// `None`), and its first two derivatives (rad, /s, /s²); `None` where the trial has
    /// no `lumbar_extension` at every kinematic instant.
    pub fn lumbar(&self, t: f64, frozen: Option<f64>) -> Option<[f64; 3]> {
        let (s, mean) = self.lumbar.as_ref()?;
        Some([
            s.eval(t) - frozen.unwrap_or(*mean),
            s.derivative(t),
            s.second_derivative(t),
        ])
    }

    /// Whether the trial has the trunk's angle on the pelvis at every kinematic instant.
    pub fn has_lumbar(&self) -> bool {
        self.lumbar.is_some()
    }

    /// The load stretch of foot `s` that holds `t` (s).
    pub fn stretch(&self, s: usize, t: f64) -> Option<&LoadStretch> {
        self.loads[s]
            .iter()
            .find(|l| l.span.0 <= t && l.span.1 >= t)
    }

    /// Foot `s`'s loads `[fx, fy (N), mz about the world origin (N·m)]` at the instant
    /// `t` (s) of a plate whose clock reads `shift` (s) late: what the plate measured
    /// at `t + shift`, with the belt's travel to `t` on a treadmill. `None` where that
    /// instant has no measured loads.
    pub fn load<S: crate::model::Scalar>(&self, s: usize, t: f64, shift: S) -> Option<[S; 3]> {
        let at = S::c(t) + shift;
        let [fx, fy, mz] = self.stretch(s, at.value())?.eval(at);
        Some([fx, fy, mz + fy * (self.belt_speed * t)])
    }
}

/// What a plate's moment is read with: its surface height (m), the belt speed (m/s, 0
/// overground) and its sample rate (Hz).
struct Plate {
    height: f64,
    belt_speed: f64,
    rate: f64,
}

/// Each measured stretch of one foot's record, filtered and splined, its moment in the
/// plate's frame (the belt's travel taken out).
fn foot_stretches(
    t: &[f64],
    foot: &FootData,
    plate: &Plate,
    cutoff_hz: f64,
) -> Result<Vec<LoadStretch>, CheckError> {
    let mut out = Vec::new();
    for (a, b) in stretch_indices(t, &foot.fy) {
        if b < a + 3 {
            continue;
        }
        let tt = &t[a..=b];
        let fx: Vec<f64> = foot.fx[a..=b]
            .iter()
            .map(|v| if v.is_finite() { *v } else { 0.0 })
            .collect();
        let fy = &foot.fy[a..=b];
        let cop = held_cop(&foot.cop_x[a..=b]);
        let mz: Vec<f64> = (0..tt.len())
            .map(|k| {
                let x = cop
                    .as_ref()
                    .map_or(0.0, |c| c[k] - plate.belt_speed * tt[k]);
                x * fy[k] - plate.height * fx[k]
            })
            .collect();
        let f = |v: &[f64]| CubicSpline::new(tt, &low_pass(v, plate.rate, cutoff_hz));
        out.push(LoadStretch {
            span: (tt[0], tt[tt.len() - 1]),
            fx: f(&fx)?,
            fy: f(fy)?,
            mz: f(&mz)?,
        });
    }
    Ok(out)
}

/// The CoP with each undefined sample replaced by the nearest defined one (earlier wins a
/// tie); `None` when no sample is defined.
fn held_cop(cop: &[f64]) -> Option<Vec<f64>> {
    let defined: Vec<usize> = (0..cop.len()).filter(|&k| cop[k].is_finite()).collect();
    if defined.is_empty() {
        return None;
    }
    let mut j = 0;
    Some(
        (0..cop.len())
            .map(|k| {
                while j + 1 < defined.len() && defined[j + 1] <= k {
                    j += 1;
                }
                let near = if defined[j] >= k || j + 1 == defined.len() {
                    defined[j]
                } else if k - defined[j] <= defined[j + 1] - k {
                    defined[j]
                } else {
                    defined[j + 1]
                };
                cop[near]
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::held_cop;

    #[test]
    fn an_undefined_cop_takes_the_nearest_defined_one() {
        let n = f64::NAN;
        let c = held_cop(&[n, 1.0, n, n, n, 5.0, n]).unwrap();
        assert_eq!(c, vec![1.0, 1.0, 1.0, 1.0, 5.0, 5.0, 5.0]);
        assert!(held_cop(&[n, n]).is_none());
    }
}
