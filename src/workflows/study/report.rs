//! The study's files: `study.csv` (one row per trial), `study.json` (the table and the
//! pooled readings) and `report.html` (both, with each group's pooled readings), each
//! written atomically.

use super::entry::{Status, TrialEntry};
use super::findings::{value_text, GroupFindings, GroupKind};
use super::table::StudyTable;
use super::StudyError;
use crate::problems::check::Param;
use crate::report::html::{Report, Section, Summary, Tone};
use crate::report::plot::{BarChart, BarSeries};
use crate::report::table::Table;
use crate::runfolder::write_atomic;
use std::fmt::Write;
use std::path::Path;

/// Write `study.csv`, `study.json` and `report.html` into `dir`.
pub fn write(dir: &Path, t: &StudyTable) -> Result<(), StudyError> {
    let json = serde_json::to_string_pretty(t).map_err(|e| StudyError::file(dir, e))?;
    for (name, text) in [
        ("study.csv", csv(t)),
        ("study.json", json),
        ("report.html", html(t)),
    ] {
        write_atomic(dir, name, text.as_bytes())
            .map_err(|e| StudyError::file(&dir.join(name), e))?;
    }
    Ok(())
}

/// A number as Rust prints it (shortest round trip); empty where absent.
fn num(v: Option<f64>) -> String {
    v.filter(|x| x.is_finite())
        .map_or(String::new(), |x| x.to_string())
}

/// A CSV cell, quoted where needed.
fn cell(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `study.csv`: per trial its identity, status, error, the check's readings (estimate,
/// sd and verdict per candidate, SI units), the masses and the track's outcome.
pub fn csv(t: &StudyTable) -> String {
    let mut head = vec![
        "row",
        "id",
        "subject",
        "session",
        "condition",
        "data",
        "status",
        "error",
        "found",
    ]
    .into_iter()
    .map(String::from)
    .collect::<Vec<_>>();
    for p in Param::ALL {
        for suffix in ["", "_sd", "_verdict"] {
            head.push(format!("{}{suffix}", p.name()));
        }
    }
    head.extend(
        [
            "model_mass_kg",
            "implied_mass_kg",
            "track_status",
            "track_objective",
            "track_iterations",
            "diagnose_significant",
            "diagnose_found",
            "diagnose_add_effects",
        ]
        .map(String::from),
    );
    let mut s = head.join(",") + "\n";
    for e in &t.trials {
        s.push_str(
            &csv_row(e)
                .iter()
                .map(|c| cell(c))
                .collect::<Vec<_>>()
                .join(","),
        );
        s.push('\n');
    }
    s
}

fn csv_row(e: &TrialEntry) -> Vec<String> {
    let mut r = vec![
        e.row.to_string(),
        e.id.clone(),
        e.subject.clone(),
        e.session.clone(),
        e.condition.clone(),
        e.data.clone(),
        e.status.name().into(),
        e.error.clone().unwrap_or_default(),
        e.check
            .as_ref()
            .map_or(String::new(), |c| c.found.join(";")),
    ];
    for p in Param::ALL {
        let reading = e
            .check
            .as_ref()
            .and_then(|c| c.readings.iter().find(|x| x.effect == p.name()));
        r.push(num(reading.and_then(|x| x.estimate)));
        r.push(num(reading.and_then(|x| x.sd)));
        r.push(reading.map_or(String::new(), |x| x.verdict.clone()));
    }
    let mass = e.check.as_ref().map_or((None, None), |c| c.mass_kg);
    r.push(num(mass.0));
    r.push(num(mass.1));
    r.push(e.track.as_ref().map_or(String::new(), |x| x.status.clone()));
    r.push(num(e.track.as_ref().and_then(|x| x.objective)));
    r.push(
        e.track
            .as_ref()
            .and_then(|x| x.iterations)
            .map_or(String::new(), |i| i.to_string()),
    );
    let d = e.diagnose.as_ref();
    r.push(
        d.and_then(|d| d.significant)
            .map_or(String::new(), |n| n.to_string()),
    );
    r.push(
        d.and_then(|d| d.found)
            .map_or(String::new(), |n| n.to_string()),
    );
    r.push(d.map_or(String::new(), |d| d.add_effects.join(";")));
    r
}

fn group_heading(g: &GroupFindings) -> String {
    match g.kind {
        GroupKind::Session => format!("session {}: instruments", g.name),
        GroupKind::Subject => format!("subject {}: body", g.name),
    }
}

/// A few lines for the terminal: trials by status, the tracks that did not converge, and
/// each group's verdict.
pub fn summary_text(t: &StudyTable) -> String {
    let count = |s: Status| t.trials.iter().filter(|e| e.status == s).count();
    let mut out = format!(
        "study: {} trial(s): {} done, {} failed, {} not run\n",
        t.trials.len(),
        count(Status::Done),
        count(Status::Failed),
        count(Status::NotRun)
    );
    for e in t.trials.iter().filter(|e| e.error.is_some()) {
        writeln!(
            out,
            "  {} ({}): {}",
            e.id,
            e.status.name(),
            e.error.as_deref().unwrap_or("")
        )
        .ok();
    }
    let tracks: Vec<(&str, &str)> = t
        .trials
        .iter()
        .filter_map(|e| e.track.as_ref().map(|r| (e.id.as_str(), r.status.as_str())))
        .collect();
    if !tracks.is_empty() {
        let unconverged: Vec<String> = tracks
            .iter()
            .filter(|(_, status)| *status != "converged")
            .map(|(id, status)| format!("{id} ({status})"))
            .collect();
        write!(
            out,
            "tracks: {} of {} converged",
            tracks.len() - unconverged.len(),
            tracks.len()
        )
        .ok();
        if !unconverged.is_empty() {
            write!(out, "; not converged: {}", unconverged.join(", ")).ok();
        }
        out.push('\n');
    }
    for g in &t.pooled {
        writeln!(out, "{}: {}", group_heading(g), g.statements.join("; ")).ok();
    }
    out
}

fn trials_table(t: &StudyTable) -> Table {
    let mut headers: Vec<String> = ["id", "subject", "session", "condition", "status", "found"]
        .map(String::from)
        .to_vec();
    headers.extend(Param::ALL.iter().take(8).map(|p| p.label().to_string()));
    headers.push("track".into());
    headers.push("diagnosis suggests".into());
    let rows = t
        .trials
        .iter()
        .map(|e| {
            let mut r = vec![
                e.id.clone(),
                e.subject.clone(),
                e.session.clone(),
                e.condition.clone(),
                match &e.error {
                    Some(err) => format!("{}: {err}", e.status.name()),
                    None => e.status.name().into(),
                },
                e.check
                    .as_ref()
                    .map_or(String::new(), |c| c.found.join(", ")),
            ];
            for p in Param::ALL.iter().take(8) {
                let x = e
                    .check
                    .as_ref()
                    .and_then(|c| c.readings.iter().find(|x| x.effect == p.name()));
                r.push(match x.and_then(|x| Some((x.estimate?, x.sd?))) {
                    Some((v, sd)) => value_text(p.name(), v, sd),
                    None => "—".into(),
                });
            }
            r.push(e.track.as_ref().map_or("—".into(), |x| {
                format!(
                    "{}, J {}, {} it.",
                    x.status,
                    num(x.objective),
                    x.iterations.unwrap_or(0)
                )
            }));
            r.push(e.diagnose.as_ref().map_or("—".into(), |d| {
                if d.add_effects.is_empty() {
                    "nothing".into()
                } else {
                    d.add_effects.join("; ")
                }
            }));
            r
        })
        .collect();
    Table {
        title: "Trials: the check's readings (each jointly with what it found)".into(),
        headers,
        rows,
    }
}

/// One group's pooled readings; `threshold` is the study's |z| point, so that each row
/// says the smallest pooled effect, from what untouched trials read, it would be beyond.
fn group_table(g: &GroupFindings, threshold: Option<f64>) -> Table {
    Table {
        title: group_heading(g),
        headers: [
            "candidate",
            "pooled",
            "untouched trials read",
            "z",
            "beyond its band from",
            "trials",
            "Cochran's Q (df)",
            "p",
            "I²",
            "found by the check in",
            "beyond the band",
            "pooled jointly with the checks' findings",
        ]
        .map(String::from)
        .to_vec(),
        rows: g
            .readings
            .iter()
            .map(|r| {
                let p = &r.pooled;
                vec![
                    Param::from_name(&r.effect)
                        .map_or("?", |x| x.label())
                        .into(),
                    value_text(&r.effect, p.estimate, p.sd),
                    centre_text(&r.effect, p.centre),
                    format!("{:.2}", p.z),
                    threshold.map_or("—".into(), |z| {
                        format!(
                            "±{}",
                            centre_text(&r.effect, z * p.sd).trim_start_matches('+')
                        )
                    }),
                    p.trials.to_string(),
                    format!("{:.2} ({})", p.q, p.df),
                    format!("{:.3}", p.p_heterogeneity),
                    format!("{:.0} %", 100.0 * p.i2),
                    r.found_in.join(", "),
                    if r.beyond { "yes" } else { "no" }.into(),
                    r.joint
                        .map_or("—".into(), |j| value_text(&r.effect, j.estimate, j.sd)),
                ]
            })
            .collect(),
    }
}

/// The shared effect of a group: each trial's reading alone (its sd on the bar) against
/// the pooled value.
fn shared_chart(t: &StudyTable, g: &GroupFindings) -> Option<String> {
    let effect = g.shared.as_deref()?;
    let p = Param::from_name(effect)?;
    let pooled = g.readings.iter().find(|r| r.effect == effect)?.pooled;
    let (mut values, mut labels) = (Vec::new(), Vec::new());
    for id in &g.trials {
        let r = t
            .trials
            .iter()
            .find(|e| &e.id == id)
            .and_then(|e| e.check.as_ref())
            .and_then(|c| c.alone.iter().find(|r| r.effect == effect));
        let (v, sd) = (r.and_then(|r| r.estimate), r.and_then(|r| r.sd));
        values.push(v.map_or(f64::NAN, |v| p.display_value(v).0));
        labels.push(sd.map_or(String::new(), |sd| {
            format!("± {:.2}", p.display_value(sd).0)
        }));
    }
    let (v, unit) = p.display_value(pooled.estimate);
    let mut chart = BarChart::new(format!("{}: each trial read alone", p.label()), unit);
    chart.categories = g.trials.clone();
    chart.series = vec![BarSeries::new("read alone", values, labels)];
    chart.reference = Some((
        v,
        format!("pooled {}", value_text(effect, pooled.estimate, pooled.sd)),
    ));
    Some(chart.to_svg())
}

/// `report.html`.
pub fn html(t: &StudyTable) -> String {
    let shared: Vec<String> = t
        .pooled
        .iter()
        .filter_map(|g| {
            g.shared
                .as_ref()
                .map(|s| format!("{} ({})", s, group_heading(g)))
        })
        .collect();
    let failed = t.trials.iter().filter(|e| e.error.is_some()).count();
    let (status, tone) = match (failed, shared.is_empty()) {
        (0, true) => ("nothing shared found", Tone::Good),
        (0, false) => ("shared effects found", Tone::Warning),
        _ => ("some trials have no results", Tone::Bad),
    };
    let mut summary = Summary::new(
        status,
        tone,
        summary_text(t).lines().next().unwrap_or_default(),
    );
    summary.extra = vec![(
        "threshold".into(),
        t.threshold.map_or("nothing pooled".into(), |z| {
            format!(
                "|z| > {z:.2} (family-wise {} over the study's pooled readings)",
                t.level
            )
        }),
    )];
    let mut sections = vec![Section {
        heading: "Trials".into(),
        paragraphs: vec!["One row per trial of the manifest: its status and the measurement check's readings (estimate ± sd) of the plates and the body. Each trial's folder is trials/ID/.".into()],
        tables: vec![trials_table(t)],
        svgs: vec![],
    }];
    sections.push(Section {
        heading: "Across trials".into(),
        paragraphs: vec!["Each candidate read alone in every trial, pooled by inverse-variance weighting over a lab session's trials (the plates) and a subject's (the body). The body model's own error, the spread untouched trials show, is common to a subject's trials and is added once to the pooled sd. Cochran's Q and I² say whether the trials read the same value.".into()],
        tables: t.pooled.iter().filter(|g| !g.readings.is_empty()).map(|g| group_table(g, t.threshold)).collect(),
        svgs: vec![],
    });
    for g in &t.pooled {
        sections.push(Section {
            heading: group_heading(g),
            paragraphs: g.statements.clone(),
            tables: vec![],
            svgs: shared_chart(t, g).into_iter().collect(),
        });
    }
    Report {
        title: "footfall study".into(),
        summary,
        sections,
    }
    .to_html()
}

/// A band's centre in the candidate's reporting unit, e.g. `+5.58 ms`.
fn centre_text(effect: &str, centre: f64) -> String {
    match Param::from_name(effect) {
        Some(p) => {
            let (v, unit) = p.display_value(centre);
            format!("{v:+.2} {unit}")
        }
        None => format!("{centre:+.4}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::workflows::study::entry::TrackResult;

    fn entry(id: &str, track: Option<&str>) -> TrialEntry {
        TrialEntry {
            row: 1,
            id: id.into(),
            subject: "s".into(),
            session: "lab".into(),
            condition: "untouched".into(),
            data: "trial.csv".into(),
            status: Status::Done,
            error: None,
            check: None,
            track: track.map(|status| TrackResult {
                status: status.into(),
                objective: Some(7.0),
                iterations: Some(40),
            }),
            diagnose: None,
        }
    }

    /// The summary counts the tracks that converged and names those that did not, with
    /// their stop reasons; a study without tracks says nothing of them.
    #[test]
    fn the_summary_names_the_tracks_that_did_not_converge() {
        let table = |trials| StudyTable {
            trials,
            pooled: Vec::new(),
            threshold: None,
            level: 0.05,
        };
        let text = summary_text(&table(vec![
            entry("a", Some("converged")),
            entry("b", Some("max_iterations")),
            entry("c", Some("evaluation_failure")),
        ]));
        assert!(
            text.contains(
                "tracks: 1 of 3 converged; not converged: b (max_iterations), c (evaluation_failure)"
            ),
            "{text}"
        );
        let checks_only = summary_text(&table(vec![entry("a", None)]));
        assert!(!checks_only.contains("tracks"), "{checks_only}");
    }
}
