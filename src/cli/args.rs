//! Arguments and printing shared by several subcommands.

use footfall::workflows::{Stream, TextProgress};
use std::path::PathBuf;

/// The model and foot shared by `simulate`, `fit-foot` and `track`.
#[derive(Debug, Clone, clap::Args)]
pub struct ModelArgs {
    /// Model file (JSON). Read from the current folder; footfall's own `models/…`,
    /// `phases/…` files are found wherever it is started.
    #[arg(long, default_value = "models/opensim_subject01.json")]
    pub model: PathBuf,
    /// Foot: `ellipse`, `double-circle` or a foot file (JSON).
    #[arg(long, default_value = "ellipse")]
    pub foot: String,
}

/// The measured trial shared by `track`, `fit-foot`, `predict` and `compare`: a sagittal
/// CSV, or an OpenSim pair (inverse kinematics and external loads), and what its files do
/// not say.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct TrialArgs {
    /// Trial: a sagittal CSV (with its `_meta.json`), or OpenSim inverse kinematics
    /// (`.mot`/`.sto`: pelvis_tx, pelvis_ty, pelvis_tilt, hip_flexion_r, knee_angle_r,
    /// ankle_angle_r, … the same `_l`; inDegrees honoured) with `--forces` (default: the
    /// bundled OpenSim subject01 trial, moved overground).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Forces of an OpenSim `--data`: OpenSim external loads (`.mot`/`.sto`:
    /// ground_force_vx, ground_force_vy, ground_force_px of each foot, per prefix, see
    /// `--plate`), or a C3D file's force plates (`.c3d`, types 2 and 4, with `--plate` and
    /// `--lab-axes`; its first frame at t = 0 unless the file says otherwise, on the
    /// kinematics' clock).
    #[arg(long, value_name = "GRF.mot|TRIAL.c3d")]
    pub forces: Option<PathBuf>,
    /// Which forces belong to which foot (repeatable). OpenSim loads: `r=PREFIX` or
    /// `l=PREFIX`, e.g. `--plate r=1_ --plate l=2_`, `r=` for the unprefixed
    /// ground_force_*; default: `""` or `r_` is the right foot, `l_` the left (the choice
    /// is printed). C3D: the 1-based plate number(s) of each foot, e.g. `--plate r=1
    /// --plate l=2` (a foot may take several plates: `--plate r=1 --plate r=3`); required.
    #[arg(long = "plate", value_name = "FOOT=PREFIX|FOOT=N", value_parser = super::validate::plate)]
    pub plates: Vec<String>,
    /// Lab axes of a C3D `--forces` file: the walking direction and up, `FORWARD,UP`, each
    /// one of +x, -x, +y, -y, +z, -z (default `+x,+z`, the usual C3D lab).
    #[arg(long, value_name = "FORWARD,UP", allow_hyphen_values = true)]
    pub lab_axes: Option<String>,
    /// Treadmill belt speed (m/s): moves the trial to the overground frame (an OpenSim
    /// pair has no meta file; a treadmill trial without a belt speed is refused unless
    /// `--overground`).
    #[arg(long, value_name = "M/S", conflicts_with = "overground", value_parser = super::validate::positive)]
    pub belt_speed: Option<f64>,
    /// Take a trial without a belt speed as overground, as it is (a treadmill trial
    /// without one is refused otherwise).
    #[arg(long)]
    pub overground: bool,
}

impl From<TrialArgs> for footfall::workflows::trial::TrialFiles {
    fn from(a: TrialArgs) -> Self {
        Self {
            data: a.data,
            forces: a.forces,
            plates: a.plates,
            lab_axes: a.lab_axes,
            belt_speed: a.belt_speed,
            overground: a.overground,
        }
    }
}

/// The tracking solver's stopping rules and Hessian switch, shared by `track` and
/// `compare-contact` (the latter applies them to each of its runs).
#[derive(Debug, Clone, clap::Args)]
pub struct TrackSolverArgs {
    /// KKT tolerance (at most 0.01).
    #[arg(long, default_value_t = 1e-5, value_parser = super::validate::kkt_tolerance)]
    pub tol: f64,
    /// With `--hessian exact`: Gauss–Newton steps until the constraint violation is below
    /// this (default: 1e-3, and below 0.1 once five Gauss–Newton iterations have not
    /// lowered the objective by 0.1 %; given, the switch is this one alone).
    #[arg(long, value_parser = super::validate::threshold)]
    pub exact_below: Option<f64>,
    /// Iteration limit (`compare-contact`: of each run).
    #[arg(long, default_value_t = 200, value_parser = super::validate::iterations)]
    pub max_iter: usize,
    /// Wall-time limit (s; `compare-contact`: of each run).
    #[arg(long, value_parser = super::validate::positive)]
    pub max_time: Option<f64>,
}

impl TrackSolverArgs {
    /// The tracking solver's settings with `hessian`.
    pub fn settings(&self, hessian: footfall::sqp::HessianMode) -> footfall::sqp::SqpSettings {
        footfall::workflows::track::tracking_sqp_settings(
            self.tol,
            self.max_iter,
            self.max_time,
            hessian,
            self.exact_below,
        )
    }
}

/// The check-point switch shared by `track`, `predict` and `compare`.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct CheckPointArgs {
    /// Solve once and only report the validity on the 1 ms grid, without adding check
    /// points where a contact constraint breaks between the nodes (a run that breaks one
    /// still ends `converged, physically invalid`, exit 5).
    #[arg(long)]
    no_check_points: bool,
    /// Add check points where the converged solution's 1 ms re-integration breaks a
    /// contact constraint, and solve again (up to 6 rounds, while iterations remain): the
    /// default, kept for scripts that ask for it.
    #[arg(long, overrides_with = "no_check_points", hide = true)]
    check_points: bool,
}

impl CheckPointArgs {
    /// Whether check points are added.
    pub fn enabled(&self) -> bool {
        !self.no_check_points
    }
}

/// Progress as the command line shows it: results on standard output, news, the
/// iteration table and warnings on standard error.
pub type CliProgress = TextProgress;

/// The command line's progress, only warnings if `quiet`.
pub fn cli_progress(quiet: bool) -> CliProgress {
    TextProgress {
        quiet,
        write: print_line,
    }
}

fn print_line(stream: Stream, text: &str) {
    match stream {
        Stream::Results => println!("{text}"),
        Stream::Messages => eprintln!("{text}"),
    }
}

/// Hessian choice on the command line.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum HessianArg {
    /// Gauss–Newton of the least-squares objective.
    GaussNewton,
    /// Block-diagonal BFGS of the Lagrangian.
    Bfgs,
    /// Gauss–Newton plus block BFGS of the constraint curvature.
    GaussNewtonBfgs,
    /// Exact Hessian of the Lagrangian (second-order sensitivities).
    Exact,
}

impl From<HessianArg> for footfall::sqp::HessianMode {
    fn from(h: HessianArg) -> Self {
        match h {
            HessianArg::GaussNewton => footfall::sqp::HessianMode::GaussNewton,
            HessianArg::Bfgs => footfall::sqp::HessianMode::Bfgs,
            HessianArg::GaussNewtonBfgs => footfall::sqp::HessianMode::GaussNewtonBfgs,
            HessianArg::Exact => footfall::sqp::HessianMode::Exact,
        }
    }
}

/// CVODES linear multistep method.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum MethodArg {
    /// Adams–Moulton (non-stiff problems; default for the generic problems).
    Adams,
    /// BDF (stiff problems).
    Bdf,
}

impl From<MethodArg> for footfall::integrate::Method {
    fn from(m: MethodArg) -> Self {
        match m {
            MethodArg::Adams => footfall::integrate::Method::Adams,
            MethodArg::Bdf => footfall::integrate::Method::Bdf,
        }
    }
}
