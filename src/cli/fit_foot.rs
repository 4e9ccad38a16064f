//! `footfall fit_foot`: the arguments of the `fit_foot` workflow
//! ([`footfall::workflows::fit_foot`]).

use super::{cli_progress, Failure};
use footfall::workflows::fit_foot::FitFootRequest;
#[allow(unused_imports)]
use std::path::PathBuf;

/// Arguments of `footfall fit-foot`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    model: super::ModelArgs,
    #[command(flatten)]
    trial: super::TrialArgs,
    /// Output folder.
    #[arg(long, default_value = "runs/fit-foot")]
    out: PathBuf,
    /// Replace the output folder if it exists.
    #[arg(long)]
    overwrite: bool,
    /// Nelder–Mead tolerance on the simplex's cost spread.
    #[arg(long, default_value_t = 1e-6, value_parser = super::validate::positive)]
    tol: f64,
    /// Iteration limit.
    #[arg(long, default_value_t = 4000, value_parser = super::validate::iterations)]
    max_iter: usize,
}

impl From<Args> for FitFootRequest {
    fn from(a: Args) -> Self {
        FitFootRequest {
            model: footfall::workflows::ModelFiles {
                model: a.model.model,
                foot: a.model.foot,
            },
            trial: a.trial.into(),
            out: a.out,
            overwrite: a.overwrite,
            tol: a.tol,
            max_iter: a.max_iter,
        }
    }
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    footfall::workflows::fit_foot::run(&args.into(), &cli_progress(quiet))
        .map_err(Failure::classify)
}
