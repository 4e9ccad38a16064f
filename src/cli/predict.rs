//! `footfall predict`: arguments and printing of the prediction workflow
//! ([`footfall::workflows::predict`]).

use super::{CliProgress, Failure};
use footfall::problems::predict::SEED_IMPULSE_WEIGHT;
use footfall::workflows::predict::{outcome_text, predict, PredictionOptions};
use footfall::workflows::run_folder::DEFAULT_TRANSIENT_THRESHOLD_N;
use footfall::workflows::{read_solution, Progress};
use std::path::PathBuf;

/// Options shared by `predict` and `compare`.
#[derive(Debug, Clone, clap::Args)]
pub struct PredictOptions {
    #[command(flatten)]
    pub check_points: super::CheckPointArgs,
    /// Model file. Read from the current folder; footfall's own `models/…`, `phases/…`
    /// files are found wherever it is started.
    #[arg(long, default_value = "models/opensim_subject01.json")]
    pub model: PathBuf,
    #[command(flatten)]
    pub trial: super::TrialArgs,
    /// Step length (m, > 0 and ≤ 2.5; default: the subject's over the tracked half cycle).
    #[arg(long)]
    pub step_length: Option<f64>,
    /// Average forward speed (m/s, > 0 and ≤ 12; default: the subject's).
    #[arg(long)]
    pub speed: Option<f64>,
    /// Impulse weight w_Δ of Millard & Mombaur (2019), eq. 21.
    #[arg(long, default_value_t = SEED_IMPULSE_WEIGHT, value_parser = super::validate::non_negative)]
    pub impulse_weight: f64,
    /// Bound on |ankle angular velocity| (rad/s), replacing the data's range ± 1 rad/s
    /// (Millard & Mombaur's (2019) predictions: 14.6; their control experiment: 3.96).
    #[arg(long, value_parser = super::validate::positive)]
    pub ankle_velocity_limit: Option<f64>,
    /// Hessian: exact (default) or an approximation.
    #[arg(long, value_enum, default_value = "exact")]
    pub hessian: super::HessianArg,
    /// KKT tolerance (at most 0.01).
    #[arg(long, default_value_t = 1e-5, value_parser = super::validate::kkt_tolerance)]
    pub tol: f64,
    /// Relative and absolute CVODES tolerance of the shooting intervals.
    #[arg(long, default_value_t = 1e-8, value_parser = super::validate::positive)]
    pub integrator_tol: f64,
    /// With `--hessian exact`: Gauss–Newton steps until the constraint violation is below
    /// this (default: exact from the first iteration; the prediction's Gauss–Newton matrix
    /// has no curvature in positions, velocities and excitations).
    #[arg(long, default_value_t = f64::INFINITY, value_parser = super::validate::threshold)]
    pub exact_below: f64,
    /// Largest violation a line search accepts, as a multiple of the violation where the
    /// solve starts (l1 norms, at least 1): a step that lowers the effort but leaves the
    /// linearised constraints far behind is shortened instead (`inf`: the filter's loose
    /// cap of 10⁴, as tracking uses).
    #[arg(long, default_value_t = 10.0, value_parser = super::validate::threshold)]
    pub max_violation_growth: f64,
    /// Iteration limit.
    #[arg(long, default_value_t = 300, value_parser = super::validate::iterations)]
    pub max_iter: usize,
    /// Wall-time limit per solve (s).
    #[arg(long, value_parser = super::validate::positive)]
    pub max_time: Option<f64>,
    /// Report ground-force excursions above the measurement larger than this (N).
    #[arg(long, default_value_t = DEFAULT_TRANSIENT_THRESHOLD_N, value_parser = super::validate::positive)]
    pub transient_threshold: f64,
}

/// Arguments of `footfall predict`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Foot: `ellipse`, `double-circle` or a foot file.
    #[arg(long, default_value = "ellipse")]
    foot: String,
    /// Phase graph (default: Millard & Mombaur's (2019) graph for the bundled feet; for a
    /// foot file whose
    /// primitives are all volumetric, phases/volumetric_ellipse_walk.json).
    #[arg(long)]
    phases: Option<PathBuf>,
    /// Start from this solution: a run folder (its `solution.json`) or a solution file,
    /// e.g. of `footfall track` with the same foot and phases. Default: from the data.
    #[arg(long)]
    init: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "runs/predict")]
    out: PathBuf,
    /// Replace the output folder if it exists.
    #[arg(long)]
    overwrite: bool,
    /// Continue the run a killed process left unfinished in this output folder, or the
    /// interrupted run it holds, from its last SQP iteration, with the options it was
    /// started with (give no others).
    #[arg(long, value_name = "DIR")]
    pub resume: Option<PathBuf>,
    #[command(flatten)]
    options: PredictOptions,
}

impl From<&PredictOptions> for PredictionOptions {
    fn from(o: &PredictOptions) -> Self {
        PredictionOptions {
            check_points: o.check_points.enabled(),
            model: o.model.clone(),
            trial: o.trial.clone().into(),
            step_length: o.step_length,
            speed: o.speed,
            impulse_weight: o.impulse_weight,
            ankle_velocity_limit: o.ankle_velocity_limit,
            hessian: o.hessian.into(),
            tol: o.tol,
            integrator_tol: o.integrator_tol,
            exact_below: o.exact_below,
            violation_growth: o
                .max_violation_growth
                .is_finite()
                .then_some(o.max_violation_growth),
            max_iter: o.max_iter,
            max_time: o.max_time,
            transient_threshold: o.transient_threshold,
        }
    }
}

pub fn run(args: Args, progress: &CliProgress) -> Result<(), Failure> {
    run_inner(args, progress).map_err(Failure::classify)
}

fn run_inner(args: Args, progress: &CliProgress) -> anyhow::Result<()> {
    let folder =
        footfall::workflows::session::create_checkpointed_run_folder(&args.out, args.overwrite)?;
    let init = args.init.as_deref().map(read_solution).transpose()?;
    let (out, res) = predict(
        &(&args.options).into(),
        &args.foot,
        args.phases.as_deref(),
        init.as_ref(),
        folder,
        progress,
    )?;
    progress.note(&outcome_text(&out, &res));
    footfall::workflows::check_run(&out, &res)
}
