//! The inertia correction of the exact-Hessian SQP: the sparse LDLᵀ convexity test
//! against eigenvalues known in closed form.

use footfall::sqp::hessian::{convexity_shift, is_positive_definite};
use footfall::sqp::qp::Triplets;

/// Tridiagonal `tridiag(-1, d, -1)` of size n (upper triangle): eigenvalues
/// `d − 2 cos(kπ/(n+1))`, k = 1…n.
fn tridiagonal(n: usize, d: f64) -> Triplets {
    let mut t = Triplets::default();
    for i in 0..n {
        t.push(i, i, d);
        if i + 1 < n {
            t.push(i, i + 1, -1.0);
        }
    }
    t
}

#[test]
fn positive_definiteness_matches_the_smallest_eigenvalue() {
    let n = 50;
    let lmin = |d: f64| d - 2.0 * (std::f64::consts::PI / (n as f64 + 1.0)).cos();
    for d in [2.5, 2.0, 1.999, 1.0, -1.0] {
        let t = tridiagonal(n, d);
        assert_eq!(
            is_positive_definite(n, &t, 0.0),
            lmin(d) > 0.0,
            "d = {d}, λmin = {}",
            lmin(d)
        );
        // a shift just above −λmin makes it positive definite, just below does not
        if lmin(d) < 0.0 {
            assert!(is_positive_definite(n, &t, -lmin(d) * 1.001));
            assert!(!is_positive_definite(n, &t, -lmin(d) * 0.999));
        }
    }
}

#[test]
fn convexity_shift_is_zero_for_convex_and_bounded_above_for_indefinite() {
    let n = 30;
    let convex = tridiagonal(n, 3.0);
    assert_eq!(convexity_shift(n, &convex, 0.0, 1e-8, 1e6), Some(0.0));
    let indefinite = tridiagonal(n, 0.0); // λmin = −2cos(π/31) ≈ −1.99
    let lmin = -2.0 * (std::f64::consts::PI / 31.0).cos();
    let d = convexity_shift(n, &indefinite, 0.0, 1e-3, 1e6).unwrap();
    assert!(d > -lmin && d <= 8.0 * -lmin, "shift {d} for λmin {lmin}");
    // no shift up to the limit helps: None
    assert_eq!(convexity_shift(n, &indefinite, 0.0, 1e-3, 1.0), None);
}

#[test]
fn one_factorisation_serves_every_trial_of_rho_and_shift() {
    // h = tridiag(-1, 0.5, -1) is indefinite; g = Σ e_i e_iᵀ over the even i penalises
    // half the coordinates. Each trial (ρ, δ) of one ConvexityTest must agree with a
    // fresh test of the summed matrix, whatever the order of the trials.
    use footfall::sqp::hessian::ConvexityTest;
    let n = 20;
    let h = tridiagonal(n, 0.5);
    let mut g = Triplets::default();
    for i in (0..n).step_by(2) {
        g.push(i, i, 1.0);
    }
    // duplicates and lower-triangle entries are summed into the upper triangle
    g.push(3, 2, 0.25);
    g.push(2, 3, 0.25);
    let mut test = ConvexityTest::new(n, &h, &g);
    for (rho, shift) in [
        (0.0, 0.0),
        (1e4, 0.0),
        (1.0, 1.0),
        (10.0, 0.5),
        (0.0, 2.0),
        (1e2, 1e-3),
        (0.0, 0.0),
    ] {
        // the oracle: the smallest eigenvalue of the dense symmetric matrix
        let mut dense = nalgebra::DMatrix::<f64>::identity(n, n) * shift;
        for (t, scale) in [(&h, 1.0), (&g, rho)] {
            for k in 0..t.vals.len() {
                let (r, c) = (t.rows[k].min(t.cols[k]), t.rows[k].max(t.cols[k]));
                dense[(r, c)] += scale * t.vals[k];
                if r != c {
                    dense[(c, r)] += scale * t.vals[k];
                }
            }
        }
        let lmin = dense.symmetric_eigen().eigenvalues.min();
        assert_eq!(
            test.is_positive_definite(rho, shift),
            lmin > 0.0,
            "ρ = {rho}, δ = {shift}, λmin = {lmin}"
        );
    }
    assert!(!test.is_positive_definite(0.0, 0.0));
    assert!(test.is_positive_definite(0.0, 2.0));
}
