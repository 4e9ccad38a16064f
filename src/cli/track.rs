//! `footfall track`: track measured walking with the model (seed 001 §3.4).

use super::Failure;
use anyhow::{anyhow, Context};
use super::gait_run::GaitRun;
use footfall::integrate::IntegratorSettings;
use footfall::model::GaitModel;
use footfall::ocp::Transcription;
use footfall::phases::PhaseSequence;
use footfall::problems::gait::GaitCycle;
use footfall::problems::track::TrackingSetup;
use footfall::problems::evaluation::GaitSolution;
use footfall::runfolder::RunFolder;
use footfall::sqp::{ExactConvexification, HessianMode, SqpSettings, SqpStatus};
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
    /// Low-pass the measured coordinates at this cutoff (Hz; zero-phase 2nd-order
    /// Butterworth) before tracking, for raw motion-capture data.
    #[arg(long)]
    kinematics_cutoff: Option<f64>,
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
    /// Report ground-force excursions above the measurement larger than this (N).
    #[arg(long, default_value_t = super::gait_run::DEFAULT_TRANSIENT_THRESHOLD_N)]
    transient_threshold: f64,
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
    let mut data = super::load_data(args.data.as_deref())?;
    if let Some(fc) = args.kinematics_cutoff {
        data = data.low_pass_kinematics(fc).context("--kinematics-cutoff")?;
    }
    let setup = TrackingSetup::new(&model, &seq, &sets, &data).map_err(|e| anyhow!("{}: {e}", data.source.display()))?;
    let cycle = GaitCycle::new(&model, &setup.seq, &sets).map_err(|e| anyhow!(e))?;
    let integrator = IntegratorSettings { rtol: args.integrator_tol, atol: args.integrator_tol, ..Default::default() };
    integrator.validate().context("--integrator-tol")?;
    let ocp = setup.ocp(&cycle, &model, &sets, integrator.clone()).map_err(|e| anyhow!(e))?;
    let tr = Transcription::new(&ocp).context("transcribing the tracking problem")?;
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let hessian: HessianMode = args.hessian.into();
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
    let res = super::solve_interruptibly(&tr, &w0, &settings, quiet);

    let solution = GaitSolution::from_nlp(&tr, &res.w, &cycle.continuous, setup.window.0);
    let out = super::gait_run::write(
        GaitRun {
            command: "track",
            title: format!("footfall tracking — {} foot, {}", model.foot_name, data.name),
            data: &data,
            model: &model,
            sets: &sets,
            phases_path: &phases,
            result: &res,
            solution: &solution,
            integrator,
            extra_summary: vec![],
            extra_json: Default::default(),
            extra_sections: vec![],
            extra_files: vec![],
            transient_threshold_n: args.transient_threshold,
        },
        folder,
    )?;
    let converged = res.status == SqpStatus::Converged;
    if !quiet {
        eprintln!("{}\n{}: J = {:.6}, KKT {:.2e}, {} iterations, {:.1} s", out.table.to_markdown(), res.status, res.objective, res.kkt, res.history.len().saturating_sub(1), res.seconds);
        if let Some(f) = &out.fine {
            eprintln!(
                "1 ms re-integration: peak normal force {:.1} N (right), {:.1} N (left); largest Baumgarte force {:.1e} N; largest drift {:.2e} m",
                f.peak_normal_force_n[0], f.peak_normal_force_n[1], f.max_baumgarte_force_n, f.max_position_drift_m
            );
        }
        eprintln!("report: {}", out.path.join("report.html").display());
    }
    if converged {
        Ok(())
    } else {
        Err(anyhow!("the solver stopped without converging: {} (results written to {})", res.status, out.path.display()))
    }
}
