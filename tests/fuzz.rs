//! Property-based fuzzing of the input readers: model, foot and phase files,
//! the sagittal CSV and its meta file, OpenSim `.mot`/`.sto` storages, `solve` problem
//! files, run summaries, control tables, and the command line.
//!
//! Each case mutates a seed of the checked-in corpus (`tests/data/fuzz/`) and checks: no
//! panic, done within 10 s, and either a successful load (whose object then works once)
//! or an error whose message names the file. The RNG seed is fixed, so a run is
//! reproducible; `FOOTFALL_FUZZ_CASES` sets the cases per target (without it, the CLI target,
//! one process per case, runs a tenth of the library targets' count) and `FOOTFALL_FUZZ_SEED` (any text) picks other cases. Inputs that once failed live in `tests/data/fuzz/regressions/`
//! and are replayed by every run. A failing case is written to
//! `target/fuzz-failures/<target>/` after shrinking.

#[path = "fuzz/cli.rs"]
mod cli;
#[path = "fuzz/mutate.rs"]
mod mutate;
#[path = "fuzz/targets.rs"]
mod targets;

use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};
use targets::{corpus, seed, Outcome, Target, TARGETS};

/// Longest a case may take.
const LIMIT: Duration = Duration::from_secs(10);

/// Cases per library target: `FOOTFALL_FUZZ_CASES`, else `default`.
fn cases(default: u32) -> u32 {
    match std::env::var("FOOTFALL_FUZZ_CASES") {
        Ok(v) => v
            .parse()
            .unwrap_or_else(|_| panic!("FOOTFALL_FUZZ_CASES={v:?} is not a count")),
        Err(_) => default,
    }
}

/// Run `f` on its own thread: a panic, or no answer within [`LIMIT`], is an error.
fn guarded<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, String> + Send + 'static,
) -> Result<T, String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
        tx.send(r).ok();
    });
    let start = Instant::now();
    match rx.recv_timeout(LIMIT) {
        Ok(Ok(r)) => r,
        Ok(Err(p)) => {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "(non-text panic)".into());
            Err(format!("panic: {msg}"))
        }
        Err(_) => Err(format!("no answer after {:?} (hang)", start.elapsed())),
    }
}

/// Check one input of `t` in the scratch folder `dir`.
fn run_case(t: &'static Target, dir: &Path, s: usize, bytes: Vec<u8>) -> Result<Outcome, String> {
    let dir = dir.to_path_buf();
    guarded(move || (t.check)(&dir, s, &bytes))
}

/// Keep a failing input for inspection.
fn keep_failure(target: &str, name: &str, bytes: &[u8]) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("fuzz-failures")
        .join(target);
    std::fs::create_dir_all(&d).ok();
    let p = d.join(name);
    std::fs::write(&p, bytes).ok();
    p
}

/// A fixed RNG per target, so that CI runs the same cases every time;
/// `FOOTFALL_FUZZ_SEED` (any text) picks other cases for a long run.
fn runner(name: &str, cases: u32) -> TestRunner {
    let config = Config {
        cases,
        failure_persistence: None,
        rng_algorithm: RngAlgorithm::ChaCha,
        max_shrink_iters: 500,
        max_shrink_time: 60_000,
        ..Config::default()
    };
    let mut key = [0u8; 32];
    let extra = std::env::var("FOOTFALL_FUZZ_SEED").unwrap_or_default();
    for (k, b) in name.bytes().chain([0]).chain(extra.bytes()).enumerate() {
        key[k % 32] ^= b;
    }
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &key))
}

/// Fuzz `t` for `n` cases; returns the outcome tally.
fn fuzz_target(t: &'static Target, n: u32) -> BTreeMap<String, usize> {
    let scratch = tempfile::tempdir().unwrap();
    let tally = Arc::new(Mutex::new(BTreeMap::<String, usize>::new()));
    let examples = Mutex::new(Vec::<String>::new());
    let strategy = (0..t.seeds.len(), mutate::mutations());
    let result = runner(t.name, n).run(&strategy, |(s, ms)| {
        let bytes = mutate::apply_all(&seed(t.seeds[s]), &ms);
        match run_case(t, scratch.path(), s, bytes.clone()) {
            Ok(o) => {
                let key = match o {
                    Outcome::Accepted => "accepted".to_string(),
                    Outcome::Refused => "refused".to_string(),
                    Outcome::UseFailed(m) => {
                        let mut e = examples.lock().unwrap();
                        if e.len() < 5 && !e.contains(&m) {
                            e.push(m);
                        }
                        "loaded, first use failed".to_string()
                    }
                };
                *tally.lock().unwrap().entry(key).or_default() += 1;
                Ok(())
            }
            Err(e) => {
                let name = t.seeds[s].rsplit('/').next().unwrap();
                let kept = keep_failure(t.name, name, &bytes);
                Err(TestCaseError::fail(format!(
                    "{e}\n(input from {} kept in {})",
                    t.seeds[s],
                    kept.display()
                )))
            }
        }
    });
    if let Err(e) = result {
        panic!("fuzz target '{}': {e}", t.name);
    }
    let tally = tally.lock().unwrap().clone();
    eprintln!("fuzz target '{}': {n} cases: {tally:?}", t.name);
    for e in examples.lock().unwrap().iter() {
        eprintln!("  first use failed: {e}");
    }
    tally
}

/// Default cases per library target: the short run (all targets and the CLI) takes well
/// under a minute in the test profile.
const SHORT: u32 = 1000;

macro_rules! library_target {
    ($test:ident, $i:expr) => {
        #[test]
        fn $test() {
            let t = &TARGETS[$i];
            let tally = fuzz_target(t, cases(SHORT));
            // the seeds load, so some mutated inputs must too: otherwise the harness only
            // exercises the first refusal and the target is broken
            assert!(
                tally.get("accepted").copied().unwrap_or(0) > 0,
                "'{}': no input was accepted: {tally:?}",
                t.name
            );
            assert!(
                tally.get("refused").copied().unwrap_or(0) > 0,
                "'{}': no input was refused: {tally:?}",
                t.name
            );
        }
    };
}

library_target!(fuzz_model_files, 0);
library_target!(fuzz_foot_files, 1);
library_target!(fuzz_phase_files, 2);
library_target!(fuzz_sagittal_csv, 3);
library_target!(fuzz_storage_files, 4);
library_target!(fuzz_problem_files, 5);
library_target!(fuzz_run_summaries, 6);
library_target!(fuzz_control_tables, 7);

#[test]
fn seeds_load_unchanged() {
    let scratch = tempfile::tempdir().unwrap();
    for t in TARGETS {
        for (s, rel) in t.seeds.iter().enumerate() {
            let r = run_case(t, scratch.path(), s, seed(rel));
            assert_eq!(r, Ok(Outcome::Accepted), "seed {rel} of '{}'", t.name);
        }
    }
}

/// Every input in `regressions/<target>/` (named `<seed stem>__<what>.<ext>`, the seed
/// it was mutated from choosing its sibling files) is checked again.
#[test]
fn regressions_stay_fixed() {
    let scratch = tempfile::tempdir().unwrap();
    let mut n = 0;
    for t in TARGETS {
        let dir = corpus().join("regressions").join(t.name);
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            let stem = name.split("__").next().unwrap();
            let s = t
                .seeds
                .iter()
                .position(|r| Path::new(r).file_stem().unwrap().to_string_lossy() == stem)
                .unwrap_or_else(|| {
                    panic!("{}: no seed '{stem}' in target '{}'", p.display(), t.name)
                });
            let r = run_case(t, scratch.path(), s, std::fs::read(&p).unwrap());
            assert!(r.is_ok(), "{}: {}", p.display(), r.unwrap_err());
            n += 1;
        }
    }
    eprintln!("{n} regression inputs replayed");
}

#[test]
fn fuzz_command_line() {
    let n = if std::env::var_os("FOOTFALL_FUZZ_CASES").is_some() {
        cases(SHORT)
    } else {
        SHORT / 10
    };
    let scratch = tempfile::tempdir().unwrap();
    let result = runner("cli", n).run(&cli::case(), |c| {
        let dir = scratch.path().to_path_buf();
        cli::run(&c, &dir, LIMIT).map_err(TestCaseError::fail)
    });
    if let Err(e) = result {
        panic!("fuzz target 'cli': {e}");
    }
    eprintln!("fuzz target 'cli': {n} cases");
}

#[test]
fn mutations_change_the_seeds() {
    // the mutation operators must edit (a harness that fed the seeds unchanged would
    // pass trivially)
    use proptest::strategy::{Strategy, ValueTree};
    let mut r = runner("self-test", 1);
    let text = seed(TARGETS[0].seeds[0]);
    let changed = (0..200)
        .filter(|_| {
            let ms = mutate::mutations().new_tree(&mut r).unwrap().current();
            mutate::apply_all(&text, &ms) != text
        })
        .count();
    assert!(
        changed > 150,
        "only {changed} of 200 mutation lists changed the seed"
    );
}
