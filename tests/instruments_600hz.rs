//! The re-fits of the compliant foot's CoP, body-mass and gain
//! trials at 600 Hz (`tests/data/real_hidden_600hz`, the real trial edited by
//! `tools/make-real-hidden-trials`): the right foot's CoP 25 mm forward, every force 5 %
//! high, and the left plate's forces 6 % high. Each trial's track and its re-fit with the
//! diagnosed effect added by one line (`footfall track … --effect cop_offset:side=right`,
//! `--effect body_mass_error` or `--effect force_plate_gain:side=left`, from the trial's
//! own track) are kept in `tests/data/real_compliant_600hz/<trial>`. The clock
//! trials' re-fits are in `clocks_600hz`.
//!
//! The diagnosis tests diagnose each trial afresh (every candidate, the clock profiles, no
//! verifying re-fit and no held-out half cycle, as the kept diagnoses were made) against
//! the untouched trial's fresh diagnosis (`clocks_600hz::untouched_compliant_diagnosis`),
//! each solve started from the trial's kept diagnosis's
//! (`tests/data/real_compliant_600hz/<trial>/diagnosis_starts`): a solve that
//! is a KKT point of the current code's problem stops there, so each diagnosis takes one
//! to three minutes instead of 11–25 and still checks where every solve converges.

use super::clocks_600hz::{
    diagnosed_against_the_untouched_trial, refit_brings_every_channel_near_the_untouched_trials,
    within_truth,
};
use serde_json::Value;

/// The re-fit of each trial with its diagnosed effect brings every channel's error at the
/// nodes near the untouched trial's: it closes at least half the gap the edit opened, or
/// lies within 20 % of the untouched trial's. The CoP edit opens a gap in the CoP (the
/// track follows the moved CoP with the foot, so the gap is small: 0.89 against 0.70 cm),
/// the mass and gain edits in the normal force (31.2 and 33.2 against 22.5 N). The three
/// re-fits converged (J 0.316933 in 21 iterations, 0.320114 in 24, 0.315913 in 26; the
/// untouched trial's J is 0.320195).
#[test]
fn the_compliant_cop_mass_and_gain_refits_bring_every_channel_near_the_untouched_trials() {
    for (trial, channel, gap_at_least) in [
        ("real_cop_r+25mm", "CoP", 0.1),
        ("real_mass+5pct", "normal GRF", 4.0),
        ("real_gain_l+6pct", "normal GRF", 4.0),
    ] {
        let (untouched, edited) = refit_brings_every_channel_near_the_untouched_trials(trial);
        let i = untouched.iter().position(|(n, _)| n == channel).unwrap();
        assert!(
            edited[i].1 - untouched[i].1 > gap_at_least,
            "{trial}: the edit's gap in {channel}"
        );
    }
}

/// `trial` tracked from its kept solution and diagnosed afresh from its kept solves
/// against the untouched trial's fresh diagnosis: the comparison's first row is `row`
/// (label, parameter), read within 20 % or 2 sd of `truth`; with `favoured`, also
/// significant, the joint gains favouring that hypothesis. The comparison, for the caller's further checks.
fn diagnosed_first_against_the_untouched_trial(
    trial: &str,
    row: (&str, &str),
    truth: f64,
    favoured: Option<&str>,
) -> Value {
    let c = diagnosed_against_the_untouched_trial(trial);
    let first = &c["differences"][0];
    assert_eq!(
        (first["label"].as_str(), first["parameter"].as_str()),
        (Some(row.0), Some(row.1)),
        "{trial}: {first}"
    );
    let (diff, sd) = (
        first["difference"].as_f64().unwrap(),
        first["sd"].as_f64().unwrap(),
    );
    assert!(
        within_truth(diff, sd, truth),
        "{trial}: {diff} ± {sd} against {truth}"
    );
    if let Some(hypothesis) = favoured {
        assert_eq!(first["significant"], true, "{trial}: {first}");
        assert_eq!(
            c["which_gain"]["favoured"], hypothesis,
            "{trial}: {}",
            c["which_gain"]
        );
    }
    c
}

/// The left plate's forces 6 % high: the left plate's gain first and significant, the
/// joint gains favouring the left plate alone (kept: +5.96 ± 1.37 %, z +4.35;
/// left alone 1.24 : 1 over both alike, not settled).
#[test]
fn the_left_plates_gain_is_diagnosed_first_against_the_untouched_trial() {
    diagnosed_first_against_the_untouched_trial(
        "real_gain_l+6pct",
        ("force-plate gain (left)", "force_plate_gain.left.error"),
        0.06,
        Some("left"),
    );
}

/// Every force 5 % high, as a body-mass error makes them: the body mass first and
/// significant, the joint gains favouring both plates alike (kept: +4.92 ±
/// 1.13 %, z +4.34; both alike 1.28 : 1 over the left plate alone, not settled).
#[test]
fn the_body_mass_is_diagnosed_first_against_the_untouched_trial() {
    diagnosed_first_against_the_untouched_trial(
        "real_mass+5pct",
        ("body-mass error", "body_mass_error.relative"),
        0.05,
        Some("both"),
    );
}

/// The right foot's CoP 25 mm forward: its CoP offset first, above one sd but within
/// noise (kept: against the untouched trial's diagnosis without the joint gains:
/// +26.9 ± 17.7 mm, z +1.51). That the edit moves no other reading by as much is checked
/// on the kept diagnosis (`diagnose::reference`'s library test), not here.
#[test]
fn the_right_cop_offset_is_diagnosed_first_against_the_untouched_trial() {
    let c = diagnosed_first_against_the_untouched_trial(
        "real_cop_r+25mm",
        ("CoP offset (right)", "cop_offset.right.offset"),
        0.025,
        None,
    );
    assert!(c["differences"][0]["z"].as_f64().unwrap() > 1.0, "{c}");
}
