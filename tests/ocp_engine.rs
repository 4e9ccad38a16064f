//! Engine properties: results independent of the thread count (bit for bit), and a clear
//! 'infeasible' stop naming the violated constraints.

use footfall::benchmarks::read_problem_json;
use footfall::integrate::{ControlShape, ControlledOde, IntegratorSettings, OdeError};
use footfall::ocp::{Block, Constraint, Ocp, Phase, PhaseDuration, Term, Transcription};
use footfall::problems::benchmark::Benchmark;
use footfall::problems::Linear;
use footfall::sqp::{self, HessianMode, Silent, SqpResult, SqpSettings, SqpStatus};
use std::path::PathBuf;
use std::sync::Arc;

fn solve_cartpole(threads: usize) -> Option<SqpResult> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/peer/problems/cartpole_swingup.json");
    if !p.exists() {
        eprintln!("{} not found: skipped", p.display());
        return None;
    }
    let bench = Benchmark::from_json(read_problem_json(&p).unwrap()).unwrap();
    let ocp = bench.ocp(IntegratorSettings::default()).unwrap();
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let settings = SqpSettings { tol_kkt: 1e-6, hessian: HessianMode::GaussNewton, max_iter: 100, ..Default::default() };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    Some(pool.install(|| sqp::solve(&tr, &w0, &settings, &mut Silent)))
}

#[test]
fn solution_is_bit_identical_with_one_and_two_threads() {
    let (Some(a), Some(b)) = (solve_cartpole(1), solve_cartpole(2)) else { return };
    assert_eq!(a.status, SqpStatus::Converged);
    assert_eq!(a.history.len(), b.history.len());
    assert!(a.w.iter().zip(&b.w).all(|(x, y)| x.to_bits() == y.to_bits()), "solutions differ in some bit");
    assert!(a.lambda.iter().zip(&b.lambda).all(|(x, y)| x.to_bits() == y.to_bits()));
    assert_eq!(a.objective.to_bits(), b.objective.to_bits());
}

/// ẋ = u on one state.
struct Integrator1;
impl ControlledOde for Integrator1 {
    fn nx(&self) -> usize {
        1
    }
    fn nu(&self) -> usize {
        1
    }
    fn ntheta(&self) -> usize {
        0
    }
    fn f(&self, _: &[f64], u: &[f64], _: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        xdot[0] = u[0];
        Ok(())
    }
    fn f_jac(&self, x: &[f64], u: &[f64], t: &[f64], xdot: &mut [f64], fx: &mut [f64], fu: &mut [f64], _: &mut [f64]) -> Result<(), OdeError> {
        self.f(x, u, t, xdot)?;
        fx[0] = 0.0;
        fu[0] = 1.0;
        Ok(())
    }
}

/// Start at 0, |u| ≤ 1 for 1 s (reachable: x ≤ 1), but the final state must be ≥ 3.
#[test]
fn infeasible_problem_stops_as_infeasible_and_names_the_constraint() {
    let ode = Integrator1;
    let n = 10;
    let inf = f64::INFINITY;
    let mut x_lb = vec![vec![-inf]; n + 1];
    let mut x_ub = vec![vec![inf]; n + 1];
    x_lb[0] = vec![0.0];
    x_ub[0] = vec![0.0];
    let ocp = Ocp {
        phases: vec![Phase {
            name: "reach".into(),
            ode: &ode,
            intervals: n,
            duration: PhaseDuration::fixed(1.0),
            controls: ControlShape::Constant,
            x_lb,
            x_ub,
            u_lb: vec![vec![-1.0]; n],
            u_ub: vec![vec![1.0]; n],
            x_guess: vec![vec![0.0]; n + 1],
            u_guess: vec![vec![0.0]; n],
        }],
        transitions: vec![],
        ntheta: 0,
        theta_guess: vec![],
        theta_lb: vec![],
        theta_ub: vec![],
        constraints: vec![Constraint {
            term: Term { name: "final_reach".into(), args: vec![Block::State { phase: 0, node: n }], f: Arc::new(Linear::new(vec![1.0], 1)) },
            lb: vec![3.0],
            ub: vec![inf],
        }],
        least_squares: vec![Term {
            name: "effort".into(),
            args: vec![Block::Control { phase: 0, node: 0 }],
            f: Arc::new(Linear::new(vec![1.0], 1)),
        }],
        costs: vec![],
        integrator: IntegratorSettings::default(),
    };
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let res = sqp::solve(&tr, &w0, &SqpSettings::default(), &mut Silent);
    eprintln!("status: {}; most violated: {:?}", res.status, res.most_violated);
    assert_eq!(res.status, SqpStatus::Infeasible);
    let top = &res.most_violated[0];
    assert!(top.name.contains("phase 'reach'") && top.name.contains("node 10") && top.name.contains("final_reach"), "{}", top.name);
    assert!((top.amount - 2.0).abs() < 1e-6, "the best reachable final state is 1, violation 2, got {}", top.amount);
}

/// The exact weighted Hessians of the biped's boundary terms match central differences
/// of their exact Jacobians.
#[test]
fn biped_term_hessians_match_finite_differences() {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("problems/five_link_biped.json");
    let bench = Benchmark::from_json(read_problem_json(&p).unwrap()).unwrap();
    let ocp = bench.ocp(IntegratorSettings::default()).unwrap();
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    for name in ["periodicity", "step_length_height", "touchdown", "liftoff"] {
        let con = ocp.constraints.iter().find(|c| c.term.name == name).unwrap();
        let f = &con.term.f;
        assert!(f.has_hessian());
        let z: Vec<f64> = con.term.args.iter().flat_map(|b| w0[tr.range(*b)].to_vec()).collect();
        let (d, nz) = (f.dim(), z.len());
        let wts: Vec<f64> = (0..d).map(|i| 0.3 + 0.1 * i as f64).collect();
        let mut h = vec![0.0; nz * nz];
        f.weighted_hessian(&z, &wts, &mut h).unwrap();
        let grad = |z: &[f64]| {
            let mut v = vec![0.0; d];
            let mut j = vec![0.0; d * nz];
            f.eval(z, &mut v, Some(&mut j)).unwrap();
            (0..nz).map(|c| (0..d).map(|i| wts[i] * j[i + c * d]).sum::<f64>()).collect::<Vec<f64>>()
        };
        let mut worst = 0.0f64;
        for c in 0..nz {
            let e = 1e-6;
            let mut zp = z.clone();
            zp[c] += e;
            let mut zm = z.clone();
            zm[c] -= e;
            let (gp, gm) = (grad(&zp), grad(&zm));
            for r in 0..nz {
                worst = worst.max(((gp[r] - gm[r]) / (2.0 * e) - h[r + c * nz]).abs());
            }
        }
        assert!(worst < 1e-6, "{name}: Hessian differs from FD by {worst:e}");
    }
}
