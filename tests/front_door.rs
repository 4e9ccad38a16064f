//! The project's front door: the README stays short, the product carries no development
//! history, nothing built is committed, and every command the README and the command guide
//! show runs as written.
//!
//! Checked in `README.md`, `docs/`, `src/`, `tests/` (without `tests/data/`), `tools/`,
//! `python/`, `benches/`, `Cargo.toml` and `.ci/`:
//! - no numbered development milestone (the word for a halt followed by a number),
//! - no abbreviated or full hash of one of this repository's own commits (from
//!   `git rev-list --all`; skipped with a note when git or its history is unavailable),
//! - no absolute path of a machine or a path that leaves the repository for a sibling
//!   folder; the provenance of outside data (an upstream project's commit) is allowed.
//!
//! The patterns are assembled from pieces at run time, so that this file does not match
//! its own checks.

use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::docs::{invocations, sh_lines, DOCUMENTED};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The README's length limit (lines).
const README_MAX_LINES: usize = 400;

/// Tracked files larger than this must lie in `data/` or `tests/data/` (bytes).
const MAX_TRACKED_BYTES: u64 = 1_000_000;

/// Findings in files another change owns at the moment, each with the end of the finding's
/// text: tolerated while the file holds it, and named in a note once it is gone, so that the
/// entry is removed with the fix.
const PENDING: &[(&str, &str)] = &[];

/// Every text file the history checks read, relative to the repository root.
fn checked_files() -> Vec<PathBuf> {
    let r = root();
    let mut out = vec![PathBuf::from("README.md"), PathBuf::from("Cargo.toml")];
    for dir in ["docs", "src", "tests", "tools", "python", "benches", ".ci"] {
        walk(&r, Path::new(dir), &mut out);
    }
    out.retain(|p| r.join(p).is_file());
    out
}

fn walk(root: &Path, rel: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(root.join(rel)) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let name = name.to_string_lossy();
        let child = rel.join(&*name);
        if child == Path::new("tests").join("data") {
            continue;
        }
        let Ok(ft) = e.file_type() else { continue };
        if ft.is_dir() {
            if matches!(
                &*name,
                "target" | "__pycache__" | ".venv" | "venv" | ".pytest_cache"
            ) {
                continue;
            }
            walk(root, &child, out);
        } else if ft.is_file() {
            out.push(child);
        }
    }
}

/// The file's text, or `None` for a binary file.
fn text(rel: &Path) -> Option<String> {
    String::from_utf8(std::fs::read(root().join(rel)).ok()?).ok()
}

/// A numbered halt: the halt word, an optional plural, one space or none, digits.
fn milestone_mentions(line: &str) -> Vec<String> {
    let word = ["st", "op"].concat();
    let lower = line.to_ascii_lowercase();
    let b = lower.as_bytes();
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(k) = lower[from..].find(&word) {
        let start = from + k;
        from = start + word.len();
        if start > 0 && (b[start - 1].is_ascii_alphanumeric() || b[start - 1] == b'_') {
            continue;
        }
        let mut i = start + word.len();
        if i < b.len() && b[i] == b's' {
            i += 1;
        }
        if i < b.len() && b[i] == b' ' {
            i += 1;
        }
        let digits = b[i..].iter().take_while(|c| c.is_ascii_digit()).count();
        if digits > 0 {
            found.push(line[start..i + digits].to_string());
        }
    }
    found
}

/// Absolute machine paths and paths into a sibling folder of the repository.
fn outside_paths(line: &str) -> Vec<String> {
    let sep = "/";
    let patterns = [
        [sep, "work", sep].concat(),
        [sep, "home", sep].concat(),
        [sep, "root", sep].concat(),
        [sep, "Users", sep].concat(),
        ["C:", "\\"].concat(),
        ["..", sep, "shared"].concat(),
    ];
    patterns
        .iter()
        .filter(|p| line.contains(p.as_str()))
        .cloned()
        .collect()
}

/// Whole words of 7 to 40 hexadecimal digits.
fn hex_words(line: &str) -> Vec<&str> {
    line.split(|c: char| !c.is_ascii_alphanumeric() && c != '_')
        .filter(|w| (7..=40).contains(&w.len()) && w.bytes().all(|c| c.is_ascii_hexdigit()))
        .collect()
}

/// This repository's commit hashes, lower case, or `None` without git or history.
fn own_commits() -> Option<Vec<String>> {
    let o = Command::new("git")
        .args(["rev-list", "--all"])
        .current_dir(root())
        .output()
        .ok()?;
    if !o.status.success() {
        return None;
    }
    let hashes: Vec<String> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| l.trim().to_ascii_lowercase())
        .filter(|l| l.len() == 40)
        .collect();
    (!hashes.is_empty()).then_some(hashes)
}

#[test]
fn readme_is_short() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let n = readme.lines().count();
    assert!(
        n <= README_MAX_LINES,
        "README.md has {n} lines, more than {README_MAX_LINES}: move detail to docs/"
    );
}

#[test]
fn no_development_history_in_the_product() {
    let commits = own_commits();
    let prefixes: HashSet<&str> = commits
        .iter()
        .flatten()
        .map(|h| &h[..7])
        .collect::<HashSet<_>>();
    if commits.is_none() {
        eprintln!("git history unavailable: the commit-hash check is skipped");
    }
    let mut findings: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for rel in checked_files() {
        let Some(t) = text(&rel) else { continue };
        let key = rel.to_string_lossy().replace('\\', "/");
        for (n, line) in t.lines().enumerate() {
            let mut hits = milestone_mentions(line);
            hits.extend(outside_paths(line));
            if let Some(all) = &commits {
                for w in hex_words(line) {
                    let w = w.to_ascii_lowercase();
                    if prefixes.contains(&w[..7]) && all.iter().any(|h| h.starts_with(&w)) {
                        hits.push(format!("commit {w}"));
                    }
                }
            }
            for h in hits {
                findings
                    .entry(key.clone())
                    .or_default()
                    .push(format!("{}: {h}", n + 1));
            }
        }
    }
    let mut unexpected = Vec::new();
    for (file, hits) in &findings {
        for h in hits {
            let pending = PENDING
                .iter()
                .any(|(f, what)| f == file && h.ends_with(what));
            if !pending {
                unexpected.push(format!("{file}:{h}"));
            }
        }
    }
    let stale: Vec<_> = PENDING
        .iter()
        .filter(|(f, what)| {
            !findings
                .get(*f)
                .is_some_and(|hits| hits.iter().any(|h| h.ends_with(what)))
        })
        .collect();
    assert!(
        unexpected.is_empty(),
        "development history or outside paths ({}):\n{}",
        unexpected.len(),
        unexpected.join("\n")
    );
    if !stale.is_empty() {
        eprintln!("PENDING entries no longer found, remove them: {stale:?}");
    }
}

#[test]
fn nothing_large_is_tracked_outside_the_data_folders() {
    let o = Command::new("git")
        .args(["ls-files", "-z"])
        .current_dir(root())
        .output();
    let o = match o {
        Ok(o) if o.status.success() => o,
        _ => {
            eprintln!("git unavailable: the tracked-file size check is skipped");
            return;
        }
    };
    let mut large = Vec::new();
    for f in o.stdout.split(|&c| c == 0).filter(|f| !f.is_empty()) {
        let f = String::from_utf8_lossy(f).into_owned();
        if f.starts_with("data/") || f.starts_with("tests/data/") {
            continue;
        }
        if let Ok(m) = std::fs::metadata(root().join(&f)) {
            if m.len() > MAX_TRACKED_BYTES {
                large.push(format!("{f} ({} bytes)", m.len()));
            }
        }
    }
    assert!(
        large.is_empty(),
        "tracked files over 1 MB outside data/: {large:?}"
    );
}

/// `footfall <sub> --help`, or an error naming what failed.
fn help_of(sub: &str) -> Result<String, String> {
    let o = Command::new(env!("CARGO_BIN_EXE_footfall"))
        .args([sub, "--help"])
        .current_dir(root())
        .output()
        .map_err(|e| e.to_string())?;
    if !o.status.success() {
        return Err(format!(
            "`footfall {sub} --help` exits {:?}: {}",
            o.status.code(),
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    Ok(String::from_utf8_lossy(&o.stdout).into_owned())
}

/// Whether a help text lists this option (as `--name`, followed by a space, comma, `=` or
/// the end of the line).
fn lists_option(help: &str, flag: &str) -> bool {
    help.match_indices(flag).any(|(k, _)| {
        let before_ok = k == 0 || help.as_bytes()[k - 1].is_ascii_whitespace();
        let after = help[k + flag.len()..].chars().next();
        before_ok && matches!(after, None | Some(' ' | ',' | '=' | '\n' | '\r'))
    })
}

/// Every `footfall` command of the README's and the command guide's shell blocks names an
/// existing subcommand and only options it has; every `./tools/…` script they run exists.
#[test]
fn documented_commands_parse() {
    let mut problems = Vec::new();
    let mut helps: BTreeMap<String, Result<String, String>> = BTreeMap::new();
    let mut checked = 0;
    for doc in DOCUMENTED {
        let Ok(md) = std::fs::read_to_string(root().join(doc)) else {
            problems.push(format!("{doc} is missing"));
            continue;
        };
        for line in sh_lines(&md) {
            for word in line.split_whitespace() {
                if let Some(script) = word.strip_prefix("./tools/") {
                    if !root().join("tools").join(script).is_file() {
                        problems.push(format!("{doc}: `{line}`: no tools/{script}"));
                    }
                }
            }
            for inv in invocations(&line) {
                checked += 1;
                let help = helps
                    .entry(inv.subcommand.clone())
                    .or_insert_with(|| help_of(&inv.subcommand));
                match help {
                    Err(e) => problems.push(format!("{doc}: `{}`: {e}", inv.line)),
                    Ok(h) => {
                        for f in inv.flags.iter().filter(|f| !lists_option(h, f)) {
                            problems.push(format!(
                                "{doc}: `{}`: `footfall {}` has no option {f}",
                                inv.line, inv.subcommand
                            ));
                        }
                    }
                }
            }
        }
    }
    assert!(
        checked >= 5,
        "only {checked} footfall commands found in the docs' sh blocks"
    );
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_checks_see_what_they_look_for() {
    let halt = ["St", "op"].concat();
    assert_eq!(
        milestone_mentions(&format!("at {halt} 64,")),
        vec![format!("{halt} 64")]
    );
    assert_eq!(milestone_mentions(&format!("({halt}s 52 and 58)")).len(), 1);
    assert!(milestone_mentions("the solve stops when it converges").is_empty());
    assert!(milestone_mentions(&format!("non{halt} 3")).is_empty());
    let p = ["..", "/", "shared", "/peer"].concat();
    assert_eq!(outside_paths(&p).len(), 1);
    assert_eq!(hex_words("at 0badc0de: setup"), vec!["0badc0de"]);
    assert!(hex_words("0x1f and deadbee_f").is_empty());
    let inv = invocations("./tools/setup && cargo run --release -- track --overwrite");
    assert_eq!(inv.len(), 1);
    assert_eq!(inv[0].subcommand, "track");
    assert_eq!(inv[0].flags, vec!["--overwrite".to_string()]);
    assert!(lists_option("      --out <OUT>\n", "--out"));
    assert!(!lists_option("      --outer <OUT>\n", "--out"));
    assert_eq!(
        sh_lines("```sh\nfootfall diff a \\\n  b\n```\n"),
        vec!["footfall diff a b".to_string()]
    );
}
