//! C3D force plates on the command line, end to end on the real trial: the bundled
//! treadmill trial's raw forces (`subject01_walk1_grf.mot`, 600 Hz, both feet measured
//! separately) re-encoded here as a C3D file with two TYPE-2 plates (plate 1 the right
//! foot, plate 2 the left, turned 180° about the vertical, ORIGIN offsets, POINT:UNITS
//! mm, moments in N·mm, shuffled channels, float storage) by the inverse plate equations,
//! then tracked with `--forces trial.c3d --plate r=1 --plate l=2` and compared with the
//! same track of the `.mot`.
//!
//! The `.mot`'s time column is printed to 4 decimals (0, 0.0017, 0.0033, …), while a C3D's
//! samples are at k/600 s exactly; the exact comparison (1e-6) is therefore against a copy
//! of the `.mot` with its instants written as k/600 in full (`retimed`), and the
//! comparison with the original file has the tolerance its rounded instants explain.

use crate::common;
use common::{csv_columns, footfall, grf, ik, json, root, s, stderr};

use footfall::data::{read_storage, Storage};
use footfall::workflows::trial::{load_trial, LoadedTrial, TrialFiles};
use std::path::{Path, PathBuf};

const BELT_SPEED: &str = "1.1322";
const RATE: f64 = 600.0;
/// Analog samples per 60 Hz point frame.
const PER_FRAME: usize = 10;

/// A lab frame of the C3D file: the OpenSim ground vector (x forward, y up, z right) in
/// the lab's (X, Y, Z), and the `--lab-axes` that undo it.
#[derive(Clone, Copy)]
enum Lab {
    /// X = x, Y = −z, Z = y: walking along +X, Z up (the default `+x,+z`).
    Default,
    /// X = −z, Y = −x, Z = y: walking along −Y (`-y,+z`).
    AlongMinusY,
}

impl Lab {
    fn of_opensim(self, v: [f64; 3]) -> [f64; 3] {
        match self {
            Lab::Default => [v[0], -v[2], v[1]],
            Lab::AlongMinusY => [-v[2], -v[0], v[1]],
        }
    }
}

/// One TYPE-2 plate: rows of `axes` are the plate's x, y, z in the lab (z down).
struct Plate {
    centre_mm: [f64; 3],
    axes: [[f64; 3]; 3],
    half_mm: [f64; 2],
    /// `FORCE_PLATFORM:ORIGIN` (mm, plate frame): measurement origin → surface centre.
    origin_mm: [f64; 3],
    /// Analog channels (1-based) of Fx Fy Fz Mx My Mz.
    channels: [usize; 6],
}

impl Plate {
    fn to_plate(&self, v: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| (0..3).map(|d| self.axes[i][d] * v[d]).sum())
    }
    fn to_lab(&self, v: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|d| (0..3).map(|i| self.axes[i][d] * v[i]).sum())
    }
    /// Fx Fy Fz (N), Mx My Mz (N·mm) the plate measures for the ground reaction `g` (N,
    /// lab, on the foot) at the CoP `cop` (mm, lab, on the surface) with free moment `tau`
    /// (N·mm, on the foot about the upward normal).
    fn channels(&self, g: [f64; 3], cop: [f64; 3], tau: f64) -> [f64; 6] {
        let f = self.to_plate([-g[0], -g[1], -g[2]]);
        let rel = self.to_plate(std::array::from_fn(|d| cop[d] - self.centre_mm[d]));
        let p: [f64; 3] = std::array::from_fn(|i| self.origin_mm[i] + rel[i]);
        [
            f[0],
            f[1],
            f[2],
            p[1] * f[2] - p[2] * f[1],
            p[2] * f[0] - p[0] * f[2],
            p[0] * f[1] - p[1] * f[0] + tau,
        ]
    }
}

/// The two plates in `lab`: plate 1 under the right foot, plate 2 under the left turned
/// by 180° about the vertical, both with their surface at the `.mot`'s CoP height.
fn plates(lab: Lab, height_m: f64) -> [Plate; 2] {
    let unit = |v: [f64; 3]| lab.of_opensim(v);
    let (fwd, up, right) = (
        unit([1.0, 0.0, 0.0]),
        unit([0.0, 1.0, 0.0]),
        unit([0.0, 0.0, 1.0]),
    );
    let neg = |v: [f64; 3]| v.map(|x| -x);
    let mm = |v: [f64; 3]| lab.of_opensim(v).map(|x| x * 1e3);
    [
        Plate {
            centre_mm: mm([0.6, height_m, 0.15]),
            // x forward, y right, z down
            axes: [fwd, right, neg(up)],
            half_mm: [500.0, 250.0],
            origin_mm: [1.0, -2.0, -38.0],
            channels: [1, 2, 3, 4, 5, 6],
        },
        Plate {
            centre_mm: mm([0.6, height_m, -0.15]),
            // turned by 180°: x backward, y left, z down
            axes: [neg(fwd), neg(right), neg(up)],
            half_mm: [500.0, 250.0],
            origin_mm: [-0.5, 1.5, -41.0],
            channels: [8, 7, 9, 12, 10, 11],
        },
    ]
}

/// The ground reaction of foot prefix `pre` at sample `k`: force (N), CoP (m), vertical
/// free moment (N·m), in OpenSim ground coordinates.
fn foot(g: &Storage, pre: &str, k: usize) -> ([f64; 3], [f64; 3], f64) {
    let c = |n: &str| g.column(&format!("{pre}{n}")).unwrap()[k];
    (
        [
            c("ground_force_vx"),
            c("ground_force_vy"),
            c("ground_force_vz"),
        ],
        [
            c("ground_force_px"),
            c("ground_force_py"),
            c("ground_force_pz"),
        ],
        g.column(&format!(
            "{}ground_torque_y",
            if pre.is_empty() { "" } else { "l_" }
        ))
        .unwrap()[k],
    )
}

/// Write the raw forces as a two-plate C3D file in `lab` (the first whole 60 Hz frames of
/// the 600 Hz samples; first frame 1, so sample k is at k/600 s).
fn write_c3d(path: &Path, lab: Lab) {
    use c3dio::{AnalogOffset, C3d, ForcePlatform, ForcePlatformType};
    let g = read_storage(&grf()).unwrap();
    let height = g.column("ground_force_py").unwrap()[0];
    let plates = plates(lab, height);
    let frames = g.len() / PER_FRAME;
    let n = frames * PER_FRAME;
    let mut c = C3d::new();
    for grp in [
        "POINT",
        "ANALOG",
        "FORCE_PLATFORM",
        "EVENT",
        "EVENT_CONTEXT",
        "MANUFACTURER",
        "SEG",
    ] {
        c.parameters.insert_group(grp, String::new());
    }
    c.points.units = ['m', 'm', ' ', ' '];
    c.points.frame_rate = (RATE / PER_FRAME as f64) as f32;
    c.points.first_frame = 1;
    c.points.last_frame = frames as u16;
    c.points.scale_factor = 1.0;
    let a = &mut c.analog;
    a.rate = RATE as f32;
    a.samples_per_channel_per_frame = PER_FRAME as u16;
    a.samples_per_frame = (PER_FRAME * 12) as u16;
    a.gen_scale = 1.0;
    // dyadic scales and whole offsets: exact in the float channels
    a.scales = vec![0.5; 12];
    a.offset = AnalogOffset::Signed(vec![0, 2, -1, 0, 3, 0, 0, -4, 0, 1, 0, 0]);
    a.bits = 16;
    let mut labels = vec![String::new(); 12];
    let mut units = vec![String::new(); 12];
    for (p, plate) in plates.iter().enumerate() {
        for (j, &ch) in plate.channels.iter().enumerate() {
            labels[ch - 1] = format!("{}{}", ["Fx", "Fy", "Fz", "Mx", "My", "Mz"][j], p + 1);
            units[ch - 1] = if j < 3 { "N" } else { "Nmm" }.into();
        }
    }
    a.labels = labels;
    a.descriptions = vec!["subject01_walk1".into(); 12];
    a.units = units;
    for k in 0..n {
        let mut row = vec![0.0; 12];
        for (plate, pre) in plates.iter().zip(["", "l_"]) {
            let (f, cop, tau) = foot(&g, pre, k);
            let v = plate.channels(
                lab.of_opensim(f),
                lab.of_opensim(cop).map(|x| x * 1e3),
                tau * 1e3,
            );
            for (j, &ch) in plate.channels.iter().enumerate() {
                row[ch - 1] = v[j];
            }
        }
        a.analog.push_row(row);
    }
    for plate in &plates {
        let mut fp = ForcePlatform {
            plate_type: ForcePlatformType::Type2,
            ..Default::default()
        };
        let quadrant = [[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]];
        for (i, q) in quadrant.iter().enumerate() {
            let off = plate.to_lab([q[0] * plate.half_mm[0], q[1] * plate.half_mm[1], 0.0]);
            fp.corners[i] = std::array::from_fn(|d| (plate.centre_mm[d] + off[d]) as f32);
        }
        for d in 0..3 {
            fp.origin[d] = plate.origin_mm[d] as f32;
        }
        let mut ch = [0u8; 8];
        for (j, &v) in plate.channels.iter().enumerate() {
            ch[j] = v as u8;
        }
        fp.channels = ch;
        c.forces.force_platforms.push(fp);
    }
    c.write_path(path.to_path_buf()).expect("write C3D");
}

/// The raw `.mot` with its instants written as k/600 s in full (the file prints them to 4
/// decimals); checked to be within that rounding of the printed ones.
fn write_retimed(path: &Path) {
    let text = std::fs::read_to_string(grf()).unwrap();
    let (head, body) = text.split_once("endheader").unwrap();
    // the rest of the `endheader` line (tabs), then the column names
    let mut lines = body.split_once('\n').unwrap().1.lines();
    let mut out = format!("{head}endheader\n{}\n", lines.next().unwrap());
    for (k, l) in lines.filter(|l| !l.trim().is_empty()).enumerate() {
        let (t, rest) = l.split_once('\t').unwrap();
        let exact = k as f64 / RATE;
        let printed: f64 = t.trim().parse().unwrap();
        assert!(
            (printed - exact).abs() <= 5.1e-5,
            "row {k}: {printed} is not {exact}"
        );
        out.push_str(&format!("{exact:.15}\t{rest}\n"));
    }
    std::fs::write(path, out).unwrap();
}

fn trial(forces: &Path, plates: &[&str], axes: Option<&str>) -> anyhow::Result<LoadedTrial> {
    load_trial(&TrialFiles {
        data: Some(ik()),
        forces: Some(forces.to_path_buf()),
        plates: plates.iter().map(|p| p.to_string()).collect(),
        lab_axes: axes.map(str::to_string),
        belt_speed: Some(1.1322),
        overground: false,
    })
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter()
        .filter(|x| x.is_finite())
        .fold(0.0, |m, x| m.max(x.abs()))
}

/// Largest difference of two channels relative to the channel's largest value; NaN must
/// be at the same instants.
fn rel_diff(a: &[f64], b: &[f64], what: &str) -> f64 {
    assert_eq!(a.len(), b.len(), "{what}");
    let scale = max_abs(b).max(1e-12);
    a.iter().zip(b).enumerate().fold(0.0, |m, (k, (x, y))| {
        assert_eq!(x.is_nan(), y.is_nan(), "{what} at {k}: {x} vs {y}");
        if x.is_nan() {
            m
        } else {
            m.max((x - y).abs() / scale)
        }
    })
}

#[test]
fn the_c3d_plates_give_the_mot_trials_forces_through_the_library() {
    let dir = tempfile::tempdir().unwrap();
    let (c3d, minus_y, mot) = (
        dir.path().join("walk1.c3d"),
        dir.path().join("walk1_y.c3d"),
        dir.path().join("retimed.mot"),
    );
    write_c3d(&c3d, Lab::Default);
    write_c3d(&minus_y, Lab::AlongMinusY);
    write_retimed(&mot);
    let want = trial(&mot, &[], None).unwrap().data;
    let orig = trial(&grf(), &[], None).unwrap().data;
    for (file, axes) in [(&c3d, None), (&minus_y, Some("-y,+z"))] {
        let got = trial(file, &["r=1", "l=2"], axes).unwrap();
        let note = &got.notes[0];
        assert!(
            note.contains("right foot plate 1, left foot plate 2"),
            "{note}"
        );
        assert!(
            note.contains(axes.unwrap_or("+x,+z")) && note.contains("t = 0 s"),
            "{note}"
        );
        let got = got.data;
        assert_eq!(got.time, want.time);
        assert_eq!(got.q, want.q);
        let mut worst = 0.0f64;
        for s in 0..2 {
            let (a, b) = (&got.feet[s], &want.feet[s]);
            worst = worst
                .max(rel_diff(&a.fx, &b.fx, "fx"))
                .max(rel_diff(&a.fy, &b.fy, "fy"))
                .max(rel_diff(&a.cop_x, &b.cop_x, "cop_x"));
        }
        // float channels: 7 significant digits of the forces and N·mm moments
        assert!(
            worst < 1e-6,
            "{}: relative difference {worst:e}",
            file.display()
        );
        let (h, hw) = (
            got.force_plate_height.unwrap(),
            want.force_plate_height.unwrap(),
        );
        assert!((h - hw).abs() < 1e-9, "plate height {h} vs {hw}");
        // the original .mot: its instants rounded to 0.05 ms move the forces by up to
        // |dF/dt|·5e-5 s
        let mut worst_orig = 0.0f64;
        for s in 0..2 {
            let (a, b) = (&got.feet[s], &orig.feet[s]);
            worst_orig = worst_orig
                .max(rel_diff(&a.fx, &b.fx, "fx"))
                .max(rel_diff(&a.fy, &b.fy, "fy"));
        }
        assert!(worst_orig < 1e-2, "vs the printed instants: {worst_orig:e}");
        eprintln!(
            "{}: {worst:e} (retimed), {worst_orig:e} (original .mot)",
            file.display()
        );
    }
}

/// `track --max-iter 0` of the IK with `forces`: its folder.
fn track(dir: &Path, name: &str, forces: &Path, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let ik = ik();
    let mut args = vec![
        "track",
        "--data",
        s(&ik),
        "--forces",
        s(forces),
        "--belt-speed",
        BELT_SPEED,
        "--max-iter",
        "0",
        "--no-check-points",
        "--out",
        s(&out),
    ];
    args.extend_from_slice(extra);
    let o = footfall(&args);
    // no iteration: stopped at the iteration limit (exit 3), the run folder written
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    out
}

/// Starting cost and the largest relative difference of the `data_*` targets of two runs.
fn compare_runs(a: &Path, b: &Path) -> (f64, f64, f64) {
    let j = |d: &Path| {
        json(&d.join("summary.json"))["history"][0]["objective"]
            .as_f64()
            .unwrap()
    };
    let (na, nb) = (
        csv_columns(&a.join("tracking.csv")),
        csv_columns(&b.join("tracking.csv")),
    );
    let mut worst = 0.0f64;
    let mut compared = 0;
    for (name, va) in &na {
        if name == "time" || name.starts_with("data_") {
            let vb = &nb.iter().find(|(n, _)| n == name).expect(name).1;
            worst = worst.max(rel_diff(va, vb, name));
            compared += 1;
        }
    }
    assert!(compared >= 15, "only {compared} target columns");
    (j(a), j(b), worst)
}

#[test]
fn track_with_c3d_plates_starts_where_the_mot_does() {
    let dir = tempfile::tempdir().unwrap();
    let (c3d, mot) = (dir.path().join("walk1.c3d"), dir.path().join("retimed.mot"));
    write_c3d(&c3d, Lab::AlongMinusY);
    write_retimed(&mot);
    let plates = ["--plate", "r=1", "--plate", "l=2", "--lab-axes", "-y,+z"];
    let a = track(dir.path(), "c3d", &c3d, &plates);
    let setup = json(&a.join("setup.json"));
    // the run folder holds a copy of the C3D, which setup.json names
    assert_eq!(setup["forces"].as_str(), Some("inputs/forces/walk1.c3d"));
    assert_eq!(
        std::fs::read(a.join("inputs/forces/walk1.c3d")).unwrap(),
        std::fs::read(&c3d).unwrap()
    );
    assert_eq!(setup["plates"], serde_json::json!(["r=1", "l=2"]));
    assert_eq!(setup["lab_axes"].as_str(), Some("-y,+z"));
    let b = track(dir.path(), "retimed", &mot, &[]);
    let (ja, jb, worst) = compare_runs(&a, &b);
    eprintln!("starting cost {ja} (C3D) vs {jb} (retimed .mot), targets {worst:e}");
    assert!(
        (ja - jb).abs() < 1e-6 * jb,
        "starting cost {ja} (C3D) vs {jb} (.mot)"
    );
    assert!(worst < 1e-6, "targets differ by {worst:e} relative");
    // the original .mot, its instants printed to 0.1 ms: forces 5.7e-4 apart (see above),
    // and tracked at those rounded instants (forces at their own rate); measured: starting
    // cost 1.7e-4, targets 6.4e-4 (relative)
    let c = track(dir.path(), "mot", &grf(), &[]);
    let (_, jc, worst) = compare_runs(&a, &c);
    eprintln!("starting cost {ja} (C3D) vs {jc} (original .mot), targets {worst:e}");
    assert!(
        (ja - jc).abs() < 5e-4 * jc,
        "starting cost {ja} (C3D) vs {jc} (.mot)"
    );
    assert!(
        worst < 5e-3,
        "targets differ from the original .mot's by {worst:e}"
    );
    // `report` of the run re-reads the same trial from setup.json: the recorded objective
    // re-evaluates (it refuses a mismatch)
    let o = footfall(&["report", s(&a), "--out", s(&dir.path().join("report"))]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// The message of a refused trial, checked to name every item of `words`.
fn refused(r: anyhow::Result<LoadedTrial>, words: &[&str]) -> String {
    let e = match r {
        Ok(_) => panic!("accepted"),
        Err(e) => format!("{e:#}"),
    };
    for w in words {
        assert!(e.contains(w), "'{w}' not in: {e}");
    }
    e
}

#[test]
fn plates_and_lab_axes_are_checked_naming_the_file_and_what_is_valid() {
    let dir = tempfile::tempdir().unwrap();
    let c3d = dir.path().join("walk1.c3d");
    write_c3d(&c3d, Lab::Default);
    let name = "walk1.c3d";
    let listed =
        "plate 1 centred at (0.600, -0.150, -0.007) m, plate 2 centred at (0.600, 0.150, -0.007) m";
    // without --plate: the file's plates and an example
    refused(
        trial(&c3d, &[], None),
        &["--forces", name, "--plate r=1 --plate l=2", listed],
    );
    // a plate number not in the file
    refused(
        trial(&c3d, &["r=1", "l=3"], None),
        &["--plate l=3", name, "no plate 3", listed],
    );
    refused(
        trial(&c3d, &["r=one", "l=2"], None),
        &["--plate r=one", "'one' is not a plate number", listed],
    );
    refused(
        trial(&c3d, &["x=1", "l=2"], None),
        &["--plate x=1", "neither r (right) nor l (left)"],
    );
    // a foot with no plate
    refused(
        trial(&c3d, &["r=1"], None),
        &[
            "--plate",
            "left (l) foot has no plate",
            name,
            "--plate l=N",
            listed,
        ],
    );
    refused(
        trial(&c3d, &["r=1", "l=1"], None),
        &["--plate l=1", "plate 1 is given twice"],
    );
    // malformed --lab-axes
    for (axes, says) in [
        ("+x+z", "expected FORWARD,UP"),
        (
            "+x,up",
            "'up' is not a lab axis; valid: +x, -x, +y, -y, +z, -z",
        ),
        ("+z,-z", "the same lab axis"),
    ] {
        refused(
            trial(&c3d, &["r=1", "l=2"], Some(axes)),
            &[&format!("--lab-axes {axes}"), says],
        );
    }
    // axes that turn the vertical force upside down: refused by the trial's conventions,
    // naming the C3D file, the plates and the axes
    refused(
        trial(&c3d, &["r=1", "l=2"], Some("+x,-z")),
        &[
            name,
            "grf_y_r",
            "plates r=1, l=2",
            "negative",
            "--lab-axes +x,-z",
        ],
    );
    // --lab-axes belongs to a C3D file
    refused(
        trial(&grf(), &[], Some("+x,+z")),
        &["--lab-axes +x,+z", "C3D"],
    );
    // a sagittal CSV holds its forces
    let csv = root().join("data/opensim_subject01_sagittal.csv");
    refused(
        load_trial(&TrialFiles {
            data: Some(csv),
            forces: Some(c3d.clone()),
            ..Default::default()
        }),
        &["--forces", name, "holds its own forces"],
    );
    // and on the command line: exit 1, an `error:` line, no run folder
    let out = dir.path().join("never");
    let ik = ik();
    let o = footfall(&[
        "track",
        "--data",
        s(&ik),
        "--forces",
        s(&c3d),
        "--belt-speed",
        BELT_SPEED,
        "--out",
        s(&out),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.starts_with("error: ") && err.contains(listed), "{err}");
    assert!(!out.exists());
}

#[test]
fn fit_foot_reads_the_c3d_plates() {
    let dir = tempfile::tempdir().unwrap();
    let (c3d, mot) = (dir.path().join("walk1.c3d"), dir.path().join("retimed.mot"));
    write_c3d(&c3d, Lab::Default);
    write_retimed(&mot);
    let ik = ik();
    let fit = |name: &str, forces: &Path, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec![
            "fit-foot",
            "--data",
            s(&ik),
            "--forces",
            s(forces),
            "--belt-speed",
            BELT_SPEED,
            "--max-iter",
            "5",
            "--quiet",
            "--out",
            s(&out),
        ];
        args.extend_from_slice(extra);
        let o = footfall(&args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        json(&out.join("summary.json"))
    };
    let a = fit("c3d", &c3d, &["--plate", "r=1", "--plate", "l=2"]);
    let b = fit("mot", &mot, &[]);
    assert_eq!(a["forces"].as_str(), Some(s(&c3d)));
    assert_eq!(a["plates"], serde_json::json!(["r=1", "l=2"]));
    assert!(a["stances"].as_u64().unwrap() >= 4, "{a}");
    assert_eq!(
        (&a["stances"], &a["samples"]),
        (&b["stances"], &b["samples"])
    );
    let (ca, cb) = (
        a["cost_initial"].as_f64().unwrap(),
        b["cost_initial"].as_f64().unwrap(),
    );
    eprintln!("fit-foot initial cost {ca} (C3D) vs {cb} (retimed .mot)");
    assert!((ca - cb).abs() < 1e-6 * cb, "eq. 13 cost {ca} vs {cb}");
}

#[test]
fn an_instant_next_to_an_unloaded_sample_keeps_the_loaded_samples_cop() {
    use footfall::data::c3d::{feet_from_plates, AxisMap, C3dForces, PlateForces};
    use footfall::model::Side;
    // one plate, 3 samples at 1 kHz: unloaded (CoP undefined), 100 N at x = 0.2 m, 300 N
    // at x = 0.4 m
    let plate = PlateForces {
        plate: 1,
        plate_type: 2,
        time: vec![0.0, 0.001, 0.002],
        force: vec![[0.0; 3], [10.0, 0.0, 100.0], [30.0, 0.0, 300.0]],
        cop: vec![[f64::NAN; 3], [0.2, 0.0, 0.0], [0.4, 0.0, 0.0]],
        free_moment: vec![f64::NAN, 0.0, 0.0],
        centre: [0.0; 3],
        up: [0.0, 0.0, 1.0],
    };
    let forces = C3dForces {
        path: "in-memory.c3d".into(),
        analog_rate: 1000.0,
        cop_threshold: 20.0,
        plates: vec![plate],
    };
    let time = [0.0001, 0.0009, 0.0015];
    let [r, _] = feet_from_plates(&forces, &[(Side::Right, 1)], AxisMap::default(), &time).unwrap();
    // 0.1 ms: 10 N, below the threshold; 0.9 ms: 90 N between the unloaded sample and the
    // 0.2 m one: 0.2 m (not NaN); 1.5 ms: between two loaded samples, linear: 0.3 m
    assert!(
        (r.fy[0] - 10.0).abs() < 1e-9 && r.cop_x[0].is_nan(),
        "{r:?}"
    );
    assert!(
        (r.fy[1] - 90.0).abs() < 1e-9 && (r.cop_x[1] - 0.2).abs() < 1e-12,
        "{r:?}"
    );
    assert!(
        (r.fy[2] - 200.0).abs() < 1e-9 && (r.cop_x[2] - 0.3).abs() < 1e-12,
        "{r:?}"
    );
    assert!((r.fx[1] - 9.0).abs() < 1e-9, "{r:?}");
}
