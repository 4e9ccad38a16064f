//! The transcription as the [`Nlp`](crate::sqp::Nlp) the SQP solves.

use super::{TermKind, Transcription};
use crate::sqp::EvalError;

impl crate::sqp::Nlp for Transcription<'_, '_> {
    fn n(&self) -> usize {
        self.n
    }
    fn m(&self) -> usize {
        self.m
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        let (wl, wu, _) = self.variable_bounds_and_guess();
        let (cl, cu) = self.constraint_bounds();
        (wl, wu, cl, cu)
    }
    fn jacobian_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        (self.jac_rows.clone(), self.jac_cols.clone())
    }
    fn gauss_newton_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        (self.gn_rows.clone(), self.gn_cols.clone())
    }
    fn hessian_blocks(&self) -> Vec<Vec<usize>> {
        Transcription::hessian_blocks(self)
    }
    fn evaluate(&self, w: &[f64], derivs: bool) -> Result<crate::sqp::NlpEval, EvalError> {
        let ev = Transcription::evaluate(self, w, derivs)?;
        Ok(crate::sqp::NlpEval {
            f: ev.f,
            c: ev.c,
            grad: ev.grad,
            jac: ev.jac,
            gn: ev.gauss_newton,
        })
    }
    fn integration_tolerance(&self) -> Option<f64> {
        Some(Transcription::integration_tolerance(self))
    }
    fn set_integration_tolerance(&self, rtol: f64) {
        Transcription::set_integration_tolerance(self, rtol);
    }
    fn curvature_on_demand(&self) -> bool {
        self.ocp.phases.iter().any(|p| p.ode.stiff_transition())
    }
    fn elastic_weights(&self) -> Vec<f64> {
        let dynamics = self
            .ocp
            .phases
            .iter()
            .map(|p| p.intervals * p.ode.nx())
            .sum::<usize>()
            + self
                .ocp
                .phases
                .iter()
                .skip(1)
                .map(|p| p.ode.nx())
                .sum::<usize>();
        (0..self.m)
            .map(|i| if i < dynamics { 10.0 } else { 1.0 })
            .collect()
    }
    fn evaluate_with_hessian(
        &self,
        w: &[f64],
        lambda: &[f64],
    ) -> Result<(crate::sqp::NlpEval, (Vec<usize>, Vec<usize>, Vec<f64>)), EvalError> {
        let (ev, h) = Transcription::evaluate_with_hessian(self, w, lambda)?;
        Ok((
            crate::sqp::NlpEval {
                f: ev.f,
                c: ev.c,
                grad: ev.grad,
                jac: ev.jac,
                gn: ev.gauss_newton,
            },
            h,
        ))
    }
    fn rows_with_exact_hessian(&self) -> Vec<bool> {
        let mut rows = vec![false; self.m];
        for t in &self.terms {
            let (f, dim) = match t.kind {
                TermKind::Transition => match &self.ocp.transitions[t.term] {
                    Some(term) => (&term.f, term.f.dim()),
                    None => continue,
                },
                TermKind::Constraint => (
                    &self.ocp.constraints[t.term].term.f,
                    self.ocp.constraints[t.term].term.f.dim(),
                ),
                _ => continue,
            };
            if f.has_hessian() {
                rows[t.row..t.row + dim].iter_mut().for_each(|r| *r = true);
            }
        }
        rows
    }
    fn exact_hessian(
        &self,
        w: &[f64],
        lambda: &[f64],
    ) -> Result<(Vec<usize>, Vec<usize>, Vec<f64>), EvalError> {
        Ok(self.term_curvature(w, lambda, false)?)
    }
    fn row_name(&self, i: usize) -> String {
        let l = &self.labels[i];
        format!("phase '{}', node {}, {}", l.phase, l.node, l.name)
    }
}
