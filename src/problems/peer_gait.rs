//! The CasADi gait peer's tracking problem, exactly as its problem file defines it
//! (`problems/peer_gait_track_ellipse.json`, a copy of
//! `shared/peer_gait/problem/gait_track_ellipse.json` with a `footfall` block naming the
//! model and foot files that realise its body): one measured gait cycle, torque driven,
//! rigid ellipse feet, phases DS1 → SS_R → impact → DS2 → SS_L → terminal impact with
//! [7, 18, 7, 18] intervals of fixed duration, the peer's cost weights, references at the
//! cost nodes and initial guess from the data.
//!
//! What the walking-cycle OCP ([`super::gait`]) already holds is taken from it: node
//! states and controls, impact maps, the landing rows, swing clearance at the inner nodes
//! of single stance, and the friction cone at every node with that node's interval
//! control. This module adds what a non-periodic tracked cycle needs beside it: the first
//! node at rest on the double-stance manifold (`G q̇ = 0`), the landing foot's impulse in
//! the friction cone at both impacts, and the peer's least-squares cost:
//!
//! `J = Σₙ [Σₐ w_θ(q−θ)² + w_ω(q̇−ω)² + Σ_feet (w_cop (x_cp−cop)² + w_f((fx−fx̂)² + (fy−fŷ)²))
//!      + w_τ Σ (τ/τ_ref)²] + terminal angle and velocity terms + w_Λ Σ Λ²`
//!
//! over the 50 interval starts. The peer's optimum, J* = 1.2584987, is the check.

use super::error::{FieldError, PeerGaitError, ProblemError};
use super::gait::{GaitCycle, GaitGuess, ImpulseRows};
use super::{AdTerm, GenericFunction};
use crate::integrate::IntegratorSettings;
use crate::model::effects::ModelScalar;
use crate::model::gait::COORDINATES;
use crate::model::{ConstraintSet, GaitModel, RowKind};
use crate::ocp::{Block, Constraint, Ocp, Term};
use crate::phases::PhaseSequence;
use crate::sqp::{ExactConvexification, HessianMode, SqpSettings};
use serde_json::Value;
use std::path::Path;
use std::sync::Arc;

mod problem_file;

use problem_file::{cost_nodes, field, initial_guess, number, peer_model, peer_phases, PeerPhases};

/// The feet in the problem file's order: right, then left.
const FEET: [&str; 2] = ["r", "l"];

/// The references and weights of one cost node (the start of a shooting interval).
#[derive(Debug, Clone)]
struct NodeTargets {
    /// Continuous phase index.
    phase: usize,
    /// Interval (= node) index within the phase.
    node: usize,
    /// Angle references of the tracked coordinates (rad).
    theta: Vec<f64>,
    /// Angular velocity references (rad/s).
    omega: Vec<f64>,
    /// The feet in contact.
    feet: Vec<FootTarget>,
}

/// The references of one foot in contact at a cost node.
#[derive(Debug, Clone, Copy)]
struct FootTarget {
    /// Foot: 0 right, 1 left.
    side: usize,
    /// Tangential force reference (N).
    fx: f64,
    /// Normal force reference (N).
    fy: f64,
    /// CoP reference (m) and its weight (1/m²), where the CoP is weighted.
    cop: Option<(f64, f64)>,
}

/// The peer's tracking problem with the model that realises its body.
pub struct PeerGaitTrack {
    /// The model (torque driven, ellipse feet), loaded from the `footfall` block's files.
    pub model: GaitModel,
    /// The phases of the problem file as a phase sequence (non-periodic).
    pub seq: PhaseSequence,
    /// Constraint set of every phase of `seq`.
    pub sets: Vec<ConstraintSet>,
    /// Contact index of each foot's primitive (right, left).
    contacts: [usize; 2],
    /// Indices of the tracked coordinates in `q`.
    tracked: Vec<usize>,
    w_theta: Vec<f64>,
    w_omega: Vec<f64>,
    w_force: f64,
    w_torque: f64,
    w_impulse: f64,
    friction: f64,
    nodes: Vec<NodeTargets>,
    terminal_theta: Vec<f64>,
    terminal_omega: Vec<f64>,
    guess: GaitGuess,
}

impl PeerGaitTrack {
    /// Build the problem from the problem file's JSON `json` (read from `path`, against
    /// which the `footfall` block's files are resolved). Refuses a model whose mass matrix
    /// and bias forces differ from the file's check values: the problem is only the
    /// peer's if the body is.
    pub fn from_json(json: &Value, path: &Path) -> Result<Self, PeerGaitError> {
        let (model, contacts) = peer_model(json, path)?;
        let PeerPhases {
            seq,
            sets,
            intervals,
            friction,
        } = peer_phases(json, path, &model, contacts)?;
        let guess = initial_guess(json, &model, &intervals)?;
        let unit = model.torque_unit().expect("checked above");

        // cost
        let names = || FieldError::kind("/cost/tracked", "an array of coordinate names");
        let tracked_names: Vec<String> = field(json, "/cost/tracked")?
            .as_array()
            .ok_or_else(names)?
            .iter()
            .map(|v| v.as_str().map(String::from).ok_or_else(names))
            .collect::<Result<_, _>>()?;
        let tracked = tracked_names
            .iter()
            .map(|n| {
                COORDINATES.iter().position(|c| c == n).ok_or_else(|| {
                    PeerGaitError::UnknownCoordinate {
                        coordinate: n.clone(),
                    }
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let per = |ptr: &str| -> Result<Vec<f64>, FieldError> {
            tracked_names
                .iter()
                .map(|n| number(json, &format!("{ptr}/{n}")))
                .collect()
        };
        let w_theta = per("/cost/w_theta")?;
        let w_omega = per("/cost/w_omega")?;
        let w_force = number(json, "/cost/w_f")?;
        let w_torque = number(json, "/cost/w_tau")?;
        let tau_ref = number(json, "/cost/tau_ref_Nm")?;
        if (tau_ref - unit).abs() > 1e-12 * unit {
            return Err(PeerGaitError::TorqueUnit { tau_ref, unit });
        }
        let w_impulse = number(json, "/cost/w_impulse")?;
        let nodes = cost_nodes(json, &tracked_names, &intervals)?;
        let terminal_theta = per("/references/terminal/theta")?;
        let terminal_omega = per("/references/terminal/omega")?;
        Ok(Self {
            model,
            seq,
            sets,
            contacts,
            tracked,
            w_theta,
            w_omega,
            w_force,
            w_torque,
            w_impulse,
            friction,
            nodes,
            terminal_theta,
            terminal_omega,
            guess,
        })
    }

    /// The walking cycle of the problem's phases.
    pub fn cycle(&self) -> Result<GaitCycle<'_>, ProblemError> {
        GaitCycle::new(&self.model, &self.seq, &self.sets)
    }

    /// The optimal control problem on `cycle` (from [`cycle`](Self::cycle)).
    pub fn ocp<'c>(
        &'c self,
        cycle: &'c GaitCycle<'c>,
        integrator: IntegratorSettings,
    ) -> Result<Ocp<'c>, ProblemError> {
        let model = &self.model;
        let mut ocp = cycle.ocp(&self.guess, integrator)?;
        let cont = &cycle.continuous;
        let last = cont.len() - 1;
        // the first node at rest on the contact manifold of its phase
        let first = &self.sets[cont[0]];
        ocp.constraints.push(Constraint {
            term: Term {
                name: "at_rest(first node)".into(),
                args: vec![Block::State { phase: 0, node: 0 }, Block::Params],
                f: Arc::new(AdTerm(ContactVelocity {
                    model,
                    set: first.clone(),
                })),
            },
            lb: vec![0.0; first.rows.len()],
            ub: vec![0.0; first.rows.len()],
        });
        // impacts after continuous phase j (the last one after the final phase): the
        // impulses are costed, the landing foot's kept in the friction cone
        for (j, &i) in cont.iter().enumerate() {
            let impact = i + 1;
            let Some(crate::phases::Phase::Impact { name, .. }) = self.seq.phases.get(impact)
            else {
                continue;
            };
            let (before, after) = (&self.sets[i], &self.sets[impact]);
            let pre = Block::State {
                phase: j,
                node: ocp.phases[j].intervals,
            };
            let scale = self.w_impulse.sqrt();
            ocp.least_squares.push(Term {
                name: format!("impulses({name})"),
                args: vec![pre, Block::Params],
                f: Arc::new(AdTerm(ImpulseRows::scaled(model, after, scale))),
            });
            let mut cone = Vec::new();
            for (r, row) in after.rows.iter().enumerate() {
                let landing = !before.rows.iter().any(|b| b.contact == row.contact);
                if landing && row.kind == RowKind::Normal {
                    if let Some(t) = after
                        .rows
                        .iter()
                        .position(|o| o.contact == row.contact && o.kind == RowKind::Tangential)
                    {
                        cone.push(vec![(r, self.friction), (t, -1.0)]);
                        cone.push(vec![(r, self.friction), (t, 1.0)]);
                    }
                }
            }
            if !cone.is_empty() {
                let n = cone.len();
                ocp.constraints.push(Constraint {
                    term: Term {
                        name: format!("impulse_cone({name})"),
                        args: vec![pre, Block::Params],
                        f: Arc::new(AdTerm(ImpulseRows::new(model, after, cone))),
                    },
                    lb: vec![0.0; n],
                    ub: vec![f64::INFINITY; n],
                });
            }
        }
        // tracking at the start of every interval, with that interval's torques
        let sq = |w: &[f64]| w.iter().map(|v| v.sqrt()).collect::<Vec<_>>();
        let (sw_theta, sw_omega) = (sq(&self.w_theta), sq(&self.w_omega));
        for t in &self.nodes {
            ocp.least_squares.push(Term {
                name: "tracking".into(),
                args: vec![
                    Block::State {
                        phase: t.phase,
                        node: t.node,
                    },
                    Block::Control {
                        phase: t.phase,
                        node: t.node,
                    },
                    Block::Params,
                ],
                f: Arc::new(AdTerm(NodeResidual {
                    model,
                    set: self.sets[cont[t.phase]].clone(),
                    contacts: self.contacts,
                    tracked: self.tracked.clone(),
                    sw_theta: sw_theta.clone(),
                    sw_omega: sw_omega.clone(),
                    sw_force: self.w_force.sqrt(),
                    sw_torque: self.w_torque.sqrt(),
                    targets: t.clone(),
                })),
            });
        }
        // the terminal (pre-impact) node's angles and angular velocities
        ocp.least_squares.push(Term {
            name: "tracking(terminal)".into(),
            args: vec![Block::State {
                phase: last,
                node: ocp.phases[last].intervals,
            }],
            f: Arc::new(AdTerm(TerminalResidual {
                nq: model.nq(),
                tracked: self.tracked.clone(),
                sw_theta,
                sw_omega,
                theta: self.terminal_theta.clone(),
                omega: self.terminal_omega.clone(),
            })),
        });
        Ok(ocp)
    }
}

/// One stage of [`stages`]: the integrator and the SQP settings it solves with.
#[derive(Debug, Clone)]
pub struct SolveStage {
    /// CVODES settings of the shooting intervals.
    pub integrator: IntegratorSettings,
    /// SQP settings (the iteration limit is what is left of the whole solve's).
    pub settings: SqpSettings,
}

/// CVODES tolerance (relative and absolute) of the first stage of [`stages`].
pub const STAGE1_TOL: f64 = 1e-6;

/// CVODES tolerance (relative and absolute) of the second stage of [`stages`].
pub const STAGE2_TOL: f64 = 1e-12;

/// KKT residual at which [`stages`] hands over from block BFGS to the exact Hessian.
pub const EXACT_BELOW_KKT: f64 = 1e-3;

/// How the problem is solved from its data guess, to the KKT tolerance `tol`:
/// 1. block BFGS (per node) with CVODES at [`STAGE1_TOL`], until the KKT residual is
///    [`EXACT_BELOW_KKT`]. The exact Hessian of the Lagrangian is far from convex on the
///    way: from the data its inertia correction needed shifts of 1e2–4e3 and crawled at
///    J = 1.3096 (KKT 2e-2) for hundreds of iterations, where BFGS walks on to the
///    peer's optimum. Its line search compares objectives that differ by far more than
///    the states' error at that tolerance, and a shooting interval takes about half the
///    steps it takes at 1e-8;
/// 2. the exact Hessian (inertia correction) with CVODES at [`STAGE2_TOL`]: near the
///    optimum it is convex on the active constraints' null space, and the tight
///    integration keeps its noise below the line search's (at 1e-8 both Hessians stall
///    at KKT 1e-5 to 1e-6 with every step rejected, at 1e-10 the exact one at 3e-5;
///    at 1e-12 it converges in about 10 iterations).
///
/// In both the sensitivities are integrated at a tenth of the stage's KKT tolerance
/// ([`IntegratorSettings::sensitivities_for_kkt_tol`]), never tighter than the states.
pub fn stages(tol: f64) -> [SolveStage; 2] {
    let base = IntegratorSettings::default();
    [
        SolveStage {
            integrator: IntegratorSettings {
                rtol: STAGE1_TOL,
                atol: STAGE1_TOL,
                ..base.clone()
            }
            .sensitivities_for_kkt_tol(tol.max(EXACT_BELOW_KKT)),
            settings: SqpSettings {
                tol_kkt: tol.max(EXACT_BELOW_KKT),
                hessian: HessianMode::Bfgs,
                ..Default::default()
            },
        },
        SolveStage {
            integrator: IntegratorSettings {
                rtol: STAGE2_TOL,
                atol: STAGE2_TOL,
                ..base
            }
            .sensitivities_for_kkt_tol(tol),
            settings: SqpSettings {
                tol_kkt: tol,
                hessian: HessianMode::Exact,
                exact_convexification: ExactConvexification::InertiaCorrection,
                ..Default::default()
            },
        },
    ]
}

/// `G q̇` of every row of a contact set. Arguments: `(x, θ)`.
struct ContactVelocity<'a> {
    model: &'a GaitModel,
    set: ConstraintSet,
}

impl GenericFunction for ContactVelocity<'_> {
    fn dim(&self) -> usize {
        self.set.rows.len()
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), crate::ocp::TermError> {
        let nx = self.model.nx();
        let v = self
            .model
            .constraint_velocity(&self.set, &z[..nx], &z[nx..]);
        out.copy_from_slice(&v);
        Ok(())
    }
}

/// The weighted residuals of one cost node: tracked angles and angular velocities, each
/// loaded foot's forces and contact-point CoP, and the torques. Arguments: `(x, u, θ)`.
struct NodeResidual<'a> {
    model: &'a GaitModel,
    set: ConstraintSet,
    contacts: [usize; 2],
    tracked: Vec<usize>,
    sw_theta: Vec<f64>,
    sw_omega: Vec<f64>,
    sw_force: f64,
    sw_torque: f64,
    targets: NodeTargets,
}

impl GenericFunction for NodeResidual<'_> {
    fn dim(&self) -> usize {
        let feet: usize = self
            .targets
            .feet
            .iter()
            .map(|f| 2 + usize::from(f.cop.is_some()))
            .sum();
        2 * self.tracked.len() + feet + self.model.nu()
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), crate::ocp::TermError> {
        let (nx, nu, nq) = (self.model.nx(), self.model.nu(), self.model.nq());
        let (x, rest) = z.split_at(nx);
        let (u, th) = rest.split_at(nu);
        let t = &self.targets;
        let mut o = 0;
        for (a, &c) in self.tracked.iter().enumerate() {
            out[o] = (x[c] - S::c(t.theta[a])) * S::c(self.sw_theta[a]);
            out[o + 1] = (x[nq + c] - S::c(t.omega[a])) * S::c(self.sw_omega[a]);
            o += 2;
        }
        if !t.feet.is_empty() {
            let loads = self.model.foot_loads_generic(&self.set, x, u, th)?;
            for f in &t.feet {
                let s = f.side;
                out[o] = (loads[s].0 - S::c(f.fx)) * S::c(self.sw_force);
                out[o + 1] = (loads[s].1 - S::c(f.fy)) * S::c(self.sw_force);
                o += 2;
                if let Some((cop, w)) = f.cop {
                    let (pt, _) = self
                        .model
                        .contact_point_generic(self.contacts[s], &x[..nq], th);
                    out[o] = (pt[0] - S::c(cop)) * S::c(w.sqrt());
                    o += 1;
                }
            }
        }
        for (i, ui) in u.iter().enumerate() {
            out[o + i] = *ui * S::c(self.sw_torque);
        }
        Ok(())
    }
    fn curved_inputs(&self) -> Option<(Vec<usize>, usize)> {
        Some(self.model.curved_inputs())
    }
}

/// The terminal node's weighted angle and angular-velocity residuals. Argument: `x`.
struct TerminalResidual {
    nq: usize,
    tracked: Vec<usize>,
    sw_theta: Vec<f64>,
    sw_omega: Vec<f64>,
    theta: Vec<f64>,
    omega: Vec<f64>,
}

impl GenericFunction for TerminalResidual {
    fn dim(&self) -> usize {
        2 * self.tracked.len()
    }
    fn eval<S: ModelScalar>(&self, z: &[S], out: &mut [S]) -> Result<(), crate::ocp::TermError> {
        for (a, &c) in self.tracked.iter().enumerate() {
            out[2 * a] = (z[c] - S::c(self.theta[a])) * S::c(self.sw_theta[a]);
            out[2 * a + 1] = (z[self.nq + c] - S::c(self.omega[a])) * S::c(self.sw_omega[a]);
        }
        Ok(())
    }
    fn is_linear(&self) -> bool {
        true
    }
}
