//! A study's manifest: one row per trial, as a CSV file (a header row, then one row per
//! trial) or a JSON file (an array of objects, or `{"trials": [...]}`) with the same
//! fields. A relative file path is read from the manifest's folder where the file is
//! there, else as given (from the current folder, or footfall's bundled `models/…`).

use crate::workflows::trial::TrialFiles;
use std::path::{Path, PathBuf};

/// The fields a row may have, as the manifest names them.
pub const FIELDS: [&str; 15] = [
    "id",
    "subject",
    "session",
    "condition",
    "data",
    "forces",
    "plate",
    "lab_axes",
    "belt_speed",
    "overground",
    "model",
    "foot",
    "cutoff",
    "max_iter",
    "kinematics_cutoff",
];

/// Default model of a row that names none (the bundled subject's).
pub const DEFAULT_MODEL: &str = "models/opensim_subject01.json";

/// Why a manifest cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum ManifestError {
    /// The file cannot be read.
    #[error("manifest {path}: {source}")]
    Read {
        /// The manifest.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// Neither `.csv` nor `.json`.
    #[error(
        "manifest {0}: cannot tell the format from the extension: give a .csv or a .json file"
    )]
    Format(PathBuf),
    /// The JSON does not parse.
    #[error("manifest {path}: {source}")]
    JsonSyntax {
        /// The manifest.
        path: PathBuf,
        /// serde's description (with line and column).
        source: serde_json::Error,
    },
    /// The JSON is not an array of objects.
    #[error("manifest {path}: {message}")]
    Json {
        /// The manifest.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A CSV line with another number of cells than the header.
    #[error("manifest {path}, line {line}: {found} cells where the header has {expected}")]
    Cells {
        /// The manifest.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// Cells found.
        found: usize,
        /// Cells in the header.
        expected: usize,
    },
    /// A field footfall does not know.
    #[error("manifest {path}: unknown field '{field}' (valid: {})", FIELDS.join(", "))]
    UnknownField {
        /// The manifest.
        path: PathBuf,
        /// The field.
        field: String,
    },
    /// A field's value is refused.
    #[error("manifest {path}, row {row}, field '{field}': '{value}' {expected}")]
    Value {
        /// The manifest.
        path: PathBuf,
        /// 1-based trial row.
        row: usize,
        /// The field.
        field: &'static str,
        /// The value given.
        value: String,
        /// What would be valid.
        expected: String,
    },
    /// Two rows with one id.
    #[error("manifest {path}: rows {first} and {second} both have the id '{id}' (each trial needs its own)")]
    DuplicateId {
        /// The manifest.
        path: PathBuf,
        /// The id.
        id: String,
        /// The rows (1-based).
        first: usize,
        /// The second row.
        second: usize,
    },
    /// No rows.
    #[error("manifest {0}: no trials (a header and at least one row are needed)")]
    Empty(PathBuf),
}

/// One trial of a study.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialRow {
    /// 1-based row of the manifest (the Slurm array index).
    pub row: usize,
    /// The trial's folder name under `trials/`.
    pub id: String,
    /// Subject (body effects are pooled over a subject's trials).
    pub subject: String,
    /// Lab session (instrument effects are pooled over a session's trials).
    pub session: String,
    /// Condition (reported, not pooled over).
    pub condition: String,
    /// The trial's files.
    pub files: TrialFiles,
    /// Model file.
    pub model: PathBuf,
    /// Foot of a track.
    pub foot: String,
    /// The check's low-pass cutoff (Hz), if not the study's.
    pub cutoff_hz: Option<f64>,
    /// A track's iteration limit, if not the study's.
    pub max_iter: Option<usize>,
    /// A track's kinematics cutoff (Hz).
    pub kinematics_cutoff: Option<f64>,
}

type Record = Vec<(String, String)>;

/// Read the manifest at `path`.
pub fn read(path: &Path) -> Result<Vec<TrialRow>, ManifestError> {
    let text = std::fs::read_to_string(path).map_err(|source| ManifestError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let text = text.trim_start_matches('\u{feff}');
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let records = match ext.as_deref() {
        Some("csv") => csv_records(path, text)?,
        Some("json") => json_records(path, text)?,
        _ => return Err(ManifestError::Format(path.to_path_buf())),
    };
    if records.is_empty() {
        return Err(ManifestError::Empty(path.to_path_buf()));
    }
    let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let width = records.len().to_string().len();
    let mut rows = Vec::with_capacity(records.len());
    for (i, rec) in records.iter().enumerate() {
        let row = row_of(path, &base, i + 1, width, rec)?;
        if let Some(first) = rows.iter().find(|r: &&TrialRow| r.id == row.id) {
            return Err(ManifestError::DuplicateId {
                path: path.to_path_buf(),
                id: row.id,
                first: first.row,
                second: i + 1,
            });
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The cells of one manifest line, each trimmed.
fn csv_cells(line: &str) -> Vec<String> {
    crate::report::table::csv_fields(line)
        .into_iter()
        .map(|c| c.trim().to_string())
        .collect()
}

fn csv_records(path: &Path, text: &str) -> Result<Vec<Record>, ManifestError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((_, header)) = lines.next() else {
        return Ok(vec![]);
    };
    let header = csv_cells(header);
    for h in &header {
        known(path, h)?;
    }
    lines
        .map(|(n, line)| {
            let cells = csv_cells(line);
            if cells.len() != header.len() {
                return Err(ManifestError::Cells {
                    path: path.to_path_buf(),
                    line: n + 1,
                    found: cells.len(),
                    expected: header.len(),
                });
            }
            Ok(header.iter().cloned().zip(cells).collect())
        })
        .collect()
}

fn json_records(path: &Path, text: &str) -> Result<Vec<Record>, ManifestError> {
    let bad = |message: String| ManifestError::Json {
        path: path.to_path_buf(),
        message,
    };
    let v: serde_json::Value =
        serde_json::from_str(text).map_err(|source| ManifestError::JsonSyntax {
            path: path.to_path_buf(),
            source,
        })?;
    let list = match &v {
        serde_json::Value::Array(a) => a,
        serde_json::Value::Object(o) => match o.get("trials") {
            Some(serde_json::Value::Array(a)) => a,
            _ => {
                return Err(bad(
                    "expected an array of trials or {\"trials\": [...]}".into()
                ))
            }
        },
        _ => {
            return Err(bad(
                "expected an array of trials or {\"trials\": [...]}".into()
            ))
        }
    };
    let mut out = Vec::new();
    for (i, item) in list.iter().enumerate() {
        let serde_json::Value::Object(o) = item else {
            return Err(bad(format!("trial {} is not an object", i + 1)));
        };
        let mut rec = Record::new();
        for (k, v) in o {
            known(path, k)?;
            let text = match v {
                serde_json::Value::String(s) => s.clone(),
                serde_json::Value::Array(a) => a
                    .iter()
                    .map(|x| x.as_str().map_or(x.to_string(), str::to_string))
                    .collect::<Vec<_>>()
                    .join(";"),
                serde_json::Value::Null => String::new(),
                other => other.to_string(),
            };
            rec.push((k.clone(), text));
        }
        out.push(rec);
    }
    Ok(out)
}

fn known(path: &Path, field: &str) -> Result<(), ManifestError> {
    if FIELDS.contains(&field) {
        Ok(())
    } else {
        Err(ManifestError::UnknownField {
            path: path.to_path_buf(),
            field: field.to_string(),
        })
    }
}

/// One record's fields, with the row they are on for the errors.
struct Fields<'a> {
    path: &'a Path,
    row: usize,
    rec: &'a Record,
}

impl Fields<'_> {
    /// A field's value (`None` when absent or empty).
    fn get(&self, f: &str) -> Option<&str> {
        self.rec
            .iter()
            .find(|(k, _)| k == f)
            .map(|(_, v)| v.as_str())
            .filter(|v| !v.is_empty())
    }

    fn refuse(&self, field: &'static str, value: &str, expected: &str) -> ManifestError {
        ManifestError::Value {
            path: self.path.to_path_buf(),
            row: self.row,
            field,
            value: value.to_string(),
            expected: expected.to_string(),
        }
    }

    /// A positive finite number.
    fn number(&self, field: &'static str) -> Result<Option<f64>, ManifestError> {
        self.get(field)
            .map(|v| {
                v.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite() && *x > 0.0)
                    .ok_or_else(|| self.refuse(field, v, "is not a positive finite number"))
            })
            .transpose()
    }

    /// true/yes/1 or false/no/0 (absent: false).
    fn flag(&self, field: &'static str) -> Result<bool, ManifestError> {
        match self.get(field).map(str::to_ascii_lowercase).as_deref() {
            None | Some("false") | Some("no") | Some("0") => Ok(false),
            Some("true") | Some("yes") | Some("1") => Ok(true),
            Some(other) => Err(self.refuse(field, other, "is not true or false")),
        }
    }

    /// An iteration count from 1 to 100000.
    fn count(&self, field: &'static str) -> Result<Option<usize>, ManifestError> {
        self.get(field)
            .map(|v| {
                v.parse::<usize>()
                    .ok()
                    .filter(|n| (1..=100_000).contains(n))
                    .ok_or_else(|| {
                        self.refuse(field, v, "is not an iteration count from 1 to 100000")
                    })
            })
            .transpose()
    }

    /// `r=…`/`l=…` items separated by `;` or spaces.
    fn plates(&self) -> Result<Vec<String>, ManifestError> {
        let items = self.get("plate").map_or(vec![], |p| {
            p.split([';', ' ']).filter(|s| !s.is_empty()).collect()
        });
        items
            .into_iter()
            .map(|p| {
                if p.starts_with("r=") || p.starts_with("l=") {
                    Ok(p.to_string())
                } else {
                    Err(self.refuse(
                        "plate",
                        p,
                        "is not FOOT=PREFIX or FOOT=N with FOOT r or l (several separated by ';')",
                    ))
                }
            })
            .collect()
    }

    /// The id given, or `row-N` (zero-padded to `width` digits).
    fn id(&self, width: usize) -> Result<String, ManifestError> {
        match self.get("id") {
            Some(id) if valid_id(id) => Ok(id.to_string()),
            Some(id) => Err(self.refuse("id", id, "is not a folder name: use letters, digits, '.', '_', '+', '-', not starting with '.'")),
            None => Ok(format!("row-{:0width$}", self.row)),
        }
    }
}

/// One record as a trial row.
fn row_of(
    path: &Path,
    base: &Path,
    row: usize,
    width: usize,
    rec: &Record,
) -> Result<TrialRow, ManifestError> {
    let f = Fields { path, row, rec };
    let data = f.get("data").ok_or_else(|| {
        f.refuse("data", "", "is missing: each trial needs its trial file (a sagittal CSV or OpenSim inverse kinematics)")
    })?;
    let text = |k: &str| f.get(k).unwrap_or("").to_string();
    Ok(TrialRow {
        row,
        id: f.id(width)?,
        subject: text("subject"),
        session: text("session"),
        condition: text("condition"),
        files: TrialFiles {
            data: Some(resolve(base, data)),
            forces: f.get("forces").map(|p| resolve(base, p)),
            plates: f.plates()?,
            lab_axes: f.get("lab_axes").map(str::to_string),
            belt_speed: f.number("belt_speed")?,
            overground: f.flag("overground")?,
        },
        model: resolve(base, f.get("model").unwrap_or(DEFAULT_MODEL)),
        foot: f.get("foot").unwrap_or("ellipse").to_string(),
        cutoff_hz: f.number("cutoff")?,
        max_iter: f.count("max_iter")?,
        kinematics_cutoff: f.number("kinematics_cutoff")?,
    })
}

/// Whether `id` is a safe folder name.
fn valid_id(id: &str) -> bool {
    !id.starts_with('.')
        && id.len() <= 100
        && id
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "._+-".contains(c))
}

/// A manifest's path: relative to the manifest's folder where the file is there, else as
/// given.
fn resolve(base: &Path, p: &str) -> PathBuf {
    let given = PathBuf::from(p);
    if given.is_absolute() {
        return given;
    }
    let beside = base.join(&given);
    if beside.exists() {
        beside
    } else {
        given
    }
}
