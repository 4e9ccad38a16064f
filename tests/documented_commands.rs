//! Every command the README and the command guide show runs as written on a fresh clone.
//!
//! Each document's shell lines run in order in one shell, in a scratch folder that holds
//! the repository's top-level entries (symbolic links) and none of its runs, so that a
//! command can use what an earlier one of the same document wrote, as a reader following
//! the page would. `footfall` (and `cargo run --release --`) is the binary this test build
//! made. What each command checks is its own test's job; here each must start, read its
//! files, build its problem and write its output, so the solving commands stop at their
//! start (`--max-iter 0`: evaluated, checked and written) and end with exit 0, 3 (not
//! converged) or 5 (physically invalid), the codes of a run that solved and wrote its
//! folder. A `track` takes one iteration, `--max-iter 1`: later commands build on its
//! solution (`synth` makes a trial from it and refuses the data guess's forces, which
//! imply another body weight), and a `--resume` runs with the options it was started
//! with. `synth` runs in full: its re-fit with a hidden model effect is what the next
//! command of the guide tracks.
//!
//! The lines that build the project or install the Python binding are not run here:
//! `.ci/run` runs them, and [`RUN_BY_CI`] names the text of `.ci/run` that does.

use crate::common::docs::{sh_lines, DOCUMENTED};
use crate::common::root;
use std::process::{Command, Stdio};

/// Documented lines `.ci/run` runs (the start of the line, and the text in `.ci/run`
/// that runs it).
const RUN_BY_CI: &[(&str, &str)] = &[
    ("./tools/setup && ./tools/test", "./tools/test"),
    (
        "python3 -m venv .venv && .venv/bin/pip install ./python",
        "pip install -q ./python",
    ),
    (".venv/bin/python -c", "the command guide's Python example"),
];

/// The subcommands that solve, and take `--max-iter` (a study's tracks), besides `track`.
const SOLVING: &str = "predict|compare|compare-contact|diagnose|fit-foot|solve|study";

/// The shell that runs a document's lines: `footfall` and `cargo run --release --` call
/// the test build's binary, solves capped (tracks at one iteration, the others at their
/// start), and any other exit than 0, 3 or 5 stops it.
fn preamble(bin: &str) -> String {
    format!(
        r#"set -u
footfall() {{
    local cap=()
    case " $* " in *" --resume "*) ;; *)
        case "$1" in
            track) cap=(--max-iter 1) ;;
            {SOLVING}) cap=(--max-iter 0) ;;
        esac ;;
    esac
    "{bin}" "$@" "${{cap[@]}}" </dev/null
    local rc=$?
    case $rc in 0|3|5) return 0 ;; esac
    echo "documented command failed with exit $rc: footfall $*" >&2
    exit 1
}}
cargo() {{
    if [ "$1 $2 $3" = "run --release --" ]; then shift 3; footfall "$@"; return; fi
    echo "documented command runs cargo $*, which this test does not run" >&2
    exit 1
}}
"#
    )
}

/// A scratch folder like a fresh clone: every top-level entry of the repository but its
/// build output, runs and version control, linked.
fn scratch_clone() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(root()).unwrap() {
        let name = entry.unwrap().file_name();
        if [".git", "target", "runs", ".venv"].contains(&name.to_str().unwrap_or("")) {
            continue;
        }
        std::os::unix::fs::symlink(root().join(&name), dir.path().join(&name)).unwrap();
    }
    dir
}

/// Runs the shell lines of `doc` and fails with the log of the one that failed.
fn run_documented(doc: &str) {
    let md = std::fs::read_to_string(root().join(doc)).unwrap();
    let ci = std::fs::read_to_string(root().join(".ci/run")).unwrap();
    let mut script = preamble(env!("CARGO_BIN_EXE_footfall"));
    let mut ran = 0;
    for line in sh_lines(&md) {
        if let Some((_, by)) = RUN_BY_CI.iter().find(|(start, _)| line.starts_with(start)) {
            assert!(
                ci.contains(by),
                "{doc}: `{line}` is left to .ci/run, which has no `{by}`"
            );
            continue;
        }
        script.push_str(&format!("echo {:?} >&2\n{line}\n", format!("$ {line}")));
        ran += 1;
    }
    assert!(ran >= 3, "{doc}: only {ran} shell lines to run");
    let dir = scratch_clone();
    let out = Command::new("bash")
        .arg("-c")
        .arg(&script)
        .current_dir(dir.path())
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&out.stderr);
    let tail: Vec<&str> = log.lines().rev().take(30).collect();
    assert!(
        out.status.success(),
        "{doc}: a documented command failed:\n{}",
        tail.into_iter().rev().collect::<Vec<_>>().join("\n")
    );
}

#[test]
fn the_readmes_commands_run_as_written() {
    run_documented(DOCUMENTED[0]);
}

#[test]
fn the_command_guides_commands_run_as_written() {
    run_documented(DOCUMENTED[1]);
}
