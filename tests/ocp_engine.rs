//! Engine properties: results independent of the thread count (bit for bit), and a clear
//! 'infeasible' stop naming the violated constraints.

use footfall::integrate::{ControlShape, ControlledOde, IntegratorSettings, OdeError};
use footfall::ocp::{Block, Constraint, Ocp, Phase, PhaseDuration, Term, Transcription};
use footfall::problems::benchmarks::{read_problem_json, Benchmark};
use footfall::problems::Linear;
use footfall::sqp::{self, HessianMode, Silent, SqpResult, SqpSettings, SqpStatus};
use std::path::PathBuf;
use std::sync::Arc;

use crate::common;

fn solve_problem(file: &str, hessian: HessianMode, threads: usize) -> Option<SqpResult> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("problems")
        .join(file);
    let bench = Benchmark::from_json(read_problem_json(&p).unwrap()).unwrap();
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
        max_iter: 100,
        ..Default::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    Some(pool.install(|| sqp::solve(&tr, &w0, &settings, &mut Silent)))
}

#[test]
fn solution_is_bit_identical_with_one_and_two_threads() {
    for (file, hessian) in [
        ("cartpole_swingup.json", HessianMode::GaussNewton),
        ("five_link_biped.json", HessianMode::Exact),
    ] {
        let (Some(a), Some(b)) = (
            solve_problem(file, hessian, 1),
            solve_problem(file, hessian, 2),
        ) else {
            return;
        };
        assert_eq!(a.status, SqpStatus::Converged, "{file}");
        assert_eq!(a.history.len(), b.history.len(), "{file}");
        assert!(
            a.w.iter()
                .zip(&b.w)
                .all(|(x, y)| x.to_bits() == y.to_bits()),
            "{file}: solutions differ in some bit"
        );
        assert!(
            a.lambda
                .iter()
                .zip(&b.lambda)
                .all(|(x, y)| x.to_bits() == y.to_bits()),
            "{file}"
        );
        assert_eq!(a.objective.to_bits(), b.objective.to_bits(), "{file}");
    }
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
    fn f_jac(
        &self,
        x: &[f64],
        u: &[f64],
        t: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fu: &mut [f64],
        _: &mut [f64],
    ) -> Result<(), OdeError> {
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
            term: Term {
                name: "final_reach".into(),
                args: vec![Block::State { phase: 0, node: n }],
                f: Arc::new(Linear::new(vec![1.0], 1)),
            },
            lb: vec![3.0],
            ub: vec![inf],
        }],
        least_squares: vec![Term {
            name: "effort".into(),
            args: vec![Block::Control { phase: 0, node: 0 }],
            f: Arc::new(Linear::new(vec![1.0], 1)),
        }],
        samples: Vec::new(),
        checks: Vec::new(),
        costs: vec![],
        integrator: IntegratorSettings::default(),
    };
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let res = sqp::solve(&tr, &w0, &SqpSettings::default(), &mut Silent);
    eprintln!(
        "status: {}; most violated: {:?}",
        res.status, res.most_violated
    );
    assert_eq!(res.status, SqpStatus::Infeasible);
    let top = &res.most_violated[0];
    assert!(
        top.name.contains("phase 'reach'")
            && top.name.contains("node 10")
            && top.name.contains("final_reach"),
        "{}",
        top.name
    );
    assert!(
        (top.amount - 2.0).abs() < 1e-6,
        "the best reachable final state is 1, violation 2, got {}",
        top.amount
    );
}

/// The exact weighted Hessians of the biped's boundary terms match central differences
/// of their exact Jacobians.
#[test]
fn biped_term_hessians_match_finite_differences() {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("problems/five_link_biped.json");
    let bench = Benchmark::from_json(read_problem_json(&p).unwrap()).unwrap();
    let ocp = bench
        .ocp(IntegratorSettings {
            method: footfall::integrate::Method::Adams,
            ..Default::default()
        })
        .unwrap();
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    for name in ["periodicity", "step_length_height", "touchdown", "liftoff"] {
        let con = ocp
            .constraints
            .iter()
            .find(|c| c.term.name == name)
            .unwrap();
        let f = &con.term.f;
        assert!(f.has_hessian());
        let z: Vec<f64> = con
            .term
            .args
            .iter()
            .flat_map(|b| w0[tr.range(*b)].to_vec())
            .collect();
        let (d, nz) = (f.dim(), z.len());
        let wts: Vec<f64> = (0..d).map(|i| 0.3 + 0.1 * i as f64).collect();
        let mut h = vec![0.0; nz * nz];
        f.weighted_hessian(&z, &wts, &mut h).unwrap();
        let grad = |z: &[f64]| {
            let mut v = vec![0.0; d];
            let mut j = vec![0.0; d * nz];
            f.eval(z, &mut v, Some(&mut j)).unwrap();
            (0..nz)
                .map(|c| (0..d).map(|i| wts[i] * j[i + c * d]).sum::<f64>())
                .collect::<Vec<f64>>()
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

/// The exact interval curvature ∇²_z λᵀx(1) (second-order adjoint identity from forward
/// sensitivities) matches central differences of the exact gradient Sᵀλ, for the biped
/// and the cart-pole, constant and linear controls.
#[test]
fn interval_hessian_matches_finite_differences_of_sensitivities() {
    use footfall::integrate::ShootingInterval;
    use footfall::problems::benchmarks::{CartPole, FiveLinkBiped};
    let tight = IntegratorSettings {
        rtol: 1e-12,
        atol: 1e-12,
        ..Default::default()
    };
    let biped = FiveLinkBiped::default();
    let cart = CartPole::default();
    let cases: Vec<(&dyn ControlledOde, Vec<f64>, Vec<f64>, f64)> = vec![
        (
            &biped,
            vec![-0.3, 0.7, 0.0, -0.5, -0.6, 0.5, -0.4, 0.1, 0.3, -0.2],
            vec![0.0, 20.0, -10.0, 5.0, 3.0],
            0.0175,
        ),
        (&cart, vec![0.1, 0.5, 0.3, -1.0], vec![4.0], 0.05),
    ];
    for (ode, x0, u, h) in cases {
        for shape in [ControlShape::Constant, ControlShape::Linear] {
            let iv = ShootingInterval::new(ode, shape);
            let nx = ode.nx();
            let u1: Vec<f64> = u.iter().map(|v| 0.7 * v + 1.0).collect();
            let mut p = Vec::new();
            iv.pack_params(
                &u,
                (shape == ControlShape::Linear).then_some(&u1[..]),
                h,
                &[],
                &mut p,
            )
            .unwrap();
            let lambda: Vec<f64> = (0..nx).map(|i| 0.5 - 0.13 * i as f64).collect();
            let (worst, scale, _) =
                common::interval_curvature_fd_error(&iv, &x0, &p, &lambda, tight.clone(), 1e-5);
            eprintln!("nx {nx} {shape:?}: interval Hessian vs FD relative error {worst:.2e} (scale {scale:.2e})");
            assert!(
                worst < 1e-5,
                "interval Hessian differs from FD by {worst:e}"
            );
        }
    }
}

/// ∫ u² dt as a quadrature state gives the same cart-pole optimum as the node-wise
/// least-squares form h Σ u_k² (exact for piecewise-constant u).
#[test]
fn integrated_cost_by_quadrature_state_matches_the_least_squares_form() {
    use footfall::ocp::{quadrature_cost, Integrand, TermError, WithQuadrature};
    struct USquared;
    impl Integrand for USquared {
        fn dim(&self) -> usize {
            1
        }
        fn eval(
            &self,
            _x: &[f64],
            u: &[f64],
            _t: &[f64],
            v: &mut [f64],
            jac: Option<&mut [f64]>,
        ) -> Result<(), TermError> {
            v[0] = u[0] * u[0];
            if let Some(j) = jac {
                j.iter_mut().for_each(|x| *x = 0.0);
                j[4] = 2.0 * u[0];
            }
            Ok(())
        }
        fn weighted_hessian(
            &self,
            _x: &[f64],
            _u: &[f64],
            _t: &[f64],
            w: &[f64],
            out: &mut [f64],
        ) -> Result<bool, TermError> {
            out.iter_mut().for_each(|x| *x = 0.0);
            out[4 + 4 * 5] = 2.0 * w[0];
            Ok(true)
        }
    }
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("problems/cartpole_swingup.json");
    let bench = Benchmark::from_json(read_problem_json(&p).unwrap()).unwrap();
    let settings = IntegratorSettings {
        method: footfall::integrate::Method::Adams,
        ..Default::default()
    };
    let base = bench.ocp(settings.clone()).unwrap();
    let integrand = USquared;
    let ext = WithQuadrature {
        ode: base.phases[0].ode,
        integrand: &integrand,
    };
    let ph = &base.phases[0];
    let n = ph.intervals;
    let grow = |rows: &Vec<Vec<f64>>, v: f64| {
        rows.iter()
            .map(|r| r.iter().copied().chain([v]).collect())
            .collect::<Vec<Vec<f64>>>()
    };
    let mut x_lb = grow(&ph.x_lb, f64::NEG_INFINITY);
    let mut x_ub = grow(&ph.x_ub, f64::INFINITY);
    x_lb[0][4] = 0.0;
    x_ub[0][4] = 0.0;
    let ocp = Ocp {
        phases: vec![Phase {
            name: ph.name.clone(),
            ode: &ext,
            intervals: n,
            duration: ph.duration,
            controls: ph.controls,
            x_lb,
            x_ub,
            u_lb: ph.u_lb.clone(),
            u_ub: ph.u_ub.clone(),
            x_guess: grow(&ph.x_guess, 0.0),
            u_guess: ph.u_guess.clone(),
        }],
        transitions: vec![],
        ntheta: 0,
        theta_guess: vec![],
        theta_lb: vec![],
        theta_ub: vec![],
        constraints: vec![],
        least_squares: vec![],
        samples: Vec::new(),
        checks: Vec::new(),
        costs: vec![quadrature_cost(0, n, 4, 1)],
        integrator: settings,
    };
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let res = sqp::solve(
        &tr,
        &w0,
        &SqpSettings {
            tol_kkt: 1e-6,
            hessian: HessianMode::Exact,
            ..Default::default()
        },
        &mut Silent,
    );
    eprintln!(
        "quadrature cost: {} after {} iterations, J = {:.9}",
        res.status,
        res.history.len() - 1,
        res.objective
    );
    assert_eq!(res.status, SqpStatus::Converged);
    assert!(
        (res.objective - 76.665674185).abs() / 76.665674185 < 1e-5,
        "J = {}",
        res.objective
    );
}
