//! `footfall study` on a real one-node Slurm (tools/slurm-local starts munge, slurmctld
//! and slurmd on this machine): the array's per-trial results bit for bit the local
//! run's; and a study that tracks records each trial's objective, iterations and status.

use crate::common::study::{study_manifest, trial_files};
use crate::common::{root, stderr};
use footfall::workflows::study::{self, StudyRequest, StudySettings};
use footfall::workflows::Collected;
use std::path::Path;
use std::time::{Duration, Instant};

fn settings(manifest: &Path, track: bool) -> StudySettings {
    StudySettings {
        manifest: manifest.canonicalize().unwrap(),
        track,
        max_iter: 1,
        cutoff_hz: 6.0,
        level: 0.05,
    }
}

fn run_local(s: &StudySettings, out: &Path) -> study::StudyTable {
    let req = StudyRequest {
        settings: s.clone(),
        out: out.to_path_buf(),
        jobs: 2,
        only_row: None,
    };
    study::run(&req, &Collected::default())
        .expect("study")
        .table
        .expect("table")
}

/// The one-node cluster's `SLURM_CONF`, or why it cannot start.
fn local_slurm() -> Result<String, String> {
    let o = std::process::Command::new(root().join("tools/slurm-local"))
        .arg("start")
        .output()
        .map_err(|e| e.to_string())?;
    let out = String::from_utf8_lossy(&o.stdout);
    match out.lines().find_map(|l| l.strip_prefix("SLURM_CONF=")) {
        Some(conf) if o.status.success() => Ok(conf.to_string()),
        _ => Err(stderr(&o)),
    }
}

#[test]
fn a_study_run_as_a_slurm_array_gives_the_local_runs_results_bit_for_bit() {
    let conf = match local_slurm() {
        Ok(c) => c,
        Err(why) => {
            eprintln!(
                "skipped: a one-node Slurm cannot start here (tools/slurm-local start: {})",
                why.trim()
            );
            return;
        }
    };
    let dir = tempfile::tempdir().unwrap();
    let m = study_manifest(dir.path());
    let local = dir.path().join("local");
    let array = dir.path().join("array");
    run_local(&settings(&m, false), &local);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_footfall"))
        .args([
            "study",
            m.to_str().unwrap(),
            "--out",
            array.to_str().unwrap(),
            "--slurm",
        ])
        .env("SLURM_CONF", &conf)
        .current_dir(root())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("submitted job array"));
    // the collect job writes the table once the array has ended
    let start = Instant::now();
    while !array.join("report.html").exists() {
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "no table after 300 s; squeue: {}",
            String::from_utf8_lossy(
                &std::process::Command::new("squeue")
                    .env("SLURM_CONF", &conf)
                    .output()
                    .unwrap()
                    .stdout
            )
        );
        std::thread::sleep(Duration::from_millis(500));
    }
    std::thread::sleep(Duration::from_millis(200));
    assert_eq!(trial_files(&local), trial_files(&array));
    for f in ["study.csv", "study.json"] {
        assert_eq!(
            std::fs::read(local.join(f)).unwrap(),
            std::fs::read(array.join(f)).unwrap(),
            "{f}"
        );
    }
    let log = std::fs::read_to_string(array.join("slurm/collect.out")).unwrap();
    assert!(log.contains("1 of 7 trial(s) have no results"), "{log}");
}

#[test]
fn a_study_that_tracks_records_each_trials_objective_iterations_and_status() {
    let dir = tempfile::tempdir().unwrap();
    let r = root();
    let m = crate::common::study::file(
        dir.path(),
        "m.csv",
        &format!(
            "id,subject,session,data,model\nw1,s4,lab,{},{}\nw2,s4,lab,{},{}\n",
            r.join("data/opencap_s4_walking1_sagittal.csv").display(),
            r.join("models/opencap_s4.json").display(),
            r.join("data/opencap_s4_walking2_sagittal.csv").display(),
            r.join("models/opencap_s4.json").display(),
        ),
    );
    let out = dir.path().join("out");
    let t = run_local(&settings(&m, true), &out);
    for e in &t.trials {
        let summary: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join("trials").join(&e.id).join("track/summary.json"))
                .unwrap(),
        )
        .unwrap();
        let tr = e.track.as_ref().expect("track");
        assert_eq!(tr.iterations, Some(1), "{}", e.id);
        assert_eq!(tr.status, "max_iterations");
        assert_eq!(tr.objective, summary["objective"].as_f64());
        assert!(tr.objective.unwrap() > 0.0);
    }
    // asked again with the check's folders in place: only what is missing runs
    std::fs::remove_dir_all(out.join("trials/w2/track")).unwrap();
    let progress = Collected::default();
    let req = StudyRequest {
        settings: settings(&m, true),
        out: out.clone(),
        jobs: 1,
        only_row: None,
    };
    let outcome = study::run(&req, &progress).unwrap();
    assert_eq!((outcome.ran, outcome.skipped), (1, 1));
    let lines = progress.lines.into_inner().unwrap();
    assert!(
        lines
            .iter()
            .any(|l| l.contains("w2: track:") && !l.contains("check:")),
        "{lines:?}"
    );
}
