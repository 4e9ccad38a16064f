//! Two standard non-gait optimal-control benchmark models, used to prove the generic
//! multiple-shooting engine against an independent CasADi/IPOPT implementation of the same
//! problems (the peer problem files `problems/cartpole_swingup.json` and
//! `problems/five_link_biped.json`), and the [`Benchmark`] problems built on them
//! ([`problem`]: JSON problem loading and transcription).
//!
//! Both models implement [`ControlledOde`](crate::integrate::ControlledOde) with no free
//! model parameters (nθ = 0).  Their dynamics are written once, generic over
//! [`Scalar`](crate::model::Scalar); the Jacobians come from forward-mode automatic
//! differentiation (`num_dual` vector duals), never from difference quotients: one 5-lane
//! pass over (x, u) for the cart-pole; for the biped, AD of M(q) and of the right-hand side
//! r(q, q̇, u) of M q̈ = r in three 5-lane passes (blocks q, q̇, u) combined with the exact
//! derivative rule of the linear solve, ∂q̈ = M⁻¹(∂r − ∂M q̈), which gives the same
//! Jacobian as AD through the Cholesky factorisation at about 0.6× the cost of the best
//! plain-AD variant (3 passes of 5 lanes) and a quarter of one 15-lane pass (see
//! `tests/benchmark_models.rs`, `timing_of_f_and_f_jac`).
//!
//! # Cart-pole ([`CartPole`])
//!
//! State $x = (x_c, \theta, \dot x_c, \dot\theta)$ (cart position, pole angle with
//! $\theta = 0$ hanging down and $\theta = \pi$ upright, counter-clockwise positive),
//! control $u$ = horizontal force on the cart.  With cart mass $m_c$, pole mass $m_p$,
//! distance $l_c$ from the pivot to the pole's centre of mass and pole inertia $I$ about its
//! centre of mass (uniform rod of length $2 l_c$: $I = m_p (2 l_c)^2 / 12$), the Lagrangian
//! equations are
//! $$(m_c + m_p)\,\ddot x_c + m_p l_c \cos\theta\,\ddot\theta - m_p l_c \sin\theta\,\dot\theta^2 = u,$$
//! $$m_p l_c \cos\theta\,\ddot x_c + (I + m_p l_c^2)\,\ddot\theta + m_p g l_c \sin\theta = 0.$$
//! Physical parameters: Barto, Sutton & Anderson (1983), "Neuronlike adaptive elements that
//! can solve difficult learning control problems", IEEE Trans. SMC 13(5) (the OpenAI-gym
//! CartPole values: 1.0 kg cart, 0.1 kg pole of half-length 0.5 m), with g = 9.81 m/s².
//! Task form (fixed-time swing-up, minimum ∫u²): Kelly (2017), sec. 6.
//!
//! # Five-link biped ([`FiveLinkBiped`])
//!
//! The planar point-foot walker of Kelly (2017), sec. 7 (OptimTraj `demo/fiveLinkBiped`,
//! RABBIT-like parameters of Westervelt, Grizzle & Koditschek, IEEE TAC 2003).  State
//! $(q_1..q_5, \dot q_1..\dot q_5)$ with absolute link angles from the vertical
//! (stance tibia, stance femur, torso, swing femur, swing tibia; counter-clockwise positive),
//! control $u_1..u_5$ (stance ankle, stance knee, stance hip, swing hip, swing knee torques).
//! In single stance with the stance foot pinned at the origin,
//! $$M(q)\,\ddot q + C(q, \dot q) + G(q) = Q,\qquad
//!   Q = (u_1 - u_2,\ u_2 - u_3,\ u_3 - u_4,\ u_4 - u_5,\ u_5).$$
//! Because every link centre of mass is a constant combination
//! $G_k = \sum_j a_{kj}\,\hat e(q_j)$ of the unit vectors $\hat e(q) = (-\sin q, \cos q)$,
//! with $B = \sum_k m_k a_k a_k^T$ and $b = \sum_k m_k a_k$:
//! $$M_{ij} = B_{ij}\cos(q_i - q_j) + I_i\,\delta_{ij},\quad
//!   C_i = \sum_j B_{ij} \sin(q_i - q_j)\,\dot q_j^2,\quad G_i = -g\, b_i \sin q_i .$$
//! Heel strike ([`FiveLinkBiped::heel_strike`]) is the perfectly plastic, non-slipping
//! impact of the swing foot followed by relabelling of the legs:
//! in extended coordinates $z = (b_x, b_y, q)$,
//! $M_e(\dot z^+ - \dot z^-) = J_5^T \Lambda$, $J_5 \dot z^+ = 0$, $\dot z^- = (0, 0, \dot q^-)$,
//! and $x^+ = (F q^-, F \dot q^+)$ with $F$ = reversal of the link order.
//! Note (from the peer's `c_note`): the torso's centre of mass lies $c_3$ *below the top of
//! the torso*, i.e. $l_3 - c_3$ above the hip, as in OptimTraj's generated code.
//!
//! # References
//!
//! * M. Kelly, "An Introduction to Trajectory Optimization: How to Do Your Own Direct
//!   Collocation", SIAM Review 59(4):849–904, 2017.
//! * A. G. Barto, R. S. Sutton, C. W. Anderson, IEEE Trans. Systems, Man, and Cybernetics
//!   13(5):834–846, 1983.
//! * E. R. Westervelt, J. W. Grizzle, D. E. Koditschek, "Hybrid zero dynamics of planar
//!   biped walkers", IEEE Trans. Automatic Control 48(1), 2003.
//!
//! # Loading
//!
//! `CartPole::from_problem_json` and `FiveLinkBiped::from_problem_json` read the physical
//! parameters from the peer problem files (see [`read_problem_json`]); the `Default`
//! implementations hold the same values, so nothing depends on files being present.

pub mod biped;
pub mod cartpole;
pub mod problem;

pub use biped::{FiveLinkBiped, HeelStrike};
pub use cartpole::CartPole;
pub use problem::{Benchmark, BenchmarkError, ProblemFileError, GAIT_TRACK, MAX_INTERVALS};

use std::path::Path;

use serde_json::Value;

/// Why a benchmark model's physical parameters were refused (`model`: `cart-pole` or
/// `five-link biped`; fields as dotted paths, e.g. `parameters.m`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParameterError {
    /// A field of the problem JSON is absent.
    #[error("{model} problem JSON: missing field `{field}`")]
    Missing {
        /// The model.
        model: &'static str,
        /// The field (the first absent part of its path).
        field: String,
    },
    /// A field of the problem JSON is not a finite number.
    #[error("{model} problem JSON: field `{field}` must be a finite number, got {value}")]
    NotANumber {
        /// The model.
        model: &'static str,
        /// The field.
        field: String,
        /// The value found.
        value: Value,
    },
    /// A field of the problem JSON is not an array of finite numbers of the right length.
    #[error("{model} problem JSON: field `{field}` must be an array of {len} finite numbers, got {value}")]
    NotNumbers {
        /// The model.
        model: &'static str,
        /// The field.
        field: String,
        /// Entries expected.
        len: usize,
        /// The value found.
        value: Value,
    },
    /// A parameter (a mass, length or inertia) is not positive and finite.
    #[error("{model}: {parameter} must be positive and finite, got {value}")]
    NotPositive {
        /// The model.
        model: &'static str,
        /// The parameter.
        parameter: &'static str,
        /// Its value (kg, m or kg m²).
        value: f64,
    },
    /// An entry of a per-link parameter is not positive and finite.
    #[error("{model}: every {parameter} must be positive and finite, got {value}")]
    NotAllPositive {
        /// The model.
        model: &'static str,
        /// The parameter.
        parameter: &'static str,
        /// The first entry refused (kg, m or kg m²).
        value: f64,
    },
    /// A parameter (gravity) is not finite.
    #[error("{model}: {parameter} must be finite, got {value}")]
    NotFinite {
        /// The model.
        model: &'static str,
        /// The parameter.
        parameter: &'static str,
        /// Its value (m/s²).
        value: f64,
    },
    /// An entry of a per-link parameter is not finite.
    #[error("{model}: every {parameter} must be finite, got {value}")]
    NotAllFinite {
        /// The model.
        model: &'static str,
        /// The parameter.
        parameter: &'static str,
        /// The first entry refused (m).
        value: f64,
    },
}

/// Read and parse a problem JSON file; errors name the file.
pub fn read_problem_json(path: impl AsRef<Path>) -> Result<Value, ProblemFileError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| ProblemFileError::Io {
        path: path.into(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|source| ProblemFileError::Json {
        path: path.into(),
        source,
    })
}

/// The value at the dotted `path` (e.g. `["parameters", "m"]`), or an error naming it.
fn field<'a>(
    problem: &'a Value,
    path: &[&str],
    model: &'static str,
) -> Result<&'a Value, ParameterError> {
    let mut v = problem;
    for (depth, key) in path.iter().enumerate() {
        v = v.get(key).ok_or_else(|| ParameterError::Missing {
            model,
            field: path[..=depth].join("."),
        })?;
    }
    Ok(v)
}

/// A finite number at `path`.
fn number(problem: &Value, path: &[&str], model: &'static str) -> Result<f64, ParameterError> {
    let v = field(problem, path, model)?;
    match v.as_f64() {
        Some(x) if x.is_finite() => Ok(x),
        _ => Err(ParameterError::NotANumber {
            model,
            field: path.join("."),
            value: v.clone(),
        }),
    }
}

/// An array of `N` finite numbers at `path`.
fn numbers<const N: usize>(
    problem: &Value,
    path: &[&str],
    model: &'static str,
) -> Result<[f64; N], ParameterError> {
    let v = field(problem, path, model)?;
    let bad = || ParameterError::NotNumbers {
        model,
        field: path.join("."),
        len: N,
        value: v.clone(),
    };
    let arr = v.as_array().ok_or_else(bad)?;
    if arr.len() != N {
        return Err(bad());
    }
    let mut out = [0.0; N];
    for (o, x) in out.iter_mut().zip(arr) {
        *o = x.as_f64().filter(|x| x.is_finite()).ok_or_else(bad)?;
    }
    Ok(out)
}

/// Check the buffer lengths of a `ControlledOde` call on a model without parameters.
pub(crate) fn check_dims(
    model: &str,
    nx: usize,
    nu: usize,
    x: &[f64],
    u: &[f64],
    theta: &[f64],
    xdot: &[f64],
) -> Result<(), crate::integrate::OdeError> {
    if x.len() != nx || u.len() != nu || !theta.is_empty() || xdot.len() != nx {
        return Err(crate::integrate::OdeError::Fatal(format!(
            "{model}: expected x, xdot of length {nx}, u of length {nu} and no θ, got {}, {}, {}, {}",
            x.len(),
            xdot.len(),
            u.len(),
            theta.len()
        )));
    }
    Ok(())
}

/// A non-finite derivative is recoverable: CVODES retries with a smaller step.
pub(crate) fn finite(model: &str, v: &[f64]) -> Result<(), crate::integrate::OdeError> {
    if v.iter().all(|a| a.is_finite()) {
        Ok(())
    } else {
        Err(crate::integrate::OdeError::Recoverable(format!(
            "{model}: non-finite state derivative"
        )))
    }
}

/// `∇²_{(x,u)} (μᵀ f)` of a parameter-free model with `nx` states and `N − nx` controls into
/// `out` (`N × N`, column-major), for [`ControlledOde::weighted_hessian`]; `f` maps
/// `z = (x, u)` to the state derivative. `Ok(false)` when the Hessian is not finite.
///
/// [`ControlledOde::weighted_hessian`]: crate::integrate::ControlledOde::weighted_hessian
pub(crate) fn weighted_hessian<const N: usize, F>(
    nx: usize,
    x: &[f64],
    u: &[f64],
    mu: &[f64],
    out: &mut [f64],
    f: impl Fn(&[num_dual::Dual2SVec64<N>]) -> F,
) -> Result<bool, crate::integrate::OdeError>
where
    F: IntoIterator<Item = num_dual::Dual2SVec64<N>>,
{
    if x.len() != nx || u.len() != N - nx || mu.len() != nx || out.len() != N * N {
        return Err(crate::integrate::OdeError::Fatal(
            "weighted_hessian: wrong buffer lengths".into(),
        ));
    }
    let z: Vec<f64> = x.iter().chain(u).copied().collect();
    let h = crate::model::ad::dense_hessian::<N>(&z, |zs| {
        f(zs)
            .into_iter()
            .zip(mu)
            .fold(num_dual::Dual2SVec64::<N>::from(0.0), |acc, (fi, m)| {
                acc + fi * *m
            })
    });
    out.copy_from_slice(&h);
    Ok(out.iter().all(|v| v.is_finite()))
}

/// The state derivative and its Jacobians `(f, fx, fu)` from `eval` into the buffers of
/// [`ControlledOde::f_jac`] of a parameter-free model, after checking the lengths of `fx`
/// (nx×nx) and `fu` (nx×nu); a non-finite value is recoverable.
///
/// [`ControlledOde::f_jac`]: crate::integrate::ControlledOde::f_jac
pub(crate) fn write_f_jac<A: AsRef<[f64]>, B: AsRef<[f64]>, C: AsRef<[f64]>>(
    model: &str,
    (nx, nu): (usize, usize),
    xdot: &mut [f64],
    fx: &mut [f64],
    fu: &mut [f64],
    eval: impl FnOnce() -> (A, B, C),
) -> Result<(), crate::integrate::OdeError> {
    if fx.len() != nx * nx || fu.len() != nx * nu {
        return Err(crate::integrate::OdeError::Fatal(format!(
            "{model}: expected fx of length {} and fu of length {}, got {}, {}",
            nx * nx,
            nx * nu,
            fx.len(),
            fu.len()
        )));
    }
    let (v, jx, ju) = eval();
    xdot.copy_from_slice(v.as_ref());
    fx.copy_from_slice(jx.as_ref());
    fu.copy_from_slice(ju.as_ref());
    finite(model, xdot)?;
    finite(model, fx)?;
    finite(model, fu)
}
