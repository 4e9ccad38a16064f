//! The `foot_geometry` effect: each contact primitive's centre, size and orientation as
//! parameters of the model — "is the fitted shape the shape that the forces ask for?"

use super::{Effect, ParamSpec};
use crate::model::geometry::Shape;

/// Frees the geometry of the foot's contact primitives, rigid and volumetric: per
/// primitive its centre `x`, `y` in the foot frame (m), its size (`radius` of a circle,
/// semi-axes `a`, `b` of an ellipse, m) and an ellipse's `angle` (rad), each shared by
/// the same primitive of both feet (a symmetric subject). The parameters enter the
/// contact point, gap and constraint rows of rigid primitives and the penetration of
/// volumetric ones as the model's generic scalar, so their sensitivities are exact.
///
/// The bounds are relative to the foot file's shape: the centre within ±3 cm, sizes within
/// ±30 %, the angle within ±0.35 rad (20°).
#[derive(Debug, Clone)]
pub struct FootGeometry {
    primitives: Vec<(String, usize)>,
    params: Vec<ParamSpec>,
}

impl FootGeometry {
    /// How far the centre may move (m).
    pub const CENTRE_RANGE: f64 = 0.03;
    /// How far a size may change (fraction).
    pub const SIZE_RANGE: f64 = 0.3;
    /// How far an ellipse may turn (rad).
    pub const ANGLE_RANGE: f64 = 0.35;

    /// The primitives `(name, shape)` of the foot file, with the centres, sizes and
    /// angles free as `free` says (`[centre, size, angle]`).
    pub fn new(primitives: &[(String, Shape)], free: [bool; 3]) -> Self {
        let mut params = Vec::new();
        let mut slots = Vec::new();
        for (name, shape) in primitives {
            slots.push((name.clone(), params.len()));
            let base = format!("foot_geometry.{name}");
            let mut push = |field: &str, value: f64, (lo, hi): (f64, f64), unit: &str, f: bool| {
                params.push(ParamSpec {
                    name: format!("{base}.{field}"),
                    value,
                    lower: lo,
                    upper: hi,
                    unit: unit.into(),
                    free: f,
                })
            };
            let centre = shape.centre();
            let r = Self::CENTRE_RANGE;
            push("x", centre[0], (centre[0] - r, centre[0] + r), "m", free[0]);
            push("y", centre[1], (centre[1] - r, centre[1] + r), "m", free[0]);
            let size = |v: f64| (v * (1.0 - Self::SIZE_RANGE), v * (1.0 + Self::SIZE_RANGE));
            match *shape {
                Shape::Point { .. } => {}
                Shape::Circle { radius, .. } => push("radius", radius, size(radius), "m", free[1]),
                Shape::Ellipse {
                    angle, semi_axes, ..
                } => {
                    push("a", semi_axes[0], size(semi_axes[0]), "m", free[1]);
                    push("b", semi_axes[1], size(semi_axes[1]), "m", free[1]);
                    let t = Self::ANGLE_RANGE;
                    push("angle", angle, (angle - t, angle + t), "rad", free[2]);
                }
            }
        }
        Self {
            primitives: slots,
            params,
        }
    }
}

impl Effect for FootGeometry {
    fn kind(&self) -> &'static str {
        "foot_geometry"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn geometry_primitives(&self) -> &[(String, usize)] {
        &self.primitives
    }
}
