//! Simulation sanity: the shipped `phases/sim_*.json` examples end their
//! swing at the touchdown of the landing contact, so the impact starts on the ground;
//! a landing away from the ground, a touchdown not reached, or a large stabilisation force
//! is a typed warning of the library, printed by `footfall simulate` (exit 0) or refused
//! with `--strict` (exit 1, no output folder).

use crate::common;
use common::{root, stderr};
use footfall::controls::ControlTable;
use footfall::model::{ConstraintSet, GaitModel, RowKind};
use footfall::phases::{Duration, Phase, PhaseSequence};
use footfall::simulate::{
    simulate, SanityTolerances, SimulationResult, SimulationSettings, SimulationWarning,
};
use std::path::Path;
use std::process::{Command, Output};

const EXAMPLES: [(&str, &str, &str); 2] = [
    ("phases/sim_ellipse_step.json", "ellipse", "l.sole"),
    (
        "phases/sim_double_circle_step.json",
        "double_circle",
        "l.heel",
    ),
];

fn load(phases: &str, foot: &str) -> (GaitModel, PhaseSequence) {
    let model = GaitModel::load(
        &root().join("models/opensim_subject01.json"),
        &root().join(format!("models/feet/{foot}.json")),
    )
    .unwrap();
    let seq = PhaseSequence::load(&root().join(phases)).unwrap();
    (model, seq)
}

/// Simulate `seq` as `footfall simulate` does by default: the initial state projected onto
/// the first phase's contacts, activations 0.01, excitations 0.025.
fn run(model: &GaitModel, seq: &PhaseSequence) -> (SimulationResult, Vec<ConstraintSet>) {
    let sets = seq.resolve(model, Path::new("<test>")).unwrap();
    let init = seq.initial_state.clone().unwrap();
    let theta = model.theta0();
    let (q, qd, gap) = model.project(&sets[0], &init.q, &init.qd, &theta).unwrap();
    assert!(gap < 1e-9);
    let mut x0 = q;
    x0.extend(qd);
    x0.extend(vec![0.01; model.na()]);
    let controls = ControlTable::constant(model.control_names(), vec![0.025; model.nu()]);
    let res = simulate(
        model,
        seq,
        &sets,
        &x0,
        &controls,
        &theta,
        &SimulationSettings::default(),
    )
    .unwrap();
    (res, sets)
}

/// The first phase of `seq` with its touchdown end removed and a fixed duration (s).
fn fixed_first_phase(seq: &mut PhaseSequence, seconds: f64) {
    match &mut seq.phases[0] {
        Phase::Continuous { duration, end, .. } => {
            *duration = Duration::Fixed(seconds);
            *end = None;
        }
        Phase::Impact { .. } => unreachable!(),
    }
}

#[test]
fn shipped_examples_land_on_the_ground() {
    for (phases, foot, landing) in EXAMPLES {
        let (model, seq) = load(phases, foot);
        let (res, sets) = run(&model, &seq);
        let span = &res.phases[0];
        let td = span
            .touchdown
            .as_ref()
            .expect("the swing ends at a touchdown");
        assert_eq!(td.contact, landing);
        assert!(td.landed, "{phases}: no touchdown");
        assert!(
            span.t1 > 0.1 && span.t1 < 0.5,
            "{phases}: touchdown at {} s",
            span.t1
        );
        let imp = &res.impacts[0];
        assert_eq!(imp.t, span.t1);
        let gap = imp
            .gaps
            .iter()
            .find(|(c, _)| c == landing)
            .expect("landing contact active after the impact")
            .1;
        let worst = imp.gaps.iter().fold(0.0f64, |m, (_, g)| m.max(g.abs()));
        eprintln!(
            "{phases}: touchdown at {:.6} s, landing gap {gap:.3e} m, worst gap {worst:.3e} m, max Baumgarte force {:.3e} N",
            span.t1,
            res.max_baumgarte_force(&sets)
        );
        assert!(
            worst < 1e-3,
            "{phases}: a contact is {worst} m from the ground at the impact"
        );
        // the root is located to a few ulp of t: the landing contact is on the ground
        assert!(gap.abs() < 1e-9, "{phases}: landing gap {gap} m");
        assert!(res.max_baumgarte_force(&sets) < 1e-3, "{phases}");
        let warnings = res.check(&model, &sets, &SanityTolerances::default());
        assert!(warnings.is_empty(), "{phases}: {warnings:?}");
    }
}

/// The case: a fixed 0.30 s swing puts the ellipse's sole 13.6 cm into the ground.
#[test]
fn a_fixed_swing_duration_lands_below_the_ground_and_is_reported() {
    let (model, mut seq) = load(EXAMPLES[0].0, EXAMPLES[0].1);
    fixed_first_phase(&mut seq, 0.3);
    let (res, sets) = run(&model, &seq);
    assert!(res.phases[0].touchdown.is_none());
    let w = res.check(&model, &sets, &SanityTolerances::default());
    for x in &w {
        eprintln!("{x}");
    }
    assert_eq!(w.len(), 2, "{w:?}");
    match &w[0] {
        SimulationWarning::LandingGap {
            phase,
            contact,
            t,
            gap_m,
            tolerance_m,
        } => {
            assert_eq!(
                (phase.as_str(), contact.as_str()),
                ("heel_strike_l", "l.sole")
            );
            assert!((t - 0.3).abs() < 1e-12);
            assert!((-0.14..-0.13).contains(gap_m), "{gap_m}");
            assert_eq!(*tolerance_m, 1e-3);
        }
        other => panic!("expected a landing gap, got {other:?}"),
    }
    match &w[1] {
        SimulationWarning::BaumgarteForce {
            phase,
            contact,
            row,
            force_n,
            ..
        } => {
            assert_eq!(
                (phase.as_str(), contact.as_str(), *row),
                ("double_stance", "l.sole", RowKind::Normal)
            );
            assert!(*force_n > 100.0, "{force_n}");
        }
        other => panic!("expected a Baumgarte force, got {other:?}"),
    }
    let msg = w[0].to_string();
    assert!(
        msg.contains("phase 'heel_strike_l'")
            && msg.contains("'l.sole'")
            && msg.contains("136.0 mm below"),
        "{msg}"
    );
    // looser tolerances silence them
    let loose = SanityTolerances {
        landing_gap_m: 0.2,
        baumgarte_force_n: 1e3,
    };
    assert!(res.check(&model, &sets, &loose).is_empty());
}

/// A swing whose longest duration ends before the touchdown says so, and the impact that
/// follows is away from the ground.
#[test]
fn a_touchdown_not_reached_is_reported() {
    let (model, mut seq) = load(EXAMPLES[1].0, EXAMPLES[1].1);
    if let Phase::Continuous { duration, .. } = &mut seq.phases[0] {
        *duration = Duration::Fixed(0.1);
    }
    let (res, sets) = run(&model, &seq);
    let td = res.phases[0].touchdown.as_ref().unwrap();
    assert!(!td.landed && td.gap_m > 1e-3, "{td:?}");
    assert!((res.phases[0].t1 - 0.1).abs() < 1e-12);
    let w = res.check(&model, &sets, &SanityTolerances::default());
    for x in &w {
        eprintln!("{x}");
    }
    assert!(
        matches!(&w[0], SimulationWarning::NoTouchdown { phase, contact, gap_m, .. }
            if phase == "single_stance_r" && contact == "l.heel" && *gap_m == td.gap_m),
        "{w:?}"
    );
    assert!(
        w.iter().any(
            |x| matches!(x, SimulationWarning::LandingGap { phase, contact, gap_m, .. }
            if phase == "heel_strike_l" && contact == "l.heel" && *gap_m > 1e-3)
        ),
        "{w:?}"
    );
}

#[test]
fn touchdown_end_names_a_known_contact_not_on_the_ground() {
    let (model, seq) = load(EXAMPLES[0].0, EXAMPLES[0].1);
    let p = Path::new("x.json");
    for (contact, expect) in [
        ("l.toe", "unknown contact 'l.toe'"),
        ("r.sole", "already on the ground"),
    ] {
        let mut bad = seq.clone();
        if let Phase::Continuous { end, .. } = &mut bad.phases[0] {
            end.as_mut().unwrap().touchdown = contact.into();
        }
        let e = bad.resolve(&model, p).unwrap_err().to_string();
        assert!(e.contains("end.touchdown") && e.contains(expect), "{e}");
    }
    // files without `end` load and write as before
    let walk = PhaseSequence::load(&root().join("phases/ellipse_walk.json")).unwrap();
    assert!(walk.phases.iter().all(|p| p.end().is_none()));
    assert!(!serde_json::to_string(&walk).unwrap().contains("\"end\""));
}

// ---------------------------------------------------------------------------------------
// The CLI

fn footfall(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_footfall"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("run footfall")
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn cli_shipped_examples_land_without_warnings() {
    let tmp = tempfile::tempdir().unwrap();
    for (phases, foot, landing) in EXAMPLES {
        let out = tmp.path().join(foot);
        let o = footfall(&[
            "simulate",
            "--phase-set",
            phases,
            "--foot",
            foot,
            "--out",
            out.to_str().unwrap(),
            "--strict",
        ]);
        let err = stderr(&o);
        assert!(o.status.success(), "{phases}: {err}");
        assert!(!err.contains("warning"), "{phases}: {err}");
        let s = summary(&out);
        assert_eq!(s["warnings"], serde_json::json!([]));
        assert_eq!(s["phases"][0]["touchdown"]["contact"], landing);
        assert_eq!(s["phases"][0]["touchdown"]["landed"], true);
        for g in s["impacts"][0]["gaps"].as_array().unwrap() {
            assert!(g[1].as_f64().unwrap().abs() < 1e-3, "{phases}: {g}");
        }
        assert!(s["max_baumgarte_force_n"].as_f64().unwrap() < 1e-3);
    }
}

/// The command with the swing's old fixed 0.30 s: a warning naming the phase, the
/// contact and the gap, exit 0; with `--strict`, exit 1 and no output folder.
#[test]
fn cli_warns_of_a_landing_below_the_ground_and_strict_refuses() {
    let tmp = tempfile::tempdir().unwrap();
    let phases = tmp.path().join("fixed.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root().join(EXAMPLES[0].0)).unwrap())
            .unwrap();
    v["phases"][0].as_object_mut().unwrap().remove("end");
    v["phases"][0]["duration"] = 0.3.into();
    std::fs::write(&phases, v.to_string()).unwrap();
    let out = tmp.path().join("run");
    let args = [
        "simulate",
        "--phase-set",
        phases.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];

    let o = footfall(&args);
    let err = stderr(&o);
    eprintln!("{err}");
    assert!(o.status.success(), "{err}");
    let line = err
        .lines()
        .find(|l| l.starts_with("warning: ") && l.contains("'l.sole'"))
        .unwrap_or_else(|| panic!("{err}"));
    for part in [
        "phase 'heel_strike_l'",
        "136.0 mm below the ground",
        "gap -136.0 mm",
    ] {
        assert!(line.contains(part), "{line}");
    }
    assert!(err.contains("warning: phase 'double_stance': contact 'l.sole' has a normal stabilisation (Baumgarte) force of 128."), "{err}");
    let s = summary(&out);
    let w = s["warnings"].as_array().unwrap();
    assert_eq!(w.len(), 2);
    assert_eq!(w[0]["kind"], "landing_gap");
    assert_eq!(w[0]["phase"], "heel_strike_l");
    assert_eq!(w[0]["contact"], "l.sole");
    assert!(w[0]["gap_m"].as_f64().unwrap() < -0.13);
    assert_eq!(w[1]["kind"], "baumgarte_force");

    std::fs::remove_dir_all(&out).unwrap();
    // --quiet: the refusal is then the only output
    let mut strict = args.to_vec();
    strict.extend(["--strict", "--quiet"]);
    let o = footfall(&strict);
    let err = stderr(&o);
    eprintln!("{err}");
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.starts_with("error: "), "{err}");
    for part in [
        "--strict",
        "phase 'heel_strike_l'",
        "'l.sole'",
        "136.0 mm below",
    ] {
        assert!(err.contains(part), "{err}");
    }
    assert!(!out.exists(), "an output folder was written");
    assert_eq!(
        entries(tmp.path()),
        ["fixed.json"],
        "something was left behind"
    );
}

/// A deliberately bad initial state: the pelvis 5 cm above its stance, not projected onto
/// the ground. The stabilisation pulls the right foot down with a large force, named.
#[test]
fn cli_warns_of_a_bad_initial_state_and_strict_refuses() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = PhaseSequence::load(&root().join(EXAMPLES[0].0)).unwrap();
    let mut init = seq.initial_state.unwrap();
    init.q[1] += 0.05;
    let initial = tmp.path().join("raised.json");
    std::fs::write(&initial, serde_json::to_string(&init).unwrap()).unwrap();
    let out = tmp.path().join("run");
    let mut args = vec![
        "simulate",
        "--phase-set",
        EXAMPLES[0].0,
        "--initial",
        initial.to_str().unwrap(),
        "--no-project",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = footfall(&args);
    let err = stderr(&o);
    eprintln!("{err}");
    assert!(o.status.success(), "{err}");
    assert!(
        err.lines().any(|l| l.starts_with("warning: phase 'single_stance_r': contact 'r.sole' has a normal stabilisation (Baumgarte) force of")),
        "{err}"
    );
    assert!(summary(&out)["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w["kind"] == "baumgarte_force"
            && w["phase"] == "single_stance_r"
            && w["contact"] == "r.sole"
            && w["force_n"].as_f64().unwrap() > 50.0));

    std::fs::remove_dir_all(&out).unwrap();
    args.extend(["--strict", "--quiet"]);
    let o = footfall(&args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with("error: ") && err.contains("phase 'single_stance_r': contact 'r.sole'"),
        "{err}"
    );
    assert!(!out.exists());
    assert_eq!(entries(tmp.path()), ["raised.json"]);
}
