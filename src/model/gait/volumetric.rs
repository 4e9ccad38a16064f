//! The ground forces of the foot's volumetric primitives ([`crate::model::volumetric`]):
//! evaluated from the state in every phase, on a flat or sloped ground, and applied to the
//! foot as generalised forces.

use super::GaitModel;
use crate::model::effects::VolumetricContact;
use crate::model::geometry::ShapeScalars;
use crate::model::multibody::{dot, Kinematics, V2};
use crate::model::volumetric::{ContactForce, LawScalars};
use crate::model::Scalar;

/// The ground force on one volumetric primitive, in the ground's frame and the world's.
#[derive(Debug, Clone, Copy)]
pub(crate) struct GroundForce<S> {
    /// Along the ground tangent (+ forward, N).
    pub tangential: S,
    /// Along the ground normal (+ up, N).
    pub normal: S,
    /// The force in world coordinates (N).
    pub world: V2<S>,
    /// Point of application, the penetrated area's centroid (world, m).
    pub point: V2<S>,
    /// World x of the centre of pressure on the ground (m).
    pub cop_x: S,
    /// Depth of the primitive's lowest point below the ground (m).
    pub depth: S,
    /// Penetrated area (m²).
    pub area: S,
}

/// One volumetric primitive's contact, as reports show it (f64).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct VolumetricReport {
    /// Index into [`GaitModel::contacts`].
    pub contact: usize,
    /// Tangential (+ forward) and normal (+ up) force on the foot (N).
    pub force: [f64; 2],
    /// World x of its centre of pressure (m).
    pub cop_x: f64,
    /// Depth of the primitive's lowest point below the ground (m).
    pub depth: f64,
    /// Penetrated area (m²).
    pub area: f64,
}

impl<S: Scalar> GroundForce<S> {
    /// The report of contact `contact`.
    pub(crate) fn report(&self, contact: usize) -> VolumetricReport {
        VolumetricReport {
            contact,
            force: [self.tangential.value(), self.normal.value()],
            cop_x: self.cop_x.value(),
            depth: self.depth.value(),
            area: self.area.value(),
        }
    }
}

impl GaitModel {
    /// Whether the foot has volumetric primitives.
    pub fn has_volumetric_contacts(&self) -> bool {
        self.contacts.iter().any(|c| c.law.is_some())
    }

    /// Whether contact `c` is volumetric (a force in every phase, never a constraint).
    pub fn is_volumetric(&self, c: usize) -> bool {
        self.contacts[c].law.is_some()
    }

    /// The ground force of every volumetric primitive that touches the ground at
    /// kinematics `k` (positions and velocities), against the ground at height `ground_h`
    /// along its unit normal `n`, with the effect parameters `p` (all of them, fixed and
    /// free: a `volumetric_contact` effect's replace the foot file's law): `(contact
    /// index, force)`.
    pub(crate) fn volumetric_forces<S: Scalar>(
        &self,
        k: &Kinematics<S>,
        ground_h: S,
        n: V2<S>,
        p: &[S],
    ) -> Vec<(usize, GroundForce<S>)> {
        let mut out = Vec::new();
        // every dynamics evaluation comes here: nothing to set up for rigid feet
        if !self.has_volumetric_contacts() {
            return out;
        }
        // the ground's frame: tangent t (forward along the ground), normal n
        let t = [n[1], -n[0]];
        let ground_angle = (-n[0]).atan2(n[1]);
        let to_ground = |v: V2<S>| [dot(t, v), dot(n, v)];
        let to_world = |v: V2<S>| [t[0] * v[0] + n[0] * v[1], t[1] * v[0] + n[1] * v[1]];
        for (ci, c) in self.contacts.iter().enumerate() {
            let Some(law) = &c.law else { continue };
            let params: LawScalars<S> = match self.volumetric_params[ci] {
                Some((e, slot)) => {
                    let q = &self.effect_params(p, e)[3 * slot..3 * slot + 3];
                    LawScalars {
                        stiffness: q[0] * VolumetricContact::STIFFNESS_UNIT,
                        damping: q[1],
                        mu_dynamic: q[2],
                    }
                }
                None => law.scalars(),
            };
            let (centre_local, angle, semi_axes) = match self.shape_of(ci, p) {
                ShapeScalars::Circle { centre, radius } => (centre, S::c(0.0), (radius, radius)),
                ShapeScalars::Ellipse {
                    centre,
                    angle,
                    semi_axes,
                } => (centre, angle, (semi_axes[0], semi_axes[1])),
                // refused when the foot file is read
                ShapeScalars::Point { .. } => continue,
            };
            let centre = self.tree.point(k, c.body, centre_local);
            let (velocity, _) = self.tree.point_motion(k, c.body, centre);
            let alpha = k.angle[c.body] + angle - ground_angle;
            let Some(ContactForce {
                force,
                point,
                cop_x,
                penetration,
            }) = law.force_with(
                params,
                to_ground(centre),
                alpha,
                semi_axes,
                to_ground(velocity),
                k.omega[c.body],
                ground_h,
            )
            else {
                continue;
            };
            let cop_world = to_world([cop_x, ground_h]);
            out.push((
                ci,
                GroundForce {
                    tangential: force[0],
                    normal: force[1],
                    world: to_world(force),
                    point: to_world(point),
                    cop_x: cop_world[0],
                    depth: penetration.depth,
                    area: penetration.area,
                },
            ));
        }
        out
    }
}
