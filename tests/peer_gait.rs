//! The CasADi gait peer's tracking problem (`problems/peer_gait_track_ellipse.json`),
//! transcribed from its file and solved from its data guess; the peer's optimum
//! J* = 1.2584987 (IPOPT, multiple shooting with the exact Hessian, and collocation with
//! two elements per interval, agreeing to 1e-6) is the independent truth.

use footfall::integrate::IntegratorSettings;
use footfall::ocp::{Block, Transcription};
use footfall::problems::benchmarks::Benchmark;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The peer's optimum of this problem.
const J_STAR: f64 = 1.2584987;

fn bench() -> Benchmark {
    Benchmark::load(&root().join("problems/peer_gait_track_ellipse.json")).unwrap()
}

/// The peer's solution (node states and torques per phase) as our variables.
fn peer_solution(tr: &Transcription, file: &str) -> Option<Vec<f64>> {
    let p = crate::common::peer_dir()
        .join("peer_gait/results")
        .join(file);
    if !p.exists() {
        eprintln!("{} not found: skipped", p.display());
        return None;
    }
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
    let (_, _, mut w) = tr.variable_bounds_and_guess();
    for (j, ph) in v["solution"]["phases"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
    {
        for (k, x) in ph["X"].as_array().unwrap().iter().enumerate() {
            let r = tr.range(Block::State { phase: j, node: k });
            for (i, xi) in x.as_array().unwrap().iter().enumerate() {
                w[r.start + i] = xi.as_f64().unwrap();
            }
        }
        for (k, u) in ph["tau"].as_array().unwrap().iter().enumerate() {
            let r = tr.range(Block::Control { phase: j, node: k });
            for (i, ui) in u.as_array().unwrap().iter().enumerate() {
                w[r.start + i] = ui.as_f64().unwrap() / 100.0;
            }
        }
    }
    Some(w)
}

#[test]
fn the_peers_optimum_has_the_peers_objective_in_our_transcription() {
    let b = bench();
    b.with_ocp(IntegratorSettings::default(), |ocp| {
        let tr = Transcription::new(ocp).unwrap();
        let Some(w) = peer_solution(&tr, "ms_exact.json") else {
            return;
        };
        let ev = tr.evaluate(&w, false).unwrap();
        let (lb, ub) = tr.constraint_bounds();
        let mut worst = (0.0f64, 0usize);
        for (i, c) in ev.c.iter().enumerate() {
            let v = (lb[i] - c).max(c - ub[i]).max(0.0);
            if v > worst.0 {
                worst = (v, i);
            }
        }
        eprintln!(
            "J at the peer's optimum {:.9}, infeasibility {:.2e} at {:?}",
            ev.f,
            worst.0,
            tr.labels()[worst.1]
        );
        assert!((ev.f - J_STAR).abs() < 1e-4 * J_STAR, "J = {}", ev.f);
    })
    .unwrap();
}

/// Solved from the data guess as `footfall solve` does it (block BFGS, then the exact
/// Hessian with CVODES at 1e-12), the optimum is the peer's: J* to 1e-4 (relative), node
/// states and torques close to the peer's exact-Hessian solution, valid on the 1 ms
/// re-integration (no pulling ground, no broken cone, no foot in the floor), with the
/// peer's peak normal forces and landing impulses.
#[test]
fn the_peers_gait_problem_is_solved_from_its_data_guess() {
    use footfall::problems::evaluation::GaitSolution;
    use footfall::problems::peer_gait::stages;
    use footfall::problems::validity::{self, ValidityLimits};
    use footfall::sqp::{self, Silent, SqpStatus};
    let b = bench();
    let Benchmark::GaitTrack(g) = &b else {
        panic!("not the gait problem")
    };
    let [first, second] = stages(1e-6);
    let r1 = b
        .with_ocp(first.integrator.clone(), |ocp| {
            let tr = Transcription::new(ocp).unwrap();
            let (_, _, w0) = tr.variable_bounds_and_guess();
            sqp::solve(&tr, &w0, &first.settings, &mut Silent)
        })
        .unwrap();
    eprintln!(
        "stage 1 (block BFGS): {:?}, {} iterations, {:.1} s, J = {:.9}, KKT {:.1e}",
        r1.status,
        r1.history.len() - 1,
        r1.seconds,
        r1.objective,
        r1.kkt
    );
    assert_eq!(r1.status, SqpStatus::Converged, "stage 1");
    b.with_ocp(second.integrator.clone(), |ocp| {
        let tr = Transcription::new(ocp).unwrap();
        let r2 = sqp::solve(&tr, &r1.w, &second.settings, &mut Silent);
        eprintln!(
            "stage 2 (exact Hessian): {:?}, {} iterations, {:.1} s, J = {:.9}, KKT {:.1e}",
            r2.status,
            r2.history.len() - 1,
            r2.seconds,
            r2.objective,
            r2.kkt
        );
        assert_eq!(r2.status, SqpStatus::Converged, "stage 2");
        assert!(r2.kkt <= 1e-6);
        assert!(
            (r2.objective - J_STAR).abs() < 1e-4 * J_STAR,
            "J = {}",
            r2.objective
        );

        // the same optimum as the peer's, node by node
        if let Some(peer) = peer_solution(&tr, "ms_exact.json") {
            let (mut dq, mut dtau) = (0.0f64, 0.0f64);
            for (j, ph) in ocp.phases.iter().enumerate() {
                for k in 0..=ph.intervals {
                    let r = tr.range(Block::State { phase: j, node: k });
                    let q = r.start..r.start + 9;
                    for (a, b) in r2.w[q.clone()].iter().zip(&peer[q]) {
                        dq = dq.max((a - b).abs());
                    }
                }
                for k in 0..ph.intervals {
                    let r = tr.range(Block::Control { phase: j, node: k });
                    for i in r {
                        dtau = dtau.max(100.0 * (r2.w[i] - peer[i]).abs());
                    }
                }
            }
            eprintln!("largest difference to the peer's solution: q {dq:.2e} (m, rad), τ {dtau:.2e} N·m");
            assert!(dq < 1e-3 && dtau < 1.0, "q {dq:e}, τ {dtau:e}");
        }

        // the 1 ms re-integration of every interval from its node
        let continuous: Vec<usize> = g
            .seq
            .phases
            .iter()
            .enumerate()
            .filter(|(_, p)| matches!(p, footfall::phases::Phase::Continuous { .. }))
            .map(|(i, _)| i)
            .collect();
        let sol = GaitSolution::from_nlp(&tr, &r2.w, &continuous, 0.61818);
        let re = sol
            .reintegrate(&g.model, &g.sets, 1e-3, &IntegratorSettings::default())
            .unwrap();
        let names: Vec<String> = g.seq.phases.iter().map(|p| p.name().to_string()).collect();
        let v = validity::check(
            &g.model,
            &re.result.samples,
            &g.sets,
            &names,
            &sol.theta,
            0.8,
            ValidityLimits::default(),
        );
        assert!(v.is_valid(), "{:?}", v.violations);
        let fig = re.figures(&g.sets, 1e-3);
        eprintln!(
            "1 ms: {} samples, largest defect {:.1e}, peak normal force {:.1} N right, {:.1} N left (peer 908.9, 894.9)",
            re.result.samples.len(),
            re.max_defect,
            fig.peak_normal_force_n[0],
            fig.peak_normal_force_n[1]
        );
        assert!(re.max_defect < 1e-5, "defect {}", re.max_defect);
        for (got, peer) in fig.peak_normal_force_n.iter().zip([908.93, 894.91]) {
            assert!((got - peer).abs() < 0.01 * peer, "peak {got} N, peer {peer} N");
        }
    })
    .unwrap();
}
