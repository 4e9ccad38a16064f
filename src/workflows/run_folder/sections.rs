//! The report sections of a gait run folder: physical validity on the 1 ms grid, the
//! ground-force transients, and the body animation.

use crate::model::GaitModel;
use crate::problems::evaluation::{Comparison, GaitSolution};
use crate::problems::transient::ForceTransient;
use crate::report::body::{BodyAnimation, BodyFrame, Pose};
use crate::report::gait_figures::CycleAxis;
use crate::report::html::Section;
use crate::report::table::Table;

/// The report's account of physical validity on the 1 ms grid.
pub(super) fn validity_section(
    v: &crate::problems::validity::Validity,
    check_points: usize,
) -> Section {
    let l = &v.limits;
    let mut paragraphs = vec![format!(
        "The solution re-integrated on the 1 ms grid, checked for a normal force below −{} N, a tangential force beyond the friction cone by more than {} N, a primitive not in contact more than {} mm below the ground, and a Baumgarte force above {} N. The contact constraints hold at the shooting nodes and at {check_points} check point(s) between them.",
        l.normal_force_n,
        l.friction_n,
        l.penetration_m * 1e3,
        l.baumgarte_n
    )];
    let mut tables = Vec::new();
    if v.is_valid() {
        paragraphs
            .push("Nothing is broken: the solution is physically valid between the nodes.".into());
    } else {
        paragraphs.push(format!("**The solution is physically invalid** in {} stretch(es): it is not a gait the model can walk. Check points (on unless `--no-check-points`) hold the contact constraints between the nodes where they break; here they did not repair it (no check point could be placed, or the rounds or iterations ran out).", v.violations.len()));
        let mut t = Table {
            title: "Where physics is broken on the 1 ms grid".into(),
            headers: [
                "what",
                "contact",
                "phase",
                "from (s)",
                "to (s)",
                "worst at (s)",
                "worst",
            ]
            .map(String::from)
            .to_vec(),
            rows: Vec::new(),
        };
        for x in v.violations.iter().take(20) {
            let worst = match x.kind {
                crate::problems::validity::ViolationKind::Penetration => {
                    format!("{:.1} mm", x.amount * 1e3)
                }
                _ => format!("{:.1} N", x.amount),
            };
            t.rows.push(vec![
                x.kind.describe().into(),
                x.contact.clone(),
                x.phase.clone(),
                format!("{:.3}", x.from_s),
                format!("{:.3}", x.to_s),
                format!("{:.3}", x.worst_s),
                worst,
            ]);
        }
        tables.push(t);
    }
    Section {
        heading: "Physical validity".into(),
        paragraphs,
        tables,
        svgs: vec![],
    }
}

/// The report's account of the ground-force transients.
pub(super) fn transient_section(
    transients: &[ForceTransient],
    threshold: f64,
    have_fine: bool,
) -> Section {
    let mut paragraphs = Vec::new();
    let mut tables = Vec::new();
    if !have_fine {
        paragraphs.push("No transient analysis: the 1 ms re-integration failed.".to_string());
    } else if transients.is_empty() {
        paragraphs.push(format!("On the 1 ms grid no ground force exceeds the measurement by more than {threshold:.0} N."));
    } else {
        let t = &transients[0];
        paragraphs.push(format!(
            "Largest: the {} foot's {} force reaches {:.1} N at {:.3} s in phase {}, {:.1} N above the measurement, for {:.1} ms above the {threshold:.0} N threshold; ankle angular velocity {:.2} rad/s; largest Baumgarte force in the window {:.1e} N{}.",
            t.foot,
            t.component,
            t.peak_n,
            t.t_peak,
            t.phase,
            t.excess_n,
            1e3 * t.duration_s,
            t.ankle_velocity_rad_s,
            t.max_baumgarte_force_n,
            if t.between_nodes { "; it falls between shooting nodes and shows only on the fine grid" } else { "" }
        ));
        tables.push(Table {
            title: format!("Ground-force excursions above the measurement by more than {threshold:.0} N (1 ms grid)"),
            headers: ["foot", "force", "phase", "peak time (s)", "peak (N)", "measured (N)", "excess (N)", "duration (ms)", "ankle ω (rad/s)", "max Baumgarte (N)", "between nodes"]
                .iter()
                .map(|h| h.to_string())
                .collect(),
            rows: transients
                .iter()
                .map(|t| {
                    vec![
                        t.foot.to_string(),
                        t.component.to_string(),
                        t.phase.clone(),
                        format!("{:.3}", t.t_peak),
                        format!("{:.1}", t.peak_n),
                        format!("{:.1}", t.measured_n),
                        format!("{:.1}", t.excess_n),
                        format!("{:.1}", 1e3 * t.duration_s),
                        format!("{:.2}", t.ankle_velocity_rad_s),
                        format!("{:.1e}", t.max_baumgarte_force_n),
                        if t.between_nodes { "yes" } else { "no" }.to_string(),
                    ]
                })
                .collect(),
        });
    }
    Section {
        heading: "Ground-force transients".into(),
        paragraphs,
        tables,
        svgs: vec![],
    }
}

/// Frame step of the body animation (s).
const FRAME_STEP: f64 = 0.01;

/// The body animation over `states` (one frame per 10 ms), with the measured pose and
/// loads from `line` (the comparison at the same instants).
pub(super) fn body_animation(
    model: &GaitModel,
    sol: &GaitSolution,
    line: &Comparison,
    states: &[crate::simulate::Sample],
    cycle: &CycleAxis,
    window: (f64, f64),
) -> BodyAnimation {
    let (h, n) = model.ground(&sol.theta);
    let lead = cycle.lead_side(window);
    let mut frames = Vec::new();
    let mut next = f64::NEG_INFINITY;
    for (k, s) in states.iter().enumerate() {
        if s.t + 1e-9 < next || k >= line.times.len() {
            continue;
        }
        next = s.t + FRAME_STEP;
        let q: Vec<f64> = s.x[..model.nq()].to_vec();
        let qd: Vec<f64> = (0..model.nq()).map(|i| line.data_q[i][k]).collect();
        let opt = |v: f64| v.is_finite().then_some(v);
        frames.push(BodyFrame {
            t: s.t,
            percent: cycle.percent(lead, s.t),
            model: Pose::of_model(model, &q, &sol.theta),
            measured: Pose::of_model(model, &qd, &sol.theta),
            cop_model: [0, 1].map(|f| opt(line.model_feet[f][2][k])),
            cop_measured: [0, 1].map(|f| opt(line.data_feet[f][2][k])),
            grf_model: [0, 1].map(|f| [line.model_feet[f][0][k], line.model_feet[f][1][k]]),
            grf_measured: [0, 1].map(|f| [line.data_feet[f][0][k], line.data_feet[f][1][k]]),
        });
    }
    let mut a = BodyAnimation {
        frames,
        ground_height: h,
        ground_normal: n,
        keys: vec![],
    };
    a.find_keys(lead);
    a
}
