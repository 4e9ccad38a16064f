//! `footfall solve`: the arguments of the `solve` workflow
//! ([`footfall::workflows::solve`]).

use super::{cli_progress, Failure, HessianArg, MethodArg};
use footfall::workflows::solve::SolveRequest;
#[allow(unused_imports)]
use std::path::PathBuf;

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
    /// Continue the run a killed process left unfinished in this output folder, or the
    /// interrupted run it holds, from its last SQP iteration, with the options it was
    /// started with (give no others).
    #[arg(long, value_name = "DIR")]
    pub resume: Option<PathBuf>,
    /// Start from the variables of a previous solution.json.
    #[arg(long)]
    warm_start: Option<PathBuf>,
    /// KKT tolerance (at most 0.01).
    #[arg(long, default_value_t = 1e-6, value_parser = super::validate::kkt_tolerance)]
    tol: f64,
    /// Iteration limit.
    #[arg(long, default_value_t = 200, value_parser = super::validate::iterations)]
    max_iter: usize,
    /// Wall-time limit (s).
    #[arg(long, value_parser = super::validate::positive)]
    max_time: Option<f64>,
    /// CVODES method for the shooting intervals (default: adams, or bdf for the gait
    /// problem).
    #[arg(long, value_enum)]
    integrator: Option<MethodArg>,
    /// Hessian approximation (default: exact).
    #[arg(long, value_enum)]
    hessian: Option<HessianArg>,
}

impl From<Args> for SolveRequest {
    fn from(a: Args) -> Self {
        SolveRequest {
            problem: a.problem,
            out: a.out,
            overwrite: a.overwrite,
            warm_start: a.warm_start,
            tol: a.tol,
            max_iter: a.max_iter,
            max_time: a.max_time,
            integrator: a.integrator.map(Into::into),
            hessian: a.hessian.map(Into::into),
        }
    }
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    footfall::workflows::solve::run(&args.into(), &cli_progress(quiet)).map_err(Failure::classify)
}
