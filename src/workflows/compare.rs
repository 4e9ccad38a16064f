//! `footfall compare`: the same prediction for two or more feet, side by side (Millard &
//! Mombaur 2019, §4: the ellipse foot's ground-force transient against the double-circle foot).

use super::predict::predict;
use super::read_solution;
use super::run_folder::GaitRunOutput;
#[allow(unused_imports)]
use super::{note, warn_note, Progress};
use crate::model::GaitModel;
use crate::phases::PhaseSequence;
use crate::problems::evaluation::GaitSolution;
use crate::report::html::{Report, Section, Summary, Tone};
use crate::report::plot::{LinePlot, LineStyle, Series};
use crate::report::table::Table;
use crate::runfolder::RunFolder;
use crate::sqp::SqpStatus;
use anyhow::{anyhow, bail};
use std::path::PathBuf;

/// What `compare` does: the arguments of `footfall compare`.
#[derive(Debug, Clone)]
pub struct CompareRequest {
    /// Feet to compare, comma separated: `ellipse`, `double-circle` or `FOOT_FILE:PHASE_FILE`.
    pub feet: Vec<String>,
    /// Start a foot's prediction from a solution: `FOOT=RUN_FOLDER_OR_FILE` (repeatable).
    /// Feet without one start from the data.
    pub inits: Vec<String>,
    /// Exit with status 1 unless this foot's peak normal-force excess over the
    /// measurement is at least `--expect-ratio` times every other foot's (a prediction
    /// that did not converge, or one that is physically invalid on the 1 ms grid, exits
    /// with its own code first).
    pub expect_transient: Option<String>,
    /// Ratio for `--expect-transient`.
    pub expect_ratio: f64,
    /// Output folder (one prediction run folder per foot inside).
    pub out: PathBuf,
    /// Replace the output folder if it exists.
    pub overwrite: bool,
    /// The prediction every foot gets.
    pub options: super::predict::PredictionOptions,
}

struct Outcome {
    name: String,
    out: GaitRunOutput,
    converged: bool,
    status: String,
    /// The solver's status, and whether it stopped before any iteration.
    result: SqpStatus,
    at_start: bool,
    seconds: f64,
    iterations: usize,
    objective: f64,
    kkt: f64,
}

/// A `--feet` item: the foot and its phase file, if given (`FOOT_FILE:PHASE_FILE`).
fn foot_and_phases(spec: &str) -> (String, Option<PathBuf>) {
    match spec.split_once(':') {
        Some((f, p)) => (f.to_string(), Some(PathBuf::from(p))),
        None => (spec.to_string(), None),
    }
}

/// Every foot and its phase file read and checked against the model before the first
/// prediction, so that a bad later foot does not cost the earlier ones' solves.
fn check_feet(args: &CompareRequest) -> anyhow::Result<()> {
    for spec in &args.feet {
        let (foot, phases) = foot_and_phases(spec);
        let model = GaitModel::load(&args.options.model, &super::foot_path(&foot))
            .map_err(|e| anyhow!("--feet {spec}: {e}"))?;
        let phases = phases.unwrap_or_else(|| super::default_phases(&foot));
        PhaseSequence::load(&phases)
            .and_then(|seq| seq.resolve(&model, &phases).map(|_| ()))
            .map_err(|e| anyhow!("--feet {spec}: {e}"))?;
    }
    Ok(())
}

impl Outcome {
    /// Whether the prediction is physically valid on the 1 ms grid.
    fn valid(&self) -> bool {
        self.out.validity.as_ref().is_some_and(|v| v.is_valid())
    }

    /// The largest normal-force excess over the measurement on the fine grid (N).
    fn excess(&self) -> Option<f64> {
        self.out.fine_forces.as_ref().map(|f| f.max_excess(1).0)
    }

    /// `f` of the fine-grid forces, or a dash without them.
    fn fine(&self, f: &dyn Fn(&super::run_folder::FineForces) -> String) -> String {
        self.out.fine_forces.as_ref().map_or("—".to_string(), f)
    }
}

/// The `--init` solutions by foot, the arguments checked before any work.
fn check_request(args: &CompareRequest) -> anyhow::Result<Vec<(String, GaitSolution)>> {
    args.options.check_limits()?;
    if args.feet.len() < 2 {
        bail!(
            "--feet: give at least two feet to compare, got {:?}",
            args.feet
        );
    }
    let mut inits: Vec<(String, GaitSolution)> = Vec::new();
    for i in &args.inits {
        let (foot, path) = i
            .split_once('=')
            .ok_or_else(|| anyhow!("--init {i}: expected FOOT=RUN_FOLDER_OR_FILE"))?;
        if !args.feet.iter().any(|f| f.split(':').next() == Some(foot)) {
            bail!("--init {i}: '{foot}' is not among --feet {:?}", args.feet);
        }
        inits.push((foot.to_string(), read_solution(std::path::Path::new(path))?));
    }
    if let Some(e) = &args.expect_transient {
        if !args
            .feet
            .iter()
            .any(|f| f.split(':').next() == Some(e.as_str()))
        {
            bail!("--expect-transient {e}: not among --feet {:?}", args.feet);
        }
    }
    check_feet(args)?;
    Ok(inits)
}

/// Predict with every foot, each into a sub-folder of `folder` named after it.
fn predict_each(
    args: &CompareRequest,
    inits: &[(String, GaitSolution)],
    folder: &RunFolder,
    progress: &dyn Progress,
) -> anyhow::Result<Vec<Outcome>> {
    let mut outcomes = Vec::new();
    for spec in &args.feet {
        let (foot, phases) = foot_and_phases(spec);
        let name = std::path::Path::new(&foot)
            .file_stem()
            .map_or(foot.clone(), |s| s.to_string_lossy().replace('_', "-"));
        let init = inits.iter().find(|(f, _)| *f == foot).map(|(_, s)| s);
        {
            note!(progress, "── {name} ──");
        }
        let sub = RunFolder::create(&folder.staging_path().join(&name), false)?;
        let (out, res) = predict(&args.options, &foot, phases.as_deref(), init, sub, progress)?;
        outcomes.push(Outcome {
            name,
            converged: res.status == SqpStatus::Converged,
            status: res.status.to_string(),
            result: res.status.clone(),
            at_start: res.history.is_empty(),
            seconds: res.seconds,
            iterations: res.history.len().saturating_sub(1),
            objective: res.objective,
            kkt: res.kkt,
            out,
        });
    }
    Ok(outcomes)
}

/// The predictions side by side: solver figures, fine-grid forces, transients and errors.
fn side_by_side(outcomes: &[Outcome]) -> Table {
    let mut headers = vec!["".to_string()];
    headers.extend(outcomes.iter().map(|o| o.name.clone()));
    let row = |label: &str, f: &dyn Fn(&Outcome) -> String| {
        let mut r = vec![label.to_string()];
        r.extend(outcomes.iter().map(f));
        r
    };
    let mut rows = vec![
        row("status", &|o| o.status.clone()),
        row("physically valid (1 ms grid)", &|o| match &o.out.validity {
            Some(v) if v.is_valid() => "yes".into(),
            Some(v) => format!(
                "NO: {}",
                v.violations
                    .iter()
                    .max_by(|a, b| a.amount.total_cmp(&b.amount))
                    .map(|x| x.to_string())
                    .unwrap_or_default()
            ),
            None => "unknown (no re-integration)".into(),
        }),
        row("solve time (s)", &|o| format!("{:.1}", o.seconds)),
        row("iterations", &|o| o.iterations.to_string()),
        row("objective", &|o| format!("{:.6}", o.objective)),
        row("KKT", &|o| format!("{:.1e}", o.kkt)),
        row("peak normal force (N)", &|o| {
            o.fine(&|f| format!("{:.1}", f.peak(1)))
        }),
        row("peak tangential force (N)", &|o| {
            o.fine(&|f| format!("{:.1}", f.peak(0)))
        }),
        row("normal-force excess over the measurement (N)", &|o| {
            o.fine(&|f| {
                let (e, t, s) = f.max_excess(1);
                format!("{e:.1} ({} foot, {t:.3} s)", ["right", "left"][s])
            })
        }),
        row("tangential-force excess (N)", &|o| {
            o.fine(&|f| format!("{:.1}", f.max_excess(0).0))
        }),
        row("largest transient", &|o| {
            o.out.transients.first().map_or("none".into(), |t| {
                format!(
                    "{} {}: {:.1} N for {:.1} ms in {} ({})",
                    t.foot,
                    t.component,
                    t.excess_n,
                    1e3 * t.duration_s,
                    t.phase,
                    if t.between_nodes {
                        "between nodes"
                    } else {
                        "at a node"
                    }
                )
            })
        }),
        row("ankle ω at the transient (rad/s)", &|o| {
            o.out
                .transients
                .first()
                .map_or("—".into(), |t| format!("{:.2}", t.ankle_velocity_rad_s))
        }),
        row("largest Baumgarte force (N)", &|o| {
            o.out
                .fine
                .as_ref()
                .map_or("—".into(), |f| format!("{:.1e}", f.max_baumgarte_force_n))
        }),
    ];
    for (c, ch) in outcomes[0].out.errors.iter().enumerate() {
        rows.push(row(&format!("{} ({})", ch.name, ch.unit), &|o| {
            o.out.errors[c].runs[0].map_or("—".into(), |s| s.cell(1))
        }));
    }
    Table { title: "Prediction compared across feet (errors in the layout of Millard & Mombaur 2019, Table 4; forces on the 1 ms grid)".into(), headers, rows }
}

/// The normal forces of all feet over the measurement, right foot then left (SVG).
fn normal_force_plots(outcomes: &[Outcome]) -> Vec<String> {
    let mut plots = Vec::new();
    for (s, side) in ["right", "left"].iter().enumerate() {
        let mut p = LinePlot::new(
            format!("Normal ground force, {side} foot"),
            "time (s)",
            "force (N)",
        );
        if let Some(f) = outcomes.iter().find_map(|o| o.out.fine_forces.as_ref()) {
            p.series.push(Series::new(
                "measured",
                f.times.clone(),
                f.measured[s][1].clone(),
                LineStyle::Dashed,
            ));
        }
        for o in outcomes {
            if let Some(f) = &o.out.fine_forces {
                p.series.push(Series::new(
                    o.name.clone(),
                    f.times.clone(),
                    f.model[s][1].clone(),
                    LineStyle::Solid,
                ));
            }
        }
        plots.push(p.to_svg());
    }
    plots
}

/// Whether `--expect-transient` holds, and why (None without one).
fn expectation(
    args: &CompareRequest,
    outcomes: &[Outcome],
) -> anyhow::Result<Option<(bool, String)>> {
    let Some(e) = &args.expect_transient else {
        return Ok(None);
    };
    let key = std::path::Path::new(e)
        .file_stem()
        .map_or(e.clone(), |s| s.to_string_lossy().replace('_', "-"));
    let expected = outcomes
        .iter()
        .find(|o| o.name == key)
        .ok_or_else(|| anyhow!("--expect-transient {e}: no such foot in the comparison"))?;
    let mut ok = outcomes.iter().all(|o| o.converged);
    let mut lines = Vec::new();
    if !ok {
        lines.push("not every prediction converged".to_string());
    }
    // a transient of a solution that breaks physics between its nodes is not a finding
    // of the model: the expectation fails on it
    for o in outcomes.iter().filter(|o| !o.valid()) {
        ok = false;
        lines.push(format!(
            "{}: physically invalid on the 1 ms grid, its transient not counted (see its report)",
            o.name
        ));
    }
    match expected.excess() {
        None => {
            ok = false;
            lines.push(format!("{}: no fine-grid forces", expected.name));
        }
        Some(ee) => {
            for o in outcomes.iter().filter(|o| o.name != expected.name) {
                match o.excess() {
                    Some(oe) => {
                        let holds = ee >= args.expect_ratio * oe.max(0.0);
                        ok &= holds;
                        lines.push(format!(
                            "{} excess {ee:.1} N {} {} × {} excess {oe:.1} N (ratio {:.2})",
                            expected.name,
                            if holds { "≥" } else { "<" },
                            args.expect_ratio,
                            o.name,
                            ee / oe.max(f64::MIN_POSITIVE)
                        ));
                    }
                    None => {
                        ok = false;
                        lines.push(format!("{}: no fine-grid forces", o.name));
                    }
                }
            }
        }
    }
    Ok(Some((ok, lines.join("; "))))
}

/// The comparison's report: the verdict, the table side by side and the normal forces.
fn report(
    outcomes: &[Outcome],
    verdict: &Option<(bool, String)>,
    table: &Table,
    plots: &[String],
) -> Report {
    let all_converged = outcomes.iter().all(|o| o.converged);
    let mut summary = Summary::new(
        match verdict {
            Some((true, _)) => "expectation holds",
            Some((false, _)) => "expectation fails",
            None if all_converged => "all converged",
            None => "not all converged",
        },
        if verdict.as_ref().map_or(all_converged, |v| v.0) {
            Tone::Good
        } else {
            Tone::Warning
        },
        verdict
            .as_ref()
            .map_or_else(|| "comparison written".to_string(), |v| v.1.clone()),
    );
    summary.time_s = Some(outcomes.iter().map(|o| o.seconds).sum());
    Report {
        title: format!("footfall compare — {}", outcomes.iter().map(|o| o.name.as_str()).collect::<Vec<_>>().join(" vs ")),
        summary,
        sections: vec![
            Section {
                heading: "Side by side".into(),
                paragraphs: vec!["Identical prediction problems that differ only in the foot (Millard & Mombaur 2019, §4). Each foot's full run folder, with its own report, is in the sub-folder of its name.".into()],
                tables: vec![table.clone()],
                svgs: vec![],
            },
            Section { heading: "Normal ground forces".into(), paragraphs: vec!["1 ms re-integration of each prediction over the measurement.".into()], tables: vec![], svgs: plots.to_vec() },
        ],
    }
}

/// The comparison's `summary.json`.
fn summary_json(
    args: &CompareRequest,
    outcomes: &[Outcome],
    verdict: &Option<(bool, String)>,
) -> serde_json::Value {
    serde_json::json!({
        "command": "compare",
        "feet": outcomes.iter().map(|o| serde_json::json!({
            "name": o.name,
            "status": o.status,
            "converged": o.converged,
            "physically_valid": o.out.validity.as_ref().map(|v| v.is_valid()),
            "violations": o.out.validity.as_ref().map(|v| v.violations.clone()),
            "seconds": o.seconds,
            "iterations": o.iterations,
            "objective": o.objective,
            "kkt": o.kkt,
            "peak_normal_force_n": o.out.fine_forces.as_ref().map(|f| f.peak(1)),
            "peak_tangential_force_n": o.out.fine_forces.as_ref().map(|f| f.peak(0)),
            "normal_force_excess_n": o.excess(),
            "tangential_force_excess_n": o.out.fine_forces.as_ref().map(|f| f.max_excess(0).0),
            "largest_transient": o.out.transients.first(),
        })).collect::<Vec<_>>(),
        "expect_transient": args.expect_transient,
        "expect_ratio": args.expect_ratio,
        "expectation_holds": verdict.as_ref().map(|v| v.0),
        "verdict": verdict.as_ref().map(|v| v.1.clone()),
    })
}

/// The exit status of a written comparison: a prediction that did not converge decides
/// it before the expectation (interrupted first, then infeasible, then any other stop),
/// then a prediction that breaks physics between its nodes (exit 5), whose transient
/// the expectation did not count, then the expectation.
fn exit_status(
    outcomes: &[Outcome],
    verdict: Option<(bool, String)>,
    path: &std::path::Path,
) -> anyhow::Result<()> {
    let rank = |o: &Outcome| match o.result {
        SqpStatus::Interrupted => 0,
        SqpStatus::Infeasible => 1,
        _ => 2,
    };
    if let Some(o) = outcomes
        .iter()
        .filter(|o| !o.converged)
        .min_by_key(|o| rank(o))
    {
        return Err(super::Unsolved {
            status: o.result.clone(),
            at_start: o.at_start,
            message: format!(
                "not every prediction converged ({}: {}; results in {})",
                o.name,
                o.status,
                path.display()
            ),
        }
        .into());
    }
    if let Some(o) = outcomes.iter().find(|o| !o.valid()) {
        super::Invalid::check(&o.out)?;
    }
    match verdict {
        Some((false, v)) => Err(anyhow!("expected transient ordering does not hold: {v}")),
        _ => Ok(()),
    }
}

/// Run `compare` as `args` describes, reporting to `progress`.
pub fn run(args: &CompareRequest, progress: &dyn Progress) -> anyhow::Result<()> {
    let inits = check_request(args)?;
    let folder = RunFolder::create(&args.out, args.overwrite)?;
    let outcomes = predict_each(args, &inits, &folder, progress)?;
    let table = side_by_side(&outcomes);
    let plots = normal_force_plots(&outcomes);
    let verdict = expectation(args, &outcomes)?;
    let report = report(&outcomes, &verdict, &table, &plots);
    let summary_json = summary_json(args, &outcomes, &verdict);
    folder.write(
        "summary.json",
        serde_json::to_string_pretty(&summary_json)?.as_bytes(),
    )?;
    folder.write("compare.md", table.to_markdown().as_bytes())?;
    folder.write("normal_force_right.svg", plots[0].as_bytes())?;
    folder.write("normal_force_left.svg", plots[1].as_bytes())?;
    folder.write("report.html", report.to_html().as_bytes())?;
    let path = folder.commit()?;
    {
        note!(progress, "{}", table.to_markdown());
        if let Some((_, v)) = &verdict {
            note!(progress, "{v}");
        }
        note!(progress, "report: {}", path.join("report.html").display());
    }
    exit_status(&outcomes, verdict, &path)
}
