//! Synthetic trials: the documented noise model (per-channel Gaussian standard deviations,
//! seeded, unloaded feet exactly zero, CoP undefined below the threshold), exact events,
//! and a round trip through the sagittal CSV writer and reader.

use crate::common;

use footfall::data::{read_sagittal_csv, write_sagittal_csv, GaitData};
use footfall::integrate::IntegratorSettings;
use footfall::ocp::Transcription;
use footfall::phases::PhaseSequence;
use footfall::problems::evaluation::GaitSolution;
use footfall::problems::gait::GaitCycle;
use footfall::problems::synth::{synthesize, NoiseModel, SynthSettings};
use footfall::problems::track::TrackingSetup;

#[test]
fn noise_model_events_and_csv_round_trip() {
    let model = common::model("opensim_subject01.json", "ellipse.json");
    let pp = common::root().join("phases/ellipse_walk.json");
    let seq = PhaseSequence::load(&pp).unwrap();
    let sets = seq.resolve(&model, &pp).unwrap();
    let data = GaitData::bundled(&common::root()).unwrap();
    let setup = TrackingSetup::new(&model, &seq, &sets, &data).unwrap();
    let cycle = GaitCycle::new(&model, &setup.seq, &sets).unwrap();
    let ocp = setup
        .ocp(&cycle, &model, &sets, IntegratorSettings::default())
        .unwrap();
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    // any solution drives the generator: here the tracking guess (each interval from its node)
    let mut sol = GaitSolution::from_nlp(&tr, &w0, &cycle.continuous, 0.0);
    sol.phases.iter_mut().for_each(|p| {
        p.x.iter_mut()
            .for_each(|x| x[18..].iter_mut().for_each(|a| *a = 0.05))
    });
    let half = sol.span().1;
    let deg = std::f64::consts::PI / 180.0;
    let noise = NoiseModel {
        position_m: 0.002,
        angle_rad: 0.5 * deg,
        force_n: 5.0,
        cop_m: 0.005,
        seed: 3,
    };
    let settings = SynthSettings {
        rate_hz: 100.0,
        start_s: -0.2,
        duration_s: 4.0 * half,
        noise,
        integrator: IntegratorSettings::default(),
        measurement: Default::default(),
    };
    let (noisy, truth) = synthesize(&model, &sets, &sol, &settings, "t").unwrap();
    let (again, _) = synthesize(&model, &sets, &sol, &settings, "t").unwrap();
    assert_eq!(noisy.q, again.q, "same seed, same bits");

    // noise statistics per channel kind
    let sd = |a: &[f64], b: &[f64]| {
        let d: Vec<f64> = a
            .iter()
            .zip(b)
            .filter(|(x, y)| x.is_finite() && y.is_finite() && **y != 0.0)
            .map(|(x, y)| x - y)
            .collect();
        let m = d.iter().sum::<f64>() / d.len() as f64;
        (
            (d.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (d.len() - 1) as f64).sqrt(),
            d.len(),
        )
    };
    let mut angles = Vec::new();
    for i in 2..9 {
        angles.push(sd(&noisy.q[i], &truth.clean.q[i]).0);
    }
    let a = angles.iter().sum::<f64>() / angles.len() as f64;
    assert!(
        (a / noise.angle_rad - 1.0).abs() < 0.1,
        "angle noise sd {a} vs {}",
        noise.angle_rad
    );
    let (p, _) = sd(&noisy.q[1], &truth.clean.q[1]);
    assert!(
        (p / noise.position_m - 1.0).abs() < 0.15,
        "position noise sd {p}"
    );
    let (f, n) = sd(&noisy.feet[0].fy, &truth.clean.feet[0].fy);
    assert!(
        n > 100 && (f / noise.force_n - 1.0).abs() < 0.15,
        "force noise sd {f} over {n}"
    );
    for s in 0..2 {
        for k in 0..noisy.time.len() {
            let (c, nz) = (&truth.clean.feet[s], &noisy.feet[s]);
            if c.fy[k] == 0.0 && c.fx[k] == 0.0 {
                assert_eq!(
                    (nz.fx[k], nz.fy[k]),
                    (0.0, 0.0),
                    "an unloaded foot reads zero"
                );
            }
            assert_eq!(
                nz.cop_x[k].is_nan(),
                !(nz.fy[k] >= noisy.cop_threshold),
                "CoP defined exactly where loaded"
            );
        }
    }
    // exact events: one heel strike per foot per cycle, alternating, half a cycle apart
    let ev = noisy.events.as_ref().unwrap();
    assert!(ev.heel_strike[1].iter().any(|&t| t.abs() < 1e-12), "{ev:?}");
    assert!(
        ev.heel_strike[0].iter().any(|&t| (t - half).abs() < 1e-12),
        "{ev:?}"
    );

    // CSV + meta round trip, events included
    let dir = tempfile::tempdir().unwrap();
    let (csv, meta) = write_sagittal_csv(&noisy);
    std::fs::write(dir.path().join("trial.csv"), csv).unwrap();
    std::fs::write(dir.path().join("trial_meta.json"), meta).unwrap();
    let back = read_sagittal_csv(&dir.path().join("trial.csv")).unwrap();
    assert_eq!(back.time, noisy.time);
    assert_eq!(back.q, noisy.q);
    for s in 0..2 {
        assert_eq!(
            (&back.feet[s].fx, &back.feet[s].fy),
            (&noisy.feet[s].fx, &noisy.feet[s].fy)
        );
    }
    let be = back.events.clone().unwrap();
    assert_eq!(
        (&be.heel_strike, &be.toe_off, be.loaded_at_start),
        (&ev.heel_strike, &ev.toe_off, ev.loaded_at_start)
    );
    // a tracking setup built from the file uses the given events
    let s2 = TrackingSetup::new(&model, &seq, &sets, &back).unwrap();
    assert!(
        s2.window.0.abs() < 1e-12 && (s2.window.1 - half).abs() < 1e-12,
        "{:?}",
        s2.window
    );
}

/// A model effect is hidden by re-fitting the `--from` run's data with the effect held in
/// the model. A downhill slope of −0.022 rad once stopped that re-fit on Clarabel's
/// numerical error; it converges, and the truth it keeps is the slope.
#[test]
fn a_downhill_slope_is_hidden_by_a_converged_refit() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("slope");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_footfall"))
        .current_dir(&root)
        .args([
            "synth",
            "--from",
            "tests/data/hidden/base",
            "--hidden-effect",
            "ground_slope:angle=-0.022",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("truth.json")).unwrap()).unwrap();
    assert_eq!(truth["effect_parameters"][0]["name"], "ground_slope.angle");
    assert_eq!(truth["effect_parameters"][0]["value"], -0.022);
    assert!(out.join("synthetic.csv").exists());
}
