//! `footfall simulate`: the arguments of the `simulate` workflow
//! ([`footfall::workflows::simulate`]).

use super::{cli_progress, Failure};
use footfall::workflows::simulate::SimulateRequest;
#[allow(unused_imports)]
use std::path::PathBuf;

/// Arguments of `footfall simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    model: super::ModelArgs,
    /// Phase sequence file (JSON) with the contacts and durations of each phase.
    #[arg(long)]
    phase_set: PathBuf,
    /// Control table (CSV: `time,<control names>`); default: every control at 0.025
    /// (excitations) or 0 (torques).
    #[arg(long)]
    controls: Option<PathBuf>,
    /// Initial state (JSON: q, qd, optional a); default: the phase file's `initial_state`.
    #[arg(long)]
    initial: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "runs/simulate")]
    out: PathBuf,
    /// Replace the output folder if it exists.
    #[arg(long)]
    overwrite: bool,
    /// Output grid step (s).
    #[arg(long, default_value_t = 0.001, value_parser = super::validate::positive)]
    dt: f64,
    /// Do not project the initial state onto the first phase's contact constraints.
    #[arg(long)]
    no_project: bool,
    /// Relative and absolute integrator tolerance.
    #[arg(long, default_value_t = 1e-8, value_parser = super::validate::positive)]
    tol: f64,
    /// Refuse (exit 1, no output folder) instead of warning when a landing is away from
    /// the ground, a touchdown is not reached, or a stabilisation force is too large.
    #[arg(long)]
    strict: bool,
    /// Largest landing gap |φ| at an impact before a warning (m).
    #[arg(long, default_value_t = 1e-3)]
    gap_tolerance: f64,
    /// Largest stabilisation (Baumgarte) force before a warning (N).
    #[arg(long, default_value_t = 1.0)]
    baumgarte_tolerance: f64,
}

impl From<Args> for SimulateRequest {
    fn from(a: Args) -> Self {
        SimulateRequest {
            model: footfall::workflows::ModelFiles {
                model: a.model.model,
                foot: a.model.foot,
            },
            phase_set: a.phase_set,
            controls: a.controls,
            initial: a.initial,
            out: a.out,
            overwrite: a.overwrite,
            dt: a.dt,
            no_project: a.no_project,
            tol: a.tol,
            strict: a.strict,
            gap_tolerance: a.gap_tolerance,
            baumgarte_tolerance: a.baumgarte_tolerance,
        }
    }
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    footfall::workflows::simulate::run(&args.into(), &cli_progress(quiet))
        .map_err(Failure::classify)
}
