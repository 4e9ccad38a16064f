//! Least-squares readings of the balance's parameters, with uncertainties that honour the
//! residual's autocorrelation.
//!
//! The residual $r_k(\theta)$ (three components per instant) is minimised by Gauss–Newton
//! with the exact Jacobian. Each component is weighted by the inverse of its own mean
//! square once the largest model is fitted ([`LARGEST`], feasible weighted least squares):
//! the weights are the body model's own misfit in each component, the same whichever
//! effect the data carry. Weights taken before any effect is read would shrink the
//! component that carries the effect (a plate's clock inflates the vertical force's
//! residual most) and hand the reading to the components the body model fits worst.
//! The covariance is the sandwich $B^{-1}\Omega B^{-1}$, $B = \sum_k J_k^T W J_k$, with $\Omega$ the Newey–West
//! (Bartlett-kernel) long-run covariance of the scores $s_k = J_k^T W r_k$ (Newey and West
//! 1987): neighbouring force samples of a smoothed residual are far from independent, and
//! an ordinary least-squares standard error would be too small by the square root of the
//! residual's correlation length in samples.

use super::balance::{residual, Body, Instant, Param, NPARAM};
use super::signals::Signals;
use crate::model::ad;
use nalgebra::{DMatrix, DVector};

/// The data of one reading: the body, the smoothed trial, the instants, the weights.
pub struct Problem<'a> {
    /// The model's body.
    pub body: &'a Body,
    /// The smoothed trial.
    pub signals: &'a Signals,
    /// The instants read.
    pub instants: &'a [Instant],
    /// Bartlett bandwidth (samples).
    pub bandwidth: usize,
    /// Largest clock magnitude (s): clocks are held within it.
    pub clock_limit: f64,
    /// Weights of the three components (1/N², 1/N², 1/(N·m)²): the inverse mean squares
    /// of the residual with the [`LARGEST`] model read ([`Problem::weighted`]).
    pub weights: [f64; 3],
}

/// The largest model whose parameters can be read together: each plate's clock, gain
/// and CoP offset, the trunk's centre of mass and the slope (the shared clock is the two
/// plates' clocks alike, the body mass the two gains alike, the trunk's mass the body
/// mass but for the limbs).
pub const LARGEST: [Param; 8] = [
    Param::ClockRight,
    Param::ClockLeft,
    Param::GainRight,
    Param::GainLeft,
    Param::CopRight,
    Param::CopLeft,
    Param::TrunkCom,
    Param::Slope,
];

/// Residual and Jacobian (in the listed parameters) at every instant.
pub struct Linearised {
    /// `[R_Fx, R_Fy, R_M]` per instant.
    pub r: Vec<[f64; 3]>,
    /// Row-major `3 × p` Jacobian per instant.
    pub jac: Vec<Vec<f64>>,
}

/// A fitted set of parameters.
#[derive(Debug, Clone)]
pub struct Fit {
    /// The parameters read, in θ order.
    pub active: Vec<Param>,
    /// θ (zero for the parameters not read).
    pub theta: [f64; NPARAM],
    /// Covariance of the active parameters (row-major).
    pub cov: Vec<f64>,
    /// Weighted residual sum of squares.
    pub rss: f64,
    /// Residual at each instant.
    pub residual: Vec<[f64; 3]>,
}

impl Fit {
    /// Standard deviation of parameter `p` (NaN if not read).
    pub fn sd(&self, p: Param) -> f64 {
        match self.active.iter().position(|&a| a == p) {
            Some(i) => self.cov[i * self.active.len() + i].max(0.0).sqrt(),
            None => f64::NAN,
        }
    }
}

impl<'a> Problem<'a> {
    /// The balance of `instants`, with the settings' Bartlett bandwidth and clock limit
    /// (1.5 force samples inside the stated one), each component weighing 1.
    pub fn new(
        body: &'a Body,
        signals: &'a Signals,
        instants: &'a [Instant],
        settings: &super::CheckSettings,
    ) -> Self {
        Problem {
            body,
            signals,
            instants,
            bandwidth: (settings.bandwidth_s * signals.force_rate).round() as usize,
            clock_limit: settings.clock_limit_s - 1.5 / signals.force_rate,
            weights: [1.0; 3],
        }
    }

    /// The same balance with each component weighted by the inverse of its mean square
    /// once the [`LARGEST`] model is read (until then every component weighs 1).
    pub fn weighted(mut self) -> Self {
        self.weights = self.weights_at(&[0.0; NPARAM]);
        for _ in 0..3 {
            let theta = self.descend(&LARGEST, &[0.0; NPARAM], 1e-6);
            self.weights = self.weights_at(&theta);
        }
        self
    }
}

impl Problem<'_> {
    /// Residual and Jacobian in `cols` at θ.
    pub fn linearise(&self, theta: &[f64; NPARAM], cols: &[Param]) -> Linearised {
        let p = cols.len();
        let mut r = Vec::with_capacity(self.instants.len());
        let mut jac = Vec::with_capacity(self.instants.len());
        let x: Vec<f64> = cols.iter().map(|c| theta[c.index()]).collect();
        for at in self.instants {
            let mut value = [0.0; 3];
            let mut j = vec![0.0; 3 * p];
            let ok = ad::jacobian(
                &x,
                3,
                |xs, out| {
                    let mut th = [ad::AdChunk::from(0.0); NPARAM];
                    for (k, v) in theta.iter().enumerate() {
                        th[k] = ad::AdChunk::from(*v);
                    }
                    for (c, v) in cols.iter().zip(xs) {
                        th[c.index()] = *v;
                    }
                    let res = residual(self.body, self.signals, at, &th).ok_or(())?;
                    out.copy_from_slice(&res);
                    Ok::<(), ()>(())
                },
                &mut value,
                &mut j,
            );
            if ok.is_err() {
                value = [f64::NAN; 3];
            }
            // column-major (i + j·3) to row-major (i·p + j)
            let mut row = vec![0.0; 3 * p];
            for i in 0..3 {
                for c in 0..p {
                    row[i * p + c] = j[i + 3 * c];
                }
            }
            r.push(value);
            jac.push(row);
        }
        Linearised { r, jac }
    }

    /// Read the parameters `active` (the others held at `start`) by Gauss–Newton.
    pub fn fit(&self, active: &[Param], start: &[f64; NPARAM]) -> Fit {
        let theta = self.descend(active, start, 0.0);
        self.finish(active, theta)
    }

    /// θ after Gauss–Newton in `active` from `start`, each step's normal matrix with
    /// `ridge` times its diagonal added (a window that cannot read some of them still
    /// moves the others).
    fn descend(&self, active: &[Param], start: &[f64; NPARAM], ridge: f64) -> [f64; NPARAM] {
        let mut theta = *start;
        for _ in 0..25 {
            let lin = self.linearise(&theta, active);
            let (mut b, g) = normal_equations(&lin, &self.weights, active.len());
            for k in 0..active.len() {
                b[(k, k)] *= 1.0 + ridge;
            }
            let Some(step) = b.cholesky().map(|c| c.solve(&(-g))) else {
                break;
            };
            for (k, c) in active.iter().enumerate() {
                theta[c.index()] += step[k];
            }
            self.hold_in_range(&mut theta);
            if step
                .iter()
                .zip(active)
                .all(|(s, c)| s.abs() < 1e-9 * scale(*c))
            {
                break;
            }
        }
        theta
    }

    /// The fit's covariance, residual and weighted sum of squares at θ.
    pub fn finish(&self, active: &[Param], theta: [f64; NPARAM]) -> Fit {
        let lin = self.linearise(&theta, active);
        let p = active.len();
        let (b, _) = normal_equations(&lin, &self.weights, p);
        let cov = sandwich(&lin, &self.weights, p, &b, self.bandwidth);
        Fit {
            active: active.to_vec(),
            theta,
            cov,
            rss: weighted_rss(&lin.r, &self.weights),
            residual: lin.r,
        }
    }

    /// `1 / mean square` of each residual component at θ.
    pub fn weights_at(&self, theta: &[f64; NPARAM]) -> [f64; 3] {
        let lin = self.linearise(theta, &[]);
        let mut ms = [0.0; 3];
        let mut n = 0.0;
        for r in lin.r.iter().filter(|r| r[0].is_finite()) {
            for i in 0..3 {
                ms[i] += r[i] * r[i];
            }
            n += 1.0;
        }
        ms.map(|m| if m > 0.0 { n / m } else { 1.0 })
    }

    /// Hold θ in the range a reading can take: the clocks within `clock_limit` (alone
    /// and with the shared one), every other parameter within [`range`]. Two near-equal
    /// signatures read together (a body-mass error and both plates' gains) can otherwise
    /// walk off along their shared direction to a fit of no physical meaning.
    fn hold_in_range(&self, theta: &mut [f64; NPARAM]) {
        for p in Param::ALL {
            if let Some(r) = range(p) {
                theta[p.index()] = theta[p.index()].clamp(-r, r);
            }
        }
        let lim = self.clock_limit;
        for c in [Param::SharedClock, Param::ClockRight, Param::ClockLeft] {
            theta[c.index()] = theta[c.index()].clamp(-lim, lim);
        }
        for c in [Param::ClockRight, Param::ClockLeft] {
            let total = theta[Param::SharedClock.index()] + theta[c.index()];
            let over = total.abs() - lim;
            if over > 0.0 {
                theta[c.index()] -= over * total.signum();
            }
        }
    }
}

/// The largest magnitude a reading of `p` can take (`None`: the clocks, held by the
/// problem's `clock_limit`): twice the body-mass error the units check refuses (25 %),
/// a CoP offset of a foot's length, a trunk COM shift of half the trunk, a mass of half
/// a trunk and a slope of 1 in 5.
pub fn range(p: Param) -> Option<f64> {
    match p {
        Param::SharedClock | Param::ClockRight | Param::ClockLeft => None,
        Param::GainRight | Param::GainLeft | Param::BodyMass => Some(0.5),
        Param::CopRight | Param::CopLeft => Some(0.25),
        Param::TrunkCom => Some(0.2),
        Param::TrunkMass => Some(20.0),
        Param::Slope => Some(0.2),
    }
}

/// A parameter's natural size, for the convergence test (s, 1, m, 1, m, kg, rad).
fn scale(p: Param) -> f64 {
    match p {
        Param::SharedClock | Param::ClockRight | Param::ClockLeft => 1e-3,
        Param::CopRight | Param::CopLeft | Param::TrunkCom => 1e-3,
        Param::TrunkMass => 0.1,
        _ => 1e-3,
    }
}

/// `B = Σ JᵀWJ` and `g = Σ JᵀWr` over the finite instants.
pub fn normal_equations(lin: &Linearised, w: &[f64; 3], p: usize) -> (DMatrix<f64>, DVector<f64>) {
    let mut b = DMatrix::zeros(p, p);
    let mut g = DVector::zeros(p);
    for (r, j) in lin.r.iter().zip(&lin.jac) {
        if !r[0].is_finite() {
            continue;
        }
        for i in 0..3 {
            for a in 0..p {
                let wa = w[i] * j[i * p + a];
                g[a] += wa * r[i];
                for c in 0..p {
                    b[(a, c)] += wa * j[i * p + c];
                }
            }
        }
    }
    (b, g)
}

/// Weighted residual sum of squares over the finite instants.
pub fn weighted_rss(r: &[[f64; 3]], w: &[f64; 3]) -> f64 {
    r.iter()
        .filter(|r| r[0].is_finite())
        .map(|r| (0..3).map(|i| w[i] * r[i] * r[i]).sum::<f64>())
        .sum()
}

/// The Newey–West sandwich covariance (row-major `p × p`; NaN where `b` is singular).
pub fn sandwich(
    lin: &Linearised,
    w: &[f64; 3],
    p: usize,
    b: &DMatrix<f64>,
    bandwidth: usize,
) -> Vec<f64> {
    if p == 0 {
        return vec![];
    }
    let scores: Vec<DVector<f64>> = lin
        .r
        .iter()
        .zip(&lin.jac)
        .filter(|(r, _)| r[0].is_finite())
        .map(|(r, j)| {
            DVector::from_iterator(
                p,
                (0..p).map(|a| (0..3).map(|i| w[i] * j[i * p + a] * r[i]).sum::<f64>()),
            )
        })
        .collect();
    let mut omega = DMatrix::zeros(p, p);
    for lag in 0..=bandwidth.min(scores.len().saturating_sub(1)) {
        let k = 1.0 - lag as f64 / (bandwidth as f64 + 1.0);
        let mut gamma = DMatrix::zeros(p, p);
        for t in lag..scores.len() {
            gamma += &scores[t] * scores[t - lag].transpose();
        }
        if lag == 0 {
            omega += gamma;
        } else {
            omega += (&gamma + gamma.transpose()) * k;
        }
    }
    match b.clone().try_inverse() {
        Some(bi) => (&bi * omega * &bi).as_slice().to_vec(),
        None => vec![f64::NAN; p * p],
    }
}
