//! Arguments and printing shared by several subcommands.

use footfall::workflows::Printed;
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

/// Progress printed as the command line shows it (the library's [`Printed`]).
pub type CliProgress = Printed;

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
