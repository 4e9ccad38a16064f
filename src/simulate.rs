//! Forward simulation through a phase sequence with CVODES, sampled on a fine grid.
//!
//! Each continuous phase is integrated from knot to knot of the control table (the
//! piecewise-linear controls have kinks there), the state is read on an output grid from
//! the integrator's dense output, and every sample is re-evaluated to report ground
//! reaction forces, centres of pressure, constraint drift and Baumgarte forces. An impact
//! phase applies the plastic impact map.

use crate::controls::ControlTable;
use crate::integrate::{IntegrationStats, Integrator, IntegratorError, IntegratorSettings, Ode, OdeError};
use crate::model::gait::{ContactReport, FootLoad};
use crate::model::{ConstraintSet, DynamicsError, GaitModel, RowKind};
use crate::phases::{Phase, PhaseSequence};
use serde::Serialize;

/// Settings of a forward simulation.
#[derive(Debug, Clone, Serialize)]
pub struct SimulationSettings {
    /// Output grid step (s, default 0.001).
    pub output_step: f64,
    /// Integrator settings.
    pub integrator: IntegratorSettings,
}

impl Default for SimulationSettings {
    fn default() -> Self {
        Self { output_step: 1e-3, integrator: IntegratorSettings::default() }
    }
}

/// Failure of a simulation, naming the phase and time.
#[derive(Debug, thiserror::Error)]
pub enum SimulationError {
    /// The integrator failed.
    #[error("phase '{phase}': {source}")]
    Integrator {
        /// Phase name.
        phase: String,
        /// Cause (names the time).
        #[source]
        source: IntegratorError,
    },
    /// The dynamics could not be evaluated.
    #[error("phase '{phase}' at t = {t} s: {source}")]
    Dynamics {
        /// Phase name.
        phase: String,
        /// Time (s).
        t: f64,
        /// Cause.
        #[source]
        source: DynamicsError,
    },
    /// The initial state or settings are unusable.
    #[error("{0}")]
    Input(String),
}

/// One output sample.
#[derive(Debug, Clone, Serialize)]
pub struct Sample {
    /// Time (s).
    pub t: f64,
    /// Phase index.
    pub phase: usize,
    /// State `(q, q̇, a)`.
    pub x: Vec<f64>,
    /// Right and left foot loads.
    pub feet: [FootLoad; 2],
    /// Constraint details for the phase's rows.
    pub contact: ContactReport,
}

/// An applied impact.
#[derive(Debug, Clone, Serialize)]
pub struct ImpactRecord {
    /// Impact phase name.
    pub phase: String,
    /// Time (s).
    pub t: f64,
    /// `(contact, row kind, impulse N·s)` for each row active after the impact.
    pub impulses: Vec<(String, RowKind, f64)>,
    /// Kinetic energy before and after (J).
    pub kinetic_energy: (f64, f64),
    /// Normal gap φ (m) of each contact active after the impact, at the impact: a fixed
    /// phase duration does not place the landing foot on the ground, so a non-zero gap is
    /// closed afterwards by the Baumgarte terms.
    pub gaps: Vec<(String, f64)>,
}

/// Start and end of one phase.
#[derive(Debug, Clone, Serialize)]
pub struct PhaseSpan {
    /// Name.
    pub name: String,
    /// Start (s).
    pub t0: f64,
    /// End (s).
    pub t1: f64,
}

/// The result of a simulation.
#[derive(Debug, Clone, Serialize)]
pub struct SimulationResult {
    /// Samples in time order.
    pub samples: Vec<Sample>,
    /// Impacts applied.
    pub impacts: Vec<ImpactRecord>,
    /// Phase spans.
    pub phases: Vec<PhaseSpan>,
    /// Integrator counters summed over all phases.
    pub stats: IntegrationStats,
}

/// Figures of one continuous phase.
#[derive(Debug, Clone, Serialize)]
pub struct PhaseFigures {
    /// Phase name.
    pub name: String,
    /// Largest |φ| over normal rows (m).
    pub max_position_drift_m: f64,
    /// Largest |G q̇| over all rows (m/s).
    pub max_velocity_drift_m_s: f64,
    /// Largest |Baumgarte force| (N).
    pub max_baumgarte_force_n: f64,
    /// Peak normal force of the right and left foot (N).
    pub peak_normal_force_n: [f64; 2],
}

impl SimulationResult {
    /// Per-phase drift, Baumgarte and force figures (continuous phases only).
    pub fn phase_figures(&self, sets: &[ConstraintSet]) -> Vec<PhaseFigures> {
        let mut out: Vec<PhaseFigures> = Vec::new();
        for (pi, set) in sets.iter().enumerate() {
            let samples: Vec<&Sample> = self.samples.iter().filter(|s| s.phase == pi).collect();
            if samples.is_empty() {
                continue;
            }
            let mut f = PhaseFigures {
                name: set.name.clone(),
                max_position_drift_m: 0.0,
                max_velocity_drift_m_s: 0.0,
                max_baumgarte_force_n: 0.0,
                peak_normal_force_n: [0.0; 2],
            };
            for s in samples {
                for (r, row) in set.rows.iter().enumerate() {
                    if row.kind == RowKind::Normal {
                        f.max_position_drift_m = f.max_position_drift_m.max(s.contact.position_error[r].abs());
                    }
                    f.max_velocity_drift_m_s = f.max_velocity_drift_m_s.max(s.contact.velocity_error[r].abs());
                    f.max_baumgarte_force_n = f.max_baumgarte_force_n.max(s.contact.baumgarte_force[r].abs());
                }
                for k in 0..2 {
                    f.peak_normal_force_n[k] = f.peak_normal_force_n[k].max(s.feet[k].fy);
                }
            }
            out.push(f);
        }
        out
    }

    /// Largest |φ| over normal rows of all samples (m).
    pub fn max_position_drift(&self, sets: &[ConstraintSet]) -> f64 {
        self.max_over_rows(sets, |s, r| if s.rows[r].kind == RowKind::Normal { Some(0) } else { None }, |c, r| c.position_error[r])
    }
    /// Largest |G q̇| over all rows (m/s).
    pub fn max_velocity_drift(&self, sets: &[ConstraintSet]) -> f64 {
        self.max_over_rows(sets, |_, _| Some(0), |c, r| c.velocity_error[r])
    }
    /// Largest |Baumgarte force| over all rows (N).
    pub fn max_baumgarte_force(&self, sets: &[ConstraintSet]) -> f64 {
        self.max_over_rows(sets, |_, _| Some(0), |c, r| c.baumgarte_force[r])
    }
    fn max_over_rows(
        &self,
        sets: &[ConstraintSet],
        keep: impl Fn(&ConstraintSet, usize) -> Option<u8>,
        val: impl Fn(&ContactReport, usize) -> f64,
    ) -> f64 {
        let mut m = 0.0f64;
        for s in &self.samples {
            for r in 0..s.contact.lambda.len() {
                if keep(&sets[s.phase], r).is_some() {
                    m = m.max(val(&s.contact, r).abs());
                }
            }
        }
        m
    }
}

/// The model under one constraint set, driven by a control table, as an [`Ode`] in
/// physical time with the free model parameters as sensitivity parameters.
pub struct SimulationOde<'a> {
    /// Model.
    pub model: &'a GaitModel,
    /// Active constraints.
    pub set: &'a ConstraintSet,
    /// Controls.
    pub controls: &'a ControlTable,
}

impl Ode for SimulationOde<'_> {
    fn nx(&self) -> usize {
        self.model.nx()
    }
    fn np(&self) -> usize {
        self.model.ntheta()
    }
    fn rhs(&self, t: f64, x: &[f64], p: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        let mut u = vec![0.0; self.model.nu()];
        self.controls.at(t, &mut u);
        let mut lam = vec![0.0; self.set.rows.len()];
        self.model.dynamics(self.set, x, &u, p, xdot, &mut lam, None).map_err(|e| OdeError::Fatal(e.to_string()))?;
        if xdot.iter().any(|v| !v.is_finite()) {
            return Err(OdeError::Recoverable("non-finite state derivative".into()));
        }
        Ok(())
    }
    fn jacobians(&self, t: f64, x: &[f64], p: &[f64], xdot: &mut [f64], fx: &mut [f64], fp: &mut [f64]) -> Result<(), OdeError> {
        let (nx, nu) = (self.model.nx(), self.model.nu());
        let mut u = vec![0.0; nu];
        self.controls.at(t, &mut u);
        let mut jac = vec![0.0; nx * (nx + nu + p.len())];
        self.model
            .dynamics_jacobian(self.set, x, &u, p, xdot, &mut jac)
            .map_err(|e| OdeError::Fatal(e.to_string()))?;
        fx.copy_from_slice(&jac[..nx * nx]);
        fp.copy_from_slice(&jac[nx * (nx + nu)..]);
        Ok(())
    }
}

/// Simulate `seq` from `x0` under `controls`, with free parameters `theta`.
pub fn simulate(
    model: &GaitModel,
    seq: &PhaseSequence,
    sets: &[ConstraintSet],
    x0: &[f64],
    controls: &ControlTable,
    theta: &[f64],
    settings: &SimulationSettings,
) -> Result<SimulationResult, SimulationError> {
    if x0.len() != model.nx() {
        return Err(SimulationError::Input(format!(
            "initial state has {} values, the model has {} states",
            x0.len(),
            model.nx()
        )));
    }
    if !(settings.output_step.is_finite() && settings.output_step > 0.0) {
        return Err(SimulationError::Input(format!("output step must be positive, got {}", settings.output_step)));
    }
    let nq = model.nq();
    let mut integrator = Integrator::new(model.nx(), model.ntheta(), settings.integrator.clone())
        .map_err(|e| SimulationError::Integrator { phase: seq.phases[0].name().into(), source: e })?;
    let mut x = x0.to_vec();
    let mut t = 0.0;
    let mut res = SimulationResult { samples: Vec::new(), impacts: Vec::new(), phases: Vec::new(), stats: Default::default() };
    let mut u = vec![0.0; model.nu()];
    for (pi, phase) in seq.phases.iter().enumerate() {
        let set = &sets[pi];
        match phase {
            Phase::Impact { name, .. } => {
                let (q, qd) = (&x[..nq], &x[nq..2 * nq]);
                let (qd_plus, imp) = model
                    .impact(set, q, qd, theta)
                    .map_err(|e| SimulationError::Dynamics { phase: name.clone(), t, source: e })?;
                let ke0 = model.energy(q, qd, theta).0;
                let ke1 = model.energy(q, &qd_plus, theta).0;
                res.impacts.push(ImpactRecord {
                    phase: name.clone(),
                    t,
                    impulses: set
                        .rows
                        .iter()
                        .zip(&imp)
                        .map(|(r, v)| (model.contacts[r.contact].name.clone(), r.kind, *v))
                        .collect(),
                    kinetic_energy: (ke0, ke1),
                    gaps: set
                        .rows
                        .iter()
                        .filter(|r| r.kind == RowKind::Normal)
                        .map(|r| (model.contacts[r.contact].name.clone(), model.contact_point(r.contact, q, theta).1))
                        .collect(),
                });
                x[nq..2 * nq].copy_from_slice(&qd_plus);
                res.phases.push(PhaseSpan { name: name.clone(), t0: t, t1: t });
            }
            Phase::Continuous { name, duration, .. } => {
                let t_end = t + duration.value();
                let ode = SimulationOde { model, set, controls };
                let mut bounds = controls.knots_within(t, t_end);
                bounds.push(t_end);
                let mut a = t;
                let sample = |tt: f64, xx: &[f64], u: &mut Vec<f64>| -> Result<Sample, SimulationError> {
                    controls.at(tt, u);
                    let mut xdot = vec![0.0; model.nx()];
                    let mut lam = vec![0.0; set.rows.len()];
                    let mut rep = ContactReport::default();
                    model
                        .dynamics(set, xx, u, theta, &mut xdot, &mut lam, Some(&mut rep))
                        .map_err(|e| SimulationError::Dynamics { phase: name.clone(), t: tt, source: e })?;
                    Ok(Sample { t: tt, phase: pi, x: xx.to_vec(), feet: model.foot_loads(set, &rep), contact: rep })
                };
                res.samples.push(sample(t, &x, &mut u)?);
                for &b in &bounds {
                    let step = settings.output_step;
                    let mut times: Vec<f64> = Vec::new();
                    let mut k = (a / step).floor() as i64 + 1;
                    while (k as f64) * step < b - 1e-12 {
                        if (k as f64) * step > a + 1e-12 {
                            times.push(k as f64 * step);
                        }
                        k += 1;
                    }
                    times.push(b);
                    let mut out = Vec::new();
                    let st = integrator
                        .integrate_dense(&ode, a, b, &x, theta, &times, &mut out)
                        .map_err(|e| SimulationError::Integrator { phase: name.clone(), source: e })?;
                    res.stats += st;
                    for (i, &tt) in times.iter().enumerate() {
                        let xi = &out[i * model.nx()..(i + 1) * model.nx()];
                        res.samples.push(sample(tt, xi, &mut u)?);
                    }
                    x.copy_from_slice(&out[out.len() - model.nx()..]);
                    a = b;
                }
                res.phases.push(PhaseSpan { name: name.clone(), t0: t, t1: t_end });
                t = t_end;
            }
        }
    }
    Ok(res)
}
