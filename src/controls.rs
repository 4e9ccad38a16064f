//! Control trajectories for forward simulation: a table of control values at knot times,
//! interpolated piecewise linearly (held constant outside the table).

use crate::model::ModelError;
use std::path::Path;

/// Why a control table built in code is refused ([`ControlTable::validate`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ControlsError {
    /// No knot, or not one value row per knot time.
    #[error("{times} knot times but {rows} value rows (need at least one)")]
    Knots {
        /// Number of knot times.
        times: usize,
        /// Number of value rows.
        rows: usize,
    },
    /// A knot time is not finite or not larger than the previous one.
    #[error("knot {knot}: time {time} is not finite or not increasing")]
    Time {
        /// Index of the knot (0-based).
        knot: usize,
        /// Its time (s).
        time: f64,
    },
    /// A knot's value row does not hold one value per control name.
    #[error("knot {knot}: {values} values for {controls} controls")]
    RowLength {
        /// Index of the knot (0-based).
        knot: usize,
        /// Number of values in its row.
        values: usize,
        /// Number of control names.
        controls: usize,
    },
    /// A control value is NaN or infinite.
    #[error("knot {knot}: control `{control}` is not finite")]
    NotFinite {
        /// Index of the knot (0-based).
        knot: usize,
        /// Name of the control.
        control: String,
    },
}

/// Piecewise-linear control table.
#[derive(Debug, Clone, PartialEq)]
pub struct ControlTable {
    /// Control names, in model order.
    pub names: Vec<String>,
    /// Knot times (s), strictly increasing.
    pub times: Vec<f64>,
    /// `values[k]` = controls at `times[k]`, in model order.
    pub values: Vec<Vec<f64>>,
}

impl ControlTable {
    /// The same controls at all times.
    pub fn constant(names: Vec<String>, values: Vec<f64>) -> Self {
        Self {
            names,
            times: vec![0.0],
            values: vec![values],
        }
    }

    /// Read a CSV file with a header `time,<control names…>`; columns may come in any order
    /// but every name in `model_controls` must be present exactly once and no other.
    pub fn load_csv(path: &Path, model_controls: &[String]) -> Result<Self, ModelError> {
        let path = &crate::bundled::resolve(path);
        let text = std::fs::read_to_string(path).map_err(|source| ModelError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse_csv(&text, path, model_controls)
    }

    /// As [`load_csv`](Self::load_csv), refusing a value outside its control's range:
    /// `ranges[i]` = `(low, high, what)` for `model_controls[i]` (e.g. `(0, 1,
    /// "an excitation")`), `None` for a control without one.
    pub fn load_csv_within(
        path: &Path,
        model_controls: &[String],
        ranges: &[Option<(f64, f64, &str)>],
    ) -> Result<Self, ModelError> {
        let path = &crate::bundled::resolve(path);
        let text = std::fs::read_to_string(path).map_err(|source| ModelError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse_csv_within(&text, path, model_controls, ranges)
    }

    /// Parse CSV text (see [`load_csv`](Self::load_csv)).
    pub fn parse_csv(
        text: &str,
        path: &Path,
        model_controls: &[String],
    ) -> Result<Self, ModelError> {
        Self::parse_csv_within(text, path, model_controls, &[])
    }

    /// Parse CSV text with control ranges (see [`load_csv_within`](Self::load_csv_within)).
    pub fn parse_csv_within(
        text: &str,
        path: &Path,
        model_controls: &[String],
        ranges: &[Option<(f64, f64, &str)>],
    ) -> Result<Self, ModelError> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
        let (_, header) = lines.next().ok_or_else(|| {
            ModelError::invalid(
                path,
                "header",
                "the file is empty; expected a header `time,<control names>`",
            )
        })?;
        let cols: Vec<&str> = header.split(',').map(str::trim).collect();
        if cols.first() != Some(&"time") {
            return Err(ModelError::invalid(
                path,
                "header",
                format!("first column must be `time`, found `{}`", cols[0]),
            ));
        }
        let mut index = Vec::new();
        for name in model_controls {
            let found: Vec<usize> = cols
                .iter()
                .enumerate()
                .filter(|(_, c)| *c == name)
                .map(|(i, _)| i)
                .collect();
            match found.len() {
                1 => index.push(found[0]),
                0 => {
                    return Err(ModelError::invalid(
                        path,
                        "header",
                        format!(
                            "missing control column `{name}`; the model's controls are: {}",
                            model_controls.join(", ")
                        ),
                    ))
                }
                _ => {
                    return Err(ModelError::invalid(
                        path,
                        "header",
                        format!("column `{name}` appears twice"),
                    ))
                }
            }
        }
        if let Some(extra) = cols[1..]
            .iter()
            .find(|c| !model_controls.iter().any(|m| m == *c))
        {
            return Err(ModelError::invalid(
                path,
                "header",
                format!(
                    "unknown column `{extra}`; the model's controls are: {}",
                    model_controls.join(", ")
                ),
            ));
        }
        let mut times = Vec::new();
        let mut values = Vec::new();
        for (ln, line) in lines {
            let row: Vec<&str> = line.split(',').map(str::trim).collect();
            let field = |c: usize| format!("row at line {}, column `{}`", ln + 1, cols[c]);
            if row.len() != cols.len() {
                return Err(ModelError::invalid(
                    path,
                    format!("line {}", ln + 1),
                    format!("has {} values, the header has {}", row.len(), cols.len()),
                ));
            }
            let parse = |c: usize| -> Result<f64, ModelError> {
                if row[c].is_empty() {
                    return Err(ModelError::invalid(
                        path,
                        field(c),
                        "the cell is empty; expected a number",
                    ));
                }
                let v: f64 = row[c].parse().map_err(|_| {
                    ModelError::invalid(path, field(c), format!("`{}` is not a number", row[c]))
                })?;
                if !v.is_finite() {
                    return Err(ModelError::invalid(
                        path,
                        field(c),
                        format!("must be finite, got `{}`", row[c]),
                    ));
                }
                Ok(v)
            };
            let t = parse(0)?;
            if let Some(&last) = times.last() {
                if t <= last {
                    return Err(ModelError::invalid(
                        path,
                        field(0),
                        format!("time {t} does not increase (previous {last}); times must be strictly increasing"),
                    ));
                }
            }
            times.push(t);
            let row_values = index
                .iter()
                .map(|&c| parse(c))
                .collect::<Result<Vec<_>, _>>()?;
            for (i, (&v, &c)) in row_values.iter().zip(&index).enumerate() {
                if let Some(Some((lo, hi, what))) = ranges.get(i) {
                    if v < *lo || v > *hi {
                        return Err(ModelError::invalid(
                            path,
                            field(c),
                            format!("{v} is outside [{lo}, {hi}], the range of {what}"),
                        ));
                    }
                }
            }
            values.push(row_values);
        }
        if times.is_empty() {
            return Err(ModelError::invalid(
                path,
                "rows",
                "no data rows after the header",
            ));
        }
        Ok(Self {
            names: model_controls.to_vec(),
            times,
            values,
        })
    }

    /// Controls at time `t` (piecewise linear, constant outside the table).
    ///
    /// A table built by hand with fewer values than `out` leaves the remaining entries of
    /// `out` unchanged (see [`validate`](Self::validate)); an empty table leaves all.
    pub fn at(&self, t: f64, out: &mut [f64]) {
        let n = self.times.len().min(self.values.len());
        if n == 0 {
            return;
        }
        let k = self.times[..n].partition_point(|&s| s <= t);
        let copy = |out: &mut [f64], v: &[f64]| out.iter_mut().zip(v).for_each(|(o, x)| *o = *x);
        if k == 0 {
            copy(out, &self.values[0]);
        } else if k == n {
            copy(out, &self.values[n - 1]);
        } else {
            let (t0, t1) = (self.times[k - 1], self.times[k]);
            let w = (t - t0) / (t1 - t0);
            for ((o, a), b) in out.iter_mut().zip(&self.values[k - 1]).zip(&self.values[k]) {
                *o = (1.0 - w) * a + w * b;
            }
        }
    }

    /// Check a table built in code: at least one knot, strictly increasing finite times, and
    /// one finite value per name at every knot.
    pub fn validate(&self) -> Result<(), ControlsError> {
        if self.times.is_empty() || self.times.len() != self.values.len() {
            return Err(ControlsError::Knots {
                times: self.times.len(),
                rows: self.values.len(),
            });
        }
        for (k, (t, v)) in self.times.iter().zip(&self.values).enumerate() {
            if !t.is_finite() || (k > 0 && *t <= self.times[k - 1]) {
                return Err(ControlsError::Time { knot: k, time: *t });
            }
            if v.len() != self.names.len() {
                return Err(ControlsError::RowLength {
                    knot: k,
                    values: v.len(),
                    controls: self.names.len(),
                });
            }
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(ControlsError::NotFinite {
                    knot: k,
                    control: self.names[i].clone(),
                });
            }
        }
        Ok(())
    }

    /// Knot times strictly inside `(t0, t1)`, where the interpolant has kinks.
    pub fn knots_within(&self, t0: f64, t1: f64) -> Vec<f64> {
        self.times
            .iter()
            .copied()
            .filter(|&t| t > t0 && t < t1)
            .collect()
    }
}
