//! `footfall report`: the arguments of the `report` workflow
//! ([`footfall::workflows::report`]).

use super::{cli_progress, Failure};
use footfall::workflows::report::ReportRequest;
#[allow(unused_imports)]
use std::path::PathBuf;

/// Arguments of `footfall report`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A track run folder (with setup.json, solution.json and summary.json); or two or
    /// more run folders of `track` or `predict` to set side by side in one report.
    #[arg(required = true, num_args = 1..)]
    runs: Vec<PathBuf>,
    /// Output folder (default for one run: the run folder itself, replaced as a whole
    /// once the new report is complete; required for several runs).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace `--out` if it exists.
    #[arg(long)]
    overwrite: bool,
    /// Report ground-force excursions above the measurement larger than this (N).
    #[arg(long, default_value_t = footfall::workflows::run_folder::DEFAULT_TRANSIENT_THRESHOLD_N, value_parser = super::validate::positive)]
    transient_threshold: f64,
}

impl From<Args> for ReportRequest {
    fn from(a: Args) -> Self {
        ReportRequest {
            runs: a.runs,
            out: a.out,
            overwrite: a.overwrite,
            transient_threshold: a.transient_threshold,
        }
    }
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    footfall::workflows::report::run(&args.into(), &cli_progress(quiet)).map_err(Failure::classify)
}
