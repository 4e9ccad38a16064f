//! Measurement sets generated from a model solution, for tests with a known truth.
//!
//! A gait OCP solution spans one half cycle (left heel strike to right heel strike). The
//! walk is extended periodically through the left↔right mirror: half cycle `k` is the
//! solution with the legs and feet swapped when `k` is odd, and everything moved forward
//! by `k` step lengths. Each requested sample is the model itself — the shooting interval
//! containing it integrated from its node — so the data carry no interpolation error.
//! Noise: independent Gaussian per channel and sample, with standard deviations per
//! channel kind ([`NoiseModel`]) from a seeded ChaCha8 generator, so a seed gives the same
//! bits on every machine.

use super::evaluation::GaitSolution;
use super::track::loaded_feet;
use crate::data::{Events, FootData, GaitData, SideSource, DEFAULT_COP_THRESHOLD};
use crate::integrate::IntegratorSettings;
use crate::model::{ConstraintSet, GaitModel};
use crate::simulate::SimulationError;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Standard deviations of the Gaussian measurement noise, per channel kind.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NoiseModel {
    /// Pelvis x and y (m).
    pub position_m: f64,
    /// Pelvis tilt and joint angles (rad).
    pub angle_rad: f64,
    /// Ground reaction forces, both components (N).
    pub force_n: f64,
    /// Centre of pressure x (m).
    pub cop_m: f64,
    /// Seed of the generator.
    pub seed: u64,
}

impl NoiseModel {
    /// No noise.
    pub fn none() -> Self {
        Self {
            position_m: 0.0,
            angle_rad: 0.0,
            force_n: 0.0,
            cop_m: 0.0,
            seed: 0,
        }
    }
}

/// How to sample the synthetic trial.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthSettings {
    /// Sampling rate (Hz).
    pub rate_hz: f64,
    /// Start of the trial relative to the solution's first instant (s; negative to start
    /// inside the previous half cycle).
    pub start_s: f64,
    /// Length of the trial (s).
    pub duration_s: f64,
    /// Noise.
    pub noise: NoiseModel,
    /// Integrator of the intervals.
    pub integrator: IntegratorSettings,
    /// Hidden measurement effects (zero: none).
    pub measurement: MeasurementOffsets,
}

/// Measurement effects hidden in a synthetic trial, as the catalog defines them: the
/// force plates' clock runs `force_time_offset_s` behind the motion capture's (the force
/// recorded at t is the model's at t − offset) and their CoP reads `cop_offset_m` too far
/// along the walkway.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct MeasurementOffsets {
    /// Force-plate clock offset (s).
    pub force_time_offset_s: f64,
    /// CoP offset (m).
    pub cop_offset_m: f64,
}

/// The truth behind a synthetic trial: where each sample came from.
#[derive(Debug, Clone)]
pub struct SynthTruth {
    /// The noise-free trial.
    pub clean: GaitData,
    /// Half-cycle period (s) and step length (m) of the periodic extension.
    pub half_period_s: f64,
    /// Step length (m).
    pub step_length_m: f64,
    /// The exact gait events: where the phase graph puts a foot on or off the ground.
    pub events: Events,
}

/// Index map of the left↔right mirror on [`crate::data::Q_NAMES`].
const MIRROR_Q: [usize; 9] = [0, 1, 2, 6, 7, 8, 3, 4, 5];

/// Generate a trial from `solution` (one half cycle of `model` under `sets`) extended
/// periodically, sampled and noised as `settings` says. Returns the noisy trial and the
/// truth. Time 0 of the trial is the solution's first instant.
pub fn synthesize(
    model: &GaitModel,
    sets: &[ConstraintSet],
    solution: &GaitSolution,
    settings: &SynthSettings,
    name: &str,
) -> Result<(GaitData, SynthTruth), SimulationError> {
    if !(settings.rate_hz.is_finite()
        && settings.rate_hz > 0.0
        && settings.duration_s.is_finite()
        && settings.duration_s > 0.0
        && settings.start_s.is_finite())
    {
        return Err(SimulationError::Input(format!(
            "synthetic trial: rate {} Hz, start {} s, duration {} s (need a positive rate and duration)",
            settings.rate_hz, settings.start_s, settings.duration_s
        )));
    }
    let (s0, s1) = solution.span();
    let half = s1 - s0;
    let nodes = solution
        .node_samples(model, sets)
        .map_err(|e| SimulationError::Dynamics {
            phase: "node".into(),
            t: s0,
            source: e,
        })?;
    let step_length = nodes.last().map_or(0.0, |l| l.x[0]) - nodes[0].x[0];
    let dt = 1.0 / settings.rate_hz;
    let n = (settings.duration_s * settings.rate_hz).floor() as usize + 1;
    let time: Vec<f64> = (0..n).map(|k| settings.start_s + k as f64 * dt).collect();
    // each sample's half cycle k and time τ within the solution (the force plates'
    // samples at the model's time t − offset)
    let locate = |t: f64| {
        let k = (t / half).floor() as i64;
        (k, (s0 + t - k as f64 * half).clamp(s0, s1))
    };
    let place: Vec<(i64, f64)> = time.iter().map(|&t| locate(t)).collect();
    let delay = settings.measurement.force_time_offset_s;
    let place_force: Vec<(i64, f64)> = time.iter().map(|&t| locate(t - delay)).collect();
    let mut taus: Vec<f64> = place.iter().chain(&place_force).map(|p| p.1).collect();
    taus.sort_by(f64::total_cmp);
    taus.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    let samples = solution.sample_at(model, sets, &taus, &settings.integrator)?;
    let find = |tau: f64| {
        let i = taus.partition_point(|&v| v < tau - 1e-12);
        &samples[i.min(samples.len() - 1)]
    };
    let mut q: [Vec<f64>; 9] = Default::default();
    let mut feet: [FootData; 2] = Default::default();
    for (&(k, tau), &(kf, tau_f)) in place.iter().zip(&place_force) {
        let s = find(tau);
        let odd = k.rem_euclid(2) == 1;
        let shift = k as f64 * step_length;
        for (i, qi) in q.iter_mut().enumerate() {
            let src = if odd { MIRROR_Q[i] } else { i };
            qi.push(s.x[src] + if i == 0 { shift } else { 0.0 });
        }
        let s = find(tau_f);
        let odd = kf.rem_euclid(2) == 1;
        let shift = kf as f64 * step_length + settings.measurement.cop_offset_m;
        for (side, foot) in feet.iter_mut().enumerate() {
            let l = &s.feet[if odd { 1 - side } else { side }];
            foot.fx.push(l.fx);
            foot.fy.push(l.fy);
            foot.cop_x.push(if l.fy > 0.0 {
                l.cop_x + shift
            } else {
                f64::NAN
            });
        }
    }
    let clean = GaitData {
        name: name.to_string(),
        source: PathBuf::from(format!("<synthetic: {name}>")),
        time,
        q,
        feet,
        forces: None,
        extra: BTreeMap::new(),
        body_mass: None,
        force_plate_height: None,
        belt_speed: None,
        cop_threshold: DEFAULT_COP_THRESHOLD,
        sides: [SideSource::Measured, SideSource::Measured],
        overground: true,
        events: None,
    };
    // noise first (the noisy force decides where the noisy CoP is defined), then the
    // clean CoP hidden below the threshold as well
    let noisy = add_noise(&clean, &settings.noise);
    let mut clean = clean;
    hide_unloaded_cop(&mut clean);
    // a foot of volumetric primitives has no contact changes in its phase graph: its
    // events are where its clean normal force crosses Millard & Mombaur's event threshold (5 % of
    // the peak), as a lab would find them on noise-free forces
    let events = if sets.iter().all(|s| s.rows.is_empty()) && model.has_volumetric_contacts() {
        crate::data::detect_events(&clean, crate::data::DEFAULT_EVENT_FRACTION).map_err(|e| {
            SimulationError::Input(format!("gait events of the synthetic trial: {e}"))
        })?
    } else {
        exact_events(model, sets, solution, &clean)
    };
    let mut noisy = noisy;
    noisy.events = Some(events.clone());
    clean.events = Some(events.clone());
    Ok((
        noisy,
        SynthTruth {
            clean,
            half_period_s: half,
            step_length_m: step_length,
            events,
        },
    ))
}

/// Heel strikes and toe offs of the periodic extension over the span of `data`: the
/// instants where the contact sets of consecutive continuous phases put a foot on or off
/// the ground.
fn exact_events(
    model: &GaitModel,
    sets: &[ConstraintSet],
    solution: &GaitSolution,
    data: &GaitData,
) -> Events {
    let (s0, s1) = solution.span();
    let half = s1 - s0;
    let (t_start, t_end) = (data.time[0], data.time[data.time.len() - 1]);
    // (time, [right, left] loaded) at the start of every continuous phase of the extension
    let mut spans: Vec<(f64, [bool; 2])> = Vec::new();
    let k0 = (t_start / half).floor() as i64;
    let k1 = (t_end / half).ceil() as i64;
    for k in k0..=k1 {
        for p in &solution.phases {
            let mut feet = loaded_feet(model, &sets[p.set]);
            if k.rem_euclid(2) == 1 {
                feet.swap(0, 1);
            }
            spans.push((p.t0 - s0 + k as f64 * half, feet));
        }
    }
    let mut ev = Events {
        heel_strike: [Vec::new(), Vec::new()],
        toe_off: [Vec::new(), Vec::new()],
        threshold: 0.0,
        loaded_at_start: [false; 2],
        span: (t_start, t_end),
        source: data.source.clone(),
    };
    let mut current: Option<[bool; 2]> = None;
    for (t, feet) in spans {
        if t <= t_start {
            current = Some(feet);
            continue;
        }
        if t >= t_end {
            break;
        }
        let before = current.unwrap_or(feet);
        for s in 0..2 {
            if feet[s] && !before[s] {
                ev.heel_strike[s].push(t);
            } else if !feet[s] && before[s] {
                ev.toe_off[s].push(t);
            }
        }
        current = Some(feet);
    }
    // the first phase in the data decides what is loaded at the start
    ev.loaded_at_start = current.map_or([false; 2], |_| {
        let mut first = [false; 2];
        let k = (t_start / half).floor() as i64;
        let tau = s0 + t_start - k as f64 * half;
        if let Some(p) = solution.phases.iter().rev().find(|p| p.t0 <= tau) {
            first = loaded_feet(model, &sets[p.set]);
            if k.rem_euclid(2) == 1 {
                first.swap(0, 1);
            }
        }
        first
    });
    ev
}

/// CoP undefined (NaN) where the normal force is below the data's CoP threshold, as a
/// force plate reports it.
fn hide_unloaded_cop(data: &mut GaitData) {
    let th = data.cop_threshold;
    for f in data.feet.iter_mut() {
        for (c, fy) in f.cop_x.iter_mut().zip(&f.fy) {
            if !(*fy >= th) {
                *c = f64::NAN;
            }
        }
    }
}

/// `data` with independent Gaussian noise added to every defined sample (see the module
/// docs). A foot that carries no load (zero force, as after the usual force-plate
/// threshold) reads exactly zero, and the CoP is undefined wherever the noisy normal
/// force is below the CoP threshold.
pub fn add_noise(data: &GaitData, noise: &NoiseModel) -> GaitData {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(noise.seed);
    let mut out = data.clone();
    let mut perturb = |v: &mut Vec<f64>, sd: f64, keep: &dyn Fn(usize) -> bool| {
        if sd > 0.0 {
            let d = Normal::new(0.0, sd).expect("a positive standard deviation");
            for (k, x) in v.iter_mut().enumerate() {
                if x.is_finite() && keep(k) {
                    *x += d.sample(&mut rng);
                }
            }
        }
    };
    for (i, qi) in out.q.iter_mut().enumerate() {
        perturb(
            qi,
            if i < 2 {
                noise.position_m
            } else {
                noise.angle_rad
            },
            &|_| true,
        );
    }
    for f in out.feet.iter_mut() {
        let loaded: Vec<bool> =
            f.fy.iter()
                .zip(&f.fx)
                .map(|(y, x)| *y != 0.0 || *x != 0.0)
                .collect();
        perturb(&mut f.fx, noise.force_n, &|k| loaded[k]);
        perturb(&mut f.fy, noise.force_n, &|k| loaded[k]);
        perturb(&mut f.cop_x, noise.cop_m, &|_| true);
    }
    hide_unloaded_cop(&mut out);
    out
}
