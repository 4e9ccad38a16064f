//! `footfall synth`: the arguments of the `synth` workflow
//! ([`footfall::workflows::synth`]).

use super::{cli_progress, Failure};
use footfall::workflows::synth::SynthRequest;
#[allow(unused_imports)]
use std::path::PathBuf;

/// Arguments of `footfall synth`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The solution that drives the model: a track or predict run folder (or its solution.json).
    #[arg(long)]
    from: PathBuf,
    /// Model file (must be the one the solution was found with; default: the one the
    /// `--from` track run's setup.json names, else models/opensim_subject01.json).
    #[arg(long)]
    model: Option<PathBuf>,
    /// Foot: `ellipse`, `double-circle` or a foot file (the solution's; default: the
    /// `--from` track run's, else ellipse).
    #[arg(long)]
    foot: Option<String>,
    /// Phase graph (default: the `--from` track run's, else Millard & Mombaur's
    /// (2019) graph for the foot).
    #[arg(long)]
    phases: Option<PathBuf>,
    /// Sampling rate (Hz).
    #[arg(long, default_value_t = SynthRequest::DEFAULT_RATE_HZ, value_parser = super::validate::positive)]
    rate: f64,
    /// Length of the trial in half cycles of the solution.
    #[arg(long, default_value_t = SynthRequest::DEFAULT_HALF_CYCLES)]
    half_cycles: f64,
    /// Noise standard deviation of the joint and pelvis angles (degrees).
    #[arg(long, default_value_t = SynthRequest::DEFAULT_NOISE_ANGLE_DEG, value_parser = super::validate::non_negative)]
    noise_angle_deg: f64,
    /// Noise standard deviation of the pelvis position (mm).
    #[arg(long, default_value_t = SynthRequest::DEFAULT_NOISE_POSITION_MM, value_parser = super::validate::non_negative)]
    noise_position_mm: f64,
    /// Noise standard deviation of the ground forces (N).
    #[arg(long, default_value_t = SynthRequest::DEFAULT_NOISE_FORCE_N, value_parser = super::validate::non_negative)]
    noise_force_n: f64,
    /// Noise standard deviation of the centre of pressure (mm).
    #[arg(long, default_value_t = SynthRequest::DEFAULT_NOISE_COP_MM, value_parser = super::validate::non_negative)]
    noise_cop_mm: f64,
    /// Seed of the noise generator.
    #[arg(long, default_value_t = SynthRequest::DEFAULT_SEED)]
    seed: u64,
    /// Output folder: `synthetic.csv`, `synthetic_meta.json`, `truth.json`.
    #[arg(long, default_value = "runs/synth")]
    out: PathBuf,
    /// Replace the output folder if it exists.
    #[arg(long)]
    overwrite: bool,
    /// Hide an effect in the data, `NAME:key=value,…` with the parameter values (e.g.
    /// `ground_slope:angle=0.03`; repeatable). Measurement effects (force-plate time
    /// offset, CoP offset, of both plates: `side=both`) are applied to the samples; one
    /// plate's clock, CoP or gain is refused (tools/make-real-hidden-trials makes such
    /// trials from measured data); a model effect first re-fits the
    /// `--from` track run's data with the effect in the model (held at the given values),
    /// so the truth is a solution of the model with the effect.
    #[arg(long = "hidden-effect", value_name = "NAME:key=value,…")]
    hidden_effects: Vec<String>,
}

impl From<Args> for SynthRequest {
    fn from(a: Args) -> Self {
        SynthRequest {
            from: a.from,
            model: a.model,
            foot: a.foot,
            phases: a.phases,
            rate: a.rate,
            half_cycles: a.half_cycles,
            noise_angle_deg: a.noise_angle_deg,
            noise_position_mm: a.noise_position_mm,
            noise_force_n: a.noise_force_n,
            noise_cop_mm: a.noise_cop_mm,
            seed: a.seed,
            out: a.out,
            overwrite: a.overwrite,
            hidden_effects: a.hidden_effects,
        }
    }
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    footfall::workflows::synth::run(&args.into(), &cli_progress(quiet)).map_err(Failure::classify)
}
