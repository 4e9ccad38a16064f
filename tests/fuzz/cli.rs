//! The command line under fuzzing: the built binary run with mutated input files and
//! option values that make every run fail (or finish) before any solve or simulation.

use super::mutate::{apply_all, mutations, Mutation};
use super::targets::seed;
use proptest::prelude::*;
use proptest::sample::Index;
use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Tolerances that every command refuses (`simulate` and `solve` check them before
/// simulating or solving).
const BAD_TOL: &[&str] = &[
    "-1", "0", "-0", "NaN", "inf", "-inf", "1e400", "2", "abc", "", "0x1", "1e-9999",
];

/// Values of numeric options that need not be valid.
const ANY_NUMBER: &[&str] = &[
    "1",
    "0.5",
    "0",
    "-1",
    "NaN",
    "inf",
    "1e308",
    "-1e308",
    "x",
    "",
    "1e-300",
    "18446744073709551616",
];

/// One command-line case.
#[derive(Debug, Clone)]
pub struct CliCase {
    /// 0 simulate, 1 solve, 2 diff, 3 report.
    pub command: usize,
    /// Seed index within the command's seeds.
    pub seed: Index,
    /// Mutations of the seed.
    pub mutations: Vec<Mutation>,
    /// Option values.
    pub values: (Index, Index),
}

/// Any command-line case.
pub fn case() -> impl Strategy<Value = CliCase> {
    (
        0usize..4,
        any::<Index>(),
        mutations(),
        any::<(Index, Index)>(),
    )
        .prop_map(|(command, seed, mutations, values)| CliCase {
            command,
            seed,
            mutations,
            values,
        })
}

const SEEDS: [&[&str]; 4] = [
    &["phases/sim_ellipse_step.json"],
    &[
        "problem/cartpole_swingup.json",
        "problem/five_link_biped.json",
    ],
    &["summary/run_a.json", "summary/run_b.json"],
    &["summary/run_a.json"],
];

/// Write the case's files into `dir` and return the arguments.
fn arguments(c: &CliCase, dir: &Path) -> Vec<String> {
    let seeds = SEEDS[c.command];
    let bytes = apply_all(&seed(seeds[c.seed.index(seeds.len())]), &c.mutations);
    let d = |p: &str| dir.join(p).display().to_string();
    let tol = BAD_TOL[c.values.0.index(BAD_TOL.len())];
    let any = ANY_NUMBER[c.values.1.index(ANY_NUMBER.len())];
    std::fs::create_dir_all(dir.join("A")).unwrap();
    let mut args: Vec<String> = vec!["--quiet".into()];
    let v = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    match c.command {
        0 => {
            std::fs::write(dir.join("phases.json"), &bytes).unwrap();
            args.extend(v(&[
                "simulate",
                "--phase-set",
                &d("phases.json"),
                "--out",
                &d("out"),
                "--overwrite",
            ]));
            args.push(format!("--tol={tol}"));
            args.push(format!("--dt={any}"));
        }
        1 => {
            std::fs::write(dir.join("problem.json"), &bytes).unwrap();
            args.extend(v(&[
                "solve",
                "--problem",
                &d("problem.json"),
                "--out",
                &d("out"),
                "--overwrite",
            ]));
            args.push(format!("--tol={tol}"));
            args.push(format!("--max-iter={any}"));
        }
        2 => {
            std::fs::write(dir.join("A/summary.json"), &bytes).unwrap();
            std::fs::create_dir_all(dir.join("B")).unwrap();
            std::fs::write(dir.join("B/summary.json"), seed("summary/run_b.json")).unwrap();
            args.extend(v(&[
                "diff",
                &d("A"),
                &d("B"),
                "--out",
                &d("out"),
                "--overwrite",
            ]));
            args.push(format!("--threshold-pct={any}"));
        }
        _ => {
            std::fs::write(dir.join("A/summary.json"), &bytes).unwrap();
            args.extend(v(&["report", &d("A"), "--out", &d("out"), "--overwrite"]));
            args.push(format!("--transient-threshold={any}"));
        }
    }
    args
}

/// Run the case in `dir` (the repository root is the working folder, so the default model
/// and foot paths resolve): no panic (exit 101), no run over `limit`, and a failure's
/// stderr starts with `error:`. Commands that cannot succeed (a refused tolerance) must
/// fail.
pub fn run(c: &CliCase, dir: &Path, limit: Duration) -> Result<(), String> {
    let args = arguments(c, dir);
    let mut child = Command::new(env!("CARGO_BIN_EXE_footfall"))
        .args(&args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start footfall: {e}"))?;
    let mut err = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        err.read_to_end(&mut s).ok();
        String::from_utf8_lossy(&s).into_owned()
    });
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().map_err(|e| e.to_string())? {
            break s;
        }
        if start.elapsed() > limit {
            child.kill().ok();
            child.wait().ok();
            return Err(format!(
                "footfall {args:?} still running after {limit:?} (killed)"
            ));
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let stderr = reader.join().unwrap();
    let code = status.code();
    if code == Some(101) {
        return Err(format!("footfall {args:?} panicked:\n{stderr}"));
    }
    if c.command <= 1 && status.success() {
        return Err(format!("footfall {args:?} accepted a refused tolerance"));
    }
    if !status.success() && !stderr.starts_with("error:") {
        return Err(format!(
            "footfall {args:?} failed ({status}) without an `error:` line:\n{stderr}"
        ));
    }
    Ok(())
}
