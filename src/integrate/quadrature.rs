//! Gauss–Legendre quadrature on [0, 1] for the interval curvature identity: the fixed
//! 4-point rule, and the same interval split into pieces at interior instants (sample
//! targets), each piece with a rule sized to its length; for a stiff model every piece
//! is divided further ([`STIFF_SPLIT`]).

/// Gauss–Legendre nodes and weights on [0, 1], 4 points (exact for polynomials of
/// degree 7; on 17.5–50 ms intervals the interval Hessians agree with finite differences
/// of the exact gradient to the differences' own accuracy, ~1e-8, tests/ocp_engine.rs).
pub(super) const GAUSS4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

/// Into how many equal parts each piece of a stiff model's interval is divided, each with
/// the piece's rule. The compliant foot's integrand (the contact force's curvature along
/// the state's sensitivities) changes within a few milliseconds at heel strike and
/// toe-off. Measured at the kept solution of the bundled trial's compliant
/// identification track (tests/gait_hessian.rs): the assembled Hessian against
/// differences of the gradient, worst block of a random direction, 0.67 of the block's
/// largest entry undivided (the first interval, at heel strike), 0.20 in two parts, 4e-3
/// in four. With the undivided rule the SQP's KKT residual fell by 7 % per iteration near
/// the optimum, steps alternating in sign (the Hessian too flat along the pelvis height);
/// in two parts the same track converges. The generators' fast mode on a rigid foot
/// (the bundled tracking problem at 1e-12, tests/gait_hessian.rs): 1.4e-4 and 4.9e-4 of
/// the differences' largest entry undivided, 4.7e-6 and 1.5e-5 in two parts.
pub(super) const STIFF_SPLIT: usize = 2;

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
/// interior instants: the 4-point rule on [0, 1]. With `split` > 1 each piece's rule is
/// applied on that many equal parts of it (a stiff model, [`STIFF_SPLIT`]); the nodes
/// still name their piece's end, where the adjoint jumps.
#[cfg(test)]
pub(super) fn piece_nodes(interior: &[f64], split: usize) -> Vec<(f64, f64, f64)> {
    flatten(&piece_cells(interior, split))
}

/// One part of a piece: `[a, b]`, the end of its piece (where the adjoint jumps) and its
/// Gauss–Legendre nodes and weights.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Cell {
    pub(super) a: f64,
    pub(super) b: f64,
    pub(super) piece_end: f64,
    pub(super) nodes: Vec<(f64, f64)>,
}

/// The cells of [`piece_nodes`], in time order.
pub(super) fn piece_cells(interior: &[f64], split: usize) -> Vec<Cell> {
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
        push_split(&mut out, rule, a, b, split);
        a = b;
    }
    out
}

/// The 4-point rule on `split` equal parts of `[0, end]`, every node naming `end` as its
/// piece's end (a check point's own span).
#[cfg(test)]
pub(super) fn span_nodes(end: f64, split: usize) -> Vec<(f64, f64, f64)> {
    flatten(&span_cells(end, split))
}

/// The cells of [`span_nodes`], in time order.
pub(super) fn span_cells(end: f64, split: usize) -> Vec<Cell> {
    let mut out = Vec::new();
    push_split(&mut out, &GAUSS4, 0.0, end, split);
    out
}

/// Into how many geometrically shrinking cells (ratio 4) a stiff model's first cell is
/// divided toward τ = 0, each with the 2-point rule. The sensitivities start at
/// `[I | 0]`, and the fast contact mode of a compliant foot decays within microseconds
/// (`∂f/∂x` has eigenvalues near −2.7e5 1/s): the integrand has a boundary layer at the
/// interval's start that the piece's own rule, spaced in milliseconds, misses. The smallest
/// cell is 4⁻⁵ of the first, about a microsecond of a 20 ms interval split in two.
pub(super) const START_LAYER_CELLS: usize = 5;

/// Divide the first of `cells` into [`START_LAYER_CELLS`] cells shrinking toward its start,
/// plus the outer three quarters of it with its own rule.
pub(super) fn grade_start(cells: &mut Vec<Cell>) {
    let Some(first) = cells.first().cloned() else {
        return;
    };
    let (a, h) = (first.a, first.b - first.a);
    let mut graded = Vec::with_capacity(START_LAYER_CELLS + 1);
    let mut lo = a;
    for k in (1..=START_LAYER_CELLS).rev() {
        let hi = a + h * 0.25f64.powi(k as i32 - 1) * 0.25;
        let len = hi - lo;
        graded.push(Cell {
            a: lo,
            b: hi,
            piece_end: first.piece_end,
            nodes: GAUSS2
                .iter()
                .map(|&(g, w)| (lo + len * g, len * w))
                .collect(),
        });
        lo = hi;
    }
    // the outer part, [a + h/4, b], with the cell's own rule rescaled to it
    let len = first.b - lo;
    graded.push(Cell {
        a: lo,
        b: first.b,
        piece_end: first.piece_end,
        nodes: first
            .nodes
            .iter()
            .map(|&(t, w)| (lo + (t - a) / h * len, w / h * len))
            .collect(),
    });
    cells.splice(0..1, graded);
}

/// The nodes of `cells` as `(τ, weight, end of τ's piece)`, in order.
pub(super) fn flatten(cells: &[Cell]) -> Vec<(f64, f64, f64)> {
    cells
        .iter()
        .flat_map(|c| c.nodes.iter().map(move |&(t, w)| (t, w, c.piece_end)))
        .collect()
}

/// Append `rule` on each of `split` equal parts of `[a, b]` as cells of the piece ending at
/// `b`.
fn push_split(out: &mut Vec<Cell>, rule: &[(f64, f64)], a: f64, b: f64, split: usize) {
    let parts = split.max(1);
    let len = (b - a) / parts as f64;
    for k in 0..parts {
        let start = a + len * k as f64;
        let end = if k + 1 == parts {
            b
        } else {
            a + len * (k + 1) as f64
        };
        out.push(Cell {
            a: start,
            b: end,
            piece_end: b,
            nodes: rule
                .iter()
                .map(|&(g, w)| (start + len * g, len * w))
                .collect(),
        });
    }
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
        for (interior, split) in cases.iter().flat_map(|c| [(*c, 1), (*c, 2), (*c, 3)]) {
            let nodes = piece_nodes(interior, split);
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
                    0.0 < t && t < end && end <= 1.0,
                    "{interior:?}, split {split}: node {t} in a piece ending at {end}"
                );
            }
            // each piece's nodes are `split` copies of its rule, in time order
            assert!(
                nodes.windows(2).all(|p| p[0].0 < p[1].0),
                "{interior:?}: order"
            );
            assert_eq!(nodes.len() % split, 0);
        }
        assert_eq!(piece_nodes(&[], 1).len(), 4);
        assert_eq!(piece_nodes(&[], 2).len(), 8);
        // a sample every millisecond of a 20 ms interval: 20 one-point pieces
        let ms: Vec<f64> = (1..20).map(|k| f64::from(k) / 20.0).collect();
        assert_eq!(piece_nodes(&ms, 1).len(), 20);
    }

    /// A check point's own span: the 4-point rule on `split` parts of [0, end] integrates
    /// τ⁷ exactly on each part, so a degree-7 polynomial over the span exactly.
    #[test]
    fn span_nodes_integrate_a_degree_7_polynomial_over_the_span() {
        for split in 1..=3 {
            let end = 0.6;
            let nodes = span_nodes(end, split);
            assert_eq!(nodes.len(), 4 * split);
            let integral: f64 = nodes.iter().map(|&(t, w, _)| w * t.powi(7)).sum();
            let exact = end.powi(8) / 8.0;
            assert!(
                (integral - exact).abs() < 1e-15,
                "split {split}: {integral} vs {exact}"
            );
            assert!(nodes
                .iter()
                .all(|&(t, _, e)| e == end && 0.0 < t && t < end));
        }
    }
}
