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
use std::path::{Path, PathBuf};

mod gait;
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
    let head = StorageHeader::read(&lines[..end], path)?;
    let (in_degrees, angle_unit_stated) = head.angle_unit(path)?;
    let (idx, labels, columns) = read_labels(&lines, end, path)?;
    let label_line = idx + 1;
    if let Some((n, row, key)) = &head.n_cols {
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
    let (data, row_lines) = read_rows(&lines, idx, &columns, path)?;
    if let Some((n, row, key)) = &head.n_rows {
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
        name: head.name,
        header: head.lines,
        columns,
        labels,
        data,
        lines: row_lines,
        label_line,
        in_degrees,
        angle_unit_stated,
    })
}

/// A count the header states (`nRows=N`, `datacolumns N`, …): the count, its line and the
/// key as written.
type HeaderCount = Option<(usize, usize, String)>;

/// What a storage file's header says.
struct StorageHeader {
    /// The storage's name: `name X`, or a first line that is neither `key=value` nor a
    /// comment, or the file stem.
    name: String,
    /// The header's non-empty lines, trimmed.
    lines: Vec<String>,
    /// `inDegrees=yes|no`, and its line.
    in_degrees_key: Option<(bool, usize)>,
    /// `Angles are in degrees|radians` (true: degrees), and its line.
    angles_sentence: Option<(bool, usize)>,
    /// `nRows` or `datarows`.
    n_rows: HeaderCount,
    /// `nColumns` or `datacolumns`.
    n_cols: HeaderCount,
}

impl StorageHeader {
    /// The header from its `lines` (those before `endheader`); an `inDegrees` that is not
    /// yes or no, an angle sentence that names no unit and a count that is not a number
    /// are errors.
    fn read(lines: &[&str], path: &Path) -> Result<Self, DataError> {
        let p = path.to_path_buf();
        let mut name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut header = Vec::new();
        let mut in_degrees_key: Option<(bool, usize)> = None;
        let mut angles_sentence: Option<(bool, usize)> = None;
        let mut n_rows: HeaderCount = None;
        let mut n_cols: HeaderCount = None;
        let parse_count = |text: &str, key: &str, row: usize| -> Result<usize, DataError> {
            text.trim().parse::<usize>().map_err(|e| DataError::Format {
                path: p.clone(),
                row,
                reason: format!("header '{key}' = '{}' is not a count: {e}", text.trim()),
            })
        };
        for (i, raw) in lines.iter().enumerate() {
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
        Ok(Self {
            name,
            lines: header,
            in_degrees_key,
            angles_sentence,
            n_rows,
            n_cols,
        })
    }

    /// Whether angles are in degrees, and whether the header says so either way; an
    /// `inDegrees` that contradicts the sentence is an error.
    fn angle_unit(&self, path: &Path) -> Result<(bool, bool), DataError> {
        Ok(match (self.in_degrees_key, self.angles_sentence) {
            (Some((a, row)), Some((b, _))) if a != b => {
                return Err(DataError::Units {
                    path: path.to_path_buf(),
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
        })
    }
}

/// The column labels, the first non-empty line after `endheader` (line `end` + 1): its
/// index in `lines`, the labels as written and their short names; a first column that is
/// not `time` is an error.
fn read_labels(
    lines: &[&str],
    end: usize,
    path: &Path,
) -> Result<(usize, Vec<String>, Vec<String>), DataError> {
    let mut idx = end + 1;
    while idx < lines.len() && lines[idx].trim().is_empty() {
        idx += 1;
    }
    if idx >= lines.len() {
        return Err(DataError::Format {
            path: path.to_path_buf(),
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
            path: path.to_path_buf(),
            row: label_line,
            column: "time".into(),
            reason: format!("the first column must be 'time', found '{}'", labels[0]),
        });
    }
    Ok((idx, labels, columns))
}

/// The numbers of the rows after the labels (at `lines[idx]`), column-major, and each
/// row's line (1-based); a row of the wrong length, a field that is not a number and no
/// rows at all are errors.
fn read_rows(
    lines: &[&str],
    idx: usize,
    columns: &[String],
    path: &Path,
) -> Result<(Vec<Vec<f64>>, Vec<usize>), DataError> {
    let p = path.to_path_buf();
    let ncol = columns.len();
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
            row: idx + 1,
            reason: "no data rows after the column labels".into(),
        });
    }
    Ok((data, row_lines))
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
