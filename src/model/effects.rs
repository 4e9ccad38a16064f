//! Optional physical effects: model components with named parameters an optimiser may free.
//!
//! An effect is one type implementing [`Effect`]. Its hooks are generic over the scalar
//! type, so parameter sensitivities come from the same automatic differentiation as the
//! rest of the model. The blanket implementation of [`DynEffect`] makes every [`Effect`]
//! usable as a trait object; [`ModelScalar`] routes generic model code to it.
//!
//! A user adds an effect with one entry in the model JSON (`"effects": [{"type": …}]`);
//! [`EffectSpec`] lists the known kinds.

use super::ad::{AdChunk, AdNested};
use super::multibody::{Inertia, V2};
use super::Scalar;
use num_dual::Dual64;
use serde::{Deserialize, Serialize};

/// One named parameter of an effect.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamSpec {
    /// Fully qualified name, e.g. `passive_joint_stiffness.knee_r.stiffness`.
    pub name: String,
    /// Current (or initial) value.
    pub value: f64,
    /// Lower bound for identification.
    pub lower: f64,
    /// Upper bound for identification.
    pub upper: f64,
    /// Unit, for reports.
    pub unit: String,
    /// Whether the parameter is free (a sensitivity parameter θ of the model).
    pub free: bool,
}

/// Model quantities an effect may change before the dynamics are evaluated.
#[derive(Debug)]
pub struct ModelAdjust<'a, S> {
    /// Inertial parameters of each body.
    pub inertia: &'a mut [Inertia<S>],
    /// Gravity vector in the world frame (m/s²).
    pub gravity: &'a mut V2<S>,
    /// Ground plane height along its normal (m).
    pub ground_height: &'a mut S,
    /// Ground plane unit normal (world).
    pub ground_normal: &'a mut V2<S>,
}

/// Read-only state seen by an effect's generalised forces.
#[derive(Debug, Clone, Copy)]
pub struct EffectState<'a, S> {
    /// Generalised positions.
    pub q: &'a [S],
    /// Generalised velocities.
    pub qd: &'a [S],
}

/// A physical effect, written once for any scalar type.
pub trait Effect: std::fmt::Debug + Send + Sync {
    /// Kind name as used in JSON (`"type"`).
    fn kind(&self) -> &'static str;
    /// The effect's parameters (values, bounds, whether free), in a fixed order.
    fn parameters(&self) -> &[ParamSpec];
    /// Change inertial parameters, gravity or ground (default: nothing).
    fn adjust_model<S: Scalar>(&self, _p: &[S], _m: &mut ModelAdjust<'_, S>) {}
    /// Add generalised forces (N or N·m) to `tau` (default: nothing).
    fn generalized_forces<S: Scalar>(&self, _p: &[S], _x: EffectState<'_, S>, _tau: &mut [S]) {}
}

/// Object-safe form of [`Effect`], implemented for every effect. The methods are
/// monomorphic copies of the generic hooks, one per scalar type the model uses.
#[allow(missing_docs)]
pub trait DynEffect: std::fmt::Debug + Send + Sync {
    fn kind(&self) -> &'static str;
    fn parameters(&self) -> &[ParamSpec];
    fn adjust_f64(&self, p: &[f64], m: &mut ModelAdjust<'_, f64>);
    fn adjust_dual(&self, p: &[Dual64], m: &mut ModelAdjust<'_, Dual64>);
    fn adjust_chunk(&self, p: &[AdChunk], m: &mut ModelAdjust<'_, AdChunk>);
    fn adjust_nested(&self, p: &[AdNested], m: &mut ModelAdjust<'_, AdNested>);
    fn forces_f64(&self, p: &[f64], x: EffectState<'_, f64>, tau: &mut [f64]);
    fn forces_dual(&self, p: &[Dual64], x: EffectState<'_, Dual64>, tau: &mut [Dual64]);
    fn forces_chunk(&self, p: &[AdChunk], x: EffectState<'_, AdChunk>, tau: &mut [AdChunk]);
    fn forces_nested(&self, p: &[AdNested], x: EffectState<'_, AdNested>, tau: &mut [AdNested]);
}

impl<E: Effect> DynEffect for E {
    fn kind(&self) -> &'static str {
        Effect::kind(self)
    }
    fn parameters(&self) -> &[ParamSpec] {
        Effect::parameters(self)
    }
    fn adjust_f64(&self, p: &[f64], m: &mut ModelAdjust<'_, f64>) {
        self.adjust_model(p, m)
    }
    fn adjust_dual(&self, p: &[Dual64], m: &mut ModelAdjust<'_, Dual64>) {
        self.adjust_model(p, m)
    }
    fn adjust_chunk(&self, p: &[AdChunk], m: &mut ModelAdjust<'_, AdChunk>) {
        self.adjust_model(p, m)
    }
    fn adjust_nested(&self, p: &[AdNested], m: &mut ModelAdjust<'_, AdNested>) {
        self.adjust_model(p, m)
    }
    fn forces_f64(&self, p: &[f64], x: EffectState<'_, f64>, tau: &mut [f64]) {
        self.generalized_forces(p, x, tau)
    }
    fn forces_dual(&self, p: &[Dual64], x: EffectState<'_, Dual64>, tau: &mut [Dual64]) {
        self.generalized_forces(p, x, tau)
    }
    fn forces_chunk(&self, p: &[AdChunk], x: EffectState<'_, AdChunk>, tau: &mut [AdChunk]) {
        self.generalized_forces(p, x, tau)
    }
    fn forces_nested(&self, p: &[AdNested], x: EffectState<'_, AdNested>, tau: &mut [AdNested]) {
        self.generalized_forces(p, x, tau)
    }
}

/// The scalar types the model's dynamics can be evaluated in (those [`DynEffect`] has a
/// method for).
pub trait ModelScalar: Scalar {
    /// Route to the effect's model adjustment for this scalar type.
    fn adjust(e: &dyn DynEffect, p: &[Self], m: &mut ModelAdjust<'_, Self>);
    /// Route to the effect's generalised forces for this scalar type.
    fn forces(e: &dyn DynEffect, p: &[Self], x: EffectState<'_, Self>, tau: &mut [Self]);
}

macro_rules! model_scalar {
    ($t:ty, $adj:ident, $frc:ident) => {
        impl ModelScalar for $t {
            fn adjust(e: &dyn DynEffect, p: &[Self], m: &mut ModelAdjust<'_, Self>) {
                e.$adj(p, m)
            }
            fn forces(e: &dyn DynEffect, p: &[Self], x: EffectState<'_, Self>, tau: &mut [Self]) {
                e.$frc(p, x, tau)
            }
        }
    };
}
model_scalar!(f64, adjust_f64, forces_f64);
model_scalar!(Dual64, adjust_dual, forces_dual);
model_scalar!(AdChunk, adjust_chunk, forces_chunk);
model_scalar!(AdNested, adjust_nested, forces_nested);

/// A linear torsional spring at one joint coordinate: τ = −k (θ − θ₀).
///
/// Models the passive elastic torque of ligaments, joint capsule and stretched muscle
/// that the muscle-torque generators leave out (seed §2 ignores it).
#[derive(Debug, Clone)]
pub struct PassiveJointStiffness {
    coordinate: usize,
    params: Vec<ParamSpec>,
}

impl PassiveJointStiffness {
    /// Spring at coordinate index `coordinate` (named `coordinate_name`) with stiffness
    /// `stiffness` (N·m/rad) and rest angle `rest_angle` (rad).
    pub fn new(
        coordinate: usize,
        coordinate_name: &str,
        stiffness: f64,
        rest_angle: f64,
        free_stiffness: bool,
        free_rest_angle: bool,
    ) -> Self {
        let base = format!("passive_joint_stiffness.{coordinate_name}");
        Self {
            coordinate,
            params: vec![
                ParamSpec {
                    name: format!("{base}.stiffness"),
                    value: stiffness,
                    lower: 0.0,
                    upper: 500.0,
                    unit: "N·m/rad".into(),
                    free: free_stiffness,
                },
                ParamSpec {
                    name: format!("{base}.rest_angle"),
                    value: rest_angle,
                    lower: -std::f64::consts::PI,
                    upper: std::f64::consts::PI,
                    unit: "rad".into(),
                    free: free_rest_angle,
                },
            ],
        }
    }
}

impl Effect for PassiveJointStiffness {
    fn kind(&self) -> &'static str {
        "passive_joint_stiffness"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn generalized_forces<S: Scalar>(&self, p: &[S], x: EffectState<'_, S>, tau: &mut [S]) {
        let (k, rest) = (p[0], p[1]);
        tau[self.coordinate] -= k * (x.q[self.coordinate] - rest);
    }
}

/// An effect as written in a model JSON file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum EffectSpec {
    /// [`PassiveJointStiffness`] on one joint, on one or both legs.
    PassiveJointStiffness {
        /// `hip`, `knee` or `ankle`.
        joint: String,
        /// `both` (default), `right` or `left`.
        #[serde(default = "both")]
        side: String,
        /// Stiffness (N·m/rad, ≥ 0).
        stiffness: f64,
        /// Rest angle (rad).
        #[serde(default)]
        rest_angle: f64,
        /// Names of the parameters to free: `stiffness`, `rest_angle`.
        #[serde(default)]
        free: Vec<String>,
    },
}

fn both() -> String {
    "both".into()
}

impl EffectSpec {
    /// Check the entry without a model; the error names the offending field (`joint`,
    /// `side`, `stiffness`, `rest_angle`, `free`) and what is wrong.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        match self {
            EffectSpec::PassiveJointStiffness {
                joint,
                side,
                stiffness,
                rest_angle,
                free,
            } => {
                if !["hip", "knee", "ankle"].contains(&joint.as_str()) {
                    return Err((
                        "joint",
                        format!(
                            "'{joint}' is not a joint of the model; use one of hip, knee, ankle"
                        ),
                    ));
                }
                if !["both", "right", "left"].contains(&side.as_str()) {
                    return Err(("side", format!("'{side}' is not one of both, right, left")));
                }
                if !(stiffness.is_finite() && *stiffness >= 0.0) {
                    return Err((
                        "stiffness",
                        format!("must be a finite number ≥ 0 N·m/rad, got {stiffness}"),
                    ));
                }
                if !rest_angle.is_finite() {
                    return Err((
                        "rest_angle",
                        format!("must be a finite number of radians, got {rest_angle}"),
                    ));
                }
                for (k, f) in free.iter().enumerate() {
                    if f != "stiffness" && f != "rest_angle" {
                        return Err((
                            "free",
                            format!("entry {k} '{f}' is not one of stiffness, rest_angle"),
                        ));
                    }
                    if free[..k].contains(f) {
                        return Err(("free", format!("'{f}' is listed twice")));
                    }
                }
                Ok(())
            }
        }
    }

    /// Build the effect instances for a model with generalised coordinates `coords`.
    pub fn build(&self, coords: &[String]) -> Result<Vec<Box<dyn DynEffect>>, String> {
        self.check()
            .map_err(|(field, reason)| format!("{field}: {reason}"))?;
        match self {
            EffectSpec::PassiveJointStiffness {
                joint,
                side,
                stiffness,
                rest_angle,
                free,
            } => {
                let sides: &[&str] = match side.as_str() {
                    "right" => &["r"],
                    "left" => &["l"],
                    _ => &["r", "l"],
                };
                let mut out: Vec<Box<dyn DynEffect>> = Vec::new();
                for s in sides {
                    let name = format!("{joint}_{s}");
                    let idx = coords
                        .iter()
                        .position(|c| *c == name)
                        .ok_or_else(|| format!("joint: the model has no coordinate '{name}'"))?;
                    out.push(Box::new(PassiveJointStiffness::new(
                        idx,
                        &name,
                        *stiffness,
                        *rest_angle,
                        free.iter().any(|f| f == "stiffness"),
                        free.iter().any(|f| f == "rest_angle"),
                    )));
                }
                Ok(out)
            }
        }
    }
}
