//! `footfall diagnose RUN`: which effect of the catalog is the model of a tracking run
//! missing? For every candidate: is it testable with the run's cost at all (reduced
//! Fisher information), its score test at the run's solution (a full re-fit for the
//! heel pad, which has no null value) with the statistic corrected for correlated
//! residuals; the significant ones are validated on another half cycle of the trial
//! (`diagnose/heldout.rs`) and the top found ones re-fitted for real (each written as a track run
//! folder, so `diff` and a second `diagnose` can start from it). The instruments and the
//! body are not among the candidates: the measurement stage (`footfall check`, the trial's
//! own Newton–Euler balance) reads them without a contact model, and its verdict is shown
//! first.

use super::track::{read_run_setup, TrackingProblem};
#[allow(unused_imports)]
use super::{note, warn_note, Progress};
use crate::model::effects::{catalog, EffectSpec};
use crate::model::GaitModel;
use crate::problems::diagnose::{ScoreTest, TrackingRunSetup};

mod heldout;
mod model_null;
mod noise;
mod output;
mod refit;
mod scoring;
mod starts;
pub mod summary;
use crate::problems::evaluation::GaitSolution;
use crate::report::diff::RunSummary;
use crate::runfolder::RunFolder;
use anyhow::anyhow;
use noise::{baseline_residuals, linearisation};
use refit::{diff_with, refit, Evidence, Verified};
use scoring::score_all;
use std::path::{Path, PathBuf};

/// The `--candidate` name that stands for the default candidates: the catalog, the heel
/// pad on a foot with a heel circle and the contact law on a volumetric foot.
pub const CATALOG: &str = "catalog";

/// What `diagnose` does: the arguments of `footfall diagnose`.
#[derive(Debug, Clone)]
pub struct DiagnoseRequest {
    /// A track run folder.
    pub run: PathBuf,
    /// Re-fit this many of the top significant candidates to verify them.
    pub verify: usize,
    /// Only these candidates (effect names or `NAME:key=value,…`; default: the catalog).
    /// [`CATALOG`] among them stands for the default set, so that others can be added to
    /// it (`catalog`, `foot_geometry`).
    pub candidates: Vec<String>,
    /// Output folder (default: `<RUN>-diagnose`); re-fits go to `<RUN>+<effect>`.
    pub out: Option<PathBuf>,
    /// Replace existing output folders.
    pub overwrite: bool,
    /// KKT tolerance of the re-fits.
    pub tol: f64,
    /// Iteration limit of the re-fits.
    pub max_iter: usize,
    /// Validate significant candidates on another half cycle of the trial (default on;
    /// off: they are reported "significant, not validated").
    pub held_out: bool,
    /// Another recording of the same subject to validate on (`--held-out-data`): its
    /// first half cycle is held out instead of one of the run's own trial. It is read as
    /// the run's trial is (`--data`), without a forces file.
    pub held_out_data: Option<PathBuf>,
    /// Kept solutions to start the diagnosis's own solves from (`--start`): run folders
    /// with `setup.json` and `solution.json` (an earlier re-fit `<RUN>+<effect>`), or
    /// folders of them (an earlier `<RUN>-diagnose`, whose `held_out` is its held-out
    /// track); each starts the solve
    /// of the same problem, which still iterates to the KKT tolerance from there.
    pub starts: Vec<PathBuf>,
}

impl DiagnoseRequest {
    /// A request with `footfall diagnose`'s defaults for the track run `run`: the default
    /// candidates, one verifying re-fit, held-out validation, re-fits to KKT 1e-5 within
    /// 200 iterations, the output beside the run (`<RUN>-diagnose`, not replaced); no
    /// kept starts.
    pub fn new(run: PathBuf) -> Self {
        DiagnoseRequest {
            run,
            verify: 1,
            candidates: Vec::new(),
            out: None,
            overwrite: false,
            tol: 1e-5,
            max_iter: 200,
            held_out: true,
            held_out_data: None,
            starts: Vec::new(),
        }
    }
}

/// The run being diagnosed: its solution, summary, cost and data residual count.
pub(super) struct Baseline<'a> {
    solution: &'a GaitSolution,
    summary: &'a RunSummary,
    objective: f64,
    rows: usize,
}

fn sibling(run: &Path, suffix: &str) -> PathBuf {
    let name = run
        .file_name()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "run".into());
    run.with_file_name(format!("{name}{suffix}"))
}

/// The first stage: the run's trial checked against itself (whole-body Newton–Euler,
/// no model fitted), reported before the model stage. Returns its text (`None` where the
/// trial cannot be read so, which is said). Where it finds an instrument or body effect
/// the run's model lacks, the text says that the model stage reads the model against a
/// measurement not yet corrected, and how to correct it first.
fn measurement_stage(
    setup: &crate::problems::diagnose::TrackingRunSetup,
    progress: &dyn Progress,
) -> Option<String> {
    let req = super::check::CheckRequest {
        trial: super::trial::TrialFiles {
            data: setup.data.clone(),
            forces: setup.forces.clone(),
            plates: setup.plates.clone(),
            lab_axes: setup.lab_axes.clone(),
            belt_speed: setup.belt_speed,
            overground: setup.overground,
        },
        model: setup.model.clone(),
        out: None,
        overwrite: false,
        settings: crate::problems::check::CheckSettings::default(),
    };
    match super::check::read(&req) {
        Ok((_, check, _)) => {
            let mut text = format!(
                "stage 1, the measurement against itself (footfall check):\n{}",
                super::check::output::verdict_text(&check)
            );
            let missing: Vec<String> = super::check::effect_lines(&check)
                .into_iter()
                .filter(|line| !held_already(setup, line))
                .collect();
            if !missing.is_empty() {
                text += &format!(
                    "The model stage below reads the model against this measurement as it is: what the check found also moves the model's misfit. To read the model's physics alone, re-track the run with {} (or on the check's corrected trial, `footfall check TRIAL --out DIR` then `--data DIR/corrected/trial.csv`) and diagnose that run.\n",
                    missing
                        .iter()
                        .map(|l| format!("`--effect {l}`"))
                        .collect::<Vec<_>>()
                        .join(" ")
                );
            }
            progress.result(&text);
            Some(text)
        }
        Err(e) => {
            progress.note(&format!(
                "stage 1, the measurement against itself: not read ({e:#})"
            ));
            None
        }
    }
}

/// Whether the run's model already holds an effect of the kind `line` (an `--effect`
/// line of the check) adds.
fn held_already(setup: &crate::problems::diagnose::TrackingRunSetup, line: &str) -> bool {
    EffectSpec::parse_cli(line).is_ok_and(|spec| setup.effects.iter().any(|e| e.overlaps(&spec)))
}

/// What every step of a diagnosis reads: the request, the run's setup, solution and
/// summary, and where progress goes.
struct RunInputs<'a> {
    args: &'a DiagnoseRequest,
    setup: &'a TrackingRunSetup,
    solution: &'a GaitSolution,
    before: &'a RunSummary,
    progress: &'a dyn Progress,
}

/// Run `diagnose` as `args` describes, reporting to `progress`: the measurement stage
/// first, then the model stage.
pub fn run(args: &DiagnoseRequest, progress: &dyn Progress) -> anyhow::Result<()> {
    // a bad --start is named before any work
    starts::kept_solutions(&args.starts)?;
    let setup = read_run_setup(&args.run)?;
    let solution = super::read_solution(&args.run)?;
    let before = RunSummary::read(&args.run)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| sibling(&args.run, "-diagnose"));
    let folder = RunFolder::create(&out, args.overwrite)?;
    let measured = measurement_stage(&setup, progress);
    if let Some(text) = &measured {
        folder.write("measurement.md", text.as_bytes())?;
    }
    let run = RunInputs {
        args,
        setup: &setup,
        solution: &solution,
        before: &before,
        progress,
    };
    // the baseline: the run's own problem at its solution
    let mut base = linearisation(TrackingProblem::build(&setup, &[])?);
    base.setup
        .start_from(&solution)
        .map_err(|e| anyhow!("{}: {e}", args.run.display()))?;
    let (resid, phi_all) = baseline_residuals(&run, &base)?;
    let candidates = candidates_of(args, &base.model)?;
    let (mut tests, evidence, skipped, full) = score_all(
        &run,
        &base,
        &resid,
        phi_all,
        &candidates,
        &folder.staging_path().join("model_null"),
    )?;
    let (held_out_note, held_base) = validate_held_out(&run, base.setup.window, &mut tests)?;
    for t in &mut tests {
        t.settle();
    }
    let verified = verify_found(&run, resid.objective, &tests, &evidence)?;
    let ctx = output::Outcome {
        args,
        before: &before,
        objective: resid.objective,
        rows: resid.rows,
        resid: &resid,
        phi: phi_all,
        noise: full.as_ref(),
        tests: &tests,
        evidence: &evidence,
        verified: &verified,
        skipped: &skipped,
        held_out_note: held_out_note.trim().to_string(),
        measurement: measured,
        held_out: held_base.as_ref().and_then(|b| b.as_ref().ok()),
        clock_moves_events: setup.sample_targets || setup.one_sided_targets,
    };
    output::write(&ctx, folder, progress)
}

/// The candidates to test: the named ones, and the default set (the catalog, the heel
/// pad on a foot with a heel circle, the contact law on a volumetric foot) when none is
/// named or [`CATALOG`] is among them.
fn candidates_of(args: &DiagnoseRequest, model: &GaitModel) -> anyhow::Result<Vec<EffectSpec>> {
    let with_catalog = args.candidates.is_empty() || args.candidates.iter().any(|c| c == CATALOG);
    let mut candidates: Vec<EffectSpec> = if with_catalog { catalog() } else { Vec::new() };
    for c in args.candidates.iter().filter(|c| *c != CATALOG) {
        let spec = EffectSpec::parse_cli(c).map_err(|e| anyhow!("--candidate: {e}"))?;
        if !candidates.contains(&spec) {
            candidates.push(spec);
        }
    }
    if !with_catalog {
        return Ok(candidates);
    }
    // the heel pad, tested by a re-fit on runs with sample or one-sided targets, named as
    // not scored on others
    let mut extra = Vec::new();
    if model.contacts.iter().any(|c| c.name.ends_with(".heel")) {
        extra.push("heel_pad_compliance");
    }
    // the volumetric contact law, its null value the foot file's law ("is the law the
    // one the forces ask for?")
    if model.has_volumetric_contacts() {
        extra.push("volumetric_contact");
    }
    for name in extra {
        let spec = EffectSpec::parse_cli(name)?;
        if !candidates.contains(&spec) {
            candidates.push(spec);
        }
    }
    Ok(candidates)
}

/// The held-out half cycle's plain track, once (`None`: none was needed; `Err`: why the
/// trial has none).
type HeldOutTrack = Option<Result<heldout::HeldOutBase, heldout::NoHeldOut>>;

/// Validate the significant candidates of `tests` on another half cycle of the trial
/// than the run's (`window`, s): the note that says how it went, and that half cycle's
/// track.
fn validate_held_out(
    run: &RunInputs,
    window: (f64, f64),
    tests: &mut [ScoreTest],
) -> anyhow::Result<(String, HeldOutTrack)> {
    let (args, progress) = (run.args, run.progress);
    let validated = |t: &ScoreTest| t.significant && t.at_bound.is_empty() && !t.refit;
    let mut note: String = tests
        .iter()
        .filter(|t| t.significant && t.refit)
        .map(|t| format!(" {} is not validated on a held-out half cycle: it was tested by a full re-fit, which gives no reduced curvature to set its noise band.", t.label))
        .collect();
    if !tests.iter().any(validated) {
        return Ok((note, None));
    }
    if !args.held_out {
        note += " Held-out validation was not asked for (--no-held-out): significant candidates are not validated.";
        return Ok((note, None));
    }
    let held_base = heldout::held_out_base(args, run.setup, window, progress)?;
    let hb = match &held_base {
        Ok(hb) => hb,
        Err(why) => {
            note += &format!(" No held-out half cycle in this trial ({why}): significant candidates are not validated.");
            return Ok((note, Some(held_base)));
        }
    };
    note += &format!(
        " Held-out: each significant candidate, with the values fitted on this run's half cycle ({:.3}–{:.3} s), applied to {} ({:.3}–{:.3} s; the plain model tracked there: J = {:.6}, {} iterations{}) with the other variables re-fitted; it is found if it lowers that cost beyond its noise band (2 sd, inflated by φ, above the mean change a fit to noise makes, which is a rise). Each is applied at the opposite values too: the two changes give that half cycle's own curvature along the candidate, which sets its band, and its own reading of the candidate as a fraction of the fitted values (found: that reading lies beyond 2 sd). Where a true effect of the fitted size would not clear the band on average (the reading's sd above one half), that half cycle is too weakly informed to confirm or refute it: not validatable.",
        window.0,
        window.1,
        hb.name(),
        hb.window.0,
        hb.window.1,
        hb.objective,
        hb.iterations,
        if hb.converged { "" } else { ", NOT converged" }
    );
    for t in tests.iter_mut().filter(|t| validated(t)) {
        match heldout::validate(hb, t) {
            Ok(h) => {
                note!(
                    progress,
                    "  held-out {:<32} change {:>10.3e} ({:>5.1} % of J), noise band {:.3e}{}{}",
                    t.label,
                    h.change,
                    100.0 * h.change_fraction,
                    h.band,
                    reading_note(&h),
                    confirmed_note(&h)
                );
                t.held_out = Some(h);
            }
            Err(e) => {
                note += &format!(" {}: the held-out validation failed ({e:#}).", t.label);
            }
        }
    }
    Ok((note, Some(held_base)))
}

/// Re-fit the top `--verify` found candidates for real, each from where its test got to.
fn verify_found(
    run: &RunInputs,
    objective: f64,
    tests: &[ScoreTest],
    evidence: &[Evidence],
) -> anyhow::Result<Vec<Verified>> {
    let mut verified = Vec::new();
    for (t, e) in tests
        .iter()
        .zip(evidence)
        .filter(|(t, _)| t.found)
        .take(run.args.verify)
    {
        let v = match e {
            // the test was the re-fit
            Evidence::Refit(refitted, diff) => Verified::new(t, refitted, diff.clone(), objective),
            // from where the candidate's truncated re-fit got to (fewer SQP iterations
            // than from the run's solution)
            Evidence::Start(start) => {
                let refitted = refit(run.args, run.setup, &t.effect, start, run.progress)?;
                Verified::new(t, &refitted, diff_with(run.before, &refitted)?, objective)
            }
        };
        verified.push(v);
    }
    Ok(verified)
}

/// The progress line's reading of a held-out validation: `, reads 0.62 ± 0.41 of it`.
fn reading_note(h: &crate::problems::diagnose::HeldOut) -> String {
    h.reading
        .as_ref()
        .map_or(String::new(), |r| format!(", {}", r.text()))
}

/// The progress line's verdict of a held-out validation.
fn confirmed_note(h: &crate::problems::diagnose::HeldOut) -> &'static str {
    if h.beyond_noise {
        "  confirmed"
    } else if h.too_weakly_informed() {
        "  not validatable (too weakly informed there)"
    } else {
        "  not confirmed"
    }
}
