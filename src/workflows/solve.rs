//! `footfall solve`: generic optimal control problems (not gait) through the same
//! multiple-shooting + SQP engine.

#[allow(unused_imports)]
use super::{note, warn_note, Progress};
use crate::integrate::{IntegrationStats, IntegratorSettings, Method};
use crate::ocp::{Block, Ocp, Transcription};
use crate::problems::benchmarks::{Benchmark, ProblemFileError};
use crate::problems::peer_gait::{stages, STAGE2_TOL};
use crate::runfolder::RunFolder;
use crate::sqp::{ExactConvexification, HessianMode, SqpResult, SqpSettings, SqpStatus};
use anyhow::{anyhow, Context};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What `solve` does: the arguments of `footfall solve`.
#[derive(Debug, Clone)]
pub struct SolveRequest {
    /// Problem file (JSON), e.g. problems/cartpole_swingup.json or problems/five_link_biped.json.
    pub problem: Option<PathBuf>,
    /// Output folder.
    pub out: PathBuf,
    /// Replace the output folder if it exists.
    pub overwrite: bool,
    /// Start from the variables of a previous solution.json.
    pub warm_start: Option<PathBuf>,
    /// KKT tolerance.
    pub tol: f64,
    /// Iteration limit.
    pub max_iter: usize,
    /// Wall-time limit (s).
    pub max_time: Option<f64>,
    /// CVODES method for the shooting intervals (default: adams, or bdf for the gait
    /// problem).
    pub integrator: Option<crate::integrate::Method>,
    /// Hessian approximation (default: exact).
    pub hessian: Option<crate::sqp::HessianMode>,
}

/// Run `solve` as `args` describes, reporting to `progress`.
pub fn run(args: &SolveRequest, progress: &dyn Progress) -> anyhow::Result<()> {
    // clap requires --problem unless --resume, which main replaces by the killed run's options
    let problem = args
        .problem
        .clone()
        .ok_or_else(|| anyhow!("--problem is required"))?;
    crate::limits::kkt_tolerance(args.tol)?;
    crate::limits::iteration_limit(args.max_iter)?;
    if let Some(t) = args.max_time {
        crate::limits::time_limit(t)?;
    }
    let bench = Benchmark::load(&problem)?;
    // Adams for the smooth generic problems; BDF for the gait, whose light feet make the
    // contact dynamics stiff
    let method = match args.integrator {
        Some(m) => m,
        None if matches!(bench, Benchmark::GaitTrack(_)) => Method::Bdf,
        None => Method::Adams,
    };
    let integrator = IntegratorSettings {
        method,
        ..Default::default()
    };
    let in_file = |source| ProblemFileError::Invalid {
        path: problem.clone(),
        source,
    };
    // the gait problem from its data guess: block BFGS, then the exact Hessian with tight
    // integration (peer_gait::stages), unless the Hessian or integrator is chosen
    let staged = matches!(bench, Benchmark::GaitTrack(_))
        && args.hessian.is_none()
        && args.integrator.is_none();
    if !staged {
        let settings = single_stage_settings(&bench, &args);
        return bench
            .with_ocp(integrator, |ocp| {
                let tr = Transcription::new(ocp).context("transcribing the problem")?;
                let w0 = start(&tr, &args)?;
                let folder =
                    super::session::create_checkpointed_run_folder(&args.out, args.overwrite)?;
                announce(&bench, &tr, &format!("{:?}", settings.hessian), progress);
                let res = super::solve_interruptibly(&tr, &w0, &settings, progress)?;
                let counters = tr.integration_totals();
                write_run(
                    folder, ocp, &tr, &bench, &problem, &settings, res, counters, progress,
                )
            })
            .map_err(in_file)?;
    }
    let [first, second] = stages(args.tol);
    let limit =
        |stage: &crate::problems::peer_gait::SolveStage, used: usize, spent: f64| SqpSettings {
            max_iter: args.max_iter.saturating_sub(used),
            max_time: args.max_time.map(|t| (t - spent).max(0.0)),
            ..stage.settings.clone()
        };
    let s1 = limit(&first, 0, 0.0);
    let mut folder = None;
    let mut counters = IntegrationStats::default();
    let r1 = bench
        .with_ocp(first.integrator.clone(), |ocp| {
            let tr = Transcription::new(ocp).context("transcribing the problem")?;
            let w0 = start(&tr, &args)?;
            folder = Some(super::session::create_checkpointed_run_folder(
                &args.out,
                args.overwrite,
            )?);
            announce(
                &bench,
                &tr,
                &format!(
                    "block BFGS to KKT {:.0e}, then the exact Hessian with CVODES at {STAGE2_TOL:.0e}",
                    s1.tol_kkt
                ),
                progress,
            );
            let res = super::solve_interruptibly(&tr, &w0, &s1, progress);
            counters += tr.integration_totals();
            res
        })
        .map_err(in_file)??;
    let folder = folder.expect("created by the first stage");
    let go_on = r1.status == SqpStatus::Converged && r1.kkt > args.tol;
    let s2 = limit(&second, r1.history.len().saturating_sub(1), r1.seconds);
    let integrator2 = if go_on {
        second.integrator.clone()
    } else {
        first.integrator.clone()
    };
    bench
        .with_ocp(integrator2, |ocp| {
            let tr = Transcription::new(ocp).context("transcribing the problem")?;
            if !go_on {
                return write_run(
                    folder, ocp, &tr, &bench, &problem, &s1, r1, counters, progress,
                );
            }
            {
                note!(
                    progress,
                    "KKT {:.2e} ≤ {:.0e}: on with the exact Hessian and CVODES at {STAGE2_TOL:.0e}",
                    r1.kkt,
                    s1.tol_kkt
                );
            }
            let r2 = super::solve_interruptibly(&tr, &r1.w, &s2, progress)?;
            let res = r1.followed_by(r2);
            counters += tr.integration_totals();
            write_run(
                folder, ocp, &tr, &bench, &problem, &s2, res, counters, progress,
            )
        })
        .map_err(in_file)?
}

/// SQP settings of a one-stage solve: the command line's, and for the gait problem
/// footfall track's globalisation (Gauss–Newton steps until the constraints nearly hold,
/// then the exact curvature kept convex by an inertia correction).
fn single_stage_settings(bench: &Benchmark, args: &SolveRequest) -> SqpSettings {
    let hessian = args.hessian.map_or(HessianMode::Exact, HessianMode::from);
    let mut settings = SqpSettings {
        tol_kkt: args.tol,
        max_iter: args.max_iter,
        max_time: args.max_time,
        hessian,
        ..Default::default()
    };
    if matches!(bench, Benchmark::GaitTrack(_)) {
        settings.exact_hessian_below = 1e-3;
        settings.exact_convexification = ExactConvexification::InertiaCorrection;
    }
    settings
}

fn announce(bench: &Benchmark, tr: &Transcription, how: &str, progress: &dyn Progress) {
    {
        note!(
            progress,
            "solving {} ({} variables, {} constraints) with {how}",
            bench.name(),
            tr.n(),
            tr.m()
        );
    }
}

/// The starting point: the problem's guess, or the variables of `--warm-start`.
fn start(tr: &Transcription, args: &SolveRequest) -> anyhow::Result<Vec<f64>> {
    let (_, _, mut w0) = tr.variable_bounds_and_guess();
    if let Some(ws) = &args.warm_start {
        let v: serde_json::Value = crate::model::spec::read_json(ws)?;
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
    Ok(w0)
}

/// Write the run folder of the result `res` of `ocp` (transcribed as `tr`; `integration`:
/// the integrator counters of every stage) and commit it.
#[allow(clippy::too_many_arguments)]
fn write_run(
    folder: RunFolder,
    ocp: &Ocp<'_>,
    tr: &Transcription,
    bench: &Benchmark,
    problem: &Path,
    settings: &SqpSettings,
    res: SqpResult,
    integration: IntegrationStats,
    progress: &dyn Progress,
) -> anyhow::Result<()> {
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
            csv.push_str("time,status,phase");
            for i in 0..ph.ode.nx() {
                write!(csv, ",x{i}").ok();
            }
            for i in 0..ph.ode.nu() {
                write!(csv, ",u{i}").ok();
            }
            csv.push('\n');
        }
        for (k, x) in states.iter().enumerate() {
            write!(
                csv,
                "{:.9},{},{}",
                k as f64 * h,
                res.status.outcome(),
                ph.name
            )
            .ok();
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
        "time_split_s": {
            "evaluations": res.timings.evaluation_s,
            "qp": res.timings.qp_s,
            "other": (res.seconds - res.timings.evaluation_s - res.timings.qp_s).max(0.0),
        },
        "evaluations": res.timings.evaluations,
        "qp_solves": res.timings.qp_solves,
        "integration": integration,
        "variables": tr.n(),
        "constraints": tr.m(),
        "settings": settings,
        "most_violated": res.most_violated,
        "history": res.history,
    });
    super::write_json(&folder, "solution.json", &solution)?;
    folder.write("solution.csv", csv.as_bytes())?;
    super::write_json(&folder, "summary.json", &summary)?;
    let out = folder.commit()?;
    {
        note!(
            progress,
            "{}: {}, {} iterations, {:.2} s → {}",
            res.status,
            res.objective_and_kkt(9),
            res.history.len().saturating_sub(1),
            res.seconds,
            out.display()
        );
        for v in res.most_violated.iter().take(5) {
            note!(progress, "  violated: {} by {:.3e}", v.name, v.amount);
        }
    }
    super::Unsolved::check(&res, &out)
}
