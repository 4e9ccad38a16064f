//! The walking cycle as an OCP: the seed's phase graphs load, validate and transcribe;
//! their constraint functions have exact Jacobians; invalid graphs are refused with a
//! message naming the phase.

use crate::common;
use common::*;
use footfall::integrate::IntegratorSettings;
use footfall::model::GaitModel;
use footfall::ocp::Transcription;
use footfall::phases::PhaseSequence;
use footfall::problems::gait::{GaitCycle, GaitGuess};
use std::path::Path;

fn guess(m: &GaitModel, seq: &PhaseSequence, sets: &[footfall::model::ConstraintSet]) -> GaitGuess {
    let q = [0.0, 0.95, 0.1, 0.2, -0.2, 0.0, -0.3, -0.3, 0.1];
    let qd = [1.1, 0.0, 0.0, 0.5, -0.5, 0.2, -0.5, 0.3, 0.1];
    let (mut x, mut u) = (Vec::new(), Vec::new());
    for (i, ph) in seq.phases.iter().enumerate() {
        if let footfall::phases::Phase::Continuous { intervals, .. } = ph {
            let (qp, qdp, _) = m.project(&sets[i], &q, &qd, &m.theta0()).unwrap();
            let mut xs = qp.clone();
            xs.extend(qdp);
            xs.extend(vec![0.01; m.na()]);
            x.push(vec![xs; intervals + 1]);
            u.push(vec![vec![0.025; m.nu()]; intervals + 1]);
        }
    }
    let inf = f64::INFINITY;
    let mut x_lb = vec![-inf; m.nx()];
    let mut x_ub = vec![inf; m.nx()];
    for i in 2 * m.nq()..m.nx() {
        x_lb[i] = 0.0;
        x_ub[i] = 1.0;
    }
    GaitGuess {
        x,
        u,
        x_lb,
        x_ub,
        u_lb: vec![0.0; m.nu()],
        u_ub: vec![1.0; m.nu()],
    }
}

#[test]
fn seed_phase_graphs_transcribe_with_the_seed_interval_counts() {
    // the continuous phases an impact starts: 2e after 1e*; 2c after 1c*, 4c after 3c*
    for (foot, phases, intervals, n_cont, after_impact) in [
        ("ellipse.json", "phases/ellipse_walk.json", 25, 2, &[0][..]),
        (
            "double_circle.json",
            "phases/double_circle_walk.json",
            31,
            4,
            &[0, 1][..],
        ),
    ] {
        let m = model("opensim_subject01.json", foot);
        let p = path(phases);
        let seq = PhaseSequence::load(&p).unwrap();
        let sets = seq.resolve(&m, &p).unwrap();
        let cycle = GaitCycle::new(&m, &seq, &sets).unwrap();
        assert_eq!(cycle.continuous.len(), n_cont);
        let sites: Vec<(usize, usize, f64)> =
            after_impact.iter().map(|&j| (j, 0, 1.0 / 3.0)).collect();
        assert_eq!(seq.impact_sites(), sites, "{phases}");
        let g = guess(&m, &seq, &sets);
        let ocp = cycle.ocp(&g, IntegratorSettings::default()).unwrap();
        let total: usize = ocp.phases.iter().map(|p| p.intervals).sum();
        assert_eq!(total, intervals, "{phases}");
        let tr = Transcription::new(&ocp).unwrap();
        let (_, _, w0) = tr.variable_bounds_and_guess();
        let ev = tr.evaluate(&w0, false).unwrap();
        assert!(ev.c.iter().all(|v| v.is_finite()));
        let names: Vec<String> = ocp
            .constraints
            .iter()
            .map(|c| c.term.name.clone())
            .collect();
        for must in ["contact_forces", "periodicity", "control_periodicity"] {
            assert!(
                names.iter().any(|n| n == must),
                "{phases}: no '{must}' constraint"
            );
        }
        assert!(
            names.iter().any(|n| n.starts_with("clearance(")),
            "{phases}: no clearance"
        );
        // periodic through the trailing impact: the landing row puts the first node's
        // feet on the ground, so it has no on-ground rows that would repeat it
        assert!(
            !names.iter().any(|n| n.starts_with("on_ground(")),
            "{phases}: on-ground rows repeat the landing row"
        );
        assert!(
            names.iter().any(|n| n.starts_with("landing(")),
            "{phases}: no landing constraint"
        );
        eprintln!(
            "{phases}: {} variables, {} constraints, {} intervals",
            tr.n(),
            tr.m(),
            total
        );
    }
}

/// Every gait constraint function's Jacobian against central differences.
#[test]
fn gait_constraint_jacobians_match_finite_differences() {
    let m = model_with_effects(
        "opensim_subject01.json",
        "double_circle.json",
        serde_json::json!([{ "type": "passive_joint_stiffness", "joint": "ankle", "stiffness": 30.0, "free": ["stiffness"] }]),
    );
    let p = path("phases/double_circle_walk.json");
    let seq = PhaseSequence::load(&p).unwrap();
    let sets = seq.resolve(&m, &p).unwrap();
    let cycle = GaitCycle::new(&m, &seq, &sets).unwrap();
    let g = guess(&m, &seq, &sets);
    let ocp = cycle.ocp(&g, IntegratorSettings::default()).unwrap();
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, mut w0) = tr.variable_bounds_and_guess();
    let mut rng = Rng::new(9);
    for v in w0.iter_mut() {
        *v += rng.uniform(-0.02, 0.02);
    }
    let mut seen = std::collections::BTreeSet::new();
    let mut cons: Vec<footfall::ocp::Constraint> = ocp.constraints.clone();
    // the mid-cycle impact 3c* as a transition, and the whole-cycle targets
    for tr_term in ocp.transitions.iter().flatten() {
        cons.push(footfall::ocp::Constraint {
            term: tr_term.clone(),
            lb: vec![],
            ub: vec![],
        });
    }
    cons.extend(cycle.step_constraints(&ocp, Some(0.6), Some(1.13)));
    for con in &cons {
        let kind = con.term.name.split('(').next().unwrap().to_string();
        if !seen.insert(kind.clone()) {
            continue;
        }
        let f = &con.term.f;
        let z: Vec<f64> = con
            .term
            .args
            .iter()
            .flat_map(|b| w0[tr.range(*b)].to_vec())
            .collect();
        let (d, nz) = (f.dim(), z.len());
        let mut v = vec![0.0; d];
        let mut jac = vec![0.0; d * nz];
        f.eval(&z, &mut v, Some(&mut jac)).unwrap();
        let scale = v.iter().map(|x| x.abs()).fold(1.0, f64::max);
        let mut worst = 0.0f64;
        for c in 0..nz {
            let h = 1e-6 * z[c].abs().max(1.0);
            let (mut zp, mut zm) = (z.clone(), z.clone());
            zp[c] += h;
            zm[c] -= h;
            let (mut vp, mut vm) = (vec![0.0; d], vec![0.0; d]);
            f.eval(&zp, &mut vp, None).unwrap();
            f.eval(&zm, &mut vm, None).unwrap();
            for r in 0..d {
                worst = worst.max(((vp[r] - vm[r]) / (2.0 * h) - jac[r + c * d]).abs() / scale);
            }
        }
        eprintln!("{kind}: Jacobian vs FD {worst:.2e}");
        assert!(
            worst < 1e-5,
            "{kind}: Jacobian differs from FD by {worst:e}"
        );
    }
    // every kind of row of a periodic cycle (its first node has no on-ground rows: the
    // periodic landing puts its feet on the ground)
    assert!(seen.len() >= 8, "checked {seen:?}");
}

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn invalid_gait_graphs_are_refused_naming_the_phase() {
    let d = tempfile::tempdir().unwrap();
    let m = model("opensim_subject01.json", "double_circle.json");
    // both circles of one foot rolling: four rows on a 3-DoF foot
    let p = write(
        d.path(),
        "over.json",
        r#"{ "name": "over", "phases": [ { "type": "continuous", "name": "flat", "intervals": 4, "duration": 0.2,
             "contacts": [ { "contact": "l.heel" }, { "contact": "l.forefoot" } ] } ] }"#,
    );
    let seq = PhaseSequence::load(&p).unwrap();
    let e = seq.resolve(&m, &p).unwrap_err().to_string();
    assert!(
        e.contains("'flat'") && e.contains("over-constrains") && e.contains("rolling"),
        "{e}"
    );
    // a symmetry map naming a coordinate twice
    let p = write(
        d.path(),
        "sym.json",
        r#"{ "name": "sym", "phases": [ { "type": "continuous", "name": "a", "intervals": 4, "duration": 0.2, "contacts": [] } ],
             "gait": { "symmetry": [ ["hip_r", "hip_l"], ["hip_r", "knee_l"] ] } }"#,
    );
    let e = PhaseSequence::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("gait.symmetry[1]") && e.contains("permutation"),
        "{e}"
    );
    // a symmetry map naming something that is not a leg coordinate
    let p = write(
        d.path(),
        "sym2.json",
        r#"{ "name": "sym", "phases": [ { "type": "continuous", "name": "a", "intervals": 4, "duration": 0.2, "contacts": [] } ],
             "gait": { "symmetry": [ ["hip_r", "elbow_l"] ] } }"#,
    );
    let e = PhaseSequence::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("elbow_l") && e.contains("not a leg coordinate"),
        "{e}"
    );
    // zero intervals and unknown contacts are refused by the phase reader (tests/bad_input.rs)
}
