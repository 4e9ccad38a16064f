//! Gauss–Legendre quadrature on [0, 1] for the interval curvature identity: the fixed
//! 4-point rule, and the same interval split into pieces at interior instants (sample
//! targets), each piece with a rule sized to its length.

/// Gauss–Legendre nodes and weights on [0, 1], 4 points (exact for polynomials of
/// degree 7; on 17.5–50 ms intervals the interval Hessians agree with finite differences
/// of the exact gradient to the differences' own accuracy, ~1e-8, tests/ocp_engine.rs).
pub(super) const GAUSS4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

/// Gauss–Legendre rules of 1 to 3 points on [0, 1] (nodes, weights).
const GAUSS1: [(f64, f64); 1] = [(0.5, 1.0)];
const GAUSS2: [(f64, f64); 2] = [
    (0.211_324_865_405_187_1, 0.5),
    (0.788_675_134_594_812_9, 0.5),
];
const GAUSS3: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];

/// Quadrature nodes of `[0, 1]` split at the interior instants `interior` (where the
/// adjoint of the curvature identity jumps): `(τ, weight, end of τ's piece)`, a
/// Gauss–Legendre rule on each piece with 4 points on a piece of at least half the
/// interval, 3 from a quarter, 2 from a tenth, 1 below (a sample every millisecond inside
/// a 20 ms interval: 20 one-point pieces instead of 19 four-point spans). Without
/// interior instants: the 4-point rule on [0, 1].
pub(super) fn piece_nodes(interior: &[f64]) -> Vec<(f64, f64, f64)> {
    let mut breaks: Vec<f64> = interior
        .iter()
        .copied()
        .filter(|&t| t > 0.0 && t < 1.0)
        .collect();
    breaks.sort_by(f64::total_cmp);
    breaks.dedup();
    breaks.push(1.0);
    let mut out = Vec::new();
    let mut a = 0.0;
    for b in breaks {
        let len = b - a;
        let rule: &[(f64, f64)] = if len >= 0.5 {
            &GAUSS4
        } else if len >= 0.25 {
            &GAUSS3
        } else if len >= 0.1 {
            &GAUSS2
        } else {
            &GAUSS1
        };
        out.extend(rule.iter().map(|&(g, w)| (a + len * g, len * w, b)));
        a = b;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫₀¹ τᵏ dτ = 1/(k+1) by a rule of (node, weight) pairs.
    fn moment(rule: &[(f64, f64)], k: i32) -> f64 {
        rule.iter().map(|&(t, w)| w * t.powi(k)).sum()
    }

    #[test]
    fn each_rule_is_exact_to_degree_2n_minus_1() {
        let rules: [&[(f64, f64)]; 4] = [&GAUSS1, &GAUSS2, &GAUSS3, &GAUSS4];
        for rule in rules {
            let n = rule.len() as i32;
            for k in 0..2 * n {
                let err = (moment(rule, k) - 1.0 / f64::from(k + 1)).abs();
                assert!(err < 1e-15, "{n}-point rule, degree {k}: error {err:e}");
            }
            // and not beyond: degree 2n is off (the rule is Gauss, not more)
            assert!((moment(rule, 2 * n) - 1.0 / f64::from(2 * n + 1)).abs() > 1e-6);
        }
    }

    #[test]
    fn pieces_cover_the_interval_and_integrate_a_cubic_exactly() {
        // one-point pieces integrate linear functions exactly: use instants that leave
        // only pieces of at least a tenth (two points and up) for the cubic
        let cases: [&[f64]; 4] = [&[], &[0.5], &[0.3, 0.3, 0.8, 1.0, 0.0], &[0.15, 0.45, 0.7]];
        for interior in cases {
            let nodes = piece_nodes(interior);
            let total: f64 = nodes.iter().map(|n| n.1).sum();
            assert!(
                (total - 1.0).abs() < 1e-15,
                "{interior:?}: weights sum to {total}"
            );
            let cubic: f64 = nodes
                .iter()
                .map(|&(t, w, _)| w * (t * t * t - 2.0 * t))
                .sum();
            assert!(
                (cubic - (0.25 - 1.0)).abs() < 1e-14,
                "{interior:?}: ∫ = {cubic}"
            );
            // every node lies inside its piece, and the pieces end at the instants
            for &(t, _, end) in &nodes {
                assert!(
                    t < end && end <= 1.0,
                    "{interior:?}: node {t} in a piece ending at {end}"
                );
            }
        }
        assert_eq!(piece_nodes(&[]).len(), 4);
        // a sample every millisecond of a 20 ms interval: 20 one-point pieces
        let ms: Vec<f64> = (1..20).map(|k| f64::from(k) / 20.0).collect();
        assert_eq!(piece_nodes(&ms).len(), 20);
    }
}
