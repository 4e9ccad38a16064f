//! The check's run folder: `summary.json`, `readings.md`/`.csv`, `half_cycles.csv`,
//! `residual.csv`, `residual.svg`, `momentum.svg`, `joint_torques.csv`/`.svg`,
//! `joint_powers.csv`/`.svg`, `effects.txt`, the corrected trial (`corrected/trial.csv`
//! with its meta file) and `report.html`.

use super::{corrected, effect_lines, CheckRequest, HalfCycle};
use crate::data::{write_sagittal_csv, GaitData};
use crate::problems::check::{
    JointKinetics, MeasurementCheck, Param, Reading, Thresholds, Verdict,
};
use crate::report::html::{Report, Section, Summary, Tone};
use crate::report::plot::{grid, LinePlot, LineStyle, Series};
use crate::report::table::Table;
use crate::runfolder::RunFolder;
use serde_json::json;
use std::fmt::Write;

/// A reading's estimate ± sd in its reporting unit, e.g. `+29.8 ± 1.2 ms`.
pub fn estimate_text(r: &Reading) -> String {
    if !r.estimate.is_finite() {
        return "—".into();
    }
    let (v, unit) = r.param.display_value(r.estimate);
    let (sd, _) = r.param.display_value(r.sd);
    format!("{v:+.2} ± {sd:.2} {unit}")
}

/// The verdict in a few lines: what was found, with the line that adds it.
pub fn verdict_text(c: &MeasurementCheck) -> String {
    let mut s = String::new();
    let found: Vec<&Reading> = c.found().collect();
    if found.is_empty() {
        s.push_str("measurement check: nothing found beyond the noise (every candidate's reading is within its band)\n");
    } else {
        s.push_str("measurement check: found\n");
        for r in &found {
            writeln!(
                s,
                "  {}: {} (z {:.1} against {:.2}); or: {}",
                r.param.label(),
                estimate_text(r),
                r.z,
                r.threshold,
                r.param.look_alikes()
            )
            .ok();
            if !r.alternatives.is_empty() {
                writeln!(
                    s,
                    "    these data cannot tell it from: {}",
                    alternatives_text(r)
                )
                .ok();
            }
        }
        s.push_str("add to track with:");
        for l in effect_lines(c) {
            write!(s, " --effect {l}").ok();
        }
        s.push('\n');
    }
    for r in c.readings.iter().filter(|r| r.verdict == Verdict::Baseline) {
        writeln!(
            s,
            "baseline (read beside every candidate, not tested): {} {}, where untouched trials read {}; or: {}",
            r.param.label(),
            estimate_text(r),
            baseline_text(r),
            r.param.look_alikes()
        )
        .ok();
    }
    s.push_str(&limits_text(c));
    s.push_str(&coverage_text(c));
    let [before, after] = &c.thresholds;
    writeln!(
        s,
        "residual thresholds (Hicks et al. 2015): peak force {:.1} N → {:.1} N (limit {:.1}), RMS moment {:.2} → {:.2} N·m (limit {:.2})",
        before.peak_force, after.peak_force, after.force_limit, before.rms_moment, after.rms_moment, after.moment_limit
    )
    .ok();
    if let Some([frozen, moving]) = &c.trunk {
        writeln!(
            s,
            "the trunk's rocking on the pelvis (lumbar_extension): residual {:.1} N horizontal, {:.2} N·m moment (RMS) with the trunk frozen in the HAT, {:.1} N and {:.2} N·m with it moving (check --lumbar)",
            frozen.rms_force[0], frozen.rms_moment, moving.rms_force[0], moving.rms_moment
        )
        .ok();
    }
    s
}

/// What the check could not have seen: each candidate not found, with the smallest
/// effect it would have called found here, and those it could not test at all.
pub fn limits_text(c: &MeasurementCheck) -> String {
    let unseen = |r: &&Reading| r.verdict != Verdict::Found && r.verdict != Verdict::Baseline;
    let sized: Vec<String> = c
        .readings
        .iter()
        .filter(unseen)
        .filter(|r| r.smallest_found().is_finite())
        .map(|r| format!("{} {}", r.param.label(), smallest_found_text(r)))
        .collect();
    let untested: Vec<&str> = c
        .readings
        .iter()
        .filter(unseen)
        .filter(|r| matches!(r.verdict, Verdict::NotTestable { .. }))
        .map(|r| r.param.label())
        .collect();
    let mut s = String::new();
    if !sized.is_empty() {
        writeln!(
            s,
            "found here only beyond (from what untouched trials read): {}",
            sized.join(", ")
        )
        .ok();
    }
    if !untested.is_empty() {
        writeln!(s, "not testable here: {}", untested.join(", ")).ok();
    }
    s
}

/// Where the balance was read, against the motion: a trial whose forces stop early, start
/// late or have gaps is read only where both feet's loads are known, and says so.
pub fn coverage_text(c: &MeasurementCheck) -> String {
    let cov = c.coverage();
    let mut s = format!(
        "read over {:.3}–{:.3} s ({} force samples with both feet's loads known) of the motion's {:.3}–{:.3} s",
        cov.first, cov.last, cov.samples, c.motion.0, c.motion.1
    );
    if cov.gaps > 0 {
        write!(
            s,
            ", with {} gap(s) of {:.3} s in all where a foot's load is unknown",
            cov.gaps, cov.gap_s
        )
        .ok();
    }
    s.push('\n');
    s
}

/// How many half cycles were read on their own and what they found.
pub fn half_cycle_text(half: &[HalfCycle]) -> String {
    let read: Vec<&MeasurementCheck> = half.iter().filter_map(|h| h.result.as_ref().ok()).collect();
    let found: Vec<String> = read
        .iter()
        .flat_map(|c| {
            c.found()
                .map(|r| format!("{} {}", r.param.label(), estimate_text(r)))
        })
        .collect();
    format!(
        "each half cycle on its own: {} of {} read, {} effect(s) found in them{}",
        read.len(),
        half.len(),
        found.len(),
        if found.is_empty() {
            String::new()
        } else {
            format!(" ({})", found.join("; "))
        }
    )
}

/// A found reading's alternatives: each candidate also beyond the band at its step, read
/// in its place.
pub fn alternatives_text(r: &Reading) -> String {
    r.alternatives
        .iter()
        .map(|&(p, v, z)| {
            let (v, unit) = p.display_value(v);
            format!("{} {v:+.2} {unit} (z {z:.1})", p.label())
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The smallest effect a reading would call found, about the untouched trials' centre,
/// e.g. `±9.75 ms`; `—` where the candidate was not tested.
pub fn smallest_found_text(r: &Reading) -> String {
    let v = r.smallest_found();
    if !v.is_finite() {
        return "—".into();
    }
    let (v, unit) = r.param.display_value(v);
    format!("±{v:.2} {unit}")
}

/// The null band a reading is judged against, in the reading's unit.
fn baseline_text(r: &Reading) -> String {
    if !r.baseline.mean.is_finite() {
        return "—".into();
    }
    let (m, unit) = r.param.display_value(r.baseline.mean);
    let (sd, _) = r.param.display_value(r.baseline.sd);
    format!("{m:+.2} ± {sd:.2} {unit}")
}

fn readings_table(c: &MeasurementCheck) -> Table {
    Table {
        title: "Readings of the whole-body balance".into(),
        headers: [
            "candidate",
            "estimate ± sd",
            "untouched trials read",
            "z",
            "threshold |z|",
            "found beyond",
            "explains",
            "verdict",
            "what else could produce it",
        ]
        .map(String::from)
        .to_vec(),
        rows: c
            .readings
            .iter()
            .map(|r| {
                vec![
                    r.param.label().into(),
                    estimate_text(r),
                    baseline_text(r),
                    fmt(r.z, 2),
                    fmt(r.threshold, 2),
                    smallest_found_text(r),
                    format!("{:.1} %", 100.0 * r.explained),
                    if r.alternatives.is_empty() {
                        r.verdict.text()
                    } else {
                        format!(
                            "{}; cannot be told here from {}",
                            r.verdict.text(),
                            alternatives_text(r)
                        )
                    },
                    r.param.look_alikes().into(),
                ]
            })
            .collect(),
    }
}

fn thresholds_table(c: &MeasurementCheck) -> Table {
    let row = |name: &str, t: &Thresholds| {
        vec![
            name.into(),
            format!("{:.1} N", t.peak_force),
            format!("{:.1} N", t.force_limit),
            pass(t.force_passes()),
            format!("{:.2} N·m", t.rms_moment),
            format!("{:.2} N·m", t.moment_limit),
            pass(t.moment_passes()),
        ]
    };
    Table {
        title: "Residual thresholds (Hicks et al. 2015)".into(),
        headers: [
            "",
            "peak residual force",
            "limit (5 % of peak ground force)",
            "",
            "RMS residual moment",
            "limit (1 % of COM height × peak force)",
            "",
        ]
        .map(String::from)
        .to_vec(),
        rows: vec![
            row("as measured", &c.thresholds[0]),
            row("corrected", &c.thresholds[1]),
        ],
    }
}

fn half_cycle_table(half: &[HalfCycle]) -> Table {
    let mut rows = Vec::new();
    for h in half {
        let span = format!("{:.3}–{:.3} s", h.span.0, h.span.1);
        match &h.result {
            Ok(c) => {
                let found: Vec<String> = c
                    .found()
                    .map(|r| format!("{} {}", r.param.label(), estimate_text(r)))
                    .collect();
                let clock = c.readings.iter().find(|r| r.param == Param::SharedClock);
                rows.push(vec![
                    span,
                    if found.is_empty() {
                        "—".into()
                    } else {
                        found.join("; ")
                    },
                    clock.map_or("—".into(), estimate_text),
                ]);
            }
            Err(e) => rows.push(vec![span, format!("not read: {e}"), String::new()]),
        }
    }
    Table {
        title: "Each half cycle on its own".into(),
        headers: ["half cycle", "found", "both plates' clock"]
            .map(String::from)
            .to_vec(),
        rows,
    }
}

fn pass(ok: bool) -> String {
    if ok { "pass" } else { "fail" }.into()
}

fn fmt(v: f64, d: usize) -> String {
    if v.is_finite() {
        format!("{v:.d$}")
    } else {
        "—".into()
    }
}

/// Three panels against time, one per component `[x, y, moment]`, each with the series
/// `series` gives for its component.
fn three_panels(
    c: &MeasurementCheck,
    names: [(&str, &str); 3],
    series: impl Fn(usize) -> Vec<(&'static str, Vec<f64>)>,
) -> String {
    let plots: Vec<LinePlot> = (0..3)
        .map(|i| {
            let mut p = LinePlot::new(names[i].0, "time (s)", names[i].1);
            for (name, y) in series(i) {
                p.series
                    .push(Series::new(name, c.time.clone(), y, LineStyle::Solid));
            }
            p
        })
        .collect();
    grid(&plots, 1)
}

fn residual_plots(c: &MeasurementCheck) -> String {
    let names = [
        ("horizontal residual force", "N"),
        ("vertical residual force", "N"),
        ("residual moment about the COM", "N·m"),
    ];
    three_panels(c, names, |i| {
        vec![
            ("as measured", c.before.iter().map(|r| r[i]).collect()),
            ("corrected", c.after.iter().map(|r| r[i]).collect()),
        ]
    })
}

fn momentum_plots(c: &MeasurementCheck) -> String {
    let names = [
        ("horizontal linear momentum", "N·s"),
        ("vertical linear momentum", "N·s"),
        ("angular momentum about the COM", "N·m·s"),
    ];
    three_panels(c, names, |i| {
        vec![("", c.momentum.iter().map(|m| m[i]).collect())]
    })
}

/// One quantity of the leg joints' inverse dynamics: its name, unit and values.
struct JointQuantity {
    what: &'static str,
    unit: &'static str,
    of: fn(&JointKinetics) -> [f64; 6],
}

const TORQUE: JointQuantity = JointQuantity {
    what: "torque",
    unit: "N·m",
    of: |k| k.torque,
};

const POWER: JointQuantity = JointQuantity {
    what: "power",
    unit: "W",
    of: |k| k.power,
};

/// Hip, knee and ankle against time, right and left in each panel.
fn joint_plots(c: &MeasurementCheck, q: &JointQuantity) -> String {
    let time: Vec<f64> = c.joints.iter().map(|k| k.t).collect();
    let plots: Vec<LinePlot> = ["hip", "knee", "ankle"]
        .iter()
        .enumerate()
        .map(|(j, joint)| {
            let mut p = LinePlot::new(format!("{joint} {}", q.what), "time (s)", q.unit);
            for (side, name) in [(0, "right"), (3, "left")] {
                let y = c.joints.iter().map(|k| (q.of)(k)[side + j]).collect();
                p.series
                    .push(Series::new(name, time.clone(), y, LineStyle::Solid));
            }
            p
        })
        .collect();
    grid(&plots, 1)
}

/// `time` and each leg joint's value, columns named `<joint>_<unit>` (`hip_r_Nm`).
fn joint_csv(c: &MeasurementCheck, q: &JointQuantity) -> String {
    let unit = q.unit.replace('·', "");
    let mut s = String::from("time");
    for name in JointKinetics::names() {
        write!(s, ",{name}_{unit}").ok();
    }
    s.push('\n');
    for k in &c.joints {
        write!(s, "{}", k.t).ok();
        for v in (q.of)(k) {
            write!(s, ",{v}").ok();
        }
        s.push('\n');
    }
    s
}

fn residual_csv(c: &MeasurementCheck) -> String {
    let mut s = String::from("time,fx_measured,fy_measured,m_measured,fx_corrected,fy_corrected,m_corrected,px,py,h_com\n");
    for k in 0..c.time.len() {
        let (b, a, m) = (c.before[k], c.after[k], c.momentum[k]);
        writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{}",
            c.time[k], b[0], b[1], b[2], a[0], a[1], a[2], m[0], m[1], m[2]
        )
        .ok();
    }
    s
}

fn summary_json(
    req: &CheckRequest,
    data: &GaitData,
    c: &MeasurementCheck,
    half: &[HalfCycle],
) -> serde_json::Value {
    let reading = |r: &Reading| {
        let (v, unit) = r.param.display_value(r.estimate);
        let (sd, _) = r.param.display_value(r.sd);
        let (least, _) = r.param.display_value(r.smallest_found());
        let mut j = json!({
            "effect": r.param.name(), "label": r.param.label(), "estimate": finite(r.estimate), "sd": finite(r.sd), "sd_within": finite(r.sd_within),
            "display": {"estimate": finite(v), "sd": finite(sd), "smallest_found": finite(least), "unit": unit},
            "z": finite(r.z), "threshold": finite(r.threshold), "smallest_found": finite(r.smallest_found()), "explained": r.explained,
            "untouched": {"mean": finite(r.baseline.mean), "sd": finite(r.baseline.sd)},
            "verdict": r.verdict.text(), "look_alikes": r.param.look_alikes(),
        });
        if !r.alternatives.is_empty() {
            j["alternatives"] = json!(r
                .alternatives
                .iter()
                .map(|(p, v, z)| json!({"effect": p.name(), "estimate": v, "z": z}))
                .collect::<Vec<_>>());
        }
        if let Verdict::NotSeparable { from } = &r.verdict {
            j["not_separable_from"] = json!(from.iter().map(|p| p.name()).collect::<Vec<_>>());
        }
        j
    };
    let half_json: Vec<serde_json::Value> = half
        .iter()
        .map(|h| match &h.result {
            Ok(c) => json!({"span_s": [h.span.0, h.span.1], "found": c.found().map(|r| r.param.name()).collect::<Vec<_>>(),
                "readings": c.readings.iter().map(reading).collect::<Vec<_>>(),
                "alone": c.alone.iter().map(reading).collect::<Vec<_>>()}),
            Err(e) => json!({"span_s": [h.span.0, h.span.1], "error": e.to_string()}),
        })
        .collect();
    let found_total: usize = half
        .iter()
        .filter_map(|h| h.result.as_ref().ok())
        .map(|c| c.found().count())
        .sum();
    json!({
        "command": "check",
        "trial": data.source.display().to_string(),
        "model": req.model.display().to_string(),
        "settings": {"cutoff_hz": req.settings.cutoff_hz, "level": req.settings.level, "bandwidth_s": req.settings.bandwidth_s, "clock_limit_s": req.settings.clock_limit_s, "lumbar": req.settings.lumbar},
        "rates_hz": {"forces": c.rates.0, "kinematics": c.rates.1},
        "window_s": [c.time.first(), c.time.last()],
        "instants": c.time.len(),
        "mass_kg": {"model": c.mass.0, "implied_by_forces": c.mass.1},
        "warnings": c.warnings,
        "candidates": c.readings.iter().map(reading).collect::<Vec<_>>(),
        "alone": c.alone.iter().map(reading).collect::<Vec<_>>(),
        "found": c.found().map(|r| r.param.name()).collect::<Vec<_>>(),
        "add_effects": effect_lines(c),
        "thresholds": {"as_measured": c.thresholds[0], "corrected": c.thresholds[1]},
        "trunk_rocking": c.trunk.map(|[frozen, moving]| serde_json::json!({"frozen": frozen, "moving": moving})),
        "half_cycles": half_json,
        "half_cycles_found_total": found_total,
    })
}

fn finite(v: f64) -> serde_json::Value {
    if v.is_finite() {
        json!(v)
    } else {
        serde_json::Value::Null
    }
}

/// Write every file of the check's run folder into `folder` (staged; the caller commits).
pub fn write_folder(
    folder: &RunFolder,
    req: &CheckRequest,
    data: &GaitData,
    c: &MeasurementCheck,
    half: &[HalfCycle],
) -> anyhow::Result<()> {
    let readings = readings_table(c);
    let thresholds = thresholds_table(c);
    let halves = half_cycle_table(half);
    let residual_svg = residual_plots(c);
    let momentum_svg = momentum_plots(c);
    let torque_svg = joint_plots(c, &TORQUE);
    let power_svg = joint_plots(c, &POWER);
    let verdict = verdict_text(c);
    folder.write(
        "summary.json",
        serde_json::to_string_pretty(&summary_json(req, data, c, half))?.as_bytes(),
    )?;
    folder.write(
        "readings.md",
        format!(
            "{}\n{}\n{}",
            readings.to_markdown(),
            thresholds.to_markdown(),
            halves.to_markdown()
        )
        .as_bytes(),
    )?;
    folder.write("readings.csv", readings.to_csv().as_bytes())?;
    folder.write("half_cycles.csv", halves.to_csv().as_bytes())?;
    folder.write("residual.csv", residual_csv(c).as_bytes())?;
    folder.write("residual.svg", residual_svg.as_bytes())?;
    folder.write("momentum.svg", momentum_svg.as_bytes())?;
    folder.write("joint_torques.csv", joint_csv(c, &TORQUE).as_bytes())?;
    folder.write("joint_torques.svg", torque_svg.as_bytes())?;
    folder.write("joint_powers.csv", joint_csv(c, &POWER).as_bytes())?;
    folder.write("joint_powers.svg", power_svg.as_bytes())?;
    folder.write(
        "effects.txt",
        effect_lines(c)
            .iter()
            .map(|l| format!("--effect {l}\n"))
            .collect::<String>()
            .as_bytes(),
    )?;
    let (csv, meta) = write_sagittal_csv_mixed(&corrected(data, c));
    std::fs::create_dir_all(folder.staging_path().join("corrected"))?;
    folder.write("corrected/trial.csv", csv.as_bytes())?;
    folder.write("corrected/trial_meta.json", meta.as_bytes())?;
    let found = c.found().count();
    let (status, tone) = if found == 0 {
        ("nothing found", Tone::Good)
    } else {
        ("effects found", Tone::Warning)
    };
    let mut summary = Summary::new(status, tone, verdict.lines().next().unwrap_or_default());
    summary.extra = vec![
        ("trial".into(), data.source.display().to_string()),
        (
            "body".into(),
            format!(
                "{} ({:.1} kg; the forces imply {:.1} kg)",
                req.model.display(),
                c.mass.0,
                c.mass.1
            ),
        ),
        (
            "window".into(),
            format!("{} instants at {:.0} Hz", c.time.len(), c.rates.0),
        ),
    ];
    let report = Report {
        title: format!("footfall check — {}", data.name),
        summary,
        sections: vec![
            Section {
                heading: "What the measurement says of itself".into(),
                paragraphs: vec![
                    "Measured motion and measured ground forces must satisfy Newton–Euler for the whole body, with no contact model. Each instrument or body error leaves its own signature in the residual; each candidate is read by least squares, jointly with those already found, and is found when it exceeds its Newey–West band by the Bonferroni-corrected point of the family-wise level.".into(),
                    verdict.clone(),
                ],
                tables: vec![readings, thresholds],
                svgs: vec![],
            },
            Section { heading: "Residual wrench".into(), paragraphs: vec!["The force and moment the measured loads leave unexplained, as measured and with the found effects corrected.".into()], tables: vec![], svgs: vec![residual_svg] },
            Section { heading: "Whole-body momentum".into(), paragraphs: vec!["Linear momentum and angular momentum about the centre of mass, from the measured motion and the model's segments.".into()], tables: vec![], svgs: vec![momentum_svg] },
            Section { heading: "Joint torques and powers".into(), paragraphs: vec!["The inverse dynamics of the measured trial as recorded (nothing corrected): each leg joint's torque in its coordinate's positive sense, each foot's load applied at its centre of pressure, and its power, the torque times the joint's angular velocity (positive where the torque does work on the body).".into()], tables: vec![], svgs: vec![torque_svg, power_svg] },
            Section { heading: "Each half cycle on its own".into(), paragraphs: vec![], tables: vec![halves], svgs: vec![] },
        ],
    };
    folder.write("report.html", report.to_html().as_bytes())?;
    Ok(())
}

/// The trial as a sagittal CSV at the force record's own instants where it has one
/// (rows between the kinematic ones carry forces only, their coordinates `NaN`).
pub fn write_sagittal_csv_mixed(data: &GaitData) -> (String, String) {
    let Some(f) = &data.forces else {
        return write_sagittal_csv(data);
    };
    let (head, meta) = write_sagittal_csv(data);
    let meta = match (
        serde_json::from_str::<serde_json::Value>(&meta),
        data.force_plate_height,
    ) {
        (Ok(mut m), Some(h)) => {
            m["force_plate_surface_y_m"] = json!(h);
            serde_json::to_string_pretty(&m).unwrap_or(meta)
        }
        _ => meta,
    };
    let header = head.lines().next().unwrap_or_default().to_string();
    let mut rows: Vec<(f64, String)> = Vec::new();
    for k in 0..data.time.len() {
        let mut r = format!("{}", data.time[k]);
        for q in &data.q {
            write!(r, ",{}", q[k]).ok();
        }
        rows.push((data.time[k], r));
    }
    let mut forces: Vec<(f64, String)> = (0..f.time.len())
        .map(|k| {
            let mut r = String::new();
            for foot in &f.feet {
                write!(r, ",{},{},{}", foot.fx[k], foot.fy[k], foot.cop_x[k]).ok();
            }
            (f.time[k], r)
        })
        .collect();
    forces.sort_by(|a, b| a.0.total_cmp(&b.0));
    let nan_q = ",NaN".repeat(9);
    let mut out = header + "\n";
    let mut i = 0;
    for (t, fr) in &forces {
        while i < rows.len() && rows[i].0 < *t - 1e-9 {
            writeln!(out, "{}{}", rows[i].1, ",NaN".repeat(6)).ok();
            i += 1;
        }
        if i < rows.len() && (rows[i].0 - t).abs() <= 1e-9 {
            writeln!(out, "{}{fr}", rows[i].1).ok();
            i += 1;
        } else {
            writeln!(out, "{t}{nan_q}{fr}").ok();
        }
    }
    for r in &rows[i..] {
        writeln!(out, "{}{}", r.1, ",NaN".repeat(6)).ok();
    }
    (out, meta)
}
