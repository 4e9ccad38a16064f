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
    let cli = Cli::parse();
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

static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Wraps an SQP observer so that Ctrl-C stops the solve after the current iteration:
/// the solver returns its current (last accepted) iterate with status `interrupted`,
/// and the run folder is written from it as for any other stop.
pub struct Interruptible<'a>(pub &'a mut dyn footfall::sqp::Observer);

impl Interruptible<'_> {
    /// Install the Ctrl-C handler (once per process; later calls are no-ops).
    pub fn install() {
        let _ = ctrlc::set_handler(|| {
            if INTERRUPTED.swap(true, std::sync::atomic::Ordering::SeqCst) {
                // a second Ctrl-C while the iteration finishes: give up at once
                std::process::exit(130);
            }
            eprintln!("interrupted: stopping after this iteration (Ctrl-C again to abort)");
        });
    }
}

/// Solve `nlp` from `w0` with the Ctrl-C handler installed, logging each iteration to
/// stderr unless `quiet`.
pub fn solve_interruptibly(nlp: &dyn footfall::sqp::Nlp, w0: &[f64], settings: &footfall::sqp::SqpSettings, quiet: bool) -> footfall::sqp::SqpResult {
    Interruptible::install();
    if quiet {
        footfall::sqp::solve(nlp, w0, settings, &mut Interruptible(&mut footfall::sqp::Silent))
    } else {
        footfall::sqp::solve(nlp, w0, settings, &mut Interruptible(&mut footfall::sqp::StderrLog))
    }
}

impl footfall::sqp::Observer for Interruptible<'_> {
    fn iteration(&mut self, rec: &footfall::sqp::IterationRecord) -> bool {
        let go_on = self.0.iteration(rec);
        go_on && !INTERRUPTED.load(std::sync::atomic::Ordering::SeqCst)
    }
}
