//! What `diagnose` writes: `diagnose.md`, `summary.json` and `report.html`, each with
//! every candidate's testability, in-sample statistic, held-out change and verdict.

#[allow(unused_imports)]
use super::super::{note, Progress};
use super::summary::{
    self, ChannelInflation, DiagnosisSummary, NoiseModel, VarianceInflation, VerifiedParameter,
    VerifiedRecord,
};
use super::{DiagnoseRequest, Evidence, Residuals, Verified};
use crate::problems::diagnose::stats::variance_inflation;
use crate::problems::diagnose::{HeldOut, ScoreTest, NOT_VALIDATABLE};
use crate::report::diff::{fmt_value, RunSummary};
use crate::report::html::{Report, Section, Summary, Tone};
use crate::report::table::Table;
use crate::runfolder::RunFolder;
use std::path::PathBuf;

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
    pub noise: Option<&'a super::FullModel>,
    pub tests: &'a [ScoreTest],
    pub evidence: &'a [Evidence],
    pub verified: &'a [Verified],
    pub skipped: &'a [String],
    /// How the held-out validation went (empty when none was needed).
    pub held_out_note: String,
    /// The run re-tracked by `--make-testable` (diagnosed into `<it>-diagnose`).
    pub testable_run: Option<PathBuf>,
    /// The readings against a reference trial's (`--reference`).
    pub comparison: Option<&'a super::reference::Comparison>,
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
fn noise_inflation(full: &super::FullModel) -> Vec<(String, Option<f64>)> {
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
            "No testable candidate explains more than the noise: every statistic (corrected for correlated residuals) is below its χ² 0.1 % point. No effect is suggested.".to_string()
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
            "{} of {} candidates are significant in-sample, none validated on a held-out half cycle (the verdicts say why): the first by the decrease it explains is {first}, which a held-out half cycle would have to confirm.",
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

/// A likelihood ratio as people read it: `4.8 : 1`, `2.1e5 : 1`.
fn ratio_text(r: f64) -> String {
    if r < 1e4 {
        format!("{r:.1} : 1")
    } else {
        format!("{r:.1e} : 1")
    }
}

/// Which plate's clock differs from the reference's, by the joint reading of both
/// plates' clocks (`None`: not read jointly in both runs).
fn joint_clock_sentence(c: &super::reference::Comparison) -> Option<String> {
    use super::plate_clocks::{PARAMETERS, RELATIVE};
    let (r, l, rel) = (
        c.joint(PARAMETERS[0])?,
        c.joint(PARAMETERS[1])?,
        c.joint(RELATIVE)?,
    );
    let read = |d: &super::reference::Difference| {
        format!(
            "{:+.1} ± {:.1} ms ({:+.1} sd)",
            1e3 * d.difference,
            1e3 * d.sd,
            d.z
        )
    };
    let which = match (r.significant, l.significant, rel.significant) {
        (true, false, _) => "it is the right plate's clock",
        (false, true, _) => "it is the left plate's clock",
        (true, true, _) => "both plates' clocks differ",
        (false, false, true) => "the plates' relative timing differs, but which plate moved is not settled: neither plate's own offset differs beyond noise",
        (false, false, false) => "with both plates' clocks free, neither plate's offset nor their relative timing differs beyond noise, so which plate moved is not settled",
    };
    // said only when a one-plate clock differs: otherwise there is nothing to place
    let one_plate_differs = c
        .differences
        .iter()
        .any(|d| !d.jointly && d.significant && PARAMETERS.contains(&d.parameter.as_str()));
    let evidence = c.which_plate.as_ref().filter(|_| one_plate_differs).map_or(String::new(), |w| {
        let f = w.index();
        // the other hypothesis holds the favoured plate's offset at zero
        let rejected = [r, l][f].significant;
        format!(
            " Of the two one-plate hypotheses, the {} plate's clock alone leaves less of the joint difference unexplained (χ² {:.2}, against {:.2} for the {} plate's alone: a likelihood ratio of {}), so its one-plate row is listed first of the two; {}.",
            w.favoured,
            w.unexplained[f],
            w.unexplained[1 - f],
            ["right", "left"][1 - f],
            ratio_text(w.likelihood_ratio),
            if rejected {
                "the other is rejected"
            } else {
                "that is a preference, not a finding, for the other is not rejected at the threshold"
            }
        )
    });
    Some(format!(
        " Both plates' clocks read jointly ({}: each run's three clock profiles as sections of one quadratic in both offsets, its minimum and curvature): the left plate against the right {}, the right plate {}, the left plate {}; {which}. A one-plate clock's difference holds the other plate's clock at zero, so it takes the plates' relative timing as its own plate's either way.{evidence}",
        super::plate_clocks::LABEL,
        read(rel),
        read(r),
        read(l),
    ))
}

/// What the joint reading of both plates' clocks says of a one-plate clock's significant
/// difference `d` (empty for any other row, or without a joint reading): that the joint
/// reading does not settle which plate it is, or puts it on the other plate.
fn one_plate_caveat(c: &super::reference::Comparison, d: &super::reference::Difference) -> String {
    use super::plate_clocks::PARAMETERS;
    let Some(own) = PARAMETERS.iter().position(|p| *p == d.parameter) else {
        return String::new();
    };
    if d.jointly || !d.significant {
        return String::new();
    }
    let (Some(mine), Some(other)) = (c.joint(PARAMETERS[own]), c.joint(PARAMETERS[1 - own])) else {
        return String::new();
    };
    let other_plate = ["right", "left"][1 - own];
    match (mine.significant, other.significant) {
        (true, _) => String::new(),
        (false, true) => format!("; the joint reading puts it on the {other_plate} plate"),
        (false, false) => format!(
            "; as the plates' relative timing: the joint reading does not settle which plate{}",
            c.which_plate.as_ref().map_or(String::new(), |w| format!(
                " (it favours the {}, {})",
                w.favoured,
                ratio_text(w.likelihood_ratio)
            ))
        ),
    }
}

/// What each gain hypothesis of [`plate_gains`](super::plate_gains) is, in words.
const GAIN_HYPOTHESES: [&str; 3] = [
    "only the right plate's gain",
    "only the left plate's gain",
    "both plates alike (a body-mass error, or one gain of both plates)",
];

/// The hypothesis group of a difference's row among the gain hypotheses' rows, if any.
fn gain_group(d: &super::reference::Difference) -> Option<usize> {
    super::plate_gains::group((d.label.as_str(), d.parameter.as_str()))
}

/// Which gain hypothesis the joint reading of both plates' gains favours, said when a
/// one-plate gain's or the body mass's row differs significantly (empty otherwise).
fn joint_gain_sentence(c: &super::reference::Comparison) -> String {
    let Some(w) = &c.which_gain else {
        return String::new();
    };
    if !c
        .differences
        .iter()
        .any(|d| d.significant && gain_group(d).is_some())
    {
        return String::new();
    }
    let f = w.index();
    let pct = |i: usize| {
        format!(
            "{:+.1} ± {:.1} %",
            100.0 * w.difference[i],
            100.0 * w.covariance[i][i].sqrt()
        )
    };
    format!(
        " Both plates' gains read jointly ({}, both free in one re-fit): the right plate {}, the left {} against the reference. A one-plate gain holds the other plate's at zero, and a body-mass error moves both alike; of the three hypotheses, {} leaves least of the joint difference unexplained (χ² {:.2} for only the right plate's gain, {:.2} for only the left's, {:.2} for both alike: a likelihood ratio of {} over the next), so its rows are listed first of the one-plate gains' and the body mass's; {}.",
        super::plate_gains::LABEL,
        pct(0),
        pct(1),
        GAIN_HYPOTHESES[f],
        w.unexplained[0],
        w.unexplained[1],
        w.unexplained[2],
        ratio_text(w.likelihood_ratio),
        if w.settled(c.threshold) {
            "the others are rejected"
        } else {
            "that is a preference, not a finding, for another is not rejected at the threshold"
        }
    )
}

/// What the joint reading of both plates' gains says of a significant one-plate gain's
/// or body mass's difference `d` (empty for any other row, or without it).
fn gain_caveat(c: &super::reference::Comparison, d: &super::reference::Difference) -> String {
    let (Some(w), Some(g), true) = (&c.which_gain, gain_group(d), d.significant) else {
        return String::new();
    };
    match (w.index() == g, w.settled(c.threshold)) {
        (true, true) => String::new(),
        (false, true) => format!("; the joint gains put it on {}", GAIN_HYPOTHESES[w.index()]),
        (_, false) => format!(
            "; the joint gains do not settle which (they favour {}, {})",
            GAIN_HYPOTHESES[w.index()],
            ratio_text(w.likelihood_ratio)
        ),
    }
}

/// The readings against a reference trial's: a paragraph and the table.
fn comparison_section(c: &super::reference::Comparison) -> (String, Table) {
    let significant: Vec<String> = c
        .differences
        .iter()
        .filter(|d| d.significant)
        .map(|d| format!("{} ({:+.3e}, {:.1} sd)", d.label, d.difference, d.z))
        .collect();
    let mut text = format!(
        "Each candidate's reading less the reference's ({}, diagnosed the same way): the model's own bias, in both trials, cancels; an instrument error of this trial does not. The difference's sd is the two readings' (each inflated by its φ) in quadrature; (Δ/sd)² is judged against the χ²₁ point at 0.1 % / {} parameters compared = {:.1}. {}",
        c.reference.display(),
        c.differences.len(),
        c.threshold,
        if significant.is_empty() {
            "No reading differs significantly from the reference's.".to_string()
        } else {
            format!("Differs significantly from the reference: {}. A significant difference is applied, as the candidate's value, to the held-out half cycle of this trial and of the reference; it is confirmed when this trial's change there less the reference's exceeds the paired noise band (the held-out note says how, and whether the reference's half cycle could be tracked).", significant.join(", "))
        }
    );
    let by_profiles: Vec<&str> = c
        .differences
        .iter()
        .filter(|d| d.by_profiles)
        .map(|d| d.label.as_str())
        .collect();
    if !by_profiles.is_empty() {
        text += &format!(
            " Read by the two clock profiles' vertices (the profile's re-fit was the test in one run only; each reading is the vertex of the parabola through its profile's lowest point, the run's cost among its points, with its sd from the curvature): {}.",
            by_profiles.join(", ")
        );
    }
    text += &joint_clock_sentence(c).unwrap_or_default();
    text += &joint_gain_sentence(c);
    if !c.not_compared.is_empty() {
        text += &format!(" Not compared: {}.", c.not_compared.join("; "));
    }
    let table = Table {
        title: "Readings against the reference trial (the largest |Δ|/sd first)".into(),
        headers: [
            "effect",
            "parameter",
            "this run",
            "reference",
            "difference",
            "sd",
            "difference / sd",
            "held-out change vs noise band",
            "verdict",
        ]
        .map(String::from)
        .to_vec(),
        rows: c
            .differences
            .iter()
            .map(|d| {
                let by = if d.by_profiles {
                    " (profile vertex)"
                } else if d.jointly {
                    " (joint)"
                } else {
                    ""
                };
                vec![
                    d.label.clone(),
                    d.parameter.clone(),
                    format!("{:.4e}{by}", d.reading),
                    format!("{:.4e}{by}", d.reference),
                    format!("{:+.4e}", d.difference),
                    format!("{:.2e}", d.sd),
                    format!("{:+.1}", d.z),
                    d.held_out.as_ref().map_or("—".into(), |h| match h.reference_change {
                        // the trial's change less the reference's, against the paired band
                        Some(_) if !h.reference_curvature.is_some_and(|q| q > 0.0) => format!(
                            "{:.3e} ({:.1} % of J); the reference's cost there does not curve along the difference",
                            h.change,
                            100.0 * h.change_fraction
                        ),
                        Some(rc) => format!(
                            "{:.3e} ({:.1} % of J) − the reference's {:.3e} = {:.3e} vs {:.3e}{}",
                            h.change,
                            100.0 * h.change_fraction,
                            rc,
                            h.change - rc,
                            h.band,
                            reading_text(h)
                        ),
                        None => format!(
                            "{:.3e} ({:.1} % of J) vs {:.3e}",
                            h.change,
                            100.0 * h.change_fraction,
                            h.band
                        ),
                    }),
                    match (&d.held_out, d.significant) {
                        (_, false) => "same within noise",
                        (Some(h), true) if h.beyond_noise => "differs, confirmed held-out",
                        (Some(h), true) if h.too_weakly_informed() => {
                            "differs, not validatable on the held-out half cycle (too weakly informed there)"
                        }
                        (Some(_), true) => "differs, not confirmed on the held-out half cycle",
                        (None, true) => "differs, not validated",
                    }
                    .to_string()
                        + &one_plate_caveat(c, d)
                        + &gain_caveat(c, d),
                ]
            })
            .collect(),
    };
    (text, table)
}

/// Both plates' clocks read jointly from the three clock profiles
/// ([`plate_clocks::read`](super::plate_clocks::read)), in a sentence or two (`None`: the
/// three were not all profiled).
fn plate_clocks_paragraph(
    joint: Option<&Result<super::plate_clocks::PlateClocks, String>>,
) -> Option<String> {
    Some(match joint? {
        Err(why) => format!(
            "Each plate's clock, read jointly from the three clock profiles: no reading ({why})."
        ),
        Ok(j) => {
            let [sr, sl] = j.sd();
            let (rel, rel_sd) = j.relative();
            format!(
                "Each plate's clock, read jointly from the three clock profiles (the minimum of the quadratic whose sections they are): right {:+.1} ± {:.1} ms, left {:+.1} ± {:.1} ms (correlation {:+.2}); the left plate against the right {:+.1} ± {:.1} ms, which the forces decide, while the shared part is what the kinematics settle. The quadratic lies {:.3e} below the run there (a statistic of {:.1} against the χ²₂ 0.1 % point {:.1}, from the profiles' points alone, not a re-fit); the shared profile's slope at zero differs from the two plates' sum by {:.0} % of the largest{}. A one-plate clock's reading holds the other plate's at zero, so it takes the relative timing either way.",
                1e3 * j.offsets[0],
                1e3 * sr,
                1e3 * j.offsets[1],
                1e3 * sl,
                j.correlation(),
                1e3 * rel,
                1e3 * rel_sd,
                j.decrease,
                j.decrease / j.noise_scale,
                crate::problems::diagnose::chi2_999(2),
                100.0 * j.slope_mismatch.abs(),
                if j.at_bound {
                    "; an offset lies at its bound: a limit, not a reading"
                } else {
                    ""
                }
            )
        }
    })
}

/// What the profile of a plate's clock (`--profile-clocks`) found, in a sentence or two.
fn profile_paragraph(t: &ScoreTest) -> Option<String> {
    let p = t.profile.as_ref()?;
    let points = p
        .points
        .iter()
        .map(|q| {
            format!(
                "{:+.0} ms: {}",
                1e3 * q.offset,
                match (q.objective, q.compared) {
                    (Some(j), Some(c)) => format!("J = {j:.4}, {c:.4} over the common samples"),
                    (Some(j), None) => format!("J = {j:.4}"),
                    (None, _) => q.status.clone(),
                }
            )
        })
        .collect::<Vec<_>>()
        .join(", ");
    // with sample targets a held offset moves the window with its plate's events
    let common = p.compared.as_ref().map_or(String::new(), |c| {
        format!(
            " The points hold different samples (a held offset moves the window's start or end with its plate's events), so they are compared by their data cost over the {} samples that each point, the run and the re-fit compare ({:.3}–{:.3} s): the run's {:.4}{}.",
            c.samples,
            c.span.0,
            c.span.1,
            c.run,
            c.refit.map_or(String::new(), |r| format!(", the re-fit's {r:.4}"))
        )
    });
    let outcome = match (p.start, p.refit, p.refit_error.as_deref()) {
        (Some(start), None, Some(error)) => format!(
            " The profile is lowest at {:+.0} ms, but its re-fit failed ({error}): the score test stands",
            1e3 * start
        ),
        (Some(start), Some((value, j)), _) => format!(
            "{}{}; {}",
            if p.refined {
                format!(" With one-sided or sample targets a free offset cannot move its plate's events, so the profile is refined instead: the parabola through the lowest point ({:+.0} ms) and its neighbours has its vertex at {:+.1} ms, where the re-fit held there reaches J = {j:.4}", 1e3 * start, 1e3 * value)
            } else {
                format!(
                    " The free re-fit from {:+.0} ms reached {:+.1} ms, J = {j:.4}",
                    1e3 * start,
                    1e3 * value
                )
            },
            p.refit_unconverged.as_deref().map_or(String::new(), |why| format!(
                " (the re-fit stopped short of its tolerance: {why}; its cost bounds the held minimum from above, so its decrease is a lower bound)"
            )),
            if p.chosen {
                format!(
                    "it lowers the cost more than the score test's truncated re-fit from zero, so it is this candidate's test, against the χ²₁ point at 0.1 %/{} = {:.1} (the best of {} starts)",
                    p.family, t.threshold, p.family
                )
            } else {
                "the score test's truncated re-fit from zero lowers the cost more, and stays the candidate's test".into()
            }
        ),
        _ => format!(
            " No point lies below the run's cost: the score test stands{}",
            match p.vertex {
                Some(v) if !p.chosen => format!(
                    "; the parabola through the lowest point (the run's) and its neighbours has its vertex at {:+.1} ms{}, the profile's own reading, which `--reference` compares with another trial's profile",
                    1e3 * v.offset,
                    v.sd.map_or(String::new(), |sd| format!(" ± {:.1}", 1e3 * sd))
                ),
                _ => String::new(),
            }
        ),
    };
    Some(format!(
        "Profile of {} (the run re-fitted with the offset held fixed; {points}).{common}{outcome}.",
        t.label
    ))
}

/// Write the diagnosis into `folder` and commit it.
pub(super) fn write(
    o: &Outcome<'_>,
    folder: RunFolder,
    progress: &dyn Progress,
) -> anyhow::Result<()> {
    let (args, tests, objective, rows) = (o.args, o.tests, o.objective, o.rows);
    let significant = tests.iter().filter(|t| t.significant).count();
    let found = tests.iter().filter(|t| t.found).count();
    let verdict = verdict(o);
    let joint = super::plate_clocks::read(tests);
    let ranking = Table {
        title: "Candidate effects ranked: testability, in-sample score statistic (predicted cost decrease / the largest model's residual mean square, divided by the variance inflation φ of correlated residuals), held-out change, verdict".into(),
        headers: ["rank", "effect", "testable", "parameters (truncated re-fit, ± sd)", "expected decrease", "% of J", "statistic", "φ", "χ² 0.1 % point", "held-out change vs noise band", "verdict"].map(String::from).to_vec(),
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
                    format!("{:.1}", t.threshold),
                    held_out_cell(t),
                    t.verdict.clone(),
                ]
            })
            .collect(),
    };
    let untestable: Vec<String> = tests
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
        .collect();
    let inflation = format!(
        "Correlated residuals: per channel, the variance inflation φ = N/N_eff (N_eff = N/(1 + 2 Σ ρ_k), ρ_k the error's autocorrelation at the nodes, summed up to the first lag ≤ 0): {}; these are the plain model's; each candidate's statistic is divided by the φ of the residuals left after the truncated re-fit of the largest model (every scored candidate at once, each plate's instruments on their own; as an F-test takes the larger model's variance), averaged over the channels the candidate's re-fit improves, weighted by their relative improvement.",
        o.resid
            .series
            .iter()
            .zip(&o.resid.inflation)
            .map(|(s, p)| format!("{} {}", s.0, p.map_or("—".into(), |p| format!("{p:.1}"))))
            .collect::<Vec<_>>()
            .join(", ")
    ) + &match o.noise {
        Some(full) => format!(
            " The largest model ({}) lowers J from {:.6} to {:.6}; its residuals' φ per channel: {}; every statistic's residual mean square is its J/N.",
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
    };
    // channels by name: a re-fit's come from its run summary, a score test's from the
    // problem
    let channels: Vec<(String, String)> = tests.first().map_or(vec![], |t| {
        t.expected_channels
            .iter()
            .map(|c| (c.0.clone(), c.1.clone()))
            .collect()
    });
    let expected = Table {
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
    };
    let refits: Vec<String> = tests
        .iter()
        .zip(o.evidence)
        .filter_map(|(t, e)| match e {
            Evidence::Refit(_, _) if t.profile.is_some() => None,
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
        .collect();
    let mut paragraphs = vec![verdict.clone()];
    if !o.held_out_note.is_empty() {
        paragraphs.push(o.held_out_note.clone());
    }
    paragraphs.push(inflation.clone());
    paragraphs.extend(untestable.iter().cloned());
    if let Some(p) = &o.testable_run {
        paragraphs.push(format!(
            "--make-testable: the run re-tracked with the pelvis position tracked is {}; its diagnosis is {}-diagnose.",
            p.display(),
            p.display()
        ));
    }
    paragraphs.extend(refits.iter().map(|r| format!("{r}.")));
    paragraphs.extend(tests.iter().filter_map(profile_paragraph));
    paragraphs.extend(plate_clocks_paragraph(joint.as_ref()));
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
    if let Some(c) = o.comparison {
        let (text, table) = comparison_section(c);
        md += &format!(
            "\n## Against the reference trial\n\n{text}\n\n{}\n",
            table.to_markdown()
        );
        sections.push(Section {
            heading: "Against the reference trial".into(),
            paragraphs: vec![text],
            tables: vec![table],
            svgs: vec![],
        });
    }
    for v in o.verified {
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
        let text = match [&args.run, &v.folder]
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
        };
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
    let summary = DiagnosisSummary {
        command: summary::COMMAND.into(),
        run: args.run.clone(),
        objective,
        data_residuals: rows,
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
        significant,
        found,
        untestable: tests.iter().filter(|t| !t.testable).count(),
        held_out_note: o.held_out_note.clone(),
        testable_run: o.testable_run.clone(),
        reference: o.comparison.cloned(),
        plate_clocks: joint,
        verdict: verdict.clone(),
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
    };
    folder.write("diagnose.md", md.as_bytes())?;
    if let Some(hb) = o.held_out {
        hb.write_into(&folder.staging_path().join("held_out"))?;
    }
    folder.write(
        "summary.json",
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    let summary_box = Summary {
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
        stop_reason: verdict.clone(),
        iterations: None,
        time_s: None,
        extra: vec![
            ("tracking cost J".into(), format!("{objective:.6}")),
            ("data residuals".into(), rows.to_string()),
            ("variance inflation φ".into(), format!("{:.1}", o.phi)),
            (
                "untestable candidates".into(),
                tests.iter().filter(|t| !t.testable).count().to_string(),
            ),
        ],
    };
    let report = Report {
        title: format!("footfall diagnose — {}", args.run.display()),
        summary: summary_box,
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
            window: (0.0, 0.5),
            values: vec![0.01],
            objective: 1.0,
            change: if beyond { 0.1 } else { -0.1 },
            change_fraction: 0.1,
            band: 0.05,
            beyond_noise: beyond,
            reference_change: None,
            reference_curvature: None,
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

    /// A profile whose re-fit stopped at its iteration limit says so, and that its
    /// decrease is then a lower bound; a converged one does not.
    #[test]
    fn a_profile_says_when_its_refit_stopped_short_of_its_tolerance() {
        let mut t = slope(None);
        let mut p = crate::problems::diagnose::ClockProfile {
            points: Vec::new(),
            start: Some(-0.02),
            refit: Some((-0.013, 0.3204)),
            family: 5,
            chosen: true,
            refined: true,
            refit_error: None,
            refit_unconverged: Some(
                "iteration limit reached, KKT 1.7e-3 after 200 iterations".into(),
            ),
            compared: None,
            vertex: None,
        };
        t.profile = Some(p.clone());
        let text = profile_paragraph(&t).unwrap();
        assert!(text.contains("stopped short of its tolerance: iteration limit reached, KKT 1.7e-3 after 200 iterations"), "{text}");
        assert!(text.contains("its decrease is a lower bound"), "{text}");
        p.refit_unconverged = None;
        t.profile = Some(p);
        assert!(!profile_paragraph(&t).unwrap().contains("stopped short"));
    }

    /// A compared parameter's difference, significant when `|z|` exceeds 4.
    fn difference(
        label: &str,
        parameter: &str,
        difference: f64,
        sd: f64,
        jointly: bool,
    ) -> super::super::reference::Difference {
        super::super::reference::Difference {
            label: label.into(),
            parameter: parameter.into(),
            reading: difference,
            reference: 0.0,
            difference,
            sd,
            z: difference / sd,
            significant: (difference / sd).abs() > 4.0,
            by_profiles: false,
            jointly,
            held_out: None,
        }
    }

    /// A one-plate clock that differs significantly is qualified by the joint reading of
    /// both plates' clocks: as the plates' relative timing when the joint reading does not
    /// settle which plate (the compliant left-clock trial, its one-plate right clock
    /// spurious), or put on the other plate when it does; the paragraph says which.
    #[test]
    fn a_one_plate_clock_is_qualified_by_the_joint_reading() {
        use super::super::plate_clocks::{LABEL, PARAMETERS, RELATIVE};
        let comparison = |left_sd: f64| super::super::reference::Comparison {
            reference: "UV-diagnose".into(),
            threshold: 16.0,
            differences: vec![
                difference(
                    "force-plate time offset (right)",
                    PARAMETERS[0],
                    0.0249,
                    0.0054,
                    false,
                ),
                difference(
                    "force-plate time offset (left)",
                    PARAMETERS[1],
                    -0.0206,
                    0.0045,
                    false,
                ),
                difference(LABEL, RELATIVE, -0.0199, 0.0053, true),
                difference(LABEL, PARAMETERS[1], -0.0213, left_sd, true),
                difference(LABEL, PARAMETERS[0], -0.0014, 0.0123, true),
            ],
            not_compared: Vec::new(),
            which_plate: Some(super::super::plate_clocks::WhichPlate {
                favoured: "left".into(),
                unexplained: [3.16, 0.01],
                likelihood_ratio: 4.8,
            }),
            which_gain: None,
        };
        let verdict = |c: &super::super::reference::Comparison, row: usize| {
            comparison_section(c).1.rows[row].last().unwrap().clone()
        };
        let unsettled = comparison(0.0120);
        assert!(
            verdict(&unsettled, 0).contains("does not settle which plate"),
            "{}",
            verdict(&unsettled, 0)
        );
        assert!(verdict(&unsettled, 1).contains("does not settle which plate"));
        assert_eq!(verdict(&unsettled, 2), "same within noise");
        assert!(
            verdict(&unsettled, 0).ends_with("(it favours the left, 4.8 : 1)"),
            "{}",
            verdict(&unsettled, 0)
        );
        let text = comparison_section(&unsettled).0;
        assert!(text.contains("which plate moved is not settled"), "{text}");
        assert!(
            text.contains("the left plate's clock alone leaves less")
                && text.contains("a likelihood ratio of 4.8 : 1")
                && text.contains("a preference, not a finding"),
            "{text}"
        );
        // a joint left reading beyond noise puts the right clock's difference on the left
        let settled = comparison(0.0040);
        assert!(
            verdict(&settled, 0).ends_with("the joint reading puts it on the left plate"),
            "{}",
            verdict(&settled, 0)
        );
        assert_eq!(verdict(&settled, 1), "differs, not validated");
        let text = comparison_section(&settled).0;
        assert!(text.contains("it is the left plate's clock"), "{text}");
        assert!(text.contains("the other is rejected"), "{text}");
        assert_eq!(ratio_text(2.1e5), "2.1e5 : 1");
        // no one-plate clock differs: nothing to place, so no preference is stated
        let mut quiet = comparison(0.0120);
        for d in &mut quiet.differences {
            d.significant = false;
        }
        assert!(!comparison_section(&quiet).0.contains("alone leaves less"));
    }
    /// A significant body-mass or one-plate gain row is qualified by the joint reading of
    /// both plates' gains: the paragraph names the favoured hypothesis with the three χ²,
    /// and each such row says whether the joint gains settle it.
    #[test]
    fn a_gain_or_body_mass_row_is_qualified_by_the_joint_gains() {
        use super::super::plate_gains::WhichGain;
        let which = |favoured: &str, unexplained: [f64; 3]| WhichGain {
            difference: [0.02, 0.06],
            covariance: [[0.07 * 0.07, 0.0], [0.0, 0.014 * 0.014]],
            favoured: favoured.into(),
            unexplained,
            likelihood_ratio: 1.9,
        };
        let mut c = super::super::reference::Comparison {
            reference: "UV-diagnose".into(),
            threshold: 16.0,
            differences: vec![
                difference(
                    "force-plate gain (left)",
                    "force_plate_gain.left.error",
                    0.0596,
                    0.0137,
                    false,
                ),
                difference(
                    "body-mass error",
                    "body_mass_error.relative",
                    0.0509,
                    0.0114,
                    false,
                ),
                difference("ground slope", "ground_slope.angle", 0.001, 0.003, false),
            ],
            not_compared: Vec::new(),
            which_plate: None,
            which_gain: Some(which("left", [18.4, 0.1, 1.4])),
        };
        let verdict = |c: &super::super::reference::Comparison, row: usize| {
            comparison_section(c).1.rows[row].last().unwrap().clone()
        };
        let text = comparison_section(&c).0;
        assert!(
            text.contains("only the left plate's gain leaves least")
                && text.contains("χ² 18.40 for only the right plate's gain, 0.10 for only the left's, 1.40 for both alike")
                && text.contains("the right plate +2.0 ± 7.0 %, the left +6.0 ± 1.4 %")
                && text.contains("a preference, not a finding"),
            "{text}"
        );
        assert!(verdict(&c, 0).ends_with("; the joint gains do not settle which (they favour only the left plate's gain, 1.9 : 1)"), "{}", verdict(&c, 0));
        assert_eq!(verdict(&c, 2), "same within noise");
        // settled: the favoured row stands alone, the other is put on it
        c.which_gain = Some(which("left", [18.4, 0.1, 17.0]));
        assert!(comparison_section(&c).0.contains("the others are rejected"));
        assert_eq!(verdict(&c, 0), "differs, not validated");
        assert!(
            verdict(&c, 1).ends_with("; the joint gains put it on only the left plate's gain"),
            "{}",
            verdict(&c, 1)
        );
        // nothing to say when no gain row differs
        for d in &mut c.differences {
            d.significant = false;
        }
        assert!(!comparison_section(&c).0.contains("gains read jointly"));
    }
}
