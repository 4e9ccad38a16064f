//! The five-link planar biped of Kelly (2017), sec. 7 (see the [module docs](super) for
//! the equations and sources).
//!
//! Geometry (x forward, y up; absolute link angles from the vertical, counter-clockwise
//! positive): unit vectors $e_k = (-\sin q_k, \cos q_k)$ for the stance tibia, stance femur
//! and torso ($k = 1, 2, 3$, pointing up) and $e_k = (\sin q_k, -\cos q_k)$ for the swing
//! femur and tibia ($k = 4, 5$, pointing down).  Joint points: $P_0 = 0$ (stance foot),
//! $P_1 = l_1 e_1$ (stance knee), $P_2 = P_1 + l_2 e_2$ (hip), $P_3 = P_2 + l_3 e_3$ (top of
//! the torso), $P_4 = P_2 + l_4 e_4$ (swing knee), $P_5 = P_4 + l_5 e_5$ (swing foot).  Centres
//! of mass: $G_1 = P_1 - c_1 e_1$, $G_2 = P_2 - c_2 e_2$, $G_3 = P_3 - c_3 e_3$,
//! $G_4 = P_2 + c_4 e_4$, $G_5 = P_4 + c_5 e_5$.

use num_dual::DualSVec64;
use serde_json::Value;

use super::{number, numbers, ParameterError};
use crate::integrate::{ControlledOde, OdeError};
use crate::model::ad::{dense_jacobian, eps, seed};
use crate::model::linalg::{cholesky, cholesky_solve};
use crate::model::Scalar;

/// Number of generalised coordinates (link angles).
pub const NQ: usize = 5;
/// Number of states (q, q̇).
pub const NX: usize = 2 * NQ;
/// Number of controls (joint torques u1..u5; u1 = stance ankle).
pub const NU: usize = 5;

/// Relabelling of the links at heel strike: new link k is old link `FLIP[k]`.
pub const FLIP: [usize; NQ] = [4, 3, 2, 1, 0];

/// Sign of each link's unit vector relative to ê(q) = (−sin q, cos q).
const SIGN: [f64; NQ] = [1.0, 1.0, 1.0, -1.0, -1.0];

/// Dual number with one lane per coordinate of a block (q, q̇ or u).
type Ad5 = DualSVec64<NQ>;

/// Cholesky pivot tolerance relative to the largest diagonal entry (the mass matrices are
/// well conditioned for every configuration; this only rejects non-finite input).
const PIVOT_TOL: f64 = 1e-14;

/// Planar five-link point-foot biped in single stance (stance foot pinned at the origin).
///
/// The parameters are fixed at construction (the derived coefficients of the mass matrix
/// are precomputed); use [`new`](Self::new), [`from_problem_json`](Self::from_problem_json)
/// or [`Default`].
#[derive(Debug, Clone, PartialEq)]
pub struct FiveLinkBiped {
    m: [f64; NQ],
    inertia: [f64; NQ],
    l: [f64; NQ],
    c: [f64; NQ],
    g: f64,
    /// G_k = Σ_j com[k][j] ê(q_j).
    com: [[f64; NQ]; NQ],
    /// P5 = Σ_j foot[j] ê(q_j).
    foot: [f64; NQ],
    /// B = Σ_k m_k com_k com_kᵀ.
    bmat: [[f64; NQ]; NQ],
    /// b = Σ_k m_k com_k.
    bvec: [f64; NQ],
    total_mass: f64,
}

impl Default for FiveLinkBiped {
    /// The peer problem's (OptimTraj / RABBIT) values.
    fn default() -> Self {
        Self::new(
            [3.2, 6.8, 20.0, 6.8, 3.2],
            [0.93, 1.08, 2.22, 1.08, 0.93],
            [0.4, 0.4, 0.625, 0.4, 0.4],
            [0.128, 0.163, 0.2, 0.163, 0.128],
            9.81,
        )
        .expect("default parameters are valid")
    }
}

/// Result of the heel-strike map with its by-products.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeelStrike<S> {
    /// Post-impact, relabelled state x⁺ = (F q⁻, F q̇⁺).
    pub x_plus: [S; NX],
    /// Impulse Λ of the ground on the impacting foot (N s), x and y.
    pub impulse: [S; 2],
    /// Velocity of the old stance foot (the new swing foot) just after impact (m/s).
    pub old_stance_foot_velocity: [S; 2],
    /// Post-impact angular velocities in the OLD labelling (q̇⁺ before relabelling).
    pub dq_plus_old_labels: [S; NQ],
}

impl FiveLinkBiped {
    /// A biped with link masses `m` (kg), inertias about the link centres of mass
    /// (kg m²), lengths `l` (m), centre-of-mass offsets `c` (m, measured as described in the
    /// module docs: from the stance knee, hip, TOP of the torso, hip, swing knee) and
    /// gravity `g` (m/s²); links ordered stance tibia, stance femur, torso, swing femur,
    /// swing tibia.
    pub fn new(
        m: [f64; NQ],
        inertia: [f64; NQ],
        l: [f64; NQ],
        c: [f64; NQ],
        g: f64,
    ) -> Result<Self, ParameterError> {
        const MODEL: &str = "five-link biped";
        for (name, v) in [("m", &m), ("I", &inertia), ("l", &l)] {
            if let Some(x) = v.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
                return Err(ParameterError::NotAllPositive {
                    model: MODEL,
                    parameter: name,
                    value: *x,
                });
            }
        }
        if let Some(x) = c.iter().find(|x| !x.is_finite()) {
            return Err(ParameterError::NotAllFinite {
                model: MODEL,
                parameter: "c",
                value: *x,
            });
        }
        if !g.is_finite() {
            return Err(ParameterError::NotFinite {
                model: MODEL,
                parameter: "g",
                value: g,
            });
        }
        // Coefficients of ê(q_j) (sign of e_j folded in).
        let [l1, l2, l3, l4, _l5] = l;
        let raw = [
            [l1 - c[0], 0.0, 0.0, 0.0, 0.0],
            [l1, l2 - c[1], 0.0, 0.0, 0.0],
            [l1, l2, l3 - c[2], 0.0, 0.0],
            [l1, l2, 0.0, c[3], 0.0],
            [l1, l2, 0.0, l4, c[4]],
        ];
        let com: [[f64; NQ]; NQ] =
            std::array::from_fn(|k| std::array::from_fn(|j| raw[k][j] * SIGN[j]));
        let foot: [f64; NQ] = std::array::from_fn(|j| [l[0], l[1], 0.0, l[3], l[4]][j] * SIGN[j]);
        let bmat = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..NQ).map(|k| m[k] * com[k][i] * com[k][j]).sum())
        });
        let bvec = std::array::from_fn(|i| (0..NQ).map(|k| m[k] * com[k][i]).sum());
        Ok(Self {
            m,
            inertia,
            l,
            c,
            g,
            com,
            foot,
            bmat,
            bvec,
            total_mass: m.iter().sum(),
        })
    }

    /// Physical parameters from a problem JSON like the peer's `five_link_biped.json`:
    /// `parameters.{m, I, l, c}` (arrays of 5) and `parameters.g`.  The error names the
    /// missing or malformed field.
    pub fn from_problem_json(problem: &Value) -> Result<Self, ParameterError> {
        const WHAT: &str = "five-link biped";
        let arr = |k: &str| numbers::<NQ>(problem, &["parameters", k], WHAT);
        Self::new(
            arr("m")?,
            arr("I")?,
            arr("l")?,
            arr("c")?,
            number(problem, &["parameters", "g"], WHAT)?,
        )
    }

    /// Link masses (kg).
    pub fn masses(&self) -> [f64; NQ] {
        self.m
    }
    /// Link inertias about their centres of mass (kg m²).
    pub fn inertias(&self) -> [f64; NQ] {
        self.inertia
    }
    /// Link lengths (m).
    pub fn lengths(&self) -> [f64; NQ] {
        self.l
    }
    /// Centre-of-mass offsets c (m), measured as in [`new`](Self::new).
    pub fn com_offsets(&self) -> [f64; NQ] {
        self.c
    }
    /// Gravitational acceleration (m/s²).
    pub fn gravity(&self) -> f64 {
        self.g
    }
    /// Total mass (kg).
    pub fn total_mass(&self) -> f64 {
        self.total_mass
    }

    /// Generalised forces of the joint torques: Q = (u1−u2, u2−u3, u3−u4, u4−u5, u5).
    #[inline]
    pub fn generalized_forces<S: Scalar>(u: &[S]) -> [S; NQ] {
        assert_eq!(u.len(), NU, "u must have length {NU}");
        [u[0] - u[1], u[1] - u[2], u[2] - u[3], u[3] - u[4], u[4]]
    }

    /// Mass matrix M(q) (5×5, symmetric, row-major) for the stance foot pinned.
    pub fn mass_matrix<S: Scalar>(&self, q: &[S]) -> [S; NQ * NQ] {
        let (s, c) = sin_cos(q);
        self.mass_matrix_sc(&s, &c)
    }

    #[inline]
    fn mass_matrix_sc<S: Scalar>(&self, s: &[S; NQ], c: &[S; NQ]) -> [S; NQ * NQ] {
        let mut mm = [S::c(0.0); NQ * NQ];
        for i in 0..NQ {
            mm[i * NQ + i] = S::c(self.bmat[i][i] + self.inertia[i]);
            for j in (i + 1)..NQ {
                let bij = self.bmat[i][j];
                if bij != 0.0 {
                    let v = (c[i] * c[j] + s[i] * s[j]) * bij;
                    mm[i * NQ + j] = v;
                    mm[j * NQ + i] = v;
                }
            }
        }
        mm
    }

    /// Coriolis/centrifugal plus gravity terms C(q, q̇) + G(q).
    pub fn bias<S: Scalar>(&self, q: &[S], dq: &[S]) -> [S; NQ] {
        assert_eq!(dq.len(), NQ, "dq must have length {NQ}");
        let (s, c) = sin_cos(q);
        let mut r = [S::c(0.0); NQ];
        self.subtract_bias(&s, &c, dq, &mut r);
        r.map(|v| -v)
    }

    /// r −= C + G.
    #[inline]
    fn subtract_bias<S: Scalar>(&self, s: &[S; NQ], c: &[S; NQ], dq: &[S], r: &mut [S; NQ]) {
        let dq2: [S; NQ] = std::array::from_fn(|j| dq[j] * dq[j]);
        for i in 0..NQ {
            // G_i = −g b_i sin q_i
            r[i] += s[i] * (self.g * self.bvec[i]);
            for j in (i + 1)..NQ {
                let bij = self.bmat[i][j];
                if bij != 0.0 {
                    // sin(q_i − q_j) B_ij
                    let sij = (s[i] * c[j] - c[i] * s[j]) * bij;
                    r[i] -= sij * dq2[j];
                    r[j] += sij * dq2[i];
                }
            }
        }
    }

    /// State derivative ẋ = (q̇, M⁻¹(Q − C − G)) for any scalar type.
    ///
    /// Non-finite input gives non-finite output.  Panics unless `x.len() == 10` and
    /// `u.len() == 5`.
    #[inline]
    pub fn rhs<S: Scalar>(&self, x: &[S], u: &[S]) -> [S; NX] {
        assert_eq!(x.len(), NX, "x must have length {NX}");
        let (q, dq) = x.split_at(NQ);
        let (s, c) = sin_cos(q);
        let mm = self.mass_matrix_sc(&s, &c);
        let mut r = Self::generalized_forces(u);
        self.subtract_bias(&s, &c, dq, &mut r);
        let Some(chol) = Chol5::new(&mm) else {
            return [S::c(f64::NAN); NX];
        };
        chol.solve(&mut r);
        std::array::from_fn(|k| if k < NQ { dq[k] } else { r[k - NQ] })
    }

    /// f and its Jacobians `(xdot, fx (10×10), fu (10×5))`, column-major.
    ///
    /// ẋ = (q̇, q̈) with q̈ = M(q)⁻¹ r(q, q̇, u), r = Q − C − G.  M and r are differentiated by
    /// forward-mode AD (the generic code of [`rhs`](Self::rhs), one 5-lane dual pass per
    /// block q, q̇, u, so that the q̇ and u passes carry no derivative through M), and the
    /// solve by its exact derivative rule ∂q̈ = M⁻¹ (∂r − ∂M q̈) with the plain `f64` Cholesky
    /// factor; ∂q̇/∂x = [0 I] is filled in directly.  This equals AD through the whole
    /// right-hand side (tested) at about a third of the cost.  Non-finite input gives
    /// non-finite output.
    pub fn rhs_jacobian(
        &self,
        x: &[f64],
        u: &[f64],
    ) -> ([f64; NX], [f64; NX * NX], [f64; NX * NU]) {
        assert!(
            x.len() == NX && u.len() == NU,
            "x, u must have lengths {NX}, {NU}"
        );
        let (q, dq) = x.split_at(NQ);
        let (s, c) = sin_cos(q);
        let mm = self.mass_matrix_sc(&s, &c);
        let mut qdd = Self::generalized_forces(u);
        self.subtract_bias(&s, &c, dq, &mut qdd);
        let mut xdot = [f64::NAN; NX];
        let mut fx = [f64::NAN; NX * NX];
        let mut fu = [f64::NAN; NX * NU];
        let Some(chol) = Chol5::new(&mm) else {
            return (xdot, fx, fu);
        };
        chol.solve(&mut qdd);
        xdot[..NQ].copy_from_slice(dq);
        xdot[NQ..].copy_from_slice(&qdd);
        // rhs[i][col] = ∂r_i/∂z_col − Σ_j ∂M_ij/∂z_col q̈_j,  z = (q, q̇, u)
        let mut rhs = [[0.0; NX + NU]; NQ];
        for block in 0..3 {
            let seeded = |v: &[f64], b: usize| -> [Ad5; NQ] {
                std::array::from_fn(|k| {
                    if b == block {
                        seed(v[k], k)
                    } else {
                        Ad5::from_re(v[k])
                    }
                })
            };
            let (qs, dqs, us) = (seeded(q, 0), seeded(dq, 1), seeded(u, 2));
            let (sd, cd) = if block == 0 {
                sin_cos(&qs)
            } else {
                (s.map(Ad5::from_re), c.map(Ad5::from_re))
            };
            let mut r = Self::generalized_forces(&us);
            self.subtract_bias(&sd, &cd, &dqs, &mut r);
            for (row, ri) in rhs.iter_mut().zip(&r) {
                for lane in 0..NQ {
                    row[block * NQ + lane] = eps(ri, lane);
                }
            }
            if block == 0 {
                // ∂M only in the q block
                let m = self.mass_matrix_sc(&sd, &cd);
                for (i, row) in rhs.iter_mut().enumerate() {
                    for (j, a) in qdd.iter().enumerate() {
                        let mij = &m[i * NQ + j];
                        for (lane, v) in row[..NQ].iter_mut().enumerate() {
                            *v -= eps(mij, lane) * a;
                        }
                    }
                }
            }
        }
        chol.solve_many(&mut rhs);
        fx.fill(0.0);
        fu.fill(0.0);
        for k in 0..NQ {
            fx[k + (NQ + k) * NX] = 1.0;
        }
        for (i, row) in rhs.iter().enumerate() {
            for (col, v) in row.iter().enumerate() {
                if col < NX {
                    fx[NQ + i + col * NX] = *v;
                } else {
                    fu[NQ + i + (col - NX) * NX] = *v;
                }
            }
        }
        (xdot, fx, fu)
    }

    /// Joint points P0..P5 (stance foot, stance knee, hip, torso top, swing knee, swing foot)
    /// and link centres of mass G1..G5.
    pub fn points<S: Scalar>(&self, q: &[S]) -> ([[S; 2]; 6], [[S; 2]; NQ]) {
        let (s, c) = sin_cos(q);
        // e_k = SIGN_k ê(q_k), ê = (−sin, cos)
        let e: [[S; 2]; NQ] = std::array::from_fn(|k| [s[k] * (-SIGN[k]), c[k] * SIGN[k]]);
        let add = |p: [S; 2], k: usize, len: f64| [p[0] + e[k][0] * len, p[1] + e[k][1] * len];
        let l = self.l;
        let p0 = [S::c(0.0), S::c(0.0)];
        let p1 = add(p0, 0, l[0]);
        let p2 = add(p1, 1, l[1]);
        let p3 = add(p2, 2, l[2]);
        let p4 = add(p2, 3, l[3]);
        let p5 = add(p4, 4, l[4]);
        let c = self.c;
        let g = [
            add(p1, 0, -c[0]),
            add(p2, 1, -c[1]),
            add(p3, 2, -c[2]),
            add(p2, 3, c[3]),
            add(p4, 4, c[4]),
        ];
        ([p0, p1, p2, p3, p4, p5], g)
    }

    /// Swing-foot position P5(q) relative to the stance foot (m).
    pub fn swing_foot<S: Scalar>(&self, q: &[S]) -> [S; 2] {
        let (s, c) = sin_cos(q);
        let mut p = [S::c(0.0), S::c(0.0)];
        for j in 0..NQ {
            p[0] -= s[j] * self.foot[j];
            p[1] += c[j] * self.foot[j];
        }
        p
    }

    /// Swing-foot velocity dP5/dt = ∂P5/∂q q̇ (m/s).
    pub fn swing_foot_velocity<S: Scalar>(&self, q: &[S], dq: &[S]) -> [S; 2] {
        assert_eq!(dq.len(), NQ, "dq must have length {NQ}");
        let (s, c) = sin_cos(q);
        let mut v = [S::c(0.0), S::c(0.0)];
        for j in 0..NQ {
            // ∂ê/∂q = (−cos q, −sin q)
            let w = dq[j] * self.foot[j];
            v[0] -= c[j] * w;
            v[1] -= s[j] * w;
        }
        v
    }

    /// Kinetic and potential energy (J); potential zero at the stance-foot height.
    pub fn energy<S: Scalar>(&self, q: &[S], dq: &[S]) -> (S, S) {
        assert_eq!(dq.len(), NQ, "dq must have length {NQ}");
        let (s, c) = sin_cos(q);
        let mm = self.mass_matrix_sc(&s, &c);
        let mut kinetic = S::c(0.0);
        let mut potential = S::c(0.0);
        for i in 0..NQ {
            let mut mdq = S::c(0.0);
            for j in 0..NQ {
                mdq += mm[i * NQ + j] * dq[j];
            }
            kinetic += mdq * dq[i] * 0.5;
            potential += c[i] * (self.g * self.bvec[i]);
        }
        (kinetic, potential)
    }

    /// Heel-strike map Δ: plastic, non-slipping impact of the swing foot, then relabelling
    /// of the legs, x⁺ = (F q⁻, F q̇⁺) with F the reversal of the link order.
    ///
    /// Non-finite input gives non-finite output.  Panics unless `x_minus.len() == 10`.
    pub fn heel_strike<S: Scalar>(&self, x_minus: &[S]) -> Vec<S> {
        self.heel_strike_details(x_minus).x_plus.to_vec()
    }

    /// [`heel_strike`](Self::heel_strike) with the impulse and the velocities it implies.
    ///
    /// Extended coordinates z = (b_x, b_y, q) with b the old stance foot:
    /// M_e (ż⁺ − ż⁻) = J₅ᵀ Λ and J₅ ż⁺ = 0 with ż⁻ = (0, 0, q̇⁻), solved through the Schur
    /// complement (J₅ M_e⁻¹ J₅ᵀ) Λ = −J₅ ż⁻.
    pub fn heel_strike_details<S: Scalar>(&self, x_minus: &[S]) -> HeelStrike<S> {
        assert_eq!(x_minus.len(), NX, "x_minus must have length {NX}");
        const NE: usize = NQ + 2;
        let (q, dq) = x_minus.split_at(NQ);
        let (s, c) = sin_cos(q);
        let nan = HeelStrike {
            x_plus: [S::c(f64::NAN); NX],
            impulse: [S::c(f64::NAN); 2],
            old_stance_foot_velocity: [S::c(f64::NAN); 2],
            dq_plus_old_labels: [S::c(f64::NAN); NQ],
        };
        // M_e = [[m_tot I, Bq], [Bqᵀ, M]], Bq column j = b_j ∂ê/∂q_j; J5 = [I, ∂P5/∂q].
        let mm = self.mass_matrix_sc(&s, &c);
        let mut me = [S::c(0.0); NE * NE];
        me[0] = S::c(self.total_mass);
        me[NE + 1] = S::c(self.total_mass);
        let mut j5 = [[S::c(0.0); NE]; 2];
        j5[0][0] = S::c(1.0);
        j5[1][1] = S::c(1.0);
        for j in 0..NQ {
            let (bx, by) = (-c[j] * self.bvec[j], -s[j] * self.bvec[j]);
            me[j + 2] = bx;
            me[(j + 2) * NE] = bx;
            me[NE + j + 2] = by;
            me[(j + 2) * NE + 1] = by;
            for i in 0..NQ {
                me[(i + 2) * NE + j + 2] = mm[i * NQ + j];
            }
            j5[0][j + 2] = -c[j] * self.foot[j];
            j5[1][j + 2] = -s[j] * self.foot[j];
        }
        if cholesky(&mut me, NE, PIVOT_TOL).is_err() {
            return nan;
        }
        // X = M_e⁻¹ J5ᵀ (two columns); A = J5 X (2×2, SPD); rhs = −J5 ż⁻ = −v5⁻.
        let mut x_cols = j5;
        for col in &mut x_cols {
            cholesky_solve(&me, NE, col);
        }
        let dot = |a: &[S; NE], b: &[S; NE]| {
            let mut acc = S::c(0.0);
            for k in 0..NE {
                acc += a[k] * b[k];
            }
            acc
        };
        let a00 = dot(&j5[0], &x_cols[0]);
        let a01 = dot(&j5[0], &x_cols[1]);
        let a11 = dot(&j5[1], &x_cols[1]);
        let v5 = self.swing_foot_velocity(q, dq);
        let det = a00 * a11 - a01 * a01;
        if det.value().is_nan() || det.value() <= 0.0 {
            return nan;
        }
        let inv = det.recip();
        let lx = (a01 * v5[1] - a11 * v5[0]) * inv;
        let ly = (a01 * v5[0] - a00 * v5[1]) * inv;
        // ż⁺ = ż⁻ + X Λ
        let zp: [S; NE] = std::array::from_fn(|k| {
            let base = if k < 2 { S::c(0.0) } else { dq[k - 2] };
            base + x_cols[0][k] * lx + x_cols[1][k] * ly
        });
        let dq_old: [S; NQ] = std::array::from_fn(|k| zp[k + 2]);
        HeelStrike {
            x_plus: std::array::from_fn(|k| {
                if k < NQ {
                    q[FLIP[k]]
                } else {
                    dq_old[FLIP[k - NQ]]
                }
            }),
            impulse: [lx, ly],
            old_stance_foot_velocity: [zp[0], zp[1]],
            dq_plus_old_labels: dq_old,
        }
    }

    /// Heel-strike map and its 10×10 Jacobian (column-major), by one 10-lane AD pass.
    pub fn heel_strike_jacobian(&self, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
        dense_jacobian::<NX, NX>(x, |xs| self.heel_strike_details(xs).x_plus)
    }

    /// Swing-foot position and its 2×5 Jacobian ∂P5/∂q (column-major), by AD.
    pub fn swing_foot_jacobian(&self, q: &[f64]) -> (Vec<f64>, Vec<f64>) {
        dense_jacobian::<NQ, 2>(q, |qs| self.swing_foot(qs))
    }

    /// Swing-foot velocity and its 2×10 Jacobian with respect to x = (q, q̇) (column-major),
    /// by AD.
    pub fn swing_foot_velocity_jacobian(&self, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
        dense_jacobian::<NX, 2>(x, |xs| self.swing_foot_velocity(&xs[..NQ], &xs[NQ..]))
    }
}

/// Cholesky factor of a symmetric positive-definite 5×5 matrix, with the reciprocals of
/// its diagonal so that solves multiply instead of divide.
struct Chol5<S> {
    /// Lower triangle, row-major (upper part unused).
    l: [S; NQ * NQ],
    inv_diag: [S; NQ],
}

impl<S: Scalar> Chol5<S> {
    /// Factor the row-major matrix `a`; `None` if a pivot is not above
    /// `PIVOT_TOL · max a_ii` (including NaN).
    #[inline]
    fn new(a: &[S; NQ * NQ]) -> Option<Self> {
        let scale = (0..NQ)
            .map(|i| a[i * NQ + i].value().abs())
            .fold(0.0, f64::max);
        let mut l = *a;
        let mut inv_diag = [S::c(0.0); NQ];
        for j in 0..NQ {
            let mut d = l[j * NQ + j];
            for k in 0..j {
                d -= l[j * NQ + k] * l[j * NQ + k];
            }
            let pivot = d.value();
            if pivot.is_nan() || pivot <= PIVOT_TOL * scale {
                return None;
            }
            let inv = d.sqrt().recip();
            inv_diag[j] = inv;
            for i in (j + 1)..NQ {
                let mut v = l[i * NQ + j];
                for k in 0..j {
                    v -= l[i * NQ + k] * l[j * NQ + k];
                }
                l[i * NQ + j] = v * inv;
            }
        }
        Some(Self { l, inv_diag })
    }

    /// Solve A x = b in place.
    #[inline]
    fn solve(&self, b: &mut [S; NQ]) {
        let l = &self.l;
        for i in 0..NQ {
            let mut v = b[i];
            for k in 0..i {
                v -= l[i * NQ + k] * b[k];
            }
            b[i] = v * self.inv_diag[i];
        }
        for i in (0..NQ).rev() {
            let mut v = b[i];
            for k in (i + 1)..NQ {
                v -= l[k * NQ + i] * b[k];
            }
            b[i] = v * self.inv_diag[i];
        }
    }
}

impl Chol5<f64> {
    /// Solve A X = B in place for the `W` columns of B (`b[i][col]`).
    #[inline]
    fn solve_many<const W: usize>(&self, b: &mut [[f64; W]; NQ]) {
        let l = &self.l;
        for i in 0..NQ {
            let (done, rest) = b.split_at_mut(i);
            let bi = &mut rest[0];
            for (k, bk) in done.iter().enumerate() {
                let f = l[i * NQ + k];
                for (v, w) in bi.iter_mut().zip(bk) {
                    *v -= f * w;
                }
            }
            bi.iter_mut().for_each(|v| *v *= self.inv_diag[i]);
        }
        for i in (0..NQ).rev() {
            let (head, done) = b.split_at_mut(i + 1);
            let bi = &mut head[i];
            for (k, bk) in done.iter().enumerate() {
                let f = l[(i + 1 + k) * NQ + i];
                for (v, w) in bi.iter_mut().zip(bk) {
                    *v -= f * w;
                }
            }
            bi.iter_mut().for_each(|v| *v *= self.inv_diag[i]);
        }
    }
}

/// (sin q_k, cos q_k) for the five angles.
#[inline]
fn sin_cos<S: Scalar>(q: &[S]) -> ([S; NQ], [S; NQ]) {
    assert!(q.len() >= NQ, "q must have length {NQ}");
    let mut s = [S::c(0.0); NQ];
    let mut c = [S::c(0.0); NQ];
    for k in 0..NQ {
        (s[k], c[k]) = q[k].sin_cos();
    }
    (s, c)
}

fn check_dims(x: &[f64], u: &[f64], theta: &[f64], xdot: &[f64]) -> Result<(), OdeError> {
    super::check_dims("five-link biped", NX, NU, x, u, theta, xdot)
}

fn finite(v: &[f64]) -> Result<(), OdeError> {
    super::finite("five-link biped", v)
}

impl ControlledOde for FiveLinkBiped {
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
        xdot.copy_from_slice(&self.rhs(x, u));
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
            self.rhs(&zs[..NX], &zs[NX..])
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
        super::write_f_jac("five-link biped", (NX, NU), xdot, fx, fu, || {
            self.rhs_jacobian(x, u)
        })
    }
}
