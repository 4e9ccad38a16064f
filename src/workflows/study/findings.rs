//! Findings across trials: an instrument's readings (plate clocks, gains, CoP offsets)
//! pooled over the trials of a lab session, the body's (mass, trunk) over the trials of a
//! subject. Each trial's candidate read alone (the check's first step, the same reading
//! in every trial whatever else it found) is pooled ([`super::pool`]); a pooled reading is
//! beyond its band when its |z| exceeds the Bonferroni point of the family-wise level over
//! every pooled reading of the study. Of those beyond on which the trials agree (Cochran's
//! Q below its point at the same level), the one that explains most of the trials'
//! residual is the group's shared effect, the others its look-alikes, as the check's own
//! first step decides; where every trial's check found the same effects, the
//! shared effect's joint readings (each check's final value) are pooled too. A finding of the check that holds in some trials of a
//! group and not in the others is said to.

use super::entry::{Reading, TrialEntry};
use super::pool::{pool, Pooled, Sample};
use crate::problems::check::Param;
use crate::problems::distributions::chi2_1_upper;
use serde::Serialize;

/// The candidates pooled over a lab session's trials.
pub const INSTRUMENT: [Param; 7] = [
    Param::SharedClock,
    Param::ClockRight,
    Param::ClockLeft,
    Param::GainRight,
    Param::GainLeft,
    Param::CopRight,
    Param::CopLeft,
];

/// The candidates pooled over a subject's trials.
pub const BODY: [Param; 2] = [Param::BodyMass, Param::TrunkCom];

/// What a group of trials shares.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GroupKind {
    /// A lab session: its instruments.
    Session,
    /// A subject: the body.
    Subject,
}

/// One candidate pooled over a group.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PooledReading {
    /// Candidate ([`Param::name`]).
    pub effect: String,
    /// The pooled reading.
    pub pooled: Pooled,
    /// Mean share of the trials' residual it explains, read alone.
    pub explained: f64,
    /// Whether |z| exceeds the study's threshold.
    pub beyond: bool,
    /// The trials' readings jointly with what each check found, pooled, where every
    /// trial's check found the same candidates (the same reading in each): the group's
    /// best value of an effect its checks found.
    pub joint: Option<Pooled>,
    /// Trials whose check found it.
    pub found_in: Vec<String>,
}

/// The pooled readings of one group and what they say.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GroupFindings {
    /// Session or subject.
    pub kind: GroupKind,
    /// Its name in the manifest.
    pub name: String,
    /// The group's trials with a check (of the current inputs), by id.
    pub trials: Vec<String>,
    /// The group's trials without one (failed or not run).
    pub missing: Vec<String>,
    /// Each candidate, pooled.
    pub readings: Vec<PooledReading>,
    /// The shared effect found, if any.
    pub shared: Option<String>,
    /// The other candidates beyond their band, which the pool cannot tell from it.
    pub look_alikes: Vec<String>,
    /// A subject's diagnoses: each effect they suggest, and in which trials.
    pub model_stage: Vec<String>,
    /// What the readings say, in sentences.
    pub statements: Vec<String>,
}

/// Pool every session's and subject's trials; the groups and the study's threshold
/// (`None` when nothing could be pooled).
pub fn pool_study(trials: &[TrialEntry], level: f64) -> (Vec<GroupFindings>, Option<f64>) {
    let mut groups = Vec::new();
    for (kind, params) in [
        (GroupKind::Session, &INSTRUMENT[..]),
        (GroupKind::Subject, &BODY[..]),
    ] {
        for name in names(trials, kind) {
            let members: Vec<&TrialEntry> = trials
                .iter()
                .filter(|t| group_name(t, kind) == name)
                .collect();
            groups.push(pool_group(kind, &name, &members, params));
        }
    }
    let tests: usize = groups.iter().map(|g| g.readings.len()).sum();
    let threshold = (tests > 0).then(|| chi2_1_upper(level / tests as f64).sqrt());
    for g in groups.iter_mut() {
        // with nothing pooled no group has a reading to judge
        decide(g, threshold.unwrap_or(f64::INFINITY), level);
    }
    (groups, threshold)
}

fn group_name(t: &TrialEntry, kind: GroupKind) -> &str {
    match kind {
        GroupKind::Session => &t.session,
        GroupKind::Subject => &t.subject,
    }
}

/// The group names of `kind` in order of first appearance (empty names are no group).
fn names(trials: &[TrialEntry], kind: GroupKind) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for t in trials {
        let n = group_name(t, kind);
        if !n.is_empty() && !out.iter().any(|o| o == n) {
            out.push(n.to_string());
        }
    }
    out
}

fn alone_of(t: &TrialEntry, p: Param) -> Option<&Reading> {
    t.check
        .as_ref()?
        .alone
        .iter()
        .find(|r| r.effect == p.name())
}

fn pool_group(
    kind: GroupKind,
    name: &str,
    members: &[&TrialEntry],
    params: &[Param],
) -> GroupFindings {
    let read: Vec<&TrialEntry> = members
        .iter()
        .copied()
        .filter(|t| t.check.is_some())
        .collect();
    let mut readings = Vec::new();
    for &p in params {
        let rs: Vec<&Reading> = read.iter().filter_map(|t| alone_of(t, p)).collect();
        let samples: Vec<Sample> = rs
            .iter()
            .filter_map(|r| {
                Some(Sample {
                    estimate: r.estimate?,
                    sd: r.sd?,
                    sd_within: r.sd_within?,
                    centre: r.centre?,
                })
            })
            .collect();
        let Some(pooled) = pool(&samples).filter(|q| q.trials >= 2) else {
            continue;
        };
        let explained = rs.iter().filter_map(|r| r.explained).sum::<f64>() / rs.len() as f64;
        readings.push(PooledReading {
            effect: p.name().to_string(),
            pooled,
            explained,
            beyond: false,
            joint: joint(&read, p),
            found_in: read
                .iter()
                .filter(|t| {
                    t.check
                        .as_ref()
                        .is_some_and(|c| c.found.iter().any(|f| f == p.name()))
                })
                .map(|t| t.id.clone())
                .collect(),
        });
    }
    GroupFindings {
        kind,
        name: name.to_string(),
        trials: read.iter().map(|t| t.id.clone()).collect(),
        missing: members
            .iter()
            .filter(|t| !read.iter().any(|r| r.id == t.id))
            .map(|t| t.id.clone())
            .collect(),
        readings,
        shared: None,
        look_alikes: vec![],
        model_stage: match kind {
            GroupKind::Subject => model_stage(&read),
            GroupKind::Session => vec![],
        },
        statements: vec![],
    }
}

/// Each effect the trials' diagnoses suggest (`--effect NAME:…`), with the trials that
/// suggest it out of those diagnosed: the model's physics is the same in every trial of a
/// subject.
fn model_stage(read: &[&TrialEntry]) -> Vec<String> {
    let diagnosed: Vec<(&str, Vec<&str>)> = read
        .iter()
        .filter_map(|t| {
            let d = t.diagnose.as_ref()?;
            let names = d
                .add_effects
                .iter()
                .map(|l| l.split(':').next().unwrap_or(l))
                .collect();
            Some((t.id.as_str(), names))
        })
        .collect();
    if diagnosed.is_empty() {
        return vec![];
    }
    let mut effects: Vec<&str> = diagnosed.iter().flat_map(|(_, e)| e.clone()).collect();
    effects.sort();
    effects.dedup();
    if effects.is_empty() {
        return vec![format!(
            "model stage: no diagnosis of the {} diagnosed trial(s) suggests an effect",
            diagnosed.len()
        )];
    }
    effects
        .iter()
        .map(|e| {
            let with: Vec<&str> = diagnosed
                .iter()
                .filter(|(_, es)| es.contains(e))
                .map(|(id, _)| *id)
                .collect();
            format!(
                "model stage: {e} suggested in {} of {} diagnosed trial(s) ({}){}",
                with.len(),
                diagnosed.len(),
                with.join(", "),
                if with.len() < diagnosed.len() {
                    ": not in the others"
                } else {
                    ""
                }
            )
        })
        .collect()
}

/// The trials' joint readings of `p` pooled, when every trial's check found the same
/// candidates, `p` among them.
fn joint(read: &[&TrialEntry], p: Param) -> Option<Pooled> {
    let checks: Vec<_> = read.iter().filter_map(|t| t.check.as_ref()).collect();
    let first = checks.first()?;
    let mut same: Vec<&String> = first.found.iter().collect();
    same.sort();
    let all_same = checks.iter().all(|c| {
        let mut f: Vec<&String> = c.found.iter().collect();
        f.sort();
        f == same
    });
    if !all_same || !first.found.iter().any(|f| f == p.name()) {
        return None;
    }
    let samples: Vec<Sample> = checks
        .iter()
        .filter_map(|c| {
            let r = c.readings.iter().find(|r| r.effect == p.name())?;
            Some(Sample {
                estimate: r.estimate?,
                sd: r.sd?,
                sd_within: r.sd_within?,
                centre: r.centre?,
            })
        })
        .collect();
    pool(&samples).filter(|q| q.trials >= 2)
}

/// Mark the readings beyond `threshold`, pick the shared effect, and say what holds.
fn decide(g: &mut GroupFindings, threshold: f64, level: f64) {
    for r in g.readings.iter_mut() {
        r.beyond = r.pooled.z.abs() > threshold;
    }
    // one value shared by the trials: beyond its band, and the trials agree on it
    let shared = |r: &&PooledReading| r.beyond && r.pooled.p_heterogeneity >= level;
    let best = g
        .readings
        .iter()
        .filter(shared)
        .max_by(|a, b| a.explained.total_cmp(&b.explained))
        .map(|r| r.effect.clone());
    g.look_alikes = g
        .readings
        .iter()
        .filter(shared)
        .filter(|r| Some(&r.effect) != best.as_ref())
        .map(|r| r.effect.clone())
        .collect();
    g.shared = best;
    g.statements = statements(g, threshold, level);
}

fn label(effect: &str) -> &'static str {
    Param::from_name(effect).map_or("?", |p| p.label())
}

/// The shared effect: pooled value, z, how many checks found it, whether the trials
/// agree, and the pooled joint reading.
fn shared_text(r: &PooledReading, what: &str, threshold: f64) -> String {
    let p = &r.pooled;
    let mut s = format!(
        "shared {what}: {} {} over {} trials (z {:.1} against {:.2}); the check found it in {} of them",
        label(&r.effect),
        value_text(&r.effect, p.estimate, p.sd),
        p.trials,
        p.z,
        threshold,
        r.found_in.len()
    );
    if p.df > 0 {
        s.push_str(&format!(
            "; the trials agree (Cochran's Q {:.1} on {} df, p {:.2})",
            p.q, p.df, p.p_heterogeneity
        ));
    }
    if let Some(j) = &r.joint {
        s.push_str(&format!(
            "; read jointly with what each trial's check found, {}",
            value_text(&r.effect, j.estimate, j.sd)
        ));
    }
    s
}

/// A pooled reading beyond its band on which the trials disagree.
fn disagree_text(r: &PooledReading) -> String {
    let p = &r.pooled;
    format!(
        "{}: pooled {} (z {:.1}) is beyond its band, but the trials disagree (Cochran's Q {:.1} on {} df, p {:.3}, I² {:.0} %): not one value the trials share",
        label(&r.effect),
        value_text(&r.effect, p.estimate, p.sd),
        p.z,
        p.q,
        p.df,
        p.p_heterogeneity,
        100.0 * p.i2
    )
}

/// The other pooled readings beyond their band.
fn look_alikes_text(g: &GroupFindings) -> String {
    let items: Vec<String> = g
        .look_alikes
        .iter()
        .filter_map(|e| g.readings.iter().find(|r| &r.effect == e))
        .map(|r| {
            format!(
                "{} {} (z {:.1})",
                label(&r.effect),
                value_text(&r.effect, r.pooled.estimate, r.pooled.sd),
                r.pooled.z
            )
        })
        .collect();
    format!(
        "the pooled readings cannot tell it from: {}",
        items.join(", ")
    )
}

/// A check's finding in some of the group's trials and not the others, if it is one.
fn partly_text(g: &GroupFindings, r: &PooledReading) -> Option<String> {
    let (k, n) = (r.found_in.len(), g.trials.len());
    if k == 0 || k == n {
        return None;
    }
    let not: Vec<&str> = g
        .trials
        .iter()
        .filter(|t| !r.found_in.contains(t))
        .map(String::as_str)
        .collect();
    Some(format!(
        "{}: found in {} only ({k} of {n}), not in {}; pooled {} (z {:.1}){}",
        label(&r.effect),
        r.found_in.join(", "),
        not.join(", "),
        value_text(&r.effect, r.pooled.estimate, r.pooled.sd),
        r.pooled.z,
        if r.beyond {
            ""
        } else {
            ": it does not hold across the trials"
        }
    ))
}

/// `+23.16 ± 2.74 ms`
pub fn value_text(effect: &str, v: f64, sd: f64) -> String {
    match Param::from_name(effect) {
        Some(p) => {
            let (v, unit) = p.display_value(v);
            let (sd, _) = p.display_value(sd);
            format!("{v:+.2} ± {sd:.2} {unit}")
        }
        None => format!("{v:+.4} ± {sd:.4}"),
    }
}

fn statements(g: &GroupFindings, threshold: f64, level: f64) -> Vec<String> {
    let what = match g.kind {
        GroupKind::Session => "instrument effect",
        GroupKind::Subject => "body effect",
    };
    let mut out = Vec::new();
    if g.readings.is_empty() {
        out.push(format!(
            "{} trial(s) read: fewer than two, nothing to pool",
            g.trials.len()
        ));
        out.extend(g.model_stage.iter().cloned());
        return out;
    }
    let shared = g
        .readings
        .iter()
        .find(|r| Some(&r.effect) == g.shared.as_ref());
    match shared {
        Some(r) => {
            out.push(shared_text(r, what, threshold));
            if !g.look_alikes.is_empty() {
                out.push(look_alikes_text(g));
            }
        }
        None if g.readings.iter().any(|r| r.beyond) => out.push(format!(
            "no shared {what}: the trials disagree on every pooled reading beyond its band (|z| > {threshold:.2})"
        )),
        None => out.push(format!(
            "no shared {what}: every pooled reading is within its band (|z| ≤ {threshold:.2})"
        )),
    }
    out.extend(
        g.readings
            .iter()
            .filter(|r| r.beyond && r.pooled.p_heterogeneity < level)
            .map(disagree_text),
    );
    out.extend(g.readings.iter().filter_map(|r| partly_text(g, r)));
    out.extend(g.model_stage.iter().cloned());
    if !g.missing.is_empty() {
        out.push(format!(
            "not read (failed or not run): {}",
            g.missing.join(", ")
        ));
    }
    out
}
