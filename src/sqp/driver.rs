//! The SQP iteration: start (or resume from a checkpoint), then per iteration the step
//! ([`step`]), the KKT test ([`kkt`]), the filter line search
//! ([`line_search`]) and the quasi-Newton update, with a checkpoint
//! after every accepted step.

use super::checkpoint::{ExactRecord, ExactVec, SqpCheckpoint, CHECKPOINT_VERSION};
use super::evaluator::Evaluator;
use super::hessian::BlockBfgs;
use super::iterate::{State, Structure};
use super::kkt::{self, KktPoint};
use super::line_search::{self, Filter, Search};
use super::qp::{QpData, QpSolution};
use super::step::{self, StepMemory};
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
    let fail = |status: SqpStatus, w: Vec<f64>| SqpResult {
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
    };
    if let Some(cp) = resume {
        if let Err(e) = cp.check(n, m) {
            return fail(SqpStatus::EvaluationFailure(e.to_string()), w);
        }
        if !bfgs.restore(cp.bfgs.iter().map(|(b, s)| (b.values(), *s)).collect()) {
            return fail(
                SqpStatus::EvaluationFailure(
                    "the checkpoint's BFGS blocks do not fit this problem".into(),
                ),
                w,
            );
        }
    }
    let eval = Evaluator::new(
        nlp,
        settings,
        resume.map_or_else(SqpTimings::default, |cp| cp.timings),
    );
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
    let (ev, hess) = match eval.derivs(&w, &lambda0, !eval.on_demand()) {
        Ok(r) => r,
        Err(e) => return fail(SqpStatus::EvaluationFailure(e.chain()), w),
    };
    let plain = match eval.plain(&w) {
        Ok(p) => (p.f, violations(&p.c, &s.c_lb, &s.c_ub).iter().sum::<f64>()),
        Err(e) => return fail(SqpStatus::EvaluationFailure(e.chain()), w),
    };
    let mut st = State { w, ev, hess, plain };
    let mut zero_blocks = BlockBfgs::new(nlp.hessian_blocks(), settings.bfgs_update);
    zero_blocks.scale(0.0);
    let mut mem = StepMemory::default();
    let mut lambda = lambda0;
    let mut nu = match warm {
        Some(ws) if fits(ws.nu, n) => ws.nu.to_vec(),
        _ => vec![0.0; n],
    };
    let mut filter = Filter::new();
    let mut history = Vec::new();
    let mut status = SqpStatus::MaxIterations;
    let mut kkt = f64::INFINITY;
    let mut last_step = 0.0;
    let mut first_iter = 0;
    // whether the observer has been told that the Gauss–Newton steps stalled
    let mut stall_told = false;
    if let Some(cp) = resume {
        nu = cp.nu.values();
        let sc = cp.scalars.values();
        (
            mem.lam_est,
            mem.test_rho_scale,
            mem.shift,
            filter.theta_max,
            last_step,
        ) = (sc[0], sc[1], sc[2], sc[3], sc[4]);
        filter.entries = cp
            .filter
            .values()
            .chunks_exact(2)
            .map(|p| (p[0], p[1]))
            .collect();
        history = cp.records();
        first_iter = cp.next_iter;
        mem.shift_stalled = shift_switch_made(settings, &history);
    }
    for iter in first_iter..=settings.max_iter {
        if crate::interrupt::requested() {
            status = SqpStatus::Interrupted;
            break;
        }
        // --- QP subproblem at the current point
        let mut viol = violations(&st.ev.c, &s.c_lb, &s.c_ub);
        let mut infeas = viol.iter().copied().fold(0.0, f64::max);
        let curvature = step::curvature_in_use(settings, infeas, &history);
        // the exact mode's curvature where the accepted point's evaluation went without
        // (its violation said Gauss–Newton): where asked, first the Gauss–Newton QP, whose
        // multipliers may already show a KKT point (a kept solution re-evaluated: the
        // curvature, most of a compliant foot's evaluation, is then not needed);
        // otherwise the same evaluation again, with it
        if curvature && eval.exact() && st.hess.is_none() {
            if let Some(rec) = settings
                .gauss_newton_check
                .then(|| {
                    gauss_newton_check(
                        nlp,
                        settings,
                        &s,
                        &st,
                        (&lambda, &nu),
                        (&bfgs, &zero_blocks),
                        mem,
                        &eval,
                        (iter, infeas, last_step, start),
                    )
                })
                .flatten()
            {
                observer.iteration(&rec.record);
                kkt = rec.record.kkt;
                history.push(rec.record);
                lambda = rec.lambda;
                nu = rec.nu;
                status = SqpStatus::Converged;
                break;
            }
            match eval.derivs(&st.w, &lambda, true) {
                Ok((ev, hess)) => {
                    st.ev = ev;
                    st.hess = hess;
                    viol = violations(&st.ev.c, &s.c_lb, &s.c_ub);
                    infeas = viol.iter().copied().fold(0.0, f64::max);
                }
                Err(e) => {
                    status = SqpStatus::EvaluationFailure(e.chain());
                    break;
                }
            }
        }
        // shifted exact steps that no longer progress: Gauss–Newton where not convex
        if !mem.shift_stalled && shift_switch_made(settings, &history) {
            mem.shift_stalled = true;
            observer.note(&format!(
                "the steps from iteration {iter} on take the Gauss–Newton Hessian where the exact one is not convex: the last {} shifted steps did not halve the KKT residual",
                super::SHIFTED_STALL
            ));
        }
        // the curvature in use only because the Gauss–Newton steps stalled, not told yet
        let stalled = settings
            .exact_hessian_on_stall
            .filter(|_| !stall_told && curvature && infeas > settings.exact_hessian_below);
        if let Some(rule) = stalled {
            stall_told = true;
            observer.note(&format!(
                "the steps from iteration {} on use the exact Hessian: the last {} iterations, at a violation of at most {:e}, lowered the objective by less than {} %",
                iter,
                rule.iterations,
                rule.below,
                100.0 * rule.relative_decrease
            ));
        }
        let sub = match step::subproblem(
            nlp,
            settings,
            &s,
            &st,
            (&lambda, &nu),
            curvature,
            (&bfgs, &zero_blocks),
            &mut mem,
        ) {
            Ok(sub) => sub,
            Err(e) => {
                status = e;
                break;
            }
        };
        let (sol, elastic, route) = match step::solve(&eval, &sub, &mut mem) {
            Ok(step) => (step.sol, step.elastic, step.route),
            Err(e) => {
                status = e;
                break;
            }
        };
        // --- KKT residual at the current point with the QP multipliers
        kkt = kkt_with(&s, &st, &sol, infeas);
        // --- inexact SQP: integrate more precisely as the optimum nears
        let tightened = !kkt::converged(kkt, settings.tol_kkt, elastic)
            && tighten_integration(nlp, settings, kkt);
        let shift = (curvature && settings.hessian == HessianMode::Exact && !mem.gauss_newton)
            .then_some(mem.shift);
        let rec = record(
            nlp,
            &st,
            (iter, infeas, last_step, start),
            kkt,
            (&sol, route),
            shift,
        );
        let go_on = observer.iteration(&rec);
        history.push(rec);
        lambda.clone_from(&sol.lambda);
        nu.clone_from(&sol.nu);
        if kkt::converged(kkt, settings.tol_kkt, elastic) {
            status = SqpStatus::Converged;
            break;
        }
        if !go_on {
            status = SqpStatus::Interrupted;
            break;
        }
        if iter == settings.max_iter {
            status = SqpStatus::MaxIterations;
            break;
        }
        if settings
            .max_time
            .is_some_and(|t| start.elapsed().as_secs_f64() > t)
        {
            status = SqpStatus::MaxTime;
            break;
        }
        if kkt::stationary_infeasible(&sol.d, &st.w, elastic, infeas, settings.tol_kkt) {
            status = SqpStatus::Infeasible;
            break;
        }
        // the line search compares trial points with the current point evaluated alike
        let plain = match tightened.then(|| eval.plain(&st.w)) {
            Some(Ok(p)) => (p.f, violations(&p.c, &s.c_lb, &s.c_ub).iter().sum::<f64>()),
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
                &s,
                settings,
                &mut filter,
                (&st, plain),
                &sol.d,
                max_step,
                &|w| eval.plain(w),
                &|c_soc| {
                    eval.qp(&QpData {
                        c: c_soc,
                        ..sub.data(None)
                    })
                    .ok()
                    .map(|q| q.d)
                },
            );
            let trial = match search {
                Search::Accepted(trial) => trial,
                Search::Failed => {
                    break Err(if elastic {
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
        let (trial, ev_new, hess_new) = match found {
            Ok(found) => found,
            Err(stop) => {
                status = stop;
                break;
            }
        };
        if trial.augment {
            filter.augment(theta0, f0);
        }
        last_step = trial.step;
        // --- quasi-Newton update with the new multipliers
        if settings.hessian == HessianMode::Bfgs || settings.hessian == HessianMode::GaussNewtonBfgs
        {
            quasi_newton_update(
                &mut bfgs,
                &s,
                settings.hessian == HessianMode::GaussNewtonBfgs,
                (&st, &trial.w, &ev_new),
                &sol.lambda,
            );
        }
        st = State {
            w: trial.w,
            ev: ev_new,
            hess: hess_new,
            plain: trial.plain,
        };
        if observer.wants_checkpoints() {
            observer.checkpoint(&SqpCheckpoint {
                version: CHECKPOINT_VERSION,
                n,
                m,
                next_iter: iter + 1,
                w: ExactVec::new(&st.w),
                lambda: ExactVec::new(&lambda),
                nu: ExactVec::new(&nu),
                scalars: ExactVec::new(&[
                    mem.lam_est,
                    mem.test_rho_scale,
                    mem.shift,
                    filter.theta_max,
                    last_step,
                    start.elapsed().as_secs_f64(),
                    nlp.integration_tolerance().unwrap_or(f64::NAN),
                ]),
                filter: ExactVec::new(
                    &filter
                        .entries
                        .iter()
                        .flat_map(|&(a, b)| [a, b])
                        .collect::<Vec<f64>>(),
                ),
                bfgs: bfgs
                    .state()
                    .into_iter()
                    .map(|(b, s)| (ExactVec::new(&b), s))
                    .collect(),
                history: history.iter().map(ExactRecord::from).collect(),
                timings: eval.timings(),
            });
        }
    }
    // an evaluation or a QP that failed because the solve was asked to stop
    if status != SqpStatus::Converged {
        status = interrupted_or(status);
    }
    let viol = violations(&st.ev.c, &s.c_lb, &s.c_ub);
    let mut order: Vec<usize> = (0..m).filter(|&i| viol[i] > settings.tol_kkt).collect();
    order.sort_by(|&a, &b| viol[b].total_cmp(&viol[a]));
    let most_violated = order
        .iter()
        .take(10)
        .map(|&i| Violation {
            name: nlp.row_name(i),
            amount: viol[i],
        })
        .collect();
    SqpResult {
        objective: st.ev.f,
        infeasibility: viol.iter().copied().fold(0.0, f64::max),
        kkt,
        status,
        history,
        most_violated,
        seconds: start.elapsed().as_secs_f64(),
        timings: eval.timings(),
        w: st.w,
        lambda,
        nu,
    }
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

/// The Gauss–Newton check of the exact mode at a point evaluated without the curvature:
/// its QP's multipliers, a record and the multipliers if they show a KKT point at
/// `settings.tol_kkt` (elastic QPs are not a KKT point's), otherwise `None`. Works on a
/// copy of the step memory, so that a point that is no KKT point goes on as if unchecked.
#[allow(clippy::too_many_arguments)]
fn gauss_newton_check(
    nlp: &dyn Nlp,
    settings: &SqpSettings,
    s: &Structure,
    st: &State,
    (lambda, nu): (&[f64], &[f64]),
    blocks: (&BlockBfgs, &BlockBfgs),
    mut mem: StepMemory,
    eval: &Evaluator<'_>,
    (iter, infeas, last_step, start): (usize, f64, f64, Instant),
) -> Option<Checked> {
    let sub = step::subproblem(nlp, settings, s, st, (lambda, nu), false, blocks, &mut mem).ok()?;
    let step = step::solve(eval, &sub, &mut mem).ok()?;
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
            nlp,
            st,
            (iter, infeas, last_step, start),
            kkt,
            (&sol, step.route),
            None,
        ),
        lambda: sol.lambda,
        nu: sol.nu,
    })
}

/// A KKT point shown by [`gauss_newton_check`]: its iteration record and the QP's
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
