//! The HTML report of a gait run: its summary box (verdict, solver figures, fine-grid
//! figures, validity) and its sections (errors, validity, transients, phases, kinematics,
//! ground forces, actuators, the body).

use super::evaluation::{Evaluation, Verdict};
use super::figures::Figures;
use super::sections::{transient_section, validity_section};
use super::GaitRun;
use crate::report::html::{Report, Section, Summary, Tone};

/// The report of `run` evaluated as `ev`; takes the run's extra summary lines and
/// sections.
pub(super) fn report(
    run: &mut GaitRun,
    ev: &Evaluation,
    verdict: &Verdict,
    figures: &Figures,
) -> Report {
    let (mut summary, fine_text) = summary_box(run, ev, verdict);
    summary.extra.extend(std::mem::take(&mut run.extra_summary));
    let mut sections = vec![Section {
        heading: "Errors".into(),
        paragraphs: vec![
            "Model against the measurement at the shooting nodes, overall and phase by phase (mean ± sd (max) of |error|; ground forces where the measured foot is loaded).".into(),
        ],
        tables: vec![ev.table.clone(), ev.by_phase.clone()],
        svgs: vec![],
    }];
    if let Some(v) = &ev.validity {
        sections.push(validity_section(v, run.check_points));
    }
    sections.push(transient_section(
        &ev.transients,
        run.transient_threshold_n,
        ev.fine_run.is_ok(),
    ));
    sections.extend(std::mem::take(&mut run.extra_sections));
    sections.extend(figure_sections(run, figures, fine_text));
    Report {
        title: std::mem::take(&mut run.title),
        summary,
        sections,
    }
}

/// The summary box (before the run's extra lines), and the ground-force section's
/// paragraph on the fine grid.
fn summary_box(run: &GaitRun, ev: &Evaluation, verdict: &Verdict) -> (Summary, String) {
    let res = run.result;
    let (t0, t1) = run.solution.span();
    let mut summary = Summary::new(
        verdict.text,
        // red for a converged solution that breaks physics: presented as a solution, it is
        // not one; an unfinished solve stays amber, its verdict naming the invalidity
        if verdict.invalid && verdict.converged {
            Tone::Bad
        } else if verdict.converged {
            Tone::Good
        } else {
            Tone::Warning
        },
        res.status.to_string(),
    );
    summary.iterations = Some(res.history.len().saturating_sub(1));
    summary.time_s = Some(res.seconds);
    summary.extra = vec![
        ("objective".into(), format!("{:.6}", res.objective)),
        ("KKT residual".into(), format!("{:.2e}", res.kkt)),
        ("infeasibility".into(), format!("{:.2e}", res.infeasibility)),
        ("window".into(), format!("{t0:.3}–{t1:.3} s")),
    ];
    let fine_text = match (&ev.fine, &ev.fine_run) {
        (Some(f), _) => {
            summary.extra.push((
                "peak normal GRF (1 ms grid)".into(),
                format!(
                    "right {:.1} N, left {:.1} N",
                    f.peak_normal_force_n[0], f.peak_normal_force_n[1]
                ),
            ));
            summary.extra.push((
                "largest constraint drift (1 ms grid)".into(),
                format!(
                    "{:.2e} m, {:.2e} m/s",
                    f.max_position_drift_m, f.max_velocity_drift_m_s
                ),
            ));
            summary.extra.push((
                "largest Baumgarte force (1 ms grid)".into(),
                format!("{:.1e} N", f.max_baumgarte_force_n),
            ));
            format!(
                "Forces between the nodes come from the 1 ms re-integration (transients hide between nodes, Millard & Mombaur 2019, §5): peak normal force {:.1} N (right) and {:.1} N (left); largest Baumgarte force {:.1e} N; largest position drift {:.2e} m.",
                f.peak_normal_force_n[0], f.peak_normal_force_n[1], f.max_baumgarte_force_n, f.max_position_drift_m
            )
        }
        (None, Err(e)) => {
            summary
                .extra
                .push(("1 ms re-integration".into(), e.to_string()));
            format!("{e}; the plots show the shooting nodes only.")
        }
        (None, Ok(_)) => String::new(),
    };
    if let Some(v) = &ev.validity {
        let text = if v.is_valid() {
            format!(
                "valid on the 1 ms grid ({} check point(s) between the nodes)",
                run.check_points
            )
        } else {
            format!(
                "INVALID: {} ({} stretch(es); {} check point(s) between the nodes)",
                v.violations
                    .iter()
                    .max_by(|a, b| a.amount.total_cmp(&b.amount))
                    .map(|x| x.to_string())
                    .unwrap_or_default(),
                v.violations.len(),
                run.check_points
            )
        };
        summary.extra.push(("physical validity".into(), text));
    }
    (summary, fine_text)
}

/// The sections of the figures: phases, kinematics, ground forces (with `fine_text`),
/// actuators and the body.
fn figure_sections(run: &GaitRun, figures: &Figures, fine_text: String) -> Vec<Section> {
    let cycle = &figures.cycle;
    let sequence = run.sequence;
    let axis_note = format!(
        "The x axis is percent of the gait cycle ({:.3} s), each leg from its own heel strike (right {:.3} s, left {:.3} s): over a mirrored half cycle one leg fills 0–50 % and the other 50–100 % of one leg's cycle. The trial's clock runs along the top. Lines: the solution re-integrated interval by interval on a 1 ms grid; markers: the shooting nodes; dashes: the measurement; the tinted band between them is the residual the cost sees. Phases shaded and named in the phase legend.",
        cycle.period, cycle.heel_strike[0], cycle.heel_strike[1]
    );
    let mut phase_paragraphs = vec![];
    if !sequence.description.is_empty() {
        phase_paragraphs.push(sequence.description.clone());
    }
    phase_paragraphs.push("Impacts are instantaneous; a contact listed as on the ground rolls without slipping unless marked normal only.".into());
    let mut sections = vec![Section {
        heading: "Phases".into(),
        paragraphs: phase_paragraphs,
        tables: vec![figures.legend.clone()],
        svgs: vec![],
    }];
    sections.push(Section {
        heading: "Kinematics: angles".into(),
        paragraphs: vec![axis_note],
        tables: vec![],
        svgs: figures.angles.clone(),
    });
    sections.push(Section {
        heading: "Kinematics: angular velocities".into(),
        paragraphs: vec!["Model and measured velocities (the derivative of the measurement's spline, as the cost's velocity targets).".into()],
        tables: vec![],
        svgs: figures.velocities.clone(),
    });
    sections.push(Section {
        heading: "Ground reaction forces and centre of pressure".into(),
        paragraphs: vec![fine_text],
        tables: vec![],
        svgs: figures.forces.clone(),
    });
    sections.push(Section {
        heading: "Actuators".into(),
        paragraphs: vec!["Joint torques by source (the actuators with their passive damping, each effect, residual actuators), then activations and controls per joint; black dots mark a control held at its bound. Solid: right leg; dashed: left.".into()],
        tables: vec![],
        svgs: figures.actuators.clone(),
    });
    let animation = &figures.animation;
    let mut body_svgs = vec![];
    if !animation.frames.is_empty() {
        body_svgs.push(animation.to_html());
    }
    if !animation.keys.is_empty() {
        body_svgs.push(figures.film_strip.clone());
    }
    sections.push(Section {
        heading: "The body, moving".into(),
        paragraphs: vec!["The model (black, feet in colour: right blue, left orange) over the measured pose (grey, dashed: the data's coordinates on the same model). Arrows: each foot's ground force from its centre of pressure (0.4 m per kN); filled dots: the model's CoP, rings: the measured CoP. Below: the key instants for print.".into()],
        tables: vec![],
        svgs: body_svgs,
    });
    sections
}
