//! `footfall check`: the arguments of the measurement check
//! ([`footfall::workflows::check`]).

use super::{CliProgress, Failure, TrialArgs};
use footfall::problems::check::CheckSettings;
use footfall::workflows::check::CheckRequest;
use std::path::PathBuf;

/// Arguments of `footfall check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Trial: a sagittal CSV (with its `_meta.json`) or OpenSim inverse kinematics with
    /// `--forces` (the same as `--data`; default: the bundled trial).
    #[arg(value_name = "TRIAL", conflicts_with = "data")]
    trial: Option<PathBuf>,
    #[command(flatten)]
    files: TrialArgs,
    /// Model file whose body (segment masses, centres of mass, inertias, lengths) the
    /// balance uses.
    #[arg(long, default_value = "models/opensim_subject01.json")]
    model: PathBuf,
    /// Output folder (default: runs/check-<trial name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace the output folder if footfall wrote it.
    #[arg(long)]
    overwrite: bool,
    /// Low-pass cutoff of kinematics and forces alike (Hz).
    #[arg(long, default_value_t = 6.0, value_parser = super::validate::positive)]
    cutoff: f64,
    /// Family-wise significance level of the readings.
    #[arg(long, default_value_t = 0.05, value_parser = super::validate::positive)]
    level: f64,
    /// What your own untouched trials read as each candidate: a JSON object of effect
    /// name to its centre and spread in SI units, e.g. {"shared_clock": {"mean": 0.008,
    /// "sd": 0.002}} (`tools/calibrate-check` writes one), replacing the shipped
    /// calibration for the effects it names.
    #[arg(long, value_name = "FILE.json")]
    null: Option<PathBuf>,
    /// Move the trunk above the lumbar joint by the trial's `lumbar_extension` column
    /// instead of freezing it in the rigid HAT (needs a body that describes its trunk: an
    /// OpenSim model summary or de Leva's tables). The trunk's rocking carries most of a
    /// rigid HAT's horizontal residual; the shipped bands are calibrated with the rigid
    /// HAT, so judge with your own (`--null`, from `tools/calibrate-check --lumbar`).
    #[arg(long)]
    lumbar: bool,
}

pub fn run(args: Args, progress: &CliProgress) -> Result<(), Failure> {
    let mut files: footfall::workflows::trial::TrialFiles = args.files.into();
    if args.trial.is_some() {
        files.data = args.trial;
    }
    let mut settings = CheckSettings {
        cutoff_hz: args.cutoff,
        level: args.level,
        lumbar: args.lumbar,
        ..CheckSettings::default()
    };
    if let Some(path) = &args.null {
        footfall::workflows::check::read_null(path, &mut settings.null).map_err(Failure::Input)?;
    }
    let req = CheckRequest {
        trial: files,
        model: args.model,
        out: args.out,
        overwrite: args.overwrite,
        settings,
    };
    footfall::workflows::check::run(&req, progress)
        .map(|_| ())
        .map_err(Failure::classify)
}
