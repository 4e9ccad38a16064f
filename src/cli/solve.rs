//! `footfall solve`: generic optimal control problems (not gait) through the same
//! multiple-shooting + SQP engine.

use super::Failure;
use anyhow::{anyhow, Context};
use footfall::integrate::{IntegratorSettings, Method};
use footfall::ocp::{Block, Transcription};
use footfall::problems::benchmark::Benchmark;
use footfall::sqp::{HessianMode, SqpSettings};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Hessian choice on the command line.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum HessianArg {
    /// Gauss–Newton of the least-squares objective.
    GaussNewton,
    /// Block-diagonal BFGS of the Lagrangian.
    Bfgs,
    /// Gauss–Newton plus block BFGS of the constraint curvature.
    GaussNewtonBfgs,
    /// Exact Hessian of the Lagrangian (second-order sensitivities).
    Exact,
}

impl From<HessianArg> for HessianMode {
    fn from(h: HessianArg) -> Self {
        match h {
            HessianArg::GaussNewton => HessianMode::GaussNewton,
            HessianArg::Bfgs => HessianMode::Bfgs,
            HessianArg::GaussNewtonBfgs => HessianMode::GaussNewtonBfgs,
            HessianArg::Exact => HessianMode::Exact,
        }
    }
}

/// CVODES linear multistep method.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum MethodArg {
    /// Adams–Moulton (non-stiff problems; default for the generic problems).
    Adams,
    /// BDF (stiff problems).
    Bdf,
}

/// Arguments of `footfall solve`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Problem file (JSON), e.g. problems/cartpole_swingup.json or problems/five_link_biped.json.
    #[arg(long, required_unless_present = "resume")]
    problem: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "runs/solve")]
    out: PathBuf,
    /// Replace the output folder if it exists.
    #[arg(long)]
    overwrite: bool,
    /// Continue the run a killed process left unfinished in this output folder, from its
    /// last SQP iteration, with the options it was started with (give no others).
    #[arg(long, value_name = "DIR")]
    pub resume: Option<PathBuf>,
    /// Start from the variables of a previous solution.json.
    #[arg(long)]
    warm_start: Option<PathBuf>,
    /// KKT tolerance.
    #[arg(long, default_value_t = 1e-6, value_parser = super::validate::positive)]
    tol: f64,
    /// Iteration limit.
    #[arg(long, default_value_t = 200, value_parser = super::validate::iterations)]
    max_iter: usize,
    /// Wall-time limit (s).
    #[arg(long, value_parser = super::validate::positive)]
    max_time: Option<f64>,
    /// CVODES method for the shooting intervals.
    #[arg(long, value_enum, default_value = "adams")]
    integrator: MethodArg,
    /// Hessian approximation (default: exact).
    #[arg(long, value_enum)]
    hessian: Option<HessianArg>,
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    run_inner(args, quiet).map_err(Failure::classify)
}

fn run_inner(args: Args, quiet: bool) -> anyhow::Result<()> {
    // clap requires --problem unless --resume, which main replaces by the killed run's options
    let problem = args
        .problem
        .clone()
        .ok_or_else(|| anyhow!("--problem is required"))?;
    let bench = Benchmark::load(&problem)?;
    let method = match args.integrator {
        MethodArg::Adams => Method::Adams,
        MethodArg::Bdf => Method::Bdf,
    };
    let ocp = bench
        .ocp(IntegratorSettings {
            method,
            ..Default::default()
        })
        .map_err(|e| anyhow!("{}: {e}", problem.display()))?;
    let tr = Transcription::new(&ocp).context("transcribing the problem")?;
    let (_, _, mut w0) = tr.variable_bounds_and_guess();
    if let Some(ws) = &args.warm_start {
        let v: serde_json::Value = footfall::model::spec::read_json(ws)?;
        let w: Vec<f64> = v
            .get("w")
            .and_then(|w| w.as_array())
            .ok_or_else(|| {
                anyhow!(
                    "{}: field 'w' missing (expected a footfall solution.json)",
                    ws.display()
                )
            })?
            .iter()
            .map(|x| {
                x.as_f64()
                    .ok_or_else(|| anyhow!("{}: field 'w' must hold numbers", ws.display()))
            })
            .collect::<anyhow::Result<_>>()?;
        if w.len() != w0.len() {
            return Err(anyhow!(
                "{}: field 'w' has {} values, this problem has {}",
                ws.display(),
                w.len(),
                w0.len()
            ));
        }
        w0 = w;
    }
    let hessian = args.hessian.map_or(HessianMode::Exact, HessianMode::from);
    let settings = SqpSettings {
        tol_kkt: args.tol,
        max_iter: args.max_iter,
        max_time: args.max_time,
        hessian,
        ..Default::default()
    };
    let folder = super::session::create_checkpointed_run_folder(&args.out, args.overwrite)?;
    if !quiet {
        eprintln!(
            "solving {} ({} variables, {} constraints) with {hessian:?}",
            bench.name(),
            tr.n(),
            tr.m()
        );
    }
    let res = super::solve_interruptibly(&tr, &w0, &settings, quiet)?;

    // solution: variables, and node states/controls per phase on their time grid
    let mut phases = Vec::new();
    let mut csv = String::new();
    for (j, ph) in ocp.phases.iter().enumerate() {
        let h = ph.duration.value / ph.intervals as f64;
        let states: Vec<Vec<f64>> = (0..=ph.intervals)
            .map(|k| res.w[tr.range(Block::State { phase: j, node: k })].to_vec())
            .collect();
        let controls: Vec<Vec<f64>> = (0..ph.control_nodes())
            .map(|k| res.w[tr.range(Block::Control { phase: j, node: k })].to_vec())
            .collect();
        if j == 0 {
            csv.push_str("time,phase");
            for i in 0..ph.ode.nx() {
                write!(csv, ",x{i}").ok();
            }
            for i in 0..ph.ode.nu() {
                write!(csv, ",u{i}").ok();
            }
            csv.push('\n');
        }
        for (k, x) in states.iter().enumerate() {
            write!(csv, "{:.9},{}", k as f64 * h, ph.name).ok();
            for v in x {
                write!(csv, ",{v:.12e}").ok();
            }
            // piecewise-constant control of the interval that starts here (the last node repeats the last)
            let u = &controls[k.min(controls.len() - 1)];
            for v in u {
                write!(csv, ",{v:.12e}").ok();
            }
            csv.push('\n');
        }
        phases.push(serde_json::json!({
            "name": ph.name, "duration_s": ph.duration.value, "intervals": ph.intervals,
            "states": states, "controls": controls,
        }));
    }
    let solution = serde_json::json!({
        "problem": bench.name(),
        "status": res.status,
        "objective": res.objective,
        "w": res.w,
        "lambda": res.lambda,
        "phases": phases,
    });
    let summary = serde_json::json!({
        "command": "solve",
        "problem": bench.name(),
        "problem_file": problem,
        "status": res.status,
        "stop_reason": res.status.to_string(),
        "objective": res.objective,
        "kkt": res.kkt,
        "infeasibility": res.infeasibility,
        "iterations": res.history.len().saturating_sub(1),
        "seconds": res.seconds,
        "variables": tr.n(),
        "constraints": tr.m(),
        "settings": settings,
        "most_violated": res.most_violated,
        "history": res.history,
    });
    folder.write(
        "solution.json",
        serde_json::to_string_pretty(&solution)?.as_bytes(),
    )?;
    folder.write("solution.csv", csv.as_bytes())?;
    folder.write(
        "summary.json",
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    let out = folder.commit()?;
    if !quiet {
        eprintln!(
            "{}: J = {:.9}, KKT {:.2e}, {} iterations, {:.2} s → {}",
            res.status,
            res.objective,
            res.kkt,
            res.history.len().saturating_sub(1),
            res.seconds,
            out.display()
        );
        for v in res.most_violated.iter().take(5) {
            eprintln!("  violated: {} by {:.3e}", v.name, v.amount);
        }
    }
    super::Unsolved::check(&res, &out)
}
