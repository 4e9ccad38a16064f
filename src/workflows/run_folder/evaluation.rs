//! A gait run evaluated: model against measurement at the shooting nodes and on the 1 ms
//! re-integration, the error tables, physical validity on the fine grid, the ground-force
//! transients, and the verdict they give with the solver's stop.

use super::{GaitRun, FINE_STEP};
use crate::problems::evaluation::{
    channel_errors, Comparison, ErrorChannel, FineGridFigures, Reintegration,
};
use crate::problems::transient::{force_transients, ForceTransient};
use crate::problems::validity::Validity;
use crate::report::table::{error_table, Table};
use crate::simulate::{Sample, SimulationError};
use crate::sqp::{SqpResult, SqpStatus};
use anyhow::Context;

/// Why a run has no 1 ms re-integration: reported with the run, not fatal.
#[derive(Debug, thiserror::Error)]
pub(super) enum FineGridError {
    /// It failed (e.g. that of an early iterate).
    #[error("the 1 ms re-integration failed: {0}")]
    Failed(#[source] SimulationError),
    /// The run was interrupted: it is written from its last iterate at once, and the
    /// re-integration (seconds to minutes on a fine mesh far from a solution) is left to
    /// `footfall report`.
    #[error("the 1 ms re-integration was not run: the run was interrupted (`footfall report RUN` runs it)")]
    Interrupted,
}

/// Model against measurement, at the nodes and on the fine grid.
pub(super) struct Evaluation {
    /// The solution's states at the shooting nodes.
    pub nodes: Vec<Sample>,
    /// Model against measurement at the nodes.
    pub cmp: Comparison,
    /// The channels of the error tables.
    pub channels: Vec<ErrorChannel>,
    /// The overall error table.
    pub table: Table,
    /// The error table phase by phase.
    pub by_phase: Table,
    /// Each solved phase's constraint set.
    pub phase_ids: Vec<usize>,
    /// Each solved phase's name.
    pub phase_names: Vec<String>,
    /// The 1 ms re-integration, or why it failed.
    pub fine_run: Result<Reintegration, FineGridError>,
    /// Its figures (None when it failed).
    pub fine: Option<FineGridFigures>,
    /// Model against measurement on the fine grid (None when it failed).
    pub fine_cmp: Option<Comparison>,
    /// Physical validity on the fine grid (None when it failed).
    pub validity: Option<Validity>,
    /// Ground-force transients on the fine grid, strongest first.
    pub transients: Vec<ForceTransient>,
}

impl Evaluation {
    /// Evaluate the run's solution at the nodes and on the 1 ms grid.
    pub fn of(run: &GaitRun) -> anyhow::Result<Self> {
        let (model, sets, data, sol) = (run.model, run.sets, run.data, run.solution);
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

        // fine grid: a failure (e.g. of an early iterate) is reported, not fatal
        let fine_run = if crate::interrupt::requested() {
            Err(FineGridError::Interrupted)
        } else {
            sol.reintegrate(model, sets, FINE_STEP, &run.integrator)
                .map_err(FineGridError::Failed)
        };
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
        Ok(Evaluation {
            nodes,
            cmp,
            channels,
            table,
            by_phase,
            phase_ids,
            phase_names,
            fine_run,
            fine,
            fine_cmp,
            validity,
            transients,
        })
    }

    /// What the plots draw as lines: the fine grid where there is one, else the nodes.
    pub fn line(&self) -> &Comparison {
        self.fine_cmp.as_ref().unwrap_or(&self.cmp)
    }

    /// The legend of the plots' model line.
    pub fn line_label(&self) -> &'static str {
        if self.fine_cmp.is_some() {
            "model (1 ms re-integration)"
        } else {
            "model"
        }
    }

    /// The states the figures of the body and the actuators show: the fine grid's, else
    /// the nodes'.
    pub fn states(&self) -> &[Sample] {
        match &self.fine_run {
            Ok(f) => &f.result.samples,
            Err(_) => &self.nodes,
        }
    }
}

/// The run's verdict: the solver's stop and the physical validity on the fine grid.
pub(super) struct Verdict {
    /// The solver converged.
    pub converged: bool,
    /// The solve was interrupted.
    pub interrupted: bool,
    /// The solution breaks physics on the fine grid.
    pub invalid: bool,
    /// The verdict in words (`converged`, `not converged, physically invalid`, …).
    pub text: &'static str,
}

impl Verdict {
    /// The verdict of the solver result `res` with `validity` on the fine grid.
    pub fn of(res: &SqpResult, validity: Option<&Validity>) -> Self {
        let converged = res.status == SqpStatus::Converged;
        let interrupted = res.status == crate::sqp::SqpStatus::Interrupted;
        let invalid = validity.is_some_and(|v| !v.is_valid());
        let text = match (converged, invalid) {
            (true, false) => "converged",
            (true, true) => "converged, physically invalid",
            (false, true) if interrupted => "interrupted, physically invalid",
            (false, false) if interrupted => "interrupted",
            (false, true) => "not converged, physically invalid",
            (false, false) => "not converged",
        };
        Verdict {
            converged,
            interrupted,
            invalid,
            text,
        }
    }

    /// The caution an unconverged run's table, motion and film strip open with (None
    /// when converged).
    pub fn unsolved(&self, res: &SqpResult) -> Option<String> {
        let verdict = self.text;
        (!self.converged).then(|| match self.interrupted {
            true => format!("{verdict}: the last accepted iterate, not a solution"),
            false => format!(
                "{verdict} ({}): the last iterate, not a solution",
                res.status
            ),
        })
    }
}
