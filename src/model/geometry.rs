//! Foot contact primitives and their lowest point against a ground plane.
//!
//! A primitive is fixed in a body frame (the foot). Against a plane with unit normal
//! $n$ (world), its *contact point* is the point of the primitive furthest along $-n$.
//! [`Primitive::contact_offset`] returns the world vector $d(\psi)$ from the primitive's
//! reference point (its centre) to that point, where $\psi$ is the body's world angle.
//!
//! The ellipse's lowest point has a closed form: with $A = \mathrm{diag}(a^2, b^2)$ and
//! $n_e$ the normal in the ellipse frame, the point of $p^T A^{-1} p = 1$ that minimises
//! $n_e \cdot p$ is $p = -A n_e / \sqrt{n_e^T A n_e}$ (a Lagrange multiplier argument). It is
//! the point Millard & Mombaur (2019, eq. 3–4) find by a root search in the polar angle,
//! and every derivative follows from it by AD, with no iteration.

use super::multibody::{rotate, V2};
use super::Scalar;
use serde::{Deserialize, Serialize};

/// A contact primitive in a body frame. Lengths in metres, angles in radians.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// A circle.
    Circle {
        /// Centre in the body frame.
        centre: [f64; 2],
        /// Radius (> 0).
        radius: f64,
    },
    /// An ellipse.
    Ellipse {
        /// Centre in the body frame.
        centre: [f64; 2],
        /// Orientation of the first semi-axis relative to the body x axis.
        angle: f64,
        /// Semi-axes (a along the rotated x, b along the rotated y), both > 0.
        semi_axes: [f64; 2],
    },
    /// A single point.
    Point {
        /// Position in the body frame.
        position: [f64; 2],
    },
}

impl Shape {
    /// Reference point (centre) in the body frame.
    pub fn centre(&self) -> [f64; 2] {
        match *self {
            Shape::Circle { centre, .. } | Shape::Ellipse { centre, .. } => centre,
            Shape::Point { position } => position,
        }
    }

    /// Check physical validity: positive finite sizes, finite positions.
    pub fn validate(&self) -> Result<(), crate::model::ShapeError> {
        self.check()
            .map_err(|(field, reason)| crate::model::ShapeError { field, reason })
    }

    /// Largest size (radius, semi-axis) and distance from the foot frame's origin (m) a
    /// foot's contact primitive may have.
    pub const MAX_EXTENT: f64 = 1.0;

    /// Like [`validate`](Self::validate), naming the offending field (`radius`,
    /// `semi_axes`, `centre`, `angle`, `position`) separately from the reason.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        let max = Self::MAX_EXTENT;
        let position = |name: &'static str, v: &[f64; 2]| {
            if v.iter().all(|x| x.is_finite() && x.abs() <= max) {
                Ok(())
            } else {
                Err((
                    name,
                    format!("must be two finite numbers of metres within ±{max} m of the ankle, got [{:?}, {:?}]", v[0], v[1]),
                ))
            }
        };
        let size = |name: &'static str, v: &[f64]| {
            if v.iter().all(|x| x.is_finite() && *x > 0.0 && *x <= max) {
                Ok(())
            } else {
                let got: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
                let what = if v.len() == 1 {
                    "a positive number"
                } else {
                    "positive numbers"
                };
                Err((
                    name,
                    format!(
                        "must be {what} of metres, at most {max} m, got {}",
                        got.join(", ")
                    ),
                ))
            }
        };
        match self {
            Shape::Circle { centre, radius } => {
                position("centre", centre)?;
                size("radius", &[*radius])?;
            }
            Shape::Ellipse {
                centre,
                angle,
                semi_axes,
            } => {
                position("centre", centre)?;
                if !angle.is_finite() {
                    return Err((
                        "angle",
                        format!("must be a finite number of radians, got {angle}"),
                    ));
                }
                size("semi_axes", semi_axes)?;
            }
            Shape::Point { position: p } => position("position", p)?,
        }
        Ok(())
    }

    /// Height of the primitive's lowest point in its body frame (m), with the body frame
    /// upright (y up); `None` for an invalid shape.
    pub fn lowest_y(&self) -> Option<f64> {
        self.check().ok()?;
        let y = self.centre()[1] + self.contact_offset::<f64>(0.0, [0.0, 1.0])[1];
        y.is_finite().then_some(y)
    }

    /// World offset from the reference point to the contact point, for body world angle
    /// `psi` and ground normal `n` (unit, world).
    pub fn contact_offset<S: Scalar>(&self, psi: S, n: V2<S>) -> V2<S> {
        self.scalars::<S>().contact_offset(psi, n)
    }

    /// The shape's numbers as constants of scalar type `S`.
    pub fn scalars<S: Scalar>(&self) -> ShapeScalars<S> {
        let c = |v: [f64; 2]| [S::c(v[0]), S::c(v[1])];
        match *self {
            Shape::Point { position } => ShapeScalars::Point {
                position: c(position),
            },
            Shape::Circle { centre, radius } => ShapeScalars::Circle {
                centre: c(centre),
                radius: S::c(radius),
            },
            Shape::Ellipse {
                centre,
                angle,
                semi_axes,
            } => ShapeScalars::Ellipse {
                centre: c(centre),
                angle: S::c(angle),
                semi_axes: c(semi_axes),
            },
        }
    }
}

/// A [`Shape`] in a generic scalar: its centre, sizes and orientation may be free
/// parameters of an identification (the `foot_geometry` effect), with exact derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ShapeScalars<S> {
    /// A circle: centre (body frame, m) and radius (m).
    Circle {
        /// Centre in the body frame.
        centre: V2<S>,
        /// Radius.
        radius: S,
    },
    /// An ellipse: centre (body frame, m), orientation (rad) and semi-axes (m).
    Ellipse {
        /// Centre in the body frame.
        centre: V2<S>,
        /// Orientation of the first semi-axis relative to the body x axis.
        angle: S,
        /// Semi-axes.
        semi_axes: V2<S>,
    },
    /// A point (body frame, m).
    Point {
        /// Position in the body frame.
        position: V2<S>,
    },
}

impl<S: Scalar> ShapeScalars<S> {
    /// Reference point (centre) in the body frame.
    pub fn centre(&self) -> V2<S> {
        match *self {
            ShapeScalars::Circle { centre, .. } | ShapeScalars::Ellipse { centre, .. } => centre,
            ShapeScalars::Point { position } => position,
        }
    }

    /// The same shape in another scalar type `T` built from `S` (e.g. a dual number over
    /// `S` for derivatives in the body angle).
    pub fn map<T: Scalar>(&self, f: impl Fn(S) -> T) -> ShapeScalars<T> {
        let v = |p: V2<S>| [f(p[0]), f(p[1])];
        match *self {
            ShapeScalars::Circle { centre, radius } => ShapeScalars::Circle {
                centre: v(centre),
                radius: f(radius),
            },
            ShapeScalars::Ellipse {
                centre,
                angle,
                semi_axes,
            } => ShapeScalars::Ellipse {
                centre: v(centre),
                angle: f(angle),
                semi_axes: v(semi_axes),
            },
            ShapeScalars::Point { position } => ShapeScalars::Point {
                position: v(position),
            },
        }
    }

    /// World offset from the reference point to the contact point, for body world angle
    /// `psi` and ground normal `n` (unit, world).
    pub fn contact_offset(&self, psi: S, n: V2<S>) -> V2<S> {
        match *self {
            ShapeScalars::Point { .. } => [S::c(0.0), S::c(0.0)],
            ShapeScalars::Circle { radius, .. } => [-n[0] * radius, -n[1] * radius],
            ShapeScalars::Ellipse {
                angle, semi_axes, ..
            } => {
                let (a2, b2) = (semi_axes[0] * semi_axes[0], semi_axes[1] * semi_axes[1]);
                let ang = psi + angle;
                let (s, c) = (ang.sin(), ang.cos());
                // normal in the ellipse frame: Rᵀ n; the support point −A nₑ/√(nₑᵀ A nₑ)
                let ne = [c * n[0] + s * n[1], -s * n[0] + c * n[1]];
                let scale = -(ne[0] * ne[0] * a2 + ne[1] * ne[1] * b2).sqrt().recip();
                let p = [ne[0] * a2 * scale, ne[1] * b2 * scale];
                rotate(c, s, p)
            }
        }
    }
}
