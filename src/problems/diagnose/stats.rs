//! The statistics `diagnose` needs beyond the score test itself: whether a candidate's
//! parameters can be identified under the run's cost at all (the reduced Fisher
//! information), how much the residuals' autocorrelation inflates the variance of a
//! cost decrease (an effective sample size), and the noise band of a decrease measured
//! on data the fit did not see (held-out validation).
//!
//! Units: with the tracking cost `f = Σ rᵢ²` and residuals of variance `σ²`, the reduced
//! Hessian `H` of `f` w.r.t. a candidate's parameters (the other variables optimised
//! out) gives `Cov(θ̂) = 2 σ² H⁻¹` and, for parameters `θ` fixed from elsewhere, a cost
//! change `Δ = −gᵀθ − ½ θᵀHθ` with `Var(Δ) = 2 σ² θᵀHθ` (`g = 2 J_θᵀ r`,
//! `Cov(g) = 2 σ² H`). Correlated residuals replace `σ²` by `φ σ²`, `φ` the variance
//! inflation ([`variance_inflation`]).

use crate::ocp::{Block, Transcription};
use crate::problems::error::DiagnoseError;
use crate::sqp::linearised::{GaussNewtonModel, GaussNewtonStep, LinearisedError};
use crate::sqp::Nlp;
use serde::{Deserialize, Serialize};

/// A candidate is identifiable only if each parameter's standard deviation is below this
/// fraction of its bound span: an sd of a quarter of the span means the data cannot
/// tell apart values across the whole admissible range (a ±2 sd interval covers it).
pub const MAX_RELATIVE_SD: f64 = 0.25;

/// A candidate's reduced information is taken as rank deficient when the smallest
/// eigenvalue of its parameters' correlation matrix falls below this (the parameters
/// are then combinations the cost cannot separate, even if each alone looks bounded).
pub const MIN_CORRELATION_EIGENVALUE: f64 = 1e-6;

/// Whether a candidate's parameters are identifiable under the run's cost.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Identifiability {
    /// Parameter names.
    pub parameters: Vec<String>,
    /// Reduced Hessian inverse `H⁻¹` of the cost w.r.t. the parameters (the other
    /// variables optimised out under the linearised constraints), row-major `k × k`,
    /// in (parameter unit)² per cost unit (empty when it could not be computed).
    pub reduced_inverse_hessian: Vec<Vec<f64>>,
    /// Standard deviation of each parameter, `√(2 φ s² (H⁻¹)ⱼⱼ)` with `s² = J/N` and `φ`
    /// the variance inflation of correlated residuals (parameter units; `None` where the
    /// information is not positive).
    pub sd: Vec<Option<f64>>,
    /// Each parameter's bound span (upper − lower; parameter units).
    pub span: Vec<f64>,
    /// The smallest eigenvalue of the parameters' correlation matrix (1 for one
    /// parameter; near 0 when they trade off against each other).
    pub min_correlation_eigenvalue: f64,
    /// Whether every sd is finite and below [`MAX_RELATIVE_SD`] of its span and the
    /// information has full rank.
    pub testable: bool,
    /// Why not, when not testable.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

impl Identifiability {
    /// A candidate whose information could not be computed or is nil (`why`): not
    /// testable.
    pub fn unknown(parameters: Vec<String>, span: Vec<f64>, why: String) -> Self {
        let k = parameters.len();
        Identifiability {
            parameters,
            reduced_inverse_hessian: Vec::new(),
            sd: vec![None; k],
            span,
            min_correlation_eigenvalue: 0.0,
            testable: false,
            reason: Some(why),
        }
    }
}

/// The reduced Hessian inverse of the cost of `tr` at `w` w.r.t. the variables `cols`:
/// rows and columns `cols` of `Z (ZᵀHZ)⁻¹ Zᵀ` for the Gauss–Newton Hessian H and the
/// constraints active at the Gauss–Newton step ([`GaussNewtonModel::reduced_inverse`]),
/// i.e. the step's response to a unit shift of `∂f/∂w_j` while the active set stays
/// (the fallback probes the full QP with shifted gradients, 1–8 solves per column).
/// The bounds of `cols` are not held: a step that ran to a parameter's bound would not
/// respond, and the parameter would look perfectly known (a real left CoP offset held
/// so read "0.1000 ± 8e-5" at its 0.1 m bound). H is regularised as the score
/// test's (`1e-12` of the largest curvature), so a direction the cost does not see gets
/// an inverse of ~1e12 / max curvature instead of a singular matrix.
pub fn reduced_inverse_hessian(
    tr: &dyn Nlp,
    w: &[f64],
    cols: &[usize],
) -> Result<Vec<Vec<f64>>, DiagnoseError> {
    let m = GaussNewtonModel::new(tr, w, 1e-12)?;
    let base = m.step(None)?;
    reduced_inverse_hessian_at(tr, &m, &base, cols)
}

/// [`reduced_inverse_hessian`] from the Gauss–Newton model `m` at the point and its step
/// `base` (computed once with the score test's first step).
pub fn reduced_inverse_hessian_at(
    tr: &dyn Nlp,
    m: &GaussNewtonModel<'_>,
    base: &GaussNewtonStep,
    cols: &[usize],
) -> Result<Vec<Vec<f64>>, DiagnoseError> {
    let (w_lb, w_ub, _, _) = tr.bounds();
    // the active set of the step without the parameters' bounds, unless the step stays
    // clear of them (the same step either way)
    let near_bound = cols.iter().any(|&col| {
        let span = (w_ub[col] - w_lb[col]).min(1e6);
        let to = m.point()[col] + base.d[col];
        to - w_lb[col] <= 1e-2 * span || w_ub[col] - to <= 1e-2 * span
    });
    let relaxed;
    let base = if near_bound {
        relaxed = m.step_with(None, cols)?;
        &relaxed
    } else {
        base
    };
    // the equality-constrained QPs of the step's active set; should one fail, the full
    // QP's response to shifted gradients, probed column by column
    let k = cols.len();
    let mut c = match m.reduced_inverse(base, cols) {
        Ok(c) => c,
        Err(_) => probe_reduced_inverse(tr, m, base, cols)?,
    };
    for i in 0..k {
        for j in 0..i {
            let v = 0.5 * (c[i][j] + c[j][i]);
            c[i][j] = v;
            c[j][i] = v;
        }
    }
    Ok(c)
}

/// The reduced Hessian inverse from the Gauss–Newton QP's response to gradient shifts:
/// `(H⁻¹)_{·j}` is minus the step's change per unit shift of `∂f/∂w_j` while the active
/// set stays, with the bounds of `cols` lifted. Each probe aims its response at 1e-3 of
/// the variable's bound span.
fn probe_reduced_inverse(
    tr: &dyn Nlp,
    m: &GaussNewtonModel<'_>,
    base: &GaussNewtonStep,
    cols: &[usize],
) -> Result<Vec<Vec<f64>>, DiagnoseError> {
    let (w_lb, w_ub, _, _) = tr.bounds();
    let k = cols.len();
    let mut c = vec![vec![0.0; k]; k];
    let objective = m.objective().abs().max(1e-12);
    for (j, &col) in cols.iter().enumerate() {
        let span = (w_ub[col] - w_lb[col]).min(1e6);
        let target = 1e-3 * span;
        // first guess: a curvature that moves the cost by J over the span
        let mut eps = target * objective / (span * span);
        let mut column = vec![0.0; k];
        let mut probed = false;
        let mut failures = 0;
        let mut tries = 0;
        while tries < 8 {
            tries += 1;
            let mut shift = vec![0.0; tr.n()];
            shift[col] = eps;
            let s = match m.step_with(Some(&shift), cols) {
                Ok(s) => s,
                // a QP the shift made ill-posed: probe more gently
                Err(e) => {
                    failures += 1;
                    if failures > 3 {
                        return Err(DiagnoseError::Probe {
                            column: col,
                            source: e,
                        });
                    }
                    eps *= 1e-2;
                    continue;
                }
            };
            for (i, &ci) in cols.iter().enumerate() {
                column[i] = (base.d[ci] - s.d[ci]) / eps;
            }
            probed = true;
            let h = column[j];
            let ratio = (h * eps).abs() / target;
            if h <= 0.0 || (0.1..=10.0).contains(&ratio) {
                break;
            }
            eps = target / h;
        }
        if !probed {
            return Err(DiagnoseError::ProbeUnsolved { column: col });
        }
        for i in 0..k {
            c[i][j] = column[i];
        }
    }
    Ok(c)
}

/// Decide identifiability from the reduced Hessian inverse `c` of parameters `names`
/// with bound spans `span`, the cost's residual mean square `s2 = J/N` and the variance
/// inflation `phi`.
pub fn identifiability(
    names: Vec<String>,
    c: Vec<Vec<f64>>,
    span: Vec<f64>,
    s2: f64,
    phi: f64,
) -> Identifiability {
    let k = names.len();
    let sd: Vec<Option<f64>> = (0..k)
        .map(|j| {
            let v = 2.0 * phi * s2 * c[j][j];
            (v.is_finite() && c[j][j] > 0.0).then(|| v.sqrt())
        })
        .collect();
    let min_eig = if sd.iter().all(Option::is_some) {
        let corr: Vec<Vec<f64>> = (0..k)
            .map(|i| {
                (0..k)
                    .map(|j| c[i][j] / (c[i][i] * c[j][j]).sqrt())
                    .collect()
            })
            .collect();
        symmetric_eigenvalues(corr)
            .into_iter()
            .fold(f64::INFINITY, f64::min)
    } else {
        0.0
    };
    let mut reasons = Vec::new();
    for j in 0..k {
        let short = names[j].rsplit('.').next().unwrap_or(&names[j]).to_string();
        match sd[j] {
            None => reasons.push(format!("{short}: the cost has no curvature in it")),
            Some(s) if !(s < MAX_RELATIVE_SD * span[j]) => reasons.push(format!(
                "{short}: sd {s:.3e} is {:.0} % of its bound span {:.3e} (testable below {:.0} %)",
                100.0 * s / span[j],
                span[j],
                100.0 * MAX_RELATIVE_SD
            )),
            Some(_) => {}
        }
    }
    if reasons.is_empty() && !(min_eig > MIN_CORRELATION_EIGENVALUE) {
        reasons.push(format!(
            "its parameters trade off against each other (smallest correlation eigenvalue {min_eig:.1e})"
        ));
    }
    Identifiability {
        parameters: names,
        reduced_inverse_hessian: c,
        sd,
        span,
        min_correlation_eigenvalue: if min_eig.is_finite() { min_eig } else { 0.0 },
        testable: reasons.is_empty(),
        reason: (!reasons.is_empty()).then(|| reasons.join("; ")),
    }
}

/// Identifiability of the last `k` parameters of θ in `tr` ([`identifiability`]), from
/// the Gauss–Newton model `m` at the run's solution and its unshifted step `base` (or the
/// error computing it), computed once for the score test and the probes. Parameters whose
/// information cannot be computed are not testable, the reason saying why.
pub fn candidate_identifiability_at(
    tr: &Transcription,
    m: &GaussNewtonModel<'_>,
    base: Result<&GaussNewtonStep, &LinearisedError>,
    names: Vec<String>,
    s2: f64,
    phi: f64,
) -> Identifiability {
    let range = tr.range(Block::Params);
    let k = names.len();
    let cols: Vec<usize> = (range.end - k..range.end).collect();
    let (w_lb, w_ub, _, _) = crate::sqp::Nlp::bounds(tr);
    let span = cols.iter().map(|&c| w_ub[c] - w_lb[c]).collect();
    let failure = match base.map(|base| reduced_inverse_hessian_at(tr, m, base, &cols)) {
        Ok(Ok(c)) => return identifiability(names, c, span, s2, phi),
        Ok(Err(e)) => e.to_string(),
        Err(e) => e.to_string(),
    };
    if failure.contains("DualInfeasible") {
        // an unbounded probe: nothing in the cost resists a change of the parameter
        Identifiability::unknown(
            names,
            span,
            format!(
                "the cost has no curvature in it: the probing QP is unbounded along it ({failure})"
            ),
        )
    } else {
        Identifiability::unknown(
            names,
            span,
            format!("its information could not be computed ({failure})"),
        )
    }
}

/// `θᵀ H θ` for parameters `theta` (the reduced curvature along them) from the reduced
/// Hessian inverse `c` (`None` when `c` is singular).
pub fn curvature_along(c: &[Vec<f64>], theta: &[f64]) -> Option<f64> {
    if c.len() != theta.len() || theta.is_empty() {
        return None;
    }
    let h = invert(c)?;
    let q: f64 = (0..theta.len())
        .map(|i| {
            (0..theta.len())
                .map(|j| theta[i] * h[i][j] * theta[j])
                .sum::<f64>()
        })
        .sum();
    (q.is_finite() && q >= 0.0).then_some(q)
}

/// The noise band of a held-out cost change: a candidate fitted on noise alone and
/// applied with its values `θ` fixed to independent data changes that cost by
/// `Δ ~ N(−½ θᵀHθ, 2 φ s² θᵀHθ)` (module docs; it makes the fit worse on average). The
/// band's upper edge, `−½ q + 2 √(2 φ s² q)` with `q = θᵀHθ`, is what a held-out
/// decrease must exceed: below it, noise alone would explain it (one-sided, about 2.3 %).
pub fn held_out_band(q: f64, s2: f64, phi: f64) -> f64 {
    -0.5 * q + 2.0 * (2.0 * phi * s2 * q).sqrt()
}

/// Effective sample size of a residual series `x` (NaN entries split it into segments,
/// e.g. a force channel undefined in swing): `N_eff = N / (1 + 2 Σ ρ_k)`, with `ρ_k` the
/// autocorrelation at lag `k` pooled over the segments (about their common mean) and
/// the sum truncated before the first lag with `ρ_k ≤ 0` (or at `N/2`). Clamped to
/// `[1, N]`: negative correlation is not credited. `None` for fewer than 3 finite
/// values or a constant series.
pub fn effective_sample_size(x: &[f64]) -> Option<f64> {
    let segments: Vec<&[f64]> = x
        .split(|v| !v.is_finite())
        .filter(|s| !s.is_empty())
        .collect();
    let n: usize = segments.iter().map(|s| s.len()).sum();
    if n < 3 {
        return None;
    }
    let mean = segments.iter().flat_map(|s| s.iter()).sum::<f64>() / n as f64;
    let gamma = |lag: usize| -> f64 {
        segments
            .iter()
            .filter(|s| s.len() > lag)
            .map(|s| {
                (0..s.len() - lag)
                    .map(|t| (s[t] - mean) * (s[t + lag] - mean))
                    .sum::<f64>()
            })
            .sum::<f64>()
            / n as f64
    };
    let g0 = gamma(0);
    if !(g0 > 0.0) {
        return None;
    }
    let mut sum = 0.0;
    for lag in 1..n / 2 {
        let rho = gamma(lag) / g0;
        if !(rho > 0.0) {
            break;
        }
        sum += rho;
    }
    Some((n as f64 / (1.0 + 2.0 * sum)).clamp(1.0, n as f64))
}

/// Variance inflation `φ = N / N_eff` of each channel's residual series, and their mean
/// weighted by `weights` (e.g. how much of a candidate's decrease comes from each
/// channel; all-zero weights count every channel alike). Channels without a defined
/// size are left out; `1` when none is defined.
pub fn variance_inflation(series: &[Vec<f64>], weights: &[f64]) -> (Vec<Option<f64>>, f64) {
    let phis: Vec<Option<f64>> = series
        .iter()
        .map(|x| {
            let n = x.iter().filter(|v| v.is_finite()).count() as f64;
            effective_sample_size(x).map(|ne| n / ne)
        })
        .collect();
    let defined: Vec<(f64, f64)> = phis
        .iter()
        .zip(weights.iter().chain(std::iter::repeat(&0.0)))
        .filter_map(|(p, &w)| p.map(|p| (p, w.max(0.0))))
        .collect();
    if defined.is_empty() {
        return (phis, 1.0);
    }
    let wsum: f64 = defined.iter().map(|d| d.1).sum();
    let phi = if wsum > 0.0 {
        defined.iter().map(|(p, w)| p * w).sum::<f64>() / wsum
    } else {
        defined.iter().map(|d| d.0).sum::<f64>() / defined.len() as f64
    };
    (phis, phi.max(1.0))
}

/// Eigenvalues of a small symmetric matrix (cyclic Jacobi rotations).
pub fn symmetric_eigenvalues(mut a: Vec<Vec<f64>>) -> Vec<f64> {
    let n = a.len();
    for _ in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        if off < 1e-30 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
            }
        }
    }
    (0..n).map(|i| a[i][i]).collect()
}

/// Inverse of a small matrix by Gauss–Jordan with partial pivoting (`None` if singular).
fn invert(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    let mut m: Vec<Vec<f64>> = a
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let mut row = r.clone();
            row.extend((0..n).map(|j| if i == j { 1.0 } else { 0.0 }));
            row
        })
        .collect();
    let scale = a
        .iter()
        .flatten()
        .fold(0.0f64, |s, v| s.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    for col in 0..n {
        let p = (col..n).max_by(|&x, &y| m[x][col].abs().total_cmp(&m[y][col].abs()))?;
        if m[p][col].abs() < 1e-14 * scale {
            return None;
        }
        m.swap(col, p);
        let d = m[col][col];
        for v in &mut m[col] {
            *v /= d;
        }
        for r in 0..n {
            if r != col {
                let f = m[r][col];
                if f != 0.0 {
                    for c in 0..2 * n {
                        m[r][c] -= f * m[col][c];
                    }
                }
            }
        }
    }
    Some(m.into_iter().map(|r| r[n..].to_vec()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic AR(1) series `x_t = ρ x_{t−1} + e_t` (e uniform, zero mean, from
    /// a fixed linear congruential generator).
    fn ar1(rho: f64, n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let mut x = 0.0;
        (0..n + 200)
            .map(|_| {
                x = rho * x + next();
                x
            })
            .skip(200)
            .collect()
    }

    #[test]
    fn ar1_effective_sample_size_matches_the_analytic_value() {
        // for AR(1), 1 + 2 Σ ρ^k = (1 + ρ)/(1 − ρ)
        for &rho in &[0.0, 0.3, 0.6, 0.8] {
            let n = 20_000;
            let x = ar1(rho, n, 7);
            let want = n as f64 * (1.0 - rho) / (1.0 + rho);
            let got = effective_sample_size(&x).unwrap();
            assert!(
                (got / want - 1.0).abs() < 0.12,
                "ρ = {rho}: N_eff {got:.0}, analytic {want:.0}"
            );
        }
    }

    #[test]
    fn segments_split_at_nan_are_pooled() {
        let mut x = ar1(0.6, 5000, 3);
        x.push(f64::NAN);
        x.extend(ar1(0.6, 5000, 11));
        let want = 10_000.0 * 0.4 / 1.6;
        let got = effective_sample_size(&x).unwrap();
        assert!((got / want - 1.0).abs() < 0.15, "{got} vs {want}");
        assert_eq!(effective_sample_size(&[1.0, f64::NAN, 2.0]), None);
        assert_eq!(effective_sample_size(&[2.0; 10]), None);
    }

    #[test]
    fn inflation_weights_channels() {
        let white = ar1(0.0, 10_000, 5);
        let smooth = ar1(0.8, 10_000, 9);
        let (phis, phi) = variance_inflation(&[white.clone(), smooth.clone()], &[1.0, 0.0]);
        assert!((phi - phis[0].unwrap()).abs() < 1e-12);
        assert!((phis[1].unwrap() - 9.0).abs() < 1.2, "{:?}", phis);
        let (_, even) = variance_inflation(&[white, smooth], &[0.0, 0.0]);
        assert!((even - 0.5 * (phis[0].unwrap() + phis[1].unwrap())).abs() < 1e-12);
    }

    #[test]
    fn identifiability_flags_flat_and_traded_off_parameters() {
        // a well-determined parameter: sd √(2·1·1e-4·0.5) = 0.01 of span 1
        let ok = identifiability(vec!["a.x".into()], vec![vec![0.5]], vec![1.0], 1e-4, 1.0);
        assert!(ok.testable);
        assert!((ok.sd[0].unwrap() - 0.01).abs() < 1e-12);
        // the same with a 1e12 inverse curvature (what the regularised QP gives a
        // direction the cost does not see): sd far above a quarter of the span
        let flat = identifiability(vec!["a.x".into()], vec![vec![1e12]], vec![1.0], 1e-4, 1.0);
        assert!(!flat.testable && flat.reason.unwrap().contains("bound span"));
        // two parameters each bounded but almost perfectly correlated
        let c = vec![vec![1e-4, 0.999_999_9e-4], vec![0.999_999_9e-4, 1e-4]];
        let pair = identifiability(
            vec!["a.x".into(), "a.y".into()],
            c,
            vec![1.0, 1.0],
            1e-4,
            1.0,
        );
        assert!(!pair.testable, "{pair:?}");
        assert!(pair.min_correlation_eigenvalue < 1e-6);
    }

    #[test]
    fn eigenvalues_and_curvature() {
        let mut e = symmetric_eigenvalues(vec![vec![2.0, 1.0], vec![1.0, 2.0]]);
        e.sort_by(f64::total_cmp);
        assert!((e[0] - 1.0).abs() < 1e-12 && (e[1] - 3.0).abs() < 1e-12);
        // H⁻¹ = diag(0.5, 0.25): θᵀHθ = 2·1 + 4·4 = 18
        let q = curvature_along(&[vec![0.5, 0.0], vec![0.0, 0.25]], &[1.0, 2.0]).unwrap();
        assert!((q - 18.0).abs() < 1e-12);
        assert!((held_out_band(18.0, 0.5, 2.0) - (-9.0 + 2.0 * 36f64.sqrt())).abs() < 1e-12);
    }
}
