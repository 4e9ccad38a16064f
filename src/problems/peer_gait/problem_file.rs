//! The peer's problem file read: its model (checked against the file's body), its
//! phases as a phase sequence, its bounds and initial guess, and the references of its cost
//! nodes.

use super::{FootTarget, NodeTargets, FEET};
use crate::model::{ConstraintSet, GaitModel};
use crate::phases::PhaseSequence;
use crate::problems::error::{dotted, FieldError, PeerGaitError};
use crate::problems::gait::GaitGuess;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// The value at the JSON pointer `ptr` of `v`.
pub(super) fn field<'v>(v: &'v Value, ptr: &str) -> Result<&'v Value, FieldError> {
    v.pointer(ptr).ok_or_else(|| FieldError::missing(ptr))
}

/// The number at the JSON pointer `ptr` of `v`.
pub(super) fn number(v: &Value, ptr: &str) -> Result<f64, FieldError> {
    field(v, ptr)?
        .as_f64()
        .ok_or_else(|| FieldError::kind(ptr, "a number"))
}

/// The array of numbers at the JSON pointer `ptr` of `v` (of `len` entries, where given).
pub(super) fn numbers(v: &Value, ptr: &str, len: Option<usize>) -> Result<Vec<f64>, FieldError> {
    let a = field(v, ptr)?
        .as_array()
        .ok_or_else(|| FieldError::kind(ptr, "an array of numbers"))?;
    if let Some(n) = len {
        if a.len() != n {
            return Err(FieldError::Length {
                field: dotted(ptr),
                found: a.len(),
                expected: n,
            });
        }
    }
    a.iter()
        .enumerate()
        .map(|(i, x)| {
            x.as_f64().ok_or_else(|| FieldError::Kind {
                field: format!("{}[{i}]", dotted(ptr)),
                expected: "a number",
            })
        })
        .collect()
}

/// The string at the JSON pointer `ptr` of `v`.
pub(super) fn string<'v>(v: &'v Value, ptr: &str) -> Result<&'v str, FieldError> {
    field(v, ptr)?
        .as_str()
        .ok_or_else(|| FieldError::kind(ptr, "a string"))
}

/// The model of the problem file's `footfall` block (its files resolved against the
/// folder of `path`), refused unless torque driven and of the file's body, and the contact
/// index of each foot's primitive (right, left).
pub(super) fn peer_model(
    json: &Value,
    path: &Path,
) -> Result<(GaitModel, [usize; 2]), PeerGaitError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let file = |ptr: &str| -> Result<PathBuf, FieldError> { Ok(dir.join(string(json, ptr)?)) };
    let model_path = file("/footfall/model")?;
    let foot_path = file("/footfall/foot")?;
    let model = GaitModel::load(&model_path, &foot_path)?;
    if model.na() > 0 || model.torque_unit().is_none() {
        return Err(PeerGaitError::NotTorqueDriven { model: model_path });
    }
    check_body(&model, json)?;
    let [right, left] = [0, 1].map(|s| {
        let name = string(json, &format!("/footfall/contacts/{}", FEET[s]))?;
        model
            .contact_index(name)
            .ok_or_else(|| PeerGaitError::UnknownContact {
                side: FEET[s],
                contact: name.to_string(),
            })
    });
    Ok((model, [right?, left?]))
}

/// The problem file's phases and transitions as a phase sequence.
pub(super) struct PeerPhases {
    /// The phases (non-periodic).
    pub(super) seq: PhaseSequence,
    /// Constraint set of every phase of `seq`.
    pub(super) sets: Vec<ConstraintSet>,
    /// Intervals of each continuous phase.
    pub(super) intervals: Vec<usize>,
    /// Friction coefficient μ.
    pub(super) friction: f64,
}

/// The feet listed at `ptr` as the contact entries of a phase file (`contacts`: the
/// contact index of each foot's primitive).
fn contact_list(
    json: &Value,
    ptr: &str,
    model: &GaitModel,
    contacts: [usize; 2],
) -> Result<Vec<Value>, PeerGaitError> {
    let feet = field(json, ptr)?
        .as_array()
        .ok_or_else(|| FieldError::kind(ptr, "an array"))?;
    feet.iter()
        .map(|f| {
            let s = FEET
                .iter()
                .position(|n| Some(*n) == f.as_str())
                .ok_or_else(|| PeerGaitError::UnknownFoot {
                    field: dotted(ptr),
                    foot: f.clone(),
                })?;
            Ok(json!({ "contact": model.contacts[contacts[s]].name }))
        })
        .collect()
}

/// The phase sequence of the problem file `json` (read from `path`), validated and
/// resolved for `model` (`contacts`: the contact index of each foot's primitive).
pub(super) fn peer_phases(
    json: &Value,
    path: &Path,
    model: &GaitModel,
    contacts: [usize; 2],
) -> Result<PeerPhases, PeerGaitError> {
    let phases = field(json, "/phases")?
        .as_array()
        .ok_or_else(|| FieldError::kind("/phases", "an array"))?;
    let transitions = field(json, "/transitions")?
        .as_array()
        .ok_or_else(|| FieldError::kind("/transitions", "an array"))?;
    let impact_after = impacts_after(json, transitions, phases.len(), model, contacts)?;
    let mut seq_phases = Vec::new();
    let mut intervals = Vec::new();
    for (j, _) in phases.iter().enumerate() {
        let n = number(json, &format!("/phases/{j}/intervals"))?;
        if !(n >= 1.0 && n.fract() == 0.0) {
            return Err(PeerGaitError::Intervals { phase: j });
        }
        intervals.push(n as usize);
        seq_phases.push(json!({
            "type": "continuous",
            "name": string(json, &format!("/phases/{j}/name"))?,
            "contacts": contact_list(json, &format!("/phases/{j}/contacts"), model, contacts)?,
            "intervals": n as usize,
            "duration": number(json, &format!("/phases/{j}/duration"))?,
        }));
        if let Some((name, feet)) = &impact_after[j] {
            seq_phases.push(json!({ "type": "impact", "name": name, "contacts": feet }));
        }
    }
    let friction = number(json, "/constraints/friction_mu")?;
    let seq: PhaseSequence = serde_json::from_value(json!({
        "name": string(json, "/name")?,
        "description": string(json, "/summary").unwrap_or(""),
        "phases": seq_phases,
        "gait": { "friction": friction, "periodic": false, "clearance": true, "controls": "constant" },
    }))
    .map_err(|source| PeerGaitError::Phases { source })?;
    seq.validate(path)?;
    let sets = seq.resolve(model, path)?;
    Ok(PeerPhases {
        seq,
        sets,
        intervals,
        friction,
    })
}

/// The impacts of the problem file's `transitions`: after continuous phase j (of
/// `phases`; the terminal one after the last), its name and the contact entries of the
/// feet after it.
#[allow(clippy::type_complexity)]
fn impacts_after(
    json: &Value,
    transitions: &[Value],
    phases: usize,
    model: &GaitModel,
    contacts: [usize; 2],
) -> Result<Vec<Option<(String, Vec<Value>)>>, PeerGaitError> {
    let mut impact_after: Vec<Option<(String, Vec<Value>)>> = vec![None; phases];
    let mut j = 0usize;
    for (t, tr) in transitions.iter().enumerate() {
        match string(tr, "/type")? {
            "initial" => {}
            "continuous" => j += 1,
            "impact" | "terminal impact" => {
                let at = string(tr, "/at").unwrap_or("impact");
                let name = at
                    .split('(')
                    .nth(1)
                    .map_or("impact", |s| s.trim_end_matches(')'));
                let slot = impact_after
                    .get_mut(j)
                    .ok_or(PeerGaitError::ImpactAfterEnd { transition: t })?;
                *slot = Some((
                    name.to_string(),
                    contact_list(
                        json,
                        &format!("/transitions/{t}/feet_after"),
                        model,
                        contacts,
                    )?,
                ));
                j += 1;
            }
            other => {
                return Err(PeerGaitError::UnknownTransition {
                    transition: t,
                    kind: other.to_string(),
                })
            }
        }
    }
    Ok(impact_after)
}

/// The bounds and initial guess of the problem file: state bounds, torque bounds (in the
/// model's torque unit) and the guess at the nodes of the continuous phases of
/// `intervals`, the torques clamped into their bounds.
pub(super) fn initial_guess(
    json: &Value,
    model: &GaitModel,
    intervals: &[usize],
) -> Result<GaitGuess, PeerGaitError> {
    let nq = model.nq();
    let mut x_lb = numbers(json, "/constraints/bounds/q_lb", Some(nq))?;
    x_lb.extend(numbers(json, "/constraints/bounds/qd_lb", Some(nq))?);
    let mut x_ub = numbers(json, "/constraints/bounds/q_ub", Some(nq))?;
    x_ub.extend(numbers(json, "/constraints/bounds/qd_ub", Some(nq))?);
    let unit = model.torque_unit().expect("checked above");
    let tau_max = number(json, "/constraints/bounds/tau_max_Nm")?;
    let nu = model.nu();
    let u_lb = vec![-tau_max / unit; nu];
    let u_ub = vec![tau_max / unit; nu];
    let node_count: usize = intervals.iter().map(|n| n + 1).sum();
    let q = field(json, "/initial_guess/nodes/q")?
        .as_array()
        .ok_or_else(|| FieldError::kind("/initial_guess/nodes/q", "an array"))?;
    if q.len() != node_count {
        return Err(PeerGaitError::GuessNodes {
            found: q.len(),
            expected: node_count,
        });
    }
    let (mut gx, mut gu) = (Vec::new(), Vec::new());
    let mut at = 0usize;
    for &n in intervals {
        let mut xs = Vec::new();
        let mut us = Vec::new();
        for k in 0..=n {
            let mut x = numbers(
                json,
                &format!("/initial_guess/nodes/q/{}", at + k),
                Some(nq),
            )?;
            x.extend(numbers(
                json,
                &format!("/initial_guess/nodes/qd/{}", at + k),
                Some(nq),
            )?);
            xs.push(x);
            if k < n {
                let tau = numbers(
                    json,
                    &format!("/initial_guess/nodes/tau/{}", at + k),
                    Some(nu),
                )?;
                us.push(
                    tau.iter()
                        .map(|t| (t / unit).clamp(-tau_max / unit, tau_max / unit))
                        .collect(),
                );
            }
        }
        at += n + 1;
        gx.push(xs);
        gu.push(us);
    }
    Ok(GaitGuess {
        x: gx,
        u: gu,
        x_lb,
        x_ub,
        u_lb,
        u_ub,
    })
}

/// The references of the cost nodes (the interval starts of the continuous phases of
/// `intervals`, in the file's order) for the coordinates `tracked_names`.
pub(super) fn cost_nodes(
    json: &Value,
    tracked_names: &[String],
    intervals: &[usize],
) -> Result<Vec<NodeTargets>, PeerGaitError> {
    let ncost: usize = intervals.iter().sum();
    let phase_of = numbers(json, "/references/phase", Some(ncost))?;
    let mut nodes = Vec::with_capacity(ncost);
    let mut count = vec![0usize; intervals.len()];
    for (i, p) in phase_of.iter().enumerate() {
        let j = *p as usize;
        if j >= intervals.len() || p.fract() != 0.0 {
            return Err(PeerGaitError::PhaseIndex { node: i });
        }
        let node = count[j];
        count[j] += 1;
        let at = |ptr: String| number(json, &format!("{ptr}/{i}"));
        let theta = tracked_names
            .iter()
            .map(|n| at(format!("/references/theta/{n}")))
            .collect::<Result<_, _>>()?;
        let omega = tracked_names
            .iter()
            .map(|n| at(format!("/references/omega/{n}")))
            .collect::<Result<_, _>>()?;
        let mut feet = Vec::new();
        for (s, foot) in FEET.iter().enumerate() {
            let listed = field(json, &format!("/phases/{j}/contacts"))?
                .as_array()
                .is_some_and(|a| a.iter().any(|f| f.as_str() == Some(foot)));
            if !listed {
                continue;
            }
            let fx = at(format!("/references/grf/fx_{foot}"))?;
            let fy = at(format!("/references/grf/fy_{foot}"))?;
            let w = at(format!("/references/cop_weight/{foot}"))?;
            let cop = if w > 0.0 {
                Some((at(format!("/references/cop/{foot}"))?, w))
            } else {
                None
            };
            feet.push(FootTarget {
                side: s,
                fx,
                fy,
                cop,
            });
        }
        nodes.push(NodeTargets {
            phase: j,
            node,
            theta,
            omega,
            feet,
        });
    }
    if count != intervals {
        return Err(PeerGaitError::CostNodes {
            found: count,
            intervals: intervals.to_vec(),
        });
    }
    Ok(nodes)
}

/// Refuse a model whose mass matrix and bias forces at the file's check state differ from
/// its check values by more than 1e-7 (relative to the largest entry).
fn check_body(model: &GaitModel, json: &Value) -> Result<(), PeerGaitError> {
    let nq = model.nq();
    let q = numbers(json, "/check_values/q", Some(nq))?;
    let qd = numbers(json, "/check_values/qd", Some(nq))?;
    let want_m: Vec<f64> = field(json, "/check_values/M")?
        .as_array()
        .ok_or_else(|| FieldError::kind("/check_values/M", "an array of rows"))?
        .iter()
        .enumerate()
        .map(|(r, _)| numbers(json, &format!("/check_values/M/{r}"), Some(nq)))
        .collect::<Result<Vec<_>, _>>()?
        .concat();
    let want_c = numbers(json, "/check_values/bias", Some(nq))?;
    let (m, c) = model.mass_matrix_and_bias(&q, &qd, &model.theta0());
    let rel = |a: &[f64], b: &[f64]| {
        let scale = b.iter().fold(1.0f64, |s, v| s.max(v.abs()));
        a.iter()
            .zip(b)
            .fold(0.0f64, |w, (x, y)| w.max((x - y).abs() / scale))
    };
    const TOLERANCE: f64 = 1e-7;
    if want_m.len() != m.len() || rel(&m, &want_m) > TOLERANCE || rel(&c, &want_c) > TOLERANCE {
        return Err(PeerGaitError::NotTheBody {
            mass_matrix: rel(&m, &want_m),
            bias: rel(&c, &want_c),
            tolerance: TOLERANCE,
        });
    }
    Ok(())
}
