//! The phase legend table: each phase's kind, contacts, times, percent of the cycle, and
//! the events that begin and end it.

use super::{CycleAxis, SIDES};
use crate::phases::{Phase, PhaseSequence};
use crate::problems::evaluation::PhaseSolution;
use crate::report::table::Table;

/// The phase legend: every phase of the file in order, what kind it is, which contacts
/// are on the ground, its times and percent of the lead leg's cycle, and what begins and
/// ends it (an impact and the contact it lands, or the contacts that lift off).
pub fn phase_legend(
    seq: &PhaseSequence,
    solved: &[PhaseSolution],
    cycle: &CycleAxis,
    window: (f64, f64),
) -> Table {
    let lead = cycle.lead_side(window);
    let names = |c: &[crate::phases::ContactUse]| -> String {
        if c.is_empty() {
            "none (flight)".into()
        } else {
            c.iter()
                .map(|u| {
                    format!(
                        "{}{}",
                        u.contact,
                        if u.rolling { "" } else { " (normal only)" }
                    )
                })
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let set_of =
        |c: &[crate::phases::ContactUse]| c.iter().map(|u| u.contact.clone()).collect::<Vec<_>>();
    let minus = |a: &[String], b: &[String]| {
        a.iter()
            .filter(|x| !b.contains(x))
            .cloned()
            .collect::<Vec<_>>()
            .join(", ")
    };
    // the contacts on the ground before phase `i` (those of the closest earlier phase)
    let before = |i: usize| -> Option<Vec<String>> {
        (0..i)
            .rev()
            .map(|k| set_of(seq.phases[k].contacts()))
            .next()
    };
    let transition = |from: Option<Vec<String>>, to: &Phase| -> String {
        let now = set_of(to.contacts());
        match (to, from) {
            (Phase::Impact { name, .. }, Some(prev)) => {
                let landing = minus(&now, &prev);
                if landing.is_empty() {
                    format!("impact {name}")
                } else {
                    format!("impact {name}: {landing} lands")
                }
            }
            (Phase::Impact { name, .. }, None) => format!("impact {name} (the window's start)"),
            (Phase::Continuous { .. }, Some(prev)) => {
                let off = minus(&prev, &now);
                let on = minus(&now, &prev);
                match (off.is_empty(), on.is_empty()) {
                    (false, _) => format!("{off} lifts off"),
                    (true, false) => format!("{on} touches down"),
                    (true, true) => "the previous phase's end".into(),
                }
            }
            (Phase::Continuous { .. }, None) => "the window's start".into(),
        }
    };
    let mut rows = Vec::new();
    let mut solved_iter = solved.iter();
    let mut t = window.0;
    for (i, ph) in seq.phases.iter().enumerate() {
        let begins = match (ph, i.checked_sub(1).map(|k| &seq.phases[k])) {
            (Phase::Continuous { .. }, Some(prev @ Phase::Impact { .. })) => {
                transition(before(i - 1), prev)
            }
            _ => transition(before(i), ph),
        };
        let ends = match (ph, seq.phases.get(i + 1)) {
            (Phase::Impact { .. }, _) => "instantaneous".into(),
            (_, Some(next)) => transition(Some(set_of(ph.contacts())), next),
            (_, None) => "the window's end".into(),
        };
        let (kind, times, pct) = match ph {
            Phase::Impact { .. } => (
                "impact".to_string(),
                format!("{t:.3}"),
                format!("{:.1}", cycle.percent(lead, t)),
            ),
            Phase::Continuous { .. } => match solved_iter.next() {
                Some(p) => {
                    t = p.t0 + p.duration;
                    (
                        "continuous".to_string(),
                        format!("{:.3}–{:.3}", p.t0, t),
                        format!(
                            "{:.1}–{:.1}",
                            cycle.percent(lead, p.t0),
                            cycle.percent(lead, t)
                        ),
                    )
                }
                None => ("continuous".to_string(), "—".into(), "—".into()),
            },
        };
        rows.push(vec![
            ph.name().to_string(),
            kind,
            names(ph.contacts()),
            times,
            pct,
            begins,
            ends,
        ]);
    }
    Table {
        title: format!(
            "Phases of {} (percent of the {} leg's cycle)",
            seq.name, SIDES[lead]
        ),
        headers: [
            "phase",
            "kind",
            "on the ground",
            "time (s)",
            "% of cycle",
            "begins with",
            "ends with",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    }
}
