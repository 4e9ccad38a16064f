//! The SQP iteration: start (or resume from a checkpoint), then per iteration the step
//! ([`step`]), the KKT test ([`kkt`]), the filter line search
//! ([`line_search`]) and the quasi-Newton update, with a checkpoint
//! after every accepted step.

use super::checkpoint::{ExactRecord, ExactVec, SqpCheckpoint, CHECKPOINT_VERSION};
use super::evaluator::Evaluator;
use super::hessian::BlockBfgs;
use super::iterate::{State, Structure};
use super::kkt::{self, KktPoint};
use super::line_search::{self, Filter, Search, Trial};
use super::qp::{ActiveHint, QpData, QpSolution, Triplets};
use super::step::{self, Step, StepMemory, Subproblem};
use super::ExactConvexification;
use super::{
    violations, HessianMode, IterationRecord, Nlp, NlpEval, Observer, QpRoute, SqpResult,
    SqpSettings, SqpStatus, SqpTimings, Violation,
};
use std::time::Instant;

/// Solve `nlp` from `w0` (with the multipliers `warm`, where given and of the right
/// lengths; zero otherwise), or continue the solve `resume` checkpointed.
pub(super) fn run(
    nlp: &dyn Nlp,
    w0: &[f64],
    warm: Option<super::WarmStart<'_>>,
    settings: &SqpSettings,
    observer: &mut dyn Observer,
    resume: Option<&SqpCheckpoint>,
) -> SqpResult {
    // the integrator, the QP and the evaluations stop while this runs, if asked to
    let _solving = crate::interrupt::solving();
    let elapsed_before =
        resume.map_or(0.0, |cp| cp.scalars.values().get(5).copied().unwrap_or(0.0));
    let start = Instant::now()
        .checked_sub(std::time::Duration::from_secs_f64(elapsed_before.max(0.0)))
        .unwrap_or_else(Instant::now);
    let (solver, mut st, mut progress) =
        match Solver::start(nlp, settings, (w0, warm), resume, start) {
            Ok(started) => started,
            Err(failed) => return *failed,
        };
    let first_iter = resume.map_or(0, |cp| cp.next_iter);
    let mut status = SqpStatus::MaxIterations;
    for iter in first_iter..=settings.max_iter {
        if let Err(stop) = solver.iteration(iter, &mut st, &mut progress, observer) {
            status = stop;
            break;
        }
    }
    solver.finish(status, st, progress)
}

/// What stays fixed while the SQP iterates: the NLP, its settings and structure, the
/// evaluator and the solve's start.
struct Solver<'a> {
    nlp: &'a dyn Nlp,
    settings: &'a SqpSettings,
    s: Structure,
    eval: Evaluator<'a>,
    start: Instant,
}

/// What the iterations carry from one to the next besides the iterate (and what a
/// checkpoint keeps of it).
struct Progress {
    /// The quasi-Newton blocks.
    bfgs: BlockBfgs,
    /// The Hessian's block structure with zero matrices (convexification block by block).
    zero_blocks: BlockBfgs,
    mem: StepMemory,
    /// Constraint multipliers of the last QP.
    lambda: Vec<f64>,
    /// Bound multipliers of the last QP.
    nu: Vec<f64>,
    filter: Filter,
    history: Vec<IterationRecord>,
    /// The last KKT residual.
    kkt: f64,
    /// The step that reached the current point.
    last_step: f64,
    /// Whether the observer has been told that the Gauss–Newton steps stalled.
    stall_told: bool,
    /// Whether the observer said at the milestone to go on.
    milestone_passed: bool,
}

/// The result of a solve that failed before its first iteration, at `w` (`n` variables,
/// `m` constraints; `start`: the solve's start).
fn failed(status: SqpStatus, w: Vec<f64>, (n, m): (usize, usize), start: Instant) -> SqpResult {
    SqpResult {
        status: interrupted_or(status),
        lambda: vec![0.0; m],
        nu: vec![0.0; n],
        objective: f64::NAN,
        infeasibility: f64::NAN,
        kkt: f64::NAN,
        history: Vec::new(),
        most_violated: Vec::new(),
        seconds: start.elapsed().as_secs_f64(),
        timings: SqpTimings::default(),
        w,
    }
}

impl<'a> Solver<'a> {
    /// The solve of `nlp` from `w0` (with the multipliers `warm`, where given and of the
    /// right lengths; zero otherwise), or continued from the checkpoint `resume`: the solver,
    /// the first iterate evaluated and what the iterations carry; a failure is the solve's
    /// result.
    fn start(
        nlp: &'a dyn Nlp,
        settings: &'a SqpSettings,
        (w0, warm): (&[f64], Option<super::WarmStart<'_>>),
        resume: Option<&SqpCheckpoint>,
        start: Instant,
    ) -> Result<(Self, State, Progress), Box<SqpResult>> {
        let s = Structure::new(nlp, settings);
        let (n, m) = (s.n, s.m);
        let mut bfgs = BlockBfgs::new(nlp.hessian_blocks(), settings.bfgs_update);
        if settings.hessian == HessianMode::GaussNewtonBfgs {
            bfgs.scale(1e-4);
        }
        let w: Vec<f64> = w0
            .iter()
            .zip(s.w_lb.iter().zip(&s.w_ub))
            .map(|(&v, (&l, &u))| v.max(l).min(u))
            .collect();
        let fail = |status: SqpStatus, w: Vec<f64>| Box::new(failed(status, w, (n, m), start));
        if let Some(cp) = resume {
            if let Err(e) = cp.check(n, m) {
                return Err(fail(SqpStatus::EvaluationFailure(e.to_string()), w));
            }
            if !bfgs.restore(cp.bfgs.iter().map(|(b, s)| (b.values(), *s)).collect()) {
                return Err(fail(
                    SqpStatus::EvaluationFailure(
                        "the checkpoint's BFGS blocks do not fit this problem".into(),
                    ),
                    w,
                ));
            }
        }
        let solver = Self {
            nlp,
            settings,
            s,
            eval: Evaluator::new(
                nlp,
                settings,
                resume.map_or_else(SqpTimings::default, |cp| cp.timings),
            ),
            start,
        };
        if let Some(tol) = resume.and_then(|cp| cp.scalars.values().get(6).copied()) {
            if tol.is_finite() {
                nlp.set_integration_tolerance(tol);
            }
        }
        // a warm start's multipliers, where they fit this problem
        let fits = |v: &[f64], len: usize| v.len() == len && v.iter().all(|x| x.is_finite());
        let lambda0 = match (resume, warm) {
            (Some(cp), _) => cp.lambda.values(),
            (None, Some(ws)) if fits(ws.lambda, m) => ws.lambda.to_vec(),
            (None, _) => vec![0.0; m],
        };
        // on demand, the curvature only once a step uses it (below, at the top of the loop)
        let (ev, hess) = match solver.eval.derivs(&w, &lambda0, !solver.eval.on_demand()) {
            Ok(r) => r,
            Err(e) => return Err(fail(SqpStatus::EvaluationFailure(e.chain()), w)),
        };
        let plain = match solver.eval.plain(&w) {
            Ok(p) => (
                p.f,
                violations(&p.c, &solver.s.c_lb, &solver.s.c_ub)
                    .iter()
                    .sum::<f64>(),
            ),
            Err(e) => return Err(fail(SqpStatus::EvaluationFailure(e.chain()), w)),
        };
        let st = State { w, ev, hess, plain };
        let nu = match warm {
            Some(ws) if fits(ws.nu, n) => ws.nu.to_vec(),
            _ => vec![0.0; n],
        };
        let progress = Progress::new(nlp, settings, bfgs, (lambda0, nu), resume);
        Ok((solver, st, progress))
    }

    /// Iteration `iter` at `st`: the QP step, the KKT test, the filter line search, the
    /// quasi-Newton update and the checkpoint; `st` becomes the accepted point. An error is
    /// the status the solve ends with (also [`SqpStatus::Converged`]).
    fn iteration(
        &self,
        iter: usize,
        st: &mut State,
        p: &mut Progress,
        observer: &mut dyn Observer,
    ) -> Result<(), SqpStatus> {
        if crate::interrupt::requested() {
            return Err(SqpStatus::Interrupted);
        }
        // --- QP subproblem at the current point
        let viol = violations(&st.ev.c, &self.s.c_lb, &self.s.c_ub);
        let mut infeas = viol.iter().copied().fold(0.0, f64::max);
        let curvature = step::curvature_in_use(self.settings, infeas, &p.history);
        if curvature && self.eval.exact() && st.hess.is_none() {
            infeas = self.add_curvature((iter, infeas), st, p, observer)?;
        }
        self.note_switches(iter, (curvature, infeas), p, observer);
        let mut sub = step::subproblem(
            self.nlp,
            self.settings,
            &self.s,
            st,
            (&p.lambda, &p.nu),
            curvature,
            (&p.bfgs, &p.zero_blocks),
            &mut p.mem,
        )?;
        if !step::guess_active_set(iter, &p.history) {
            sub.without_guess();
        }
        let step = step::solve(&self.eval, &sub, &mut p.mem)?;
        let tightened = self.conclude_step((iter, infeas, curvature), st, &step, p, observer)?;
        let accepted = self.line_search(st, &sub, &step, &mut p.filter, (curvature, tightened))?;
        self.accept(iter, st, p, accepted, &step.sol.lambda, observer);
        Ok(())
    }

    /// The exact mode's curvature where the accepted point's evaluation went without (its
    /// violation said Gauss–Newton): where asked, first the Gauss–Newton QP, whose
    /// multipliers may already show a KKT point (a kept solution re-evaluated: the
    /// curvature, most of a compliant foot's evaluation, is then not needed; the solve then
    /// ends, [`SqpStatus::Converged`]); otherwise the same evaluation again, with it. The
    /// largest violation at `st` so evaluated, or the status the solve ends with.
    fn add_curvature(
        &self,
        (iter, infeas): (usize, f64),
        st: &mut State,
        p: &mut Progress,
        observer: &mut dyn Observer,
    ) -> Result<f64, SqpStatus> {
        if let Some(rec) = self
            .settings
            .gauss_newton_check
            .then(|| self.gauss_newton_check(st, p, (iter, infeas)))
            .flatten()
        {
            observer.iteration(&rec.record);
            p.kkt = rec.record.kkt;
            p.history.push(rec.record);
            p.lambda = rec.lambda;
            p.nu = rec.nu;
            return Err(SqpStatus::Converged);
        }
        match self.eval.derivs(&st.w, &p.lambda, true) {
            Ok((ev, hess)) => {
                st.ev = ev;
                st.hess = hess;
                let viol = violations(&st.ev.c, &self.s.c_lb, &self.s.c_ub);
                Ok(viol.iter().copied().fold(0.0, f64::max))
            }
            Err(e) => Err(SqpStatus::EvaluationFailure(e.chain())),
        }
    }

    /// Mark and tell the observer, once each, the switches the steps make at iteration
    /// `iter` (`curvature`: whether it uses the curvature; `infeas`: its largest
    /// violation): to Gauss–Newton where the exact Hessian is not convex, and to the exact
    /// Hessian because the Gauss–Newton steps stalled.
    fn note_switches(
        &self,
        iter: usize,
        (curvature, infeas): (bool, f64),
        p: &mut Progress,
        observer: &mut dyn Observer,
    ) {
        // shifted exact steps that no longer progress: Gauss–Newton where not convex
        if !p.mem.shift_stalled && shift_switch_made(self.settings, &p.history) {
            p.mem.shift_stalled = true;
            observer.note(&format!(
                "the steps from iteration {iter} on take the Gauss–Newton Hessian where the exact one is not convex: the last {} shifted steps did not halve the KKT residual",
                super::SHIFTED_STALL
            ));
        }
        // the curvature in use only because the Gauss–Newton steps stalled, not told yet
        let stalled = self
            .settings
            .exact_hessian_on_stall
            .filter(|_| !p.stall_told && curvature && infeas > self.settings.exact_hessian_below);
        if let Some(rule) = stalled {
            p.stall_told = true;
            observer.note(&format!(
                "the steps from iteration {} on use the exact Hessian: the last {} iterations, at a violation of at most {:e}, lowered the objective by less than {} %",
                iter,
                rule.iterations,
                rule.below,
                100.0 * rule.relative_decrease
            ));
        }
    }

    /// The KKT residual at `st` with the multipliers of the QP `step`, the integrator
    /// tightened as the optimum nears, the iteration's record (told to the observer) and
    /// the QP's multipliers taken. Whether the integrator was tightened, or the status the
    /// solve ends with: converged, interrupted, out of iterations or time, or infeasible.
    fn conclude_step(
        &self,
        (iter, infeas, curvature): (usize, f64, bool),
        st: &State,
        step: &Step,
        p: &mut Progress,
        observer: &mut dyn Observer,
    ) -> Result<bool, SqpStatus> {
        let (settings, sol, elastic) = (self.settings, &step.sol, step.elastic);
        // --- KKT residual at the current point with the QP multipliers
        p.kkt = kkt_with(&self.s, st, sol, infeas);
        // --- inexact SQP: integrate more precisely as the optimum nears
        let tightened = !kkt::converged(p.kkt, settings.tol_kkt, elastic)
            && tighten_integration(self.nlp, settings, p.kkt);
        let shift = (curvature && settings.hessian == HessianMode::Exact && !p.mem.gauss_newton)
            .then_some(p.mem.shift);
        let rec = record(
            self.nlp,
            st,
            (iter, infeas, p.last_step, self.start),
            p.kkt,
            (sol, step.route),
            shift,
        );
        let go_on = observer.iteration(&rec);
        p.history.push(rec);
        p.lambda.clone_from(&sol.lambda);
        p.nu.clone_from(&sol.nu);
        if kkt::converged(p.kkt, settings.tol_kkt, elastic) {
            return Err(SqpStatus::Converged);
        }
        if !go_on {
            return Err(SqpStatus::Interrupted);
        }
        let milestone = settings.milestone_tol.filter(|_| !p.milestone_passed);
        if milestone.is_some_and(|tol| kkt::converged(p.kkt, tol, elastic)) {
            if !observer.milestone(&st.w) {
                return Err(SqpStatus::Converged);
            }
            p.milestone_passed = true;
        }
        if iter == settings.max_iter {
            return Err(SqpStatus::MaxIterations);
        }
        if settings
            .max_time
            .is_some_and(|t| self.start.elapsed().as_secs_f64() > t)
        {
            return Err(SqpStatus::MaxTime);
        }
        if kkt::stationary_infeasible(&sol.d, &st.w, elastic, infeas, settings.tol_kkt) {
            return Err(SqpStatus::Infeasible);
        }
        Ok(tightened)
    }

    /// The filter line search from `st` along the step of the QP `sub`'s solution `step`
    /// (`curvature`: whether the step used the curvature; `tightened`: whether the
    /// integrator was tightened since `st` was evaluated): the accepted point with its
    /// derivatives, computed once there, and the filter augmented where the search says;
    /// or the status the solve ends with.
    fn line_search(
        &self,
        st: &State,
        sub: &Subproblem<'_>,
        step: &Step,
        filter: &mut Filter,
        (curvature, tightened): (bool, bool),
    ) -> Result<Accepted, SqpStatus> {
        let (settings, eval, sol) = (self.settings, &self.eval, &step.sol);
        // the line search compares trial points with the current point evaluated alike
        let plain = match tightened.then(|| eval.plain(&st.w)) {
            Some(Ok(p)) => (
                p.f,
                violations(&p.c, &self.s.c_lb, &self.s.c_ub)
                    .iter()
                    .sum::<f64>(),
            ),
            _ => st.plain,
        };
        // --- filter line search; derivatives and curvature are computed once, at the
        // accepted point
        let (f0, theta0) = plain;
        // derivatives where the plain evaluation succeeded can still fail (the
        // sensitivities' integration, a non-finite curvature): a recoverable failure there
        // rejects the point, and the search is repeated with at most half its step
        let mut max_step = 1.0;
        let found = loop {
            let search = line_search::search(
                &self.s,
                settings,
                filter,
                (st, plain),
                &sol.d,
                max_step,
                &|w| eval.plain(w),
                &|c_soc| {
                    // the correction's active set is most likely the step's
                    eval.qp(&QpData {
                        c: c_soc,
                        hint: Some(ActiveHint {
                            lambda: &sol.lambda,
                            nu: &sol.nu,
                        }),
                        ..sub.data(None)
                    })
                    .ok()
                    .map(|q| q.d)
                },
            );
            let trial = match search {
                Search::Accepted(trial) => trial,
                Search::Failed => {
                    break Err(if step.elastic {
                        SqpStatus::Infeasible
                    } else {
                        SqpStatus::LineSearchFailure
                    })
                }
                Search::Fatal(e) => break Err(SqpStatus::EvaluationFailure(e.chain())),
            };
            // with the curvature unless on demand; then when the next step will likely use
            // it: this one did, or the trial's summed violation bounds its largest one
            // below the switch
            let want =
                !eval.on_demand() || curvature || trial.plain.1 <= settings.exact_hessian_below;
            match eval.derivs(&trial.w, &sol.lambda, want) {
                Ok((ev, hess)) => break Ok((trial, ev, hess)),
                Err(e)
                    if e.is_recoverable() && 0.5 * trial.step >= settings.line_search_min_step =>
                {
                    max_step = 0.5 * trial.step;
                }
                Err(e) => break Err(SqpStatus::EvaluationFailure(e.chain())),
            }
        };
        let (trial, ev, hess) = found?;
        if trial.augment {
            filter.augment(theta0, f0);
        }
        Ok(Accepted { trial, ev, hess })
    }

    /// Move to the accepted point: the quasi-Newton update with the new multipliers
    /// `lambda`, the new iterate, and a checkpoint where the observer wants one.
    fn accept(
        &self,
        iter: usize,
        st: &mut State,
        p: &mut Progress,
        accepted: Accepted,
        lambda: &[f64],
        observer: &mut dyn Observer,
    ) {
        let Accepted { trial, ev, hess } = accepted;
        p.last_step = trial.step;
        // --- quasi-Newton update with the new multipliers
        let hessian = self.settings.hessian;
        if hessian == HessianMode::Bfgs || hessian == HessianMode::GaussNewtonBfgs {
            quasi_newton_update(
                &mut p.bfgs,
                &self.s,
                hessian == HessianMode::GaussNewtonBfgs,
                (&*st, &trial.w, &ev),
                lambda,
            );
        }
        *st = State {
            w: trial.w,
            ev,
            hess,
            plain: trial.plain,
        };
        if observer.wants_checkpoints() {
            observer.checkpoint(&self.checkpoint(iter, st, p));
        }
    }

    /// The checkpoint after iteration `iter`, at the accepted point `st`.
    fn checkpoint(&self, iter: usize, st: &State, p: &Progress) -> SqpCheckpoint {
        SqpCheckpoint {
            version: CHECKPOINT_VERSION,
            n: self.s.n,
            m: self.s.m,
            next_iter: iter + 1,
            w: ExactVec::new(&st.w),
            lambda: ExactVec::new(&p.lambda),
            nu: ExactVec::new(&p.nu),
            scalars: ExactVec::new(&[
                p.mem.lam_est,
                p.mem.test_rho_scale,
                p.mem.shift,
                p.filter.theta_max,
                p.last_step,
                self.start.elapsed().as_secs_f64(),
                self.nlp.integration_tolerance().unwrap_or(f64::NAN),
            ]),
            filter: ExactVec::new(
                &p.filter
                    .entries
                    .iter()
                    .flat_map(|&(a, b)| [a, b])
                    .collect::<Vec<f64>>(),
            ),
            bfgs: p
                .bfgs
                .state()
                .into_iter()
                .map(|(b, s)| (ExactVec::new(&b), s))
                .collect(),
            history: p.history.iter().map(ExactRecord::from).collect(),
            timings: self.eval.timings(),
        }
    }

    /// The solve's result at `st` once it stopped with `status`.
    fn finish(&self, mut status: SqpStatus, st: State, p: Progress) -> SqpResult {
        // an evaluation or a QP that failed because the solve was asked to stop
        if status != SqpStatus::Converged {
            status = interrupted_or(status);
        }
        let viol = violations(&st.ev.c, &self.s.c_lb, &self.s.c_ub);
        let mut order: Vec<usize> = (0..self.s.m)
            .filter(|&i| viol[i] > self.settings.tol_kkt)
            .collect();
        order.sort_by(|&a, &b| viol[b].total_cmp(&viol[a]));
        let most_violated = order
            .iter()
            .take(10)
            .map(|&i| Violation {
                name: self.nlp.row_name(i),
                amount: viol[i],
            })
            .collect();
        SqpResult {
            objective: st.ev.f,
            infeasibility: viol.iter().copied().fold(0.0, f64::max),
            kkt: p.kkt,
            status,
            history: p.history,
            most_violated,
            seconds: self.start.elapsed().as_secs_f64(),
            timings: self.eval.timings(),
            w: st.w,
            lambda: p.lambda,
            nu: p.nu,
        }
    }

    /// The Gauss–Newton check of the exact mode at a point `st` evaluated without the
    /// curvature (iteration `iter`, violation `infeas`): its QP's multipliers, a record and
    /// the multipliers if they show a KKT point at `settings.tol_kkt` (elastic QPs are not
    /// a KKT point's), otherwise `None`. Works on a copy of the step memory, so that a point
    /// that is no KKT point goes on as if unchecked.
    fn gauss_newton_check(
        &self,
        st: &State,
        p: &Progress,
        (iter, infeas): (usize, f64),
    ) -> Option<Checked> {
        let (s, settings) = (&self.s, self.settings);
        let mut mem = p.mem;
        let sub = step::subproblem(
            self.nlp,
            settings,
            s,
            st,
            (&p.lambda, &p.nu),
            false,
            (&p.bfgs, &p.zero_blocks),
            &mut mem,
        )
        .ok()?;
        let step = step::solve(&self.eval, &sub, &mut mem).ok()?;
        if step.elastic {
            return None;
        }
        let sol = step.sol;
        let kkt = kkt_with(s, st, &sol, infeas);
        if !kkt::converged(kkt, settings.tol_kkt, false) {
            return None;
        }
        Some(Checked {
            record: record(
                self.nlp,
                st,
                (iter, infeas, p.last_step, self.start),
                kkt,
                (&sol, step.route),
                None,
            ),
            lambda: sol.lambda,
            nu: sol.nu,
        })
    }
}

impl Progress {
    /// The state of the first iteration: the quasi-Newton blocks `bfgs`, the multipliers
    /// `lambda`, `nu`, and, when resumed, the rest from the checkpoint `resume`.
    fn new(
        nlp: &dyn Nlp,
        settings: &SqpSettings,
        bfgs: BlockBfgs,
        (lambda, nu): (Vec<f64>, Vec<f64>),
        resume: Option<&SqpCheckpoint>,
    ) -> Self {
        let mut zero_blocks = BlockBfgs::new(nlp.hessian_blocks(), settings.bfgs_update);
        zero_blocks.scale(0.0);
        let mut p = Self {
            bfgs,
            zero_blocks,
            mem: StepMemory::default(),
            lambda,
            nu,
            filter: Filter::new(),
            history: Vec::new(),
            kkt: f64::INFINITY,
            last_step: 0.0,
            stall_told: false,
            milestone_passed: false,
        };
        if let Some(cp) = resume {
            p.nu = cp.nu.values();
            let sc = cp.scalars.values();
            (
                p.mem.lam_est,
                p.mem.test_rho_scale,
                p.mem.shift,
                p.filter.theta_max,
                p.last_step,
            ) = (sc[0], sc[1], sc[2], sc[3], sc[4]);
            p.filter.entries = cp
                .filter
                .values()
                .chunks_exact(2)
                .map(|p| (p[0], p[1]))
                .collect();
            p.history = cp.records();
            p.mem.shift_stalled = shift_switch_made(settings, &p.history);
        }
        p
    }
}

/// The point a line search accepted, with its derivatives and curvature.
struct Accepted {
    trial: Trial,
    ev: NlpEval,
    hess: Option<Triplets>,
}

/// `status`, or [`SqpStatus::Interrupted`] when the solve was asked to stop: the failure
/// is then the stop's.
fn interrupted_or(status: SqpStatus) -> SqpStatus {
    if crate::interrupt::requested() {
        SqpStatus::Interrupted
    } else {
        status
    }
}

/// Whether the solve has switched to Gauss–Newton steps where the exact Hessian is not
/// convex ([`ExactConvexification::InertiaCorrectionThenGaussNewton`]): a function of the
/// history, made at the first iteration whose history so far had stalled, so that a resumed
/// solve finds the switch where the killed one made it.
fn shift_switch_made(settings: &SqpSettings, history: &[IterationRecord]) -> bool {
    settings.exact_convexification == ExactConvexification::InertiaCorrectionThenGaussNewton
        && (1..=history.len())
            .any(|l| super::shifted_steps_stalled(&history[..l], settings.exact_hessian_below))
}

/// The KKT residual at the point `st` with the multipliers of the QP solution `sol`
/// (`infeas`: its constraint violation).
fn kkt_with(s: &Structure, st: &State, sol: &QpSolution, infeas: f64) -> f64 {
    kkt::residual(&KktPoint {
        grad: &st.ev.grad,
        jac_rows: &s.jac_rows,
        jac_cols: &s.jac_cols,
        jac: &st.ev.jac,
        c: &st.ev.c,
        c_lb: &s.c_lb,
        c_ub: &s.c_ub,
        lambda: &sol.lambda,
        nu: &sol.nu,
        w: &st.w,
        w_lb: &s.w_lb,
        w_ub: &s.w_ub,
        infeasibility: infeas,
    })
}

/// The record of iteration `iter` at the point `st` (`infeas`: its violation; `last_step`:
/// the step that reached it; `start`: the solve's start), whose QP `sol` came by `route`
/// (`hessian_shift`: the exact Hessian's inertia correction, where it was used).
fn record(
    nlp: &dyn Nlp,
    st: &State,
    (iter, infeas, last_step, start): (usize, f64, f64, Instant),
    kkt: f64,
    (sol, route): (&QpSolution, QpRoute),
    hessian_shift: Option<f64>,
) -> IterationRecord {
    IterationRecord {
        iter,
        objective: st.ev.f,
        infeasibility: infeas,
        kkt,
        step: last_step,
        seconds: start.elapsed().as_secs_f64(),
        qp_iterations: sol.iterations,
        integration_tol: nlp.integration_tolerance(),
        hessian_shift,
        qp_route: Some(route),
    }
}

/// The tightest integrator tolerance the inexact SQP asks for.
const TIGHTEST_INTEGRATION_TOL: f64 = 1e-12;

/// A KKT point shown by [`Solver::gauss_newton_check`]: its iteration record and the QP's
/// multipliers.
struct Checked {
    record: IterationRecord,
    lambda: Vec<f64>,
    nu: Vec<f64>,
}

/// Tighten the NLP's integrator tolerance to `inexact_integration · kkt` when that is
/// less than half the current one (so that it changes in few, clear steps); whether it
/// changed.
fn tighten_integration(nlp: &dyn Nlp, settings: &SqpSettings, kkt: f64) -> bool {
    let Some(current) = nlp.integration_tolerance() else {
        return false;
    };
    let want = (settings.inexact_integration * kkt).max(TIGHTEST_INTEGRATION_TOL);
    if settings.inexact_integration > 0.0 && want.is_finite() && want < 0.5 * current {
        nlp.set_integration_tolerance(want);
        true
    } else {
        false
    }
}

/// BFGS update of the Lagrangian's curvature from `old` to the accepted point
/// (`w_new`, `ev_new`) with the new multipliers: the full Lagrangian gradient, or with
/// `structured` (Gauss–Newton + BFGS) only the constraint part; rows with exact curvature
/// are left out.
fn quasi_newton_update(
    bfgs: &mut BlockBfgs,
    s: &Structure,
    structured: bool,
    (old, w_new, ev_new): (&State, &[f64], &NlpEval),
    lambda: &[f64],
) {
    let n = s.n;
    let mut gl_new = if structured {
        vec![0.0; n]
    } else {
        ev_new.grad.clone()
    };
    let mut gl_old = if structured {
        vec![0.0; n]
    } else {
        old.ev.grad.clone()
    };
    for k in 0..s.jac_rows.len() {
        if s.exact_rows[s.jac_rows[k]] {
            continue;
        }
        gl_new[s.jac_cols[k]] += ev_new.jac[k] * lambda[s.jac_rows[k]];
        gl_old[s.jac_cols[k]] += old.ev.jac[k] * lambda[s.jac_rows[k]];
    }
    let sv: Vec<f64> = (0..n).map(|i| w_new[i] - old.w[i]).collect();
    let y: Vec<f64> = (0..n).map(|i| gl_new[i] - gl_old[i]).collect();
    bfgs.update(&sv, &y);
}
