//! Why a problem could not be built: the walking-cycle, tracking and prediction problems
//! ([`ProblemError`]), the tracked half cycle ([`WindowError`]), a field of a JSON problem
//! file ([`FieldError`]), the CasADi gait peer's problem file ([`PeerGaitError`]), the
//! diagnosis's re-fits ([`DiagnoseError`]) and the foot fit ([`FootFitError`]).

use crate::data::DataError;
use crate::model::gait::COORDINATES;
use crate::model::{DynamicsError, ModelError};
use crate::ocp::TermError;
use crate::problems::check::CheckError;
use crate::simulate::SimulationError;
use crate::sqp::linearised::LinearisedError;
use std::path::PathBuf;
use std::sync::Arc;

/// Why a walking-cycle, tracking or prediction problem could not be built from its model,
/// phase file, data and settings.
#[derive(Debug, thiserror::Error)]
pub enum ProblemError {
    /// The constraint sets do not match the phases one to one.
    #[error("{sets} constraint sets for {phases} phases")]
    SetCount {
        /// Constraint sets given.
        sets: usize,
        /// Phases of the phase file.
        phases: usize,
    },
    /// The phase file has no continuous phase.
    #[error("the phase file has no continuous phase")]
    NoContinuousPhase,
    /// The initial guess has another number of phases than the phase file has continuous
    /// phases.
    #[error("the guess has {guess} phases, the file {phases} continuous phases")]
    GuessPhases {
        /// Phases of the guess.
        guess: usize,
        /// Continuous phases of the phase file.
        phases: usize,
    },
    /// A starting solution has another number of continuous phases than the phase graph.
    #[error(
        "the initial solution has {found} continuous phases, the phase graph '{graph}' {expected}"
    )]
    SolutionPhaseCount {
        /// Continuous phases of the solution.
        found: usize,
        /// Name of the phase graph.
        graph: String,
        /// Continuous phases of the phase graph.
        expected: usize,
    },
    /// A phase of a starting solution is not the phase graph's phase in its place.
    #[error("the initial solution's phase '{found}' ({found_intervals} intervals) does not match the phase graph's '{expected}' ({expected_intervals} intervals)")]
    SolutionPhase {
        /// The solution's phase name.
        found: String,
        /// Its shooting intervals.
        found_intervals: usize,
        /// The phase graph's phase name in that place.
        expected: String,
        /// Its shooting intervals.
        expected_intervals: usize,
    },
    /// A starting solution has more controls than the model.
    #[error("the initial solution has more controls than the model's {controls}")]
    SolutionControls {
        /// The model's controls.
        controls: usize,
    },
    /// A prediction's step length or speed is not finite, or its speed not positive.
    #[error("step length {step_length} m and speed {speed} m/s: need finite values and a positive speed")]
    StepOrSpeed {
        /// Step length (m).
        step_length: f64,
        /// Average forward speed (m/s).
        speed: f64,
    },
    /// A prediction's impulse weight is negative or not finite.
    #[error("impulse weight {weight}: need a finite value ≥ 0")]
    ImpulseWeight {
        /// The weight w_Δ given (N⁻²s⁻²).
        weight: f64,
    },
    /// A prediction's bound on the ankles' angular velocity is not positive.
    #[error("ankle angular velocity limit {limit} rad/s: need a positive value")]
    AnkleVelocityLimit {
        /// The bound given (rad/s).
        limit: f64,
    },
    /// The trial's force-plate surface is too far from the model's ground.
    #[error("the force-plate surface is at y = {} m (force_plate_surface_y_m of the meta file, or the force file's CoP height), but the model's ground (contact.ground_height) is at y = {} m; they may differ by at most {} mm: set the model's contact.ground_height to the plate surface", crate::limits::show(*.plate), crate::limits::show(*.ground), .max_gap * 1e3)]
    PlateHeight {
        /// Height of the plate surface (m).
        plate: f64,
        /// Height of the model's ground (m).
        ground: f64,
        /// Largest accepted distance between them (m).
        max_gap: f64,
    },
    /// The phase graph's sequence of loaded feet is not the measured one in the window.
    #[error("phase graph '{graph}' ({}) does not match the measured contacts between {start:.3} s and {end:.3} s ({})", stances(.phases), stances(.measured))]
    ContactsMismatch {
        /// Name of the phase graph.
        graph: String,
        /// The feet each group of its continuous phases loads, `[right, left]`.
        phases: Vec<[bool; 2]>,
        /// The feet each measured contact phase loads, `[right, left]`.
        measured: Vec<[bool; 2]>,
        /// Start of the window (s).
        start: f64,
        /// End of the window (s).
        end: f64,
    },
    /// A span that one-sided targets are read from holds too few samples.
    #[error("one-sided targets: {span} ({start:.4}–{end:.4} s) holds {samples} samples, fewer than {min}; sample faster or use interpolated targets")]
    TooFewSamples {
        /// The span.
        span: SampleSpan,
        /// Its start (s).
        start: f64,
        /// Its end (s).
        end: f64,
        /// Samples strictly inside it.
        samples: usize,
        /// The fewest accepted.
        min: usize,
    },
    /// The splines of a span that one-sided targets are read from could not be built.
    #[error("{span}: {source}")]
    SegmentSpline {
        /// The span.
        span: SampleSpan,
        /// Cause.
        #[source]
        source: DataError,
    },
    /// One-sided targets asked of a trial whose forces are not measured throughout.
    #[error("one-sided targets read the forces at the kinematic instants and need them measured throughout; where they are not, use interpolated or sample targets")]
    OneSidedForcesMissing,
    /// The data have no channel of a model coordinate.
    #[error("no channel {channel}")]
    NoChannel {
        /// The coordinate.
        channel: &'static str,
    },
    /// The data could not be projected onto a phase's contacts at a node.
    #[error("projecting the data at t = {time:.3} s: {source}")]
    Projection {
        /// Time of the node (s).
        time: f64,
        /// Cause.
        #[source]
        source: DynamicsError,
    },
    /// A solution could not be integrated to the instants of its samples.
    #[error("integrating to the samples: {source}")]
    Sampling {
        /// Cause.
        #[source]
        source: SimulationError,
    },
    /// A tracking residual could not be evaluated.
    #[error(transparent)]
    Residual(#[from] TermError),
    /// No half cycle to track.
    #[error(transparent)]
    Window(#[from] WindowError),
    /// The data are unusable.
    #[error(transparent)]
    Data(#[from] DataError),
    /// The trial's balance (for the start from the inverse dynamics) cannot be read.
    #[error(transparent)]
    Check(#[from] CheckError),
}

/// The span of samples that one-sided targets are read from.
#[derive(Debug, Clone, PartialEq)]
pub enum SampleSpan {
    /// The angles of a continuous phase: the samples between the impacts around it.
    BetweenImpacts {
        /// Name of the phase.
        phase: String,
    },
    /// The forces of a continuous phase: the samples strictly inside it.
    Phase {
        /// Name of the phase.
        phase: String,
    },
}

impl std::fmt::Display for SampleSpan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SampleSpan::BetweenImpacts { phase } => {
                write!(f, "the segment between the impacts around phase {phase}")
            }
            SampleSpan::Phase { phase } => write!(f, "phase {phase}"),
        }
    }
}

/// The loaded feet of each phase, `[right, left]`, as `double stance → right stance → …`.
fn stances(feet: &[[bool; 2]]) -> String {
    feet.iter()
        .map(|f| match f {
            [true, true] => "double stance",
            [true, false] => "right stance",
            [false, true] => "left stance",
            [false, false] => "flight",
        })
        .collect::<Vec<_>>()
        .join(" → ")
}

/// Why no half cycle (a left heel strike to the next right heel strike) of a trial can
/// be tracked as asked.
#[derive(Debug, thiserror::Error)]
pub enum WindowError {
    /// The events hold no left heel strike followed by a right heel strike.
    #[error("the data contain no left heel strike followed by a right heel strike (heel strikes right {:?}, left {:?} (s))", rounded(&.heel_strike[0]), rounded(&.heel_strike[1]))]
    NoHalfCycle {
        /// The heel strikes of the right and the left foot (s).
        heel_strike: [Vec<f64>; 2],
    },
    /// Every half cycle has a loaded foot without measured forces.
    #[error("no half cycle has both feet's forces measured where the phases load them; {}. Choose one by its window or stride to track it with those force terms left out", unmeasured(.gaps))]
    NoMeasuredHalfCycle {
        /// Each half cycle (start and end, s) and the loads not measured in it.
        gaps: Vec<((f64, f64), String)>,
    },
    /// No half cycle lies inside the window asked for.
    #[error("no half cycle (left heel strike to right heel strike) lies inside the window {start}–{end} s; the half cycles are {}", numbered(.half_cycles))]
    NotInWindow {
        /// Start of the window (s).
        start: f64,
        /// End of the window (s).
        end: f64,
        /// The trial's half cycles (start and end, s).
        half_cycles: Vec<(f64, f64)>,
    },
    /// The stride asked for is not among the trial's half cycles.
    #[error("stride {stride} does not exist: strides are numbered from 1 and the data hold {} half cycle(s) ({})", .half_cycles.len(), numbered(.half_cycles))]
    NoStride {
        /// The stride asked for (1-based).
        stride: usize,
        /// The trial's half cycles (start and end, s).
        half_cycles: Vec<(f64, f64)>,
    },
    /// The half cycle chosen on the plates' own clocks is not among the half cycles once
    /// the clocks are moved.
    #[error("the half cycle {:.3}–{:.3} s has no counterpart once the plates' clocks are moved by {:+.1} ms (right) and {:+.1} ms (left): its left heel strike would be near {target:.3} s, and the half cycles are then {:?}", .window.0, .window.1, 1e3 * .offsets[0], 1e3 * .offsets[1], rounded_pairs(.half_cycles))]
    NoCounterpart {
        /// The half cycle chosen (start and end, s).
        window: (f64, f64),
        /// The plates' clock offsets, right and left (s).
        offsets: [f64; 2],
        /// Where its left heel strike would be on the moved clocks (s).
        target: f64,
        /// The half cycles on the moved clocks (start and end, s).
        half_cycles: Vec<(f64, f64)>,
    },
    /// The events could not be detected.
    #[error(transparent)]
    Events(#[from] DataError),
}

/// Times rounded to the millisecond.
fn rounded(t: &[f64]) -> Vec<f64> {
    t.iter().map(|t| (t * 1e3).round() / 1e3).collect()
}

/// Spans rounded to the millisecond.
fn rounded_pairs(spans: &[(f64, f64)]) -> Vec<(f64, f64)> {
    spans
        .iter()
        .map(|&(a, b)| ((a * 1e3).round() / 1e3, (b * 1e3).round() / 1e3))
        .collect()
}

/// Half cycles as `1: a–b s, 2: …`, or `none`.
fn numbered(half_cycles: &[(f64, f64)]) -> String {
    if half_cycles.is_empty() {
        return "none".to_string();
    }
    half_cycles
        .iter()
        .enumerate()
        .map(|(i, (a, b))| format!("{}: {a:.3}–{b:.3} s", i + 1))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Half cycles with what is not measured in each, as `a–b s: why; …`.
fn unmeasured(gaps: &[((f64, f64), String)]) -> String {
    gaps.iter()
        .map(|((a, b), m)| format!("{a:.3}–{b:.3} s: {m}"))
        .collect::<Vec<_>>()
        .join("; ")
}

/// A field of a JSON problem file that is missing or of the wrong kind (the field as a
/// dotted path, array entries indexed: `bounds.x_lb[3]`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FieldError {
    /// The field is absent.
    #[error("field '{field}' missing")]
    Missing {
        /// The field.
        field: String,
    },
    /// The field is not of the kind expected.
    #[error("field '{field}' must be {expected}")]
    Kind {
        /// The field.
        field: String,
        /// What it must be, e.g. `a number`, `an array of numbers`.
        expected: &'static str,
    },
    /// The array has another number of entries than expected.
    #[error("field '{field}' has {found} entries, expected {expected}")]
    Length {
        /// The field.
        field: String,
        /// Entries found.
        found: usize,
        /// Entries expected.
        expected: usize,
    },
}

impl FieldError {
    /// The field at the JSON pointer `ptr` is absent.
    pub fn missing(ptr: &str) -> Self {
        FieldError::Missing { field: dotted(ptr) }
    }

    /// The field at the JSON pointer `ptr` is not `expected`.
    pub fn kind(ptr: &str, expected: &'static str) -> Self {
        FieldError::Kind {
            field: dotted(ptr),
            expected,
        }
    }
}

/// The JSON pointer `ptr` as a dotted field path (`/a/b` → `a.b`).
pub fn dotted(ptr: &str) -> String {
    ptr.trim_start_matches('/').replace('/', ".")
}

/// Why the CasADi gait peer's problem file (`gait_track_ellipse`) was refused.
#[derive(Debug, thiserror::Error)]
pub enum PeerGaitError {
    /// A field is missing or of the wrong kind.
    #[error(transparent)]
    Field(#[from] FieldError),
    /// The model, foot or phases the file names could not be loaded or resolved.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The model is not torque driven.
    #[error("field 'footfall.model': {} must be torque driven (\"actuators\": {{\"type\": \"joint_torques\"}}), as the problem is", .model.display())]
    NotTorqueDriven {
        /// The model file.
        model: PathBuf,
    },
    /// A foot's contact is not one of the model's.
    #[error("field 'footfall.contacts.{side}': the foot has no contact '{contact}'")]
    UnknownContact {
        /// The foot: `r` or `l`.
        side: &'static str,
        /// The contact named.
        contact: String,
    },
    /// A foot of a contact list is neither `r` nor `l`.
    #[error("field '{field}': feet are \"r\" or \"l\", got {foot}")]
    UnknownFoot {
        /// The contact list.
        field: String,
        /// The entry found.
        foot: serde_json::Value,
    },
    /// A phase's intervals are not a whole number ≥ 1.
    #[error("field 'phases[{phase}].intervals' must be a whole number ≥ 1")]
    Intervals {
        /// Index of the phase.
        phase: usize,
    },
    /// An impact after the end of the last phase.
    #[error("field 'transitions[{transition}]': an impact after the last phase's end")]
    ImpactAfterEnd {
        /// Index of the transition.
        transition: usize,
    },
    /// A transition of unknown type.
    #[error("field 'transitions[{transition}].type': unknown '{kind}' (initial, continuous, impact, terminal impact)")]
    UnknownTransition {
        /// Index of the transition.
        transition: usize,
        /// The type found.
        kind: String,
    },
    /// The phases do not make a phase sequence.
    #[error("phases: {source}")]
    Phases {
        /// Cause.
        #[source]
        source: serde_json::Error,
    },
    /// The initial guess has another number of nodes than the phases.
    #[error("field 'initial_guess.nodes.q' has {found} nodes, the phases {expected} (intervals + 1 each)")]
    GuessNodes {
        /// Nodes of the guess.
        found: usize,
        /// Nodes of the phases.
        expected: usize,
    },
    /// A cost node's phase is not a phase index.
    #[error("field 'references.phase[{node}]' must be a phase index")]
    PhaseIndex {
        /// Index of the cost node.
        node: usize,
    },
    /// The cost nodes per phase are not the phases' intervals.
    #[error("field 'references.phase': {found:?} cost nodes per phase, the phases have {intervals:?} intervals")]
    CostNodes {
        /// Cost nodes of each phase.
        found: Vec<usize>,
        /// Intervals of each phase.
        intervals: Vec<usize>,
    },
    /// The model's mass matrix or bias forces differ from the file's check values.
    #[error("the model of field 'footfall.model' is not the problem's body: its mass matrix differs from 'check_values.M' by {mass_matrix:.1e} and its bias forces from 'check_values.bias' by {bias:.1e} (relative; at most {tolerance:e} allowed)")]
    NotTheBody {
        /// Largest relative difference of the mass matrix.
        mass_matrix: f64,
        /// Largest relative difference of the bias forces.
        bias: f64,
        /// Largest relative difference accepted.
        tolerance: f64,
    },
    /// A tracked coordinate is not one of the model's.
    #[error("field 'cost.tracked': unknown coordinate '{coordinate}' (known: {})", COORDINATES.join(", "))]
    UnknownCoordinate {
        /// The coordinate named.
        coordinate: String,
    },
    /// The torque reference of the cost is not the model's torque unit.
    #[error("field 'cost.tau_ref_Nm' is {tau_ref} N·m, but the model's torque controls are in units of {unit} N·m (its 'reference_torque'): make them equal")]
    TorqueUnit {
        /// The file's torque reference (N·m).
        tau_ref: f64,
        /// The model's torque unit (N·m).
        unit: f64,
    },
}

/// Why a step of the diagnosis (a channel comparison, a Gauss–Newton re-fit, a reduced
/// Hessian probe) failed.
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    /// The solution's dynamics could not be evaluated at its nodes.
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// The solution could not be compared with the data.
    #[error(transparent)]
    Data(#[from] DataError),
    /// The Gauss–Newton model or one of its steps could not be computed (shared: the
    /// first step at a solution serves the score test and the identifiability probes).
    #[error(transparent)]
    GaussNewton(Arc<LinearisedError>),
    /// A probe of a parameter's information failed.
    #[error("probing the information of column {column}: {source}")]
    Probe {
        /// The variable probed.
        column: usize,
        /// Why the step with the shifted gradient failed.
        #[source]
        source: LinearisedError,
    },
    /// No probe of a parameter's information solved its QP.
    #[error("probing the information of column {column}: no QP solved")]
    ProbeUnsolved {
        /// The variable probed.
        column: usize,
    },
}

impl From<LinearisedError> for DiagnoseError {
    fn from(e: LinearisedError) -> Self {
        DiagnoseError::GaussNewton(Arc::new(e))
    }
}

impl From<Arc<LinearisedError>> for DiagnoseError {
    fn from(e: Arc<LinearisedError>) -> Self {
        DiagnoseError::GaussNewton(e)
    }
}

/// Why a foot could not be fitted to the measured stances.
#[derive(Debug, thiserror::Error)]
pub enum FootFitError {
    /// The foot as given cannot roll along the measured CoP.
    #[error("the foot cannot roll along the measured CoP")]
    CannotRoll,
    /// The fitted foot cannot roll along the measured CoP.
    #[error("the fitted foot cannot roll")]
    FittedCannotRoll,
    /// The Nelder–Mead search failed (its reason is the source).
    #[error("the Nelder–Mead search of the foot's shape failed")]
    Search(#[source] Box<dyn std::error::Error + Send + Sync + 'static>),
    /// The gait events could not be detected.
    #[error(transparent)]
    Events(#[from] DataError),
    /// The model has no foot body of that name.
    #[error("the model has no foot body '{body}'")]
    NoFootBody {
        /// The body's name.
        body: String,
    },
    /// The data contain no complete stance with a measured CoP.
    #[error("the data contain no complete stance (heel strike to toe-off) with a measured CoP")]
    NoStance,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The messages read as the inline texts they replace did.
    #[test]
    fn messages_read_as_the_texts_they_replace() {
        let e = ProblemError::ContactsMismatch {
            graph: "walk".into(),
            phases: vec![[true, true], [true, false]],
            measured: vec![[false, true]],
            start: 0.5,
            end: 1.0,
        };
        assert_eq!(
            e.to_string(),
            "phase graph 'walk' (double stance → right stance) does not match the measured contacts between 0.500 s and 1.000 s (left stance)"
        );
        let e = ProblemError::PlateHeight {
            plate: 0.05,
            ground: 0.0,
            max_gap: 0.01,
        };
        assert!(
            e.to_string()
                .starts_with("the force-plate surface is at y = 0.05 m (force_plate_surface_y_m")
                && e.to_string()
                    .contains("at y = 0 m; they may differ by at most 10 mm"),
            "{e}"
        );
        let e = WindowError::NotInWindow {
            start: 0.0,
            end: 0.4,
            half_cycles: vec![(0.6, 1.2), (1.2, 1.8)],
        };
        assert_eq!(
            e.to_string(),
            "no half cycle (left heel strike to right heel strike) lies inside the window 0–0.4 s; the half cycles are 1: 0.600–1.200 s, 2: 1.200–1.800 s"
        );
        let e = WindowError::NoStride {
            stride: 3,
            half_cycles: vec![],
        };
        assert_eq!(
            e.to_string(),
            "stride 3 does not exist: strides are numbered from 1 and the data hold 0 half cycle(s) (none)"
        );
        let e = ProblemError::TooFewSamples {
            span: SampleSpan::Phase {
                phase: "SS_R".into(),
            },
            start: 0.1,
            end: 0.2,
            samples: 2,
            min: 4,
        };
        assert!(
            e.to_string().starts_with(
                "one-sided targets: phase SS_R (0.1000–0.2000 s) holds 2 samples, fewer than 4"
            ),
            "{e}"
        );
        assert_eq!(
            FieldError::kind("/bounds/x_lb", "an array").to_string(),
            "field 'bounds.x_lb' must be an array"
        );
    }
}
