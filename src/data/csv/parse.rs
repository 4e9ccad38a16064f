//! Reading a sagittal CSV's text (the schema of the parent module): its header and
//! columns, its numbers and their checks, and the split of a mixed-rate file into
//! kinematic rows and the force record.

use super::Units;
use crate::data::error::DataError;
use crate::data::storage::check_time;
use crate::data::{FootData, ForceSamples, GaitData, SideSource, Q_NAMES};
use std::collections::BTreeMap;
use std::path::Path;

/// A file's numbers by column: `table[j][k]` is column `j` at row `k`.
type Table = Vec<Vec<f64>>;

/// Where the schema's columns are in a sagittal CSV's header (indices into `names`).
struct Columns {
    /// The header's column names, in file order.
    names: Vec<String>,
    /// The header's row in the file (1-based).
    header_row: usize,
    /// `time`.
    time: usize,
    /// The coordinates in [`Q_NAMES`] order; `usize::MAX` for those of a side left out.
    q: [usize; 9],
    /// Each side's six columns (`hip`, `knee`, `ankle`, `grf_x`, `grf_y`, `cop_x`), if
    /// given.
    sides: [Option<[usize; 6]>; 2],
    /// The columns beyond the schema's.
    extra: Vec<usize>,
}

fn foot_columns(side: &str) -> [String; 6] {
    [
        format!("hip_{side}"),
        format!("knee_{side}"),
        format!("ankle_{side}"),
        format!("grf_x_{side}"),
        format!("grf_y_{side}"),
        format!("cop_x_{side}"),
    ]
}

/// A header that is one column holding semicolons or tabs: the file is separated by
/// those, and footfall reads commas.
fn check_separator(header: &str, row: usize, path: &Path) -> Result<(), DataError> {
    if header.contains(',') {
        return Ok(());
    }
    let Some((sep, name)) = [(';', "semicolons"), ('\t', "tabs")]
        .into_iter()
        .find(|(c, _)| header.contains(*c))
    else {
        return Ok(());
    };
    let first: Vec<&str> = header.split(sep).take(3).collect();
    Err(DataError::Format {
        path: path.to_path_buf(),
        row,
        reason: format!(
            "the header ('{}{sep}…') is separated by {name}; footfall reads comma-separated values ('time,pelvis_x,…' with '.' as the decimal point): save the file with commas",
            first.join(&sep.to_string())
        ),
    })
}

pub(super) fn parse_sagittal_csv(
    text: &str,
    path: &Path,
    cop_threshold: f64,
    units: Units,
) -> Result<GaitData, DataError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let (header_row, names) = read_header(lines.next(), path)?;
    let cols = Columns::locate(names, header_row, path)?;
    let (table, rows) = read_rows(lines, &cols, path)?;
    check_force_range(&table, &rows, &cols, path)?;
    // an extra channel with no value in any row (lower-body Plug-in Gait output has no
    // trunk: lumbar_extension all NaN) is not read; one with gaps keeps its NaN: the
    // model reads no extra channel, so neither decides a row's kind
    let empty: Vec<usize> = cols
        .extra
        .iter()
        .copied()
        .filter(|&j| table[j].iter().all(|v| v.is_nan()))
        .collect();
    let force_only = force_only_rows(&table, &rows, &cols, path)?;
    // A mixed-rate file: kinematic rows and force-only rows (forces at their own rate).
    let (table, rows, force_record) = if force_only.iter().any(|&f| f) {
        let (kt, kr, record) = split_mixed_rate(&table, &rows, &force_only, &cols, units, path)?;
        (kt, kr, Some(record))
    } else {
        (table, rows, None)
    };
    let time: Vec<f64> = table[cols.time].iter().map(|t| t * units.time).collect();
    check_time(&time, &rows, "time", path)?;

    let q = coordinates(&table, &cols, units, time.len());
    let (mut feet, sides) = measured_feet(&table, &cols, units, time.len());
    if let Some(rec) = &force_record {
        feet = std::array::from_fn(|s| rec.resample_foot(s, &time));
    }
    let extra = extra_channels(&table, &cols, &empty, units);
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = stem.strip_suffix("_sagittal").unwrap_or(&stem).to_string();
    Ok(GaitData {
        events: None,
        name,
        source: path.to_path_buf(),
        time,
        q,
        feet,
        forces: force_record,
        extra,
        body_mass: None,
        force_plate_height: None,
        belt_speed: None,
        cop_threshold,
        sides,
        overground: false,
    })
}

/// The header's row and column names, from the first line that is neither blank nor a
/// comment; an empty file, a file not separated by commas and a repeated column are
/// errors.
fn read_header(
    first: Option<(usize, &str)>,
    path: &Path,
) -> Result<(usize, Vec<String>), DataError> {
    let (header_row, header) = first.ok_or_else(|| DataError::Format {
        path: path.to_path_buf(),
        row: 1,
        reason: "the file is empty; expected a header row 'time,pelvis_x,…'".into(),
    })?;
    let header = header.trim_start_matches('\u{feff}');
    check_separator(header, header_row, path)?;
    let cols: Vec<String> = header
        .split(',')
        .map(|c| c.trim().trim_matches('"').to_string())
        .collect();
    for (j, c) in cols.iter().enumerate() {
        if cols[..j].contains(c) {
            return Err(DataError::DuplicateColumn {
                path: path.to_path_buf(),
                row: header_row,
                column: c.clone(),
            });
        }
    }
    Ok((header_row, cols))
}

impl Columns {
    /// The schema's columns among `names`: `time` and the pelvis coordinates are needed,
    /// and of each side all six columns or none (not none of both sides).
    fn locate(names: Vec<String>, header_row: usize, path: &Path) -> Result<Self, DataError> {
        let find = |name: &str| names.iter().position(|c| c == name);
        let missing = |name: &str, reason: String| DataError::MissingColumn {
            path: path.to_path_buf(),
            row: header_row,
            column: name.to_string(),
            reason,
        };
        let t_col = find("time").ok_or_else(|| missing("time", "the sample times (s)".into()))?;
        let mut q_cols = [usize::MAX; 9];
        for i in [0, 1, 2] {
            q_cols[i] = find(Q_NAMES[i]).ok_or_else(|| {
                missing(
                    Q_NAMES[i],
                    "a pelvis coordinate of the sagittal schema".into(),
                )
            })?;
        }
        let mut side_cols: [Option<[usize; 6]>; 2] = [None, None];
        for (s, side) in ["r", "l"].iter().enumerate() {
            let names = foot_columns(side);
            let found: Vec<Option<usize>> = names.iter().map(|n| find(n)).collect();
            if found.iter().all(Option::is_some) {
                side_cols[s] = Some(std::array::from_fn(|k| found[k].unwrap_or_default()));
            } else if let Some(k) = found.iter().position(Option::is_some) {
                let absent = found.iter().position(Option::is_none).unwrap_or_default();
                return Err(missing(
                    &names[absent],
                    format!(
                        "'{}' is present, so all six columns of that side are needed ({}); leave all six out if the side was not measured",
                        names[k],
                        names.join(", ")
                    ),
                ));
            }
        }
        if side_cols.iter().all(Option::is_none) {
            return Err(missing(
                "hip_r",
                "neither leg is in the file; at least one side's six columns are needed".into(),
            ));
        }
        for s in 0..2 {
            if let Some(c) = side_cols[s] {
                q_cols[3 + 3 * s..6 + 3 * s].copy_from_slice(&c[..3]);
            }
        }
        let known: Vec<usize> = std::iter::once(t_col)
            .chain(q_cols.iter().copied().filter(|&c| c != usize::MAX))
            .chain(side_cols.iter().flatten().flat_map(|c| c.iter().copied()))
            .collect();
        let extra_cols: Vec<usize> = (0..names.len()).filter(|j| !known.contains(j)).collect();
        Ok(Self {
            names,
            header_row,
            time: t_col,
            q: q_cols,
            sides: side_cols,
            extra: extra_cols,
        })
    }

    /// The ground-load columns of the sides given: `grf_x`, `grf_y`, `cop_x`.
    fn load(&self) -> Vec<usize> {
        self.sides
            .iter()
            .flatten()
            .flat_map(|c| c[3..6].iter().copied())
            .collect()
    }
}

/// Every data row's numbers, by column, and each row's line in the file (1-based); a row
/// of the wrong length, a field that is not a number and fewer than two rows are errors.
fn read_rows<'a>(
    lines: impl Iterator<Item = (usize, &'a str)>,
    cols: &Columns,
    path: &Path,
) -> Result<(Table, Vec<usize>), DataError> {
    let p = path.to_path_buf();
    let ncol = cols.names.len();
    let mut table = vec![Vec::new(); ncol];
    let mut rows = Vec::new();
    for (row, line) in lines {
        let fields: Vec<&str> = line.split(',').collect();
        DataError::check_row_length(&p, row, ncol, fields.len())?;
        for (j, f) in fields.iter().enumerate() {
            let t = f.trim();
            let refused = |reason: String| DataError::Parse {
                path: p.clone(),
                row,
                column: cols.names[j].clone(),
                text: t.to_string(),
                reason,
            };
            if t.is_empty() {
                return Err(refused(
                    "empty field (write NaN for a missing value)".to_string(),
                ));
            }
            let v = t.parse::<f64>().map_err(|e| refused(e.to_string()))?;
            table[j].push(v);
        }
        rows.push(row);
    }
    if rows.len() < 2 {
        return Err(DataError::Format {
            path: p,
            row: cols.header_row,
            reason: format!("{} data row(s); at least two are needed", rows.len()),
        });
    }
    Ok((table, rows))
}

/// Ground forces beyond any walker's are an error (forces are always in N).
fn check_force_range(
    table: &[Vec<f64>],
    rows: &[usize],
    cols: &Columns,
    path: &Path,
) -> Result<(), DataError> {
    for &j in cols.sides.iter().flatten().flat_map(|c| &c[3..5]) {
        if let Some(k) = table[j]
            .iter()
            .position(|v| v.abs() > crate::limits::MAX_FORCE)
        {
            return Err(DataError::OutOfRange {
                path: path.to_path_buf(),
                row: rows[k],
                column: cols.names[j].clone(),
                value: table[j][k],
                limit: crate::limits::MAX_FORCE,
                unit: "N",
            });
        }
    }
    Ok(())
}

/// Which rows are force-only (every coordinate NaN), once every value is checked. NaN:
/// in forces and CoP it means "not measured" (off the plates, a CoP the lab did not
/// export); in an extra column a gap; in the coordinates only in force-only rows of a
/// mixed-rate file (every coordinate NaN). ∞ nowhere.
fn force_only_rows(
    table: &[Vec<f64>],
    rows: &[usize],
    cols: &Columns,
    path: &Path,
) -> Result<Vec<bool>, DataError> {
    let load_cols = cols.load();
    let kin_cols: Vec<usize> = (0..cols.names.len())
        .filter(|j| *j != cols.time && !load_cols.contains(j) && !cols.extra.contains(j))
        .collect();
    let force_only: Vec<bool> = (0..rows.len())
        .map(|k| kin_cols.iter().all(|&j| table[j][k].is_nan()))
        .collect();
    for (j, col) in table.iter().enumerate() {
        let may_be_nan = load_cols.contains(&j) || cols.extra.contains(&j);
        for (k, &v) in col.iter().enumerate() {
            if v.is_finite() || (v.is_nan() && (may_be_nan || force_only[k])) {
                continue;
            }
            let reason = if v.is_nan() {
                "value is NaN; NaN is allowed in grf_* and cop_x_* (not measured), in extra columns such as lumbar_extension (which the model does not read), and in the coordinates only in a force-only row of a mixed-rate file (every coordinate NaN)".to_string()
            } else {
                format!("value is {v}; NaN marks a value that was not measured")
            };
            return Err(DataError::NotFinite {
                path: path.to_path_buf(),
                row: rows[k],
                column: cols.names[j].clone(),
                reason,
            });
        }
    }
    Ok(force_only)
}

/// A mixed-rate file's kinematic rows (their numbers by column and their lines) and its
/// force record: the forces at the force-only rows and at the kinematic rows that carry
/// a force (N, CoP in m, times in s). Fewer than two kinematic rows are an error.
fn split_mixed_rate(
    table: &[Vec<f64>],
    rows: &[usize],
    force_only: &[bool],
    cols: &Columns,
    units: Units,
    path: &Path,
) -> Result<(Table, Vec<usize>, ForceSamples), DataError> {
    let load_cols = cols.load();
    let all_time: Vec<f64> = table[cols.time].iter().map(|t| t * units.time).collect();
    check_time(&all_time, rows, "time", path)?;
    // force instants: force-only rows, and kinematic rows that carry a force
    let frows: Vec<usize> = (0..rows.len())
        .filter(|&k| force_only[k] || load_cols.iter().any(|&j| table[j][k].is_finite()))
        .collect();
    let pick = |j: usize, f: f64, idx: &[usize]| -> Vec<f64> {
        idx.iter().map(|&k| table[j][k] * f).collect()
    };
    let n = frows.len();
    let record = ForceSamples {
        time: frows.iter().map(|&k| all_time[k]).collect(),
        feet: std::array::from_fn(|s| match cols.sides[s] {
            Some(c) => FootData {
                fx: pick(c[3], 1.0, &frows),
                fy: pick(c[4], 1.0, &frows),
                cop_x: pick(c[5], units.position, &frows),
            },
            None => FootData {
                fx: vec![f64::NAN; n],
                fy: vec![f64::NAN; n],
                cop_x: vec![f64::NAN; n],
            },
        }),
    };
    let krows: Vec<usize> = (0..rows.len()).filter(|&k| !force_only[k]).collect();
    if krows.len() < 2 {
        return Err(DataError::Format {
            path: path.to_path_buf(),
            row: cols.header_row,
            reason: format!(
                "{} kinematic row(s) (rows whose kinematic columns are not all NaN); at least two are needed",
                krows.len()
            ),
        });
    }
    let kt: Table = table
        .iter()
        .map(|col| krows.iter().map(|&k| col[k]).collect())
        .collect();
    let kr: Vec<usize> = krows.iter().map(|&k| rows[k]).collect();
    Ok((kt, kr, record))
}

/// A column times `f`.
fn scaled(col: &[f64], f: f64) -> Vec<f64> {
    col.iter().map(|v| v * f).collect()
}

/// The nine coordinates of the `n` rows (m and rad); NaN for those of a side left out.
fn coordinates(table: &[Vec<f64>], cols: &Columns, units: Units, n: usize) -> [Vec<f64>; 9] {
    let mut q: [Vec<f64>; 9] = Default::default();
    for i in 0..9 {
        let f = if i < 2 { units.position } else { units.angle };
        q[i] = if cols.q[i] == usize::MAX {
            vec![f64::NAN; n]
        } else {
            scaled(&table[cols.q[i]], f)
        };
    }
    q
}

/// Each foot's forces (N) and CoP (m) at the `n` rows, and which sides the file gives
/// (NaN for a side left out).
fn measured_feet(
    table: &[Vec<f64>],
    cols: &Columns,
    units: Units,
    n: usize,
) -> ([FootData; 2], [SideSource; 2]) {
    let mut feet: [FootData; 2] = Default::default();
    let mut sides = [SideSource::Missing; 2];
    for s in 0..2 {
        feet[s] = match cols.sides[s] {
            Some(c) => {
                sides[s] = SideSource::Measured;
                FootData {
                    fx: scaled(&table[c[3]], 1.0),
                    fy: scaled(&table[c[4]], 1.0),
                    cop_x: scaled(&table[c[5]], units.position),
                }
            }
            None => FootData {
                fx: vec![f64::NAN; n],
                fy: vec![f64::NAN; n],
                cop_x: vec![f64::NAN; n],
            },
        };
    }
    (feet, sides)
}

/// The extra columns by name, except the `empty` ones; `hip_center_*` in m,
/// `lumbar_extension` in rad, any other as written.
fn extra_channels(
    table: &[Vec<f64>],
    cols: &Columns,
    empty: &[usize],
    units: Units,
) -> BTreeMap<String, Vec<f64>> {
    cols.extra
        .iter()
        .filter(|j| !empty.contains(j))
        .map(|&j| {
            let f = match cols.names[j].as_str() {
                "hip_center_x" | "hip_center_y" => units.position,
                "lumbar_extension" => units.angle,
                _ => 1.0,
            };
            (cols.names[j].clone(), scaled(&table[j], f))
        })
        .collect()
}
