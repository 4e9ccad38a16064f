//! Issue 23, Done-means 1's re-fits, for the compliant foot's CoP and body-mass trials at
//! 600 Hz (`tests/data/real_hidden_600hz`, the real trial edited by
//! `tools/make-real-hidden-trials`): the right foot's CoP 25 mm forward, and every force
//! 5 % high. Each trial's track and its re-fit with the diagnosed effect added by one line
//! (`footfall track … --effect cop_offset:side=right` or `--effect body_mass_error`, from
//! the trial's own track) are kept in `tests/data/real_compliant_600hz/<trial>` (stop 75).
//! The clock trials' re-fits are in `clocks_600hz`.

use super::clocks_600hz::errors_at;
use crate::common::*;

/// The re-fit of each trial with its diagnosed effect brings every channel's error at the
/// nodes near the untouched trial's: it closes at least half the gap the edit opened, or
/// lies within 20 % of the untouched trial's. The CoP edit opens a gap in the CoP (the
/// track follows the moved CoP with the foot, so the gap is small: 0.89 against 0.70 cm),
/// the mass edit in the normal force (31.2 against 22.5 N). Both re-fits converged
/// (stop 75: J 0.316933 in 21 iterations, 0.320114 in 24; the untouched trial's J is
/// 0.320195).
#[test]
fn the_compliant_cop_and_mass_refits_bring_every_channel_near_the_untouched_trials() {
    let kept = root().join("tests/data/real_compliant_600hz");
    let untouched = errors_at("untouched", &kept.join("untouched"));
    for (trial, channel, gap_at_least) in [
        ("real_cop_r+25mm", "CoP", 0.1),
        ("real_mass+5pct", "normal GRF", 4.0),
    ] {
        let edited = errors_at(trial, &kept.join(trial));
        let refit = errors_at(trial, &kept.join(trial).join("refit"));
        for ((name, u), ((_, e), (_, r))) in untouched.iter().zip(edited.iter().zip(&refit)) {
            eprintln!("{trial} {name}: untouched {u:.3}, edited {e:.3}, re-fitted {r:.3}");
            assert!(
                (r - u).abs() <= (0.5 * (e - u).abs()).max(0.2 * u),
                "{trial} {name}: re-fitted {r:.3} against the untouched {u:.3} (edited {e:.3})"
            );
        }
        let i = untouched.iter().position(|(n, _)| n == channel).unwrap();
        assert!(
            edited[i].1 - untouched[i].1 > gap_at_least,
            "{trial}: the edit's gap in {channel}"
        );
    }
}
