//! Command-line interface: argument parsing, progress output and exit codes.
//!
//! Exit codes ([`EXIT_CODES`]): 0 success; 1 bad input or I/O error; 2 usage error
//! (clap, including a numeric option out of range); 3 solved but not converged; 4
//! infeasible; 5 converged but physically invalid; 130 interrupted. A command returns a
//! [`Failure`]; a solve that did not converge is an [`Unsolved`] error, whose status
//! picks the code.

mod args;
mod check;
mod compare;
mod compare_contact;
mod diagnose;
mod diff;
mod fit_foot;
mod predict;
mod report;
mod simulate;
mod solve;
mod study;
mod synth;
mod track;
mod validate;

pub use args::{
    cli_progress, CheckPointArgs, CliProgress, HessianArg, MethodArg, ModelArgs, TrackSolverArgs,
    TrialArgs,
};
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use footfall::sqp::SqpStatus;
use std::process::ExitCode;

/// The exit codes, as `--help` prints them.
pub const EXIT_CODES: &str = "\
Exit codes:
  0    success
  1    bad input (a file, field or option value the command refuses) or an I/O error
  2    usage error (unknown option, missing or malformed value, a number out of range)
  3    solved but not converged (iteration or time limit, line search, QP or evaluation failure); the run folder is written
  4    infeasible: the constraints cannot be satisfied; the run folder is written
  5    converged but physically invalid (with or without check points): on the 1 ms grid a ground pulls, a contact leaves its friction cone, a foot is inside the floor or a stabilisation force is large; the run folder is written
  130  interrupted (Ctrl-C); the run folder is written from the last accepted iterate";

/// Fit and predict human gait with rigid foot-ground contact models.
#[derive(Debug, Parser)]
#[command(name = "footfall", version, about, after_help = EXIT_CODES)]
struct Cli {
    /// Print nothing but errors.
    #[arg(long, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate the model forward through a phase sequence.
    Simulate(simulate::Args),
    /// Solve a generic optimal control problem (cart-pole, five-link biped).
    Solve(solve::Args),
    /// Fit a foot's geometry to the measured stance (Millard & Mombaur 2019, §3.2); a foot file's values are
    /// the start.
    FitFoot(fit_foot::Args),
    /// Check the measurement against itself before any model: the trial's whole-body
    /// Newton–Euler balance reads the plates' clocks, gains and CoP offsets, the body's
    /// mass and trunk, and the ground slope (no contact model, no optimal control).
    Check(check::Args),
    /// Track measured walking (default: the bundled trial with the ellipse foot).
    Track(track::Args),
    /// Predict the gait the model prefers (minimum activation and impulses; Millard & Mombaur 2019, §3.5).
    Predict(predict::Args),
    /// Run the same prediction for two or more feet and compare their ground forces.
    Compare(compare::Args),
    /// Track one trial with a rigid foot, its geometry identified, a volumetric foot and its
    /// contact law identified, side by side (RMSE next to Ezati et al. 2020, Table 7).
    CompareContact(compare_contact::Args),
    /// Generate a measurement set from a model solution, with noise and the truth kept apart.
    Synth(synth::Args),
    /// Which physical effect is the model of a track run missing? Score tests, then a re-fit.
    Diagnose(diagnose::Args),
    /// Compare the per-channel tracking errors of two runs: A (before) against B (after).
    Diff(diff::Args),
    /// Rewrite a track run's report from its solution: where the model fails, by channel,
    /// phase and time.
    Report(report::Args),
    /// Check (and track) every trial of a manifest, each into its own run folder, here or
    /// as a Slurm array, and read the findings across trials: instruments pooled over a
    /// lab session, the body over a subject.
    Study(study::Args),
}

/// Failure classes mapped to exit codes.
pub enum Failure {
    /// An option value refused after parsing, e.g. two `--effect` items that add the
    /// same effect (exit 2, as clap's usage errors).
    Usage(anyhow::Error),
    /// Bad input or an I/O error (exit 1).
    Input(anyhow::Error),
    /// Solved but not converged (exit 3).
    NotConverged(anyhow::Error),
    /// The constraints cannot be satisfied (exit 4).
    Infeasible(anyhow::Error),
    /// Converged, but the solution breaks physics between the nodes (exit 5).
    PhysicallyInvalid(anyhow::Error),
    /// Stopped by Ctrl-C (exit 130).
    Interrupted(anyhow::Error),
}

impl Failure {
    /// The class of an error: an [`Unsolved`] in its chain by its status, anything else
    /// bad input.
    pub fn classify(e: anyhow::Error) -> Self {
        if e.chain()
            .any(|c| c.downcast_ref::<footfall::workflows::Invalid>().is_some())
        {
            return Failure::PhysicallyInvalid(e);
        }
        let Some(u) = e
            .chain()
            .find_map(|c| c.downcast_ref::<footfall::workflows::Unsolved>())
        else {
            return Failure::Input(e);
        };
        match &u.status {
            SqpStatus::Infeasible => Failure::Infeasible(e),
            SqpStatus::Interrupted => Failure::Interrupted(e),
            // the start could not be evaluated: the problem as given is broken
            SqpStatus::EvaluationFailure(_) if u.at_start => Failure::Input(e),
            _ => Failure::NotConverged(e),
        }
    }

    /// The process exit code.
    pub fn code(&self) -> u8 {
        match self {
            Failure::Usage(_) => 2,
            Failure::Input(_) => 1,
            Failure::NotConverged(_) => 3,
            Failure::Infeasible(_) => 4,
            Failure::PhysicallyInvalid(_) => 5,
            Failure::Interrupted(_) => 130,
        }
    }

    fn error(&self) -> &anyhow::Error {
        match self {
            Failure::Usage(e)
            | Failure::Input(e)
            | Failure::NotConverged(e)
            | Failure::Infeasible(e)
            | Failure::PhysicallyInvalid(e)
            | Failure::Interrupted(e) => e,
        }
    }
}

pub fn main() -> ExitCode {
    // before any work: a Ctrl-C during setup removes what this process staged and exits 130
    install_interrupt_handler();
    quiet_reader_panics();
    let mut cli = parse(std::env::args_os());
    let args: Vec<String> = std::env::args().skip(1).collect();
    let resuming = match &cli.command {
        Command::Track(a) => a.resume.is_some().then_some("track"),
        Command::Predict(a) => a.resume.is_some().then_some("predict"),
        Command::Solve(a) => a.resume.is_some().then_some("solve"),
        _ => None,
    };
    let recorded = match resuming {
        Some(sub) => footfall::workflows::session::prepare_resume(sub, &args).map(|original| {
            let quiet = cli.quiet;
            cli = parse(std::iter::once("footfall".to_string()).chain(original.iter().cloned()));
            cli.quiet |= quiet;
            original
        }),
        None => Ok(args),
    };
    if let Err(e) = recorded.and_then(footfall::workflows::session::record_command) {
        eprintln!("error: {}", footfall::workflows::error_text(&e));
        return ExitCode::from(1);
    }
    let progress = cli_progress(cli.quiet);
    let result = match cli.command {
        Command::Simulate(args) => simulate::run(args, cli.quiet),
        Command::Solve(args) => solve::run(args, cli.quiet),
        Command::Check(args) => check::run(args, &progress),
        Command::Track(args) => track::run(args, &progress),
        Command::FitFoot(args) => fit_foot::run(args, cli.quiet),
        Command::Predict(args) => predict::run(args, &progress),
        Command::Compare(args) => compare::run(args, cli.quiet),
        Command::CompareContact(args) => compare_contact::run(args, cli.quiet),
        Command::Synth(args) => synth::run(args, cli.quiet),
        Command::Diagnose(args) => diagnose::run(args, cli.quiet),
        Command::Diff(args) => diff::run(args, cli.quiet),
        Command::Report(args) => report::run(args, cli.quiet),
        Command::Study(args) => study::run(args, &progress),
    };
    // printed even with --quiet: the results are not where the command line said
    for (target, went) in footfall::runfolder::take_relocations() {
        eprintln!(
            "warning: the output folder {} appeared while this run was working and is left as it is; the results are in {}",
            target.display(),
            went.display()
        );
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("error: {}", footfall::workflows::error_text(f.error()));
            ExitCode::from(f.code())
        }
    }
}

/// Ctrl-C: during a solve the first one asks the library to stop
/// ([`footfall::interrupt`]): the solve ends within a second, inside an iteration too, and
/// the run folder is written from its last accepted iterate, with the checkpoints that
/// `--resume` continues from. A second one, or one outside a solve, removes this process's
/// unfinished staging folders and exits with 130 at once.
fn install_interrupt_handler() {
    let _ = ctrlc::set_handler(|| {
        if footfall::interrupt::in_solve() && !footfall::interrupt::request() {
            eprintln!("interrupted: stopping the solve and writing the run from its last accepted iterate (Ctrl-C again to abort)");
        } else {
            eprintln!("interrupted: nothing written");
            // held until the process ends: nothing is written into a removed folder
            let _no_writes = footfall::runfolder::remove_unfinished();
            std::process::exit(130);
        }
    });
}

/// Panics inside the C3D reader crate print nothing: the reader catches them and returns an
/// error naming the file and the damaged section, which the user sees instead of the
/// crate's panic text. Every other panic is a bug of footfall's and prints as usual.
fn quiet_reader_panics() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !footfall::data::c3d::crate_is_parsing() {
            default(info);
        }
    }));
}

/// The command line parsed, or clap's usage error printed and exit 2. Every option's
/// value may start with a minus sign: `--tol -1` is the value −1, refused by the option's
/// range, where clap would take `-1` for an unknown flag.
fn parse<I, T>(argv: I) -> Cli
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let mut cmd = Cli::command().mut_subcommands(|s| {
        s.mut_args(|a| {
            let values = a.get_action().takes_values();
            a.allow_negative_numbers(values)
        })
    });
    let matches = cmd.clone().get_matches_from(argv);
    Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.format(&mut cmd).exit())
}

/// One subcommand's arguments `A` parsed from `argv` (its name first), as `footfall`
/// would parse them: for the subcommands' unit tests.
#[cfg(test)]
pub(crate) fn parse_args<A: clap::Args>(argv: &[&str]) -> A {
    #[derive(Parser)]
    struct Only<A: clap::Args> {
        #[command(flatten)]
        args: A,
    }
    Only::<A>::try_parse_from(argv).unwrap().args
}

#[cfg(test)]
mod tests {
    use super::*;

    fn code(status: SqpStatus, at_start: bool) -> u8 {
        let e = anyhow::Error::new(footfall::workflows::Unsolved {
            status,
            at_start,
            message: String::new(),
        })
        .context("wrapped");
        Failure::classify(e).code()
    }

    #[test]
    fn the_solver_status_picks_the_exit_code() {
        assert_eq!(code(SqpStatus::MaxIterations, false), 3);
        assert_eq!(code(SqpStatus::MaxTime, false), 3);
        assert_eq!(code(SqpStatus::LineSearchFailure, false), 3);
        assert_eq!(code(SqpStatus::QpFailure("x".into()), false), 3);
        assert_eq!(code(SqpStatus::EvaluationFailure("x".into()), false), 3);
        assert_eq!(code(SqpStatus::EvaluationFailure("x".into()), true), 1);
        assert_eq!(code(SqpStatus::Infeasible, false), 4);
        assert_eq!(code(SqpStatus::Interrupted, false), 130);
        assert_eq!(Failure::classify(anyhow::anyhow!("bad file")).code(), 1);
    }
}
