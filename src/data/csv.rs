//! The documented sagittal CSV schema (`data/README.md`) and its meta JSON file.
//!
//! One header row, then one row per sample, comma separated; blank lines and lines
//! starting with `#` are skipped. Columns, in any order:
//!
//! | column | unit | meaning |
//! |---|---|---|
//! | `time` | s | strictly increasing |
//! | `pelvis_x`, `pelvis_y` | m | pelvis origin in the global frame (x forward, y up) |
//! | `pelvis_tilt` | rad | pelvis (HAT) angle, counter-clockwise positive seen from the right |
//! | `hip_r`, `knee_r`, `ankle_r`, `hip_l`, `knee_l`, `ankle_l` | rad | + = hip flexion, knee extension (flexion is negative), ankle dorsiflexion |
//! | `grf_x_r`, `grf_y_r`, `grf_x_l`, `grf_y_l` | N | force of the ground on the foot, + forward / + up |
//! | `cop_x_r`, `cop_x_l` | m | centre of pressure x; `NaN` while that foot's `grf_y` < 20 N |
//! | any other | | kept in [`GaitData::extra`] (e.g. `hip_center_x`, `hip_center_y`, `lumbar_extension`) |
//!
//! The six columns of one side (`hip`, `knee`, `ankle`, `grf_x`, `grf_y`, `cop_x`) may be
//! left out together when only one side was measured
//! ([`SideSource::Missing`](super::SideSource::Missing); fill it with
//! [`GaitData::mirror_missing_side`]); leaving out some of them is an error. `NaN`
//! in `grf_*` and `cop_x_*` means "not measured" (a foot off the force plates; a CoP the
//! lab did not export while the foot is loaded, which then tracks its forces only); in an
//! extra column (which the model does not read) it is a gap, kept as it is.
//!
//! **Mixed rates in one file.** Kinematics at 60–200 Hz and forces at 600–2,000 Hz may
//! share one file: a row whose coordinates (pelvis and angles) are all `NaN` is a
//! force-only row. The kinematics are then the other rows, and the forces are kept
//! at their own instants ([`GaitData::forces`]: the force-only rows and the kinematic
//! rows that carry a force), with their view at the kinematic instants in
//! [`GaitData::feet`].
//!
//! The optional meta JSON ([`TrialMeta`]) supplies the body mass, the treadmill belt
//! speed, the force-plate height, the CoP threshold and the units.

use super::error::DataError;
use super::{Events, GaitData, DEFAULT_COP_THRESHOLD, Q_NAMES};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

mod parse;
use parse::parse_sagittal_csv;

/// Gait events stored in a meta file (s).
#[derive(Debug, Clone, PartialEq, Default, Deserialize, serde::Serialize)]
pub struct MetaEvents {
    /// Heel strikes (s).
    #[serde(default)]
    pub heel_strike_s: Vec<f64>,
    /// Toe offs (s).
    #[serde(default)]
    pub toe_off_s: Vec<f64>,
}

/// The meta file of a trial (`<name>_meta.json`); unknown fields are ignored.
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
pub struct TrialMeta {
    /// Data-set name.
    #[serde(default)]
    pub dataset: Option<String>,
    /// Body mass (kg) of the model (also read from `body_mass_kg`).
    #[serde(default, alias = "body_mass_kg")]
    pub body_mass_kg_model: Option<f64>,
    /// Body mass estimated from the mean vertical force (kg).
    #[serde(default)]
    pub body_mass_kg_from_grf: Option<f64>,
    /// Whether the trial was recorded on a treadmill.
    #[serde(default)]
    pub treadmill: Option<bool>,
    /// Treadmill belt speed (m/s, the belt moves backward).
    #[serde(default)]
    pub belt_speed_m_s: Option<f64>,
    /// Height of the force-plate surface (m).
    #[serde(default)]
    pub force_plate_surface_y_m: Option<f64>,
    /// CoP is NaN below this normal force (N).
    #[serde(default)]
    pub cop_threshold_n: Option<f64>,
    /// Hip-joint centre in the pelvis frame (m).
    #[serde(default)]
    pub hip_offset_in_pelvis_m: Option<[f64; 2]>,
    /// Units of the CSV columns: keys `time` (s, ms), `positions` (m, cm, mm),
    /// `angles` (rad, deg), `forces` (N).
    #[serde(default)]
    pub units: Option<BTreeMap<String, String>>,
    /// Gait events to use instead of force-threshold detection, keyed `r` and `l`.
    #[serde(default)]
    pub events_s: Option<BTreeMap<String, MetaEvents>>,
    /// Events detected on the raw forces with a 20 N threshold, keyed `r` and `l`.
    #[serde(default, rename = "events_from_raw_grf_threshold_20N")]
    pub events_20n: Option<BTreeMap<String, MetaEvents>>,
}

/// The meta file's fields; an error names the field, what serde found and its line.
fn parse_meta(text: &str, path: &Path) -> Result<TrialMeta, DataError> {
    let mut de = serde_json::Deserializer::from_str(text);
    serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let field = e.path().to_string();
        let inner = e.into_inner();
        let what = inner.to_string();
        let what = match what.rfind(" at line ") {
            Some(k) => what[..k].replace("f64", "a number"),
            None => what,
        };
        DataError::Json {
            path: path.to_path_buf(),
            message: match field.as_str() {
                "." | "" => what,
                f => format!("field '{f}': {what}"),
            },
            line: inner.line(),
            column: inner.column(),
        }
    })
}

/// Fastest treadmill belt a meta file may give (m/s), beyond a sprinter's speed.
pub const MAX_BELT_SPEED: f64 = 12.0;

/// Read a meta JSON file (its units are checked too).
pub fn read_meta(path: &Path) -> Result<TrialMeta, DataError> {
    load_meta(path).map(|(m, _)| m)
}

fn load_meta(path: &Path) -> Result<(TrialMeta, Units), DataError> {
    let text = std::fs::read_to_string(path).map_err(|e| DataError::io(path, e))?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let meta = parse_meta(text, path)?;
    for (field, v) in [
        ("body_mass_kg_model", meta.body_mass_kg_model),
        ("belt_speed_m_s", meta.belt_speed_m_s),
        ("force_plate_surface_y_m", meta.force_plate_surface_y_m),
        ("cop_threshold_n", meta.cop_threshold_n),
    ] {
        if let Some(x) = v {
            if !x.is_finite() {
                return Err(DataError::invalid(
                    path,
                    field,
                    format!("must be finite, got {x}"),
                ));
            }
        }
    }
    if let Some(m) = meta.body_mass_kg_model {
        if m <= 0.0 {
            return Err(DataError::invalid(
                path,
                "body_mass_kg_model",
                format!("must be positive, got {m}"),
            ));
        }
    }
    if let Some(v) = meta.belt_speed_m_s {
        if !(v > 0.0 && v <= MAX_BELT_SPEED) {
            return Err(DataError::invalid(
                path,
                "belt_speed_m_s",
                format!(
                    "must be the belt's backward speed, > 0 and ≤ {MAX_BELT_SPEED} m/s, got {} m/s (leave the field out for an overground trial)",
                    crate::limits::show(v)
                ),
            ));
        }
    }
    let units = Units::from_meta(&meta, text, path)?;
    Ok((meta, units))
}

/// Scale factors to SI of the CSV columns.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Units {
    time: f64,
    position: f64,
    angle: f64,
}

impl Units {
    fn si() -> Self {
        Self {
            time: 1.0,
            position: 1.0,
            angle: 1.0,
        }
    }

    fn from_meta(meta: &TrialMeta, text: &str, path: &Path) -> Result<Self, DataError> {
        let mut u = Self::si();
        let Some(map) = &meta.units else { return Ok(u) };
        for (key, value) in map {
            let v = value.trim();
            let (factor, valid): (Option<f64>, &str) = match key.as_str() {
                "time" => (
                    match v {
                        "s" => Some(1.0),
                        "ms" => Some(1e-3),
                        _ => None,
                    },
                    "s or ms",
                ),
                "positions" => (
                    match v {
                        "m" => Some(1.0),
                        "cm" => Some(1e-2),
                        "mm" => Some(1e-3),
                        _ => None,
                    },
                    "m, cm or mm",
                ),
                "angles" => (
                    match v {
                        "rad" | "radians" => Some(1.0),
                        "deg" | "degrees" => Some(std::f64::consts::PI / 180.0),
                        _ => None,
                    },
                    "rad or deg",
                ),
                "forces" => (if v == "N" { Some(1.0) } else { None }, "N"),
                _ => continue,
            };
            let Some(f) = factor else {
                return Err(DataError::Units {
                    path: path.to_path_buf(),
                    row: json_key_line(text, key),
                    column: format!("units.{key}"),
                    text: value.clone(),
                    reason: format!("not a unit of {key}; expected {valid}"),
                });
            };
            match key.as_str() {
                "time" => u.time = f,
                "positions" => u.position = f,
                "angles" => u.angle = f,
                _ => {}
            }
        }
        Ok(u)
    }
}

/// Line (1-based) of `"key"` after the line holding `"units"`, for error messages.
fn json_key_line(text: &str, key: &str) -> Option<usize> {
    let lines: Vec<&str> = text.lines().collect();
    let start = lines.iter().position(|l| l.contains("\"units\""))?;
    let needle = format!("\"{key}\"");
    (start..lines.len())
        .find(|&i| lines[i].contains(&needle))
        .map(|i| i + 1)
}

/// Where the meta file of a CSV comes from.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum MetaSource {
    /// `<name>_meta.json` beside the CSV, where `<name>` is the CSV's stem without a
    /// trailing `_sagittal` (also tried: `<stem>_meta.json`); none if absent.
    #[default]
    Sibling,
    /// This file (must exist).
    File(PathBuf),
    /// No meta file.
    None,
}

/// The sibling meta file of a CSV, if one exists.
pub fn sibling_meta_path(csv: &Path) -> Option<PathBuf> {
    let stem = csv.file_stem()?.to_string_lossy().into_owned();
    let dir = csv.parent().unwrap_or(Path::new(""));
    let mut names = Vec::new();
    if let Some(base) = stem.strip_suffix("_sagittal") {
        names.push(format!("{base}_meta.json"));
    }
    names.push(format!("{stem}_meta.json"));
    names.into_iter().map(|n| dir.join(n)).find(|p| p.is_file())
}

/// Read a sagittal CSV (see the module docs) with its sibling meta file, if any.
///
/// # Example
/// ```no_run
/// let d = footfall::data::read_sagittal_csv("data/opensim_subject01_sagittal.csv".as_ref())?;
/// assert_eq!(d.body_mass, Some(72.6));
/// # Ok::<(), footfall::data::DataError>(())
/// ```
pub fn read_sagittal_csv(path: &Path) -> Result<GaitData, DataError> {
    read_sagittal_csv_with(path, &MetaSource::Sibling)
}

/// Read a sagittal CSV with the meta file chosen by `meta`.
///
/// The meta file sets `body_mass` (`body_mass_kg_model`), `belt_speed`,
/// `force_plate_height`, the CoP threshold (default 20 N) and the units of the columns
/// (converted to SI). The data stay in the frame of the file: call
/// [`GaitData::to_overground`] for treadmill trials.
///
/// Errors ([`DataError`]): unreadable file; empty file or fewer than two data rows;
/// duplicate or missing columns (a side's six columns may only be missing together, and
/// not both sides); a row with the wrong number of fields; an unparsable number (row,
/// column); ∞ anywhere, NaN in a kinematic column of a row that has kinematics (row,
/// column); time not strictly increasing (row); a meta
/// file that is not valid JSON, has invalid values or units that do not parse.
pub fn read_sagittal_csv_with(path: &Path, meta: &MetaSource) -> Result<GaitData, DataError> {
    let meta_path = match meta {
        MetaSource::Sibling => sibling_meta_path(path),
        MetaSource::File(p) => Some(p.clone()),
        MetaSource::None => None,
    };
    let (meta, units) = match &meta_path {
        Some(mp) => {
            let (m, u) = load_meta(mp)?;
            (Some(m), u)
        }
        None => (None, Units::si()),
    };
    let text = std::fs::read_to_string(path).map_err(|e| DataError::io(path, e))?;
    let cop_threshold = meta
        .as_ref()
        .and_then(|m| m.cop_threshold_n)
        .unwrap_or(DEFAULT_COP_THRESHOLD);
    let mut data = parse_sagittal_csv(&text, path, cop_threshold, units)?;
    if let (Some(mp), true) = (&meta_path, units.angle != 1.0) {
        check_degrees_declared(&data, mp)?;
    }
    if let Some(m) = meta {
        data.body_mass = m.body_mass_kg_model;
        data.belt_speed = m.belt_speed_m_s;
        data.force_plate_height = m.force_plate_surface_y_m;
        if let Some(name) = m.dataset {
            data.name = name;
        }
        if let Some(ev) = m.events_s {
            data.events = Some(given_events(
                &data,
                &ev,
                meta_path.as_deref().unwrap_or(path),
            )?);
        }
    }
    Ok(data)
}

/// A meta file that declares degrees over angles that, so converted, barely move: they
/// were radians.
fn check_degrees_declared(data: &GaitData, meta_path: &Path) -> Result<(), DataError> {
    let Some((widest, s, duration)) = data.still_legs() else {
        return Ok(());
    };
    Err(DataError::invalid(
        meta_path,
        "units.angles",
        format!(
            "declares degrees, but then {} of {} spans only {:.3}° in {duration:.2} s, the most of any leg joint: a walking knee spans about 60°, so the angles look like radians; declare \"angles\": \"rad\" (or leave the unit out) if they are",
            Q_NAMES[widest],
            data.source.display(),
            s.to_degrees()
        ),
    ))
}

/// Events given in a meta file: both sides, increasing, inside the recording; a foot is
/// loaded at the start when its first event is a toe off.
fn given_events(
    data: &GaitData,
    ev: &BTreeMap<String, MetaEvents>,
    meta: &Path,
) -> Result<Events, DataError> {
    let mut out = Events {
        heel_strike: [Vec::new(), Vec::new()],
        toe_off: [Vec::new(), Vec::new()],
        threshold: 0.0,
        loaded_at_start: [false; 2],
        span: (data.time[0], data.time[data.time.len() - 1]),
        source: data.source.clone(),
    };
    for (s, side) in ["r", "l"].iter().enumerate() {
        let e = ev.get(*side).ok_or_else(|| {
            DataError::invalid(
                meta,
                format!("events_s.{side}"),
                "missing: give heel_strike_s and toe_off_s for both sides r and l",
            )
        })?;
        for (what, v) in [
            ("heel_strike_s", &e.heel_strike_s),
            ("toe_off_s", &e.toe_off_s),
        ] {
            if let Some(k) = (0..v.len()).find(|&k| {
                !(v[k] >= out.span.0 && v[k] <= out.span.1) || (k > 0 && v[k] <= v[k - 1])
            }) {
                return Err(DataError::invalid(
                    meta,
                    format!("events_s.{side}.{what}[{k}]"),
                    format!(
                        "{} s: events must increase and lie within the recording {}–{} s",
                        v[k], out.span.0, out.span.1
                    ),
                ));
            }
        }
        out.loaded_at_start[s] = match (e.heel_strike_s.first(), e.toe_off_s.first()) {
            (Some(h), Some(t)) => t < h,
            (None, Some(_)) => true,
            _ => false,
        };
        out.heel_strike[s] = e.heel_strike_s.clone();
        out.toe_off[s] = e.toe_off_s.clone();
    }
    Ok(out)
}

/// The trial as a sagittal CSV (the schema of the module docs, SI units; `NaN` for an
/// undefined CoP) and its meta JSON (CoP threshold, body mass, given events), so that
/// [`read_sagittal_csv`] reads it back.
pub fn write_sagittal_csv(data: &GaitData) -> (String, String) {
    use std::fmt::Write as _;
    let mut csv = String::from("time");
    for n in Q_NAMES {
        write!(csv, ",{n}").ok();
    }
    for side in ["r", "l"] {
        write!(csv, ",grf_x_{side},grf_y_{side},cop_x_{side}").ok();
    }
    csv.push('\n');
    for k in 0..data.time.len() {
        write!(csv, "{}", data.time[k]).ok();
        for q in &data.q {
            write!(csv, ",{}", q[k]).ok();
        }
        for f in &data.feet {
            write!(
                csv,
                ",{},{},{}",
                f.fx[k],
                f.fy[k],
                if f.cop_x[k].is_finite() {
                    f.cop_x[k].to_string()
                } else {
                    "NaN".into()
                }
            )
            .ok();
        }
        csv.push('\n');
    }
    let mut meta = serde_json::json!({
        "dataset": data.name,
        "cop_threshold_n": data.cop_threshold,
        "treadmill": false,
    });
    if let Some(m) = data.body_mass {
        meta["body_mass_kg_model"] = m.into();
    }
    if let Some(e) = &data.events {
        let side = |s: usize| MetaEvents {
            heel_strike_s: e.heel_strike[s].clone(),
            toe_off_s: e.toe_off[s].clone(),
        };
        meta["events_s"] = serde_json::json!({"r": side(0), "l": side(1)});
    }
    (csv, serde_json::to_string_pretty(&meta).unwrap_or_default())
}
