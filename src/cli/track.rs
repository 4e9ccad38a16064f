//! `footfall track`: track measured walking with the model (seed 001 §3.4).

use super::gait_run::GaitRun;
use super::Failure;
use anyhow::{anyhow, Context};
use footfall::integrate::IntegratorSettings;
use footfall::model::effects::EffectSpec;
use footfall::model::GaitModel;
use footfall::ocp::Transcription;
use footfall::phases::PhaseSequence;
use footfall::problems::diagnose::{parameter_sd, IdentifiedParameter, TrackingRunSetup};
use footfall::problems::evaluation::GaitSolution;
use footfall::problems::gait::GaitCycle;
use footfall::problems::track::{TargetSides, TrackingSetup};
use footfall::runfolder::RunFolder;
use footfall::sqp::{ExactConvexification, HessianMode, SqpSettings, SqpStatus};
use std::path::PathBuf;

/// Arguments of `footfall track`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file.
    #[arg(long, default_value = "models/opensim_subject01.json")]
    model: PathBuf,
    /// Foot: `ellipse`, `double-circle` or a foot file.
    #[arg(long, default_value = "ellipse")]
    foot: String,
    /// Phase graph (default: the seed's graph for the bundled feet).
    #[arg(long)]
    phases: Option<PathBuf>,
    /// Sagittal CSV (default: the bundled OpenSim subject01 trial, moved overground).
    #[arg(long)]
    data: Option<PathBuf>,
    /// Take a trial whose meta file gives no belt speed as overground, as it is (a
    /// treadmill trial without a belt speed is refused otherwise).
    #[arg(long)]
    overground: bool,
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
    check_points: super::refine::CheckPointArgs,
    /// Continue the run a killed process left unfinished in this output folder, from its
    /// last SQP iteration, with the options it was started with (give no others).
    #[arg(long, value_name = "DIR")]
    pub resume: Option<PathBuf>,
    /// Hessian: exact (converges), or gauss-newton (the seed's; stalls near KKT 3e-5).
    #[arg(long, value_enum, default_value = "exact")]
    hessian: super::solve::HessianArg,
    /// KKT tolerance.
    #[arg(long, default_value_t = 1e-5, value_parser = super::validate::positive)]
    tol: f64,
    /// Relative and absolute CVODES tolerance of the shooting intervals.
    #[arg(long, default_value_t = 1e-8, value_parser = super::validate::positive)]
    integrator_tol: f64,
    /// CVODES tolerance of the forward sensitivities (default: the states'; with a heel
    /// pad, whose states are integrated at 1e-10, `--integrator-tol`). The KKT residual is
    /// computed from them: tighten it if a fit stalls just above `--tol`.
    #[arg(long, value_parser = super::validate::positive)]
    sensitivity_tol: Option<f64>,
    /// With `--hessian exact`: Gauss–Newton steps until the constraint violation is below this.
    #[arg(long, default_value_t = 1e-3, value_parser = super::validate::threshold)]
    exact_below: f64,
    /// Iteration limit.
    #[arg(long, default_value_t = 200, value_parser = super::validate::iterations)]
    max_iter: usize,
    /// Wall-time limit (s).
    #[arg(long, value_parser = super::validate::positive)]
    max_time: Option<f64>,
    /// Report ground-force excursions above the measurement larger than this (N).
    #[arg(long, default_value_t = super::gait_run::DEFAULT_TRANSIENT_THRESHOLD_N, value_parser = super::validate::positive)]
    transient_threshold: f64,
    /// Add an effect and identify its parameters: `NAME[:key=value,…]`, e.g.
    /// `ground_slope`, `passive_joint_stiffness:joint=knee`, `cop_offset:offset=0.01,free=`
    /// (repeatable; names: ground_slope, trunk_mass, passive_joint_stiffness,
    /// force_plate_time_offset, cop_offset, heel_pad_compliance).
    #[arg(long = "effect", value_name = "NAME[:key=value,…]")]
    effects: Vec<String>,
    /// Track the pelvis position (x, y) too, weighted 1/(0.1 m) as angles are by
    /// 1/(π/4); the seed leaves it untracked (then a CoP offset cannot be identified: the
    /// model shifts along the walkway instead).
    #[arg(long)]
    track_pelvis_position: bool,
    /// Add residual actuators: a force on each pelvis translation and a torque on the
    /// pelvis tilt and every joint (100 N or N·m per unit control, penalised at 1e-2 per
    /// unit²), so the model can follow the data and the residuals show what it lacks.
    #[arg(long)]
    residual_actuators: bool,
    /// Weight of the excitation² and activation² regularisation terms (default: the
    /// seed's 1e-3). Smaller weights let effort-costly parameters (slope, trunk mass)
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
    /// the seed's weights (the maximum-likelihood weighting; the angles keep the seed's
    /// weight, so the regularisation keeps its meaning): `angle=DEG,position=MM,force=N,cop=MM`,
    /// e.g. `angle=0.5,position=2,force=5,cop=5` (synth's default noise).
    #[arg(long, value_name = "angle=DEG,position=MM,force=N,cop=MM")]
    noise_weights: Option<String>,
    /// Weight of the angular-velocity targets relative to the angles (default: the seed's
    /// 0.1; 0 drops them). The targets differentiate the smoothed angles, so they carry
    /// the filter's bias and its low-passed noise, which a fit can follow.
    #[arg(long, allow_negative_numbers = true, value_parser = super::validate::non_negative)]
    velocity_weight: Option<f64>,
    /// Start from the solution of a track run (its folder or solution.json) of the same
    /// phase graph instead of the data; effect parameters it identified start at its
    /// values, unless an `--effect` holds them fixed at its own.
    #[arg(long)]
    init: Option<PathBuf>,
}

/// CVODES tolerance of the states of problems with a compliant heel pad or residual
/// actuators: at 1e-8 integration noise stalls the line search (a pad near KKT 2e-4; the
/// bundled trial with residual actuators at KKT 3.2e-5 after 103 iterations, where 1e-10
/// converges in 38). With a pad the sensitivities keep the run's tolerance: at 1e-10 they
/// cost 37–46 % of a pad re-fit's time (`diagnose` on the 100 Hz sample-target trials:
/// the padded one's re-fit reaches the same optimum in the same 22 iterations, 90 → 57 s;
/// the no-effect one's in 43 instead of 49, 177 → 96 s). With residual actuators they
/// stay at 1e-10: the KKT residual is computed from them, and at 1e-8 the bundled trial's
/// residual fit reaches the same J but stalls at KKT 2.4e-5.
pub const PADDED_INTEGRATOR_TOL: f64 = 1e-10;

/// Force (N) or torque (N·m) of a residual actuator per unit control.
pub const RESIDUAL_SCALE: f64 = 100.0;

/// The residual actuators' profiles at the nodes (plots, phases shaded), their RMS and
/// peak values (N or N·m) and how often they sit on their bounds, for a model that has
/// them.
fn residual_report(
    model: &GaitModel,
    sol: &GaitSolution,
) -> Option<(footfall::report::html::Section, serde_json::Value)> {
    use footfall::report::plot::{LinePlot, LineStyle, Series, Span};
    let uses = footfall::problems::evaluation::residual_use(model, sol);
    if uses.is_empty() {
        return None;
    }
    let spans: Vec<Span> = sol
        .phase_spans()
        .iter()
        .map(|p| Span::new(p.t0, p.t1, p.name.clone()))
        .collect();
    let mut forces = LinePlot::new("Residual forces on the pelvis", "time (s)", "force (N)");
    let mut torques = LinePlot::new("Residual torques", "time (s)", "torque (N·m)");
    for r in &uses {
        let p = if r.unit == "N" {
            &mut forces
        } else {
            &mut torques
        };
        p.series.push(Series::new(
            r.name.trim_end_matches("_residual").replace('_', " "),
            r.times.clone(),
            r.values.clone(),
            LineStyle::Solid,
        ));
    }
    forces.shaded = spans.clone();
    torques.shaded = spans;
    let rows = uses
        .iter()
        .map(|r| {
            vec![
                r.name.clone(),
                format!("{:.2}", r.rms),
                format!("{:.2}", r.peak),
                format!("±{}", r.bound),
                format!("{:.0}", 100.0 * r.at_bound_fraction),
                r.unit.to_string(),
            ]
        })
        .collect();
    let table = footfall::report::table::Table {
        title: "Residual actuators at the nodes".into(),
        headers: [
            "residual",
            "RMS",
            "peak |·|",
            "bound",
            "% of nodes at the bound",
            "unit",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    };
    let mut paragraphs = vec!["What the model needs beyond its own actuators to follow the data, and when: residual forces on the pelvis translations and torques on the pelvis tilt and the joints, at the shooting nodes.".to_string()];
    let saturated: Vec<&str> = uses
        .iter()
        .filter(|r| r.at_bound_fraction > 0.0)
        .map(|r| r.name.as_str())
        .collect();
    if !saturated.is_empty() {
        paragraphs.push(format!(
            "{} of {} residuals reach their bound ({}): where they do, the model needs more than the residual may give, so the profile is a lower bound of what is missing and the tracking error there carries the rest.",
            saturated.len(),
            uses.len(),
            saturated.join(", ")
        ));
    }
    let stats = serde_json::to_value(&uses).unwrap_or_default();
    Some((
        footfall::report::html::Section {
            heading: "Residual actuators".into(),
            paragraphs,
            tables: vec![table],
            svgs: vec![forces.to_svg(), torques.to_svg()],
        },
        stats,
    ))
}

/// The parts of a tracking problem that do not borrow each other.
pub struct TrackingProblem {
    pub model: GaitModel,
    pub sets: Vec<footfall::model::ConstraintSet>,
    pub data: footfall::data::GaitData,
    pub setup: TrackingSetup,
    pub phases: PathBuf,
    pub integrator: IntegratorSettings,
    /// Check points the problem has from the start (those of the run it was rebuilt from).
    pub check_sites: super::refine::CheckSites,
    /// Whether a solve adds check points where the solution breaks a contact constraint
    /// between the nodes.
    pub refine: bool,
    /// Integrator counters of every solve of this problem so far (all stages and
    /// refinement rounds), written to `summary.json` as `integration`.
    pub integration: std::cell::Cell<footfall::integrate::IntegrationStats>,
}

impl TrackingProblem {
    /// Rebuild the problem a run describes, with `extra` effects added (parameters free
    /// at their values) and the run's identified parameter values. The run's values
    /// only start free parameters; a fixed one keeps the value its effect gives (a fixed
    /// parameter does not move, so a run's value of it is its effect's — except for
    /// `extra`: `--effect trunk_mass:added_mass=4,com_offset=0.03,free=` with `--init` of
    /// a run that identified other values holds 4 kg and 0.03 m).
    pub fn build(run: &TrackingRunSetup, extra: &[EffectSpec]) -> anyhow::Result<Self> {
        let foot_path = super::simulate::foot_path(&run.foot);
        let mut effects = run.effects.clone();
        effects.extend(extra.iter().cloned());
        let mut model = GaitModel::load_with_effects(&run.model, &foot_path, &effects)?;
        if run.residual_actuators {
            model = model.with_residual_actuators(RESIDUAL_SCALE, RESIDUAL_SCALE);
        }
        for p in &run.parameters {
            // a free parameter the run knew is started at its value (one the model lacks
            // or holds fixed is left as it is)
            if model
                .parameters()
                .iter()
                .any(|q| q.name == p.name && q.free)
            {
                model
                    .set_parameter_value(&p.name, p.value)
                    .map_err(|e| anyhow!(e))?;
            }
        }
        let seq = PhaseSequence::load(&run.phases)?;
        let sets = seq.resolve(&model, &run.phases)?;
        let mut data = super::load_data(run.data.as_deref(), run.overground)?;
        let sides = if run.one_sided_targets {
            TargetSides::OneSided {
                cutoff_hz: run.kinematics_cutoff,
            }
        } else if run.sample_targets {
            TargetSides::Samples
        } else {
            TargetSides::Interpolated
        };
        if let Some(fc) = run.kinematics_cutoff {
            // one-sided targets filter segment by segment (the same sampling and cutoff checks)
            if run.one_sided_targets {
                data.kinematics_filter_rate(fc)
                    .context("--kinematics-cutoff")?;
            } else {
                data = data
                    .low_pass_kinematics(fc)
                    .context("--kinematics-cutoff")?;
            }
        }
        let mut setup = TrackingSetup::new_with_sides(&model, &seq, &sets, &data, sides)
            .map_err(|e| anyhow!("{}: {e}", data.source.display()))?;
        if run.track_pelvis_position {
            setup.weights = setup.weights.clone().with_pelvis_position();
        }
        if let Some(noise) = &run.noise_weights {
            setup.weights = setup.weights.clone().with_noise_weights(noise);
        }
        if let Some(w) = run.regularisation {
            if !(w.is_finite() && w >= 0.0) {
                return Err(anyhow!(
                    "--regularisation {w}: expected a finite weight ≥ 0 (the seed's is 1e-3)"
                ));
            }
            setup.weights.excitation = w;
            setup.weights.activation = w;
        }
        if let Some(v) = run.velocity_weight {
            if !(v.is_finite() && v >= 0.0) {
                return Err(anyhow!("--velocity-weight {v}: expected a finite weight ≥ 0 relative to the angles' (the seed's is 0.1)"));
            }
            setup.weights = setup.weights.clone().with_velocity_weight(v);
        }
        // a pad (from the model file or `extra`) or residual actuators need a tighter tolerance
        let stiff =
            run.residual_actuators || (0..model.contacts.len()).any(|c| model.is_compliant(c));
        let tol = if stiff {
            run.integrator_tol.min(PADDED_INTEGRATOR_TOL)
        } else {
            run.integrator_tol
        };
        let sens_tol = run.sensitivity_tol.unwrap_or(if run.residual_actuators {
            tol
        } else {
            run.integrator_tol
        });
        let sens_tol = (sens_tol != tol).then_some(sens_tol);
        let integrator = IntegratorSettings {
            rtol: tol,
            atol: tol,
            sens_tol,
            ..Default::default()
        };
        integrator
            .validate()
            .context("--integrator-tol or --sensitivity-tol")?;
        Ok(Self {
            model,
            sets,
            data,
            setup,
            phases: run.phases.clone(),
            integrator,
            check_sites: run.check_points.clone(),
            refine: false,
            integration: Default::default(),
        })
    }

    /// The run description of a solution `theta` of this problem with standard
    /// deviations `sd` (per θ).
    pub fn record(
        &self,
        base: &TrackingRunSetup,
        extra: &[EffectSpec],
        theta: &[f64],
        sd: &[Option<f64>],
        check_points: &[(usize, usize, f64)],
    ) -> TrackingRunSetup {
        let free = self.model.free_parameters();
        let parameters = self
            .model
            .parameters()
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let k = free.iter().position(|&f| f == i);
                IdentifiedParameter {
                    name: p.name.clone(),
                    value: k.map_or(p.value, |k| theta[k]),
                    sd: k.and_then(|k| sd.get(k).copied().flatten()),
                    unit: p.unit.clone(),
                    free: p.free,
                }
            })
            .collect();
        let mut effects = base.effects.clone();
        effects.extend(extra.iter().cloned());
        TrackingRunSetup {
            effects,
            parameters,
            integrator_tol: self.integrator.rtol,
            sensitivity_tol: self.integrator.sens_tol,
            check_points: check_points.to_vec(),
            ..base.clone()
        }
    }
}

/// `--noise-weights angle=DEG,position=MM,force=N,cop=MM`: every key once, each a
/// positive, finite standard deviation.
fn parse_noise_weights(text: &str) -> anyhow::Result<footfall::problems::tracking::ChannelNoise> {
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
    Ok(footfall::problems::tracking::ChannelNoise {
        angle_rad: a.to_radians(),
        position_m: p * 1e-3,
        force_n: f,
        cop_m: c * 1e-3,
    })
}

/// The tracking solver's settings (exact Hessian once nearly feasible, as `track`'s
/// defaults).
pub fn tracking_sqp_settings(
    tol: f64,
    max_iter: usize,
    max_time: Option<f64>,
    hessian: HessianMode,
    exact_below: f64,
) -> SqpSettings {
    SqpSettings {
        tol_kkt: tol,
        max_iter,
        max_time,
        hessian,
        exact_hessian_below: exact_below,
        exact_convexification: ExactConvexification::InertiaCorrection,
        ..Default::default()
    }
}

impl TrackingProblem {
    /// Start the problem at `start`: its states, controls and free parameters (its
    /// θ lists the free parameters in the model's order). `diagnose` starts a verifying
    /// re-fit where the candidate's truncated re-fit got to.
    pub fn start_at(&mut self, start: &GaitSolution) -> anyhow::Result<()> {
        self.setup.start_from(start).map_err(|e| anyhow!(e))?;
        let names: Vec<String> = self
            .model
            .free_parameters()
            .iter()
            .map(|&i| self.model.parameters()[i].name.clone())
            .collect();
        for (name, &v) in names.iter().zip(&start.theta) {
            self.model
                .set_parameter_value(name, v)
                .map_err(|e| anyhow!(e))?;
        }
        Ok(())
    }

    /// Run `f` on the problem's transcription, its walking cycle and its initial point
    /// (the guess: the data, or the solution it was started from).
    pub fn with_transcription<R>(
        &self,
        f: impl FnOnce(&Transcription, &GaitCycle, Vec<f64>) -> anyhow::Result<R>,
    ) -> anyhow::Result<R> {
        let cycle =
            GaitCycle::new(&self.model, &self.setup.seq, &self.sets).map_err(|e| anyhow!(e))?;
        let mut ocp = self
            .setup
            .ocp(&cycle, &self.model, &self.sets, self.integrator.clone())
            .map_err(|e| anyhow!(e))?;
        ocp.checks = self.checks(&cycle);
        let tr = Transcription::new(&ocp).context("transcribing the tracking problem")?;
        let (_, _, w0) = tr.variable_bounds_and_guess();
        f(&tr, &cycle, w0)
    }

    /// Solve the problem (interruptibly, with progress unless `quiet`) and read its
    /// solution.
    pub fn solve(
        &self,
        settings: &SqpSettings,
        quiet: bool,
    ) -> anyhow::Result<(footfall::sqp::SqpResult, GaitSolution)> {
        self.with_transcription(|tr, cycle, w0| {
            self.solve_staged(tr, cycle, &w0, settings, quiet, |tr, res| {
                let sol =
                    GaitSolution::from_nlp(tr, &res.w, &cycle.continuous, self.setup.window.0);
                Ok((res, sol))
            })
        })
    }

    /// Solve on `tr` from `w0` and hand the result, with the transcription it was last
    /// iterated on, to `finish`. When the line search fails, the solve goes on once from
    /// that iterate with more precise integration, because near an optimum the
    /// integrator's error is what stops it:
    /// - sensitivities looser than the states (a heel pad): at the states' tolerance. The
    ///   KKT residual is computed from them, so the looser ones can leave an optimum
    ///   uncertified (a padded 100 Hz trial's re-fit stopped at KKT 2.4e-5 with them at
    ///   1e-8 and converged at 1e-10 to the same parameters);
    /// - otherwise states and sensitivities 100× tighter (down to 1e-12): the force-plate
    ///   clock's re-fit of its hidden-effect trial stalled at J = 0.2988352308, KKT 9.7e-4,
    ///   with every trial step rejected; restarted at 1e-8 its line search fails at once,
    ///   at 1e-10 it converges in 8 iterations (KKT 4.9e-7).
    fn solve_staged<R>(
        &self,
        tr: &Transcription,
        cycle: &GaitCycle,
        w0: &[f64],
        settings: &SqpSettings,
        quiet: bool,
        finish: impl FnOnce(&Transcription, footfall::sqp::SqpResult) -> anyhow::Result<R>,
    ) -> anyhow::Result<R> {
        let first = super::solve_interruptibly(tr, w0, settings, quiet);
        self.count_integration(tr);
        let first = first?;
        if first.status != footfall::sqp::SqpStatus::LineSearchFailure {
            return finish(tr, first);
        }
        let current = &self.integrator;
        let (tight, what) = match current.sens_tol.filter(|&t| t > current.rtol) {
            Some(sens_tol) => (
                IntegratorSettings { sens_tol: None, ..current.clone() },
                format!("the sensitivities at {sens_tol:e}: going on from there with them at {:e} (the KKT residual is computed from them)", current.rtol),
            ),
            None if current.rtol > TIGHTEST_TOL => {
                let rtol = (current.rtol * 1e-2).max(TIGHTEST_TOL);
                let atol = (current.atol * 1e-2).max(TIGHTEST_TOL);
                let sens_tol = current.sens_tol.map(|t| (t * 1e-2).max(TIGHTEST_TOL));
                (
                    IntegratorSettings { rtol, atol, sens_tol, ..current.clone() },
                    format!("the integrator at {:e}: going on from there at {rtol:e} (integration error stalls a line search near an optimum)", current.rtol),
                )
            }
            None => return finish(tr, first),
        };
        let used = first.history.len().saturating_sub(1);
        if !quiet {
            eprintln!("line search failed at KKT {:.2e} with {what}", first.kkt);
        }
        let mut ocp = self
            .setup
            .ocp(cycle, &self.model, &self.sets, tight)
            .map_err(|e| anyhow!(e))?;
        ocp.checks = self.checks(cycle);
        let tr2 = Transcription::new(&ocp).context("transcribing the tracking problem")?;
        let rest = SqpSettings {
            max_iter: settings.max_iter.saturating_sub(used),
            max_time: settings.max_time.map(|t| (t - first.seconds).max(0.0)),
            ..settings.clone()
        };
        let second = super::solve_interruptibly(&tr2, &first.w, &rest, quiet);
        self.count_integration(&tr2);
        finish(&tr2, merge_stages(first, second?))
    }

    /// Add the integrator counters of `tr`'s evaluations to this problem's.
    fn count_integration(&self, tr: &Transcription) {
        let mut total = self.integration.get();
        total += tr.integration_totals();
        self.integration.set(total);
    }

    /// The path constraints at this problem's check points.
    fn checks<'m>(&self, cycle: &GaitCycle<'m>) -> Vec<footfall::ocp::CheckPoint<'m>> {
        self.check_sites
            .iter()
            .flat_map(|&(j, k, tau)| cycle.contact_checks(j, k, tau))
            .collect()
    }
}

/// The tightest integrator tolerance a failed line search moves a tracking solve to.
const TIGHTEST_TOL: f64 = 1e-12;

/// One result of two solves, the second started where the first stopped: the second's
/// point and status, the iteration history of both (the second's numbered on, without
/// its repeated initial point), their times added up.
pub(super) fn merge_stages(
    first: footfall::sqp::SqpResult,
    second: footfall::sqp::SqpResult,
) -> footfall::sqp::SqpResult {
    let (used, elapsed) = (first.history.len().saturating_sub(1), first.seconds);
    let mut history = first.history;
    history.extend(
        second
            .history
            .iter()
            .skip(1)
            .map(|r| footfall::sqp::IterationRecord {
                iter: r.iter + used,
                seconds: r.seconds + elapsed,
                ..r.clone()
            }),
    );
    let mut timings = first.timings;
    timings += second.timings;
    footfall::sqp::SqpResult {
        history,
        timings,
        seconds: first.seconds + second.seconds,
        ..second
    }
}

/// The cost-share table (channel × phase, % of J), the normalised-error table (channel ×
/// phase) and the worst windows.
pub fn cost_tables(
    b: &footfall::problems::track::CostBreakdown,
) -> (
    footfall::report::table::Table,
    footfall::report::table::Table,
    footfall::report::table::Table,
) {
    use footfall::report::table::Table;
    let total = b.total().max(f64::MIN_POSITIVE);
    let mut order: Vec<usize> = (0..b.channels.len()).collect();
    let sums: Vec<f64> = b.cost.iter().map(|per| per.iter().sum()).collect();
    order.sort_by(|&x, &y| sums[y].total_cmp(&sums[x]));
    let mut headers = vec!["channel".to_string(), "% of J".into()];
    headers.extend(b.phases.iter().map(|p| format!("{p} %")));
    let share = Table {
        title: "Share of the tracking cost per channel and phase".into(),
        headers,
        rows: order
            .iter()
            .map(|&c| {
                let mut row = vec![
                    b.channels[c].clone(),
                    format!("{:.1}", 100.0 * sums[c] / total),
                ];
                row.extend(
                    b.cost[c]
                        .iter()
                        .map(|v| format!("{:.1}", 100.0 * v / total)),
                );
                row
            })
            .collect(),
    };
    let rms = b.normalised_rms();
    let mut headers = vec!["channel".to_string(), "all".into()];
    headers.extend(b.phases.iter().cloned());
    let normalised = Table {
        title: "Normalised error per channel and phase (RMS of the weighted residual)".into(),
        headers,
        rows: order
            .iter()
            .map(|&c| {
                let n: usize = b.rows[c].iter().sum();
                let mut row = vec![
                    b.channels[c].clone(),
                    if n > 0 {
                        format!("{:.4}", (sums[c] / n as f64).sqrt())
                    } else {
                        "—".into()
                    },
                ];
                row.extend(
                    rms[c]
                        .iter()
                        .map(|v| v.map_or("—".into(), |v| format!("{v:.4}"))),
                );
                row
            })
            .collect(),
    };
    let windows = Table {
        title: "Worst stretches (five nodes)".into(),
        headers: [
            "from (s)",
            "to (s)",
            "% of the data cost",
            "largest channel",
        ]
        .map(String::from)
        .to_vec(),
        rows: {
            let data: f64 = b
                .nodes
                .iter()
                .map(|n| n.data)
                .sum::<f64>()
                .max(f64::MIN_POSITIVE);
            b.worst_windows(5, 3)
                .into_iter()
                .map(|(t0, t1, v, c)| {
                    vec![
                        format!("{t0:.3}"),
                        format!("{t1:.3}"),
                        format!("{:.1}", 100.0 * v / data),
                        c,
                    ]
                })
                .collect()
        },
    };
    (share, normalised, windows)
}

/// Read a run's `setup.json`.
pub fn read_run_setup(run: &std::path::Path) -> anyhow::Result<TrackingRunSetup> {
    let file = if run.is_dir() {
        run.join("setup.json")
    } else {
        run.to_path_buf()
    };
    let text = std::fs::read_to_string(&file)
        .with_context(|| format!("reading {} (a track run folder has one)", file.display()))?;
    serde_json::from_str(&text)
        .with_context(|| format!("{}: not a footfall tracking setup", file.display()))
}

/// Table of effect parameters (identified ones with their standard deviation).
pub fn parameter_table(params: &[IdentifiedParameter]) -> footfall::report::table::Table {
    footfall::report::table::Table {
        title: "Effect parameters".into(),
        headers: vec![
            "parameter".into(),
            "value".into(),
            "± sd".into(),
            "unit".into(),
            "identified".into(),
        ],
        rows: params
            .iter()
            .map(|p| {
                vec![
                    p.name.clone(),
                    format!("{:.5}", p.value),
                    p.sd.map_or("—".into(), |v| format!("{v:.2e}")),
                    p.unit.clone(),
                    if p.free { "yes".into() } else { "no".into() },
                ]
            })
            .collect(),
    }
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    run_inner(args, quiet).map_err(Failure::classify)
}

fn run_inner(args: Args, quiet: bool) -> anyhow::Result<()> {
    let phases = args
        .phases
        .clone()
        .unwrap_or_else(|| super::predict::default_phases(&args.foot));
    let extra: Vec<EffectSpec> = args
        .effects
        .iter()
        .map(|e| EffectSpec::parse_cli(e).map_err(|r| anyhow!("--effect: {r}")))
        .collect::<Result<_, _>>()?;
    let mut base = TrackingRunSetup {
        model: args.model.clone(),
        foot: args.foot.clone(),
        phases,
        data: args.data.clone(),
        overground: args.overground,
        kinematics_cutoff: args.kinematics_cutoff,
        integrator_tol: args.integrator_tol,
        sensitivity_tol: args.sensitivity_tol,
        track_pelvis_position: args.track_pelvis_position,
        residual_actuators: args.residual_actuators,
        regularisation: args.regularisation,
        velocity_weight: args.velocity_weight,
        one_sided_targets: args.one_sided_targets,
        sample_targets: args.sample_targets,
        noise_weights: args
            .noise_weights
            .as_deref()
            .map(parse_noise_weights)
            .transpose()?,
        check_points: vec![],
        effects: vec![],
        parameters: vec![],
    };
    let init = match &args.init {
        Some(p) => {
            let sol = super::predict::read_solution(p)?;
            if p.is_dir() && p.join("setup.json").exists() {
                let from = read_run_setup(p)?;
                base.parameters = from.parameters;
                base.check_points = from.check_points;
            }
            Some(sol)
        }
        None => None,
    };
    let mut prob = TrackingProblem::build(&base, &extra)?;
    prob.refine = args.check_points.enabled();
    base.check_points.clear();
    if prob.integrator.rtol < base.integrator_tol && !quiet {
        let why = if args.residual_actuators {
            "residual actuators"
        } else {
            "the heel pad's stiff dynamics"
        };
        eprintln!("{why}: integrator tolerance of the states {:e} → {:e} (integration noise stalls the line search at 1e-8), of the sensitivities {:e}", base.integrator_tol, prob.integrator.rtol, prob.integrator.sens_tol.unwrap_or(prob.integrator.rtol));
    }
    if let Some(sol) = &init {
        prob.setup.start_from(sol).map_err(|e| {
            anyhow!(
                "--init {}: {e}",
                args.init
                    .as_ref()
                    .map(|p| p.display().to_string())
                    .unwrap_or_default()
            )
        })?;
    }
    base.parameters.clear();
    let hessian: HessianMode = args.hessian.into();
    let settings = tracking_sqp_settings(
        args.tol,
        args.max_iter,
        args.max_time,
        hessian,
        args.exact_below,
    );
    let folder = super::session::create_checkpointed_run_folder(&args.out, args.overwrite)?;
    let run = prob.solve_and_write(
        &base,
        &extra,
        &settings,
        folder,
        args.transient_threshold,
        quiet,
    )?;
    super::Unsolved::check(&run.result, &run.output.path)?;
    super::Invalid::check(&run.output)?;
    Ok(())
}

impl TrackingProblem {
    /// Solve the problem and write its run folder (`setup.json` records the effects and
    /// the identified parameters with their uncertainty). `base` describes the run
    /// without `extra` effects.
    pub fn solve_and_write(
        &self,
        base: &TrackingRunSetup,
        extra: &[EffectSpec],
        settings: &SqpSettings,
        folder: RunFolder,
        transient_threshold: f64,
        quiet: bool,
    ) -> anyhow::Result<TrackedRun> {
        let w0 = self.with_transcription(|tr, _, w0| {
            if !quiet {
                eprintln!(
                    "tracking {:.3}–{:.3} s of {} with the {} foot ({} variables, {} constraints, {:?})",
                    self.setup.window.0,
                    self.setup.window.1,
                    self.data.name,
                    self.model.foot_name,
                    tr.n(),
                    tr.m(),
                    settings.hessian
                );
            }
            Ok(w0)
        })?;
        let cycle =
            GaitCycle::new(&self.model, &self.setup.seq, &self.sets).map_err(|e| anyhow!(e))?;
        let refinement = super::refine::Refinement {
            cycle: &cycle,
            model: &self.model,
            sets: &self.sets,
            integrator: self.integrator.clone(),
            t0: self.setup.window.0,
            enabled: self.refine,
            max_iter: settings.max_iter,
        };
        let build = || {
            self.setup
                .ocp(&cycle, &self.model, &self.sets, self.integrator.clone())
                .map_err(|e| anyhow!(e))
        };
        let mut solve = |tr: &Transcription, w: &[f64]| {
            self.solve_staged(tr, &cycle, w, settings, quiet, |_, res| Ok(res))
        };
        let (sites, res) = refinement.solve(&build, &self.check_sites, &w0, &mut solve, quiet)?;
        let mut ocp = build()?;
        ocp.checks = refinement.checks(&sites);
        let tr = Transcription::new(&ocp).context("transcribing the tracking problem")?;
        self.write_run(
            &tr,
            &cycle,
            res,
            RunWriting {
                base,
                extra,
                folder,
                transient_threshold,
                quiet,
                provenance: None,
                check_sites: &sites,
            },
        )
    }

    /// Write the run folder of the solver result `res` of this problem's transcription
    /// `tr` (solved by `track`, or re-evaluated by `report`).
    pub fn write_run(
        &self,
        tr: &Transcription,
        cycle: &GaitCycle,
        res: footfall::sqp::SqpResult,
        how: RunWriting,
    ) -> anyhow::Result<TrackedRun> {
        let TrackingProblem {
            model,
            sets,
            data,
            setup,
            phases,
            integrator,
            ..
        } = self;
        let RunWriting {
            base,
            extra,
            folder,
            transient_threshold,
            quiet,
            provenance,
            check_sites,
        } = how;
        let solution = GaitSolution::from_nlp(tr, &res.w, &cycle.continuous, setup.window.0);
        let converged = res.status == SqpStatus::Converged;
        let data_rows = setup.data_rows(model, sets, &cycle.continuous);
        let sd = if model.ntheta() > 0 && converged {
            parameter_sd(tr, &res.w, data_rows).unwrap_or_else(|e| {
                eprintln!("warning: no parameter uncertainty: {e}");
                vec![None; model.ntheta()]
            })
        } else {
            vec![None; model.ntheta()]
        };
        let record = self.record(base, extra, &solution.theta, &sd, check_sites);
        let mut extra_json = serde_json::Map::new();
        extra_json.insert("setup".into(), serde_json::to_value(&record)?);
        extra_json.insert("data_residuals".into(), data_rows.into());
        extra_json.insert(
            "integration".into(),
            serde_json::to_value(self.integration.get())?,
        );
        let mut extra_sections = Vec::new();
        let mut extra_summary = Vec::new();
        if let Some(p) = &provenance {
            extra_summary.push(("report".into(), p.clone()));
        }
        let breakdown =
            match setup.cost_breakdown(model, sets, &cycle.continuous, &solution, integrator) {
                Ok(b) => {
                    extra_json.insert("cost_breakdown".into(), serde_json::to_value(&b)?);
                    extra_sections.push(where_it_fails(&b, &solution));
                    Some(b)
                }
                Err(e) => {
                    eprintln!("warning: no cost breakdown: {e}");
                    None
                }
            };
        let residuals = residual_report(model, &solution);
        if let Some((section, stats)) = &residuals {
            extra_sections.push(section.clone());
            extra_json.insert("residual_actuators".into(), stats.clone());
        }
        if !record.parameters.is_empty() {
            extra_sections.push(footfall::report::html::Section {
                heading: "Effects".into(),
                paragraphs: vec!["Effect parameters of the model; identified ones with an approximate standard deviation from the Gauss–Newton Hessian reduced to the constraints, s² = J/(N − p).".into()],
                tables: vec![parameter_table(&record.parameters)],
                svgs: vec![],
            });
        }
        let out = super::gait_run::write(
            GaitRun {
                command: "track",
                title: format!(
                    "footfall tracking — {} foot, {}",
                    model.foot_name, data.name
                ),
                data,
                model,
                sets,
                phases_path: phases,
                events: &self.setup.events,
                sequence: &self.setup.seq,
                control_bounds: (&self.setup.guess.u_lb, &self.setup.guess.u_ub),
                result: &res,
                solution: &solution,
                integrator: integrator.clone(),
                extra_summary,
                extra_json,
                extra_sections,
                extra_files: vec![(
                    "setup.json".into(),
                    serde_json::to_string_pretty(&record)?.into_bytes(),
                )],
                transient_threshold_n: transient_threshold,
                friction: cycle.friction(),
                check_points: check_sites.len(),
                },
            folder,
        )?;
        if !quiet {
            if !record.parameters.is_empty() {
                eprintln!("{}", parameter_table(&record.parameters).to_markdown());
            }
            eprintln!(
                "{}\n{}: J = {:.6}, KKT {:.2e}, {} iterations, {:.1} s",
                out.table.to_markdown(),
                res.status,
                res.objective,
                res.kkt,
                res.history.len().saturating_sub(1),
                res.seconds
            );
            if let Some(f) = &out.fine {
                eprintln!(
                    "1 ms re-integration: peak normal force {:.1} N (right), {:.1} N (left); largest Baumgarte force {:.1e} N; largest drift {:.2e} m",
                    f.peak_normal_force_n[0], f.peak_normal_force_n[1], f.max_baumgarte_force_n, f.max_position_drift_m
                );
            }
            eprintln!("report: {}", out.path.join("report.html").display());
        }
        Ok(TrackedRun {
            converged,
            result: res,
            output: out,
            record,
            breakdown,
            residuals: residuals.map(|r| r.0),
        })
    }
}

/// How [`TrackingProblem::write_run`] writes a run.
pub struct RunWriting<'a> {
    /// The run without `extra` effects.
    pub base: &'a TrackingRunSetup,
    /// Effects added to `base`.
    pub extra: &'a [EffectSpec],
    /// Where to write.
    pub folder: RunFolder,
    /// Report ground-force excursions above the measurement larger than this (N).
    pub transient_threshold: f64,
    /// Print nothing.
    pub quiet: bool,
    /// Where the figures come from, when not from a solve just made.
    pub provenance: Option<String>,
    /// The problem's check points (recorded in `setup.json`).
    pub check_sites: &'a [(usize, usize, f64)],
}

/// The report section on where the model fails: normalised error and cost share per
/// channel and phase, the node cost over time with the phases shaded and the worst
/// stretches.
pub fn where_it_fails(
    b: &footfall::problems::track::CostBreakdown,
    solution: &GaitSolution,
) -> footfall::report::html::Section {
    use footfall::report::plot::{LinePlot, LineStyle, Series, Span};
    let (share, normalised, windows) = cost_tables(b);
    let mut plot = LinePlot::new(
        "Data cost per shooting node",
        "time (s)",
        "Σ weighted residual²",
    );
    plot.series.push(Series::new(
        "data cost",
        b.nodes.iter().map(|n| n.time).collect(),
        b.nodes.iter().map(|n| n.data).collect(),
        LineStyle::Solid,
    ));
    plot.shaded = solution
        .phase_spans()
        .iter()
        .map(|p| Span::new(p.t0, p.t1, p.name.clone()))
        .collect();
    footfall::report::html::Section {
        heading: "Where the model fails".into(),
        paragraphs: vec![format!(
            "The tracking cost J = {:.6} (weighted squared residuals at the nodes, seed eq. 18) by channel and phase: its share, and the normalised error (RMS of the weighted residual: the error in units of the channel's weighting scale). Below, the data cost of every node over time (phases shaded) and the stretches of five nodes where it is largest.",
            b.total()
        )],
        tables: vec![share, normalised, windows],
        svgs: vec![plot.to_svg()],
    }
}

/// A solved and written tracking run.
pub struct TrackedRun {
    /// Whether the solver converged.
    pub converged: bool,
    /// The solver's result.
    pub result: footfall::sqp::SqpResult,
    /// What the run folder holds.
    pub output: super::gait_run::GaitRunOutput,
    /// The run's description.
    pub record: TrackingRunSetup,
    /// Where the cost comes from (None when it could not be evaluated).
    pub breakdown: Option<footfall::problems::track::CostBreakdown>,
    /// The residual actuators' section, for a model that has them.
    pub residuals: Option<footfall::report::html::Section>,
}
