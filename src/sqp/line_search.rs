//! Filter line search (Wächter & Biegler 2006) with a second-order correction.
//!
//! A trial point is accepted when it sufficiently reduces the objective (an f-type step:
//! the step is a descent direction and the violation is small, so Armijo decides) or the
//! l1 constraint violation, and is not dominated by the filter of earlier (violation,
//! objective) pairs. Trial points are plain evaluations (no derivatives). When the full
//! step is rejected, one second-order correction re-solves the QP with the constraint
//! values at `w + d`; then the step is halved. A recoverable evaluation failure at a
//! trial point counts as a rejection (the step is shortened); a fatal one ends the search.

use super::iterate::{State, Structure};
use super::{violations, EvalError, NlpEval, SqpSettings};

/// Margin of the violation in the filter and the h-type test (γ_θ).
const GAMMA_THETA: f64 = 1e-5;
/// Margin of the objective in the filter and the h-type test (γ_f).
const GAMMA_F: f64 = 1e-5;
/// Switching condition `α (−∇fᵀd)^{s_f} > δ θ₀^{s_θ}`: δ.
const DELTA: f64 = 1.0;
/// Switching condition: exponent s_θ of the violation.
const S_THETA: f64 = 1.1;
/// Switching condition: exponent s_f of the descent.
const S_F: f64 = 2.3;

/// The filter: (l1 violation, objective) pairs no accepted point may be dominated by,
/// and the largest violation θ_max accepted at all. Kept for the whole solve (and in
/// checkpoints).
#[derive(Debug, Clone)]
pub(super) struct Filter {
    /// (violation, objective) pairs, oldest first.
    pub(super) entries: Vec<(f64, f64)>,
    /// Largest acceptable l1 violation; infinity until the first line search.
    pub(super) theta_max: f64,
}

/// The point a line search starts from.
struct Reference {
    /// Objective (plain evaluation).
    f0: f64,
    /// l1 violation (plain evaluation).
    theta0: f64,
    /// Directional derivative ∇fᵀd.
    grad_d: f64,
    /// Armijo constant.
    eta: f64,
}

impl Filter {
    /// An empty filter; the first line search sets θ_max.
    pub(super) fn new() -> Self {
        Self {
            entries: Vec::new(),
            theta_max: f64::INFINITY,
        }
    }

    /// At the first line search: θ_max = max(10⁴, 1.2 θ₀), or max(1, k·θ₀) with the
    /// violation growth cap `k` ([`SqpSettings::violation_growth`]); the filter's first
    /// entry.
    fn start(&mut self, theta0: f64, growth: Option<f64>) {
        if self.entries.is_empty() {
            self.theta_max = match growth {
                Some(k) => (1.0f64).max(k * theta0),
                None => (1e4f64).max(1.2 * theta0),
            };
            self.entries.push((self.theta_max, f64::NEG_INFINITY));
        }
    }

    /// Add the margin-shifted start point of an accepted h-type step.
    pub(super) fn augment(&mut self, theta0: f64, f0: f64) {
        self.entries
            .push(((1.0 - GAMMA_THETA) * theta0, f0 - GAMMA_F * theta0));
    }

    /// Whether a trial point (objective `f`, l1 violation `th`, step length `a`) is
    /// acceptable: `None` if not; `Some(true)` for an h-type step (the filter is
    /// augmented once it is taken), `Some(false)` for an f-type step (it is not).
    fn acceptable(&self, r: &Reference, f: f64, th: f64, a: f64) -> Option<bool> {
        if !f.is_finite() || !th.is_finite() || th > self.theta_max {
            return None;
        }
        if self.entries.iter().any(|&(ft, ff)| th >= ft && f >= ff) {
            return None;
        }
        let switching =
            r.grad_d < 0.0 && a * (-r.grad_d).powf(S_F) > DELTA * r.theta0.powf(S_THETA);
        if switching && r.theta0 <= 1e-4 * self.theta_max.max(1.0) {
            // f-type step: Armijo on the objective, the filter is not augmented
            (f <= r.f0 + r.eta * a * r.grad_d).then_some(false)
        } else if th <= (1.0 - GAMMA_THETA) * r.theta0 || f <= r.f0 - GAMMA_F * r.theta0 {
            Some(true)
        } else {
            None
        }
    }
}

/// An accepted trial point.
#[derive(Debug)]
pub(super) struct Trial {
    /// The point (clipped into the bounds).
    pub(super) w: Vec<f64>,
    /// The step length reported for it: the accepted α; 0.5 when the second-order
    /// correction was accepted (the length the backtracking would have tried next).
    pub(super) step: f64,
    /// Whether the filter is to be augmented (h-type step).
    pub(super) augment: bool,
    /// Objective and l1 violation of its plain evaluation.
    pub(super) plain: (f64, f64),
}

/// How a line search ended.
#[derive(Debug)]
pub(super) enum Search {
    /// A point was accepted.
    Accepted(Trial),
    /// Every trial down to the smallest step was rejected.
    Failed,
    /// A trial point's evaluation failed fatally.
    Fatal(EvalError),
}

/// An acceptable trial point's verdict: whether to augment the filter, and its
/// (objective, l1 violation).
type Verdict = (bool, (f64, f64));

/// Keep the first fatal evaluation failure of a line search; recoverable ones only
/// shorten the step.
fn keep_fatal(slot: &mut Option<EvalError>, e: EvalError) {
    if !e.is_recoverable() && slot.is_none() {
        *slot = Some(e);
    }
}

/// Search along `d` from `st`, whose plain evaluation's objective and l1 violation are
/// `plain` (the reference; `st.plain` unless the integration changed since): `eval` is the
/// plain evaluation of a trial point, `soc` the second-order correction step for
/// corrected constraint values `c(w + d) − J d` (`None` if its QP fails). Starts the
/// filter at the first call; the caller augments it once the point is taken.
#[allow(clippy::too_many_arguments)]
pub(super) fn search(
    s: &Structure,
    settings: &SqpSettings,
    filter: &mut Filter,
    (st, plain): (&State, (f64, f64)),
    d: &[f64],
    max_step: f64,
    eval: &dyn Fn(&[f64]) -> Result<NlpEval, EvalError>,
    soc: &dyn Fn(&[f64]) -> Option<Vec<f64>>,
) -> Search {
    let (n, m) = (s.n, s.m);
    let theta0 = plain.1;
    filter.start(theta0, settings.violation_growth);
    let filter: &Filter = filter;
    let r = Reference {
        f0: plain.0,
        theta0,
        grad_d: st.ev.grad.iter().zip(d).map(|(a, b)| a * b).sum(),
        eta: settings.line_search_armijo,
    };
    let judge = |ev: &NlpEval, a: f64| -> Option<Verdict> {
        let th = violations(&ev.c, &s.c_lb, &s.c_ub).iter().sum::<f64>();
        filter
            .acceptable(&r, ev.f, th, a)
            .map(|augment| (augment, (ev.f, th)))
    };
    let trial = |a: f64, dir: &[f64]| -> Vec<f64> {
        (0..n)
            .map(|i| (st.w[i] + a * dir[i]).max(s.w_lb[i]).min(s.w_ub[i]))
            .collect()
    };
    let mut alpha = max_step.min(1.0);
    let mut found: Option<(Vec<f64>, Verdict)> = None;
    let mut fatal: Option<EvalError> = None;
    // the full step and its second-order correction, unless a shorter step is asked for
    // (a point of an earlier search was rejected)
    if alpha >= 1.0 {
        let w1 = trial(1.0, d);
        match eval(&w1) {
            Ok(ev1) => match judge(&ev1, 1.0) {
                Some(j) => found = Some((w1, j)),
                None => {
                    // second-order correction: re-solve with the constraint values at w + d
                    let mut jd = vec![0.0; m];
                    for k in 0..s.jac_rows.len() {
                        jd[s.jac_rows[k]] += st.ev.jac[k] * d[s.jac_cols[k]];
                    }
                    let c_soc: Vec<f64> = (0..m).map(|i| ev1.c[i] - jd[i]).collect();
                    if let Some(d2) = soc(&c_soc) {
                        let w2 = trial(1.0, &d2);
                        match eval(&w2) {
                            Ok(ev2) => {
                                if let Some(j) = judge(&ev2, 1.0) {
                                    found = Some((w2, j));
                                }
                            }
                            Err(e) => keep_fatal(&mut fatal, e),
                        }
                    }
                    alpha = 0.5;
                }
            },
            Err(e) => {
                keep_fatal(&mut fatal, e);
                alpha = 0.5;
            }
        }
    }
    while found.is_none() && fatal.is_none() && alpha >= settings.line_search_min_step {
        let wa = trial(alpha, d);
        match eval(&wa) {
            Ok(eva) => {
                if let Some(j) = judge(&eva, alpha) {
                    found = Some((wa, j));
                    break;
                }
            }
            Err(e) => keep_fatal(&mut fatal, e),
        }
        alpha *= 0.5;
    }
    if let Some(e) = fatal {
        return Search::Fatal(e);
    }
    match found {
        Some((w, (augment, plain))) => Search::Accepted(Trial {
            w,
            step: alpha,
            augment,
            plain,
        }),
        None => Search::Failed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sqp::qp::{self, QpData, Triplets};
    use crate::sqp::NlpEval;
    use std::cell::{Cell, RefCell};

    /// One variable x ∈ [−10, 10] and one equality row c(x) = x − 1 = 0, objective
    /// `f(x)`; the state at `x0` with J = 1.
    fn structure(m: usize) -> Structure {
        Structure {
            n: 1,
            m,
            w_lb: vec![-10.0],
            w_ub: vec![10.0],
            c_lb: vec![0.0; m],
            c_ub: vec![0.0; m],
            jac_rows: vec![0; m],
            jac_cols: vec![0; m],
            ..Structure::default()
        }
    }

    fn eval_at(f: fn(f64) -> f64, m: usize, x: f64) -> NlpEval {
        NlpEval {
            f: f(x),
            c: vec![x - 1.0; m],
            ..NlpEval::default()
        }
    }

    fn state(f: fn(f64) -> f64, grad: f64, m: usize, x0: f64) -> State {
        let ev = NlpEval {
            grad: vec![grad],
            jac: vec![1.0; m],
            ..eval_at(f, m, x0)
        };
        let plain = (ev.f, ev.c.iter().map(|v| v.abs()).sum());
        State {
            w: vec![x0],
            ev,
            hess: None,
            plain,
        }
    }

    fn settings() -> SqpSettings {
        SqpSettings::default()
    }

    fn zero(_: f64) -> f64 {
        0.0
    }

    /// Search along `d` from x = 0 with objective `f` (gradient `grad` there) and `m`
    /// rows x − 1 = 0; the outcome and the number of trial evaluations.
    fn run(
        f: fn(f64) -> f64,
        grad: f64,
        m: usize,
        d: f64,
        filter: &mut Filter,
        soc: &dyn Fn(&[f64]) -> Option<Vec<f64>>,
    ) -> (Search, usize) {
        let s = structure(m);
        let st = state(f, grad, m, 0.0);
        let evals = Cell::new(0);
        let eval = |w: &[f64]| {
            evals.set(evals.get() + 1);
            Ok(eval_at(f, m, w[0]))
        };
        let out = search(
            &s,
            &settings(),
            filter,
            (&st, st.plain),
            &[d],
            1.0,
            &eval,
            soc,
        );
        (out, evals.get())
    }

    /// From x = 0 (θ = 1) the Newton step d = 1 reaches the feasible x = 1 (θ = 0): an
    /// h-type step at α = 1; the first search sets θ_max = 10⁴.
    #[test]
    fn a_full_step_that_reduces_the_violation_is_accepted() {
        let mut filter = Filter::new();
        let (out, evals) = run(zero, 0.0, 1, 1.0, &mut filter, &|_| {
            panic!("no second-order correction for an accepted full step")
        });
        let Search::Accepted(t) = out else {
            panic!("{out:?}")
        };
        assert_eq!(
            (t.w, t.step, t.augment, t.plain),
            (vec![1.0], 1.0, true, (0.0, 0.0))
        );
        assert_eq!(evals, 1);
        assert_eq!(filter.theta_max, 1e4);
        assert_eq!(filter.entries, vec![(1e4, f64::NEG_INFINITY)]);
    }

    /// From x = 0 the step d = 3 overshoots to x = 3 (θ = 2 > θ₀ = 1, f unchanged): it
    /// is rejected; the correction gets c(w + d) − J d = 2 − 3 = −1, and its QP
    /// (min ½ d² s.t. d − 1 = 0 after the shift) gives d = 1, the feasible x = 1,
    /// accepted with the reported step 0.5.
    #[test]
    fn a_rejected_full_step_is_rescued_by_the_second_order_correction() {
        let seen = RefCell::new(Vec::new());
        let one = Triplets {
            rows: vec![0],
            cols: vec![0],
            vals: vec![1.0],
        };
        let soc = |c_soc: &[f64]| {
            seen.borrow_mut().push(c_soc.to_vec());
            qp::solve(&QpData {
                h: &one,
                g: &[0.0],
                jac: &one,
                c: c_soc,
                c_lb: &[0.0],
                c_ub: &[0.0],
                d_lb: &[-10.0],
                d_ub: &[10.0],
                elastic: None,
                elastic_weights: &[1.0],
                hint: None,
            })
            .ok()
            .map(|q| q.d)
        };
        let (out, evals) = run(zero, 0.0, 1, 3.0, &mut Filter::new(), &soc);
        assert_eq!(*seen.borrow(), vec![vec![-1.0]]);
        let Search::Accepted(t) = out else {
            panic!("{out:?}")
        };
        assert!((t.w[0] - 1.0).abs() < 1e-7, "{:?}", t.w);
        assert_eq!((t.step, t.augment, evals), (0.5, true, 2));
    }

    /// From x = 0 the step d = −1 raises the violation at every length (θ = 1 + α) and
    /// the objective x² too: every trial is rejected down to the smallest step, after
    /// one correction that does not help either.
    #[test]
    fn a_step_that_worsens_both_measures_fails() {
        fn sq(x: f64) -> f64 {
            x * x
        }
        let (out, evals) = run(sq, 0.0, 1, -1.0, &mut Filter::new(), &|_| Some(vec![-1.0]));
        assert!(matches!(out, Search::Failed), "{out:?}");
        // α = 1, the correction, then 0.5, 0.25, … down to the last α ≥ 10⁻¹⁰ (2⁻³³)
        assert_eq!(evals, 2 + 33);
    }

    /// Unconstrained f(x) = (x − 1)² from x = 0 (f₀ = 1, ∇f = −2) along d = 2: θ₀ = 0,
    /// so steps are f-type. α = 1 gives f = 1, no Armijo decrease, rejected (no
    /// correction QP: it fails); α = 0.5 gives f = 0 ≤ 1 − 10⁻⁴·0.5·4, accepted
    /// without augmenting the filter.
    #[test]
    fn an_f_type_step_is_judged_by_armijo_and_does_not_augment_the_filter() {
        fn f(x: f64) -> f64 {
            (x - 1.0) * (x - 1.0)
        }
        let mut filter = Filter::new();
        let (out, _) = run(f, -2.0, 0, 2.0, &mut filter, &|c| {
            assert!(c.is_empty());
            None
        });
        let Search::Accepted(t) = out else {
            panic!("{out:?}")
        };
        assert_eq!(
            (t.w, t.step, t.augment, t.plain),
            (vec![1.0], 0.5, false, (0.0, 0.0))
        );
        assert_eq!(filter.entries.len(), 1);
    }

    /// A recoverable failure beyond x = 0.6 shortens the step d = 1 to α = 0.5; a fatal
    /// one there ends the search with it.
    #[test]
    fn evaluation_failures_shorten_the_step_or_end_the_search() {
        let s = structure(1);
        let st = state(zero, 0.0, 1, 0.0);
        let run = |fatal: bool| {
            search(
                &s,
                &settings(),
                &mut Filter::new(),
                (&st, st.plain),
                &[1.0],
                1.0,
                &|w| {
                    if w[0] > 0.6 {
                        Err(if fatal {
                            EvalError::fatal("broken")
                        } else {
                            EvalError::recoverable("too far")
                        })
                    } else {
                        Ok(eval_at(zero, 1, w[0]))
                    }
                },
                &|_| panic!("no correction after a failed evaluation"),
            )
        };
        let Search::Accepted(t) = run(false) else {
            panic!("recoverable")
        };
        assert_eq!((t.w, t.step, t.augment), (vec![0.5], 0.5, true));
        assert!(matches!(run(true), Search::Fatal(EvalError::Fatal(_))));
    }

    /// With the violation growth cap k = 10, a search from θ₀ = 0.05 (x = 0.95, row
    /// x − 1 = 0) along d = 3 with f = −10x falling steeply refuses the full step
    /// (θ = 2.95 above θ_max = max(1, 10·0.05) = 1) and the half step (θ = 1.45), and takes
    /// α = 1/4 (θ = 0.7, f from −9.5 to −17). Without the cap θ_max = 10⁴ and the full
    /// step is taken.
    #[test]
    fn the_violation_growth_cap_shortens_a_step_that_leaves_the_linearisation() {
        fn falling(x: f64) -> f64 {
            -10.0 * x
        }
        let s = structure(1);
        let st = state(falling, -10.0, 1, 0.95);
        let eval = |w: &[f64]| Ok(eval_at(falling, 1, w[0]));
        let no_soc = |_: &[f64]| None;
        for (growth, step, theta_max) in [(Some(10.0), 0.25, 1.0), (None, 1.0, 1e4)] {
            let settings = SqpSettings {
                violation_growth: growth,
                ..settings()
            };
            let mut filter = Filter::new();
            let out = search(
                &s,
                &settings,
                &mut filter,
                (&st, st.plain),
                &[3.0],
                1.0,
                &eval,
                &no_soc,
            );
            let Search::Accepted(t) = out else {
                panic!("{growth:?}: {out:?}")
            };
            assert_eq!(t.step, step, "{growth:?}");
            assert!(
                (t.w[0] - (0.95 + 3.0 * step)).abs() < 1e-15,
                "{growth:?}: {:?}",
                t.w
            );
            assert_eq!(filter.theta_max, theta_max, "{growth:?}");
        }
        // far from feasibility the cap is k·θ₀
        let mut filter = Filter::new();
        filter.start(500.0, Some(10.0));
        assert_eq!(filter.theta_max, 5000.0);
    }

    /// A point the filter dominates is rejected even if it reduces the violation.
    #[test]
    fn the_filter_rejects_dominated_points() {
        let r = Reference {
            f0: 0.0,
            theta0: 1.0,
            grad_d: 0.0,
            eta: 1e-4,
        };
        let mut filter = Filter::new();
        filter.start(1.0, None);
        assert_eq!(filter.acceptable(&r, 0.0, 0.5, 1.0), Some(true));
        filter.augment(0.4, 0.0);
        // the entry (0.4·(1 − 10⁻⁵), −0.4·10⁻⁵) dominates (0.5, 0), not (0.5, −10⁻³)
        assert_eq!(filter.acceptable(&r, 0.0, 0.5, 1.0), None);
        assert_eq!(filter.acceptable(&r, -1e-3, 0.5, 1.0), Some(true));
        // above θ_max = 10⁴: never
        assert_eq!(filter.acceptable(&r, -1e9, 2e4, 1.0), None);
    }
}
