//! Node targets and the initial guess of a tracking: splines of the data (through all the
//! samples, or one-sided per phase), read at the shooting nodes, and the data projected onto
//! the contacts.

use super::{loaded_feet, TargetSides};
use crate::data::{interp_linear, CubicSpline, GaitData};
use crate::model::gait::COORDINATES;
use crate::model::{ConstraintSet, GaitModel, Side};
use crate::phases::{Phase, PhaseSequence};
use crate::problems::error::{ProblemError, SampleSpan};
use crate::problems::tracking::NodeTarget;

/// The fewest samples a phase (forces) or an impact-to-impact segment (angles) must hold
/// for one-sided targets.
pub const MIN_SEGMENT_SAMPLES: usize = 4;

/// Splines of `columns` through the samples strictly inside `(a, b)` (low-passed at
/// `cutoff_hz` first, if given); `what` names the span in errors.
fn segment_splines(
    data: &GaitData,
    columns: &[&[f64]],
    (a, b): (f64, f64),
    cutoff_hz: Option<f64>,
    what: SampleSpan,
) -> Result<Vec<CubicSpline>, ProblemError> {
    let idx: Vec<usize> = (0..data.time.len())
        .filter(|&k| data.time[k] > a + 1e-9 && data.time[k] < b - 1e-9)
        .collect();
    if idx.len() < MIN_SEGMENT_SAMPLES {
        return Err(ProblemError::TooFewSamples {
            span: what,
            start: a,
            end: b,
            samples: idx.len(),
            min: MIN_SEGMENT_SAMPLES,
        });
    }
    let t: Vec<f64> = idx.iter().map(|&k| data.time[k]).collect();
    let fs = (t.len() - 1) as f64 / (t[t.len() - 1] - t[0]);
    columns
        .iter()
        .map(|col| {
            let y: Vec<f64> = idx.iter().map(|&k| col[k]).collect();
            let y = match cutoff_hz {
                Some(fc) => crate::data::filter::low_pass(&y, fs, fc),
                None => y,
            };
            CubicSpline::new(&t, &y).map_err(|source| ProblemError::SegmentSpline {
                span: what.clone(),
                source,
            })
        })
        .collect()
}

/// One foot's measured forces as splines over the measured stretch that overlaps the
/// tracked window most (all of the record when nothing is missing).
#[derive(Clone)]
pub(super) struct ForceTrack {
    pub(super) fx: CubicSpline,
    pub(super) fy: CubicSpline,
    /// The stretch (s); node targets outside it have no force terms for this foot.
    stretch: (f64, f64),
}

impl ForceTrack {
    pub(super) fn new(
        data: &GaitData,
        s: usize,
        (t0, t1): (f64, f64),
    ) -> Result<Self, ProblemError> {
        let (time, feet) = data.force_record();
        let f = &feet[s];
        if f.fx.iter().chain(&f.fy).all(|v| v.is_finite()) {
            return Ok(Self {
                fx: CubicSpline::new(time, &f.fx)?,
                fy: CubicSpline::new(time, &f.fy)?,
                stretch: (f64::NEG_INFINITY, f64::INFINITY),
            });
        }
        let overlap = |(a, b): (f64, f64)| (b.min(t1) - a.max(t0)).max(0.0);
        let best = data
            .measured_stretches([Side::Right, Side::Left][s])
            .into_iter()
            .filter(|&(a, b)| {
                let k = time.iter().filter(|&&t| t >= a && t <= b).count();
                k >= 4 && b > a
            })
            .max_by(|x, y| overlap(*x).total_cmp(&overlap(*y)));
        let Some((a, b)) = best else {
            // never measured: zero splines that no target reads (every node is outside
            // the empty stretch)
            let z = vec![0.0; data.time.len()];
            let zs = CubicSpline::new(&data.time, &z)?;
            return Ok(Self {
                fx: zs.clone(),
                fy: zs,
                stretch: (f64::INFINITY, f64::NEG_INFINITY),
            });
        };
        let idx: Vec<usize> = (0..time.len())
            .filter(|&k| time[k] >= a && time[k] <= b && f.fx[k].is_finite())
            .collect();
        let t: Vec<f64> = idx.iter().map(|&k| time[k]).collect();
        let pick = |v: &[f64]| idx.iter().map(|&k| v[k]).collect::<Vec<f64>>();
        Ok(Self {
            fx: CubicSpline::new(&t, &pick(&f.fx))?,
            fy: CubicSpline::new(&t, &pick(&f.fy))?,
            stretch: (t[0], t[t.len() - 1]),
        })
    }

    /// Whether `t` (s) lies in the measured stretch (to 1e-9 s).
    fn covers(&self, t: f64) -> bool {
        t >= self.stretch.0 - 1e-9 && t <= self.stretch.1 + 1e-9
    }
}

/// The warnings for the feet that are loaded but miss their CoP inside `(t0, t1)`: there
/// they track the forces only.
pub(super) fn cop_gap_notes(data: &GaitData, (t0, t1): (f64, f64)) -> Vec<String> {
    let mut notes = Vec::new();
    let cop_gaps = data.cop_missing_while_loaded();
    for (s, gaps) in cop_gaps.iter().enumerate() {
        let inside: Vec<f64> = gaps
            .iter()
            .copied()
            .filter(|&t| t >= t0 && t <= t1)
            .collect();
        if let (Some(a), Some(b)) = (inside.first(), inside.last()) {
            notes.push(format!(
                "warning: the {} foot is loaded but its CoP is missing at {} sample(s) between {a:.3} and {b:.3} s; there it tracks the forces only",
                ["right", "left"][s],
                inside.len()
            ));
        }
    }
    notes
}

/// What the node targets and the initial guess are read from.
pub(super) struct NodeSource<'d> {
    pub(super) model: &'d GaitModel,
    /// The constraint set of every phase of the phase file.
    pub(super) sets: &'d [ConstraintSet],
    pub(super) data: &'d GaitData,
    pub(super) sides: TargetSides,
    /// The tracked window (s).
    pub(super) window: (f64, f64),
    /// Splines of the coordinates through all the samples.
    pub(super) splines: &'d [CubicSpline],
    /// Each foot's measured forces (right, left).
    pub(super) tracks: &'d [ForceTrack; 2],
    /// The feet's tangential forces as splines (right, left).
    pub(super) fx: &'d [CubicSpline; 2],
    /// The feet's normal forces as splines (right, left).
    pub(super) fy: &'d [CubicSpline; 2],
    /// The model's parameters.
    pub(super) theta: Vec<f64>,
}

/// Node times, node targets and the initial guess, per continuous phase.
pub(super) struct Nodes {
    /// Node times (s).
    pub(super) times: Vec<Vec<f64>>,
    /// Node targets.
    pub(super) targets: Vec<Vec<NodeTarget>>,
    /// Initial guess of the states at the nodes.
    pub(super) x: Vec<Vec<Vec<f64>>>,
    /// Initial guess of the controls at the control nodes.
    pub(super) u: Vec<Vec<Vec<f64>>>,
}

impl NodeSource<'_> {
    /// The nodes of the continuous phases of `seq` (durations fixed, the first starting at
    /// the window's start): their times, targets and initial guess, the data projected onto
    /// the contacts (activations 0.01, excitations 0.025, joint torques and residual
    /// actuators 0).
    pub(super) fn nodes(&self, seq: &PhaseSequence) -> Result<Nodes, ProblemError> {
        let (t0, t1) = self.window;
        let mut node_times = Vec::new();
        let mut targets = Vec::new();
        let mut gx = Vec::new();
        let mut gu = Vec::new();
        let mut t = t0;
        let linear = seq
            .gait
            .as_ref()
            .is_none_or(|g| g.controls == crate::integrate::ControlShape::Linear);
        // the impacts' times (with the window's ends), where one-sided angle segments break
        let mut impacts = vec![t0];
        let mut at = t0;
        for ph in &seq.phases {
            match ph {
                Phase::Impact { .. } => impacts.push(at),
                Phase::Continuous { duration, .. } => at += duration.value(),
            }
        }
        impacts.push(t1);
        for (i, ph) in seq.phases.iter().enumerate() {
            let Phase::Continuous {
                name,
                duration,
                intervals,
                ..
            } = ph
            else {
                continue;
            };
            let h = duration.value() / *intervals as f64;
            let one_sided = match self.sides {
                TargetSides::Interpolated | TargetSides::Samples => None,
                TargetSides::OneSided { cutoff_hz } => Some(self.one_sided_splines(
                    name,
                    (t, t + duration.value()),
                    &impacts,
                    cutoff_hz,
                )?),
            };
            let (splines, fx, fy): (&[CubicSpline], &[CubicSpline], &[CubicSpline]) =
                match &one_sided {
                    Some((a, x, y)) => (a, x, y),
                    None => (self.splines, self.fx, self.fy),
                };
            let times: Vec<f64> = (0..=*intervals).map(|k| t + k as f64 * h).collect();
            let (tg, xs) = self.phase_nodes(i, &times, (splines, fx, fy))?;
            let cn = if linear { *intervals + 1 } else { *intervals };
            // excitations 0.025; joint torques and residual actuators 0
            let excitations = if self.model.na() > 0 {
                self.model.nu_actuators()
            } else {
                0
            };
            let mut u0 = vec![0.025; self.model.nu()];
            u0[excitations..].iter_mut().for_each(|v| *v = 0.0);
            gu.push(vec![u0; cn]);
            gx.push(xs);
            targets.push(tg);
            node_times.push(times);
            t += duration.value();
        }
        Ok(Nodes {
            times: node_times,
            targets,
            x: gx,
            u: gu,
        })
    }

    /// One-sided splines of the continuous phase `name` spanning `(t, end)`: the angles
    /// from the samples between the neighbouring `impacts`, low-passed at `cutoff_hz`, and
    /// the forces from the samples strictly inside the phase.
    #[allow(clippy::type_complexity)]
    fn one_sided_splines(
        &self,
        name: &str,
        (t, end): (f64, f64),
        impacts: &[f64],
        cutoff_hz: Option<f64>,
    ) -> Result<(Vec<CubicSpline>, Vec<CubicSpline>, Vec<CubicSpline>), ProblemError> {
        let (data, (t0, t1)) = (self.data, self.window);
        if data.feet.iter().any(|f| f.fy.iter().any(|v| v.is_nan())) {
            return Err(ProblemError::OneSidedForcesMissing);
        }
        let a = impacts
            .iter()
            .copied()
            .filter(|&x| x <= t + 1e-9)
            .fold(t0, f64::max);
        let b = impacts
            .iter()
            .copied()
            .filter(|&x| x >= end - 1e-9)
            .fold(t1, f64::min);
        let angles: Vec<&[f64]> = COORDINATES
            .iter()
            .map(|&c| {
                data.channel(c)
                    .ok_or(ProblemError::NoChannel { channel: c })
            })
            .collect::<Result<_, _>>()?;
        let between = SampleSpan::BetweenImpacts {
            phase: name.to_string(),
        };
        let angles = segment_splines(data, &angles, (a, b), cutoff_hz, between)?;
        let (f, phase) = (
            &data.feet,
            SampleSpan::Phase {
                phase: name.to_string(),
            },
        );
        let fx = segment_splines(data, &[&f[0].fx, &f[1].fx], (t, end), None, phase.clone())?;
        let fy = segment_splines(data, &[&f[0].fy, &f[1].fy], (t, end), None, phase)?;
        Ok((angles, fx, fy))
    }

    /// The targets and initial states at the node `times` of the continuous phase with
    /// constraint set `i`, read from the angle `splines` and the force splines `fx`, `fy`
    /// (right, left); the states are the data projected onto the contacts, activations
    /// 0.01.
    #[allow(clippy::type_complexity)]
    fn phase_nodes(
        &self,
        i: usize,
        times: &[f64],
        (splines, fx, fy): (&[CubicSpline], &[CubicSpline], &[CubicSpline]),
    ) -> Result<(Vec<NodeTarget>, Vec<Vec<f64>>), ProblemError> {
        let (model, data, sets) = (self.model, self.data, self.sets);
        let (nq, na) = (model.nq(), model.na());
        let untracked = NodeTarget {
            time: 0.0,
            q: vec![None; nq],
            qd: vec![None; nq],
            feet: [None, None],
        };
        let feet = loaded_feet(model, &sets[i]);
        let mut tg = Vec::new();
        let mut xs = Vec::new();
        for &tk in times {
            let q: Vec<f64> = splines.iter().map(|s| s.eval(tk)).collect();
            let qd: Vec<f64> = splines.iter().map(|s| s.derivative(tk)).collect();
            let foot_target = |s: usize| {
                // a foot whose force was not measured here loses its force terms
                (feet[s] && self.tracks[s].covers(tk)).then(|| {
                    let fyv = fy[s].eval(tk);
                    (
                        fx[s].eval(tk),
                        fyv,
                        if fyv >= data.cop_threshold {
                            self.cop_at(s, tk)
                        } else {
                            None
                        },
                    )
                })
            };
            tg.push(if self.sides == TargetSides::Samples {
                NodeTarget {
                    time: tk,
                    ..untracked.clone()
                }
            } else {
                NodeTarget {
                    time: tk,
                    q: q.iter().map(|v| Some(*v)).collect(),
                    qd: qd.iter().map(|v| Some(*v)).collect(),
                    feet: [foot_target(0), foot_target(1)],
                }
            });
            let (qp, qdp, _) = model
                .project(&sets[i], &q, &qd, &self.theta)
                .map_err(|source| ProblemError::Projection { time: tk, source })?;
            let mut x = qp;
            x.extend(qdp);
            x.extend(vec![0.01; na]);
            xs.push(x);
        }
        Ok((tg, xs))
    }

    /// The measured CoP of foot `s` at `t` (s), linearly interpolated where the foot is
    /// loaded.
    fn cop_at(&self, s: usize, t: f64) -> Option<f64> {
        let (force_time, force_feet) = self.data.force_record();
        // linear interpolation of the measured CoP where the foot is loaded
        let v = interp_linear(&[t], force_time, &force_feet[s].cop_x)[0];
        v.is_finite().then_some(v)
    }
}

/// The state bounds of a tracking: the data's range ± 1 (m, rad) and ± 1 (m/s, rad/s)
/// beyond the measured velocities (Millard & Mombaur 2019, §3.3, the velocities from the
/// coordinates' `splines`); knee hyper-extension up to 0.1 rad; activations in [0, 1].
pub(super) fn state_bounds(
    model: &GaitModel,
    data: &GaitData,
    splines: &[CubicSpline],
) -> (Vec<f64>, Vec<f64>) {
    let nq = model.nq();
    // bounds: the data's range ± 1 (m, rad) and ± 1 (m/s, rad/s) beyond the measured
    // velocities (Millard & Mombaur 2019, §3.3); knee hyper-extension up to 0.1 rad; a, u in [0, 1]
    let (mut x_lb, mut x_ub) = (vec![0.0; model.nx()], vec![0.0; model.nx()]);
    for i in 0..nq {
        let (lo, hi) = data.q[i]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let sp = &splines[i];
        let (dlo, dhi) = data
            .time
            .iter()
            .map(|&tt| sp.derivative(tt))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        x_lb[i] = lo - 1.0;
        x_ub[i] = hi + 1.0;
        x_lb[nq + i] = dlo - 1.0;
        x_ub[nq + i] = dhi + 1.0;
    }
    for i in [4, 7] {
        x_ub[i] = 0.1;
    }
    for i in 2 * nq..model.nx() {
        x_lb[i] = 0.0;
        x_ub[i] = 1.0;
    }
    (x_lb, x_ub)
}
