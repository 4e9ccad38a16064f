//! `footfall diff RUN_A RUN_B` end to end on hand-written run summaries with known errors:
//! the figures in `summary.json`, `diff.csv` and on stdout against hand-computed values,
//! channels and phases present in one run only, the default output folder, and bad
//! input (missing, unparsable or incomplete `summary.json`) giving exit code 1 with an
//! error that names the file and field, no panic and no output folder.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Run A: knee 4.0 °, CoP 2.0 cm, normal GRF 50 N, hip 1.0 ° (hip only in A); knee by phase.
const SUMMARY_A: &str = r#"{
  "command": "track", "foot": "ellipse",
  "errors": [
    {"channel": "knee angle", "unit": "°", "stats": {"mean": 4.0, "sd": 1.0, "max": 7.0}},
    {"channel": "CoP", "unit": "cm", "stats": {"mean": 2.0, "sd": 0.5, "max": 3.5}},
    {"channel": "normal GRF", "unit": "N", "stats": {"mean": 50.0, "sd": 10.0, "max": 90.0}},
    {"channel": "hip angle", "unit": "°", "stats": {"mean": 1.0, "sd": 0.2, "max": 1.5}}
  ],
  "errors_by_phase": [
    {"channel": "knee angle", "unit": "°", "phases": [
      {"phase": "1e", "stats": {"mean": 3.0, "sd": 1.0, "max": 4.0}},
      {"phase": "2", "stats": {"mean": 5.0, "sd": 1.0, "max": 7.0}}]},
    {"channel": "CoP", "unit": "cm", "phases": []}
  ]
}"#;

/// Run B: knee 3.0 ° (−25 %), CoP 3.0 cm (+50 %), normal GRF 50.2 N (+0.4 %, within
/// the 1 % threshold), ankle 0.5 ° (only in B); knee phase 1e halved, phase 2 missing.
const SUMMARY_B: &str = r#"{
  "command": "track", "foot": "double_circle",
  "errors": [
    {"channel": "knee angle", "unit": "°", "stats": {"mean": 3.0, "sd": 0.5, "max": 6.0}},
    {"channel": "CoP", "unit": "cm", "stats": {"mean": 3.0, "sd": 0.5, "max": 4.0}},
    {"channel": "normal GRF", "unit": "N", "stats": {"mean": 50.2, "sd": 9.0, "max": 80.0}},
    {"channel": "ankle angle", "unit": "°", "stats": {"mean": 0.5, "sd": 0.1, "max": 0.9}}
  ],
  "errors_by_phase": [
    {"channel": "knee angle", "unit": "°", "phases": [
      {"phase": "1e", "stats": {"mean": 1.5, "sd": 0.5, "max": 2.0}}]}
  ]
}"#;

/// A scratch folder holding run folders `A` and `B` (when given a summary text).
struct Scratch(tempfile::TempDir);

impl Scratch {
    fn new(a: Option<&str>, b: Option<&str>) -> Self {
        let s = Self(tempfile::tempdir().expect("temp dir"));
        for (name, text) in [("A", a), ("B", b)] {
            std::fs::create_dir(s.path(name)).expect("run folder");
            if let Some(t) = text {
                std::fs::write(s.path(name).join("summary.json"), t).expect("write summary");
            }
        }
        s
    }
    fn path(&self, name: &str) -> PathBuf {
        self.0.path().join(name)
    }
    /// `footfall ARGS` run in the scratch folder.
    fn footfall(&self, args: &[&str]) -> Output {
        Command::new(env!("CARGO_BIN_EXE_footfall"))
            .args(args)
            .current_dir(self.0.path())
            .output()
            .expect("run the footfall binary")
    }
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn read_json(p: &Path) -> serde_json::Value {
    let t = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&t).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn channel<'a>(summary: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    summary["channels"]
        .as_array()
        .expect("channels")
        .iter()
        .find(|c| c["channel"] == name)
        .unwrap_or_else(|| panic!("channel {name} in {summary}"))
}

fn assert_close(v: &serde_json::Value, expected: f64, what: &str) {
    let x = v
        .as_f64()
        .unwrap_or_else(|| panic!("{what}: expected a number, got {v}"));
    assert!(
        (x - expected).abs() < 1e-9,
        "{what}: {x}, expected {expected}"
    );
}

/// A failed run: exit code 1, an `error:` line naming every item of `names`, no panic.
fn assert_user_error(o: &Output, names: &[&str]) {
    let err = text(&o.stderr);
    assert_eq!(
        o.status.code(),
        Some(1),
        "expected exit code 1, stderr: {err}"
    );
    assert!(err.starts_with("error: "), "stderr: {err}");
    assert!(!err.contains("panicked"), "panic: {err}");
    for n in names {
        assert!(err.contains(n), "error should name {n:?}: {err}");
    }
}

#[test]
fn diff_figures_match_hand_computed_values() {
    let s = Scratch::new(Some(SUMMARY_A), Some(SUMMARY_B));
    let out = s.path("out");
    let o = s.footfall(&["diff", "A", "B", "--out", out.to_str().expect("UTF-8 path")]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "stderr: {}", text(&o.stderr));
    for f in [
        "diff.md",
        "diff.csv",
        "diff.svg",
        "report.html",
        "summary.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }

    let sum = read_json(&out.join("summary.json"));
    assert_eq!(sum["command"], "diff");
    let knee = channel(&sum, "knee angle");
    assert_close(&knee["a"]["mean"], 4.0, "knee mean A");
    assert_close(&knee["b"]["mean"], 3.0, "knee mean B");
    assert_close(&knee["change"], -1.0, "knee change");
    assert_close(&knee["change_pct"], -25.0, "knee change %");
    assert_eq!(knee["verdict"], "better");
    let cop = channel(&sum, "CoP");
    assert_close(&cop["change"], 1.0, "CoP change");
    assert_close(&cop["change_pct"], 50.0, "CoP change %");
    assert_eq!(cop["verdict"], "worse");
    let grf = channel(&sum, "normal GRF");
    assert_close(&grf["change_pct"], 0.4, "GRF change %");
    assert_eq!(
        grf["verdict"], "unchanged",
        "0.4 % is within the default 1 % threshold"
    );
    assert_eq!(sum["counts"]["better"], 1);
    assert_eq!(sum["counts"]["worse"], 1);
    assert_eq!(sum["counts"]["unchanged"], 1);

    // knee by phase: 1e in both (3.0 → 1.5, −50 %), 2 in A only
    let phases = knee["phases"].as_array().expect("phases");
    assert_eq!(phases.len(), 2);
    assert_eq!(phases[0]["phase"], "1e");
    assert_close(&phases[0]["change_pct"], -50.0, "knee 1e change %");
    assert_eq!(phases[1]["phase"], "2");
    assert_eq!(phases[1]["verdict"], "only_in_a");
    assert!(phases[1]["mean_b"].is_null());

    // CSV: full-precision numbers, one row per channel
    let csv = std::fs::read_to_string(out.join("diff.csv")).expect("diff.csv");
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("channel,unit,mean_a,mean_b,change,change_pct,verdict,sd_a,sd_b,max_a,max_b")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 5, "{csv}");
    let knee_row = rows
        .iter()
        .find(|r| r[0] == "knee angle")
        .expect("knee row");
    let num = |s: &str| s.parse::<f64>().unwrap_or_else(|e| panic!("{s:?}: {e}"));
    assert_eq!(
        (knee_row[1], num(knee_row[2]), num(knee_row[3])),
        ("°", 4.0, 3.0)
    );
    assert_eq!(
        (num(knee_row[4]), num(knee_row[5]), knee_row[6]),
        (-1.0, -25.0, "better")
    );

    // stdout and diff.md: the table with the change and the verdict
    for doc in [
        stdout.as_str(),
        &std::fs::read_to_string(out.join("diff.md")).expect("diff.md"),
    ] {
        let row = doc
            .lines()
            .find(|l| l.starts_with("| knee angle"))
            .unwrap_or_else(|| panic!("no knee row in:\n{doc}"));
        for cell in ["4.00", "3.00", "-1.00", "-25.0 %", "better"] {
            assert!(row.contains(cell), "{cell:?} missing in {row:?}");
        }
    }
    let md = std::fs::read_to_string(out.join("diff.md")).expect("diff.md");
    assert!(md.contains("3.00 → 1.50"), "by-phase table: {md}");
    let svg = std::fs::read_to_string(out.join("diff.svg")).expect("diff.svg");
    assert!(svg.starts_with("<svg") && svg.contains("% of A"), "{svg}");
    let html = std::fs::read_to_string(out.join("report.html")).expect("report.html");
    assert!(html.contains("<svg") && html.contains("knee angle") && html.contains("-25.0 %"));
}

#[test]
fn channel_in_one_run_only_is_reported() {
    let s = Scratch::new(Some(SUMMARY_A), Some(SUMMARY_B));
    let out = s.path("out");
    let o = s.footfall(&["diff", "A", "B", "--out", out.to_str().expect("UTF-8 path")]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "stderr: {}", text(&o.stderr));
    let sum = read_json(&out.join("summary.json"));
    let hip = channel(&sum, "hip angle");
    assert_eq!(hip["verdict"], "only_in_a");
    assert_close(&hip["a"]["mean"], 1.0, "hip mean A");
    assert!(hip["b"].is_null() && hip["change"].is_null());
    assert_eq!(channel(&sum, "ankle angle")["verdict"], "only_in_b");
    assert_eq!(sum["counts"]["only_in_a"], 1);
    let hip_row = stdout
        .lines()
        .find(|l| l.starts_with("| hip angle"))
        .unwrap_or_else(|| panic!("no hip row:\n{stdout}"));
    assert!(hip_row.contains("only in A"), "{hip_row}");
    assert!(
        stdout.contains("Only in run A") && stdout.contains("hip angle (°)"),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(out.join("diff.csv")).expect("diff.csv");
    assert!(csv.contains("hip angle,°,1,,,,only_in_a,"), "{csv}");
}

#[test]
fn default_output_folder_and_overwrite() {
    let s = Scratch::new(Some(SUMMARY_A), Some(SUMMARY_B));
    let o = s.footfall(&["--quiet", "diff", "A", "B"]);
    assert!(o.status.success(), "stderr: {}", text(&o.stderr));
    assert!(
        o.stdout.is_empty() && o.stderr.is_empty(),
        "--quiet prints nothing"
    );
    let out = s.path("runs/diff-A-vs-B");
    assert!(out.join("summary.json").is_file());
    // an existing folder is kept unless --overwrite
    assert_user_error(
        &s.footfall(&["diff", "A", "B"]),
        &["diff-A-vs-B", "--overwrite"],
    );
    assert!(s
        .footfall(&["diff", "A", "B", "--overwrite"])
        .status
        .success());
    // a run folder cannot be its own output
    assert_user_error(
        &s.footfall(&["diff", "A", "B", "--out", "A", "--overwrite"]),
        &["would replace the input run"],
    );
    assert!(s.path("A/summary.json").is_file());
}

#[test]
fn bad_summaries_name_the_file_and_field() {
    // (summary of A, what the error must name besides the file)
    let cases: [(Option<&str>, &[&str]); 6] = [
        (None, &["run A", "summary.json", "not found"]),
        (
            Some("{\"errors\": [ {\"channel\": "),
            &["run A", "not valid JSON"],
        ),
        (
            Some("{\"command\": \"track\"}"),
            &["field `errors`", "missing"],
        ),
        (Some("[1, 2]"), &["expected a JSON object"]),
        (
            Some(
                r#"{"errors": [{"channel": "knee angle", "unit": "°", "stats": {"mean": "4.0"}}]}"#,
            ),
            &["errors[0].stats.mean", "expected a number"],
        ),
        (
            Some(r#"{"errors": [{"channel": "knee angle", "unit": "°", "stats": {"mean": -1}}]}"#),
            &["errors[0].stats.mean", "≥ 0"],
        ),
    ];
    for (summary, names) in cases {
        let s = Scratch::new(summary, Some(SUMMARY_B));
        let o = s.footfall(&["diff", "A", "B", "--out", "out"]);
        let mut all = names.to_vec();
        all.push("A/summary.json");
        assert_user_error(&o, &all);
        assert!(!s.path("out").exists(), "no output folder after bad input");
    }
    // a run path that does not exist; B is checked as well as A
    let s = Scratch::new(Some(SUMMARY_A), Some(SUMMARY_B));
    assert_user_error(
        &s.footfall(&["diff", "A", "nowhere", "--out", "out"]),
        &["run B", "nowhere", "no such run folder"],
    );
    std::fs::write(s.path("B/summary.json"), r#"{"errors": {}}"#).expect("write");
    assert_user_error(
        &s.footfall(&["diff", "A", "B", "--out", "out"]),
        &[
            "run B",
            "B/summary.json",
            "field `errors`",
            "expected an array",
        ],
    );
    assert!(!s.path("out").exists());
}
