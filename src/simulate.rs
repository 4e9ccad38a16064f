//! Forward simulation through a phase sequence with CVODES, sampled on a fine grid.
//!
//! Each continuous phase is integrated from knot to knot of the control table (the
//! piecewise-linear controls have kinks there), the state is read on an output grid from
//! the integrator's dense output, and every sample is re-evaluated to report ground
//! reaction forces, centres of pressure, constraint drift and Baumgarte forces. An impact
//! phase applies the plastic impact map. A continuous phase with `end.touchdown` stops at
//! the first instant the named contact reaches the ground (CVODES root finding on its gap).
//! [`SimulationResult::check`] lists landings away from the ground, touchdowns not reached
//! and large stabilisation forces as [`SimulationWarning`]s.

use crate::controls::ControlTable;
use crate::integrate::{
    IntegrationStats, Integrator, IntegratorError, IntegratorSettings, Ode, OdeError,
};
use crate::model::gait::{ContactReport, FootLoad};
use crate::model::{ConstraintSet, DynamicsError, GaitModel, RowKind};
use crate::phases::{Phase, PhaseEnd, PhaseSequence};
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
        Self {
            output_step: 1e-3,
            integrator: IntegratorSettings::default(),
        }
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
    /// Normal gap φ (m) of each contact active after the impact, at the impact. A phase
    /// ending at its landing contact's touchdown (`end.touchdown`) puts it on the ground; a
    /// fixed duration does not, and the non-zero gap is then closed afterwards by the
    /// Baumgarte terms ([`SimulationResult::check`] reports it).
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
    /// Outcome of the phase's `end.touchdown` event, if it has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub touchdown: Option<TouchdownOutcome>,
}

/// What became of a phase's `end.touchdown` event.
#[derive(Debug, Clone, Serialize)]
pub struct TouchdownOutcome {
    /// The landing contact.
    pub contact: String,
    /// Whether it reached the ground before the phase's duration ran out (the phase then
    /// ends at the touchdown instant).
    pub landed: bool,
    /// Its gap φ at the end of the phase (m): zero to the root-finding precision when it
    /// landed.
    pub gap_m: f64,
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

/// Tolerances of [`SimulationResult::check`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SanityTolerances {
    /// Largest |φ| (m) of a contact at the impact that puts it on the ground (default
    /// 1e-3 m). A larger gap is closed, or a penetration pushed out, by the Baumgarte terms
    /// after the impact, not by the impact map.
    pub landing_gap_m: f64,
    /// Largest |Baumgarte force| (N) of a contact row (default 1 N). The stabilisation is
    /// meant to hold integration drift (its forces are below 1e-5 N on contacts that land
    /// on the ground); a 1 mm landing gap already asks about 1 N of it.
    pub baumgarte_force_n: f64,
}

impl Default for SanityTolerances {
    fn default() -> Self {
        Self {
            landing_gap_m: 1e-3,
            baumgarte_force_n: 1.0,
        }
    }
}

/// A physically doubtful feature of a simulation, found by [`SimulationResult::check`].
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SimulationWarning {
    /// A contact made active by an impact is away from the ground at the impact
    /// (φ > 0: above it; φ < 0: below it).
    LandingGap {
        /// Impact phase.
        phase: String,
        /// Contact.
        contact: String,
        /// Time of the impact (s).
        t: f64,
        /// Gap φ (m).
        gap_m: f64,
        /// Tolerance on |φ| (m).
        tolerance_m: f64,
    },
    /// A phase's `end.touchdown` contact did not reach the ground within the duration.
    NoTouchdown {
        /// Continuous phase.
        phase: String,
        /// Contact.
        contact: String,
        /// End of the phase (s).
        t: f64,
        /// Gap φ at the end (m).
        gap_m: f64,
    },
    /// A stabilisation force above the tolerance (largest over the phase for the contact).
    BaumgarteForce {
        /// Continuous phase.
        phase: String,
        /// Contact.
        contact: String,
        /// Row (normal or tangential).
        row: RowKind,
        /// Time of the largest force (s).
        t: f64,
        /// The force (N).
        force_n: f64,
        /// Tolerance (N).
        tolerance_n: f64,
    },
}

impl std::fmt::Display for SimulationWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let side = |g: f64| if g < 0.0 { "below" } else { "above" };
        match self {
            SimulationWarning::LandingGap { phase, contact, t, gap_m, tolerance_m } => write!(
                f,
                "phase '{phase}': contact '{contact}' is {:.1} mm {} the ground at the impact, t = {t:.4} s (gap {:.1} mm, tolerance {:.1} mm)",
                gap_m.abs() * 1e3,
                side(*gap_m),
                gap_m * 1e3,
                tolerance_m * 1e3
            ),
            SimulationWarning::NoTouchdown { phase, contact, t, gap_m } => write!(
                f,
                "phase '{phase}': contact '{contact}' does not touch down within the phase's duration; \
                 at its end, t = {t:.4} s, it is {:.1} mm {} the ground (gap {:.1} mm)",
                gap_m.abs() * 1e3,
                side(*gap_m),
                gap_m * 1e3
            ),
            SimulationWarning::BaumgarteForce { phase, contact, row, t, force_n, tolerance_n } => write!(
                f,
                "phase '{phase}': contact '{contact}' has a {} stabilisation (Baumgarte) force of {force_n:.2} N at t = {t:.4} s (tolerance {tolerance_n} N)",
                match row {
                    RowKind::Normal => "normal",
                    RowKind::Tangential => "tangential",
                }
            ),
        }
    }
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
                        f.max_position_drift_m = f
                            .max_position_drift_m
                            .max(s.contact.position_error[r].abs());
                    }
                    f.max_velocity_drift_m_s = f
                        .max_velocity_drift_m_s
                        .max(s.contact.velocity_error[r].abs());
                    f.max_baumgarte_force_n = f
                        .max_baumgarte_force_n
                        .max(s.contact.baumgarte_force[r].abs());
                }
                for k in 0..2 {
                    f.peak_normal_force_n[k] = f.peak_normal_force_n[k].max(s.feet[k].fy);
                }
            }
            out.push(f);
        }
        out
    }

    /// Physical sanity of the simulation: landings away from the ground, touchdown events
    /// not reached, and stabilisation forces above the tolerances. `sets` are the phases'
    /// constraint sets of `model`, as passed to [`simulate`]. Warnings come in time order
    /// of the phases; within a continuous phase, one Baumgarte warning per contact (its
    /// largest force).
    pub fn check(
        &self,
        model: &GaitModel,
        sets: &[ConstraintSet],
        tol: &SanityTolerances,
    ) -> Vec<SimulationWarning> {
        let mut out = Vec::new();
        for (pi, span) in self.phases.iter().enumerate() {
            if let Some(imp) = self.impacts.iter().find(|i| i.phase == span.name) {
                for (contact, gap) in &imp.gaps {
                    if gap.abs() > tol.landing_gap_m {
                        out.push(SimulationWarning::LandingGap {
                            phase: imp.phase.clone(),
                            contact: contact.clone(),
                            t: imp.t,
                            gap_m: *gap,
                            tolerance_m: tol.landing_gap_m,
                        });
                    }
                }
                continue;
            }
            if let Some(td) = span.touchdown.as_ref().filter(|td| !td.landed) {
                out.push(SimulationWarning::NoTouchdown {
                    phase: span.name.clone(),
                    contact: td.contact.clone(),
                    t: span.t1,
                    gap_m: td.gap_m,
                });
            }
            let Some(set) = sets.get(pi) else { continue };
            // (row, |force|, t) of the largest force of each contact
            let mut worst: Vec<Option<(usize, f64, f64)>> = vec![None; model.contacts.len()];
            for smp in self.samples.iter().filter(|s| s.phase == pi) {
                for (r, row) in set.rows.iter().enumerate() {
                    let v = smp.contact.baumgarte_abs(r);
                    let w = &mut worst[row.contact];
                    if v > tol.baumgarte_force_n && w.is_none_or(|(_, m, _)| v > m) {
                        *w = Some((r, v, smp.t));
                    }
                }
            }
            for (r, force_n, t) in worst.into_iter().flatten() {
                let row = &set.rows[r];
                out.push(SimulationWarning::BaumgarteForce {
                    phase: span.name.clone(),
                    contact: model.contacts[row.contact].name.clone(),
                    row: row.kind,
                    t,
                    force_n,
                    tolerance_n: tol.baumgarte_force_n,
                });
            }
        }
        out
    }

    /// Largest |φ| over normal rows of all samples (m).
    pub fn max_position_drift(&self, sets: &[ConstraintSet]) -> f64 {
        self.max_over_rows(
            sets,
            |s, r| {
                if s.rows[r].kind == RowKind::Normal {
                    Some(0)
                } else {
                    None
                }
            },
            |c, r| c.position_error[r],
        )
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
        self.model
            .dynamics(self.set, x, &u, p, xdot, &mut lam, None)
            .map_err(|e| OdeError::Fatal(e.to_string()))?;
        if xdot.iter().any(|v| !v.is_finite()) {
            return Err(OdeError::Recoverable("non-finite state derivative".into()));
        }
        Ok(())
    }
    fn jacobians(
        &self,
        t: f64,
        x: &[f64],
        p: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fp: &mut [f64],
    ) -> Result<(), OdeError> {
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
        return Err(SimulationError::Input(format!(
            "output step must be positive, got {}",
            settings.output_step
        )));
    }
    let integrator = Integrator::new(model.nx(), model.ntheta(), settings.integrator.clone())
        .map_err(|e| SimulationError::Integrator {
            phase: seq.phases[0].name().into(),
            source: e,
        })?;
    let mut run = Run {
        model,
        controls,
        theta,
        settings,
        integrator,
        x: x0.to_vec(),
        t: 0.0,
        u: vec![0.0; model.nu()],
        res: SimulationResult {
            samples: Vec::new(),
            impacts: Vec::new(),
            phases: Vec::new(),
            stats: Default::default(),
        },
    };
    for (pi, phase) in seq.phases.iter().enumerate() {
        let set = &sets[pi];
        match phase {
            Phase::Impact { name, .. } => run.impact(set, name)?,
            Phase::Continuous {
                name,
                duration,
                end,
                ..
            } => {
                let sampler = Sampler {
                    model,
                    controls,
                    set,
                    theta,
                    phase: pi,
                    name,
                };
                run.continuous(&sampler, duration.value(), end.as_ref())?;
            }
        }
    }
    Ok(run.res)
}

/// A simulation under way: its inputs, the integrator, the state reached and the result
/// so far.
struct Run<'a> {
    model: &'a GaitModel,
    controls: &'a ControlTable,
    theta: &'a [f64],
    settings: &'a SimulationSettings,
    integrator: Integrator,
    /// The state at `t`.
    x: Vec<f64>,
    /// The time reached (s).
    t: f64,
    /// The controls at a sample (scratch).
    u: Vec<f64>,
    res: SimulationResult,
}

/// The samples of one continuous phase: the dynamics re-evaluated at a state to report
/// the contact forces.
struct Sampler<'a> {
    model: &'a GaitModel,
    controls: &'a ControlTable,
    /// The phase's active constraints.
    set: &'a ConstraintSet,
    theta: &'a [f64],
    /// The phase's index in the sequence.
    phase: usize,
    /// The phase's name.
    name: &'a str,
}

impl Sampler<'_> {
    /// The sample at time `tt` (s) and state `xx`; `u` receives the controls.
    fn at(&self, tt: f64, xx: &[f64], u: &mut [f64]) -> Result<Sample, SimulationError> {
        let (model, set) = (self.model, self.set);
        self.controls.at(tt, u);
        let mut xdot = vec![0.0; model.nx()];
        let mut lam = vec![0.0; set.rows.len()];
        let mut rep = ContactReport::default();
        model
            .dynamics(set, xx, u, self.theta, &mut xdot, &mut lam, Some(&mut rep))
            .map_err(|e| SimulationError::Dynamics {
                phase: self.name.to_string(),
                t: tt,
                source: e,
            })?;
        Ok(Sample {
            t: tt,
            phase: self.phase,
            x: xx.to_vec(),
            feet: model.foot_loads(set, &rep),
            contact: rep,
        })
    }
}

/// The output instants of a span from `a` to `b` (s): the multiples of `step` (s) more
/// than 1e-12 s inside it, then `b`.
fn output_times(a: f64, b: f64, step: f64) -> Vec<f64> {
    let mut times: Vec<f64> = Vec::new();
    let mut k = (a / step).floor() as i64 + 1;
    while (k as f64) * step < b - 1e-12 {
        if (k as f64) * step > a + 1e-12 {
            times.push(k as f64 * step);
        }
        k += 1;
    }
    times.push(b);
    times
}

impl Run<'_> {
    /// Apply impact phase `name`'s plastic impact map under `set` to the velocities, and
    /// record its impulses, kinetic energies and gaps.
    fn impact(&mut self, set: &ConstraintSet, name: &str) -> Result<(), SimulationError> {
        let (model, theta, t) = (self.model, self.theta, self.t);
        let nq = model.nq();
        let (q, qd) = (&self.x[..nq], &self.x[nq..2 * nq]);
        let (qd_plus, imp) =
            model
                .impact(set, q, qd, theta)
                .map_err(|e| SimulationError::Dynamics {
                    phase: name.to_string(),
                    t,
                    source: e,
                })?;
        let ke0 = model.energy(q, qd, theta).0;
        let ke1 = model.energy(q, &qd_plus, theta).0;
        self.res.impacts.push(ImpactRecord {
            phase: name.to_string(),
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
                .map(|r| {
                    (
                        model.contacts[r.contact].name.clone(),
                        model.contact_point(r.contact, q, theta).1,
                    )
                })
                .collect(),
        });
        self.x[nq..2 * nq].copy_from_slice(&qd_plus);
        self.res.phases.push(PhaseSpan {
            name: name.to_string(),
            t0: t,
            t1: t,
            touchdown: None,
        });
        Ok(())
    }

    /// Integrate the continuous phase of `sampler` for at most `duration` (s) from knot to
    /// knot of the controls, sampling on the output grid; with an `end`, stop at the
    /// first touchdown of its contact.
    fn continuous(
        &mut self,
        sampler: &Sampler<'_>,
        duration: f64,
        end: Option<&PhaseEnd>,
    ) -> Result<(), SimulationError> {
        let (model, theta, t, name) = (self.model, self.theta, self.t, sampler.name);
        let nq = model.nq();
        let t_max = t + duration;
        let ode = SimulationOde {
            model,
            set: sampler.set,
            controls: self.controls,
        };
        let mut bounds = self.controls.knots_within(t, t_max);
        bounds.push(t_max);
        // The touchdown watch: the landing contact's index; CVODES stops at the first
        // fall of its gap φ from above zero to zero.
        let watch = match end {
            Some(e) => Some(model.contact_index(&e.touchdown).ok_or_else(|| {
                SimulationError::Input(format!(
                    "phase '{name}' ends at the touchdown of unknown contact '{}'",
                    e.touchdown
                ))
            })?),
            None => None,
        };
        let mut landed = false;
        self.res.samples.push(sampler.at(t, &self.x, &mut self.u)?);
        let mut a = t;
        for &b in &bounds {
            if let Some(tr) = self.span(&ode, sampler, (a, b), watch)? {
                a = tr;
                landed = true;
                break;
            }
            a = b;
        }
        let touchdown = watch.map(|c| TouchdownOutcome {
            contact: model.contacts[c].name.clone(),
            landed,
            gap_m: model.contact_point(c, &self.x[..nq], theta).1,
        });
        self.res.phases.push(PhaseSpan {
            name: name.to_string(),
            t0: t,
            t1: a,
            touchdown,
        });
        self.t = a;
        Ok(())
    }

    /// Integrate from `a` to `b` (s), sampling on the output grid and at `b`; with a
    /// `watch`ed contact, stop at its touchdown and return the instant (s).
    fn span(
        &mut self,
        ode: &SimulationOde<'_>,
        sampler: &Sampler<'_>,
        (a, b): (f64, f64),
        watch: Option<usize>,
    ) -> Result<Option<f64>, SimulationError> {
        let (model, theta) = (self.model, self.theta);
        let nq = model.nq();
        let times = output_times(a, b, self.settings.output_step);
        let mut out = Vec::new();
        let (st, root) = match watch {
            Some(c) => {
                let gap = |_: f64, xx: &[f64]| model.contact_point(c, &xx[..nq], theta).1;
                self.integrator
                    .integrate_dense_until(ode, a, b, &self.x, theta, &times, &gap, &mut out)
            }
            None => self
                .integrator
                .integrate_dense(ode, a, b, &self.x, theta, &times, &mut out)
                .map(|st| (st, None)),
        }
        .map_err(|e| SimulationError::Integrator {
            phase: sampler.name.to_string(),
            source: e,
        })?;
        self.res.stats += st;
        // with a root, the last row of `out` is the state at the touchdown
        let n_out = out.len() / model.nx();
        for i in 0..n_out {
            let tt = match root {
                Some(tr) if i + 1 == n_out => tr,
                _ => times[i],
            };
            self.res.samples.push(sampler.at(
                tt,
                &out[i * model.nx()..(i + 1) * model.nx()],
                &mut self.u,
            )?);
        }
        self.x.copy_from_slice(&out[out.len() - model.nx()..]);
        Ok(root)
    }
}
