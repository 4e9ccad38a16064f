//! Writing a solved tracking run: its run folder (tables, plots, report), `setup.json`
//! with the effects and the identified parameters and their uncertainty.

use super::*;

impl TrackingProblem {
    /// Solve the problem and write its run folder (`setup.json` records the effects and
    /// the identified parameters with their uncertainty). `base` describes the run
    /// without `extra` effects.
    pub fn solve_and_write(
        &self,
        base: &TrackingRunSetup,
        extra: &[EffectSpec],
        settings: &SqpSettings,
        folder: RunFolder,
        transient_threshold: f64,
        progress: &dyn Progress,
    ) -> anyhow::Result<TrackedRun> {
        let w0 = self.with_transcription(|tr, _, w0| {
            {
                note!(progress,
                    "tracking {:.3}–{:.3} s of {}{} with the {} foot ({} variables, {} constraints, {:?})",
                    self.setup.window.0,
                    self.setup.window.1,
                    self.data.name,
                    if base.mirror {
                        " (legs swapped: the model's right leg follows the subject's left)"
                    } else {
                        ""
                    },
                    self.model.foot_name,
                    tr.n(),
                    tr.m(),
                    settings.hessian
                );
            }
            Ok(w0)
        })?;
        let cycle =
            GaitCycle::new(&self.model, &self.setup.seq, &self.sets).map_err(|e| anyhow!(e))?;
        let refinement = crate::workflows::refine::Refinement {
            cycle: &cycle,
            model: &self.model,
            sets: &self.sets,
            integrator: self.integrator.clone(),
            t0: self.setup.window.0,
            enabled: self.refine,
            max_iter: settings.max_iter,
            tol_kkt: settings.tol_kkt,
        };
        let build = || {
            self.setup
                .ocp(&cycle, &self.model, &self.sets, self.integrator.clone())
                .map_err(|e| anyhow!(e))
        };
        let mut solve = |tr: &Transcription, round: crate::workflows::refine::Round<'_>| {
            let settings = round.settings(settings);
            let judge = Some(round.judge);
            self.solve_staged(
                tr,
                &cycle,
                round.w0,
                &settings,
                progress,
                judge,
                |_, res| Ok(res),
            )
        };
        let (sites, res) =
            refinement.solve(&build, &self.check_sites, &w0, &mut solve, progress)?;
        let mut ocp = build()?;
        ocp.checks = cycle.checks_at(&sites);
        let tr = Transcription::new(&ocp).context("transcribing the tracking problem")?;
        self.write_run(
            &tr,
            &cycle,
            res,
            RunWriting {
                base,
                extra,
                folder,
                transient_threshold,
                progress,
                provenance: None,
                check_sites: &sites,
            },
        )
    }

    /// Write the run folder of the solver result `res` of this problem's transcription
    /// `tr` (solved by `track`, or re-evaluated by `report`).
    pub fn write_run(
        &self,
        tr: &Transcription,
        cycle: &GaitCycle,
        res: crate::sqp::SqpResult,
        how: RunWriting,
    ) -> anyhow::Result<TrackedRun> {
        let TrackingProblem {
            model,
            sets,
            data,
            setup,
            phases,
            integrator,
            ..
        } = self;
        let RunWriting {
            base,
            extra,
            folder,
            transient_threshold,
            progress,
            provenance,
            check_sites,
        } = how;
        let mut solution = GaitSolution::from_nlp(tr, &res.w, &cycle.continuous, setup.window.0);
        // a plate's clock offset moves the window's start with the events it gave
        setup.place(model, &mut solution);
        let converged = res.status == SqpStatus::Converged;
        let data_rows = setup.data_rows(model, sets, &cycle.continuous);
        let sd = self.parameter_uncertainty(tr, &res, data_rows, progress);
        let record = self.record(base, extra, &solution.theta, &sd, check_sites);
        // the run folder holds its inputs; setup.json names them relative to it
        let inputs = crate::workflows::inputs::copy_inputs(
            &folder,
            &record.model,
            &record.foot,
            &record.phases,
            record.data.as_deref(),
            record.forces.as_deref(),
        )?;
        let stored = TrackingRunSetup {
            model: inputs.model.clone(),
            foot: inputs.foot.to_string_lossy().into_owned(),
            phases: inputs.phases.clone(),
            data: Some(inputs.data.clone()),
            forces: inputs.forces.clone(),
            ..record.clone()
        };
        let extras = self.report_extras(ReportInputs {
            cycle,
            solution: &solution,
            record: &record,
            stored: &stored,
            data_rows,
            provenance: provenance.as_ref(),
            progress,
        })?;
        let out = crate::workflows::run_folder::write(
            GaitRun {
                command: "track",
                title: format!(
                    "footfall tracking — {} foot, {}",
                    model.foot_name, data.name
                ),
                data,
                model,
                sets,
                phases_path: phases,
                inputs: Some(&inputs),
                events: &self.setup.events,
                sequence: &self.setup.seq,
                control_bounds: (&self.setup.guess.u_lb, &self.setup.guess.u_ub),
                result: &res,
                solution: &solution,
                integrator: integrator.clone(),
                extra_summary: extras.summary,
                extra_json: extras.json,
                extra_sections: extras.sections,
                extra_files: vec![(
                    "setup.json".into(),
                    serde_json::to_string_pretty(&stored)?.into_bytes(),
                )],
                transient_threshold_n: transient_threshold,
                friction: cycle.friction(),
                check_points: check_sites.len(),
            },
            folder,
        )?;
        print_outcome(progress, &record, &out, &res);
        Ok(TrackedRun {
            converged,
            result: res,
            output: out,
            record,
            breakdown: extras.breakdown,
            residuals: extras.residuals,
            state_names: model.state_names(),
            solution,
        })
    }
}

impl TrackingProblem {
    /// The approximate standard deviation of each free parameter at the solution `res`
    /// of `tr` (None where the solve did not converge or the Hessian gives none).
    fn parameter_uncertainty(
        &self,
        tr: &Transcription,
        res: &crate::sqp::SqpResult,
        data_rows: usize,
        progress: &dyn Progress,
    ) -> Vec<Option<f64>> {
        let model = &self.model;
        let converged = res.status == SqpStatus::Converged;
        if model.ntheta() > 0 && converged {
            parameter_sd(tr, &res.w, data_rows).unwrap_or_else(|e| {
                warn_note!(progress, "warning: no parameter uncertainty: {e}");
                vec![None; model.ntheta()]
            })
        } else {
            vec![None; model.ntheta()]
        }
    }

    /// What a track run adds to the gait run folder: `summary.json`'s setup, data
    /// residual count, integration figures, cost breakdown and residual actuators, and
    /// the report's sections on them and on the effects.
    fn report_extras(&self, r: ReportInputs) -> anyhow::Result<ReportExtras> {
        let TrackingProblem {
            model,
            sets,
            setup,
            integrator,
            ..
        } = self;
        let mut extra_json = serde_json::Map::new();
        extra_json.insert("setup".into(), serde_json::to_value(r.stored)?);
        extra_json.insert("data_residuals".into(), r.data_rows.into());
        extra_json.insert(
            "integration".into(),
            serde_json::to_value(self.integration.get())?,
        );
        let mut extra_sections = Vec::new();
        let mut extra_summary = Vec::new();
        if let Some(p) = r.provenance {
            extra_summary.push(("report".into(), p.clone()));
        }
        let solution = r.solution;
        let breakdown =
            match setup.cost_breakdown(model, sets, &r.cycle.continuous, solution, integrator) {
                Ok(b) => {
                    extra_json.insert("cost_breakdown".into(), serde_json::to_value(&b)?);
                    extra_sections.push(crate::report::tracking::where_it_fails(&b, solution));
                    Some(b)
                }
                Err(e) => {
                    warn_note!(r.progress, "warning: no cost breakdown: {e}");
                    None
                }
            };
        let residuals = crate::report::tracking::residual_report(model, solution);
        if let Some((section, stats)) = &residuals {
            extra_sections.push(section.clone());
            extra_json.insert("residual_actuators".into(), stats.clone());
        }
        if !r.record.parameters.is_empty() {
            extra_sections.push(crate::report::html::Section {
                heading: "Effects".into(),
                paragraphs: vec!["Effect parameters of the model; identified ones with an approximate standard deviation from the Gauss–Newton Hessian reduced to the constraints, s² = J/(N − p).".into()],
                tables: vec![crate::report::tracking::parameter_table(&r.record.parameters)],
                svgs: vec![],
            });
        }
        Ok(ReportExtras {
            json: extra_json,
            sections: extra_sections,
            summary: extra_summary,
            breakdown,
            residuals: residuals.map(|r| r.0),
        })
    }
}

/// The progress lines after a track run is written: the identified parameters, the
/// solver's stop, the 1 ms re-integration's figures and where the report is.
fn print_outcome(
    progress: &dyn Progress,
    record: &TrackingRunSetup,
    out: &crate::workflows::run_folder::GaitRunOutput,
    res: &crate::sqp::SqpResult,
) {
    if !record.parameters.is_empty() {
        note!(
            progress,
            "{}",
            crate::report::tracking::parameter_table(&record.parameters).to_markdown()
        );
    }
    note!(progress, "{}", out.solve_summary(res));
    if let Some(f) = &out.fine {
        note!(progress,
            "1 ms re-integration: peak normal force {:.1} N (right), {:.1} N (left); largest Baumgarte force {:.1e} N; largest drift {:.2e} m",
            f.peak_normal_force_n[0], f.peak_normal_force_n[1], f.max_baumgarte_force_n, f.max_position_drift_m
        );
    }
    note!(
        progress,
        "report: {}",
        out.path.join("report.html").display()
    );
}

/// What [`TrackingProblem::report_extras`] reads.
struct ReportInputs<'a> {
    /// The problem's gait cycle.
    cycle: &'a GaitCycle<'a>,
    /// The solution, placed in the trial's time.
    solution: &'a GaitSolution,
    /// The run's description.
    record: &'a TrackingRunSetup,
    /// The description as `setup.json` stores it (inputs named as copied into the run).
    stored: &'a TrackingRunSetup,
    /// Number of data residuals of the cost.
    data_rows: usize,
    /// Where the figures come from, when not from a solve just made.
    provenance: Option<&'a String>,
    /// Where warnings go.
    progress: &'a dyn Progress,
}

/// What a track run adds to the gait run folder's `summary.json`, summary box and report.
struct ReportExtras {
    /// Extra `summary.json` fields.
    json: serde_json::Map<String, serde_json::Value>,
    /// Extra report sections.
    sections: Vec<crate::report::html::Section>,
    /// Extra summary lines.
    summary: Vec<(String, String)>,
    /// Where the cost comes from (None when it could not be evaluated).
    breakdown: Option<crate::problems::track::CostBreakdown>,
    /// The residual actuators' section, for a model that has them.
    residuals: Option<crate::report::html::Section>,
}

/// How [`TrackingProblem::write_run`] writes a run.
pub struct RunWriting<'a> {
    /// The run without `extra` effects.
    pub base: &'a TrackingRunSetup,
    /// Effects added to `base`.
    pub extra: &'a [EffectSpec],
    /// Where to write.
    pub folder: RunFolder,
    /// Report ground-force excursions above the measurement larger than this (N).
    pub transient_threshold: f64,
    /// Print nothing.
    pub progress: &'a dyn Progress,
    /// Where the figures come from, when not from a solve just made.
    pub provenance: Option<String>,
    /// The problem's check points (recorded in `setup.json`).
    pub check_sites: &'a [(usize, usize, f64)],
}

/// A solved and written tracking run.
pub struct TrackedRun {
    /// Whether the solver converged.
    pub converged: bool,
    /// The solver's result.
    pub result: crate::sqp::SqpResult,
    /// What the run folder holds.
    pub output: crate::workflows::run_folder::GaitRunOutput,
    /// The run's description.
    pub record: TrackingRunSetup,
    /// Where the cost comes from (None when it could not be evaluated).
    pub breakdown: Option<crate::problems::track::CostBreakdown>,
    /// The residual actuators' section, for a model that has them.
    pub residuals: Option<crate::report::html::Section>,
    /// The solution: states and controls at the shooting nodes, free parameters.
    pub solution: GaitSolution,
    /// Names of the states (`q`, `q̇`, activations), in the solution's order.
    pub state_names: Vec<String>,
}
