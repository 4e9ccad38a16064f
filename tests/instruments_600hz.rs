//! Issue 23, Done-means 1's re-fits, for the compliant foot's CoP, body-mass and gain
//! trials at 600 Hz (`tests/data/real_hidden_600hz`, the real trial edited by
//! `tools/make-real-hidden-trials`): the right foot's CoP 25 mm forward, every force 5 %
//! high, and the left plate's forces 6 % high. Each trial's track and its re-fit with the
//! diagnosed effect added by one line (`footfall track … --effect cop_offset:side=right`,
//! `--effect body_mass_error` or `--effect force_plate_gain:side=left`, from the trial's
//! own track) are kept in `tests/data/real_compliant_600hz/<trial>` (stop 75). The clock
//! trials' re-fits are in `clocks_600hz`.

use super::clocks_600hz::refit_brings_every_channel_near_the_untouched_trials;

/// The re-fit of each trial with its diagnosed effect brings every channel's error at the
/// nodes near the untouched trial's: it closes at least half the gap the edit opened, or
/// lies within 20 % of the untouched trial's. The CoP edit opens a gap in the CoP (the
/// track follows the moved CoP with the foot, so the gap is small: 0.89 against 0.70 cm),
/// the mass and gain edits in the normal force (31.2 and 33.2 against 22.5 N). The three
/// re-fits converged (stop 75: J 0.316933 in 21 iterations, 0.320114 in 24, 0.315913 in 26; the
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
