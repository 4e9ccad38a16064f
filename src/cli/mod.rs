//! Command-line interface: argument parsing, progress output and exit codes.
//!
//! Exit codes: 0 success, 1 bad input or a run that did not succeed, 2 internal error.

mod compare;
mod diagnose;
mod diff;
mod report;
mod fit_foot;
mod gait_run;
mod predict;
mod session;
mod simulate;
mod solve;
mod synth;
mod track;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Fit and predict human gait with rigid foot-ground contact models.
#[derive(Debug, Parser)]
#[command(name = "footfall", version, about)]
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
    /// Fit a foot's geometry to the measured stance (seed §3.2).
    FitFoot(fit_foot::Args),
    /// Track measured walking (default: the bundled trial with the ellipse foot).
    Track(track::Args),
    /// Predict the gait the model prefers (minimum activation and impulses; seed §3.5).
    Predict(predict::Args),
    /// Run the same prediction for two or more feet and compare their ground forces.
    Compare(compare::Args),
    /// Generate a measurement set from a model solution, with noise and the truth kept apart.
    Synth(synth::Args),
    /// Which physical effect is the model of a track run missing? Score tests, then a re-fit.
    Diagnose(diagnose::Args),
    /// Compare the per-channel tracking errors of two runs: A (before) against B (after).
    Diff(diff::Args),
    /// Rewrite a track run's report from its solution: where the model fails, by channel,
    /// phase and time.
    Report(report::Args),
}

/// Failure classes mapped to exit codes.
pub enum Failure {
    /// Bad user input or a run that did not succeed (exit 1).
    User(anyhow::Error),
}

pub fn main() -> ExitCode {
    // before any work: a Ctrl-C during setup removes what this process staged and exits 130
    session::install_interrupt_handler();
    let mut cli = Cli::parse();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let resuming = match &cli.command {
        Command::Track(a) => a.resume.is_some().then_some("track"),
        Command::Predict(a) => a.resume.is_some().then_some("predict"),
        Command::Solve(a) => a.resume.is_some().then_some("solve"),
        _ => None,
    };
    let recorded = match resuming {
        Some(sub) => session::prepare_resume(sub, &args).map(|original| {
            let quiet = cli.quiet;
            cli = Cli::parse_from(std::iter::once("footfall".to_string()).chain(original.iter().cloned()));
            cli.quiet |= quiet;
            original
        }),
        None => Ok(args),
    };
    if let Err(e) = recorded.and_then(session::record_command) {
        eprintln!("error: {}", render_chain(&e));
        return ExitCode::from(1);
    }
    let result = match cli.command {
        Command::Simulate(args) => simulate::run(args, cli.quiet),
        Command::Solve(args) => solve::run(args, cli.quiet),
        Command::Track(args) => track::run(args, cli.quiet),
        Command::FitFoot(args) => fit_foot::run(args, cli.quiet),
        Command::Predict(args) => predict::run(args, cli.quiet),
        Command::Compare(args) => compare::run(args, cli.quiet),
        Command::Synth(args) => synth::run(args, cli.quiet),
        Command::Diagnose(args) => diagnose::run(args, cli.quiet),
        Command::Diff(args) => diff::run(args, cli.quiet),
        Command::Report(args) => report::run(args, cli.quiet),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::User(e)) => {
            eprintln!("error: {}", render_chain(&e));
            ExitCode::from(1)
        }
    }
}

/// The error and its causes joined by ": ", skipping a cause whose text the message
/// already contains (library errors often quote their cause).
fn render_chain(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if out.is_empty() {
            out = text;
        } else if !out.contains(&text) {
            out.push_str(": ");
            out.push_str(&text);
        }
    }
    out
}

/// Measured data from a sagittal CSV (moved overground when its meta file gives a belt
/// speed), or the bundled trial.
pub fn load_data(path: Option<&std::path::Path>) -> anyhow::Result<footfall::data::GaitData> {
    Ok(match path {
        Some(p) => {
            let d = footfall::data::read_sagittal_csv(p)?;
            match d.belt_speed {
                Some(v) if !d.overground => d.to_overground(v)?,
                _ => d,
            }
        }
        None => footfall::data::GaitData::bundled(std::path::Path::new("."))?,
    })
}

pub use session::solve_interruptibly;
