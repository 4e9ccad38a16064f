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
use std::path::{Path, PathBuf};

mod params;
mod sagittal;
pub use sagittal::{feet_from_plates, AxisMap, LabAxis, SagittalPlate};

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
        .map_err(|e| c3d_err(path, what, e.to_string()))?
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
    let ls = length_scale(path, &point_units(&c3d))?;
    let time = analog_times(path, &c3d, rate)?;
    let mut plates = Vec::new();
    let used = c3d.forces.len();
    let mut type4_seen = 0;
    for (i, fp) in c3d.forces.iter().enumerate() {
        let number = i + 1;
        let plate_type = plate_type(path, number, fp)?;
        let channels = plate_channels(path, number, fp, analog.cols())?;
        // Type 2: channels in N and N·m (or N·mm); type 4: channels (V) through the
        // calibration matrix to N and N·(POINT unit).
        let (cal, moment_scales) = if plate_type == 4 {
            let c = cal_matrix(path, &bytes, number, type4_seen, used)?;
            type4_seen += 1;
            (Some(c), vec![ls; 3])
        } else {
            (None, type2_moment_scales(path, analog, &channels, ls)?)
        };
        let reading = PlateReading {
            path,
            number,
            channels,
            cal,
            moment_scales,
            frame: PlateFrame::new(path, number, fp, ls)?,
        };
        let PlateLoads { force, cop, free } = reading.samples(analog, &time, cop_threshold)?;
        plates.push(PlateForces {
            plate: number,
            plate_type,
            time: time.clone(),
            force,
            cop,
            free_moment: free,
            centre: reading.frame.centre,
            up: reading.frame.up(),
        });
    }
    Ok(C3dForces {
        path: path.to_path_buf(),
        analog_rate: rate,
        cop_threshold,
        plates,
    })
}

/// `POINT:UNITS`: c3dio fills `points.units` only when there are markers; a plate-only
/// file keeps it among the raw parameters.
fn point_units(c3d: &c3dio::C3d) -> String {
    let mut units: String = c3d.points.units.iter().collect();
    if units.trim().is_empty() {
        if let Some(p) = c3d.parameters.get("POINT", "UNITS") {
            units = String::try_from(p).unwrap_or_default();
        }
    }
    units
}

/// The instants of the analog samples (s), from the first point frame's time at `rate`
/// (Hz); no analog samples is an error.
fn analog_times(path: &Path, c3d: &c3dio::C3d, rate: f64) -> Result<Vec<f64>, DataError> {
    let analog = &c3d.analog;
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
    Ok((0..n).map(|k| t0 + k as f64 / rate).collect())
}

/// Plate `number`'s `FORCE_PLATFORM:TYPE`, one of [`SUPPORTED_PLATE_TYPES`].
fn plate_type(path: &Path, number: usize, fp: &c3dio::ForcePlatform) -> Result<i64, DataError> {
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
    Ok(plate_type)
}

/// Plate `number`'s six channels (`Fx Fy Fz Mx My Mz`) as 0-based indices into the
/// `cols` analog channels (the file's are 1-based).
fn plate_channels(
    path: &Path,
    number: usize,
    fp: &c3dio::ForcePlatform,
    cols: usize,
) -> Result<[usize; 6], DataError> {
    let mut ch = [0usize; 6];
    for (j, c) in ch.iter_mut().enumerate() {
        let idx = fp.channels[j] as usize;
        if idx == 0 || idx > cols {
            return Err(c3d_err(
                path,
                "FORCE_PLATFORM:CHANNEL",
                format!(
                    "plate {number}, entry {}: channel {idx} is not one of the {} analog channels (valid: 1–{})",
                    j + 1,
                    cols,
                    cols
                ),
            ));
        }
        *c = idx - 1;
    }
    Ok(ch)
}

/// A type-2 plate's moment scales to N·m of its three moment channels, once its force
/// channels are checked to be in N (or blank).
fn type2_moment_scales(
    path: &Path,
    analog: &c3dio::Analog,
    ch: &[usize; 6],
    ls: f64,
) -> Result<Vec<f64>, DataError> {
    let unit_of = |c: usize| analog.units.get(c).map(String::as_str).unwrap_or("");
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
    ch[3..]
        .iter()
        .map(|&c| moment_scale(path, unit_of(c), ls, c + 1))
        .collect::<Result<Vec<f64>, _>>()
}

/// A plate's frame in the lab (m): its axes, the centre of its working surface and its
/// measurement origin.
struct PlateFrame {
    /// The plate's axes in the lab, `[x, y, z]` (z pointing down into the plate).
    r: [[f64; 3]; 3],
    /// `FORCE_PLATFORM:ORIGIN` in the plate frame (m).
    origin: [f64; 3],
    /// Geometric centre of the working surface, lab frame (m).
    centre: [f64; 3],
    /// The measurement origin in the lab (m).
    o_lab: [f64; 3],
}

impl PlateFrame {
    /// Plate `number`'s frame from its corners and origin, scaled to metres by `ls`;
    /// corners that span no rectangle are an error.
    fn new(
        path: &Path,
        number: usize,
        fp: &c3dio::ForcePlatform,
        ls: f64,
    ) -> Result<Self, DataError> {
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
        Ok(Self {
            r,
            origin,
            centre,
            o_lab,
        })
    }

    /// Upward unit normal of the working surface, lab frame.
    fn up(&self) -> [f64; 3] {
        let z = self.r[2];
        [-z[0], -z[1], -z[2]]
    }
}

/// How one plate's analog channels become its loads.
struct PlateReading<'a> {
    /// The file, for errors.
    path: &'a Path,
    /// Plate number (1-based).
    number: usize,
    /// Its six analog channels (0-based).
    channels: [usize; 6],
    /// A type-4 plate's calibration matrix.
    cal: Option<[[f64; 6]; 6]>,
    /// Scale of the three moment outputs to N·m.
    moment_scales: Vec<f64>,
    /// The plate's frame.
    frame: PlateFrame,
}

impl PlateReading<'_> {
    /// Force of the ground on the foot (N), CoP (m) and free moment (N·m) in the lab at
    /// each analog sample (instants `time`, s); CoP and free moment NaN below
    /// `cop_threshold` (N). A channel that is not finite is an error.
    fn samples(
        &self,
        analog: &c3dio::Analog,
        time: &[f64],
        cop_threshold: f64,
    ) -> Result<PlateLoads, DataError> {
        let (path, number, ch, ms) = (self.path, self.number, &self.channels, &self.moment_scales);
        let PlateFrame {
            r, origin, o_lab, ..
        } = self.frame;
        let n = time.len();
        let mut force = Vec::with_capacity(n);
        let mut cop = Vec::with_capacity(n);
        let mut free = Vec::with_capacity(n);
        #[allow(clippy::needless_range_loop)] // k indexes the analog grid too
        for k in 0..n {
            let v = |j: usize| analog.get(k, ch[j]).copied().unwrap_or(f64::NAN);
            let raw: [f64; 6] = std::array::from_fn(v);
            let out: [f64; 6] = match &self.cal {
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
        Ok(PlateLoads { force, cop, free })
    }
}

/// A plate's loads at its analog samples, lab frame: the ground's force on the foot (N),
/// the CoP (m) and the free moment (N·m).
struct PlateLoads {
    force: Vec<[f64; 3]>,
    cop: Vec<[f64; 3]>,
    free: Vec<f64>,
}
