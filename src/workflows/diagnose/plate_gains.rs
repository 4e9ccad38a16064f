//! Both force plates' gains read jointly (the catalog's `force_plate_gain:side=each`
//! candidate), and which of three hypotheses their difference from a reference favours:
//! only the right plate's gain is off, only the left's, or both alike.
//!
//! A one-plate gain candidate holds the other plate's gain at zero. In double support the
//! two plates share the body's load, so a one-plate reading takes up part of a load error
//! of the other plate: on the real 600 Hz trial whose left plate was edited 6 % high, the
//! compliant foot read the right plate's gain +10.5 ± 7.6 % against the untouched trial
//! (truth 0), and the body-mass error, which scales both plates' forces alike, ranked
//! above the left gain by 0.14 sd. Both gains free in one
//! truncated re-fit read each plate's with the other's taken into account; the difference
//! from the reference is then a point `d` in the plane of the two gains with covariance
//! `C` (the two runs' summed, each `2 φ s² H⁻¹` of its reduced Fisher information).
//!
//! Each hypothesis is a line through zero along `u`: `(1, 0)` the right plate only,
//! `(0, 1)` the left only, `(1, 1)` both plates alike (a body-mass error, or one gain of
//! both plates: in the forces the two are the same, only the joint torques tell them
//! apart). The best point on the line leaves `dᵀC⁻¹d − (uᵀC⁻¹d)² / uᵀC⁻¹u` of the
//! difference's χ² unexplained (one degree of freedom). The hypothesis that leaves least
//! is favoured, by the likelihood ratio `exp(Δχ² / 2)` over the next; another hypothesis
//! is rejected when what it leaves exceeds the comparison's threshold. For the axes this
//! is [`plate_clocks::which_plate`](super::plate_clocks::which_plate)'s `d_q² / C_qq`.
//!
//! On the gain trial the joint reading puts the right plate at +0.4 ± 7.4 % and the left
//! at +5.9 ± 1.8 % and favours the left plate alone, 1.24 : 1 over both alike; on the
//! trial with every force 5 % high it favours both alike, 1.28 : 1. The right
//! plate, loaded only in the first double support of the half cycle, reads its gain to
//! 7 %, so neither is settled.

use crate::problems::diagnose::ScoreTest;
use serde::{Deserialize, Serialize};

/// The candidate's label (`EffectSpec::label` of `force_plate_gain:side=each`).
pub const LABEL: &str = "force-plate gain (each plate)";

/// Its parameters: the right plate's gain error, then the left's.
pub const PARAMETERS: [&str; 2] = [
    "force_plate_gain.right.error",
    "force_plate_gain.left.error",
];

/// The hypotheses, in the order of [`WhichGain::unexplained`]: each a direction in the
/// plane of the two gains (right, left).
pub const HYPOTHESES: [(&str, [f64; 2]); 3] = [
    ("right", [1.0, 0.0]),
    ("left", [0.0, 1.0]),
    ("both", [1.0, 1.0]),
];

/// The one-candidate rows each hypothesis stands for in a comparison: `(label,
/// parameter)`. Both plates alike is what a body-mass error and a gain of both plates
/// make of the forces.
pub const ROWS: [&[(&str, &str)]; 3] = [
    &[("force-plate gain (right)", "force_plate_gain.right.error")],
    &[("force-plate gain (left)", "force_plate_gain.left.error")],
    &[
        ("body-mass error", "body_mass_error.relative"),
        ("force-plate gain", "force_plate_gain.error"),
    ],
];

/// The joint gains' difference from the reference, and which hypothesis explains it
/// best.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WhichGain {
    /// The difference of the two gains from the reference's (right, left; relative).
    pub difference: [f64; 2],
    /// Its covariance (the two runs' summed).
    pub covariance: [[f64; 2]; 2],
    /// The favoured hypothesis: `right`, `left` or `both` (plates alike).
    pub favoured: String,
    /// The χ² each hypothesis leaves unexplained, in the order of [`HYPOTHESES`].
    pub unexplained: [f64; 3],
    /// The favoured hypothesis's likelihood ratio over the next best (≥ 1; at most
    /// `exp(700)`, a finite number in `summary.json`).
    pub likelihood_ratio: f64,
}

impl WhichGain {
    /// The index of the favoured hypothesis in [`HYPOTHESES`].
    pub fn index(&self) -> usize {
        HYPOTHESES
            .iter()
            .position(|h| h.0 == self.favoured)
            .unwrap_or(0)
    }

    /// Whether every other hypothesis leaves more than `threshold` (the comparison's
    /// `z²` threshold) unexplained: the favoured one is then a finding, not a preference.
    pub fn settled(&self, threshold: f64) -> bool {
        let f = self.index();
        (0..3)
            .filter(|&i| i != f)
            .all(|i| self.unexplained[i] > threshold)
    }
}

/// What the line through zero along `u` leaves of the χ² of `d` with covariance `c`:
/// `dᵀC⁻¹d − (uᵀC⁻¹d)² / uᵀC⁻¹u`. `None` when `c` is not positive definite or a value is
/// not finite.
pub fn unexplained_along(d: [f64; 2], c: [[f64; 2]; 2], u: [f64; 2]) -> Option<f64> {
    let det = c[0][0] * c[1][1] - c[0][1] * c[1][0];
    let finite = d.iter().chain(c.iter().flatten()).all(|v| v.is_finite());
    if !(finite && c[0][0] > 0.0 && c[1][1] > 0.0 && det > 0.0) {
        return None;
    }
    let inv = [
        [c[1][1] / det, -c[0][1] / det],
        [-c[1][0] / det, c[0][0] / det],
    ];
    let form = |a: [f64; 2], b: [f64; 2]| {
        (0..2)
            .map(|i| (0..2).map(|j| a[i] * inv[i][j] * b[j]).sum::<f64>())
            .sum::<f64>()
    };
    let (dd, ud, uu) = (form(d, d), form(u, d), form(u, u));
    Some((dd - ud * ud / uu).max(0.0))
}

/// The three hypotheses compared on the joint difference `d` (right, left) with
/// covariance `c`: `None` when `c` is not positive definite or two hypotheses explain it
/// equally well at the best.
pub fn which_gain(d: [f64; 2], c: [[f64; 2]; 2]) -> Option<WhichGain> {
    let mut unexplained = [0.0; 3];
    for (u, h) in unexplained.iter_mut().zip(HYPOTHESES) {
        *u = unexplained_along(d, c, h.1)?;
    }
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| unexplained[a].total_cmp(&unexplained[b]));
    let (best, next) = (order[0], order[1]);
    if unexplained[best] == unexplained[next] {
        return None;
    }
    Some(WhichGain {
        difference: d,
        covariance: c,
        favoured: HYPOTHESES[best].0.to_string(),
        unexplained,
        likelihood_ratio: (0.5 * (unexplained[next] - unexplained[best]))
            .min(700.0)
            .exp(),
    })
}

/// The joint candidate's reading in a diagnosis: its two gains and their covariance
/// `2 φ s² H⁻¹` (each sd as the candidate's own, their correlation from `H⁻¹`). `None`
/// when it is not testable, lacks its information, or a gain is at its bound.
pub fn reading(t: &ScoreTest) -> Option<([f64; 2], [[f64; 2]; 2])> {
    if !t.testable || t.label != LABEL || t.parameters != PARAMETERS || !t.at_bound.is_empty() {
        return None;
    }
    let id = t.identifiability.as_ref()?;
    let h = &id.reduced_inverse_hessian;
    let sd = [id.sd.first()?.as_ref()?, id.sd.get(1)?.as_ref()?].map(|s| *s);
    if h.len() != 2 || h.iter().any(|r| r.len() != 2) || !(h[0][0] > 0.0 && h[1][1] > 0.0) {
        return None;
    }
    let rho = h[0][1] / (h[0][0] * h[1][1]).sqrt();
    let values = [*t.step_values.first()?, *t.step_values.get(1)?];
    let off = rho * sd[0] * sd[1];
    Some((values, [[sd[0] * sd[0], off], [off, sd[1] * sd[1]]]))
}

/// Both runs' joint readings compared: this run's (`ours`) less the reference's
/// (`theirs`), with the summed covariance.
pub fn compare(ours: &[ScoreTest], theirs: &[&ScoreTest]) -> Option<WhichGain> {
    let (a, ca) = ours.iter().find_map(reading)?;
    let (b, cb) = theirs.iter().find_map(|t| reading(t))?;
    let c = [0, 1].map(|i| [0, 1].map(|j| ca[i][j] + cb[i][j]));
    which_gain([a[0] - b[0], a[1] - b[1]], c)
}

/// The hypothesis (index into [`HYPOTHESES`]) whose rows include `row`, a difference's
/// `(label, parameter)`, if any.
pub fn group(row: (&str, &str)) -> Option<usize> {
    ROWS.iter().position(|g| g.contains(&row))
}

/// The rows of `rows` (each a difference's `(label, parameter)`, sorted by |z|) that the
/// three hypotheses stand for, reordered so that the favoured hypothesis's rows take the
/// earliest of their places and the others follow in their own order; every other row
/// keeps its place. Returns the new order as indices into `rows`.
pub fn order(rows: &[(&str, &str)], w: &WhichGain) -> Vec<usize> {
    let group = |i: usize| group(rows[i]);
    let places: Vec<usize> = (0..rows.len()).filter(|&i| group(i).is_some()).collect();
    let favoured = w.index();
    let mut moved: Vec<usize> = places
        .iter()
        .copied()
        .filter(|&i| group(i) == Some(favoured))
        .collect();
    moved.extend(
        places
            .iter()
            .copied()
            .filter(|&i| group(i) != Some(favoured)),
    );
    let mut out: Vec<usize> = (0..rows.len()).collect();
    for (slot, from) in places.iter().zip(moved) {
        out[*slot] = from;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each hypothesis leaves the minimum over its line of the difference's quadratic form
    /// (brute force on a fine grid), and the line that leaves least is favoured; on the
    /// axes this is `d_q² / C_qq`, the one-plate clocks' rule.
    #[test]
    fn the_hypothesis_whose_line_leaves_least_is_favoured() {
        let (sr, sl, rho) = (0.070, 0.014, -0.4);
        let c = [[sr * sr, rho * sr * sl], [rho * sr * sl, sl * sl]];
        let det = c[0][0] * c[1][1] - c[0][1] * c[0][1];
        let form = |d: [f64; 2], x: f64, y: f64| {
            let (a, b) = (d[0] - x, d[1] - y);
            (c[1][1] * a * a - 2.0 * c[0][1] * a * b + c[0][0] * b * b) / det
        };
        let grid = |f: &dyn Fn(f64) -> f64| {
            (-300_000..=300_000)
                .map(|i| f(i as f64 * 1e-6))
                .fold(f64::INFINITY, f64::min)
        };
        // a left plate 6 % high, the right read near zero: the left is favoured
        let d = [0.01, 0.06];
        let w = which_gain(d, c).unwrap();
        for (i, h) in HYPOTHESES.iter().enumerate() {
            let brute = grid(&|t| form(d, t * h.1[0], t * h.1[1]));
            assert!(
                (w.unexplained[i] - brute).abs() < 1e-6,
                "{}: {w:?} {brute}",
                h.0
            );
        }
        assert_eq!(w.favoured, "left");
        let mut sorted = w.unexplained;
        sorted.sort_by(f64::total_cmp);
        let ratio = (0.5 * (sorted[1] - sorted[0])).exp();
        assert!((w.likelihood_ratio - ratio).abs() < 1e-9 * ratio, "{w:?}");
        // the axes' rule
        assert!((w.unexplained[0] - d[1] * d[1] / c[1][1]).abs() < 1e-9);
        assert!((w.unexplained[1] - d[0] * d[0] / c[0][0]).abs() < 1e-9);
        // both plates 5 % high: both alike is favoured, and rejects the others when the
        // two are read well
        let both = which_gain([0.05, 0.05], c).unwrap();
        assert_eq!(both.favoured, "both");
        assert!(both.unexplained[2] < 1e-12);
        assert!(!both.settled(16.0), "the right plate's gain is read to 7 %");
        let sharp = [[1e-4, 0.0], [0.0, 1e-4]];
        assert!(which_gain([0.05, 0.05], sharp).unwrap().settled(16.0));
        // no preference without a positive definite covariance
        assert!(which_gain(d, [[c[0][0], sr * sl], [sr * sl, c[1][1]]]).is_none());
        assert!(which_gain(d, [[0.0, 0.0], [0.0, 1e-4]]).is_none());
    }

    /// The favoured hypothesis's rows take the earliest of the gain rows' places; the
    /// others keep their order after it, every other row its place.
    #[test]
    fn the_favoured_hypothesis_rows_come_first_of_the_gain_rows() {
        let rows = [
            ("body-mass error", "body_mass_error.relative"),
            ("ground slope", "ground_slope.angle"),
            ("force-plate gain (left)", "force_plate_gain.left.error"),
            ("force-plate gain (right)", "force_plate_gain.right.error"),
            (LABEL, PARAMETERS[1]),
        ];
        let favour = |f: &str| WhichGain {
            difference: [0.0; 2],
            covariance: [[1.0, 0.0], [0.0, 1.0]],
            favoured: f.into(),
            unexplained: [0.0; 3],
            likelihood_ratio: 1.0,
        };
        assert_eq!(order(&rows, &favour("left")), vec![2, 1, 0, 3, 4]);
        assert_eq!(order(&rows, &favour("right")), vec![3, 1, 0, 2, 4]);
        assert_eq!(order(&rows, &favour("both")), vec![0, 1, 2, 3, 4]);
    }
}
