//! Phase sequences in JSON (`phases/`): ordered continuous phases (an active contact set
//! held for a duration) and instantaneous impact phases (the plastic impact map of the
//! contacts that are active after it), seed 001 §3.3.

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
        /// Number of shooting intervals (used by optimal control; ≥ 1).
        #[serde(default = "one_interval")]
        intervals: usize,
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
}

impl PhaseSequence {
    /// Read a phase file (structure only; see [`resolve`](Self::resolve)).
    pub fn load(path: &Path) -> Result<Self, ModelError> {
        let s: PhaseSequence = read_json(path)?;
        s.validate(path)?;
        Ok(s)
    }

    /// Structural checks that need no model.
    pub fn validate(&self, path: &Path) -> Result<(), ModelError> {
        if self.phases.is_empty() {
            return Err(ModelError::invalid(
                path,
                "phases",
                "the sequence has no phase; list at least one continuous phase",
            ));
        }
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
                if *intervals == 0 {
                    return Err(ModelError::invalid(
                        path,
                        f("intervals"),
                        "must be at least 1 shooting interval, got 0",
                    ));
                }
                let ok = match *duration {
                    Duration::Fixed(v) => v.is_finite() && v > 0.0,
                    Duration::Free { initial, min, max } => {
                        min.is_finite()
                            && max.is_finite()
                            && min > 0.0
                            && min <= initial
                            && initial <= max
                    }
                };
                if !ok {
                    return Err(ModelError::invalid(
                        path,
                        f("duration"),
                        format!(
                            "must be a positive number of seconds, or {{initial, min, max}} with 0 < min ≤ initial ≤ max; got {}",
                            match *duration {
                                Duration::Fixed(v) => format!("{v}"),
                                Duration::Free { initial, min, max } => format!("{{initial: {initial}, min: {min}, max: {max}}}"),
                            }
                        ),
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
                                known.join(", ")
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
                let list: Vec<(&str, bool)> = ph
                    .contacts()
                    .iter()
                    .map(|c| (c.contact.as_str(), c.rolling))
                    .collect();
                model
                    .constraint_set(ph.name(), &list)
                    .map_err(|r| ModelError::invalid(path, f("contacts".into()), r))
            })
            .collect()
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
