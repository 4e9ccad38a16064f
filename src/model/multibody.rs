//! Planar rigid-body tree: kinematics, mass matrix and bias forces.
//!
//! Every body carries exactly one joint (one generalised coordinate, `q[b]` for body `b`),
//! so `nq` equals the number of bodies; a floating base is a chain of two prismatic
//! joints and one revolute joint with massless intermediate bodies. Bodies are stored
//! parent-before-child. A revolute joint sits at the child's origin; a prismatic joint
//! slides the child's origin along an axis fixed in the parent frame.
//!
//! With body angles $\theta_b$, angular velocities $\omega_b$, centre-of-mass Jacobians
//! $J_b$ (2 × nq) and rotational Jacobians $J_{\omega,b}$ (1 × nq, constant in the plane),
//! $$M(q) = \sum_b m_b J_b^T J_b + I_b J_{\omega,b}^T J_{\omega,b},\qquad
//!   c(q,\dot q) = \sum_b m_b J_b^T (\dot J_b \dot q - g),$$
//! where $\dot J_b \dot q$ is the centre-of-mass acceleration at $\ddot q = 0$, computed by
//! a forward recursion over the tree (planar: $\dot J_\omega = 0$).
//!
//! All functions are generic over [`Scalar`]; derivatives come from forward-mode AD.

use super::error::TreeError;
use super::Scalar;
use serde::{Deserialize, Serialize};

/// 2-D vector.
pub type V2<S> = [S; 2];

#[inline]
pub(crate) fn add<S: Scalar>(a: V2<S>, b: V2<S>) -> V2<S> {
    [a[0] + b[0], a[1] + b[1]]
}
#[inline]
pub(crate) fn sub<S: Scalar>(a: V2<S>, b: V2<S>) -> V2<S> {
    [a[0] - b[0], a[1] - b[1]]
}
#[inline]
pub(crate) fn scale<S: Scalar>(a: V2<S>, s: S) -> V2<S> {
    [a[0] * s, a[1] * s]
}
#[inline]
pub(crate) fn dot<S: Scalar>(a: V2<S>, b: V2<S>) -> S {
    a[0] * b[0] + a[1] * b[1]
}
/// `ẑ × a` (rotation by +90°).
#[inline]
pub(crate) fn perp<S: Scalar>(a: V2<S>) -> V2<S> {
    [-a[1], a[0]]
}
/// Rotate `a` by the angle with cosine `c` and sine `s`.
#[inline]
pub(crate) fn rotate<S: Scalar>(c: S, s: S, a: V2<S>) -> V2<S> {
    [c * a[0] - s * a[1], s * a[0] + c * a[1]]
}
#[inline]
pub(crate) fn lift<S: Scalar>(a: [f64; 2]) -> V2<S> {
    [S::c(a[0]), S::c(a[1])]
}

/// The joint between a body and its parent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "type")]
pub enum Joint {
    /// Rotation about the out-of-plane axis at the body origin (rad, counter-clockwise +).
    Revolute,
    /// Translation of the body origin along a unit axis fixed in the parent frame (m).
    Prismatic {
        /// Unit axis in the parent frame.
        axis: [f64; 2],
    },
}

/// Inertial parameters of one body, possibly carrying derivative parts (effects may make
/// them depend on free parameters).
#[derive(Debug, Clone, Copy)]
pub struct Inertia<S> {
    /// Mass (kg).
    pub mass: S,
    /// Centre of mass in the body frame (m).
    pub com: V2<S>,
    /// Moment of inertia about the centre of mass, out-of-plane axis (kg·m²).
    pub izz: S,
}

/// One body of the tree.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Body {
    /// Name, unique in the tree.
    pub name: String,
    /// Parent body index (`None` = ground).
    pub parent: Option<usize>,
    /// Joint to the parent.
    pub joint: Joint,
    /// Joint location in the parent frame at q = 0 (m).
    pub joint_in_parent: [f64; 2],
    /// Mass (kg); zero for virtual bodies of a floating base.
    pub mass: f64,
    /// Centre of mass in the body frame (m).
    pub com: [f64; 2],
    /// Moment of inertia about the COM (kg·m²).
    pub izz: f64,
}

/// A planar tree of bodies.
#[derive(Debug, Clone, PartialEq)]
pub struct Tree {
    bodies: Vec<Body>,
    /// `ancestors[b]`: the bodies whose joints move body `b` (including `b`), root first.
    ancestors: Vec<Vec<usize>>,
}

/// Kinematic quantities of all bodies at one state.
#[derive(Debug, Clone)]
pub struct Kinematics<S> {
    /// World angle of each body (rad).
    pub angle: Vec<S>,
    /// cos, sin of the world angle.
    pub cs: Vec<(S, S)>,
    /// World origin of each body (m).
    pub origin: Vec<V2<S>>,
    /// Angular velocity (rad/s).
    pub omega: Vec<S>,
    /// Origin velocity (m/s).
    pub vel: Vec<V2<S>>,
    /// Origin acceleration at zero generalised acceleration (m/s²).
    pub acc_bias: Vec<V2<S>>,
    /// World direction of each prismatic joint axis (zero for revolute joints).
    pub axis: Vec<V2<S>>,
}

impl Tree {
    /// Build a tree; bodies must be ordered parent before child.
    pub fn new(bodies: Vec<Body>) -> Result<Self, TreeError> {
        let mut ancestors: Vec<Vec<usize>> = Vec::with_capacity(bodies.len());
        for (b, body) in bodies.iter().enumerate() {
            let mut chain = match body.parent {
                None => Vec::new(),
                Some(p) if p < b => ancestors[p].clone(),
                Some(p) => {
                    return Err(TreeError::ParentOrder {
                        body: body.name.clone(),
                        index: b,
                        parent: p,
                    })
                }
            };
            chain.push(b);
            ancestors.push(chain);
            if let Joint::Prismatic { axis } = body.joint {
                let n = (axis[0] * axis[0] + axis[1] * axis[1]).sqrt();
                if (n - 1.0).abs() > 1e-9 {
                    return Err(TreeError::PrismaticAxis {
                        body: body.name.clone(),
                        axis,
                    });
                }
            }
        }
        Ok(Self { bodies, ancestors })
    }

    /// The bodies.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }
    /// Number of generalised coordinates (= bodies).
    pub fn nq(&self) -> usize {
        self.bodies.len()
    }
    /// Index of the body called `name`.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }
    /// Joints that move body `b`, root first, including `b`.
    pub fn ancestors(&self, b: usize) -> &[usize] {
        &self.ancestors[b]
    }
    /// Inertial parameters as constants.
    pub fn inertias<S: Scalar>(&self) -> Vec<Inertia<S>> {
        self.bodies
            .iter()
            .map(|b| Inertia {
                mass: S::c(b.mass),
                com: lift(b.com),
                izz: S::c(b.izz),
            })
            .collect()
    }

    /// Forward kinematic recursion.
    pub fn kinematics<S: Scalar>(&self, q: &[S], qd: &[S]) -> Kinematics<S> {
        let n = self.nq();
        let z = S::c(0.0);
        let mut k = Kinematics {
            angle: Vec::with_capacity(n),
            cs: Vec::with_capacity(n),
            origin: Vec::with_capacity(n),
            omega: Vec::with_capacity(n),
            vel: Vec::with_capacity(n),
            acc_bias: Vec::with_capacity(n),
            axis: Vec::with_capacity(n),
        };
        for (b, body) in self.bodies.iter().enumerate() {
            let (pa, pcs, po, pw, pv, pab) = match body.parent {
                Some(p) => (
                    k.angle[p],
                    k.cs[p],
                    k.origin[p],
                    k.omega[p],
                    k.vel[p],
                    k.acc_bias[p],
                ),
                None => (z, (S::c(1.0), z), [z, z], z, [z, z], [z, z]),
            };
            let attach = add(po, rotate(pcs.0, pcs.1, lift(body.joint_in_parent)));
            let r = sub(attach, po);
            // material point of the parent at the joint
            let v_attach = add(pv, scale(perp(r), pw));
            let a_attach = sub(pab, scale(r, pw * pw));
            match body.joint {
                Joint::Revolute => {
                    let ang = pa + q[b];
                    k.angle.push(ang);
                    k.cs.push((ang.cos(), ang.sin()));
                    k.origin.push(attach);
                    k.omega.push(pw + qd[b]);
                    k.vel.push(v_attach);
                    k.acc_bias.push(a_attach);
                    k.axis.push([z, z]);
                }
                Joint::Prismatic { axis } => {
                    let u = rotate(pcs.0, pcs.1, lift(axis));
                    let o = add(attach, scale(u, q[b]));
                    let ro = sub(o, po);
                    k.angle.push(pa);
                    k.cs.push(pcs);
                    k.origin.push(o);
                    k.omega.push(pw);
                    k.vel
                        .push(add(add(pv, scale(perp(ro), pw)), scale(u, qd[b])));
                    let coriolis = scale(perp(u), S::c(2.0) * pw * qd[b]);
                    k.acc_bias.push(add(sub(pab, scale(ro, pw * pw)), coriolis));
                    k.axis.push(u);
                }
            }
        }
        k
    }

    /// World position of a point given in body `b`'s frame.
    pub fn point<S: Scalar>(&self, k: &Kinematics<S>, b: usize, local: V2<S>) -> V2<S> {
        add(k.origin[b], rotate(k.cs[b].0, k.cs[b].1, local))
    }

    /// Jacobian column `j` of the material point at world position `p` on body `b`
    /// (zero if joint `j` does not move `b`). Writes into `out` (2 × nq, row-major).
    pub fn point_jacobian<S: Scalar>(&self, k: &Kinematics<S>, b: usize, p: V2<S>, out: &mut [S]) {
        let n = self.nq();
        for v in out.iter_mut() {
            *v = S::c(0.0);
        }
        for &j in &self.ancestors[b] {
            let col = match self.bodies[j].joint {
                Joint::Revolute => perp(sub(p, k.origin[j])),
                Joint::Prismatic { .. } => k.axis[j],
            };
            out[j] = col[0];
            out[n + j] = col[1];
        }
    }

    /// Material velocity and zero-q̈ acceleration of a world point `p` fixed to body `b`.
    pub fn point_motion<S: Scalar>(&self, k: &Kinematics<S>, b: usize, p: V2<S>) -> (V2<S>, V2<S>) {
        let r = sub(p, k.origin[b]);
        let w = k.omega[b];
        (
            add(k.vel[b], scale(perp(r), w)),
            sub(k.acc_bias[b], scale(r, w * w)),
        )
    }

    /// Mass matrix (row-major nq × nq) and bias forces `c(q, q̇)` including gravity
    /// `gravity` (m/s², world frame).
    pub fn mass_matrix_and_bias<S: Scalar>(
        &self,
        k: &Kinematics<S>,
        inertia: &[Inertia<S>],
        gravity: V2<S>,
        m: &mut [S],
        c: &mut [S],
    ) {
        let n = self.nq();
        for v in m.iter_mut() {
            *v = S::c(0.0);
        }
        for v in c.iter_mut() {
            *v = S::c(0.0);
        }
        let mut jc = vec![S::c(0.0); 2 * n];
        for (b, body) in self.bodies.iter().enumerate() {
            let ib = &inertia[b];
            if body.mass == 0.0 && ib.mass.value() == 0.0 && ib.izz.value() == 0.0 {
                continue;
            }
            let com = self.point(k, b, ib.com);
            self.point_jacobian(k, b, com, &mut jc);
            let (_, a_bias) = self.point_motion(k, b, com);
            let f = scale(sub(a_bias, gravity), ib.mass);
            let anc = &self.ancestors[b];
            for &i in anc {
                c[i] += jc[i] * f[0] + jc[n + i] * f[1];
                let rot_i = matches!(self.bodies[i].joint, Joint::Revolute);
                for &j in anc {
                    let rot_j = matches!(self.bodies[j].joint, Joint::Revolute);
                    let mut v = ib.mass * (jc[i] * jc[j] + jc[n + i] * jc[n + j]);
                    if rot_i && rot_j {
                        v += ib.izz;
                    }
                    m[i * n + j] += v;
                }
            }
        }
    }

    /// Kinetic and potential energy (J) for gravity `gravity`.
    pub fn energy<S: Scalar>(
        &self,
        k: &Kinematics<S>,
        inertia: &[Inertia<S>],
        gravity: V2<S>,
    ) -> (S, S) {
        let mut ke = S::c(0.0);
        let mut pe = S::c(0.0);
        for (b, ib) in inertia.iter().enumerate() {
            let com = self.point(k, b, ib.com);
            let (v, _) = self.point_motion(k, b, com);
            ke += S::c(0.5) * (ib.mass * dot(v, v) + ib.izz * k.omega[b] * k.omega[b]);
            pe -= ib.mass * dot(gravity, com);
        }
        (ke, pe)
    }
}
