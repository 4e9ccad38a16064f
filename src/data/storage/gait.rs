//! Sagittal gait data from OpenSim storages: the coordinates, extra channels and ground
//! forces a [`StorageMap`] names, checked and converted to SI units.

use super::{ColumnMap, Storage, StorageMap};
use crate::data::error::DataError;
use crate::data::{FootData, ForceSamples, GaitData, SideSource, Q_NAMES};
use std::collections::BTreeMap;

/// A mapped column: present and unambiguous.
fn column<'a>(s: &'a Storage, name: &str, what: &str) -> Result<&'a [f64], DataError> {
    let j = s
        .column_index(name)
        .ok_or_else(|| DataError::MissingColumn {
            path: s.path.clone(),
            row: s.label_line,
            column: name.to_string(),
            reason: format!("needed for {what}"),
        })?;
    let count = |v: &[String]| v.iter().filter(|c| *c == name).count();
    if count(&s.columns) > 1 || count(&s.labels) > 1 {
        return Err(DataError::DuplicateColumn {
            path: s.path.clone(),
            row: s.label_line,
            column: name.to_string(),
        });
    }
    Ok(&s.data[j])
}

fn check_finite(s: &Storage, name: &str, v: &[f64]) -> Result<(), DataError> {
    check_values(s, name, v, false)
}

/// No infinity in `v`, and no NaN unless `gaps` (an extra channel, which the model does
/// not read, may have gaps).
fn check_values(s: &Storage, name: &str, v: &[f64], gaps: bool) -> Result<(), DataError> {
    if let Some(k) = v
        .iter()
        .position(|x| x.is_infinite() || (x.is_nan() && !gaps))
    {
        return Err(DataError::NotFinite {
            path: s.path.clone(),
            row: s.line_of(k),
            column: name.to_string(),
            reason: format!(
                "value is {} (NaN is allowed only in a CoP column while that foot is unloaded, and in an extra channel such as lumbar_extension)",
                v[k]
            ),
        });
    }
    Ok(())
}

fn check_not_infinite(s: &Storage, name: &str, v: &[f64]) -> Result<(), DataError> {
    if let Some(k) = v.iter().position(|x| x.is_infinite()) {
        return Err(DataError::NotFinite {
            path: s.path.clone(),
            row: s.line_of(k),
            column: name.to_string(),
            reason: format!(
                "value is {}; a force or CoP is finite, or NaN where not measured",
                v[k]
            ),
        });
    }
    Ok(())
}

impl GaitData {
    /// Sagittal gait data from OpenSim storages: `kinematics` (coordinates) and, optionally,
    /// `grf` (external loads), with the columns named in `map`.
    ///
    /// Rotational coordinates are converted from degrees to radians when the kinematics
    /// header says `inDegrees=yes` (or `Angles are in degrees`); a kinematics file that
    /// states no angle unit is refused. Forces and CoP are resampled onto the kinematic
    /// instants by linear interpolation (as `data/convert_opensim_subject01.py` does); CoP
    /// is NaN where the resampled normal force is below `map.cop_threshold`. The forces
    /// must cover the kinematic time span. The force-plate height is the mean CoP y of
    /// the loaded samples when `cop_y` columns are mapped. The result is in the lab frame
    /// (`belt_speed` and `body_mass` are `None`; see [`GaitData::to_overground`]).
    ///
    /// Errors: missing or repeated columns (row = the label line), NaN/∞ in kinematics or forces, NaN
    /// CoP while loaded (row, column), unstated angle unit, forces not covering the
    /// kinematics.
    pub fn from_storage(
        kinematics: &Storage,
        grf: Option<&Storage>,
        map: &StorageMap,
    ) -> Result<GaitData, DataError> {
        let ks = kinematics;
        ks.validate()?;
        if let Some(g) = grf {
            g.validate()?;
        }
        let time = ks.time().to_vec();
        check_angle_unit_stated(ks, map)?;
        let q = coordinates(ks, map)?;
        let extra = extra_channels(ks, map, &q, time.len())?;
        let n = time.len();
        let nan_foot = || FootData {
            fx: vec![f64::NAN; n],
            fy: vec![f64::NAN; n],
            cop_x: vec![f64::NAN; n],
        };
        let mut feet = [nan_foot(), nan_foot()];
        let mut plate = Vec::new();
        let mut forces = None;
        if let Some(g) = grf {
            let (record, heights) = ground_forces(ks, g, map, &time, &mut feet)?;
            plate = heights;
            forces = Some(record);
        }
        let force_plate_height =
            (!plate.is_empty()).then(|| plate.iter().sum::<f64>() / plate.len() as f64);
        Ok(GaitData {
            events: None,
            name: ks.name.clone(),
            source: ks.path.clone(),
            time,
            q,
            feet,
            forces,
            extra,
            body_mass: None,
            force_plate_height,
            belt_speed: None,
            cop_threshold: map.cop_threshold,
            sides: [SideSource::Measured, SideSource::Measured],
            overground: false,
        })
    }
}

/// Rotational columns need a kinematics file that states its angle unit.
fn check_angle_unit_stated(ks: &Storage, map: &StorageMap) -> Result<(), DataError> {
    let needs_angles = map
        .q
        .iter()
        .chain(map.extras.iter().map(|(_, c)| c))
        .any(|c| c.rotational);
    if needs_angles && !ks.angle_unit_stated {
        return Err(DataError::Units {
            path: ks.path.clone(),
            row: None,
            column: "inDegrees".into(),
            text: String::new(),
            reason:
                "the header states neither 'inDegrees=yes|no' nor 'Angles are in degrees|radians'; \
                     set Storage::in_degrees and Storage::angle_unit_stated once the unit is known"
                    .into(),
        });
    }
    Ok(())
}

/// The factor to SI of a mapped column: π/180 for a rotational one of a file in degrees.
fn scale(ks: &Storage, c: &ColumnMap) -> f64 {
    if c.rotational && ks.in_degrees {
        std::f64::consts::PI / 180.0
    } else {
        1.0
    }
}

/// The nine coordinates (m and rad), finite.
fn coordinates(ks: &Storage, map: &StorageMap) -> Result<[Vec<f64>; 9], DataError> {
    let mut q: [Vec<f64>; 9] = Default::default();
    for (i, c) in map.q.iter().enumerate() {
        let v = column(ks, &c.column, &format!("coordinate {}", Q_NAMES[i]))?;
        check_finite(ks, &c.column, v)?;
        let f = scale(ks, c);
        q[i] = v.iter().map(|x| x * f).collect();
    }
    Ok(q)
}

/// The mapped extra channels (NaN kept as gaps) and, with a hip offset in the pelvis
/// frame, the hip centre `hip_center_x`, `hip_center_y` (m) at the `n` samples of `q`.
fn extra_channels(
    ks: &Storage,
    map: &StorageMap,
    q: &[Vec<f64>; 9],
    n: usize,
) -> Result<BTreeMap<String, Vec<f64>>, DataError> {
    let mut extra = BTreeMap::new();
    for (name, c) in &map.extras {
        let v = column(ks, &c.column, &format!("extra channel {name}"))?;
        check_values(ks, &c.column, v, true)?;
        let f = scale(ks, c);
        extra.insert(name.clone(), v.iter().map(|x| x * f).collect::<Vec<f64>>());
    }
    if let Some([ox, oy]) = map.hip_offset_in_pelvis {
        let (hx, hy): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|k| {
                let (s, c) = q[2][k].sin_cos();
                (q[0][k] + c * ox - s * oy, q[1][k] + s * ox + c * oy)
            })
            .unzip();
        extra.insert("hip_center_x".into(), hx);
        extra.insert("hip_center_y".into(), hy);
    }
    Ok(extra)
}

/// The ground forces of `g` at their own instants over the kinematic span `time` (s),
/// one sample beyond either end for interpolation, and the CoP heights of the loaded
/// samples (m, where `cop_y` is mapped); the mapped feet of `feet` become the forces'
/// view at the kinematic instants.
fn ground_forces(
    ks: &Storage,
    g: &Storage,
    map: &StorageMap,
    time: &[f64],
    feet: &mut [FootData; 2],
) -> Result<(ForceSamples, Vec<f64>), DataError> {
    let tg = g.time();
    let n = time.len();
    check_force_span(ks, g, time)?;
    let FeetForces {
        record,
        raw_px,
        plate,
    } = feet_forces(g, map)?;
    // the record at its own instants over the kinematic span (one sample beyond
    // either end, for interpolation), and its view at the kinematic instants
    let k0 = tg.partition_point(|&t| t < time[0]).saturating_sub(1);
    let k1 = (tg.partition_point(|&t| t <= time[n - 1]) + 1).min(tg.len());
    let crop = |v: &[f64]| v[k0..k1].to_vec();
    let record = ForceSamples {
        time: crop(tg),
        feet: std::array::from_fn(|s| FootData {
            fx: crop(&record.feet[s].fx),
            fy: crop(&record.feet[s].fy),
            cop_x: crop(&record.feet[s].cop_x),
        }),
    };
    for s in 0..2 {
        if map.feet[s].is_some() {
            feet[s] = cop_view(&record, s, &crop(&raw_px[s]), time, map.cop_threshold);
        }
    }
    Ok((record, plate))
}

/// The forces must cover the kinematic time span.
fn check_force_span(ks: &Storage, g: &Storage, time: &[f64]) -> Result<(), DataError> {
    let tg = g.time();
    let n = time.len();
    let (g0, g1) = (tg[0], tg[tg.len() - 1]);
    let tol = 1e-9 * (1.0 + g1.abs());
    if time[0] < g0 - tol || time[n - 1] > g1 + tol {
        return Err(DataError::invalid(
            &g.path,
            "time",
            format!(
                "the forces cover {g0}–{g1} s but the kinematics ({}) run {}–{} s",
                ks.path.display(),
                time[0],
                time[n - 1]
            ),
        ));
    }
    Ok(())
}

/// The feet's ground forces at every sample of a force storage.
struct FeetForces {
    /// Each mapped foot's forces (N) and CoP (m, NaN below the CoP threshold); NaN for a
    /// foot not mapped. The time is left empty.
    record: ForceSamples,
    /// Each mapped foot's CoP as in the file (m).
    raw_px: [Vec<f64>; 2],
    /// The CoP heights of the loaded samples (m, where `cop_y` is mapped).
    plate: Vec<f64>,
}

/// The mapped feet's forces at every sample of `g`; a missing or repeated column and ∞
/// are errors.
fn feet_forces(g: &Storage, map: &StorageMap) -> Result<FeetForces, DataError> {
    let tg = g.time();
    let mut raw_px = [Vec::new(), Vec::new()];
    let mut plate = Vec::new();
    let mut record = ForceSamples {
        time: Vec::new(),
        feet: std::array::from_fn(|_| FootData {
            fx: vec![f64::NAN; tg.len()],
            fy: vec![f64::NAN; tg.len()],
            cop_x: vec![f64::NAN; tg.len()],
        }),
    };
    for (s, cols) in map.feet.iter().enumerate() {
        let Some(cols) = cols else { continue };
        let fx = column(g, &cols.fx, "the horizontal ground reaction force")?;
        let fy = column(g, &cols.fy, "the vertical ground reaction force")?;
        let px = column(g, &cols.cop_x, "the centre of pressure")?;
        // NaN is "not measured" (the foot off the plates); ∞ is refused
        check_not_infinite(g, &cols.fx, fx)?;
        check_not_infinite(g, &cols.fy, fy)?;
        check_not_infinite(g, &cols.cop_x, px)?;
        let cop: Vec<f64> = (0..px.len())
            .map(|k| {
                if fy[k] >= map.cop_threshold {
                    px[k]
                } else {
                    f64::NAN
                }
            })
            .collect();
        record.feet[s] = FootData {
            fx: fx.to_vec(),
            fy: fy.to_vec(),
            cop_x: cop,
        };
        raw_px[s] = px.to_vec();
        if let Some(py) = cols.cop_y.as_deref().and_then(|c| g.column(c)) {
            plate.extend(
                (0..py.len())
                    .filter(|&k| fy[k] >= map.cop_threshold && py[k].is_finite())
                    .map(|k| py[k]),
            );
        }
    }
    Ok(FeetForces {
        record,
        raw_px,
        plate,
    })
}

/// Foot `s` of `record` at the kinematic instants `time` (s), its CoP the raw CoP
/// `raw_px` (m, at the record's instants) resampled, NaN where the resampled normal
/// force is below `threshold` (N).
fn cop_view(
    record: &ForceSamples,
    s: usize,
    raw_px: &[f64],
    time: &[f64],
    threshold: f64,
) -> FootData {
    let raw = ForceSamples {
        time: record.time.clone(),
        feet: std::array::from_fn(|_| FootData {
            fx: record.feet[s].fx.clone(),
            fy: record.feet[s].fy.clone(),
            cop_x: raw_px.to_vec(),
        }),
    };
    let mut f = raw.resample_foot(0, time);
    for (c, &fy) in f.cop_x.iter_mut().zip(&f.fy) {
        if fy.is_nan() || fy < threshold {
            *c = f64::NAN;
        }
    }
    f
}
