//! The tracking workflow: track measured walking with the model (Millard & Mombaur 2019,
//! §3.4), solve until valid between the nodes, and write the run folder.

use super::run_folder::GaitRun;
use super::{note, warn_note, Progress};
use crate::data::GaitData;
use crate::integrate::IntegratorSettings;
use crate::model::effects::EffectSpec;
use crate::model::GaitModel;
use crate::ocp::Transcription;
use crate::phases::PhaseSequence;
use crate::problems::diagnose::{parameter_sd, IdentifiedParameter, TrackingRunSetup};
use crate::problems::evaluation::GaitSolution;
use crate::problems::gait::GaitCycle;
use crate::problems::track::start::{self, Guess};
use crate::problems::track::{TrackingSetup, WindowChoice};
use crate::problems::{ProblemError, WindowError};
use crate::runfolder::RunFolder;
use crate::sqp::{ExactConvexification, HessianMode, SqpSettings, SqpStatus, StallSwitch};
use anyhow::{anyhow, Context};
use std::path::PathBuf;

mod write;
pub use write::{RunWriting, TrackedRun};

/// When a tracking solve with the exact Hessian uses it above the usual violation
/// ([`tracking_sqp_settings`]): once five Gauss–Newton iterations below a violation of 0.1
/// have not lowered the best objective by 0.1 %. Gauss–Newton steps can cycle above the
/// usual 1e-3 for good: a volumetric track at violations of 1e-3 to 1e-2, a rigid one
/// between two points for 35 iterations (the real right-clock trial). The exact Hessian
/// from the data's start (violation ~10) runs into a QP failure or a far worse local
/// minimum, so it is not the default from the first step.
pub const STALL_SWITCH: StallSwitch = StallSwitch {
    below: 0.1,
    iterations: 5,
    relative_decrease: 1e-3,
};

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

/// CVODES tolerance of the forward sensitivities of a rigid-foot track without residual
/// actuators (unless `--sensitivity-tol` is given, or the states' tolerance is looser): a
/// tenth of the default KKT tolerance, which is computed from them (a tighter `--tol`
/// tightens them alike, [`TrackingProblem::sensitivities_for_kkt_tol`]). Their error test
/// then rejects fewer steps than at the states' 1e-8: on every shipped recording with
/// either rigid foot the track reaches the same optimum (J to seven digits, KKT below
/// 1e-5) with about two thirds of the integrator's steps. Where a line search still fails
/// near the optimum, the solve goes on with them at the states' tolerance
/// (`TrackingProblem::solve_staged`).
pub const RIGID_SENSITIVITY_TOL: f64 = 1e-6;

/// Force (N) or torque (N·m) of a residual actuator per unit control.
pub const RESIDUAL_SCALE: f64 = 100.0;

/// The parts of a tracking problem that do not borrow each other.
pub struct TrackingProblem {
    /// The model with the run's effects and parameter values.
    pub model: GaitModel,
    /// Contact set of every phase of the phase file.
    pub sets: Vec<crate::model::ConstraintSet>,
    /// The measurement.
    pub data: crate::data::GaitData,
    /// Targets, weights, events and the initial guess.
    pub setup: TrackingSetup,
    /// The phase file.
    pub phases: PathBuf,
    /// The shooting intervals' integrator.
    pub integrator: IntegratorSettings,
    /// Check points the problem has from the start (those of the run it was rebuilt from).
    pub check_sites: super::refine::CheckSites,
    /// Whether a solve adds check points where the solution breaks a contact constraint
    /// between the nodes.
    pub refine: bool,
    /// Integrator counters of every solve of this problem so far (all stages and
    /// refinement rounds), written to `summary.json` as `integration`.
    pub integration: std::cell::Cell<crate::integrate::IntegrationStats>,
    /// What was chosen reading the trial (an OpenSim pair's plates), to tell the user.
    pub trial_notes: Vec<String>,
}

impl TrackingProblem {
    /// Rebuild the problem a run describes, with `extra` effects added (parameters free
    /// at their values) and the run's identified parameter values. The run's values
    /// only start free parameters; a fixed one keeps the value its effect gives (a fixed
    /// parameter does not move, so a run's value of it is its effect's — except for
    /// `extra`: `--effect trunk_mass:added_mass=4,com_offset=0.03,free=` with `--init` of
    /// a run that identified other values holds 4 kg and 0.03 m).
    pub fn build(run: &TrackingRunSetup, extra: &[EffectSpec]) -> anyhow::Result<Self> {
        let foot_path = super::foot_path(&run.foot);
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
                model.set_parameter_value(&p.name, p.value)?;
            }
        }
        let seq = PhaseSequence::load(&run.phases)?;
        let sets = seq.resolve(&model, &run.phases)?;
        let trial = super::trial::load_trial(&run.into())?;
        let mut trial_notes = trial.notes;
        let mut data = trial.data;
        trial_notes.extend(forces_fit_the_body(&data, &model)?);
        if run.mirror {
            data.swap_sides();
        }
        let sides = run.target_sides();
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
        let choice = match (run.window, run.stride) {
            (Some(_), Some(_)) => {
                return Err(anyhow!(
                    "--window and --stride both choose the half cycle; give one"
                ))
            }
            (Some((a, b)), None) => WindowChoice::Within(a, b),
            (None, Some(n)) => WindowChoice::Stride(n),
            (None, None) => WindowChoice::First,
        };
        let mut setup = TrackingSetup::for_window(&model, &seq, &sets, &data, sides, choice)
            .map_err(|e| {
                // the data layer's errors name the file already
                let source = data.source.display().to_string();
                let choose = matches!(
                    e,
                    ProblemError::Window(WindowError::NoMeasuredHalfCycle { .. })
                );
                if choose {
                    anyhow!("{source}: {e} (--window T0,T1 or --stride N)")
                } else if e.to_string().starts_with(&format!("{source}: ")) {
                    anyhow!(e)
                } else {
                    anyhow!("{source}: {e}")
                }
            })?;
        if run.guess == Guess::InverseDynamics {
            let r =
                start::from_inverse_dynamics(&model, &data, &setup.node_times, &mut setup.guess)
                    .map_err(|e| {
                        anyhow!(
                            "{}: the start from the inverse dynamics: {e}",
                            data.source.display()
                        )
                    })?;
            trial_notes.push(format!(
                "start: the actuators' activations and excitations (or joint torques) from the inverse dynamics at {} of {} nodes ({} joint torques beyond the actuators' strength, held at it)",
                r.set, r.nodes, r.saturated
            ));
        }
        if run.track_pelvis_position {
            setup.weights = setup.weights.clone().with_pelvis_position();
        }
        if let Some(noise) = &run.noise_weights {
            setup.weights = setup.weights.clone().with_noise_weights(noise);
        }
        if let Some(w) = run.regularisation {
            if !(w.is_finite() && w >= 0.0) {
                return Err(anyhow!(
                    "--regularisation {w}: expected a finite weight ≥ 0 (Millard & Mombaur 2019 use 1e-3)"
                ));
            }
            setup.weights.excitation = w;
            setup.weights.activation = w;
        }
        if let Some(v) = run.velocity_weight {
            if !(v.is_finite() && v >= 0.0) {
                return Err(anyhow!("--velocity-weight {v}: expected a finite weight ≥ 0 relative to the angles' (Millard & Mombaur 2019 use 0.1)"));
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
        } else if stiff {
            run.integrator_tol
        } else {
            RIGID_SENSITIVITY_TOL.max(tol)
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
            trial_notes,
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

/// Violation below which a tracking solve with `HessianMode::Exact` always uses the exact
/// Hessian (`track`'s default; `--exact-below` replaces it).
pub const EXACT_BELOW: f64 = 1e-3;

/// The tracking solver's settings (as `track`'s defaults). With `HessianMode::Exact` and
/// `exact_below` `None`, the exact Hessian below a violation of [`EXACT_BELOW`], or below
/// 0.1 once the Gauss–Newton steps have stalled ([`STALL_SWITCH`]); with `Some(v)`, below
/// `v` alone (a fixed switch, as `--exact-below v`).
pub fn tracking_sqp_settings(
    tol: f64,
    max_iter: usize,
    max_time: Option<f64>,
    hessian: HessianMode,
    exact_below: Option<f64>,
) -> SqpSettings {
    SqpSettings {
        tol_kkt: tol,
        max_iter,
        max_time,
        hessian,
        exact_hessian_below: exact_below.unwrap_or(EXACT_BELOW),
        exact_convexification: ExactConvexification::InertiaCorrectionThenGaussNewton,
        exact_hessian_on_stall: (hessian == HessianMode::Exact && exact_below.is_none())
            .then_some(STALL_SWITCH),
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
            self.model.set_parameter_value(name, v)?;
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
        ocp.checks = cycle.checks_at(&self.check_sites);
        let tr = Transcription::new(&ocp).context("transcribing the tracking problem")?;
        let (_, _, w0) = tr.variable_bounds_and_guess();
        f(&tr, &cycle, w0)
    }

    /// Solve the problem (interruptibly, with `progress`) and read its
    /// solution.
    pub fn solve(
        &self,
        settings: &SqpSettings,
        progress: &dyn Progress,
    ) -> anyhow::Result<(crate::sqp::SqpResult, GaitSolution)> {
        self.with_transcription(|tr, cycle, w0| {
            self.solve_staged(tr, cycle, &w0, settings, progress, None, |tr, res| {
                let mut sol =
                    GaitSolution::from_nlp(tr, &res.w, &cycle.continuous, self.setup.window.0);
                self.setup.place(&self.model, &mut sol);
                Ok((res, sol))
            })
        })
    }

    /// Solve on `tr` from `w0` (asking `judge` at the milestone, if any) and hand the
    /// result, with the transcription it was last iterated on, to `finish`. When the line search
    /// fails, the solve goes on once from that iterate and its multipliers with more
    /// precise integration, because near an optimum the integrator's error is what stops
    /// it:
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
        progress: &dyn Progress,
        mut judge: Option<super::Judge<'_>>,
        finish: impl FnOnce(&Transcription, crate::sqp::SqpResult) -> anyhow::Result<R>,
    ) -> anyhow::Result<R> {
        let first =
            super::solve_interruptibly_warm(tr, w0, None, settings, progress, reborrow(&mut judge));
        self.count_integration(tr);
        let first = first?;
        if first.status != crate::sqp::SqpStatus::LineSearchFailure {
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
        {
            note!(
                progress,
                "line search failed at KKT {:.2e} with {what}",
                first.kkt
            );
        }
        let mut ocp = self
            .setup
            .ocp(cycle, &self.model, &self.sets, tight)
            .map_err(|e| anyhow!(e))?;
        // the check points of the problem being solved: a refinement round's, not only
        // those the problem started with
        ocp.checks = tr.ocp().checks.clone();
        let tr2 = Transcription::new(&ocp).context("transcribing the tracking problem")?;
        let rest = SqpSettings {
            max_iter: settings.max_iter.saturating_sub(used),
            max_time: settings.max_time.map(|t| (t - first.seconds).max(0.0)),
            ..settings.clone()
        };
        // from the first stage's multipliers: the same problem, integrated more precisely,
        // keeps its constraints' curvature and the bounds it held
        let warm = crate::sqp::WarmStart {
            lambda: &first.lambda,
            nu: &first.nu,
        };
        let second =
            super::solve_interruptibly_warm(&tr2, &first.w, Some(warm), &rest, progress, judge);
        self.count_integration(&tr2);
        finish(&tr2, first.followed_by(second?))
    }

    /// Integrate the sensitivities at a tenth of the KKT tolerance `tol_kkt` where the
    /// default left them looser ([`RIGID_SENSITIVITY_TOL`] is a tenth of the default
    /// 1e-5): the KKT residual is computed from them. Never tighter than the states.
    pub fn sensitivities_for_kkt_tol(&mut self, tol_kkt: f64) {
        let Some(sens) = self.integrator.sens_tol else {
            return;
        };
        let held = self.integrator.clone().sensitivities_for_kkt_tol(tol_kkt);
        if held.sens_tol.unwrap_or(held.rtol) < sens {
            self.integrator = held;
        }
    }

    /// Add the integrator counters of `tr`'s evaluations to this problem's.
    fn count_integration(&self, tr: &Transcription) {
        let mut total = self.integration.get();
        total += tr.integration_totals();
        self.integration.set(total);
    }
}

/// The judge `judge` holds, for one solve of several.
fn reborrow<'s>(judge: &'s mut Option<super::Judge<'_>>) -> Option<super::Judge<'s>> {
    match judge {
        Some(j) => Some(&mut **j),
        None => None,
    }
}

/// The measurement check's gate ([`crate::problems::check::gate`]): a trial whose forces
/// cannot belong to the model's body (the mass they imply more than 25 % off, the
/// horizontal force against the body's acceleration), or whose loaded feet the model
/// posed by its coordinates does not stand on the floor, is refused before the solve;
/// one more than 10 % off, or with an ankle height near the limits, is tracked with a
/// note. A trial whose balance cannot be read (a
/// foot never loaded, too short) is not judged here.
fn forces_fit_the_body(data: &GaitData, model: &GaitModel) -> anyhow::Result<Vec<String>> {
    use crate::problems::check::{gate, CheckError, CheckSettings};
    match gate(data, model, &CheckSettings::default()) {
        Ok(warnings) => Ok(warnings
            .into_iter()
            .map(|w| format!("{}: {w}", data.source.display()))
            .collect()),
        Err(CheckError::Implausible(why)) => Err(anyhow!(why)),
        Err(_) => Ok(Vec::new()),
    }
}

/// The tightest integrator tolerance a failed line search moves a tracking solve to.
const TIGHTEST_TOL: f64 = 1e-12;

pub use super::inputs::read_run_setup;

/// What the tracking workflow solves: the run's description, the effects added to it,
/// where it starts and how it is solved.
#[derive(Debug, Clone)]
pub struct TrackRequest {
    /// Model, foot, phases, data and the problem's options (its `parameters` and
    /// `check_points` come from `init`'s run, when it has a `setup.json`).
    pub run: TrackingRunSetup,
    /// Effects added to the model, their free parameters identified.
    pub effects: Vec<EffectSpec>,
    /// Start from this solution (a run folder or a `solution.json`; None: the data).
    pub init: Option<PathBuf>,
    /// Add check points where the 1 ms re-integration breaks a contact constraint, and
    /// solve again.
    pub check_points: bool,
    /// The solver's settings ([`tracking_sqp_settings`]).
    pub sqp: SqpSettings,
    /// Report ground-force excursions above the measurement larger than this (N).
    pub transient_threshold: f64,
}

impl TrackRequest {
    /// The `track` command's defaults for `foot` (`ellipse`, `double-circle` or a foot
    /// file) on the bundled trial: the repository's paths, read from the compiled-in
    /// copies where the current folder lacks them ([`crate::bundled`]).
    pub fn new(foot: &str) -> Self {
        TrackRequest {
            run: TrackingRunSetup {
                model: PathBuf::from("models/opensim_subject01.json"),
                foot: foot.to_string(),
                phases: super::default_phases(foot),
                data: None,
                overground: false,
                forces: None,
                plates: vec![],
                lab_axes: None,
                belt_speed: None,
                kinematics_cutoff: None,
                integrator_tol: 1e-8,
                sensitivity_tol: None,
                residual_actuators: false,
                track_pelvis_position: false,
                regularisation: None,
                one_sided_targets: false,
                sample_targets: false,
                window: None,
                stride: None,
                mirror: false,
                noise_weights: None,
                velocity_weight: None,
                guess: Default::default(),
                check_points: vec![],
                effects: vec![],
                parameters: vec![],
            },
            effects: vec![],
            init: None,
            check_points: true,
            sqp: tracking_sqp_settings(1e-5, 200, None, HessianMode::Exact, None),
            transient_threshold: super::run_folder::DEFAULT_TRANSIENT_THRESHOLD_N,
        }
    }
}

/// Track: build the problem `req` describes, solve it (with check points until valid
/// between the nodes, if asked) and write its run folder into `folder`. A solve that
/// does not converge or stays physically invalid is still written; [`check_run`](super::check_run)
/// turns it into an error.
pub fn track(
    req: &TrackRequest,
    folder: RunFolder,
    progress: &dyn Progress,
) -> anyhow::Result<TrackedRun> {
    req.sqp.check_limits()?;
    let mut base = req.run.clone();
    let init = match &req.init {
        Some(p) => {
            let sol = super::read_solution(p)?;
            if p.is_dir() && p.join("setup.json").exists() {
                let from = read_run_setup(p)?;
                base.parameters = from.parameters;
                base.check_points = from.check_points;
            }
            Some(sol)
        }
        None => None,
    };
    let mut prob = TrackingProblem::build(&base, &req.effects)?;
    for n in &prob.setup.notes {
        if n.starts_with("warning: ") {
            progress.warn(n)
        } else {
            progress.note(n)
        }
    }
    prob.refine = req.check_points;
    // from the data, a refined solve starts with the impact sites; a kept run's solution
    // keeps the sites that run was checked with on the 1 ms grid
    if prob.refine && req.init.is_none() && prob.check_sites.is_empty() {
        prob.check_sites = prob.setup.seq.impact_sites();
    }
    for n in &prob.trial_notes {
        progress.note(n);
    }
    base.check_points.clear();
    if base.sensitivity_tol.is_none() {
        prob.sensitivities_for_kkt_tol(req.sqp.tol_kkt);
    }
    if prob.integrator.rtol < base.integrator_tol {
        let why = if base.residual_actuators {
            "residual actuators"
        } else {
            "the heel pad's stiff dynamics"
        };
        progress.note(&format!("{why}: integrator tolerance of the states {:e} → {:e} (integration noise stalls the line search at 1e-8), of the sensitivities {:e}", base.integrator_tol, prob.integrator.rtol, prob.integrator.sens_tol.unwrap_or(prob.integrator.rtol)));
    }
    if let (Some(sol), Some(p)) = (&init, &req.init) {
        prob.setup
            .start_from(sol)
            .map_err(|e| anyhow!("--init {}: {e}", p.display()))?;
    }
    base.parameters.clear();
    prob.solve_and_write(
        &base,
        &req.effects,
        &req.sqp,
        folder,
        req.transient_threshold,
        progress,
    )
}
