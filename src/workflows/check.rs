//! `footfall check TRIAL`: the measurement against itself, before any model is fitted.
//! The trial's whole-body Newton–Euler balance ([`crate::problems::check`]) over the
//! whole trial and over each half cycle on its own, written as a run folder: the
//! readings with their verdicts, the labs' residual thresholds before and after
//! correction, the residual wrench and the whole-body momenta against time, the trial
//! with the found instrument effects corrected, and the `--effect` lines that add each
//! found effect to `track`.

use super::trial::{load_trial, TrialFiles};
use super::Progress;
use crate::data::{detect_events, GaitData, DEFAULT_EVENT_FRACTION};
use crate::model::effects::EffectSpec;
use crate::model::GaitModel;
use crate::problems::check::{
    check, CheckError, CheckSettings, MeasurementCheck, NullBand, Param, Reading,
};
use crate::runfolder::RunFolder;
use anyhow::Context;
use std::path::PathBuf;

pub mod output;
pub use crate::problems::check::footing::hips_on_measured_centres;
pub use output::write_folder;

/// What `check` does: the arguments of `footfall check`.
#[derive(Debug, Clone)]
pub struct CheckRequest {
    /// The trial.
    pub trial: TrialFiles,
    /// Model file whose body the balance uses.
    pub model: PathBuf,
    /// Output folder (default `runs/check-<trial>`).
    pub out: Option<PathBuf>,
    /// Replace the output folder if it exists.
    pub overwrite: bool,
    /// How the balance is read.
    pub settings: CheckSettings,
}

/// One half cycle read on its own.
#[derive(Debug)]
pub struct HalfCycle {
    /// From one heel strike to the next (either foot's) (s).
    pub span: (f64, f64),
    /// Its reading, or why it has none.
    pub result: Result<MeasurementCheck, CheckError>,
}

/// The outcome of `check`.
#[derive(Debug)]
pub struct CheckOutcome {
    /// The trial as read.
    pub data: GaitData,
    /// The whole trial's reading.
    pub check: MeasurementCheck,
    /// Each half cycle's.
    pub half_cycles: Vec<HalfCycle>,
    /// The run folder written (`None` when not asked to write one).
    pub folder: Option<PathBuf>,
}

/// Read the trial and the model, and check the balance of the whole trial and of each
/// half cycle.
pub fn read(req: &CheckRequest) -> anyhow::Result<(GaitData, MeasurementCheck, Vec<HalfCycle>)> {
    let loaded = load_trial(&req.trial)?;
    let model = GaitModel::load(&req.model, &super::foot_path("ellipse"))
        .with_context(|| format!("--model {}", req.model.display()))?;
    let data = hips_on_measured_centres(loaded.data, &model);
    let whole = check(&data, &model, &req.settings, None).map_err(|e| checked(e, &data))?;
    let half_cycles = half_cycles(&data)
        .into_iter()
        .map(|span| HalfCycle {
            span,
            result: check(&data, &model, &req.settings, Some(span)),
        })
        .collect();
    Ok((data, whole, half_cycles))
}

/// Run `check` as `req` describes: read, report to `progress`, write the run folder.
pub fn run(req: &CheckRequest, progress: &dyn Progress) -> anyhow::Result<CheckOutcome> {
    let (data, check, half_cycles) = read(req)?;
    for w in &check.warnings {
        progress.warn(&format!("warning: {w}"));
    }
    progress.result(&output::verdict_text(&check));
    progress.result(&output::half_cycle_text(&half_cycles));
    let out = req
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("runs").join(format!("check-{}", data.name)));
    let folder = RunFolder::create(&out, req.overwrite)?;
    write_folder(&folder, req, &data, &check, &half_cycles)?;
    let done = folder.commit()?;
    progress.note(&format!("run folder: {}", done.display()));
    Ok(CheckOutcome {
        data,
        check,
        half_cycles,
        folder: Some(done),
    })
}

fn checked(e: CheckError, data: &GaitData) -> anyhow::Error {
    match e {
        CheckError::Data(d) => d.into(),
        // names the model file, which is at fault
        e @ CheckError::NoTorso { .. } => e.into(),
        other => {
            let text = other.to_string();
            let file = data.source.display().to_string();
            if text.contains(&file) {
                anyhow::anyhow!(text)
            } else {
                anyhow::anyhow!("{file}: {text}")
            }
        }
    }
}

/// From each heel strike to the next (either foot's), over the trial's force record.
pub fn half_cycles(data: &GaitData) -> Vec<(f64, f64)> {
    let Ok(ev) = detect_events(data, DEFAULT_EVENT_FRACTION) else {
        return vec![];
    };
    let mut hs: Vec<f64> = ev.heel_strike.iter().flatten().copied().collect();
    hs.sort_by(f64::total_cmp);
    hs.windows(2).map(|w| (w[0], w[1])).collect()
}

/// Replace entries of `null` by those a JSON file names (`{"shared_clock": {"mean":
/// 0.008, "sd": 0.002}}`, SI units, each finite, the spread ≥ 0).
pub fn read_null(
    path: &std::path::Path,
    null: &mut [NullBand; crate::problems::check::NPARAM],
) -> anyhow::Result<()> {
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Entry {
        mean: f64,
        sd: f64,
    }
    let text =
        std::fs::read_to_string(path).with_context(|| format!("--null {}", path.display()))?;
    let map: std::collections::BTreeMap<String, Entry> =
        serde_json::from_str(text.trim_start_matches('\u{feff}')).with_context(|| {
            format!(
                "--null {}: expected a JSON object of effect name to {{\"mean\": number, \"sd\": number}}",
                path.display()
            )
        })?;
    for (name, e) in map {
        let Some(p) = Param::from_name(&name) else {
            anyhow::bail!(
                "--null {}: '{name}' is not a candidate; use one of {}",
                path.display(),
                Param::ALL.map(|p| p.name()).join(", ")
            );
        };
        if !(e.mean.is_finite() && e.sd.is_finite() && e.sd >= 0.0) {
            anyhow::bail!(
                "--null {}: '{name}': mean {} and sd {} must be finite, the sd ≥ 0",
                path.display(),
                e.mean,
                e.sd
            );
        }
        null[p.index()] = NullBand {
            mean: e.mean,
            sd: e.sd,
        };
    }
    Ok(())
}

/// The `track --effect` line of each found effect, held at its reading.
pub fn effect_lines(check: &MeasurementCheck) -> Vec<String> {
    check
        .found()
        .filter_map(|r| effect_spec(r).and_then(|e| e.cli_text()))
        .collect()
}

/// The model effect a found reading adds, held at its value.
pub fn effect_spec(r: &Reading) -> Option<EffectSpec> {
    let side = |p: Param| match p {
        Param::ClockRight | Param::GainRight | Param::CopRight => "right",
        Param::ClockLeft | Param::GainLeft | Param::CopLeft => "left",
        _ => "both",
    };
    let v = r.estimate;
    let e = match r.param {
        Param::SharedClock | Param::ClockRight | Param::ClockLeft => {
            EffectSpec::ForcePlateTimeOffset {
                side: side(r.param).into(),
                offset: round4(v),
                free: vec![],
            }
        }
        Param::GainRight | Param::GainLeft => EffectSpec::ForcePlateGain {
            side: side(r.param).into(),
            error: round4(v),
            free: vec![],
        },
        Param::CopRight | Param::CopLeft => EffectSpec::CopOffset {
            side: side(r.param).into(),
            offset: round4(v),
            free: vec![],
        },
        Param::BodyMass => EffectSpec::BodyMassError {
            relative: round4(v),
            free: vec![],
        },
        Param::TrunkCom => EffectSpec::TrunkMass {
            added_mass: 0.0,
            com_offset: round4(v),
            free: vec![],
        },
        Param::TrunkMass => EffectSpec::TrunkMass {
            added_mass: round4(v),
            com_offset: 0.0,
            free: vec![],
        },
        Param::Slope => EffectSpec::GroundSlope {
            angle: round4(v),
            free: vec![],
        },
    };
    Some(e)
}

/// Four significant digits.
fn round4(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let mag = 10f64.powi(3 - v.abs().log10().floor() as i32);
    (v * mag).round() / mag
}

/// The trial with the found instrument effects (clocks, gains, CoP offsets) taken out of
/// its forces, at the force record's own instants. Body effects (mass, trunk, slope) stay
/// for the model: they are `--effect` lines.
pub fn corrected(data: &GaitData, check: &MeasurementCheck) -> GaitData {
    let th = &check.fit.theta;
    let mut out = data.clone();
    let (t, feet) = data.force_record();
    let mut fixed = feet.clone();
    for s in 0..2 {
        let (clock, gain, cop) = if s == 0 {
            (Param::ClockRight, Param::GainRight, Param::CopRight)
        } else {
            (Param::ClockLeft, Param::GainLeft, Param::CopLeft)
        };
        let shift = th[Param::SharedClock.index()] + th[clock.index()];
        let at: Vec<f64> = t.iter().map(|x| x + shift).collect();
        let moved = crate::data::ForceSamples {
            time: t.to_vec(),
            feet: feet.clone(),
        }
        .resample_foot(s, &at);
        let g = 1.0 + th[gain.index()];
        fixed[s].fx = moved.fx.iter().map(|v| v / g).collect();
        fixed[s].fy = moved.fy.iter().map(|v| v / g).collect();
        fixed[s].cop_x = moved.cop_x.iter().map(|v| v - th[cop.index()]).collect();
    }
    match &mut out.forces {
        Some(f) => {
            f.feet = fixed;
            for s in 0..2 {
                out.feet[s] = f.resample_foot(s, &data.time);
            }
        }
        None => out.feet = fixed,
    }
    out
}
