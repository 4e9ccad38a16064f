//! Never lose a user's files, leave nothing half-written, and continue a killed run:
//! `--overwrite` replaces only footfall's own run folders holding nothing else; a run
//! whose output folder appeared meanwhile goes beside it; staging folders of dead
//! processes are cleaned up; Ctrl-C during setup or a solve exits 130 with nothing
//! half-written, within two seconds even inside a long iteration; a solve killed with
//! SIGKILL or interrupted resumes (`--resume`) to the same optimum, following the same
//! iterates bit for bit.

use crate::common;
use common::stderr;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_footfall"))
}

fn r(p: &str) -> String {
    root().join(p).to_string_lossy().into_owned()
}

/// `footfall simulate` of the bundled step with every input given by absolute path, so it
/// runs from any folder.
fn simulate(cwd: &Path, out: &str, extra: &[&str]) -> Output {
    bin()
        .args([
            "--quiet",
            "simulate",
            "--phase-set",
            &r("phases/sim_ellipse_step.json"),
            "--model",
            &r("models/opensim_subject01.json"),
        ])
        .args(["--foot", &r("models/feet/ellipse.json"), "--out", out])
        .args(extra)
        .current_dir(cwd)
        .output()
        .expect("run footfall")
}

/// Everything in `dir`, hidden entries included, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("read dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn refused(o: &Output, names: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "expected exit code 1: {err}");
    assert!(
        err.starts_with("error: ") && !err.contains("panicked"),
        "{err}"
    );
    for n in names {
        assert!(err.contains(n), "stderr does not name {n:?}: {err}");
    }
}

#[test]
fn overwrite_refuses_a_foreign_folder_the_current_folder_and_a_file() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    // a folder of the user's own
    std::fs::create_dir(t.join("mine")).unwrap();
    std::fs::write(t.join("mine/precious.txt"), "precious").unwrap();
    refused(
        &simulate(t, "mine", &["--overwrite"]),
        &["mine", "was not written by footfall", "'precious.txt'"],
    );
    assert_eq!(
        std::fs::read_to_string(t.join("mine/precious.txt")).unwrap(),
        "precious"
    );
    assert_eq!(entries(t), ["mine"], "something was left behind");

    // the current folder, even one footfall wrote, and its parent
    let o = simulate(t, "run", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let run = t.join("run");
    for out in [".", "..", "./"] {
        refused(&simulate(&run, out, &["--overwrite"]), &["current folder"]);
    }
    refused(
        &simulate(&t.join("mine"), ".", &["--overwrite"]),
        &["current folder"],
    );
    assert_eq!(
        entries(&run),
        [".footfall-run", "summary.json", "timeseries.csv"]
    );
    assert_eq!(entries(&t.join("mine")), ["precious.txt"]);

    // a file
    std::fs::write(t.join("notes.txt"), "notes").unwrap();
    refused(
        &simulate(t, "notes.txt", &["--overwrite"]),
        &["notes.txt", "is not a folder"],
    );
    assert_eq!(
        std::fs::read_to_string(t.join("notes.txt")).unwrap(),
        "notes"
    );

    // footfall's own folder is replaced, and a file added to it since is refused
    let before = std::fs::read(run.join("summary.json")).unwrap();
    let o = simulate(t, "run", &["--overwrite", "--dt", "0.002"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(
        std::fs::read(run.join("summary.json")).unwrap(),
        before,
        "not replaced"
    );
    assert_eq!(entries(t), ["mine", "notes.txt", "run"]);
}

#[test]
fn overwrite_refuses_a_run_folder_holding_a_users_file_and_deletes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let o = simulate(t, "run", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let run = t.join("run");
    let before = std::fs::read(run.join("summary.json")).unwrap();
    std::fs::write(run.join("notes.txt"), "mine").unwrap();
    refused(
        &simulate(t, "run", &["--overwrite", "--dt", "0.002"]),
        &[
            "run",
            "footfall did not write",
            "'notes.txt'",
            "nothing was replaced",
        ],
    );
    assert_eq!(
        std::fs::read_to_string(run.join("notes.txt")).unwrap(),
        "mine"
    );
    assert_eq!(std::fs::read(run.join("summary.json")).unwrap(), before);
    assert_eq!(
        entries(&run),
        [
            ".footfall-run",
            "notes.txt",
            "summary.json",
            "timeseries.csv"
        ]
    );
    assert_eq!(entries(t), ["run"], "something was left behind");
    // moved out, the run folder is footfall's alone and replaced
    std::fs::remove_file(run.join("notes.txt")).unwrap();
    let o = simulate(t, "run", &["--overwrite", "--dt", "0.002"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(std::fs::read(run.join("summary.json")).unwrap(), before);
}

#[test]
fn a_solve_whose_output_folder_appeared_meanwhile_keeps_its_results_beside_it() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    // a start for `--init`
    let first = t.join("first");
    let o = bin()
        .args(["--quiet", "track", "--max-iter", "0", "--out"])
        .arg(&first)
        .current_dir(root())
        .output()
        .expect("run footfall");
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    // the run reads --init from a FIFO after making its staging folder: it is held there
    // while the output folder appears
    let fifo = t.join("init.json");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo")
        .success());
    let out = t.join("run");
    let child = bin()
        .args(["track", "--max-iter", "0", "--init"])
        .arg(&fifo)
        .arg("--out")
        .arg(&out)
        .current_dir(root())
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .expect("spawn");
    let staging = t.join(format!(".run.partial-{}", child.id()));
    let start = Instant::now();
    while !staging.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no staging folder"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("theirs.txt"), "theirs").unwrap();
    std::fs::write(&fifo, std::fs::read(first.join("solution.json")).unwrap()).unwrap();
    let o = child.wait_with_output().expect("wait");
    let err = stderr(&o);
    // the exit code of the run itself: the iteration limit
    assert_eq!(o.status.code(), Some(3), "{err}");
    let sibling = t.join("run-2");
    assert!(
        err.contains(&format!(
            "the output folder {} appeared while this run was working",
            out.display()
        )) && err.contains(&format!("the results are in {}", sibling.display())),
        "{err}"
    );
    assert!(
        err.contains(&format!("results written to {}", sibling.display())),
        "{err}"
    );
    assert_eq!(entries(&out), ["theirs.txt"]);
    assert!(sibling.join("summary.json").is_file() && sibling.join(".footfall-run").is_file());
    assert_eq!(entries(t), ["first", "init.json", "run", "run-2"]);
}

/// The status column of a run's CSV file: the header's second name and every row's value.
fn status_column(csv: &Path) -> (String, Vec<String>) {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let values = lines
        .map(|l| l.split(',').nth(1).unwrap_or_default().to_string())
        .collect();
    (header[1].to_string(), values)
}

#[test]
fn an_unconverged_runs_files_say_so() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    let o = bin()
        .args(["--quiet", "track", "--max-iter", "0", "--out"])
        .arg(&run)
        .current_dir(root())
        .output()
        .expect("run footfall");
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    for csv in ["tracking.csv", "fine_grid.csv"] {
        let (name, values) = status_column(&run.join(csv));
        assert_eq!(name, "status", "{csv}");
        assert!(
            values.len() > 10 && values.iter().all(|v| v == "not converged"),
            "{csv}: {values:?}"
        );
    }
    let first_line = |f: &str| {
        std::fs::read_to_string(run.join(f))
            .unwrap()
            .lines()
            .next()
            .unwrap()
            .to_string()
    };
    for f in ["table3.md", "kinematics.sto", "film_strip.svg"] {
        let line = first_line(f);
        // "not converged" or "not converged, physically invalid"
        assert!(
            line.contains("not converged")
                && line.contains("(iteration limit reached): the last iterate, not a solution"),
            "{f}: {line}"
        );
    }
    assert!(first_line("film_strip.svg").starts_with("<!-- "));
    // footfall's own reader of the files takes the column: the runs side by side
    let side = tmp.path().join("side");
    let o = bin()
        .args(["--quiet", "report"])
        .args([&run, &run])
        .arg("--out")
        .arg(&side)
        .current_dir(root())
        .output()
        .expect("run footfall");
    assert!(o.status.success(), "{}", stderr(&o));
    let html = std::fs::read_to_string(side.join("report.html")).unwrap();
    assert!(
        html.contains("run (not converged"),
        "the curves are not marked"
    );
    // a generic solve's table too
    let o = bin()
        .args(["--quiet", "solve", "--max-iter", "1", "--problem"])
        .arg(r("problems/cartpole_swingup.json"))
        .arg("--out")
        .arg(tmp.path().join("solve"))
        .output()
        .expect("run footfall");
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let (name, values) = status_column(&tmp.path().join("solve/solution.csv"));
    assert_eq!(name, "status");
    assert!(!values.is_empty() && values.iter().all(|v| v == "not converged"));
}

#[test]
fn stale_staging_folders_of_dead_processes_are_cleaned_up() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    // PIDs above the kernel's limit (4194304) belong to no process
    let dead = t.join(".run.partial-4194399");
    let dead_old = t.join(".run.old-4194398");
    let not_ours = t.join(".run.partial-4194397");
    for d in [&dead, &dead_old, &not_ours] {
        std::fs::create_dir(d).unwrap();
    }
    std::fs::write(dead.join(".footfall-run"), "x").unwrap();
    std::fs::write(dead.join("summary.json"), "{}").unwrap();
    std::fs::write(dead_old.join(".footfall-run"), "x").unwrap();
    std::fs::write(not_ours.join("mine.txt"), "mine").unwrap();
    let o = simulate(t, "run", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    // footfall's stale folders are gone; a folder without its marker is never touched
    assert_eq!(entries(t), [".run.partial-4194397", "run"]);
    assert_eq!(entries(&not_ours), ["mine.txt"]);
}

/// Wait (up to `limit`) for a line on the child's stderr containing `needle`.
fn wait_for_line(child: &mut Child, needle: impl Fn(&str) -> bool, limit: Duration) -> Vec<String> {
    let err = child.stderr.take().expect("piped stderr");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        // read to the end, so the child never writes into a closed pipe
        for line in BufReader::new(err).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    let start = Instant::now();
    let mut seen = Vec::new();
    while start.elapsed() < limit {
        match rx.recv_timeout(Duration::from_millis(50)) {
            Ok(line) => {
                let hit = needle(&line);
                seen.push(line);
                if hit {
                    return seen;
                }
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
            Err(_) => break,
        }
    }
    panic!("no such line within {limit:?}: {seen:?}");
}

fn signal(child: &Child, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .expect("run kill")
        .success();
    assert!(ok, "kill {sig} failed");
}

fn wait_with_limit(child: &mut Child, limit: Duration) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(s) = child.try_wait().expect("wait") {
            return s;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("footfall did not exit within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn ctrl_c_during_setup_exits_130_and_leaves_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    // `predict` makes its staging folder first, then reads --init: from a FIFO nobody
    // writes, so the process is held in its setup when the Ctrl-C comes
    let fifo = t.join("init.json");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo")
        .success());
    let out = t.join("pred");
    let mut child = bin()
        .args([
            "predict",
            "--init",
            fifo.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .current_dir(root())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let staging = t.join(format!(".pred.partial-{}", child.id()));
    let start = Instant::now();
    while !staging.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the staging folder never appeared"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    signal(&child, "-INT");
    let status = wait_with_limit(&mut child, Duration::from_secs(30));
    assert_eq!(status.code(), Some(130), "{status:?}");
    assert_eq!(entries(t), ["init.json"], "something was left behind");
}

#[test]
fn ctrl_c_twice_during_a_solve_exits_130_and_leaves_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let mut child = bin()
        .args([
            "solve",
            "--problem",
            &r("problems/five_link_biped.json"),
            "--hessian",
            "bfgs",
            "--max-iter",
            "500",
            "--out",
            "run",
        ])
        .current_dir(t)
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    // the log line of iteration 2
    let lines = wait_for_line(
        &mut child,
        |l| l.trim_start().starts_with("2 "),
        Duration::from_secs(120),
    );
    signal(&child, "-INT");
    std::thread::sleep(Duration::from_millis(5));
    signal(&child, "-INT");
    let status = wait_with_limit(&mut child, Duration::from_secs(60));
    assert_eq!(status.code(), Some(130), "{status:?} after {lines:?}");
    // either the second Ctrl-C came before the first stopped the solve (nothing written)
    // or after (the interrupted run written whole); never a staging folder
    let left = entries(t);
    assert!(left.is_empty() || left == ["run"], "{left:?}");
    if left == ["run"] {
        let summary =
            std::fs::read_to_string(t.join("run/summary.json")).expect("a complete run folder");
        assert!(summary.contains("\"interrupted\""), "{summary}");
    }
}

/// Every line of the child's stderr, as it comes.
fn stderr_lines(child: &mut Child) -> std::sync::mpsc::Receiver<String> {
    let err = child.stderr.take().expect("piped stderr");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(err).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    rx
}

#[test]
fn ctrl_c_inside_a_long_iteration_stops_the_track_within_two_seconds() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    // 500 shooting intervals: the first evaluation alone takes many seconds
    let phases = t.join("fine.json");
    let mut v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("phases/ellipse_walk.json")).unwrap(),
    )
    .unwrap();
    v["phases"][1]["intervals"] = 120.into();
    v["phases"][2]["intervals"] = 380.into();
    std::fs::write(&phases, v.to_string()).unwrap();
    let out = t.join("run");
    let mut child = bin()
        .args(["track", "--max-iter", "5", "--phases"])
        .arg(&phases)
        .arg("--out")
        .arg(&out)
        .current_dir(root())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let rx = stderr_lines(&mut child);
    let mut log = Vec::new();
    // the line that opens the solve
    loop {
        let line = rx
            .recv_timeout(Duration::from_secs(120))
            .unwrap_or_else(|_| panic!("the solve did not start: {log:?}"));
        let start = line.starts_with("tracking ");
        log.push(line);
        if start {
            break;
        }
    }
    // inside the first evaluation of the shooting intervals
    std::thread::sleep(Duration::from_millis(1500));
    assert!(child.try_wait().unwrap().is_none(), "{log:?}");
    signal(&child, "-INT");
    let sent = Instant::now();
    let status = wait_with_limit(&mut child, Duration::from_secs(60));
    let took = sent.elapsed();
    log.extend(rx.try_iter());
    assert_eq!(status.code(), Some(130), "{log:?}");
    assert!(
        took < Duration::from_millis(2500),
        "exited {took:?} after the signal: {log:?}"
    );
    let log = log.join("\n");
    assert!(log.contains("interrupted: stopping the solve"), "{log}");
    assert!(
        log.contains("the solver stopped without converging: interrupted (results written to"),
        "{log}"
    );
    let summary = common::json(&out.join("summary.json"));
    assert_eq!(summary["status"], "interrupted");
    let (name, values) = status_column(&out.join("tracking.csv"));
    assert_eq!(name, "status");
    assert!(values.iter().all(|v| v == "interrupted"), "{values:?}");
    // the command line, for --resume
    assert!(out.join(".resume-command.json").is_file());
}

#[test]
fn an_interrupted_solve_resumes_from_its_run_folder_along_the_same_iterates() {
    let args = [
        "--problem",
        &r("problems/five_link_biped.json"),
        "--hessian",
        "bfgs",
        "--max-iter",
        "25",
    ];
    let tmp = tempfile::tempdir().unwrap();
    let whole = tmp.path().join("whole");
    let stopped = tmp.path().join("stopped");
    std::fs::create_dir_all(&whole).unwrap();
    std::fs::create_dir_all(&stopped).unwrap();
    let o = solve_whole(&whole, &args, Some("1"));
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let mut child = bin()
        .arg("solve")
        .args(args)
        .args(["--out", "run"])
        .env("RAYON_NUM_THREADS", "1")
        .current_dir(&stopped)
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let lines = wait_for_line(
        &mut child,
        |l| l.trim_start().starts_with("3 "),
        Duration::from_secs(120),
    );
    signal(&child, "-INT");
    let status = wait_with_limit(&mut child, Duration::from_secs(60));
    assert_eq!(status.code(), Some(130), "{lines:?}");
    let run = stopped.join("run");
    let (h, _, s) = iterates(&run);
    assert_eq!(s, "\"interrupted\"");
    assert!(h.len() < 26, "not interrupted: {} iterations", h.len());
    assert!(run.join(".resume-checkpoint-0.json").is_file());
    // --resume continues it in place, to the end the whole run reached
    let o = resume(&stopped, "1");
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert_eq!(iterates(&whole.join("run")), iterates(&run));
    assert_eq!(entries(&stopped), ["run"]);
    assert!(entries(&run).iter().all(|e| !e.starts_with(".resume-")));
}

/// The iterate history (exact bits of every figure but the time) and the final variables
/// of a `solve` run folder.
fn iterates(run: &Path) -> (Vec<[u64; 4]>, Vec<u64>, String) {
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    let solution: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("solution.json")).unwrap()).unwrap();
    let f = |v: &serde_json::Value| v.as_f64().expect("number").to_bits();
    let history = summary["history"]
        .as_array()
        .unwrap()
        .iter()
        .map(|h| {
            [
                f(&h["objective"]),
                f(&h["infeasibility"]),
                f(&h["kkt"]),
                f(&h["step"]),
            ]
        })
        .collect();
    let w = solution["w"].as_array().unwrap().iter().map(f).collect();
    (history, w, summary["status"].to_string())
}

/// `footfall --quiet solve ARGS --out run` in `dir`, run to its end undisturbed, with
/// `threads` threads (`None`: the machine's).
fn solve_whole(dir: &Path, args: &[&str], threads: Option<&str>) -> Output {
    let mut cmd = bin();
    cmd.args(["--quiet", "solve"])
        .args(args)
        .args(["--out", "run"])
        .current_dir(dir);
    if let Some(t) = threads {
        cmd.env("RAYON_NUM_THREADS", t);
    }
    cmd.output().expect("run footfall")
}

/// Start `footfall solve ARGS --out run` in `dir`, SIGKILL it once its checkpoint has
/// reached iteration `kill_at`, and return the iteration of the checkpoint it left.
fn kill_after_checkpoint(dir: &Path, args: &[&str], threads: &str, kill_at: usize) -> usize {
    let mut child = bin()
        .args(["--quiet", "solve"])
        .args(args)
        .args(["--out", "run"])
        .env("RAYON_NUM_THREADS", threads)
        .current_dir(dir)
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    let cp = dir.join(format!(
        ".run.partial-{}/.resume-checkpoint-0.json",
        child.id()
    ));
    let start = Instant::now();
    let next_iter = |p: &Path| -> Option<usize> {
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(p).ok()?).ok()?;
        v["next_iter"].as_u64().map(|n| n as usize)
    };
    loop {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the solve ended before it was killed"
        );
        if next_iter(&cp).is_some_and(|k| k >= kill_at) {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "no checkpoint of iteration {kill_at}"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    signal(&child, "-KILL");
    let status = child.wait().unwrap();
    assert_eq!(status.code(), None, "not killed by a signal");
    assert!(
        !dir.join("run").exists(),
        "a killed run left a folder that looks complete"
    );
    next_iter(&cp).expect("the killed run's checkpoint is readable")
}

fn resume(dir: &Path, threads: &str) -> Output {
    bin()
        .args(["--quiet", "solve", "--resume", "run"])
        .env("RAYON_NUM_THREADS", threads)
        .current_dir(dir)
        .output()
        .expect("run footfall")
}

#[test]
fn a_killed_solve_resumes_along_the_same_iterates() {
    // BFGS on the five-link biped: many iterations, and a solver state (the BFGS blocks,
    // the filter) that a resume must restore exactly; one thread, as the issue asks
    let args = [
        "--problem",
        &r("problems/five_link_biped.json"),
        "--hessian",
        "bfgs",
        "--max-iter",
        "25",
    ];
    let tmp = tempfile::tempdir().unwrap();
    let whole = tmp.path().join("whole");
    let killed = tmp.path().join("killed");
    std::fs::create_dir_all(&whole).unwrap();
    std::fs::create_dir_all(&killed).unwrap();
    let o = solve_whole(&whole, &args, Some("1"));
    assert_eq!(
        o.status.code(),
        Some(3),
        "the iteration limit: {}",
        stderr(&o)
    );

    let at = kill_after_checkpoint(&killed, &args, "1", 6);
    assert!(at < 25, "killed at iteration {at}");
    let o = resume(&killed, "1");
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let (h1, w1, s1) = iterates(&whole.join("run"));
    let (h2, w2, s2) = iterates(&killed.join("run"));
    assert_eq!(h1.len(), 26);
    assert_eq!(h1, h2, "the resumed run took other iterates");
    assert_eq!(w1, w2, "the resumed run ended elsewhere");
    assert_eq!(s1, s2);
    // nothing left but the run folder, and no checkpoint inside it
    assert_eq!(entries(&killed), ["run"]);
    assert!(entries(&killed.join("run"))
        .iter()
        .all(|e| !e.starts_with(".resume-")));
    // nothing left to resume
    let o = resume(&killed, "1");
    refused(&o, &["no killed or interrupted run to resume"]);
}

#[test]
fn a_checkpoint_holding_nan_is_refused_naming_the_file_and_the_entry() {
    let args = ["--problem", &r("problems/five_link_biped.json")];
    let tmp = tempfile::tempdir().unwrap();
    let killed = tmp.path();
    kill_after_checkpoint(killed, &args, "1", 2);
    let partial = entries(killed)
        .into_iter()
        .find(|e| e.starts_with(".run.partial-"))
        .expect("the killed run's staging folder");
    let cp = killed.join(partial).join(".resume-checkpoint-0.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&cp).unwrap()).unwrap();
    v["w"][3] = f64::NAN.to_bits().into();
    std::fs::write(&cp, v.to_string()).unwrap();
    let o = resume(killed, "1");
    refused(
        &o,
        &[
            ".resume-checkpoint-0.json",
            "the checkpoint is damaged: w[3] is NaN",
            "without --resume",
        ],
    );
    assert!(!killed.join("run").exists(), "{}", stderr(&o));
}

#[test]
fn a_killed_solve_resumes_to_the_same_optimum() {
    let args = ["--problem", &r("problems/five_link_biped.json")];
    let tmp = tempfile::tempdir().unwrap();
    let whole = tmp.path().join("whole");
    let killed = tmp.path().join("killed");
    std::fs::create_dir_all(&whole).unwrap();
    std::fs::create_dir_all(&killed).unwrap();
    let o = solve_whole(&whole, &args, None);
    assert!(o.status.success(), "{}", stderr(&o));
    kill_after_checkpoint(&killed, &args, "2", 3);
    // other options beside --resume are refused: the run continues as it was started
    refused(
        &bin()
            .args(["solve", "--resume", "run", "--tol", "1e-3"])
            .current_dir(&killed)
            .output()
            .unwrap(),
        &["--resume", "--tol"],
    );
    let o = resume(&killed, "2");
    assert!(o.status.success(), "{}", stderr(&o));
    let (h1, w1, s1) = iterates(&whole.join("run"));
    let (h2, w2, s2) = iterates(&killed.join("run"));
    assert_eq!(s1, s2);
    assert_eq!(s2, "\"converged\"");
    assert_eq!(h1.len(), h2.len());
    let (j1, j2) = (
        f64::from_bits(h1.last().unwrap()[0]),
        f64::from_bits(h2.last().unwrap()[0]),
    );
    assert!((j1 - j2).abs() <= 1e-9 * j1.abs(), "J {j1} against {j2}");
    assert_eq!(
        w1, w2,
        "deterministic whatever the thread count: the same bits"
    );
}

#[test]
fn a_killed_track_resumes_along_the_same_iterates() {
    // the bundled trial, killed after its first accepted iteration: the resumed run
    // re-parses the recorded command in its working folder (the repository; relative
    // model and data paths) and writes the same solution as a run that was never killed
    let tmp = tempfile::tempdir().unwrap();
    let whole = tmp.path().join("whole");
    let killed = tmp.path().join("killed");
    let track = |out: &Path| {
        let mut c = bin();
        c.args([
            "--quiet",
            "track",
            "--max-iter",
            "2",
            "--out",
            out.to_str().unwrap(),
        ])
        .current_dir(root());
        c
    };
    let o = track(&whole).output().unwrap();
    assert_eq!(
        o.status.code(),
        Some(3),
        "the iteration limit: {}",
        stderr(&o)
    );
    let mut child = track(&killed).stderr(Stdio::null()).spawn().unwrap();
    let cp = tmp.path().join(format!(
        ".killed.partial-{}/.resume-checkpoint-0.json",
        child.id()
    ));
    let start = Instant::now();
    while !cp.exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the track ended before it was killed"
        );
        assert!(start.elapsed() < Duration::from_secs(600), "no checkpoint");
        std::thread::sleep(Duration::from_millis(5));
    }
    signal(&child, "-KILL");
    child.wait().unwrap();
    assert!(!killed.exists());
    // resumed from another folder
    let o = bin()
        .args(["--quiet", "track", "--resume", killed.to_str().unwrap()])
        .current_dir(tmp.path())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let history = |run: &Path| -> Vec<[u64; 3]> {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap())
                .unwrap();
        let f = |x: &serde_json::Value| x.as_f64().unwrap().to_bits();
        v["history"]
            .as_array()
            .unwrap()
            .iter()
            .map(|h| [f(&h["objective"]), f(&h["kkt"]), f(&h["step"])])
            .collect()
    };
    assert_eq!(history(&whole).len(), 3);
    assert_eq!(
        history(&whole),
        history(&killed),
        "the resumed track took other iterates"
    );
    assert_eq!(
        std::fs::read(whole.join("solution.json")).unwrap(),
        std::fs::read(killed.join("solution.json")).unwrap(),
        "the resumed track wrote another solution"
    );
}
