//! Hessian approximations and convexity checks for the QP subproblems: block-diagonal
//! BFGS of the Lagrangian Hessian and the inertia correction of the exact Hessian.
//!
//! One dense block per group of variables (in multiple shooting: a node's state and
//! control). With $s$, $y$ the block's step and Lagrangian-gradient change, the block is
//! updated $B \leftarrow B - Bss^TB/(s^TBs) + rr^T/(s^Tr)$, with $r = y$ when the curvature
//! condition $s^Ty > 10^{-8}\|s\|\|y\|$ holds (the update is skipped otherwise), or with
//! Powell's damped $r$ ([`BfgsUpdate`]); either way every block stays positive definite.
//! Measured on the five-link biped: skipping reaches the reference optimum in about a
//! third of the iterations Powell damping needs, which keeps over-estimated curvature.
//! The first update rescales the initial identity by $y^Ty/s^Ty$ (Nocedal–Wright 6.20).

/// How a block treats a step along which its Lagrangian is not convex.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BfgsUpdate {
    /// Skip the update unless `sᵀy > 1e-8 ‖s‖‖y‖`.
    SkipNonconvex,
    /// Powell's damping: replace y by `r = θy + (1−θ)Bs` with θ chosen so that
    /// `sᵀr ≥ 0.2 sᵀBs`.
    PowellDamped,
}

/// Block BFGS matrices.
#[derive(Debug, Clone)]
pub struct BlockBfgs {
    blocks: Vec<Vec<usize>>,
    mats: Vec<Vec<f64>>,
    scaled: Vec<bool>,
    rule: BfgsUpdate,
}

impl BlockBfgs {
    /// Identity blocks.
    pub fn new(blocks: Vec<Vec<usize>>, rule: BfgsUpdate) -> Self {
        let mats = blocks
            .iter()
            .map(|b| {
                let k = b.len();
                let mut m = vec![0.0; k * k];
                for i in 0..k {
                    m[i * k + i] = 1.0;
                }
                m
            })
            .collect();
        let scaled = vec![false; blocks.len()];
        Self {
            blocks,
            mats,
            scaled,
            rule,
        }
    }

    /// The blocks (row-major) and whether each has been scaled: the state a checkpoint keeps.
    pub fn state(&self) -> Vec<(Vec<f64>, bool)> {
        self.mats
            .iter()
            .cloned()
            .zip(self.scaled.iter().copied())
            .collect()
    }

    /// Restore the blocks from [`state`](Self::state); `false` if the block sizes differ.
    pub fn restore(&mut self, state: Vec<(Vec<f64>, bool)>) -> bool {
        if state.len() != self.mats.len()
            || state
                .iter()
                .zip(&self.mats)
                .any(|((m, _), own)| m.len() != own.len())
        {
            return false;
        }
        for (i, (m, s)) in state.into_iter().enumerate() {
            self.mats[i] = m;
            self.scaled[i] = s;
        }
        true
    }

    /// Multiply every block by `s` (e.g. a small initial curvature for the structured
    /// mode, where the Gauss–Newton part carries the objective).
    pub fn scale(&mut self, s: f64) {
        for m in &mut self.mats {
            for v in m.iter_mut() {
                *v *= s;
            }
        }
    }

    /// Update every block with the full-space step `s` and gradient change `y`.
    pub fn update(&mut self, s: &[f64], y: &[f64]) {
        for (bi, block) in self.blocks.iter().enumerate() {
            let k = block.len();
            let sb: Vec<f64> = block.iter().map(|&i| s[i]).collect();
            let yb: Vec<f64> = block.iter().map(|&i| y[i]).collect();
            let ss: f64 = sb.iter().map(|v| v * v).sum();
            if ss < 1e-24 {
                continue;
            }
            let m = &mut self.mats[bi];
            let sy: f64 = sb.iter().zip(&yb).map(|(a, b)| a * b).sum();
            if !self.scaled[bi] {
                let yy: f64 = yb.iter().map(|v| v * v).sum();
                if sy > 1e-12 * ss.sqrt() * yy.sqrt() && yy > 0.0 {
                    let gamma = yy / sy;
                    for v in m.iter_mut() {
                        *v *= gamma;
                    }
                    self.scaled[bi] = true;
                }
            }
            let bs: Vec<f64> = (0..k)
                .map(|i| (0..k).map(|j| m[i * k + j] * sb[j]).sum())
                .collect();
            let sbs: f64 = sb.iter().zip(&bs).map(|(a, b)| a * b).sum();
            if sbs <= 0.0 {
                continue;
            }
            let r: Vec<f64> = match self.rule {
                BfgsUpdate::SkipNonconvex => {
                    let yy: f64 = yb.iter().map(|v| v * v).sum();
                    if sy <= 1e-8 * ss.sqrt() * yy.sqrt() {
                        continue;
                    }
                    yb
                }
                BfgsUpdate::PowellDamped => {
                    let theta = if sy >= 0.2 * sbs {
                        1.0
                    } else {
                        0.8 * sbs / (sbs - sy)
                    };
                    (0..k)
                        .map(|i| theta * yb[i] + (1.0 - theta) * bs[i])
                        .collect()
                }
            };
            let sr: f64 = sb.iter().zip(&r).map(|(a, b)| a * b).sum();
            if sr <= 1e-16 * sbs {
                continue;
            }
            for i in 0..k {
                for j in 0..k {
                    m[i * k + j] += -bs[i] * bs[j] / sbs + r[i] * r[j] / sr;
                }
            }
        }
    }

    /// Add exact curvature `ex` (upper-triangle triplets) to the BFGS blocks it falls in,
    /// project each affected block onto the positive semidefinite cone (eigenvalues
    /// clipped at 1e-8 of the largest) so the QP stays convex, and append the result of
    /// those blocks to `h`; entries outside every block are appended unchanged. The
    /// stored BFGS blocks are not modified. Call instead of [`push_upper`](Self::push_upper).
    pub fn convexify_into(&self, ex: &mut super::qp::Triplets, h: &mut super::qp::Triplets) {
        use std::collections::HashMap;
        let mut where_: HashMap<usize, (usize, usize)> = HashMap::new();
        for (bi, block) in self.blocks.iter().enumerate() {
            for (a, &v) in block.iter().enumerate() {
                where_.insert(v, (bi, a));
            }
        }
        let mut extra: HashMap<usize, Vec<f64>> = HashMap::new();
        for k in 0..ex.vals.len() {
            let (r, c, v) = (ex.rows[k], ex.cols[k], ex.vals[k]);
            match (where_.get(&r), where_.get(&c)) {
                (Some(&(br, a)), Some(&(bc, b))) if br == bc => {
                    let kk = self.blocks[br].len();
                    let m = extra.entry(br).or_insert_with(|| vec![0.0; kk * kk]);
                    m[a * kk + b] += v;
                    if a != b {
                        m[b * kk + a] += v;
                    }
                }
                _ => h.push(r, c, v),
            }
        }
        for (bi, block) in self.blocks.iter().enumerate() {
            let k = block.len();
            let mut m = self.mats[bi].clone();
            if let Some(e) = extra.get(&bi) {
                for i in 0..k * k {
                    m[i] += e[i];
                }
                let sym = nalgebra::DMatrix::from_row_slice(k, k, &m);
                let eig = sym.symmetric_eigen();
                let top = eig.eigenvalues.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                let clipped = eig.eigenvalues.map(|v| v.max(1e-8 * top));
                let proj = &eig.eigenvectors
                    * nalgebra::DMatrix::from_diagonal(&clipped)
                    * eig.eigenvectors.transpose();
                for i in 0..k {
                    for j in 0..k {
                        m[i * k + j] = proj[(i, j)];
                    }
                }
            }
            for a in 0..k {
                for b in a..k {
                    let (r, c) = (block[a].min(block[b]), block[a].max(block[b]));
                    h.push(r, c, m[a * k + b]);
                }
            }
        }
    }

    /// Append the upper triangles of all blocks as triplets.
    pub fn push_upper(&self, t: &mut super::qp::Triplets) {
        for (bi, block) in self.blocks.iter().enumerate() {
            let k = block.len();
            for a in 0..k {
                for b in a..k {
                    let (r, c) = (block[a].min(block[b]), block[a].max(block[b]));
                    t.push(r, c, self.mats[bi][a * k + b]);
                }
            }
        }
    }
}

use super::qp::{CscPattern, Triplets};
use clarabel::qdldl::{QDLDLFactorisation, QDLDLSettings};

/// The matrices `h + ρ g + δI` of one convexity test (`h`, `g` symmetric, as triplets on
/// either triangle, duplicates summed). They share one sparsity pattern and one symbolic
/// LDLᵀ (QDLDL, AMD ordering), so each trial `(ρ, δ)` costs a numeric refactorisation
/// only: the exact-Hessian SQP tries up to three ρ and a sequence of δ per iteration on
/// patterns of a million entries, where sorting and ordering anew each time cost more
/// than the iteration's QP.
pub struct ConvexityTest {
    n: usize,
    nz_h: Vec<f64>,
    nz_g: Vec<f64>,
    diagonal: Vec<usize>,
    all: Vec<usize>,
    nz: Vec<f64>,
    factor: Option<QDLDLFactorisation<f64>>,
}

impl ConvexityTest {
    /// The test of `h + ρ g + δI` for `n` variables.
    pub fn new(n: usize, h: &Triplets, g: &Triplets) -> Self {
        let len = h.rows.len() + g.rows.len() + n;
        let (mut rows, mut cols) = (Vec::with_capacity(len), Vec::with_capacity(len));
        for t in [h, g] {
            for k in 0..t.rows.len() {
                rows.push(t.rows[k].min(t.cols[k]));
                cols.push(t.rows[k].max(t.cols[k]));
            }
        }
        rows.extend(0..n);
        cols.extend(0..n);
        let pattern = CscPattern::new(n, n, &rows, &cols);
        let (mut nz_h, mut nz_g) = (vec![0.0; pattern.nnz()], vec![0.0; pattern.nnz()]);
        for k in 0..h.vals.len() {
            nz_h[pattern.slot(k)] += h.vals[k];
        }
        for k in 0..g.vals.len() {
            nz_g[pattern.slot(h.vals.len() + k)] += g.vals[k];
        }
        let diagonal = (0..n)
            .map(|i| pattern.slot(h.vals.len() + g.vals.len() + i))
            .collect();
        let nz = vec![0.0; pattern.nnz()];
        let settings = QDLDLSettings {
            regularize_enable: false,
            logical: true,
            ..Default::default()
        };
        let factor = QDLDLFactorisation::new(&pattern.matrix(nz.clone()), Some(settings)).ok();
        Self {
            n,
            nz_h,
            nz_g,
            diagonal,
            all: (0..pattern.nnz()).collect(),
            nz,
            factor,
        }
    }

    /// Whether `h + ρ g + δI` is positive definite: its LDLᵀ (no regularisation) has `n`
    /// positive, finite pivots.
    pub fn is_positive_definite(&mut self, rho: f64, shift: f64) -> bool {
        let Some(factor) = self.factor.as_mut() else {
            return false;
        };
        for (k, v) in self.nz.iter_mut().enumerate() {
            *v = self.nz_h[k] + rho * self.nz_g[k];
        }
        for &k in &self.diagonal {
            self.nz[k] += shift;
        }
        factor.update_values(&self.all, &self.nz);
        factor.refactor().is_ok()
            && factor.positive_inertia() == self.n
            && factor.D.iter().all(|d| d.is_finite() && *d > 0.0)
    }

    /// Smallest shift δ of the sequence `0, δ₀, 8δ₀, 64δ₀, …` (δ₀ = a third of the
    /// previous shift, at least `min_shift`) that makes `h + ρ g + δI` positive definite
    /// (the inertia correction of Wächter & Biegler 2006, §3.1); `None` above `max_shift`.
    pub fn shift(
        &mut self,
        rho: f64,
        previous: f64,
        min_shift: f64,
        max_shift: f64,
    ) -> Option<f64> {
        if self.is_positive_definite(rho, 0.0) {
            return Some(0.0);
        }
        let mut delta = (previous / 3.0).max(min_shift);
        while delta <= max_shift {
            if self.is_positive_definite(rho, delta) {
                return Some(delta);
            }
            delta *= 8.0;
        }
        None
    }
}

/// Whether the symmetric matrix `h` (upper-triangle triplets, duplicates summed) plus
/// `shift·I` is positive definite (a [`ConvexityTest`] of one trial).
pub fn is_positive_definite(n: usize, h: &Triplets, shift: f64) -> bool {
    ConvexityTest::new(n, h, &Triplets::default()).is_positive_definite(0.0, shift)
}

/// Smallest shift of the inertia-correction sequence that makes `h + δI` positive
/// definite (see [`ConvexityTest::shift`]); `None` above `max_shift`.
pub fn convexity_shift(
    n: usize,
    h: &Triplets,
    previous: f64,
    min_shift: f64,
    max_shift: f64,
) -> Option<f64> {
    ConvexityTest::new(n, h, &Triplets::default()).shift(0.0, previous, min_shift, max_shift)
}
