//! The prediction workflow: the gait the model prefers (Millard & Mombaur 2019, §3.5):
//! minimum activation plus impulses, at the subject's step length and speed, started from a tracking solution.

use super::run_folder::{GaitRun, GaitRunOutput, DEFAULT_TRANSIENT_THRESHOLD_N};
#[allow(unused_imports)]
use super::{note, warn_note, Progress};
use crate::integrate::IntegratorSettings;
use crate::model::GaitModel;
use crate::ocp::Transcription;
use crate::phases::PhaseSequence;
use crate::problems::evaluation::GaitSolution;
use crate::problems::gait::GaitCycle;
use crate::problems::predict::{PredictionSettings, PredictionSetup, SEED_IMPULSE_WEIGHT};
use crate::problems::track::TrackingSetup;
use crate::report::html::Section;
use crate::runfolder::RunFolder;
use crate::sqp::{ExactConvexification, HessianMode, SqpResult, SqpSettings, SqpStatus};
use anyhow::{anyhow, Context};
use std::path::{Path, PathBuf};

/// The prediction's default cap on the violation a line search accepts, as a multiple of
/// the violation where the solve starts ([`SqpSettings::violation_growth`]). A prediction
/// usually starts from a tracking solution, near feasibility, where the effort can fall
/// a long way along steps the linearised constraints do not describe.
pub const PREDICTION_VIOLATION_GROWTH: f64 = 10.0;

/// How to predict: the model, data, targets and solver settings of a prediction (the
/// `predict` and `compare` commands fill it from their arguments).
#[derive(Debug, Clone)]
pub struct PredictionOptions {
    /// Add check points where the 1 ms re-integration breaks a contact constraint, and
    /// solve again.
    pub check_points: bool,
    /// Model file.
    pub model: PathBuf,
    /// The trial (default: the bundled one).
    pub trial: super::trial::TrialFiles,
    /// Step length (m; None: the subject's).
    pub step_length: Option<f64>,
    /// Average forward speed (m/s; None: the subject's).
    pub speed: Option<f64>,
    /// Impulse weight w_Δ of eq. 21.
    pub impulse_weight: f64,
    /// Bound on |ankle angular velocity| (rad/s; None: the data's range ± 1 rad/s).
    pub ankle_velocity_limit: Option<f64>,
    /// Hessian of the SQP.
    pub hessian: HessianMode,
    /// KKT tolerance.
    pub tol: f64,
    /// Relative and absolute CVODES tolerance.
    pub integrator_tol: f64,
    /// With the exact Hessian: Gauss–Newton steps until the violation is below this.
    pub exact_below: f64,
    /// Cap on the violation a line search accepts, as a multiple of the start's
    /// ([`SqpSettings::violation_growth`]; default 10).
    pub violation_growth: Option<f64>,
    /// Iteration limit.
    pub max_iter: usize,
    /// Wall-time limit per solve (s).
    pub max_time: Option<f64>,
    /// Report ground-force excursions above the measurement larger than this (N).
    pub transient_threshold: f64,
}

impl PredictionOptions {
    /// The stopping rules within the ranges of [`crate::limits`] (the KKT tolerance, the
    /// iteration and time limits), as [`SqpSettings::check_limits`].
    pub fn check_limits(&self) -> Result<(), crate::limits::OutOfRange> {
        SqpSettings {
            tol_kkt: self.tol,
            max_iter: self.max_iter,
            max_time: self.max_time,
            ..Default::default()
        }
        .check_limits()
    }
}

impl Default for PredictionOptions {
    /// The `predict` command's defaults.
    fn default() -> Self {
        Self {
            check_points: true,
            model: PathBuf::from("models/opensim_subject01.json"),
            trial: super::trial::TrialFiles::default(),
            step_length: None,
            speed: None,
            impulse_weight: SEED_IMPULSE_WEIGHT,
            ankle_velocity_limit: None,
            hessian: HessianMode::Exact,
            tol: 1e-5,
            integrator_tol: 1e-8,
            exact_below: f64::INFINITY,
            violation_growth: Some(PREDICTION_VIOLATION_GROWTH),
            max_iter: 300,
            max_time: None,
            transient_threshold: DEFAULT_TRANSIENT_THRESHOLD_N,
        }
    }
}

/// The outcome lines of a written gait run: its error table, the solver's stop, the
/// largest ground-force transient and where the report is.
pub fn outcome_text(out: &GaitRunOutput, res: &SqpResult) -> String {
    let mut text = out.solve_summary(res) + "\n";
    text += &match out.transients.first() {
        Some(t) => format!(
            "largest ground-force transient: {} {} force {:.1} N at {:.3} s ({}), {:.1} N above the measurement for {:.1} ms",
            t.foot, t.component, t.peak_n, t.t_peak, t.phase, t.excess_n, 1e3 * t.duration_s
        ),
        None => "no ground-force transient above the threshold on the 1 ms grid".to_string(),
    };
    text += &format!("\nreport: {}", out.path.join("report.html").display());
    text
}

/// A prediction's problem: the model with its phases, the measurement, and the targets
/// and start the prediction is set up with.
struct Problem {
    /// The model and foot.
    model: GaitModel,
    /// The phase file.
    phases: PathBuf,
    /// Contact set of every phase of the phase file.
    sets: Vec<crate::model::ConstraintSet>,
    /// The measurement.
    data: crate::data::GaitData,
    /// The tracking problem of the measurement (its window, events and targets).
    tracking: TrackingSetup,
    /// Targets and weights.
    settings: PredictionSettings,
    /// The phase sequence, guess and bounds.
    setup: PredictionSetup,
}

impl Problem {
    /// Read the model, phases and trial of a prediction with `foot`, and set it up from
    /// `init` (else from the data).
    fn load(
        o: &PredictionOptions,
        foot: &str,
        phases: Option<&Path>,
        init: Option<&GaitSolution>,
        progress: &dyn Progress,
    ) -> anyhow::Result<Self> {
        let foot_path = super::foot_path(foot);
        let model = GaitModel::load(&o.model, &foot_path)?;
        let phases = phases
            .map(Path::to_path_buf)
            .unwrap_or_else(|| super::default_phases(foot));
        let seq = PhaseSequence::load(&phases)?;
        let sets = seq.resolve(&model, &phases)?;
        let trial = super::trial::load_trial(&o.trial)?;
        for n in &trial.notes {
            progress.note(n);
        }
        let data = trial.data;
        let tracking = TrackingSetup::new(&model, &seq, &sets, &data)
            .map_err(|e| anyhow!("{}: {e}", data.source.display()))?;
        let mut settings = PredictionSettings::from_data(&tracking, &data);
        settings.set_targets(o.step_length, o.speed)?;
        settings.impulse_weight = o.impulse_weight;
        settings.ankle_velocity_limit = o.ankle_velocity_limit;
        let setup = match init {
            Some(sol) => PredictionSetup::from_solution(&seq, &tracking, sol, settings.clone()),
            None => PredictionSetup::from_data(&seq, &tracking, settings.clone()),
        }
        .map_err(|e| anyhow!("{}: {e}", phases.display()))?;
        Ok(Problem {
            model,
            phases,
            sets,
            data,
            tracking,
            settings,
            setup,
        })
    }
}

/// Solve one prediction and write its run folder.
pub fn predict(
    o: &PredictionOptions,
    foot: &str,
    phases: Option<&Path>,
    init: Option<&GaitSolution>,
    folder: RunFolder,
    progress: &dyn Progress,
) -> anyhow::Result<(GaitRunOutput, SqpResult)> {
    o.check_limits()?;
    let p = Problem::load(o, foot, phases, init, progress)?;
    let (model, sets, settings) = (&p.model, &p.sets, &p.settings);
    let cycle = GaitCycle::new(model, &p.setup.seq, sets).map_err(|e| anyhow!(e))?;
    let integrator = IntegratorSettings {
        rtol: o.integrator_tol,
        atol: o.integrator_tol,
        ..Default::default()
    };
    integrator.validate().context("--integrator-tol")?;
    let build = || {
        p.setup
            .ocp(&cycle, model, sets, integrator.clone())
            .map_err(|e| anyhow!(e))
    };
    let ocp = build()?;
    let tr = Transcription::new(&ocp).context("transcribing the prediction problem")?;
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let hessian = o.hessian;
    let sqp_settings = SqpSettings {
        tol_kkt: o.tol,
        max_iter: o.max_iter,
        max_time: o.max_time,
        hessian,
        exact_hessian_below: o.exact_below,
        violation_growth: o.violation_growth,
        exact_convexification: ExactConvexification::InertiaCorrection,
        ..Default::default()
    };
    {
        note!(progress,
            "predicting with the {} foot: step length {:.3} m, speed {:.3} m/s, w_Δ = {}{} ({} variables, {} constraints, {:?}, from {})",
            model.foot_name,
            settings.step_length,
            settings.speed,
            settings.impulse_weight,
            settings.ankle_velocity_limit.map_or(String::new(), |w| format!(", |ankle ω| ≤ {w} rad/s")),
            tr.n(),
            tr.m(),
            hessian,
            if init.is_some() { "the given solution" } else { "the data" }
        );
    }
    let refinement = super::refine::Refinement {
        cycle: &cycle,
        model,
        sets,
        integrator: integrator.clone(),
        t0: p.tracking.window.0,
        enabled: o.check_points,
        max_iter: sqp_settings.max_iter,
        tol_kkt: sqp_settings.tol_kkt,
    };
    let (sites, res) = refinement.solve(
        &build,
        &[],
        &w0,
        &mut |tr, round| solve_staged(tr, round, &sqp_settings, progress),
        progress,
    )?;
    let mut ocp = build()?;
    ocp.checks = cycle.checks_at(&sites);
    let tr = Transcription::new(&ocp).context("transcribing the prediction problem")?;
    let solution = GaitSolution::from_nlp(&tr, &res.w, &cycle.continuous, p.tracking.window.0);
    let solved = Solved {
        result: &res,
        solution: &solution,
        integrator,
        friction: cycle.friction(),
        check_points: sites.len(),
        from_solution: init.is_some(),
    };
    let out = write_run(o, foot, &p, solved, folder)?;
    Ok((out, res))
}

/// One round of a prediction's solve ([`super::refine::Round`]). A failed line search of
/// the exact Hessian goes on once from that iterate
/// with block BFGS. Near a stationary point the inertia correction can shift the QP's
/// Hessian by far more than its curvature, and the QP's step and multipliers with it:
/// the CI's double-circle prediction stalled at KKT 3.7e-3 with steps of 1e-5, its
/// integrator at 1e-10 or 1e-12, where block BFGS certifies the same point at KKT 2.4e-7
/// at once.
fn solve_staged(
    tr: &Transcription,
    round: super::refine::Round<'_>,
    sqp_settings: &SqpSettings,
    progress: &dyn Progress,
) -> anyhow::Result<SqpResult> {
    let sqp_settings = round.settings(sqp_settings);
    let judge = round.judge;
    let first = super::solve_interruptibly_warm(
        tr,
        round.w0,
        None,
        &sqp_settings,
        progress,
        Some(&mut *judge),
    )?;
    if first.status != SqpStatus::LineSearchFailure || sqp_settings.hessian != HessianMode::Exact {
        return Ok(first);
    }
    {
        note!(progress,
            "line search failed at KKT {:.2e} with the exact Hessian: going on from there with block BFGS",
            first.kkt
        );
    }
    let used = first.history.len().saturating_sub(1);
    let rest = SqpSettings {
        max_iter: sqp_settings.max_iter.saturating_sub(used),
        max_time: sqp_settings.max_time.map(|t| (t - first.seconds).max(0.0)),
        hessian: HessianMode::Bfgs,
        ..sqp_settings.clone()
    };
    let second = super::solve_interruptibly_warm(tr, &first.w, None, &rest, progress, Some(judge))?;
    Ok(first.followed_by(second))
}

/// A solved prediction, as its run folder records it.
struct Solved<'a> {
    /// The solver's result.
    result: &'a SqpResult,
    /// The solution read from it.
    solution: &'a GaitSolution,
    /// The shooting intervals' integrator.
    integrator: IntegratorSettings,
    /// Friction coefficient of the contacts' cone.
    friction: f64,
    /// Number of check points holding the contact constraints between the nodes.
    check_points: usize,
    /// Whether the prediction started from a given solution (else from the data).
    from_solution: bool,
}

/// Write the run folder of the prediction `p` with `foot`, solved as `solved`.
fn write_run(
    o: &PredictionOptions,
    foot: &str,
    p: &Problem,
    solved: Solved,
    folder: RunFolder,
) -> anyhow::Result<GaitRunOutput> {
    let (model, settings, solution) = (&p.model, &p.settings, solved.solution);
    let durations: Vec<String> = solution
        .phases
        .iter()
        .map(|p| format!("{} {:.3} s", p.name, p.duration))
        .collect();
    let mut extra_json = serde_json::Map::new();
    extra_json.insert("prediction".into(), serde_json::to_value(settings)?);
    extra_json.insert(
        "durations_s".into(),
        solution
            .phases
            .iter()
            .map(|p| serde_json::json!({"phase": p.name, "duration": p.duration}))
            .collect(),
    );
    // the run folder holds its inputs (summary.json names the copies)
    let inputs = super::inputs::copy_inputs(
        &folder,
        &o.model,
        foot,
        &p.phases,
        o.trial.data.as_deref(),
        o.trial.forces.as_deref(),
    )?;
    super::run_folder::write(
        GaitRun {
            command: "predict",
            title: format!("footfall prediction — {} foot, {}", model.foot_name, p.data.name),
            data: &p.data,
            model,
            sets: &p.sets,
            phases_path: &p.phases,
            inputs: Some(&inputs),
            events: &p.tracking.events,
            sequence: &p.setup.seq,
            control_bounds: (&p.setup.guess.u_lb, &p.setup.guess.u_ub),
            result: solved.result,
            solution,
            integrator: solved.integrator,
            extra_summary: vec![
                ("targets".into(), format!("step length {:.3} m, speed {:.3} m/s", settings.step_length, settings.speed)),
                ("phase durations".into(), durations.join(", ")),
            ],
            extra_json,
            extra_sections: vec![Section {
                heading: "Problem".into(),
                paragraphs: vec![format!(
                    "Minimum ∫Σa² dt plus w_Δ ΣΔ² with w_Δ = {} (Millard & Mombaur 2019, eq. 20–21), at step length {:.3} m and average speed {:.3} m/s{}; started from {}. The errors above compare the predicted gait with the measurement in the layout of their Table 4.",
                    settings.impulse_weight,
                    settings.step_length,
                    settings.speed,
                    settings.ankle_velocity_limit.map_or(String::new(), |w| format!(", ankle angular velocity bounded by {w} rad/s")),
                    if solved.from_solution { "the given solution" } else { "the data" }
                )],
                tables: vec![],
                svgs: vec![],
            }],
            extra_files: vec![],
            friction: solved.friction,
            check_points: solved.check_points,
            transient_threshold_n: o.transient_threshold,
        },
        folder,
    )
}
