//! A study as a Slurm job array: one task per manifest row, each the same `footfall
//! study … --only-row N` on its row (`$SLURM_ARRAY_TASK_ID`), then one job, run once the
//! array has ended (`afterany`), that builds the table with `footfall study --collect`.

use super::StudyError;
use std::path::{Path, PathBuf};

/// What the scripts run.
#[derive(Debug, Clone)]
pub struct SlurmJob {
    /// The footfall executable (absolute).
    pub exe: PathBuf,
    /// The study folder (absolute).
    pub out: PathBuf,
    /// Manifest rows (array indices 1 … rows).
    pub rows: usize,
    /// The arguments of `footfall study` every task repeats (the manifest first).
    pub args: Vec<String>,
    /// CPUs per task (a check uses one; a track the cores it is given).
    pub cpus_per_task: usize,
    /// Wall-time limit per task (`--time`, e.g. `00:10:00`).
    pub time: Option<String>,
    /// Partition.
    pub partition: Option<String>,
}

/// `'text'` for a POSIX shell.
pub fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

fn header(job: &SlurmJob, name: &str, log: &str) -> String {
    let mut s = format!("#!/bin/sh\n#SBATCH --job-name={name}\n");
    s.push_str(&format!(
        "#SBATCH --output={}\n",
        quote_sbatch(&job.out.join("slurm").join(log))
    ));
    if let Some(t) = &job.time {
        s.push_str(&format!("#SBATCH --time={t}\n"));
    }
    if let Some(p) = &job.partition {
        s.push_str(&format!("#SBATCH --partition={p}\n"));
    }
    s
}

/// An `#SBATCH` path (no shell there: written as it is; a space would end it, so the
/// study folder must have none).
fn quote_sbatch(p: &Path) -> String {
    p.display().to_string()
}

/// The array script: one task per row.
pub fn array_script(job: &SlurmJob) -> String {
    let mut s = header(job, "footfall-study", "trial-%a.out");
    s.push_str(&format!("#SBATCH --array=1-{}\n", job.rows));
    s.push_str(&format!("#SBATCH --cpus-per-task={}\n", job.cpus_per_task));
    s.push_str("#SBATCH --ntasks=1\n\n");
    let args: Vec<String> = job.args.iter().map(|a| quote(a)).collect();
    s.push_str(&format!(
        "exec {} --quiet study {} --out {} --only-row \"$SLURM_ARRAY_TASK_ID\"\n",
        quote(&job.exe.display().to_string()),
        args.join(" "),
        quote(&job.out.display().to_string())
    ));
    s
}

/// The script that gathers the table once the array has ended.
pub fn collect_script(job: &SlurmJob) -> String {
    let mut s = header(job, "footfall-study-collect", "collect.out");
    s.push_str("#SBATCH --ntasks=1\n\n");
    s.push_str(&format!(
        "exec {} study --collect {}\n",
        quote(&job.exe.display().to_string()),
        quote(&job.out.display().to_string())
    ));
    s
}

/// Write both scripts into `DIR/slurm/`; their paths.
pub fn write_scripts(job: &SlurmJob) -> Result<(PathBuf, PathBuf), StudyError> {
    let dir = job.out.join("slurm");
    if job.out.display().to_string().contains(char::is_whitespace) {
        return Err(StudyError::file(
            &job.out,
            "a Slurm study folder's path may hold no spaces (sbatch's --output takes it as it is): choose another --out",
        ));
    }
    std::fs::create_dir_all(&dir).map_err(|e| StudyError::file(&dir, e))?;
    let mut paths = Vec::new();
    for (name, text) in [
        ("array.sbatch", array_script(job)),
        ("collect.sbatch", collect_script(job)),
    ] {
        crate::runfolder::write_atomic(&dir, name, text.as_bytes())
            .map_err(|e| StudyError::file(&dir.join(name), e))?;
        paths.push(dir.join(name));
    }
    Ok((paths[0].clone(), paths[1].clone()))
}

/// Why a submission failed.
#[derive(Debug, thiserror::Error)]
pub enum SubmitError {
    /// `sbatch` could not be started.
    #[error("sbatch could not be started ({0}): is Slurm installed here? `--dry-run` prints the scripts instead")]
    Spawn(std::io::Error),
    /// `sbatch` refused the script.
    #[error("sbatch {script} refused it: {stderr}")]
    Refused {
        /// The script.
        script: PathBuf,
        /// What sbatch said.
        stderr: String,
    },
}

/// Submit `script` with `sbatch --parsable` and extra options; the job id.
pub fn sbatch(script: &Path, extra: &[String]) -> Result<String, SubmitError> {
    let out = std::process::Command::new("sbatch")
        .arg("--parsable")
        .args(extra)
        .arg(script)
        .output()
        .map_err(SubmitError::Spawn)?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let id = stdout.trim().split(';').next().unwrap_or("").to_string();
    if !out.status.success() || id.is_empty() {
        return Err(SubmitError::Refused {
            script: script.to_path_buf(),
            stderr: String::from_utf8_lossy(&out.stderr).trim().to_string(),
        });
    }
    Ok(id)
}

/// Submit the array, then the collect job after it; both job ids.
pub fn submit(array: &Path, collect: &Path) -> Result<(String, String), SubmitError> {
    let id = sbatch(array, &[])?;
    let after = sbatch(collect, &[format!("--dependency=afterany:{id}")])?;
    Ok((id, after))
}
