//! The run folder of a gait OCP (tracking or prediction): model against measurement at
//! the nodes, overall and by phase, the 1 ms re-integration figures, plots, the solution
//! for later runs, `summary.json` and `report.html`.

#[allow(unused_imports)]
use super::{note, warn_note, Progress};
use crate::data::GaitData;
use crate::integrate::IntegratorSettings;
use crate::model::{ConstraintSet, GaitModel};
use crate::problems::evaluation::{channel_errors, Comparison, FineGridFigures, GaitSolution};
use crate::problems::transient::ForceTransient;
use crate::report::html::Section;
use crate::report::table::Table;
use crate::runfolder::RunFolder;
use crate::sqp::SqpResult;
use evaluation::{Evaluation, Verdict};
use figures::Figures;
use std::path::PathBuf;

mod evaluation;
mod figures;
mod files;
mod report;
mod sections;

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
            "{}\n{}: {}, {} iterations, {:.1} s",
            self.table.to_markdown(),
            res.status,
            res.objective_and_kkt(6),
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
    /// The ground forces of both feet on the fine grid of `fc`.
    fn of(fc: Comparison) -> Self {
        FineForces {
            model: [
                [fc.model_feet[0][0].clone(), fc.model_feet[0][1].clone()],
                [fc.model_feet[1][0].clone(), fc.model_feet[1][1].clone()],
            ],
            measured: [
                [fc.data_feet[0][0].clone(), fc.data_feet[0][1].clone()],
                [fc.data_feet[1][0].clone(), fc.data_feet[1][1].clone()],
            ],
            times: fc.times,
        }
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
pub fn write(mut run: GaitRun, folder: RunFolder) -> anyhow::Result<GaitRunOutput> {
    let ev = Evaluation::of(&run)?;
    let verdict = Verdict::of(run.result, ev.validity.as_ref());
    let figures = Figures::draw(&run, &ev, verdict.text);
    let series = files::Series::of(&run, &ev)?;
    let report = report::report(&mut run, &ev, &verdict, &figures);
    let overall = channel_errors(&ev.channels, &ev.cmp, None);
    let summary_file = files::summary_file(&run, &ev, &verdict, &figures.cycle, &overall);
    let summary_json = summary_file.to_json(std::mem::take(&mut run.extra_json))?;
    folder.write(
        "summary.json",
        serde_json::to_string_pretty(&summary_json)?.as_bytes(),
    )?;
    folder.write(
        "solution.json",
        serde_json::to_string_pretty(run.solution)?.as_bytes(),
    )?;
    files::write_tables(&folder, &run, &ev, &verdict, &series, &figures)?;
    folder.write("report.html", report.to_html().as_bytes())?;
    let path = folder.commit()?;
    let fine_forces = ev.fine_cmp.map(FineForces::of);
    Ok(GaitRunOutput {
        path,
        table: ev.table,
        fine: ev.fine,
        transients: ev.transients,
        errors: overall,
        fine_forces,
        validity: ev.validity,
    })
}
