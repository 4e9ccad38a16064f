//! The whole-body Newton–Euler balance of the measured trial, and its inverse dynamics.
//!
//! At each instant the measured motion fixes every body's centre-of-mass acceleration
//! $a_b$ and angular acceleration $\alpha_b$ (the model's own tree, [`Tree::kinematics`]).
//! With the plates' forces $F_s$ and moments $M_s$ about the world origin, the residual
//! wrench the measurement leaves unexplained is
//! $$R_F = \sum_b m_b (a_b - g) - \sum_s F_s,\qquad
//!   R_M = \sum_b \big[(c_b - c)\times m_b (a_b - g) + I_b \alpha_b\big]
//!         - \sum_s \big(M_s - c \times F_s\big),$$
//! about the whole-body centre of mass $c$ of the model as given. Gravity acts at the
//! centre of mass, so $R_M$ is $\dot H_c$ minus the plates' moment about it.
//!
//! Instrument and body effects enter as parameters $\theta$ ([`Param`]): a plate's clock
//! reads its loads at $t + \delta$, a gain divides them by $1 + e$, a CoP offset $d$
//! removes $d F_y$ from the moment, a mass error scales every mass and inertia by
//! $1 + \varepsilon$, a trunk offset moves the trunk's centre of mass along its x axis and
//! adds mass to it, a slope tilts gravity to $|g|(-\sin\alpha, -\cos\alpha)$. The
//! residual is written once over any scalar, so its Jacobian in $\theta$ is exact
//! (forward-mode AD).

use super::signals::Signals;
use super::CheckError;
use crate::model::multibody::{Joint, Tree};
use crate::model::torso::Torso;
use crate::model::{GaitModel, Scalar};

/// The parameters of the balance, in this order in every θ vector.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Param {
    /// Both plates' clock (s; + the plates report late).
    SharedClock,
    /// The right foot's plate clock (s), on top of the shared one.
    ClockRight,
    /// The left foot's plate clock (s).
    ClockLeft,
    /// The right plate's gain error (reported over true, minus one).
    GainRight,
    /// The left plate's gain error.
    GainLeft,
    /// The right plate's CoP offset (m, reported minus true, + forward).
    CopRight,
    /// The left plate's CoP offset (m).
    CopLeft,
    /// The subject's mass over the model's, minus one.
    BodyMass,
    /// Shift of the trunk's centre of mass along its x axis (m).
    TrunkCom,
    /// Mass added to the trunk (kg).
    TrunkMass,
    /// Ground slope (rad, + uphill).
    Slope,
}

/// Number of parameters.
pub const NPARAM: usize = 11;

impl Param {
    /// Every parameter, in θ order.
    pub const ALL: [Param; NPARAM] = [
        Param::SharedClock,
        Param::ClockRight,
        Param::ClockLeft,
        Param::GainRight,
        Param::GainLeft,
        Param::CopRight,
        Param::CopLeft,
        Param::BodyMass,
        Param::TrunkCom,
        Param::TrunkMass,
        Param::Slope,
    ];

    /// Position in θ.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Name in files (`summary.json`, CSV headers).
    pub fn name(self) -> &'static str {
        match self {
            Param::SharedClock => "shared_clock",
            Param::ClockRight => "clock_right",
            Param::ClockLeft => "clock_left",
            Param::GainRight => "gain_right",
            Param::GainLeft => "gain_left",
            Param::CopRight => "cop_offset_right",
            Param::CopLeft => "cop_offset_left",
            Param::BodyMass => "body_mass",
            Param::TrunkCom => "trunk_com_offset",
            Param::TrunkMass => "trunk_mass",
            Param::Slope => "ground_slope",
        }
    }

    /// The candidate whose [`Param::name`] is `name`.
    pub fn from_name(name: &str) -> Option<Param> {
        Param::ALL.into_iter().find(|p| p.name() == name)
    }

    /// What it is, for people.
    pub fn label(self) -> &'static str {
        match self {
            Param::SharedClock => "both plates' clock",
            Param::ClockRight => "right plate's clock",
            Param::ClockLeft => "left plate's clock",
            Param::GainRight => "right plate's gain",
            Param::GainLeft => "left plate's gain",
            Param::CopRight => "right plate's CoP offset",
            Param::CopLeft => "left plate's CoP offset",
            Param::BodyMass => "body mass",
            Param::TrunkCom => "trunk's centre of mass",
            Param::TrunkMass => "trunk's mass",
            Param::Slope => "ground slope",
        }
    }

    /// A value in the unit people read it in: ms, %, mm, kg, degrees.
    pub fn display_value(self, v: f64) -> (f64, &'static str) {
        match self {
            Param::SharedClock | Param::ClockRight | Param::ClockLeft => (1e3 * v, "ms"),
            Param::GainRight | Param::GainLeft | Param::BodyMass => (1e2 * v, "%"),
            Param::CopRight | Param::CopLeft | Param::TrunkCom => (1e3 * v, "mm"),
            Param::TrunkMass => (v, "kg"),
            Param::Slope => (v.to_degrees(), "°"),
        }
    }

    /// The effects whose signature in the whole-body balance is the same or nearly so,
    /// by the equations alone: what else could produce this reading.
    pub fn look_alikes(self) -> &'static str {
        match self {
            Param::SharedClock => "the kinematics' own timing (a filter or marker-processing lag moves the motion against the forces the same way), or the soft tissue's lag behind the rigid segments (the forces move the whole mass, the model only its skeleton's motion)",
            Param::ClockRight | Param::ClockLeft => "a lag of that plate's own signal chain, or the other plate's clock of the opposite sign (in double support one plate's rise mirrors the other's fall, so the force balance sees mostly their sum; only the moment balance tells the plates apart)",
            Param::GainRight | Param::GainLeft => "a calibration error of that plate alone",
            Param::BodyMass => "the same gain error on both plates (the whole-body balance scales with mass and forces alike), or a trunk mass error",
            Param::CopRight | Param::CopLeft => "the foot's position error in the kinematics while on that plate",
            Param::TrunkCom => "the same CoP offset on both plates, or the trunk's neutral angle in the body model",
            Param::TrunkMass => "a body-mass error",
            Param::Slope => "a zero offset of the plates' horizontal force",
        }
    }
}

/// One massive body's motion at one instant: origin, orientation, angular velocity and
/// acceleration, origin velocity and acceleration (world frame).
#[derive(Debug, Clone, Copy)]
struct BodyMotion {
    body: usize,
    origin: [f64; 2],
    cs: (f64, f64),
    omega: f64,
    alpha: f64,
    vel: [f64; 2],
    acc: [f64; 2],
}

impl BodyMotion {
    /// The world position of the point `com` of the body's frame (m).
    fn com_at(&self, com: [f64; 2]) -> [f64; 2] {
        let (c, s) = self.cs;
        [
            self.origin[0] + com[0] * c - com[1] * s,
            self.origin[1] + com[0] * s + com[1] * c,
        ]
    }
}

/// The trunk above the lumbar joint turned from its `frozen` motion (the HAT's, about the
/// lumbar joint) by the lumbar angle less the frozen one `[δ, δ̇, δ̈]` (rad, /s, /s²); its
/// inertia is the one before the frozen copy's.
fn moved_trunk(frozen: &BodyMotion, [d, dd, ddd]: [f64; 3]) -> BodyMotion {
    let (c, s) = frozen.cs;
    let (sd, cd) = d.sin_cos();
    BodyMotion {
        body: frozen.body - 1,
        cs: (c * cd - s * sd, s * cd + c * sd),
        omega: frozen.omega + dd,
        alpha: frozen.alpha + ddd,
        ..*frozen
    }
}

/// The body's side of the balance at one instant, ready for any θ.
#[derive(Debug, Clone)]
pub struct Instant {
    /// Time (s).
    pub t: f64,
    bodies: Vec<BodyMotion>,
    /// The whole-body centre of mass (m).
    pub com: [f64; 2],
}

/// The body of the model as the balance sees it: the model's rigid segments and, where
/// the model describes its trunk above the lumbar joint and the trial measures the
/// lumbar angle, that trunk moved by it ([`crate::model::torso`]). The moved trunk enters
/// as itself at its measured pose plus a copy of negative mass and inertia at the pose the
/// rigid HAT froze, so that the HAT's own parameters stay those of the model.
#[derive(Debug, Clone)]
pub struct Body {
    tree: Tree,
    /// `(mass, com, izz)` of each body; with a torso, the moved trunk and its frozen
    /// negative copy last.
    inertia: Vec<(f64, [f64; 2], f64)>,
    trunk: usize,
    torso: Option<Torso>,
    gravity: f64,
}

impl Body {
    /// The body of `model`, its HAT rigid as the solvers have it.
    pub fn of(model: &GaitModel) -> Result<Self, CheckError> {
        let tree = model.tree().clone();
        let trunk = tree.body_index("hat").ok_or(CheckError::NoTrunk)?;
        let inertia = tree
            .bodies()
            .iter()
            .map(|b| (b.mass, b.com, b.izz))
            .collect();
        Ok(Self {
            tree,
            inertia,
            trunk,
            torso: None,
            gravity: model.gravity(),
        })
    }

    /// The body of `model` with the HAT's trunk above the lumbar joint moving by the
    /// trial's lumbar angle wherever the signals measure it; `None` when the model does
    /// not describe that trunk.
    pub fn with_torso(model: &GaitModel) -> Option<Result<Self, CheckError>> {
        let t = *model.torso()?;
        Some(Self::of(model).map(|mut body| {
            body.inertia.push((t.mass, t.com, t.izz));
            body.inertia.push((-t.mass, t.com, -t.izz));
            body.torso = Some(t);
            body
        }))
    }

    /// Total mass (kg).
    pub fn mass(&self) -> f64 {
        self.inertia.iter().map(|i| i.0).sum()
    }

    /// Gravitational acceleration (m/s²).
    pub fn gravity(&self) -> f64 {
        self.gravity
    }

    /// Trunk mass (kg).
    pub fn trunk_mass(&self) -> f64 {
        self.inertia[self.trunk].0
    }

    /// The tree.
    pub fn tree(&self) -> &Tree {
        &self.tree
    }

    /// Whether the trunk above the lumbar joint moves by the trial's lumbar angle: the
    /// model describes it and `signals` measure the angle.
    pub fn moves_trunk(&self, signals: &Signals) -> bool {
        self.torso.is_some() && signals.has_lumbar()
    }

    /// The motion of every massive body at `t`.
    pub fn instant(&self, signals: &Signals, t: f64) -> Instant {
        let (q, qd, qdd) = signals.motion(t);
        let k = self.tree.kinematics::<f64>(&q, &qd);
        let n = self.tree.nq();
        let mut jac = vec![0.0; 2 * n];
        // a world point fixed to body b: its velocity and acceleration
        let mut point = |b: usize, o: [f64; 2]| {
            self.tree.point_jacobian(&k, b, o, &mut jac);
            let (vel, mut acc) = self.tree.point_motion(&k, b, o);
            for j in 0..n {
                acc[0] += jac[j] * qdd[j];
                acc[1] += jac[n + j] * qdd[j];
            }
            (vel, acc)
        };
        let mut bodies = Vec::new();
        for (b, &(mass, _, _)) in self
            .inertia
            .iter()
            .enumerate()
            .take(self.tree.bodies().len())
        {
            if mass == 0.0 {
                continue;
            }
            let o = k.origin[b];
            let (vel, acc) = point(b, o);
            let alpha = self
                .tree
                .ancestors(b)
                .iter()
                .filter(|&&j| matches!(self.tree.bodies()[j].joint, Joint::Revolute))
                .map(|&j| qdd[j])
                .sum();
            bodies.push(BodyMotion {
                body: b,
                origin: o,
                cs: k.cs[b],
                omega: k.omega[b],
                alpha,
                vel,
                acc,
            });
        }
        if let (Some(torso), Some(hat)) = (self.torso, bodies.iter().find(|m| m.body == self.trunk))
        {
            if let Some(lumbar) = signals.lumbar(t, torso.frozen) {
                let hat = *hat;
                let o = self.tree.point(&k, self.trunk, torso.joint);
                let (vel, acc) = point(self.trunk, o);
                let frozen = BodyMotion {
                    body: self.tree.bodies().len() + 1,
                    origin: o,
                    vel,
                    acc,
                    ..hat
                };
                bodies.extend([moved_trunk(&frozen, lumbar), frozen]);
            }
        }
        let (mut m, mut mc) = (0.0, [0.0, 0.0]);
        for bm in &bodies {
            let (mass, com, _) = self.inertia[bm.body];
            let c = bm.com_at(com);
            m += mass;
            mc = [mc[0] + mass * c[0], mc[1] + mass * c[1]];
        }
        Instant {
            t,
            bodies,
            com: [mc[0] / m, mc[1] / m],
        }
    }

    /// Linear momentum (N·s, x and y) and angular momentum about the centre of mass
    /// (N·m·s) at one instant.
    pub fn momentum(&self, at: &Instant) -> [f64; 3] {
        let mut out = [0.0; 3];
        for bm in &at.bodies {
            let (mass, com, izz) = self.inertia[bm.body];
            let c = bm.com_at(com);
            let r = [c[0] - bm.origin[0], c[1] - bm.origin[1]];
            let v = [bm.vel[0] - bm.omega * r[1], bm.vel[1] + bm.omega * r[0]];
            out[0] += mass * v[0];
            out[1] += mass * v[1];
            out[2] +=
                mass * ((c[0] - at.com[0]) * v[1] - (c[1] - at.com[1]) * v[0]) + izz * bm.omega;
        }
        out
    }

    /// The body's side `[Σ m (a − g) (N, 2), Σ (c_b − c) × m (a − g) + I α (N·m)]` at one
    /// instant for parameters θ.
    pub fn required<S: Scalar>(&self, at: &Instant, theta: &[S]) -> [S; 3] {
        let p = |k: Param| theta[k.index()];
        let scale = S::c(1.0) + p(Param::BodyMass);
        let (sa, ca) = (p(Param::Slope).sin(), p(Param::Slope).cos());
        let g = [-sa * self.gravity, -ca * self.gravity];
        let mut out = [S::c(0.0); 3];
        for bm in &at.bodies {
            let (mut mass, com, mut izz) = {
                let (m, c, i) = self.inertia[bm.body];
                (S::c(m), [S::c(c[0]), S::c(c[1])], S::c(i))
            };
            let mut com = com;
            if bm.body == self.trunk {
                let added = p(Param::TrunkMass);
                izz *= (mass + added) / mass;
                mass += added;
                com[0] += p(Param::TrunkCom);
            }
            mass *= scale;
            izz *= scale;
            let (c, s) = bm.cs;
            let r = [com[0] * c - com[1] * s, com[0] * s + com[1] * c];
            let w2 = bm.omega * bm.omega;
            let a = [
                r[1] * (-bm.alpha) - r[0] * w2 + bm.acc[0],
                r[0] * bm.alpha - r[1] * w2 + bm.acc[1],
            ];
            let f = [(a[0] - g[0]) * mass, (a[1] - g[1]) * mass];
            let arm = [
                r[0] + (bm.origin[0] - at.com[0]),
                r[1] + (bm.origin[1] - at.com[1]),
            ];
            out[0] += f[0];
            out[1] += f[1];
            out[2] += arm[0] * f[1] - arm[1] * f[0] + izz * bm.alpha;
        }
        out
    }
}

/// The plates' side `[Σ F (N, 2), Σ (M − c × F) (N·m)]` at one instant for parameters θ;
/// `None` where a plate's loads are not known at its shifted instant.
pub fn measured<S: Scalar>(signals: &Signals, at: &Instant, theta: &[S]) -> Option<[S; 3]> {
    let p = |k: Param| theta[k.index()];
    let sides = [
        (Param::ClockRight, Param::GainRight, Param::CopRight),
        (Param::ClockLeft, Param::GainLeft, Param::CopLeft),
    ];
    let mut out = [S::c(0.0); 3];
    for (s, (clock, gain, cop)) in sides.into_iter().enumerate() {
        let [fx, fy, mz] = signals.load(s, at.t, p(Param::SharedClock) + p(clock))?;
        let inv = (S::c(1.0) + p(gain)).recip();
        let mz = (mz - fy * p(cop)) * inv;
        let (fx, fy) = (fx * inv, fy * inv);
        out[0] += fx;
        out[1] += fy;
        out[2] += mz - (fy * at.com[0] - fx * at.com[1]);
    }
    Some(out)
}

/// The residual wrench `[R_Fx, R_Fy (N), R_M (N·m)]` at one instant for parameters θ.
pub fn residual<S: Scalar>(
    body: &Body,
    signals: &Signals,
    at: &Instant,
    theta: &[S],
) -> Option<[S; 3]> {
    let m = measured(signals, at, theta)?;
    let r = body.required(at, theta);
    Some([r[0] - m[0], r[1] - m[1], r[2] - m[2]])
}

/// The generalised forces the measured trial needs at one instant (N or N·m per
/// coordinate, in the model's order): $\tau = M\ddot q + c - \sum_s J_s^T F_s$, each
/// foot's load applied at its CoP on the foot (at the ankle where the foot is unloaded).
/// The joint rows are the joint torques of the inverse dynamics; the pelvis rows are the
/// residual wrench in joint space. `None` where a foot's load is not measured at `t`.
pub fn inverse_dynamics(
    body: &Body,
    signals: &Signals,
    model: &GaitModel,
    t: f64,
) -> Option<Vec<f64>> {
    let tree = &body.tree;
    let (q, qd, qdd) = signals.motion(t);
    let k = tree.kinematics::<f64>(&q, &qd);
    let n = tree.nq();
    let inertia = tree.inertias::<f64>();
    let g = [0.0, -model.gravity()];
    let mut mm = vec![0.0; n * n];
    let mut c = vec![0.0; n];
    tree.mass_matrix_and_bias(&k, &inertia, g, &mut mm, &mut c);
    let mut tau: Vec<f64> = (0..n)
        .map(|i| c[i] + (0..n).map(|j| mm[i * n + j] * qdd[j]).sum::<f64>())
        .collect();
    let mut jac = vec![0.0; 2 * n];
    for (s, prefix) in ["r", "l"].into_iter().enumerate() {
        let foot = tree.body_index(&format!("foot_{prefix}"))?;
        let [fx, fy, mz] = signals.load(s, t, 0.0_f64)?;
        // a point of the load's line of action (where it crosses y = 0, the moment being
        // about the origin); at the ankle where the foot is unloaded
        let p = if fy.abs() > 1.0 {
            [mz / fy, 0.0]
        } else {
            k.origin[foot]
        };
        tree.point_jacobian(&k, foot, p, &mut jac);
        for j in 0..n {
            tau[j] -= jac[j] * fx + jac[n + j] * fy;
        }
    }
    Some(tau)
}
