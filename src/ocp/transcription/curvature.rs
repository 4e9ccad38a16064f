//! Exact second derivatives: the intervals' curvature blocks mapped to NLP columns, and
//! the curvature of the terms that provide it.

use super::{Evaluation, TermKind, TermRef, Transcription, TranscriptionError};
use crate::integrate::{ControlShape, ShootingInterval};
use crate::ocp::problem::{Block, NodeFunction};
use rayon::prelude::*;

impl<'o, 'a> Transcription<'o, 'a> {
    /// Evaluate with derivatives and the exact curvature `Σ λ_i ∇²c_i` of the continuity
    /// rows (from interval Hessians) and of the terms that provide it, as upper-triangle
    /// triplets `(rows, cols, vals)`.
    #[allow(clippy::type_complexity)]
    pub fn evaluate_with_hessian(
        &self,
        w: &[f64],
        lambda: &[f64],
    ) -> Result<(Evaluation, (Vec<usize>, Vec<usize>, Vec<f64>)), TranscriptionError> {
        let (ev, blocks) = self.evaluate_inner(w, true, Some(lambda))?;
        let (mut rows, mut cols, mut vals) = self.term_curvature(w, lambda, true)?;
        for (iv, h) in self.intervals.iter().zip(blocks) {
            let Some(h) = h else { continue };
            let ph = &self.ocp.phases[iv.phase];
            let interval = ShootingInterval::new(ph.ode, ph.controls);
            let nx = ph.ode.nx();
            let nz = nx + interval.np();
            // z order: x0, u0, [u1], h, θ  → NLP columns (h = T/N)
            let mut map: Vec<(usize, f64)> = self
                .range(Block::State {
                    phase: iv.phase,
                    node: iv.k,
                })
                .map(|c| (c, 1.0))
                .collect();
            map.extend(
                self.range(Block::Control {
                    phase: iv.phase,
                    node: iv.k,
                })
                .map(|c| (c, 1.0)),
            );
            if ph.controls == ControlShape::Linear {
                map.extend(
                    self.range(Block::Control {
                        phase: iv.phase,
                        node: iv.k + 1,
                    })
                    .map(|c| (c, 1.0)),
                );
            }
            map.push((self.duration_off[iv.phase], 1.0 / ph.intervals as f64));
            map.extend(self.range(Block::Params).map(|c| (c, 1.0)));
            assert_eq!(map.len(), nz);
            for a in 0..nz {
                for b in a..nz {
                    let (ca, sa) = map[a];
                    let (cb, sb) = map[b];
                    let mut v = h[a + b * nz] * sa * sb;
                    if ca == cb && a != b {
                        v *= 2.0;
                    }
                    if v != 0.0 {
                        rows.push(ca.min(cb));
                        cols.push(ca.max(cb));
                        vals.push(v);
                    }
                }
            }
        }
        Ok((ev, (rows, cols, vals)))
    }

    /// Exact curvature of the terms that provide it, as upper-triangle triplets: of the
    /// constraints and transitions `Σ λ_i ∇²c_i`, and with `objective` also of the
    /// objective (`2 Σ r_i ∇²r_i` of least-squares terms, whose `2 JᵀJ` part is the
    /// Gauss–Newton matrix, and `∇²f` of general costs). Terms are evaluated in parallel
    /// and assembled in term order, so the result does not depend on the thread count. A
    /// failure names its term.
    #[allow(clippy::type_complexity)]
    pub(super) fn term_curvature(
        &self,
        w: &[f64],
        lambda: &[f64],
        objective: bool,
    ) -> Result<(Vec<usize>, Vec<usize>, Vec<f64>), TranscriptionError> {
        let blocks: Vec<Result<Option<(&TermRef, Vec<f64>)>, TranscriptionError>> = self
            .terms
            .par_iter()
            .map(|t| {
                let z = self.gather(w, &t.cols);
                // transitions are written x0 − ψ(z): their curvature enters with −λ
                let (f, name, weights): (&dyn NodeFunction, &str, Vec<f64>) = match t.kind {
                    TermKind::Transition => match &self.ocp.transitions[t.term] {
                        Some(term) => (
                            &*term.f,
                            &term.name,
                            (0..term.f.dim()).map(|i| -lambda[t.row + i]).collect(),
                        ),
                        None => return Ok(None),
                    },
                    TermKind::Constraint => {
                        let term = &self.ocp.constraints[t.term].term;
                        (
                            &*term.f,
                            &term.name,
                            (0..term.f.dim()).map(|i| lambda[t.row + i]).collect(),
                        )
                    }
                    TermKind::LeastSquares if objective => {
                        let term = &self.ocp.least_squares[t.term];
                        if !term.f.has_hessian() {
                            return Ok(None);
                        }
                        let mut r = vec![0.0; term.f.dim()];
                        term.f
                            .eval(&z, &mut r, None)
                            .map_err(TranscriptionError::of_term(&term.name))?;
                        (&*term.f, &term.name, r.iter().map(|v| 2.0 * v).collect())
                    }
                    TermKind::Cost if objective => {
                        let term = &self.ocp.costs[t.term];
                        (&*term.f, &term.name, vec![1.0])
                    }
                    _ => return Ok(None),
                };
                if !f.has_hessian() || weights.iter().all(|v| *v == 0.0) {
                    return Ok(None);
                }
                let nz = z.len();
                let mut hm = vec![0.0; nz * nz];
                f.weighted_hessian(&z, &weights, &mut hm)
                    .map_err(TranscriptionError::of_term(name))?;
                Ok(Some((t, hm)))
            })
            .collect();
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        for b in blocks {
            let Some((t, hm)) = b? else { continue };
            let nz = t.cols.len();
            for a in 0..nz {
                for b in a..nz {
                    let mut v = hm[a + b * nz];
                    if v == 0.0 {
                        continue;
                    }
                    if t.cols[a] == t.cols[b] && a != b {
                        v *= 2.0;
                    }
                    rows.push(t.cols[a].min(t.cols[b]));
                    cols.push(t.cols[a].max(t.cols[b]));
                    vals.push(v);
                }
            }
        }
        Ok((rows, cols, vals))
    }
}
