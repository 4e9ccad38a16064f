//! Building an effect entry's effects for a model: the model's coordinates, bodies and
//! foot primitives that each kind acts on, checked against the entry.

use super::{side_index, BuildContext, EffectSpec};
use crate::model::effects::actuator_properties::{
    ActivationTimeConstants, MtgDampingScale, MtgStrengthScale,
};
use crate::model::effects::geometry::FootGeometry;
use crate::model::effects::instruments::{BodyMassError, ForcePlateGain};
use crate::model::effects::kinds::{
    CopOffset, ForcePlateTimeOffset, GroundSlope, HeelPadCompliance, PassiveJointStiffness,
    TrunkMass,
};
use crate::model::effects::volumetric::{VolumetricContact, VolumetricStart};
use crate::model::effects::DynEffect;
use crate::model::error::EffectError;
use crate::model::geometry::Shape;

impl EffectSpec {
    /// Build the effect instances for a model.
    pub fn build(&self, ctx: &BuildContext<'_>) -> Result<Vec<Box<dyn DynEffect>>, EffectError> {
        self.check()
            .map_err(|(field, reason)| EffectError::Field { field, reason })?;
        Ok(match self {
            EffectSpec::PassiveJointStiffness {
                joint,
                side,
                stiffness,
                rest_angle,
                ..
            } => self.passive_joint_stiffness(ctx, joint, side, *stiffness, *rest_angle)?,
            EffectSpec::GroundSlope { angle, .. } => {
                vec![Box::new(GroundSlope::new(*angle, self.is_free("angle")))]
            }
            EffectSpec::TrunkMass {
                added_mass,
                com_offset,
                ..
            } => {
                let body = ctx
                    .bodies
                    .iter()
                    .position(|b| b == "hat")
                    .ok_or(EffectError::NoTrunk)?;
                vec![Box::new(TrunkMass::new(
                    body,
                    *added_mass,
                    *com_offset,
                    self.is_free("added_mass"),
                    self.is_free("com_offset"),
                ))]
            }
            EffectSpec::ForcePlateTimeOffset { side, offset, .. } => {
                vec![Box::new(ForcePlateTimeOffset::on(
                    side_index(side),
                    *offset,
                    self.is_free("offset"),
                ))]
            }
            EffectSpec::CopOffset { side, offset, .. } => {
                vec![Box::new(CopOffset::on(
                    side_index(side),
                    *offset,
                    self.is_free("offset"),
                ))]
            }
            EffectSpec::ForcePlateGain { side, error, .. } if side == "each" => [0, 1]
                .map(|s| {
                    Box::new(ForcePlateGain::on(Some(s), *error, self.is_free("error")))
                        as Box<dyn DynEffect>
                })
                .into(),
            EffectSpec::ForcePlateGain { side, error, .. } => {
                vec![Box::new(ForcePlateGain::on(
                    side_index(side),
                    *error,
                    self.is_free("error"),
                ))]
            }
            EffectSpec::BodyMassError { relative, .. } => {
                vec![Box::new(BodyMassError::new(
                    *relative,
                    self.is_free("relative"),
                ))]
            }
            EffectSpec::MtgDamping { change, .. } => {
                vec![Box::new(MtgDampingScale::new(
                    *change,
                    self.is_free("change"),
                ))]
            }
            EffectSpec::MtgStrength { change, .. } => {
                vec![Box::new(MtgStrengthScale::new(
                    *change,
                    self.is_free("change"),
                ))]
            }
            EffectSpec::ActivationTimeConstants { change, .. } => {
                vec![Box::new(ActivationTimeConstants::new(
                    *change,
                    self.is_free("change"),
                ))]
            }
            EffectSpec::HeelPadCompliance {
                primitive,
                stiffness,
                damping,
                ..
            } => {
                if !ctx.primitives.contains(primitive) {
                    return Err(EffectError::NoPrimitive {
                        primitive: primitive.clone(),
                        primitives: ctx.primitives.to_vec(),
                    });
                }
                vec![Box::new(HeelPadCompliance::new(
                    primitive,
                    *stiffness,
                    *damping,
                    self.is_free("stiffness"),
                    self.is_free("damping"),
                ))]
            }
            EffectSpec::VolumetricContact {
                stiffness,
                damping,
                mu_dynamic,
                ..
            } => self.volumetric_contact(ctx, *stiffness, *damping, *mu_dynamic)?,
            EffectSpec::FootGeometry { .. } => {
                let shapes: Vec<(String, Shape)> = ctx
                    .primitives
                    .iter()
                    .cloned()
                    .zip(ctx.shapes.iter().cloned())
                    .collect();
                vec![Box::new(FootGeometry::new(
                    &shapes,
                    [
                        self.is_free("centre"),
                        self.is_free("size"),
                        self.is_free("angle"),
                    ],
                ))]
            }
        })
    }

    /// A passive spring on `joint` of `side` (`right`, `left`, or both legs sharing one
    /// stiffness (N·m/rad) and rest angle (rad)); a joint the model lacks is an error.
    fn passive_joint_stiffness(
        &self,
        ctx: &BuildContext<'_>,
        joint: &str,
        side: &str,
        stiffness: f64,
        rest_angle: f64,
    ) -> Result<Vec<Box<dyn DynEffect>>, EffectError> {
        let (sides, name): (&[&str], String) = match side {
            "right" => (&["r"], format!("{joint}_r")),
            "left" => (&["l"], format!("{joint}_l")),
            _ => (&["r", "l"], joint.to_string()),
        };
        let mut coords = Vec::new();
        for s in sides {
            let c = format!("{joint}_{s}");
            coords.push(
                ctx.coordinates
                    .iter()
                    .position(|x| *x == c)
                    .ok_or_else(|| EffectError::NoCoordinate {
                        coordinate: c.clone(),
                    })?,
            );
        }
        Ok(vec![Box::new(PassiveJointStiffness::new(
            coords,
            &name,
            stiffness,
            rest_angle,
            self.is_free("stiffness"),
            self.is_free("rest_angle"),
        ))])
    }

    /// The contact law of every volumetric primitive of the foot, starting from the
    /// entry's values or else the foot file's; a foot without volumetric primitives, or
    /// one whose values lie outside the effect's bounds, is an error.
    fn volumetric_contact(
        &self,
        ctx: &BuildContext<'_>,
        stiffness: Option<f64>,
        damping: Option<f64>,
        mu_dynamic: Option<f64>,
    ) -> Result<Vec<Box<dyn DynEffect>>, EffectError> {
        let starts: Vec<(String, VolumetricStart)> = ctx
            .primitives
            .iter()
            .zip(ctx.laws)
            .filter_map(|(name, law)| {
                let law = law.as_ref()?;
                Some((
                    name.clone(),
                    VolumetricStart {
                        stiffness: stiffness
                            .map_or(law.stiffness, |k| k * VolumetricContact::STIFFNESS_UNIT),
                        damping: damping.unwrap_or(law.damping),
                        mu_dynamic: mu_dynamic.unwrap_or(law.mu_dynamic),
                    },
                ))
            })
            .collect();
        if starts.is_empty() {
            return Err(EffectError::NoVolumetricPrimitive {
                foot: ctx.foot.to_string(),
                primitives: ctx.primitives.to_vec(),
            });
        }
        // a value outside the bounds from the foot file (the effect's own values
        // are checked by `check`)
        for (name, s) in &starts {
            let k = s.stiffness / VolumetricContact::STIFFNESS_UNIT;
            for (parameter, value, (lower, upper)) in [
                ("stiffness", k, VolumetricContact::STIFFNESS_BOUNDS),
                ("damping", s.damping, VolumetricContact::DAMPING_BOUNDS),
                ("mu_dynamic", s.mu_dynamic, VolumetricContact::MU_BOUNDS),
            ] {
                if !(lower..=upper).contains(&value) {
                    return Err(EffectError::LawOutOfBounds {
                        primitive: name.clone(),
                        foot: ctx.foot.to_string(),
                        parameter,
                        value,
                        lower,
                        upper,
                    });
                }
            }
        }
        Ok(vec![Box::new(VolumetricContact::new(
            &starts,
            [
                self.is_free("stiffness"),
                self.is_free("damping"),
                self.is_free("mu_dynamic"),
            ],
        ))])
    }
}
