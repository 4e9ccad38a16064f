//! The run folder of a gait OCP (tracking or prediction): model against measurement at
//! the nodes, overall and by phase, the 1 ms re-integration figures, plots, the solution
//! for later runs, `summary.json` and `report.html`.

#[allow(unused_imports)]
use super::{note, warn_note, Progress};
use crate::data::GaitData;
use crate::integrate::IntegratorSettings;
use crate::model::gait::COORDINATES;
use crate::model::{ConstraintSet, GaitModel};
use crate::problems::evaluation::{
    channel_errors, Comparison, FineGridFigures, GaitSolution, Reintegration, LOAD_NAMES,
};
use crate::problems::transient::{force_transients, ForceTransient};
use crate::report::csv::TimeSeries;
use crate::report::gait_figures::{phase_legend, ActuatorTraces, ChannelFigures, CycleAxis};
use crate::report::html::{Report, Section, Summary, Tone};
use crate::report::table::{error_table, Table};
use crate::runfolder::RunFolder;
use crate::sqp::{SqpResult, SqpStatus};
use anyhow::Context;
use std::path::PathBuf;

mod sections;
use sections::{body_animation, transient_section, validity_section};

/// Step of the fine re-integration grid (s).
pub const FINE_STEP: f64 = 1e-3;

/// Default threshold of a reported ground-force transient: excess over the measurement (N).
pub const DEFAULT_TRANSIENT_THRESHOLD_N: f64 = 250.0;

/// What a gait run wrote and found.
pub struct GaitRunOutput {
    /// Committed run folder.
    pub path: PathBuf,
    /// The overall error table.
    pub table: Table,
    /// Fine-grid figures (None when the re-integration failed; the report says why).
    pub fine: Option<FineGridFigures>,
    /// Ground-force transients on the fine grid, strongest first.
    pub transients: Vec<ForceTransient>,
    /// Overall error statistics per channel (name, unit, stats).
    pub errors: Vec<crate::report::table::ChannelErrors>,
    /// Ground forces on the fine grid (None when the re-integration failed).
    pub fine_forces: Option<FineForces>,
    /// Physical validity on the fine grid (None when the re-integration failed).
    pub validity: Option<crate::problems::validity::Validity>,
}

impl GaitRunOutput {
    /// The run's error table and the solver's stop (status, objective, KKT error,
    /// iterations, seconds), as printed after a gait run.
    pub fn solve_summary(&self, res: &SqpResult) -> String {
        format!(
            "{}\n{}: J = {:.6}, KKT {:.2e}, {} iterations, {:.1} s",
            self.table.to_markdown(),
            res.status,
            res.objective,
            res.kkt,
            res.history.len().saturating_sub(1),
            res.seconds
        )
    }
}

/// Ground forces of both feet on the fine grid, model and measurement.
pub struct FineForces {
    /// Times (s).
    pub times: Vec<f64>,
    /// Model `[side][fx, fy]` (N).
    pub model: [[Vec<f64>; 2]; 2],
    /// Measured `[side][fx, fy]` (N).
    pub measured: [[Vec<f64>; 2]; 2],
}

impl FineForces {
    /// Largest excess of the model over the measurement, `(N, time s, side)`, of
    /// component `c` (0 tangential, by magnitude along the model force; 1 normal).
    pub fn max_excess(&self, c: usize) -> (f64, f64, usize) {
        let mut best = (f64::NEG_INFINITY, f64::NAN, 0);
        for s in 0..2 {
            for (k, &t) in self.times.iter().enumerate() {
                let (m, d) = (self.model[s][c][k], self.measured[s][c][k]);
                let e = if c == 0 { (m - d) * m.signum() } else { m - d };
                if e > best.0 {
                    best = (e, t, s);
                }
            }
        }
        best
    }
    /// Peak |force| of component `c` over both feet (N).
    pub fn peak(&self, c: usize) -> f64 {
        self.model
            .iter()
            .flat_map(|m| m[c].iter())
            .fold(0.0, |a, v| a.max(v.abs()))
    }
}

/// Everything the writer needs.
pub struct GaitRun<'a> {
    /// `track` or `predict`.
    pub command: &'a str,
    /// Report title.
    pub title: String,
    /// The measurement the run compares with.
    pub data: &'a GaitData,
    /// Model and constraint sets.
    pub model: &'a GaitModel,
    /// Constraint sets, one per phase-file phase.
    pub sets: &'a [ConstraintSet],
    /// Phase file.
    pub phases_path: &'a std::path::Path,
    /// The inputs copied into the run folder (`summary.json` then names the copies).
    pub inputs: Option<&'a super::inputs::RunInputs>,
    /// The phase sequence the problem was built from (for the phase legend).
    pub sequence: &'a crate::phases::PhaseSequence,
    /// Lower and upper bounds of the controls in the solved problem (to mark a control
    /// held at one).
    pub control_bounds: (&'a [f64], &'a [f64]),
    /// The measured events (heel strikes set each leg's percent of the gait cycle).
    pub events: &'a crate::data::events::Events,
    /// Solver result.
    pub result: &'a SqpResult,
    /// The solution read from `result.w`.
    pub solution: &'a GaitSolution,
    /// Integrator settings for the re-integration.
    pub integrator: IntegratorSettings,
    /// Extra summary lines and JSON fields.
    pub extra_summary: Vec<(String, String)>,
    /// Extra `summary.json` fields.
    pub extra_json: serde_json::Map<String, serde_json::Value>,
    /// Extra report sections, placed after the errors.
    pub extra_sections: Vec<Section>,
    /// Extra files (name, bytes).
    pub extra_files: Vec<(String, Vec<u8>)>,
    /// Report ground-force excursions above the measurement larger than this (N).
    pub transient_threshold_n: f64,
    /// Friction coefficient of the contacts' cone.
    pub friction: f64,
    /// Number of check points holding the contact constraints between the nodes.
    pub check_points: usize,
}

/// Evaluate, write and commit the run folder.
pub fn write(run: GaitRun, folder: RunFolder) -> anyhow::Result<GaitRunOutput> {
    let (model, sets, data, res, sol) = (run.model, run.sets, run.data, run.result, run.solution);
    let nodes = sol
        .node_samples(model, sets)
        .context("evaluating the solution at the nodes")?;
    let cmp = Comparison::through_model(&nodes, data, model, &sol.theta)?;
    let channels = cmp.table_channels();
    let foot = model.foot_name.clone();
    let what = if run.command == "predict" {
        "Prediction"
    } else {
        "Tracking"
    };
    let table = error_table(
        &format!(
            "{what} errors at the shooting nodes (layout of Millard & Mombaur 2019, Table {}; both legs pooled)",
            if run.command == "predict" { 4 } else { 3 }
        ),
        &[foot],
        &channel_errors(&channels, &cmp, None),
    );
    let phase_ids: Vec<usize> = sol.phases.iter().map(|p| p.set).collect();
    let phase_names: Vec<String> = sol.phases.iter().map(|p| p.name.clone()).collect();
    let by_phase = error_table(
        &format!("{what} errors by phase"),
        &phase_names,
        &channel_errors(&channels, &cmp, Some(&phase_ids)),
    );

    // fine grid: a failure (e.g. of an interrupted early iterate) is reported, not fatal
    let fine_run: Result<Reintegration, String> = sol
        .reintegrate(model, sets, FINE_STEP, &run.integrator)
        .map_err(|e| format!("the 1 ms re-integration failed: {e}"));
    let fine = fine_run.as_ref().ok().map(|f| f.figures(sets, FINE_STEP));
    let fine_cmp = match &fine_run {
        Ok(f) => Some(Comparison::through_model(
            &f.result.samples,
            data,
            model,
            &sol.theta,
        )?),
        Err(_) => None,
    };
    let phase_file_names: Vec<String> = sets.iter().map(|s| s.name.clone()).collect();
    let validity = fine_run.as_ref().ok().map(|f| {
        crate::problems::validity::check(
            model,
            &f.result.samples,
            sets,
            &phase_file_names,
            &sol.theta,
            run.friction,
            Default::default(),
        )
    });
    let transients = match (&fine_run, &fine_cmp) {
        (Ok(f), Some(fc)) => force_transients(
            f,
            fc,
            sets,
            &cmp.times,
            model.nq(),
            run.transient_threshold_n,
        ),
        _ => Vec::new(),
    };
    // plots show the fine grid where there is one, else the nodes
    let line = fine_cmp.as_ref().unwrap_or(&cmp);
    let line_label = if fine_cmp.is_some() {
        "model (1 ms re-integration)"
    } else {
        "model"
    };

    let (t0, t1) = sol.span();
    let converged = res.status == SqpStatus::Converged;
    let interrupted = res.status == crate::sqp::SqpStatus::Interrupted;
    let invalid = validity.as_ref().is_some_and(|v| !v.is_valid());
    let verdict = match (converged, invalid) {
        (true, false) => "converged",
        (true, true) => "converged, physically invalid",
        (false, true) if interrupted => "interrupted, physically invalid",
        (false, false) if interrupted => "interrupted",
        (false, true) => "not converged, physically invalid",
        (false, false) => "not converged",
    };
    let cycle = CycleAxis::from_events(run.events, (t0, t1));
    let figures = ChannelFigures {
        line,
        nodes: &cmp,
        line_label,
        cycle,
        window: (t0, t1),
        phases: sol
            .phase_spans()
            .iter()
            .map(|p| (p.t0, p.t1, p.name.clone()))
            .collect(),
        note: (verdict != "converged").then(|| verdict.to_string()),
    };
    let (angle_plots, velocity_plots) = figures.kinematics();
    let kin: Vec<String> = angle_plots.iter().map(|p| p.to_svg()).collect();
    let vel: Vec<String> = velocity_plots.iter().map(|p| p.to_svg()).collect();
    let forces: Vec<String> = figures.loads().iter().map(|p| p.to_svg()).collect();
    let sequence = run.sequence;
    let legend = phase_legend(sequence, &sol.phases, &cycle, (t0, t1));
    // the states the figures of the body and the actuators show: the fine grid's, else
    // the nodes'
    let states: &[crate::simulate::Sample] = match &fine_run {
        Ok(f) => &f.result.samples,
        Err(_) => &nodes,
    };
    let (lo, hi) = run.control_bounds;
    let actuators =
        ActuatorTraces::from_samples(model, sol, states, Some((lo.to_vec(), hi.to_vec())));
    let actuator_svgs: Vec<String> = figures
        .actuators(&actuators)
        .iter()
        .map(|p| p.to_svg())
        .collect();
    let animation = body_animation(model, sol, line, states, &cycle, (t0, t1));
    let film_strip = animation.film_strip();

    // time series at the nodes; every row carries the solve's outcome, so that a table of
    // an unfinished solve says so wherever it is read (a comment line would break CSV
    // readers)
    let outcome = |n: usize| vec![res.status.outcome().to_string(); n];
    let mut ts = TimeSeries::new(cmp.times.clone())?;
    ts.push_text("status", outcome(cmp.times.len()))?;
    ts.push_text(
        "phase",
        cmp.phase.iter().map(|&p| sets[p].name.clone()).collect(),
    )?;
    for i in 0..9 {
        ts.push(&format!("model_{}", COORDINATES[i]), cmp.model_q[i].clone())?;
        ts.push(&format!("data_{}", COORDINATES[i]), cmp.data_q[i].clone())?;
    }
    for (s, side) in ["r", "l"].iter().enumerate() {
        for (k, what) in LOAD_NAMES.iter().enumerate() {
            ts.push(
                &format!("model_{what}_{side}"),
                cmp.model_feet[s][k].clone(),
            )?;
            ts.push(&format!("data_{what}_{side}"), cmp.data_feet[s][k].clone())?;
        }
    }
    let fine_ts = match (&fine_run, &fine_cmp) {
        (Ok(f), Some(fc)) => {
            let mut t = TimeSeries::new(fc.times.clone())?;
            t.push_text("status", outcome(fc.times.len()))?;
            t.push_text(
                "phase",
                fc.phase.iter().map(|&p| sets[p].name.clone()).collect(),
            )?;
            for i in 0..9 {
                t.push(&format!("model_{}", COORDINATES[i]), fc.model_q[i].clone())?;
            }
            for (s, side) in ["r", "l"].iter().enumerate() {
                for (k, what) in LOAD_NAMES.iter().enumerate() {
                    t.push(&format!("model_{what}_{side}"), fc.model_feet[s][k].clone())?;
                    t.push(&format!("data_{what}_{side}"), fc.data_feet[s][k].clone())?;
                }
            }
            t.push(
                "baumgarte_max",
                f.result
                    .samples
                    .iter()
                    .map(|s| {
                        s.contact
                            .baumgarte_force
                            .iter()
                            .fold(0.0f64, |m, v| m.max(v.abs()))
                    })
                    .collect(),
            )?;
            Some(t)
        }
        _ => None,
    };

    let mut summary = Summary::new(
        verdict,
        // red for a converged solution that breaks physics: presented as a solution, it is
        // not one; an unfinished solve stays amber, its verdict naming the invalidity
        if invalid && converged {
            Tone::Bad
        } else if converged {
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
    let fine_text = match (&fine, &fine_run) {
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
                .push(("1 ms re-integration".into(), e.clone()));
            format!("{e}; the plots show the shooting nodes only.")
        }
        (None, Ok(_)) => String::new(),
    };
    if let Some(v) = &validity {
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
    summary.extra.extend(run.extra_summary);
    let mut sections = vec![Section {
        heading: "Errors".into(),
        paragraphs: vec![
            "Model against the measurement at the shooting nodes, overall and phase by phase (mean ± sd (max) of |error|; ground forces where the measured foot is loaded).".into(),
        ],
        tables: vec![table.clone(), by_phase.clone()],
        svgs: vec![],
    }];
    if let Some(v) = &validity {
        sections.push(validity_section(v, run.check_points));
    }
    sections.push(transient_section(
        &transients,
        run.transient_threshold_n,
        fine_run.is_ok(),
    ));
    sections.extend(run.extra_sections);
    let axis_note = format!(
        "The x axis is percent of the gait cycle ({:.3} s), each leg from its own heel strike (right {:.3} s, left {:.3} s): over a mirrored half cycle one leg fills 0–50 % and the other 50–100 % of one leg's cycle. The trial's clock runs along the top. Lines: the solution re-integrated interval by interval on a 1 ms grid; markers: the shooting nodes; dashes: the measurement; the tinted band between them is the residual the cost sees. Phases shaded and named in the phase legend.",
        cycle.period, cycle.heel_strike[0], cycle.heel_strike[1]
    );
    let mut phase_paragraphs = vec![];
    if !sequence.description.is_empty() {
        phase_paragraphs.push(sequence.description.clone());
    }
    phase_paragraphs.push("Impacts are instantaneous; a contact listed as on the ground rolls without slipping unless marked normal only.".into());
    sections.push(Section {
        heading: "Phases".into(),
        paragraphs: phase_paragraphs,
        tables: vec![legend],
        svgs: vec![],
    });
    sections.push(Section {
        heading: "Kinematics: angles".into(),
        paragraphs: vec![axis_note],
        tables: vec![],
        svgs: kin,
    });
    sections.push(Section {
        heading: "Kinematics: angular velocities".into(),
        paragraphs: vec!["Model and measured velocities (the derivative of the measurement's spline, as the cost's velocity targets).".into()],
        tables: vec![],
        svgs: vel,
    });
    sections.push(Section {
        heading: "Ground reaction forces and centre of pressure".into(),
        paragraphs: vec![fine_text],
        tables: vec![],
        svgs: forces,
    });
    sections.push(Section {
        heading: "Actuators".into(),
        paragraphs: vec!["Joint torques by source (the actuators with their passive damping, each effect, residual actuators), then activations and controls per joint; black dots mark a control held at its bound. Solid: right leg; dashed: left.".into()],
        tables: vec![],
        svgs: actuator_svgs,
    });
    let mut body_svgs = vec![];
    if !animation.frames.is_empty() {
        body_svgs.push(animation.to_html());
    }
    if !animation.keys.is_empty() {
        body_svgs.push(film_strip.clone());
    }
    sections.push(Section {
        heading: "The body, moving".into(),
        paragraphs: vec!["The model (black, feet in colour: right blue, left orange) over the measured pose (grey, dashed: the data's coordinates on the same model). Arrows: each foot's ground force from its centre of pressure (0.4 m per kN); filled dots: the model's CoP, rings: the measured CoP. Below: the key instants for print.".into()],
        tables: vec![],
        svgs: body_svgs,
    });
    let report = Report {
        title: run.title,
        summary,
        sections,
    };
    // channels without a defined sample in a phase are left out (no nulls)
    use crate::report::run_summary as rs;
    let stats = |s: &Option<crate::report::table::ErrorStats>| {
        s.map(|v| rs::SummaryStats {
            mean: v.mean,
            sd: Some(v.sd),
            max: Some(v.max),
        })
    };
    let overall = channel_errors(&channels, &cmp, None);
    let phased = channel_errors(&channels, &cmp, Some(&phase_ids));
    let summary_file = rs::RunSummaryFile {
        command: Some(run.command.to_string()),
        model: Some(model.name.clone()),
        foot: Some(model.foot_name.clone()),
        phases: Some(
            run.inputs
                .map_or(run.phases_path, |i| &i.phases)
                .to_path_buf(),
        ),
        data: Some(run.inputs.map_or(&data.source, |i| &i.data).clone()),
        inputs: run.inputs.cloned(),
        window_s: Some([t0, t1]),
        gait_cycle: Some(rs::GaitCycleRecord {
            period_s: cycle.period,
            heel_strike_s: cycle.heel_strike,
        }),
        phase_spans: sol
            .phase_spans()
            .iter()
            .map(|p| rs::PhaseSpan {
                phase: p.name.clone(),
                from_s: p.t0,
                to_s: p.t1,
            })
            .collect(),
        status: Some(res.status.clone()),
        verdict: Some(verdict.to_string()),
        physically_valid: validity.as_ref().map(|v| v.is_valid()),
        validity: validity.clone(),
        check_points: Some(run.check_points),
        stop_reason: Some(res.status.to_string()),
        iterations: Some(res.history.len().saturating_sub(1)),
        seconds: Some(res.seconds),
        objective: Some(res.objective),
        kkt: Some(res.kkt),
        infeasibility: Some(res.infeasibility),
        timings: res.timings,
        errors: overall
            .iter()
            .filter_map(|c| {
                stats(&c.runs[0]).map(|s| rs::ChannelStats {
                    channel: c.name.clone(),
                    unit: c.unit.clone(),
                    stats: s,
                })
            })
            .collect(),
        errors_by_phase: Some(
            phased
                .iter()
                .map(|c| rs::ChannelPhaseErrors {
                    channel: c.name.clone(),
                    unit: c.unit.clone(),
                    phases: phase_names
                        .iter()
                        .zip(&c.runs)
                        .filter_map(|(p, s)| {
                            stats(s).map(|s| rs::PhaseErrors {
                                phase: p.clone(),
                                stats: s,
                            })
                        })
                        .collect(),
                })
                .collect(),
        ),
        fine_grid: fine.clone(),
        fine_grid_error: fine_run.as_ref().err().cloned(),
        transient_threshold_n: Some(run.transient_threshold_n),
        transients: transients.clone(),
        most_violated: res.most_violated.clone(),
        history: res.history.clone(),
    };
    let summary_json = summary_file.to_json(run.extra_json)?;
    folder.write(
        "summary.json",
        serde_json::to_string_pretty(&summary_json)?.as_bytes(),
    )?;
    folder.write(
        "solution.json",
        serde_json::to_string_pretty(sol)?.as_bytes(),
    )?;
    let csv_name = if run.command == "predict" {
        "prediction"
    } else {
        "tracking"
    };
    // the CSV files also carry the measured coordinates and both velocities (what the
    // cost compares, and what `footfall report RUN_A RUN_B` overlays); the `.sto` keeps
    // the model's coordinates only
    let with_kinematics = |series: &TimeSeries, c: &Comparison| -> anyhow::Result<TimeSeries> {
        let mut t = series.clone();
        for (i, coordinate) in COORDINATES.iter().enumerate() {
            let data = format!("data_{coordinate}");
            if !t.names().contains(&data.as_str()) {
                t.push(data, c.data_q[i].clone())?;
            }
            t.push(format!("model_{coordinate}_dot"), c.model_qd[i].clone())?;
            t.push(format!("data_{coordinate}_dot"), c.data_qd[i].clone())?;
        }
        Ok(t)
    };
    folder.write(
        &format!("{csv_name}.csv"),
        with_kinematics(&ts, &cmp)?.to_csv().as_bytes(),
    )?;
    if let (Some(f), Some(fc)) = (&fine_ts, &fine_cmp) {
        folder.write("fine_grid.csv", with_kinematics(f, fc)?.to_csv().as_bytes())?;
    }
    // the model's coordinates under OpenSim's names (radians, inDegrees=no), on the 1 ms
    // grid when there is one, so the motion loads onto the subject's OpenSim model; an
    // impact's second sample (the same instant, the same coordinates) is left out, as
    // OpenSim's tables need time strictly increasing
    let keep: Vec<usize> = (0..line.times.len())
        .filter(|&k| k == 0 || line.times[k] > line.times[k - 1])
        .collect();
    let pick = |v: &[f64]| keep.iter().map(|&k| v[k]).collect::<Vec<f64>>();
    let mut kinematics = TimeSeries::new(pick(&line.times))?;
    for (name, q) in crate::data::OPENSIM_COORDINATES.iter().zip(&line.model_q) {
        kinematics.push(*name, pick(q))?;
    }
    // an unconverged run's table, motion and film strip say so in their first line
    let unsolved = (!converged).then(|| match interrupted {
        true => format!("{verdict}: the last accepted iterate, not a solution"),
        false => format!(
            "{verdict} ({}): the last iterate, not a solution",
            res.status
        ),
    });
    let sto_name = match &unsolved {
        Some(note) => format!("footfall_{csv_name}: {note}"),
        None => format!("footfall_{csv_name}"),
    };
    folder.write("kinematics.sto", kinematics.to_sto(&sto_name).as_bytes())?;
    let table_file = if run.command == "predict" {
        "table4.md"
    } else {
        "table3.md"
    };
    let unsolved_note = unsolved.clone();
    let caution = unsolved
        .map(|note| format!("**{note}**\n\n"))
        .unwrap_or_default();
    folder.write(
        table_file,
        format!(
            "{caution}{}\n{}",
            table.to_markdown(),
            by_phase.to_markdown()
        )
        .as_bytes(),
    )?;
    for (name, bytes) in &run.extra_files {
        folder.write(name, bytes)?;
    }
    if !animation.keys.is_empty() {
        // an XML comment may open the file before the <svg> element
        let caution = unsolved_note
            .as_ref()
            .map(|note| format!("<!-- {note} -->\n"))
            .unwrap_or_default();
        folder.write(
            "film_strip.svg",
            format!("{caution}{film_strip}").as_bytes(),
        )?;
    }
    folder.write("report.html", report.to_html().as_bytes())?;
    let path = folder.commit()?;
    let fine_forces = fine_cmp.map(|fc| FineForces {
        model: [
            [fc.model_feet[0][0].clone(), fc.model_feet[0][1].clone()],
            [fc.model_feet[1][0].clone(), fc.model_feet[1][1].clone()],
        ],
        measured: [
            [fc.data_feet[0][0].clone(), fc.data_feet[0][1].clone()],
            [fc.data_feet[1][0].clone(), fc.data_feet[1][1].clone()],
        ],
        times: fc.times,
    });
    Ok(GaitRunOutput {
        path,
        table,
        fine,
        transients,
        errors: overall,
        fine_forces,
        validity,
    })
}
