//! The trunk above the lumbar joint, as a part of the rigid HAT.
//!
//! The planar model's HAT is one rigid body: pelvis, trunk, head and arms with the lumbar
//! joint frozen. A walking trunk rocks on the pelvis by several degrees each step, and
//! with a third of the body's mass some 0.3 m above the lumbar joint that rocking moves
//! tens of newtons of horizontal force. Whole-body balances of a measured trial (the
//! measurement check) that know the trial's lumbar angle move this part by it; the
//! optimal control problems keep the HAT rigid.

use super::anthropometry::{de_leva_hat_parts, DeLevaTable, RadiusColumn, Sex};
use super::error::{AnthropometryError, ModelError};
use super::spec::{LumbarChoice, OpensimSummary};

/// The trunk above the lumbar joint, in the HAT (pelvis) frame with the lumbar joint at
/// the angle the rigid HAT froze it at. Its mass, centre of mass and inertia are part of
/// the HAT's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Torso {
    /// Mass (kg).
    pub mass: f64,
    /// The lumbar joint in the HAT frame (m).
    pub joint: [f64; 2],
    /// Centre of mass relative to the lumbar joint, in the HAT frame at the frozen angle
    /// (m).
    pub com: [f64; 2],
    /// Moment of inertia about its centre of mass (kg·m²).
    pub izz: f64,
    /// The lumbar extension (rad, the trial's convention) the HAT froze; `None`: the
    /// trial's mean.
    pub frozen: Option<f64>,
}

/// The torso of an OpenSim model summary (`bodies.torso`, `joints.back`): rotated into
/// the pelvis frame at the lumbar angle the rigid HAT uses; `None` for a summary without
/// a torso body.
pub fn opensim_torso(
    summary: &OpensimSummary,
    lumbar: LumbarChoice,
) -> Result<Option<Torso>, ModelError> {
    if !summary.has("/bodies/torso") {
        return Ok(None);
    }
    let get = |ptr: &str| summary.number(ptr);
    let pair = |ptr: &str| summary.pair(ptr);
    let frozen = match lumbar {
        LumbarChoice::TrialMean => {
            get("/nine_dof_mapping/HAT_at_trial_mean_lumbar/lumbar_extension_rad")?
        }
        LumbarChoice::Zero => 0.0,
    };
    let com = pair("/bodies/torso/com_in_body_m")?;
    let in_child = pair("/joints/back/location_in_child_m")?;
    let local = [com[0] - in_child[0], com[1] - in_child[1]];
    let (s, c) = frozen.sin_cos();
    Ok(Some(Torso {
        mass: get("/bodies/torso/mass_kg")?,
        joint: pair("/joints/back/location_in_parent_m")?,
        com: [c * local[0] - s * local[1], s * local[0] + c * local[1]],
        izz: get("/bodies/torso/inertia_about_com_kg_m2/zz")?,
        frozen: Some(frozen),
    }))
}

/// The torso of de Leva's HAT ([`de_leva_hat_parts`]): the middle and upper trunk, the
/// head and both arms, hinged at the omphalion, the lower trunk's cranial end (the
/// tables' boundary closest to the lumbar spine). On the vertical line through the hip
/// midpoint, the HAT frame's origin; frozen at the trial's mean lumbar angle.
pub fn de_leva_torso(mass_kg: f64, height_m: f64, sex: Sex) -> Result<Torso, AnthropometryError> {
    let parts = de_leva_hat_parts(mass_kg, height_m, sex, RadiusColumn::Transverse)?;
    let t = DeLevaTable::for_sex(sex);
    let joint = t.lower_trunk.length_mm * 1e-3 * height_m / (t.stature_mm * 1e-3);
    let upper: Vec<_> = parts.iter().filter(|p| p.name != "lower_trunk").collect();
    let mass: f64 = upper.iter().map(|p| p.mass).sum();
    let h = upper.iter().map(|p| p.mass * p.com_height).sum::<f64>() / mass;
    let izz = upper
        .iter()
        .map(|p| p.inertia_com + p.mass * (p.com_height - h).powi(2))
        .sum();
    Ok(Torso {
        mass,
        joint: [0.0, joint],
        com: [0.0, h - joint],
        izz,
        frozen: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn de_levas_torso_is_the_hat_above_the_omphalion() {
        let parts = de_leva_hat_parts(70.0, 1.75, Sex::Male, RadiusColumn::Transverse).unwrap();
        let torso = de_leva_torso(70.0, 1.75, Sex::Male).unwrap();
        let lower = parts.iter().find(|p| p.name == "lower_trunk").unwrap();
        let hat: f64 = parts.iter().map(|p| p.mass).sum();
        assert!((torso.mass + lower.mass - hat).abs() < 1e-12);
        // the torso's centre of mass and the lower trunk's make the HAT's
        let h_hat = parts.iter().map(|p| p.mass * p.com_height).sum::<f64>() / hat;
        let h_torso = torso.joint[1] + torso.com[1];
        let h = (torso.mass * h_torso + lower.mass * lower.com_height) / hat;
        assert!((h - h_hat).abs() < 1e-12);
        // the lower trunk's centre of mass lies below the hinge, the torso's above it
        assert!(lower.com_height < torso.joint[1] && torso.com[1] > 0.0);
    }
}
