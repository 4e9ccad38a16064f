//! What drives the joints over a run ([`ActuatorTraces`]) and its figures: torques by
//! source, activations and excitations (or torque controls), per joint and leg.

use super::{ChannelFigures, JOINTS, SIDES};
use crate::report::plot::{LinePlot, LineStyle, Series};

/// One actuator quantity of one leg joint over time.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// Joint: 0 hip, 1 knee, 2 ankle.
    pub joint: usize,
    /// 0 right, 1 left.
    pub side: usize,
    /// Legend, e.g. "flexor" or "passive_joint_stiffness".
    pub name: String,
    /// Values at [`ActuatorTraces::times`].
    pub values: Vec<f64>,
    /// Bounds of a control, to mark where it is held at one.
    pub bounds: Option<(f64, f64)>,
}

/// What drives the joints over a run: torques by source, and the muscle-torque
/// generators' activations and excitations.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ActuatorTraces {
    /// Times (s).
    pub times: Vec<f64>,
    /// Joint torques (N·m): the actuators, each effect acting on the joint, residuals.
    pub torques: Vec<Trace>,
    /// Activations (MTG models).
    pub activations: Vec<Trace>,
    /// Excitations, or the joint torques as controls (N·m, with their bounds).
    pub controls: Vec<Trace>,
}

impl ActuatorTraces {
    /// From the model at the states `samples` and the solution's controls there.
    pub fn from_samples(
        model: &crate::model::GaitModel,
        solution: &crate::problems::evaluation::GaitSolution,
        samples: &[crate::simulate::Sample],
        control_bounds: Option<(Vec<f64>, Vec<f64>)>,
    ) -> Self {
        let nq = model.nq();
        let mut out = Self {
            times: samples.iter().map(|s| s.t).collect(),
            ..Self::default()
        };
        let controls: Vec<Vec<f64>> = samples
            .iter()
            .map(|s| {
                solution
                    .control_at(s.t)
                    .unwrap_or_else(|| vec![f64::NAN; model.nu()])
            })
            .collect();
        let parts: Vec<_> = samples
            .iter()
            .zip(&controls)
            .map(|(s, u)| model.generalized_force_parts(&s.x, u, &solution.theta))
            .collect();
        let joint_of = |c: usize| (3..nq).contains(&c).then(|| ((c - 3) % 3, (c - 3) / 3));
        let column = |f: &dyn Fn(usize) -> f64| (0..samples.len()).map(f).collect::<Vec<f64>>();
        for c in 3..nq.min(9) {
            let Some((joint, side)) = joint_of(c) else {
                continue;
            };
            out.torques.push(Trace {
                joint,
                side,
                name: "actuators".into(),
                values: column(&|k| parts[k].actuators[c]),
                bounds: None,
            });
            for e in 0..parts.first().map_or(0, |p| p.effects.len()) {
                let v = column(&|k| parts[k].effects[e].1[c]);
                if v.iter().any(|x| *x != 0.0) {
                    out.torques.push(Trace {
                        joint,
                        side,
                        name: parts[0].effects[e].0.clone(),
                        values: v,
                        bounds: None,
                    });
                }
            }
            let r = column(&|k| parts[k].residual[c]);
            if r.iter().any(|x| *x != 0.0) {
                out.torques.push(Trace {
                    joint,
                    side,
                    name: "residual actuator".into(),
                    values: r,
                    bounds: None,
                });
            }
        }
        let split = |name: &str| -> Option<(usize, usize, String)> {
            let joint = JOINTS
                .iter()
                .position(|j| name.starts_with(&format!("{j}_")))?;
            let rest = &name[JOINTS[joint].len() + 1..];
            let side = match rest.get(..2) {
                Some("r_") => 0,
                Some("l_") => 1,
                _ => return None,
            };
            Some((joint, side, rest[2..].to_string()))
        };
        let na = model.na();
        for (i, name) in model.state_names().iter().enumerate().skip(2 * nq).take(na) {
            if let Some((joint, side, what)) = split(name) {
                out.activations.push(Trace {
                    joint,
                    side,
                    name: what.replace("_activation", ""),
                    values: column(&|k| samples[k].x[i]),
                    bounds: None,
                });
            }
        }
        // torque controls are drawn in N·m (the model's controls are in its torque unit)
        let unit = model.torque_unit().unwrap_or(1.0);
        for (i, name) in model
            .control_names()
            .iter()
            .enumerate()
            .take(model.nu_actuators())
        {
            if let Some((joint, side, what)) = split(name) {
                out.controls.push(Trace {
                    joint,
                    side,
                    name: what
                        .replace("_excitation", "")
                        .replace("torque", "torque control"),
                    values: column(&|k| controls[k][i] * unit),
                    bounds: control_bounds
                        .as_ref()
                        .map(|(lo, hi)| (lo[i] * unit, hi[i] * unit)),
                });
            }
        }
        out
    }
}

impl ChannelFigures<'_> {
    /// Per joint: torques by source, then activations and excitations (or torque
    /// controls) with the points held at a bound marked; both legs on their own percent
    /// of the cycle.
    pub fn actuators(&self, a: &ActuatorTraces) -> Vec<LinePlot> {
        let mut plots = Vec::new();
        for (group, title, unit) in [
            (&a.torques, "torques", "torque (N·m)"),
            (&a.activations, "activations", "activation"),
            (&a.controls, "controls", "control"),
        ] {
            for (j, joint) in JOINTS.iter().enumerate() {
                let traces: Vec<&Trace> = group.iter().filter(|t| t.joint == j).collect();
                if traces.is_empty() {
                    continue;
                }
                let (title, unit) = match (title, traces[0].name.contains("torque control")) {
                    ("controls", true) => (format!("{joint} torque controls"), "torque (N·m)"),
                    ("controls", false) => (format!("{joint} excitations"), unit),
                    _ => (format!("{joint} {title}"), unit),
                };
                let mut p = self.cycle_plot(&title, unit, &[0, 1]);
                let mut names: Vec<&str> = Vec::new();
                for t in &traces {
                    if !names.contains(&t.name.as_str()) {
                        names.push(&t.name);
                    }
                }
                let mut at_bound = (Vec::new(), Vec::new());
                // one point per 3 samples is plenty for these smooth curves
                let n = a.times.len();
                let thin = |v: &[f64]| {
                    v.iter()
                        .enumerate()
                        .filter(|(i, _)| i % 3 == 0 || i + 1 == n)
                        .map(|(_, x)| *x)
                        .collect::<Vec<f64>>()
                };
                for t in &traces {
                    let k = names.iter().position(|n| *n == t.name).unwrap_or(0);
                    let x = thin(&self.percent(t.side, &a.times));
                    let values = thin(&t.values);
                    let style = if t.side == 0 {
                        LineStyle::Solid
                    } else {
                        LineStyle::Dashed
                    };
                    p.series.push(
                        Series::new(
                            format!("{}, {}", SIDES[t.side], t.name),
                            x.clone(),
                            values.clone(),
                            style,
                        )
                        .coloured(k),
                    );
                    if let Some((lo, hi)) = t.bounds {
                        let tol = 1e-3 * (hi - lo).abs().max(1e-12);
                        for (xi, &v) in x.iter().zip(&values) {
                            if v <= lo + tol || v >= hi - tol {
                                at_bound.0.push(*xi);
                                at_bound.1.push(v);
                            }
                        }
                    }
                }
                if !at_bound.0.is_empty() {
                    p.series.push(
                        Series::new("at a bound", at_bound.0, at_bound.1, LineStyle::Markers)
                            .coloured(6),
                    );
                }
                plots.push(p);
            }
        }
        plots
    }
}
