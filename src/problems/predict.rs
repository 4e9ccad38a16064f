//! The prediction problem (Millard & Mombaur 2019, §3.5): the walking cycle that minimises muscle
//! activation, $\int \sum a_i^2\,dt$ (eq. 20), plus the foot-ground impulses,
//! $w_\Delta \sum \Delta_i^2$ with $w_\Delta = 10^{-2}$ (eq. 21), at the subject's step
//! length and average forward speed. Phase durations are free within the phase file's
//! bounds; the rest of the cycle (periodicity, unilateral forces, friction cone, swing
//! clearance, landing contacts) is the [`GaitCycle`]'s.
//!
//! The Lagrange term is integrated by the trapezoidal rule over the shooting nodes (the
//! activations are smooth states, driven by piecewise-linear excitations), so that it is
//! a least-squares term `r = √(c_k T_j/N_j) a` with exact derivatives in the node state
//! and the phase duration.

use super::error::ProblemError;
use super::evaluation::GaitSolution;
use super::gait::{GaitCycle, GaitGuess, ImpulseRows};
use super::track::TrackingSetup;
use super::{AdTerm, GenericFunction};
use crate::data::GaitData;
use crate::integrate::IntegratorSettings;
use crate::model::effects::ModelScalar;
use crate::model::{ConstraintSet, GaitModel};
use crate::ocp::{Block, Ocp, Term};
use crate::phases::{Duration, Phase, PhaseSequence};
use std::sync::Arc;

/// Millard & Mombaur's impulse weight w_Δ (eq. 21, N⁻²s⁻²).
pub const SEED_IMPULSE_WEIGHT: f64 = 1e-2;

/// Longest step a prediction accepts (m): forward pelvis travel over a half cycle,
/// beyond a sprinter's.
pub const MAX_STEP_LENGTH: f64 = 2.5;
/// Fastest average speed a prediction accepts (m/s), beyond a sprinter's.
pub const MAX_SPEED: f64 = 12.0;

/// A step length or speed target outside human gait.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{what} {value} {unit} is not a human gait's: expected a forward {what} > 0 and ≤ {max} {unit} (the subject's: {subject:.3} {unit})")]
pub struct TargetError {
    /// `step length` or `speed`.
    pub what: &'static str,
    /// The target given.
    pub value: f64,
    /// Its unit.
    pub unit: &'static str,
    /// The largest accepted.
    pub max: f64,
    /// The subject's, from the data.
    pub subject: f64,
}

/// Targets and options of the prediction.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PredictionSettings {
    /// Step length: forward pelvis displacement over the half cycle (m).
    pub step_length: f64,
    /// Average forward speed (m/s).
    pub speed: f64,
    /// Impulse weight w_Δ.
    pub impulse_weight: f64,
    /// Bound on |ankle angular velocity| (rad/s), replacing the data-derived bound
    /// (measured range ± 1 rad/s, Millard & Mombaur 2019, §3.3). Millard & Mombaur's predictions ran with 14.6 rad/s
    /// (which its ellipse foot reached) and its control experiment with 3.96.
    pub ankle_velocity_limit: Option<f64>,
}

impl PredictionSettings {
    /// The subject's step length and speed over the tracked half cycle of `data`.
    pub fn from_data(setup: &TrackingSetup, data: &GaitData) -> Self {
        let (t0, t1) = setup.window;
        let x = crate::data::interp_linear(&[t0, t1], &data.time, &data.q[0]);
        let step_length = x[1] - x[0];
        Self {
            step_length,
            speed: step_length / (t1 - t0),
            impulse_weight: SEED_IMPULSE_WEIGHT,
            ankle_velocity_limit: None,
        }
    }

    /// Replace the subject's step length and speed by the given targets, each > 0 and at
    /// most [`MAX_STEP_LENGTH`] and [`MAX_SPEED`].
    pub fn set_targets(
        &mut self,
        step_length: Option<f64>,
        speed: Option<f64>,
    ) -> Result<(), TargetError> {
        let target = |what, unit, max, value: Option<f64>, subject: f64| match value {
            Some(v) if !(v > 0.0 && v <= max) => Err(TargetError {
                what,
                value: v,
                unit,
                max,
                subject,
            }),
            _ => Ok(value.unwrap_or(subject)),
        };
        self.step_length = target(
            "step length",
            "m",
            MAX_STEP_LENGTH,
            step_length,
            self.step_length,
        )?;
        self.speed = target("speed", "m/s", MAX_SPEED, speed, self.speed)?;
        Ok(())
    }
}

/// Everything the prediction OCP needs.
pub struct PredictionSetup {
    /// The phase file with free durations initialised from the guess.
    pub seq: PhaseSequence,
    /// Initial guess and bounds.
    pub guess: GaitGuess,
    /// Targets and options.
    pub settings: PredictionSettings,
    /// Forward pelvis position at the first node (m): the cost and constraints are
    /// invariant to a shift along the ground, so the start is pinned to the subject's
    /// (a free direction of zero curvature would leave the problem singular).
    pub pelvis_x0: f64,
}

impl PredictionSetup {
    /// Start from `solution` (e.g. a tracking solution of the same model and phase file),
    /// with the state bounds of the tracking problem of `tracking` (Millard & Mombaur 2019, §3.3).
    pub fn from_solution(
        original: &PhaseSequence,
        tracking: &TrackingSetup,
        solution: &GaitSolution,
        settings: PredictionSettings,
    ) -> Result<Self, ProblemError> {
        let cont: Vec<usize> = original.continuous_indices();
        if cont.len() != solution.phases.len() {
            return Err(ProblemError::SolutionPhaseCount {
                found: solution.phases.len(),
                graph: original.name.clone(),
                expected: cont.len(),
            });
        }
        let mut seq = original.clone();
        for (&i, ph) in cont.iter().zip(&solution.phases) {
            let Phase::Continuous {
                name,
                intervals,
                duration,
                ..
            } = &mut seq.phases[i]
            else {
                unreachable!()
            };
            if *name != ph.name || *intervals != ph.intervals() {
                return Err(ProblemError::SolutionPhase {
                    found: ph.name.clone(),
                    found_intervals: ph.intervals(),
                    expected: name.clone(),
                    expected_intervals: *intervals,
                });
            }
            *duration = match *duration {
                Duration::Fixed(_) => Duration::Fixed(ph.duration),
                Duration::Free { min, max, .. } => Duration::Free {
                    initial: ph.duration.clamp(min, max),
                    min,
                    max,
                },
            };
        }
        let mut guess = tracking.guess.clone();
        guess.x = solution.phases.iter().map(|p| p.x.clone()).collect();
        guess.u = solution.phases.iter().map(|p| p.u.clone()).collect();
        Self::new(seq, guess, settings, tracking.guess.x[0][0][0])
    }

    /// Start from the data, as tracking does (positions projected onto the contacts,
    /// activations 0.01, excitations 0.025), with the measured durations as initial values.
    pub fn from_data(
        original: &PhaseSequence,
        tracking: &TrackingSetup,
        settings: PredictionSettings,
    ) -> Result<Self, ProblemError> {
        let mut seq = original.clone();
        for (p, measured) in seq.phases.iter_mut().zip(&tracking.seq.phases) {
            if let (
                Phase::Continuous {
                    duration: Duration::Free { initial, min, max },
                    ..
                },
                Phase::Continuous { duration: m, .. },
            ) = (p, measured)
            {
                *initial = m.value().clamp(*min, *max);
            }
        }
        Self::new(
            seq,
            tracking.guess.clone(),
            settings,
            tracking.guess.x[0][0][0],
        )
    }

    fn new(
        seq: PhaseSequence,
        mut guess: GaitGuess,
        settings: PredictionSettings,
        pelvis_x0: f64,
    ) -> Result<Self, ProblemError> {
        if !(settings.step_length.is_finite() && settings.speed.is_finite() && settings.speed > 0.0)
        {
            return Err(ProblemError::StepOrSpeed {
                step_length: settings.step_length,
                speed: settings.speed,
            });
        }
        if !(settings.impulse_weight.is_finite() && settings.impulse_weight >= 0.0) {
            return Err(ProblemError::ImpulseWeight {
                weight: settings.impulse_weight,
            });
        }
        if let Some(w) = settings.ankle_velocity_limit {
            if !(w.is_finite() && w > 0.0) {
                return Err(ProblemError::AnkleVelocityLimit { limit: w });
            }
            // ankle_r and ankle_l are coordinates 5 and 8; their velocities follow the nq positions
            let nq = crate::model::gait::COORDINATES.len();
            for i in [nq + 5, nq + 8] {
                guess.x_lb[i] = -w;
                guess.x_ub[i] = w;
            }
            for phase in guess.x.iter_mut() {
                for x in phase.iter_mut() {
                    for i in [nq + 5, nq + 8] {
                        x[i] = x[i].clamp(-w, w);
                    }
                }
            }
        }
        Ok(Self {
            seq,
            guess,
            settings,
            pelvis_x0,
        })
    }

    /// The prediction OCP on `cycle` (built from [`Self::seq`]).
    pub fn ocp<'c>(
        &self,
        cycle: &'c GaitCycle<'c>,
        model: &'c GaitModel,
        sets: &'c [ConstraintSet],
        integrator: IntegratorSettings,
    ) -> Result<Ocp<'c>, ProblemError> {
        let mut ocp = cycle.ocp(&self.guess, integrator)?;
        ocp.phases[0].x_lb[0][0] = self.pelvis_x0;
        ocp.phases[0].x_ub[0][0] = self.pelvis_x0;
        ocp.phases[0].x_guess[0][0] = self.pelvis_x0;
        let steps = cycle.step_constraints(
            &ocp,
            Some(self.settings.step_length),
            Some(self.settings.speed),
        );
        ocp.constraints.extend(steps);
        let (nq, na) = (model.nq(), model.na());
        // eq. 20: ∫ Σ a² dt by the trapezoidal rule over the nodes
        if na > 0 {
            for (j, ph) in ocp.phases.iter().enumerate() {
                let n = ph.intervals;
                for k in 0..=n {
                    let c = if k == 0 || k == n { 0.5 } else { 1.0 };
                    let f = ActivationEffort {
                        offset: 2 * nq,
                        na,
                        nx: model.nx(),
                        weight: c / n as f64,
                    };
                    ocp.least_squares.push(Term {
                        name: "activation".into(),
                        args: vec![
                            Block::State { phase: j, node: k },
                            Block::Duration { phase: j },
                        ],
                        f: Arc::new(AdTerm(f)),
                    });
                }
            }
        }
        // eq. 21: w_Δ Σ Δ², every impact that follows a continuous phase (a leading impact
        // is the mirrored trailing one)
        if self.settings.impulse_weight > 0.0 {
            let seq = &self.seq;
            let mut prev: Option<usize> = None;
            for (i, ph) in seq.phases.iter().enumerate() {
                match ph {
                    Phase::Continuous { .. } => {
                        prev = Some(
                            cycle
                                .continuous
                                .iter()
                                .position(|&c| c == i)
                                .expect("a continuous phase"),
                        )
                    }
                    Phase::Impact { name, .. } => {
                        let Some(j) = prev else { continue };
                        let f = ImpulseRows::scaled(
                            model,
                            &sets[i],
                            self.settings.impulse_weight.sqrt(),
                        );
                        ocp.least_squares.push(Term {
                            name: format!("impulse({name})"),
                            args: vec![
                                Block::State {
                                    phase: j,
                                    node: ocp.phases[j].intervals,
                                },
                                Block::Params,
                            ],
                            f: Arc::new(AdTerm(f)),
                        });
                    }
                }
            }
        }
        Ok(ocp)
    }
}

/// `√(weight · T) · a` at one node: its square is the node's share of ∫ Σ a² dt.
/// Arguments: `(x, T)`.
struct ActivationEffort {
    offset: usize,
    na: usize,
    nx: usize,
    weight: f64,
}

impl GenericFunction for ActivationEffort {
    fn dim(&self) -> usize {
        self.na
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), crate::ocp::TermError> {
        let t = z[self.nx];
        let s = (t * self.weight).sqrt();
        for (o, a) in out.iter_mut().zip(&z[self.offset..self.offset + self.na]) {
            *o = s * *a;
        }
        Ok(())
    }
}
