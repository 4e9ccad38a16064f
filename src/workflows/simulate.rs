//! `footfall simulate`: forward simulation through a phase sequence.

#[allow(unused_imports)]
use super::{note, warn_note, Progress};
use crate::controls::ControlTable;
use crate::integrate::IntegratorSettings;
use crate::model::gait::COORDINATES;
use crate::model::{GaitModel, RowKind};
use crate::phases::{InitialState, PhaseSequence};
use crate::runfolder::RunFolder;
use crate::simulate::{
    simulate, SanityTolerances, SimulationResult, SimulationSettings, SimulationWarning,
};
use anyhow::{anyhow, Context};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// What `simulate` does: the arguments of `footfall simulate`.
#[derive(Debug, Clone)]
pub struct SimulateRequest {
    /// The model and foot files.
    pub model: super::ModelFiles,
    /// Phase sequence file (JSON) with the contacts and durations of each phase.
    pub phase_set: PathBuf,
    /// Control table (CSV: `time,<control names>`); default: every control at 0.025
    /// (excitations) or 0 (torques).
    pub controls: Option<PathBuf>,
    /// Initial state (JSON: q, qd, optional a); default: the phase file's `initial_state`.
    pub initial: Option<PathBuf>,
    /// Output folder.
    pub out: PathBuf,
    /// Replace the output folder if it exists.
    pub overwrite: bool,
    /// Output grid step (s).
    pub dt: f64,
    /// Do not project the initial state onto the first phase's contact constraints.
    pub no_project: bool,
    /// Relative and absolute integrator tolerance.
    pub tol: f64,
    /// Refuse (exit 1, no output folder) instead of warning when a landing is away from
    /// the ground, a touchdown is not reached, or a stabilisation force is too large.
    pub strict: bool,
    /// Largest landing gap |φ| at an impact before a warning (m).
    pub gap_tolerance: f64,
    /// Largest stabilisation (Baumgarte) force before a warning (N).
    pub baumgarte_tolerance: f64,
}

/// Run `simulate` as `args` describes, reporting to `progress`.
pub fn run(args: &SimulateRequest, progress: &dyn Progress) -> anyhow::Result<()> {
    let started = Instant::now();
    let foot = super::foot_path(&args.model.foot);
    let model = GaitModel::load(&args.model.model, &foot)?;
    let seq = PhaseSequence::load(&args.phase_set)?;
    let sets = seq.resolve(&model, &args.phase_set)?;
    let theta = model.theta0();
    let x0 = initial_state(args, &model, &seq, &sets, &theta)?;
    let controls = controls(args, &model)?;
    let settings = SimulationSettings {
        output_step: args.dt,
        integrator: IntegratorSettings {
            rtol: args.tol,
            atol: args.tol,
            ..Default::default()
        },
    };
    settings
        .integrator
        .validate()
        .context("integrator settings")?;
    for (flag, v) in [
        ("--gap-tolerance", args.gap_tolerance),
        ("--baumgarte-tolerance", args.baumgarte_tolerance),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(anyhow!("{flag} must be a positive number, got {v}"));
        }
    }
    let tolerances = SanityTolerances {
        landing_gap_m: args.gap_tolerance,
        baumgarte_force_n: args.baumgarte_tolerance,
    };
    {
        note!(
            progress,
            "simulating {} phases of '{}' with model '{}' and foot '{}'…",
            seq.phases.len(),
            seq.name,
            model.name,
            model.foot_name
        );
    }
    // refuse an existing output folder before the work, not after it
    let folder = RunFolder::create(&args.out, args.overwrite)?;
    let res = simulate(&model, &seq, &sets, &x0, &controls, &theta, &settings)?;
    let warnings = res.check(&model, &sets, &tolerances);
    if args.strict && !warnings.is_empty() {
        // the staged folder is dropped uncommitted: nothing is left behind
        let list: Vec<String> = warnings.iter().map(|w| format!("  {w}")).collect();
        return Err(anyhow!(
            "the simulation is not physically sound (--strict; {} problem{}):\n{}",
            warnings.len(),
            if warnings.len() == 1 { "" } else { "s" },
            list.join("\n")
        ));
    }
    for w in &warnings {
        warn_note!(progress, "warning: {w}");
    }
    folder.write(
        "timeseries.csv",
        timeseries_csv(&model, &sets, &res).as_bytes(),
    )?;
    let summary = summary_json(
        &model,
        &seq,
        &sets,
        &res,
        args,
        &tolerances,
        &warnings,
        started.elapsed().as_secs_f64(),
    );
    super::write_json(&folder, "summary.json", &summary)?;
    let out = folder.commit()?;
    {
        note!(progress,
            "done: {} samples, {} CVODES steps, max drift {:.2e} m, max Baumgarte force {:.2e} N → {}",
            res.samples.len(),
            res.stats.steps,
            res.max_position_drift(&sets),
            res.max_baumgarte_force(&sets),
            out.display()
        );
    }
    Ok(())
}

/// The initial state `[q, q̇, a]`: `--initial` or the phase file's, checked against the
/// model and (unless `--no-project`) projected onto the first phase's contacts.
fn initial_state(
    args: &SimulateRequest,
    model: &GaitModel,
    seq: &PhaseSequence,
    sets: &[crate::model::ConstraintSet],
    theta: &[f64],
) -> anyhow::Result<Vec<f64>> {
    let init: InitialState = match &args.initial {
        Some(p) => crate::model::spec::read_json(p)?,
        None => seq.initial_state.clone().ok_or_else(|| {
            anyhow!(
                "{}: no `initial_state` in the phase file and no --initial given",
                args.phase_set.display()
            )
        })?,
    };
    let src = args
        .initial
        .as_ref()
        .unwrap_or(&args.phase_set)
        .display()
        .to_string();
    let nq = model.nq();
    for (field, v, n) in [("q", &init.q, nq), ("qd", &init.qd, nq)] {
        if v.len() != n {
            return Err(anyhow!(
                "{src}: initial state field '{field}' has {} values, expected {n} ({})",
                v.len(),
                COORDINATES.join(", ")
            ));
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(anyhow!(
                "{src}: initial state field '{field}[{i}]' is not finite"
            ));
        }
    }
    let a = match &init.a {
        Some(a) if a.len() != model.na() => {
            return Err(anyhow!(
                "{src}: initial state field 'a' has {} values, expected {}",
                a.len(),
                model.na()
            ))
        }
        Some(a) => a.clone(),
        None => vec![0.01; model.na()],
    };
    let (q0, qd0) = if args.no_project {
        (init.q.clone(), init.qd.clone())
    } else {
        let (q, qd, gap) = model
            .project(&sets[0], &init.q, &init.qd, theta)
            .with_context(|| {
                format!(
                    "projecting the initial state onto phase '{}'",
                    seq.phases[0].name()
                )
            })?;
        if gap > 1e-9 {
            return Err(anyhow!(
                "{src}: the initial state cannot be placed on the contacts of phase '{}' (gap {gap:.3e} m remains)",
                seq.phases[0].name()
            ));
        }
        (q, qd)
    };
    let mut x0 = q0;
    x0.extend(&qd0);
    x0.extend(&a);
    Ok(x0)
}

/// The controls: `--controls` read within their ranges, else every control at 0.025
/// (excitations) or 0 (torques).
fn controls(args: &SimulateRequest, model: &GaitModel) -> anyhow::Result<ControlTable> {
    Ok(match &args.controls {
        Some(p) => {
            // excitations of muscle-torque generators are fractions of full activation
            let names = model.control_names();
            let mtg = matches!(model.actuation(), crate::model::gait::Actuation::Mtg(_));
            let ranges: Vec<Option<(f64, f64, &str)>> = (0..names.len())
                .map(|i| (mtg && i < model.nu_actuators()).then_some((0.0, 1.0, "an excitation")))
                .collect();
            ControlTable::load_csv_within(p, &names, &ranges)?
        }
        None => {
            let v = if model.na() > 0 { 0.025 } else { 0.0 };
            ControlTable::constant(model.control_names(), vec![v; model.nu()])
        }
    })
}

fn timeseries_csv(
    model: &GaitModel,
    sets: &[crate::model::ConstraintSet],
    res: &SimulationResult,
) -> String {
    let mut s = String::from("time,phase");
    for n in model.state_names() {
        write!(s, ",{n}").ok();
    }
    for side in ["r", "l"] {
        write!(s, ",grf_x_{side},grf_y_{side},cop_x_{side}").ok();
    }
    for c in &model.contacts {
        let n = &c.name;
        write!(
            s,
            ",{n}.normal_force,{n}.tangential_force,{n}.gap,{n}.normal_velocity_error,{n}.tangential_velocity_error,{n}.baumgarte_normal_force,{n}.baumgarte_tangential_force"
        )
        .ok();
    }
    s.push('\n');
    let cell = |v: Option<f64>| {
        v.filter(|x| x.is_finite())
            .map(|x| format!("{x:.9e}"))
            .unwrap_or_default()
    };
    for smp in &res.samples {
        write!(s, "{:.6},{}", smp.t, sets[smp.phase].name).ok();
        for v in &smp.x {
            write!(s, ",{v:.9e}").ok();
        }
        for f in &smp.feet {
            write!(
                s,
                ",{},{},{}",
                cell(Some(f.fx)),
                cell(Some(f.fy)),
                cell(Some(f.cop_x))
            )
            .ok();
        }
        for (ci, contact) in model.contacts.iter().enumerate() {
            if contact.law.is_some() {
                // a volumetric primitive: its force from the law, its gap the depth of its
                // lowest point below the ground (negative), no constraint errors
                let v = smp.contact.volumetric.iter().find(|v| v.contact == ci);
                write!(
                    s,
                    ",{},{},{},,,,",
                    cell(Some(v.map_or(0.0, |v| v.force[1]))),
                    cell(Some(v.map_or(0.0, |v| v.force[0]))),
                    cell(v.map(|v| -v.depth)),
                )
                .ok();
                continue;
            }
            let row = |k: RowKind| {
                sets[smp.phase]
                    .rows
                    .iter()
                    .position(|r| r.contact == ci && r.kind == k)
            };
            let (rn, rt) = (row(RowKind::Normal), row(RowKind::Tangential));
            let get = |r: Option<usize>, v: &Vec<f64>| r.map(|r| v[r]);
            let c = &smp.contact;
            write!(
                s,
                ",{},{},{},{},{},{},{}",
                cell(get(rn, &c.lambda)),
                cell(get(rt, &c.lambda)),
                cell(get(rn, &c.position_error)),
                cell(get(rn, &c.velocity_error)),
                cell(get(rt, &c.velocity_error)),
                cell(get(rn, &c.baumgarte_force)),
                cell(get(rt, &c.baumgarte_force)),
            )
            .ok();
        }
        s.push('\n');
    }
    s
}

#[allow(clippy::too_many_arguments)]
fn summary_json(
    model: &GaitModel,
    seq: &PhaseSequence,
    sets: &[crate::model::ConstraintSet],
    res: &SimulationResult,
    args: &SimulateRequest,
    tolerances: &SanityTolerances,
    warnings: &[SimulationWarning],
    seconds: f64,
) -> serde_json::Value {
    let warnings: Vec<serde_json::Value> = warnings
        .iter()
        .map(|w| {
            let mut v = serde_json::to_value(w).unwrap_or_default();
            if let Some(o) = v.as_object_mut() {
                o.insert("message".into(), w.to_string().into());
            }
            v
        })
        .collect();
    let peak = |side: usize| {
        res.samples
            .iter()
            .map(|s| s.feet[side].fy)
            .fold(0.0f64, f64::max)
    };
    let last = res.samples.last().map(|s| s.x.clone()).unwrap_or_default();
    serde_json::json!({
        "command": "simulate",
        "model": model.name,
        "model_file": args.model.model,
        "foot": model.foot_name,
        "phase_set": seq.name,
        "phase_file": args.phase_set,
        "phases": res.phases,
        "impacts": res.impacts,
        "samples": res.samples.len(),
        "output_step_s": args.dt,
        "integrator_tolerance": args.tol,
        "integrator_stats": res.stats,
        "peak_normal_force_n": { "right": peak(0), "left": peak(1) },
        "per_phase": res.phase_figures(sets),
        "max_position_drift_m": res.max_position_drift(sets),
        "max_velocity_drift_m_s": res.max_velocity_drift(sets),
        "max_baumgarte_force_n": res.max_baumgarte_force(sets),
        "sanity_tolerances": tolerances,
        "warnings": warnings,
        "final_state": last,
        "state_names": model.state_names(),
        "wall_time_s": seconds,
    })
}
