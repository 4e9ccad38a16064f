//! Measured gait data in: readers, validation, interpolation, events and the generated
//! second leg.
//!
//! * [`read_sagittal_csv`]: the documented sagittal CSV schema of `data/README.md` (time;
//!   pelvis x, y, tilt; hip, knee, ankle per side; GRF tangential/normal and CoP per foot;
//!   SI units, radians, x forward, y up, angles counter-clockwise positive seen from the
//!   right, knee flexion negative) with an optional meta JSON ([`TrialMeta`]).
//! * [`read_storage`] and [`GaitData::from_storage`]: OpenSim `.mot`/`.sto` files, with
//!   the angle unit from the header; the forces kept at their own instants
//!   ([`GaitData::forces`]) and read at the kinematic instants in [`GaitData::feet`].
//! * Partial force coverage: `NaN` forces or CoP are "not measured" (an overground trial's
//!   foot off the plates); [`GaitData::measured_stretches`] says where a foot's force is
//!   known, [`GaitData::cop_missing_while_loaded`] where a loaded foot lacks its CoP.
//! * [`CubicSpline`] / [`GaitData::spline`]: tracked quantities as smooth ($C^2$) functions
//!   of time, interpolated before integration.
//! * [`detect_events`]: heel strike and toe off from the normal-force threshold
//!   $F_y > f\,\max F_y$ ($f$ = 5 %), crossings linearly interpolated; [`gait_cycle`],
//!   [`Events::contact_phases`] give initial phase durations.
//! * [`half_cycle_shift`] / [`GaitData::mirror_missing_side`]: the unmeasured leg as the
//!   measured one's Fourier series shifted by half a cycle, $x_l(t) = x_r(t + T_c/2)$
//!   (Ezati et al. 2020, §3.3).
//! * [`GaitData::to_overground`]: treadmill data moved to an overground frame,
//!   $x \mapsto x + v_{belt}\,t$.
//!
//! Bad data are refused with a [`DataError`] naming the file, the row (1-based line), the
//! column and the reason; nothing here panics on input.
//!
//! # Example
//! ```no_run
//! use footfall::data::{detect_events, gait_cycle, GaitData};
//! use footfall::model::Side;
//! let d = GaitData::bundled(env!("CARGO_MANIFEST_DIR").as_ref())?; // overground frame
//! let ev = detect_events(&d, 0.05)?;
//! let (t0, t1) = gait_cycle(&ev, Side::Right)?;
//! let hip = d.spline("hip_r")?;
//! println!("right cycle {t0}–{t1} s, hip velocity at heel strike {} rad/s", hip.derivative(t0));
//! # Ok::<(), footfall::data::DataError>(())
//! ```

pub mod c3d;
pub mod conventions;
pub mod csv;
pub mod error;
pub mod events;
pub mod filter;
pub mod fourier;
mod sides;
pub mod spline;
pub mod storage;

pub use csv::{
    read_meta, read_sagittal_csv, read_sagittal_csv_with, sibling_meta_path, write_sagittal_csv,
    MetaEvents, MetaSource, TrialMeta,
};
pub use error::{DataError, LabAxisError};
pub use events::{
    detect_events, gait_cycle, threshold_crossings, ContactPhase, Events, DEFAULT_EVENT_FRACTION,
};
pub use fourier::{half_cycle_shift, half_cycle_shift_order, FourierSeries, SEED_FOURIER_ORDER};
pub use spline::CubicSpline;
pub use storage::{
    parse_storage, read_storage, storage_text, ColumnMap, ForceColumns, Storage, StorageMap,
    OPENSIM_COORDINATES,
};

use crate::model::Side;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Names of the nine generalised coordinates, in model order (m, m, rad × 7).
pub const Q_NAMES: [&str; 9] = crate::model::gait::COORDINATES;

/// Normal force below which the CoP is undefined (N), as in `data/README.md`.
pub const DEFAULT_COP_THRESHOLD: f64 = 20.0;

/// Extra channels that are global x positions and move with [`GaitData::to_overground`]
/// (besides `pelvis_x` and `cop_x_*`).
pub const OVERGROUND_SHIFTED_EXTRAS: [&str; 1] = ["hip_center_x"];

/// Name of the bundled example trial (files `data/opensim_subject01_*`).
pub const BUNDLED_TRIAL: &str = "opensim_subject01";

/// Ground reaction force and centre of pressure of one foot, at the kinematic instants.
///
/// All three are NaN throughout when the forces were not measured
/// ([`GaitData::from_storage`] without a GRF file, a [`SideSource::Missing`] side).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FootData {
    /// Tangential (horizontal) force of the ground on the foot, + forward (N).
    pub fx: Vec<f64>,
    /// Normal (vertical) force of the ground on the foot, + up (N).
    pub fy: Vec<f64>,
    /// Centre-of-pressure x in the global frame (m); NaN where undefined (foot unloaded).
    pub cop_x: Vec<f64>,
}

/// Ground reaction forces and CoP sampled at their own instants (force plates at
/// 600–2,000 Hz beside kinematics at 60–200 Hz), as [`GaitData::forces`].
///
/// A sample is `NaN` where that foot's force was not measured (off the plates).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ForceSamples {
    /// Sample times (s), strictly increasing.
    pub time: Vec<f64>,
    /// `[right, left]` forces and CoP at `time`.
    pub feet: [FootData; 2],
}

impl ForceSamples {
    /// Foot `s`'s record read at the instants `at` (s): linear interpolation inside a
    /// measured stretch ([`stretch_indices`]), `NaN` outside (and the CoP `NaN` where a
    /// neighbouring sample's is).
    pub fn resample_foot(&self, s: usize, at: &[f64]) -> FootData {
        let f = &self.feet[s];
        let mut out = FootData {
            fx: vec![f64::NAN; at.len()],
            fy: vec![f64::NAN; at.len()],
            cop_x: vec![f64::NAN; at.len()],
        };
        for (a, b) in stretch_indices(&self.time, &f.fy) {
            let (ta, tb) = (self.time[a], self.time[b]);
            let idx: Vec<usize> = (0..at.len())
                .filter(|&k| at[k] >= ta && at[k] <= tb)
                .collect();
            let tt: Vec<f64> = idx.iter().map(|&k| at[k]).collect();
            let t = &self.time[a..=b];
            for (dst, src) in [
                (&mut out.fx, &f.fx),
                (&mut out.fy, &f.fy),
                (&mut out.cop_x, &f.cop_x),
            ] {
                for (&k, v) in idx.iter().zip(interp_linear(&tt, t, &src[a..=b])) {
                    dst[k] = v;
                }
            }
        }
        out
    }
}

/// The median time step of increasing instants `t` (s; `None` for fewer than two).
pub fn median_step(t: &[f64]) -> Option<f64> {
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    steps.get(steps.len() / 2).copied()
}

/// The measured stretches of a force channel `fy` sampled at `t`, as index ranges
/// `(first, last)`: runs of consecutive finite samples, broken also where a time step is
/// more than 1.5 times the median step (rows left out of a mixed-rate file).
pub fn stretch_indices(t: &[f64], fy: &[f64]) -> Vec<(usize, usize)> {
    let n = t.len().min(fy.len());
    let gap = median_step(&t[..n]).map_or(f64::INFINITY, |m| 1.5 * m);
    let mut out = Vec::new();
    let mut start: Option<usize> = None;
    for k in 0..n {
        if let Some(a) = start {
            if !fy[k].is_finite() || t[k] - t[k - 1] > gap {
                out.push((a, k - 1));
                start = None;
            }
        }
        if start.is_none() && fy[k].is_finite() {
            start = Some(k);
        }
    }
    if let Some(a) = start {
        out.push((a, n - 1));
    }
    out
}

/// Where one side's data come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SideSource {
    /// Read from the file.
    Measured,
    /// Not in the file: its channels are NaN.
    Missing,
    /// Generated from the other side by [`GaitData::mirror_missing_side`].
    Mirrored,
}

/// One measured trial in the model's sagittal coordinates.
///
/// All channels are sampled at `time`. Coordinates `q` follow [`Q_NAMES`]: `pelvis_x`,
/// `pelvis_y` (m) are the pelvis (HAT) reference point, `pelvis_tilt` is the HAT angle,
/// the joint angles are relative (rad, counter-clockwise positive seen from the right:
/// hip flexion +, knee flexion −, ankle dorsiflexion +). For the bundled OpenSim trial the
/// model's HAT is pelvis + torso frozen at the trial-mean lumbar angle, so the HAT angle is
/// `pelvis_tilt` as measured (its neutral is the OpenSim pelvis neutral, tilted 6–10°
/// posteriorly while walking), and `lumbar_extension` stays an extra channel.
#[derive(Debug, Clone, PartialEq)]
pub struct GaitData {
    /// Trial name.
    pub name: String,
    /// File the data were read from (the kinematics file for OpenSim storages).
    pub source: PathBuf,
    /// Sample times (s), strictly increasing.
    pub time: Vec<f64>,
    /// `pelvis_x, pelvis_y, pelvis_tilt, hip_r, knee_r, ankle_r, hip_l, knee_l, ankle_l`
    /// (m, rad); NaN for a [`SideSource::Missing`] side.
    pub q: [Vec<f64>; 9],
    /// `[right, left]` forces and CoP at the kinematic instants `time` (`NaN` where not
    /// measured). With [`Self::forces`] these are that record read at `time` (linear
    /// interpolation inside a measured stretch), for plots and summaries.
    pub feet: [FootData; 2],
    /// The forces at their own instants when they were sampled apart from the kinematics
    /// (a force file or the force-only rows of a mixed-rate CSV); `None` when they were
    /// sampled at `time`. Event detection, force targets and error tables read these.
    pub forces: Option<ForceSamples>,
    /// Other channels by name, e.g. `lumbar_extension` (rad), `hip_center_x`, `hip_center_y` (m).
    pub extra: BTreeMap<String, Vec<f64>>,
    /// Body mass (kg), from the meta file.
    pub body_mass: Option<f64>,
    /// Height of the force-plate surface (m), from the meta file or the CoP y column.
    pub force_plate_height: Option<f64>,
    /// Treadmill belt speed (m/s), from the meta file (or as applied by [`Self::to_overground`]).
    pub belt_speed: Option<f64>,
    /// CoP is NaN below this normal force (N, default 20).
    pub cop_threshold: f64,
    /// Where each side's data come from: `[right, left]`.
    pub sides: [SideSource; 2],
    /// Whether x positions are in the overground frame (belt displacement added).
    pub overground: bool,
    /// Gait events given with the data (meta file `events_s`), used instead of the force
    /// threshold when present: e.g. a lab's event markers or a synthetic trial's truth.
    pub events: Option<Events>,
}

pub(crate) fn side_index(side: Side) -> usize {
    match side {
        Side::Right => 0,
        Side::Left => 1,
    }
}

fn side_of(s: usize) -> Side {
    if s == 0 {
        Side::Right
    } else {
        Side::Left
    }
}

/// Piecewise-linear interpolation of `(x, y)` at `xn` (`x` increasing), held constant
/// outside `[x_0, x_{n-1}]` (numpy's `interp`).
pub fn interp_linear(xn: &[f64], x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len();
    xn.iter()
        .map(|&t| {
            if t <= x[0] {
                return y[0];
            }
            if t >= x[n - 1] {
                return y[n - 1];
            }
            let i = x.partition_point(|&v| v <= t) - 1;
            let s = (t - x[i]) / (x[i + 1] - x[i]);
            if s == 0.0 {
                y[i]
            } else {
                y[i] + s * (y[i + 1] - y[i])
            }
        })
        .collect()
}

impl GaitData {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// Largest vertical ground force of either foot (N; 0 without samples).
    pub fn peak_vertical_force(&self) -> f64 {
        self.force_record()
            .1
            .iter()
            .flat_map(|f| f.fy.iter())
            .copied()
            .fold(0.0, f64::max)
    }

    /// Forces and CoP of one foot.
    pub fn foot(&self, side: Side) -> &FootData {
        &self.feet[side_index(side)]
    }

    /// A channel by its CSV name: `time`, a [`Q_NAMES`] entry, `grf_x_r`, `grf_y_r`,
    /// `cop_x_r`, the same `_l`, or an extra channel.
    pub fn channel(&self, name: &str) -> Option<&[f64]> {
        if name == "time" {
            return Some(&self.time);
        }
        if let Some(i) = Q_NAMES.iter().position(|&q| q == name) {
            return Some(&self.q[i]);
        }
        for (s, side) in ["r", "l"].iter().enumerate() {
            let f = &self.feet[s];
            if let Some(base) = name.strip_suffix(&format!("_{side}")) {
                match base {
                    "grf_x" => return Some(&f.fx),
                    "grf_y" => return Some(&f.fy),
                    "cop_x" => return Some(&f.cop_x),
                    _ => {}
                }
            }
        }
        self.extra.get(name).map(Vec::as_slice)
    }

    /// Names of all channels except `time`, in CSV order, extras last.
    pub fn channel_names(&self) -> Vec<String> {
        let mut v: Vec<String> = Q_NAMES.iter().map(|s| s.to_string()).collect();
        for side in ["r", "l"] {
            for c in ["grf_x", "grf_y", "cop_x"] {
                v.push(format!("{c}_{side}"));
            }
        }
        v.extend(self.extra.keys().cloned());
        v
    }

    /// The not-a-knot [`CubicSpline`] of a channel (see [`Self::channel`]) over `time`.
    ///
    /// Errors: unknown channel; a NaN sample (CoP while unloaded, a missing side): cut a
    /// window where the channel is defined first.
    pub fn spline(&self, channel: &str) -> Result<CubicSpline, DataError> {
        let y = self.channel(channel).ok_or_else(|| {
            DataError::invalid(
                &self.source,
                channel,
                format!(
                    "no such channel; channels are {}",
                    self.channel_names().join(", ")
                ),
            )
        })?;
        if let Some(k) = y.iter().position(|v| !v.is_finite()) {
            return Err(DataError::invalid(
                &self.source,
                channel,
                format!(
                    "sample {k} (t = {} s) is {}; a spline needs finite values (cut a window where the channel is defined)",
                    self.time[k], y[k]
                ),
            ));
        }
        CubicSpline::new(&self.time, y).map_err(|e| match e {
            DataError::Invalid { reason, .. } => DataError::invalid(&self.source, channel, reason),
            other => other,
        })
    }

    /// The trial with its coordinates (pelvis and joint angles; not the forces or the
    /// CoP, which force plates measure accurately) low-pass filtered at `cutoff_hz` by a
    /// zero-phase second-order Butterworth filter ([`filter::low_pass`]), as gait labs
    /// smooth kinematics before differentiating them.
    ///
    /// Errors: data that fail [`Self::validate`]; samples not uniformly spaced (to 1 %);
    /// a cutoff not in (0, f_s/2).
    pub fn low_pass_kinematics(&self, cutoff_hz: f64) -> Result<GaitData, DataError> {
        let fs = self.kinematics_filter_rate(cutoff_hz)?;
        let mut out = self.clone();
        for q in out.q.iter_mut() {
            if q.iter().all(|v| v.is_finite()) {
                *q = filter::low_pass(q, fs, cutoff_hz);
            }
        }
        Ok(out)
    }

    /// The sampling rate (Hz) at which the trial's kinematics can be low-pass filtered at
    /// `cutoff_hz`: what [`Self::low_pass_kinematics`] checks, for callers that filter
    /// parts of the trial themselves.
    ///
    /// Errors: as [`Self::low_pass_kinematics`].
    pub fn kinematics_filter_rate(&self, cutoff_hz: f64) -> Result<f64, DataError> {
        self.validate()?;
        let n = self.time.len();
        let dt = (self.time[n - 1] - self.time[0]) / (n - 1) as f64;
        if let Some(k) =
            (1..n).find(|&k| ((self.time[k] - self.time[k - 1]) - dt).abs() > 0.01 * dt)
        {
            return Err(DataError::invalid(
                &self.source,
                "time",
                format!("filtering needs uniform sampling; the step before sample {k} is {} s, the mean {dt} s", self.time[k] - self.time[k - 1]),
            ));
        }
        let fs = 1.0 / dt;
        if !(cutoff_hz > 0.0 && cutoff_hz < 0.5 * fs) {
            return Err(DataError::invalid(
                &self.source,
                "cutoff",
                format!(
                    "the cutoff must lie in (0, {} Hz) for {fs} Hz sampling, got {cutoff_hz}",
                    0.5 * fs
                ),
            ));
        }
        Ok(fs)
    }

    /// The samples with `t0 ≤ t ≤ t1` (to within 1e-9 s; no interpolation at the ends:
    /// use [`Self::spline`] for values at exact event times).
    ///
    /// Errors: data that fail [`Self::validate`]; `t0 ≥ t1`, not finite, or fewer than two
    /// samples in the window.
    pub fn window(&self, t0: f64, t1: f64) -> Result<GaitData, DataError> {
        self.validate()?;
        if !(t0.is_finite() && t1.is_finite() && t0 < t1) {
            return Err(DataError::invalid(
                &self.source,
                "window",
                format!("need finite t0 < t1, got {t0}, {t1}"),
            ));
        }
        let eps = 1e-9;
        let keep: Vec<usize> = (0..self.len())
            .filter(|&k| self.time[k] >= t0 - eps && self.time[k] <= t1 + eps)
            .collect();
        if keep.len() < 2 {
            return Err(DataError::invalid(
                &self.source,
                "window",
                format!(
                    "{t0}–{t1} s holds {} sample(s) of the data ({}–{} s); at least two are needed",
                    keep.len(),
                    self.time.first().copied().unwrap_or(f64::NAN),
                    self.time.last().copied().unwrap_or(f64::NAN)
                ),
            ));
        }
        let pick = |v: &[f64]| keep.iter().map(|&k| v[k]).collect::<Vec<f64>>();
        Ok(GaitData {
            events: None,
            name: self.name.clone(),
            source: self.source.clone(),
            time: pick(&self.time),
            q: std::array::from_fn(|i| pick(&self.q[i])),
            feet: std::array::from_fn(|s| FootData {
                fx: pick(&self.feet[s].fx),
                fy: pick(&self.feet[s].fy),
                cop_x: pick(&self.feet[s].cop_x),
            }),
            extra: self
                .extra
                .iter()
                .map(|(k, v)| (k.clone(), pick(v)))
                .collect(),
            forces: self.forces.as_ref().map(|f| {
                let keep: Vec<usize> = (0..f.time.len())
                    .filter(|&k| f.time[k] >= t0 - eps && f.time[k] <= t1 + eps)
                    .collect();
                let pick = |v: &[f64]| keep.iter().map(|&k| v[k]).collect::<Vec<f64>>();
                ForceSamples {
                    time: pick(&f.time),
                    feet: std::array::from_fn(|s| FootData {
                        fx: pick(&f.feet[s].fx),
                        fy: pick(&f.feet[s].fy),
                        cop_x: pick(&f.feet[s].cop_x),
                    }),
                }
            }),
            body_mass: self.body_mass,
            force_plate_height: self.force_plate_height,
            belt_speed: self.belt_speed,
            cop_threshold: self.cop_threshold,
            sides: self.sides,
            overground: self.overground,
        })
    }

    /// Treadmill data in an overground-equivalent frame: the belt moves backward at
    /// `belt_speed` (m/s), so `belt_speed · t` (with the data's own time stamps) is added
    /// to `pelvis_x`, both `cop_x` and the extras in [`OVERGROUND_SHIFTED_EXTRAS`]
    /// (`hip_center_x`). Valid for a constant belt speed. Sets `belt_speed` and `overground`.
    ///
    /// Errors: a speed that is not finite, or data already in the overground frame.
    pub fn to_overground(mut self, belt_speed: f64) -> Result<GaitData, DataError> {
        if !belt_speed.is_finite() {
            return Err(DataError::invalid(
                &self.source,
                "belt_speed",
                format!("must be finite, got {belt_speed}"),
            ));
        }
        if self.overground {
            return Err(DataError::invalid(
                &self.source,
                "belt_speed",
                "the data are already in the overground frame (the belt displacement was added once)",
            ));
        }
        let t = self.time.clone();
        let shift = |v: &mut Vec<f64>| {
            for (x, &tk) in v.iter_mut().zip(&t) {
                *x += belt_speed * tk;
            }
        };
        shift(&mut self.q[0]);
        for f in &mut self.feet {
            shift(&mut f.cop_x);
        }
        for name in OVERGROUND_SHIFTED_EXTRAS {
            if let Some(v) = self.extra.get_mut(name) {
                shift(v);
            }
        }
        if let Some(f) = &mut self.forces {
            for foot in &mut f.feet {
                for (x, &tk) in foot.cop_x.iter_mut().zip(&f.time) {
                    *x += belt_speed * tk;
                }
            }
        }
        self.belt_speed = Some(belt_speed);
        self.overground = true;
        Ok(self)
    }

    /// Path of the bundled example CSV under a project root: `ROOT/data/opensim_subject01_sagittal.csv`.
    pub fn bundled_csv_path(root: &Path) -> PathBuf {
        root.join("data")
            .join(format!("{BUNDLED_TRIAL}_sagittal.csv"))
    }

    /// The bundled example (OpenSim subject01, instrumented treadmill, 0–2.5 s at 60 Hz,
    /// 72.6 kg), read from `ROOT/data/opensim_subject01_sagittal.csv` with its meta file
    /// and moved to the overground frame with the meta file's belt speed (1.1322 m/s).
    ///
    /// `root` is the project root (`env!("CARGO_MANIFEST_DIR")` in this crate); other
    /// trials are read with [`read_sagittal_csv`]. Neutral offsets: the HAT angle is
    /// `pelvis_tilt` unchanged (the model's HAT is pelvis + torso frozen at the trial-mean
    /// `lumbar_extension`, −0.3634 rad, see `models/opensim_subject01.json`), and
    /// `lumbar_extension` is kept as an extra channel; the force-plate surface is at
    /// `force_plate_height` = −0.0075 m.
    pub fn bundled(root: &Path) -> Result<GaitData, DataError> {
        let path = Self::bundled_csv_path(root);
        let data = read_sagittal_csv(&path)?;
        let v = data.belt_speed.ok_or_else(|| {
            DataError::invalid(
                &path,
                "belt_speed_m_s",
                "the bundled treadmill trial needs its belt speed in the meta file",
            )
        })?;
        data.to_overground(v)
    }

    /// The force record at its own instants: [`Self::forces`] if the forces were sampled
    /// apart from the kinematics, else `(time, feet)`.
    pub fn force_record(&self) -> (&[f64], &[FootData; 2]) {
        match &self.forces {
            Some(f) => (&f.time, &f.feet),
            None => (&self.time, &self.feet),
        }
    }

    /// The stretches (s) over which foot `s`'s normal force was measured: the first and
    /// last instant of each run of consecutive finite samples of the force record (one
    /// per force plate the foot stepped on; the whole trial when nothing is missing).
    pub fn measured_stretches(&self, side: Side) -> Vec<(f64, f64)> {
        let (t, feet) = self.force_record();
        stretch_indices(t, &feet[side_index(side)].fy)
            .into_iter()
            .map(|(a, b)| (t[a], t[b]))
            .collect()
    }

    /// Whether foot `side`'s forces are known over all of `[t0, t1]` (inside one measured
    /// stretch, to within one force sample interval at either end).
    pub fn forces_known(&self, side: Side, t0: f64, t1: f64) -> bool {
        let (t, _) = self.force_record();
        let dt = if t.len() > 1 {
            (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64
        } else {
            0.0
        };
        self.measured_stretches(side)
            .iter()
            .any(|&(a, b)| a <= t0 + dt && b >= t1 - dt)
    }

    /// Instants (s) of the force record where a foot is loaded (`fy` ≥ the CoP
    /// threshold) but its CoP is missing (`NaN`), `[right, left]`: those samples track
    /// the forces only (labs export the CoP with their own thresholds).
    pub fn cop_missing_while_loaded(&self) -> [Vec<f64>; 2] {
        let (t, feet) = self.force_record();
        std::array::from_fn(|s| {
            let f = &feet[s];
            (0..t.len())
                .filter(|&k| f.fy[k] >= self.cop_threshold && f.cop_x[k].is_nan())
                .map(|k| t[k])
                .collect()
        })
    }

    /// Check the invariants of data built or edited in memory: every channel as long as
    /// its time vector; times finite and strictly increasing; pelvis, extras and every
    /// non-missing side's angles finite. Forces and CoP may be `NaN` anywhere (not
    /// measured: off the plates, or a CoP a lab did not export) but never infinite; a
    /// loaded foot without CoP is listed by [`Self::cop_missing_while_loaded`]. The
    /// readers return only data that pass.
    pub fn validate(&self) -> Result<(), DataError> {
        let n = self.time.len();
        let bad =
            |field: &str, reason: String| Err(DataError::invalid(&self.source, field, reason));
        if n < 2 {
            return bad("time", format!("{n} sample(s); at least two are needed"));
        }
        let increasing = |name: &str, t: &[f64]| -> Result<(), DataError> {
            for k in 0..t.len() {
                if !t[k].is_finite() || (k > 0 && t[k] <= t[k - 1]) {
                    return bad(
                        name,
                        format!(
                            "sample {k} ({}) is not finite and larger than the previous",
                            t[k]
                        ),
                    );
                }
            }
            Ok(())
        };
        increasing("time", &self.time)?;
        let mut channels: Vec<(String, &[f64], bool, usize)> = Vec::new();
        for (i, name) in Q_NAMES.iter().enumerate() {
            let required = i < 3 || self.sides[(i - 3) / 3] != SideSource::Missing;
            channels.push((name.to_string(), &self.q[i], required, n));
        }
        let mut loads: Vec<(String, &[f64], &[f64])> = Vec::new();
        for (s, side) in ["r", "l"].iter().enumerate() {
            let f = &self.feet[s];
            loads.push((format!("grf_x_{side}"), &f.fx, &self.time));
            loads.push((format!("grf_y_{side}"), &f.fy, &self.time));
            loads.push((format!("cop_x_{side}"), &f.cop_x, &self.time));
        }
        if let Some(fs) = &self.forces {
            increasing("force time", &fs.time)?;
            for (s, side) in ["r", "l"].iter().enumerate() {
                let f = &fs.feet[s];
                loads.push((format!("grf_x_{side} (force record)"), &f.fx, &fs.time));
                loads.push((format!("grf_y_{side} (force record)"), &f.fy, &fs.time));
                loads.push((format!("cop_x_{side} (force record)"), &f.cop_x, &fs.time));
            }
        }
        // extra channels may have gaps (NaN): the model reads none of them
        for (k, v) in &self.extra {
            channels.push((k.clone(), v, false, n));
        }
        for (name, v, required, len) in &channels {
            if v.len() != *len {
                return bad(name, format!("{} samples but time has {len}", v.len()));
            }
            if *required {
                if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                    return bad(
                        name,
                        format!("sample {k} (t = {} s) is {}", self.time[k], v[k]),
                    );
                }
            }
        }
        for (name, v, t) in &loads {
            if v.len() != t.len() {
                return bad(
                    name,
                    format!("{} samples but its time has {}", v.len(), t.len()),
                );
            }
            if let Some(k) = v.iter().position(|x| x.is_infinite()) {
                return bad(
                    name,
                    format!(
                        "sample {k} (t = {} s) is {}; a force or CoP is finite, or NaN where not measured",
                        t[k], v[k]
                    ),
                );
            }
        }
        Ok(())
    }
}
