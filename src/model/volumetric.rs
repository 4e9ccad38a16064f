//! Volumetric contact of a foot primitive with the ground, reduced to the sagittal plane
//! (Brown & McPhee 2018, eq. 1, 4–5; Ezati et al. 2020, §2).
//!
//! In 3-D the normal force is proportional to the penetrated volume, $F_n = k_V V(1 + a_V
//! v_{cn})$, and acts at the volume's centroid. In the plane the penetrated volume is the
//! penetrated *area* $A$ of the ellipse (or circle) below the ground line times the foot's
//! width, which the stiffness absorbs: $F_n = k_A A (1 + a_V v_{cn})$ with $k_A$ in N/m²
//! and $v_{cn}$ the velocity of the foot's material point at the area's centroid into the
//! ground (m/s). The tangential force is Brown & McPhee's (2018) continuous velocity-based friction law
//! (eq. 4–5) with the signed tangential velocity $v$ of that point:
//! $F_t = -F_n\,\mu(v)$, $\mu(v) = \mu_d \tanh(4v/v_t) + (\mu_s - \mu_d)\,
//! \frac{v/v_t}{(\frac14 (v/v_t)^2 + \frac34)^2}$; in the plane $\mu(|v|)\,v/|v|$ is this odd,
//! smooth function of $v$. Brown & McPhee found the law unusable for identification by inverse
//! simulation (the measured sticking foot has no slip velocity to make friction from);
//! Ezati et al. (2020) used it in optimal control, where the dynamics make the small slip, with
//! $v_t$ = 0.1 m/s, and identified it there. That is how footfall uses it.
//!
//! **Geometry.** An affine map takes the ellipse to the unit disc and the ground line to a
//! chord; areas scale by $ab$ and centroids map to centroids. With the ellipse's world
//! orientation $\alpha$, $M = R(\alpha)\,\mathrm{diag}(a^2, b^2)\,R(\alpha)^T$, its half
//! height is $h = \sqrt{M_{yy}}$ and its lowest point is $c + \ell$, $\ell = (-M_{xy}/h,
//! -h)$. A lowest point $\delta$ below the ground cuts the disc at normalised depth
//! $s = \delta / h \in (0, 2)$; with $\theta = 2 \arcsin\sqrt{s/2}$ (half the chord's
//! central angle) the disc segment has area $S = (2\theta - \sin 2\theta)/2$, so
//! $A = ab\,S$, and its centroid lies on the conjugate radius through the lowest point at
//! the fraction $\tau = \tfrac23 \sin^3\theta / S$ of it: the centroid is $c + \tau\ell$.
//! $2\theta - \sin 2\theta$ is summed as its series for small angles, so the area keeps
//! its full relative precision down to first contact, where $A \propto s^{3/2}$: the
//! force, its first derivative and the CoP are continuous there, and the derivatives are
//! finite for every $0 < s < 2$ (at $s \le 0$ the primitive is clear of the ground and
//! everything is zero; at $s \ge 2$ it is sunk whole). Past the centre the segment is
//! the disc less the other side's, so the derivatives stay finite as $s \to 2$ too.

use super::multibody::V2;
use super::Scalar;
use serde::{Deserialize, Serialize};

/// Parameters of a primitive's volumetric contact law.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VolumetricLaw {
    /// Area stiffness $k_A$ (N/m²): normal force per penetrated area of the sagittal
    /// section (Brown & McPhee's volumetric stiffness times the foot's width).
    pub stiffness: f64,
    /// Damping $a_V$ (s/m): the normal force grows by this fraction per m/s of penetration
    /// rate at the centroid (Brown & McPhee 2018, eq. 1).
    pub damping: f64,
    /// Dynamic friction coefficient $\mu_d$.
    pub mu_dynamic: f64,
    /// Static friction coefficient $\mu_s$ ($\ge \mu_d$; equal: no Stribeck peak).
    pub mu_static: f64,
    /// Transition velocity $v_t$ (m/s) of the friction law (Ezati et al. 2020: 0.1 m/s).
    pub transition_velocity: f64,
}

impl VolumetricLaw {
    /// Check that every parameter is finite and physical: stiffness and transition
    /// velocity positive, damping and friction coefficients non-negative, μ_s ≥ μ_d.
    /// Errors name the field.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        let positive = |name: &'static str, v: f64, unit: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err((
                    name,
                    format!("must be a positive number of {unit}, got {v:?}"),
                ))
            }
        };
        let non_negative = |name: &'static str, v: f64, unit: &str| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err((
                    name,
                    format!("must be a non-negative number{unit}, got {v:?}"),
                ))
            }
        };
        positive("stiffness", self.stiffness, "N/m²")?;
        non_negative("damping", self.damping, " of s/m")?;
        non_negative("mu_dynamic", self.mu_dynamic, "")?;
        non_negative("mu_static", self.mu_static, "")?;
        if self.mu_static < self.mu_dynamic {
            return Err((
                "mu_static",
                format!(
                    "must be at least mu_dynamic ({}), got {}",
                    self.mu_dynamic, self.mu_static
                ),
            ));
        }
        positive("transition_velocity", self.transition_velocity, "m/s")
    }

    /// The friction coefficient at signed slip velocity `v` (m/s, + forward): odd in `v`,
    /// smooth, $\approx \mu_s$ at $|v| = v_t$ and $\to \mu_d$ for $|v| \gg v_t$.
    pub fn friction_coefficient<S: Scalar>(&self, v: S) -> S {
        self.friction_coefficient_with(v, S::c(self.mu_dynamic))
    }

    /// [`friction_coefficient`](Self::friction_coefficient) with the dynamic coefficient
    /// `mu_dynamic` in place of the law's; the static peak keeps the law's margin
    /// $\mu_s - \mu_d$ above it.
    pub fn friction_coefficient_with<S: Scalar>(&self, v: S, mu_dynamic: S) -> S {
        let r = v / self.transition_velocity;
        let d = r * r * 0.25 + 0.75;
        (r * 4.0).tanh() * mu_dynamic + r / (d * d) * (self.mu_static - self.mu_dynamic)
    }

    /// The law's identifiable parameters as constants of scalar type `S`.
    pub fn scalars<S: Scalar>(&self) -> LawScalars<S> {
        LawScalars {
            stiffness: S::c(self.stiffness),
            damping: S::c(self.damping),
            mu_dynamic: S::c(self.mu_dynamic),
        }
    }
}

/// The parameters of a [`VolumetricLaw`] that an identification may free
/// (`volumetric_contact` effect), in a generic scalar so that their sensitivities come
/// from the same automatic differentiation as the rest of the dynamics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawScalars<S> {
    /// Area stiffness (N/m²).
    pub stiffness: S,
    /// Damping (s/m).
    pub damping: S,
    /// Dynamic friction coefficient (the static one keeps the law's margin above it).
    pub mu_dynamic: S,
}

/// The part of a primitive below the ground line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Penetration<S> {
    /// Penetrated area (m²).
    pub area: S,
    /// Centroid of the penetrated area (world, m).
    pub centroid: V2<S>,
    /// Depth of the primitive's lowest point below the ground (m, > 0).
    pub depth: S,
}

/// $2\theta - \sin 2\theta$ for $x = 2\theta \in [0, 2\pi]$, to full relative precision
/// for small $x$ (where the difference cancels).
fn x_minus_sin<S: Scalar>(x: S) -> S {
    if x.value() < 0.5 {
        // x³/3! − x⁵/5! + … + x¹⁵/15!; the first left-out term is below 1e-18 of the sum
        // at x = 0.5
        let x2 = x * x;
        let mut term = x * x2 / 6.0;
        let mut sum = term;
        for k in [4.0, 6.0, 8.0, 10.0, 12.0, 14.0] {
            term = -term * x2 / (k * (k + 1.0));
            sum += term;
        }
        sum
    } else {
        x - x.sin()
    }
}

/// The segment of the unit disc beyond a chord at normalised depth `s` (the chord's
/// distance from the disc's edge, as a fraction of the radius; 0 < s < 2): its area and
/// the fraction of the radius (towards the segment) at which its centroid lies.
///
/// Past the centre (s > 1) the segment is the disc less the segment of depth 2 − s on the
/// other side, so that near either end (first contact, fully sunk) the angle comes from
/// the small depth, where its derivatives stay finite.
pub fn disc_segment<S: Scalar>(s: S) -> (S, S) {
    let (small, past_centre) = if s.value() <= 1.0 {
        (s, false)
    } else {
        (-s + 2.0, true)
    };
    let theta = (small * 0.5).sqrt().asin() * 2.0;
    let segment = x_minus_sin(theta * 2.0) * 0.5;
    let area = if past_centre {
        -segment + std::f64::consts::PI
    } else {
        segment
    };
    // the first moment of either part about the centre is ⅔ sin³θ (of the chord's
    // half-angle θ, the same for both parts)
    let sin = theta.sin();
    (area, sin * sin * sin * (2.0 / 3.0) / area)
}

/// The penetration of an ellipse with semi-axes `(a, b)` whose centre is at `centre`
/// (world) and whose first semi-axis makes the world angle `alpha` with the x axis, into
/// the ground below `ground_y`; `None` when it is clear of the ground. A circle is the
/// ellipse with `a = b`. Fully sunk (more than its height below ground) counts as its
/// whole area at its centre.
pub fn penetration<S: Scalar>(
    centre: V2<S>,
    alpha: S,
    (a, b): (f64, f64),
    ground_y: S,
) -> Option<Penetration<S>> {
    penetration_with(centre, alpha, (S::c(a), S::c(b)), ground_y)
}

/// [`penetration`] with semi-axes in the generic scalar (free parameters of an
/// identification).
pub fn penetration_with<S: Scalar>(
    centre: V2<S>,
    alpha: S,
    (a, b): (S, S),
    ground_y: S,
) -> Option<Penetration<S>> {
    let (sin, cos) = (alpha.sin(), alpha.cos());
    let (a2, b2) = (a * a, b * b);
    let myy = sin * sin * a2 + cos * cos * b2;
    let mxy = sin * cos * (a2 - b2);
    let h = myy.sqrt();
    let depth = -(centre[1] - h - ground_y);
    if depth.value() <= 0.0 {
        return None;
    }
    let s = depth / h;
    if s.value() >= 2.0 {
        return Some(Penetration {
            area: a * b * std::f64::consts::PI,
            centroid: centre,
            depth,
        });
    }
    let (segment, tau) = disc_segment(s);
    let lowest = [-mxy / h, -h];
    Some(Penetration {
        area: segment * (a * b),
        centroid: [centre[0] + lowest[0] * tau, centre[1] + lowest[1] * tau],
        depth,
    })
}

/// The ground's force on a penetrating primitive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactForce<S> {
    /// Force on the foot (world, N): tangential (+ forward), normal (+ up).
    pub force: V2<S>,
    /// Point of application: the penetrated area's centroid (world, m).
    pub point: V2<S>,
    /// Centre of pressure on the ground line (m): where the force's moment about a point of
    /// the ground vanishes, as a force plate reports it; equal to the centroid's x up to
    /// the tangential force times the centroid's depth over the normal force.
    pub cop_x: S,
    /// The penetration it comes from.
    pub penetration: Penetration<S>,
}

impl VolumetricLaw {
    /// The ground's force on an ellipse (`centre`, world angle `alpha`, semi-axes `(a, b)`)
    /// of a rigid body moving with the velocity `centre_velocity` of the centre (m/s) and
    /// angular velocity `omega` (rad/s, counter-clockwise), against the fixed ground at
    /// height `ground_y`; `None` when the ellipse is clear of the ground.
    pub fn force<S: Scalar>(
        &self,
        centre: V2<S>,
        alpha: S,
        semi_axes: (f64, f64),
        centre_velocity: V2<S>,
        omega: S,
        ground_y: S,
    ) -> Option<ContactForce<S>> {
        self.force_with(
            self.scalars(),
            centre,
            alpha,
            (S::c(semi_axes.0), S::c(semi_axes.1)),
            centre_velocity,
            omega,
            ground_y,
        )
    }

    /// [`force`](Self::force) with the stiffness, damping and dynamic friction coefficient
    /// `params` in place of the law's and the semi-axes in the generic scalar (free
    /// parameters of an identification).
    #[allow(clippy::too_many_arguments)]
    pub fn force_with<S: Scalar>(
        &self,
        params: LawScalars<S>,
        centre: V2<S>,
        alpha: S,
        semi_axes: (S, S),
        centre_velocity: V2<S>,
        omega: S,
        ground_y: S,
    ) -> Option<ContactForce<S>> {
        let p = penetration_with(centre, alpha, semi_axes, ground_y)?;
        let r = [p.centroid[0] - centre[0], p.centroid[1] - centre[1]];
        // velocity of the body's material point at the centroid
        let v = [
            centre_velocity[0] - omega * r[1],
            centre_velocity[1] + omega * r[0],
        ];
        let normal = p.area * params.stiffness * (-v[1] * params.damping + 1.0);
        let mu = self.friction_coefficient_with(v[0], params.mu_dynamic);
        let tangential = -normal * mu;
        // F_t / F_n = −μ: no division by a normal force that vanishes at first contact
        let cop_x = p.centroid[0] + (p.centroid[1] - ground_y) * mu;
        Some(ContactForce {
            force: [tangential, normal],
            point: p.centroid,
            cop_x,
            penetration: p,
        })
    }
}
