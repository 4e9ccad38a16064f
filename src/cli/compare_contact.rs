//! `footfall compare-contact`: the arguments of the rigid-against-compliant comparison
//! ([`footfall::workflows::compare_contact`]).

use super::{cli_progress, Failure};
use footfall::workflows::compare_contact::{
    compare_contact, first_unconverged, CompareContactRequest,
};
use footfall::workflows::run_folder::DEFAULT_TRANSIENT_THRESHOLD_N;
use footfall::workflows::track::TrackRequest;
use footfall::workflows::{default_phases, Unsolved};
use std::path::PathBuf;

/// Arguments of `footfall compare-contact`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file (JSON).
    #[arg(long, default_value = "models/opensim_subject01.json")]
    model: PathBuf,
    #[command(flatten)]
    trial: super::TrialArgs,
    /// The rigid foot: `ellipse`, `double-circle` or a foot file (JSON).
    #[arg(long, default_value = "ellipse")]
    rigid_foot: String,
    /// The rigid foot's phase graph (default: Millard & Mombaur's (2019)
    /// graph for the bundled feet).
    #[arg(long)]
    rigid_phases: Option<PathBuf>,
    /// The volumetric foot file (JSON).
    #[arg(long, default_value = "models/feet/volumetric_ellipse.json")]
    volumetric_foot: String,
    /// The volumetric foot's phase graph.
    #[arg(long, default_value = "phases/volumetric_ellipse_walk.json")]
    volumetric_phases: PathBuf,
    /// Track the pelvis position (x, y) too, in every run.
    #[arg(long)]
    track_pelvis_position: bool,
    /// Compare every sample in the tracked window with the model at its own instant
    /// instead of node targets from splines (as `track --sample-targets`), in every run.
    /// The volumetric law's identification on the bundled trial converges with it and
    /// the pelvis position tracked.
    #[arg(long)]
    sample_targets: bool,
    /// Relative and absolute CVODES tolerance of the shooting intervals (the volumetric
    /// contact's stiff dynamics need 1e-10).
    #[arg(long, default_value_t = 1e-10, value_parser = super::validate::positive)]
    integrator_tol: f64,
    #[command(flatten)]
    solver: super::TrackSolverArgs,
    #[command(flatten)]
    check_points: super::CheckPointArgs,
    /// Report ground-force excursions above the measurement larger than this (N).
    #[arg(long, default_value_t = DEFAULT_TRANSIENT_THRESHOLD_N, value_parser = super::validate::positive)]
    transient_threshold: f64,
    /// Output folder (one track run folder per run inside).
    #[arg(long, default_value = "runs/compare-contact")]
    out: PathBuf,
    /// Replace the output folder if it exists.
    #[arg(long)]
    overwrite: bool,
}

impl From<Args> for CompareContactRequest {
    fn from(a: Args) -> Self {
        let mut run = TrackRequest::new(&a.rigid_foot).run;
        run.model = a.model;
        run.data = a.trial.data;
        run.forces = a.trial.forces;
        run.plates = a.trial.plates;
        run.lab_axes = a.trial.lab_axes;
        run.belt_speed = a.trial.belt_speed;
        run.overground = a.trial.overground;
        run.integrator_tol = a.integrator_tol;
        run.track_pelvis_position = a.track_pelvis_position;
        run.sample_targets = a.sample_targets;
        CompareContactRequest {
            run,
            rigid_phases: a
                .rigid_phases
                .unwrap_or_else(|| default_phases(&a.rigid_foot)),
            rigid_foot: a.rigid_foot,
            volumetric_foot: a.volumetric_foot,
            volumetric_phases: a.volumetric_phases,
            check_points: a.check_points.enabled(),
            sqp: a.solver.settings(footfall::sqp::HessianMode::Exact),
            transient_threshold: a.transient_threshold,
            out: a.out,
            overwrite: a.overwrite,
        }
    }
}

pub fn run(args: Args, quiet: bool) -> Result<(), Failure> {
    let progress = cli_progress(quiet);
    let cmp = compare_contact(&args.into(), &progress).map_err(Failure::classify)?;
    match first_unconverged(&cmp) {
        Some(r) => Err(Failure::classify(
            Unsolved {
                status: r.sqp_status.clone(),
                at_start: r.iterations == 0,
                message: format!(
                    "not every run converged ({}: {}; results in {})",
                    r.name,
                    r.status,
                    cmp.path.display()
                ),
            }
            .into(),
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(argv: &[&str]) -> CompareContactRequest {
        let argv: Vec<&str> = std::iter::once("compare-contact")
            .chain(argv.iter().copied())
            .collect();
        super::super::parse_args::<Args>(&argv).into()
    }

    /// The cost's options reach every run's setup: node targets and the pelvis untracked
    /// unless asked.
    #[test]
    fn the_target_options_reach_the_runs_setup() {
        let plain = request(&[]);
        assert!(!plain.run.sample_targets && !plain.run.track_pelvis_position);
        let asked = request(&["--sample-targets", "--track-pelvis-position"]);
        assert!(asked.run.sample_targets && asked.run.track_pelvis_position);
        assert_eq!(asked.run.integrator_tol, 1e-10);
    }

    /// The exact Hessian comes in below a violation of 1e-3, or below 0.1 once the
    /// Gauss–Newton steps stall; `--exact-below` gives a fixed switch alone.
    #[test]
    fn exact_below_replaces_the_switch_on_stalled_steps() {
        let default = request(&[]).sqp;
        assert_eq!(default.exact_hessian_below, 1e-3);
        assert_eq!(
            default.exact_hessian_on_stall,
            Some(footfall::workflows::track::STALL_SWITCH)
        );
        let fixed = request(&["--exact-below", "0.1"]).sqp;
        assert_eq!(fixed.exact_hessian_below, 0.1);
        assert_eq!(fixed.exact_hessian_on_stall, None);
    }
}
