//! A linear-quadratic OCP through the full multiple-shooting + SQP path against the
//! discrete Riccati solution of the exactly discretised system.

use footfall::integrate::{ControlShape, ControlledOde, IntegratorSettings, OdeError};
use footfall::ocp::{
    Block, NodeFunction, Ocp, Phase, PhaseDuration, Term, TermError, Transcription,
};
use footfall::sqp::{self, HessianMode, Silent, SqpSettings, SqpStatus};
use nalgebra::{DMatrix, DVector};
use std::sync::Arc;

const A: [[f64; 2]; 2] = [[0.0, 1.0], [-1.0, -0.2]];
const B: [f64; 2] = [0.0, 1.0];

struct Linear;
impl ControlledOde for Linear {
    fn nx(&self) -> usize {
        2
    }
    fn nu(&self) -> usize {
        1
    }
    fn ntheta(&self) -> usize {
        0
    }
    fn f(&self, x: &[f64], u: &[f64], _: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        for i in 0..2 {
            xdot[i] = A[i][0] * x[0] + A[i][1] * x[1] + B[i] * u[0];
        }
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
        for i in 0..2 {
            for j in 0..2 {
                fx[i + 2 * j] = A[i][j];
            }
            fu[i] = B[i];
        }
        Ok(())
    }
}

/// r = diag(w) z
struct Weighted(Vec<f64>);
impl NodeFunction for Weighted {
    fn dim(&self) -> usize {
        self.0.len()
    }
    fn eval(&self, z: &[f64], v: &mut [f64], jac: Option<&mut [f64]>) -> Result<(), TermError> {
        let d = self.0.len();
        for i in 0..d {
            v[i] = self.0[i] * z[i];
        }
        if let Some(j) = jac {
            j.iter_mut().for_each(|x| *x = 0.0);
            for i in 0..d {
                j[i + i * d] = self.0[i];
            }
        }
        Ok(())
    }
}

#[test]
fn lq_problem_matches_discrete_riccati() {
    let (n_int, horizon) = (20usize, 2.0);
    let h = horizon / n_int as f64;
    let (q, r, qf): ([f64; 2], f64, [f64; 2]) = ([1.0, 0.5], 0.1, [5.0, 2.0]);
    let x0 = [1.0, 0.0];
    let ode = Linear;
    let inf = f64::INFINITY;
    let mut x_lb = vec![vec![-inf; 2]; n_int + 1];
    let mut x_ub = vec![vec![inf; 2]; n_int + 1];
    x_lb[0] = x0.to_vec();
    x_ub[0] = x0.to_vec();
    let phase = Phase {
        name: "lq".into(),
        ode: &ode,
        intervals: n_int,
        duration: PhaseDuration::fixed(horizon),
        controls: ControlShape::Constant,
        x_lb,
        x_ub,
        u_lb: vec![vec![-inf]; n_int],
        u_ub: vec![vec![inf]; n_int],
        x_guess: vec![vec![0.0; 2]; n_int + 1],
        u_guess: vec![vec![0.0]; n_int],
    };
    let stage = Arc::new(Weighted(vec![q[0].sqrt(), q[1].sqrt(), r.sqrt()]));
    let mut ls: Vec<Term> = (0..n_int)
        .map(|k| Term {
            name: "stage".into(),
            args: vec![
                Block::State { phase: 0, node: k },
                Block::Control { phase: 0, node: k },
            ],
            f: stage.clone(),
        })
        .collect();
    ls.push(Term {
        name: "terminal".into(),
        args: vec![Block::State {
            phase: 0,
            node: n_int,
        }],
        f: Arc::new(Weighted(vec![qf[0].sqrt(), qf[1].sqrt()])),
    });
    let ocp = Ocp {
        phases: vec![phase],
        transitions: vec![],
        ntheta: 0,
        theta_guess: vec![],
        theta_lb: vec![],
        theta_ub: vec![],
        constraints: vec![],
        least_squares: ls,
        samples: Vec::new(),
        checks: Vec::new(),
        costs: vec![],
        integrator: IntegratorSettings {
            rtol: 1e-12,
            atol: 1e-12,
            ..Default::default()
        },
    };
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let settings = SqpSettings {
        tol_kkt: 1e-9,
        hessian: HessianMode::GaussNewton,
        ..Default::default()
    };
    let res = sqp::solve(&tr, &w0, &settings, &mut Silent);
    assert_eq!(res.status, SqpStatus::Converged, "{res:?}");

    // discrete Riccati on the exact discretisation exp([[A, B], [0, 0]] h)
    let mut aug = DMatrix::<f64>::zeros(3, 3);
    for i in 0..2 {
        for j in 0..2 {
            aug[(i, j)] = A[i][j] * h;
        }
        aug[(i, 2)] = B[i] * h;
    }
    let e = aug.exp();
    let ad = e.view((0, 0), (2, 2)).into_owned();
    let bd = e.view((0, 2), (2, 1)).into_owned();
    let qm = DMatrix::from_diagonal(&DVector::from_vec(q.to_vec()));
    let rm = DMatrix::from_element(1, 1, r);
    let mut p = DMatrix::from_diagonal(&DVector::from_vec(qf.to_vec()));
    let mut gains = vec![DMatrix::zeros(1, 2); n_int];
    for k in (0..n_int).rev() {
        let btp = bd.transpose() * &p;
        let k_gain = (&rm + &btp * &bd).try_inverse().unwrap() * &btp * &ad;
        p = &qm + ad.transpose() * &p * &ad - ad.transpose() * &p * &bd * &k_gain;
        gains[k] = k_gain;
    }
    let x0v = DVector::from_vec(x0.to_vec());
    let j_star = (x0v.transpose() * &p * &x0v)[(0, 0)];
    let rel = (res.objective - j_star).abs() / j_star;
    eprintln!(
        "LQ: J = {:.12} vs Riccati {:.12} (rel {rel:.2e}), {} SQP iterations",
        res.objective,
        j_star,
        res.history.len() - 1
    );
    assert!(rel < 1e-8, "objective differs by {rel:e}");
    let mut x = x0v;
    for (k, gain) in gains.iter().enumerate() {
        let sx = &res.w[tr.range(Block::State { phase: 0, node: k })];
        for i in 0..2 {
            assert!(
                (sx[i] - x[i]).abs() < 1e-6,
                "state {i} at node {k}: {} vs {}",
                sx[i],
                x[i]
            );
        }
        let u = -(gain * &x)[(0, 0)];
        let su = res.w[tr.range(Block::Control { phase: 0, node: k })][0];
        assert!((su - u).abs() < 1e-6, "control at {k}: {su} vs {u}");
        x = &ad * &x + &bd * u;
    }
}
