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
use crate::sqp::{SqpResult, SqpSettings, SqpStatus};
use anyhow::{anyhow, Context};

/// Most rounds of check points after the first solve.
pub const MAX_ROUNDS: usize = 6;

/// Step of the validity grid (s).
pub const GRID_STEP: f64 = 1e-3;

/// KKT tolerance at which a round that may still be followed by another is judged on the
/// validity grid: a solution that needs more check points there ends the round (the next
/// round moves it anyway), and one that needs none goes on in place to the run's
/// tolerance, and is checked again. Solving every round to the run's tolerance spent 5–11
/// iterations of the bundled ellipse track's 29–36 on problems it then left.
pub const ROUND_TOL: f64 = 1e-3;

/// Where check points hold the contact constraints: (continuous phase, interval, τ).
pub type CheckSites = Vec<(usize, usize, f64)>;

/// One round's solve, as [`Refinement::solve`] asks for it.
pub struct Round<'a> {
    /// The start point: the data's guess, or the last round's solution.
    pub w0: &'a [f64],
    /// The run's KKT tolerance.
    pub tol_kkt: f64,
    /// The iterations the round may make (what the earlier rounds left).
    pub max_iter: usize,
    /// The KKT tolerance at which the solve asks `judge` whether to go on
    /// ([`crate::sqp::SqpSettings::milestone_tol`]).
    pub milestone: Option<f64>,
    /// Whether the solve at the milestone goes on, given its iterate.
    pub judge: super::Judge<'a>,
}

impl Round<'_> {
    /// `base` with this round's KKT tolerance, iteration limit and milestone.
    pub fn settings(&self, base: &SqpSettings) -> SqpSettings {
        SqpSettings {
            tol_kkt: self.tol_kkt,
            max_iter: self.max_iter,
            milestone_tol: self.milestone,
            ..base.clone()
        }
    }
}

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

/// A solution, its validity on the grid and the check sites it asks for beyond those held.
type Verdict = (GaitSolution, validity::Validity, CheckSites);

impl<'m> Refinement<'_, 'm> {
    /// Solve with `solve` (on the problem `build` makes, with the check points so far, from
    /// the last solution), starting with the check points at `initial` and adding more
    /// while the re-integration breaks a contact constraint. A round that may be followed
    /// by another is judged at [`ROUND_TOL`] ([`Round::milestone`]). Returns the check
    /// sites and the result of the last solve, its history following the earlier rounds'.
    pub fn solve<'o>(
        &self,
        build: &dyn Fn() -> anyhow::Result<Ocp<'o>>,
        initial: &[(usize, usize, f64)],
        w0: &[f64],
        solve: &mut dyn FnMut(&Transcription, Round<'_>) -> anyhow::Result<SqpResult>,
        progress: &dyn Progress,
    ) -> anyhow::Result<(CheckSites, SqpResult)>
    where
        'm: 'o,
    {
        let mut sites: CheckSites = initial.to_vec();
        let mut w = w0.to_vec();
        let mut merged: Option<SqpResult> = None;
        for round in 0..=MAX_ROUNDS {
            let mut ocp = build()?;
            ocp.checks = self.cycle.checks_at(&sites);
            let tr = Transcription::new(&ocp)
                .context("transcribing the problem with its check points")?;
            let loose = self.enabled && round < MAX_ROUNDS;
            // the iteration limit is the whole solve's, not each round's
            let done = merged
                .as_ref()
                .map_or(0, |m| m.history.len().saturating_sub(1));
            let mut judged: Option<(Vec<f64>, anyhow::Result<Verdict>)> = None;
            let mut judge = |w: &[f64]| {
                let verdict = self.judge(&tr, w, &sites);
                let go_on = matches!(&verdict, Ok((_, _, new)) if new.is_empty());
                judged = Some((w.to_vec(), verdict));
                go_on
            };
            let res = solve(
                &tr,
                Round {
                    w0: &w,
                    tol_kkt: self.tol_kkt,
                    max_iter: self.max_iter.saturating_sub(done),
                    milestone: (loose && ROUND_TOL > self.tol_kkt).then_some(ROUND_TOL),
                    judge: &mut judge,
                },
            )?;
            let converged = res.status == SqpStatus::Converged;
            // ended at the milestone: the judge asked for check points
            let short = converged && !(res.kkt <= self.tol_kkt);
            let next = res.w.clone();
            let mut all = match merged {
                None => res,
                Some(first) => first.followed_by(res),
            };
            let used = all.history.len().saturating_sub(1);
            if short && used >= self.max_iter {
                // converged only to the round's tolerance, with no iterations left
                all.status = SqpStatus::MaxIterations;
            }
            merged = Some(all);
            if !converged || !self.enabled || round == MAX_ROUNDS || used >= self.max_iter {
                break;
            }
            let (solution, found, new) = match judged {
                Some((at, verdict)) if at == next => verdict?,
                _ => self.judge(&tr, &next, &sites)?,
            };
            if new.is_empty() {
                break;
            }
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

    /// The solution `w` of `tr`, its validity on the grid and the check sites it asks
    /// for beyond `sites`: one per instant (a pulling ground and a broken cone are often
    /// worst at the same instant).
    fn judge(
        &self,
        tr: &Transcription,
        w: &[f64],
        sites: &[(usize, usize, f64)],
    ) -> anyhow::Result<Verdict> {
        let solution = GaitSolution::from_nlp(tr, w, &self.cycle.continuous, self.t0);
        let found = self.validity(&solution)?;
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
        Ok((solution, found, new))
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
