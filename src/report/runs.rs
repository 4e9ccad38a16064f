//! Runs side by side: the curves of several `track` or `predict` run folders on the same
//! plots (one colour per run, the first run's measurement dashed in black) with their
//! error tables next to each other: before and after adding an effect, or one foot
//! against another.
//!
//! Each run is read from its files alone (`summary.json` and `fine_grid.csv`, else the
//! node table `tracking.csv`/`prediction.csv`), so nothing is solved or re-evaluated.

use super::diff::RunSummary;
use super::gait_figures::{channel_plots, ChannelPlot, CycleAxis};
use super::html::{Report, Section, Summary, Tone};
use super::plot::{LinePlot, LineStyle, Series, Span};
use super::table::Table;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Failure to read a run for the side-by-side report; names the file and what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {reason}")]
pub struct RunReadError {
    /// The file at fault.
    pub path: PathBuf,
    /// What is wrong and what would be valid.
    pub reason: String,
}

/// One run's curves and figures.
#[derive(Debug, Clone)]
pub struct RunCurves {
    /// Its folder's name.
    pub name: String,
    /// The verdict it recorded (`converged`, `not converged`, …).
    pub verdict: String,
    /// The errors it recorded.
    pub summary: RunSummary,
    /// Sample times (s).
    pub time: Vec<f64>,
    /// Numeric columns by name (NaN where empty).
    pub columns: BTreeMap<String, Vec<f64>>,
    /// Percent of the gait cycle.
    pub cycle: CycleAxis,
    /// Continuous phases `(start s, end s, name)`.
    pub phases: Vec<(f64, f64, String)>,
}

fn err(path: &Path, reason: impl Into<String>) -> RunReadError {
    RunReadError {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Numeric columns of a CSV written by footfall (first column time; text columns and
/// empty cells become NaN).
/// Times and numeric columns by name.
type Columns = (Vec<f64>, BTreeMap<String, Vec<f64>>);

fn read_csv(path: &Path) -> Result<Columns, RunReadError> {
    let text = std::fs::read_to_string(path).map_err(|e| err(path, e.to_string()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .ok_or_else(|| err(path, "empty file"))?
        .split(',')
        .collect();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); header.len()];
    for (row, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != header.len() {
            return Err(err(
                path,
                format!(
                    "line {}: {} fields, the header has {}",
                    row + 2,
                    cells.len(),
                    header.len()
                ),
            ));
        }
        for (c, cell) in cells.iter().enumerate() {
            cols[c].push(cell.trim().parse::<f64>().unwrap_or(f64::NAN));
        }
    }
    let time = cols.first().cloned().unwrap_or_default();
    if time.iter().any(|t| !t.is_finite()) {
        return Err(err(
            path,
            "the first column (time) has a value that is not a number",
        ));
    }
    Ok((
        time,
        header
            .iter()
            .map(|h| h.trim_matches('"').to_string())
            .zip(cols)
            .skip(1)
            .collect(),
    ))
}

impl RunCurves {
    /// Read the run folder `dir`.
    pub fn read(dir: &Path) -> Result<Self, RunReadError> {
        let summary =
            RunSummary::read(dir).map_err(|e| err(&dir.join("summary.json"), e.to_string()))?;
        let sp = dir.join("summary.json");
        let file =
            super::run_summary::RunSummaryFile::read(&sp).map_err(|e| err(&sp, e.to_string()))?;
        let window = match file.window_s {
            Some([a, b]) => (a, b),
            None => return Err(err(&sp, "field `window_s`: missing (a run folder written by `track` or `predict` has it: [start, end] in seconds)")),
        };
        let cycle = match file.gait_cycle {
            Some(c) if c.period_s > 0.0 => CycleAxis {
                period: c.period_s,
                heel_strike: c.heel_strike_s,
            },
            Some(_) => {
                return Err(err(
                    &sp,
                    "field `gait_cycle.period_s`: expected a period > 0 s",
                ))
            }
            // runs written before the field: their window is a half cycle from a left heel strike
            None => {
                let period = 2.0 * (window.1 - window.0);
                CycleAxis {
                    period,
                    heel_strike: [window.0 - period / 2.0, window.0],
                }
            }
        };
        let phases = file
            .phase_spans
            .iter()
            .map(|p| (p.from_s, p.to_s, p.phase.clone()))
            .collect();
        let csv = ["fine_grid.csv", "tracking.csv", "prediction.csv"]
            .iter()
            .map(|n| dir.join(n))
            .find(|p| p.is_file())
            .ok_or_else(|| err(dir, "no fine_grid.csv, tracking.csv or prediction.csv: not a run folder of `track` or `predict`"))?;
        let (time, columns) = read_csv(&csv)?;
        Ok(Self {
            name: summary.name.clone(),
            verdict: file
                .verdict
                .clone()
                .or_else(|| summary.status.clone())
                .unwrap_or_else(|| "unknown".to_string()),
            summary,
            time,
            columns,
            cycle,
            phases,
        })
    }

    fn column(&self, name: &str) -> Option<&[f64]> {
        self.columns.get(name).map(|v| v.as_slice())
    }
}

/// The side-by-side report of `runs` (at least one).
pub fn side_by_side(runs: &[RunCurves]) -> Report {
    let all_converged = runs.iter().all(|r| r.verdict == "converged");
    let mut summary = Summary::new(
        format!("{} runs side by side", runs.len()),
        if all_converged {
            Tone::Neutral
        } else {
            Tone::Warning
        },
        if all_converged {
            "every run converged".to_string()
        } else {
            "not every run converged: its curves are marked".to_string()
        },
    );
    summary.extra = runs
        .iter()
        .map(|r| {
            (
                r.name.clone(),
                format!("{}; {}", r.verdict, r.summary.describe()),
            )
        })
        .collect();
    // the channels of a run's own report, each angle beside its velocity, then the loads
    let [angles, velocities, loads] = channel_plots();
    let channels: Vec<&ChannelPlot> = angles
        .iter()
        .zip(&velocities)
        .flat_map(|(a, v)| [a, v])
        .chain(&loads)
        .collect();
    let first = &runs[0];
    let lead = first.cycle.lead_side((
        first.time.first().copied().unwrap_or(0.0),
        first.time.last().copied().unwrap_or(0.0),
    ));
    let mut svgs = Vec::new();
    for cp in channels {
        let sides: Vec<usize> = if cp.bilateral { vec![0, 1] } else { vec![lead] };
        let col = |r: &RunCurves, who: &str, s: usize| -> Option<Vec<f64>> {
            r.column(&cp.csv_column(who, cp.bilateral.then_some(s)))
                .map(|v| v.iter().map(|x| x * cp.scale).collect())
        };
        let mut p = LinePlot::new(
            cp.title.as_str(),
            if cp.bilateral {
                "% of gait cycle (each leg from its heel strike)"
            } else {
                "% of gait cycle"
            },
            cp.unit,
        );
        let mut any = false;
        for (k, r) in runs.iter().enumerate() {
            let label = if r.verdict == "converged" {
                r.name.clone()
            } else {
                format!("{} ({})", r.name, r.verdict)
            };
            for (i, &s) in sides.iter().enumerate() {
                if let Some(v) = col(r, "model", s) {
                    let x = r.time.iter().map(|&t| r.cycle.percent(s, t)).collect();
                    p.series.push(
                        Series::new(
                            if i == 0 { label.clone() } else { String::new() },
                            x,
                            v,
                            LineStyle::Solid,
                        )
                        .coloured(k),
                    );
                    any = true;
                }
            }
        }
        for (i, &s) in sides.iter().enumerate() {
            if let Some(v) = col(first, "data", s) {
                let x = first
                    .time
                    .iter()
                    .map(|&t| first.cycle.percent(s, t))
                    .collect();
                p.series.push(
                    Series::new(
                        if i == 0 {
                            format!("measured ({})", first.name)
                        } else {
                            String::new()
                        },
                        x,
                        v,
                        LineStyle::Dashed,
                    )
                    .coloured(6),
                );
            }
            for (t0, t1, name) in &first.phases {
                p.shaded.push(Span::new(
                    first.cycle.percent(s, *t0),
                    first.cycle.percent(s, *t1),
                    name.clone(),
                ));
            }
        }
        if any {
            svgs.push(p.to_svg());
        }
    }
    Report {
        title: format!("footfall — {}", runs.iter().map(|r| r.name.as_str()).collect::<Vec<_>>().join(" vs ")),
        summary,
        sections: vec![
            Section {
                heading: "Errors side by side".into(),
                paragraphs: vec!["Mean ± sd (max) of |model − measurement| at the shooting nodes, as each run recorded it (both legs pooled).".into()],
                tables: vec![error_table(runs)],
                svgs: vec![],
            },
            Section {
                heading: "Curves side by side".into(),
                paragraphs: vec![format!(
                    "One colour per run; dashes: the measurement of {}. Percent of the gait cycle, each leg from its own heel strike; phases of {} shaded.",
                    first.name, first.name
                )],
                tables: vec![],
                svgs,
            },
        ],
    }
}

/// The runs' recorded errors, one column per run, channels in order of first appearance.
fn error_table(runs: &[RunCurves]) -> Table {
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in runs {
        for c in &r.summary.channels {
            let k = (c.channel.clone(), c.unit.clone());
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
    }
    let rows = keys
        .iter()
        .map(|(ch, unit)| {
            let mut row = vec![format!("{ch} ({unit})")];
            for r in runs {
                row.push(
                    r.summary
                        .channels
                        .iter()
                        .find(|c| &c.channel == ch && &c.unit == unit)
                        .map_or("—".into(), |c| {
                            let s = c.stats;
                            match (s.sd, s.max) {
                                (Some(sd), Some(m)) => {
                                    format!("{:.2} ± {:.2} ({:.2})", s.mean, sd, m)
                                }
                                _ => format!("{:.2}", s.mean),
                            }
                        }),
                );
            }
            row
        })
        .collect();
    Table {
        title: "Errors at the shooting nodes".into(),
        headers: std::iter::once("channel".to_string())
            .chain(runs.iter().map(|r| r.name.clone()))
            .collect(),
        rows,
    }
}
