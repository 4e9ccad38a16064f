//! The distributions the tests of significance read: the χ² distribution's upper tail
//! and its points, central and noncentral (through the complementary error function, the
//! regularised incomplete gamma function and ln Γ).

/// The χ² 99.9 % point for `k` degrees of freedom (k ≥ 6 by the Wilson–Hilferty
/// approximation).
pub fn chi2_999(k: usize) -> f64 {
    const TABLE: [f64; 5] = [10.828, 13.816, 16.266, 18.467, 20.515];
    if (1..=5).contains(&k) {
        return TABLE[k - 1];
    }
    let kf = k.max(1) as f64;
    let z = 3.0902; // standard normal 99.9 % point
    kf * (1.0 - 2.0 / (9.0 * kf) + z * (2.0 / (9.0 * kf)).sqrt()).powi(3)
}

/// The upper `alpha` point of the χ² distribution with one degree of freedom: the `x`
/// with `P(χ²₁ > x) = erfc(√(x/2)) = alpha` (bisection; `alpha` in (0, 1)).
pub fn chi2_1_upper(alpha: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 200.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if erfc((0.5 * mid).sqrt()) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// `P(χ'²_k(λ) > x)`: the upper tail of the noncentral χ² distribution with `k` degrees
/// of freedom and noncentrality `λ ≥ 0`, the Poisson(λ/2) mixture of central χ²_{k+2j}
/// tails (summed from the Poisson mode outwards until the weights left are below 1e-15).
pub fn noncentral_chi2_upper(x: f64, k: f64, lambda: f64) -> f64 {
    if !(lambda > 0.0) {
        return chi2_upper(x, k);
    }
    let m = 0.5 * lambda;
    let mode = m.floor();
    let weight = |j: f64| (j * m.ln() - m - ln_gamma(j + 1.0)).exp();
    let mut sum = 0.0;
    let mut mass = 0.0;
    // upwards from the mode, then downwards: each side's weights fall monotonically
    let mut j = mode;
    loop {
        let w = weight(j);
        sum += w * chi2_upper(x, k + 2.0 * j);
        mass += w;
        if w < 1e-16 || 1.0 - mass < 1e-15 {
            break;
        }
        j += 1.0;
    }
    let mut j = mode - 1.0;
    while j >= 0.0 && 1.0 - mass >= 1e-15 {
        let w = weight(j);
        sum += w * chi2_upper(x, k + 2.0 * j);
        mass += w;
        if w < 1e-16 {
            break;
        }
        j -= 1.0;
    }
    sum.clamp(0.0, 1.0)
}

/// The upper `alpha` point of the noncentral χ² distribution with `k` degrees of freedom
/// and noncentrality `λ`: the `x` with `P(χ'²_k(λ) > x) = alpha` (bisection; `alpha` in
/// (0, 1)). At `λ = 0` it is the central point.
pub fn noncentral_chi2_point(k: usize, lambda: f64, alpha: f64) -> f64 {
    let kf = k.max(1) as f64;
    let lambda = lambda.max(0.0);
    let mut hi = kf + lambda + 10.0;
    while noncentral_chi2_upper(hi, kf, lambda) > alpha {
        hi *= 2.0;
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if noncentral_chi2_upper(mid, kf, lambda) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-10 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// The complementary error function (Numerical Recipes' Chebyshev fit, relative error
/// below 1.2e-7 everywhere).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// `P(χ²_k > x)`: the regularised upper incomplete gamma function `Q(k/2, x/2)`.
pub fn chi2_upper(x: f64, k: f64) -> f64 {
    if x.is_nan() || x <= 0.0 {
        return 1.0;
    }
    gamma_q(0.5 * k, 0.5 * x)
}

/// Regularised upper incomplete gamma `Q(a, x)` (series below `a + 1`, Lentz's continued
/// fraction above; Numerical Recipes §6.2), to about 1e-14.
fn gamma_q(a: f64, x: f64) -> f64 {
    let log_prefactor = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        let (mut sum, mut term, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..1000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (1.0 - sum * log_prefactor.exp()).clamp(0.0, 1.0)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (log_prefactor.exp() * h).clamp(0.0, 1.0)
    }
}

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7, nine terms; relative error below 1e-15).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The χ²₁ upper points against a published table (Abramowitz & Stegun, table 26.8):
    /// 3.841 at 5 %, 6.635 at 1 %, 10.828 at 0.1 % (the same as [`chi2_999`]'s), 15.137
    /// at 0.01 %.
    #[test]
    fn chi2_1_upper_points_match_the_table() {
        for (alpha, x) in [
            (0.05, 3.841),
            (0.01, 6.635),
            (0.001, 10.828),
            (1e-4, 15.137),
        ] {
            let got = chi2_1_upper(alpha);
            assert!((got - x).abs() < 2e-3, "α = {alpha}: {got} against {x}");
        }
        assert!((chi2_1_upper(0.001) - chi2_999(1)).abs() < 2e-3);
    }

    /// With one degree of freedom the noncentral χ² is the square of a normal variable of
    /// mean √λ, so its tail is `Φ̄(√x − √λ) + Φ̄(√x + √λ)` in closed form; at λ = 0 the
    /// noncentral tail and points are the central ones.
    #[test]
    fn noncentral_chi2_matches_the_closed_form_of_one_degree_of_freedom() {
        let normal_upper = |z: f64| 0.5 * erfc(z / std::f64::consts::SQRT_2);
        for lambda in [0.3f64, 1.0, 4.0, 25.0, 120.0] {
            for x in [0.5f64, 3.0, 10.8, 40.0, 200.0] {
                let exact =
                    normal_upper(x.sqrt() - lambda.sqrt()) + normal_upper(x.sqrt() + lambda.sqrt());
                let got = noncentral_chi2_upper(x, 1.0, lambda);
                assert!(
                    (got - exact).abs() < 1e-6 * exact.max(1e-3),
                    "λ {lambda}, x {x}: {got} against {exact}"
                );
            }
            let x = noncentral_chi2_point(1, lambda, 0.001);
            let tail =
                normal_upper(x.sqrt() - lambda.sqrt()) + normal_upper(x.sqrt() + lambda.sqrt());
            assert!(
                (tail - 0.001).abs() < 1e-8,
                "λ {lambda}: point {x}, tail {tail}"
            );
        }
        for k in 1..=5 {
            assert!((noncentral_chi2_point(k, 0.0, 0.001) - chi2_999(k)).abs() < 2e-3);
            assert!(
                (noncentral_chi2_upper(7.0, k as f64, 0.0) - chi2_upper(7.0, k as f64)).abs()
                    < 1e-15
            );
        }
    }
}
