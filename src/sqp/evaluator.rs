//! The NLP evaluations and QP solves of one solve, timed and counted for
//! [`SqpTimings`], with the test-only injected QP failures
//! ([`SqpSettings::inject_qp_failures`]).

use super::qp::{self, QpData, QpError, QpSolution, Triplets};
use super::{EvalError, HessianMode, Nlp, NlpEval, SqpSettings, SqpTimings};
use std::cell::Cell;
use std::time::Instant;

/// Every call the SQP makes to the NLP and to Clarabel goes through this, so the time
/// split and the QP count (which numbers the injected failures) see all of them.
pub(super) struct Evaluator<'a> {
    nlp: &'a dyn Nlp,
    /// [`HessianMode::Exact`]: derivatives come with the constraint curvature.
    exact: bool,
    inject_qp_failures: &'a [usize],
    timings: Cell<SqpTimings>,
}

impl<'a> Evaluator<'a> {
    /// Count from `timings` (zero, or a resumed solve's split so far).
    pub(super) fn new(nlp: &'a dyn Nlp, settings: &'a SqpSettings, timings: SqpTimings) -> Self {
        Self {
            nlp,
            exact: settings.hessian == HessianMode::Exact,
            inject_qp_failures: &settings.inject_qp_failures,
            timings: Cell::new(timings),
        }
    }

    /// The time split so far.
    pub(super) fn timings(&self) -> SqpTimings {
        self.timings.get()
    }

    fn timed(&self, eval: bool, f: &mut dyn FnMut()) {
        let t = Instant::now();
        f();
        let mut tm = self.timings.get();
        if eval {
            tm.evaluation_s += t.elapsed().as_secs_f64();
            tm.evaluations += 1;
        } else {
            tm.qp_s += t.elapsed().as_secs_f64();
            tm.qp_solves += 1;
        }
        self.timings.set(tm);
    }

    /// Objective and constraints at `w`, without derivatives (a trial point).
    pub(super) fn plain(&self, w: &[f64]) -> Result<NlpEval, EvalError> {
        let mut r = Err(EvalError::fatal("not evaluated"));
        if crate::interrupt::stop_now() {
            return Err(EvalError::fatal(crate::interrupt::STOPPED));
        }
        self.timed(true, &mut || r = self.nlp.evaluate(w, false));
        stopped(r)
    }

    /// Derivatives at `w`; in Exact mode with `curvature`, also the constraint curvature
    /// for the multipliers `lam` (a compliant foot's costs about seven evaluations
    /// without it, so its Gauss–Newton steps of the exact mode go without,
    /// [`on_demand`](Self::on_demand)).
    pub(super) fn derivs(
        &self,
        w: &[f64],
        lam: &[f64],
        curvature: bool,
    ) -> Result<(NlpEval, Option<Triplets>), EvalError> {
        let mut out = Err(EvalError::fatal("not evaluated"));
        if crate::interrupt::stop_now() {
            return Err(EvalError::fatal(crate::interrupt::STOPPED));
        }
        self.timed(true, &mut || {
            out = if self.exact && curvature {
                self.nlp
                    .evaluate_with_hessian(w, lam)
                    .map(|(ev, (r, c, v))| {
                        (
                            ev,
                            Some(Triplets {
                                rows: r,
                                cols: c,
                                vals: v,
                            }),
                        )
                    })
            } else {
                self.nlp.evaluate(w, true).map(|ev| (ev, None))
            }
        });
        stopped(out)
    }

    /// Whether derivatives can come with the constraint curvature (Exact mode).
    pub(super) fn exact(&self) -> bool {
        self.exact
    }

    /// Whether the curvature is computed only where a step uses it
    /// ([`Nlp::curvature_on_demand`]); otherwise at every accepted point.
    pub(super) fn on_demand(&self) -> bool {
        self.exact && self.nlp.curvature_on_demand()
    }

    /// Solve a QP with Clarabel (or fail it, if its number is one of the injected ones).
    pub(super) fn qp(&self, d: &QpData<'_>) -> Result<QpSolution, QpError> {
        let mut r = Err(QpError::Failed(String::new()));
        if self
            .inject_qp_failures
            .contains(&self.timings.get().qp_solves)
        {
            self.timed(false, &mut || {
                r = Err(QpError::Failed("NumericalError (injected)".into()))
            });
            return r;
        }
        self.timed(false, &mut || r = qp::solve(d));
        r
    }
}

/// An evaluation that failed because the solve was asked to stop, as a fatal failure: the
/// line search does not step around it.
fn stopped<T>(r: Result<T, EvalError>) -> Result<T, EvalError> {
    match r {
        Err(_) if crate::interrupt::stop_now() => Err(EvalError::fatal(crate::interrupt::STOPPED)),
        r => r,
    }
}
