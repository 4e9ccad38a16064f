//! The tracking OCP and its data residuals: rows per node and sample, the OCP with its
//! node-wise least-squares terms.

use super::{SampleTarget, TrackingSetup};
use crate::model::{ConstraintSet, GaitModel};
use crate::ocp::{Block, NodeFunction, Ocp, SampleTerm, Term};
use crate::problems::gait::GaitCycle;
use crate::problems::tracking::{ForceClockShift, NodeTarget, TrackingResidual, TrackingWeights};
use std::sync::Arc;

impl TrackingSetup {
    /// The residual of `target` on contact set `set`, with the measured loads (for their
    /// force and CoP rows) when `with_loads`.
    pub(super) fn residual<'m>(
        &self,
        model: &'m GaitModel,
        set: &ConstraintSet,
        target: NodeTarget,
        with_loads: bool,
    ) -> TrackingResidual<'m> {
        self.residual_weighted(model, set, target, self.weights.clone(), with_loads)
    }

    /// As [`residual`](Self::residual), with `weights` instead of the setup's.
    fn residual_weighted<'m>(
        &self,
        model: &'m GaitModel,
        set: &ConstraintSet,
        target: NodeTarget,
        weights: TrackingWeights,
        with_loads: bool,
    ) -> TrackingResidual<'m> {
        TrackingResidual::new(
            model,
            set.clone(),
            target,
            weights,
            with_loads.then(|| self.measured.clone()),
        )
    }

    /// Number of data residuals (angles, velocities, forces and CoP at the nodes or
    /// samples; not the regularisation of excitations and activations): the count the
    /// residual mean square `J / N` divides by. A force sample weighted by its sample
    /// period ([`SampleTarget::load_weight`](super::SampleTarget::load_weight)) counts
    /// by that weight, so that forces recorded ten times faster, each weighing a tenth,
    /// neither lower the mean square nor add information the weights do not give them.
    pub fn data_rows(
        &self,
        model: &GaitModel,
        sets: &[ConstraintSet],
        continuous: &[usize],
    ) -> usize {
        let mut n = 0;
        for (j, tg) in self.targets.iter().enumerate() {
            let last = j + 1 == self.targets.len();
            for (k, target) in tg.iter().enumerate() {
                if k + 1 == tg.len() && !last {
                    continue;
                }
                let r = self.residual(model, &sets[continuous[j]], target.clone(), false);
                n += crate::problems::GenericFunction::dim(&r) - model.nu() - model.na();
            }
        }
        let mut weighted = 0.0;
        for s in &self.samples {
            let rows = self
                .sample_residuals(model, sets, continuous, s)
                .iter()
                .map(|(r, _)| crate::problems::GenericFunction::dim(r))
                .sum::<usize>();
            // loads only (forces at their own instants) or weighed as the angles
            if s.target.q.iter().all(Option::is_none) {
                weighted += rows as f64 * s.load_weight;
            } else {
                n += rows;
            }
        }
        n + weighted.round() as usize
    }

    /// The data-only residuals of a sample target, each with the foot whose plate's clock
    /// offset moves its instant (`None`: fixed): one residual; or, when an effect of the
    /// model shifts the plates' clocks and the sample has loads, the angles at the
    /// sample's instant and each loaded foot's loads, at their measured values, at the
    /// instant that foot's plate offset moves them to ([`ForceClockShift`]).
    pub(super) fn sample_residuals<'m>(
        &self,
        model: &'m GaitModel,
        sets: &[ConstraintSet],
        continuous: &[usize],
        s: &SampleTarget,
    ) -> Vec<(TrackingResidual<'m>, Option<usize>)> {
        let mut weights = self.weights.clone();
        weights.force *= s.load_weight;
        weights.cop *= s.load_weight;
        // the residual in `phase`'s contact set
        let residual = |target: NodeTarget, phase: usize| {
            self.residual_weighted(
                model,
                &sets[continuous[phase]],
                target,
                weights.clone(),
                true,
            )
            .data_only()
        };
        if !model.shifts_force_clock() || s.target.feet.iter().all(Option::is_none) {
            return vec![(residual(s.target.clone(), s.phase), None)];
        }
        let angles = residual(
            NodeTarget {
                feet: [None, None],
                ..s.target.clone()
            },
            s.phase,
        );
        let mut out = vec![(angles, None)];
        for side in 0..2 {
            if s.target.feet[side].is_none() {
                continue;
            }
            let mut feet = [None, None];
            feet[side] = s.target.feet[side];
            let loads = residual(
                NodeTarget {
                    q: vec![None; s.target.q.len()],
                    feet,
                    ..s.target.clone()
                },
                s.loads_at[side].0,
            )
            .at_measured_values();
            out.push((loads, Some(side)));
        }
        out.into_iter()
            .filter(|(r, _)| crate::problems::GenericFunction::dim(r) > 0)
            .collect()
    }

    /// The tracking OCP: the walking cycle of `cycle` plus the node-wise residuals.
    pub fn ocp<'c>(
        &self,
        cycle: &'c GaitCycle<'c>,
        model: &'c GaitModel,
        sets: &'c [ConstraintSet],
        integrator: crate::integrate::IntegratorSettings,
    ) -> Result<Ocp<'c>, crate::problems::error::ProblemError> {
        let mut ocp = cycle.ocp(&self.guess, integrator)?;
        self.free_moving_durations(model, &mut ocp);
        let linear = ocp
            .phases
            .iter()
            .all(|p| p.controls == crate::integrate::ControlShape::Linear);
        for (j, tg) in self.targets.iter().enumerate() {
            let set = &sets[cycle.continuous[j]];
            let n = ocp.phases[j].intervals;
            let last = j + 1 == self.targets.len();
            for (k, target) in tg.iter().enumerate() {
                // a phase's last node coincides with the next phase's first: count it once
                if k == n && !last {
                    continue;
                }
                let ku = if linear { k } else { k.min(n - 1) };
                let r = self.node_residual(model, set, (j, k), target.clone());
                ocp.least_squares.push(Term {
                    name: "tracking".into(),
                    args: vec![
                        Block::State { phase: j, node: k },
                        Block::Control { phase: j, node: ku },
                        Block::Params,
                    ],
                    f: Arc::new(crate::problems::AdTerm(r)),
                });
            }
        }
        for s in &self.samples {
            for (r, shifted) in self.sample_residuals(model, sets, &cycle.continuous, s) {
                let shift = shifted.map(|side| {
                    Arc::new(crate::problems::AdTerm(ForceClockShift {
                        model,
                        side,
                        placed: s.load_offset[side],
                    })) as Arc<dyn NodeFunction + 'c>
                });
                let (phase, interval, tau) = s.place_of(shifted);
                ocp.samples.push(SampleTerm {
                    name: "tracking sample".into(),
                    phase,
                    interval,
                    tau,
                    f: Arc::new(crate::problems::AdTerm(r)),
                    shift,
                });
            }
        }
        Ok(ocp)
    }
}
