//! `footfall track`: arguments and printing of the tracking workflow
//! ([`footfall::workflows::track`]).

use super::{CliProgress, Failure};
use anyhow::anyhow;
use footfall::model::effects::EffectSpec;
use footfall::problems::diagnose::TrackingRunSetup;
use footfall::problems::track::start::Guess;
use footfall::problems::tracking::ChannelNoise;
use footfall::workflows::run_folder::DEFAULT_TRANSIENT_THRESHOLD_N;
use footfall::workflows::track::{track, TrackRequest};
use footfall::workflows::{default_phases, session};
use std::path::PathBuf;

/// Arguments of `footfall track`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    model: super::ModelArgs,
    /// Phase graph (default: Millard & Mombaur's (2019) graph for the bundled feet; for a
    /// foot file whose
    /// primitives are all volumetric, phases/volumetric_ellipse_walk.json).
    #[arg(long)]
    phases: Option<PathBuf>,
    #[command(flatten)]
    trial: super::TrialArgs,
    /// Low-pass the measured coordinates at this cutoff (Hz; zero-phase 2nd-order
    /// Butterworth) before tracking, for raw motion-capture data.
    #[arg(long, value_parser = super::validate::positive)]
    kinematics_cutoff: Option<f64>,
    /// Output folder.
    #[arg(long, default_value = "runs/track")]
    out: PathBuf,
    /// Replace the output folder if it exists.
    #[arg(long)]
    overwrite: bool,
    #[command(flatten)]
    check_points: super::CheckPointArgs,
    /// Continue the run a killed process left unfinished in this output folder, or the
    /// interrupted run it holds, from its last SQP iteration, with the options it was
    /// started with (give no others).
    #[arg(long, value_name = "DIR")]
    pub resume: Option<PathBuf>,
    /// Hessian: exact (converges), or gauss-newton (Millard & Mombaur's
    /// (2019) method; stalls near KKT 3e-5).
    #[arg(long, value_enum, default_value = "exact")]
    hessian: super::HessianArg,
    /// Relative and absolute CVODES tolerance of the shooting intervals.
    #[arg(long, default_value_t = 1e-8, value_parser = super::validate::positive)]
    integrator_tol: f64,
    /// CVODES tolerance of the forward sensitivities (default: on rigid feet a tenth of
    /// `--tol`, at most 1e-6, or the states' where looser; with a heel pad, whose states
    /// are integrated at 1e-10, `--integrator-tol`; with residual actuators the states').
    /// The KKT residual is computed from them: tighten it if a fit stalls just above
    /// `--tol`.
    #[arg(long, value_parser = super::validate::positive)]
    sensitivity_tol: Option<f64>,
    #[command(flatten)]
    solver: super::TrackSolverArgs,
    /// Report ground-force excursions above the measurement larger than this (N).
    #[arg(long, default_value_t = DEFAULT_TRANSIENT_THRESHOLD_N, value_parser = super::validate::positive)]
    transient_threshold: f64,
    /// Add an effect and identify its parameters: `NAME[:key=value,…]`, e.g.
    /// `ground_slope`, `passive_joint_stiffness:joint=knee`, `cop_offset:offset=0.01,free=`,
    /// `force_plate_time_offset:side=right` (one foot's plate; its clock also moves the
    /// contact events of its force threshold) (repeatable; names: ground_slope,
    /// trunk_mass, passive_joint_stiffness, force_plate_time_offset, cop_offset,
    /// force_plate_gain, body_mass_error, heel_pad_compliance, mtg_damping, mtg_strength,
    /// activation_time_constants, volumetric_contact — a volumetric foot's stiffness
    /// (N/mm²), damping (s/m) and mu_dynamic — and foot_geometry — the primitives' centres,
    /// sizes and angles).
    #[arg(long = "effect", value_name = "NAME[:key=value,…]", value_parser = super::validate::effect)]
    effects: Vec<String>,
    /// Track the pelvis position (x, y) too, weighted 1/(0.1 m) as angles are by
    /// 1/(π/4); Millard & Mombaur (2019) leave it untracked (then a CoP offset cannot be identified: the
    /// model shifts along the walkway instead).
    #[arg(long)]
    track_pelvis_position: bool,
    /// Add residual actuators: a force on each pelvis translation and a torque on the
    /// pelvis tilt and every joint (100 N or N·m per unit control, penalised at 1e-2 per
    /// unit²), so the model can follow the data and the residuals show what it lacks.
    #[arg(long)]
    residual_actuators: bool,
    /// Weight of the excitation² and activation² regularisation terms (default: 1e-3,
    /// as Millard & Mombaur 2019). Smaller weights let effort-costly parameters (slope, trunk mass)
    /// move further from zero.
    #[arg(long, value_parser = super::validate::non_negative)]
    regularisation: Option<f64>,
    /// Read each phase's node targets from its own samples, so a node on a contact change
    /// gets the limit from its phase's side instead of an average across the jump a rigid
    /// contact makes there (angles split at impacts, forces at every contact change; the
    /// kinematics cutoff filters each segment). For high-rate data: every phase needs 4
    /// samples, and the targets at a contact change are extrapolated over up to one
    /// sample interval.
    #[arg(long, conflicts_with = "sample_targets")]
    one_sided_targets: bool,
    /// Compare every sample in the tracked window with the model at its own instant (the
    /// shooting interval that holds it integrated to it, with its sensitivities) instead of
    /// node targets from splines: no sample is averaged across a contact change, and there
    /// are no velocity targets. The excitation and activation regularisation stays at the
    /// nodes.
    #[arg(long)]
    sample_targets: bool,
    /// Weight every channel by the inverse variance of its measurement noise instead of
    /// Millard & Mombaur's (2019) weights (the maximum-likelihood weighting; the angles
    /// keep their weight, so the regularisation keeps its meaning): `angle=DEG,position=MM,force=N,cop=MM`,
    /// e.g. `angle=0.5,position=2,force=5,cop=5` (synth's default noise).
    #[arg(long, value_name = "angle=DEG,position=MM,force=N,cop=MM")]
    noise_weights: Option<String>,
    /// Weight of the angular-velocity targets relative to the angles (default: 0.1,
    /// as Millard & Mombaur 2019; 0 drops them). The targets differentiate the smoothed angles, so they carry
    /// the filter's bias and its low-passed noise, which a fit can follow.
    #[arg(long, allow_negative_numbers = true, value_parser = super::validate::non_negative)]
    velocity_weight: Option<f64>,
    /// Where the solve from the data starts: `data`, the measured states with the
    /// activations 0.01 and excitations 0.025 of Millard & Mombaur (2019, §3.6); or
    /// `inverse-dynamics`, the measured states with the activations and excitations that
    /// give the trial's own joint torques (static optimisation of the inverse dynamics).
    /// The two can end at different local optima.
    #[arg(long, value_enum, default_value = "data")]
    guess: GuessArg,
    /// Track the first half cycle (left heel strike to the next right heel strike) that
    /// lies inside T0–T1 (s). Default: the first half cycle in which every loaded foot's
    /// force was measured (overground trials with force plates in places).
    #[arg(long, value_name = "T0,T1", value_parser = parse_window, conflicts_with = "stride")]
    window: Option<(f64, f64)>,
    /// Track the N-th half cycle of the trial (1 = the first).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    stride: Option<u64>,
    /// Swap the trial's legs: track a half cycle from a right heel strike to the next
    /// left one (`--stride` counts those), the model's right leg following the subject's
    /// left. The planar model's legs are identical; `diagnose` validates on such a half
    /// cycle when the trial has no other of its own.
    #[arg(long)]
    mirror: bool,
    /// Start from the solution of a track run (its folder or solution.json) of the same
    /// phase graph instead of the data; effect parameters it identified start at its
    /// values, unless an `--effect` holds them fixed at its own.
    #[arg(long)]
    init: Option<PathBuf>,
}

/// `--window T0,T1`: two finite times (s), T0 < T1.
fn parse_window(s: &str) -> Result<(f64, f64), String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [a, b] = parts.as_slice() else {
        return Err(format!(
            "expected T0,T1 in seconds (e.g. 0.5,1.6), got '{s}'"
        ));
    };
    let num = |v: &str| {
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("'{v}' is not a finite time in seconds"))
    };
    let (t0, t1) = (num(a)?, num(b)?);
    if t0 >= t1 {
        return Err(format!("T0 = {t0} s must be before T1 = {t1} s"));
    }
    Ok((t0, t1))
}

/// `--noise-weights angle=DEG,position=MM,force=N,cop=MM`: every key once, each a
/// positive, finite standard deviation.
fn parse_noise_weights(text: &str) -> anyhow::Result<ChannelNoise> {
    const KEYS: &str = "keys: angle in °, position in mm, force in N, cop in mm";
    let keys = ["angle", "position", "force", "cop"];
    let mut v = [None; 4];
    for part in text.split(',') {
        let (k, x) = part.split_once('=').ok_or_else(|| {
            anyhow!("--noise-weights '{text}': '{part}' is not key=value ({KEYS})")
        })?;
        let i = keys
            .iter()
            .position(|n| *n == k.trim())
            .ok_or_else(|| anyhow!("--noise-weights: unknown key '{}' ({KEYS})", k.trim()))?;
        let x: f64 = x
            .trim()
            .parse()
            .map_err(|_| anyhow!("--noise-weights: {k}='{x}' is not a number"))?;
        if !(x.is_finite() && x > 0.0) {
            return Err(anyhow!(
                "--noise-weights: {k}={x}: a standard deviation must be positive and finite"
            ));
        }
        if v[i].replace(x).is_some() {
            return Err(anyhow!("--noise-weights: '{k}' given twice"));
        }
    }
    let missing: Vec<&str> = keys
        .iter()
        .zip(&v)
        .filter(|(_, x)| x.is_none())
        .map(|(k, _)| *k)
        .collect();
    if !missing.is_empty() {
        return Err(anyhow!(
            "--noise-weights '{text}': missing {} (give angle=DEG,position=MM,force=N,cop=MM)",
            missing.join(", ")
        ));
    }
    let [a, p, f, c] = v.map(|x| x.unwrap_or_default());
    Ok(ChannelNoise {
        angle_rad: a.to_radians(),
        position_m: p * 1e-3,
        force_n: f,
        cop_m: c * 1e-3,
    })
}

pub fn run(args: Args, progress: &CliProgress) -> Result<(), Failure> {
    // two --effect items that add the same effect are a usage error, like a malformed one
    let effects = EffectSpec::parse_cli_all(&args.effects)
        .map_err(|r| Failure::Usage(anyhow!("--effect: {r}")))?;
    run_inner(args, effects, progress).map_err(Failure::classify)
}

fn run_inner(args: Args, effects: Vec<EffectSpec>, progress: &CliProgress) -> anyhow::Result<()> {
    let phases = args
        .phases
        .clone()
        .unwrap_or_else(|| default_phases(&args.model.foot));
    let req = TrackRequest {
        run: TrackingRunSetup {
            model: args.model.model.clone(),
            foot: args.model.foot.clone(),
            phases,
            data: args.trial.data.clone(),
            overground: args.trial.overground,
            forces: args.trial.forces.clone(),
            plates: args.trial.plates.clone(),
            lab_axes: args.trial.lab_axes.clone(),
            belt_speed: args.trial.belt_speed,
            kinematics_cutoff: args.kinematics_cutoff,
            integrator_tol: args.integrator_tol,
            sensitivity_tol: args.sensitivity_tol,
            track_pelvis_position: args.track_pelvis_position,
            residual_actuators: args.residual_actuators,
            regularisation: args.regularisation,
            velocity_weight: args.velocity_weight,
            guess: match args.guess {
                GuessArg::Data => Guess::Data,
                GuessArg::InverseDynamics => Guess::InverseDynamics,
            },
            one_sided_targets: args.one_sided_targets,
            sample_targets: args.sample_targets,
            window: args.window,
            stride: args.stride.map(|n| n as usize),
            mirror: args.mirror,
            noise_weights: args
                .noise_weights
                .as_deref()
                .map(parse_noise_weights)
                .transpose()?,
            check_points: vec![],
            effects: vec![],
            parameters: vec![],
        },
        effects,
        init: args.init.clone(),
        check_points: args.check_points.enabled(),
        sqp: args.solver.settings(args.hessian.into()),
        transient_threshold: args.transient_threshold,
    };
    let folder = session::create_checkpointed_run_folder(&args.out, args.overwrite)?;
    let run = track(&req, folder, progress)?;
    footfall::workflows::check_run(&run.output, &run.result)
}

/// `--guess`.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum GuessArg {
    Data,
    InverseDynamics,
}
