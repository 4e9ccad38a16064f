//! Each force plate's clock read jointly from the three clock profiles
//! (`diagnose --profile-clocks` with the right, left and shared clock among the candidates).
//!
//! In the forces alone a left plate 20 ms early is the right plate 20 ms late and both
//! plates 20 ms early: only the kinematics, through the contact events each plate's
//! clock moves, tell the shared part from the relative one. A one-plate clock candidate
//! holds the other plate's clock at zero, so it takes the relative timing either way. On
//! the real 600 Hz trial whose left plate was edited 20 ms early, the compliant foot read
//! the left clock −20.6 ± 4.5 ms against the untouched trial and the right clock, which
//! was not edited, +24.9 ± 5.4 ms (`tests/clocks_600hz.rs`).
//!
//! The three profiles are sections of one cost over both offsets `x = (r, l)`, along
//! `(1, 0)`, `(0, 1)` and `(1, 1)`. If that cost is quadratic near its minimum,
//! `J ≈ c + gᵀx + ½ xᵀHx`, each profile's parabola `c + b δ + a δ²` gives
//! `a_R = ½ H_rr`, `a_L = ½ H_ll`, `a_B = ½ (H_rr + 2 H_rl + H_ll)` and
//! `b_R = g_r`, `b_L = g_l`, `b_B = g_r + g_l`: `H` from the curvatures, `g` from the
//! three slopes by least squares. The joint minimum is `x* = −H⁻¹ g`, with covariance
//! `2 k H⁻¹`, where `k = φ s²` is the noise scale each profile's own sd was set with
//! (its `sd² a`; the largest of the three). No solve is added: the profiles' points are
//! the only evidence, and a profile whose parabola is missing leaves no joint reading.

use super::profile::{at_bound, plate};
use crate::problems::diagnose::{ProfileVertex, ScoreTest};
use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};

/// The label of the joint reading wherever it is reported or compared.
pub const LABEL: &str = "each plate's clock (the three profiles jointly)";

/// The parameter names of the joint reading: the right plate's, then the left's.
pub const PARAMETERS: [&str; 2] = [
    "force_plate_time_offset.right.offset",
    "force_plate_time_offset.left.offset",
];

/// The name of the plates' relative timing, the left plate's offset less the right's:
/// the part of the joint reading the forces decide ([`PlateClocks::relative`]).
pub const RELATIVE: &str = "force_plate_time_offset.left_minus_right";

/// Both plates' clock offsets read jointly from the three clock profiles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlateClocks {
    /// The offsets (s) of the right and the left plate at the quadratic's minimum.
    pub offsets: [f64; 2],
    /// Their covariance (s²).
    pub covariance: [[f64; 2]; 2],
    /// How much lower the quadratic is at its minimum than at zero offsets (in the costs
    /// the profiles compare their points by).
    pub decrease: f64,
    /// The noise scale `k = φ s²` (the same costs): the largest of the three profiles'
    /// `sd² a`. `decrease / k` is the reading's statistic, as a profile's is its
    /// decrease over `φ s²`, against the χ²₂ point.
    #[serde(default)]
    pub noise_scale: f64,
    /// The shared clock's profile slope at zero less the sum of the two plates' (as a
    /// fraction of the largest of the three): how far the three sections are from one
    /// quadratic (0: exactly one).
    pub slope_mismatch: f64,
    /// Whether either offset lies at or beyond the bounds of its range: a limit the data
    /// push against, not a reading.
    pub at_bound: bool,
}

impl PlateClocks {
    /// The two offsets' standard deviations (s).
    pub fn sd(&self) -> [f64; 2] {
        [self.covariance[0][0].sqrt(), self.covariance[1][1].sqrt()]
    }

    /// The correlation of the two offsets.
    pub fn correlation(&self) -> f64 {
        let [sr, sl] = self.sd();
        self.covariance[0][1] / (sr * sl)
    }

    /// The left plate's offset less the right's (s), with its sd: the plates' relative
    /// timing, which the forces alone decide.
    pub fn relative(&self) -> (f64, f64) {
        let c = &self.covariance;
        (
            self.offsets[1] - self.offsets[0],
            (c[0][0] + c[1][1] - 2.0 * c[0][1]).max(0.0).sqrt(),
        )
    }

    /// The joint reading from the right (`r`), left (`l`) and shared (`b`) clock profiles'
    /// vertices, or why there is none.
    pub fn from_profiles(
        r: &ProfileVertex,
        l: &ProfileVertex,
        b: &ProfileVertex,
    ) -> Result<Self, String> {
        let section = |v: &ProfileVertex, name: &str| -> Result<(f64, f64, f64), String> {
            let (a, slope) = v
                .parabola
                .ok_or_else(|| format!("the {name} clock's profile has no parabola"))?;
            let sd =
                v.sd.filter(|s| s.is_finite() && *s > 0.0)
                    .ok_or_else(|| format!("the {name} clock's profile vertex has no sd"))?;
            if !(a > 0.0 && a.is_finite() && slope.is_finite()) {
                return Err(format!(
                    "the {name} clock's profile does not bend upwards at its lowest"
                ));
            }
            Ok((a, slope, sd * sd * a))
        };
        let (ar, br, kr) = section(r, "right")?;
        let (al, bl, kl) = section(l, "left")?;
        let (ab, bb, kb) = section(b, "shared")?;
        let h = Matrix2::new(2.0 * ar, ab - ar - al, ab - ar - al, 2.0 * al);
        let Some(cholesky) = h.cholesky() else {
            return Err(format!(
                "the three profiles' curvatures (right {ar:.3e}, left {al:.3e}, shared {ab:.3e} per s²) make no quadratic with a minimum: the shared profile bends too little or too much for the two plates' profiles"
            ));
        };
        // least squares of g_r = b_R, g_l = b_L, g_r + g_l = b_B
        let g = Vector2::new((2.0 * br - bl + bb) / 3.0, (2.0 * bl - br + bb) / 3.0);
        let x = -cholesky.solve(&g);
        let k = kr.max(kl).max(kb);
        let covariance = cholesky.inverse() * (2.0 * k);
        let scale = br.abs().max(bl.abs()).max(bb.abs());
        Ok(PlateClocks {
            offsets: [x[0], x[1]],
            covariance: [
                [covariance[(0, 0)], covariance[(0, 1)]],
                [covariance[(1, 0)], covariance[(1, 1)]],
            ],
            decrease: -0.5 * g.dot(&x),
            noise_scale: k,
            slope_mismatch: if scale > 0.0 {
                (bb - br - bl) / scale
            } else {
                0.0
            },
            at_bound: x.iter().any(|&o| at_bound(o)),
        })
    }
}

/// Which plate's clock alone explains a joint difference from the reference better.
///
/// Both one-plate clock candidates take the plates' relative timing (the module's
/// introduction), so against a reference they differ together or not at all; what tells
/// them apart is the shared timing, in the joint reading. Each one-plate hypothesis is
/// the joint difference `d` with the other plate's offset held at zero: with `p` free,
/// holding `q` at zero leaves `d_q² / C_qq` unexplained (the minimum over `p` of the
/// quadratic form is the marginal of `q`). The hypothesis that leaves less is favoured,
/// by the likelihood ratio `exp(Δχ² / 2)`. It is settled only when the other hypothesis
/// is rejected, i.e. when the favoured plate's own offset (which the other holds at zero)
/// differs beyond the threshold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WhichPlate {
    /// The plate whose clock alone explains the difference better: `right` or `left`.
    pub favoured: String,
    /// The χ² each one-plate hypothesis leaves unexplained: only the right plate's clock
    /// moved, only the left's.
    pub unexplained: [f64; 2],
    /// The favoured hypothesis's likelihood ratio over the other's (≥ 1; at most
    /// `exp(700)`, so that it stays a finite number in `summary.json`).
    pub likelihood_ratio: f64,
}

impl WhichPlate {
    /// The index of the favoured plate in [`PARAMETERS`] (0 right, 1 left).
    pub fn index(&self) -> usize {
        usize::from(self.favoured == "left")
    }
}

/// The one-plate hypotheses compared on the joint difference `difference` (right, left;
/// s) with covariance `covariance` (s²): `None` when a variance is not positive and
/// finite, or the two explain it equally.
pub fn which_plate(difference: [f64; 2], covariance: [[f64; 2]; 2]) -> Option<WhichPlate> {
    let var = [covariance[0][0], covariance[1][1]];
    if !var.iter().all(|v| v.is_finite() && *v > 0.0) || !difference.iter().all(|d| d.is_finite()) {
        return None;
    }
    // only the right plate moved leaves the left plate's difference, and vice versa
    let unexplained = [
        difference[1] * difference[1] / var[1],
        difference[0] * difference[0] / var[0],
    ];
    let favoured = match unexplained[0].total_cmp(&unexplained[1]) {
        std::cmp::Ordering::Less => 0,
        std::cmp::Ordering::Greater => 1,
        std::cmp::Ordering::Equal => return None,
    };
    Some(WhichPlate {
        favoured: ["right", "left"][favoured].to_string(),
        unexplained,
        likelihood_ratio: (0.5 * (unexplained[1 - favoured] - unexplained[favoured]))
            .min(700.0)
            .exp(),
    })
}

/// The refined profile vertex of the clock candidate of plate `side` (`right`, `left`,
/// `both`) among `tests`, if it was profiled.
fn vertex_of<'a>(tests: &[&'a ScoreTest], side: &str) -> Option<&'a ProfileVertex> {
    tests
        .iter()
        .find(|t| plate(&t.effect) == Some(side))
        .and_then(|t| t.profile.as_ref()?.vertex.as_ref())
}

/// The joint reading of `tests` (a diagnosis's ranking): `None` when not all three clock
/// candidates were profiled, else the reading or why there is none.
pub fn read<'a>(
    tests: impl IntoIterator<Item = &'a ScoreTest>,
) -> Option<Result<PlateClocks, String>> {
    let tests: Vec<&ScoreTest> = tests.into_iter().filter(|t| t.testable).collect();
    let [r, l, b] = ["right", "left", "both"].map(|s| vertex_of(&tests, s));
    Some(PlateClocks::from_profiles(r?, l?, b?))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vertex of the profile of `f` along `dir` at the offsets a profile holds, the
    /// parabola through its lowest point and neighbours, its sd with noise scale `k`.
    fn section(f: &dyn Fn(f64, f64) -> f64, dir: (f64, f64), k: f64) -> ProfileVertex {
        let pts: Vec<(f64, f64)> = [-0.04, -0.02, 0.0, 0.02, 0.04]
            .iter()
            .map(|&t| (t, f(t * dir.0, t * dir.1)))
            .collect();
        let p = super::super::profile::parabola(&pts).unwrap();
        ProfileVertex {
            offset: -p.b / (2.0 * p.a),
            sd: Some((k / p.a).sqrt()),
            parabola: Some((p.a, p.b)),
        }
    }

    /// On an exact quadratic in both offsets, steeper across the plates' relative timing
    /// than along their shared one (as the forces make it), the three sections give its
    /// minimum and `2 k H⁻¹` (against the inverse computed by hand), the one-plate
    /// sections' own vertices being elsewhere; the relative timing's sd is then smaller
    /// than either plate's.
    #[test]
    fn three_sections_of_a_quadratic_give_its_minimum_and_covariance() {
        // H = [[2400, −1600], [−1600, 2000]], minimum at (+24 ms, +4 ms)
        let (hrr, hrl, hll) = (2400.0, -1600.0, 2000.0);
        let (r0, l0) = (0.024, 0.004);
        let f = |r: f64, l: f64| {
            let (dr, dl) = (r - r0, l - l0);
            0.3 + 0.5 * (hrr * dr * dr + 2.0 * hrl * dr * dl + hll * dl * dl)
        };
        let k = 1.3e-4;
        let [vr, vl, vb] = [(1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].map(|d| section(&f, d, k));
        // the one-plate sections read elsewhere than the joint minimum
        assert!((vl.offset - l0).abs() > 0.01, "{}", vl.offset);
        let j = PlateClocks::from_profiles(&vr, &vl, &vb).unwrap();
        assert!(
            (j.offsets[0] - r0).abs() < 1e-12 && (j.offsets[1] - l0).abs() < 1e-12,
            "{j:?}"
        );
        let det = hrr * hll - hrl * hrl;
        let want = [[hll / det, -hrl / det], [-hrl / det, hrr / det]];
        for i in 0..2 {
            for m in 0..2 {
                let w = 2.0 * k * want[i][m];
                assert!(
                    (j.covariance[i][m] - w).abs() < 1e-9 * w.abs(),
                    "{i}{m}: {j:?}"
                );
            }
        }
        assert!(j.slope_mismatch.abs() < 1e-9);
        let d0 = f(0.0, 0.0) - f(r0, l0);
        assert!((j.decrease - d0).abs() < 1e-9 * d0);
        assert_eq!(j.noise_scale, k);
        let (rel, rel_sd) = j.relative();
        assert!((rel - (l0 - r0)).abs() < 1e-12);
        assert!(rel_sd < j.sd()[0].min(j.sd()[1]));
        assert!(!j.at_bound);
    }

    /// Each one-plate hypothesis leaves what the quadratic form of the joint difference
    /// keeps at its minimum over that plate's offset (found by brute force on a fine
    /// grid), and the plate that leaves less is favoured: on the stop-73 compliant
    /// left-clock figures (left −21.3, right −1.4 ms, sd 12 ms, correlation +0.91) the
    /// left, by about 4.8 : 1.
    #[test]
    fn the_plate_whose_clock_alone_leaves_least_unexplained_is_favoured() {
        let (sr, sl, rho) = (0.0122, 0.0120, 0.907);
        let c = [[sr * sr, rho * sr * sl], [rho * sr * sl, sl * sl]];
        let d = [-0.0014, -0.0213];
        let det = c[0][0] * c[1][1] - c[0][1] * c[0][1];
        let form = |x: f64, y: f64| {
            let (a, b) = (d[0] - x, d[1] - y);
            (c[1][1] * a * a - 2.0 * c[0][1] * a * b + c[0][0] * b * b) / det
        };
        let grid = |f: &dyn Fn(f64) -> f64| {
            (-200_000..=200_000)
                .map(|i| f(i as f64 * 1e-6))
                .fold(f64::INFINITY, f64::min)
        };
        let right_only = grid(&|x| form(x, 0.0));
        let left_only = grid(&|y| form(0.0, y));
        let w = which_plate(d, c).unwrap();
        assert!(
            (w.unexplained[0] - right_only).abs() < 1e-6,
            "{w:?} {right_only}"
        );
        assert!(
            (w.unexplained[1] - left_only).abs() < 1e-6,
            "{w:?} {left_only}"
        );
        assert_eq!(w.favoured, "left");
        assert_eq!(w.index(), 1);
        let ratio = (0.5 * (right_only - left_only)).exp();
        assert!((w.likelihood_ratio - ratio).abs() < 1e-5 * ratio, "{w:?}");
        assert!(
            w.likelihood_ratio > 4.0 && w.likelihood_ratio < 6.0,
            "{w:?}"
        );
        // the mirror image favours the right plate by the same ratio
        let m = which_plate([d[1], d[0]], [[c[1][1], c[0][1]], [c[0][1], c[0][0]]]).unwrap();
        assert_eq!(m.favoured, "right");
        assert!((m.likelihood_ratio - w.likelihood_ratio).abs() < 1e-12);
        // a decisive difference keeps a finite ratio
        let far = which_plate([0.0, 1.0], [[1e-4, 0.0], [0.0, 1e-4]]).unwrap();
        assert!(
            far.likelihood_ratio.is_finite() && far.likelihood_ratio > 1e300,
            "{far:?}"
        );
        // no preference between equal explanations, none without a variance
        assert!(which_plate([0.01, 0.01], [[1e-4, 0.0], [0.0, 1e-4]]).is_none());
        assert!(which_plate(d, [[0.0, 0.0], [0.0, 1e-4]]).is_none());
    }

    /// A shared profile flatter than the two plates' leave no minimum (an indefinite
    /// quadratic), and a profile without its parabola leaves no reading: both say why.
    #[test]
    fn sections_that_make_no_minimum_give_no_reading() {
        let bowl = |a: f64| ProfileVertex {
            offset: 0.0,
            sd: Some(0.005),
            parabola: Some((a, 0.0)),
        };
        // a_B = 0.1 a: H_rl = −1.9 a, det = 4a² − 3.61 a² > 0 still; a_B → 0 makes
        // H_rl = −2a, det 0
        let e = PlateClocks::from_profiles(&bowl(300.0), &bowl(300.0), &bowl(0.0)).unwrap_err();
        assert!(e.contains("shared clock") || e.contains("bend"), "{e}");
        let e = PlateClocks::from_profiles(&bowl(300.0), &bowl(300.0), &bowl(1500.0)).unwrap_err();
        assert!(e.contains("no quadratic with a minimum"), "{e}");
        let mut none = bowl(300.0);
        none.parabola = None;
        let e = PlateClocks::from_profiles(&bowl(300.0), &none, &bowl(600.0)).unwrap_err();
        assert!(e.contains("left clock's profile has no parabola"), "{e}");
    }
}
