//! The generic benchmark problems of the CasADi peer's problem files (copies in
//! `problems/`), transcribed exactly as defined there: N equal intervals, piecewise-constant controls, objective
//! `h Σ_k |u_k|²`, bounds and path constraints at the N + 1 nodes, the same initial guess.

use super::{biped, CartPole, FiveLinkBiped, ParameterError};
use crate::integrate::{ControlShape, IntegratorSettings};
use crate::model::ad::dense_hessian;
use crate::ocp::{Block, Constraint, Ocp, Phase, PhaseDuration, Term};
use crate::problems::error::{dotted, FieldError, PeerGaitError, ProblemError};
use crate::problems::peer_gait::PeerGaitTrack;
use crate::problems::{FnTerm, Linear};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Why a problem file was refused; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ProblemFileError {
    /// The file could not be read.
    #[error("cannot read problem file {path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// The file is not valid JSON.
    #[error("problem file {path} is not valid JSON: {source}")]
    Json {
        /// File.
        path: PathBuf,
        /// Cause (with line and column).
        source: serde_json::Error,
    },
    /// The problem is unknown or a field is missing or invalid.
    #[error("{path}: {source}")]
    Invalid {
        /// File.
        path: PathBuf,
        /// What is wrong (names the field).
        source: BenchmarkError,
    },
}

/// Why a benchmark problem (a problem file's JSON) cannot be built: an unknown problem, a
/// field missing or invalid, or its optimal control problem refused.
#[derive(Debug, thiserror::Error)]
pub enum BenchmarkError {
    /// A field is missing or of the wrong kind.
    #[error(transparent)]
    Field(#[from] FieldError),
    /// The model's physical parameters are missing or invalid.
    #[error(transparent)]
    Parameters(#[from] ParameterError),
    /// The CasADi gait peer's problem is refused.
    #[error(transparent)]
    PeerGait(#[from] PeerGaitError),
    /// The gait peer's walking cycle or its optimal control problem cannot be built.
    #[error(transparent)]
    Problem(#[from] ProblemError),
    /// The problem's name is none of the known problems'.
    #[error("field 'name': unknown problem '{name}' (known: cartpole_swingup, five_link_biped, {GAIT_TRACK})")]
    UnknownProblem {
        /// The name found.
        name: String,
    },
    /// The gait peer's problem was given without the path it resolves its files against.
    #[error("{GAIT_TRACK} names its model files relative to the problem file: load it with Benchmark::load")]
    NeedsPath,
    /// The gait peer's OCP was asked for on its own, without the walking cycle it borrows.
    #[error("the {GAIT_TRACK} OCP borrows its walking cycle: use Benchmark::with_ocp")]
    BorrowsCycle,
    /// The number of shooting intervals is not a whole number in range.
    #[error(
        "field 'discretization.N' must be a whole number of intervals from 1 to {max}, got {value}"
    )]
    Intervals {
        /// The number found.
        value: f64,
        /// The most accepted.
        max: usize,
    },
    /// The horizon is not a duration in range.
    #[error("field 'horizon.T' must be a duration > 0 and ≤ {} s, got {}", crate::limits::show(*.max), crate::limits::show(*.value))]
    Horizon {
        /// The horizon found (s).
        value: f64,
        /// The longest accepted (s).
        max: f64,
    },
    /// A lower bound is above its upper bound.
    #[error("field 'bounds.{kind}_ub[{index}]' ({}) is below 'bounds.{kind}_lb[{index}]' ({}): the lower bound must be at most the upper one", crate::limits::show(*.upper), crate::limits::show(*.lower))]
    CrossedBounds {
        /// The bounded variables: `x` (states) or `u` (controls).
        kind: &'static str,
        /// Index of the entry.
        index: usize,
        /// The lower bound.
        lower: f64,
        /// The upper bound.
        upper: f64,
    },
}

/// The `name` of the CasADi gait peer's tracking problem.
pub const GAIT_TRACK: &str = "gait_track_ellipse";

/// A benchmark model with its problem definition.
pub enum Benchmark {
    /// Cart-pole swing-up.
    CartPole {
        /// Model.
        model: CartPole,
        /// Problem JSON.
        json: Value,
    },
    /// Five-link biped, one periodic step.
    Biped {
        /// Model.
        model: FiveLinkBiped,
        /// Problem JSON.
        json: Value,
    },
    /// The CasADi gait peer's torque-driven tracking of one measured cycle
    /// (`gait_track_ellipse`).
    GaitTrack(Box<PeerGaitTrack>),
}

fn num(v: &Value, ptr: &str) -> Result<f64, FieldError> {
    v.pointer(ptr)
        .ok_or_else(|| FieldError::missing(ptr))?
        .as_f64()
        .ok_or_else(|| FieldError::kind(ptr, "a number"))
}

/// Most shooting intervals a problem file may ask for: far more than any of these problems
/// needs, and few enough that the transcription's vectors can be allocated.
pub const MAX_INTERVALS: usize = 100_000;

/// The number of shooting intervals `discretization.N`: a whole number from 1 to
/// [`MAX_INTERVALS`].
fn intervals(v: &Value) -> Result<usize, BenchmarkError> {
    let n = num(v, "/discretization/N")?;
    if !(n >= 1.0 && n <= MAX_INTERVALS as f64 && n.fract() == 0.0) {
        return Err(BenchmarkError::Intervals {
            value: n,
            max: MAX_INTERVALS,
        });
    }
    Ok(n as usize)
}

/// Longest horizon a problem file may ask for (s).
pub const MAX_HORIZON: f64 = 1e4;

/// The horizon `horizon.T`: finite, > 0 and at most [`MAX_HORIZON`] s.
fn horizon(v: &Value) -> Result<f64, BenchmarkError> {
    let t = num(v, "/horizon/T")?;
    if !(t > 0.0 && t <= MAX_HORIZON) {
        return Err(BenchmarkError::Horizon {
            value: t,
            max: MAX_HORIZON,
        });
    }
    Ok(t)
}

/// Lower and upper bounds `bounds.{kind}_lb`, `bounds.{kind}_ub` of `len` entries (null:
/// unbounded), each lower bound at most its upper one.
fn bounds(
    v: &Value,
    kind: &'static str,
    len: usize,
) -> Result<(Vec<f64>, Vec<f64>), BenchmarkError> {
    let lb = vecn(v, &format!("/bounds/{kind}_lb"), len)?;
    let ub = vecn(v, &format!("/bounds/{kind}_ub"), len)?;
    if let Some(i) = (0..len).find(|&i| lb[i] > ub[i]) {
        return Err(BenchmarkError::CrossedBounds {
            kind,
            index: i,
            lower: lb[i],
            upper: ub[i],
        });
    }
    Ok((bound(lb, f64::NEG_INFINITY), bound(ub, f64::INFINITY)))
}

fn vecn(v: &Value, ptr: &str, len: usize) -> Result<Vec<f64>, FieldError> {
    let a = v
        .pointer(ptr)
        .ok_or_else(|| FieldError::missing(ptr))?
        .as_array()
        .ok_or_else(|| FieldError::kind(ptr, "an array"))?;
    if a.len() != len {
        return Err(FieldError::Length {
            field: dotted(ptr),
            found: a.len(),
            expected: len,
        });
    }
    // null = unbounded
    a.iter()
        .enumerate()
        .map(|(i, x)| {
            if x.is_null() {
                Ok(f64::NAN)
            } else {
                x.as_f64().ok_or_else(|| FieldError::Kind {
                    field: format!("{}[{i}]", dotted(ptr)),
                    expected: "a number",
                })
            }
        })
        .collect()
}

fn bound(v: Vec<f64>, inf: f64) -> Vec<f64> {
    v.into_iter()
        .map(|x| if x.is_nan() { inf } else { x })
        .collect()
}

impl Benchmark {
    /// Read a problem file (e.g. `problems/cartpole_swingup.json`) and build its model;
    /// the fields of the optimal control problem are checked too (by building it once), so
    /// that [`ocp`](Self::ocp) succeeds on what this returns.
    pub fn load(path: &Path) -> Result<Self, ProblemFileError> {
        let text = std::fs::read_to_string(path).map_err(|source| ProblemFileError::Io {
            path: path.into(),
            source,
        })?;
        let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
        let json: Value = serde_json::from_str(text).map_err(|source| ProblemFileError::Json {
            path: path.into(),
            source,
        })?;
        let invalid = |source| ProblemFileError::Invalid {
            path: path.into(),
            source,
        };
        let bench = match json.get("name").and_then(Value::as_str) {
            Some(GAIT_TRACK) => Benchmark::GaitTrack(Box::new(
                PeerGaitTrack::from_json(&json, path)
                    .map_err(|e| invalid(BenchmarkError::from(e)))?,
            )),
            _ => Self::from_json(json).map_err(invalid)?,
        };
        bench
            .with_ocp(IntegratorSettings::default(), |_| ())
            .map_err(invalid)?;
        Ok(bench)
    }

    /// Call `f` with the OCP of the problem with CVODES settings `integrator` (the gait
    /// problem's OCP borrows a walking cycle built here, so it is lent, not returned).
    pub fn with_ocp<R>(
        &self,
        integrator: IntegratorSettings,
        f: impl FnOnce(&Ocp<'_>) -> R,
    ) -> Result<R, BenchmarkError> {
        match self {
            Benchmark::GaitTrack(g) => {
                let cycle = g.cycle()?;
                let ocp = g.ocp(&cycle, integrator)?;
                Ok(f(&ocp))
            }
            _ => Ok(f(&self.ocp(integrator)?)),
        }
    }

    /// Recognise a generic problem by its `name` and build its model (the gait problem
    /// names model files relative to its own: [`load`](Self::load) it).
    pub fn from_json(json: Value) -> Result<Self, BenchmarkError> {
        match json.get("name").and_then(Value::as_str) {
            Some("cartpole_swingup") => Ok(Benchmark::CartPole {
                model: CartPole::from_problem_json(&json)?,
                json,
            }),
            Some("five_link_biped") => Ok(Benchmark::Biped {
                model: FiveLinkBiped::from_problem_json(&json)?,
                json,
            }),
            Some(GAIT_TRACK) => Err(BenchmarkError::NeedsPath),
            Some(other) => Err(BenchmarkError::UnknownProblem {
                name: other.to_string(),
            }),
            None => Err(FieldError::missing("/name").into()),
        }
    }

    /// Problem name.
    pub fn name(&self) -> &'static str {
        match self {
            Benchmark::CartPole { .. } => "cartpole_swingup",
            Benchmark::Biped { .. } => "five_link_biped",
            Benchmark::GaitTrack(_) => GAIT_TRACK,
        }
    }

    /// The OCP with CVODES settings `integrator`, for the generic problems; the gait
    /// problem's OCP is lent by [`with_ocp`](Self::with_ocp).
    pub fn ocp(&self, integrator: IntegratorSettings) -> Result<Ocp<'_>, BenchmarkError> {
        match self {
            Benchmark::CartPole { model, json } => cartpole(model, json, integrator),
            Benchmark::Biped { model, json } => five_link_biped(model, json, integrator),
            Benchmark::GaitTrack(_) => Err(BenchmarkError::BorrowsCycle),
        }
    }
}

fn u_squared_terms(n: usize, nu: usize, h: f64) -> Vec<Term<'static>> {
    let w = h.sqrt();
    let f = Arc::new(Linear::new(
        (0..nu * nu)
            .map(|k| if k / nu == k % nu { w } else { 0.0 })
            .collect(),
        nu,
    ));
    (0..n)
        .map(|k| Term {
            name: "u_squared".into(),
            args: vec![Block::Control { phase: 0, node: k }],
            f: f.clone(),
        })
        .collect()
}

fn cartpole<'a>(
    model: &'a CartPole,
    json: &Value,
    integrator: IntegratorSettings,
) -> Result<Ocp<'a>, BenchmarkError> {
    let n = intervals(json)?;
    let t = horizon(json)?;
    let xi = vecn(json, "/boundary/x_initial", 4)?;
    let xf = vecn(json, "/boundary/x_final", 4)?;
    let (u_lb, u_ub) = bounds(json, "u", 1)?;
    let (x_lb, x_ub) = bounds(json, "x", 4)?;
    let mut xl = vec![x_lb; n + 1];
    let mut xu = vec![x_ub; n + 1];
    xl[0] = xi.clone();
    xu[0] = xi.clone();
    xl[n] = xf.clone();
    xu[n] = xf.clone();
    let x_guess = (0..=n)
        .map(|k| {
            (0..4)
                .map(|i| xi[i] + k as f64 / n as f64 * (xf[i] - xi[i]))
                .collect()
        })
        .collect();
    Ok(Ocp {
        phases: vec![Phase {
            name: "swing_up".into(),
            ode: model,
            intervals: n,
            duration: PhaseDuration::fixed(t),
            controls: ControlShape::Constant,
            x_lb: xl,
            x_ub: xu,
            u_lb: vec![u_lb; n],
            u_ub: vec![u_ub; n],
            x_guess,
            u_guess: vec![vec![0.0]; n],
        }],
        transitions: vec![],
        ntheta: 0,
        theta_guess: vec![],
        theta_lb: vec![],
        theta_ub: vec![],
        constraints: vec![],
        least_squares: u_squared_terms(n, 1, t / n as f64),
        samples: Vec::new(),
        checks: Vec::new(),
        costs: vec![],
        integrator,
    })
}

fn five_link_biped<'a>(
    model: &'a FiveLinkBiped,
    json: &Value,
    integrator: IntegratorSettings,
) -> Result<Ocp<'a>, BenchmarkError> {
    use biped::{NQ, NU, NX};
    let n = intervals(json)?;
    let t = horizon(json)?;
    let step = num(json, "/parameters/step_length")?;
    let (x_lb, x_ub) = bounds(json, "x", NX)?;
    let (u_lb, u_ub) = bounds(json, "u", NU)?;
    let q0 = vecn(json, "/initial_guess/q_start", NQ)?;
    let qf: Vec<f64> = q0.iter().rev().copied().collect();
    let dq: Vec<f64> = (0..NQ).map(|i| (qf[i] - q0[i]) / t).collect();
    let x_guess = (0..=n)
        .map(|k| {
            let s = k as f64 / n as f64;
            let mut x: Vec<f64> = (0..NQ).map(|i| q0[i] + s * (qf[i] - q0[i])).collect();
            x.extend(&dq);
            x
        })
        .collect();
    let mut constraints = knee_hyperextension(n);
    constraints.push(heel_strike_periodicity(model, n));
    constraints.push(swing_foot_end(model, n, step));
    // lift-off (ẏ₅ ≥ 0 at t = 0) and touch-down (ẏ₅ ≤ 0 at t = T)
    for (node, name, lb, ub) in [
        (0, "liftoff", 0.0, f64::INFINITY),
        (n, "touchdown", f64::NEG_INFINITY, 0.0),
    ] {
        constraints.push(swing_foot_vertical_velocity(model, node, name, (lb, ub)));
    }
    Ok(Ocp {
        phases: vec![Phase {
            name: "single_stance".into(),
            ode: model,
            intervals: n,
            duration: PhaseDuration::fixed(t),
            controls: ControlShape::Constant,
            x_lb: vec![x_lb; n + 1],
            x_ub: vec![x_ub; n + 1],
            u_lb: vec![u_lb; n],
            u_ub: vec![u_ub; n],
            x_guess,
            u_guess: vec![vec![0.0; NU]; n],
        }],
        transitions: vec![],
        ntheta: 0,
        theta_guess: vec![],
        theta_lb: vec![],
        theta_ub: vec![],
        constraints,
        least_squares: u_squared_terms(n, NU, t / n as f64),
        samples: Vec::new(),
        checks: Vec::new(),
        costs: vec![],
        integrator,
    })
}

/// The five-link biped's path constraints q1 − q2 ≤ 0 and q5 − q4 ≤ 0 at every node of
/// `n` intervals.
fn knee_hyperextension<'a>(n: usize) -> Vec<Constraint<'a>> {
    use biped::NX;
    let mut constraints = Vec::new();
    // path: q1 − q2 ≤ 0 and q5 − q4 ≤ 0 at every node
    let mut a = vec![0.0; 2 * NX];
    a[0] = 1.0;
    a[1] = -1.0;
    a[NX + 4] = 1.0;
    a[NX + 3] = -1.0;
    let knee = Arc::new(Linear::new(a, 2));
    for k in 0..=n {
        constraints.push(Constraint {
            term: Term {
                name: "knee_hyperextension".into(),
                args: vec![Block::State { phase: 0, node: k }],
                f: knee.clone(),
            },
            lb: vec![f64::NEG_INFINITY; 2],
            ub: vec![0.0; 2],
        });
    }
    constraints
}

/// The five-link biped's periodicity through heel strike, `x_0 − Δ(x_N) = 0` (`n`: the
/// intervals).
fn heel_strike_periodicity<'a>(model: &FiveLinkBiped, n: usize) -> Constraint<'a> {
    use biped::NX;
    let m1 = model.clone();
    // periodicity through heel strike: x_0 − Δ(x_N) = 0
    let periodic = FnTerm::new(
        NX,
        move |z: &[f64], v: &mut [f64], jac: Option<&mut [f64]>| {
            let (x0, xn) = z.split_at(NX);
            let (d, dj) = m1.heel_strike_jacobian(xn);
            for i in 0..NX {
                v[i] = x0[i] - d[i];
            }
            if let Some(j) = jac {
                j.iter_mut().for_each(|x| *x = 0.0);
                for i in 0..NX {
                    j[i + i * NX] = 1.0;
                    for c in 0..NX {
                        j[i + (NX + c) * NX] = -dj[i + c * NX];
                    }
                }
            }
            Ok(())
        },
    );
    let m1h = model.clone();
    let periodic = periodic.with_hessian(Box::new(move |z: &[f64], w: &[f64], out: &mut [f64]| {
        // Σ w_i (x0_i − Δ_i(x_N)): curvature only in x_N
        let hx = dense_hessian::<NX>(&z[NX..], |xs| {
            let d = m1h.heel_strike(xs);
            d.iter()
                .zip(w)
                .fold(num_dual::Dual2SVec64::<NX>::from(0.0), |acc, (di, wi)| {
                    acc - *di * *wi
                })
        });
        out.iter_mut().for_each(|v| *v = 0.0);
        let nz = 2 * NX;
        for a in 0..NX {
            for c in 0..NX {
                out[(NX + a) + (NX + c) * nz] = hx[a + c * NX];
            }
        }
        Ok(())
    }));
    Constraint {
        term: Term {
            name: "periodicity".into(),
            args: vec![
                Block::State { phase: 0, node: 0 },
                Block::State { phase: 0, node: n },
            ],
            f: Arc::new(periodic),
        },
        lb: vec![0.0; NX],
        ub: vec![0.0; NX],
    }
}

/// The five-link biped's swing foot at the last node (of `n` intervals): `step` (m) ahead
/// and on the ground.
fn swing_foot_end<'a>(model: &FiveLinkBiped, n: usize, step: f64) -> Constraint<'a> {
    use biped::{NQ, NX};
    // step length and height of the swing foot at the end
    let m2 = model.clone();
    let foot_end = FnTerm::new(
        2,
        move |z: &[f64], v: &mut [f64], jac: Option<&mut [f64]>| {
            let (p, pj) = m2.swing_foot_jacobian(&z[..NQ]);
            v[0] = p[0] - step;
            v[1] = p[1];
            if let Some(j) = jac {
                j.iter_mut().for_each(|x| *x = 0.0);
                for c in 0..NQ {
                    j[c * 2] = pj[c * 2];
                    j[1 + c * 2] = pj[1 + c * 2];
                }
            }
            Ok(())
        },
    );
    let m2h = model.clone();
    let foot_end = foot_end.with_hessian(Box::new(move |z: &[f64], w: &[f64], out: &mut [f64]| {
        let hq = dense_hessian::<NQ>(&z[..NQ], |qs| {
            let p = m2h.swing_foot(qs);
            p[0] * w[0] + p[1] * w[1]
        });
        out.iter_mut().for_each(|v| *v = 0.0);
        for a in 0..NQ {
            for c in 0..NQ {
                out[a + c * NX] = hq[a + c * NQ];
            }
        }
        Ok(())
    }));
    Constraint {
        term: Term {
            name: "step_length_height".into(),
            args: vec![Block::State { phase: 0, node: n }],
            f: Arc::new(foot_end),
        },
        lb: vec![0.0; 2],
        ub: vec![0.0; 2],
    }
}

/// The five-link biped's swing foot's vertical velocity ẏ₅ at `node`, named `name`, in
/// `[lb, ub]`.
fn swing_foot_vertical_velocity<'a>(
    model: &FiveLinkBiped,
    node: usize,
    name: &str,
    (lb, ub): (f64, f64),
) -> Constraint<'a> {
    use biped::{NQ, NX};
    let m3 = model.clone();
    let vy = FnTerm::new(
        1,
        move |z: &[f64], v: &mut [f64], jac: Option<&mut [f64]>| {
            let (vel, vj) = m3.swing_foot_velocity_jacobian(z);
            v[0] = vel[1];
            if let Some(j) = jac {
                for c in 0..NX {
                    j[c] = vj[1 + c * 2];
                }
            }
            Ok(())
        },
    );
    let m4 = model.clone();
    let vy = vy.with_hessian(Box::new(move |z: &[f64], w: &[f64], out: &mut [f64]| {
        let hx = dense_hessian::<NX>(z, |xs| {
            m4.swing_foot_velocity(&xs[..NQ], &xs[NQ..])[1] * w[0]
        });
        out.copy_from_slice(&hx);
        Ok(())
    }));
    Constraint {
        term: Term {
            name: name.into(),
            args: vec![Block::State { phase: 0, node }],
            f: Arc::new(vy),
        },
        lb: vec![lb],
        ub: vec![ub],
    }
}
