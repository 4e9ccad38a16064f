//! Tracking-error statistics: what the error tables of Millard & Mombaur
//! (2019), Tables 3/4, report,
//! computed here; the report layer (`table` module) renders them.
//!
//! [`ErrorStats`] summarises a tracking error ε(t) = |model − measurement| over the
//! samples where it is defined: mean, standard deviation (population, 1/n, as NumPy's
//! default `std` in the CasADi peer's `evaluate.py`) and maximum.

/// Mean, standard deviation and maximum of absolute errors.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ErrorStats {
    /// Mean of |ε| (NaN when `n == 0`).
    pub mean: f64,
    /// Population standard deviation of |ε| (NaN when `n == 0`).
    pub sd: f64,
    /// Maximum of |ε| (NaN when `n == 0`).
    pub max: f64,
    /// Number of samples used (NaN samples are left out).
    pub n: usize,
}

impl ErrorStats {
    /// Statistics of |e| over the entries of `errors` that are not NaN. Infinite errors
    /// are kept (they make the mean infinite rather than hide a failure).
    pub fn from_errors(errors: &[f64]) -> Self {
        let abs: Vec<f64> = errors
            .iter()
            .filter(|e| !e.is_nan())
            .map(|e| e.abs())
            .collect();
        let n = abs.len();
        if n == 0 {
            return Self {
                mean: f64::NAN,
                sd: f64::NAN,
                max: f64::NAN,
                n: 0,
            };
        }
        let mean = abs.iter().sum::<f64>() / n as f64;
        let var = abs.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / n as f64;
        let max = abs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Self {
            mean,
            sd: var.sqrt(),
            max,
            n,
        }
    }

    /// Statistics of |model − measured| sample by sample (over the shorter length); a
    /// sample where either is NaN is left out.
    pub fn from_pair(model: &[f64], measured: &[f64]) -> Self {
        let e: Vec<f64> = model.iter().zip(measured).map(|(m, d)| m - d).collect();
        Self::from_errors(&e)
    }

    /// The same statistics in other units: mean, sd and max multiplied by `factor`
    /// (e.g. 180/π for radians to degrees, 100 for metres to centimetres).
    pub fn scaled(self, factor: f64) -> Self {
        let k = factor.abs();
        Self {
            mean: self.mean * k,
            sd: self.sd * k,
            max: self.max * k,
            n: self.n,
        }
    }
}

/// The errors of one channel (a joint angle, a GRF component, the CoP) in every run.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelErrors {
    /// Channel name, e.g. "knee angle θ_K − θ_K^EXP".
    pub name: String,
    /// Unit of the statistics, e.g. "°", "cm", "N" (convert with [`ErrorStats::scaled`]).
    pub unit: String,
    /// Digits after the decimal point.
    pub decimals: usize,
    /// One entry per run, in the order of the run names; `None`: not available (`—`).
    pub runs: Vec<Option<ErrorStats>>,
}
