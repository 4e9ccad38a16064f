//! `footfall solve` end to end: a converged run folder, warm start, and clear errors.

use crate::common::footfall;

#[test]
fn solve_writes_a_converged_run_and_warm_starts_from_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cartpole");
    let o = footfall(&[
        "solve",
        "--problem",
        "problems/cartpole_swingup.json",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "converged");
    let j = summary["objective"].as_f64().unwrap();
    assert!(
        (j - 76.665674185).abs() / 76.665674185 < 1e-5,
        "objective {j}"
    );
    assert!(summary["kkt"].as_f64().unwrap() <= 1e-6);
    let csv = std::fs::read_to_string(out.join("solution.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 41);
    // warm start from the solution: converges at once
    let out2 = dir.path().join("warm");
    let sol = out.join("solution.json");
    let o = footfall(&[
        "solve",
        "--problem",
        "problems/cartpole_swingup.json",
        "--out",
        out2.to_str().unwrap(),
        "--warm-start",
        sol.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s2: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out2.join("summary.json")).unwrap()).unwrap();
    assert!(
        s2["iterations"].as_u64().unwrap() <= 2,
        "warm start took {} iterations",
        s2["iterations"]
    );
}

#[test]
fn solve_reports_an_iteration_limit_with_exit_code_3_and_keeps_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("limited");
    let o = footfall(&[
        "solve",
        "--problem",
        "problems/cartpole_swingup.json",
        "--out",
        out.to_str().unwrap(),
        "--max-iter",
        "3",
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("iteration limit"), "{err}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "max_iterations");
}

#[test]
fn solve_refuses_an_unknown_problem_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("p.json");
    std::fs::write(&p, r#"{ "name": "double_pendulum" }"#).unwrap();
    let out = dir.path().join("x");
    let o = footfall(&[
        "solve",
        "--problem",
        p.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("p.json") && err.contains("'name'") && err.contains("cartpole_swingup"),
        "{err}"
    );
    assert!(!out.exists());
}
