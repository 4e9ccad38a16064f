//! Evaluation of the objective, the constraints and their first derivatives: the
//! intervals in parallel, then transitions, user terms, check points and sample terms
//! assembled in pattern order.

use super::sweep::{IntervalResult, SampleSums};
use super::{Evaluation, IntervalRef, TermKind, TermRef, Transcription, TranscriptionError};
use crate::integrate::{IntegrationStats, ShootingInterval};
use crate::ocp::checks::CheckValues;
use crate::ocp::problem::Block;
use rayon::prelude::*;

impl<'o, 'a> Transcription<'o, 'a> {
    /// Evaluate objective and constraints, and with `derivs` their first derivatives
    /// and the Gauss–Newton Hessian.
    pub fn evaluate(&self, w: &[f64], derivs: bool) -> Result<Evaluation, TranscriptionError> {
        self.evaluate_inner(w, derivs, None).map(|(ev, _)| ev)
    }
    /// [`evaluate`](Self::evaluate), and with the multipliers `lambda` each interval's
    /// curvature block (in interval order).
    #[allow(clippy::type_complexity)]
    pub(super) fn evaluate_inner(
        &self,
        w: &[f64],
        derivs: bool,
        lambda: Option<&[f64]>,
    ) -> Result<(Evaluation, Vec<Option<Vec<f64>>>), TranscriptionError> {
        let (lists, moves) = self.place_shifted(w)?;
        let results: Vec<_> = self
            .intervals
            .par_iter()
            .zip(&lists)
            .map(|(iv, list)| {
                self.integrate_interval(
                    iv,
                    list.as_deref().unwrap_or(&iv.samples),
                    &moves,
                    w,
                    derivs,
                    lambda,
                )
            })
            .collect();
        let mut ev = Evaluation {
            f: 0.0,
            c: vec![0.0; self.m],
            grad: if derivs {
                vec![0.0; self.n]
            } else {
                Vec::new()
            },
            jac: if derivs {
                Vec::with_capacity(self.jac_rows.len())
            } else {
                Vec::new()
            },
            gauss_newton: if derivs {
                Vec::with_capacity(self.gn_rows.len())
            } else {
                Vec::new()
            },
            stats: IntegrationStats::default(),
        };
        let out = self.add_continuity(&mut ev, w, derivs, results)?;
        self.add_transitions(&mut ev, w, derivs)?;
        self.add_terms(&mut ev, w, derivs)?;
        add_check_values(&mut ev, derivs, out.check_values);
        self.add_sample_sums(&mut ev, derivs, out.sample_sums);
        if let Ok(mut t) = self.totals.lock() {
            *t += ev.stats;
        }
        Ok((ev, out.blocks))
    }

    /// The continuity rows from the intervals' integrations `results` (Jacobian values in
    /// pattern order); what the rest of the assembly needs of them.
    fn add_continuity<'t>(
        &'t self,
        ev: &mut Evaluation,
        w: &[f64],
        derivs: bool,
        results: Vec<Result<IntervalResult, TranscriptionError>>,
    ) -> Result<IntervalOutputs<'t>, TranscriptionError> {
        let mut blocks = Vec::with_capacity(results.len());
        let mut sample_sums = Vec::new();
        let mut check_values = Vec::new();
        for (iv, r) in self.intervals.iter().zip(results) {
            let (x1, s, st, hess, sums, checks) = r?;
            blocks.push(hess);
            check_values.extend(checks);
            if let Some(sums) = sums {
                sample_sums.push((iv, sums));
            }
            ev.stats += st;
            let ph = &self.ocp.phases[iv.phase];
            let nx = ph.ode.nx();
            let next = &w[self.range(Block::State {
                phase: iv.phase,
                node: iv.k + 1,
            })];
            for i in 0..nx {
                ev.c[iv.row + i] = next[i] - x1[i];
            }
            if derivs {
                let interval = ShootingInterval::new(ph.ode, ph.controls);
                let np = interval.np();
                let hscale = 1.0 / ph.intervals as f64;
                let dur = interval.p_duration();
                // sensitivity columns in pattern order: x0, u0, [u1], T, θ
                let mut order: Vec<(usize, f64)> = (0..nx).map(|c| (c, 1.0)).collect();
                order.extend(interval.p_u0().map(|c| (nx + c, 1.0)));
                if let Some(r) = interval.p_u1() {
                    order.extend(r.map(|c| (nx + c, 1.0)));
                }
                order.push((nx + dur, hscale));
                order.extend(interval.p_theta().map(|c| (nx + c, 1.0)));
                assert_eq!(order.len(), nx + np);
                for i in 0..nx {
                    for &(c, sc) in &order {
                        ev.jac.push(-s[c * nx + i] * sc);
                    }
                    ev.jac.push(1.0);
                }
            }
        }
        Ok(IntervalOutputs {
            blocks,
            sample_sums,
            check_values,
        })
    }

    /// The transition rows, in pattern order.
    fn add_transitions(
        &self,
        ev: &mut Evaluation,
        w: &[f64],
        derivs: bool,
    ) -> Result<(), TranscriptionError> {
        for (j, tr) in self.ocp.transitions.iter().enumerate() {
            let next = &self.ocp.phases[j + 1];
            let nx1 = next.ode.nx();
            let x0: Vec<f64> = w[self.range(Block::State {
                phase: j + 1,
                node: 0,
            })]
            .to_vec();
            match tr {
                Some(term) => {
                    let t = self
                        .terms
                        .iter()
                        .find(|t| t.kind == TermKind::Transition && t.term == j)
                        .expect("transition term registered in new()");
                    let z = self.gather(w, &t.cols);
                    let mut v = vec![0.0; nx1];
                    let mut jac = vec![0.0; nx1 * z.len()];
                    eval_term(term, &z, &mut v, derivs.then_some(&mut jac[..]))?;
                    for i in 0..nx1 {
                        ev.c[t.row + i] = x0[i] - v[i];
                    }
                    if derivs {
                        self.push_transition_jac(&mut ev.jac, t, nx1, &jac);
                    }
                }
                None => {
                    let prev = &self.ocp.phases[j];
                    let xe = &w[self.range(Block::State {
                        phase: j,
                        node: prev.intervals,
                    })];
                    let row = self.transition_row(j);
                    for i in 0..nx1 {
                        ev.c[row + i] = x0[i] - xe[i];
                    }
                    if derivs {
                        ev.jac.extend(std::iter::repeat(-1.0).take(nx1));
                        ev.jac.extend(std::iter::repeat(1.0).take(nx1));
                    }
                }
            }
        }
        Ok(())
    }

    /// The user constraints and costs, in term order.
    fn add_terms(
        &self,
        ev: &mut Evaluation,
        w: &[f64],
        derivs: bool,
    ) -> Result<(), TranscriptionError> {
        for t in &self.terms {
            match t.kind {
                TermKind::Transition => {}
                TermKind::Constraint => {
                    let con = &self.ocp.constraints[t.term];
                    let d = con.term.f.dim();
                    let z = self.gather(w, &t.cols);
                    let mut jac = vec![0.0; d * z.len()];
                    eval_term(
                        &con.term,
                        &z,
                        &mut ev.c[t.row..t.row + d],
                        derivs.then_some(&mut jac[..]),
                    )?;
                    if derivs {
                        for i in 0..d {
                            for c in 0..z.len() {
                                ev.jac.push(jac[i + c * d]);
                            }
                        }
                    }
                }
                TermKind::LeastSquares => self.add_least_squares(ev, t, w, derivs)?,
                TermKind::Cost => {
                    let term = &self.ocp.costs[t.term];
                    let z = self.gather(w, &t.cols);
                    let mut v = [0.0];
                    let mut jac = vec![0.0; z.len()];
                    eval_term(term, &z, &mut v, derivs.then_some(&mut jac[..]))?;
                    ev.f += v[0];
                    if derivs {
                        for (a, &ca) in t.cols.iter().enumerate() {
                            ev.grad[ca] += jac[a];
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// The least-squares term `t`: its square sum, and with `derivs` its gradient and
    /// Gauss–Newton block.
    fn add_least_squares(
        &self,
        ev: &mut Evaluation,
        t: &TermRef,
        w: &[f64],
        derivs: bool,
    ) -> Result<(), TranscriptionError> {
        let term = &self.ocp.least_squares[t.term];
        let d = term.f.dim();
        let z = self.gather(w, &t.cols);
        let mut r = vec![0.0; d];
        let mut jac = vec![0.0; d * z.len()];
        eval_term(term, &z, &mut r, derivs.then_some(&mut jac[..]))?;
        ev.f += r.iter().map(|v| v * v).sum::<f64>();
        if derivs {
            let nz = z.len();
            for (a, &ca) in t.cols.iter().enumerate() {
                ev.grad[ca] += 2.0 * (0..d).map(|i| jac[i + a * d] * r[i]).sum::<f64>();
            }
            for a in 0..nz {
                for b in a..nz {
                    let mut v = 2.0 * (0..d).map(|i| jac[i + a * d] * jac[i + b * d]).sum::<f64>();
                    if t.cols[a] == t.cols[b] && a != b {
                        v *= 2.0;
                    }
                    ev.gauss_newton.push(v);
                }
            }
        }
        Ok(())
    }

    /// The sample terms, in interval order (their Gauss–Newton blocks follow the
    /// least-squares terms' in the pattern).
    fn add_sample_sums(
        &self,
        ev: &mut Evaluation,
        derivs: bool,
        sample_sums: Vec<(&IntervalRef, SampleSums)>,
    ) {
        for (iv, sums) in sample_sums {
            ev.f += sums.f;
            if derivs {
                let cols = self.interval_cols(iv.phase, iv.k);
                for (&c, g) in cols.iter().zip(&sums.grad) {
                    ev.grad[c] += g;
                }
                ev.gauss_newton.extend_from_slice(&sums.gauss_newton);
            }
        }
    }

    fn transition_row(&self, j: usize) -> usize {
        let cont: usize = self
            .ocp
            .phases
            .iter()
            .map(|p| p.intervals * p.ode.nx())
            .sum();
        cont + (0..j)
            .map(|i| self.ocp.phases[i + 1].ode.nx())
            .sum::<usize>()
    }

    fn push_transition_jac(&self, jac_out: &mut Vec<f64>, t: &TermRef, nx1: usize, jac: &[f64]) {
        for i in 0..nx1 {
            for c in 0..t.cols.len() {
                jac_out.push(-jac[i + c * nx1]);
            }
        }
        for _ in 0..nx1 {
            jac_out.push(1.0);
        }
    }
}

/// Evaluate `term` at `z` into `out`, with its Jacobian into `jac` when given; a failure
/// names the term.
fn eval_term(
    term: &crate::ocp::Term<'_>,
    z: &[f64],
    out: &mut [f64],
    jac: Option<&mut [f64]>,
) -> Result<(), TranscriptionError> {
    term.f
        .eval(z, out, jac)
        .map_err(|source| TranscriptionError::Term {
            term: term.name.clone(),
            source,
        })
}

/// The check points, in row order (after the user constraints in the pattern).
fn add_check_values(ev: &mut Evaluation, derivs: bool, check_values: Vec<CheckValues>) {
    for cv in check_values {
        let d = cv.values.len();
        ev.c[cv.row..cv.row + d].copy_from_slice(&cv.values);
        if derivs {
            let ncols = cv.jac.len() / d.max(1);
            for i in 0..d {
                ev.jac.extend((0..ncols).map(|c| cv.jac[i + c * d]));
            }
        }
    }
}

/// What the intervals' integrations leave for the assembly after the continuity rows:
/// their curvature blocks (in interval order), their sample terms' sums and their check
/// points' values.
struct IntervalOutputs<'t> {
    blocks: Vec<Option<Vec<f64>>>,
    sample_sums: Vec<(&'t IntervalRef, SampleSums)>,
    check_values: Vec<CheckValues>,
}
