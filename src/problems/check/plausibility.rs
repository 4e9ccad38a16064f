//! Whether the data can be right as declared, judged against physics before anything is
//! solved: times in seconds, positions and CoP in metres, the horizontal force's sign,
//! and the body mass the forces imply against the model's. Angles in radians and the
//! vertical force's sign are checked where every trial is read
//! ([`GaitData::check_conventions`]).

use super::CheckError;
use crate::data::GaitData;

/// Slowest kinematic rate that counts as motion capture (Hz); times in milliseconds read
/// as a rate below 1 Hz.
pub const MIN_RATE_HZ: f64 = 10.0;
/// Fastest (Hz); times in minutes read as tens of kilohertz.
pub const MAX_RATE_HZ: f64 = 5000.0;
/// Highest pelvis above the ground that a walking adult reaches (m); millimetres read as
/// hundreds of metres.
pub const MAX_PELVIS_HEIGHT_M: f64 = 2.0;
/// Farthest a loaded foot's CoP lies from the pelvis horizontally (m): a step is under
/// 1 m, so 1.5 m is beyond any foot's reach; CoP in millimetres reads as hundreds.
pub const MAX_COP_REACH_M: f64 = 1.5;
/// How far the mass the forces imply may lie from the model's before the trial is
/// refused (fraction): beyond 25 % the forces, their unit or the model belong to
/// someone else.
pub const MASS_REFUSED: f64 = 0.25;
/// Beyond this (fraction) the check warns.
pub const MASS_WARNED: f64 = 0.10;

/// Refuse data whose units cannot be right: the first finding, naming the file and the
/// column, with what would be plausible.
pub fn check_units(data: &GaitData) -> Result<(), CheckError> {
    let path = data.source.display();
    let rate = super::signals::median_rate(&data.time);
    if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate) {
        return Err(CheckError::Implausible(format!(
            "{path}: column 'time': samples {:.4} apart, a rate of {rate:.3} Hz; motion capture runs at {MIN_RATE_HZ}–{MAX_RATE_HZ} Hz. footfall reads time in seconds: times in milliseconds read as a rate below 1 Hz",
            1.0 / rate
        )));
    }
    let pelvis_y = &data.q[1];
    if let Some(top) = pelvis_y
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .reduce(f64::max)
    {
        if top > MAX_PELVIS_HEIGHT_M {
            return Err(CheckError::Implausible(format!(
                "{path}: column 'pelvis_y' reaches {top:.3}; a walking pelvis is under {MAX_PELVIS_HEIGHT_M} m above the ground. footfall reads positions in metres: millimetres read a thousand times too high"
            )));
        }
    }
    for (s, side) in [(0, "r"), (1, "l")] {
        let foot = &data.feet[s];
        for k in 0..data.time.len() {
            let (c, fy, px) = (foot.cop_x[k], foot.fy[k], data.q[0][k]);
            if c.is_finite() && fy > data.cop_threshold && (c - px).abs() > MAX_COP_REACH_M {
                return Err(CheckError::Implausible(format!(
                    "{path}: column 'cop_x_{side}', row {}: the CoP lies {:.3} from the pelvis (x {px:.3}), beyond the {MAX_COP_REACH_M} m any foot reaches. footfall reads the CoP in metres in the same frame as pelvis_x: millimetres read a thousand times too far",
                    k + 2,
                    c - px
                )));
            }
        }
    }
    Ok(())
}

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
