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
        assert_eq!(is_positive_definite(n, &t, 0.0), lmin(d) > 0.0, "d = {d}, λmin = {}", lmin(d));
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
