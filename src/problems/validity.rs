//! Physical validity of a solution between its shooting nodes.
//!
//! A multiple-shooting solution satisfies its path constraints (λₙ ≥ 0, the friction cone,
//! swing-foot clearance) at the nodes only. Re-integrated on a fine grid, the ground can
//! pull a foot down or a swing foot pass through the floor between two nodes, however small
//! the KKT residual. [`check`] finds such stretches on the samples of a re-integration, and
//! [`Validity::refinement`] names where check points ([`crate::ocp::CheckPoint`]) would
//! hold the constraints there.

use crate::model::{ConstraintSet, GaitModel, RowKind};
use crate::simulate::Sample;
use serde::Serialize;

/// Tolerances of [`check`].
#[derive(Debug, Clone, Copy, Serialize, serde::Deserialize)]
pub struct ValidityLimits {
    /// A normal force below −this pulls the foot (N).
    pub normal_force_n: f64,
    /// A tangential force beyond μλₙ + this leaves the friction cone (N).
    pub friction_n: f64,
    /// A primitive more than this below the ground is inside the floor (m).
    pub penetration_m: f64,
    /// A Baumgarte (stabilisation) force above this is not physics but drift correction (N).
    pub baumgarte_n: f64,
}

impl Default for ValidityLimits {
    fn default() -> Self {
        // −1 N and the cone's 1 N: the bounds, well above integration noise; 1 mm of
        // penetration: the clearance a fine grid can resolve; 50 N of stabilisation: a
        // converged solution has below 1e-4 N, the simulated examples up to 128 N
        Self {
            normal_force_n: 1.0,
            friction_n: 1.0,
            penetration_m: 1e-3,
            baumgarte_n: 50.0,
        }
    }
}

/// What is broken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ViolationKind {
    /// λₙ < 0: the ground pulls.
    NegativeNormalForce,
    /// |λₜ| > μλₙ: the contact would slip.
    FrictionCone,
    /// A primitive not in contact is below the ground.
    Penetration,
    /// The Baumgarte terms carry a large force.
    BaumgarteForce,
}

impl ViolationKind {
    /// Words for reports.
    pub fn describe(self) -> &'static str {
        match self {
            ViolationKind::NegativeNormalForce => "negative normal force (the ground pulls)",
            ViolationKind::FrictionCone => "friction cone violated",
            ViolationKind::Penetration => "foot inside the floor",
            ViolationKind::BaumgarteForce => "large stabilisation (Baumgarte) force",
        }
    }
}

/// One stretch of the fine grid where one contact breaks one condition.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub struct Violation {
    /// What is broken.
    pub kind: ViolationKind,
    /// Contact primitive name (e.g. `l.sole`).
    pub contact: String,
    /// Phase name.
    pub phase: String,
    /// First and last sample time of the stretch (s).
    pub from_s: f64,
    /// Last sample time (s).
    pub to_s: f64,
    /// Time of the worst sample (s).
    pub worst_s: f64,
    /// How far beyond the condition at the worst sample (N, or m for penetration), ≥ 0.
    pub amount: f64,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (v, unit) = match self.kind {
            ViolationKind::Penetration => (self.amount * 1000.0, "mm"),
            _ => (self.amount, "N"),
        };
        write!(
            f,
            "{}: {} in phase {}, {:.3}–{:.3} s, worst {v:.1} {unit} at {:.3} s",
            self.kind.describe(),
            self.contact,
            self.phase,
            self.from_s,
            self.to_s,
            self.worst_s
        )
    }
}

/// The validity of a re-integrated solution.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub struct Validity {
    /// Tolerances used.
    pub limits: ValidityLimits,
    /// Every stretch that breaks a condition, in time order.
    pub violations: Vec<Violation>,
    /// Per violated stretch of a constraint the optimiser holds (not the Baumgarte
    /// force): the worst sample's phase (index in the phase file) and time.
    #[serde(skip)]
    worst: Vec<(usize, f64)>,
}

impl Validity {
    /// Whether nothing is broken.
    pub fn is_valid(&self) -> bool {
        self.violations.is_empty()
    }

    /// The phase-file indices and times (s) of the worst samples of every stretch the contact
    /// constraints could hold with check points there.
    pub fn refinement(&self) -> &[(usize, f64)] {
        &self.worst
    }
}

/// Check `samples` of a re-integration (each with the index of its phase in the phase
/// file, into `sets`, the contact set of every phase, and `phase_names`) against
/// `limits`, with friction coefficient `mu`. Contacts of a phase's set are checked for their forces; every other
/// primitive for clearance.
pub fn check(
    model: &GaitModel,
    samples: &[Sample],
    sets: &[ConstraintSet],
    phase_names: &[String],
    theta: &[f64],
    mu: f64,
    limits: ValidityLimits,
) -> Validity {
    // (kind, contact, phase) → open stretch
    struct Open {
        kind: ViolationKind,
        contact: usize,
        phase: usize,
        from: f64,
        to: f64,
        worst_t: f64,
        amount: f64,
        last_index: usize,
    }
    let mut open: Vec<Open> = Vec::new();
    let mut done: Vec<Open> = Vec::new();
    let nq = model.nq();
    for (si, s) in samples.iter().enumerate() {
        let Some(set) = sets.get(s.phase) else {
            continue;
        };
        let mut found: Vec<(ViolationKind, usize, f64)> = Vec::new();
        for (r, row) in set.rows.iter().enumerate() {
            let lam = s.contact.lambda.get(r).copied().unwrap_or(0.0);
            if row.kind == RowKind::Normal {
                if lam < -limits.normal_force_n {
                    found.push((ViolationKind::NegativeNormalForce, row.contact, -lam));
                }
                if let Some(t) = set
                    .rows
                    .iter()
                    .position(|o| o.contact == row.contact && o.kind == RowKind::Tangential)
                {
                    let lt = s.contact.lambda.get(t).copied().unwrap_or(0.0);
                    let excess = lt.abs() - mu * lam;
                    if excess > limits.friction_n {
                        found.push((ViolationKind::FrictionCone, row.contact, excess));
                    }
                }
            }
            let b = s.contact.baumgarte_abs(r);
            if b > limits.baumgarte_n {
                found.push((ViolationKind::BaumgarteForce, row.contact, b));
            }
        }
        // a volumetric primitive's ground pulls where its damping outweighs its stiffness
        for v in &s.contact.volumetric {
            if v.force[1] < -limits.normal_force_n {
                found.push((ViolationKind::NegativeNormalForce, v.contact, -v.force[1]));
            }
        }
        for c in 0..model.contacts.len() {
            // a volumetric primitive penetrates the ground by design
            if set.rows.iter().any(|r| r.contact == c) || model.is_volumetric(c) {
                continue;
            }
            let gap = model.gap(c, &s.x[..nq], theta);
            if gap < -limits.penetration_m {
                found.push((ViolationKind::Penetration, c, -gap));
            }
        }
        for (kind, contact, amount) in found {
            match open.iter_mut().find(|o| {
                o.kind == kind
                    && o.contact == contact
                    && o.phase == s.phase
                    && o.last_index + 1 == si
            }) {
                Some(o) => {
                    o.to = s.t;
                    o.last_index = si;
                    if amount > o.amount {
                        o.amount = amount;
                        o.worst_t = s.t;
                    }
                }
                None => open.push(Open {
                    kind,
                    contact,
                    phase: s.phase,
                    from: s.t,
                    to: s.t,
                    worst_t: s.t,
                    amount,
                    last_index: si,
                }),
            }
        }
        // close the stretches this sample did not continue
        let (still, closed): (Vec<Open>, Vec<Open>) =
            open.into_iter().partition(|o| o.last_index == si);
        open = still;
        done.extend(closed);
    }
    done.extend(open);
    done.sort_by(|a, b| a.from.total_cmp(&b.from).then(a.contact.cmp(&b.contact)));
    let worst = done
        .iter()
        .filter(|o| o.kind != ViolationKind::BaumgarteForce)
        .map(|o| (o.phase, o.worst_t))
        .collect();
    let violations = done
        .into_iter()
        .map(|o| Violation {
            kind: o.kind,
            contact: model.contacts[o.contact].name.clone(),
            phase: phase_names.get(o.phase).cloned().unwrap_or_default(),
            from_s: o.from,
            to_s: o.to,
            worst_s: o.worst_t,
            amount: o.amount,
        })
        .collect();
    Validity {
        limits,
        violations,
        worst,
    }
}
