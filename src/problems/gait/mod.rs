//! The walking cycle as a multi-phase OCP (Millard & Mombaur 2019, §3.3): continuous phases with their
//! contact sets, impacts as state transitions, contact-force path constraints
//! (λₙ ≥ 0, friction cone |λₜ| ≤ μλₙ), swing-foot clearance, landing contacts on the
//! ground, and periodicity through the left↔right symmetry map. Costs are added by the
//! tracking and prediction problems.
//!
//! Leading impact phases of a phase file (e.g. `1e*`) are realised by the trailing impact
//! of the mirrored cycle: the state after the last impact, mirrored, is the first state.

use super::error::ProblemError;
use super::{AdTerm, GaitOde, Linear};
use crate::integrate::{ControlShape, IntegratorSettings};
use crate::model::gait::COORDINATES;
use crate::model::{ConstraintSet, GaitModel, RowKind};
use crate::ocp::{Block, CheckPoint, Constraint, Ocp, Phase as OcpPhase, PhaseDuration, Term};
use crate::phases::{Duration, GaitSpec, Phase, PhaseSequence};

use std::sync::Arc;

/// Bounds and initial guess for the gait OCP.
#[derive(Debug, Clone)]
pub struct GaitGuess {
    /// Node states per continuous phase (`intervals + 1` rows each).
    pub x: Vec<Vec<Vec<f64>>>,
    /// Controls per continuous phase (control nodes).
    pub u: Vec<Vec<Vec<f64>>>,
    /// State bounds (applied at every node).
    pub x_lb: Vec<f64>,
    /// State upper bounds.
    pub x_ub: Vec<f64>,
    /// Control bounds.
    pub u_lb: Vec<f64>,
    /// Control upper bounds.
    pub u_ub: Vec<f64>,
}

/// Index permutation and signs of the left↔right map on states and controls.
fn mirror_maps(model: &GaitModel, spec: &GaitSpec) -> (Vec<usize>, Vec<usize>) {
    let nq = model.nq();
    let mut qmap: Vec<usize> = (0..nq).collect();
    for [a, b] in &spec.symmetry {
        let ia = COORDINATES.iter().position(|c| c == a).unwrap_or(0);
        let ib = COORDINATES.iter().position(|c| c == b).unwrap_or(0);
        qmap[ia] = ib;
        qmap[ib] = ia;
    }
    let mut xmap: Vec<usize> = qmap.clone();
    xmap.extend(qmap.iter().map(|&i| nq + i));
    // activations/controls come in (flexor, extensor) pairs per leg joint in the order
    // hip_r, knee_r, ankle_r, hip_l, knee_l, ankle_l: joint k ↔ the joint of its mirror
    let leg = [3usize, 4, 5, 6, 7, 8];
    let base = model.nu_actuators();
    let per = base / leg.len();
    let mut umap: Vec<usize> = (0..model.nu()).collect();
    for (k, &c) in leg.iter().enumerate() {
        let m = leg.iter().position(|&d| d == qmap[c]).unwrap_or(k);
        for s in 0..per {
            umap[k * per + s] = m * per + s;
        }
    }
    // residual actuators (one per coordinate) mirror with their coordinates
    for i in 0..model.nu() - base {
        umap[base + i] = base + qmap[i];
    }
    if model.na() > 0 {
        xmap.extend(umap[..model.na()].iter().map(|&i| 2 * nq + i));
    }
    (xmap, umap)
}

/// A resolved walking cycle: the model, the phase file, the constraint set of every phase
/// and the dynamics of every continuous phase, from which [`GaitCycle::ocp`] builds the
/// optimal control problem.
pub struct GaitCycle<'m> {
    model: &'m GaitModel,
    seq: PhaseSequence,
    sets: &'m [ConstraintSet],
    odes: Vec<GaitOde<'m>>,
    /// Index (into the phase file) of each continuous phase.
    pub continuous: Vec<usize>,
}

impl<'m> GaitCycle<'m> {
    /// Resolve `seq` (with its constraint sets `sets`, one per phase) for `model`.
    pub fn new(
        model: &'m GaitModel,
        seq: &PhaseSequence,
        sets: &'m [ConstraintSet],
    ) -> Result<Self, ProblemError> {
        if sets.len() != seq.phases.len() {
            return Err(ProblemError::SetCount {
                sets: sets.len(),
                phases: seq.phases.len(),
            });
        }
        let continuous: Vec<usize> = seq.continuous_indices();
        if continuous.is_empty() {
            return Err(ProblemError::NoContinuousPhase);
        }
        let odes = continuous
            .iter()
            .map(|&i| GaitOde {
                model,
                set: &sets[i],
            })
            .collect();
        Ok(Self {
            model,
            seq: seq.clone(),
            sets,
            odes,
            continuous,
        })
    }

    /// The optimal control problem with initial guess and bounds `guess`.
    pub fn ocp(
        &self,
        guess: &GaitGuess,
        integrator: IntegratorSettings,
    ) -> Result<Ocp<'_>, ProblemError> {
        gait_ocp(
            self.model, &self.seq, self.sets, &self.odes, guess, integrator,
        )
    }

    /// Whole-cycle constraints: step length `L` = pelvis_x(end) − pelvis_x(start) (m) and
    /// average forward speed `L / Σ T_j` (m/s), each when given (Millard & Mombaur 2019, §3.5).
    pub fn step_constraints<'s>(
        &'s self,
        ocp: &Ocp<'s>,
        step_length: Option<f64>,
        speed: Option<f64>,
    ) -> Vec<Constraint<'s>> {
        let last = ocp.phases.len() - 1;
        let n_last = ocp.phases[last].intervals;
        let nx = self.model.nx();
        let np = ocp.phases.len();
        let mut args = vec![
            Block::State { phase: 0, node: 0 },
            Block::State {
                phase: last,
                node: n_last,
            },
        ];
        args.extend((0..np).map(|j| Block::Duration { phase: j }));
        let mut out = Vec::new();
        if let Some(l) = step_length {
            let mut a = vec![0.0; 2 * nx + np];
            a[0] = -1.0;
            a[nx] = 1.0;
            out.push(Constraint {
                term: Term {
                    name: "step_length".into(),
                    args: args.clone(),
                    f: Arc::new(Linear::new(a, 1)),
                },
                lb: vec![l],
                ub: vec![l],
            });
        }
        if let Some(v_avg) = speed {
            // pelvis_x(end) − pelvis_x(start) − v Σ T_j = 0
            let mut a = vec![0.0; 2 * nx + np];
            a[0] = -1.0;
            a[nx] = 1.0;
            a[2 * nx..].iter_mut().for_each(|v| *v = -v_avg);
            let f = Linear::new(a, 1);
            out.push(Constraint {
                term: Term {
                    name: "average_speed".into(),
                    args,
                    f: Arc::new(f),
                },
                lb: vec![0.0],
                ub: vec![0.0],
            });
        }
        out
    }
}

fn gait_ocp<'a>(
    model: &'a GaitModel,
    seq: &PhaseSequence,
    sets: &'a [ConstraintSet],
    odes: &'a [GaitOde<'a>],
    guess: &GaitGuess,
    integrator: IntegratorSettings,
) -> Result<Ocp<'a>, ProblemError> {
    let spec = seq
        .gait
        .clone()
        .unwrap_or_else(|| serde_json::from_str("{}").expect("defaults"));
    let theta = model.theta0();
    let nt = theta.len();
    let layout = PhaseLayout::of(seq);
    if layout.cont.is_empty() {
        return Err(ProblemError::NoContinuousPhase);
    }
    if guess.x.len() != layout.cont.len() || guess.u.len() != layout.cont.len() {
        return Err(ProblemError::GuessPhases {
            guess: guess.x.len(),
            phases: layout.cont.len(),
        });
    }
    let phases = layout.ocp_phases(&spec, odes, guess);
    let cont = &layout.cont;
    // transitions: impact maps where an impact phase separates continuous phases
    let mut transitions = Vec::new();
    for j in 1..cont.len() {
        transitions.push(
            layout.impact_before[j].map(|i| impact_term(model, &sets[i], cont[j - 1].2, j - 1)),
        );
    }
    let rows = GaitRows {
        model,
        sets,
        spec: &spec,
        layout: &layout,
        lands_after: layout.lands_after(sets),
    };
    let mut constraints = Vec::new();
    for j in 0..cont.len() {
        rows.add_phase_constraints(j, &mut constraints);
    }
    rows.add_cycle_constraints(&mut constraints);
    Ok(Ocp {
        phases,
        transitions,
        ntheta: nt,
        theta_guess: theta.clone(),
        theta_lb: model
            .free_parameters()
            .iter()
            .map(|&i| model.parameters()[i].lower)
            .collect(),
        theta_ub: model
            .free_parameters()
            .iter()
            .map(|&i| model.parameters()[i].upper)
            .collect(),
        constraints,
        least_squares: Vec::new(),
        samples: Vec::new(),
        checks: Vec::new(),
        costs: Vec::new(),
        integrator,
    })
}

/// The continuous phases of a phase file and the impacts between them.
struct PhaseLayout<'s> {
    /// Continuous phases: (index in the file, name, intervals, duration).
    cont: Vec<(usize, &'s str, usize, Duration)>,
    /// Per continuous phase, the impact phase that precedes it (none before the first).
    impact_before: Vec<Option<usize>>,
    /// The impact phase after the last continuous phase, if any.
    trailing_impact: Option<usize>,
}

impl<'s> PhaseLayout<'s> {
    /// The continuous phases of `seq` and the impact that precedes each of them.
    fn of(seq: &'s PhaseSequence) -> Self {
        let mut cont: Vec<(usize, &str, usize, Duration)> = Vec::new();
        let mut pending_impact: Option<usize> = None;
        let mut impact_before: Vec<Option<usize>> = Vec::new();
        let mut trailing_impact: Option<usize> = None;
        for (i, ph) in seq.phases.iter().enumerate() {
            match ph {
                Phase::Impact { .. } => pending_impact = Some(i),
                Phase::Continuous {
                    name,
                    duration,
                    intervals,
                    ..
                } => {
                    impact_before.push(if cont.is_empty() {
                        None
                    } else {
                        pending_impact.take()
                    });
                    if cont.is_empty() {
                        pending_impact = None;
                    }
                    cont.push((i, name, *intervals, *duration));
                }
            }
        }
        if let Some(i) = pending_impact {
            trailing_impact = Some(i);
        }
        Self {
            cont,
            impact_before,
            trailing_impact,
        }
    }

    /// The contacts that land at the end of each continuous phase: those of the impact
    /// after it that are not on the ground during it.
    fn lands_after(&self, sets: &[ConstraintSet]) -> Vec<Vec<usize>> {
        let cont = &self.cont;
        (0..cont.len())
            .map(|j| {
                let impact = if j + 1 < cont.len() {
                    self.impact_before[j + 1]
                } else {
                    self.trailing_impact
                };
                let active: Vec<usize> = sets[cont[j].0].rows.iter().map(|r| r.contact).collect();
                impact.map_or(Vec::new(), |ii| {
                    sets[ii]
                        .rows
                        .iter()
                        .filter(|r| r.kind == RowKind::Normal && !active.contains(&r.contact))
                        .map(|r| r.contact)
                        .collect()
                })
            })
            .collect()
    }

    /// The OCP's phases: the continuous phases with their dynamics `odes`, bounds and
    /// initial guess.
    fn ocp_phases<'a>(
        &self,
        spec: &GaitSpec,
        odes: &'a [GaitOde<'a>],
        guess: &GaitGuess,
    ) -> Vec<OcpPhase<'a>> {
        let mut phases = Vec::new();
        for (j, &(_, name, n, dur)) in self.cont.iter().enumerate() {
            let duration = match dur {
                Duration::Fixed(v) => PhaseDuration::fixed(v),
                Duration::Free { initial, min, max } => PhaseDuration {
                    value: initial,
                    lb: min,
                    ub: max,
                },
            };
            let cn = if spec.controls == ControlShape::Linear {
                n + 1
            } else {
                n
            };
            phases.push(OcpPhase {
                name: name.to_string(),
                ode: &odes[j],
                intervals: n,
                duration,
                controls: spec.controls,
                x_lb: vec![guess.x_lb.clone(); n + 1],
                x_ub: vec![guess.x_ub.clone(); n + 1],
                u_lb: vec![guess.u_lb.clone(); cn],
                u_ub: vec![guess.u_ub.clone(); cn],
                x_guess: guess.x[j].clone(),
                u_guess: guess.u[j].clone(),
            });
        }
        phases
    }
}

/// What the gait OCP's path and point constraints are built from.
struct GaitRows<'a, 's> {
    model: &'a GaitModel,
    /// The resolved constraint sets, one per phase of the file.
    sets: &'a [ConstraintSet],
    spec: &'s GaitSpec,
    layout: &'s PhaseLayout<'s>,
    /// Per continuous phase, the contacts that land at its end.
    lands_after: Vec<Vec<usize>>,
}

impl<'a> GaitRows<'a, '_> {
    /// The constraints of continuous phase `j`: contact forces, clearance, the contacts on
    /// the ground at the start and those landing at the impact before it.
    fn add_phase_constraints(&self, j: usize, constraints: &mut Vec<Constraint<'a>>) {
        let (model, sets, spec) = (self.model, self.sets, self.spec);
        let cont = &self.layout.cont;
        let (i, _, n, _) = cont[j];
        let set = &sets[i];
        let mu = spec.friction;
        // contact forces at every node with the node's control
        for k in 0..=n {
            let ku = if spec.controls == ControlShape::Linear {
                k
            } else {
                k.min(n - 1)
            };
            let Some((f, rows_lb, rows_ub)) = contact_force_rows(model, set, mu) else {
                continue;
            };
            constraints.push(Constraint {
                term: Term {
                    name: "contact_forces".into(),
                    args: vec![
                        Block::State { phase: j, node: k },
                        Block::Control { phase: j, node: ku },
                        Block::Params,
                    ],
                    f: Arc::new(f),
                },
                lb: rows_lb,
                ub: rows_ub,
            });
        }
        if spec.clearance {
            self.add_clearance(j, constraints);
        }
        // contacts on the ground at the first node of the first phase; not in a gait
        // periodic through a trailing impact, where they would repeat the landing row:
        // the first node is the mirror of the landing, the landing foot's gap is zero and
        // every foot's normal velocity is zero after the impact, so the feet held by the
        // Baumgarte rows from there on keep a zero gap too (a repeated row leaves the
        // multipliers undetermined; on the torque-driven track, 47 iterations instead of
        // 28 to the same optimum)
        if j == 0 && !(spec.periodic && self.layout.trailing_impact.is_some()) {
            for c in set
                .rows
                .iter()
                .filter(|r| r.kind == RowKind::Normal)
                .map(|r| r.contact)
            {
                constraints.push(gap_constraint(model, c, 0, 0, "on_ground", 0.0, 0.0));
            }
        }
        // a landing contact touches the ground at the impact (last node of the phase before)
        if j > 0 {
            if let Some(ii) = self.layout.impact_before[j] {
                let prev_active: Vec<usize> =
                    sets[cont[j - 1].0].rows.iter().map(|r| r.contact).collect();
                for c in sets[ii]
                    .rows
                    .iter()
                    .filter(|r| r.kind == RowKind::Normal)
                    .map(|r| r.contact)
                {
                    if !prev_active.contains(&c) {
                        constraints.push(gap_constraint(
                            model,
                            c,
                            j - 1,
                            cont[j - 1].2,
                            "landing",
                            0.0,
                            0.0,
                        ));
                    }
                }
            }
        }
    }

    /// The clearance of every primitive not in contact in continuous phase `j`, at every
    /// node but two: the first node after it was in contact, where the phase before holds
    /// its gap at zero (a row whose gradient the Baumgarte term has all but damped away:
    /// held active, its multiplier grows without bound; and a compliant contact leaves the
    /// ground with its pad still compressed), and the last before it lands, where the
    /// landing row sets the gap to zero (the same row twice).
    fn add_clearance(&self, j: usize, constraints: &mut Vec<Constraint<'a>>) {
        let (model, sets) = (self.model, self.sets);
        let cont = &self.layout.cont;
        let (i, _, n, _) = cont[j];
        let set = &sets[i];
        let active: Vec<usize> = set.rows.iter().map(|r| r.contact).collect();
        let was_active: Vec<usize> = if j > 0 {
            sets[cont[j - 1].0].rows.iter().map(|r| r.contact).collect()
        } else {
            Vec::new()
        };
        for (c, _) in model
            .contacts
            .iter()
            .enumerate()
            // a volumetric primitive penetrates the ground by design
            .filter(|(c, _)| !active.contains(c) && !model.is_volumetric(*c))
        {
            let first = usize::from(was_active.contains(&c));
            let last = if self.lands_after[j].contains(&c) {
                n - 1
            } else {
                n
            };
            for k in first..=last {
                constraints.push(gap_constraint(
                    model,
                    c,
                    j,
                    k,
                    "clearance",
                    0.0,
                    f64::INFINITY,
                ));
            }
        }
    }

    /// The trailing impact's landing contacts and periodicity through the symmetry map.
    fn add_cycle_constraints(&self, constraints: &mut Vec<Constraint<'a>>) {
        let (model, sets, spec) = (self.model, self.sets, self.spec);
        let (nx, nu) = (model.nx(), model.nu());
        let cont = &self.layout.cont;
        let last = cont.len() - 1;
        let n_last = cont[last].2;
        let trailing_impact = self.layout.trailing_impact;
        if let Some(ti) = trailing_impact {
            let prev_active: Vec<usize> =
                sets[cont[last].0].rows.iter().map(|r| r.contact).collect();
            for c in sets[ti]
                .rows
                .iter()
                .filter(|r| r.kind == RowKind::Normal)
                .map(|r| r.contact)
            {
                if !prev_active.contains(&c) {
                    constraints.push(gap_constraint(model, c, last, n_last, "landing", 0.0, 0.0));
                }
            }
        }
        if spec.periodic {
            let (xmap, umap) = mirror_maps(model, spec);
            let skip = 0usize; // pelvis_x is not periodic
            let impact = trailing_impact.map(|ti| sets[ti].clone());
            let f = AdTerm(Periodicity {
                model,
                impact,
                xmap,
                skip,
            });
            constraints.push(Constraint {
                term: Term {
                    name: "periodicity".into(),
                    args: vec![
                        Block::State { phase: 0, node: 0 },
                        Block::State {
                            phase: last,
                            node: n_last,
                        },
                        Block::Params,
                    ],
                    f: Arc::new(f),
                },
                lb: vec![0.0; nx - 1],
                ub: vec![0.0; nx - 1],
            });
            if spec.controls == ControlShape::Linear {
                let mut a = vec![0.0; nu * 2 * nu];
                for i in 0..nu {
                    a[i * 2 * nu + i] = 1.0;
                    a[i * 2 * nu + nu + umap[i]] = -1.0;
                }
                constraints.push(Constraint {
                    term: Term {
                        name: "control_periodicity".into(),
                        args: vec![
                            Block::Control { phase: 0, node: 0 },
                            Block::Control {
                                phase: last,
                                node: n_last,
                            },
                        ],
                        f: Arc::new(Linear::new(a, nu)),
                    },
                    lb: vec![0.0; nu],
                    ub: vec![0.0; nu],
                });
            }
        }
    }
}

/// The unilateral-contact and friction-cone rows of a contact set as one function of
/// `(x, u, θ)` with its bounds; `None` for a set without contacts. A rolling contact has
/// the two cone rows μλn − λt ≥ 0 and μλn + λt ≥ 0 only, which imply λn ≥ 0 (μ > 0): a
/// third row λn ≥ 0 would be active with them wherever the foot unloads (λn = λt = 0, at
/// every toe-off), three active rows with two independent gradients, and multipliers the
/// QP cannot determine. A contact without rolling has λn ≥ 0.
fn contact_force_rows<'a>(
    model: &'a GaitModel,
    set: &ConstraintSet,
    mu: f64,
) -> Option<(AdTerm<ContactForceRows<'a>>, Vec<f64>, Vec<f64>)> {
    let mut rows_lb = Vec::new();
    let mut rows_ub = Vec::new();
    let mut a_rows: Vec<Vec<(usize, f64)>> = Vec::new();
    for (r, row) in set.rows.iter().enumerate() {
        if row.kind == RowKind::Normal {
            let tangential = set
                .rows
                .iter()
                .position(|o| o.contact == row.contact && o.kind == RowKind::Tangential);
            match tangential {
                Some(t) if mu > 0.0 => {
                    a_rows.push(vec![(r, mu), (t, -1.0)]);
                    a_rows.push(vec![(r, mu), (t, 1.0)]);
                    rows_lb.extend([0.0, 0.0]);
                    rows_ub.extend([f64::INFINITY, f64::INFINITY]);
                }
                _ => {
                    a_rows.push(vec![(r, 1.0)]);
                    rows_lb.push(0.0);
                    rows_ub.push(f64::INFINITY);
                }
            }
        }
    }
    (!a_rows.is_empty()).then(|| {
        (
            AdTerm(ContactForceRows {
                model,
                set: set.clone(),
                rows: a_rows,
            }),
            rows_lb,
            rows_ub,
        )
    })
}

impl<'m> GaitCycle<'m> {
    /// The name of every phase of the phase file, in its order.
    pub fn phase_names(&self) -> Vec<String> {
        self.seq
            .phases
            .iter()
            .map(|p| p.name().to_string())
            .collect()
    }

    /// Friction coefficient of the cone (the phase file's, default 0.8).
    pub fn friction(&self) -> f64 {
        self.seq.gait.as_ref().map_or(0.8, |g| g.friction)
    }

    /// The check points at every site `(continuous phase, interval, τ)` of `sites`
    /// ([`contact_checks`](Self::contact_checks) of each).
    pub fn checks_at(&self, sites: &[(usize, usize, f64)]) -> Vec<CheckPoint<'m>> {
        sites
            .iter()
            .flat_map(|&(j, k, tau)| self.contact_checks(j, k, tau))
            .collect()
    }

    /// Check points that hold the contact constraints of continuous phase `j` at
    /// `(interval, τ)`: λn ≥ 0 and the friction cone of its contacts, and (when the phase
    /// file asks for clearance) every primitive not in contact above the ground, as the
    /// node constraints hold them at the nodes.
    pub fn contact_checks(&self, j: usize, interval: usize, tau: f64) -> Vec<CheckPoint<'m>> {
        let model = self.model;
        let set = &self.sets[self.continuous[j]];
        let mut out = Vec::new();
        if let Some((f, lb, ub)) = contact_force_rows(model, set, self.friction()) {
            out.push(CheckPoint {
                name: "contact_forces".into(),
                phase: j,
                interval,
                tau,
                f: Arc::new(f),
                lb,
                ub,
            });
        }
        if self.seq.gait.as_ref().is_none_or(|g| g.clearance) {
            let active: Vec<usize> = set.rows.iter().map(|r| r.contact).collect();
            for c in (0..model.contacts.len())
                .filter(|&c| !active.contains(&c) && !model.is_volumetric(c))
            {
                let f = AdTerm(GapOfState { model, contact: c });
                out.push(CheckPoint {
                    name: format!("clearance({})", model.contacts[c].name),
                    phase: j,
                    interval,
                    tau,
                    f: Arc::new(f),
                    lb: vec![0.0],
                    ub: vec![f64::INFINITY],
                });
            }
        }
        out
    }
}

/// Where the instant `t` (s) of phase-file phase `set` falls in a solution's continuous
/// phases: (continuous phase, interval, τ) with τ in (0, 1), or `None` at a node (where
/// the node constraints already hold) or outside every phase.
pub fn locate_instant(
    solution: &super::evaluation::GaitSolution,
    set: usize,
    t: f64,
) -> Option<(usize, usize, f64)> {
    let (j, ph) = solution
        .phases
        .iter()
        .enumerate()
        .find(|(_, p)| p.set == set && t >= p.t0 - 1e-12 && t <= p.t0 + p.duration + 1e-12)?;
    let n = ph.intervals();
    let s = ((t - ph.t0) / ph.duration * n as f64).clamp(0.0, n as f64);
    let k = (s.floor() as usize).min(n - 1);
    let tau = s - k as f64;
    (tau > 1e-6 && tau < 1.0 - 1e-6).then_some((j, k, tau))
}

fn impact_term<'a>(
    model: &'a GaitModel,
    set: &ConstraintSet,
    n_prev: usize,
    prev: usize,
) -> Term<'a> {
    let f = AdTerm(ImpactMap {
        model,
        set: set.clone(),
    });
    Term {
        name: "impact".into(),
        args: vec![
            Block::State {
                phase: prev,
                node: n_prev,
            },
            Block::Params,
        ],
        f: Arc::new(f),
    }
}

fn gap_constraint<'a>(
    model: &'a GaitModel,
    c: usize,
    phase: usize,
    node: usize,
    name: &str,
    lb: f64,
    ub: f64,
) -> Constraint<'a> {
    let cname = model.contacts[c].name.clone();
    let f = AdTerm(Gap { model, contact: c });
    Constraint {
        term: Term {
            name: format!("{name}({cname})"),
            args: vec![Block::State { phase, node }, Block::Params],
            f: Arc::new(f),
        },
        lb: vec![lb],
        ub: vec![ub],
    }
}

mod functions;

pub(crate) use functions::ImpulseRows;
use functions::{ContactForceRows, Gap, GapOfState, ImpactMap, Periodicity};
