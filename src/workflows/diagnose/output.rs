//! What `diagnose` writes: `diagnose.md`, `summary.json` and `report.html`, each with
//! every candidate's testability, in-sample statistic, held-out change and verdict.

#[allow(unused_imports)]
use super::super::{note, Progress};
use super::noise::{FullModel, Residuals};
use super::summary::{
    self, ChannelInflation, DiagnosisSummary, NoiseModel, VarianceInflation, VerifiedParameter,
    VerifiedRecord,
};
use super::{DiagnoseRequest, Evidence, Verified};
use crate::problems::diagnose::stats::variance_inflation;
use crate::problems::diagnose::{HeldOut, ScoreTest, NOT_VALIDATABLE};
use crate::report::diff::{fmt_value, RunSummary};
use crate::report::html::{Report, Section, Summary, Tone};
use crate::report::table::Table;
use crate::runfolder::RunFolder;

/// Everything a diagnosis found.
pub(super) struct Outcome<'a> {
    pub args: &'a DiagnoseRequest,
    pub before: &'a RunSummary,
    pub objective: f64,
    pub rows: usize,
    pub resid: &'a Residuals,
    /// Variance inflation over all channels alike.
    pub phi: f64,
    /// The largest model, whose residuals are the noise (when more than one candidate
    /// was scored).
    pub noise: Option<&'a FullModel>,
    pub tests: &'a [ScoreTest],
    pub evidence: &'a [Evidence],
    pub verified: &'a [Verified],
    pub skipped: &'a [String],
    /// How the held-out validation went (empty when none was needed).
    pub held_out_note: String,
    /// The measurement stage's verdict (`footfall check`), shown before the model
    /// stage's (`None`: the trial could not be checked, which was said).
    pub measurement: Option<String>,
    /// The plain model's track of the held-out half cycle, kept in `held_out/` (a start
    /// for a later diagnosis of the run, `--start`).
    pub held_out: Option<&'a super::heldout::HeldOutBase>,
    /// Whether a held clock moves its plate's events in the run's cost (sample or
    /// one-sided targets), so that one is added held rather than freed.
    pub clock_moves_events: bool,
}

/// The first found candidate in `track --effect` form, at its reading to four significant
/// digits: held where it is a plate's clock that moves its plate's events (a free one
/// cannot), otherwise freed and started there, so that the re-fit identifies it. Both
/// plates' gains read jointly are one entry per plate. Empty when nothing was found or a
/// value has no command-line form.
pub(super) fn add_effects(tests: &[ScoreTest], clock_moves_events: bool) -> Vec<String> {
    let Some(t) = tests.iter().find(|t| t.found) else {
        return Vec::new();
    };
    let four_digits = |v: f64| {
        if v == 0.0 || !v.is_finite() {
            return v;
        }
        let scale = 10f64.powi(3 - v.abs().log10().floor() as i32);
        (v * scale).round() / scale
    };
    let values: Vec<f64> = t.step_values.iter().map(|&v| four_digits(v)).collect();
    let Ok(specs) = super::heldout::fixed_at(&t.effect, &t.parameters, &values, false) else {
        return Vec::new();
    };
    specs
        .into_iter()
        .map(|mut e| {
            let clock = matches!(
                e,
                crate::model::effects::EffectSpec::ForcePlateTimeOffset { .. }
            );
            if !(clock && clock_moves_events) {
                e.free_all();
            }
            e.cli_text()
        })
        .collect::<Option<Vec<_>>>()
        .unwrap_or_default()
}

/// Each channel's variance inflation in the largest model's residuals.
fn noise_inflation(full: &FullModel) -> Vec<(String, Option<f64>)> {
    let values: Vec<Vec<f64>> = full.series.iter().map(|s| s.1.clone()).collect();
    let (phis, _) = variance_inflation(&values, &[]);
    full.series.iter().map(|s| s.0.clone()).zip(phis).collect()
}

/// "value ± sd" of each of a candidate's parameters after its truncated re-fit.
fn parameters_cell(t: &ScoreTest) -> String {
    t.parameters
        .iter()
        .zip(&t.step_values)
        .enumerate()
        .map(|(i, (n, v))| {
            let sd = if t.at_bound.contains(n) {
                " (at its bound)".to_string()
            } else {
                t.identifiability
                    .as_ref()
                    .and_then(|id| id.sd.get(i).copied().flatten())
                    .map_or(String::new(), |s| format!(" ± {s:.2e}"))
            };
            // the last part of the name, or all but the kind where two share it (both
            // plates' gains read jointly: `right.error`, `left.error`)
            fn short(n: &str) -> &str {
                n.rsplit('.').next().unwrap_or(n)
            }
            let shared = t.parameters.iter().filter(|m| short(m) == short(n)).count() > 1;
            let name = if shared {
                n.split_once('.').map_or(n.as_str(), |(_, rest)| rest)
            } else {
                short(n)
            };
            format!("{name} = {v:.4}{sd}")
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The held-out cell: "change (% of J) vs band" or why there is none.
fn held_out_cell(t: &ScoreTest) -> String {
    match &t.held_out {
        Some(h) => format!(
            "{:.3e} ({:+.1} % of J) vs {:.3e}{}",
            h.change,
            100.0 * h.change_fraction,
            h.band,
            reading_text(h)
        ),
        None if t.significant => "not run".into(),
        None => "—".into(),
    }
}

/// What the held-out half cycle itself reads of a candidate (`; reads 0.62 ± 0.41 of
/// it`), empty when it was not measured.
fn reading_text(h: &HeldOut) -> String {
    h.reading.as_ref().map_or(String::new(), |r| {
        format!(
            "; {}{}",
            r.text(),
            if r.powered {
                ""
            } else {
                " (too weakly informed to tell)"
            }
        )
    })
}

/// The diagnosis' first sentence: what was found, and whether a held-out half cycle
/// confirmed it. A significant candidate that no held-out half cycle tested (validation
/// off, none to hold out) counts as found in the summary's tally, but is never called
/// found or "the most likely missing effect" here without saying it was not validated.
fn found_sentence(tests: &[ScoreTest]) -> String {
    let found: Vec<&ScoreTest> = tests.iter().filter(|t| t.found).collect();
    let significant = tests.iter().filter(|t| t.significant).count();
    if found.is_empty() {
        return if significant == 0 {
            "No testable candidate explains more than the noise: every statistic (corrected for correlated residuals) is below its 0.1 % point. No effect is suggested.".to_string()
        } else {
            format!("{significant} candidate(s) are significant in-sample, but none is found: each fails to lower the error of the held-out half cycle beyond its noise band, or that half cycle cannot tell, or it reads a value at its bound (the verdicts say which).")
        };
    }
    let confirmed = found.iter().filter(|t| t.held_out.is_some()).count();
    let unvalidated = found.len() - confirmed;
    let first = found[0].label.as_str();
    if unvalidated == 0 {
        format!(
            "{} of {} candidates found (significant in-sample and confirmed on the held-out half cycle); the most likely missing effect is {first}.",
            found.len(),
            tests.len()
        )
    } else if confirmed == 0 {
        format!(
            "{} of {} candidates are significant in-sample, none validated on a held-out half cycle (the verdicts say why): the first by the decrease it explains (beyond what it lowers on the model's own trial) is {first}, which a held-out half cycle would have to confirm.",
            found.len(),
            tests.len()
        )
    } else {
        format!(
            "{} of {} candidates found: {confirmed} confirmed on the held-out half cycle, {unvalidated} significant in-sample but not validated; the most likely missing effect is {first}{}.",
            found.len(),
            tests.len(),
            if found[0].held_out.is_some() {
                ""
            } else {
                " (not validated)"
            }
        )
    }
}

/// The verdict sentence of the whole diagnosis.
fn verdict(o: &Outcome<'_>) -> String {
    let tests = o.tests;
    let untestable: Vec<&ScoreTest> = tests.iter().filter(|t| !t.testable).collect();
    let mut v = found_sentence(tests);
    let add = add_effects(tests, o.clock_moves_events);
    if let Some(t) = tests
        .iter()
        .find(|t| t.found)
        .filter(|t| t.reading_biased())
    {
        v += &format!(
            " Its direction is found, not its value: on the model's own trial, {}, so the run's value says how far the cost leans, not the subject's.",
            t.model_null_text()
        );
    }
    if !add.is_empty() {
        v += &format!(
            " Add it with one line and re-fit: `footfall track <the run's options> --init {} {}`{}; then diagnose that run, where what it explained is the model's and the next missing effect can show.",
            o.args.run.display(),
            add.iter().map(|a| format!("--effect {a}")).collect::<Vec<_>>().join(" "),
            if add.iter().any(|a| a.starts_with("force_plate_time_offset") && a.ends_with("free=")) {
                " (the clock held at its reading: with sample or one-sided targets a free clock cannot move its plate's events)"
            } else {
                ""
            }
        );
    }
    let weak: Vec<&ScoreTest> = tests
        .iter()
        .filter(|t| t.verdict == NOT_VALIDATABLE)
        .collect();
    if !weak.is_empty() {
        v += &format!(
            " Significant in-sample but not validatable on the held-out half cycle, which reads each too loosely to confirm or refute it (to better than half its size at 2 sd; neither confirmed nor refuted): {}. What would validate one: a second trial of the same subject, or a half cycle where its data play the part they play in this one (a plate's foot in stance in both).",
            weak.iter()
                .map(|t| match t.held_out.as_ref().and_then(|h| h.reading.as_ref()) {
                    Some(r) => format!("{} (held out it reads {:.2} ± {:.2} of its fitted value)", t.label, r.fraction, r.sd),
                    None => t.label.clone(),
                })
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    if !untestable.is_empty() {
        v += &format!(
            " Not testable with this run's cost (neither absent nor present as far as this run can tell): {}.",
            untestable
                .iter()
                .map(|t| format!("{} — {}", t.label, t.hint.as_deref().unwrap_or("")))
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    // the score tests compare against the plain model's optimum; say so when the run
    // stopped short of it
    if o.before.status.as_deref().is_some_and(|s| s != "converged") {
        let reason = o
            .before
            .stop_reason
            .as_deref()
            .or(o.before.status.as_deref())
            .unwrap_or_default();
        v += &format!(
            " Caution: the run did not converge ({reason}), and the score tests assume the plain model's optimum; re-track it to convergence before trusting this ranking."
        );
    }
    v
}

/// The ranking of the candidates: testability, in-sample statistic, held-out change and
/// verdict.
fn ranking_table(tests: &[ScoreTest]) -> Table {
    Table {
        title: "Candidate effects ranked: testability, in-sample score statistic (predicted cost decrease / the largest model's residual mean square, divided by the variance inflation φ of correlated residuals), its decrease on the model's own trial (made at the trial's noise) and the 0.1 % point that sets (χ²ₖ, or the noncentral χ²ₖ(λ)), held-out change, verdict".into(),
        headers: ["rank", "effect", "testable", "parameters (truncated re-fit, ± sd)", "expected decrease", "% of J", "statistic", "φ", "on the model's own trial (λ)", "0.1 % point", "held-out change vs noise band", "verdict"].map(String::from).to_vec(),
        rows: tests
            .iter()
            .enumerate()
            .map(|(i, t)| {
                vec![
                    (i + 1).to_string(),
                    t.label.clone(),
                    if t.testable { "yes".into() } else { "NO".into() },
                    parameters_cell(t),
                    format!("{:.3e}", t.predicted_decrease),
                    format!("{:.1}", 100.0 * t.predicted_fraction),
                    // an untestable candidate's statistic is no evidence of absence
                    if t.testable { format!("{:.1}", t.statistic) } else { "n/a".into() },
                    format!("{:.1}", t.inflation),
                    t.model_null.map_or("—".into(), |d0| {
                        format!("{d0:.3e} ({:.1})", t.noncentrality)
                    }),
                    format!("{:.1}", t.threshold),
                    held_out_cell(t),
                    t.verdict.clone(),
                ]
            })
            .collect(),
    }
}

/// One sentence per untestable candidate: why, and how to make it testable.
fn untestable_sentences(tests: &[ScoreTest]) -> Vec<String> {
    tests
        .iter()
        .filter(|t| !t.testable)
        .map(|t| {
            format!(
                "{} is not testable with this run's cost: {}. To make it testable: {}.",
                t.label,
                t.identifiability
                    .as_ref()
                    .and_then(|i| i.reason.clone())
                    .unwrap_or_default(),
                t.hint.as_deref().unwrap_or("")
            )
        })
        .collect()
}

/// The paragraph on correlated residuals: each channel's variance inflation, the plain
/// model's and the largest model's, and how the statistics use them.
fn inflation_paragraph(o: &Outcome<'_>) -> String {
    format!(
        "Correlated residuals: per channel, the variance inflation φ = N/N_eff (N_eff = N/(1 + 2 Σ ρ_k), ρ_k the error's autocorrelation at the nodes, summed up to the first lag ≤ 0): {}; these are the plain model's; each candidate's statistic is divided by the φ of the residuals left after the truncated re-fit of the largest model (every scored candidate at once; as an F-test takes the larger model's variance), averaged over the channels the candidate's re-fit improves, weighted by their relative improvement.",
        o.resid
            .series
            .iter()
            .zip(&o.resid.inflation)
            .map(|(s, p)| format!("{} {}", s.0, p.map_or("—".into(), |p| format!("{p:.1}"))))
            .collect::<Vec<_>>()
            .join(", ")
    ) + &match o.noise {
        Some(full) => format!(
            " The largest model ({}) lowers J from {:.6} to {:.6}; its residuals' φ per channel: {}; every statistic's residual mean square is its J/N. The actuator properties are left out of it: they lower J on data that do not ask for them (they relieve the effort term), which would pass for a smaller noise.",
            full.effects.join(", "),
            o.objective,
            full.objective,
            noise_inflation(full)
                .iter()
                .map(|(c, p)| format!("{c} {}", p.map_or("—".into(), |p| format!("{p:.1}"))))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        None => " Each candidate's own re-fit is the largest model; the residual mean square is the run's J/N.".into(),
    }
}

/// Each candidate's expected mean error per channel, before → after its truncated re-fit.
fn expected_table(tests: &[ScoreTest]) -> Table {
    // channels by name: a re-fit's come from its run summary, a score test's from the
    // problem
    let channels: Vec<(String, String)> = tests.first().map_or(vec![], |t| {
        t.expected_channels
            .iter()
            .map(|c| (c.0.clone(), c.1.clone()))
            .collect()
    });
    Table {
        title: "Expected mean error per channel after the truncated re-fit with each candidate (a full re-fit for the heel pad; before → after)".into(),
        headers: std::iter::once("effect".to_string()).chain(channels.iter().map(|(c, u)| format!("{c} ({u})"))).collect(),
        rows: tests
            .iter()
            .map(|t| {
                std::iter::once(t.label.clone())
                    .chain(channels.iter().map(|(name, _)| t.expected_channels.iter().find(|c| &c.0 == name).map_or("—".into(), |c| format!("{} → {}", fmt_value(c.2), fmt_value(c.3)))))
                    .collect()
            })
            .collect(),
    }
}

/// One note per candidate tested by a full re-fit (no null value for a score test).
fn refit_notes(tests: &[ScoreTest], evidence: &[Evidence]) -> Vec<String> {
    tests
        .iter()
        .zip(evidence)
        .filter_map(|(t, e)| match e {
            Evidence::Refit(run, _) => Some(format!(
                "{} was tested by a full re-fit ({}, {}), as it has no null value for a score test",
                t.label,
                run.output.path.display(),
                if run.converged {
                    "converged"
                } else {
                    "did NOT converge"
                }
            )),
            Evidence::Start(_) => None,
        })
        .collect()
}

/// A verified candidate's account: its re-fit and identified values, and the curves
/// before and after side by side in a report of their own, written into `folder`.
fn verified_text(
    args: &DiagnoseRequest,
    v: &Verified,
    folder: &RunFolder,
) -> anyhow::Result<String> {
    let params = v
        .parameters
        .iter()
        .map(|(n, val, sd, u)| {
            format!(
                "{n} = {val:.5}{} {u}",
                sd.map_or(String::new(), |s| format!(" ± {s:.2e}"))
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    let text = format!(
        "Re-fit with {} ({}): J {:.6} → {:.6} ({:.1} % lower; expected {:.1} %), {}. Identified: {params}. {}.",
        v.test.label,
        v.folder.display(),
        v.objective_before,
        v.objective_after,
        100.0 * (v.objective_before - v.objective_after) / v.objective_before,
        100.0 * v.test.predicted_fraction,
        if v.converged { "converged" } else { "did NOT converge" },
        v.sentence
    );
    // the curves before and after, side by side, in a report of their own
    let side_by_side = format!("before_after_{}.html", v.test.effect.kind());
    Ok(
        match [&args.run, &v.folder]
            .iter()
            .map(|p| crate::report::runs::RunCurves::read(p))
            .collect::<Result<Vec<_>, _>>()
        {
            Ok(runs) => {
                folder.write(
                    &side_by_side,
                    crate::report::runs::side_by_side(&runs)
                        .to_html()
                        .as_bytes(),
                )?;
                format!("{text} The curves before and after, side by side: {side_by_side}.")
            }
            Err(e) => format!("{text} (No side-by-side curves: {e}.)"),
        },
    )
}

/// The record of `summary.json`.
fn summary_record(o: &Outcome<'_>, verdict: &str) -> DiagnosisSummary {
    let tests = o.tests;
    DiagnosisSummary {
        command: summary::COMMAND.into(),
        run: o.args.run.clone(),
        objective: o.objective,
        data_residuals: o.rows,
        baseline_decrease: o.resid.decrease,
        variance_inflation: VarianceInflation {
            all_channels: o.phi,
            channels: o
                .resid
                .series
                .iter()
                .zip(&o.resid.inflation)
                .map(|(s, p)| ChannelInflation {
                    channel: s.0.clone(),
                    inflation: *p,
                })
                .collect(),
        },
        noise_model: o.noise.map(|full| NoiseModel {
            effects: full.effects.clone(),
            objective: full.objective,
            inflation: noise_inflation(full)
                .into_iter()
                .map(|(channel, inflation)| ChannelInflation { channel, inflation })
                .collect(),
        }),
        ranking: tests.to_vec(),
        significant: tests.iter().filter(|t| t.significant).count(),
        found: tests.iter().filter(|t| t.found).count(),
        untestable: tests.iter().filter(|t| !t.testable).count(),
        held_out_note: o.held_out_note.clone(),
        measurement: o.measurement.clone(),
        verdict: verdict.to_string(),
        add_effects: add_effects(tests, o.clock_moves_events),
        verified: o
            .verified
            .iter()
            .map(|v| VerifiedRecord {
                effect: v.test.effect.clone(),
                label: v.test.label.clone(),
                folder: v.folder.clone(),
                converged: v.converged,
                objective_before: v.objective_before,
                objective_after: v.objective_after,
                predicted_fraction: v.test.predicted_fraction,
                verified_fraction: (v.objective_before - v.objective_after) / v.objective_before,
                parameters: v
                    .parameters
                    .iter()
                    .map(|(name, value, sd, unit)| VerifiedParameter {
                        name: name.clone(),
                        value: *value,
                        unit: unit.clone(),
                        sd: *sd,
                    })
                    .collect(),
                sentence: v.sentence.clone(),
            })
            .collect(),
        skipped: o.skipped.to_vec(),
    }
}

/// The report's summary box: how many candidates were found, the verdict and the run's
/// figures.
fn summary_box(o: &Outcome<'_>, verdict: &str) -> Summary {
    let tests = o.tests;
    let significant = tests.iter().filter(|t| t.significant).count();
    let found = tests.iter().filter(|t| t.found).count();
    Summary {
        status: if found > 0 {
            format!("{found} found")
        } else if significant > 0 {
            format!("{significant} significant in-sample, none confirmed")
        } else {
            "nothing significant".into()
        },
        tone: if found == 0 {
            Tone::Good
        } else {
            Tone::Warning
        },
        stop_reason: verdict.to_string(),
        iterations: None,
        time_s: None,
        extra: vec![
            ("tracking cost J".into(), format!("{:.6}", o.objective)),
            ("data residuals".into(), o.rows.to_string()),
            ("variance inflation φ".into(), format!("{:.1}", o.phi)),
            (
                "untestable candidates".into(),
                tests.iter().filter(|t| !t.testable).count().to_string(),
            ),
        ],
    }
}

/// Write the diagnosis into `folder` and commit it.
pub(super) fn write(
    o: &Outcome<'_>,
    folder: RunFolder,
    progress: &dyn Progress,
) -> anyhow::Result<()> {
    let (args, tests) = (o.args, o.tests);
    let verdict = verdict(o);
    let ranking = ranking_table(tests);
    let expected = expected_table(tests);
    let mut paragraphs: Vec<String> = o.measurement.iter().cloned().collect();
    paragraphs.push(format!(
        "Stage 2, the model against the measurement: {verdict}"
    ));
    if !o.held_out_note.is_empty() {
        paragraphs.push(o.held_out_note.clone());
    }
    paragraphs.push(inflation_paragraph(o));
    paragraphs.extend(untestable_sentences(tests));
    paragraphs.extend(
        refit_notes(tests, o.evidence)
            .iter()
            .map(|r| format!("{r}.")),
    );
    let mut md = format!(
        "# Diagnosis of {}\n\n{}\n\n{}\n\n{}\n",
        args.run.display(),
        paragraphs.join("\n\n"),
        ranking.to_markdown(),
        expected.to_markdown()
    );
    let mut sections = vec![Section {
        heading: "Ranking".into(),
        paragraphs,
        tables: vec![ranking.clone(), expected],
        svgs: vec![],
    }];
    for v in o.verified {
        let text = verified_text(args, v, &folder)?;
        md += &format!(
            "\n## {}\n\n{text}\n\n{}\n",
            v.test.label,
            v.diff.table().to_markdown()
        );
        sections.push(Section {
            heading: format!("Verified: {}", v.test.label),
            paragraphs: vec![text],
            tables: vec![v.diff.table()],
            svgs: vec![v.diff.chart().to_svg()],
        });
    }
    if !o.skipped.is_empty() {
        md += &format!("\nNot tested: {}\n", o.skipped.join("; "));
    }
    let summary = summary_record(o, &verdict);
    folder.write("diagnose.md", md.as_bytes())?;
    if let Some(hb) = o.held_out {
        hb.write_into(&folder.staging_path().join("held_out"))?;
    }
    folder.write(
        "summary.json",
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    let report = Report {
        title: format!("footfall diagnose — {}", args.run.display()),
        summary: summary_box(o, &verdict),
        sections,
    };
    folder.write("report.html", report.to_html().as_bytes())?;
    let path = folder.commit()?;
    note!(
        progress,
        "\n{md}\nreport: {}",
        path.join("report.html").display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problems::diagnose::significant_slope;

    /// A significant slope candidate (statistic 20 against 10.8), held out with
    /// `held_out`: `Some(true)` beyond its band, `Some(false)` within it, `None` not run.
    fn slope(held_out: Option<bool>) -> ScoreTest {
        let mut t = significant_slope();
        t.held_out = held_out.map(|beyond| HeldOut {
            stride: 1,
            mirrored: false,
            trial: None,
            window: (0.0, 0.5),
            values: vec![0.01],
            objective: 1.0,
            change: if beyond { 0.1 } else { -0.1 },
            change_fraction: 0.1,
            band: 0.05,
            beyond_noise: beyond,
            reading: None,
        });
        t.settle();
        t
    }

    /// Only a candidate a held-out half cycle confirmed is called found without a
    /// qualifier; one that none tested is "significant in-sample, none validated".
    #[test]
    fn the_headline_says_whether_a_held_out_half_cycle_confirmed_what_is_found() {
        let confirmed = found_sentence(&[slope(Some(true))]);
        assert!(
            confirmed.starts_with("1 of 1 candidates found (significant in-sample and confirmed"),
            "{confirmed}"
        );
        let unvalidated = found_sentence(&[slope(None), slope(None)]);
        assert!(
            unvalidated.starts_with("2 of 2 candidates are significant in-sample, none validated"),
            "{unvalidated}"
        );
        assert!(
            !unvalidated.contains("most likely missing effect"),
            "{unvalidated}"
        );
        let mixed = found_sentence(&[slope(None), slope(Some(true))]);
        assert!(
            mixed.contains(
                "1 confirmed on the held-out half cycle, 1 significant in-sample but not validated"
            ),
            "{mixed}"
        );
        assert!(mixed.ends_with("(not validated)."), "{mixed}");
        let rejected = found_sentence(&[slope(Some(false))]);
        assert!(rejected.contains("none is found"), "{rejected}");
    }
}
