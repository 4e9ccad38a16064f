//! `footfall fit-foot`: fit a foot's geometry to the measured stance (Millard & Mombaur
//! 2019, §3.2).

#[allow(unused_imports)]
use super::{note, warn_note, Progress};
use crate::model::spec::FootSpec;
use crate::model::GaitModel;
use crate::problems::foot_fit::{fit, fit_cost, foot_length, parameters, stances_from_data};
use crate::report::table::{ErrorStats, Table};
use crate::runfolder::RunFolder;
use anyhow::anyhow;
use std::path::PathBuf;

/// Arguments of `footfall fit-foot`.
#[derive(Debug, Clone)]
pub struct FitFootRequest {
    /// The model and foot files.
    pub model: super::ModelFiles,
    /// The trial (default: the bundled one).
    pub trial: super::trial::TrialFiles,
    /// Output folder.
    pub out: PathBuf,
    /// Replace the output folder if it exists.
    pub overwrite: bool,
    /// Nelder–Mead tolerance on the simplex's cost spread.
    pub tol: f64,
    /// Iteration limit.
    pub max_iter: usize,
}

/// Run `fit_foot` as `args` describes, reporting to `progress`.
pub fn run(args: &FitFootRequest, progress: &dyn Progress) -> anyhow::Result<()> {
    let foot_path = super::foot_path(&args.model.foot);
    let model = GaitModel::load(&args.model.model, &foot_path)?;
    let foot = FootSpec::load(&foot_path)?;
    let trial = super::trial::load_trial(&args.trial)?;
    for n in &trial.notes {
        progress.note(n);
    }
    let data = trial.data;
    let stances =
        stances_from_data(&model, &data).map_err(|e| anyhow!("{}: {e}", data.source.display()))?;
    let ground = model.contact_settings().ground_height;
    let folder = RunFolder::create(&args.out, args.overwrite)?;
    let n: usize = stances.iter().map(|s| s.len()).sum();
    {
        note!(
            progress,
            "fitting '{}' ({} parameters, length {:.1} cm) to {} stances, {n} samples…",
            foot.name,
            parameters(&foot).len(),
            100.0 * foot_length(&foot),
            stances.len()
        );
    }
    let started = std::time::Instant::now();
    let res =
        fit(&foot, &stances, ground, args.tol, args.max_iter as u64).map_err(|e| anyhow!(e))?;
    let seconds = started.elapsed().as_secs_f64();
    let (_, pos0, ang0) =
        fit_cost(&foot, &stances, ground).ok_or_else(|| anyhow!("the initial foot cannot roll"))?;
    let deg = 180.0 / std::f64::consts::PI;
    let stats = |v: &[f64], k: f64| ErrorStats::from_errors(v).scaled(k);
    let table1 = Table {
        title: "Ankle frame errors while rolling along the measured CoP (layout of Millard & Mombaur 2019, Table 1)"
            .into(),
        headers: vec![
            "error".into(),
            format!("{} (initial)", foot.name),
            format!("{} (fitted)", foot.name),
        ],
        rows: vec![
            vec![
                "ankle position (cm)".into(),
                stats(&pos0, 100.0).cell(2),
                stats(&res.errors.0, 100.0).cell(2),
            ],
            vec![
                "ankle orientation (°)".into(),
                stats(&ang0, deg).cell(1),
                stats(&res.errors.1, deg).cell(1),
            ],
        ],
    };
    let names = param_names(&foot);
    let (p0, p1) = (parameters(&foot), parameters(&res.foot));
    let table2 = Table {
        title: "Foot parameters (layout of Millard & Mombaur 2019, Table 2; lengths in cm, angles in degrees)".into(),
        headers: vec!["parameter".into(), "initial".into(), "fitted".into()],
        rows: names
            .iter()
            .enumerate()
            .map(|(i, nm)| {
                let k = if nm.ends_with("angle") { deg } else { 100.0 };
                vec![
                    nm.clone(),
                    format!("{:.2}", p0[i] * k),
                    format!("{:.2}", p1[i] * k),
                ]
            })
            .collect(),
    };
    let mut fitted = res.foot.clone();
    fitted.name = format!("{}_fitted", foot.name);
    fitted.description = format!(
        "{} fitted to {} by footfall fit-foot (Millard & Mombaur 2019, §3.2, eq. 13; length fixed at {:.1} cm); eq. 13 cost {:.4} → {:.4}.",
        foot.name,
        data.name,
        100.0 * foot_length(&foot),
        res.cost.0,
        res.cost.1
    );
    let summary = serde_json::json!({
        "command": "fit-foot",
        "foot": foot.name,
        "data": data.source,
        "forces": args.trial.forces,
        "plates": args.trial.plates,
        "lab_axes": args.trial.lab_axes,
        "belt_speed_m_s": data.belt_speed,
        "stances": stances.len(),
        "samples": n,
        "cost_initial": res.cost.0,
        "cost_fitted": res.cost.1,
        "iterations": res.iterations,
        "seconds": seconds,
        "length_m": foot_length(&res.foot),
        "parameters": names.iter().zip(&p1).map(|(n, v)| serde_json::json!({"name": n, "value": v})).collect::<Vec<_>>(),
    });
    folder.write(
        &format!("{}_fitted.json", foot.name),
        serde_json::to_string_pretty(&fitted)?.as_bytes(),
    )?;
    folder.write("table1.md", table1.to_markdown().as_bytes())?;
    folder.write("table2.md", table2.to_markdown().as_bytes())?;
    super::write_json(&folder, "summary.json", &summary)?;
    let out = folder.commit()?;
    {
        note!(
            progress,
            "{}\n{}",
            table1.to_markdown(),
            table2.to_markdown()
        );
        note!(
            progress,
            "eq. 13: {:.4} → {:.4} in {} iterations, {:.1} s → {}",
            res.cost.0,
            res.cost.1,
            res.iterations,
            seconds,
            out.display()
        );
    }
    Ok(())
}

fn param_names(foot: &FootSpec) -> Vec<String> {
    use crate::model::geometry::Shape;
    let mut v = Vec::new();
    for p in &foot.primitives {
        let n = &p.name;
        match p.shape {
            Shape::Point { .. } => v.extend([format!("{n}.x"), format!("{n}.y")]),
            Shape::Circle { .. } => v.extend([
                format!("{n}.centre_x"),
                format!("{n}.centre_y"),
                format!("{n}.radius"),
            ]),
            Shape::Ellipse { .. } => v.extend([
                format!("{n}.centre_x"),
                format!("{n}.centre_y"),
                format!("{n}.angle"),
                format!("{n}.semi_axis_a"),
                format!("{n}.semi_axis_b"),
            ]),
        }
    }
    v
}
