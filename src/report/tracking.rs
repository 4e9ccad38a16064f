//! The report sections of a tracking run: where the model fails (cost share and
//! normalised error by channel and phase, the node cost over time, the worst stretches),
//! the residual actuators and the effect parameters.

use super::html::Section;
use super::table::Table;
use crate::model::GaitModel;
use crate::problems::diagnose::IdentifiedParameter;
use crate::problems::evaluation::GaitSolution;

/// The residual actuators' profiles at the nodes (plots, phases shaded), their RMS and
/// peak values (N or N·m) and how often they sit on their bounds, for a model that has
/// them.
pub fn residual_report(
    model: &GaitModel,
    sol: &GaitSolution,
) -> Option<(Section, serde_json::Value)> {
    use super::plot::{LinePlot, LineStyle, Series, Span};
    let uses = crate::problems::evaluation::residual_use(model, sol);
    if uses.is_empty() {
        return None;
    }
    let spans: Vec<Span> = sol
        .phase_spans()
        .iter()
        .map(|p| Span::new(p.t0, p.t1, p.name.clone()))
        .collect();
    let mut forces = LinePlot::new("Residual forces on the pelvis", "time (s)", "force (N)");
    let mut torques = LinePlot::new("Residual torques", "time (s)", "torque (N·m)");
    for r in &uses {
        let p = if r.unit == "N" {
            &mut forces
        } else {
            &mut torques
        };
        p.series.push(Series::new(
            r.name.trim_end_matches("_residual").replace('_', " "),
            r.times.clone(),
            r.values.clone(),
            LineStyle::Solid,
        ));
    }
    forces.shaded = spans.clone();
    torques.shaded = spans;
    let rows = uses
        .iter()
        .map(|r| {
            vec![
                r.name.clone(),
                format!("{:.2}", r.rms),
                format!("{:.2}", r.peak),
                format!("±{}", r.bound),
                format!("{:.0}", 100.0 * r.at_bound_fraction),
                r.unit.to_string(),
            ]
        })
        .collect();
    let table = Table {
        title: "Residual actuators at the nodes".into(),
        headers: [
            "residual",
            "RMS",
            "peak |·|",
            "bound",
            "% of nodes at the bound",
            "unit",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    };
    let mut paragraphs = vec!["What the model needs beyond its own actuators to follow the data, and when: residual forces on the pelvis translations and torques on the pelvis tilt and the joints, at the shooting nodes.".to_string()];
    let saturated: Vec<&str> = uses
        .iter()
        .filter(|r| r.at_bound_fraction > 0.0)
        .map(|r| r.name.as_str())
        .collect();
    if !saturated.is_empty() {
        paragraphs.push(format!(
            "{} of {} residuals reach their bound ({}): where they do, the model needs more than the residual may give, so the profile is a lower bound of what is missing and the tracking error there carries the rest.",
            saturated.len(),
            uses.len(),
            saturated.join(", ")
        ));
    }
    let stats = serde_json::to_value(&uses).unwrap_or_default();
    Some((
        Section {
            heading: "Residual actuators".into(),
            paragraphs,
            tables: vec![table],
            svgs: vec![forces.to_svg(), torques.to_svg()],
        },
        stats,
    ))
}

/// The cost-share table (channel × phase, % of J), the normalised-error table (channel ×
/// phase) and the worst windows.
pub fn cost_tables(b: &crate::problems::track::CostBreakdown) -> (Table, Table, Table) {
    use Table;
    let total = b.total().max(f64::MIN_POSITIVE);
    let mut order: Vec<usize> = (0..b.channels.len()).collect();
    let sums: Vec<f64> = b.cost.iter().map(|per| per.iter().sum()).collect();
    order.sort_by(|&x, &y| sums[y].total_cmp(&sums[x]));
    let mut headers = vec!["channel".to_string(), "% of J".into()];
    headers.extend(b.phases.iter().map(|p| format!("{p} %")));
    let share = Table {
        title: "Share of the tracking cost per channel and phase".into(),
        headers,
        rows: order
            .iter()
            .map(|&c| {
                let mut row = vec![
                    b.channels[c].clone(),
                    format!("{:.1}", 100.0 * sums[c] / total),
                ];
                row.extend(
                    b.cost[c]
                        .iter()
                        .map(|v| format!("{:.1}", 100.0 * v / total)),
                );
                row
            })
            .collect(),
    };
    let rms = b.normalised_rms();
    let mut headers = vec!["channel".to_string(), "all".into()];
    headers.extend(b.phases.iter().cloned());
    let normalised = Table {
        title: "Normalised error per channel and phase (RMS of the weighted residual)".into(),
        headers,
        rows: order
            .iter()
            .map(|&c| {
                let n: usize = b.rows[c].iter().sum();
                let mut row = vec![
                    b.channels[c].clone(),
                    if n > 0 {
                        format!("{:.4}", (sums[c] / n as f64).sqrt())
                    } else {
                        "—".into()
                    },
                ];
                row.extend(
                    rms[c]
                        .iter()
                        .map(|v| v.map_or("—".into(), |v| format!("{v:.4}"))),
                );
                row
            })
            .collect(),
    };
    let windows = Table {
        title: "Worst stretches (five nodes)".into(),
        headers: [
            "from (s)",
            "to (s)",
            "% of the data cost",
            "largest channel",
        ]
        .map(String::from)
        .to_vec(),
        rows: {
            let data: f64 = b
                .nodes
                .iter()
                .map(|n| n.data)
                .sum::<f64>()
                .max(f64::MIN_POSITIVE);
            b.worst_windows(5, 3)
                .into_iter()
                .map(|(t0, t1, v, c)| {
                    vec![
                        format!("{t0:.3}"),
                        format!("{t1:.3}"),
                        format!("{:.1}", 100.0 * v / data),
                        c,
                    ]
                })
                .collect()
        },
    };
    (share, normalised, windows)
}

/// Table of effect parameters (identified ones with their standard deviation).
pub fn parameter_table(params: &[IdentifiedParameter]) -> Table {
    Table {
        title: "Effect parameters".into(),
        headers: vec![
            "parameter".into(),
            "value".into(),
            "± sd".into(),
            "unit".into(),
            "identified".into(),
        ],
        rows: params
            .iter()
            .map(|p| {
                vec![
                    p.name.clone(),
                    format!("{:.5}", p.value),
                    p.sd.map_or("—".into(), |v| format!("{v:.2e}")),
                    p.unit.clone(),
                    if p.free { "yes".into() } else { "no".into() },
                ]
            })
            .collect(),
    }
}

/// The report section on where the model fails: normalised error and cost share per
/// channel and phase, the node cost over time with the phases shaded and the worst
/// stretches.
pub fn where_it_fails(
    b: &crate::problems::track::CostBreakdown,
    solution: &GaitSolution,
) -> Section {
    use super::plot::{LinePlot, LineStyle, Series, Span};
    let (share, normalised, windows) = cost_tables(b);
    let mut plot = LinePlot::new(
        "Data cost per shooting node",
        "time (s)",
        "Σ weighted residual²",
    );
    plot.series.push(Series::new(
        "data cost",
        b.nodes.iter().map(|n| n.time).collect(),
        b.nodes.iter().map(|n| n.data).collect(),
        LineStyle::Solid,
    ));
    plot.shaded = solution
        .phase_spans()
        .iter()
        .map(|p| Span::new(p.t0, p.t1, p.name.clone()))
        .collect();
    Section {
        heading: "Where the model fails".into(),
        paragraphs: vec![format!(
            "The tracking cost J = {:.6} (weighted squared residuals at the nodes, Millard & Mombaur 2019, eq. 18) by channel and phase: its share, and the normalised error (RMS of the weighted residual: the error in units of the channel's weighting scale). Below, the data cost of every node over time (phases shaded) and the stretches of five nodes where it is largest.",
            b.total()
        )],
        tables: vec![share, normalised, windows],
        svgs: vec![plot.to_svg()],
    }
}
