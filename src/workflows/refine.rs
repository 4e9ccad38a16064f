//! Solve a gait problem until it is physically valid between its nodes: after each
//! converged solve the solution is re-integrated on a 1 ms grid, and where the ground pulls
//! a foot, a contact leaves its friction cone or a swing foot enters the floor, check points
//! ([`crate::ocp::CheckPoint`]) hold the contact constraints at the worst instants; the
//! problem is solved again from the last solution, until nothing is broken or no new check
//! point can be placed.

#[allow(unused_imports)]
use super::{note, warn_note, Progress};
use crate::integrate::IntegratorSettings;
use crate::model::{ConstraintSet, GaitModel};
use crate::ocp::{Ocp, Transcription};
use crate::problems::evaluation::GaitSolution;
use crate::problems::gait::{locate_instant, GaitCycle};
use crate::problems::validity::{self, ValidityLimits};
use crate::sqp::{SqpResult, SqpStatus};
use anyhow::{anyhow, Context};

/// Most rounds of check points after the first solve.
pub const MAX_ROUNDS: usize = 6;

/// Step of the validity grid (s).
pub const GRID_STEP: f64 = 1e-3;

/// KKT tolerance of a round that may still be followed by another: its solution only
/// says where check points are needed, and the next round moves it anyway. Solving it
/// to the run's tolerance spent 5–11 iterations of the bundled ellipse track's 29–36 on
/// a problem it then left. A round that adds nothing is finished at the run's
/// tolerance, and checked again.
pub const ROUND_TOL: f64 = 1e-3;

/// Where check points hold the contact constraints: (continuous phase, interval, τ).
pub type CheckSites = Vec<(usize, usize, f64)>;

/// Where a round starts: the point and, for a round that only finishes the last one's
/// problem, that round's multipliers (constraints' and bounds').
pub type RoundStart<'a> = (&'a [f64], Option<crate::sqp::WarmStart<'a>>);

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
    /// The run's KKT tolerance (what the last round is solved to).
    pub tol_kkt: f64,
}

impl<'m> Refinement<'_, 'm> {
    /// Solve with `solve` (on the problem `build` makes, with the check points so far, from
    /// the last solution), starting with the check points at `initial` and adding more
    /// while the re-integration breaks a contact constraint. `solve`'s last argument is the
    /// KKT tolerance of the round: [`ROUND_TOL`] (or the run's, if looser) for a round that
    /// may be followed by another, the run's own otherwise; its last, the iterations the
    /// round may make (what the earlier rounds left of [`Refinement::max_iter`]); its
    /// second, for a round that only finishes the last one's problem at the run's
    /// tolerance, that round's multipliers (the caller may start from them instead of
    /// zero). Returns
    /// the check sites and the result of the last solve, its history following the
    /// earlier rounds'.
    pub fn solve<'o>(
        &self,
        build: &dyn Fn() -> anyhow::Result<Ocp<'o>>,
        initial: &[(usize, usize, f64)],
        w0: &[f64],
        solve: &mut dyn FnMut(
            &Transcription,
            RoundStart<'_>,
            f64,
            usize,
        ) -> anyhow::Result<SqpResult>,
        progress: &dyn Progress,
    ) -> anyhow::Result<(CheckSites, SqpResult)>
    where
        'm: 'o,
    {
        let mut sites: CheckSites = initial.to_vec();
        let mut w = w0.to_vec();
        let mut merged: Option<SqpResult> = None;
        // whether the last round was solved to ROUND_TOL only
        let mut finishing = false;
        for round in 0..=MAX_ROUNDS {
            let mut ocp = build()?;
            ocp.checks = self.cycle.checks_at(&sites);
            let tr = Transcription::new(&ocp)
                .context("transcribing the problem with its check points")?;
            let loose = self.enabled && !finishing && round < MAX_ROUNDS;
            let tol = if loose {
                ROUND_TOL.max(self.tol_kkt)
            } else {
                self.tol_kkt
            };
            // the iteration limit is the whole solve's, not each round's
            let done = merged
                .as_ref()
                .map_or(0, |m| m.history.len().saturating_sub(1));
            // a finishing round continues the last round's problem: its multipliers (the
            // merged result's are the last solve's)
            let warm = merged
                .as_ref()
                .filter(|_| finishing)
                .map(|m| crate::sqp::WarmStart {
                    lambda: &m.lambda,
                    nu: &m.nu,
                });
            let res = solve(&tr, (&w, warm), tol, self.max_iter.saturating_sub(done))?;
            let converged = res.status == SqpStatus::Converged;
            let next = res.w.clone();
            let mut all = match merged {
                None => res,
                Some(first) => first.followed_by(res),
            };
            let used = all.history.len().saturating_sub(1);
            // whether the solution is still short of the run's own tolerance
            let short = loose && converged && !(all.kkt <= self.tol_kkt);
            if short && used >= self.max_iter {
                // converged only to the round's tolerance, with no iterations left
                all.status = SqpStatus::MaxIterations;
            }
            merged = Some(all);
            if !converged || !self.enabled || round == MAX_ROUNDS || used >= self.max_iter {
                break;
            }
            let solution = GaitSolution::from_nlp(&tr, &next, &self.cycle.continuous, self.t0);
            let found = self.validity(&solution)?;
            // one check point per instant: a pulling ground and a broken cone are often
            // worst at the same instant
            let same = |o: &(usize, usize, f64), s: &(usize, usize, f64)| {
                o.0 == s.0 && o.1 == s.1 && (o.2 - s.2).abs() < 1e-3
            };
            let mut new: CheckSites = Vec::new();
            for s in found
                .refinement()
                .iter()
                .filter_map(|&(set, t)| locate_instant(&solution, set, t))
            {
                if !sites.iter().chain(&new).any(|o| same(o, &s)) {
                    new.push(s);
                }
            }
            if new.is_empty() {
                if !short {
                    break;
                }
                // valid at the round's tolerance: finish at the run's, and check again
                finishing = true;
                w = next;
                continue;
            }
            finishing = false;
            {
                for v in &found.violations {
                    note!(progress, "between the nodes: {v}");
                }
                let at: Vec<String> = new
                    .iter()
                    .map(|&(j, k, tau)| {
                        format!("{} interval {k} τ = {tau:.3}", solution.phases[j].name)
                    })
                    .collect();
                note!(
                    progress,
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
