//! Foot contact primitives and their lowest point against a ground plane.
//!
//! A primitive is fixed in a body frame (the foot). Against a plane with unit normal
//! $n$ (world), its *contact point* is the point of the primitive furthest along $-n$.
//! [`Primitive::contact_offset`] returns the world vector $d(\psi)$ from the primitive's
//! reference point (its centre) to that point, where $\psi$ is the body's world angle.
//!
//! The ellipse has no closed form in the polar angle used by Millard & Mombaur (2019, eq. 3–4): the
//! polar angle $\phi$ of the lowest point, $p(\phi) = r(\phi)(\cos\phi, \sin\phi)$ with
//! $r(\phi) = ab/\sqrt{b^2\cos^2\phi + a^2\sin^2\phi}$, is bracketed by sampling, narrowed by
//! bisection on $h'(\phi)$ and polished by Newton's method to 1e-12 rad in `f64`. Derivative
//! parts are then obtained by further Newton steps in the generic scalar, which by the
//! implicit function theorem yield the exact derivatives of the converged root.

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
                let (a, b) = (semi_axes[0], semi_axes[1]);
                let ang = psi + angle;
                let (s, c) = (ang.sin(), ang.cos());
                // normal in the ellipse frame: Rᵀ n
                let ne = [c * n[0] + s * n[1], -s * n[0] + c * n[1]];
                let phi0 =
                    cached_lowest_polar_angle(a.value(), b.value(), [ne[0].value(), ne[1].value()]);
                let mut phi = S::c(phi0);
                for _ in 0..3 {
                    let (_, h1, h2) = ellipse_height_derivatives(a, b, ne, phi);
                    phi -= h1 / h2;
                }
                let (p, _, _) = ellipse_point(a, b, phi);
                rotate(c, s, p)
            }
        }
    }
}

/// Point on the ellipse at polar angle `phi` and its first two derivatives in `phi`.
fn ellipse_point<S: Scalar>(a: S, b: S, phi: S) -> (V2<S>, V2<S>, V2<S>) {
    let (s, c) = (phi.sin(), phi.cos());
    let d = s * s * (a * a) + c * c * (b * b);
    let two_phi = phi * 2.0;
    let d1 = two_phi.sin() * (a * a - b * b);
    let d2 = two_phi.cos() * ((a * a - b * b) * 2.0);
    let ab = a * b;
    let inv_sqrt = d.sqrt().recip();
    let r = inv_sqrt * ab;
    let d32 = inv_sqrt / d; // D^{-3/2}
    let r1 = -(d32 * d1) * (ab * 0.5);
    let r2 = (d32 / d * d1 * d1 * 0.75 - d32 * d2 * 0.5) * ab;
    let p = [r * c, r * s];
    let p1 = [r1 * c - r * s, r1 * s + r * c];
    let p2 = [r2 * c - r1 * s * 2.0 - r * c, r2 * s + r1 * c * 2.0 - r * s];
    (p, p1, p2)
}

/// Height `h = ne·p(φ)` along the ellipse-frame normal and its derivatives in `φ`.
fn ellipse_height_derivatives<S: Scalar>(a: S, b: S, ne: V2<S>, phi: S) -> (S, S, S) {
    let (p, p1, p2) = ellipse_point(a, b, phi);
    (
        ne[0] * p[0] + ne[1] * p[1],
        ne[0] * p1[0] + ne[1] * p1[1],
        ne[0] * p2[0] + ne[1] * p2[1],
    )
}

thread_local! {
    static ROOT_CACHE: std::cell::RefCell<([([u64; 4], f64); 4], usize)> =
        const { std::cell::RefCell::new(([([u64::MAX; 4], 0.0); 4], 0)) };
}

/// [`ellipse_lowest_polar_angle`] with a small per-thread cache: one dynamics Jacobian
/// evaluates the same contact at the same values once per AD chunk. The cache returns
/// the bit-identical value a fresh solve would, so results stay deterministic.
fn cached_lowest_polar_angle(a: f64, b: f64, ne: [f64; 2]) -> f64 {
    let key = [a.to_bits(), b.to_bits(), ne[0].to_bits(), ne[1].to_bits()];
    ROOT_CACHE.with(|c| {
        let mut c = c.borrow_mut();
        if let Some(&(_, phi)) = c.0.iter().find(|(k, _)| *k == key) {
            return phi;
        }
        let phi = ellipse_lowest_polar_angle(a, b, ne);
        let slot = c.1;
        c.0[slot] = (key, phi);
        c.1 = (slot + 1) % 4;
        phi
    })
}

/// Polar angle (in the ellipse frame) of the ellipse point furthest along `-ne`:
/// sampling bracket, bisection on h'(φ), Newton polish to 1e-12 rad.
pub fn ellipse_lowest_polar_angle(a: f64, b: f64, ne: [f64; 2]) -> f64 {
    // 16 samples bracket the single minimum of h(φ) = ne·p(φ) to within ±2π/16; twelve
    // bisection steps on h'(φ) narrow the bracket to ~2e-4 rad, well inside Newton's
    // region of quadratic convergence; Newton then polishes to 1e-12 rad.
    const SAMPLES: usize = 16;
    let step = std::f64::consts::TAU / SAMPLES as f64;
    let height = |phi: f64| ellipse_height_derivatives(a, b, ne, phi).0;
    let mut k_min = 0;
    let mut h_min = f64::INFINITY;
    for k in 0..SAMPLES {
        let h = height(k as f64 * step);
        if h < h_min {
            h_min = h;
            k_min = k;
        }
    }
    let mut lo = (k_min as f64 - 1.0) * step;
    let mut hi = (k_min as f64 + 1.0) * step;
    let dh = |phi: f64| ellipse_height_derivatives(a, b, ne, phi).1;
    // bisection on h' (negative left of the minimum, positive right of it)
    for _ in 0..12 {
        let mid = 0.5 * (lo + hi);
        if dh(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let mut phi = 0.5 * (lo + hi);
    for _ in 0..20 {
        let (_, h1, h2) = ellipse_height_derivatives(a, b, ne, phi);
        if !(h2 > 0.0) {
            break;
        }
        let dphi = h1 / h2;
        phi -= dphi;
        if dphi.abs() < 1e-12 {
            break;
        }
    }
    phi
}
