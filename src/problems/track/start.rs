//! The tracking problem's start from the measured trial's own dynamics: the inverse
//! dynamics of the smoothed data give the joint torques at every node, and static
//! optimisation turns them into the actuators' activations (or joint-torque controls),
//! the route of Wang, Guo & Tian (2022): static optimisation first, its activations as
//! the initial values of the dynamic problem.
//!
//! Every actuator acts on one joint and its generalised force is affine in its
//! activation (a muscle-torque generator, Millard & Mombaur 2019 eq. 9) or its control
//! (a joint torque). At a node the model's forces with every actuator idle (activation
//! 0.01, the data guess's, or zero torque: damping, effects, the idle activations) leave
//! `d = τ_ID − τ₀` to the actuators of each joint; the least-squares activations that
//! give it use only the actuator pulling the right way, `a = 0.01 + d / g` with `g` its
//! torque per unit activation, clipped to the bounds. The
//! excitations follow from the activation dynamics, `e = a + T ȧ` (eq. 10).

use crate::data::GaitData;
use crate::model::GaitModel;
use crate::problems::check::balance::{inverse_dynamics, Body};
use crate::problems::check::signals::Signals;
use crate::problems::error::ProblemError;
use crate::problems::gait::GaitGuess;

/// Where a tracking solve from the data starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Guess {
    /// The measured states projected onto the contacts, activations 0.01 and excitations
    /// 0.025 (Millard & Mombaur 2019, §3.6).
    #[default]
    Data,
    /// The measured states projected onto the contacts, activations and excitations from
    /// the inverse dynamics by static optimisation ([`from_inverse_dynamics`]).
    InverseDynamics,
}

impl Guess {
    /// Whether this is the default, [`Guess::Data`].
    pub fn is_data(&self) -> bool {
        *self == Guess::Data
    }
}

/// Low-pass cutoff (Hz) of the kinematics and loads the inverse dynamics read (the
/// measurement check's default).
const CUTOFF_HZ: f64 = 6.0;

/// The activation of an actuator that does not act (the data guess's, Millard & Mombaur
/// 2019 §3.6).
const IDLE_ACTIVATION: f64 = 0.01;

/// What the start did: the nodes it set from the inverse dynamics out of all nodes, and
/// the joint torques the actuators could not reach (saturated at a bound).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StartReport {
    /// Nodes whose activations come from the inverse dynamics.
    pub set: usize,
    /// All nodes.
    pub nodes: usize,
    /// Joint-node pairs whose torque needed more than the actuator's bound.
    pub saturated: usize,
}

/// One actuator of a joint: its variable (an activation state or a control) and its
/// generalised force per unit of that variable at a node.
struct Lever {
    var: usize,
    gain: f64,
}

/// Set `guess`'s activations (or joint-torque controls) and excitations from the inverse
/// dynamics of `data` at the nodes `node_times` (per continuous phase, as `guess.x`).
/// Nodes where a foot's load is not measured keep their guess.
pub fn from_inverse_dynamics(
    model: &GaitModel,
    data: &GaitData,
    node_times: &[Vec<f64>],
    guess: &mut GaitGuess,
) -> Result<StartReport, ProblemError> {
    let body = Body::of(model)?;
    let signals = Signals::new(data, CUTOFF_HZ, 0.0)?;
    let nq = model.nq();
    let bounds = if model.na() > 0 {
        (guess.x_lb[2 * nq..].to_vec(), guess.x_ub[2 * nq..].to_vec())
    } else {
        (guess.u_lb.clone(), guess.u_ub.clone())
    };
    let mut report = StartReport::default();
    for (p, times) in node_times.iter().enumerate() {
        let mut activations = Vec::with_capacity(times.len());
        for (k, &t) in times.iter().enumerate() {
            report.nodes += 1;
            let x = &mut guess.x[p][k];
            let Some(tau) = inverse_dynamics(&body, &signals, model, t) else {
                activations.push(None);
                continue;
            };
            // a node without a control of its own (piecewise-constant controls' last)
            let mut none = vec![0.0; model.nu()];
            let u = guess.u[p].get_mut(k).unwrap_or(&mut none);
            report.saturated += static_optimisation(model, &tau, x, u, &bounds);
            report.set += 1;
            activations.push(Some(x[2 * nq..].to_vec()));
        }
        if model.na() > 0 {
            excitations(model, times, &activations, &mut guess.u[p], &guess.u_ub);
        }
    }
    Ok(report)
}

/// At one node: the activations in `x` (or the torque controls in `u`) within their
/// bounds `(lb, ub)` that give the joint torques `tau`; the number of joints whose torque is beyond the bounds.
fn static_optimisation(
    model: &GaitModel,
    tau: &[f64],
    x: &mut [f64],
    u: &mut [f64],
    (lb, ub): &(Vec<f64>, Vec<f64>),
) -> usize {
    let nq = model.nq();
    let mtg = model.na() > 0;
    let n = if mtg {
        model.na()
    } else {
        model.nu_actuators()
    };
    let idle = if mtg { IDLE_ACTIVATION } else { 0.0 };
    let mut idle_x = x.to_vec();
    let mut idle_u = vec![0.0; model.nu()];
    idle_x[2 * nq..].iter_mut().for_each(|a| *a = idle);
    let theta = model.theta0();
    let passive = total(model, &idle_x, &idle_u, &theta);
    // each actuator's joint and gain, by a unit change of its variable
    let mut levers: Vec<Vec<Lever>> = (0..nq).map(|_| Vec::new()).collect();
    for var in 0..n {
        let (mut xv, mut uv) = (idle_x.clone(), idle_u.clone());
        if mtg {
            xv[2 * nq + var] += 1.0;
        } else {
            uv[var] += 1.0;
        }
        let moved = total(model, &xv, &uv, &theta);
        if let Some((c, gain)) = (0..nq)
            .map(|c| (c, moved[c] - passive[c]))
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .filter(|(_, g)| *g != 0.0)
        {
            levers[c].push(Lever { var, gain });
        }
    }
    let mut saturated = 0;
    for (c, joint) in levers.iter().enumerate() {
        let need = tau[c] - passive[c];
        let mut value = vec![None; joint.len()];
        if let Some((i, l)) = joint
            .iter()
            .enumerate()
            .filter(|(_, l)| l.gain * need > 0.0 || !mtg)
            .max_by(|a, b| a.1.gain.abs().total_cmp(&b.1.gain.abs()))
        {
            let v = idle + need / l.gain;
            // an activation stays at least idle; a joint torque may take either sign
            let lo = if mtg { lb[l.var].max(idle) } else { lb[l.var] };
            let clipped = v.clamp(lo.min(ub[l.var]), ub[l.var]);
            saturated += usize::from(clipped != v);
            value[i] = Some(clipped);
        }
        for (l, v) in joint.iter().zip(value) {
            let v = v.unwrap_or(idle);
            if mtg {
                idle_x[2 * nq + l.var] = v;
            } else {
                idle_u[l.var] = v;
            }
        }
    }
    x[2 * nq..].copy_from_slice(&idle_x[2 * nq..]);
    if !mtg {
        u[..n].copy_from_slice(&idle_u[..n]);
    }
    saturated
}

/// The model's generalised forces at state `x`, controls `u` (N or N·m per coordinate).
fn total(model: &GaitModel, x: &[f64], u: &[f64], theta: &[f64]) -> Vec<f64> {
    let parts = model.generalized_force_parts(x, u, theta);
    let mut tau = parts.actuators;
    for (_, f) in &parts.effects {
        tau.iter_mut().zip(f).for_each(|(t, v)| *t += v);
    }
    tau
}

/// The excitations at the control nodes from the activations at the state nodes:
/// `e = a + T ȧ` (the activation dynamics inverted, ȧ by central differences), within
/// the excitations' bounds; nodes without activations keep their guess.
fn excitations(
    model: &GaitModel,
    times: &[f64],
    activations: &[Option<Vec<f64>>],
    u: &mut [Vec<f64>],
    u_ub: &[f64],
) {
    let Some(time_constant) = model.activation_time_constant() else {
        return;
    };
    let last = times.len() - 1;
    for (k, uk) in u.iter_mut().enumerate() {
        let (i, j) = (k.saturating_sub(1), (k + 1).min(last));
        let (Some(a), Some(ai), Some(aj)) = (&activations[k], &activations[i], &activations[j])
        else {
            continue;
        };
        let dt = times[j] - times[i];
        for (m, e) in uk.iter_mut().take(a.len()).enumerate() {
            let rate = if dt > 0.0 { (aj[m] - ai[m]) / dt } else { 0.0 };
            *e = (a[m] + time_constant * rate).clamp(0.0, u_ub[m]);
        }
    }
}
