//! C3D force-plate input (`footfall::data::c3d`): a plate file made here from a known load
//! by the inverse of the plate equations, read back to GRF and CoP in the lab frame and to
//! the sagittal quantities; clear errors for bad files.
//!
//! The generator below writes the analog channels with c3dio's writer from the load alone
//! (the C3D user guide's TYPE-2 plate: the plate measures the foot's force $F$ and its
//! moment $M = p \times F + T\hat z$ about the measurement origin, `ORIGIN` pointing from
//! that origin to the surface centre); it shares no code with the reader. All load values
//! are dyadic (multiples of 1/4 N, 1/4 mm), so the f32 channels hold them exactly and the
//! reader must reproduce the load to rounding. `FOOTFALL_WRITE_C3D_DATA=1 cargo test --test
//! c3d` rewrites the committed file and its truth (tools/make-c3d-test-data).

use c3dio::{AnalogOffset, C3d, ForcePlatform, ForcePlatformType};
use footfall::data::c3d::{feet_from_plates, read_c3d_plates, AxisMap};
use footfall::data::DataError;
use footfall::model::Side;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

const N: usize = 40;
const ANALOG_RATE: f64 = 1000.0;
const POINT_RATE: f64 = 100.0;
const THRESHOLD: f64 = 20.0;
/// Surface centre in the lab (mm): the plate sits off the lab origin and 7.8 mm up.
const CENTRE_MM: [f64; 3] = [1500.0, 750.0, 7.8125];
/// Plate axes in the lab (columns of plate→lab): plate x along lab +y, plate y along lab
/// +x, plate z down (−z): the plate is turned by 90° against the lab.
const AXES: [[f64; 3]; 3] = [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]];
/// Half-sizes along plate x and y (mm).
const HALF: [f64; 2] = [250.0, 312.5];
/// `FORCE_PLATFORM:ORIGIN` (mm, plate frame): from the measurement origin to the surface
/// centre, 40.5 mm below it and slightly off-centre.
const ORIGIN_MM: [f64; 3] = [1.5, -2.25, -40.5];
/// Analog channel of Fx, Fy, Fz, Mx, My, Mz (1-based): channel 1 is an unrelated sync
/// signal and the plate's channels are shuffled, so that `CHANNEL` matters.
const CHANNEL: [usize; 6] = [3, 4, 2, 6, 7, 5];
const SCALE: f32 = 0.5;
const GEN_SCALE: f32 = 0.25;
const OFFSET: [i16; 7] = [0, 3, -7, 11, 0, 5, -2];

/// Calibration matrix of the type-4 variant, `CAL[i][j]` taking channel `j` (V) into
/// output `i` (`Fx Fy Fz` in N, `Mx My Mz` in N·mm): scaled, permuted channels with two
/// cross-talk terms, so that a transposed or misindexed matrix gives another load.
const CAL: [[f64; 6]; 6] = [
    [0.0, 2.0, 0.0, 0.0, 0.0, 0.0],
    [4.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [0.5, 0.0, 8.0, 0.0, 0.0, 0.0],
    [0.0, 0.0, 0.0, 0.0, 64.0, 0.0],
    [0.0, 0.0, 0.0, 128.0, 0.0, 0.0],
    [0.0, -2.0, 0.0, 0.0, 0.0, 32.0],
];

/// The channel voltages that `CAL` turns into the plate outputs `l`: `CAL`'s inverse by
/// hand (exact in binary for these entries).
fn volts(l: [f64; 6]) -> [f64; 6] {
    let v0 = l[1] / 4.0;
    let v1 = l[0] / 2.0;
    [
        v0,
        v1,
        (l[2] - 0.5 * v0) / 8.0,
        l[4] / 128.0,
        l[3] / 64.0,
        (l[5] + 2.0 * v1) / 32.0,
    ]
}

/// The known load at analog sample `k`: ground reaction on the foot (N, lab), CoP (mm,
/// lab) and free moment on the foot about the upward normal (N·mm).
fn load(k: usize) -> ([f64; 3], [f64; 3], f64) {
    let c = CENTRE_MM;
    if k < 5 {
        return ([0.0; 3], c, 0.0); // unloaded
    }
    if k == 5 {
        // loaded below the CoP threshold
        return ([1.0, -0.5, 10.0], [c[0] + 10.0, c[1] + 20.0, c[2]], 0.0);
    }
    let j = (k - 6) as f64;
    (
        [-40.0 + 2.5 * j, 6.0 - 0.25 * j, 150.0 + 16.0 * j],
        [c[0] - 120.0 + 7.5 * j, c[1] + 40.0 - 1.5 * j, c[2]],
        1500.0 - 50.0 * j,
    )
}

fn lab_to_plate(v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| (0..3).map(|d| AXES[i][d] * v[d]).sum())
}

fn plate_to_lab(v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|d| (0..3).map(|i| AXES[i][d] * v[i]).sum())
}

/// The six plate channels (N, N·mm) for sample `k`, by the inverse plate equations.
fn plate_channels(k: usize) -> [f64; 6] {
    let (g, cop, tau) = load(k);
    let f = lab_to_plate([-g[0], -g[1], -g[2]]); // the foot's force on the plate
    let rel = lab_to_plate([
        cop[0] - CENTRE_MM[0],
        cop[1] - CENTRE_MM[1],
        cop[2] - CENTRE_MM[2],
    ]);
    let p = [
        ORIGIN_MM[0] + rel[0],
        ORIGIN_MM[1] + rel[1],
        ORIGIN_MM[2] + rel[2],
    ];
    let m = [
        p[1] * f[2] - p[2] * f[1],
        p[2] * f[0] - p[0] * f[2],
        p[0] * f[1] - p[1] * f[0] + tau,
    ];
    [f[0], f[1], f[2], m[0], m[1], m[2]]
}

#[derive(Clone, Copy, PartialEq)]
enum Variant {
    /// One type-2 plate carrying the known load.
    Plate,
    /// The same analog data without a force platform.
    NoPlate,
    /// The plate declared as type 3 (Kistler, eight channels).
    Type3,
    /// A type-4 plate: channels in volts, turned into the load by `CAL`.
    Type4,
}

/// Write the test trial with c3dio's writer.
fn write_trial(path: &Path, variant: Variant) {
    let mut c = C3d::new();
    for g in [
        "POINT",
        "ANALOG",
        "FORCE_PLATFORM",
        "EVENT",
        "EVENT_CONTEXT",
        "MANUFACTURER",
        "SEG",
    ] {
        c.parameters.insert_group(g, String::new());
    }
    let spf = (ANALOG_RATE / POINT_RATE) as usize;
    c.points.units = ['m', 'm', ' ', ' '];
    c.points.frame_rate = POINT_RATE as f32;
    c.points.first_frame = 1;
    c.points.last_frame = (N / spf) as u16;
    c.points.scale_factor = 1.0;
    let a = &mut c.analog;
    a.rate = ANALOG_RATE as f32;
    a.samples_per_channel_per_frame = spf as u16;
    a.samples_per_frame = (spf * 7) as u16;
    a.gen_scale = GEN_SCALE;
    a.scales = vec![SCALE; 7];
    a.offset = AnalogOffset::Signed(OFFSET.to_vec());
    a.bits = 16;
    let names = ["Fx1", "Fy1", "Fz1", "Mx1", "My1", "Mz1"];
    let mut labels = vec![String::new(); 7];
    let mut units = vec![String::new(); 7];
    labels[0] = "Sync".into();
    units[0] = "V".into();
    for (j, &ch) in CHANNEL.iter().enumerate() {
        labels[ch - 1] = names[j].into();
        units[ch - 1] = match (variant, j < 3) {
            (Variant::Type4, _) => "V",
            (_, true) => "N",
            _ => "Nmm",
        }
        .into();
    }
    a.labels = labels;
    a.descriptions = vec!["test".into(); 7];
    a.units = units;
    for k in 0..N {
        let v = if variant == Variant::Type4 {
            volts(plate_channels(k))
        } else {
            plate_channels(k)
        };
        let mut row = vec![1.25; 7];
        for (j, &ch) in CHANNEL.iter().enumerate() {
            row[ch - 1] = v[j];
        }
        a.analog.push_row(row);
    }
    if variant != Variant::NoPlate {
        let mut fp = ForcePlatform::default();
        fp.plate_type = match variant {
            Variant::Type3 => ForcePlatformType::Type3,
            Variant::Type4 => ForcePlatformType::Type4,
            _ => ForcePlatformType::Type2,
        };
        if variant == Variant::Type4 {
            // c3dio's writer stores m[a][b] at element 6a + b; the C3D guide's
            // CAL_MATRIX(i, j) (first index fastest) is element i + 6j: m = CALᵀ.
            fp.cal_matrix = Some(std::array::from_fn(|a| {
                std::array::from_fn(|b| CAL[b][a] as f32)
            }));
        }
        let quadrant = [[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]];
        for (i, q) in quadrant.iter().enumerate() {
            let off = plate_to_lab([q[0] * HALF[0], q[1] * HALF[1], 0.0]);
            // in mm, the POINT:UNITS
            fp.corners[i] = std::array::from_fn(|d| (CENTRE_MM[d] + off[d]) as f32);
        }
        for d in 0..3 {
            fp.origin[d] = ORIGIN_MM[d] as f32;
        }
        let mut ch = [0u8; 8];
        for (j, &v) in CHANNEL.iter().enumerate() {
            ch[j] = v as u8;
        }
        if variant == Variant::Type3 {
            ch[6] = 1;
            ch[7] = 1;
        }
        fp.channels = ch;
        c.forces.force_platforms.push(fp);
    }
    c.write_path(path.to_path_buf()).expect("write C3D");
}

/// The truth of the plate trial: per sample the GRF on the foot (N), CoP (m) and free
/// moment (N·m) in the lab, null where the vertical load is below the threshold.
fn truth() -> Value {
    let samples: Vec<Value> = (0..N)
        .map(|k| {
            let (g, cop, tau) = load(k);
            let loaded = g[2] >= THRESHOLD;
            json!({
                "t_s": k as f64 / ANALOG_RATE,
                "force_n": g,
                "cop_m": if loaded { json!(cop.map(|v| v * 1e-3)) } else { Value::Null },
                "free_moment_nm": if loaded { json!(tau * 1e-3) } else { Value::Null },
            })
        })
        .collect();
    json!({
        "description": "tests/data/c3d/plate_type2.c3d: one TYPE-2 plate (POINT:UNITS mm, moments in N·mm), surface centre (1.5, 0.75, 0.0078125) m, plate x along lab +y, y along lab +x, z down, ORIGIN (1.5, -2.25, -40.5) mm; channels Fx..Mz on analog 3,4,2,6,7,5 with scale 0.5, gen_scale 0.25 and offsets; force = ground reaction on the foot in the lab (z up), cop in m, free moment about +z in N·m; null below 20 N vertical",
        "analog_rate_hz": ANALOG_RATE,
        "cop_threshold_n": THRESHOLD,
        "samples": samples,
    })
}

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/c3d")
}

fn committed() -> PathBuf {
    data_dir().join("plate_type2.c3d")
}

fn committed_truth() -> Value {
    let text = std::fs::read_to_string(data_dir().join("plate_type2.truth.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn close(a: f64, b: f64, tol: f64, what: &str) {
    assert!(
        (a - b).abs() <= tol,
        "{what}: got {a}, expected {b} (tol {tol})"
    );
}

#[test]
fn regenerate_when_asked() {
    if std::env::var("FOOTFALL_WRITE_C3D_DATA").as_deref() != Ok("1") {
        return;
    }
    std::fs::create_dir_all(data_dir()).unwrap();
    write_trial(&committed(), Variant::Plate);
    let text = serde_json::to_string_pretty(&truth()).unwrap() + "\n";
    std::fs::write(data_dir().join("plate_type2.truth.json"), text).unwrap();
}

#[test]
fn reads_the_known_load_in_the_lab_frame() {
    let f = read_c3d_plates(&committed(), THRESHOLD).unwrap();
    assert_eq!((f.plates[0].plate, f.plates[0].plate_type), (1, 2));
    check_against_truth(&f, &committed_truth());
}

#[test]
fn a_type_4_plate_is_calibrated_by_its_matrix() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("type4.c3d");
    write_trial(&p, Variant::Type4);
    let f = read_c3d_plates(&p, THRESHOLD).unwrap();
    assert_eq!((f.plates[0].plate, f.plates[0].plate_type), (1, 4));
    check_against_truth(&f, &truth_roundtrip());
}

/// The plate read agrees with the truth to 1e-6 (N, m, N·m); NaN CoP exactly where the
/// truth has none.
fn check_against_truth(f: &footfall::data::c3d::C3dForces, truth: &Value) {
    assert_eq!(f.plates.len(), 1);
    assert_eq!(f.analog_rate, truth["analog_rate_hz"].as_f64().unwrap());
    let p = &f.plates[0];
    let samples = truth["samples"].as_array().unwrap();
    assert_eq!(p.time.len(), samples.len());
    let mut loaded = 0;
    let (mut ef, mut ec, mut et) = (0.0f64, 0.0f64, 0.0f64);
    for (k, s) in samples.iter().enumerate() {
        close(
            p.time[k],
            s["t_s"].as_f64().unwrap(),
            1e-12,
            &format!("time {k}"),
        );
        for d in 0..3 {
            let g = s["force_n"][d].as_f64().unwrap();
            close(p.force[k][d], g, 1e-6, &format!("force[{d}] at sample {k}"));
            ef = ef.max((p.force[k][d] - g).abs());
        }
        if s["cop_m"].is_null() {
            assert!(
                p.cop[k].iter().all(|v| v.is_nan()),
                "sample {k}: CoP {:?} should be NaN",
                p.cop[k]
            );
            assert!(p.free_moment[k].is_nan());
        } else {
            loaded += 1;
            for d in 0..3 {
                let c = s["cop_m"][d].as_f64().unwrap();
                close(p.cop[k][d], c, 1e-6, &format!("cop[{d}] at sample {k}"));
                ec = ec.max((p.cop[k][d] - c).abs());
            }
            let t = s["free_moment_nm"].as_f64().unwrap();
            close(
                p.free_moment[k],
                t,
                1e-6,
                &format!("free moment at sample {k}"),
            );
            et = et.max((p.free_moment[k] - t).abs());
        }
    }
    eprintln!("largest errors: force {ef:e} N, CoP {ec:e} m, free moment {et:e} N·m");
    assert_eq!(loaded, N - 6, "the truth has loaded and unloaded samples");
    // The plate's geometry: surface centre and the upward normal.
    for d in 0..3 {
        close(p.centre[d], CENTRE_MM[d] * 1e-3, 1e-9, "centre");
    }
    assert_eq!(p.up, [0.0, 0.0, 1.0]);
}

#[test]
fn sagittal_components_follow_the_axis_map() {
    let truth = committed_truth();
    let f = read_c3d_plates(&committed(), THRESHOLD).unwrap();
    let samples = truth["samples"].as_array().unwrap();
    // default: forward = +x, up = +z
    let s = f.plates[0].sagittal(AxisMap::default());
    // walking along lab −y with z up: forward = −y
    let t = f.plates[0].sagittal(AxisMap::new("-y", "+z").unwrap());
    for (k, v) in samples.iter().enumerate() {
        let g = |d: usize| v["force_n"][d].as_f64().unwrap();
        close(s.fx[k], g(0), 1e-6, "fx");
        close(s.fy[k], g(2), 1e-6, "fy");
        close(t.fx[k], -g(1), 1e-6, "fx along -y");
        close(t.fy[k], g(2), 1e-6, "fy (-y map)");
        match v["cop_m"].as_array() {
            Some(c) => {
                close(s.cop_x[k], c[0].as_f64().unwrap(), 1e-6, "cop_x");
                close(t.cop_x[k], -c[1].as_f64().unwrap(), 1e-6, "cop_x along -y");
            }
            None => assert!(s.cop_x[k].is_nan() && t.cop_x[k].is_nan()),
        }
    }
    close(
        s.surface_height.unwrap(),
        CENTRE_MM[2] * 1e-3,
        1e-9,
        "surface height",
    );
    let e = AxisMap::new("+z", "-z").unwrap_err();
    assert!(e.to_string().contains("same lab axis"), "{e}");
    let e = AxisMap::new("north", "+z").unwrap_err();
    assert!(e.to_string().contains("valid: +x, -x"), "{e}");
}

#[test]
fn feet_from_an_assigned_plate_at_other_instants() {
    let truth = committed_truth();
    let samples = truth["samples"].as_array().unwrap();
    let f = read_c3d_plates(&committed(), THRESHOLD).unwrap();
    // analog samples 10 and 30, and halfway between 20 and 21
    let time = [0.010, 0.0205, 0.030];
    let feet = feet_from_plates(&f, &[(Side::Left, 1)], AxisMap::default(), &time).unwrap();
    let at = |k: usize, key: &str, d: usize| samples[k][key][d].as_f64().unwrap();
    let left = &feet[1];
    close(left.fx[0], at(10, "force_n", 0), 1e-6, "left fx at 10 ms");
    close(left.fy[2], at(30, "force_n", 2), 1e-6, "left fy at 30 ms");
    let mid = 0.5 * (at(20, "force_n", 2) + at(21, "force_n", 2));
    close(left.fy[1], mid, 1e-6, "left fy between samples");
    close(
        left.cop_x[2],
        at(30, "cop_m", 0),
        1e-6,
        "left cop_x at 30 ms",
    );
    // the right foot stepped on no plate: not measured
    assert!(feet[0].fx.iter().chain(&feet[0].fy).all(|v| v.is_nan()));
    // errors: an unknown plate, a plate twice, instants outside the samples
    let e = feet_from_plates(&f, &[(Side::Right, 2)], AxisMap::default(), &time).unwrap_err();
    assert!(e.to_string().contains("plate 2 is not in the file"), "{e}");
    let e = feet_from_plates(
        &f,
        &[(Side::Right, 1), (Side::Left, 1)],
        AxisMap::default(),
        &time,
    )
    .unwrap_err();
    assert!(e.to_string().contains("assigned twice"), "{e}");
    let e = feet_from_plates(&f, &[(Side::Right, 1)], AxisMap::default(), &[0.0, 1.0]).unwrap_err();
    assert!(e.to_string().contains("covers"), "{e}");
}

#[test]
fn the_generator_reproduces_the_committed_file() {
    let truth = committed_truth();
    assert_eq!(
        truth,
        truth_roundtrip(),
        "tests/data/c3d/plate_type2.truth.json is stale: regenerate (tools/make-c3d-test-data)"
    );
    let dir = tempfile::tempdir().unwrap();
    let fresh = dir.path().join("plate.c3d");
    write_trial(&fresh, Variant::Plate);
    let a = read_c3d_plates(&fresh, THRESHOLD).unwrap();
    let b = read_c3d_plates(&committed(), THRESHOLD).unwrap();
    let same = |x: f64, y: f64| x == y || (x.is_nan() && y.is_nan());
    let (pa, pb) = (&a.plates[0], &b.plates[0]);
    for k in 0..N {
        for d in 0..3 {
            assert!(
                same(pa.force[k][d], pb.force[k][d]) && same(pa.cop[k][d], pb.cop[k][d]),
                "sample {k}"
            );
        }
    }
}

/// The truth as the generator makes it, through JSON text (as committed).
fn truth_roundtrip() -> Value {
    serde_json::from_str(&serde_json::to_string_pretty(&truth()).unwrap()).unwrap()
}

fn c3d_error(e: DataError) -> (PathBuf, String, String) {
    match e {
        DataError::C3d {
            path,
            parameter,
            reason,
        } => (path, parameter, reason),
        other => panic!("expected DataError::C3d, got {other:?}"),
    }
}

#[test]
fn a_missing_file_is_an_io_error_naming_it() {
    let p = data_dir().join("no_such_trial.c3d");
    let e = read_c3d_plates(&p, THRESHOLD).unwrap_err();
    assert!(matches!(e, DataError::Io { .. }), "{e:?}");
    assert_eq!(e.path(), p);
    assert!(e.to_string().contains("no_such_trial.c3d"), "{e}");
}

#[test]
fn a_file_without_a_force_platform_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("markers_only.c3d");
    write_trial(&p, Variant::NoPlate);
    let (path, parameter, reason) = c3d_error(read_c3d_plates(&p, THRESHOLD).unwrap_err());
    assert_eq!(path, p);
    assert_eq!(parameter, "FORCE_PLATFORM:USED");
    assert!(
        reason.contains("no force platform") && reason.contains("type 2"),
        "{reason}"
    );
}

#[test]
fn an_unsupported_plate_type_is_refused_naming_the_valid_one() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("kistler.c3d");
    write_trial(&p, Variant::Type3);
    let e = read_c3d_plates(&p, THRESHOLD).unwrap_err();
    let msg = e.to_string();
    let (path, parameter, reason) = c3d_error(e);
    assert_eq!(path, p);
    assert_eq!(parameter, "FORCE_PLATFORM:TYPE");
    assert!(
        reason.contains("plate 1 is type 3") && reason.contains("converts types 2, 4"),
        "{reason}"
    );
    assert!(
        msg.contains("kistler.c3d") && msg.contains("FORCE_PLATFORM:TYPE"),
        "{msg}"
    );
}

#[test]
fn a_file_that_is_not_c3d_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in [
        ("text.c3d", b"time,fx\n0,1\n".repeat(100)),
        ("short.c3d", vec![2u8, 80, 0, 0]),
        (
            "truncated.c3d",
            std::fs::read(committed()).unwrap()[..1000].to_vec(),
        ),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        let e = read_c3d_plates(&p, THRESHOLD).unwrap_err();
        assert_eq!(e.path(), p, "{name}: {e}");
    }
    let e = read_c3d_plates(&committed(), f64::NAN).unwrap_err();
    assert!(e.to_string().contains("cop_threshold"), "{e}");
}

#[test]
fn a_plate_type_c3dio_refuses_is_named_with_its_value() {
    // Patch FORCE_PLATFORM:TYPE of the committed file from 2 to 5 (AMTI 6-channel with a
    // 6×8 matrix): the record is name length 4, a positive group id, "TYPE", a 2-byte
    // offset, data type 2 (i16), one dimension of 1, the value.
    let mut bytes = std::fs::read(committed()).unwrap();
    let hits: Vec<usize> = (0..bytes.len() - 12)
        .filter(|&i| bytes[i] == 4 && (bytes[i + 1] as i8) > 0 && &bytes[i + 2..i + 6] == b"TYPE")
        .collect();
    assert_eq!(hits.len(), 1, "one TYPE record");
    let at = hits[0] + 8;
    assert_eq!(&bytes[at..at + 5], &[2, 1, 1, 2, 0], "an i16 TYPE = 2");
    bytes[at + 3] = 5;
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("type5.c3d");
    std::fs::write(&p, bytes).unwrap();
    let (path, parameter, reason) = c3d_error(read_c3d_plates(&p, THRESHOLD).unwrap_err());
    assert_eq!(path, p);
    assert_eq!(parameter, "FORCE_PLATFORM:TYPE");
    assert!(
        reason.contains("plate 1 is of type 5") && reason.contains("valid: 2, 4"),
        "{reason}"
    );
}

#[test]
fn a_foot_on_two_plates_gets_the_summed_force_and_the_weighted_cop() {
    use footfall::data::c3d::{C3dForces, PlateForces};
    let time = vec![0.0, 0.001, 0.002];
    let plate = |n: usize, f: [[f64; 3]; 3], x: [f64; 3]| PlateForces {
        plate: n,
        plate_type: 2,
        time: time.clone(),
        force: f.to_vec(),
        cop: x
            .iter()
            .map(|&x| {
                if x.is_nan() {
                    [f64::NAN; 3]
                } else {
                    [x, 0.3, 0.0]
                }
            })
            .collect(),
        free_moment: vec![0.0; 3],
        centre: [0.0; 3],
        up: [0.0, 0.0, 1.0],
    };
    let forces = C3dForces {
        path: PathBuf::from("two.c3d"),
        analog_rate: 1000.0,
        cop_threshold: 20.0,
        plates: vec![
            // heel on plate 1 unloading, toe on plate 2 loading
            plate(
                1,
                [[5.0, 0.0, 300.0], [4.0, 0.0, 100.0], [0.0, 0.0, 0.0]],
                [1.0, 1.1, f64::NAN],
            ),
            plate(
                2,
                [[0.0, 0.0, 0.0], [-2.0, 0.0, 300.0], [-3.0, 0.0, 400.0]],
                [f64::NAN, 1.5, 1.6],
            ),
        ],
    };
    let feet = feet_from_plates(
        &forces,
        &[(Side::Right, 1), (Side::Right, 2)],
        AxisMap::default(),
        &time,
    )
    .unwrap();
    let r = &feet[0];
    assert_eq!(r.fx, vec![5.0, 2.0, -3.0]);
    assert_eq!(r.fy, vec![300.0, 400.0, 400.0]);
    // (100·1.1 + 300·1.5)/400 = 1.4
    close(r.cop_x[0], 1.0, 1e-12, "cop on plate 1 alone");
    close(r.cop_x[1], 1.4, 1e-12, "weighted cop");
    close(r.cop_x[2], 1.6, 1e-12, "cop on plate 2 alone");
    assert!(
        feet[1].fy.iter().all(|v| v.is_nan()),
        "the left foot was not measured"
    );
}
