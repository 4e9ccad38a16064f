//! Cart-pole swing-up and Kelly's five-link biped, defined exactly as in the CasADi peer's
//! problem files, solved by multiple shooting + SQP and compared with the peer's reference
//! optima; node defects re-integrated at 1e-12.

use footfall::integrate::{ControlShape, Integrator, IntegratorSettings, ShootingInterval};
use footfall::ocp::{Block, Transcription};
use footfall::problems::benchmarks::{read_problem_json, Benchmark};
use footfall::sqp::{self, HessianMode, Silent, SqpSettings, SqpStatus};

fn peer(name: &str) -> Option<serde_json::Value> {
    let p = crate::common::peer_dir().join("peer/problems").join(name);
    if !p.exists() {
        eprintln!("{} not found: skipped", p.display());
        return None;
    }
    Some(read_problem_json(&p).unwrap())
}

fn solve_and_check(
    file: &str,
    j_star: f64,
    hessian: HessianMode,
    max_iter: usize,
    require_kkt: bool,
) {
    let Some(json) = peer(file) else { return };
    let bench = Benchmark::from_json(json).unwrap();
    let ocp = bench
        .ocp(IntegratorSettings {
            method: footfall::integrate::Method::Adams,
            ..Default::default()
        })
        .unwrap();
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let settings = SqpSettings {
        tol_kkt: 1e-6,
        hessian,
        max_iter,
        ..Default::default()
    };
    let res = sqp::solve(&tr, &w0, &settings, &mut Silent);
    let rel = (res.objective - j_star).abs() / j_star;
    eprintln!(
        "{file}: {} after {} iterations in {:.3} s, J = {:.9} (reference {j_star}, rel {rel:.2e}), KKT {:.2e}",
        res.status,
        res.history.len() - 1,
        res.seconds,
        res.objective,
        res.kkt
    );
    if require_kkt {
        assert_eq!(res.status, SqpStatus::Converged);
        assert!(res.kkt <= 1e-6);
    }
    assert!(
        rel < 1e-5,
        "objective {} vs reference {j_star}",
        res.objective
    );
    // re-integrate every interval at 1e-12 from the solution's nodes
    let ph = &ocp.phases[0];
    let interval = ShootingInterval::new(ph.ode, ControlShape::Constant);
    let mut integ = Integrator::new(
        ph.ode.nx(),
        interval.np(),
        IntegratorSettings {
            rtol: 1e-12,
            atol: 1e-12,
            ..Default::default()
        },
    )
    .unwrap();
    let h = ph.duration.value / ph.intervals as f64;
    let mut worst = 0.0f64;
    for k in 0..ph.intervals {
        let x0 = &res.w[tr.range(Block::State { phase: 0, node: k })];
        let u = &res.w[tr.range(Block::Control { phase: 0, node: k })];
        let next = &res.w[tr.range(Block::State {
            phase: 0,
            node: k + 1,
        })];
        let mut p = Vec::new();
        interval.pack_params(u, None, h, &[], &mut p).unwrap();
        let mut x1 = vec![0.0; x0.len()];
        integ
            .integrate(&interval, 0.0, 1.0, x0, &p, &mut x1)
            .unwrap();
        worst = worst.max(
            x1.iter()
                .zip(next)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max),
        );
    }
    eprintln!("{file}: largest node defect re-integrated at 1e-12: {worst:.2e}");
    assert!(worst <= 1e-6);
}

/// Converges (KKT ≤ 1e-6) to the reference optimum, exact and Gauss–Newton Hessians.
#[test]
fn cartpole_matches_peer_optimum() {
    solve_and_check(
        "cartpole_swingup.json",
        76.665674185,
        HessianMode::Exact,
        60,
        true,
    );
    solve_and_check(
        "cartpole_swingup.json",
        76.665674185,
        HessianMode::GaussNewton,
        100,
        true,
    );
}

/// Converges (KKT ≤ 1e-6) to the reference optimum with the exact Hessian.
#[test]
fn five_link_biped_matches_peer_optimum() {
    solve_and_check(
        "five_link_biped.json",
        470.111267088,
        HessianMode::Exact,
        60,
        true,
    );
}

/// The structured Gauss–Newton + BFGS Hessian reaches the optimum's objective but its KKT
/// residual falls only linearly (5.5e-2 after 150 iterations): objective checked only.
#[test]
fn five_link_biped_structured_bfgs_reaches_the_objective() {
    solve_and_check(
        "five_link_biped.json",
        470.111267088,
        HessianMode::GaussNewtonBfgs,
        150,
        false,
    );
}
