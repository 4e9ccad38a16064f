//! The SQP's state after an accepted iteration, to continue a killed solve exactly.
//!
//! Everything the iteration loop carries from one iteration to the next is here: the
//! iterate and multipliers, the filter, the adaptive constants of the QP convexification
//! and elastic mode, the BFGS blocks, and the history so far. The NLP's values at the
//! iterate are not stored: they are evaluated again, which gives the same bits because
//! evaluations are deterministic. Floating-point numbers are stored as their IEEE-754 bit
//! patterns (JSON numbers do not round-trip every `f64` exactly, nor infinities), so a
//! resumed solve follows the same iterates as one that never stopped.

use super::{IterationRecord, SqpTimings};
use serde::{Deserialize, Serialize};

/// Format version of [`SqpCheckpoint`].
pub const CHECKPOINT_VERSION: u32 = 2;

/// `f64`s stored as bit patterns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct ExactVec(pub Vec<u64>);

impl ExactVec {
    /// Store `v`.
    pub fn new(v: &[f64]) -> Self {
        Self(v.iter().map(|x| x.to_bits()).collect())
    }
    /// The stored values.
    pub fn values(&self) -> Vec<f64> {
        self.0.iter().map(|&b| f64::from_bits(b)).collect()
    }
}

/// An iteration record with its figures stored exactly.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExactRecord {
    /// Iteration number.
    pub iter: usize,
    /// objective, infeasibility, kkt, step, seconds as bit patterns.
    pub figures: [u64; 5],
    /// QP solver iterations.
    pub qp_iterations: u32,
    /// The integrator tolerance after the iteration, as a bit pattern.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub integration_tol: Option<u64>,
    /// The exact Hessian's shift, as a bit pattern.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hessian_shift: Option<u64>,
    /// Which QP gave the step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub qp_route: Option<super::QpRoute>,
}

impl From<&IterationRecord> for ExactRecord {
    fn from(r: &IterationRecord) -> Self {
        Self {
            iter: r.iter,
            figures: [r.objective, r.infeasibility, r.kkt, r.step, r.seconds].map(f64::to_bits),
            qp_iterations: r.qp_iterations,
            integration_tol: r.integration_tol.map(f64::to_bits),
            hessian_shift: r.hessian_shift.map(f64::to_bits),
            qp_route: r.qp_route,
        }
    }
}

impl From<&ExactRecord> for IterationRecord {
    fn from(r: &ExactRecord) -> Self {
        let [objective, infeasibility, kkt, step, seconds] = r.figures.map(f64::from_bits);
        Self {
            iter: r.iter,
            objective,
            infeasibility,
            kkt,
            step,
            seconds,
            qp_iterations: r.qp_iterations,
            integration_tol: r.integration_tol.map(f64::from_bits),
            hessian_shift: r.hessian_shift.map(f64::from_bits),
            qp_route: r.qp_route,
        }
    }
}

/// The SQP loop's state at the start of iteration [`next_iter`](Self::next_iter).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SqpCheckpoint {
    /// [`CHECKPOINT_VERSION`].
    pub version: u32,
    /// Number of variables and constraints of the NLP it belongs to.
    pub n: usize,
    /// Number of constraints.
    pub m: usize,
    /// The iteration the solve continues with.
    pub next_iter: usize,
    /// Iterate.
    pub w: ExactVec,
    /// Constraint multipliers of the last QP.
    pub lambda: ExactVec,
    /// Bound multipliers of the last QP.
    pub nu: ExactVec,
    /// lam_est, test_rho_scale, shift, theta_max, last_step, elapsed seconds and the
    /// integrator tolerance in force (NaN: the NLP does not integrate).
    pub scalars: ExactVec,
    /// Filter entries (infeasibility, objective), flattened.
    pub filter: ExactVec,
    /// BFGS blocks (row-major) and whether each has been scaled.
    pub bfgs: Vec<(ExactVec, bool)>,
    /// Iteration records so far.
    pub history: Vec<ExactRecord>,
    /// Time split so far.
    pub timings: SqpTimings,
}

/// A checkpoint that does not belong to the NLP it is resumed on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CheckpointError {
    /// Another format version.
    #[error("checkpoint format version {found}, this footfall reads version {CHECKPOINT_VERSION}")]
    Version {
        /// The checkpoint's version.
        found: u32,
    },
    /// Another problem size.
    #[error("the checkpoint is of a problem with {found_n} variables and {found_m} constraints, this one has {n} and {m}: the model, data or options changed since the run started")]
    Size {
        /// Checkpoint's variables.
        found_n: usize,
        /// Checkpoint's constraints.
        found_m: usize,
        /// This problem's variables.
        n: usize,
        /// This problem's constraints.
        m: usize,
    },
    /// A number the resumed solve needs finite is not.
    #[error("the checkpoint is damaged: {what}[{index}] is {value}, where a solve needs a finite number; start the run again without --resume")]
    NonFinite {
        /// Which vector: `w` (the iterate), `lambda`, `nu`, `bfgs`, `scalars` (the adaptive
        /// constants) or `filter`.
        what: &'static str,
        /// Index in it.
        index: usize,
        /// The value found.
        value: f64,
    },
    /// Inconsistent lengths inside the checkpoint.
    #[error("the checkpoint is damaged: {0}")]
    Damaged(&'static str),
}

impl SqpCheckpoint {
    /// Check that the checkpoint can continue a solve of an NLP with `n` variables and `m`
    /// constraints.
    pub fn check(&self, n: usize, m: usize) -> Result<(), CheckpointError> {
        if self.version != CHECKPOINT_VERSION {
            return Err(CheckpointError::Version {
                found: self.version,
            });
        }
        if self.n != n || self.m != m {
            return Err(CheckpointError::Size {
                found_n: self.n,
                found_m: self.m,
                n,
                m,
            });
        }
        if self.w.0.len() != n || self.nu.0.len() != n || self.lambda.0.len() != m {
            return Err(CheckpointError::Damaged(
                "vector lengths differ from the problem size",
            ));
        }
        if self.scalars.0.len() != 7 || self.filter.0.len() % 2 != 0 {
            return Err(CheckpointError::Damaged(
                "scalars or filter of the wrong length",
            ));
        }
        if self.history.len() != self.next_iter {
            return Err(CheckpointError::Damaged(
                "history length differs from the iteration count",
            ));
        }
        self.check_finite()
    }

    /// Check that the iterate, the multipliers and the BFGS blocks are finite, and that
    /// the adaptive constants and the filter hold no NaN (either would carry on to a
    /// different result; the filter's first entry and θ_max before the first line search
    /// are infinite by design, and the integrator tolerance is NaN for an NLP that does
    /// not integrate).
    pub fn check_finite(&self) -> Result<(), CheckpointError> {
        let nan = |what: &'static str, bits: &[u64]| {
            bits.iter()
                .position(|&b| f64::from_bits(b).is_nan())
                .map(|index| CheckpointError::NonFinite {
                    what,
                    index,
                    value: f64::NAN,
                })
        };
        let constants = &self.scalars.0[..self.scalars.0.len().min(6)];
        if let Some(e) = nan("scalars", constants).or_else(|| nan("filter", &self.filter.0)) {
            return Err(e);
        }
        let bfgs = self.bfgs.iter().flat_map(|(b, _)| b.0.iter());
        let vectors: [(&'static str, Box<dyn Iterator<Item = &u64>>); 4] = [
            ("w", Box::new(self.w.0.iter())),
            ("lambda", Box::new(self.lambda.0.iter())),
            ("nu", Box::new(self.nu.0.iter())),
            ("bfgs", Box::new(bfgs)),
        ];
        for (what, bits) in vectors {
            let found = bits
                .map(|&b| f64::from_bits(b))
                .enumerate()
                .find(|(_, v)| !v.is_finite());
            if let Some((index, value)) = found {
                return Err(CheckpointError::NonFinite { what, index, value });
            }
        }
        Ok(())
    }

    /// The iteration records so far.
    pub fn records(&self) -> Vec<IterationRecord> {
        self.history.iter().map(IterationRecord::from).collect()
    }
}
