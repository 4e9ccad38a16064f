//! Contact sets and constraint kinematics: the foot-ground contact primitives, the
//! active constraint rows of a phase, their Jacobian `G`, gaps and contact points,
//! projection onto the contact manifold and per-foot ground loads.

use super::{GaitModel, Side};
use crate::model::effects::ModelScalar;
use crate::model::error::{ContactSetError, DynamicsError};
use crate::model::geometry::Shape;
use crate::model::linalg::{cholesky, cholesky_solve};
use crate::model::multibody::{add, dot, Kinematics, V2};
use crate::model::Scalar;
use num_dual::Dual;

/// A contact primitive mounted on one foot.
#[derive(Debug, Clone, PartialEq)]
pub struct Contact {
    /// `r.NAME` or `l.NAME`.
    pub name: String,
    /// Which foot.
    pub side: Side,
    /// Body index of the foot it is fixed to.
    pub body: usize,
    /// Geometry in the foot frame.
    pub shape: Shape,
    /// The volumetric contact law of a compliant primitive; `None`: rigid (held by
    /// constraint sets).
    pub law: Option<crate::model::volumetric::VolumetricLaw>,
}

/// Direction of one constraint row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RowKind {
    /// Along the ground normal (contact): force λₙ, position error φ.
    Normal,
    /// Along the ground tangent (rolling without slipping): force λₜ.
    Tangential,
}

/// One active constraint row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ConstraintRow {
    /// Index into [`GaitModel::contacts`].
    pub contact: usize,
    /// Direction.
    pub kind: RowKind,
}

/// A set of active foot-ground constraints (one continuous phase's contact state).
#[derive(Debug, Clone, PartialEq)]
pub struct ConstraintSet {
    /// Name for messages.
    pub name: String,
    /// The rows, in multiplier order.
    pub rows: Vec<ConstraintRow>,
}

/// Quantities of one dynamics evaluation that reports need (f64 only).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct ContactReport {
    /// World contact point of each row's primitive (m).
    pub points: Vec<[f64; 2]>,
    /// Constraint force along each row (N).
    pub lambda: Vec<f64>,
    /// Normal position error φ of each row's primitive (m; meaningful on normal rows;
    /// 0 on a compliant contact's normal row, whose depth is its pad's compression).
    pub position_error: Vec<f64>,
    /// Velocity error `G q̇` of each row (m/s; 0 on a compliant contact's normal row).
    pub velocity_error: Vec<f64>,
    /// Part of λ caused by the Baumgarte terms (N).
    pub baumgarte_force: Vec<f64>,
    /// The force of every volumetric primitive in contact with the ground.
    pub volumetric: Vec<super::VolumetricReport>,
}

impl ContactReport {
    /// |Baumgarte part of λ| of row `r` (N; 0 for a row the evaluation did not report).
    pub fn baumgarte_abs(&self, r: usize) -> f64 {
        self.baumgarte_force.get(r).copied().unwrap_or(0.0).abs()
    }
}

/// Ground reaction force and centre of pressure of one foot.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct FootLoad {
    /// Tangential (forward +) force on the foot (N).
    pub fx: f64,
    /// Normal (up +) force on the foot (N).
    pub fy: f64,
    /// Centre of pressure x (m): normal-force-weighted mean of the contact points; NaN
    /// when the foot carries no normal force.
    pub cop_x: f64,
}

impl GaitModel {
    /// Index of a contact by name (`r.heel`).
    pub fn contact_index(&self, name: &str) -> Option<usize> {
        self.contacts.iter().position(|c| c.name == name)
    }

    /// Build a constraint set from `(contact name, rolling)` pairs: every listed contact
    /// gets a normal row, and a tangential (rolling) row where `rolling` is true.
    pub fn constraint_set(
        &self,
        name: &str,
        contacts: &[(&str, bool)],
    ) -> Result<ConstraintSet, ContactSetError> {
        let mut rows = Vec::new();
        for (i, (c, rolling)) in contacts.iter().enumerate() {
            let idx = self
                .contact_index(c)
                .ok_or_else(|| ContactSetError::UnknownContact {
                    set: name.to_string(),
                    contact: c.to_string(),
                    known: self.contacts.iter().map(|c| c.name.clone()).collect(),
                })?;
            if self.contacts[idx].law.is_some() {
                return Err(ContactSetError::Volumetric {
                    set: name.to_string(),
                    contact: c.to_string(),
                });
            }
            if contacts[..i].iter().any(|(o, _)| o == c) {
                return Err(ContactSetError::Repeated {
                    set: name.to_string(),
                    contact: c.to_string(),
                });
            }
            if *rolling {
                rows.push(ConstraintRow {
                    contact: idx,
                    kind: RowKind::Tangential,
                });
            }
            rows.push(ConstraintRow {
                contact: idx,
                kind: RowKind::Normal,
            });
        }
        Ok(ConstraintSet {
            name: name.to_string(),
            rows,
        })
    }

    /// Contact point `P`, offset `d` and `d' = ∂d/∂ψ` of contact `c` (world).
    pub(super) fn contact_geometry<S: Scalar>(
        &self,
        k: &Kinematics<S>,
        ci: usize,
        n: V2<S>,
        p: &[S],
    ) -> (V2<S>, V2<S>, V2<S>) {
        let c = &self.contacts[ci];
        let shape = self.shape_of(ci, p);
        let centre = self.tree.point(k, c.body, shape.centre());
        let psi = Dual::new(k.angle[c.body], S::c(1.0));
        let nd = [Dual::from_re(n[0]), Dual::from_re(n[1])];
        let dd = shape.map(Dual::from_re).contact_offset(psi, nd);
        let d = [dd[0].re, dd[1].re];
        let d1 = [dd[0].eps, dd[1].eps];
        (add(centre, d), d, d1)
    }

    /// The rows of `set` that are rigid constraints (all but the normal rows of compliant
    /// contacts), and each one's index in `set`.
    pub fn rigid_rows(&self, set: &ConstraintSet) -> (ConstraintSet, Vec<usize>) {
        let idx: Vec<usize> = (0..set.rows.len())
            .filter(|&r| !self.is_compliant_row(&set.rows[r]))
            .collect();
        (
            ConstraintSet {
                name: set.name.clone(),
                rows: idx.iter().map(|&r| set.rows[r]).collect(),
            },
            idx,
        )
    }

    /// Whether `row` is the normal row of a compliant contact (a force, not a constraint).
    pub fn is_compliant_row(&self, row: &ConstraintRow) -> bool {
        row.kind == RowKind::Normal && self.compliant[row.contact].is_some()
    }

    /// Whether contact `c` has a compliant normal contact.
    pub fn is_compliant(&self, c: usize) -> bool {
        self.compliant[c].is_some()
    }

    pub(super) fn constraint_jacobian<S: Scalar>(
        &self,
        k: &Kinematics<S>,
        set: &ConstraintSet,
        n: V2<S>,
        p: &[S],
    ) -> Vec<S> {
        let nq = self.nq();
        let t = [n[1], -n[0]];
        let mut g = vec![S::c(0.0); set.rows.len() * nq];
        let mut jp = vec![S::c(0.0); 2 * nq];
        for (r, row) in set.rows.iter().enumerate() {
            let contact = &self.contacts[row.contact];
            let (pt, _, _) = self.contact_geometry(k, row.contact, n, p);
            self.tree.point_jacobian(k, contact.body, pt, &mut jp);
            let e = if row.kind == RowKind::Normal { n } else { t };
            for j in 0..nq {
                g[r * nq + j] = e[0] * jp[j] + e[1] * jp[nq + j];
            }
        }
        g
    }

    /// Index of a row of `set` that is linearly dependent on the rows before it, at a
    /// neutral standing pose (dependence of contact rows on one rigid foot does not change
    /// with the pose), or `None`.
    pub fn dependent_row(&self, set: &ConstraintSet) -> Option<usize> {
        let q = [0.0, 1.0, 0.0, 0.1, -0.2, 0.05, -0.1, -0.3, 0.1];
        let nq = self.nq();
        // only rigid rows constrain (a compliant contact's normal row is a force)
        let (set, idx) = &self.rigid_rows(set);
        let g = self.constraint_jacobian_at(set, &q[..nq.min(9)], &self.theta0());
        let nc = set.rows.len();
        let mut a = vec![0.0; nc * nc];
        for i in 0..nc {
            for j in 0..nc {
                a[i * nc + j] = (0..nq).map(|l| g[i * nq + l] * g[j * nq + l]).sum();
            }
        }
        cholesky(&mut a, nc, 1e-10).err().map(|e| idx[e.pivot])
    }

    /// Project a state onto the constraint manifold of `set` (Millard & Mombaur 2019, §3.6: the initial
    /// guess is "polished to satisfy the foot-ground constraints"): positions by
    /// minimum-norm Gauss–Newton steps on the normal gaps φ = 0, velocities by the
    /// M-orthogonal projection onto `G q̇ = 0` (the plastic impact map). Returns the
    /// projected `(q, q̇)` and the largest remaining |φ| (m).
    pub fn project(
        &self,
        set: &ConstraintSet,
        q: &[f64],
        qd: &[f64],
        theta: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>, f64), DynamicsError> {
        let nq = self.nq();
        let mut q = q.to_vec();
        // compliant contacts are left where they are (their pad holds them, not a constraint)
        let normal: Vec<usize> = (0..set.rows.len())
            .filter(|&r| {
                set.rows[r].kind == RowKind::Normal && !self.is_compliant_row(&set.rows[r])
            })
            .collect();
        let nn = normal.len();
        let mut worst = 0.0;
        for _ in 0..50 {
            let g = self.constraint_jacobian_at(set, &q, theta);
            let phi: Vec<f64> = normal
                .iter()
                .map(|&r| self.contact_point(set.rows[r].contact, &q, theta).1)
                .collect();
            worst = phi.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if worst < 1e-12 || nn == 0 {
                break;
            }
            let mut a = vec![0.0; nn * nn];
            for (i, &ri) in normal.iter().enumerate() {
                for (j, &rj) in normal.iter().enumerate() {
                    a[i * nn + j] = (0..nq).map(|l| g[ri * nq + l] * g[rj * nq + l]).sum();
                }
            }
            cholesky(&mut a, nn, 1e-12).map_err(|e| DynamicsError::OverConstrained {
                set: set.name.clone(),
                row: e.pivot,
            })?;
            let mut y = phi.clone();
            cholesky_solve(&a, nn, &mut y);
            for (i, &ri) in normal.iter().enumerate() {
                for l in 0..nq {
                    q[l] -= g[ri * nq + l] * y[i];
                }
            }
        }
        let qd = if set.rows.is_empty() {
            qd.to_vec()
        } else {
            self.impact(set, &q, qd, theta)?.0
        };
        Ok((q, qd, worst))
    }

    /// Constraint Jacobian `G` (rows × nq, row-major) of `set` at `q` (f64).
    pub fn constraint_jacobian_at(
        &self,
        set: &ConstraintSet,
        q: &[f64],
        theta: &[f64],
    ) -> Vec<f64> {
        let p = self.full_params(theta);
        let (_, _, _, n) = self.adjusted(&p);
        let k = self.tree.kinematics(q, &vec![0.0; self.nq()]);
        self.constraint_jacobian(&k, set, n, &p)
    }

    /// World contact point and normal gap φ (m) of contact `c` at `q`.
    pub fn contact_point(&self, c: usize, q: &[f64], theta: &[f64]) -> ([f64; 2], f64) {
        self.contact_point_generic(c, q, theta)
    }

    /// Normal gap φ (m) of contact `c` at `q`, over any model scalar (for exact
    /// derivatives of clearance and landing constraints).
    pub fn gap<S: ModelScalar>(&self, c: usize, q: &[S], theta: &[S]) -> S {
        self.contact_point_generic(c, q, theta).1
    }

    /// World contact point (m) and normal gap φ (m) of contact `c` at `q`, over any model
    /// scalar (for exact derivatives of a cost on the contact point).
    pub fn contact_point_generic<S: ModelScalar>(
        &self,
        c: usize,
        q: &[S],
        theta: &[S],
    ) -> (V2<S>, S) {
        let p = self.full_params(theta);
        let (_, _, h, n) = self.adjusted(&p);
        let k = self.tree.kinematics(q, &vec![S::c(0.0); self.nq()]);
        let (pt, _, _) = self.contact_geometry(&k, c, n, &p);
        (pt, dot(n, pt) - h)
    }

    /// Velocity `G q̇` (m/s) of every row of `set` at the state `x = (q, q̇, …)`: the
    /// tangential or normal velocity of each foot's material point at its contact point,
    /// which the Baumgarte rows drive to zero but do not hold (a state on the contact
    /// manifold needs `G q̇ = 0` as a constraint of its own).
    pub fn constraint_velocity<S: ModelScalar>(
        &self,
        set: &ConstraintSet,
        x: &[S],
        theta: &[S],
    ) -> Vec<S> {
        let nq = self.nq();
        let p = self.full_params(theta);
        let (_, _, _, n) = self.adjusted(&p);
        let k = self.tree.kinematics(&x[..nq], &vec![S::c(0.0); nq]);
        let g = self.constraint_jacobian(&k, set, n, &p);
        (0..set.rows.len())
            .map(|r| (0..nq).map(|l| g[r * nq + l] * x[nq + l]).sum())
            .collect()
    }

    /// Per-foot ground reaction forces and centres of pressure from a report.
    pub fn foot_loads(&self, set: &ConstraintSet, rep: &ContactReport) -> [FootLoad; 2] {
        let mut out = [FootLoad::default(); 2];
        let mut moment = [0.0; 2];
        for (r, row) in set.rows.iter().enumerate() {
            let c = &self.contacts[row.contact];
            let s = if c.side == Side::Right { 0 } else { 1 };
            match row.kind {
                RowKind::Normal => {
                    out[s].fy += rep.lambda[r];
                    moment[s] += rep.lambda[r] * rep.points[r][0];
                }
                RowKind::Tangential => out[s].fx += rep.lambda[r],
            }
        }
        for v in &rep.volumetric {
            let s = if self.contacts[v.contact].side == Side::Right {
                0
            } else {
                1
            };
            out[s].fx += v.force[0];
            out[s].fy += v.force[1];
            moment[s] += v.force[1] * v.cop_x;
        }
        for s in 0..2 {
            out[s].cop_x = if out[s].fy.abs() > 1e-9 {
                moment[s] / out[s].fy
            } else {
                f64::NAN
            };
        }
        out
    }

    /// Ground reaction force and CoP moment of each foot, generic in the scalar type:
    /// `[(fx, fy, m)]` for right and left, with `fx` the tangential and `fy` the normal
    /// force on the foot (N) and `m = Σ λₙ·x_P` (N·m) the normal-force moment about the
    /// origin, so that the centre of pressure is `m / fy` where `fy > 0`. Tracking costs use
    /// `m − x_cop·fy`, which weights the CoP error by the load and stays smooth at lift-off.
    pub fn foot_loads_generic<S: ModelScalar>(
        &self,
        set: &ConstraintSet,
        x: &[S],
        u: &[S],
        theta: &[S],
    ) -> Result<[(S, S, S); 2], DynamicsError> {
        let nq = self.nq();
        let mut xdot = vec![S::c(0.0); self.nx()];
        let mut lam = vec![S::c(0.0); set.rows.len()];
        self.dynamics(set, x, u, theta, &mut xdot, &mut lam, None)?;
        let p = self.full_params(theta);
        let (_, _, ground_h, n) = self.adjusted(&p);
        let k = self.tree.kinematics(&x[..nq], &x[nq..2 * nq]);
        let z = S::c(0.0);
        let mut out = [(z, z, z); 2];
        for (c, f) in self.volumetric_forces(&k, ground_h, n, &p) {
            let s = if self.contacts[c].side == Side::Right {
                0
            } else {
                1
            };
            out[s].0 += f.tangential;
            out[s].1 += f.normal;
            out[s].2 += f.normal * f.cop_x;
        }
        for (r, row) in set.rows.iter().enumerate() {
            let c = &self.contacts[row.contact];
            let s = if c.side == Side::Right { 0 } else { 1 };
            match row.kind {
                RowKind::Tangential => out[s].0 += lam[r],
                RowKind::Normal => {
                    let (pt, _, _) = self.contact_geometry(&k, row.contact, n, &p);
                    out[s].1 += lam[r];
                    out[s].2 += lam[r] * pt[0];
                }
            }
        }
        Ok(out)
    }
}
