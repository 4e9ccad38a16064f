//! `footfall compare`: the arguments of the `compare` workflow
//! ([`footfall::workflows::compare`]).

use super::predict::PredictOptions;
use super::{cli_progress, Failure};
use footfall::workflows::compare::CompareRequest;
#[allow(unused_imports)]
use std::path::PathBuf;

/// Arguments of `footfall compare`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Feet to compare, comma separated: `ellipse`, `double-circle` or `FOOT_FILE:PHASE_FILE`.
    #[arg(long, value_delimiter = ',', default_value = "ellipse,double-circle")]
    feet: Vec<String>,
    /// Start a foot's prediction from a solution: `FOOT=RUN_FOLDER_OR_FILE` (repeatable).
    /// Feet without one start from the data.
    #[arg(long = "init")]
    inits: Vec<String>,
    /// Exit with status 1 unless this foot's peak normal-force excess over the
    /// measurement is at least `--expect-ratio` times every other foot's (a prediction
    /// that did not converge, or one that is physically invalid on the 1 ms grid, exits
    /// with its own code first).
    #[arg(long)]
    expect_transient: Option<String>,
    /// Ratio for `--expect-transient`.
    #[arg(long, default_value_t = 3.0, value_parser = super::validate::positive)]
    expect_ratio: f64,
    /// Output folder (one prediction run folder per foot inside).
    #[arg(long, default_value = "runs/compare")]
    out: PathBuf,
    /// Replace the output folder if it exists.
    #[arg(long)]
    overwrite: bool,
    #[command(flatten)]
    options: PredictOptions,
}

impl From<Args> for CompareRequest {
    fn from(a: Args) -> Self {
        CompareRequest {
            feet: a.feet,
            inits: a.inits,
            expect_transient: a.expect_transient,
            expect_ratio: a.expect_ratio,
            out: a.out,
            overwrite: a.overwrite,
            options: (&a.options).into(),
        }
    }
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    footfall::workflows::compare::run(&args.into(), &cli_progress(quiet)).map_err(Failure::classify)
}
