//! `footfall synth`: a measurement set generated from a model solution, with a documented
//! noise model and the truth kept apart — data with a known answer.

#[allow(unused_imports)]
use super::{note, warn_note, Progress};
use crate::data::write_sagittal_csv;
use crate::integrate::IntegratorSettings;
use crate::model::effects::EffectSpec;
use crate::model::GaitModel;
use crate::phases::PhaseSequence;
use crate::problems::synth::{synthesize, MeasurementOffsets, NoiseModel, SynthSettings};
use crate::runfolder::RunFolder;
use anyhow::{anyhow, bail, Context};
use std::path::PathBuf;

/// What `synth` does: the arguments of `footfall synth`.
#[derive(Debug, Clone)]
pub struct SynthRequest {
    /// The solution that drives the model: a track or predict run folder (or its solution.json).
    pub from: PathBuf,
    /// Model file (must be the one the solution was found with; default: the one the
    /// `--from` track run's setup.json names, else models/opensim_subject01.json).
    pub model: Option<PathBuf>,
    /// Foot: `ellipse`, `double-circle` or a foot file (the solution's; default: the
    /// `--from` track run's, else ellipse).
    pub foot: Option<String>,
    /// Phase graph (default: the `--from` track run's, else Millard & Mombaur's graph for the foot).
    pub phases: Option<PathBuf>,
    /// Sampling rate (Hz).
    pub rate: f64,
    /// Length of the trial in half cycles of the solution.
    pub half_cycles: f64,
    /// Noise standard deviation of the joint and pelvis angles (degrees).
    pub noise_angle_deg: f64,
    /// Noise standard deviation of the pelvis position (mm).
    pub noise_position_mm: f64,
    /// Noise standard deviation of the ground forces (N).
    pub noise_force_n: f64,
    /// Noise standard deviation of the centre of pressure (mm).
    pub noise_cop_mm: f64,
    /// Seed of the noise generator.
    pub seed: u64,
    /// Output folder: `synthetic.csv`, `synthetic_meta.json`, `truth.json`.
    pub out: PathBuf,
    /// Replace the output folder if it exists.
    pub overwrite: bool,
    /// Hide an effect in the data, `NAME:key=value,…` with the parameter values (e.g.
    /// `ground_slope:angle=0.03`; repeatable). Measurement effects (force-plate time
    /// offset, CoP offset) are applied to the samples; a model effect first re-fits the
    /// `--from` track run's data with the effect in the model (held at the given values),
    /// so the truth is a solution of the model with the effect.
    pub hidden_effects: Vec<String>,
}

impl SynthRequest {
    /// `footfall synth`'s default sampling rate (Hz).
    pub const DEFAULT_RATE_HZ: f64 = 100.0;
    /// Its default length (half cycles of the solution).
    pub const DEFAULT_HALF_CYCLES: f64 = 5.0;
    /// Its default noise standard deviation of the angles (degrees).
    pub const DEFAULT_NOISE_ANGLE_DEG: f64 = 0.5;
    /// Its default noise standard deviation of the pelvis position (mm).
    pub const DEFAULT_NOISE_POSITION_MM: f64 = 2.0;
    /// Its default noise standard deviation of the ground forces (N).
    pub const DEFAULT_NOISE_FORCE_N: f64 = 5.0;
    /// Its default noise standard deviation of the centre of pressure (mm).
    pub const DEFAULT_NOISE_COP_MM: f64 = 5.0;
    /// Its default seed of the noise generator.
    pub const DEFAULT_SEED: u64 = 1;

    /// The default noise as tracking weights (`track --noise-weights`): weighting every
    /// channel by the inverse variance of the noise synth added makes a synthetic
    /// trial's cost its maximum-likelihood one.
    pub fn default_noise() -> crate::problems::tracking::ChannelNoise {
        crate::problems::tracking::ChannelNoise {
            angle_rad: Self::DEFAULT_NOISE_ANGLE_DEG.to_radians(),
            position_m: Self::DEFAULT_NOISE_POSITION_MM * 1e-3,
            force_n: Self::DEFAULT_NOISE_FORCE_N,
            cop_m: Self::DEFAULT_NOISE_COP_MM * 1e-3,
        }
    }

    /// A request with `footfall synth`'s defaults (the constants above, which its
    /// arguments default to): the model, foot and phases of `from`, no hidden effect, an
    /// output folder that must not exist yet.
    pub fn new(from: PathBuf, out: PathBuf) -> Self {
        SynthRequest {
            from,
            model: None,
            foot: None,
            phases: None,
            rate: Self::DEFAULT_RATE_HZ,
            half_cycles: Self::DEFAULT_HALF_CYCLES,
            noise_angle_deg: Self::DEFAULT_NOISE_ANGLE_DEG,
            noise_position_mm: Self::DEFAULT_NOISE_POSITION_MM,
            noise_force_n: Self::DEFAULT_NOISE_FORCE_N,
            noise_cop_mm: Self::DEFAULT_NOISE_COP_MM,
            seed: Self::DEFAULT_SEED,
            out,
            overwrite: false,
            hidden_effects: Vec::new(),
        }
    }
}

/// The hidden effects of `--hidden-effect`: all of them as given, the offsets of both
/// plates applied to the samples, and the model's effects.
fn hidden_effects(
    args: &SynthRequest,
) -> anyhow::Result<(Vec<EffectSpec>, MeasurementOffsets, Vec<EffectSpec>)> {
    let hidden: Vec<EffectSpec> = args
        .hidden_effects
        .iter()
        .map(|e| {
            EffectSpec::parse_cli(e)
                .map(|s| s.fixed())
                .map_err(|r| anyhow!("--hidden-effect: {r}"))
        })
        .collect::<Result<_, _>>()?;
    let mut offsets = MeasurementOffsets::default();
    let mut model_effects = Vec::new();
    for e in &hidden {
        match e {
            EffectSpec::ForcePlateTimeOffset { side, offset, .. } if side == "both" => {
                offsets.force_time_offset_s = *offset
            }
            EffectSpec::CopOffset { side, offset, .. } if side == "both" => {
                offsets.cop_offset_m = *offset
            }
            EffectSpec::ForcePlateTimeOffset { .. }
            | EffectSpec::CopOffset { .. }
            | EffectSpec::ForcePlateGain { .. } => {
                return Err(anyhow!(
                    "--hidden-effect: {} is an instrument of one force plate; synth hides the model's effects and the clock and CoP offsets of both plates (side=both). Trials with one plate's clock, CoP or gain changed are made from measured data by tools/make-real-hidden-trials",
                    e.label()
                ))
            }
            other => model_effects.push(other.clone()),
        }
    }
    Ok((hidden, offsets, model_effects))
}

/// The truth the trial is generated from: the model and foot, the phase file and the
/// solution.
struct Truth {
    /// The model file.
    model_path: PathBuf,
    /// The foot (name or file).
    foot: String,
    /// The model with the foot (and the hidden model effects).
    model: GaitModel,
    /// The phase file.
    phases: PathBuf,
    /// The solution that drives the model.
    solution: crate::problems::evaluation::GaitSolution,
}

impl Truth {
    /// The `--from` solution with its model, foot and phases (given, else the `--from`
    /// track run's, else the defaults); with `model_effects`, the `--from` run's problem
    /// re-solved with the effects in the model.
    fn read(
        args: &SynthRequest,
        model_effects: &[EffectSpec],
        progress: &dyn Progress,
    ) -> anyhow::Result<Self> {
        let solution = super::read_solution(&args.from)?;
        // what the --from run was made with, unless given
        let from_setup = if args.from.is_dir() && args.from.join("setup.json").is_file() {
            Some(super::track::read_run_setup(&args.from)?)
        } else {
            None
        };
        let model_path = args
            .model
            .clone()
            .or_else(|| from_setup.as_ref().map(|s| s.model.clone()))
            .unwrap_or_else(|| PathBuf::from("models/opensim_subject01.json"));
        let foot = args
            .foot
            .clone()
            .or_else(|| from_setup.as_ref().map(|s| s.foot.clone()))
            .unwrap_or_else(|| "ellipse".into());
        let model = GaitModel::load(&model_path, &super::foot_path(&foot))?;
        let phases = args
            .phases
            .clone()
            .or_else(|| from_setup.as_ref().map(|s| s.phases.clone()))
            .unwrap_or_else(|| super::default_phases(&foot));
        let mut truth = Truth {
            model_path,
            foot,
            model,
            phases,
            solution,
        };
        if !model_effects.is_empty() {
            truth.refit_with(args, model_effects, progress)?;
        }
        Ok(truth)
    }

    /// The truth with `model_effects` in the model: the --from run's problem re-solved
    /// with them, from its solution.
    fn refit_with(
        &mut self,
        args: &SynthRequest,
        model_effects: &[EffectSpec],
        progress: &dyn Progress,
    ) -> anyhow::Result<()> {
        let run = super::track::read_run_setup(&args.from)
            .context("--hidden-effect with a model effect needs a track run folder as --from")?;
        let mut prob = super::track::TrackingProblem::build(&run, model_effects)?;
        prob.setup
            .start_from(&self.solution)
            .map_err(|e| anyhow!("{}: {e}", args.from.display()))?;
        {
            note!(
                progress,
                "re-fitting {} with {} hidden in the model",
                args.from.display(),
                model_effects
                    .iter()
                    .map(|e| e.label())
                    .collect::<Vec<_>>()
                    .join(" and ")
            );
        }
        let settings = super::track::tracking_sqp_settings(
            1e-5,
            200,
            None,
            crate::sqp::HessianMode::Exact,
            None,
        );
        let (res, sol) = prob.solve(&settings, progress)?;
        if res.status != crate::sqp::SqpStatus::Converged {
            return Err(super::Unsolved {
                status: res.status.clone(),
                at_start: res.history.is_empty(),
                message: format!("the model with the hidden effect did not converge on the --from run's data: {}", res.status),
            }
            .into());
        }
        self.solution = sol;
        self.phases = run.phases.clone();
        self.model = prob.model;
        Ok(())
    }

    /// Refuse a solution that does not belong to the model and phase graph.
    fn check_fits(
        &self,
        args: &SynthRequest,
        sets: &[crate::model::ConstraintSet],
    ) -> anyhow::Result<()> {
        let (model, solution) = (&self.model, &self.solution);
        if solution
            .phases
            .iter()
            .any(|p| p.set >= sets.len() || p.x.iter().any(|x| x.len() != model.nx()))
        {
            bail!("{}: the solution does not belong to this model and phase graph ({} states, phases of {})", args.from.display(), model.nx(), self.phases.display());
        }
        if solution.theta.len() != model.ntheta() {
            bail!(
                "{}: the solution has {} free parameters, the model {}",
                args.from.display(),
                solution.theta.len(),
                model.ntheta()
            );
        }
        Ok(())
    }
}

/// Run `synth` as `args` describes, reporting to `progress`.
pub fn run(args: &SynthRequest, progress: &dyn Progress) -> anyhow::Result<()> {
    if !(args.half_cycles.is_finite() && args.half_cycles >= 2.5) {
        bail!(
            "--half-cycles {}: need at least 2.5 (a gait cycle plus margins for the event search)",
            args.half_cycles
        );
    }
    let (hidden, offsets, model_effects) = hidden_effects(args)?;
    let truth_run = Truth::read(args, &model_effects, progress)?;
    let (model, phases) = (&truth_run.model, &truth_run.phases);
    let seq = PhaseSequence::load(phases)?;
    let sets = seq.resolve(model, phases)?;
    truth_run.check_fits(args, &sets)?;
    let mut truth_sol = truth_run.solution.clone();
    let t0 = truth_sol.phases[0].t0;
    truth_sol.phases.iter_mut().for_each(|p| p.t0 -= t0);
    let half = truth_sol.span().1;
    let deg = std::f64::consts::PI / 180.0;
    let noise = NoiseModel {
        position_m: args.noise_position_mm * 1e-3,
        angle_rad: args.noise_angle_deg * deg,
        force_n: args.noise_force_n,
        cop_m: args.noise_cop_mm * 1e-3,
        seed: args.seed,
    };
    // start half a half cycle early so the first heel strike lies inside the trial
    let settings = SynthSettings {
        rate_hz: args.rate,
        start_s: -0.5 * half,
        duration_s: args.half_cycles * half,
        noise,
        integrator: IntegratorSettings {
            rtol: 1e-10,
            atol: 1e-10,
            ..Default::default()
        },
        measurement: offsets,
    };
    let folder = RunFolder::create(&args.out, args.overwrite)?;
    let (data, truth) = synthesize(model, &sets, &truth_sol, &settings, "synthetic")
        .map_err(|e| anyhow!("generating the trial: {e}"))?;
    let (csv, meta) = write_sagittal_csv(&data);
    let (clean_csv, _) = write_sagittal_csv(&truth.clean);
    // the trial's model, foot and phases, copied into the folder
    let (model_copy, foot_copy, phases_copy) =
        super::inputs::copy_model_inputs(&folder, &truth_run.model_path, &truth_run.foot, phases)?;
    let truth_json = serde_json::json!({
        "from": args.from,
        "model": truth_run.model_path,
        "foot": model.foot_name,
        "phases": phases,
        "inputs": {"model": model_copy, "foot": foot_copy, "phases": phases_copy},
        "hidden_effects": hidden,
        "measurement_offsets": offsets,
        "effect_parameters": model.parameters().iter().map(|p| serde_json::json!({"name": p.name, "value": p.value, "unit": p.unit})).collect::<Vec<_>>(),
        "noise": noise,
        "noise_model": "independent Gaussian per channel and sample (ChaCha8, seeded); an unloaded foot reads exactly zero; CoP undefined below the CoP threshold",
        "rate_hz": args.rate,
        "half_period_s": truth.half_period_s,
        "step_length_m": truth.step_length_m,
        "solution_time_offset_s": t0,
    });
    folder.write("synthetic.csv", csv.as_bytes())?;
    folder.write("synthetic_meta.json", meta.as_bytes())?;
    folder.write("truth_clean.csv", clean_csv.as_bytes())?;
    folder.write(
        "truth.json",
        serde_json::to_string_pretty(&truth_json)?.as_bytes(),
    )?;
    let out = folder.commit()?;
    {
        note!(progress,
            "{} samples at {} Hz over {:.3} s ({} half cycles of {:.3} s, step {:.3} m), noise {}° / {} mm / {} N / {} mm (seed {})",
            data.time.len(),
            args.rate,
            data.time[data.time.len() - 1] - data.time[0],
            args.half_cycles,
            half,
            truth.step_length_m,
            args.noise_angle_deg,
            args.noise_position_mm,
            args.noise_force_n,
            args.noise_cop_mm,
            args.seed
        );
        note!(
            progress,
            "trial: {}  (track it with --data)",
            out.join("synthetic.csv").display()
        );
    }
    Ok(())
}
