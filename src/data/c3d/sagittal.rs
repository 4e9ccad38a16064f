//! The plates' forces in the model's sagittal frame: the lab axes that are forward and up,
//! each plate's sagittal components, and each foot's forces and CoP from its plates.

use super::{C3dForces, PlateForces};
use crate::data::error::{DataError, LabAxisError};
use crate::data::{interp_linear, side_index, FootData};
use crate::model::Side;
use std::str::FromStr;

/// A signed lab axis of the C3D file (`+x`, `-z`, …).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LabAxis {
    /// 0, 1, 2 for x, y, z.
    pub index: usize,
    /// +1 or −1.
    pub sign: i8,
}

impl LabAxis {
    fn pick(self, v: [f64; 3]) -> f64 {
        f64::from(self.sign) * v[self.index]
    }
}

impl FromStr for LabAxis {
    type Err = LabAxisError;
    /// `+x`, `x`, `-x`, … `-z` (case-insensitive).
    fn from_str(s: &str) -> Result<Self, LabAxisError> {
        let t = s.trim().to_ascii_lowercase();
        let (sign, rest) = match t.strip_prefix('-') {
            Some(r) => (-1, r),
            None => (1, t.strip_prefix('+').unwrap_or(&t)),
        };
        let index = match rest {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => {
                return Err(LabAxisError {
                    text: s.to_string(),
                })
            }
        };
        Ok(LabAxis { index, sign })
    }
}

impl std::fmt::Display for LabAxis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = if self.sign < 0 { '-' } else { '+' };
        write!(f, "{s}{}", ["x", "y", "z"][self.index])
    }
}

/// Which lab axes of the C3D file are the model's forward (walking direction, sagittal
/// x) and up (sagittal y). The default is `forward = +x`, `up = +z`, the usual C3D lab
/// with z vertical and the walkway along x.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AxisMap {
    /// Lab axis of the walking direction.
    pub forward: LabAxis,
    /// Lab axis pointing up.
    pub up: LabAxis,
}

impl Default for AxisMap {
    fn default() -> Self {
        AxisMap {
            forward: LabAxis { index: 0, sign: 1 },
            up: LabAxis { index: 2, sign: 1 },
        }
    }
}

impl AxisMap {
    /// An axis map from two axis names, e.g. `AxisMap::new("-y", "+z")`.
    ///
    /// Errors: a name that is not a signed axis, or the same axis twice.
    pub fn new(forward: &str, up: &str) -> Result<AxisMap, DataError> {
        let mem = crate::data::error::memory_path();
        let f = forward
            .parse::<LabAxis>()
            .map_err(|e| DataError::invalid(&mem, "forward", e.to_string()))?;
        let u = up
            .parse::<LabAxis>()
            .map_err(|e| DataError::invalid(&mem, "up", e.to_string()))?;
        if f.index == u.index {
            return Err(DataError::invalid(
                &mem,
                "up",
                format!("forward ({f}) and up ({u}) are the same lab axis; they must be two different axes"),
            ));
        }
        Ok(AxisMap { forward: f, up: u })
    }
}

/// One plate's ground reaction in the model's sagittal frame, at the analog rate: the same
/// quantities as [`FootData`] (forces of the ground on the foot).
#[derive(Debug, Clone, PartialEq)]
pub struct SagittalPlate {
    /// Plate number (1-based).
    pub plate: usize,
    /// Sample times (s).
    pub time: Vec<f64>,
    /// Force component along the walking direction, + forward (N).
    pub fx: Vec<f64>,
    /// Vertical force, + up (N).
    pub fy: Vec<f64>,
    /// CoP along the walking direction (m); NaN where the plate is unloaded.
    pub cop_x: Vec<f64>,
    /// Mean height of the loaded CoP samples along `up` (m), the plate surface; `None` if
    /// the plate is never loaded.
    pub surface_height: Option<f64>,
}

impl PlateForces {
    /// The plate's sagittal components along `map` (the lab's forward and up axes).
    pub fn sagittal(&self, map: AxisMap) -> SagittalPlate {
        let heights: Vec<f64> = self
            .cop
            .iter()
            .map(|c| map.up.pick(*c))
            .filter(|h| h.is_finite())
            .collect();
        SagittalPlate {
            plate: self.plate,
            time: self.time.clone(),
            fx: self.force.iter().map(|f| map.forward.pick(*f)).collect(),
            fy: self.force.iter().map(|f| map.up.pick(*f)).collect(),
            cop_x: self.cop.iter().map(|c| map.forward.pick(*c)).collect(),
            surface_height: (!heights.is_empty())
                .then(|| heights.iter().sum::<f64>() / heights.len() as f64),
        }
    }
}

/// Per-foot [`FootData`] (`[right, left]`) at the instants `time` from the plates of a C3D
/// file, with `assign` saying which plate (1-based) a foot stepped on: e.g.
/// `[(Side::Right, 1), (Side::Left, 2)]`. A foot on several plates gets their summed
/// force and the force-weighted CoP $\sum_i F_{y,i} c_i / \sum_i F_{y,i}$ over its loaded
/// plates. Forces are resampled by linear interpolation (as [`crate::data::GaitData::from_storage`]
/// does), a plate's CoP too, except that between a loaded and an unloaded sample the loaded
/// one's CoP is taken; CoP is NaN where the foot's vertical force is below `forces.cop_threshold`. A foot
/// with no plate is NaN throughout (not measured).
///
/// Errors: a plate number not in the file, a plate assigned twice, `time` not finite and
/// increasing, or outside the analog samples' span.
pub fn feet_from_plates(
    forces: &C3dForces,
    assign: &[(Side, usize)],
    map: AxisMap,
    time: &[f64],
) -> Result<[FootData; 2], DataError> {
    let path = &forces.path;
    let n = time.len();
    if let Some(k) = (0..n).find(|&k| !time[k].is_finite() || (k > 0 && time[k] <= time[k - 1])) {
        return Err(DataError::invalid(
            path,
            "time",
            format!(
                "instant {k} ({} s) is not finite and larger than the previous",
                time[k]
            ),
        ));
    }
    let mut seen = Vec::new();
    let mut per_foot: [Vec<SagittalPlate>; 2] = Default::default();
    for &(side, plate) in assign {
        let Some(p) = forces.plates.iter().find(|p| p.plate == plate) else {
            return Err(DataError::invalid(
                path,
                "plate",
                format!(
                    "plate {plate} is not in the file; it has plates 1–{}",
                    forces.plates.len()
                ),
            ));
        };
        if seen.contains(&plate) {
            return Err(DataError::invalid(
                path,
                "plate",
                format!("plate {plate} is assigned twice; a plate belongs to one foot"),
            ));
        }
        seen.push(plate);
        per_foot[side_index(side)].push(p.sagittal(map));
    }
    let nan = || vec![f64::NAN; n];
    let mut feet: [FootData; 2] = std::array::from_fn(|_| FootData {
        fx: nan(),
        fy: nan(),
        cop_x: nan(),
    });
    for (s, plates) in per_foot.iter().enumerate() {
        if plates.is_empty() {
            continue;
        }
        let (mut fx, mut fy, mut moment) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut loaded_fy = vec![0.0; n];
        for p in plates {
            let (a, b) = (p.time[0], p.time[p.time.len() - 1]);
            let tol = 1e-9 * (1.0 + b.abs());
            if n > 0 && (time[0] < a - tol || time[n - 1] > b + tol) {
                return Err(DataError::invalid(
                    path,
                    "time",
                    format!(
                        "plate {} covers {a}–{b} s but the instants run {}–{} s",
                        p.plate,
                        time[0],
                        time[n - 1]
                    ),
                ));
            }
            let rx = interp_linear(time, &p.time, &p.fx);
            let ry = interp_linear(time, &p.time, &p.fy);
            // The CoP between a loaded and an unloaded sample is the loaded one's.
            let rc = interp_defined(time, &p.time, &p.cop_x);
            for k in 0..n {
                fx[k] += rx[k];
                fy[k] += ry[k];
                if rc[k].is_finite() && ry[k] > 0.0 {
                    moment[k] += ry[k] * rc[k];
                    loaded_fy[k] += ry[k];
                }
            }
        }
        let cop = (0..n)
            .map(|k| {
                if fy[k] >= forces.cop_threshold && loaded_fy[k] > 0.0 {
                    moment[k] / loaded_fy[k]
                } else {
                    f64::NAN
                }
            })
            .collect();
        feet[s] = FootData { fx, fy, cop_x: cop };
    }
    Ok(feet)
}

/// [`interp_linear`] of a channel that is NaN where undefined (the CoP of an unloaded
/// plate): between a defined and an undefined sample the defined one is taken, so that an
/// instant just inside a loaded stretch keeps its CoP; NaN between two undefined ones.
fn interp_defined(xn: &[f64], x: &[f64], y: &[f64]) -> Vec<f64> {
    let lin = interp_linear(xn, x, y);
    xn.iter()
        .zip(lin)
        .map(|(&t, v)| {
            if !v.is_nan() || t <= x[0] || t >= x[x.len() - 1] {
                return v;
            }
            let i = x.partition_point(|&u| u <= t) - 1;
            if y[i].is_nan() {
                y[i + 1]
            } else {
                y[i]
            }
        })
        .collect()
}
