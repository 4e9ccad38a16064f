//! A gait OCP solution read back from the NLP variables and held against the
//! measurement: model and data side by side at the shooting nodes or on a fine grid, the
//! error channels of Millard & Mombaur (2019), Tables 3/4 (overall and phase by phase), and
//! the re-integration of every shooting interval on a 1 ms grid, where force transients
//! that fall between nodes show (their §5).

use super::errors::{ChannelErrors, ErrorStats};
use crate::controls::ControlTable;
use crate::data::{interp_linear, CubicSpline, DataError, GaitData};
use crate::integrate::{ControlShape, Integrator, IntegratorSettings};
use crate::model::gait::{ContactReport, COORDINATES};
use crate::model::{ConstraintSet, DynamicsError, GaitModel};
use crate::ocp::{Block, Transcription};
use crate::simulate::{PhaseSpan, Sample, SimulationError, SimulationOde, SimulationResult};
use serde::{Deserialize, Serialize};

/// One continuous phase of a solution.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct PhaseSolution {
    /// Phase name.
    pub name: String,
    /// Index of the phase in the phase file (and its constraint set).
    pub set: usize,
    /// Start time (s).
    pub t0: f64,
    /// Duration (s).
    pub duration: f64,
    /// Control parameterisation.
    pub controls: ControlShape,
    /// Node states `(q, q̇, a)`, `intervals + 1` rows.
    pub x: Vec<Vec<f64>>,
    /// Controls per control node.
    pub u: Vec<Vec<f64>>,
}

impl PhaseSolution {
    /// Number of shooting intervals.
    pub fn intervals(&self) -> usize {
        self.x.len() - 1
    }
    /// Time of node `k` (s).
    pub fn node_time(&self, k: usize) -> f64 {
        self.t0 + self.duration * k as f64 / self.intervals() as f64
    }
    /// Control at node `k` (the interval's control for piecewise-constant controls).
    pub fn node_control(&self, k: usize) -> &[f64] {
        &self.u[k.min(self.u.len() - 1)]
    }
    /// Controls over interval `k` as a table in physical time.
    fn interval_controls(&self, k: usize, names: &[String]) -> ControlTable {
        let u1 = match self.controls {
            ControlShape::Linear => self.u[k + 1].clone(),
            ControlShape::Constant => self.u[k].clone(),
        };
        ControlTable {
            names: names.to_vec(),
            times: vec![self.node_time(k), self.node_time(k + 1)],
            values: vec![self.u[k].clone(), u1],
        }
    }
}

/// A solution of a gait OCP: node states and controls of every continuous phase and the
/// free model parameters. Written to `solution.json` so that other runs can start from it.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct GaitSolution {
    /// Continuous phases in order.
    pub phases: Vec<PhaseSolution>,
    /// Free model parameters θ.
    pub theta: Vec<f64>,
}

impl GaitSolution {
    /// Read the solution from the NLP variables `w` of `tr`; `continuous[j]` is the phase
    /// file index of OCP phase `j`, and the first phase starts at `t0` (s).
    pub fn from_nlp(tr: &Transcription, w: &[f64], continuous: &[usize], t0: f64) -> Self {
        let ocp = tr.ocp();
        let mut t = t0;
        let mut phases = Vec::new();
        for (j, ph) in ocp.phases.iter().enumerate() {
            let duration = if ph.duration.is_free() {
                w[tr.range(Block::Duration { phase: j }).start]
            } else {
                ph.duration.value
            };
            let x = (0..=ph.intervals)
                .map(|k| w[tr.range(Block::State { phase: j, node: k })].to_vec())
                .collect();
            let u = (0..ph.control_nodes())
                .map(|k| w[tr.range(Block::Control { phase: j, node: k })].to_vec())
                .collect();
            phases.push(PhaseSolution {
                name: ph.name.clone(),
                set: continuous[j],
                t0: t,
                duration,
                controls: ph.controls,
                x,
                u,
            });
            t += duration;
        }
        Self {
            phases,
            theta: w[tr.range(Block::Params)].to_vec(),
        }
    }

    /// The controls at time `t` (s): interpolated between the control nodes of the phase
    /// holding `t` as the phase's parameterisation says (None outside the solution).
    pub fn control_at(&self, t: f64) -> Option<Vec<f64>> {
        let p = self
            .phases
            .iter()
            .find(|p| t >= p.t0 - 1e-12 && t <= p.t0 + p.duration + 1e-12)?;
        let n = p.intervals();
        let r = ((t - p.t0) / p.duration * n as f64).clamp(0.0, n as f64);
        let k = (r.floor() as usize).min(n - 1);
        match p.controls {
            ControlShape::Constant => Some(p.u[k.min(p.u.len() - 1)].clone()),
            ControlShape::Linear => {
                let f = r - k as f64;
                let (a, b) = (&p.u[k], &p.u[(k + 1).min(p.u.len() - 1)]);
                Some(a.iter().zip(b).map(|(a, b)| a + f * (b - a)).collect())
            }
        }
    }

    /// Start and end time (s).
    pub fn span(&self) -> (f64, f64) {
        let last = self.phases.last().map_or(0.0, |p| p.t0 + p.duration);
        (self.phases.first().map_or(0.0, |p| p.t0), last)
    }

    /// Phase spans for plots and tables.
    pub fn phase_spans(&self) -> Vec<PhaseSpan> {
        self.phases
            .iter()
            .map(|p| PhaseSpan {
                name: p.name.clone(),
                t0: p.t0,
                t1: p.t0 + p.duration,
                touchdown: None,
            })
            .collect()
    }

    /// The model evaluated at every shooting node (a node shared by two phases once, from
    /// the later phase: after the impact).
    pub fn node_samples(
        &self,
        model: &GaitModel,
        sets: &[ConstraintSet],
    ) -> Result<Vec<Sample>, DynamicsError> {
        let mut out = Vec::new();
        for (j, ph) in self.phases.iter().enumerate() {
            let last = j + 1 == self.phases.len();
            for k in 0..=ph.intervals() {
                if k == ph.intervals() && !last {
                    continue;
                }
                out.push(evaluate(
                    model,
                    &sets[ph.set],
                    ph.set,
                    ph.node_time(k),
                    &ph.x[k],
                    ph.node_control(k),
                    &self.theta,
                )?);
            }
        }
        Ok(out)
    }

    /// Re-integrate every shooting interval from its node state with its controls and
    /// sample the model every `step` seconds, at every node, and at the end of every
    /// phase before its impact (so jumps show). Each interval starts from its own node,
    /// as in the shooting transcription; the mismatch at the next node is reported as
    /// [`Reintegration::max_defect`].
    pub fn reintegrate(
        &self,
        model: &GaitModel,
        sets: &[ConstraintSet],
        step: f64,
        integrator: &IntegratorSettings,
    ) -> Result<Reintegration, SimulationError> {
        if !(step.is_finite() && step > 0.0) {
            return Err(SimulationError::Input(format!(
                "the output step must be positive, got {step}"
            )));
        }
        let (t0, t1) = self.span();
        let grid: Vec<f64> = (((t0 / step).ceil() as i64)..=((t1 / step).floor() as i64))
            .map(|i| i as f64 * step)
            .collect();
        self.integrate_intervals(model, sets, &grid, true, integrator)
    }

    /// The model at the strictly increasing `times` inside the solution's span, one sample
    /// per time (a time on a phase boundary is sampled after the impact), each interval
    /// integrated from its own node.
    pub fn sample_at(
        &self,
        model: &GaitModel,
        sets: &[ConstraintSet],
        times: &[f64],
        integrator: &IntegratorSettings,
    ) -> Result<Vec<Sample>, SimulationError> {
        let (t0, t1) = self.span();
        if let Some(t) = times
            .iter()
            .find(|&&t| !(t >= t0 - 1e-12 && t <= t1 + 1e-12))
        {
            return Err(SimulationError::Input(format!(
                "sample time {t} s is outside the solution's span {t0}–{t1} s"
            )));
        }
        if times.windows(2).any(|w| w[1] <= w[0]) {
            return Err(SimulationError::Input(
                "sample times must increase strictly".into(),
            ));
        }
        Ok(self
            .integrate_intervals(model, sets, times, false, integrator)?
            .result
            .samples)
    }

    /// Integrate every interval and sample at `times` (plus, with `with_nodes`, at the
    /// nodes and phase ends).
    fn integrate_intervals(
        &self,
        model: &GaitModel,
        sets: &[ConstraintSet],
        times: &[f64],
        with_nodes: bool,
        integrator: &IntegratorSettings,
    ) -> Result<Reintegration, SimulationError> {
        let first = self
            .phases
            .first()
            .map_or("", |p| p.name.as_str())
            .to_string();
        let mut int =
            Integrator::new(model.nx(), model.ntheta(), integrator.clone()).map_err(|e| {
                SimulationError::Integrator {
                    phase: first,
                    source: e,
                }
            })?;
        let names = model.control_names();
        let mut result = SimulationResult {
            samples: Vec::new(),
            impacts: Vec::new(),
            phases: self.phase_spans(),
            stats: Default::default(),
        };
        let mut max_defect = 0.0f64;
        let nx = model.nx();
        let tol = 1e-9;
        let np = self.phases.len();
        for (j, ph) in self.phases.iter().enumerate() {
            let set = &sets[ph.set];
            let dyn_err = |t: f64, e: DynamicsError| SimulationError::Dynamics {
                phase: ph.name.clone(),
                t,
                source: e,
            };
            let n = ph.intervals();
            for k in 0..n {
                let (a, b) = (ph.node_time(k), ph.node_time(k + 1));
                let last = j + 1 == np && k + 1 == n;
                // requested times in [a, b) (and b itself at the very end)
                let mut want: Vec<f64> = times
                    .iter()
                    .copied()
                    .filter(|&t| t >= a - tol && (t < b - tol || (last && t <= b + tol)))
                    .collect();
                let at_start = with_nodes || want.first().is_some_and(|&t| (t - a).abs() <= tol);
                if at_start {
                    result.samples.push(
                        evaluate(
                            model,
                            set,
                            ph.set,
                            a,
                            &ph.x[k],
                            ph.node_control(k),
                            &self.theta,
                        )
                        .map_err(|e| dyn_err(a, e))?,
                    );
                }
                want.retain(|&t| t > a + tol && t < b - tol);
                let with_end =
                    with_nodes && k + 1 == n || times.iter().any(|&t| last && (t - b).abs() <= tol);
                want.push(b);
                let controls = ph.interval_controls(k, &names);
                let ode = SimulationOde {
                    model,
                    set,
                    controls: &controls,
                };
                let mut out = Vec::new();
                result.stats += int
                    .integrate_dense(&ode, a, b, &ph.x[k], &self.theta, &want, &mut out)
                    .map_err(|e| SimulationError::Integrator {
                        phase: ph.name.clone(),
                        source: e,
                    })?;
                let mut u = vec![0.0; model.nu()];
                let keep = if with_end { want.len() } else { want.len() - 1 };
                for (i, &t) in want.iter().enumerate().take(keep) {
                    controls.at(t, &mut u);
                    let xi = &out[i * nx..(i + 1) * nx];
                    result.samples.push(
                        evaluate(model, set, ph.set, t, xi, &u, &self.theta)
                            .map_err(|e| dyn_err(t, e))?,
                    );
                }
                let end = &out[out.len() - nx..];
                let defect = end
                    .iter()
                    .zip(&ph.x[k + 1])
                    .map(|(p, q)| (p - q).abs())
                    .fold(0.0, f64::max);
                max_defect = max_defect.max(defect);
            }
        }
        Ok(Reintegration { result, max_defect })
    }
}

/// The model at one instant: state, foot loads and constraint details.
fn evaluate(
    model: &GaitModel,
    set: &ConstraintSet,
    phase: usize,
    t: f64,
    x: &[f64],
    u: &[f64],
    theta: &[f64],
) -> Result<Sample, DynamicsError> {
    let mut xdot = vec![0.0; model.nx()];
    let mut lam = vec![0.0; set.rows.len()];
    let mut rep = ContactReport::default();
    model.dynamics(set, x, u, theta, &mut xdot, &mut lam, Some(&mut rep))?;
    Ok(Sample {
        t,
        phase,
        x: x.to_vec(),
        feet: model.foot_loads(set, &rep),
        contact: rep,
    })
}

/// A solution re-integrated on a fine grid.
#[derive(Debug, Clone)]
pub struct Reintegration {
    /// Samples (with phase spans; no impacts: they sit between phases).
    pub result: SimulationResult,
    /// Largest |state difference| between an integrated interval end and the next node
    /// (the shooting defect at the integrator tolerance of the re-integration).
    pub max_defect: f64,
}

/// Figures of a fine-grid re-integration for the run summary.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub struct FineGridFigures {
    /// Output step (s).
    pub step_s: f64,
    /// Peak normal ground force of each foot, right and left (N).
    pub peak_normal_force_n: [f64; 2],
    /// Times of the peaks (s; None for a foot that never carries load).
    pub peak_normal_force_t: [Option<f64>; 2],
    /// Peak |tangential| ground force of each foot (N).
    pub peak_tangential_force_n: [f64; 2],
    /// Largest |φ| over the normal rows (m).
    pub max_position_drift_m: f64,
    /// Largest |G q̇| over all rows (m/s).
    pub max_velocity_drift_m_s: f64,
    /// Largest |Baumgarte force| (N).
    pub max_baumgarte_force_n: f64,
    /// Largest shooting defect (state units).
    pub max_defect: f64,
}

impl Reintegration {
    /// Summary figures.
    pub fn figures(&self, sets: &[ConstraintSet], step: f64) -> FineGridFigures {
        let r = &self.result;
        let mut f = FineGridFigures {
            step_s: step,
            peak_normal_force_n: [0.0; 2],
            peak_normal_force_t: [None; 2],
            peak_tangential_force_n: [0.0; 2],
            max_position_drift_m: r.max_position_drift(sets),
            max_velocity_drift_m_s: r.max_velocity_drift(sets),
            max_baumgarte_force_n: r.max_baumgarte_force(sets),
            max_defect: self.max_defect,
        };
        for s in &r.samples {
            for k in 0..2 {
                if s.feet[k].fy > f.peak_normal_force_n[k] {
                    f.peak_normal_force_n[k] = s.feet[k].fy;
                    f.peak_normal_force_t[k] = Some(s.t);
                }
                f.peak_tangential_force_n[k] = f.peak_tangential_force_n[k].max(s.feet[k].fx.abs());
            }
        }
        f
    }
}

/// Model and measurement side by side at a set of samples.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Sample times (s).
    pub times: Vec<f64>,
    /// Phase file index of each sample.
    pub phase: Vec<usize>,
    /// Model coordinates `[coordinate][sample]` (m, rad), in [`COORDINATES`] order.
    pub model_q: Vec<Vec<f64>>,
    /// Measured coordinates (cubic spline of the data).
    pub data_q: Vec<Vec<f64>>,
    /// Model generalised velocities `[coordinate][sample]` (m/s, rad/s).
    pub model_qd: Vec<Vec<f64>>,
    /// Measured velocities: the derivative of the data's spline, as the tracking cost's
    /// velocity targets.
    pub data_qd: Vec<Vec<f64>>,
    /// Model foot loads `[side][fx, fy, cop_x][sample]` (N, N, m); side 0 = right. The
    /// model CoP is NaN where the model foot carries less than the CoP threshold.
    pub model_feet: [[Vec<f64>; 3]; 2],
    /// Measured foot loads (linear interpolation of the samples; CoP NaN where unloaded).
    pub data_feet: [[Vec<f64>; 3]; 2],
    /// Normal force below which a CoP is undefined (N).
    pub cop_threshold: f64,
}

/// Foot load component names, in [`Comparison::model_feet`] order.
pub const LOAD_NAMES: [&str; 3] = ["grf_x", "grf_y", "cop_x"];

impl Comparison {
    /// Hold `samples` of the model against `data`.
    pub fn new(samples: &[Sample], data: &GaitData) -> Result<Self, DataError> {
        Self::with_offsets(
            samples,
            data,
            &crate::model::effects::MeasurementAdjust::identity(),
        )
    }

    /// Hold `samples` of the model against `data` through the measurement effects of
    /// `model` at parameters `theta` (the force plates read at t + clock offset, their
    /// CoP less the CoP offset), as the tracking cost compares them.
    pub fn through_model(
        samples: &[Sample],
        data: &GaitData,
        model: &crate::model::GaitModel,
        theta: &[f64],
    ) -> Result<Self, DataError> {
        let adj = model.measurement_adjust::<f64>(theta);
        Self::with_offsets(samples, data, &adj)
    }

    /// As [`new`](Self::new) with each foot's force plate read at t + its clock offset
    /// (s), its CoP offset (m) taken off its CoP and its forces divided by its gain
    /// (`offsets`, per foot); on a treadmill trial the CoP read at t + δ is taken back by
    /// the belt's displacement over δ.
    pub fn with_offsets(
        samples: &[Sample],
        data: &GaitData,
        offsets: &crate::model::effects::MeasurementAdjust<f64>,
    ) -> Result<Self, DataError> {
        let splines: Vec<CubicSpline> = COORDINATES
            .iter()
            .map(|c| data.spline(c))
            .collect::<Result<_, _>>()?;
        let times: Vec<f64> = samples.iter().map(|s| s.t).collect();
        let model_q = (0..9)
            .map(|i| samples.iter().map(|s| s.x[i]).collect())
            .collect();
        let data_q = splines
            .iter()
            .map(|sp| times.iter().map(|&t| sp.eval(t)).collect())
            .collect();
        let nq = COORDINATES.len();
        let model_qd = (0..nq)
            .map(|i| samples.iter().map(|s| s.x[nq + i]).collect())
            .collect();
        let data_qd = splines
            .iter()
            .map(|sp| times.iter().map(|&t| sp.derivative(t)).collect())
            .collect();
        let th = data.cop_threshold;
        let model_side = |k: usize| -> [Vec<f64>; 3] {
            [
                samples.iter().map(|s| s.feet[k].fx).collect(),
                samples.iter().map(|s| s.feet[k].fy).collect(),
                samples
                    .iter()
                    .map(|s| {
                        if s.feet[k].fy > th {
                            s.feet[k].cop_x
                        } else {
                            f64::NAN
                        }
                    })
                    .collect(),
            ]
        };
        // the forces at their own instants; NaN (not measured) propagates to the
        // neighbouring samples and leaves those entries out of the error tables
        let (force_time, force_feet) = data.force_record();
        // a treadmill trial's overground CoP holds the belt's displacement at each
        // sample's own instant: read δ later, it is δ·v further on than at the model's
        // instant (as the tracking cost takes it back, `MeasuredLoads::belt_speed`)
        let belt = if data.overground {
            data.belt_speed.unwrap_or(0.0)
        } else {
            0.0
        };
        let data_side = |k: usize| -> [Vec<f64>; 3] {
            let f = &force_feet[k];
            let plate_times: Vec<f64> = times
                .iter()
                .map(|t| t + offsets.force_time_offset[k])
                .collect();
            let gain = offsets.force_gain[k];
            let scaled = |v: Vec<f64>| v.into_iter().map(|x| x / gain).collect();
            [
                scaled(interp_linear(&plate_times, force_time, &f.fx)),
                scaled(interp_linear(&plate_times, force_time, &f.fy)),
                interp_linear(&plate_times, force_time, &f.cop_x)
                    .into_iter()
                    .map(|c| c - offsets.cop_offset[k] - offsets.force_time_offset[k] * belt)
                    .collect(),
            ]
        };
        Ok(Self {
            phase: samples.iter().map(|s| s.phase).collect(),
            model_q,
            data_q,
            model_qd,
            data_qd,
            model_feet: [model_side(0), model_side(1)],
            data_feet: [data_side(0), data_side(1)],
            cop_threshold: th,
            times,
        })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// The error channels of Millard & Mombaur 2019, Tables 3/4 (foot orientation, CoP, tangential and
    /// normal GRF, ankle, knee, hip), each as the signed error of the right leg's samples
    /// followed by the left's, in display units (°, cm, N). Ground forces count where
    /// the measured foot is loaded (above the CoP threshold); NaN marks samples where a
    /// channel is undefined.
    pub fn table_channels(&self) -> Vec<ErrorChannel> {
        let deg = 180.0 / std::f64::consts::PI;
        let n = self.len();
        let both = |f: &dyn Fn(usize, usize) -> f64| -> Vec<f64> {
            (0..2)
                .flat_map(|s| (0..n).map(move |k| (s, k)))
                .map(|(s, k)| f(s, k))
                .collect()
        };
        let foot = |q: &Vec<Vec<f64>>, s: usize, k: usize| {
            q[2][k] + q[3 + 3 * s][k] + q[4 + 3 * s][k] + q[5 + 3 * s][k]
        };
        let loaded = |s: usize, k: usize| self.data_feet[s][1][k] > self.cop_threshold;
        let load_err = |c: usize| {
            move |s: usize, k: usize| {
                if loaded(s, k) {
                    self.model_feet[s][c][k] - self.data_feet[s][c][k]
                } else {
                    f64::NAN
                }
            }
        };
        let joint = |j: usize| {
            move |s: usize, k: usize| deg * (self.model_q[j + 3 * s][k] - self.data_q[j + 3 * s][k])
        };
        vec![
            ErrorChannel::new(
                "foot orientation",
                "°",
                both(&|s, k| deg * (foot(&self.model_q, s, k) - foot(&self.data_q, s, k))),
            ),
            ErrorChannel::new(
                "CoP",
                "cm",
                both(&|s, k| 100.0 * (self.model_feet[s][2][k] - self.data_feet[s][2][k])),
            ),
            ErrorChannel::new("tangential GRF", "N", both(&load_err(0))),
            ErrorChannel::new("normal GRF", "N", both(&load_err(1))),
            ErrorChannel::new("ankle angle", "°", both(&joint(5))),
            ErrorChannel::new("knee angle", "°", both(&joint(4))),
            ErrorChannel::new("hip angle", "°", both(&joint(3))),
        ]
    }

    /// Phase file index of entry `i` of an [`ErrorChannel`] (right leg then left).
    pub fn channel_phase(&self, i: usize) -> usize {
        self.phase[i % self.len()]
    }
}

/// The signed error of one channel over samples (display units; NaN where undefined).
#[derive(Debug, Clone)]
pub struct ErrorChannel {
    /// Channel name.
    pub name: String,
    /// Display unit.
    pub unit: String,
    /// Signed errors (right leg's samples, then the left's).
    pub errors: Vec<f64>,
}

impl ErrorChannel {
    fn new(name: &str, unit: &str, errors: Vec<f64>) -> Self {
        Self {
            name: name.into(),
            unit: unit.into(),
            errors,
        }
    }

    /// Statistics of |error| over the entries `keep` selects (None: no defined entry).
    pub fn stats(&self, keep: impl Fn(usize) -> bool) -> Option<ErrorStats> {
        let e: Vec<f64> = self
            .errors
            .iter()
            .enumerate()
            .filter(|(i, v)| keep(*i) && v.is_finite())
            .map(|(_, v)| v.abs())
            .collect();
        (!e.is_empty()).then(|| ErrorStats::from_errors(&e))
    }
}

/// Table rows for `channels`: one column over all samples when `by_phase` is `None`,
/// otherwise one column per listed phase (phase file indices).
pub fn channel_errors(
    channels: &[ErrorChannel],
    comparison: &Comparison,
    by_phase: Option<&[usize]>,
) -> Vec<ChannelErrors> {
    channels
        .iter()
        .map(|c| ChannelErrors {
            name: c.name.clone(),
            unit: c.unit.clone(),
            decimals: 1,
            runs: match by_phase {
                None => vec![c.stats(|_| true)],
                Some(ph) => ph
                    .iter()
                    .map(|&p| c.stats(|i| comparison.channel_phase(i) == p))
                    .collect(),
            },
        })
        .collect()
}

/// What one residual actuator of a solution did, at the control nodes.
#[derive(Debug, Clone, Serialize)]
pub struct ResidualUse {
    /// Control name (`<coordinate>_residual`).
    pub name: String,
    /// `N` (pelvis translations) or `N·m`.
    pub unit: &'static str,
    /// Its bound: force or torque at control ±1.
    pub bound: f64,
    /// Root mean square over the nodes.
    pub rms: f64,
    /// Largest magnitude.
    pub peak: f64,
    /// Fraction of the nodes where it sits on its bound (|control| ≥ 0.999): there the
    /// model needed more than the residual could give, so the profile is a lower bound.
    pub at_bound_fraction: f64,
    /// Node times (s), for plots.
    #[serde(skip)]
    pub times: Vec<f64>,
    /// Values at those times (N or N·m).
    #[serde(skip)]
    pub values: Vec<f64>,
}

/// The residual actuators' profiles of `sol` and their figures (empty for a model
/// without residual actuators).
pub fn residual_use(model: &GaitModel, sol: &GaitSolution) -> Vec<ResidualUse> {
    let scales = model.residual_scales();
    let base = model.nu_actuators();
    let names: Vec<String> = model.control_names().into_iter().skip(base).collect();
    let mut times = Vec::new();
    let mut values = vec![Vec::new(); scales.len()];
    for ph in &sol.phases {
        for (k, u) in ph.u.iter().enumerate() {
            times.push(ph.node_time(k));
            for (i, s) in scales.iter().enumerate() {
                values[i].push(u[base + i] * s);
            }
        }
    }
    names
        .into_iter()
        .zip(values)
        .zip(scales)
        .enumerate()
        .map(|(i, ((name, v), &bound))| {
            let n = v.len().max(1) as f64;
            ResidualUse {
                name,
                unit: if i < 2 { "N" } else { "N·m" },
                bound,
                rms: (v.iter().map(|a| a * a).sum::<f64>() / n).sqrt(),
                peak: v.iter().fold(0.0f64, |m, a| m.max(a.abs())),
                at_bound_fraction: v.iter().filter(|a| a.abs() >= (1.0 - 1e-3) * bound).count()
                    as f64
                    / n,
                times: times.clone(),
                values: v,
            }
        })
        .collect()
}
