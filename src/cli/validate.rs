//! Value parsers of numeric options: clap refuses a bad value before anything runs,
//! naming the option and what would be valid (clap's usage errors exit with code 2).

use footfall::limits::MAX_ITERATIONS;

fn number(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .map_err(|_| format!("'{s}' is not a number"))
}

/// A tolerance, time, rate or force: finite and > 0.
pub fn positive(s: &str) -> Result<f64, String> {
    match number(s)? {
        v if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err("expected a finite number > 0".into()),
    }
}

/// A KKT tolerance: finite, > 0 and at most [`MAX_KKT_TOL`](footfall::limits::MAX_KKT_TOL)
/// ([`footfall::limits::kkt_tolerance`], which the workflows apply as well).
pub fn kkt_tolerance(s: &str) -> Result<f64, String> {
    footfall::limits::kkt_tolerance(number(s)?).map_err(|e| format!("expected {}", e.expected))
}

/// A weight or standard deviation: finite and ≥ 0.
pub fn non_negative(s: &str) -> Result<f64, String> {
    match number(s)? {
        v if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err("expected a finite number ≥ 0".into()),
    }
}

/// A switching threshold: ≥ 0, `inf` allowed (never reached: switch at once).
pub fn threshold(s: &str) -> Result<f64, String> {
    match number(s)? {
        v if v >= 0.0 => Ok(v),
        _ => Err("expected a number ≥ 0 (or inf)".into()),
    }
}

/// A `--plate FOOT=PREFIX|FOOT=N` item whose foot is r or l (the file checks the rest).
pub fn plate(s: &str) -> Result<String, String> {
    footfall::workflows::trial::split_plate(s)
        .map(|_| s.to_string())
        .map_err(|e| e.to_string())
}

/// An `--effect NAME[:key=value,…]` text naming a known effect with valid parameters.
pub fn effect(s: &str) -> Result<String, String> {
    footfall::model::effects::EffectSpec::parse_cli(s)
        .map(|_| s.to_string())
        .map_err(|e| e.to_string())
}

/// An iteration limit: 0 to [`MAX_ITERATIONS`].
pub fn iterations(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n <= MAX_ITERATIONS => Ok(n),
        _ => Err(format!(
            "expected a whole number of iterations from 0 to {MAX_ITERATIONS}"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_nan_negative_infinite_and_oversized_values() {
        for bad in ["NaN", "-1", "0", "inf", "x"] {
            assert!(positive(bad).is_err(), "{bad}");
        }
        assert_eq!(positive("1e-5"), Ok(1e-5));
        assert!(kkt_tolerance("1e300").is_err() && kkt_tolerance("-1").is_err());
        assert_eq!(kkt_tolerance("1e-2"), Ok(1e-2));
        assert!(non_negative("-0.1").is_err() && non_negative("NaN").is_err());
        assert_eq!(non_negative("0"), Ok(0.0));
        assert!(threshold("NaN").is_err() && threshold("-1").is_err());
        assert_eq!(threshold("inf"), Ok(f64::INFINITY));
        assert!(iterations("100001").is_err() && iterations("-1").is_err());
        assert_eq!(iterations("100000"), Ok(100_000));
    }
}
