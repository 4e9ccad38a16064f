//! The convergence test: the KKT residual at the current point with the QP's
//! multipliers, and the stop tests built on it.

/// A point with its first derivatives and multipliers, as the KKT test reads it.
pub(super) struct KktPoint<'a> {
    /// Objective gradient (length n).
    pub(super) grad: &'a [f64],
    /// Jacobian pattern rows.
    pub(super) jac_rows: &'a [usize],
    /// Jacobian pattern columns.
    pub(super) jac_cols: &'a [usize],
    /// Jacobian values in pattern order.
    pub(super) jac: &'a [f64],
    /// Constraint values (length m).
    pub(super) c: &'a [f64],
    /// Constraint lower bounds.
    pub(super) c_lb: &'a [f64],
    /// Constraint upper bounds.
    pub(super) c_ub: &'a [f64],
    /// Constraint multipliers λ (Lagrangian `f + λᵀc + νᵀw`).
    pub(super) lambda: &'a [f64],
    /// Bound multipliers ν.
    pub(super) nu: &'a [f64],
    /// The point and its bounds (empty: the bounds are not looked at).
    pub(super) w: &'a [f64],
    pub(super) w_lb: &'a [f64],
    pub(super) w_ub: &'a [f64],
    /// Largest constraint violation.
    pub(super) infeasibility: f64,
}

/// The KKT residual: the largest of the scaled stationarity
/// `‖∇f + Jᵀλ + ν‖∞ / s_d` (IPOPT's scaling, `s_d = max(1, ‖(λ, ν)‖₁ / ((m + n) 100))`),
/// the constraint violation and the scaled complementarity of the inequality rows
/// (`|λ_i|` times the distance to the bound its sign says is active) and of the variables'
/// bounds ([`bound_complementarity`]).
///
/// A variable at one of its bounds (within [`AT_BOUND`] of it) may take the bound
/// multiplier that cancels `∇f + Jᵀλ` there, when its sign fits that bound, instead of
/// the QP's: the QP's interior point leaves such a variable a slack of ~1e-8, and the
/// QP's multiplier then balances the step's curvature `h_vv d_v` (the exact mode gives a
/// held variable a diagonal of the Hessian's size), which is not the NLP's stationarity
/// at the point. The bundled track's tail rose so, 4.7e-6 → 8.5e-6, on an excitation at
/// its lower bound 0. The component's residual
/// is the smaller of the two choices; the other's complementarity, `|ν_v|` times the
/// distance to the bound, is below `AT_BOUND · |ν_v|`.
pub(super) fn residual(p: &KktPoint<'_>) -> f64 {
    let (n, m) = (p.grad.len(), p.c.len());
    let mut reduced = p.grad.to_vec();
    for k in 0..p.jac_rows.len() {
        reduced[p.jac_cols[k]] += p.jac[k] * p.lambda[p.jac_rows[k]];
    }
    let stat: Vec<f64> = reduced
        .iter()
        .zip(p.nu)
        .enumerate()
        .map(|(i, (&g, &v))| {
            let with_qp = (g + v).abs();
            if p.w.is_empty() {
                return with_qp;
            }
            let near = |bound: f64| (p.w[i] - bound).abs() <= AT_BOUND * bound.abs().max(1.0);
            // ∇f + Jᵀλ + ν = 0 with ν ≤ 0 at a lower bound, ν ≥ 0 at an upper one: the
            // bound the gradient presses the variable against, if it is there
            let pressed = [(g >= 0.0, p.w_lb[i]), (g <= 0.0, p.w_ub[i])]
                .into_iter()
                .find(|&(fits, bound)| fits && near(bound));
            match pressed {
                Some((_, bound)) => with_qp.min((g * (p.w[i] - bound)).abs()),
                None => with_qp,
            }
        })
        .collect();
    let mult_l1: f64 = p.lambda.iter().chain(p.nu).map(|v| v.abs()).sum();
    let sd = (mult_l1 / ((m + n) as f64 * 100.0)).max(1.0);
    let stat_inf = stat.iter().copied().fold(0.0, f64::max) / sd;
    let compl = (0..m)
        .map(|i| {
            let (c, l, u) = (p.c[i], p.c_lb[i], p.c_ub[i]);
            if l == u {
                0.0
            } else if p.lambda[i] > 0.0 {
                (p.lambda[i] * (u - c)).abs()
            } else {
                (p.lambda[i] * (c - l)).abs()
            }
        })
        .fold(0.0, f64::max);
    stat_inf
        .max(p.infeasibility)
        .max(compl / sd)
        .max(bound_complementarity(p) / sd)
}

/// The largest `|ν_i|` times the distance from `w_i` to the bound the sign of `ν_i` says
/// is active (ν ≤ 0 at a lower bound, ν ≥ 0 at an upper one; 0 where the point's bounds
/// are not looked at). A QP step that runs into a bound the point is far from gives that
/// bound a multiplier which cancels `∇f + Jᵀλ` in the stationarity: without this term a
/// linear objective's first iterate, nowhere near its optimum, read 1e-8.
fn bound_complementarity(p: &KktPoint<'_>) -> f64 {
    if p.w.is_empty() {
        return 0.0;
    }
    p.nu.iter()
        .zip(p.w)
        .zip(p.w_lb.iter().zip(p.w_ub))
        .map(|((&v, &w), (&lb, &ub))| {
            let bound = if v < 0.0 { lb } else { ub };
            if v == 0.0 || !bound.is_finite() {
                0.0
            } else {
                (v * (w - bound)).abs()
            }
        })
        .fold(0.0, f64::max)
}

/// How close to a bound (relative to `max(1, |bound|)`) a variable counts as at it for
/// [`residual`]'s choice of its bound multiplier.
pub(super) const AT_BOUND: f64 = 1e-8;

/// Converged: the residual is within the tolerance and the step came from a consistent
/// QP (an elastic QP's multipliers belong to the penalty problem, not the NLP).
pub(super) fn converged(kkt: f64, tol: f64, elastic: bool) -> bool {
    kkt <= tol && !elastic
}

/// Locally infeasible: the elastic QP, which minimises the linearised violation, no
/// longer moves (`‖d‖∞ ≤ 10⁻¹⁰ max(1, ‖w‖∞)`) while the violation exceeds the tolerance.
pub(super) fn stationary_infeasible(
    d: &[f64],
    w: &[f64],
    elastic: bool,
    infeasibility: f64,
    tol: f64,
) -> bool {
    let dnorm = d.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let wnorm = w.iter().map(|v| v.abs()).fold(1.0, f64::max);
    elastic && dnorm <= 1e-10 * wnorm && infeasibility > tol
}

#[cfg(test)]
mod tests {
    use super::*;

    /// min x² + y² s.t. x + y = 1 (row 0) and 0 ≤ x − y ≤ 1 (row 1), at `w` with the
    /// given multipliers (`store` holds the gradient, constraints and Jacobian).
    fn point<'a>(
        w: [f64; 2],
        lambda: &'a [f64],
        nu: &'a [f64],
        store: &'a mut (Vec<f64>, Vec<f64>, Vec<f64>),
    ) -> KktPoint<'a> {
        let (x, y) = (w[0], w[1]);
        store.0 = vec![2.0 * x, 2.0 * y];
        store.1 = vec![x + y, x - y];
        store.2 = vec![1.0, 1.0, 1.0, -1.0];
        let infeasibility = ((x + y) - 1.0)
            .abs()
            .max((0.0 - (x - y)).max((x - y) - 1.0).max(0.0));
        KktPoint {
            grad: &store.0,
            jac_rows: &[0, 0, 1, 1],
            jac_cols: &[0, 1, 0, 1],
            jac: &store.2,
            c: &store.1,
            c_lb: &[1.0, 0.0],
            c_ub: &[1.0, 1.0],
            lambda,
            nu,
            w: &[],
            w_lb: &[],
            w_ub: &[],
            infeasibility,
        }
    }

    /// At the optimum (½, ½) with λ = (−1, 0), ν = 0 every part vanishes.
    #[test]
    fn the_residual_vanishes_at_a_kkt_point() {
        let mut s = Default::default();
        let p = point([0.5, 0.5], &[-1.0, 0.0], &[0.0, 0.0], &mut s);
        assert_eq!(residual(&p), 0.0);
        assert!(converged(residual(&p), 1e-12, false));
        assert!(!converged(residual(&p), 1e-12, true));
    }

    /// Hand-computed parts at (0.6, 0.3), λ = (−1, 0.5), ν = (0, 0.1):
    /// ∇f + Jᵀλ + ν = (1.2 − 1 + 0.5, 0.6 − 1 − 0.5 + 0.1) = (0.7, −0.8) → 0.8 (s_d = 1);
    /// violation |0.9 − 1| = 0.1; complementarity of row 1 (λ > 0: upper bound active)
    /// |0.5 · (1 − 0.3)| = 0.35. The residual is the largest, 0.8.
    #[test]
    fn the_residual_is_the_largest_of_its_hand_computed_parts() {
        let mut s = Default::default();
        let p = point([0.6, 0.3], &[-1.0, 0.5], &[0.0, 0.1], &mut s);
        assert!((p.infeasibility - 0.1).abs() < 1e-15);
        assert!((residual(&p) - 0.8).abs() < 1e-15, "{}", residual(&p));
        // with the stationarity fixed by ν, the complementarity 0.35 decides
        let p = point([0.6, 0.3], &[-1.0, 0.5], &[-0.7, 0.9], &mut s);
        assert!((residual(&p) - 0.35).abs() < 1e-15, "{}", residual(&p));
    }

    /// Large multipliers scale the stationarity down by
    /// s_d = ‖(λ, ν)‖₁ / ((m + n) 100), not the violation: with λ = (−1000, 0) and
    /// ν = (996.8, 999.4) at (0.6, 0.3) the stationarity is (−2, 0) and
    /// s_d = 2996.2 / 400, so the residual is 2 / s_d ≈ 0.267 (above the violation 0.1).
    #[test]
    fn large_multipliers_scale_the_dual_parts() {
        let mut s = Default::default();
        let p = point([0.6, 0.3], &[-1000.0, 0.0], &[996.8, 999.4], &mut s);
        let want = 2.0 / (2996.2 / 400.0);
        assert!(
            (residual(&p) - want).abs() < 1e-12,
            "{} vs {want}",
            residual(&p)
        );
    }

    /// min x² + y² s.t. x + y = 1 with y ≥ 0.6 (row 1 relaxed away): the optimum is
    /// (0.4, 0.6), λ = −0.8, where ∇f + Jᵀλ = (0, 0.4) is cancelled by ν_y = −0.4. A QP
    /// whose interior point left y a slack answers ν_y = −0.39 (stationarity 0.01); at
    /// y = 0.6 + 1e-12 (at the bound) the cancelling multiplier is taken instead, with a
    /// complementarity of 0.4e-12; at y = 0.6 + 1e-4 (not at it) the QP's stands, and a
    /// gradient pointing away from the bound is never cancelled.
    #[test]
    fn a_variable_at_its_bound_takes_the_multiplier_that_cancels_its_gradient() {
        let (lb, ub) = ([-10.0, 0.6], [10.0, 10.0]);
        let (c_lb, c_ub) = ([1.0, f64::NEG_INFINITY], [1.0, f64::INFINITY]);
        let at = |y: f64, lambda: f64, nu_y: f64| {
            let w = [1.0 - y, y];
            let (l, nu) = ([lambda, 0.0], [0.0, nu_y]);
            let mut s = Default::default();
            let p = point(w, &l, &nu, &mut s);
            residual(&KktPoint {
                w: &w,
                w_lb: &lb,
                w_ub: &ub,
                c_lb: &c_lb,
                c_ub: &c_ub,
                infeasibility: 0.0,
                ..p
            })
        };
        // at the bound: the QP's −0.39 would leave 0.01
        let r = at(0.6 + 1e-12, -0.8, -0.39);
        assert!(r < 1e-11, "{r}");
        // 1e-4 away: the QP's multiplier stands (x's component 2·0.5999 − 0.8 ≈ −2e-4)
        let r = at(0.6 + 1e-4, -0.8, -0.39);
        assert!((r - 0.01).abs() < 1e-3, "{r}");
        // a gradient that pulls y off its lower bound is not cancelled: with λ = −1.5,
        // ∇f + Jᵀλ = (0.8 − 1.5, 1.2 − 1.5) = (−0.7, −0.3); y's −0.3 points up, away
        let r = at(0.6, -1.5, 0.0);
        assert!((r - 0.7).abs() < 1e-12, "{r}");
    }

    /// At the feasible (0.7, 0.3), not optimal, λ = (−1, 0) leaves ∇f + Jᵀλ = (0.4, −0.4),
    /// which ν = (−0.4, 0.4) cancels: the multipliers of a QP step that ran into x ≥ −10
    /// and y ≤ 10. The point is 10.7 and 9.7 from those bounds, so their complementarity
    /// is 0.4 · 10.7 = 4.28, the residual.
    #[test]
    fn bound_multipliers_of_bounds_the_point_is_far_from_do_not_make_it_stationary() {
        let w = [0.7, 0.3];
        let (lambda, nu) = ([-1.0, 0.0], [-0.4, 0.4]);
        let mut s = Default::default();
        let p = point(w, &lambda, &nu, &mut s);
        assert!(
            residual(&p) < 1e-15,
            "the bounds not looked at: {}",
            residual(&p)
        );
        let r = residual(&KktPoint {
            w: &w,
            w_lb: &[-10.0, -10.0],
            w_ub: &[10.0, 10.0],
            ..p
        });
        assert!((r - 0.4 * 10.7).abs() < 1e-12, "{r}");
    }

    #[test]
    fn an_elastic_step_that_no_longer_moves_means_infeasible() {
        let w = [2.0, -3.0];
        assert!(stationary_infeasible(&[2e-10, 0.0], &w, true, 1.0, 1e-6));
        assert!(!stationary_infeasible(&[4e-10, 0.0], &w, true, 1.0, 1e-6));
        assert!(!stationary_infeasible(&[0.0, 0.0], &w, false, 1.0, 1e-6));
        assert!(!stationary_infeasible(&[0.0, 0.0], &w, true, 1e-7, 1e-6));
    }
}
