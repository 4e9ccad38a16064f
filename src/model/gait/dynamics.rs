//! Forward dynamics of the gait model with contact, and the impact map.
//!
//! Forward dynamics solve the index-reduced DAE (Millard & Mombaur 2019, eq. 1–2)
//! $$\begin{bmatrix} M & G^T \\ G & 0\end{bmatrix}\begin{bmatrix}\ddot q \\ -\lambda\end{bmatrix}
//!   = \begin{bmatrix}\tau - c \\ b\end{bmatrix},$$
//! by Cholesky factors of $M$ and of $G M^{-1} G^T$ (a rank-deficient $G$, i.e. an
//! over-constrained foot, is reported, never silently regularised). Row $i$ of $G$ is
//! $e_i^T J_P$, the velocity of the foot's material point at the contact point $P$ along
//! the ground normal or tangent, and
//! $b_i = -\dot G_i\dot q - 2\alpha G_i\dot q - \beta^2\phi_i$ (normal) or
//! $b_i = -\dot G_i\dot q - \gamma G_i\dot q$ (tangential), with
//! $\dot G_i\dot q = e_i^T\big(a_P + \omega^2(\hat z\times d' + d)\big)$, where $a_P$ is the
//! material acceleration of $P$ at $\ddot q = 0$, $d(\psi)$ the offset of $P$ from the
//! primitive's centre and $d'$ its derivative in the foot angle (the contact point moves
//! over the foot surface while it rolls). $\lambda$ is the ground force on the foot at $P$
//! (N) along the row's direction.

use super::volumetric::GroundForce;
use super::{Actuation, ConstraintSet, ContactReport, GaitModel, RowKind, LEG_JOINTS};
use crate::model::effects::{EffectState, ModelScalar};
use crate::model::error::DynamicsError;
use crate::model::linalg::{cholesky, cholesky_solve};
use crate::model::multibody::{add, dot, perp, scale, Kinematics, V2};
use crate::model::Scalar;

/// The generalised forces of the dynamics by source (N·m or N per coordinate).
#[derive(Debug, Clone, PartialEq)]
pub struct ForceParts {
    /// The actuators: muscle-torque generators with their passive damping, or the joint
    /// torques.
    pub actuators: Vec<f64>,
    /// The residual actuators (zero without them).
    pub residual: Vec<f64>,
    /// Each effect's, by its kind.
    pub effects: Vec<(String, Vec<f64>)>,
}

impl GaitModel {
    /// The generalised forces of [`dynamics`](Self::dynamics) split by source, at state
    /// `x = (q, q̇, a)`, controls `u` and free parameters `theta` (N·m or N per
    /// coordinate): the actuators (muscle-torque generators with their passive damping, or
    /// the joint torques), the residual actuators, and each effect by its kind.
    pub fn generalized_force_parts(&self, x: &[f64], u: &[f64], theta: &[f64]) -> ForceParts {
        let nq = self.nq();
        let (q, qd, a) = (&x[..nq], &x[nq..2 * nq], &x[2 * nq..]);
        let p = self.full_params(theta);
        let mut act = vec![0.0; nq];
        self.add_actuator_forces(q, qd, a, u, &p, &mut act);
        let mut residual = vec![0.0; nq];
        self.add_residual_forces(u, &mut residual);
        let effects = (0..self.effects.len())
            .map(|e| {
                let mut tau = vec![0.0; nq];
                f64::forces(
                    self.effects[e].as_ref(),
                    self.effect_params(&p, e),
                    EffectState { q, qd },
                    &mut tau,
                );
                (self.effects[e].kind().to_string(), tau)
            })
            .collect();
        ForceParts {
            actuators: act,
            residual,
            effects,
        }
    }

    /// Add the actuators' generalised forces to `tau`: the muscle-torque generators with
    /// their passive damping (scaled by the actuator effects in `p`), or the joint torques
    /// `u · reference torque` (N·m per coordinate).
    fn add_actuator_forces<S: ModelScalar>(
        &self,
        q: &[S],
        qd: &[S],
        a: &[S],
        u: &[S],
        p: &[S],
        tau: &mut [S],
    ) {
        match &self.actuation {
            Actuation::Mtg(set) => {
                let f = self.actuator_adjust(p);
                for (k, &(c, joint)) in LEG_JOINTS.iter().enumerate() {
                    tau[c] += set.joint_torque_scaled(
                        joint,
                        a[2 * k],
                        a[2 * k + 1],
                        q[c],
                        qd[c],
                        f.strength,
                        f.damping,
                    );
                }
            }
            Actuation::Torques {
                reference_torque, ..
            } => {
                for (k, &(c, _)) in LEG_JOINTS.iter().enumerate() {
                    tau[c] += u[k] * S::c(*reference_torque);
                }
            }
        }
    }

    /// Add the residual actuators' forces (their controls times their scales) to `tau`.
    fn add_residual_forces<S: ModelScalar>(&self, u: &[S], tau: &mut [S]) {
        if let Some(scales) = &self.residuals {
            let base = self.nu_actuators();
            for (i, &sc) in scales.iter().enumerate() {
                tau[i] += u[base + i] * sc;
            }
        }
    }

    /// Generalised joint forces of the actuators (and passive damping) and effects.
    pub(super) fn generalized_forces<S: ModelScalar>(
        &self,
        q: &[S],
        qd: &[S],
        a: &[S],
        u: &[S],
        p: &[S],
    ) -> Vec<S> {
        let mut tau = vec![S::c(0.0); self.nq()];
        self.add_actuator_forces(q, qd, a, u, p, &mut tau);
        self.add_residual_forces(u, &mut tau);
        for e in 0..self.effects.len() {
            S::forces(
                self.effects[e].as_ref(),
                self.effect_params(p, e),
                EffectState { q, qd },
                &mut tau,
            );
        }
        tau
    }

    /// Forward dynamics `ẋ = f(x, u, θ)` under constraint set `set`. Returns `ẋ` and
    /// the constraint forces λ (one per row). With `report`, also fills contact details.
    pub fn dynamics<S: ModelScalar>(
        &self,
        set: &ConstraintSet,
        x: &[S],
        u: &[S],
        theta: &[S],
        xdot: &mut [S],
        lambda: &mut [S],
        report: Option<&mut ContactReport>,
    ) -> Result<(), DynamicsError> {
        self.forward(set, (x, u, theta), &[], xdot, lambda, report)
            .map(|_| ())
    }

    /// [`Self::dynamics`] with the generalised forces `extra` (pairs of coordinate and
    /// force, N or N·m) added to the model's own (the Jacobian's torque directions,
    /// `jacobians.rs`, through which the activations act), also returning the
    /// accelerations and the solve's factors.
    pub(super) fn forward<S: ModelScalar>(
        &self,
        set: &ConstraintSet,
        (x, u, theta): (&[S], &[S], &[S]),
        extra: &[(usize, S)],
        xdot: &mut [S],
        lambda: &mut [S],
        report: Option<&mut ContactReport>,
    ) -> Result<(Vec<S>, Factors<S>), DynamicsError> {
        let nq = self.nq();
        let mut terms = self.assemble(set, (x, u, theta), extra, lambda);
        let adot = std::mem::take(&mut terms.adot);
        let (qdd, factors) = self.solve_terms(terms, set, lambda, report)?;
        xdot[..nq].copy_from_slice(&x[nq..2 * nq]);
        xdot[nq..2 * nq].copy_from_slice(&qdd);
        xdot[2 * nq..].copy_from_slice(&adot);
        Ok((qdd, factors))
    }

    /// The terms of the dynamics at `(x, u, θ)` with the forces `extra` added, before
    /// they are solved for the accelerations: the mass matrix, τ − c, the contact rows
    /// (the compliant rows' forces written to `lambda`), the volumetric forces and ȧ.
    fn assemble<S: ModelScalar>(
        &self,
        set: &ConstraintSet,
        (x, u, theta): (&[S], &[S], &[S]),
        extra: &[(usize, S)],
        lambda: &mut [S],
    ) -> Terms<S> {
        let nq = self.nq();
        let (q, rest) = x.split_at(nq);
        let (qd, a) = rest.split_at(nq);
        let p = self.full_params(theta);
        let (inertia, gravity, ground_h, n) = self.adjusted(&p);
        let k = self.tree.kinematics(q, qd);
        let mut m = vec![S::c(0.0); nq * nq];
        let mut c = vec![S::c(0.0); nq];
        self.tree
            .mass_matrix_and_bias(&k, &inertia, gravity, &mut m, &mut c);
        let mut tau = self.generalized_forces(q, qd, a, u, &p);
        for &(j, f) in extra {
            tau[j] += f;
        }
        // volumetric primitives: a ground force in every phase, applied at the centroid of
        // the penetrated area
        let volumetric = self.volumetric_forces(&k, ground_h, n, &p);
        if !volumetric.is_empty() {
            let mut jp = vec![S::c(0.0); 2 * nq];
            for (c, f) in &volumetric {
                self.tree
                    .point_jacobian(&k, self.contacts[*c].body, f.point, &mut jp);
                for j in 0..nq {
                    tau[j] += f.world[0] * jp[j] + f.world[1] * jp[nq + j];
                }
            }
        }
        let force = tau.iter().zip(&c).map(|(t, c)| *t - *c).collect();
        let rows = (!set.rows.is_empty())
            .then(|| self.contact_rows(set, &k, qd, &p, (ground_h, n), lambda));
        let mut adot = vec![S::c(0.0); self.na()];
        if let Actuation::Mtg(set) = &self.actuation {
            let time = self.actuator_adjust(&p).time;
            for (i, d) in adot.iter_mut().enumerate() {
                *d = set.activation.rate(u[i], a[i]) / time;
            }
        }
        Terms {
            m,
            force,
            rows,
            volumetric,
            adot,
        }
    }

    /// The accelerations' and activations' derivatives at `(x, u, θ)` by implicit
    /// differentiation of the dynamics about their solution `at` (computed in f64 at
    /// the same point): the terms are evaluated in `S` with `q̈` and λ held at their
    /// values, the residuals
    /// $r_1 = \tau - c + f_c + G^T\lambda - M\ddot q$ and $r_2 = b - G\ddot q$
    /// differentiated, and $[M\;-G^T;\,G\;0]\,[d\ddot q; d\lambda] = [dr_1; dr_2]$
    /// solved with the real factors of `at`: no factorisation in `S`. `xdot` gets `ẋ`'s
    /// values from `at` and its derivatives in the dual parts.
    pub(super) fn dynamics_tangent<S: ModelScalar>(
        &self,
        set: &ConstraintSet,
        inputs: (&[S], &[S], &[S]),
        at: &Solution,
        xdot: &mut [S],
        lambda: &mut [S],
    ) {
        let nq = self.nq();
        let x = inputs.0;
        let terms = self.assemble(set, inputs, &[], lambda);
        let f = &at.factors;
        let mut r1 = terms.force;
        for i in 0..nq {
            r1[i] -= (0..nq).map(|j| terms.m[i * nq + j] * at.qdd[j]).sum::<S>();
        }
        let mut r2 = Vec::with_capacity(f.rigid.len());
        if let Some(rows) = &terms.rows {
            for (r1, c) in r1.iter_mut().zip(&rows.compliant_force) {
                *r1 += *c;
            }
            for &r in &f.rigid {
                let g = &rows.g[r * nq..(r + 1) * nq];
                for (r1, gl) in r1.iter_mut().zip(g) {
                    *r1 += *gl * at.lambda[r];
                }
                let gq: S = g.iter().zip(&at.qdd).map(|(gl, a)| *gl * *a).sum();
                r2.push(rows.b[r] - gq);
            }
        }
        // w = M⁻¹ r1, dλ = A⁻¹ (r2 − G w), dq̈ = w + Y dλ
        cholesky_solve(&f.m_chol, nq, &mut r1);
        let nr = f.rigid.len();
        for (i, r2) in r2.iter_mut().enumerate() {
            *r2 -= (0..nq).map(|l| r1[l] * f.g_rigid[i * nq + l]).sum::<S>();
        }
        cholesky_solve(&f.a_chol, nr, &mut r2);
        for (i, dl) in r2.iter().enumerate() {
            for l in 0..nq {
                r1[l] += *dl * f.y[i * nq + l];
            }
        }
        xdot[..nq].copy_from_slice(&x[nq..2 * nq]);
        for (o, (d, v)) in xdot[nq..2 * nq].iter_mut().zip(r1.iter().zip(&at.qdd)) {
            // the value from `at`, the derivative parts from the solve
            *o = *d - S::c(d.value()) + *v;
        }
        xdot[2 * nq..].copy_from_slice(&terms.adot);
    }

    /// The dynamics at `(x, u, θ)` in f64 with the factors their derivatives need
    /// ([`dynamics_tangent`](Self::dynamics_tangent)); `xdot` gets `ẋ`.
    pub(super) fn solution(
        &self,
        set: &ConstraintSet,
        inputs: (&[f64], &[f64], &[f64]),
        xdot: &mut [f64],
    ) -> Result<Solution, DynamicsError> {
        let mut lambda = vec![0.0; set.rows.len()];
        let (qdd, factors) = self.forward(set, inputs, &[], xdot, &mut lambda, None)?;
        Ok(Solution {
            qdd,
            lambda,
            factors,
        })
    }

    /// The rows of `set` at kinematics `k` and velocities `qd`, on the ground `(h, n)`
    /// (height, unit normal): each row of G, the right-hand side of the rigid rows, and
    /// the compliant rows' forces (written to `lambda`) as generalised forces.
    fn contact_rows<S: ModelScalar>(
        &self,
        set: &ConstraintSet,
        k: &Kinematics<S>,
        qd: &[S],
        p: &[S],
        (ground_h, n): (S, V2<S>),
        lambda: &mut [S],
    ) -> ContactRows<S> {
        let nq = self.nq();
        let nc = set.rows.len();
        let t = [n[1], -n[0]];
        let cs = &self.contact_settings;
        let mut g = vec![S::c(0.0); nc * nq];
        let mut b = vec![S::c(0.0); nc];
        let mut b_baum = vec![0.0; nc];
        let mut jp = vec![S::c(0.0); 2 * nq];
        let mut rep_rows = Vec::new();
        // geometry once per contact (a rolling contact has two rows)
        let mut geo: Vec<(usize, V2<S>, V2<S>)> = Vec::with_capacity(nc);
        // compliant normal rows: an explicit force, not a constraint
        let mut compliant_force = vec![S::c(0.0); nq];
        let mut rigid = Vec::with_capacity(nc);
        for (r, row) in set.rows.iter().enumerate() {
            let contact = &self.contacts[row.contact];
            let (pt, bias) = match geo.iter().find(|g| g.0 == row.contact) {
                Some(&(_, pt, bias)) => (pt, bias),
                None => {
                    let (pt, d, d1) = self.contact_geometry(k, row.contact, n, p);
                    let (_, acc) = self.tree.point_motion(k, contact.body, pt);
                    let w = k.omega[contact.body];
                    let bias = add(acc, scale(add(perp(d1), d), w * w));
                    geo.push((row.contact, pt, bias));
                    (pt, bias)
                }
            };
            let gdot_qd_vec = bias;
            self.tree.point_jacobian(k, contact.body, pt, &mut jp);
            let e = if row.kind == RowKind::Normal { n } else { t };
            for j in 0..nq {
                g[r * nq + j] = e[0] * jp[j] + e[1] * jp[nq + j];
            }
            let gqd: S = (0..nq).map(|j| g[r * nq + j] * qd[j]).sum();
            let phi = dot(n, pt) - ground_h;
            rep_rows.push(([pt[0].value(), pt[1].value()], phi.value(), gqd.value()));
            if let (RowKind::Normal, Some(eff)) = (row.kind, self.compliant[row.contact]) {
                // depth below the ground and its rate: the pad's compression
                lambda[r] = S::normal_force(
                    self.effects[eff].as_ref(),
                    self.effect_params(p, eff),
                    -phi,
                    -gqd,
                );
                for j in 0..nq {
                    compliant_force[j] += g[r * nq + j] * lambda[r];
                }
                continue;
            }
            let stab = match row.kind {
                RowKind::Normal => {
                    gqd * (2.0 * cs.baumgarte_alpha) + phi * (cs.baumgarte_beta * cs.baumgarte_beta)
                }
                RowKind::Tangential => gqd * cs.baumgarte_gamma,
            };
            b[r] = -dot(e, gdot_qd_vec) - stab;
            b_baum[r] = -stab.value();
            rigid.push(r);
        }
        ContactRows {
            nq,
            g,
            b,
            b_baum,
            rep_rows,
            compliant_force,
            rigid,
        }
    }

    /// Fill `rep` with the rows' points, constraint errors (zero for a compliant row),
    /// forces `lambda` and the rigid rows' Baumgarte forces `b_baum_rigid`.
    fn fill_contact_report<S: ModelScalar>(
        &self,
        rep: &mut ContactReport,
        set: &ConstraintSet,
        rows: &ContactRows<S>,
        b_baum_rigid: &[f64],
        lambda: &[S],
    ) {
        let rep_rows = &rows.rep_rows;
        let mut baum = vec![0.0; set.rows.len()];
        for (i, &r) in rows.rigid.iter().enumerate() {
            baum[r] = b_baum_rigid[i];
        }
        // a compliant row's depth is its pad's compression, not a constraint error
        let rigid_or_zero = |r: usize, v: f64| {
            if self.is_compliant_row(&set.rows[r]) {
                0.0
            } else {
                v
            }
        };
        rep.points = rep_rows.iter().map(|r| r.0).collect();
        rep.position_error = rep_rows
            .iter()
            .enumerate()
            .map(|(r, x)| rigid_or_zero(r, x.1))
            .collect();
        rep.velocity_error = rep_rows
            .iter()
            .enumerate()
            .map(|(r, x)| rigid_or_zero(r, x.2))
            .collect();
        rep.lambda = lambda.iter().map(|v| v.value()).collect();
        rep.baumgarte_force = baum;
    }

    /// Plastic impact map: post-impact velocities and impulses (N·s, one per row) for
    /// the constraint set active after the impact,
    /// $[M\;G^T;\,G\;0][\dot q^+; -\Lambda] = [M\dot q^-; 0]$.
    pub fn impact<S: ModelScalar>(
        &self,
        set_after: &ConstraintSet,
        q: &[S],
        qd_minus: &[S],
        theta: &[S],
    ) -> Result<(Vec<S>, Vec<S>), DynamicsError> {
        let nq = self.nq();
        let p = self.full_params(theta);
        let (inertia, gravity, _, n) = self.adjusted(&p);
        let k = self.tree.kinematics(q, qd_minus);
        let mut m = vec![S::c(0.0); nq * nq];
        let mut c = vec![S::c(0.0); nq];
        self.tree
            .mass_matrix_and_bias(&k, &inertia, gravity, &mut m, &mut c);
        cholesky(&mut m, nq, 1e-14).map_err(|e| DynamicsError::MassMatrix { pivot: e.pivot })?;
        // a compliant normal contact takes no impulse: its pad is compressed from here on
        let (rigid, idx) = self.rigid_rows(set_after);
        let g = self.constraint_jacobian(&k, &rigid, n, &p);
        let nc = rigid.rows.len();
        let mut qd_plus = qd_minus.to_vec();
        let mut impulses = vec![S::c(0.0); set_after.rows.len()];
        if nc == 0 {
            return Ok((qd_plus, impulses));
        }
        let (y, amat, _) = schur_complement(&m, nq, &g, nc, &set_after.name)?;
        let mut imp: Vec<S> = (0..nc)
            .map(|i| -(0..nq).map(|l| g[i * nq + l] * qd_minus[l]).sum::<S>())
            .collect();
        cholesky_solve(&amat, nc, &mut imp);
        for i in 0..nc {
            for l in 0..nq {
                qd_plus[l] += y[i * nq + l] * imp[i];
            }
            impulses[idx[i]] = imp[i];
        }
        Ok((qd_plus, impulses))
    }

    /// Mass matrix (row-major) and bias forces at `(q, q̇)`.
    pub fn mass_matrix_and_bias(
        &self,
        q: &[f64],
        qd: &[f64],
        theta: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        let nq = self.nq();
        let p = self.full_params(theta);
        let (inertia, gravity, _, _) = self.adjusted(&p);
        let k = self.tree.kinematics(q, qd);
        let mut m = vec![0.0; nq * nq];
        let mut c = vec![0.0; nq];
        self.tree
            .mass_matrix_and_bias(&k, &inertia, gravity, &mut m, &mut c);
        (m, c)
    }

    /// Kinetic and potential energy (J) at `(q, q̇)`.
    pub fn energy(&self, q: &[f64], qd: &[f64], theta: &[f64]) -> (f64, f64) {
        let p = self.full_params(theta);
        let (inertia, gravity, _, _) = self.adjusted(&p);
        let k = self.tree.kinematics(q, qd);
        self.tree.energy(&k, &inertia, gravity)
    }

    /// The ground at free parameters `theta` (a slope effect tilts it): its height h (m)
    /// and unit normal n, the ground being the points p with n·p = h.
    pub fn ground(&self, theta: &[f64]) -> (f64, [f64; 2]) {
        let p = self.full_params(theta);
        let (_, _, h, n) = self.adjusted(&p);
        (h, n)
    }

    /// World position of a point given in a body frame, at `q`.
    pub fn body_point(&self, body: usize, local: [f64; 2], q: &[f64]) -> [f64; 2] {
        let k = self.tree.kinematics(q, &vec![0.0; self.nq()]);
        self.tree.point(&k, body, local)
    }
}

/// The terms of the dynamics at one state, before they are solved.
struct Terms<S> {
    /// Mass matrix (nq × nq, row-major).
    m: Vec<S>,
    /// The generalised forces less the bias forces, τ − c (N or N·m per coordinate).
    force: Vec<S>,
    /// The constraint set's rows (none without contact).
    rows: Option<ContactRows<S>>,
    /// The volumetric primitives' ground forces, by contact.
    volumetric: Vec<(usize, GroundForce<S>)>,
    /// The activations' rates ȧ (1/s).
    adot: Vec<S>,
}

/// The factors of one solve of the dynamics.
pub(super) struct Factors<S> {
    /// Cholesky factor of M (row-major, lower).
    m_chol: Vec<S>,
    /// The rigid rows' indices among the set's rows.
    rigid: Vec<usize>,
    /// The rigid rows of G (nr × nq, row-major).
    g_rigid: Vec<S>,
    /// Y = M⁻¹ G_rigidᵀ (row r = column r).
    y: Vec<S>,
    /// Cholesky factor of G_rigid M⁻¹ G_rigidᵀ.
    a_chol: Vec<S>,
}

/// The dynamics solved in f64 at one point: what their derivatives are taken about.
pub(super) struct Solution {
    /// The accelerations (m/s² or rad/s²).
    qdd: Vec<f64>,
    /// Every row's force (N).
    lambda: Vec<f64>,
    /// The solve's factors.
    factors: Factors<f64>,
}

impl Solution {
    /// The accelerations' response to a unit generalised force at coordinate `j`
    /// (∂q̈/∂τ_j, per N·m or N): $M^{-1}e_j + Y\,d\lambda$ with
    /// $A\,d\lambda = -G M^{-1} e_j$, the contact rows held.
    pub(super) fn unit_torque_response(&self, j: usize) -> Vec<f64> {
        let f = &self.factors;
        let nq = self.qdd.len();
        let mut w = vec![0.0; nq];
        w[j] = 1.0;
        cholesky_solve(&f.m_chol, nq, &mut w);
        let nr = f.rigid.len();
        let mut dl: Vec<f64> = (0..nr)
            .map(|i| -(0..nq).map(|l| f.g_rigid[i * nq + l] * w[l]).sum::<f64>())
            .collect();
        cholesky_solve(&f.a_chol, nr, &mut dl);
        for (i, d) in dl.iter().enumerate() {
            for l in 0..nq {
                w[l] += d * f.y[i * nq + l];
            }
        }
        w
    }
}

impl GaitModel {
    /// Solve `terms` for the accelerations: the rigid rows' forces are written to `lambda`
    /// (the compliant rows' are there already) and, with `report`, the contact details. Also
    /// returns the solve's factors.
    fn solve_terms<S: ModelScalar>(
        &self,
        terms: Terms<S>,
        set: &ConstraintSet,
        lambda: &mut [S],
        mut report: Option<&mut ContactReport>,
    ) -> Result<(Vec<S>, Factors<S>), DynamicsError> {
        let Terms {
            mut m,
            force: mut qdd,
            rows,
            volumetric,
            ..
        } = terms;
        let nq = qdd.len();
        cholesky(&mut m, nq, 1e-14).map_err(|e| DynamicsError::MassMatrix { pivot: e.pivot })?;
        cholesky_solve(&m, nq, &mut qdd);
        let mut factors = Factors {
            m_chol: Vec::new(),
            rigid: Vec::new(),
            g_rigid: Vec::new(),
            y: Vec::new(),
            a_chol: Vec::new(),
        };
        if let Some(mut rows) = rows {
            if rows.rigid.len() < set.rows.len() {
                cholesky_solve(&m, nq, &mut rows.compliant_force);
                for (a, f) in qdd.iter_mut().zip(&rows.compliant_force) {
                    *a += *f;
                }
            }
            let b_baum_rigid = solve_rigid_rows(
                &m,
                &rows,
                &set.name,
                &mut qdd,
                lambda,
                report.is_some(),
                &mut factors,
            )?;
            if let Some(rep) = report.as_deref_mut() {
                self.fill_contact_report(rep, set, &rows, &b_baum_rigid, lambda);
            }
            factors.rigid = rows.rigid;
        } else if let Some(rep) = report.as_deref_mut() {
            *rep = ContactReport::default();
        }
        if let Some(rep) = report {
            rep.volumetric = volumetric.iter().map(|(c, f)| f.report(*c)).collect();
        }
        factors.m_chol = m;
        Ok((qdd, factors))
    }
}

/// The rows of a constraint set at one state, before the rigid ones are solved.
struct ContactRows<S> {
    /// Number of coordinates.
    nq: usize,
    /// G (rows × nq, row-major): each row's direction times the contact point's Jacobian.
    g: Vec<S>,
    /// The rigid rows' right-hand side b, stabilisation included.
    b: Vec<S>,
    /// The Baumgarte stabilisation's part of b.
    b_baum: Vec<f64>,
    /// Per row, for the report: the contact point (m), the gap φ (m) and G q̇ (m/s).
    rep_rows: Vec<([f64; 2], f64, f64)>,
    /// The compliant rows' forces as generalised forces.
    compliant_force: Vec<S>,
    /// The rigid rows' indices.
    rigid: Vec<usize>,
}

/// Solve the rigid rows for their forces by the Schur complement of `m` (the mass
/// matrix's Cholesky factor): add their accelerations to `qdd` and write their forces to
/// `lambda`, and its factors to `factors`. With `want_baum`, returns each rigid row's
/// Baumgarte force (else zeros).
fn solve_rigid_rows<S: Scalar>(
    m: &[S],
    rows: &ContactRows<S>,
    set_name: &str,
    qdd: &mut [S],
    lambda: &mut [S],
    want_baum: bool,
    factors: &mut Factors<S>,
) -> Result<Vec<f64>, DynamicsError> {
    let (nq, rigid, b, g) = (rows.nq, &rows.rigid, &rows.b, &rows.g);
    let nr = rigid.len();
    let mut b_baum_rigid = vec![0.0; nr];
    if nr > 0 {
        let g_rigid: Vec<S> = rigid
            .iter()
            .flat_map(|&r| g[r * nq..(r + 1) * nq].iter().copied())
            .collect();
        let (y, amat, amat_f64) = schur_complement(m, nq, &g_rigid, nr, set_name)?;
        let mut lam_rigid: Vec<S> = rigid
            .iter()
            .enumerate()
            .map(|(i, &r)| {
                let gq: S = (0..nq).map(|l| g_rigid[i * nq + l] * qdd[l]).sum();
                b[r] - gq
            })
            .collect();
        cholesky_solve(&amat, nr, &mut lam_rigid);
        for i in 0..nr {
            for l in 0..nq {
                qdd[l] += y[i * nq + l] * lam_rigid[i];
            }
            lambda[rigid[i]] = lam_rigid[i];
        }
        if want_baum {
            let mut af = amat_f64;
            b_baum_rigid = rigid.iter().map(|&r| rows.b_baum[r]).collect();
            if cholesky(&mut af, nr, 1e-10).is_ok() {
                cholesky_solve(&af, nr, &mut b_baum_rigid);
            }
        }
        factors.g_rigid = g_rigid;
        factors.y = y;
        factors.a_chol = amat;
    }
    Ok(b_baum_rigid)
}

/// With the Cholesky factor of `M` and the constraint rows `G` (nc × nq, row-major):
/// `Y = M⁻¹Gᵀ` (row r of `y` = column r), the Cholesky factor of the Schur complement
/// `A = G M⁻¹ Gᵀ` and `A` itself in f64 (for reports). A dependent row of `G` is an
/// over-constrained contact set and is reported, never regularised.
#[allow(clippy::type_complexity)]
fn schur_complement<S: Scalar>(
    m_chol: &[S],
    nq: usize,
    g: &[S],
    nc: usize,
    set_name: &str,
) -> Result<(Vec<S>, Vec<S>, Vec<f64>), DynamicsError> {
    let mut y = g.to_vec();
    for r in 0..nc {
        cholesky_solve(m_chol, nq, &mut y[r * nq..(r + 1) * nq]);
    }
    let mut amat = vec![S::c(0.0); nc * nc];
    for i in 0..nc {
        for j in 0..nc {
            amat[i * nc + j] = (0..nq).map(|l| g[i * nq + l] * y[j * nq + l]).sum();
        }
    }
    let amat_f64: Vec<f64> = amat.iter().map(|v| v.value()).collect();
    cholesky(&mut amat, nc, 1e-10).map_err(|e| DynamicsError::OverConstrained {
        set: set_name.to_string(),
        row: e.pivot,
    })?;
    Ok((y, amat, amat_f64))
}
