//! The measurement against itself: the trial's whole-body Newton–Euler balance, read
//! before any contact model is fitted.
//!
//! Measured motion and measured loads must satisfy $\sum_b m_b a_b = \sum_s F_s + m g$ and
//! $\dot H_c = \sum_s (p_{cop,s} - c) \times F_s$ for the whole body ([`balance`]), with no
//! contact model and no optimal control. Each instrument or body error leaves its own
//! signature in the residual wrench: a plate's clock shifts its loads in time, a gain
//! scales one plate's loads, a CoP offset adds $d F_y$ of one plate to the moment, a mass
//! error scales the body's side, a trunk offset adds $m_t (a - g) \times d$, a slope
//! tilts gravity against the plates' normal. [`check`] reads them by forward stepwise
//! least squares ([`stepwise`], [`fit`]): at each step, of the candidates beyond their
//! band, the one that explains most of the residual is read jointly with those already
//! found; a reading is beyond its band when its distance from what untouched trials read
//! ([`NULL`]) exceeds its Newey–West standard deviation and their spread, in quadrature,
//! by the Bonferroni-corrected point of the stated family-wise level. Residual
//! thresholds labs use are checked before and after ([`thresholds`]); implausible units
//! and signs are refused first ([`plausibility`]).

pub mod balance;
pub mod fit;
pub mod footing;
pub mod plausibility;
pub mod signals;
pub mod stepwise;
pub mod thresholds;

pub use balance::{Param, NPARAM};
pub use stepwise::{BASELINE, MIN_PLATE_SHARE};
pub use thresholds::Thresholds;

use crate::data::{DataError, GaitData};
use crate::model::{GaitModel, Side};
use balance::{Body, Instant};
use fit::{Fit, Problem};
use signals::Signals;
use std::path::PathBuf;

/// Why the balance cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// The trial's data are unusable.
    #[error(transparent)]
    Data(#[from] DataError),
    /// The cutoff is not below the kinematics' Nyquist rate.
    #[error("filter cutoff {cutoff_hz} Hz: expected a frequency above 0 and below {limit_hz:.1} Hz (0.8 × the kinematics' Nyquist rate)")]
    Cutoff {
        /// The cutoff asked for (Hz).
        cutoff_hz: f64,
        /// The largest accepted (Hz).
        limit_hz: f64,
    },
    /// A coordinate has missing samples.
    #[error("coordinate '{coordinate}' has missing (NaN) samples: the balance needs the whole body's motion at every instant")]
    Kinematics {
        /// The coordinate.
        coordinate: &'static str,
    },
    /// The model has no trunk body.
    #[error("the model has no trunk body 'hat'")]
    NoTrunk,
    /// The trunk was asked to move by the trial's lumbar angle, and the model does not
    /// describe its trunk above the lumbar joint.
    #[error("{}: its body does not describe the trunk above the lumbar joint (explicit segments do not; an OpenSim model summary with a torso body or de Leva's tables do): the trunk cannot follow the trial's lumbar_extension", path.display())]
    NoTorso {
        /// The model file.
        path: PathBuf,
    },
    /// The trunk was asked to move by the trial's lumbar angle, and the trial does not
    /// measure it at every kinematic instant.
    #[error("{}: column 'lumbar_extension' is missing or has missing (NaN) samples: the trunk can follow the trial's lumbar angle only where it is measured at every kinematic instant", path.display())]
    NoLumbar {
        /// The trial's file.
        path: PathBuf,
    },
    /// A foot has no measured loads at all.
    #[error("{}: the {} foot has no measured load: the balance needs both feet's ground forces (a foot in swing reads 0 N, a foot off the plates NaN)", path.display(), foot_word(*side))]
    Forces {
        /// The trial's file.
        path: PathBuf,
        /// The foot without loads.
        side: Side,
    },
    /// The data cannot be right as declared (units, signs, the body's mass).
    #[error(transparent)]
    Implausible(#[from] Implausible),
    /// Too few instants where both feet's loads are known.
    #[error("only {instants} force samples ({seconds:.3} s) have both feet's loads known inside the motion (the balance needs both feet's loads at once, and {margin_s} s of margin at either end for the filter and any clock shift); at least {needed} are needed")]
    TooShort {
        /// Instants available.
        instants: usize,
        /// Their span (s).
        seconds: f64,
        /// The margin (s).
        margin_s: f64,
        /// Instants needed.
        needed: usize,
    },
}

/// Why a trial's forces cannot belong to the model's body ([`gate`], [`check`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Implausible {
    /// The body mass the vertical forces imply lies more than
    /// [`plausibility::MASS_REFUSED`] from the model's.
    #[error("{}: the vertical forces imply a body of {implied_kg:.1} kg, the model's is {model_kg:.1} kg ({:+.0} %): the forces are in another unit, belong to another subject, or the model does (give the subject's model with --model)", path.display(), 100.0 * (implied_kg / model_kg - 1.0))]
    Mass {
        /// The trial's file.
        path: PathBuf,
        /// The mass the vertical forces imply (kg).
        implied_kg: f64,
        /// The model's mass (kg).
        model_kg: f64,
    },
    /// The model posed by the trial's coordinates holds a loaded foot's ankle outside
    /// [`footing::ANKLE_REFUSED`] above the floor in mid-stance: the body file is
    /// not the trial's subject's, or (where that ankle lies above the swinging foot's)
    /// the loads are the other foot's.
    #[error("{}", footing::refusal(path, model, *side, *ankle_height, *other_height))]
    Footing {
        /// The trial's file.
        path: PathBuf,
        /// The model file.
        model: PathBuf,
        /// The loaded foot.
        side: Side,
        /// Median height of its ankle joint centre above the floor in mid-stance (m).
        ankle_height: f64,
        /// Median height of the other foot's ankle joint centre at the same instants (m).
        other_height: f64,
    },
    /// The horizontal ground force runs against the body's horizontal acceleration.
    #[error("{}: columns 'grf_x_r', 'grf_x_l': the horizontal ground force runs against the body's horizontal acceleration (correlation {correlation:.2}); footfall reads grf_x as the ground's force on the foot, + forward: the sign looks flipped", path.display())]
    HorizontalSign {
        /// The trial's file.
        path: PathBuf,
        /// Correlation of the horizontal force with the body's mass times its
        /// horizontal acceleration (below −0.5).
        correlation: f64,
    },
}

/// `right` or `left`.
fn foot_word(side: Side) -> &'static str {
    match side {
        Side::Right => "right",
        Side::Left => "left",
    }
}

/// How the balance is read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckSettings {
    /// Low-pass cutoff of kinematics and loads alike (Hz; 6 by default, a common choice
    /// for walking).
    pub cutoff_hz: f64,
    /// Family-wise significance level of the stepwise reading (0.05 by default).
    pub level: f64,
    /// Newey–West bandwidth (s): the residual's correlation time after smoothing and the
    /// body model's own error (0.2 s by default, about a double support).
    pub bandwidth_s: f64,
    /// Largest plate clock read (s) and the margin kept at either end of the loads.
    pub clock_limit_s: f64,
    /// What untouched trials read as each candidate, in θ order ([`NULL`]): readings are
    /// judged by their distance from the centres, the spread added in quadrature to the
    /// reading's Newey–West standard deviation.
    pub null: [NullBand; NPARAM],
    /// Whether the HAT's trunk above the lumbar joint follows the trial's
    /// `lumbar_extension` ([`crate::model::torso`]) rather than staying frozen as in the
    /// model the solvers use (false by default: [`NULL`] is calibrated with the rigid
    /// HAT).
    pub lumbar: bool,
}

/// What untouched recordings read as one candidate: a centre and the spread of their
/// readings about it. A reading is judged by its distance from the centre, in its own
/// Newey–West deviation and the spread in quadrature: the body model, the filter and a
/// lab's usual timing read as a few milliseconds of clock or millimetres of CoP on every
/// trial, and that is the baseline, not a finding.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct NullBand {
    /// Centre (the parameter's unit).
    pub mean: f64,
    /// Spread of the untouched readings about the centre, their own noise included (the
    /// parameter's unit).
    pub sd: f64,
}

const fn band(mean: f64, sd: f64) -> NullBand {
    NullBand { mean, sd }
}

/// Each candidate's [`NullBand`] over the untouched half cycles of the shipped recordings
/// (three subjects, four recordings, their bundled body models; `tools/calibrate-check`
/// recomputes it), in θ order: the spread the root mean square of the readings about the
/// centre. The centre is zero but for both plates' clock, which every recording reads
/// late (3–8 ms, half-cycle means by recording) whatever its lab, capture system and rate:
/// a lag of the method, not of a lab's plates ([`Param::look_alikes`]), centred on the
/// mean of the recordings' means. Every other candidate's recordings disagree in sign or
/// size; centred on their own means too, the bands read more edits but, each recording
/// checked with the bands of the others, find more than the level allows on untouched
/// half cycles. A lab with its own untouched trials gives its centres with `--null`.
pub const NULL: [NullBand; NPARAM] = [
    band(0.00557703, 0.00539358), // both plates' clock (s)
    band(0.0, 0.00333183),        // right plate's clock (s)
    band(0.0, 0.00223616),        // left plate's clock (s)
    band(0.0, 0.00789044),        // right plate's gain
    band(0.0, 0.0129663),         // left plate's gain
    band(0.0, 0.0526399),         // right plate's CoP offset (m)
    band(0.0, 0.0389741),         // left plate's CoP offset (m)
    band(0.0, 0.0087835),         // body mass
    band(0.0, 0.079492),          // trunk's centre of mass (m)
    band(0.0, 0.0),               // trunk's mass (kg)
    band(0.0, 0.00996167),        // ground slope (rad)
];

impl Default for CheckSettings {
    fn default() -> Self {
        Self {
            cutoff_hz: 6.0,
            level: 0.05,
            bandwidth_s: 0.2,
            clock_limit_s: 0.06,
            null: NULL,
            lumbar: false,
        }
    }
}

/// What a candidate's reading says.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case", tag = "verdict")]
pub enum Verdict {
    /// Read beyond its threshold: the measurement carries it.
    Found,
    /// Within its noise band.
    NotSignificant,
    /// Its signature is (nearly) a combination of effects already found.
    NotSeparable {
        /// The found effects it cannot be told from.
        from: Vec<Param>,
    },
    /// Read beside every candidate as the trial's baseline ([`BASELINE`]), never tested:
    /// untouched trials read it as widely as any effect would move it.
    Baseline,
    /// The data cannot read it (e.g. a plate that carries no load in the window).
    NotTestable {
        /// Why.
        reason: String,
    },
}

impl Verdict {
    /// In words.
    pub fn text(&self) -> String {
        match self {
            Verdict::Found => "found".into(),
            Verdict::NotSignificant => "not significant".into(),
            Verdict::NotSeparable { from } if from.is_empty() => {
                "not separable from the effects already found together".into()
            }
            Verdict::NotSeparable { from } => format!(
                "not separable from {}",
                from.iter()
                    .map(|p| p.label())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            Verdict::Baseline => "read as the baseline, not tested".into(),
            Verdict::NotTestable { reason } => format!("not testable: {reason}"),
        }
    }
}

/// One candidate's reading.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Reading {
    /// The candidate.
    pub param: Param,
    /// Estimate (the parameter's unit).
    pub estimate: f64,
    /// Standard deviation: the Newey–West one and the untouched trials' spread in
    /// quadrature.
    pub sd: f64,
    /// The Newey–West standard deviation alone (the window's own noise).
    pub sd_within: f64,
    /// The estimate's distance from the untouched trials' centre, in `sd`.
    pub z: f64,
    /// What untouched trials read as it: the band the reading is judged against.
    pub baseline: NullBand,
    /// The |z| it had to exceed.
    pub threshold: f64,
    /// Share of the residual's weighted sum of squares it explains when added.
    pub explained: f64,
    /// The verdict.
    pub verdict: Verdict,
    /// For a found candidate: the others that were beyond the band at the same step when
    /// read in its place, `(candidate, estimate, z)`: what these data cannot tell it from.
    pub alternatives: Vec<(Param, f64, f64)>,
}

impl Reading {
    /// The smallest effect this reading would call found, as a distance from what
    /// untouched trials read (the parameter's unit): the threshold times the reading's
    /// sd. An effect this size or smaller may be there unseen; NaN where the candidate
    /// was not tested.
    pub fn smallest_found(&self) -> f64 {
        self.threshold * self.sd
    }
}

/// The balance of one trial, read.
#[derive(Debug, Clone)]
pub struct MeasurementCheck {
    /// Instants read (s).
    pub time: Vec<f64>,
    /// Residual wrench with nothing corrected `[N, N, N·m]`.
    pub before: Vec<[f64; 3]>,
    /// Residual wrench with the found effects corrected (nothing else).
    pub after: Vec<[f64; 3]>,
    /// Every candidate's reading, found first in the order found.
    pub readings: Vec<Reading>,
    /// Every testable candidate read alone (the first step), as the calibration of
    /// [`NULL`] uses them.
    pub alone: Vec<Reading>,
    /// The final joint fit of the found effects.
    pub fit: Fit,
    /// The leg joints' inverse dynamics over the whole trial, as measured, at each
    /// instant read (empty for a window of the trial).
    pub joints: Vec<JointKinetics>,
    /// The labs' thresholds before and after correction.
    pub thresholds: [Thresholds; 2],
    /// The model's mass (kg) and the mass the vertical forces imply over the window.
    pub mass: (f64, f64),
    /// Whole-body linear momentum (N·s, x and y) and angular momentum about the centre of
    /// mass (N·m·s) at each instant.
    pub momentum: Vec<[f64; 3]>,
    /// The force record's rate (Hz) and the kinematics' (Hz).
    pub rates: (f64, f64),
    /// What the plausibility checks say short of refusing the trial.
    pub warnings: Vec<String>,
    /// The kinematics' first and last instants (s): the motion the instants read lie in.
    pub motion: (f64, f64),
    /// The residual thresholds as measured over the whole trial with the trunk above the
    /// lumbar joint frozen in the HAT and moving by the trial's lumbar angle, where the
    /// model describes that trunk and the trial measures the angle: how much of the
    /// residual the body model's rigid trunk leaves. `None` for a window of the trial.
    pub trunk: Option<[Thresholds; 2]>,
}

/// Where the balance was read: its first and last instants (s), how many there are, and
/// the gaps between them longer than two force samples (no force known for a foot).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coverage {
    /// First instant read (s).
    pub first: f64,
    /// Last instant read (s).
    pub last: f64,
    /// Instants read.
    pub samples: usize,
    /// Gaps inside `[first, last]` longer than two force samples.
    pub gaps: usize,
    /// Their total length (s).
    pub gap_s: f64,
}

impl MeasurementCheck {
    /// Where the balance was read.
    pub fn coverage(&self) -> Coverage {
        let step = 2.0 / self.rates.0;
        let (mut gaps, mut gap_s) = (0, 0.0);
        for w in self.time.windows(2) {
            if w[1] - w[0] > step {
                gaps += 1;
                gap_s += w[1] - w[0];
            }
        }
        Coverage {
            first: self.time.first().copied().unwrap_or(f64::NAN),
            last: self.time.last().copied().unwrap_or(f64::NAN),
            samples: self.time.len(),
            gaps,
            gap_s,
        }
    }

    /// The readings found, in the order found.
    pub fn found(&self) -> impl Iterator<Item = &Reading> {
        self.readings.iter().filter(|r| r.verdict == Verdict::Found)
    }
}

/// Read the balance of `data` (coordinates of `model`) over `[t0, t1]` (the whole trial
/// when `None`).
pub fn check(
    data: &GaitData,
    model: &GaitModel,
    settings: &CheckSettings,
    window: Option<(f64, f64)>,
) -> Result<MeasurementCheck, CheckError> {
    let (signals, body) = balance_inputs(data, model, settings)?;
    let instants = balance_instants(&signals, &body, settings, window)?;
    let problem = Problem::new(&body, &signals, &instants, settings).weighted();
    let mass = (body.mass(), implied_mass(&problem));
    let mut warnings =
        plausibility::check_balance(data, mass.0, mass.1, horizontal_correlation(&problem))?;
    warnings.extend(footing::check_footing(data, model)?);
    if settings.lumbar && settings.null == NULL {
        warnings.push(
            "the trunk follows the trial's lumbar angle, and the shipped bands are calibrated with the rigid HAT: the readings' verdicts are approximate (give bands of untouched trials checked with --lumbar: --null)"
                .into(),
        );
    }
    let (readings, alone, fit) = stepwise::read(&problem, settings);
    let zero = [0.0; NPARAM];
    let before = problem.linearise(&zero, &[]).r;
    let mut corrected = zero;
    for r in readings.iter().filter(|r| r.verdict == Verdict::Found) {
        corrected[r.param.index()] = r.estimate;
    }
    let after = problem.linearise(&corrected, &[]).r;
    let thresholds = [
        Thresholds::of(&before, &problem),
        Thresholds::of(&after, &problem),
    ];
    let momentum = instants.iter().map(|at| body.momentum(at)).collect();
    // properties of the body model over the trial, not repeated for each window of it
    let (trunk, joints) = match window {
        None => (
            trunk_rocking(model, &signals, settings)?,
            joint_kinetics(&body, &signals, model, &instants),
        ),
        Some(_) => (None, vec![]),
    };
    Ok(MeasurementCheck {
        time: instants.iter().map(|i| i.t).collect(),
        before,
        after,
        readings,
        alone,
        fit,
        thresholds,
        mass,
        momentum,
        rates: (signals.force_rate, signals.kinematic_rate),
        warnings,
        motion: (
            data.time.first().copied().unwrap_or(f64::NAN),
            data.time.last().copied().unwrap_or(f64::NAN),
        ),
        trunk,
        joints,
    })
}

/// The leg joints' inverse dynamics at one instant: the coordinates after the pelvis's,
/// in [`crate::model::gait::COORDINATES`] order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointKinetics {
    /// Time (s).
    pub t: f64,
    /// Each joint's torque, in its coordinate's positive sense (N·m).
    pub torque: [f64; 6],
    /// Each joint's power, its torque times its angular velocity (W): positive where the
    /// joint's torque does work on the body.
    pub power: [f64; 6],
}

impl JointKinetics {
    /// Index of the first leg joint's coordinate among the model's: the pelvis's three
    /// come first.
    const FIRST: usize = 3;

    /// The leg joints' coordinate names, in the order of `torque` and `power`.
    pub fn names() -> &'static [&'static str] {
        &crate::model::gait::COORDINATES[Self::FIRST..]
    }
}

/// The leg joints' inverse dynamics at each instant read, as measured
/// ([`balance::inverse_dynamics`]).
fn joint_kinetics(
    body: &Body,
    signals: &Signals,
    model: &GaitModel,
    instants: &[Instant],
) -> Vec<JointKinetics> {
    instants
        .iter()
        .filter_map(|at| {
            let tau = balance::inverse_dynamics(body, signals, model, at.t)?;
            let (_, qd, _) = signals.motion(at.t);
            let first = JointKinetics::FIRST;
            Some(JointKinetics {
                t: at.t,
                torque: std::array::from_fn(|j| tau[first + j]),
                power: std::array::from_fn(|j| tau[first + j] * qd[first + j]),
            })
        })
        .collect()
}

/// The residual thresholds as measured over the whole trial with the HAT's trunk frozen
/// and moving by the trial's lumbar angle; `None` where the model does not describe the
/// trunk or the trial does not measure the angle.
fn trunk_rocking(
    model: &GaitModel,
    signals: &Signals,
    settings: &CheckSettings,
) -> Result<Option<[Thresholds; 2]>, CheckError> {
    let Some(moving) = Body::with_torso(model).transpose()? else {
        return Ok(None);
    };
    if !moving.moves_trunk(signals) {
        return Ok(None);
    }
    let as_measured = |body: &Body| -> Result<Thresholds, CheckError> {
        let instants = balance_instants(signals, body, settings, None)?;
        let problem = Problem::new(body, signals, &instants, settings);
        Ok(Thresholds::of(
            &problem.linearise(&[0.0; NPARAM], &[]).r,
            &problem,
        ))
    };
    Ok(Some([
        as_measured(&Body::of(model)?)?,
        as_measured(&moving)?,
    ]))
}

/// Whether the trial's forces can belong to the body of `model`, as the measurement
/// check judges them before it reads anything (the mass the vertical forces imply within
/// 25 % of the model's, the horizontal force not running against the body's
/// acceleration, the model posed by the trial's coordinates standing each loaded foot on
/// the floor: [`footing::check_footing`]): the gate a solve passes before it
/// starts. `Ok` holds the warnings (a mass more than 10 % off, an ankle height near the
/// limits); `Err(CheckError::Implausible)` refuses the trial; any other
/// error says that the balance cannot be read on this trial (a foot without forces, too
/// short), and so cannot judge it.
pub fn gate(
    data: &GaitData,
    model: &GaitModel,
    settings: &CheckSettings,
) -> Result<Vec<String>, CheckError> {
    let (signals, body) = balance_inputs(data, model, settings)?;
    let instants = balance_instants(&signals, &body, settings, None)?;
    let problem = Problem::new(&body, &signals, &instants, settings);
    let mut warnings = plausibility::check_balance(
        data,
        body.mass(),
        implied_mass(&problem),
        horizontal_correlation(&problem),
    )?;
    warnings.extend(footing::check_footing(data, model)?);
    Ok(warnings)
}

/// The trial's filtered signals and the model's segments, once both feet are known to
/// carry loads.
fn balance_inputs(
    data: &GaitData,
    model: &GaitModel,
    settings: &CheckSettings,
) -> Result<(Signals, Body), CheckError> {
    for (s, side) in [(0, Side::Right), (1, Side::Left)] {
        let (_, feet) = data.force_record();
        if !feet[s].fy.iter().any(|v| v.is_finite() && v.abs() > 0.0) {
            return Err(CheckError::Forces {
                path: data.source.clone(),
                side,
            });
        }
    }
    let signals = Signals::new(data, settings.cutoff_hz, settings.clock_limit_s)?;
    let body = if settings.lumbar {
        let body = Body::with_torso(model).ok_or_else(|| CheckError::NoTorso {
            path: model.source().to_path_buf(),
        })??;
        if !body.moves_trunk(&signals) {
            return Err(CheckError::NoLumbar {
                path: data.source.clone(),
            });
        }
        body
    } else {
        Body::of(model)?
    };
    Ok((signals, body))
}

/// The instants inside `window` (all when `None`) where both feet's loads are known,
/// enough of them for the balance to be read.
fn balance_instants(
    signals: &Signals,
    body: &Body,
    settings: &CheckSettings,
    window: Option<(f64, f64)>,
) -> Result<Vec<Instant>, CheckError> {
    let instants: Vec<Instant> = signals
        .instants
        .iter()
        .filter(|&&t| window.is_none_or(|(a, b)| t >= a && t <= b))
        .map(|&t| body.instant(signals, t))
        .collect();
    let needed = (0.25 * signals.force_rate).ceil() as usize;
    if instants.len() < needed.max(20) {
        let seconds = match (instants.first(), instants.last()) {
            (Some(a), Some(b)) => b.t - a.t,
            _ => 0.0,
        };
        return Err(CheckError::TooShort {
            instants: instants.len(),
            seconds,
            margin_s: settings.clock_limit_s,
            needed: needed.max(20),
        });
    }
    Ok(instants)
}

/// Correlation of the measured horizontal ground force with the body's Σ m aₓ.
fn horizontal_correlation(p: &Problem) -> f64 {
    let zero = [0.0; NPARAM];
    let pairs: Vec<(f64, f64)> = p
        .instants
        .iter()
        .filter_map(|at| {
            let m = balance::measured(p.signals, at, &zero)?;
            Some((m[0], p.body.required(at, &zero)[0]))
        })
        .collect();
    let n = pairs.len() as f64;
    let (mx, my) = pairs
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in &pairs {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
    }
    sxy / (sxx * syy).sqrt()
}

/// The mass (kg) that makes the vertical balance hold on average over the instants:
/// Σ F_y / Σ (a_y + g) of the body's centre of mass.
fn implied_mass(p: &Problem) -> f64 {
    let zero = [0.0; NPARAM];
    let (mut f, mut a) = (0.0, 0.0);
    for at in p.instants {
        let req = p.body.required(at, &zero);
        if let Some(m) = balance::measured(p.signals, at, &zero) {
            f += m[1];
            a += req[1] / p.body.mass();
        }
    }
    f / a
}
