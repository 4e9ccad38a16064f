//! The two legs of a trial: swapping them (the other leg's half cycle, mirrored) and
//! filling a side the data lack from the other leg half a cycle later.

use super::{
    half_cycle_shift, interp_linear, side_of, DataError, FootData, GaitData, SideSource, Q_NAMES,
};
use crate::model::Side;

impl GaitData {
    /// The trial with its legs swapped: the right leg's angles, forces, CoP, events and
    /// source become the left's and the left's the right's (extra channels named `…_r` /
    /// `…_l` too). The planar model's legs are identical, so a half cycle from a right
    /// heel strike to the next left one is, swapped, a half cycle that a phase graph from
    /// a left heel strike to a right one tracks: the other leg's half cycle, mirrored.
    pub fn swap_sides(&mut self) {
        for k in 3..6 {
            self.q.swap(k, k + 3);
        }
        self.feet.swap(0, 1);
        if let Some(f) = &mut self.forces {
            f.feet.swap(0, 1);
        }
        self.sides.swap(0, 1);
        if let Some(e) = &mut self.events {
            e.swap_sides();
        }
        self.extra = std::mem::take(&mut self.extra)
            .into_iter()
            .map(|(k, v)| {
                let other = if let Some(stem) = k.strip_suffix("_r") {
                    format!("{stem}_l")
                } else if let Some(stem) = k.strip_suffix("_l") {
                    format!("{stem}_r")
                } else {
                    k
                };
                (other, v)
            })
            .collect();
    }

    /// Fill a [`SideSource::Missing`] side from the measured one by the half-cycle shift
    /// of a Fourier series (Ezati et al. 2020, §3.3, [`half_cycle_shift`], five harmonics):
    /// $x_{other}(t) = \hat x(t + T_c/2)$ for hip, knee, ankle, $F_x$ and $F_y$.
    ///
    /// The CoP moves with the body, so it is shifted relative to the pelvis:
    /// $c_{other}(t) = p_x(t) + [c - p_x](t + T_c/2)$, with $t + T_c/2$ taken modulo the
    /// period (from the first sample) and linear interpolation between the loaded samples
    /// of the first period;
    /// it is NaN where the generated $F_y$ is below the CoP threshold. The data should
    /// span whole cycles of duration `period` (e.g. one cycle cut with [`Self::window`]).
    /// Returns the side that was filled, or `None` if both sides were measured.
    ///
    /// Errors: data that fail [`Self::validate`]; no side measured; a period that is not
    /// positive; too few samples (< 11).
    pub fn mirror_missing_side(&mut self, period: f64) -> Result<Option<Side>, DataError> {
        self.validate()?;
        let missing: Vec<usize> = (0..2)
            .filter(|&s| self.sides[s] == SideSource::Missing)
            .collect();
        let dst = match missing.as_slice() {
            [] => return Ok(None),
            [s] => *s,
            _ => {
                return Err(DataError::invalid(
                    &self.source,
                    "sides",
                    "neither side was measured; nothing to mirror from",
                ))
            }
        };
        let src = 1 - dst;
        let named = |e: DataError, what: String| match e {
            DataError::Invalid { field, reason, .. } => {
                DataError::invalid(&self.source, format!("{what} ({field})"), reason)
            }
            other => other,
        };
        let t = &self.time;
        let mut q_new = Vec::new();
        for j in 0..3 {
            let v = half_cycle_shift(t, &self.q[3 + 3 * src + j], period)
                .map_err(|e| named(e, Q_NAMES[3 + 3 * src + j].to_string()))?;
            q_new.push(v);
        }
        let fs = &self.feet[src];
        let forces_known = fs.fx.iter().chain(&fs.fy).all(|v| v.is_finite());
        let foot = if forces_known {
            let fx = half_cycle_shift(t, &fs.fx, period).map_err(|e| named(e, "grf_x".into()))?;
            let fy = half_cycle_shift(t, &fs.fy, period).map_err(|e| named(e, "grf_y".into()))?;
            // CoP relative to the pelvis at the loaded samples of the first period,
            // repeated one period before and after so that the interpolation wraps.
            let first = t[0] + period;
            let mut rel: Vec<(f64, f64)> = Vec::new();
            for shift in [-period, 0.0, period] {
                rel.extend(
                    (0..t.len())
                        .filter(|&k| t[k] < first && fs.cop_x[k].is_finite())
                        .map(|k| (t[k] + shift, fs.cop_x[k] - self.q[0][k])),
                );
            }
            rel.sort_by(|a, b| a.0.total_cmp(&b.0));
            rel.dedup_by(|b, a| b.0 <= a.0 + 1e-12);
            let (tc, rc): (Vec<f64>, Vec<f64>) = rel.into_iter().unzip();
            let t0 = t[0];
            let cop = (0..t.len())
                .map(|k| {
                    if fy[k] < self.cop_threshold || tc.is_empty() {
                        return f64::NAN;
                    }
                    let ts = t0 + (t[k] + 0.5 * period - t0).rem_euclid(period);
                    self.q[0][k] + interp_linear(&[ts], &tc, &rc)[0]
                })
                .collect();
            FootData { fx, fy, cop_x: cop }
        } else {
            self.feet[dst].clone()
        };
        for (j, v) in q_new.into_iter().enumerate() {
            self.q[3 + 3 * dst + j] = v;
        }
        self.feet[dst] = foot;
        self.sides[dst] = SideSource::Mirrored;
        Ok(Some(side_of(dst)))
    }
}
