//! The Gauss–Newton model at a point: on a linear least-squares problem with a linear
//! equality constraint one step reaches the constrained optimum, the predicted decrease
//! is the true one, and a gradient shift probes the reduced inverse Hessian (checked
//! against the null-space formula Z (ZᵀHZ)⁻¹ Zᵀ), also for a variable whose step runs
//! to its bound; the reduced inverse from the equality-constrained QPs of the active
//! constraints against the same formula, with a variable held at its bound. The
//! truncated re-fit's stopping rules on a one-parameter nonlinear least-squares problem.

use footfall::problems::diagnose::stats::reduced_inverse_hessian;
use footfall::problems::diagnose::truncated_refit_from;
use footfall::sqp::linearised::GaussNewtonModel;
use footfall::sqp::{Nlp, NlpEval};
use nalgebra::{DMatrix, DVector};

struct LinearLs {
    a: DMatrix<f64>,
    b: DVector<f64>,
    /// Variable bounds (lower, upper).
    w_bounds: (Vec<f64>, Vec<f64>),
}

impl Nlp for LinearLs {
    fn n(&self) -> usize {
        3
    }
    fn m(&self) -> usize {
        1
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        (
            self.w_bounds.0.clone(),
            self.w_bounds.1.clone(),
            vec![1.0],
            vec![1.0],
        )
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

fn problem() -> (DMatrix<f64>, DVector<f64>) {
    let a = DMatrix::from_row_slice(
        4,
        3,
        &[1.0, 0.5, 0.0, 0.2, 2.0, 0.3, 0.0, 0.4, 1.5, 1.0, 1.0, 1.0],
    );
    let b = DVector::from_column_slice(&[1.0, -0.5, 2.0, 0.7]);
    (a, b)
}

/// Z (ZᵀHZ)⁻¹ Zᵀ, Z spanning {d: Σd = 0}: the inverse Hessian reduced to the constraint.
fn reduced_inverse(h: &DMatrix<f64>) -> DMatrix<f64> {
    let z = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, -1.0, 1.0, 0.0, -1.0]);
    &z * (z.transpose() * h * &z).try_inverse().unwrap() * z.transpose()
}

#[test]
fn one_gauss_newton_step_solves_a_linear_least_squares_problem_and_predicts_its_decrease() {
    let (a, b) = problem();
    let nlp = LinearLs {
        a: a.clone(),
        b: b.clone(),
        w_bounds: (vec![-10.0; 3], vec![10.0; 3]),
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
    // reduced inverse Hessian from a gradient shift vs Z (ZᵀHZ)⁻¹ Zᵀ
    let reduced = reduced_inverse(&h);
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

/// The information of a parameter is the cost's curvature along it, whatever range it is
/// allowed: when the step runs to the parameter's bound, a gradient shift moves nothing
/// (the naive probe reads an inverse curvature of zero: a perfectly known parameter),
/// while `reduced_inverse_hessian` lifts the bound and reads the null-space formula's.
#[test]
fn a_parameter_whose_step_runs_to_its_bound_keeps_its_reduced_curvature() {
    let (a, b) = problem();
    let h = 2.0 * a.transpose() * &a;
    let reduced = reduced_inverse(&h);
    let w0 = [0.2, 0.3, 0.5];
    let free = LinearLs {
        a: a.clone(),
        b: b.clone(),
        w_bounds: (vec![-10.0; 3], vec![10.0; 3]),
    };
    let x2 = w0[2]
        + GaussNewtonModel::new(&free, &w0, 0.0)
            .unwrap()
            .step(None)
            .unwrap()
            .d[2];
    // bound the last variable between its start and halfway to its optimum
    let (lo, hi) = if x2 > w0[2] {
        (w0[2] - 0.1, 0.5 * (w0[2] + x2))
    } else {
        (0.5 * (w0[2] + x2), w0[2] + 0.1)
    };
    let nlp = LinearLs {
        a,
        b,
        w_bounds: (vec![-10.0, -10.0, lo], vec![10.0, 10.0, hi]),
    };
    let model = GaussNewtonModel::new(&nlp, &w0, 0.0).unwrap();
    let base = model.step(None).unwrap();
    let at = w0[2] + base.d[2];
    assert!(
        (at - lo).abs() < 1e-7 || (at - hi).abs() < 1e-7,
        "the step runs to the bound: {at} in [{lo}, {hi}]"
    );
    let eps = 1e-3;
    let mut shift = vec![0.0; 3];
    shift[2] = eps;
    let naive = -(model.step(Some(&shift)).unwrap().d[2] - base.d[2]) / eps;
    assert!(
        naive.abs() < 1e-4 * reduced[(2, 2)],
        "pinned at the bound, the naive probe reads {naive} (truth {})",
        reduced[(2, 2)]
    );
    let c = reduced_inverse_hessian(&nlp, &w0, &[2]).unwrap();
    assert!(
        (c[0][0] - reduced[(2, 2)]).abs() < 1e-5 * reduced[(2, 2)],
        "{} vs {}",
        c[0][0],
        reduced[(2, 2)]
    );
}

/// The reduced inverse from the QPs on the active constraints as equalities equals
/// Z (ZᵀHZ)⁻¹ Zᵀ: on the free problem with Z spanning {Σd = 0}; with the first variable's
/// step run to its bound, with Z spanning {Σd = 0, d₀ = 0} = span{(0, 1, −1)}, since
/// that bound is active (its multiplier nonzero) and held.
#[test]
fn the_reduced_inverse_is_the_null_space_formula_of_the_active_constraints() {
    let (a, b) = problem();
    let h = 2.0 * a.transpose() * &a;
    let w0 = [0.2, 0.3, 0.5];
    let free = LinearLs {
        a: a.clone(),
        b: b.clone(),
        w_bounds: (vec![-10.0; 3], vec![10.0; 3]),
    };
    let model = GaussNewtonModel::new(&free, &w0, 0.0).unwrap();
    let step = model.step(None).unwrap();
    let c = model.reduced_inverse(&step, &[0, 1, 2]).unwrap();
    let truth = reduced_inverse(&h);
    for i in 0..3 {
        for j in 0..3 {
            assert!(
                (c[i][j] - truth[(i, j)]).abs() < 1e-10 * truth.abs().max(),
                "({i},{j}): {} vs {}",
                c[i][j],
                truth[(i, j)]
            );
        }
    }
    // hold the first variable: bound it between its start and halfway to its optimum
    let x0 = w0[0] + step.d[0];
    let (lo, hi) = if x0 > w0[0] {
        (w0[0] - 0.1, 0.5 * (w0[0] + x0))
    } else {
        (0.5 * (w0[0] + x0), w0[0] + 0.1)
    };
    let bounded = LinearLs {
        a,
        b,
        w_bounds: (vec![lo, -10.0, -10.0], vec![hi, 10.0, 10.0]),
    };
    let model = GaussNewtonModel::new(&bounded, &w0, 0.0).unwrap();
    let step = model.step(None).unwrap();
    let at = w0[0] + step.d[0];
    assert!(
        (at - lo).abs() < 1e-7 || (at - hi).abs() < 1e-7,
        "{at} in [{lo}, {hi}]"
    );
    let c = model.reduced_inverse(&step, &[1, 2]).unwrap();
    let z = DVector::from_column_slice(&[0.0, 1.0, -1.0]);
    let curvature = (z.transpose() * &h * &z)[(0, 0)];
    let held = &z * z.transpose() / curvature;
    for (i, &ri) in [1, 2].iter().enumerate() {
        for (j, &cj) in [1, 2].iter().enumerate() {
            assert!(
                (c[i][j] - held[(ri, cj)]).abs() < 1e-10 * held.abs().max(),
                "held ({ri},{cj}): {} vs {}",
                c[i][j],
                held[(ri, cj)]
            );
        }
    }
    // the bound of a variable asked for is not held: the free formula again
    let c = model.reduced_inverse(&step, &[0]).unwrap();
    assert!(
        (c[0][0] - truth[(0, 0)]).abs() < 1e-10 * truth.abs().max(),
        "{} vs {}",
        c[0][0],
        truth[(0, 0)]
    );
}

/// One parameter w, residual r(w) = eʷ − 2 (f = r², minimum at w = ln 2), with one
/// constraint row c = w that no step reaches.
struct Exponential;

impl Nlp for Exponential {
    fn n(&self) -> usize {
        1
    }
    fn m(&self) -> usize {
        1
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        (vec![-10.0], vec![10.0], vec![-100.0], vec![100.0])
    }
    fn jacobian_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        (vec![0], vec![0])
    }
    fn gauss_newton_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        (vec![0], vec![0])
    }
    fn hessian_blocks(&self) -> Vec<Vec<usize>> {
        vec![vec![0]]
    }
    fn evaluate(&self, w: &[f64], derivs: bool) -> Result<NlpEval, footfall::sqp::EvalError> {
        let (r, dr) = (w[0].exp() - 2.0, w[0].exp());
        let mut ev = NlpEval {
            f: r * r,
            c: vec![w[0]],
            ..Default::default()
        };
        if derivs {
            ev.grad = vec![2.0 * r * dr];
            ev.jac = vec![1.0];
            ev.gn = vec![2.0 * dr * dr];
        }
        Ok(ev)
    }
    fn row_name(&self, _i: usize) -> String {
        "w".into()
    }
}

/// From w = 0 the Gauss–Newton steps w ← w − r/r′ lower f = 1 by about 0.484, 0.508 and
/// 0.0077 (Newton's iteration on eʷ = 2, worked by hand): the relative rule (a step
/// adding under 5 % of the decrease so far) ends the re-fit after the third; an absolute
/// floor above the first step's decrease ends it after the first, with the decrease and
/// point of that step.
#[test]
fn the_truncated_re_fit_stops_on_a_small_relative_or_absolute_step() {
    let nlp = Exponential;
    let newton = |w: f64| w - (w.exp() - 2.0) / w.exp();
    let f = |w: f64| (w.exp() - 2.0f64).powi(2);
    let (w1, w2, w3) = (
        newton(0.0),
        newton(newton(0.0)),
        newton(newton(newton(0.0))),
    );
    let run = |abs_stop: f64| {
        let first = GaussNewtonModel::new(&nlp, &[0.0], 0.0).unwrap();
        let step = first.step(None).map_err(|e| e.to_string());
        truncated_refit_from(&nlp, &first, step, 5, 0.05, abs_stop).unwrap()
    };
    let (j0, dec, w, steps) = run(0.0);
    assert_eq!(j0, 1.0);
    assert_eq!(steps, 3, "relative rule: dec {dec}, w {w:?}");
    assert!((w[0] - w3).abs() < 1e-7, "{} vs {w3}", w[0]);
    assert!((dec - (1.0 - f(w3))).abs() < 1e-7, "{dec}");
    // the steps' decreases as worked by hand
    assert!((1.0 - f(w1) - 0.484).abs() < 1e-3 && (f(w1) - f(w2) - 0.508).abs() < 1e-3);
    assert!(f(w2) - f(w3) < 0.05 * (1.0 - f(w3)));
    let (_, dec, w, steps) = run(0.49);
    assert_eq!(steps, 1, "absolute rule: dec {dec}");
    assert!((w[0] - w1).abs() < 1e-7 && (dec - (1.0 - f(w1))).abs() < 1e-7);
    // a floor below every step's decrease changes nothing
    assert_eq!(run(1e-3).3, 3);
}
