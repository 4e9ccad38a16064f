//! The Gauss–Newton model at a point: on a linear least-squares problem with a linear
//! equality constraint one step reaches the constrained optimum, the predicted decrease
//! is the true one, and a gradient shift probes the reduced inverse Hessian (checked
//! against the null-space formula Z (ZᵀHZ)⁻¹ Zᵀ).

use footfall::sqp::linearised::GaussNewtonModel;
use footfall::sqp::{Nlp, NlpEval};
use nalgebra::{DMatrix, DVector};

struct LinearLs {
    a: DMatrix<f64>,
    b: DVector<f64>,
}

impl Nlp for LinearLs {
    fn n(&self) -> usize {
        3
    }
    fn m(&self) -> usize {
        1
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        (vec![-10.0; 3], vec![10.0; 3], vec![1.0], vec![1.0])
    }
    fn jacobian_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        (vec![0, 0, 0], vec![0, 1, 2])
    }
    fn gauss_newton_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        let (mut r, mut c) = (vec![], vec![]);
        for i in 0..3 {
            for j in i..3 {
                r.push(i);
                c.push(j);
            }
        }
        (r, c)
    }
    fn hessian_blocks(&self) -> Vec<Vec<usize>> {
        vec![vec![0, 1, 2]]
    }
    fn evaluate(&self, w: &[f64], derivs: bool) -> Result<NlpEval, footfall::sqp::EvalError> {
        let x = DVector::from_column_slice(w);
        let r = &self.a * &x - &self.b;
        let mut ev = NlpEval {
            f: r.norm_squared(),
            c: vec![w.iter().sum()],
            ..Default::default()
        };
        if derivs {
            ev.grad = (2.0 * self.a.transpose() * &r).iter().copied().collect();
            ev.jac = vec![1.0; 3];
            let h = 2.0 * self.a.transpose() * &self.a;
            let (rr, cc) = self.gauss_newton_pattern();
            ev.gn = rr.iter().zip(&cc).map(|(&i, &j)| h[(i, j)]).collect();
        }
        Ok(ev)
    }
    fn row_name(&self, _i: usize) -> String {
        "sum".into()
    }
}

#[test]
fn one_gauss_newton_step_solves_a_linear_least_squares_problem_and_predicts_its_decrease() {
    let a = DMatrix::from_row_slice(
        4,
        3,
        &[1.0, 0.5, 0.0, 0.2, 2.0, 0.3, 0.0, 0.4, 1.5, 1.0, 1.0, 1.0],
    );
    let b = DVector::from_column_slice(&[1.0, -0.5, 2.0, 0.7]);
    let nlp = LinearLs {
        a: a.clone(),
        b: b.clone(),
    };
    // brute force: the KKT system [H 1; 1ᵀ 0][x; λ] = [2Aᵀb; 1]
    let h = 2.0 * a.transpose() * &a;
    let mut k = DMatrix::zeros(4, 4);
    k.view_mut((0, 0), (3, 3)).copy_from(&h);
    for i in 0..3 {
        k[(i, 3)] = 1.0;
        k[(3, i)] = 1.0;
    }
    let mut rhs = DVector::zeros(4);
    rhs.rows_mut(0, 3).copy_from(&(2.0 * a.transpose() * &b));
    rhs[3] = 1.0;
    let sol = k.clone().lu().solve(&rhs).unwrap();
    let x_star: Vec<f64> = sol.rows(0, 3).iter().copied().collect();
    let w0 = [0.2, 0.3, 0.5];
    let f = |x: &[f64]| nlp.evaluate(x, false).unwrap().f;
    let model = GaussNewtonModel::new(&nlp, &w0, 0.0).unwrap();
    let step = model.step(None).unwrap();
    for i in 0..3 {
        assert!(
            (w0[i] + step.d[i] - x_star[i]).abs() < 1e-6,
            "step reaches the optimum: {:?} vs {x_star:?}",
            step.d
        );
    }
    let truth = f(&w0) - f(&x_star);
    assert!(truth > 0.1);
    assert!(
        (step.predicted_decrease - truth).abs() < 1e-6 * truth,
        "{} vs {truth}",
        step.predicted_decrease
    );
    // reduced inverse Hessian from a gradient shift vs Z (ZᵀHZ)⁻¹ Zᵀ, Z spanning {d: Σd = 0}
    let z = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, -1.0, 1.0, 0.0, -1.0]);
    let reduced = &z * (z.transpose() * &h * &z).try_inverse().unwrap() * z.transpose();
    let eps = 1e-3;
    for j in 0..3 {
        let mut shift = vec![0.0; 3];
        shift[j] = eps;
        let s = model.step(Some(&shift)).unwrap();
        for i in 0..3 {
            let col = -(s.d[i] - step.d[i]) / eps;
            assert!(
                (col - reduced[(i, j)]).abs() < 1e-5 * reduced.abs().max(),
                "({i},{j}): {col} vs {}",
                reduced[(i, j)]
            );
        }
    }
}
