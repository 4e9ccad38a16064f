//! The QP subproblem solved on a guessed active set (`sqp::qp::solve_near_solution`'s
//! first try, for the Gauss–Newton model's questions at a solution, and `sqp::qp::solve`'s
//! given the last SQP iteration's multipliers) is the QP's solution:
//! on random convex QPs built around a known solution whose point sits on some of its
//! bounds, it finds that solution and its multipliers, and agrees with Clarabel's
//! interior-point solution; whenever it answers a random QP, its answer meets the KKT
//! conditions checked here directly (stationarity, feasibility, multiplier signs,
//! complementarity); a wrong guess is corrected (a bound the gradient pulls the step away
//! from is released, a bound the step would cross is added); and where the Hessian is not
//! convex on the guessed active set, the guess is not taken.

use footfall::sqp::qp::{self, ActiveHint, QpData, QpSolution, Triplets};

/// xorshift, so the QPs are the same on every machine.
struct Rng(u64);
impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// A QP's data, owned.
struct Qp {
    h: Triplets,
    g: Vec<f64>,
    jac: Triplets,
    c: Vec<f64>,
    c_lb: Vec<f64>,
    c_ub: Vec<f64>,
    d_lb: Vec<f64>,
    d_ub: Vec<f64>,
}

impl Qp {
    fn data(&self) -> (QpData<'_>, Vec<f64>) {
        let weights = vec![1.0; self.c.len()];
        (
            QpData {
                h: &self.h,
                g: &self.g,
                jac: &self.jac,
                c: &self.c,
                c_lb: &self.c_lb,
                c_ub: &self.c_ub,
                d_lb: &self.d_lb,
                d_ub: &self.d_ub,
                elastic: None,
                elastic_weights: &[],
                hint: None,
            },
            weights,
        )
    }
    /// `qp::solve` given the multipliers `(λ, ν)` of a previous QP.
    fn solve_hinted(&self, lambda: &[f64], nu: &[f64]) -> QpSolution {
        let (mut d, w) = self.data();
        d.elastic_weights = &w;
        d.hint = Some(ActiveHint { lambda, nu });
        qp::solve(&d).unwrap()
    }
    fn solve(&self, interior: bool) -> QpSolution {
        let (mut d, w) = self.data();
        d.elastic_weights = &w;
        if interior {
            qp::solve(&d).unwrap()
        } else {
            qp::solve_near_solution(&d).unwrap()
        }
    }
}

/// A convex QP with `n` variables and `m` rows (the first `meq` equalities, the rest
/// ranges), `Hessian = MᵀM + 10⁻³·I` (upper triangle, `M` with `k` random rows), whose
/// solution is known: `d*` is 0 on the first `at` variables, which sit on their lower
/// bound with multipliers ν* < 0, and inside its box elsewhere; the ranges hold `J d*`
/// inside; the equality rows have random multipliers λ*; and `g = −H d* − Jᵀλ* − ν*`.
/// Returns the QP, `d*`, λ* and ν*.
fn qp_with_known_solution(
    rng: &mut Rng,
    n: usize,
    m: usize,
    meq: usize,
    at: usize,
    k: usize,
) -> (Qp, Vec<f64>, Vec<f64>, Vec<f64>) {
    let mm: Vec<Vec<f64>> = (0..k)
        .map(|_| (0..n).map(|_| rng.uniform()).collect())
        .collect();
    let mut h = Triplets::default();
    let mut hd = vec![0.0; n];
    let d: Vec<f64> = (0..n)
        .map(|j| if j < at { 0.0 } else { 0.5 * rng.uniform() })
        .collect();
    for i in 0..n {
        for j in i..n {
            let v: f64 =
                (0..k).map(|r| mm[r][i] * mm[r][j]).sum::<f64>() + if i == j { 1e-3 } else { 0.0 };
            h.push(i, j, v);
            hd[i] += v * d[j];
            if i != j {
                hd[j] += v * d[i];
            }
        }
    }
    let mut jac = Triplets::default();
    let mut jd = vec![0.0; m];
    let lambda: Vec<f64> = (0..m)
        .map(|i| if i < meq { rng.uniform() } else { 0.0 })
        .collect();
    let mut g: Vec<f64> = hd.iter().map(|v| -v).collect();
    for i in 0..m {
        for j in 0..n {
            if rng.uniform() > 0.3 {
                let v = rng.uniform();
                jac.push(i, j, v);
                jd[i] += v * d[j];
                g[j] -= v * lambda[i];
            }
        }
    }
    let c: Vec<f64> = (0..m).map(|_| 0.1 * rng.uniform()).collect();
    let (mut c_lb, mut c_ub) = (vec![0.0; m], vec![0.0; m]);
    for i in 0..m {
        let value = c[i] + jd[i];
        if i < meq {
            // the row holds at d*: c_lb − c = J d*
            (c_lb[i], c_ub[i]) = (value, value);
        } else {
            c_lb[i] = value - 0.5 - rng.uniform().abs();
            c_ub[i] = value + 0.5 + rng.uniform().abs();
        }
    }
    let nu: Vec<f64> = (0..n)
        .map(|j| {
            if j < at {
                -0.1 - rng.uniform().abs()
            } else {
                0.0
            }
        })
        .collect();
    for j in 0..n {
        g[j] -= nu[j];
    }
    let d_lb: Vec<f64> = (0..n).map(|j| if j < at { 0.0 } else { -1.0 }).collect();
    let d_ub = vec![1.0; n];
    let qp = Qp {
        h,
        g,
        jac,
        c,
        c_lb,
        c_ub,
        d_lb,
        d_ub,
    };
    (qp, d, lambda, nu)
}

/// The largest violation of the QP's KKT conditions at `s`: stationarity
/// `H d + g + Jᵀλ + ν = 0`, the rows and bounds, and the multipliers' signs and
/// complementarity (λ ≥ 0 only at an upper bound, ≤ 0 only at a lower one).
fn kkt_violation(q: &Qp, s: &QpSolution) -> f64 {
    let n = q.g.len();
    let mut r = q.g.clone();
    for k in 0..q.h.vals.len() {
        let (i, j, v) = (q.h.rows[k], q.h.cols[k], q.h.vals[k]);
        r[i] += v * s.d[j];
        if i != j {
            r[j] += v * s.d[i];
        }
    }
    let mut jd = q.c.clone();
    for k in 0..q.jac.vals.len() {
        r[q.jac.cols[k]] += q.jac.vals[k] * s.lambda[q.jac.rows[k]];
        jd[q.jac.rows[k]] += q.jac.vals[k] * s.d[q.jac.cols[k]];
    }
    let mut worst = r
        .iter()
        .zip(&s.nu)
        .fold(0.0f64, |w, (r, nu)| w.max((r + nu).abs()));
    let pair = |value: f64, lb: f64, ub: f64, y: f64| {
        let feasible = (lb - value).max(value - ub).max(0.0);
        let sign = if lb == ub {
            0.0
        } else if y > 0.0 {
            y.abs() * (ub - value).abs()
        } else {
            y.abs() * (value - lb).abs()
        };
        feasible.max(sign)
    };
    for (i, &v) in jd.iter().enumerate() {
        worst = worst.max(pair(v, q.c_lb[i], q.c_ub[i], s.lambda[i]));
    }
    for j in 0..n {
        worst = worst.max(pair(s.d[j], q.d_lb[j], q.d_ub[j], s.nu[j]));
    }
    worst
}

fn largest_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}

#[test]
fn on_the_right_guess_the_qps_known_solution_is_found_and_agrees_with_clarabel() {
    let mut rng = Rng(0x2545F4914F6CDD1D);
    for case in 0..20 {
        let (q, d, lambda, nu) = qp_with_known_solution(&mut rng, 30, 12, 5, 8, 20);
        let fast = q.solve(false);
        assert_eq!(
            fast.iterations, 0,
            "case {case}: not solved on the active set"
        );
        let (dd, dl, dn) = (
            largest_difference(&fast.d, &d),
            largest_difference(&fast.lambda, &lambda),
            largest_difference(&fast.nu, &nu),
        );
        assert!(
            dd < 1e-10 && dl < 1e-9 && dn < 1e-9,
            "case {case}: step {dd:.1e}, multipliers {dl:.1e} and {dn:.1e} from the truth"
        );
        assert!(kkt_violation(&q, &fast) < 1e-10, "case {case}");
        // Clarabel reaches the same point to its tolerance
        let reference = q.solve(true);
        assert!(reference.iterations > 0);
        assert!(
            largest_difference(&reference.d, &d) < 1e-6,
            "case {case}: Clarabel's step {:.1e} from the truth",
            largest_difference(&reference.d, &d)
        );
    }
}

#[test]
fn a_random_qp_is_solved_on_the_active_set_only_at_its_kkt_point() {
    // the point on 8 lower bounds, a large random gradient: many bounds and rows change
    // at the solution, and a guess that does not settle is left to Clarabel
    let mut rng = Rng(0x9E3779B97F4A7C15);
    let mut taken = 0;
    for case in 0..40 {
        let (mut q, ..) = qp_with_known_solution(&mut rng, 30, 12, 5, 8, 20);
        for g in q.g.iter_mut() {
            *g += 2.0 * rng.uniform();
        }
        let fast = q.solve(false);
        let reference = q.solve(true);
        assert!(kkt_violation(&q, &reference) < 1e-6, "case {case}");
        if fast.iterations == 0 {
            taken += 1;
            assert!(kkt_violation(&q, &fast) < 1e-9, "case {case}");
            let dd = largest_difference(&fast.d, &reference.d);
            assert!(dd < 1e-6, "case {case}: step {dd:.1e} from Clarabel's");
        }
    }
    eprintln!("{taken} of 40 solved on the active set");
}

#[test]
fn the_next_sqp_qp_is_solved_on_the_active_set_its_predecessors_multipliers_hold() {
    // an SQP iteration's QP differs from the last one by a small change of its data; the
    // last QP's multipliers name the bounds and rows that hold, where the point is not on
    // them (a step rarely lands exactly on a row)
    let mut rng = Rng(0xD1B54A32D192ED03);
    let mut taken = 0;
    for case in 0..20 {
        let (mut q, ..) = qp_with_known_solution(&mut rng, 30, 12, 5, 8, 20);
        let last = q.solve(true);
        // the next QP: the gradient and the constraint values moved, the point off its
        // bounds by the last step's distance
        for g in q.g.iter_mut() {
            *g += 1e-3 * rng.uniform();
        }
        for c in q.c.iter_mut() {
            *c += 1e-3 * rng.uniform();
        }
        for j in 0..8 {
            q.d_lb[j] -= 1e-3 * rng.uniform().abs();
        }
        let reference = q.solve(true);
        let hinted = q.solve_hinted(&last.lambda, &last.nu);
        assert!(kkt_violation(&q, &hinted) < 1e-9, "case {case}");
        let dd = largest_difference(&hinted.d, &reference.d);
        assert!(dd < 1e-6, "case {case}: step {dd:.1e} from Clarabel's");
        if hinted.iterations == 0 {
            taken += 1;
        }
    }
    assert_eq!(taken, 20, "solved on the hinted active set");
    // a hint that holds every bound is corrected or left to Clarabel, never taken wrong
    let (mut q, ..) = qp_with_known_solution(&mut rng, 30, 12, 5, 8, 20);
    for g in q.g.iter_mut() {
        *g += 2.0 * rng.uniform();
    }
    let reference = q.solve(true);
    let wrong = q.solve_hinted(&vec![1.0; q.c.len()], &vec![-1.0; q.g.len()]);
    assert!(kkt_violation(&q, &wrong) < 1e-6);
    assert!(largest_difference(&wrong.d, &reference.d) < 1e-6);
}

#[test]
fn a_wrong_guess_is_corrected_in_both_directions() {
    // min ½‖d‖² + gᵀd in 2-D, the point on the lower bound of x₀ (guessed held), x₁ boxed
    // in [-1, 0.25]: g = (-1, -1) pulls x₀ off its bound (released: d₀ = 1) and x₁ past
    // its upper bound (added: d₁ = 0.25, ν₁ = 0.75)
    let mut h = Triplets::default();
    h.push(0, 0, 1.0);
    h.push(1, 1, 1.0);
    let q = Qp {
        h,
        g: vec![-1.0, -1.0],
        jac: Triplets::default(),
        c: vec![],
        c_lb: vec![],
        c_ub: vec![],
        d_lb: vec![0.0, -1.0],
        d_ub: vec![2.0, 0.25],
    };
    let s = q.solve(false);
    assert_eq!(s.iterations, 0, "solved on the active set");
    assert!(largest_difference(&s.d, &[1.0, 0.25]) < 1e-12, "{:?}", s.d);
    assert!(
        largest_difference(&s.nu, &[0.0, 0.75]) < 1e-12,
        "{:?}",
        s.nu
    );
}

#[test]
fn a_hessian_not_convex_on_the_guessed_active_set_is_left_to_clarabel() {
    // H = diag(1, -1): with no bound held the reduced Hessian is indefinite, and the
    // stationary point of the equality QP is a saddle, not the QP's minimum
    let mut h = Triplets::default();
    h.push(0, 0, 1.0);
    h.push(1, 1, -1.0);
    let q = Qp {
        h,
        g: vec![0.5, 0.1],
        jac: Triplets::default(),
        c: vec![],
        c_lb: vec![],
        c_ub: vec![],
        d_lb: vec![-1.0, -1.0],
        d_ub: vec![1.0, 1.0],
    };
    let (mut d, w) = q.data();
    d.elastic_weights = &w;
    if let Ok(s) = qp::solve_near_solution(&d) {
        assert_ne!(s.iterations, 0, "the saddle {:?} was taken", s.d);
    }
    // with x₁ held on its bound (an equality), the reduced Hessian is H₀₀ = 1 > 0, and
    // the guess is taken: d = (−0.5, 1)
    let fixed = Qp {
        d_lb: vec![-1.0, 1.0],
        d_ub: vec![1.0, 1.0],
        ..q
    };
    let s = fixed.solve(false);
    assert_eq!(s.iterations, 0);
    assert!(largest_difference(&s.d, &[-0.5, 1.0]) < 1e-12, "{:?}", s.d);
}
