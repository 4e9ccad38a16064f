//! `footfall study`: the pooled statistics against values computed by hand, the
//! manifest's refusals, a study of edited and untouched real trials (the shared clock
//! edit found and pooled, nothing shared among the untouched, a corrupt trial reported
//! while the others complete), its resumption after a kill, the same results for any
//! `--jobs`, and the Slurm scripts run as a task would run them.

use crate::common::study::{file, study_manifest, trial_files};
use crate::common::{assert_exit, footfall, root, stderr};
use footfall::problems::distributions::chi2_upper;
use footfall::workflows::study::entry::Status;
use footfall::workflows::study::pool::{pool, Sample};
use footfall::workflows::study::table::StudyTable;
use footfall::workflows::study::{self, manifest, StudyRequest, StudySettings};
use footfall::workflows::Collected;
use std::path::Path;

#[test]
fn chi2_tail_matches_closed_forms_and_tables() {
    // k = 2: exp(−x/2); k = 4: exp(−x/2)(1 + x/2)
    for x in [0.1f64, 1.0, 3.0, 7.5, 20.0] {
        let p2 = (-0.5 * x).exp();
        assert!((chi2_upper(x, 2.0) - p2).abs() < 1e-12, "k 2, x {x}");
        let p4 = p2 * (1.0 + 0.5 * x);
        assert!((chi2_upper(x, 4.0) - p4).abs() < 1e-12, "k 4, x {x}");
    }
    // the tabulated 5 % points of χ²₁ and χ²₃
    assert!((chi2_upper(3.841_458_820_694_124, 1.0) - 0.05).abs() < 1e-9);
    assert!((chi2_upper(7.814_727_903_251_178, 3.0) - 0.05).abs() < 1e-9);
    assert_eq!(chi2_upper(0.0, 3.0), 1.0);
}

#[test]
fn readings_pool_as_computed_by_hand() {
    // 10 ± 1 and 13 ± 2 of the window's own noise, each with a shared spread of 3
    let s = |x: f64, within: f64| Sample {
        estimate: x,
        sd: within.hypot(3.0),
        sd_within: within,
        centre: 0.0,
    };
    let p = pool(&[s(10.0, 1.0), s(13.0, 2.0)]).unwrap();
    // w = 1, 1/4: mean (10 + 13/4)/(5/4) = 10.6; 1/Σw = 0.8; the shared 3 added once
    assert!((p.estimate - 10.6).abs() < 1e-12);
    assert!((p.sd_within - 0.8f64.sqrt()).abs() < 1e-12);
    assert!((p.sd - 9.8f64.sqrt()).abs() < 1e-12);
    assert!((p.z - 10.6 / 9.8f64.sqrt()).abs() < 1e-12);
    // Q = 1·0.6² + ¼·2.4² = 1.8 on 1 df; I² = 0.8/1.8; P(χ²₁ > 1.8) = erfc(√0.9)
    assert!((p.q - 1.8).abs() < 1e-12);
    assert_eq!((p.trials, p.df), (2, 1));
    assert!((p.i2 - 0.8 / 1.8).abs() < 1e-12);
    assert!((p.p_heterogeneity - 0.179_712_494_879).abs() < 1e-9);
    // three equal readings: Q 0, I² 0, p 1
    let same = pool(&[s(5.0, 1.0), s(5.0, 1.0), s(5.0, 1.0)]).unwrap();
    assert_eq!((same.q, same.i2), (0.0, 0.0));
    assert!((same.p_heterogeneity - 1.0).abs() < 1e-12);
    assert!((same.sd - (1.0f64 / 3.0 + 9.0).sqrt()).abs() < 1e-12);
    // a reading without a finite estimate is left out
    // judged from what untouched trials read: the same readings about a centre of 4
    let centred = |x: f64, within: f64| Sample {
        centre: 4.0,
        ..s(x, within)
    };
    let c = pool(&[centred(10.0, 1.0), centred(13.0, 2.0)]).unwrap();
    assert_eq!((c.estimate, c.sd, c.q), (p.estimate, p.sd, p.q));
    assert!((c.z - 6.6 / 9.8f64.sqrt()).abs() < 1e-12);
    let nan = Sample {
        estimate: f64::NAN,
        sd: 1.0,
        sd_within: 1.0,
        centre: 0.0,
    };
    let one = pool(&[s(2.0, 1.0), nan]).unwrap();
    assert_eq!(
        (one.trials, one.df, one.q, one.p_heterogeneity),
        (1, 0, 0.0, 1.0)
    );
    assert!(pool(&[nan]).is_none());
}

fn refused(text: &str, ext: &str, words: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let p = file(dir.path(), &format!("m.{ext}"), text);
    let e = manifest::read(&p).expect_err(text).to_string();
    assert!(e.contains(&p.display().to_string()), "{e}");
    for w in words {
        assert!(e.contains(w), "'{w}' not in: {e}");
    }
}

#[test]
fn a_bad_manifest_is_refused_naming_the_row_the_field_and_what_is_valid() {
    refused(
        "id,data,speed\na,x.csv,1\n",
        "csv",
        &["unknown field 'speed'", "belt_speed"],
    );
    refused("id,subject\na,s1\n", "csv", &["row 1", "'data'", "missing"]);
    refused(
        "id,data\na,x.csv\na,y.csv\n",
        "csv",
        &["rows 1 and 2", "'a'"],
    );
    refused(
        "id,data,belt_speed\na,x.csv,fast\n",
        "csv",
        &["row 1", "'belt_speed'", "'fast'", "positive"],
    );
    refused(
        "id,data\na,x.csv,extra\n",
        "csv",
        &["line 2", "3 cells", "2"],
    );
    refused(
        "id,data\n../up,x.csv\n",
        "csv",
        &["'id'", "'../up'", "folder name"],
    );
    refused(
        "id,data,overground\na,x.csv,maybe\n",
        "csv",
        &["'overground'", "true or false"],
    );
    refused(
        "id,data,plate\na,x.mot,x=1\n",
        "csv",
        &["'plate'", "r or l"],
    );
    refused("{\"trials\": 3}", "json", &["array of trials"]);
    refused(
        "[{\"data\": \"x.csv\", \"weight\": 3}]",
        "json",
        &["unknown field 'weight'"],
    );
    refused("id,data\n", "csv", &["no trials"]);
    refused("a", "txt", &[".csv or a .json"]);
}

#[test]
fn csv_and_json_manifests_read_the_same_rows_with_paths_beside_the_manifest() {
    let dir = tempfile::tempdir().unwrap();
    file(dir.path(), "t.csv", "");
    let csv = file(
        dir.path(),
        "m.csv",
        "# a comment\nid,subject,session,condition,data,plate,overground,cutoff\n\"a,1\",s1,lab,slow,t.csv,r=1_;l=2_,yes,8\nb,s1,lab,fast,other/t.csv,,,\n",
    );
    let json = file(
        dir.path(),
        "m.json",
        r#"{"trials": [{"id": "a,1", "subject": "s1", "session": "lab", "condition": "slow", "data": "t.csv", "plate": ["r=1_", "l=2_"], "overground": true, "cutoff": 8},
                     {"id": "b", "subject": "s1", "session": "lab", "condition": "fast", "data": "other/t.csv"}]}"#,
    );
    // "a,1" holds a comma, which no folder name may: refused in both forms
    assert!(manifest::read(&csv)
        .unwrap_err()
        .to_string()
        .contains("'a,1'"));
    assert!(manifest::read(&json)
        .unwrap_err()
        .to_string()
        .contains("'a,1'"));
    let csv_text = std::fs::read_to_string(&csv)
        .unwrap()
        .replace("\"a,1\"", "a1");
    let json_text = std::fs::read_to_string(&json).unwrap().replace("a,1", "a1");
    std::fs::write(&csv, csv_text).unwrap();
    std::fs::write(&json, json_text).unwrap();
    let (a, b) = (
        manifest::read(&csv).unwrap(),
        manifest::read(&json).unwrap(),
    );
    assert_eq!(a, b);
    assert_eq!(a[0].id, "a1");
    assert_eq!(
        a[0].files.data.as_deref(),
        Some(dir.path().join("t.csv").as_path())
    );
    assert_eq!(a[0].files.plates, ["r=1_", "l=2_"]);
    assert!(a[0].files.overground);
    assert_eq!(a[0].cutoff_hz, Some(8.0));
    // a path not beside the manifest is taken as given
    assert_eq!(a[1].files.data.as_deref(), Some(Path::new("other/t.csv")));
    assert_eq!((a[1].row, a[1].cutoff_hz), (2, None));
}

fn settings(manifest: &Path) -> StudySettings {
    StudySettings {
        manifest: manifest.to_path_buf(),
        track: false,
        diagnose: false,
        max_iter: 200,
        cutoff_hz: 6.0,
        level: 0.05,
    }
}

fn run(settings: &StudySettings, out: &Path, jobs: usize) -> (study::StudyOutcome, Vec<String>) {
    let req = StudyRequest {
        settings: settings.clone(),
        out: out.to_path_buf(),
        jobs,
        only_row: None,
    };
    let progress = Collected::default();
    let outcome = study::run(&req, &progress).expect("study");
    (outcome, progress.lines.into_inner().unwrap())
}

fn group<'a>(t: &'a StudyTable, name: &str) -> &'a study::findings::GroupFindings {
    t.pooled
        .iter()
        .find(|g| g.name == name)
        .unwrap_or_else(|| panic!("no group {name}"))
}

fn pooled(
    t: &StudyTable,
    group_name: &str,
    effect: &str,
) -> footfall::workflows::study::pool::Pooled {
    group(t, group_name)
        .readings
        .iter()
        .find(|r| r.effect == effect)
        .unwrap_or_else(|| panic!("{group_name}: no pooled {effect}"))
        .pooled
}

#[test]
fn a_clock_edit_shared_by_a_sessions_trials_is_found_in_each_and_pooled_and_untouched_trials_share_none(
) {
    let dir = tempfile::tempdir().unwrap();
    let m = study_manifest(dir.path());
    let s = settings(&m);
    let (outcome, lines) = run(&s, &dir.path().join("a"), 2);
    let t = outcome.table.expect("table");
    assert_eq!((outcome.ran, outcome.failed), (7, 1), "{lines:?}");
    // the damaged trial is reported, naming its file; the others complete
    let damaged = t.trials.iter().find(|e| e.id == "damaged").unwrap();
    assert_eq!(damaged.status, Status::Failed);
    assert!(
        damaged.error.as_deref().unwrap().contains("damaged.csv"),
        "{:?}",
        damaged.error
    );
    assert!(t
        .trials
        .iter()
        .filter(|e| e.id != "damaged")
        .all(|e| e.status == Status::Done));
    // lab-b: the right plate's clock, found by the check in every trial and pooled
    let b = group(&t, "lab-b");
    assert_eq!(
        b.shared.as_deref(),
        Some("clock_right"),
        "{:?}",
        b.statements
    );
    let r = b
        .readings
        .iter()
        .find(|r| r.effect == "clock_right")
        .unwrap();
    assert_eq!(r.found_in, ["w1-clock", "w2-clock"]);
    // read against the same recordings untouched (their own clock is not known)
    let edited = pooled(&t, "lab-b", "clock_right");
    let untouched = pooled(&t, "lab-a", "clock_right");
    let read = edited.estimate - untouched.estimate;
    assert!(
        (read - 0.02).abs() <= (0.2 * 0.02f64).max(2.0 * edited.sd),
        "pooled {read} ± {} against the untouched session, edit 0.02",
        edited.sd
    );
    // the checks' joint readings, pooled: the same edit against the same untouched pool
    let joint = r.joint.expect("both checks found the right clock alone");
    let read = joint.estimate - untouched.estimate;
    assert!(
        (read - 0.02).abs() <= (0.2 * 0.02f64).max(2.0 * joint.sd),
        "joint pooled {read} ± {} against the untouched session, edit 0.02",
        joint.sd
    );
    // lab-a, two untouched recordings: no shared instrument effect, none beyond its band
    let a = group(&t, "lab-a");
    assert_eq!(a.shared, None, "{:?}", a.statements);
    assert!(a.readings.iter().all(|r| !r.beyond), "{:?}", a.readings);
    assert_eq!(a.readings.len(), 7);
    // each pooled reading judged, as the check judges each trial's, from the band's centre
    let band = &footfall::problems::check::NULL;
    for r in &a.readings {
        let p = footfall::problems::check::Param::from_name(&r.effect).unwrap();
        assert_eq!(r.pooled.centre, band[p.index()].mean, "{}", r.effect);
        assert_eq!(
            r.pooled.z,
            (r.pooled.estimate - r.pooled.centre) / r.pooled.sd
        );
    }
    // one trial of a session pools nothing
    assert!(group(&t, "lab-d").readings.is_empty());
    // the files agree with the table
    let csv = std::fs::read_to_string(dir.path().join("a/study.csv")).unwrap();
    assert_eq!(csv.lines().count(), 8);
    assert!(csv
        .lines()
        .nth(7)
        .unwrap()
        .starts_with("7,damaged,subject01,lab-c,damaged,"));
    let html = std::fs::read_to_string(dir.path().join("a/report.html")).unwrap();
    assert!(
        html.contains("session lab-b: instruments") && html.contains("shared instrument effect")
    );
    // each pooled reading with the smallest pooled effect that would be beyond its band
    let least = a.readings[0].pooled.sd * t.threshold.expect("a threshold");
    assert!(
        html.contains("beyond its band from") && html.contains(&format!("±{:.2} ms", 1e3 * least)),
        "{least}"
    );
    // the shared effect's chart: one bar per trial of the session, the pooled value drawn
    assert_eq!(
        html.matches("<svg").count(),
        1,
        "one shared effect, one chart"
    );
    assert!(html.contains("right plate&#39;s clock: each trial read alone"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("a/study.json")).unwrap())
            .unwrap();
    assert_eq!(json["trials"].as_array().unwrap().len(), 7);

    // one trial at a time: the same trial folders and table, byte for byte
    let (one, _) = run(&s, &dir.path().join("b"), 1);
    assert_eq!(one.table.as_ref(), Some(&t));
    assert_eq!(
        trial_files(&dir.path().join("a")),
        trial_files(&dir.path().join("b"))
    );
    assert_eq!(
        csv,
        std::fs::read_to_string(dir.path().join("b/study.csv")).unwrap()
    );
}

#[test]
fn a_finding_of_one_trial_that_the_others_do_not_share_is_said_to_hold_in_it_alone() {
    // one session: one walk with the right plate's clock 20 ms late, the other untouched
    let dir = tempfile::tempdir().unwrap();
    let r = root();
    let m = file(
        dir.path(),
        "m.csv",
        &format!(
            "id,subject,session,data,model\nw1-late,s4,lab,{},{}\nw2,s4,lab,{},{}\n",
            r.join("tests/data/check/trials/opencap_s4_walking1/clock_r+20ms/trial.csv")
                .display(),
            r.join("models/opencap_s4.json").display(),
            r.join("data/opencap_s4_walking2_sagittal.csv").display(),
            r.join("models/opencap_s4.json").display(),
        ),
    );
    let (outcome, _) = run(&settings(&m), &dir.path().join("out"), 2);
    let t = outcome.table.unwrap();
    let g = group(&t, "lab");
    let clock = g
        .readings
        .iter()
        .find(|r| r.effect == "clock_right")
        .unwrap();
    assert_eq!(clock.found_in, ["w1-late"]);
    // 20 ms apart on noise of a few ms: Cochran's Q rejects one shared value
    assert!(clock.pooled.p_heterogeneity < 0.05, "{:?}", clock.pooled);
    assert_eq!(g.shared, None, "{:?}", g.statements);
    let said = g.statements.join("\n");
    assert!(
        said.contains("right plate's clock: found in w1-late only (1 of 2), not in w2"),
        "{said}"
    );
    if clock.beyond {
        assert!(said.contains("the trials disagree"), "{said}");
    }
}

#[test]
fn a_killed_study_resumes_without_redoing_finished_trials() {
    let dir = tempfile::tempdir().unwrap();
    let m = study_manifest(dir.path());
    let s = settings(&m);
    let out = dir.path().join("study");
    run(&s, &out, 2);
    let before = trial_files(&out);
    // as a kill during w2's check leaves it: no committed folder, a staging folder of a
    // process that is gone
    let w2 = out.join("trials/w2");
    std::fs::remove_dir_all(w2.join("check")).unwrap();
    let dead = w2.join(".check.partial-4000000");
    std::fs::create_dir_all(&dead).unwrap();
    std::fs::write(
        dead.join(".footfall-run"),
        "This folder was written by footfall\n",
    )
    .unwrap();
    std::fs::write(dead.join("summary.json"), "{\"half").unwrap();
    let (outcome, lines) = run(&s, &out, 2);
    // w2 run again, the damaged trial tried again, the five others skipped
    assert_eq!(
        (outcome.ran, outcome.skipped, outcome.failed),
        (2, 5, 1),
        "{lines:?}"
    );
    assert!(
        lines.iter().any(|l| l.contains("w2: check: nothing found")),
        "{lines:?}"
    );
    assert!(!dead.exists(), "the dead process's staging folder is left");
    assert_eq!(trial_files(&out), before);
    // an edited row (another cutoff for w1) redoes that trial alone
    let text = std::fs::read_to_string(&m).unwrap();
    let text = text.replacen(
        "id,subject,session,condition,data,model\n",
        "id,subject,session,condition,data,model,cutoff\n",
        1,
    );
    let text: String = text
        .lines()
        .map(|l| {
            if l.starts_with("w1,") {
                format!("{l},8\n")
            } else if l.starts_with("id,") {
                format!("{l}\n")
            } else {
                format!("{l},\n")
            }
        })
        .collect();
    std::fs::write(&m, text).unwrap();
    let (outcome, lines) = run(&s, &out, 2);
    assert_eq!((outcome.ran, outcome.skipped), (2, 5), "{lines:?}");
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("[") && l.contains("w1: check")),
        "{lines:?}"
    );
    // a row that now names a missing file: its old folder is not taken for its results
    let text: String = std::fs::read_to_string(&m)
        .unwrap()
        .lines()
        .map(|l| {
            let mut cells: Vec<&str> = l.split(',').collect();
            if cells[0] == "w2" {
                cells[4] = "/nonexistent/w2.csv";
            }
            cells.join(",") + "\n"
        })
        .collect();
    std::fs::write(&m, text).unwrap();
    let (outcome, _) = run(&s, &out, 2);
    let t = outcome.table.unwrap();
    let w2 = t.trials.iter().find(|e| e.id == "w2").unwrap();
    assert_eq!(w2.status, Status::Failed);
    let error = w2.error.as_deref().unwrap();
    assert!(error.contains("/nonexistent/w2.csv"), "{error}");
    assert!(w2.check.is_none(), "the old check of w2 is in the table");
    assert!(
        out.join("trials/w2/check/summary.json").exists(),
        "the old folder was removed"
    );
    assert_eq!(group(&t, "lab-a").trials, ["w1"]);
}

#[test]
fn the_command_line_runs_a_study_reports_a_bad_trial_and_refuses_a_foreign_folder() {
    let dir = tempfile::tempdir().unwrap();
    let m = study_manifest(dir.path());
    let out = dir.path().join("out");
    let o = footfall(&[
        "study",
        m.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--jobs",
        "2",
    ]);
    // progress on standard error, one line a trial, then the one error
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("[7/7]") && !err.contains("panicked"), "{err}");
    let last = err.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("error: 1 of 7 trial(s) have no results"),
        "{err}"
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("damaged (failed): check:") && stdout.contains("damaged.csv"),
        "{stdout}"
    );
    assert!(
        stdout
            .contains("session lab-b: instruments: shared instrument effect: right plate's clock"),
        "{stdout}"
    );
    // a folder of the user's is left alone
    let mine = dir.path().join("mine");
    std::fs::create_dir_all(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "keep").unwrap();
    let o = footfall(&[
        "study",
        m.to_str().unwrap(),
        "--out",
        mine.to_str().unwrap(),
    ]);
    assert_exit(&o, 1, &["not a footfall study folder"]);
    assert_eq!(
        std::fs::read_to_string(mine.join("notes.txt")).unwrap(),
        "keep"
    );
    // --collect of a folder that is no study
    let o = footfall(&["study", "--collect", mine.to_str().unwrap()]);
    assert_exit(&o, 1, &["is not a study folder", "study-settings.json"]);
    // --only-row outside the manifest
    let o = footfall(&[
        "study",
        m.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--only-row",
        "8",
    ]);
    assert_exit(&o, 1, &["--only-row 8", "rows 1 to 7"]);
}

#[test]
fn the_slurm_array_script_run_as_its_tasks_gives_the_local_study_and_collect_gathers_it() {
    let dir = tempfile::tempdir().unwrap();
    let m = study_manifest(dir.path());
    let local = dir.path().join("local");
    let array = dir.path().join("array");
    run(&settings(&m), &local, 2);
    let o = footfall(&[
        "study",
        m.to_str().unwrap(),
        "--out",
        array.to_str().unwrap(),
        "--slurm",
        "--dry-run",
        "--time",
        "00:10:00",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let printed = String::from_utf8_lossy(&o.stdout);
    let script = std::fs::read_to_string(array.join("slurm/array.sbatch")).unwrap();
    let collect = std::fs::read_to_string(array.join("slurm/collect.sbatch")).unwrap();
    assert!(
        printed.contains(&script) && printed.contains(&collect),
        "{printed}"
    );
    for line in [
        "#SBATCH --array=1-7",
        "#SBATCH --cpus-per-task=1",
        "#SBATCH --time=00:10:00",
        "--only-row \"$SLURM_ARRAY_TASK_ID\"",
    ] {
        assert!(script.contains(line), "'{line}' not in:\n{script}");
    }
    assert!(
        script.contains(&format!("'{}'", m.canonicalize().unwrap().display())),
        "{script}"
    );
    assert!(
        collect.contains(&format!("study --collect '{}'", array.display())),
        "{collect}"
    );
    assert!(!array.join("study.csv").exists(), "a dry run ran trials");
    // each task as Slurm would start it, in reverse order
    for task in (1..=7).rev() {
        let o = std::process::Command::new("sh")
            .arg(array.join("slurm/array.sbatch"))
            .env("SLURM_ARRAY_TASK_ID", task.to_string())
            .current_dir(root())
            .output()
            .unwrap();
        assert_eq!(o.status.success(), task != 7, "task {task}: {}", stderr(&o));
        assert!(!array.join("study.csv").exists(), "a task wrote the table");
    }
    let o = std::process::Command::new("sh")
        .arg(array.join("slurm/collect.sbatch"))
        .current_dir(root())
        .output()
        .unwrap();
    assert_exit(&o, 1, &["1 of 7 trial(s) have no results"]);
    assert_eq!(trial_files(&local), trial_files(&array));
    for f in ["study.csv", "study.json"] {
        assert_eq!(
            std::fs::read(local.join(f)).unwrap(),
            std::fs::read(array.join(f)).unwrap(),
            "{f}"
        );
    }
}
