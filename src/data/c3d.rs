//! Force-plate data from C3D files: ground reaction force and centre of pressure per plate
//! in the lab frame, and their sagittal projection onto the model's frame.
//!
//! The file is parsed by the `c3dio` crate, which already applies each analog channel's
//! `ANALOG:OFFSET`, `ANALOG:SCALE` and `ANALOG:GEN_SCALE`:
//! $v = (raw - offset)\,scale\,gen\_scale$. This module takes it from there, following the
//! force-platform chapter of the C3D user guide (c3d.org, "FORCE_PLATFORM" parameters,
//! TYPE-2 and ORIGIN):
//!
//! * **Plate frame** from `FORCE_PLATFORM:CORNERS` (lab frame): corners 1–4 lie in the
//!   plate's +x+y, −x+y, −x−y, +x−y quadrants, so $\hat x \parallel c_1 - c_2$,
//!   $\hat y \parallel c_1 - c_4$, $\hat z = \hat x \times \hat y$ (pointing down into the
//!   plate for a plate seen from above; $\hat y$ is re-orthogonalised as
//!   $\hat z \times \hat x$). $R = [\hat x\ \hat y\ \hat z]$ maps plate to lab.
//! * **`FORCE_PLATFORM:ORIGIN`** $o$ (plate frame) is, for types 2 and 4, the vector *from
//!   the plate's measurement origin to the geometric centre of its working surface*, so
//!   $o_z < 0$ when the origin lies below the surface (the guide's TYPE-2 page; note that
//!   it is not the vector from the centre to the origin). The measurement origin is at
//!   $O = C - R\,o$ in the lab, with $C$ the mean of the corners.
//! * **Type 2** (AMTI, Bertec; six channels `Fx Fy Fz Mx My Mz` in `FORCE_PLATFORM:CHANNEL`
//!   order) measures the force $F$ *of the foot on the plate* and its moment $M$ about $O$,
//!   both in the plate frame. A load $F$ at the surface point $p = (p_x, p_y, o_z)$ (from
//!   $O$) with free moment $T$ about $\hat z$ gives $M = p \times F + T\hat z$, hence
//!   $p_x = (o_z F_x - M_y)/F_z$, $p_y = (M_x + o_z F_y)/F_z$,
//!   $T = M_z - p_x F_y + p_y F_x$ (with $z_0 = -o_z$ the depth of the origin these are the
//!   guide's $(-M_y - z_0F_x)/F_z$ and $(M_x - z_0 F_y)/F_z$). The CoP in the lab is
//!   $O + R\,p$, on the surface.
//! * **Type 4** is type 2 with a 6×6 calibration matrix: the outputs are
//!   $(F, M) = C\,v$ for the six channels $v$ (often volts), with
//!   $C_{ij}$ = `FORCE_PLATFORM:CAL_MATRIX(i, j, plate)` (first index fastest, as the guide
//!   stores arrays, as ezc3d reads it), in N and N·(POINT unit). `c3dio` 0.8
//!   parses this matrix but drops it (it appends the matrices after one `None` per
//!   plate), so it is read here from the parameter section directly (a small reader of
//!   the guide's parameter records, `params`).
//!
//! Types 1 and 3 (CoP channels; eight-channel Kistler) and types beyond 4 are refused
//! with a [`DataError::C3d`] naming the plate, its type and the types converted.
//!
//! Positions are scaled to metres by `POINT:UNITS` (`mm`, `cm` or `m`), type-2 moments to
//! N·m by the moment channels' `ANALOG:UNITS` (`Nmm`, `N.mm`, `Nm`, `N.m`; blank means N·(POINT
//! unit)), forces must be in N.
//!
//! # Example
//! ```no_run
//! use footfall::data::c3d::{feet_from_plates, read_c3d_plates, AxisMap};
//! use footfall::data::DEFAULT_COP_THRESHOLD;
//! use footfall::model::Side;
//! let forces = read_c3d_plates("trial.c3d".as_ref(), DEFAULT_COP_THRESHOLD)?;
//! let map = AxisMap::new("+x", "+z")?; // walking along lab +x, z up (the default)
//! let time: Vec<f64> = (0..100).map(|k| k as f64 / 100.0).collect();
//! let [right, left] = feet_from_plates(&forces, &[(Side::Right, 1), (Side::Left, 2)], map, &time)?;
//! println!("right heel-strike load {} N, left CoP {} m", right.fy[0], left.cop_x[0]);
//! # Ok::<(), footfall::data::DataError>(())
//! ```

use super::error::DataError;
use super::{interp_linear, side_index, FootData};
use crate::model::Side;
use std::path::{Path, PathBuf};
use std::str::FromStr;

mod params;

/// Plate types [`read_c3d_plates`] converts (`FORCE_PLATFORM:TYPE`).
pub const SUPPORTED_PLATE_TYPES: [i64; 2] = [2, 4];

/// One force plate's ground reaction, at the analog rate, in the lab frame of the C3D file.
///
/// Force and free moment are those of the ground *on the foot* (the negative of what the
/// plate measures, which is the foot's force on the plate).
#[derive(Debug, Clone, PartialEq)]
pub struct PlateForces {
    /// Plate number (1-based, the order of `FORCE_PLATFORM:TYPE`).
    pub plate: usize,
    /// `FORCE_PLATFORM:TYPE`.
    pub plate_type: i64,
    /// Sample times (s): analog sample $k$ is at $(first\_frame - 1)/f_{point} + k/f_{analog}$.
    pub time: Vec<f64>,
    /// Ground reaction force on the foot, lab frame (N).
    pub force: Vec<[f64; 3]>,
    /// Centre of pressure, lab frame (m); NaN where the normal load is below the threshold.
    pub cop: Vec<[f64; 3]>,
    /// Free moment of the ground on the foot about the plate's upward surface normal (N·m,
    /// counter-clockwise seen from above); NaN where the CoP is.
    pub free_moment: Vec<f64>,
    /// Geometric centre of the working surface, lab frame (m).
    pub centre: [f64; 3],
    /// Upward unit normal of the working surface, lab frame.
    pub up: [f64; 3],
}

/// All force plates of one C3D file.
#[derive(Debug, Clone, PartialEq)]
pub struct C3dForces {
    /// The file read.
    pub path: PathBuf,
    /// Analog sampling rate (Hz).
    pub analog_rate: f64,
    /// Normal force below which CoP and free moment are NaN (N).
    pub cop_threshold: f64,
    /// The plates, in file order.
    pub plates: Vec<PlateForces>,
}

fn c3d_err(path: &Path, parameter: &str, reason: impl Into<String>) -> DataError {
    DataError::C3d {
        path: path.to_path_buf(),
        parameter: parameter.to_string(),
        reason: reason.into(),
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}
fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = norm(a);
    [a[0] / n, a[1] / n, a[2] / n]
}
/// `R v` for `R = [x y z]` (columns).
fn rot(r: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| r[0][i] * v[0] + r[1][i] * v[1] + r[2][i] * v[2])
}

/// Metres per unit of `POINT:UNITS`.
fn length_scale(path: &Path, units: &str) -> Result<f64, DataError> {
    match units.trim().to_ascii_lowercase().as_str() {
        "mm" => Ok(1e-3),
        "cm" => Ok(1e-2),
        "m" => Ok(1.0),
        "" => Err(c3d_err(
            path,
            "POINT:UNITS",
            "missing or blank; FORCE_PLATFORM:CORNERS and ORIGIN need a length unit (valid: mm, cm, m)",
        )),
        other => Err(c3d_err(
            path,
            "POINT:UNITS",
            format!("'{other}' is not a length unit this reader knows; valid: mm, cm, m"),
        )),
    }
}

/// N·m per unit of a moment channel's `ANALOG:UNITS` (blank: N times the POINT unit).
fn moment_scale(
    path: &Path,
    units: &str,
    point_scale: f64,
    channel: usize,
) -> Result<f64, DataError> {
    let u: String = units
        .trim()
        .to_ascii_lowercase()
        .chars()
        .filter(|c| !matches!(c, '.' | '*' | ' ' | '·' | '-'))
        .collect();
    match u.as_str() {
        "" => Ok(point_scale),
        "nmm" => Ok(1e-3),
        "ncm" => Ok(1e-2),
        "nm" => Ok(1.0),
        _ => Err(c3d_err(
            path,
            "ANALOG:UNITS",
            format!(
                "analog channel {channel} is a plate moment in '{}'; valid: Nmm, N.mm, Nm, N.m (or blank)",
                units.trim()
            ),
        )),
    }
}

/// Turn `c3dio`'s parse error into a [`DataError`], naming the parameter where it can.
fn parse_error(path: &Path, e: c3dio::C3dParseError) -> DataError {
    use c3dio::C3dParseError as E;
    match e {
        E::ReadError(source) => DataError::Io {
            path: path.to_path_buf(),
            source,
        },
        E::InvalidParameterFormat(s) if s.trim().parse::<i64>().is_ok() => c3d_err(
            path,
            "FORCE_PLATFORM:TYPE",
            format!(
                "plate type {} is not one c3dio reads (1–4); this reader converts type {}",
                s.trim(),
                supported_list()
            ),
        ),
        E::InvalidParameterFormat(s) => c3d_err(path, &s, "malformed parameter"),
        E::ParameterNotFound(g, p) => {
            c3d_err(path, &format!("{g}:{p}"), "required parameter is missing")
        }
        E::MissingParameter(p) | E::RequiredParameterNotFound(p) => {
            c3d_err(path, &p, "required parameter is missing")
        }
        E::MissingGroup(g) | E::GroupNotFound(g) => {
            c3d_err(path, &g, "required parameter group is missing")
        }
        E::InvalidData(_, what) => c3d_err(
            path,
            &what.replacen('_', ":", 1),
            "malformed values (wrong type or dimensions)",
        ),
        other => {
            let (section, what) = damaged_section(&other);
            c3d_err(path, section, format!("not a readable C3D file: {what}"))
        }
    }
}

/// The section of a C3D file a structural error of c3dio's points at, and what was wrong
/// there, in the terms of the C3D format's description (c3d.org).
fn damaged_section(e: &c3dio::C3dParseError) -> (&'static str, String) {
    use c3dio::C3dParseError as E;
    match e {
        E::InsufficientBlocks(part) => (
            "file",
            format!("the file ends before its {part} section (shorter than its header says)"),
        ),
        E::InvalidHeaderStartBlock => (
            "header",
            "the header's first word does not point at the parameter section".into(),
        ),
        E::InvalidParameterStartBlock | E::InvalidParametersOffset => (
            "parameter section",
            "shorter than one 512-byte block, or not where the header says".into(),
        ),
        E::InvalidDataStartBlock => (
            "header",
            "the data section's start block lies outside the file".into(),
        ),
        E::InvalidProcessorType => (
            "parameter section",
            "the processor type is none of Intel (84), DEC (85) and MIPS (86)".into(),
        ),
        E::InvalidDataType => (
            "parameter section",
            "a parameter's type byte is none of -1 (char), 1 (byte), 2 (integer) and 4 (float)".into(),
        ),
        E::MissingPointScale => ("POINT:SCALE", "missing".into()),
        E::InvalidParameterData
        | E::InvalidDescription
        | E::InvalidGroupId
        | E::InvalidNextParameter
        | E::InvalidParameterDimensions(_)
        | E::InvalidParameterType(_) => (
            "parameter section",
            "a group or parameter record is malformed (its name, type, dimensions or link to the next record)".into(),
        ),
        E::NotEnoughData | E::NumFramesMismatch(..) => (
            "data section",
            "it holds fewer frames than POINT:FRAMES and the header say".into(),
        ),
        E::AnalogBytesPerFrameMismatch => (
            "ANALOG:USED",
            "the analog bytes of a frame (header) are not ANALOG:USED channels times the samples per frame".into(),
        ),
        E::AnalogOffsetScaleMismatch | E::InsufficientAnalogOffsets => (
            "ANALOG:OFFSET",
            "fewer offsets or scales than ANALOG:USED channels".into(),
        ),
        E::FrameRateMismatch(a, b) => (
            "POINT:RATE",
            format!("the header's frame rate {a} Hz and the parameter's {b} Hz differ"),
        ),
        E::ScaleFactorMismatch(a, b) => (
            "POINT:SCALE",
            format!("the header's scale {a} and the parameter's {b} differ"),
        ),
        E::TooManyEvents(_)
        | E::InvalidEventLabel(..)
        | E::MissingEventTime(_)
        | E::MissingEventLabel(_)
        | E::NoParameterTimeEvents => (
            "EVENT",
            "the events' count, labels or times are inconsistent".into(),
        ),
        E::FileNotOpen | E::ReadError(_) => ("file", "it could not be read".into()),
        _ => (
            "file",
            "its header or parameter blocks are inconsistent".into(),
        ),
    }
}

fn supported_list() -> String {
    SUPPORTED_PLATE_TYPES
        .iter()
        .map(|t| t.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

thread_local! {
    /// Whether this thread is inside the C3D crate's parser (see [`crate_is_parsing`]).
    static CRATE_RUNNING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether this thread is inside the C3D crate's parser: a panic there is caught and
/// becomes an error naming the file, so a panic hook may leave its text unprinted.
pub fn crate_is_parsing() -> bool {
    CRATE_RUNNING.with(|r| r.get())
}

#[allow(clippy::result_large_err)] // c3dio's error type, converted at once
fn load(path: &Path) -> Result<(c3dio::C3d, Vec<u8>), DataError> {
    let bytes = std::fs::read(path).map_err(|e| DataError::io(path, e))?;
    // c3dio refuses a plate type beyond 1–4 without saying which plate: look first.
    if let Ok(Some(t)) = params::find(&bytes, "FORCE_PLATFORM", "TYPE") {
        if let Some((i, v)) = t
            .values
            .iter()
            .enumerate()
            .find(|(_, v)| !(1.0..=4.0).contains(*v))
        {
            return Err(c3d_err(
                path,
                "FORCE_PLATFORM:TYPE",
                format!(
                    "plate {} is of type {v}, which this reader does not convert; valid: {}",
                    i + 1,
                    supported_list()
                ),
            ));
        }
    }
    // c3dio indexes slices from header values; a corrupt file must become an error here,
    // never a panic of the caller.
    CRATE_RUNNING.with(|r| r.set(true));
    let parsed = std::panic::catch_unwind(|| c3dio::C3d::from_bytes(&bytes));
    CRATE_RUNNING.with(|r| r.set(false));
    match parsed {
        Ok(Ok(c)) => Ok((c, bytes)),
        Ok(Err(e)) => Err(parse_error(path, e)),
        Err(_) => Err(c3d_err(
            path,
            "file",
            "not a readable C3D file (its header or parameter blocks are inconsistent)",
        )),
    }
}

/// The 6×6 calibration matrix of plate `number` (1-based), `C[i][j]` multiplying channel
/// `j` into output `i` (`Fx Fy Fz Mx My Mz`): `FORCE_PLATFORM:CAL_MATRIX(i, j, plate)`,
/// first index fastest, as the C3D guide stores arrays. The third dimension counts all
/// plates, or only the type-4 plates when it is smaller than `USED`.
fn cal_matrix(
    path: &Path,
    bytes: &[u8],
    number: usize,
    type4_ordinal: usize,
    used: usize,
) -> Result<[[f64; 6]; 6], DataError> {
    let what = "FORCE_PLATFORM:CAL_MATRIX";
    let raw = params::find(bytes, "FORCE_PLATFORM", "CAL_MATRIX")
        .map_err(|e| c3d_err(path, what, e))?
        .ok_or_else(|| {
            c3d_err(
                path,
                what,
                format!(
                    "missing; plate {number} is of type 4, which needs its 6×6 calibration matrix"
                ),
            )
        })?;
    let count = raw.dims.get(2).copied().unwrap_or(1);
    let k = if count >= used {
        number - 1
    } else {
        type4_ordinal
    };
    if raw.dims.len() < 2 || raw.dims[0] != 6 || raw.dims[1] != 6 || k >= count {
        return Err(c3d_err(
            path,
            what,
            format!(
                "dimensions {:?} hold no 6×6 matrix for plate {number}; valid: (6, 6, USED = {used})",
                raw.dims
            ),
        ));
    }
    let v = &raw.values[36 * k..36 * (k + 1)];
    Ok(std::array::from_fn(|i| {
        std::array::from_fn(|j| v[i + 6 * j])
    }))
}

/// Read every force plate of a C3D file (types 2 and 4) to ground reaction force, CoP and
/// free moment in the file's lab frame, at the analog rate (see the module documentation
/// for the equations and conventions). The force returned is the ground's force **on the foot**.
/// CoP and free moment are NaN where the normal load ($F_z$ in the plate frame, pressing
/// into the plate) is below `cop_threshold` (N).
///
/// Errors ([`DataError::C3d`] naming the file and the parameter, or [`DataError::Io`]): a
/// missing or unreadable file; no force platform (`FORCE_PLATFORM:USED` = 0); a plate type
/// other than [`SUPPORTED_PLATE_TYPES`]; channels outside `ANALOG:USED`; unknown units;
/// degenerate corners; no analog rate or no analog samples; a threshold that is not finite and ≥ 0.
pub fn read_c3d_plates(path: &Path, cop_threshold: f64) -> Result<C3dForces, DataError> {
    if !(cop_threshold.is_finite() && cop_threshold >= 0.0) {
        return Err(DataError::invalid(
            path,
            "cop_threshold",
            format!("must be finite and ≥ 0 N, got {cop_threshold}"),
        ));
    }
    let (c3d, bytes) = load(path)?;
    if c3d.forces.is_empty() {
        return Err(c3d_err(
            path,
            "FORCE_PLATFORM:USED",
            "the file has no force platform (USED is 0 or absent); a plate of type 2 or 4 is needed",
        ));
    }
    let analog = &c3d.analog;
    let rate = analog.rate as f64;
    if !(rate.is_finite() && rate > 0.0) {
        return Err(c3d_err(
            path,
            "ANALOG:RATE",
            format!("{rate} Hz; the analog rate must be positive to time the plate samples"),
        ));
    }
    // c3dio fills `points.units` only when there are markers; a plate-only file keeps
    // POINT:UNITS among the raw parameters.
    let mut units: String = c3d.points.units.iter().collect();
    if units.trim().is_empty() {
        if let Some(p) = c3d.parameters.get("POINT", "UNITS") {
            units = String::try_from(p).unwrap_or_default();
        }
    }
    let ls = length_scale(path, &units)?;
    let t0 = if c3d.points.frame_rate > 0.0 {
        (c3d.points.first_frame.max(1) as f64 - 1.0) / c3d.points.frame_rate as f64
    } else {
        0.0
    };
    let n = analog.rows();
    if n == 0 || analog.cols() == 0 {
        return Err(c3d_err(
            path,
            "ANALOG:USED",
            format!(
                "{} analog channel(s) with {n} sample(s); the plates' channels need samples",
                analog.cols()
            ),
        ));
    }
    let time: Vec<f64> = (0..n).map(|k| t0 + k as f64 / rate).collect();
    let mut plates = Vec::new();
    let used = c3d.forces.len();
    let mut type4_seen = 0;
    for (i, fp) in c3d.forces.iter().enumerate() {
        let number = i + 1;
        let plate_type = match fp.plate_type {
            c3dio::ForcePlatformType::Type1 => 1,
            c3dio::ForcePlatformType::Type2 => 2,
            c3dio::ForcePlatformType::Type3 => 3,
            c3dio::ForcePlatformType::Type4 => 4,
        };
        if !SUPPORTED_PLATE_TYPES.contains(&plate_type) {
            let why = match plate_type {
                1 => "type 1 (force and CoP channels)",
                3 => "type 3 (eight-channel Kistler)",
                _ => "of an unknown type",
            };
            return Err(c3d_err(
                path,
                "FORCE_PLATFORM:TYPE",
                format!(
                    "plate {number} is {why}; this reader converts types {} (six channels Fx Fy Fz Mx My Mz, type 4 through its calibration matrix)",
                    supported_list()
                ),
            ));
        }
        // Six channels, 1-based indices into the analog channels.
        let mut ch = [0usize; 6];
        for (j, c) in ch.iter_mut().enumerate() {
            let idx = fp.channels[j] as usize;
            if idx == 0 || idx > analog.cols() {
                return Err(c3d_err(
                    path,
                    "FORCE_PLATFORM:CHANNEL",
                    format!(
                        "plate {number}, entry {}: channel {idx} is not one of the {} analog channels (valid: 1–{})",
                        j + 1,
                        analog.cols(),
                        analog.cols()
                    ),
                ));
            }
            *c = idx - 1;
        }
        let unit_of = |c: usize| analog.units.get(c).map(String::as_str).unwrap_or("");
        // Type 2: channels in N and N·m (or N·mm); type 4: channels (V) through the
        // calibration matrix to N and N·(POINT unit).
        let (cal, ms) = if plate_type == 4 {
            let c = cal_matrix(path, &bytes, number, type4_seen, used)?;
            type4_seen += 1;
            (Some(c), vec![ls; 3])
        } else {
            for &c in &ch[..3] {
                let u = unit_of(c).trim();
                if !(u.is_empty() || u.eq_ignore_ascii_case("n")) {
                    return Err(c3d_err(
                        path,
                        "ANALOG:UNITS",
                        format!(
                            "analog channel {} is a plate force in '{u}'; valid: N (or blank)",
                            c + 1
                        ),
                    ));
                }
            }
            let ms = ch[3..]
                .iter()
                .map(|&c| moment_scale(path, unit_of(c), ls, c + 1))
                .collect::<Result<Vec<f64>, _>>()?;
            (None, ms)
        };
        let corners: [[f64; 3]; 4] =
            std::array::from_fn(|k| std::array::from_fn(|d| fp.corners[k][d] as f64 * ls));
        let origin: [f64; 3] = std::array::from_fn(|d| fp.origin[d] as f64 * ls);
        let ex = sub(corners[0], corners[1]);
        let ey = sub(corners[0], corners[3]);
        let ez = cross(ex, ey);
        let size = norm(ex).max(norm(ey));
        if !(size > 0.0 && norm(ez) > 1e-6 * size * size)
            || corners.iter().flatten().any(|v| !v.is_finite())
        {
            return Err(c3d_err(
                path,
                "FORCE_PLATFORM:CORNERS",
                format!(
                    "plate {number}: corners {corners:?} m do not span a rectangle (corner 1 − corner 2 and corner 1 − corner 4 must be non-parallel)"
                ),
            ));
        }
        let (x, z) = (unit(ex), unit(ez));
        let r = [x, cross(z, x), z];
        let centre: [f64; 3] =
            std::array::from_fn(|d| corners.iter().map(|c| c[d]).sum::<f64>() / 4.0);
        let ro = rot(&r, origin);
        let o_lab = sub(centre, ro);
        let mut force = Vec::with_capacity(n);
        let mut cop = Vec::with_capacity(n);
        let mut free = Vec::with_capacity(n);
        #[allow(clippy::needless_range_loop)] // k indexes the analog grid too
        for k in 0..n {
            let v = |j: usize| analog.get(k, ch[j]).copied().unwrap_or(f64::NAN);
            let raw: [f64; 6] = std::array::from_fn(v);
            let out: [f64; 6] = match &cal {
                Some(c) => std::array::from_fn(|i| (0..6).map(|j| c[i][j] * raw[j]).sum()),
                None => raw,
            };
            let f = [out[0], out[1], out[2]];
            let m = [out[3] * ms[0], out[4] * ms[1], out[5] * ms[2]];
            if let Some(j) = (0..3).find(|&j| !(f[j].is_finite() && m[j].is_finite())) {
                return Err(c3d_err(
                    path,
                    "ANALOG",
                    format!(
                        "plate {number}, analog sample {k} (t = {} s): channel {} is not finite",
                        time[k],
                        ch[if f[j].is_finite() { j + 3 } else { j }] + 1
                    ),
                ));
            }
            let fl = rot(&r, f);
            force.push([-fl[0], -fl[1], -fl[2]]);
            if f[2] >= cop_threshold && f[2] > 0.0 {
                let px = (origin[2] * f[0] - m[1]) / f[2];
                let py = (m[0] + origin[2] * f[1]) / f[2];
                let p = rot(&r, [px, py, origin[2]]);
                cop.push([o_lab[0] + p[0], o_lab[1] + p[1], o_lab[2] + p[2]]);
                free.push(m[2] - px * f[1] + py * f[0]);
            } else {
                cop.push([f64::NAN; 3]);
                free.push(f64::NAN);
            }
        }
        plates.push(PlateForces {
            plate: number,
            plate_type,
            time: time.clone(),
            force,
            cop,
            free_moment: free,
            centre,
            up: [-z[0], -z[1], -z[2]],
        });
    }
    Ok(C3dForces {
        path: path.to_path_buf(),
        analog_rate: rate,
        cop_threshold,
        plates,
    })
}

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
    type Err = String;
    /// `+x`, `x`, `-x`, … `-z` (case-insensitive).
    fn from_str(s: &str) -> Result<Self, String> {
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
                return Err(format!(
                    "'{s}' is not a lab axis; valid: +x, -x, +y, -y, +z, -z"
                ))
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
        let mem = super::error::memory_path();
        let f = forward
            .parse::<LabAxis>()
            .map_err(|e| DataError::invalid(&mem, "forward", e))?;
        let u = up
            .parse::<LabAxis>()
            .map_err(|e| DataError::invalid(&mem, "up", e))?;
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
/// plates. Forces are resampled by linear interpolation (as [`super::GaitData::from_storage`]
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
