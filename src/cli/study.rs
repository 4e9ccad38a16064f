//! `footfall study`: the arguments of a study of many trials
//! ([`footfall::workflows::study`]), run here, as a Slurm array, or gathered.

use super::{CliProgress, Failure};
use footfall::workflows::study::{self, StudyRequest, StudySettings};
use footfall::workflows::Progress;
use std::path::{Path, PathBuf};

/// Arguments of `footfall study`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The manifest: a CSV (header row, one row per trial) or JSON (an array of objects)
    /// with the fields id, subject, session, condition, data, forces, plate, lab_axes,
    /// belt_speed, overground, model, foot, cutoff, max_iter, kinematics_cutoff.
    #[arg(value_name = "MANIFEST", required_unless_present = "collect")]
    manifest: Option<PathBuf>,
    /// The study folder: trials/<id>/ per trial, study.csv, study.json, report.html.
    #[arg(long, default_value = "runs/study")]
    out: PathBuf,
    /// Build the study table from the finished trial folders of DIR (after a Slurm array).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["manifest", "slurm", "only_row", "track", "diagnose"])]
    collect: Option<PathBuf>,
    /// Track each trial after its check (tens of seconds a trial).
    #[arg(long)]
    track: bool,
    /// Diagnose each track (`footfall diagnose`: score tests, held-out validation, a
    /// re-fit; minutes a trial), its re-fits at --max-iter.
    #[arg(long, requires = "track")]
    diagnose: bool,
    /// A track's iteration limit (a row's max_iter overrides it).
    #[arg(long, default_value_t = 200, value_parser = super::validate::iterations)]
    max_iter: usize,
    /// The check's low-pass cutoff (Hz; a row's cutoff overrides it).
    #[arg(long, default_value_t = 6.0, value_parser = super::validate::positive)]
    cutoff: f64,
    /// Family-wise significance level of each check and of the pooled readings.
    #[arg(long, default_value_t = 0.05, value_parser = super::validate::positive)]
    level: f64,
    /// Trials at once (default: the machine's cores), each with the cores divided by N
    /// for a track's own threads.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    jobs: Option<u32>,
    /// Run only this row of the manifest (1-based) and write no table: a Slurm task.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    only_row: Option<u32>,
    /// Write a Slurm job array (one task per row) and a job that gathers the table after
    /// it, into DIR/slurm/, and submit them with sbatch.
    #[arg(long)]
    slurm: bool,
    /// With --slurm: print the scripts instead of submitting them.
    #[arg(long, requires = "slurm")]
    dry_run: bool,
    /// With --slurm: CPUs per task.
    #[arg(long, default_value_t = 1, requires = "slurm", value_parser = clap::value_parser!(u32).range(1..=1024))]
    cpus_per_task: u32,
    /// With --slurm: wall-time limit per task (sbatch's --time, e.g. 00:30:00).
    #[arg(long, requires = "slurm")]
    time: Option<String>,
    /// With --slurm: the partition.
    #[arg(long, requires = "slurm")]
    partition: Option<String>,
}

pub fn run(args: Args, progress: &CliProgress) -> Result<(), Failure> {
    if let Some(dir) = &args.collect {
        let table = study::collect(dir, progress).map_err(|e| Failure::Input(e.into()))?;
        return failed_trials(&table);
    }
    let Some(manifest) = &args.manifest else {
        return Err(Failure::Usage(anyhow::anyhow!(
            "give a MANIFEST or --collect DIR"
        )));
    };
    let manifest = manifest
        .canonicalize()
        .map_err(|e| Failure::Input(anyhow::anyhow!("manifest {}: {e}", manifest.display())))?;
    let settings = StudySettings {
        manifest,
        track: args.track,
        diagnose: args.diagnose,
        max_iter: args.max_iter,
        cutoff_hz: args.cutoff,
        level: args.level,
    };
    let out = absolute(&args.out);
    if args.slurm {
        return slurm(&args, &settings, &out, progress);
    }
    let req = StudyRequest {
        settings,
        out,
        jobs: args.jobs.map_or_else(cores, |j| j as usize),
        only_row: args.only_row.map(|r| r as usize),
    };
    let outcome = study::run(&req, progress).map_err(|e| Failure::Input(e.into()))?;
    progress.note(&format!(
        "{} trial(s) run, {} skipped (complete), {} failed; study folder: {}",
        outcome.ran,
        outcome.skipped,
        outcome.failed,
        req.out.display()
    ));
    if outcome.interrupted {
        return Err(Failure::Interrupted(anyhow::anyhow!(
            "interrupted: the trials done are in the table; run the same command again to run the others"
        )));
    }
    if outcome.failed > 0 && req.only_row.is_some() {
        return Err(Failure::Input(anyhow::anyhow!(
            "row {}: the trial failed; its error is in {}",
            args.only_row.unwrap_or(0),
            req.out.join("trials").display()
        )));
    }
    match &outcome.table {
        Some(t) => failed_trials(t),
        None => Ok(()),
    }
}

/// Exit 1 when a trial of the table has no results (the table is written all the same).
fn failed_trials(t: &study::StudyTable) -> Result<(), Failure> {
    let bad = t.trials.iter().filter(|e| e.error.is_some()).count();
    if bad == 0 {
        return Ok(());
    }
    Err(Failure::Input(anyhow::anyhow!(
        "{bad} of {} trial(s) have no results (see study.csv's error column); the others' are in the table",
        t.trials.len()
    )))
}

fn slurm(
    args: &Args,
    settings: &StudySettings,
    out: &Path,
    progress: &CliProgress,
) -> Result<(), Failure> {
    let exe = std::env::current_exe().map_err(|e| Failure::Input(e.into()))?;
    let (job, array, collect) = study::prepare_slurm(
        settings,
        out,
        &exe,
        args.cpus_per_task as usize,
        args.time.clone(),
        args.partition.clone(),
    )
    .map_err(|e| Failure::Input(e.into()))?;
    if args.dry_run {
        progress.result(&format!(
            "# {}\n{}\n# {} (submitted with --dependency=afterany:<array job>)\n{}",
            array.display(),
            study::slurm::array_script(&job),
            collect.display(),
            study::slurm::collect_script(&job)
        ));
        return Ok(());
    }
    let (a, c) = study::slurm::submit(&array, &collect).map_err(|e| Failure::Input(e.into()))?;
    progress.result(&format!(
        "submitted job array {a} ({} task(s)) and the collect job {c}; the table will be in {}",
        job.rows,
        out.display()
    ));
    Ok(())
}

fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
