//! `footfall diff`: the arguments of the `diff` workflow
//! ([`footfall::workflows::diff`]).

use super::{cli_progress, Failure};
use footfall::workflows::diff::DiffRequest;
#[allow(unused_imports)]
use std::path::PathBuf;

/// Arguments of `footfall diff`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Run A, the baseline ("before"): a run folder written by `track` or `predict`, or its summary.json.
    run_a: PathBuf,
    /// Run B, compared with A ("after").
    run_b: PathBuf,
    /// Output folder (default: runs/diff-NAME_A-vs-NAME_B, from the run folders' names).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace the output folder if it exists.
    #[arg(long)]
    overwrite: bool,
    /// Changes of the mean error within this many per cent of A count as unchanged.
    #[arg(long, default_value_t = 1.0, value_parser = super::validate::non_negative)]
    threshold_pct: f64,
}

impl From<Args> for DiffRequest {
    fn from(a: Args) -> Self {
        DiffRequest {
            run_a: a.run_a,
            run_b: a.run_b,
            out: a.out,
            overwrite: a.overwrite,
            threshold_pct: a.threshold_pct,
        }
    }
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    footfall::workflows::diff::run(&args.into(), &cli_progress(quiet)).map_err(Failure::classify)
}
