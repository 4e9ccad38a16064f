//! Phase sequences in JSON (`phases/`): ordered continuous phases (an active contact set
//! held for a duration) and instantaneous impact phases (the plastic impact map of the
//! contacts that are active after it), as in Millard & Mombaur (2019), §3.3.

use crate::limits::{first_few, show, MAX_COORDINATE, MAX_DURATION, MAX_INTERVALS, MAX_VELOCITY};
use crate::model::spec::read_json;
use crate::model::{ConstraintSet, GaitModel, ModelError};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One foot-ground contact in a phase.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactUse {
    /// Contact name `r.PRIMITIVE` or `l.PRIMITIVE`.
    pub contact: String,
    /// Whether the contact also rolls without slipping (tangential row); a contact without
    /// rolling carries a normal force only (seed: the second circle when both touch).
    #[serde(default = "yes")]
    pub rolling: bool,
}

impl ContactUse {
    /// The same contact on the other foot (`r.` ↔ `l.`).
    pub fn mirrored(&self) -> Self {
        let contact = match self.contact.split_once('.') {
            Some(("r", p)) => format!("l.{p}"),
            Some(("l", p)) => format!("r.{p}"),
            _ => self.contact.clone(),
        };
        ContactUse {
            contact,
            rolling: self.rolling,
        }
    }
}

fn yes() -> bool {
    true
}

/// Duration of a continuous phase: fixed, or free within bounds with an initial guess.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Duration {
    /// Fixed duration (s).
    Fixed(f64),
    /// Free duration (s).
    Free {
        /// Initial value.
        initial: f64,
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
}

// By hand rather than `untagged`, so that a wrong value gets serde's "invalid type: …,
// expected …" (quoting the value) and a bad bound names its field.
impl<'de> Deserialize<'de> for Duration {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Free {
            initial: f64,
            min: f64,
            max: f64,
        }
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Duration;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a duration: a number of seconds, or {\"initial\", \"min\", \"max\"} in seconds")
            }
            fn visit_f64<E>(self, v: f64) -> Result<Duration, E> {
                Ok(Duration::Fixed(v))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Duration, E> {
                Ok(Duration::Fixed(v as f64))
            }
            fn visit_i64<E>(self, v: i64) -> Result<Duration, E> {
                Ok(Duration::Fixed(v as f64))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<Duration, A::Error> {
                let f = Free::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(Duration::Free {
                    initial: f.initial,
                    min: f.min,
                    max: f.max,
                })
            }
        }
        d.deserialize_any(V)
    }
}

impl Duration {
    /// The fixed value or the initial guess (s).
    pub fn value(&self) -> f64 {
        match *self {
            Duration::Fixed(v) => v,
            Duration::Free { initial, .. } => initial,
        }
    }
}

/// An event that ends a continuous phase in a forward simulation (`"end": {"touchdown":
/// "l.heel"}`): the phase ends at the first instant the named contact, not active in the
/// phase, reaches the ground (its gap φ falls from above zero to zero), so the impact that
/// follows starts with the landing contact on the ground. Optimal control ignores it: its
/// landing constraints put the contact on the ground at the phase end.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseEnd {
    /// Contact whose touchdown ends the phase, `r.PRIMITIVE` or `l.PRIMITIVE`.
    pub touchdown: String,
}

/// A phase of the sequence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Phase {
    /// A continuous phase with a fixed set of active contacts.
    Continuous {
        /// Name (e.g. `2e`).
        name: String,
        /// Active contacts.
        contacts: Vec<ContactUse>,
        /// Duration.
        duration: Duration,
        /// Number of shooting intervals (used by optimal control; 1 or more, at most
        /// [`MAX_INTERVALS`] in the whole sequence).
        #[serde(default = "one_interval")]
        intervals: usize,
        /// Event that ends the phase before its duration (forward simulation only; the
        /// duration is then the longest the phase may last).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        end: Option<PhaseEnd>,
    },
    /// An instantaneous plastic impact; `contacts` are those active right after it.
    Impact {
        /// Name (e.g. `1e*`).
        name: String,
        /// Contacts active after the impact.
        contacts: Vec<ContactUse>,
    },
}

fn one_interval() -> usize {
    1
}

impl Phase {
    /// The phase's name.
    pub fn name(&self) -> &str {
        match self {
            Phase::Continuous { name, .. } | Phase::Impact { name, .. } => name,
        }
    }
    /// The event that ends a continuous phase early in a simulation, if any.
    pub fn end(&self) -> Option<&PhaseEnd> {
        match self {
            Phase::Continuous { end, .. } => end.as_ref(),
            Phase::Impact { .. } => None,
        }
    }
    /// The contacts.
    pub fn contacts(&self) -> &[ContactUse] {
        match self {
            Phase::Continuous { contacts, .. } | Phase::Impact { contacts, .. } => contacts,
        }
    }
}

/// Initial state of a simulation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialState {
    /// Generalised positions (m, rad), 9 values in model order.
    pub q: Vec<f64>,
    /// Generalised velocities (m/s, rad/s).
    pub qd: Vec<f64>,
    /// Activations (0…1); default 0.01 each.
    #[serde(default)]
    pub a: Option<Vec<f64>>,
}

/// A phase sequence file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseSequence {
    /// Name.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Initial state for simulations (optional).
    #[serde(default)]
    pub initial_state: Option<InitialState>,
    /// The phases in order.
    pub phases: Vec<Phase>,
    /// Walking-cycle settings for optimal control (periodicity, symmetry, friction).
    #[serde(default)]
    pub gait: Option<GaitSpec>,
}

fn default_friction() -> f64 {
    0.8
}

fn default_symmetry() -> Vec<[String; 2]> {
    [
        ["hip_r", "hip_l"],
        ["knee_r", "knee_l"],
        ["ankle_r", "ankle_l"],
    ]
    .iter()
    .map(|p| [p[0].to_string(), p[1].to_string()])
    .collect()
}

/// Settings of a walking cycle (Millard & Mombaur 2019, §3.3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaitSpec {
    /// Coefficient of friction of the friction cone |λₜ| ≤ μ λₙ (default 0.8).
    #[serde(default = "default_friction")]
    pub friction: f64,
    /// Coordinate pairs swapped by the left↔right symmetry map (default: hip, knee and
    /// ankle of both legs); activations and excitations of the pairs swap with them.
    #[serde(default = "default_symmetry")]
    pub symmetry: Vec<[String; 2]>,
    /// Periodic, symmetric cycle: the state after the last phase, mirrored, equals the
    /// first state, except the forward pelvis position (default true).
    #[serde(default = "yes")]
    pub periodic: bool,
    /// Swing-foot clearance φ ≥ 0 for every primitive not in contact (default true).
    #[serde(default = "yes")]
    pub clearance: bool,
    /// Control parameterisation (default `linear`, as Millard & Mombaur 2019).
    #[serde(default = "linear")]
    pub controls: crate::integrate::ControlShape,
}

fn linear() -> crate::integrate::ControlShape {
    crate::integrate::ControlShape::Linear
}

impl PhaseSequence {
    /// Indices (into `phases`) of the continuous phases, in order.
    pub fn continuous_indices(&self) -> Vec<usize> {
        self.phases
            .iter()
            .enumerate()
            .filter(|(_, p)| matches!(p, Phase::Continuous { .. }))
            .map(|(i, _)| i)
            .collect()
    }

    /// One check site `(continuous phase, interval, τ)` a third into the first interval of
    /// every continuous phase an impact starts: where the contact forces build up from the
    /// impact, and where they dip below zero between the nodes when only the nodes hold
    /// them.
    pub fn impact_sites(&self) -> Vec<(usize, usize, f64)> {
        self.continuous_indices()
            .into_iter()
            .enumerate()
            .filter(|&(_, i)| i > 0 && matches!(self.phases[i - 1], Phase::Impact { .. }))
            .map(|(j, _)| (j, 0, 1.0 / 3.0))
            .collect()
    }

    /// Read a phase file (structure only; see [`resolve`](Self::resolve)).
    pub fn load(path: &Path) -> Result<Self, ModelError> {
        // a bundled name missing from the current folder is read from footfall's copy
        let path = &crate::bundled::resolve(path);
        let s: PhaseSequence = read_json(path)?;
        s.validate(path)?;
        Ok(s)
    }

    /// Structural checks that need no model.
    pub fn validate(&self, path: &Path) -> Result<(), ModelError> {
        self.check_gait(path)?;
        if self.phases.is_empty() {
            return Err(ModelError::invalid(
                path,
                "phases",
                "the sequence has no phase; list at least one continuous phase",
            ));
        }
        let (mut total_intervals, mut total_s) = (0usize, 0.0);
        for (i, ph) in self.phases.iter().enumerate() {
            let f = |x: &str| format!("phases[{i}] ('{}').{x}", ph.name());
            if ph.name().trim().is_empty() {
                return Err(ModelError::invalid(
                    path,
                    format!("phases[{i}].name"),
                    "must be a non-empty name",
                ));
            }
            if let Some(j) = self.phases[..i].iter().position(|o| o.name() == ph.name()) {
                return Err(ModelError::invalid(
                    path,
                    f("name"),
                    format!("phase name '{}' is already used by phases[{j}]; phase names must be unique", ph.name()),
                ));
            }
            if let Phase::Continuous {
                duration,
                intervals,
                ..
            } = ph
            {
                if *intervals == 0 || *intervals > MAX_INTERVALS {
                    return Err(ModelError::invalid(
                        path,
                        f("intervals"),
                        format!("must be 1 to {MAX_INTERVALS} shooting intervals, got {intervals}"),
                    ));
                }
                total_intervals += intervals;
                total_s += duration.value();
                let ok = match *duration {
                    Duration::Fixed(v) => v.is_finite() && v > 0.0 && v <= MAX_DURATION,
                    Duration::Free { initial, min, max } => {
                        min.is_finite()
                            && max.is_finite()
                            && min > 0.0
                            && min <= initial
                            && initial <= max
                            && max <= MAX_DURATION
                    }
                };
                if !ok {
                    return Err(ModelError::invalid(
                        path,
                        f("duration"),
                        format!(
                            "must be a positive number of seconds, at most {MAX_DURATION}, or {{initial, min, max}} with 0 < min ≤ initial ≤ max ≤ {MAX_DURATION}; got {}",
                            match *duration {
                                Duration::Fixed(v) => show(v),
                                Duration::Free { initial, min, max } => format!("{{initial: {}, min: {}, max: {}}}", show(initial), show(min), show(max)),
                            }
                        ),
                    ));
                }
            }
        }
        if total_intervals > MAX_INTERVALS {
            return Err(ModelError::invalid(
                path,
                "phases[*].intervals",
                format!("the phases' shooting intervals must add up to at most {MAX_INTERVALS}, got {total_intervals}"),
            ));
        }
        if total_s > MAX_DURATION {
            return Err(ModelError::invalid(
                path,
                "phases[*].duration",
                format!(
                    "the phases' durations must add up to at most {MAX_DURATION} s, got {} s",
                    show(total_s)
                ),
            ));
        }
        self.check_impacts(path)
    }

    /// Where an impact and the phase after it (`which`) name different contacts, e.g. `;
    /// the impact has 'l.sole' where the next phase '2e' has 'l.sloe': correct whichever
    /// name is mistyped` (empty when only the rolling flags differ or one list only lacks
    /// a contact).
    fn odd_names(here: &[ContactUse], there: &[ContactUse], which: &str) -> String {
        let only = |a: &[ContactUse], b: &[ContactUse]| {
            a.iter()
                .filter(|c| !b.iter().any(|o| o.contact == c.contact))
                .map(|c| format!("'{}'", c.contact))
                .collect::<Vec<_>>()
        };
        let (h, t) = (only(here, there), only(there, here));
        if h.is_empty() || t.is_empty() {
            return String::new();
        }
        format!(
            "; the impact has {} where {which} has {}: correct whichever name is mistyped",
            h.join(", "),
            t.join(", ")
        )
    }

    /// An impact lists the contacts active right after it, so it must list those of the
    /// phase after it (in a periodic gait, a last impact those of the first continuous
    /// phase mirrored), and it must add a contact to those of the phase before it.
    fn check_impacts(&self, path: &Path) -> Result<(), ModelError> {
        let names = |cs: &[ContactUse]| {
            cs.iter()
                .map(|c| {
                    if c.rolling {
                        c.contact.clone()
                    } else {
                        format!("{} (not rolling)", c.contact)
                    }
                })
                .collect::<Vec<_>>()
        };
        let same = |a: &[ContactUse], b: &[ContactUse]| {
            a.len() == b.len() && a.iter().all(|c| b.contains(c))
        };
        let list = |cs: &[ContactUse]| {
            if cs.is_empty() {
                "none".to_string()
            } else {
                names(cs).join(", ")
            }
        };
        for (i, ph) in self.phases.iter().enumerate() {
            let Phase::Impact { contacts, .. } = ph else {
                continue;
            };
            let field = format!("phases[{i}] ('{}').contacts", ph.name());
            let after: Option<(Vec<ContactUse>, String)> = match self.phases.get(i + 1) {
                Some(Phase::Impact { name, .. }) => {
                    return Err(ModelError::invalid(path, field, format!("an impact must be followed by a continuous phase, not by the impact '{name}'")));
                }
                Some(next) => Some((
                    next.contacts().to_vec(),
                    format!("the next phase '{}'", next.name()),
                )),
                None if self.gait.as_ref().is_some_and(|g| g.periodic) => self
                    .phases
                    .iter()
                    .find(|p| matches!(p, Phase::Continuous { .. }))
                    .map(|first| {
                        (
                            first.contacts().iter().map(ContactUse::mirrored).collect(),
                            format!(
                                "the first continuous phase '{}' mirrored (the cycle is periodic)",
                                first.name()
                            ),
                        )
                    }),
                None => None,
            };
            if let Some((want, which)) = after {
                if !same(contacts, &want) {
                    return Err(ModelError::invalid(
                        path,
                        field,
                        format!("an impact lists the contacts active right after it, so must list those of {which}: {}; got {}{}", list(&want), list(contacts), Self::odd_names(contacts, &want, &which)),
                    ));
                }
            }
            if let Some(before) = i.checked_sub(1).map(|j| &self.phases[j]) {
                if contacts
                    .iter()
                    .all(|c| before.contacts().iter().any(|b| b.contact == c.contact))
                {
                    return Err(ModelError::invalid(
                        path,
                        field,
                        format!("an impact must add a contact to those of the phase before it ('{}': {}); got {}", before.name(), list(before.contacts()), list(contacts)),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Constraint sets of every phase for `model`; unknown contacts name the phase. Also
    /// checks the sizes and ranges of `initial_state` against the model.
    pub fn resolve(
        &self,
        model: &GaitModel,
        path: &Path,
    ) -> Result<Vec<ConstraintSet>, ModelError> {
        if let Some(init) = &self.initial_state {
            init.check(model, path, "initial_state")?;
        }
        let known: Vec<&str> = model.contacts.iter().map(|c| c.name.as_str()).collect();
        self.phases
            .iter()
            .enumerate()
            .map(|(i, ph)| {
                let f = |x: String| format!("phases[{i}] ('{}').{x}", ph.name());
                for (k, c) in ph.contacts().iter().enumerate() {
                    if !known.contains(&c.contact.as_str()) {
                        return Err(ModelError::invalid(
                            path,
                            f(format!("contacts[{k}].contact")),
                            format!(
                                "phase '{}' uses unknown contact '{}'; foot '{}' has: {}",
                                ph.name(),
                                c.contact,
                                model.foot_name,
                                first_few(&known)
                            ),
                        ));
                    }
                    if ph.contacts()[..k].iter().any(|o| o.contact == c.contact) {
                        return Err(ModelError::invalid(
                            path,
                            f(format!("contacts[{k}].contact")),
                            format!("phase '{}' lists contact '{}' twice", ph.name(), c.contact),
                        ));
                    }
                }
                if let Some(end) = ph.end() {
                    if !known.contains(&end.touchdown.as_str()) {
                        return Err(ModelError::invalid(
                            path,
                            f("end.touchdown".into()),
                            format!(
                                "phase '{}' ends at the touchdown of unknown contact '{}'; foot '{}' has: {}",
                                ph.name(),
                                end.touchdown,
                                model.foot_name,
                                first_few(&known)
                            ),
                        ));
                    }
                    if ph.contacts().iter().any(|c| c.contact == end.touchdown) {
                        return Err(ModelError::invalid(
                            path,
                            f("end.touchdown".into()),
                            format!(
                                "phase '{}' ends at the touchdown of '{}', which is already on the ground in it; \
                                 name a contact that lands at the end of the phase",
                                ph.name(),
                                end.touchdown
                            ),
                        ));
                    }
                }
                let list: Vec<(&str, bool)> = ph
                    .contacts()
                    .iter()
                    .map(|c| (c.contact.as_str(), c.rolling))
                    .collect();
                let set = model
                    .constraint_set(ph.name(), &list)
                    .map_err(|r| ModelError::invalid(path, f("contacts".into()), r.to_string()))?;
                if let Some(row) = model.dependent_row(&set) {
                    let r = &set.rows[row];
                    return Err(ModelError::invalid(
                        path,
                        f("contacts".into()),
                        format!(
                            "phase '{}' over-constrains the body: the {:?} row of '{}' depends on the others \
                             (a rigid foot has 3 degrees of freedom in the plane; give a second contact on \
                             the same foot \"rolling\": false)",
                            ph.name(),
                            r.kind,
                            model.contacts[r.contact].name
                        ),
                    ));
                }
                Ok(set)
            })
            .collect()
    }

    /// Check the gait section against the model: symmetry pairs must name distinct
    /// coordinates of the model, each at most once.
    pub fn check_gait(&self, path: &Path) -> Result<(), ModelError> {
        let Some(g) = &self.gait else { return Ok(()) };
        if !(g.friction.is_finite() && g.friction > 0.0) {
            return Err(ModelError::invalid(
                path,
                "gait.friction",
                format!("must be a positive number, got {}", g.friction),
            ));
        }
        let coords = crate::model::gait::COORDINATES;
        let mut used: Vec<&str> = Vec::new();
        for (i, [a, b]) in g.symmetry.iter().enumerate() {
            for c in [a, b] {
                if !coords.contains(&c.as_str()) || c.starts_with("pelvis") {
                    return Err(ModelError::invalid(
                        path,
                        format!("gait.symmetry[{i}]"),
                        format!(
                            "'{c}' is not a leg coordinate of the model ({})",
                            coords[3..].join(", ")
                        ),
                    ));
                }
                if used.contains(&c.as_str()) {
                    return Err(ModelError::invalid(
                        path,
                        format!("gait.symmetry[{i}]"),
                        format!("'{c}' appears in two pairs: a symmetry map must be a permutation"),
                    ));
                }
                used.push(c);
            }
            if a == b {
                return Err(ModelError::invalid(
                    path,
                    format!("gait.symmetry[{i}]"),
                    format!("pairs '{a}' with itself"),
                ));
            }
        }
        Ok(())
    }
}

impl InitialState {
    /// Check the lengths (nq positions and velocities, na activations) and ranges against
    /// `model`; `field` is the state's dotted path in `path` (e.g. `initial_state`).
    pub fn check(&self, model: &GaitModel, path: &Path, field: &str) -> Result<(), ModelError> {
        let coords = crate::model::gait::COORDINATES.join(", ");
        for (name, v, n) in [("q", &self.q, model.nq()), ("qd", &self.qd, model.nq())] {
            if v.len() != n {
                return Err(ModelError::invalid(
                    path,
                    format!("{field}.{name}"),
                    format!("has {} values, the model has {n} ({coords})", v.len()),
                ));
            }
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(ModelError::invalid(
                    path,
                    format!("{field}.{name}[{k}]"),
                    "must be finite",
                ));
            }
            let (limit, unit) = if name == "q" {
                (MAX_COORDINATE, "m or rad")
            } else {
                (MAX_VELOCITY, "m/s or rad/s")
            };
            if let Some(k) = v.iter().position(|x| x.abs() > limit) {
                return Err(ModelError::invalid(
                    path,
                    format!("{field}.{name}[{k}]"),
                    format!("{} is beyond the sensible limit; expected a magnitude of at most {} {unit}", show(v[k]), show(limit)),
                ));
            }
        }
        if let Some(a) = &self.a {
            if a.len() != model.na() {
                return Err(ModelError::invalid(
                    path,
                    format!("{field}.a"),
                    format!("has {} activations, the model has {}", a.len(), model.na()),
                ));
            }
            if let Some(k) = a
                .iter()
                .position(|x| !(x.is_finite() && (0.0..=1.0).contains(x)))
            {
                return Err(ModelError::invalid(
                    path,
                    format!("{field}.a[{k}]"),
                    format!("activation must be in [0, 1], got {}", a[k]),
                ));
            }
        }
        Ok(())
    }
}
