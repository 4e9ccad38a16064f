//! Before/after comparison of two gait runs: the per-channel tracking errors that `track`
//! and `predict` record in their `summary.json`, read back ([`RunSummary`]), set side by
//! side ([`RunDiff`]) and laid out as tables and a bar chart.
//!
//! A run summary holds, under `"errors"`, one entry per channel with the statistics of the
//! absolute error |model − measurement| at the shooting nodes, in the channel's display
//! unit (° for angles, cm for the CoP, N for forces):
//!
//! ```json
//! {"errors": [{"channel": "knee angle", "unit": "°", "stats": {"mean": 1.2, "sd": 0.8, "max": 3.1}}],
//!  "errors_by_phase": [{"channel": "knee angle", "unit": "°",
//!                       "phases": [{"phase": "1e", "stats": {"mean": 1.0, "sd": 0.5, "max": 2.0}}]}]}
//! ```
//!
//! The comparison is of the mean errors: the change B − A in the channel's unit and
//! relative to A in per cent. A channel is matched by name *and* unit, so a channel whose
//! unit changed between runs appears as two channels, each present in one run only —
//! channels in one run only are reported as such, never dropped and never an error.
//!
//! # Example
//!
//! ```
//! use footfall::report::diff::{RunDiff, RunSummary, Verdict};
//! use std::path::Path;
//!
//! let a = RunSummary::parse(r#"{"errors": [{"channel": "knee angle", "unit": "°", "stats": {"mean": 4.0}}]}"#, Path::new("a/summary.json"), "a").unwrap();
//! let b = RunSummary::parse(r#"{"errors": [{"channel": "knee angle", "unit": "°", "stats": {"mean": 3.0}}]}"#, Path::new("b/summary.json"), "b").unwrap();
//! let d = RunDiff::new(&a, &b, 1.0);
//! assert_eq!(d.channels[0].change_pct, Some(-25.0));
//! assert_eq!(d.channels[0].verdict, Verdict::Better);
//! ```

mod summary;

pub use summary::{ChannelSummary, DiffError, PhaseErrors, RunSummary, SummaryStats};

use super::plot::{BarChart, BarSeries};
use super::table::Table;
use serde::Serialize;
use std::path::PathBuf;

/// How a mean error changed from run A to run B.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// B's error is smaller by more than the threshold.
    Better,
    /// B's error is larger by more than the threshold.
    Worse,
    /// The change is within the threshold.
    Unchanged,
    /// The channel (or phase) has errors in run A only.
    OnlyInA,
    /// The channel (or phase) has errors in run B only.
    OnlyInB,
}

impl Verdict {
    /// The verdict in words, with an arrow for the direction of the error.
    pub fn text(self) -> &'static str {
        match self {
            Verdict::Better => "better ↓",
            Verdict::Worse => "worse ↑",
            Verdict::Unchanged => "unchanged",
            Verdict::OnlyInA => "only in A",
            Verdict::OnlyInB => "only in B",
        }
    }

    /// The verdict as one lower-case word or snake_case tag (as in `summary.json`).
    pub fn tag(self) -> &'static str {
        match self {
            Verdict::Better => "better",
            Verdict::Worse => "worse",
            Verdict::Unchanged => "unchanged",
            Verdict::OnlyInA => "only_in_a",
            Verdict::OnlyInB => "only_in_b",
        }
    }
}

/// The change of a mean error from `a` to `b`: absolute (B − A, the channel's unit),
/// relative (100 (B − A)/A, per cent; `None` when A is 0) and its verdict, where changes
/// of at most `threshold_pct` per cent of A count as unchanged.
pub fn compare_means(
    a: Option<f64>,
    b: Option<f64>,
    threshold_pct: f64,
) -> (Option<f64>, Option<f64>, Verdict) {
    match (a, b) {
        (Some(a), Some(b)) => {
            let d = b - a;
            let pct = (a != 0.0).then(|| 100.0 * d / a);
            let verdict = match pct {
                Some(p) if p.abs() <= threshold_pct => Verdict::Unchanged,
                _ if d < 0.0 => Verdict::Better,
                _ if d > 0.0 => Verdict::Worse,
                _ => Verdict::Unchanged,
            };
            (Some(d), pct, verdict)
        }
        (Some(_), None) => (None, None, Verdict::OnlyInA),
        (None, _) => (None, None, Verdict::OnlyInB),
    }
}

/// One phase of one channel in the comparison: mean errors in each run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PhaseDiff {
    /// Phase name.
    pub phase: String,
    /// Mean |error| in run A (channel unit), `None` when A lacks the phase.
    pub mean_a: Option<f64>,
    /// Mean |error| in run B (channel unit), `None` when B lacks the phase.
    pub mean_b: Option<f64>,
    /// B − A (channel unit).
    pub change: Option<f64>,
    /// 100 (B − A)/A (per cent).
    pub change_pct: Option<f64>,
    /// Direction of the change.
    pub verdict: Verdict,
}

/// One channel in the comparison.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelDiff {
    /// Channel name.
    pub channel: String,
    /// Display unit of the errors.
    pub unit: String,
    /// Statistics in run A, `None` when A lacks the channel.
    pub a: Option<SummaryStats>,
    /// Statistics in run B, `None` when B lacks the channel.
    pub b: Option<SummaryStats>,
    /// Mean B − mean A (channel unit); negative is an improvement.
    pub change: Option<f64>,
    /// 100 (mean B − mean A)/mean A (per cent); `None` when mean A is 0.
    pub change_pct: Option<f64>,
    /// Direction of the change.
    pub verdict: Verdict,
    /// Phase by phase: A's phases in order, then those only B has.
    pub phases: Vec<PhaseDiff>,
}

impl ChannelDiff {
    /// `name (unit)`, or the name alone for a unitless channel.
    pub fn label(&self) -> String {
        if self.unit.is_empty() {
            self.channel.clone()
        } else {
            format!("{} ({})", self.channel, self.unit)
        }
    }
}

/// Run A or B as the comparison records it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunInfo {
    /// Short name (the run folder's name).
    pub name: String,
    /// The summary file read.
    pub path: PathBuf,
    /// The command that wrote the run, when recorded.
    pub command: Option<String>,
    /// The run's foot, when recorded.
    pub foot: Option<String>,
    /// Whether the run records errors by phase.
    pub has_phases: bool,
}

impl From<&RunSummary> for RunInfo {
    fn from(r: &RunSummary) -> Self {
        Self {
            name: r.name.clone(),
            path: r.path.clone(),
            command: r.command.clone(),
            foot: r.foot.clone(),
            has_phases: r.has_phases,
        }
    }
}

/// Per-channel tracking errors of run A ("before") against run B ("after").
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunDiff {
    /// Run A, the baseline.
    pub a: RunInfo,
    /// Run B, compared with A.
    pub b: RunInfo,
    /// Changes of at most this many per cent of A count as unchanged.
    pub threshold_pct: f64,
    /// A's channels in order, then those only B has.
    pub channels: Vec<ChannelDiff>,
}

/// The union of two ordered key lists: `a`'s order, then what only `b` has.
fn union<K: PartialEq + Clone>(a: impl Iterator<Item = K>, b: impl Iterator<Item = K>) -> Vec<K> {
    let mut keys: Vec<K> = a.collect();
    for k in b {
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys
}

impl RunDiff {
    /// Compare the runs channel by channel (matched by name and unit) and phase by
    /// phase (matched by name). `threshold_pct` (≥ 0; a negative or NaN value counts as 0)
    /// is the relative change below which a channel counts as unchanged.
    pub fn new(a: &RunSummary, b: &RunSummary, threshold_pct: f64) -> Self {
        let threshold_pct = if threshold_pct > 0.0 {
            threshold_pct
        } else {
            0.0
        };
        let key = |c: &ChannelSummary| (c.channel.clone(), c.unit.clone());
        let find = |r: &'_ RunSummary, k: &(String, String)| {
            r.channels
                .iter()
                .find(|c| c.channel == k.0 && c.unit == k.1)
                .cloned()
        };
        let channels = union(a.channels.iter().map(key), b.channels.iter().map(key))
            .into_iter()
            .map(|k| {
                let (ca, cb) = (find(a, &k), find(b, &k));
                let (change, change_pct, verdict) = compare_means(
                    ca.as_ref().map(|c| c.stats.mean),
                    cb.as_ref().map(|c| c.stats.mean),
                    threshold_pct,
                );
                let no_phases = Vec::new();
                let pa = ca.as_ref().map_or(&no_phases, |c| &c.phases);
                let pb = cb.as_ref().map_or(&no_phases, |c| &c.phases);
                let phases = union(
                    pa.iter().map(|p| p.phase.clone()),
                    pb.iter().map(|p| p.phase.clone()),
                )
                .into_iter()
                .map(|phase| {
                    let mean = |l: &[PhaseErrors]| {
                        l.iter().find(|p| p.phase == phase).map(|p| p.stats.mean)
                    };
                    let (mean_a, mean_b) = (mean(pa), mean(pb));
                    let (change, change_pct, verdict) =
                        compare_means(mean_a, mean_b, threshold_pct);
                    PhaseDiff {
                        phase,
                        mean_a,
                        mean_b,
                        change,
                        change_pct,
                        verdict,
                    }
                })
                .collect();
                ChannelDiff {
                    channel: k.0,
                    unit: k.1,
                    a: ca.as_ref().map(|c| c.stats),
                    b: cb.as_ref().map(|c| c.stats),
                    change,
                    change_pct,
                    verdict,
                    phases,
                }
            })
            .collect();
        Self {
            a: a.into(),
            b: b.into(),
            threshold_pct,
            channels,
        }
    }

    /// Number of channels with verdict `v`.
    pub fn count(&self, v: Verdict) -> usize {
        self.channels.iter().filter(|c| c.verdict == v).count()
    }

    /// Labels (`name (unit)`) of the channels with verdict `v`.
    pub fn labels(&self, v: Verdict) -> Vec<String> {
        self.channels
            .iter()
            .filter(|c| c.verdict == v)
            .map(ChannelDiff::label)
            .collect()
    }

    /// The verdict in a sentence, e.g. "B is better on 5, worse on 1 and unchanged on 0
    /// of 6 channels in both runs (threshold ±1 %)".
    pub fn headline(&self) -> String {
        let common = self
            .channels
            .iter()
            .filter(|c| c.a.is_some() && c.b.is_some())
            .count();
        format!(
            "B is better on {}, worse on {} and unchanged on {} of {common} channels in both runs (changes within ±{} % of A count as unchanged)",
            self.count(Verdict::Better),
            self.count(Verdict::Worse),
            self.count(Verdict::Unchanged),
            self.threshold_pct
        )
    }

    /// Sentences about channels in one run only (empty when the channel sets agree).
    pub fn notes(&self) -> Vec<String> {
        let mut notes = Vec::new();
        for (v, run, other) in [(Verdict::OnlyInA, "A", "B"), (Verdict::OnlyInB, "B", "A")] {
            let l = self.labels(v);
            if !l.is_empty() {
                notes.push(format!(
                    "Only in run {run} (no errors recorded in run {other}, not compared): {}.",
                    l.join(", ")
                ));
            }
        }
        for (r, name) in [(&self.a, "A"), (&self.b, "B")] {
            if !r.has_phases {
                notes.push(format!(
                    "Run {name} records no errors by phase (no `errors_by_phase` in {}).",
                    r.path.display()
                ));
            }
        }
        let phases = self.channels.iter().flat_map(|c| &c.phases);
        if self.a.has_phases
            && self.b.has_phases
            && phases.clone().next().is_some()
            && phases
                .clone()
                .all(|p| p.mean_a.is_none() || p.mean_b.is_none())
        {
            notes.push("The runs share no phase names (different phase graphs), so no phase is compared: the by-phase table lists each run's phases on their own.".into());
        }
        notes
    }

    /// The comparison for reading: channel, unit, mean error in A and B, the change
    /// (absolute and per cent) and the verdict; `—` where a run lacks the channel.
    pub fn table(&self) -> Table {
        let headers = [
            "channel",
            "unit",
            "mean error A",
            "mean error B",
            "change B − A",
            "change %",
            "verdict",
        ];
        Table {
            title: format!(
                "Mean tracking error per channel: A = {} → B = {}",
                self.a.name, self.b.name
            ),
            headers: headers.iter().map(|h| h.to_string()).collect(),
            rows: self
                .channels
                .iter()
                .map(|c| {
                    vec![
                        c.channel.clone(),
                        c.unit.clone(),
                        fmt_opt(c.a.map(|s| s.mean)),
                        fmt_opt(c.b.map(|s| s.mean)),
                        c.change.map_or("—".into(), fmt_signed),
                        c.change_pct.map_or("—".into(), fmt_pct),
                        c.verdict.text().to_string(),
                    ]
                })
                .collect(),
        }
    }

    /// Phase by phase: for each channel and phase, `mean A → mean B` with the change.
    pub fn phase_table(&self) -> Table {
        let headers = [
            "channel",
            "unit",
            "phase",
            "mean error A → B",
            "change B − A",
            "change %",
            "verdict",
        ];
        let mut rows = Vec::new();
        for c in &self.channels {
            for p in &c.phases {
                rows.push(vec![
                    c.channel.clone(),
                    c.unit.clone(),
                    p.phase.clone(),
                    format!("{} → {}", fmt_opt(p.mean_a), fmt_opt(p.mean_b)),
                    p.change.map_or("—".into(), fmt_signed),
                    p.change_pct.map_or("—".into(), fmt_pct),
                    p.verdict.text().to_string(),
                ]);
            }
        }
        Table {
            title: "Mean tracking error by phase: A → B".into(),
            headers: headers.iter().map(|h| h.to_string()).collect(),
            rows,
        }
    }

    /// The comparison for machines (write with [`Table::to_csv`]): numbers at full
    /// precision in the channel's unit (per cent for `change_pct`), empty where undefined.
    pub fn csv_table(&self) -> Table {
        let headers = [
            "channel",
            "unit",
            "mean_a",
            "mean_b",
            "change",
            "change_pct",
            "verdict",
            "sd_a",
            "sd_b",
            "max_a",
            "max_b",
        ];
        let num = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
        Table {
            title: String::new(),
            headers: headers.iter().map(|h| h.to_string()).collect(),
            rows: self
                .channels
                .iter()
                .map(|c| {
                    vec![
                        c.channel.clone(),
                        c.unit.clone(),
                        num(c.a.map(|s| s.mean)),
                        num(c.b.map(|s| s.mean)),
                        num(c.change),
                        num(c.change_pct),
                        c.verdict.tag().to_string(),
                        num(c.a.and_then(|s| s.sd)),
                        num(c.b.and_then(|s| s.sd)),
                        num(c.a.and_then(|s| s.max)),
                        num(c.b.and_then(|s| s.max)),
                    ]
                })
                .collect(),
        }
    }

    /// Grouped bars of the mean error per channel, both runs as per cent of run A's mean
    /// (A is 100 % by construction, so channels in different units share one axis); each
    /// bar is labelled with the mean in the channel's own unit. A channel in one run only
    /// shows that run's value as a label without a bar in the other; bars above 400 % are
    /// cut off at the frame.
    pub fn chart(&self) -> BarChart {
        let mut chart = BarChart::new(
            "Mean tracking error per channel, relative to run A",
            "mean error (% of A)",
        );
        let (mut va, mut la, mut vb, mut lb) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for c in &self.channels {
            chart.categories.push(if c.unit.is_empty() {
                c.channel.clone()
            } else {
                format!("{}\n({})", c.channel, c.unit)
            });
            let value = |s: &SummaryStats| fmt_value(s.mean);
            match (&c.a, &c.b) {
                (Some(a), b) => {
                    va.push(100.0);
                    la.push(value(a));
                    match b {
                        Some(b) if a.mean > 0.0 => {
                            vb.push(100.0 * b.mean / a.mean);
                            lb.push(value(b));
                        }
                        Some(b) if b.mean == 0.0 => {
                            vb.push(100.0);
                            lb.push(value(b));
                        }
                        Some(b) => {
                            vb.push(f64::NAN);
                            lb.push(format!("{} (A = 0)", value(b)));
                        }
                        None => {
                            vb.push(f64::NAN);
                            lb.push("not in B".into());
                        }
                    }
                }
                (None, b) => {
                    va.push(f64::NAN);
                    la.push("not in A".into());
                    vb.push(f64::NAN);
                    lb.push(b.as_ref().map_or(String::new(), value));
                }
            }
        }
        let top = vb
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(100.0f64, f64::max);
        if top > 400.0 {
            chart.y_range = Some((0.0, 400.0));
        }
        chart
            .series
            .push(BarSeries::new(format!("A: {}", self.a.name), va, la));
        chart
            .series
            .push(BarSeries::new(format!("B: {}", self.b.name), vb, lb));
        chart.reference = Some((100.0, "A = 100 %".into()));
        chart
    }
}

/// A mean error for a table: at least two decimals, more for small values so that three
/// significant digits show (0.0123), at most six.
pub fn fmt_value(v: f64) -> String {
    if !v.is_finite() || v == 0.0 {
        return format!("{v:.2}");
    }
    let d = (2 - v.abs().log10().floor() as i64).clamp(2, 6) as usize;
    format!("{v:.d$}")
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or("—".into(), fmt_value)
}

/// A change with its sign (+/-), digits as [`fmt_value`].
fn fmt_signed(v: f64) -> String {
    let s = fmt_value(v.abs());
    if v > 0.0 {
        format!("+{s}")
    } else if v < 0.0 {
        format!("-{s}")
    } else {
        s
    }
}

/// A relative change in per cent with its sign and one decimal.
fn fmt_pct(v: f64) -> String {
    if v == 0.0 {
        "0.0 %".into()
    } else {
        format!("{v:+.1} %")
    }
}
