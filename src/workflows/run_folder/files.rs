//! The data files of a gait run folder: the time series at the nodes and on the 1 ms
//! grid (CSV), the motion for OpenSim (`kinematics.sto`), the error tables (Markdown),
//! the film strip (SVG) and the record of `summary.json`.

use super::evaluation::{Evaluation, Verdict};
use super::figures::Figures;
use super::GaitRun;
use crate::model::gait::COORDINATES;
use crate::problems::evaluation::{channel_errors, Comparison, LOAD_NAMES};
use crate::report::csv::TimeSeries;
use crate::report::gait_figures::CycleAxis;
use crate::report::run_summary as rs;
use crate::report::table::{ChannelErrors, ErrorStats};
use crate::runfolder::RunFolder;

/// The time series of a run: at the nodes, and on the fine grid where there is one.
pub(super) struct Series {
    /// At the shooting nodes.
    pub nodes: TimeSeries,
    /// On the 1 ms grid (None when the re-integration failed).
    pub fine: Option<TimeSeries>,
}

impl Series {
    /// The time series of `run` evaluated as `ev`. Every row carries the solve's outcome,
    /// so that a table of an unfinished solve says so wherever it is read (a comment line
    /// would break CSV readers).
    pub fn of(run: &GaitRun, ev: &Evaluation) -> anyhow::Result<Self> {
        let (sets, res, cmp) = (run.sets, run.result, &ev.cmp);
        let outcome = |n: usize| vec![res.status.outcome().to_string(); n];
        let mut ts = TimeSeries::new(cmp.times.clone())?;
        ts.push_text("status", outcome(cmp.times.len()))?;
        ts.push_text(
            "phase",
            cmp.phase.iter().map(|&p| sets[p].name.clone()).collect(),
        )?;
        for i in 0..9 {
            ts.push(format!("model_{}", COORDINATES[i]), cmp.model_q[i].clone())?;
            ts.push(format!("data_{}", COORDINATES[i]), cmp.data_q[i].clone())?;
        }
        for (s, side) in ["r", "l"].iter().enumerate() {
            for (k, what) in LOAD_NAMES.iter().enumerate() {
                ts.push(format!("model_{what}_{side}"), cmp.model_feet[s][k].clone())?;
                ts.push(format!("data_{what}_{side}"), cmp.data_feet[s][k].clone())?;
            }
        }
        let fine_ts = match (&ev.fine_run, &ev.fine_cmp) {
            (Ok(f), Some(fc)) => {
                let mut t = TimeSeries::new(fc.times.clone())?;
                t.push_text("status", outcome(fc.times.len()))?;
                t.push_text(
                    "phase",
                    fc.phase.iter().map(|&p| sets[p].name.clone()).collect(),
                )?;
                for i in 0..9 {
                    t.push(format!("model_{}", COORDINATES[i]), fc.model_q[i].clone())?;
                }
                for (s, side) in ["r", "l"].iter().enumerate() {
                    for (k, what) in LOAD_NAMES.iter().enumerate() {
                        t.push(format!("model_{what}_{side}"), fc.model_feet[s][k].clone())?;
                        t.push(format!("data_{what}_{side}"), fc.data_feet[s][k].clone())?;
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
        Ok(Series {
            nodes: ts,
            fine: fine_ts,
        })
    }
}

/// The record of `summary.json` (before the run's extra fields); channels without a
/// defined sample in a phase are left out (no nulls). `overall` holds the overall error
/// statistics per channel.
pub(super) fn summary_file(
    run: &GaitRun,
    ev: &Evaluation,
    verdict: &Verdict,
    cycle: &CycleAxis,
    overall: &[ChannelErrors],
) -> rs::RunSummaryFile {
    let (model, data, res, sol) = (run.model, run.data, run.result, run.solution);
    let (t0, t1) = sol.span();
    let validity = &ev.validity;
    let phased = channel_errors(&ev.channels, &ev.cmp, Some(&ev.phase_ids));
    rs::RunSummaryFile {
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
        verdict: Some(verdict.text.to_string()),
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
                    phases: ev
                        .phase_names
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
        fine_grid: ev.fine.clone(),
        fine_grid_error: ev.fine_run.as_ref().err().map(ToString::to_string),
        transient_threshold_n: Some(run.transient_threshold_n),
        transients: ev.transients.clone(),
        most_violated: res.most_violated.clone(),
        history: res.history.clone(),
    }
}

/// One channel's error statistics as `summary.json` records them.
fn stats(s: &Option<ErrorStats>) -> Option<rs::SummaryStats> {
    s.map(|v| rs::SummaryStats {
        mean: v.mean,
        sd: Some(v.sd),
        max: Some(v.max),
    })
}

/// Write the run's tables into `folder`: the time series (CSV), the motion for OpenSim,
/// the error tables, the run's extra files and the film strip.
pub(super) fn write_tables(
    folder: &RunFolder,
    run: &GaitRun,
    ev: &Evaluation,
    verdict: &Verdict,
    series: &Series,
    figures: &Figures,
) -> anyhow::Result<()> {
    let csv_name = if run.command == "predict" {
        "prediction"
    } else {
        "tracking"
    };
    folder.write(
        &format!("{csv_name}.csv"),
        with_kinematics(&series.nodes, &ev.cmp)?.to_csv().as_bytes(),
    )?;
    if let (Some(f), Some(fc)) = (&series.fine, &ev.fine_cmp) {
        folder.write("fine_grid.csv", with_kinematics(f, fc)?.to_csv().as_bytes())?;
    }
    let kinematics = opensim_kinematics(ev.line())?;
    // an unconverged run's table, motion and film strip say so in their first line
    let unsolved = verdict.unsolved(run.result);
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
    let caution = unsolved
        .as_ref()
        .map(|note| format!("**{note}**\n\n"))
        .unwrap_or_default();
    folder.write(
        table_file,
        format!(
            "{caution}{}\n{}",
            ev.table.to_markdown(),
            ev.by_phase.to_markdown()
        )
        .as_bytes(),
    )?;
    for (name, bytes) in &run.extra_files {
        folder.write(name, bytes)?;
    }
    if !figures.animation.keys.is_empty() {
        // an XML comment may open the file before the <svg> element
        let caution = unsolved
            .as_ref()
            .map(|note| format!("<!-- {note} -->\n"))
            .unwrap_or_default();
        folder.write(
            "film_strip.svg",
            format!("{caution}{}", figures.film_strip).as_bytes(),
        )?;
    }
    Ok(())
}

/// `series` with the measured coordinates and both velocities of `c` added: the CSV
/// files carry what the cost compares, and what `footfall report RUN_A RUN_B` overlays
/// (the `.sto` keeps the model's coordinates only).
fn with_kinematics(series: &TimeSeries, c: &Comparison) -> anyhow::Result<TimeSeries> {
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
}

/// The model's coordinates of `line` under OpenSim's names (radians, inDegrees=no), so
/// the motion loads onto the subject's OpenSim model; an impact's second sample (the
/// same instant, the same coordinates) is left out, as OpenSim's tables need time
/// strictly increasing.
fn opensim_kinematics(line: &Comparison) -> anyhow::Result<TimeSeries> {
    let keep: Vec<usize> = (0..line.times.len())
        .filter(|&k| k == 0 || line.times[k] > line.times[k - 1])
        .collect();
    let pick = |v: &[f64]| keep.iter().map(|&k| v[k]).collect::<Vec<f64>>();
    let mut kinematics = TimeSeries::new(pick(&line.times))?;
    for (name, q) in crate::data::OPENSIM_COORDINATES.iter().zip(&line.model_q) {
        kinematics.push(*name, pick(q))?;
    }
    Ok(kinematics)
}
