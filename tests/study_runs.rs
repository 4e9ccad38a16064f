//! `footfall study`'s runs that take tens of seconds: on a real one-node Slurm
//! (tools/slurm-local starts munge, slurmctld and slurmd on this machine) the array's
//! per-trial results bit for bit the local run's; a study that tracks records each
//! trial's objective, iterations and status, and one that diagnoses what the diagnosis
//! suggests; a study killed during a trial, or stopped by Ctrl-C, finishes when run again
//! without redoing what was finished.

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
        diagnose: false,
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

/// A one-node cluster: its `SLURM_CONF`; stopped when dropped if this test started it.
struct LocalSlurm {
    conf: String,
    started: bool,
}

impl Drop for LocalSlurm {
    fn drop(&mut self) {
        if self.started {
            let _ = std::process::Command::new(root().join("tools/slurm-local"))
                .arg("stop")
                .output();
        }
    }
}

/// The one-node cluster, started if it is not running, or why it cannot start.
fn local_slurm() -> Result<LocalSlurm, String> {
    let o = std::process::Command::new(root().join("tools/slurm-local"))
        .arg("start")
        .output()
        .map_err(|e| e.to_string())?;
    let out = String::from_utf8_lossy(&o.stdout);
    match out.lines().find_map(|l| l.strip_prefix("SLURM_CONF=")) {
        Some(conf) if o.status.success() => Ok(LocalSlurm {
            conf: conf.to_string(),
            started: out.lines().any(|l| l == "started"),
        }),
        _ => Err(stderr(&o)),
    }
}

#[test]
fn a_study_run_as_a_slurm_array_gives_the_local_runs_results_bit_for_bit() {
    let slurm = match local_slurm() {
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
        .env("SLURM_CONF", &slurm.conf)
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
                    .env("SLURM_CONF", &slurm.conf)
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
    let m = two_walks(dir.path());
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

/// A manifest of subject 4's two untouched walks.
fn two_walks(dir: &Path) -> std::path::PathBuf {
    let r = root();
    crate::common::study::file(
        dir,
        "m.csv",
        &format!(
            "id,subject,session,data,model\nw1,s4,lab,{},{}\nw2,s4,lab,{},{}\n",
            r.join("data/opencap_s4_walking1_sagittal.csv").display(),
            r.join("models/opencap_s4.json").display(),
            r.join("data/opencap_s4_walking2_sagittal.csv").display(),
            r.join("models/opencap_s4.json").display(),
        ),
    )
}

#[test]
fn a_study_that_diagnoses_records_what_each_diagnosis_suggests() {
    let dir = tempfile::tempdir().unwrap();
    let m = two_walks(dir.path());
    let text = std::fs::read_to_string(&m).unwrap();
    std::fs::write(&m, text.lines().take(2).collect::<Vec<_>>().join("\n")).unwrap();
    let out = dir.path().join("out");
    let mut s = settings(&m, true);
    s.diagnose = true;
    let t = run_local(&s, &out);
    let e = &t.trials[0];
    assert_eq!(e.status, study::entry::Status::Done, "{:?}", e.error);
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("trials/w1/diagnose/diagnosis/summary.json")).unwrap(),
    )
    .unwrap();
    let d = e.diagnose.as_ref().expect("diagnosis");
    assert_eq!(Some(d.verdict.as_str()), summary["verdict"].as_str());
    assert_eq!(d.significant, summary["significant"].as_u64());
    let suggested: Vec<&str> = summary["add_effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap())
        .collect();
    assert_eq!(d.add_effects, suggested);
    let subject = t.pooled.iter().find(|g| g.name == "s4").unwrap();
    assert!(
        subject
            .statements
            .iter()
            .any(|l| l.starts_with("model stage: ")),
        "{:?}",
        subject.statements
    );
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    assert!(csv
        .lines()
        .next()
        .unwrap()
        .ends_with("diagnose_significant,diagnose_found,diagnose_add_effects"));
}

#[test]
fn a_study_killed_during_a_trial_resumes_without_redoing_the_finished_ones() {
    let dir = tempfile::tempdir().unwrap();
    let m = two_walks(dir.path());
    let out = dir.path().join("out");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_footfall"))
        .args([
            "--quiet",
            "study",
            m.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--track", "--max-iter", "3", "--jobs", "1"])
        .current_dir(root())
        .spawn()
        .unwrap();
    // killed (SIGKILL) once the first trial is done, while the second one works
    let done = out.join("trials/w1/track/summary.json");
    let start = Instant::now();
    while !done.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "w1 never finished"
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "the study ended before it was killed"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(300));
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!out.join("study.csv").exists(), "killed before its table");
    assert!(
        !out.join("trials/w2/track/summary.json").exists(),
        "w2 finished before the kill"
    );
    let w1 = crate::common::study::files(&out.join("trials/w1"));
    let progress = Collected::default();
    let req = StudyRequest {
        settings: StudySettings {
            max_iter: 3,
            ..settings(&m, true)
        },
        out: out.clone(),
        jobs: 1,
        only_row: None,
    };
    let outcome = study::run(&req, &progress).unwrap();
    let lines = progress.lines.into_inner().unwrap();
    assert_eq!(
        (outcome.ran, outcome.skipped, outcome.failed),
        (1, 1, 0),
        "{lines:?}"
    );
    assert!(
        lines.iter().any(|l| l.contains("w1: complete, skipped")),
        "{lines:?}"
    );
    assert_eq!(crate::common::study::files(&out.join("trials/w1")), w1);
    let t = outcome.table.unwrap();
    assert!(t
        .trials
        .iter()
        .all(|e| e.status == study::entry::Status::Done && e.track.is_some()));
    // nothing of the killed process is left beside the trials' folders
    let left: Vec<String> = std::fs::read_dir(out.join("trials/w2"))
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        left.iter().filter(|n| n.starts_with('.')).count(),
        0,
        "{left:?}"
    );
}

#[test]
fn a_study_interrupted_by_ctrl_c_keeps_no_stopped_track_and_finishes_when_run_again() {
    let dir = tempfile::tempdir().unwrap();
    let m = two_walks(dir.path());
    let out = dir.path().join("out");
    let args = [
        "study",
        m.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--track",
        "--max-iter",
        "3",
        "--jobs",
        "1",
    ];
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_footfall"))
        .args(args)
        .current_dir(root())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Ctrl-C once the first trial's track is being written
    let w1 = out.join("trials/w1");
    let start = Instant::now();
    let staging = || {
        std::fs::read_dir(&w1).ok().is_some_and(|d| {
            d.flatten().any(|e| {
                e.file_name()
                    .to_string_lossy()
                    .starts_with(".track.partial-")
            })
        })
    };
    while !staging() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no track started"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(500));
    let kill = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    assert!(
        !w1.join("track").exists(),
        "a stopped track was kept as the trial's"
    );
    assert!(
        !out.join("trials/w2").exists(),
        "a trial started after the interrupt"
    );
    // the same command again: w1's check is kept, its track and w2 run
    let o = crate::common::footfall(&args);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("w1: track:") && !err.contains("w1: check:"),
        "{err}"
    );
    assert!(err.contains("w2: check: nothing found; track:"), "{err}");
    assert!(!w1.join(study::trial::ERROR_FILE).exists());
}
