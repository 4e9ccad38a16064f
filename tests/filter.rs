//! The zero-phase Butterworth low-pass against its analytic squared magnitude response,
//! and on a trial: uniform sampling required, forces untouched.

use footfall::data::filter::low_pass;

fn gain(f: f64, fs: f64, fc: f64) -> f64 {
    let r = (std::f64::consts::PI * f / fs).tan() / (std::f64::consts::PI * fc / fs).tan();
    1.0 / (1.0 + r.powi(4))
}

#[test]
fn sines_pass_with_the_squared_butterworth_gain_and_no_phase_lag() {
    let fs = 100.0;
    let fc = 6.0;
    let n = 2000;
    for f in [0.5, 2.0, 6.0, 12.0, 30.0] {
        let x: Vec<f64> = (0..n)
            .map(|k| (2.0 * std::f64::consts::PI * f * k as f64 / fs).sin())
            .collect();
        let y = low_pass(&x, fs, fc);
        // away from the ends: y = g·x exactly in phase
        let g = gain(f, fs, fc);
        let mid = 500..1500;
        let err = mid
            .clone()
            .map(|k| (y[k] - g * x[k]).abs())
            .fold(0.0, f64::max);
        assert!(
            err < 1e-6 + 1e-3 * g,
            "f = {f} Hz: max |y − g x| = {err}, g = {g}"
        );
    }
    // a line passes unchanged (odd reflection at the ends)
    let x: Vec<f64> = (0..300).map(|k| 0.3 - 0.01 * k as f64).collect();
    let y = low_pass(&x, fs, fc);
    let err = x
        .iter()
        .zip(&y)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    // the filter starts at rest on the padded first value, so a ramp carries a start-up
    // transient that decays over the padding (3 time constants) to this level
    assert!(err < 1e-6, "line changed by {err}");
}

#[test]
fn kinematics_are_filtered_forces_are_not() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let d = footfall::data::GaitData::bundled(&root).unwrap();
    let f = d.low_pass_kinematics(6.0).unwrap();
    for s in 0..2 {
        assert_eq!(
            (&f.feet[s].fx, &f.feet[s].fy),
            (&d.feet[s].fx, &d.feet[s].fy)
        );
        assert!(f.feet[s]
            .cop_x
            .iter()
            .zip(&d.feet[s].cop_x)
            .all(|(a, b)| a == b || (a.is_nan() && b.is_nan())));
    }
    assert_ne!(f.q[5], d.q[5]);
    let change = f.q[4]
        .iter()
        .zip(&d.q[4])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        change > 0.0 && change < 0.1,
        "knee changed by up to {change} rad"
    );
    let mut bad = d.clone();
    bad.time[10] += 0.3 * (d.time[11] - d.time[10]);
    let e = bad.low_pass_kinematics(6.0).unwrap_err().to_string();
    assert!(
        e.contains("uniform sampling") && e.contains("sample 10"),
        "{e}"
    );
    let e = d.low_pass_kinematics(1e6).unwrap_err().to_string();
    assert!(e.contains("cutoff"), "{e}");
}
