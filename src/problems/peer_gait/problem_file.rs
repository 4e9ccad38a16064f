//! The peer's problem file read: its model (checked against the file's body), its
//! phases as a phase sequence, its bounds and initial guess, and the references of its cost
//! nodes.

use super::{FootTarget, NodeTargets, FEET};
use crate::model::{ConstraintSet, GaitModel};
use crate::phases::PhaseSequence;
use crate::problems::gait::GaitGuess;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// The value at the JSON pointer `ptr` of `v`.
pub(super) fn field<'v>(v: &'v Value, ptr: &str) -> Result<&'v Value, String> {
    v.pointer(ptr).ok_or_else(|| {
        format!(
            "field '{}' missing",
            ptr.trim_start_matches('/').replace('/', ".")
        )
    })
}

/// The number at the JSON pointer `ptr` of `v`.
pub(super) fn number(v: &Value, ptr: &str) -> Result<f64, String> {
    field(v, ptr)?.as_f64().ok_or_else(|| {
        format!(
            "field '{}' must be a number",
            ptr.trim_start_matches('/').replace('/', ".")
        )
    })
}

/// The array of numbers at the JSON pointer `ptr` of `v` (of `len` entries, where given).
pub(super) fn numbers(v: &Value, ptr: &str, len: Option<usize>) -> Result<Vec<f64>, String> {
    let name = ptr.trim_start_matches('/').replace('/', ".");
    let a = field(v, ptr)?
        .as_array()
        .ok_or_else(|| format!("field '{name}' must be an array of numbers"))?;
    if let Some(n) = len {
        if a.len() != n {
            return Err(format!(
                "field '{name}' has {} entries, expected {n}",
                a.len()
            ));
        }
    }
    a.iter()
        .enumerate()
        .map(|(i, x)| {
            x.as_f64()
                .ok_or_else(|| format!("field '{name}[{i}]' must be a number"))
        })
        .collect()
}

/// The string at the JSON pointer `ptr` of `v`.
pub(super) fn string<'v>(v: &'v Value, ptr: &str) -> Result<&'v str, String> {
    field(v, ptr)?.as_str().ok_or_else(|| {
        format!(
            "field '{}' must be a string",
            ptr.trim_start_matches('/').replace('/', ".")
        )
    })
}

/// The model of the problem file's `footfall` block (its files resolved against the
/// folder of `path`), refused unless torque driven and of the file's body, and the contact
/// index of each foot's primitive (right, left).
pub(super) fn peer_model(json: &Value, path: &Path) -> Result<(GaitModel, [usize; 2]), String> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let file = |ptr: &str| -> Result<PathBuf, String> { Ok(dir.join(string(json, ptr)?)) };
    let model_path = file("/footfall/model")?;
    let foot_path = file("/footfall/foot")?;
    let model = GaitModel::load(&model_path, &foot_path).map_err(|e| e.to_string())?;
    if model.na() > 0 || model.torque_unit().is_none() {
        return Err(format!(
            "field 'footfall.model': {} must be torque driven (\"actuators\": {{\"type\": \"joint_torques\"}}), as the problem is",
            model_path.display()
        ));
    }
    check_body(&model, json)?;
    let [right, left] = [0, 1].map(|s| {
        let name = string(json, &format!("/footfall/contacts/{}", FEET[s]))?;
        model.contact_index(name).ok_or_else(|| {
            format!(
                "field 'footfall.contacts.{}': the foot has no contact '{name}'",
                FEET[s]
            )
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
) -> Result<Vec<Value>, String> {
    let feet = field(json, ptr)?
        .as_array()
        .ok_or_else(|| format!("field '{}' must be an array", &ptr[1..]))?;
    feet.iter()
        .map(|f| {
            let s = FEET
                .iter()
                .position(|n| Some(*n) == f.as_str())
                .ok_or_else(|| {
                    format!("field '{}': feet are \"r\" or \"l\", got {f}", &ptr[1..])
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
) -> Result<PeerPhases, String> {
    let phases = field(json, "/phases")?
        .as_array()
        .ok_or("field 'phases' must be an array")?;
    let transitions = field(json, "/transitions")?
        .as_array()
        .ok_or("field 'transitions' must be an array")?;
    let impact_after = impacts_after(json, transitions, phases.len(), model, contacts)?;
    let mut seq_phases = Vec::new();
    let mut intervals = Vec::new();
    for (j, _) in phases.iter().enumerate() {
        let n = number(json, &format!("/phases/{j}/intervals"))?;
        if !(n >= 1.0 && n.fract() == 0.0) {
            return Err(format!(
                "field 'phases[{j}].intervals' must be a whole number ≥ 1"
            ));
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
    .map_err(|e| format!("phases: {e}"))?;
    seq.validate(path).map_err(|e| e.to_string())?;
    let sets = seq.resolve(model, path).map_err(|e| e.to_string())?;
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
) -> Result<Vec<Option<(String, Vec<Value>)>>, String> {
    let mut impact_after: Vec<Option<(String, Vec<Value>)>> = vec![None; phases];
    let mut j = 0usize;
    for (t, tr) in transitions.iter().enumerate() {
        match string(tr, "/type")? {
            "initial" => {}
            "continuous" => j += 1,
            "impact" | "terminal impact" => {
                let at = string(tr, "/at").unwrap_or("impact");
                let name = at.split('(').nth(1).map_or("impact", |s| s.trim_end_matches(')'));
                let slot = impact_after.get_mut(j).ok_or_else(|| {
                    format!("field 'transitions[{t}]': an impact after the last phase's end")
                })?;
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
                return Err(format!(
                    "field 'transitions[{t}].type': unknown '{other}' (initial, continuous, impact, terminal impact)"
                ))
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
) -> Result<GaitGuess, String> {
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
        .ok_or("field 'initial_guess.nodes.q' must be an array")?;
    if q.len() != node_count {
        return Err(format!(
            "field 'initial_guess.nodes.q' has {} nodes, the phases {node_count} (intervals + 1 each)",
            q.len()
        ));
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
) -> Result<Vec<NodeTargets>, String> {
    let ncost: usize = intervals.iter().sum();
    let phase_of = numbers(json, "/references/phase", Some(ncost))?;
    let mut nodes = Vec::with_capacity(ncost);
    let mut count = vec![0usize; intervals.len()];
    for (i, p) in phase_of.iter().enumerate() {
        let j = *p as usize;
        if j >= intervals.len() || p.fract() != 0.0 {
            return Err(format!(
                "field 'references.phase[{i}]' must be a phase index"
            ));
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
        return Err(format!(
            "field 'references.phase': {count:?} cost nodes per phase, the phases have {intervals:?} intervals"
        ));
    }
    Ok(nodes)
}

/// Refuse a model whose mass matrix and bias forces at the file's check state differ from
/// its check values by more than 1e-7 (relative to the largest entry).
fn check_body(model: &GaitModel, json: &Value) -> Result<(), String> {
    let nq = model.nq();
    let q = numbers(json, "/check_values/q", Some(nq))?;
    let qd = numbers(json, "/check_values/qd", Some(nq))?;
    let want_m: Vec<f64> = field(json, "/check_values/M")?
        .as_array()
        .ok_or("field 'check_values.M' must be an array of rows")?
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
    if want_m.len() != m.len() || rel(&m, &want_m) > 1e-7 || rel(&c, &want_c) > 1e-7 {
        return Err(format!(
            "the model of field 'footfall.model' is not the problem's body: its mass matrix differs from 'check_values.M' by {:.1e} and its bias forces from 'check_values.bias' by {:.1e} (relative; at most 1e-7 allowed)",
            rel(&m, &want_m),
            rel(&c, &want_c)
        ));
    }
    Ok(())
}
