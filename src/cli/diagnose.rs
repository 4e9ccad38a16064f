//! `footfall diagnose`: the arguments of the `diagnose` workflow
//! ([`footfall::workflows::diagnose`]).

use super::{cli_progress, Failure};
use footfall::workflows::diagnose::DiagnoseRequest;
#[allow(unused_imports)]
use std::path::PathBuf;

/// Arguments of `footfall diagnose`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A track run folder.
    run: PathBuf,
    /// Re-fit this many of the top significant candidates to verify them.
    #[arg(long, default_value_t = 1)]
    verify: usize,
    /// Only these candidates (effect names or `NAME:key=value,…`; default: the catalog).
    /// `catalog` stands for the default set, so `--candidate catalog --candidate
    /// foot_geometry` adds the foot's shape to it.
    #[arg(long = "candidate")]
    candidates: Vec<String>,
    /// Output folder (default: `<RUN>-diagnose`); re-fits go to `<RUN>+<effect>`.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace existing output folders.
    #[arg(long)]
    overwrite: bool,
    /// KKT tolerance of the re-fits (at most 0.01).
    #[arg(long, default_value_t = 1e-5, value_parser = super::validate::kkt_tolerance)]
    tol: f64,
    /// Iteration limit of the re-fits.
    #[arg(long, default_value_t = 200, value_parser = super::validate::iterations)]
    max_iter: usize,
    /// Skip the held-out validation of significant candidates (it tracks another half
    /// cycle of the trial once); they are then reported as not validated.
    #[arg(long)]
    no_held_out: bool,
    /// Validate on another recording of the same subject instead of another half cycle of
    /// the run's trial: its first half cycle is tracked with the run's model and cost and
    /// held out (a file as `track --data` takes it, without a forces file)
    #[arg(long, value_name = "FILE")]
    held_out_data: Option<PathBuf>,
    /// Start the diagnosis's own solves from kept solutions of the same problems
    /// (repeatable): an earlier re-fit's run folder (`<RUN>+<effect>`) starts the re-fit
    /// with the same effects, an earlier diagnosis folder (`<RUN>-diagnose`) gives its
    /// held-out track (`held_out`) and any run folders inside it. Each solve still
    /// iterates to the KKT tolerance from there; only its path is shortened.
    #[arg(long = "start", value_name = "DIR")]
    starts: Vec<PathBuf>,
}

impl From<Args> for DiagnoseRequest {
    fn from(a: Args) -> Self {
        DiagnoseRequest {
            run: a.run,
            verify: a.verify,
            candidates: a.candidates,
            out: a.out,
            overwrite: a.overwrite,
            tol: a.tol,
            max_iter: a.max_iter,
            held_out: !a.no_held_out,
            held_out_data: a.held_out_data,
            starts: a.starts,
        }
    }
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    footfall::workflows::diagnose::run(&args.into(), &cli_progress(quiet))
        .map_err(Failure::classify)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `footfall diagnose RUN` asks for what the library's `DiagnoseRequest::new` holds,
    /// so tests that call the library diagnose as a user's plain command does.
    #[test]
    fn the_plain_command_is_the_librarys_default_request() {
        let cli: DiagnoseRequest =
            super::super::parse_args::<Args>(&["diagnose", "runs/track"]).into();
        let library = DiagnoseRequest::new(PathBuf::from("runs/track"));
        assert_eq!(format!("{cli:?}"), format!("{library:?}"));
    }
}
