//! `footfall compare-contact`: one trial tracked with a rigid foot, the same foot with its
//! geometry identified, a volumetric foot with its file's contact law, and that foot with
//! its law identified (the optimal-control identification of Ezati et al. 2020). Each run is a
//! full track run folder; the comparison sets their Table 3 side by side, with the ground
//! forces' RMSE next to Ezati et al.'s (2020) Table 7, the push-off CoP error and the solve
//! times.

use super::track::{track, TrackRequest, TrackingProblem};
use super::{note, Progress};
use crate::model::effects::EffectSpec;
use crate::problems::diagnose::TrackingRunSetup;
use crate::problems::track::TargetSides;
use crate::report::html::{Section, Tone};
use crate::report::runs::{side_by_side, RunCurves};
use crate::report::table::Table;
use crate::runfolder::RunFolder;
use crate::sqp::{SqpSettings, SqpStatus};
use anyhow::Context;
use std::path::PathBuf;

/// Ezati et al. (2020), Table 7, optimal control: RMSE of the tangential and normal ground reaction
/// force (N), right and left leg, over the gait cycle.
pub const EZATI2020_GRF_RMSE: [[f64; 2]; 2] = [[19.81, 8.33], [26.49, 26.38]];

/// Measured normal force (N) above which a foot counts as loaded for the push-off CoP
/// error.
pub const LOADED_N: f64 = 20.0;

/// What `compare-contact` does.
#[derive(Debug, Clone)]
pub struct CompareContactRequest {
    /// The trial and the tracking problem's options (model, data, weights, tolerance);
    /// its foot, phases, effects and parameters are set per run.
    pub run: TrackingRunSetup,
    /// The rigid foot: `ellipse`, `double-circle` or a foot file.
    pub rigid_foot: String,
    /// The rigid foot's phase graph.
    pub rigid_phases: PathBuf,
    /// The volumetric foot file.
    pub volumetric_foot: String,
    /// Its phase graph (one continuous phase per half cycle).
    pub volumetric_phases: PathBuf,
    /// Add check points where the 1 ms re-integration breaks a contact constraint.
    pub check_points: bool,
    /// The solver's settings for every run.
    pub sqp: SqpSettings,
    /// Report ground-force excursions above the measurement larger than this (N).
    pub transient_threshold: f64,
    /// Output folder (one track run folder per run inside).
    pub out: PathBuf,
    /// Replace the output folder if it exists.
    pub overwrite: bool,
}

/// One run of the comparison: its folder name, foot, phases, the effect it identifies and
/// the run it starts from (by index; None: the data).
struct Plan {
    name: &'static str,
    volumetric: bool,
    effect: Option<&'static str>,
    init: Option<usize>,
}

const PLANS: [Plan; 4] = [
    Plan {
        name: "rigid",
        volumetric: false,
        effect: None,
        init: None,
    },
    Plan {
        name: "rigid-identified-geometry",
        volumetric: false,
        effect: Some("foot_geometry"),
        init: Some(0),
    },
    Plan {
        name: "volumetric",
        volumetric: true,
        effect: None,
        init: None,
    },
    Plan {
        name: "volumetric-identified",
        volumetric: true,
        effect: Some("volumetric_contact"),
        init: Some(2),
    },
];

/// What the solver did in one run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RunOutcome {
    /// The run's folder name.
    pub name: String,
    /// The solver's status, in words.
    pub status: String,
    /// The solver's status.
    #[serde(skip)]
    pub sqp_status: SqpStatus,
    /// Whether it converged.
    pub converged: bool,
    /// Physically valid on the 1 ms grid (None: not re-integrated).
    pub physically_valid: Option<bool>,
    /// SQP iterations.
    pub iterations: usize,
    /// Wall-clock time of the solve (s).
    pub seconds: f64,
    /// Objective at the end.
    pub objective: f64,
    /// KKT residual at the end.
    pub kkt: f64,
    /// The identified parameters: `(name, value, sd, unit)`.
    pub parameters: Vec<(String, f64, Option<f64>, String)>,
    /// Figures of the run's fine grid.
    pub figures: ContactFigures,
}

/// Ground-force and CoP figures of a run on its 1 ms grid.
#[derive(Debug, Clone, Copy, Default, serde::Serialize, PartialEq)]
pub struct ContactFigures {
    /// RMSE of the tangential force (N), `[right, left]`, over the window.
    pub tangential_rmse_n: [Option<f64>; 2],
    /// RMSE of the normal force (N), `[right, left]`, over the window.
    pub normal_rmse_n: [Option<f64>; 2],
    /// |model − measured| CoP (m) of the trailing foot in double support (push-off):
    /// mean, standard deviation, maximum, number of samples.
    pub push_off_cop_m: Option<(f64, f64, f64, usize)>,
}

impl ContactFigures {
    /// The figures of a run from its fine-grid columns: the RMSE of each foot's forces
    /// over every sample where both model and measurement are defined, and the push-off
    /// CoP error over the samples where both feet's measured normal forces exceed
    /// [`LOADED_N`] and the foot's measured CoP is behind the other's (walking toward +x).
    pub fn of(run: &RunCurves) -> Self {
        Self::from_columns(&run.columns)
    }

    /// As [`of`](Self::of), from the fine grid's columns by name (`model_grf_x_r`,
    /// `data_cop_x_l`, …; NaN where undefined).
    pub fn from_columns(columns: &std::collections::BTreeMap<String, Vec<f64>>) -> Self {
        let col = |n: &str| columns.get(n).map(|v| v.as_slice());
        let side = ["r", "l"];
        let rmse = |what: &str, s: usize| -> Option<f64> {
            let m = col(&format!("model_{what}_{}", side[s]))?;
            let d = col(&format!("data_{what}_{}", side[s]))?;
            let (sum, n) = m
                .iter()
                .zip(d)
                .filter(|(a, b)| a.is_finite() && b.is_finite())
                .fold((0.0, 0usize), |(s, n), (a, b)| (s + (a - b).powi(2), n + 1));
            (n > 0).then(|| (sum / n as f64).sqrt())
        };
        let mut errors = Vec::new();
        for s in 0..2 {
            let o = 1 - s;
            let (Some(fy), Some(fy_o), Some(cop), Some(cop_o), Some(mcop)) = (
                col(&format!("data_grf_y_{}", side[s])),
                col(&format!("data_grf_y_{}", side[o])),
                col(&format!("data_cop_x_{}", side[s])),
                col(&format!("data_cop_x_{}", side[o])),
                col(&format!("model_cop_x_{}", side[s])),
            ) else {
                continue;
            };
            for i in 0..fy
                .len()
                .min(fy_o.len())
                .min(cop.len())
                .min(cop_o.len())
                .min(mcop.len())
            {
                let loaded = fy[i] > LOADED_N && fy_o[i] > LOADED_N;
                if loaded && cop[i] < cop_o[i] && mcop[i].is_finite() {
                    errors.push((mcop[i] - cop[i]).abs());
                }
            }
        }
        let push_off_cop_m = (!errors.is_empty()).then(|| {
            let n = errors.len() as f64;
            let mean = errors.iter().sum::<f64>() / n;
            let sd = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / n).sqrt();
            let max = errors.iter().copied().fold(0.0, f64::max);
            (mean, sd, max, errors.len())
        });
        ContactFigures {
            tangential_rmse_n: [rmse("grf_x", 0), rmse("grf_x", 1)],
            normal_rmse_n: [rmse("grf_y", 0), rmse("grf_y", 1)],
            push_off_cop_m,
        }
    }
}

/// The comparison's result.
pub struct ContactComparison {
    /// Where it was written.
    pub path: PathBuf,
    /// One outcome per run, in order.
    pub runs: Vec<RunOutcome>,
    /// The table of solver figures, RMSE and push-off CoP error.
    pub table: Table,
}

/// Run the four tracks `req` describes into sub-folders of `req.out`, then write the
/// comparison (`contact.md`, `table3.md`, `summary.json`, `report.html`). Every run is
/// written whether or not it converged; an identifying run starts from its base run's
/// solution either way, and the table says how each ended.
pub fn compare_contact(
    req: &CompareContactRequest,
    progress: &dyn Progress,
) -> anyhow::Result<ContactComparison> {
    req.sqp.check_limits()?;
    // every run's problem is built before the first is solved: a bad foot, phase graph or
    // trial stops the comparison before any time is spent, with nothing written
    let setups: Vec<(TrackingRunSetup, Vec<EffectSpec>)> = PLANS
        .iter()
        .map(|plan| {
            let (foot, phases) = if plan.volumetric {
                (&req.volumetric_foot, &req.volumetric_phases)
            } else {
                (&req.rigid_foot, &req.rigid_phases)
            };
            let effects = match plan.effect {
                Some(e) => vec![EffectSpec::parse_cli(e)?],
                None => vec![],
            };
            let run = TrackingRunSetup {
                foot: foot.clone(),
                phases: phases.clone(),
                effects: vec![],
                parameters: vec![],
                check_points: vec![],
                ..req.run.clone()
            };
            TrackingProblem::build(&run, &effects)
                .with_context(|| format!("compare-contact, run {}", plan.name))?;
            Ok((run, effects))
        })
        .collect::<anyhow::Result<_>>()?;
    let folder = RunFolder::create(&req.out, req.overwrite)?;
    let mut dirs: Vec<PathBuf> = Vec::new();
    let mut curves: Vec<RunCurves> = Vec::new();
    let mut runs = Vec::new();
    for (plan, (run, effects)) in PLANS.iter().zip(setups) {
        note!(progress, "── {} ──", plan.name);
        let track_req = TrackRequest {
            run,
            effects,
            init: plan.init.map(|i| dirs[i].clone()),
            check_points: req.check_points,
            sqp: req.sqp.clone(),
            transient_threshold: req.transient_threshold,
        };
        let sub = RunFolder::create(&folder.staging_path().join(plan.name), false)?;
        let done = track(&track_req, sub, progress)
            .with_context(|| format!("compare-contact, run {}", plan.name))?;
        dirs.push(done.output.path.clone());
        let run_curves = RunCurves::read(&done.output.path)?;
        let figures = ContactFigures::of(&run_curves);
        curves.push(run_curves);
        runs.push(RunOutcome {
            name: plan.name.to_string(),
            status: done.result.status.to_string(),
            sqp_status: done.result.status.clone(),
            converged: done.converged,
            physically_valid: done.output.validity.as_ref().map(|v| v.is_valid()),
            iterations: done.result.history.len().saturating_sub(1),
            seconds: done.result.seconds,
            objective: done.result.objective,
            kkt: done.result.kkt,
            parameters: done
                .record
                .parameters
                .iter()
                .filter(|p| p.free)
                .map(|p| (p.name.clone(), p.value, p.sd, p.unit.clone()))
                .collect(),
            figures,
        });
    }
    let table = contact_table(&runs);
    let mut report = side_by_side(&curves);
    report.title = format!("footfall compare-contact — {}", req.run.model.display());
    let all_converged = runs.iter().all(|r| r.converged);
    report.summary.status = if all_converged {
        "all converged".into()
    } else {
        "not all converged".into()
    };
    report.summary.tone = if all_converged {
        Tone::Good
    } else {
        Tone::Warning
    };
    report.summary.time_s = Some(runs.iter().map(|r| r.seconds).sum());
    // the side-by-side summary names each run's summary file where it was staged; say
    // how each ended instead
    report.summary.extra = runs
        .iter()
        .map(|r| {
            (
                r.name.clone(),
                format!(
                    "{}; J {:.4}, {} iterations, {:.0} s",
                    r.status, r.objective, r.iterations, r.seconds
                ),
            )
        })
        .collect();
    let parameters = parameter_table(&runs);
    report.sections.insert(
        0,
        Section {
            heading: "Rigid against compliant".into(),
            paragraphs: vec![format!(
                "The same trial and tracking problem with four feet: the rigid foot ({}), the same with its geometry identified (`foot_geometry`, started from the rigid run), the volumetric foot with its file's contact law ({}) and the same with its law identified (`volumetric_contact`, started from the volumetric run). RMSE on the 1 ms grid over the tracked half cycle, each foot's forces against its own measurement; Ezati et al. (2020) report their RMSE over a gait cycle (Table 7, optimal control). The push-off CoP error: |model − measured| CoP of the trailing foot while both measured normal forces exceed {LOADED_N} N. Each run's own folder, with its report, is the sub-folder of its name. Every run's cost: {}, the pelvis position {}.",
                req.rigid_foot,
                req.volumetric_foot,
                targets_said(&req.run),
                if req.run.track_pelvis_position { "tracked" } else { "untracked" },
            )],
            tables: vec![table.clone(), parameters.clone()],
            svgs: vec![],
        },
    );
    let summary = serde_json::json!({
        "command": "compare-contact",
        "model": req.run.model,
        "rigid_foot": req.rigid_foot,
        "volumetric_foot": req.volumetric_foot,
        "targets": targets_said(&req.run),
        "pelvis_position_tracked": req.run.track_pelvis_position,
        "ezati2020_grf_rmse_n": {"tangential": EZATI2020_GRF_RMSE[0], "normal": EZATI2020_GRF_RMSE[1]},
        "runs": runs,
    });
    folder.write(
        "summary.json",
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    folder.write(
        "contact.md",
        format!("{}\n{}", table.to_markdown(), parameters.to_markdown()).as_bytes(),
    )?;
    if let Some(t3) = report.sections.get(1).and_then(|s| s.tables.first()) {
        folder.write("table3.md", t3.to_markdown().as_bytes())?;
    }
    folder.write("report.html", report.to_html().as_bytes())?;
    let path = folder.commit()?;
    progress.result(&table.to_markdown());
    note!(progress, "report: {}", path.join("report.html").display());
    Ok(ContactComparison { path, runs, table })
}

/// How the runs' cost compares model and measurement, in words.
fn targets_said(run: &TrackingRunSetup) -> &'static str {
    match run.target_sides() {
        TargetSides::Samples => "every sample at its own instant (sample targets)",
        TargetSides::OneSided { .. } => "node targets from each phase's own samples",
        TargetSides::Interpolated => "node targets from splines",
    }
}

/// The comparison's table: one column per run and one for Ezati et al. (2020).
fn contact_table(runs: &[RunOutcome]) -> Table {
    let mut headers = vec![String::new()];
    headers.extend(runs.iter().map(|r| r.name.clone()));
    headers.push("Ezati et al. 2020 (Table 7)".into());
    let n = |v: Option<f64>| v.map_or("—".to_string(), |x| format!("{x:.1}"));
    let mean = |a: [Option<f64>; 2]| match a {
        [Some(r), Some(l)] => Some(0.5 * (r + l)),
        _ => None,
    };
    let row = |label: &str, f: &dyn Fn(&RunOutcome) -> String, seed: String| {
        let mut r = vec![label.to_string()];
        r.extend(runs.iter().map(f));
        r.push(seed);
        r
    };
    let s = EZATI2020_GRF_RMSE;
    let rows = vec![
        row(
            "status",
            &|r| {
                let valid = match r.physically_valid {
                    Some(true) => "",
                    Some(false) => ", physically INVALID",
                    None => ", validity unknown",
                };
                format!("{}{valid}", r.status)
            },
            "—".into(),
        ),
        row("iterations", &|r| r.iterations.to_string(), "—".into()),
        row(
            "solve time (s)",
            &|r| format!("{:.1}", r.seconds),
            "660 (optimal control)".into(),
        ),
        row(
            "objective J",
            &|r| format!("{:.4}", r.objective),
            "—".into(),
        ),
        row("KKT", &|r| format!("{:.1e}", r.kkt), "—".into()),
        row(
            "tangential GRF RMSE, right / left (N)",
            &|r| {
                let t = r.figures.tangential_rmse_n;
                format!("{} / {}", n(t[0]), n(t[1]))
            },
            format!("{:.2} / {:.2}", s[0][0], s[0][1]),
        ),
        row(
            "normal GRF RMSE, right / left (N)",
            &|r| {
                let t = r.figures.normal_rmse_n;
                format!("{} / {}", n(t[0]), n(t[1]))
            },
            format!("{:.2} / {:.2}", s[1][0], s[1][1]),
        ),
        row(
            "tangential / normal GRF RMSE, mean of the legs (N)",
            &|r| {
                format!(
                    "{} / {}",
                    n(mean(r.figures.tangential_rmse_n)),
                    n(mean(r.figures.normal_rmse_n))
                )
            },
            format!(
                "{:.2} / {:.2}",
                0.5 * (s[0][0] + s[0][1]),
                0.5 * (s[1][0] + s[1][1])
            ),
        ),
        row(
            "push-off CoP error (cm)",
            &|r| match r.figures.push_off_cop_m {
                Some((m, sd, max, _)) => {
                    format!("{:.1} ± {:.1} (max {:.1})", 1e2 * m, 1e2 * sd, 1e2 * max)
                }
                None => "— (no double support)".into(),
            },
            "—".into(),
        ),
    ];
    Table {
        title: "Rigid against compliant: solver, ground-force RMSE (1 ms grid) and push-off CoP"
            .into(),
        headers,
        rows,
    }
}

/// The identified parameters of every run, one row each: run, parameter, value, sd, unit
/// (`—` where the run has none: a parameter at its bound, or a run that did not converge).
fn parameter_table(runs: &[RunOutcome]) -> Table {
    let rows = runs
        .iter()
        .flat_map(|r| {
            r.parameters.iter().map(move |(name, v, sd, unit)| {
                vec![
                    r.name.clone(),
                    name.clone(),
                    format!("{v:.4}"),
                    sd.map_or("—".into(), |sd| format!("{sd:.4}")),
                    unit.clone(),
                ]
            })
        })
        .collect();
    Table {
        title: "Identified parameters".into(),
        headers: ["run", "parameter", "value", "sd", "unit"]
            .map(String::from)
            .to_vec(),
        rows,
    }
}

/// The status of the comparison as a whole: the first run that did not converge (for the
/// exit code), else None.
pub fn first_unconverged(cmp: &ContactComparison) -> Option<&RunOutcome> {
    cmp.runs.iter().find(|r| !r.converged)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// Columns of `n` samples given by closures of the sample index.
    fn run(n: usize, cols: &[(&str, &dyn Fn(usize) -> f64)]) -> BTreeMap<String, Vec<f64>> {
        cols.iter()
            .map(|(name, f)| (name.to_string(), (0..n).map(f).collect()))
            .collect()
    }

    #[test]
    fn rmse_and_push_off_error_follow_their_definitions() {
        // right: a constant 3 N tangential error and a normal error alternating ±4 N; left:
        // exact except one sample off by 10 N and one undefined model sample (skipped)
        let zero = |_: usize| 0.0;
        let right_fy = |i: usize| if i < 4 { 500.0 } else { 10.0 };
        let r = run(
            10,
            &[
                ("model_grf_x_r", &|_| 3.0),
                ("data_grf_x_r", &zero),
                ("model_grf_y_r", &|i| {
                    right_fy(i) + if i % 2 == 0 { 4.0 } else { -4.0 }
                }),
                ("data_grf_y_r", &right_fy),
                ("model_grf_x_l", &zero),
                ("data_grf_x_l", &zero),
                ("model_grf_y_l", &|i| match i {
                    0 => 110.0,
                    1 => f64::NAN,
                    _ => 100.0,
                }),
                ("data_grf_y_l", &|_| 100.0),
                // double support for i < 4 (right still above 20 N); the right foot is
                // behind the left for i < 3 only
                ("data_cop_x_r", &|i| 0.1 * i as f64),
                ("data_cop_x_l", &|_| 0.25),
                ("model_cop_x_r", &|i| 0.1 * i as f64 + 0.01 * (i + 1) as f64),
                ("model_cop_x_l", &|_| 0.25),
            ],
        );
        let f = ContactFigures::from_columns(&r);
        assert_eq!(f.tangential_rmse_n[0], Some(3.0));
        assert!((f.normal_rmse_n[0].unwrap() - 4.0).abs() < 1e-12);
        assert_eq!(f.tangential_rmse_n[1], Some(0.0));
        // 9 defined samples, one of them 10 N off
        assert!((f.normal_rmse_n[1].unwrap() - (100.0f64 / 9.0).sqrt()).abs() < 1e-12);
        // right trailing at i = 0, 1, 2 (errors 1, 2, 3 cm), the left at i = 3 (right
        // CoP 0.3 m ahead of the left's 0.25 m; error 0)
        let (mean, sd, max, count) = f.push_off_cop_m.unwrap();
        assert_eq!(count, 4);
        assert!((mean - 0.015).abs() < 1e-12);
        assert!((sd - 1.25f64.sqrt() * 0.01).abs() < 1e-12);
        assert!((max - 0.03).abs() < 1e-12);
    }

    #[test]
    fn a_run_without_force_columns_has_no_figures() {
        let f = ContactFigures::from_columns(&run(5, &[("model_hip_r", &|_| 0.0)]));
        assert_eq!(f, ContactFigures::default());
    }

    #[test]
    fn each_identified_parameter_gets_a_row_and_a_missing_sd_is_said() {
        let outcome = |name: &str, parameters| RunOutcome {
            name: name.into(),
            status: "converged".into(),
            sqp_status: SqpStatus::Converged,
            converged: true,
            physically_valid: Some(true),
            iterations: 1,
            seconds: 1.0,
            objective: 1.0,
            kkt: 1e-6,
            parameters,
            figures: ContactFigures::default(),
        };
        let t = parameter_table(&[
            outcome("rigid", vec![]),
            outcome(
                "geometry",
                vec![
                    ("a".into(), 0.2, Some(0.005), "m".into()),
                    ("b".into(), 0.05, None, "m".into()),
                ],
            ),
        ]);
        assert_eq!(t.rows.len(), 2);
        assert_eq!(t.rows[0], ["geometry", "a", "0.2000", "0.0050", "m"]);
        assert_eq!(t.rows[1][3], "—");
    }

    /// The report names the targets the tracks used: the same precedence as `track`'s
    /// (one-sided targets before sample targets, should a library caller set both).
    #[test]
    fn the_targets_said_are_the_ones_the_tracks_use() {
        let mut run = crate::workflows::track::TrackRequest::new("ellipse").run;
        assert_eq!(targets_said(&run), "node targets from splines");
        run.sample_targets = true;
        assert!(targets_said(&run).contains("sample targets"));
        run.one_sided_targets = true;
        assert!(matches!(run.target_sides(), TargetSides::OneSided { .. }));
        assert_eq!(
            targets_said(&run),
            "node targets from each phase's own samples"
        );
    }

    #[test]
    fn the_published_column_is_table_7s_optimal_control() {
        // the paper's figures as means of the legs: 14.07 N tangential and 26.44 N normal
        let s = EZATI2020_GRF_RMSE;
        assert!((0.5 * (s[0][0] + s[0][1]) - 14.07).abs() < 1e-9);
        assert!((0.5 * (s[1][0] + s[1][1]) - 26.435).abs() < 1e-9);
        let t = contact_table(&[]);
        assert_eq!(t.headers.last().unwrap(), "Ezati et al. 2020 (Table 7)");
        assert!(t
            .rows
            .iter()
            .any(|r| r.last().unwrap() == "14.07 / 26.43" || r.last().unwrap() == "14.07 / 26.44"));
    }
}
