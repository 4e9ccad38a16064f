//! Solve a gait problem until it is physically valid between its nodes: after each
//! converged solve the solution is re-integrated on a 1 ms grid, and where the ground pulls
//! a foot, a contact leaves its friction cone or a swing foot enters the floor, check points
//! ([`footfall::ocp::CheckPoint`]) hold the contact constraints at the worst instants; the
//! problem is solved again from the last solution, until nothing is broken or no new check
//! point can be placed.

use anyhow::{anyhow, Context};
use footfall::integrate::IntegratorSettings;
use footfall::model::{ConstraintSet, GaitModel};
use footfall::ocp::{CheckPoint, Ocp, Transcription};
use footfall::problems::evaluation::GaitSolution;
use footfall::problems::gait::{locate_instant, GaitCycle};
use footfall::problems::validity::{self, ValidityLimits};
use footfall::sqp::{SqpResult, SqpStatus};

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

/// Most rounds of check points after the first solve.
pub const MAX_ROUNDS: usize = 6;

/// Step of the validity grid (s).
pub const GRID_STEP: f64 = 1e-3;

/// Where check points hold the contact constraints: (continuous phase, interval, τ).
pub type CheckSites = Vec<(usize, usize, f64)>;

/// What the problem needs for its check points and the validity grid.
pub struct Refinement<'c, 'm> {
    /// The walking cycle.
    pub cycle: &'c GaitCycle<'m>,
    /// The model.
    pub model: &'m GaitModel,
    /// Contact set of every phase of the phase file.
    pub sets: &'m [ConstraintSet],
    /// Integrator of the re-integration.
    pub integrator: IntegratorSettings,
    /// Time of the first node (s).
    pub t0: f64,
    /// Whether to add check points at all (`false`: solve once).
    pub enabled: bool,
    /// Iteration limit of the whole solve: no round starts once it is used up.
    pub max_iter: usize,
}

impl<'m> Refinement<'_, 'm> {
    /// The check points at `sites`.
    pub fn checks(&self, sites: &[(usize, usize, f64)]) -> Vec<CheckPoint<'m>> {
        sites
            .iter()
            .flat_map(|&(j, k, tau)| self.cycle.contact_checks(j, k, tau))
            .collect()
    }

    /// Solve with `solve` (on the problem `build` makes, with the check points so far, from
    /// the last solution), starting with the check points at `initial` and adding more
    /// while the re-integration breaks a contact constraint. Returns the check sites and the result of the last solve, its history
    /// following the earlier rounds'.
    pub fn solve<'o>(
        &self,
        build: &dyn Fn() -> anyhow::Result<Ocp<'o>>,
        initial: &[(usize, usize, f64)],
        w0: &[f64],
        solve: &mut dyn FnMut(&Transcription, &[f64]) -> anyhow::Result<SqpResult>,
        quiet: bool,
    ) -> anyhow::Result<(CheckSites, SqpResult)>
    where
        'm: 'o,
    {
        let mut sites: CheckSites = initial.to_vec();
        let mut w = w0.to_vec();
        let mut merged: Option<SqpResult> = None;
        for round in 0..=MAX_ROUNDS {
            let mut ocp = build()?;
            ocp.checks = self.checks(&sites);
            let tr = Transcription::new(&ocp)
                .context("transcribing the problem with its check points")?;
            let res = solve(&tr, &w)?;
            let converged = res.status == SqpStatus::Converged;
            let next = res.w.clone();
            let all = match merged {
                None => res,
                Some(first) => super::track::merge_stages(first, res),
            };
            let used = all.history.len().saturating_sub(1);
            merged = Some(all);
            if !converged || !self.enabled || round == MAX_ROUNDS || used >= self.max_iter {
                break;
            }
            let solution = GaitSolution::from_nlp(&tr, &next, &self.cycle.continuous, self.t0);
            let found = self.validity(&solution)?;
            let new: CheckSites = found
                .refinement()
                .iter()
                .filter_map(|&(set, t)| locate_instant(&solution, set, t))
                .filter(|s| {
                    !sites
                        .iter()
                        .any(|o| o.0 == s.0 && o.1 == s.1 && (o.2 - s.2).abs() < 1e-3)
                })
                .collect();
            if new.is_empty() {
                break;
            }
            if !quiet {
                for v in &found.violations {
                    eprintln!("between the nodes: {v}");
                }
                let at: Vec<String> = new
                    .iter()
                    .map(|&(j, k, tau)| {
                        format!("{} interval {k} τ = {tau:.3}", solution.phases[j].name)
                    })
                    .collect();
                eprintln!(
                    "adding {} check point(s) ({}; {} in all) and solving again from this solution",
                    new.len(),
                    at.join(", "),
                    sites.len() + new.len()
                );
            }
            sites.extend(new);
            w = next;
        }
        Ok((sites, merged.ok_or_else(|| anyhow!("no solve was made"))?))
    }

    /// The validity of `solution` on the 1 ms grid.
    pub fn validity(&self, solution: &GaitSolution) -> anyhow::Result<validity::Validity> {
        let re = solution
            .reintegrate(self.model, self.sets, GRID_STEP, &self.integrator)
            .context("re-integrating on the validity grid")?;
        let names: Vec<String> = self.cycle.phase_names();
        Ok(validity::check(
            self.model,
            &re.result.samples,
            self.sets,
            &names,
            &solution.theta,
            self.cycle.friction(),
            ValidityLimits::default(),
        ))
    }
}
