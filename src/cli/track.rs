//! `footfall track`: track measured walking with the model (seed 001 §3.4).

use super::Failure;
use anyhow::{anyhow, Context};
use footfall::data::CubicSpline;
use footfall::integrate::IntegratorSettings;
use footfall::model::gait::{ContactReport, COORDINATES};
use footfall::model::GaitModel;
use footfall::ocp::{Block, Transcription};
use footfall::phases::PhaseSequence;
use footfall::problems::gait::GaitCycle;
use footfall::problems::track::TrackingSetup;
use footfall::report::csv::TimeSeries;
use footfall::report::html::{Report, Section, Summary, Tone};
use footfall::report::plot::{LinePlot, LineStyle, Series, Span};
use footfall::report::table::{error_table, ChannelErrors, ErrorStats};
use footfall::runfolder::RunFolder;
use footfall::sqp::{self, ExactConvexification, HessianMode, Silent, SqpSettings, SqpStatus, StderrLog};
use std::path::PathBuf;

/// Arguments of `footfall track`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file.
    #[arg(long, default_value = "models/opensim_subject01.json")]
    model: PathBuf,
    /// Foot: `ellipse`, `double-circle` or a foot file.
    #[arg(long, default_value = "ellipse")]
    foot: String,
    /// Phase graph (default: the seed's graph for the bundled feet).
    #[arg(long)]
    phases: Option<PathBuf>,
    /// Sagittal CSV (default: the bundled OpenSim subject01 trial, moved overground).
    #[arg(long)]
    data: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "runs/track")]
    out: PathBuf,
    /// Replace the output folder if it exists.
    #[arg(long)]
    overwrite: bool,
    /// Hessian: exact (converges), or gauss-newton (the seed's; stalls near KKT 3e-5).
    #[arg(long, value_enum, default_value = "exact")]
    hessian: super::solve::HessianArg,
    /// KKT tolerance.
    #[arg(long, default_value_t = 1e-5)]
    tol: f64,
    /// Relative and absolute CVODES tolerance of the shooting intervals.
    #[arg(long, default_value_t = 1e-8)]
    integrator_tol: f64,
    /// With `--hessian exact`: Gauss–Newton steps until the constraint violation is below this.
    #[arg(long, default_value_t = 1e-3)]
    exact_below: f64,
    /// Iteration limit.
    #[arg(long, default_value_t = 200)]
    max_iter: usize,
    /// Wall-time limit (s).
    #[arg(long)]
    max_time: Option<f64>,
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    run_inner(args, quiet).map_err(Failure::User)
}

fn run_inner(args: Args, quiet: bool) -> anyhow::Result<()> {
    let foot_path = super::simulate::foot_path(&args.foot);
    let model = GaitModel::load(&args.model, &foot_path)?;
    let phases = args.phases.clone().unwrap_or_else(|| match args.foot.as_str() {
        "double-circle" | "double_circle" => PathBuf::from("phases/double_circle_walk.json"),
        _ => PathBuf::from("phases/ellipse_walk.json"),
    });
    let seq = PhaseSequence::load(&phases)?;
    let sets = seq.resolve(&model, &phases)?;
    let data = super::load_data(args.data.as_deref())?;
    let setup = TrackingSetup::new(&model, &seq, &sets, &data).map_err(|e| anyhow!("{}: {e}", data.source.display()))?;
    let cycle = GaitCycle::new(&model, &setup.seq, &sets).map_err(|e| anyhow!(e))?;
    let integrator = IntegratorSettings { rtol: args.integrator_tol, atol: args.integrator_tol, ..Default::default() };
    integrator.validate().context("--integrator-tol")?;
    let ocp = setup.ocp(&cycle, &model, &sets, integrator).map_err(|e| anyhow!(e))?;
    let tr = Transcription::new(&ocp).context("transcribing the tracking problem")?;
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let hessian = match args.hessian {
        super::solve::HessianArg::GaussNewton => HessianMode::GaussNewton,
        super::solve::HessianArg::Bfgs => HessianMode::Bfgs,
        super::solve::HessianArg::GaussNewtonBfgs => HessianMode::GaussNewtonBfgs,
        super::solve::HessianArg::Exact => HessianMode::Exact,
    };
    let settings = SqpSettings {
        tol_kkt: args.tol,
        max_iter: args.max_iter,
        max_time: args.max_time,
        hessian,
        exact_hessian_below: args.exact_below,
        exact_convexification: ExactConvexification::InertiaCorrection,
        ..Default::default()
    };
    let folder = RunFolder::create(&args.out, args.overwrite)?;
    if !quiet {
        eprintln!(
            "tracking {:.3}–{:.3} s of {} with the {} foot ({} variables, {} constraints, {:?})",
            setup.window.0,
            setup.window.1,
            data.name,
            model.foot_name,
            tr.n(),
            tr.m(),
            hessian
        );
    }
    super::Interruptible::install();
    let res = if quiet {
        sqp::solve(&tr, &w0, &settings, &mut super::Interruptible(&mut Silent))
    } else {
        sqp::solve(&tr, &w0, &settings, &mut super::Interruptible(&mut StderrLog))
    };

    // model and measurement at the nodes
    let splines: Vec<CubicSpline> = COORDINATES.iter().map(|c| data.spline(c)).collect::<Result<_, _>>()?;
    let mut times = Vec::new();
    let mut phase_of = Vec::new();
    let mut model_q: Vec<Vec<f64>> = vec![Vec::new(); 9];
    let mut meas_q: Vec<Vec<f64>> = vec![Vec::new(); 9];
    let mut model_f: Vec<Vec<f64>> = vec![Vec::new(); 6];
    let mut meas_f: Vec<Vec<f64>> = vec![Vec::new(); 6];
    let mut spans = Vec::new();
    let theta = model.theta0();
    for (j, ts) in setup.node_times.iter().enumerate() {
        let set = &sets[cycle.continuous[j]];
        spans.push(Span::new(ts[0], *ts.last().unwrap_or(&ts[0]), ocp.phases[j].name.clone()));
        let n = ts.len() - 1;
        for (k, &t) in ts.iter().enumerate() {
            if k == n && j + 1 < setup.node_times.len() {
                continue;
            }
            let x = &res.w[tr.range(Block::State { phase: j, node: k })];
            let ku = k.min(ocp.phases[j].control_nodes() - 1);
            let u = &res.w[tr.range(Block::Control { phase: j, node: ku })];
            let mut xdot = vec![0.0; model.nx()];
            let mut lam = vec![0.0; set.rows.len()];
            let mut rep = ContactReport::default();
            model.dynamics(set, x, u, &theta, &mut xdot, &mut lam, Some(&mut rep))?;
            let loads = model.foot_loads(set, &rep);
            times.push(t);
            phase_of.push(ocp.phases[j].name.clone());
            for i in 0..9 {
                model_q[i].push(x[i]);
                meas_q[i].push(splines[i].eval(t));
            }
            for s in 0..2 {
                model_f[3 * s].push(loads[s].fx);
                model_f[3 * s + 1].push(loads[s].fy);
                model_f[3 * s + 2].push(if loads[s].fy > data.cop_threshold { loads[s].cop_x } else { f64::NAN });
                let at = |v: &[f64]| footfall::data::interp_linear(&[t], &data.time, v)[0];
                meas_f[3 * s].push(at(&data.feet[s].fx));
                meas_f[3 * s + 1].push(at(&data.feet[s].fy));
                meas_f[3 * s + 2].push(at(&data.feet[s].cop_x));
            }
        }
    }
    // seed Table 3 channels, both legs pooled
    let foot_angle = |q: &Vec<Vec<f64>>, s: usize| -> Vec<f64> {
        (0..q[0].len()).map(|k| q[2][k] + q[3 + 3 * s][k] + q[4 + 3 * s][k] + q[5 + 3 * s][k]).collect()
    };
    let pooled = |a: Vec<f64>, b: Vec<f64>, c: Vec<f64>, d: Vec<f64>| -> ErrorStats {
        let mut e: Vec<f64> = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).collect();
        e.extend(c.iter().zip(&d).map(|(x, y)| (x - y).abs()));
        ErrorStats::from_errors(&e)
    };
    let deg = 180.0 / std::f64::consts::PI;
    let loaded = |s: usize, v: &Vec<f64>| -> Vec<f64> {
        v.iter().zip(&meas_f[3 * s + 1]).map(|(x, fy)| if *fy > data.cop_threshold { *x } else { f64::NAN }).collect()
    };
    let channels = vec![
        ChannelErrors {
            name: "foot orientation".into(),
            unit: "°".into(),
            decimals: 1,
            runs: vec![Some(pooled(foot_angle(&model_q, 0), foot_angle(&meas_q, 0), foot_angle(&model_q, 1), foot_angle(&meas_q, 1)).scaled(deg))],
        },
        ChannelErrors {
            name: "CoP".into(),
            unit: "cm".into(),
            decimals: 1,
            runs: vec![Some(pooled(model_f[2].clone(), meas_f[2].clone(), model_f[5].clone(), meas_f[5].clone()).scaled(100.0))],
        },
        ChannelErrors {
            name: "tangential GRF".into(),
            unit: "N".into(),
            decimals: 1,
            runs: vec![Some(pooled(loaded(0, &model_f[0]), meas_f[0].clone(), loaded(1, &model_f[3]), meas_f[3].clone()))],
        },
        ChannelErrors {
            name: "normal GRF".into(),
            unit: "N".into(),
            decimals: 1,
            runs: vec![Some(pooled(loaded(0, &model_f[1]), meas_f[1].clone(), loaded(1, &model_f[4]), meas_f[4].clone()))],
        },
        ChannelErrors { name: "ankle angle".into(), unit: "°".into(), decimals: 1, runs: vec![Some(pooled(model_q[5].clone(), meas_q[5].clone(), model_q[8].clone(), meas_q[8].clone()).scaled(deg))] },
        ChannelErrors { name: "knee angle".into(), unit: "°".into(), decimals: 1, runs: vec![Some(pooled(model_q[4].clone(), meas_q[4].clone(), model_q[7].clone(), meas_q[7].clone()).scaled(deg))] },
        ChannelErrors { name: "hip angle".into(), unit: "°".into(), decimals: 1, runs: vec![Some(pooled(model_q[3].clone(), meas_q[3].clone(), model_q[6].clone(), meas_q[6].clone()).scaled(deg))] },
    ];
    let table = error_table("Tracking errors at the shooting nodes (seed Table 3 layout; both legs pooled)", &[model.foot_name.clone()], &channels);

    // time series and plots
    let mut ts = TimeSeries::new(times.clone())?;
    ts.push_text("phase", phase_of.clone())?;
    for i in 0..9 {
        ts.push(&format!("model_{}", COORDINATES[i]), model_q[i].clone())?;
        ts.push(&format!("data_{}", COORDINATES[i]), meas_q[i].clone())?;
    }
    for (s, side) in ["r", "l"].iter().enumerate() {
        for (k, what) in ["grf_x", "grf_y", "cop_x"].iter().enumerate() {
            ts.push(&format!("model_{what}_{side}"), model_f[3 * s + k].clone())?;
            ts.push(&format!("data_{what}_{side}"), meas_f[3 * s + k].clone())?;
        }
    }
    let plot = |title: &str, unit: &str, m: &Vec<f64>, d: &Vec<f64>, scale: f64| {
        let mut p = LinePlot::new(title, "time (s)", unit);
        p.series.push(Series::new("model", times.clone(), m.iter().map(|v| v * scale).collect(), LineStyle::Solid));
        p.series.push(Series::new("measured", times.clone(), d.iter().map(|v| v * scale).collect(), LineStyle::Markers));
        p.shaded = spans.clone();
        p.to_svg()
    };
    let mut kin = Vec::new();
    for i in 2..9 {
        kin.push(plot(&COORDINATES[i].replace('_', " "), "angle (°)", &model_q[i], &meas_q[i], deg));
    }
    let mut forces = Vec::new();
    for (s, side) in ["right", "left"].iter().enumerate() {
        forces.push(plot(&format!("Normal GRF, {side} foot"), "force (N)", &model_f[3 * s + 1], &meas_f[3 * s + 1], 1.0));
        forces.push(plot(&format!("Tangential GRF, {side} foot"), "force (N)", &model_f[3 * s], &meas_f[3 * s], 1.0));
        forces.push(plot(&format!("CoP, {side} foot"), "x (m)", &model_f[3 * s + 2], &meas_f[3 * s + 2], 1.0));
    }
    let converged = res.status == SqpStatus::Converged;
    let mut summary = Summary::new(
        if converged { "converged" } else { "not converged" },
        if converged { Tone::Good } else { Tone::Warning },
        res.status.to_string(),
    );
    summary.iterations = Some(res.history.len().saturating_sub(1));
    summary.time_s = Some(res.seconds);
    summary.extra = vec![
        ("objective".into(), format!("{:.6}", res.objective)),
        ("KKT residual".into(), format!("{:.2e}", res.kkt)),
        ("window".into(), format!("{:.3}–{:.3} s", setup.window.0, setup.window.1)),
    ];
    let report = Report {
        title: format!("footfall tracking — {} foot, {}", model.foot_name, data.name),
        summary,
        sections: vec![
            Section { heading: "Errors".into(), paragraphs: vec!["Model against the measurement at the shooting nodes.".into()], tables: vec![table.clone()], svgs: vec![] },
            Section { heading: "Kinematics".into(), paragraphs: vec![], tables: vec![], svgs: kin },
            Section { heading: "Ground reaction forces and centre of pressure".into(), paragraphs: vec![], tables: vec![], svgs: forces },
        ],
    };
    let summary_json = serde_json::json!({
        "command": "track",
        "model": model.name,
        "foot": model.foot_name,
        "phases": phases,
        "data": data.source,
        "window_s": [setup.window.0, setup.window.1],
        "status": res.status,
        "stop_reason": res.status.to_string(),
        "iterations": res.history.len().saturating_sub(1),
        "seconds": res.seconds,
        "objective": res.objective,
        "kkt": res.kkt,
        "timings": res.timings,
        "errors_table3": channels.iter().map(|c| serde_json::json!({"channel": c.name, "unit": c.unit, "mean": c.runs[0].map(|s| s.mean), "sd": c.runs[0].map(|s| s.sd), "max": c.runs[0].map(|s| s.max)})).collect::<Vec<_>>(),
        "most_violated": res.most_violated,
        "history": res.history,
    });
    folder.write("summary.json", serde_json::to_string_pretty(&summary_json)?.as_bytes())?;
    folder.write("tracking.csv", ts.to_csv().as_bytes())?;
    folder.write("kinematics.sto", ts.to_sto("footfall_tracking").as_bytes())?;
    folder.write("table3.md", table.to_markdown().as_bytes())?;
    folder.write("report.html", report.to_html().as_bytes())?;
    let out = folder.commit()?;
    if !quiet {
        eprintln!("{}\n{}: J = {:.6}, KKT {:.2e}, {} iterations, {:.1} s", table.to_markdown(), res.status, res.objective, res.kkt, res.history.len().saturating_sub(1), res.seconds);
        eprintln!("report: {}", out.join("report.html").display());
    }
    if converged {
        Ok(())
    } else {
        Err(anyhow!("the solver stopped without converging: {} (results written to {})", res.status, out.display()))
    }
}
