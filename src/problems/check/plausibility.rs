//! Whether the forces can be right against the body, judged by the whole-body balance:
//! the body mass they imply against the model's, and the horizontal force's sign. Units
//! (times in seconds, positions and CoP in metres, angles in radians) and the vertical
//! force's sign are checked where every trial is read, for every command
//! ([`GaitData::check_conventions`]).

use super::CheckError;
use crate::data::GaitData;

/// How far the mass the forces imply may lie from the model's before the trial is
/// refused (fraction): beyond 25 % the forces, their unit or the model belong to
/// someone else.
pub const MASS_REFUSED: f64 = 0.25;
/// Beyond this (fraction) the check warns.
pub const MASS_WARNED: f64 = 0.10;

/// What the balance says of the forces against the body: the mass they imply against
/// the model's, and the horizontal force's sign. `Err` where the data cannot be right,
/// else warnings (possibly none).
pub fn check_balance(
    data: &GaitData,
    model_mass: f64,
    implied_mass: f64,
    horizontal_correlation: f64,
) -> Result<Vec<String>, CheckError> {
    let path = data.source.display();
    let ratio = implied_mass / model_mass;
    if !ratio.is_finite() || (ratio - 1.0).abs() > MASS_REFUSED {
        return Err(CheckError::Implausible(format!(
            "{path}: the vertical forces imply a body of {implied_mass:.1} kg, the model's is {model_mass:.1} kg ({:+.0} %): the forces are in another unit, belong to another subject, or the model does (give the subject's model with --model)",
            100.0 * (ratio - 1.0)
        )));
    }
    if horizontal_correlation < -0.5 {
        return Err(CheckError::Implausible(format!(
            "{path}: columns 'grf_x_r', 'grf_x_l': the horizontal ground force runs against the body's horizontal acceleration (correlation {horizontal_correlation:.2}); footfall reads grf_x as the ground's force on the foot, + forward: the sign looks flipped"
        )));
    }
    let mut warnings = Vec::new();
    if (ratio - 1.0).abs() > MASS_WARNED {
        warnings.push(format!(
            "the vertical forces imply a body of {implied_mass:.1} kg, {:+.0} % from the model's {model_mass:.1} kg",
            100.0 * (ratio - 1.0)
        ));
    }
    Ok(warnings)
}
