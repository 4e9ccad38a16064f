//! Limits beyond which an input value is refused as physically absurd, and a compact
//! number format for messages that quote such values.

/// Largest gravity (m/s²): ten times the Earth's.
pub const MAX_GRAVITY: f64 = 100.0;
/// Largest body or segment mass (kg).
pub const MAX_MASS: f64 = 1000.0;
/// Smallest stature (m): a newborn's; the model's segment lengths scale with it.
pub const MIN_HEIGHT: f64 = 0.5;
/// Largest stature (m).
pub const MAX_HEIGHT: f64 = 3.0;
/// Largest segment moment of inertia (kg·m²).
pub const MAX_INERTIA: f64 = 100.0;
/// Largest distance of a segment's centre of mass or joint from its frame's origin (m).
pub const MAX_SEGMENT_EXTENT: f64 = 10.0;
/// Largest measured ground-force component (N): about 100 body weights.
pub const MAX_FORCE: f64 = 1e5;
/// Largest ground height (m) from the model's origin.
pub const MAX_GROUND_HEIGHT: f64 = 10.0;
/// Largest Baumgarte stabilisation gain (1/s): stiffer than any sampling of a gait.
pub const MAX_BAUMGARTE: f64 = 1e4;
/// Largest MTG damping coefficient η (dimensionless; Millard & Mombaur use 0.4 to 2).
pub const MAX_ETA: f64 = 1e3;
/// Largest magnitude of an initial generalised coordinate (m or rad).
pub const MAX_COORDINATE: f64 = 100.0;
/// Largest magnitude of an initial generalised velocity (m/s or rad/s).
pub const MAX_VELOCITY: f64 = 1e3;
/// Most shooting intervals in a phase sequence, all phases together: forty times the
/// shipped cycles' 25 to 31; memory and the time of an iteration grow with the count.
pub const MAX_INTERVALS: usize = 1_000;
/// Longest phase (s), and longest phase sequence: a gait phase lasts under a second,
/// and a simulation's samples and time grow with its length.
pub const MAX_DURATION: f64 = 60.0;
/// Most contact primitives in a foot file: a foot of spheres has a dozen; the contact
/// bookkeeping grows with the square of the count.
pub const MAX_PRIMITIVES: usize = 100;
/// How many items a message lists before it counts the rest.
pub const LISTED: usize = 5;
/// Largest KKT tolerance a command accepts: the residual bounds the constraint violation
/// (m, rad), and a looser one calls a start centimetres off its constraints converged.
pub const MAX_KKT_TOL: f64 = 1e-2;
/// Most SQP (or Nelder–Mead) iterations a command accepts.
pub const MAX_ITERATIONS: usize = 100_000;

/// An option value outside the range a command accepts, refused before any work.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{option} {}: expected {expected}", show(*.value))]
pub struct OutOfRange {
    /// The option, as the command line spells it (`--tol`).
    pub option: &'static str,
    /// The value given.
    pub value: f64,
    /// What would be valid.
    pub expected: String,
}

/// A KKT tolerance (`--tol`): finite, > 0 and at most [`MAX_KKT_TOL`].
pub fn kkt_tolerance(tol: f64) -> Result<f64, OutOfRange> {
    if tol.is_finite() && tol > 0.0 && tol <= MAX_KKT_TOL {
        return Ok(tol);
    }
    Err(OutOfRange {
        option: "--tol",
        value: tol,
        expected: format!(
            "a KKT tolerance > 0 and ≤ {} (e.g. 1e-5; a looser one accepts constraint violations of centimetres)",
            show(MAX_KKT_TOL)
        ),
    })
}

/// An iteration limit (`--max-iter`): at most [`MAX_ITERATIONS`].
pub fn iteration_limit(n: usize) -> Result<usize, OutOfRange> {
    if n <= MAX_ITERATIONS {
        return Ok(n);
    }
    Err(OutOfRange {
        option: "--max-iter",
        value: n as f64,
        expected: format!("a whole number of iterations from 0 to {MAX_ITERATIONS}"),
    })
}

/// A wall-time limit (`--max-time`, s): finite and > 0.
pub fn time_limit(seconds: f64) -> Result<f64, OutOfRange> {
    if seconds.is_finite() && seconds > 0.0 {
        return Ok(seconds);
    }
    Err(OutOfRange {
        option: "--max-time",
        value: seconds,
        expected: "a finite number > 0 (seconds)".into(),
    })
}

/// `v` as plain decimal when that is short (1e-4 ≤ |v| < 1e6, or 0), else in
/// scientific notation: `1e308` never becomes 309 digits.
pub fn show(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// The first [`LISTED`] of `items` joined by ", ", with "and N more" for the rest: a
/// message quoting a list stays short however long the list.
pub fn first_few<T: std::fmt::Display>(items: &[T]) -> String {
    let mut out: Vec<String> = items.iter().take(LISTED).map(|i| i.to_string()).collect();
    if items.len() > LISTED {
        out.push(format!("and {} more", items.len() - LISTED));
    }
    out.join(", ")
}
