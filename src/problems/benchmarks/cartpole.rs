//! The cart-pole (see the [module docs](super) for the equations and sources).

use num_dual::DualSVec64;
use serde_json::Value;

use super::{number, ParameterError};
use crate::integrate::{ControlledOde, OdeError};
use crate::model::ad::{eps, seed};
use crate::model::Scalar;

/// Number of states (x, θ, ẋ, θ̇).
pub const NX: usize = 4;
/// Number of controls (horizontal force on the cart).
pub const NU: usize = 1;

/// Dual number with one lane per state and control: one pass gives fx and fu.
type Ad = DualSVec64<{ NX + NU }>;

/// Frictionless cart-pole: state (x, θ, ẋ, θ̇) with θ = 0 hanging down, control u (N).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CartPole {
    /// Cart mass m_c (kg).
    pub cart_mass: f64,
    /// Pole mass m_p (kg).
    pub pole_mass: f64,
    /// Distance l_c from the pivot to the pole's centre of mass (m), half the pole length.
    pub pole_half_length: f64,
    /// Pole moment of inertia about its centre of mass (kg m²).
    pub pole_inertia: f64,
    /// Gravitational acceleration (m/s²).
    pub gravity: f64,
}

impl Default for CartPole {
    /// The peer problem's values: 1.0 kg cart, 0.1 kg uniform pole of half-length 0.5 m,
    /// I = m_p (2 l_c)² / 12, g = 9.81 m/s².
    fn default() -> Self {
        Self::uniform_rod(1.0, 0.1, 0.5, 9.81)
    }
}

impl CartPole {
    /// A cart-pole whose pole is a uniform rod of length `2 * pole_half_length`.
    pub fn uniform_rod(
        cart_mass: f64,
        pole_mass: f64,
        pole_half_length: f64,
        gravity: f64,
    ) -> Self {
        let len = 2.0 * pole_half_length;
        Self {
            cart_mass,
            pole_mass,
            pole_half_length,
            pole_inertia: pole_mass * len * len / 12.0,
            gravity,
        }
    }

    /// Physical parameters from a problem JSON like the peer's `cartpole_swingup.json`:
    /// `parameters.{cart_mass, pole_mass, pole_half_length, gravity}` and optionally
    /// `parameters.pole_inertia_about_com` (default: uniform rod).  The error names the
    /// missing or malformed field.
    pub fn from_problem_json(problem: &Value) -> Result<Self, ParameterError> {
        const WHAT: &str = "cart-pole";
        let get = |k: &str| number(problem, &["parameters", k], WHAT);
        let mut cp = Self::uniform_rod(
            get("cart_mass")?,
            get("pole_mass")?,
            get("pole_half_length")?,
            get("gravity")?,
        );
        if problem["parameters"]
            .get("pole_inertia_about_com")
            .is_some()
        {
            cp.pole_inertia = get("pole_inertia_about_com")?;
        }
        cp.validate()?;
        Ok(cp)
    }

    /// Check that masses, length and inertia are positive and gravity is finite.
    pub fn validate(&self) -> Result<(), ParameterError> {
        for (name, v) in [
            ("cart_mass", self.cart_mass),
            ("pole_mass", self.pole_mass),
            ("pole_half_length", self.pole_half_length),
            ("pole_inertia", self.pole_inertia),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(ParameterError::NotPositive {
                    model: "cart-pole",
                    parameter: name,
                    value: v,
                });
            }
        }
        if !self.gravity.is_finite() {
            return Err(ParameterError::NotFinite {
                model: "cart-pole",
                parameter: "gravity",
                value: self.gravity,
            });
        }
        Ok(())
    }

    /// State derivative ẋ = f(x, u) for any scalar type (plain or dual numbers).
    ///
    /// `x = [x, θ, ẋ, θ̇]`, `u` = force on the cart.
    #[inline]
    pub fn rhs<S: Scalar>(&self, x: &[S; NX], u: S) -> [S; NX] {
        let (mc, mp, lc, g) = (
            self.cart_mass,
            self.pole_mass,
            self.pole_half_length,
            self.gravity,
        );
        let (s, c) = x[1].sin_cos();
        let dth = x[3];
        // M = [[mc + mp, b], [b, a]] with a = I + mp lc², b = mp lc cos θ.
        let a = self.pole_inertia + mp * lc * lc;
        let b = c * (mp * lc);
        let det = -(b * b) + (mc + mp) * a;
        let r1 = u + s * dth * dth * (mp * lc);
        let r2 = s * (-mp * g * lc);
        let inv = det.recip();
        let ddx = (r1 * a - b * r2) * inv;
        let ddth = (r2 * (mc + mp) - b * r1) * inv;
        [x[2], dth, ddx, ddth]
    }

    /// Kinetic and potential energy (J) of state `x`; the potential is zero with the pole's
    /// centre of mass at the pivot height.
    pub fn energy<S: Scalar>(&self, x: &[S; NX]) -> (S, S) {
        let (mc, mp, lc) = (self.cart_mass, self.pole_mass, self.pole_half_length);
        let (s, c) = x[1].sin_cos();
        let (dx, dth) = (x[2], x[3]);
        // pole CoM velocity: (ẋ + lc cos θ θ̇, lc sin θ θ̇)
        let vx = dx + c * dth * lc;
        let vy = s * dth * lc;
        let kinetic = dx * dx * (0.5 * mc)
            + (vx * vx + vy * vy) * (0.5 * mp)
            + dth * dth * (0.5 * self.pole_inertia);
        let potential = c * (-mp * self.gravity * lc);
        (kinetic, potential)
    }

    /// f and its Jacobians by one forward pass with a 5-lane dual number:
    /// returns `(xdot, fx (4×4), fu (4×1))`, column-major.
    #[inline]
    pub fn rhs_jacobian(&self, x: &[f64; NX], u: f64) -> ([f64; NX], [f64; NX * NX], [f64; NX]) {
        let xs: [Ad; NX] = std::array::from_fn(|k| seed(x[k], k));
        let y = self.rhs(&xs, seed(u, NX));
        let xdot = y.map(|v| v.re);
        let mut fx = [0.0; NX * NX];
        let mut fu = [0.0; NX];
        for (i, yi) in y.iter().enumerate() {
            for j in 0..NX {
                fx[i + j * NX] = eps(yi, j);
            }
            fu[i] = eps(yi, NX);
        }
        (xdot, fx, fu)
    }
}

fn check_dims(x: &[f64], u: &[f64], theta: &[f64], xdot: &[f64]) -> Result<(), OdeError> {
    super::check_dims("cart-pole", NX, NU, x, u, theta, xdot)
}

fn finite(v: &[f64]) -> Result<(), OdeError> {
    super::finite("cart-pole", v)
}

impl ControlledOde for CartPole {
    fn nx(&self) -> usize {
        NX
    }
    fn nu(&self) -> usize {
        NU
    }
    fn ntheta(&self) -> usize {
        0
    }
    fn f(&self, x: &[f64], u: &[f64], theta: &[f64], xdot: &mut [f64]) -> Result<(), OdeError> {
        check_dims(x, u, theta, xdot)?;
        let x: &[f64; NX] = x.try_into().expect("length checked");
        xdot.copy_from_slice(&self.rhs(x, u[0]));
        finite(xdot)
    }
    fn weighted_hessian(
        &self,
        x: &[f64],
        u: &[f64],
        _theta: &[f64],
        mu: &[f64],
        out: &mut [f64],
    ) -> Result<bool, OdeError> {
        super::weighted_hessian::<{ NX + NU }, _>(NX, x, u, mu, out, |zs| {
            self.rhs(&[zs[0], zs[1], zs[2], zs[3]], zs[4])
        })
    }
    fn f_jac(
        &self,
        x: &[f64],
        u: &[f64],
        theta: &[f64],
        xdot: &mut [f64],
        fx: &mut [f64],
        fu: &mut [f64],
        _ftheta: &mut [f64],
    ) -> Result<(), OdeError> {
        check_dims(x, u, theta, xdot)?;
        super::write_f_jac("cart-pole", (NX, NU), xdot, fx, fu, || {
            self.rhs_jacobian(x.try_into().expect("length checked"), u[0])
        })
    }
}
