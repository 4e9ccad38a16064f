//! The exact mode's QP Hessian: the Hessian of the Lagrangian made usable in a convex QP
//! (bound diagonals, a convexity test on the null space of the active rows, and the inertia
//! correction), with the sparse row algebra it uses.

use crate::sqp::hessian;
use crate::sqp::qp::Triplets;

/// What [`exact_qp_hessian`] needs to know about the current iterate.
pub(super) struct ExactQpContext<'a> {
    pub(super) n: usize,
    pub(super) w: &'a [f64],
    pub(super) w_lb: &'a [f64],
    pub(super) w_ub: &'a [f64],
    /// Bound multipliers of the last QP.
    pub(super) nu: &'a [f64],
    pub(super) c: &'a [f64],
    pub(super) c_lb: &'a [f64],
    pub(super) c_ub: &'a [f64],
    /// Constraint multipliers of the last QP.
    pub(super) lambda: &'a [f64],
    pub(super) jac_rows: &'a [usize],
    pub(super) jac_cols: &'a [usize],
    pub(super) jac: &'a [f64],
    pub(super) test_rho_scale: f64,
    pub(super) previous_shift: f64,
}

/// Make the exact Hessian of the Lagrangian `h` usable in a convex QP without changing
/// the Newton step where that is possible; returns the shift δ applied (with `search`),
/// or `Some(0)` if `h` is convex as it is and `None` if it is not (without).
///
/// Multiple-shooting Hessians are indefinite; what matters is the curvature on the
/// directions the linearised active constraints leave free. (1) Variables held at a bound
/// (at it, with a bound multiplier in the last QP) get a diagonal of the Hessian's size,
/// which costs nothing while they stay there. (2) Convexity on the null space of the
/// equalities and active inequalities is tested by a sparse LDLᵀ of `h + ρ Σ J_iᵀJ_i` over
/// those rows for ρ = (1, 10², 10⁴) · max|h| (Finsler: positive definite for some ρ iff the
/// reduced Hessian is); where it fails, δI is added, δ the smallest of a geometric
/// sequence that passes (the inertia correction of Wächter & Biegler 2006, §3.1), and at
/// least a third of the previous iteration's δ. The QP itself gets `h + δI` without the ρ
/// term, so its multipliers are the Lagrangian's.
pub(super) fn exact_qp_hessian(
    h: &mut Triplets,
    search: bool,
    cx: &ExactQpContext<'_>,
) -> Option<f64> {
    let n = cx.n;
    let hmax = h.vals.iter().map(|v| v.abs()).fold(1.0, f64::max);
    for i in 0..n {
        let tol = 1e-9 * (1.0 + cx.w[i].abs());
        if (cx.w[i] - cx.w_lb[i] <= tol || cx.w_ub[i] - cx.w[i] <= tol) && cx.nu[i] != 0.0 {
            h.push(i, i, hmax);
        }
    }
    // the rows of the test: equalities and inequalities active in the last QP
    let lam_max = cx.lambda.iter().fold(1.0f64, |a, v| a.max(v.abs()));
    let tested: Vec<bool> = (0..cx.c.len())
        .map(|i| {
            let tol = 1e-6 * (1.0 + cx.c[i].abs());
            let active = (cx.c[i] - cx.c_lb[i]).abs() <= tol || (cx.c_ub[i] - cx.c[i]).abs() <= tol;
            cx.c_lb[i] == cx.c_ub[i] || (active && cx.lambda[i].abs() > 1e-8 * lam_max)
        })
        .collect();
    let jtj = row_gram(&sparse_rows(
        cx.c.len(),
        cx.jac_rows,
        cx.jac_cols,
        cx.jac,
        |i| tested[i],
    ));
    let mut test = hessian::ConvexityTest::new(n, h, &jtj);
    let rhos = [1.0, 1e2, 1e4].map(|f| cx.test_rho_scale * hmax * f);
    if !search {
        return rhos
            .iter()
            .any(|&rho| test.is_positive_definite(rho, 0.0))
            .then_some(0.0);
    }
    let mut best: Option<f64> = None;
    for rho in rhos {
        if let Some(d) = test.shift(rho, cx.previous_shift, 1e-12 * hmax, 1e2 * hmax) {
            if best.is_none_or(|b| d < b) {
                best = Some(d);
            }
            if d == 0.0 {
                break;
            }
        }
    }
    // once a shift was needed, it decays by a third per iteration instead of dropping to
    // zero at once: near the bundled track's optimum the test passed and failed by turns
    // on a weakly curved direction (the effort-weighted excitations), and the unshifted
    // steps, 10× longer, undid the shifted ones (at KKT tolerance 1e-6: 61 iterations,
    // 106 s, the residual jumping between 1e-6 and 1e-5 for 30 of them; with the decay 30
    // iterations, 41 s)
    let delta = best.unwrap_or(1e2 * hmax).max(cx.previous_shift / 3.0);
    if delta > 0.0 {
        for i in 0..n {
            h.push(i, i, delta);
        }
    }
    Some(delta)
}

/// The rows `i` of a sparse Jacobian (triplets in pattern order) with `keep(i)`, each as
/// `(column, value)` pairs; the other rows empty.
pub(super) fn sparse_rows(
    m: usize,
    rows: &[usize],
    cols: &[usize],
    vals: &[f64],
    keep: impl Fn(usize) -> bool,
) -> Vec<Vec<(usize, f64)>> {
    let mut out: Vec<Vec<(usize, f64)>> = vec![Vec::new(); m];
    for k in 0..rows.len() {
        if keep(rows[k]) {
            out[rows[k]].push((cols[k], vals[k]));
        }
    }
    out
}

/// `Σ_i J_iᵀJ_i` over the given sparse rows, as upper-triangle triplets.
pub(super) fn row_gram(rows: &[Vec<(usize, f64)>]) -> Triplets {
    let mut t = Triplets::default();
    for row in rows {
        for a in 0..row.len() {
            for b in a..row.len() {
                let ((ca, va), (cb, vb)) = (row[a], row[b]);
                let v = if ca == cb && a != b {
                    2.0 * va * vb
                } else {
                    va * vb
                };
                t.push(ca.min(cb), ca.max(cb), v);
            }
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `exact_qp_hessian` of the diagonal Hessian `diag` of two free variables, after an
    /// iteration whose shift was `previous`: the shift it returns, after checking that
    /// exactly that shift was added to the diagonal the QP gets.
    fn diagonal_exact_hessian(diag: [f64; 2], previous: f64, search: bool) -> Option<f64> {
        let mut h = Triplets::default();
        h.push(0, 0, diag[0]);
        h.push(1, 1, diag[1]);
        let cx = ExactQpContext {
            n: 2,
            w: &[0.0, 0.0],
            w_lb: &[-1.0, -1.0],
            w_ub: &[1.0, 1.0],
            nu: &[0.0, 0.0],
            c: &[],
            c_lb: &[],
            c_ub: &[],
            lambda: &[],
            jac_rows: &[],
            jac_cols: &[],
            jac: &[],
            test_rho_scale: 1.0,
            previous_shift: previous,
        };
        let delta = exact_qp_hessian(&mut h, search, &cx);
        let added: f64 = (0..h.rows.len())
            .filter(|&k| h.rows[k] == 0 && h.cols[k] == 0)
            .map(|k| h.vals[k])
            .sum::<f64>()
            - diag[0];
        assert!(
            (added - delta.unwrap_or(0.0)).abs() < 1e-15,
            "{added} vs {delta:?}"
        );
        delta
    }

    /// The inertia correction of a convex Hessian: no shift at first; after an iteration
    /// that needed δ = 0.9, a third of it (0.3), then a ninth; an indefinite one still
    /// gets the shift that makes it convex.
    #[test]
    fn the_inertia_shift_decays_by_a_third_per_iteration() {
        let run = |diag, previous| diagonal_exact_hessian(diag, previous, true).unwrap();
        assert_eq!(run([2.0, 1.0], 0.0), 0.0);
        assert!((run([2.0, 1.0], 0.9) - 0.3).abs() < 1e-15);
        assert!((run([2.0, 1.0], 0.3) - 0.1).abs() < 1e-15);
        // indefinite: at least the shift that makes it convex, whatever the history
        let d = run([2.0, -1.0], 0.0);
        assert!(d > 1.0, "{d}");
        assert!(run([2.0, -1.0], 30.0) >= 10.0);
    }

    /// Without the search (Gauss–Newton where the exact Hessian is not convex): a convex
    /// Hessian is used as it is, whatever the history; an indefinite one is reported, not
    /// shifted.
    #[test]
    fn without_the_search_the_test_only_reports_convexity() {
        assert_eq!(diagonal_exact_hessian([2.0, 1.0], 0.9, false), Some(0.0));
        assert_eq!(diagonal_exact_hessian([2.0, 1e-9], 0.0, false), Some(0.0));
        assert_eq!(diagonal_exact_hessian([2.0, -1.0], 0.0, false), None);
        assert_eq!(diagonal_exact_hessian([-1e-9, 1.0], 30.0, false), None);
    }
}
