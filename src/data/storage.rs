//! OpenSim storage files (`.mot`, `.sto`): the form gait labs export processed
//! kinematics and ground reaction forces in, read by [`read_storage`] and written by
//! [`storage_text`] (the one reader and writer of the format in the crate).
//!
//! Layout: header lines up to a line `endheader`, then one line of column labels (the
//! first is `time`), then one row of numbers per sample, separated by tabs or spaces.
//! Header lines understood (others are kept verbatim in [`Storage::header`]):
//!
//! * `inDegrees=yes|no`: whether rotational coordinates are in degrees (OpenSim 4);
//! * `Angles are in degrees.` / `Angles are in radians.` (older files say it in words);
//! * `nRows=N`, `nColumns=N`, `datarows N`, `datacolumns N`: checked against the data;
//! * `name X` (SIMM form) or a first line without `=` (the storage's name).
//!
//! OpenSim 4 labels such as `/jointset/hip_r/hip_flexion_r/value` are shortened to the
//! coordinate name (`hip_flexion_r`); `…/speed` becomes `hip_flexion_r_speed`.
//! Translations are always in metres; `inDegrees` applies to rotational coordinates only,
//! which is why [`StorageMap`] says which columns are rotational.

use super::error::DataError;
use super::{FootData, ForceSamples, GaitData, SideSource, Q_NAMES};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

mod map;
pub use map::{ColumnMap, ForceColumns, StorageMap, OPENSIM_COORDINATES};

/// An OpenSim `.mot`/`.sto` table.
#[derive(Debug, Clone, PartialEq)]
pub struct Storage {
    /// File it was read from.
    pub path: PathBuf,
    /// Name from the header (or the file stem).
    pub name: String,
    /// Header lines before `endheader`, verbatim (trimmed).
    pub header: Vec<String>,
    /// Column names (OpenSim 4 path labels shortened, see the module docs); the first is `time`.
    pub columns: Vec<String>,
    /// Column labels exactly as in the file.
    pub labels: Vec<String>,
    /// The data, **column-major**: `data[j][k]` is column `j` at row `k`.
    pub data: Vec<Vec<f64>>,
    /// Line number (1-based) of each data row, for error messages.
    pub lines: Vec<usize>,
    /// Line number (1-based) of the column labels.
    pub label_line: usize,
    /// Whether rotational coordinates are in degrees.
    pub in_degrees: bool,
    /// Whether the header states the angle unit (`inDegrees=…` or `Angles are in …`).
    /// [`GaitData::from_storage`] refuses rotational columns of a file that does not.
    pub angle_unit_stated: bool,
}

impl Storage {
    /// Index of a column by its (short) name or its label as in the file; the first one if
    /// the name repeats (some exports repeat the labels of several force plates;
    /// [`GaitData::from_storage`] refuses such an ambiguous mapping).
    pub fn column_index(&self, name: &str) -> Option<usize> {
        self.columns
            .iter()
            .position(|c| c == name)
            .or_else(|| self.labels.iter().position(|c| c == name))
    }

    /// A column by its (short) name or its label as in the file.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.column_index(name).map(|j| self.data[j].as_slice())
    }

    /// The time column (s).
    pub fn time(&self) -> &[f64] {
        self.data.first().map_or(&[], Vec::as_slice)
    }

    /// Number of data rows.
    pub fn len(&self) -> usize {
        self.time().len()
    }

    /// Whether there are no data rows (never true for a storage returned by [`read_storage`]).
    pub fn is_empty(&self) -> bool {
        self.time().is_empty()
    }

    /// Line (1-based) of data row `k`, for error messages.
    pub fn line_of(&self, k: usize) -> usize {
        self.lines
            .get(k)
            .copied()
            .unwrap_or(self.label_line + 1 + k)
    }

    /// Check a storage built or edited in memory: a time column first, every column as
    /// long as it, time finite and strictly increasing, at least one row.
    pub fn validate(&self) -> Result<(), DataError> {
        let n = self.len();
        if n == 0 {
            return Err(DataError::Format {
                path: self.path.clone(),
                row: self.label_line,
                reason: "no data rows".into(),
            });
        }
        if self.columns.len() != self.data.len() || self.labels.len() != self.data.len() {
            return Err(DataError::invalid(
                &self.path,
                "columns",
                format!(
                    "{} names and {} labels for {} data columns",
                    self.columns.len(),
                    self.labels.len(),
                    self.data.len()
                ),
            ));
        }
        if let Some(j) = self.data.iter().position(|c| c.len() != n) {
            return Err(DataError::invalid(
                &self.path,
                self.columns[j].clone(),
                format!("{} rows but the time column has {n}", self.data[j].len()),
            ));
        }
        let lines: Vec<usize> = (0..n).map(|k| self.line_of(k)).collect();
        check_time(self.time(), &lines, &self.columns[0], &self.path)
    }
}

fn short_label(label: &str) -> String {
    if !label.starts_with('/') {
        return label.to_string();
    }
    let parts: Vec<&str> = label.split('/').filter(|s| !s.is_empty()).collect();
    match parts.as_slice() {
        [.., coord, "value"] => coord.to_string(),
        [.., coord, "speed"] => format!("{coord}_speed"),
        _ => label.to_string(),
    }
}

fn split_fields(line: &str) -> Vec<&str> {
    line.split_whitespace().collect()
}

fn parse_yes_no(text: &str) -> Option<bool> {
    match text.trim().to_ascii_lowercase().as_str() {
        "yes" | "true" => Some(true),
        "no" | "false" => Some(false),
        _ => None,
    }
}

/// Read an OpenSim `.mot`/`.sto` file (see the module docs for the layout).
///
/// Errors: the file cannot be read; no `endheader` or no column labels
/// ([`DataError::Format`]); `inDegrees` not `yes`/`no`, or contradicting the
/// `Angles are in …` line ([`DataError::Units`]); a row or column count that disagrees
/// with the header; a first column that is not `time`; a row with the
/// wrong number of fields; a field that is not a number (row, column); a time that is not
/// finite or does not increase strictly (row). Other NaN values and repeated labels are
/// kept (checked by [`GaitData::from_storage`] for the columns it uses).
///
/// # Example
/// ```no_run
/// let s = footfall::data::read_storage("data/raw/opensim_subject01/subject01_walk1_grf.mot".as_ref())?;
/// let fy_right = s.column("ground_force_vy").unwrap();
/// # Ok::<(), footfall::data::DataError>(())
/// ```
pub fn read_storage(path: &Path) -> Result<Storage, DataError> {
    let bytes = std::fs::read(path).map_err(|e| DataError::io(path, e))?;
    let text = String::from_utf8_lossy(&bytes);
    parse_storage(&text, path)
}

/// Parse the text of a storage file (see [`read_storage`]); `path` names it in errors.
pub fn parse_storage(text: &str, path: &Path) -> Result<Storage, DataError> {
    let p = path.to_path_buf();
    let lines: Vec<&str> = text.split('\n').map(|l| l.trim_end_matches('\r')).collect();
    let end = lines
        .iter()
        .position(|l| l.trim().eq_ignore_ascii_case("endheader"))
        .ok_or_else(|| DataError::Format {
            path: p.clone(),
            row: lines.len(),
            reason: "no 'endheader' line: not an OpenSim .mot/.sto file".into(),
        })?;
    let mut name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut header = Vec::new();
    let mut in_degrees_key: Option<(bool, usize)> = None;
    let mut angles_sentence: Option<(bool, usize)> = None;
    let mut n_rows: Option<(usize, usize, String)> = None;
    let mut n_cols: Option<(usize, usize, String)> = None;
    let parse_count = |text: &str, key: &str, row: usize| -> Result<usize, DataError> {
        text.trim().parse::<usize>().map_err(|e| DataError::Format {
            path: p.clone(),
            row,
            reason: format!("header '{key}' = '{}' is not a count: {e}", text.trim()),
        })
    };
    for (i, raw) in lines[..end].iter().enumerate() {
        let row = i + 1;
        let l = raw.trim();
        if l.is_empty() {
            continue;
        }
        header.push(l.to_string());
        let lower = l.to_ascii_lowercase();
        if let Some((k, v)) = l.split_once('=') {
            let key = k.trim();
            match key.to_ascii_lowercase().as_str() {
                "indegrees" => {
                    let b = parse_yes_no(v).ok_or_else(|| DataError::Units {
                        path: p.clone(),
                        row: Some(row),
                        column: key.to_string(),
                        text: v.trim().to_string(),
                        reason: "inDegrees must be 'yes' or 'no'".into(),
                    })?;
                    in_degrees_key = Some((b, row));
                }
                "nrows" => n_rows = Some((parse_count(v, key, row)?, row, key.to_string())),
                "ncolumns" => n_cols = Some((parse_count(v, key, row)?, row, key.to_string())),
                _ => {}
            }
            continue;
        }
        if let Some(rest) = lower.strip_prefix("angles are in") {
            let rest = rest.trim().trim_end_matches('.').trim();
            let b = match rest {
                "degrees" => true,
                "radians" => false,
                _ => {
                    return Err(DataError::Units {
                        path: p.clone(),
                        row: Some(row),
                        column: "Angles are in".into(),
                        text: rest.to_string(),
                        reason: "expected 'degrees' or 'radians'".into(),
                    })
                }
            };
            angles_sentence = Some((b, row));
            continue;
        }
        let mut words = l.split_whitespace();
        match words.next().map(str::to_ascii_lowercase).as_deref() {
            Some("datarows") => {
                let v = words.next().unwrap_or("");
                n_rows = Some((parse_count(v, "datarows", row)?, row, "datarows".into()));
            }
            Some("datacolumns") => {
                let v = words.next().unwrap_or("");
                n_cols = Some((
                    parse_count(v, "datacolumns", row)?,
                    row,
                    "datacolumns".into(),
                ));
            }
            Some("name") => {
                let rest: Vec<&str> = words.collect();
                if !rest.is_empty() {
                    name = rest.join(" ");
                }
            }
            _ => {
                if i == 0 && !l.starts_with('#') {
                    name = l.to_string();
                }
            }
        }
    }
    let (in_degrees, angle_unit_stated) = match (in_degrees_key, angles_sentence) {
        (Some((a, row)), Some((b, _))) if a != b => {
            return Err(DataError::Units {
                path: p,
                row: Some(row),
                column: "inDegrees".into(),
                text: if a { "yes" } else { "no" }.into(),
                reason: format!(
                    "contradicts the header line 'Angles are in {}'",
                    if b { "degrees" } else { "radians" }
                ),
            })
        }
        (Some((a, _)), _) | (None, Some((a, _))) => (a, true),
        (None, None) => (false, false),
    };

    // Column labels: the first non-empty line after endheader.
    let mut idx = end + 1;
    while idx < lines.len() && lines[idx].trim().is_empty() {
        idx += 1;
    }
    if idx >= lines.len() {
        return Err(DataError::Format {
            path: p,
            row: end + 1,
            reason: "no column labels after 'endheader'".into(),
        });
    }
    let label_line = idx + 1;
    let labels: Vec<String> = split_fields(lines[idx])
        .into_iter()
        .map(String::from)
        .collect();
    let columns: Vec<String> = labels.iter().map(|l| short_label(l)).collect();
    if !columns[0].eq_ignore_ascii_case("time") {
        return Err(DataError::MissingColumn {
            path: p,
            row: label_line,
            column: "time".into(),
            reason: format!("the first column must be 'time', found '{}'", labels[0]),
        });
    }
    if let Some((n, row, key)) = &n_cols {
        if *n != labels.len() {
            return Err(DataError::Format {
                path: p,
                row: *row,
                reason: format!(
                    "header '{key}' says {n} columns but line {label_line} has {} labels",
                    labels.len()
                ),
            });
        }
    }

    let ncol = labels.len();
    let mut data = vec![Vec::new(); ncol];
    let mut row_lines = Vec::new();
    for (i, raw) in lines.iter().enumerate().skip(idx + 1) {
        let row = i + 1;
        if raw.trim().is_empty() {
            continue;
        }
        let fields = split_fields(raw);
        DataError::check_row_length(&p, row, ncol, fields.len())?;
        for (j, f) in fields.iter().enumerate() {
            let v = f.parse::<f64>().map_err(|e| DataError::Parse {
                path: p.clone(),
                row,
                column: columns[j].clone(),
                text: f.to_string(),
                reason: e.to_string(),
            })?;
            data[j].push(v);
        }
        row_lines.push(row);
    }
    if row_lines.is_empty() {
        return Err(DataError::Format {
            path: p,
            row: label_line,
            reason: "no data rows after the column labels".into(),
        });
    }
    if let Some((n, row, key)) = &n_rows {
        if *n != row_lines.len() {
            return Err(DataError::Format {
                path: p,
                row: *row,
                reason: format!(
                    "header '{key}' says {n} rows but the file has {} data rows",
                    row_lines.len()
                ),
            });
        }
    }
    check_time(&data[0], &row_lines, &columns[0], &p)?;
    Ok(Storage {
        path: p,
        name,
        header,
        columns,
        labels,
        data,
        lines: row_lines,
        label_line,
        in_degrees,
        angle_unit_stated,
    })
}

/// The text of an OpenSim 4 storage file that [`parse_storage`] (and OpenSim's `Storage`
/// and `TimeSeriesTable`) read back: `name` on the first line (line breaks and tabs in it
/// become spaces), `version=1`, `nRows`, `nColumns`, `inDegrees=no` (SI units and
/// radians), `endheader`, the tab-separated labels `time` and `columns`, then one row per
/// sample of `time` (s). Numbers are written as `{:.9e}`, a NaN as `NaN` (OpenSim parses
/// numbers with `strtod`/`std::stod`, which accept it). Every column must be as long as
/// `time`.
pub fn storage_text(name: &str, time: &[f64], columns: &[(&str, &[f64])]) -> String {
    use std::fmt::Write;
    let name = name.replace(['\n', '\r', '\t'], " ");
    let mut out = String::new();
    writeln!(
        out,
        "{name}\nversion=1\nnRows={}\nnColumns={}\ninDegrees=no\nendheader",
        time.len(),
        columns.len() + 1
    )
    .ok();
    out.push_str("time");
    for (n, _) in columns {
        write!(out, "\t{n}").ok();
    }
    out.push('\n');
    for (i, t) in time.iter().enumerate() {
        write!(out, "{t:.9e}").ok();
        for (_, x) in columns {
            if x[i].is_nan() {
                out.push_str("\tNaN");
            } else {
                write!(out, "\t{:.9e}", x[i]).ok();
            }
        }
        out.push('\n');
    }
    out
}

/// Time must be finite and strictly increasing; `lines` gives each sample's line.
pub(crate) fn check_time(
    t: &[f64],
    lines: &[usize],
    column: &str,
    path: &Path,
) -> Result<(), DataError> {
    for k in 0..t.len() {
        if !t[k].is_finite() {
            return Err(DataError::NotFinite {
                path: path.to_path_buf(),
                row: lines[k],
                column: column.to_string(),
                reason: format!("time is {}", t[k]),
            });
        }
        if k > 0 && t[k] <= t[k - 1] {
            return Err(DataError::NonMonotonicTime {
                path: path.to_path_buf(),
                row: lines[k],
                time: t[k],
                previous: t[k - 1],
            });
        }
    }
    Ok(())
}

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
                reason: "the header states neither 'inDegrees=yes|no' nor 'Angles are in degrees|radians'; \
                         set Storage::in_degrees and Storage::angle_unit_stated once the unit is known"
                    .into(),
            });
        }
        let scale = |c: &ColumnMap| {
            if c.rotational && ks.in_degrees {
                std::f64::consts::PI / 180.0
            } else {
                1.0
            }
        };
        let mut q: [Vec<f64>; 9] = Default::default();
        for (i, c) in map.q.iter().enumerate() {
            let v = column(ks, &c.column, &format!("coordinate {}", Q_NAMES[i]))?;
            check_finite(ks, &c.column, v)?;
            let f = scale(c);
            q[i] = v.iter().map(|x| x * f).collect();
        }
        let mut extra = BTreeMap::new();
        for (name, c) in &map.extras {
            let v = column(ks, &c.column, &format!("extra channel {name}"))?;
            check_values(ks, &c.column, v, true)?;
            let f = scale(c);
            extra.insert(name.clone(), v.iter().map(|x| x * f).collect::<Vec<f64>>());
        }
        if let Some([ox, oy]) = map.hip_offset_in_pelvis {
            let (hx, hy): (Vec<f64>, Vec<f64>) = (0..time.len())
                .map(|k| {
                    let (s, c) = q[2][k].sin_cos();
                    (q[0][k] + c * ox - s * oy, q[1][k] + s * ox + c * oy)
                })
                .unzip();
            extra.insert("hip_center_x".into(), hx);
            extra.insert("hip_center_y".into(), hy);
        }
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
            let tg = g.time();
            let mut raw_px = [Vec::new(), Vec::new()];
            let mut record = ForceSamples {
                time: Vec::new(),
                feet: std::array::from_fn(|_| FootData {
                    fx: vec![f64::NAN; tg.len()],
                    fy: vec![f64::NAN; tg.len()],
                    cop_x: vec![f64::NAN; tg.len()],
                }),
            };
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
                    // the CoP view: the raw CoP resampled, NaN where the resampled normal
                    // force is below the threshold
                    let raw = ForceSamples {
                        time: record.time.clone(),
                        feet: std::array::from_fn(|_| FootData {
                            fx: record.feet[s].fx.clone(),
                            fy: record.feet[s].fy.clone(),
                            cop_x: crop(&raw_px[s]),
                        }),
                    };
                    let mut f = raw.resample_foot(0, &time);
                    for (c, &fy) in f.cop_x.iter_mut().zip(&f.fy) {
                        if fy.is_nan() || fy < map.cop_threshold {
                            *c = f64::NAN;
                        }
                    }
                    feet[s] = f;
                }
            }
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
