//! Bad input through the library API: every malformed, inconsistent or physically invalid
//! file gives a typed error whose message names the file, the field (as a dotted path) and
//! what is wrong; an integrator failure names the phase and the time. Nothing panics.

use footfall::controls::ControlTable;
use footfall::integrate::{IntegratorError, IntegratorSettings};
use footfall::model::spec::{FootSpec, ModelSpec};
use footfall::model::{GaitModel, ModelError};
use footfall::phases::PhaseSequence;
use footfall::simulate::{simulate, SimulationError, SimulationSettings};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A temporary folder that bad files are written into.
struct Scratch(tempfile::TempDir);

impl Scratch {
    fn new() -> Self {
        Self(tempfile::tempdir().expect("temp dir"))
    }
    fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.path().join(name);
        std::fs::write(&p, text).expect("write bad file");
        p
    }
}

/// A valid model file with explicit segments, `{SEG}` replaced by the thigh segment and
/// `{EXTRA}` by further top-level fields.
const EXPLICIT_MODEL: &str = r#"{
  "name": "explicit",
  "gravity": 9.81,
  "body": {
    "preset": "explicit",
    "segments": {
      "hat": { "mass": 50.0, "com": [0.0, 0.3], "izz": 3.0 },
      "thigh": {SEG},
      "shank": { "mass": 3.5, "com": [0.0, -0.18], "izz": 0.05 },
      "foot": { "mass": 1.0, "com": [0.05, -0.04], "izz": 0.004 },
      "hip_in_pelvis": [0.0, -0.08],
      "knee_in_thigh": [0.0, -0.42],
      "ankle_in_shank": [0.0, -0.42]
    }
  },
  "actuators": { "type": "joint_torques", "max_torque": 400.0 }{EXTRA}
}"#;

const GOOD_THIGH: &str = r#"{ "mass": 8.0, "com": [0.0, -0.18], "izz": 0.12 }"#;

fn explicit_model(thigh: &str, extra: &str) -> String {
    EXPLICIT_MODEL
        .replace("{SEG}", thigh)
        .replace("{EXTRA}", extra)
}

const GOOD_FOOT: &str = r#"{
  "name": "two_circles",
  "primitives": [
    { "name": "heel", "shape": { "type": "circle", "centre": [-0.06, -0.066], "radius": 0.049 } },
    { "name": "toe", "shape": { "type": "circle", "centre": [0.12, -0.066], "radius": 0.075 } }
  ]
}"#;

/// Assert an [`ModelError::Invalid`] for `file` and `field` whose reason contains `words`,
/// and that its message shows all three.
fn assert_invalid(err: ModelError, file: &Path, field: &str, words: &[&str]) -> String {
    let msg = err.to_string();
    match &err {
        ModelError::Invalid {
            path,
            field: f,
            reason,
        } => {
            assert_eq!(path, file, "wrong file in: {msg}");
            assert_eq!(f, field, "wrong field in: {msg}");
            for w in words {
                assert!(reason.contains(w), "reason lacks {w:?}: {msg}");
            }
        }
        other => panic!("expected ModelError::Invalid for {field}, got {other:?}"),
    }
    assert!(
        msg.contains(&file.display().to_string()),
        "message does not name the file: {msg}"
    );
    assert!(
        msg.contains(field),
        "message does not name the field: {msg}"
    );
    msg
}

/// Assert a [`ModelError::Json`] for `file` at `line` whose message names `field` and
/// contains `words`.
fn assert_json(err: ModelError, file: &Path, line: usize, field: &str, words: &[&str]) -> String {
    let msg = err.to_string();
    match &err {
        ModelError::Json {
            path,
            message,
            line: l,
            column,
        } => {
            assert_eq!(path, file, "wrong file in: {msg}");
            assert_eq!(*l, line, "wrong line in: {msg}");
            assert!(*column > 0, "no column in: {msg}");
            assert!(
                message.contains(field),
                "message does not name `{field}`: {msg}"
            );
            for w in words {
                assert!(message.contains(w), "message lacks {w:?}: {msg}");
            }
        }
        other => panic!("expected ModelError::Json, got {other:?}"),
    }
    assert!(
        msg.contains(&file.display().to_string()),
        "message does not name the file: {msg}"
    );
    assert!(
        msg.contains(&format!("line {line}")),
        "message does not name the line: {msg}"
    );
    msg
}

fn reference_model() -> GaitModel {
    GaitModel::load(
        &root().join("models/opensim_subject01.json"),
        &root().join("models/feet/ellipse.json"),
    )
    .expect("bundled model loads")
}

// ---------------------------------------------------------------------------------------
// Model files

#[test]
fn explicit_model_and_foot_are_valid() {
    // The templates the bad cases below are derived from load and assemble.
    let d = Scratch::new();
    let m = d.write("model.json", &explicit_model(GOOD_THIGH, ""));
    let f = d.write("foot.json", GOOD_FOOT);
    let model = GaitModel::load(&m, &f).expect("valid explicit model");
    assert_eq!(model.contacts.len(), 4);
}

#[test]
fn bundled_files_pass_the_checks() {
    for model in [
        "gait9dof.json",
        "opensim_subject01.json",
        "opensim_subject01_torque.json",
        "opensim_subject01_seed_damping.json",
    ] {
        for foot in [
            "ellipse.json",
            "double_circle.json",
            "peer_ellipse.json",
            "heel_circle_forefoot_ellipse.json",
        ] {
            let m = root().join("models").join(model);
            let f = root().join("models/feet").join(foot);
            GaitModel::load(&m, &f).unwrap_or_else(|e| panic!("{e}"));
        }
    }
    for (phases, foot) in [
        ("sim_ellipse_step.json", "ellipse.json"),
        ("sim_double_circle_step.json", "double_circle.json"),
        ("ellipse_walk.json", "ellipse.json"),
        ("double_circle_walk.json", "double_circle.json"),
        (
            "heel_circle_forefoot_ellipse_walk.json",
            "heel_circle_forefoot_ellipse.json",
        ),
    ] {
        let p = root().join("phases").join(phases);
        let model = GaitModel::load(
            &root().join("models/opensim_subject01.json"),
            &root().join("models/feet").join(foot),
        )
        .unwrap();
        PhaseSequence::load(&p)
            .unwrap()
            .resolve(&model, &p)
            .unwrap_or_else(|e| panic!("{e}"));
    }
    let names = reference_model().control_names();
    ControlTable::load_csv(
        &root().join("phases/sim_controls_cocontraction.csv"),
        &names,
    )
    .unwrap();
}

#[test]
fn malformed_json_gives_line_and_column() {
    let d = Scratch::new();
    // a missing comma after the "gravity" line (line 3)
    let text = explicit_model(GOOD_THIGH, "").replace("\"gravity\": 9.81,", "\"gravity\": 9.81");
    let m = d.write("model.json", &text);
    let err = ModelSpec::load(&m).unwrap_err();
    let msg = assert_json(err, &m, 4, "invalid JSON", &["expected `,` or `}`"]);
    eprintln!("{msg}");

    // a truncated file
    let good = explicit_model(GOOD_THIGH, "");
    let m2 = d.write("truncated.json", &good[..good.len() / 2]);
    let err = ModelSpec::load(&m2).unwrap_err();
    assert!(matches!(err, ModelError::Json { .. }), "{err:?}");
    assert!(err.to_string().contains("EOF"), "{err}");
    eprintln!("{err}");
}

#[test]
fn unknown_field_is_named() {
    let d = Scratch::new();
    let m = d.write(
        "model.json",
        &explicit_model(GOOD_THIGH, "").replace("\"gravity\"", "\"graviti\""),
    );
    let err = ModelSpec::load(&m).unwrap_err();
    let msg = assert_json(
        err,
        &m,
        3,
        "field 'graviti'",
        &["unknown field", "expected one of", "`gravity`"],
    );
    eprintln!("{msg}");

    // a typo deep inside the body: the dotted path leads to it
    let m = d.write(
        "nested.json",
        &explicit_model(r#"{ "mas": 8.0, "com": [0.0, -0.18], "izz": 0.12 }"#, ""),
    );
    let err = ModelSpec::load(&m).unwrap_err();
    let msg = assert_json(
        err,
        &m,
        8,
        "field 'body.segments.thigh.mas'",
        &["unknown field", "`mass`"],
    );
    eprintln!("{msg}");
}

#[test]
fn missing_required_field_is_named() {
    let d = Scratch::new();
    let m = d.write(
        "model.json",
        &explicit_model(r#"{ "mass": 8.0, "com": [0.0, -0.18] }"#, ""),
    );
    let err = ModelSpec::load(&m).unwrap_err();
    let msg = assert_json(
        err,
        &m,
        8,
        "field 'body.segments.thigh.izz'",
        &["missing field `izz`"],
    );
    eprintln!("{msg}");

    // a missing top-level section
    let text = explicit_model(GOOD_THIGH, "").replace(
        r#",
  "actuators": { "type": "joint_torques", "max_torque": 400.0 }"#,
        "",
    );
    let m = d.write("no_actuators.json", &text);
    let err = ModelSpec::load(&m).unwrap_err();
    let msg = assert_json(
        err,
        &m,
        text.lines().count(),
        "field 'actuators'",
        &["missing field `actuators`"],
    );
    eprintln!("{msg}");
}

#[test]
fn string_where_a_number_is_expected() {
    let d = Scratch::new();
    let m = d.write(
        "model.json",
        &explicit_model(
            r#"{ "mass": "heavy", "com": [0.0, -0.18], "izz": 0.12 }"#,
            "",
        ),
    );
    let err = ModelSpec::load(&m).unwrap_err();
    let msg = assert_json(
        err,
        &m,
        8,
        "field 'body.segments.thigh.mass'",
        &["invalid type: string \"heavy\"", "f64"],
    );
    eprintln!("{msg}");
}

#[test]
fn number_too_large_for_f64() {
    // JSON has no NaN or infinity; 1e999 is how an overflowing value arrives.
    let d = Scratch::new();
    let m = d.write(
        "model.json",
        &explicit_model(r#"{ "mass": 8.0, "com": [0.0, 1e999], "izz": 0.12 }"#, ""),
    );
    let err = ModelSpec::load(&m).unwrap_err();
    let msg = assert_json(
        err,
        &m,
        8,
        "near field 'body.segments.thigh.com[1]'",
        &["invalid JSON: number out of range"],
    );
    eprintln!("{msg}");
}

#[test]
fn non_positive_segment_mass_is_refused() {
    let d = Scratch::new();
    for mass in ["0.0", "-8.0"] {
        let m = d.write(
            "model.json",
            &explicit_model(
                &format!(r#"{{ "mass": {mass}, "com": [0.0, -0.18], "izz": 0.12 }}"#),
                "",
            ),
        );
        let err = ModelSpec::load(&m).unwrap_err();
        let msg = assert_invalid(
            err,
            &m,
            "body.segments.thigh.mass",
            &["must be a positive finite number", "kg"],
        );
        eprintln!("{msg}");
    }
    // the same check when assembling from a spec built in code
    let d2 = Scratch::new();
    let m = d2.write("model.json", &explicit_model(GOOD_THIGH, ""));
    let mut spec = ModelSpec::load(&m).unwrap();
    if let footfall::model::spec::BodySpec::Explicit { segments } = &mut spec.body {
        segments.shank.izz = -0.05;
    }
    let foot: FootSpec = serde_json::from_str(GOOD_FOOT).unwrap();
    let err = GaitModel::from_specs(&spec, &m, &foot, Path::new("foot.json")).unwrap_err();
    assert_invalid(err, &m, "body.segments.shank.izz", &["positive"]);
}

#[test]
fn non_positive_gravity_and_stature_are_refused() {
    let d = Scratch::new();
    let m = d.write(
        "model.json",
        &explicit_model(GOOD_THIGH, "").replace("9.81", "-9.81"),
    );
    let msg = assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "gravity",
        &["positive", "-9.81"],
    );
    eprintln!("{msg}");
    let m = d.write(
        "deleva.json",
        r#"{ "name": "x", "body": { "preset": "de_leva", "mass": 80.0, "height": 0.0, "sex": "male" },
             "actuators": { "type": "joint_torques" } }"#,
    );
    let msg = assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "body.height",
        &["positive", "m"],
    );
    eprintln!("{msg}");
}

#[test]
fn a_stature_below_any_humans_is_refused() {
    let d = Scratch::new();
    let m = d.write(
        "tiny.json",
        r#"{ "name": "x", "body": { "preset": "de_leva", "mass": 80.0, "height": 0.01, "sex": "male" },
             "actuators": { "type": "joint_torques" } }"#,
    );
    assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "body.height",
        &["0.01 m is below any human's", "[0.5, 3] m"],
    );
}

#[test]
fn absurd_gravity_mass_and_sizes_are_refused_with_short_numbers() {
    let d = Scratch::new();
    let m = d.write(
        "model.json",
        &explicit_model(GOOD_THIGH, "").replace("9.81", "1e308"),
    );
    let msg = assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "gravity",
        &["1e308 m/s²", "beyond the sensible limit", "(0, 100] m/s²"],
    );
    assert!(msg.len() < 200, "{msg}");
    let m = d.write(
        "model.json",
        &explicit_model(
            r#"{ "mass": 5000.0, "com": [0.0, -0.18], "izz": 0.12 }"#,
            "",
        ),
    );
    assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "body.segments.thigh.mass",
        &["5000 kg", "(0, 1000] kg"],
    );
    let m = d.write(
        "model.json",
        &explicit_model(r#"{ "mass": 8.0, "com": [0.0, -0.18], "izz": 1e6 }"#, ""),
    );
    assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "body.segments.thigh.izz",
        &["1e6 kg·m²", "(0, 100] kg·m²"],
    );
    let m = d.write(
        "model.json",
        &explicit_model(r#"{ "mass": 8.0, "com": [0.0, -1e9], "izz": 0.12 }"#, ""),
    );
    assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "body.segments.thigh.com",
        &["[0, -1e9] m", "±10 m"],
    );
    let m = d.write(
        "deleva.json",
        r#"{ "name": "x", "body": { "preset": "de_leva", "mass": 80.0, "height": 18.0, "sex": "male" },
             "actuators": { "type": "joint_torques" } }"#,
    );
    assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "body.height",
        &["18 m", "(0, 3] m"],
    );
    let m = d.write(
        "deleva.json",
        r#"{ "name": "x", "body": { "preset": "de_leva", "mass": 8e5, "height": 1.8, "sex": "male" },
             "actuators": { "type": "joint_torques" } }"#,
    );
    let msg = assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "body.mass",
        &["800000 kg", "(0, 1000] kg"],
    );
    eprintln!("{msg}");
}

#[test]
fn absurd_ground_force_is_refused_naming_line_and_column() {
    use footfall::data::DataError;
    let d = Scratch::new();
    let header = "time,pelvis_x,pelvis_y,pelvis_tilt,hip_r,knee_r,ankle_r,grf_x_r,grf_y_r,cop_x_r";
    let good =
        format!("{header}\n0.00,0,0.9,0,0,0,0,10,700,0.1\n0.01,0.01,0.9,0,0,0,0,10,700,0.1\n");
    let p = d.write("trial.csv", &good);
    footfall::data::read_sagittal_csv(&p).expect("the template is valid");
    let p = d.write(
        "trial.csv",
        &good.replace(
            "0.01,0.01,0.9,0,0,0,0,10,700,0.1",
            "0.01,0.01,0.9,0,0,0,0,10,1e308,NaN",
        ),
    );
    let err = footfall::data::read_sagittal_csv(&p).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, DataError::OutOfRange { row: 3, .. }), "{msg}");
    assert_eq!(err.column(), Some("grf_y_r"));
    for w in [
        "trial.csv",
        "line 3",
        "'grf_y_r'",
        "1e308 N",
        "at most 100000 N",
    ] {
        assert!(msg.contains(w), "{w:?} missing: {msg}");
    }
    assert!(msg.len() < 200, "{msg}");
}

#[test]
fn opensim_preset_with_missing_file_names_the_path() {
    let d = Scratch::new();
    let m = d.write(
        "model.json",
        r#"{ "name": "x", "body": { "preset": "opensim_model", "file": "no_such_model.json" },
             "actuators": { "type": "joint_torques" } }"#,
    );
    let err = ModelSpec::load(&m).unwrap_err();
    let msg = err.to_string();
    match &err {
        ModelError::Io { path, source } => {
            assert_eq!(path, &d.0.path().join("no_such_model.json"));
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("expected ModelError::Io, got {other:?}"),
    }
    assert!(
        msg.contains("no_such_model.json") && msg.contains("body.file"),
        "{msg}"
    );
    assert!(msg.contains(&m.display().to_string()), "{msg}");
    eprintln!("{msg}");
}

#[test]
fn unknown_effect_type_is_named() {
    let d = Scratch::new();
    let m = d.write(
        "model.json",
        &explicit_model(
            GOOD_THIGH,
            ",\n  \"effects\": [ { \"type\": \"tendon_slack\", \"joint\": \"knee\" } ]",
        ),
    );
    let err = ModelSpec::load(&m).unwrap_err();
    let msg = assert_json(
        err,
        &m,
        17,
        "field 'effects[0].type'",
        &["unknown variant `tendon_slack`", "passive_joint_stiffness"],
    );
    eprintln!("{msg}");
}

#[test]
fn effect_on_unknown_joint_is_refused() {
    let d = Scratch::new();
    let m = d.write(
        "model.json",
        &explicit_model(
            GOOD_THIGH,
            ",\n  \"effects\": [ { \"type\": \"passive_joint_stiffness\", \"joint\": \"elbow\", \"stiffness\": 10.0 } ]",
        ),
    );
    let err = ModelSpec::load(&m).unwrap_err();
    let msg = assert_invalid(
        err,
        &m,
        "effects[0].joint",
        &["'elbow'", "hip, knee, ankle"],
    );
    eprintln!("{msg}");

    // negative stiffness and a duplicated spring
    let m = d.write(
        "model2.json",
        &explicit_model(
            GOOD_THIGH,
            ",\n  \"effects\": [ { \"type\": \"passive_joint_stiffness\", \"joint\": \"knee\", \"stiffness\": -1.0 } ]",
        ),
    );
    assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "effects[0].stiffness",
        &["[0, 500]", "-1"],
    );
    let m = d.write(
        "model3.json",
        &explicit_model(
            GOOD_THIGH,
            ",\n  \"effects\": [ { \"type\": \"passive_joint_stiffness\", \"joint\": \"knee\", \"stiffness\": 1.0 },\n    \
             { \"type\": \"passive_joint_stiffness\", \"joint\": \"knee\", \"side\": \"left\", \"stiffness\": 2.0 } ]",
        ),
    );
    let msg = assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "effects[1].joint",
        &["left knee", "effects[0]"],
    );
    eprintln!("{msg}");
}

// ---------------------------------------------------------------------------------------
// Foot files

#[test]
fn a_foot_file_with_a_byte_order_mark_is_read() {
    let d = Scratch::new();
    let f = d.write("bom.json", &format!("\u{feff}{GOOD_FOOT}"));
    assert_eq!(FootSpec::load(&f).unwrap().primitives.len(), 2);
}

#[test]
fn a_json_file_that_is_not_an_object_says_what_it_holds() {
    let d = Scratch::new();
    for (text, held) in [("null", "null"), ("[1, 2]", "an array"), ("3", "a number")] {
        let f = d.write("foot.json", text);
        let msg = assert_json(FootSpec::load(&f).unwrap_err(), &f, 1, "", &[]);
        let want = format!("the file holds {held}, not a JSON object");
        assert!(msg.contains(&want), "{msg}");
        assert!(!msg.contains("struct"), "{msg}");
    }
}

#[test]
fn a_missing_foot_file_lists_the_bundled_feet() {
    let err = FootSpec::load(Path::new("no/such/foot.json")).unwrap_err();
    assert!(matches!(err, ModelError::NoFoot { .. }), "{err}");
    let msg = err.to_string();
    for w in [
        "no/such/foot.json",
        "`ellipse`, `double-circle`",
        "models/feet/peer_ellipse.json",
    ] {
        assert!(msg.contains(w), "{w:?} not in {msg}");
    }
}

#[test]
fn zero_or_negative_ellipse_semi_axis_is_refused() {
    let d = Scratch::new();
    for axes in ["[0.15, 0.0]", "[-0.15, 0.04]"] {
        let f = d.write(
            "foot.json",
            &format!(
                r#"{{ "name": "e", "primitives": [
  {{ "name": "sole", "shape": {{ "type": "ellipse", "centre": [0.04, -0.08], "angle": 0.0, "semi_axes": {axes} }} }} ] }}"#
            ),
        );
        let err = FootSpec::load(&f).unwrap_err();
        let msg = assert_invalid(
            err,
            &f,
            "primitives[0].shape.semi_axes",
            &["positive numbers of metres"],
        );
        eprintln!("{msg}");
    }
}

#[test]
fn extreme_primitive_size_is_refused() {
    let d = Scratch::new();
    let f = d.write("foot.json", &GOOD_FOOT.replace("0.075", "1e300"));
    let msg = assert_invalid(
        FootSpec::load(&f).unwrap_err(),
        &f,
        "primitives[1].shape.radius",
        &["at most 1 m", "1e300"],
    );
    eprintln!("{msg}");
}

#[test]
fn negative_circle_radius_is_refused() {
    let d = Scratch::new();
    let f = d.write("foot.json", &GOOD_FOOT.replace("0.075", "-0.075"));
    let err = FootSpec::load(&f).unwrap_err();
    let msg = assert_invalid(
        err,
        &f,
        "primitives[1].shape.radius",
        &["a positive number of metres", "-0.075"],
    );
    eprintln!("{msg}");
    // also through GaitModel::load
    let m = d.write("model.json", &explicit_model(GOOD_THIGH, ""));
    assert_invalid(
        GaitModel::load(&m, &f).unwrap_err(),
        &f,
        "primitives[1].shape.radius",
        &["positive"],
    );
}

#[test]
fn foot_without_primitives_is_refused() {
    let d = Scratch::new();
    let f = d.write("foot.json", r#"{ "name": "none", "primitives": [] }"#);
    let err = FootSpec::load(&f).unwrap_err();
    let msg = assert_invalid(
        err,
        &f,
        "primitives",
        &["no contact primitive", "never touch the ground"],
    );
    eprintln!("{msg}");
}

#[test]
fn foot_above_the_ankle_cannot_touch_the_ground() {
    let d = Scratch::new();
    let text = GOOD_FOOT.replace("-0.066", "0.1");
    let f = d.write("foot.json", &text);
    let err = FootSpec::load(&f).unwrap_err();
    let msg = assert_invalid(err, &f, "primitives", &["cannot touch the ground", "above"]);
    eprintln!("{msg}");
    // the model assembly refuses it too
    let m = d.write("model.json", &explicit_model(GOOD_THIGH, ""));
    let foot: FootSpec = serde_json::from_str(&text).unwrap();
    let spec = ModelSpec::load(&m).unwrap();
    assert_invalid(
        GaitModel::from_specs(&spec, &m, &foot, &f).unwrap_err(),
        &f,
        "primitives",
        &["cannot touch"],
    );
}

#[test]
fn duplicate_primitive_names_are_refused() {
    let d = Scratch::new();
    let f = d.write("foot.json", &GOOD_FOOT.replace("\"toe\"", "\"heel\""));
    let err = FootSpec::load(&f).unwrap_err();
    let msg = assert_invalid(err, &f, "primitives[1].name", &["'heel' is used twice"]);
    eprintln!("{msg}");
}

#[test]
fn unknown_shape_type_is_named() {
    let d = Scratch::new();
    let f = d.write(
        "foot.json",
        &GOOD_FOOT.replace(
            "\"circle\", \"centre\": [0.12",
            "\"blob\", \"centre\": [0.12",
        ),
    );
    let err = FootSpec::load(&f).unwrap_err();
    let msg = assert_json(
        err,
        &f,
        5,
        "field 'primitives[1].shape.type'",
        &["unknown variant `blob`", "`ellipse`"],
    );
    eprintln!("{msg}");
    // a shape lacking its size
    let f = d.write("foot2.json", &GOOD_FOOT.replace(", \"radius\": 0.075", ""));
    let err = FootSpec::load(&f).unwrap_err();
    let msg = assert_json(
        err,
        &f,
        5,
        "field 'primitives[1].shape.radius'",
        &["missing field `radius`"],
    );
    eprintln!("{msg}");
}

// ---------------------------------------------------------------------------------------
// Phase files

const PHASES: &str = r#"{
  "name": "p",
  "phases": [
    { "type": "continuous", "name": "stance", "contacts": [ { "contact": "r.sole" } ], "duration": 0.3 },
    { "type": "impact", "name": "strike", "contacts": [ { "contact": "r.sole" }, { "contact": "l.sole" } ] },
    { "type": "continuous", "name": "double", "contacts": [ { "contact": "r.sole" }, { "contact": "l.sole" } ], "duration": 0.1 }
  ]
}"#;

#[test]
fn phase_file_template_is_valid() {
    let d = Scratch::new();
    let p = d.write("phases.json", PHASES);
    let seq = PhaseSequence::load(&p).unwrap();
    assert_eq!(seq.resolve(&reference_model(), &p).unwrap().len(), 3);
}

#[test]
fn phase_file_without_phases_is_refused() {
    let d = Scratch::new();
    let p = d.write("phases.json", r#"{ "name": "p", "phases": [] }"#);
    let msg = assert_invalid(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        "phases",
        &["no phase"],
    );
    eprintln!("{msg}");
}

#[test]
fn phase_with_zero_intervals_is_refused() {
    let d = Scratch::new();
    let p = d.write(
        "phases.json",
        &PHASES.replace("\"duration\": 0.3", "\"duration\": 0.3, \"intervals\": 0"),
    );
    let msg = assert_invalid(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        "phases[0] ('stance').intervals",
        &["1 to 1000", "got 0"],
    );
    eprintln!("{msg}");
}

#[test]
fn phase_with_too_many_intervals_is_refused() {
    let d = Scratch::new();
    let p = d.write(
        "phases.json",
        &PHASES.replace(
            "\"duration\": 0.3",
            "\"duration\": 0.3, \"intervals\": 1000000",
        ),
    );
    let msg = assert_invalid(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        "phases[0] ('stance').intervals",
        &["1 to 1000", "got 1000000"],
    );
    eprintln!("{msg}");
    let p = d.write(
        "phases.json",
        &PHASES.replace("\"duration\": 0.3", "\"duration\": 0.3, \"intervals\": 999"),
    );
    // with the other phase's one, the sequence's limit of 1000
    PhaseSequence::load(&p).expect("1000 intervals are allowed");
}

/// The shipped walking cycle with its impacts' contacts replaced.
fn walk_with_impacts(file: &str, first: &str, last: &str) -> String {
    let text = std::fs::read_to_string(root().join("phases").join(file)).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let phases = v["phases"].as_array_mut().unwrap();
    let contacts = |list: &str| {
        serde_json::Value::from(
            list.split(',')
                .map(|c| serde_json::json!({ "contact": c }))
                .collect::<Vec<_>>(),
        )
    };
    phases[0]["contacts"] = contacts(first);
    let n = phases.len();
    phases[n - 1]["contacts"] = contacts(last);
    v.to_string()
}

#[test]
fn impact_that_does_not_match_the_next_phase_is_refused() {
    // the issue's case: a first impact on l.sole only, a last one on r.sole only
    let d = Scratch::new();
    let p = d.write(
        "walk.json",
        &walk_with_impacts("ellipse_walk.json", "l.sole", "r.sole"),
    );
    let msg = assert_invalid(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        "phases[0] ('1e*').contacts",
        &[
            "contacts active right after it",
            "the next phase '2e'",
            "r.sole, l.sole",
            "got l.sole",
        ],
    );
    eprintln!("{msg}");
    // rolling flags count: a non-rolling contact is another constraint
    let p = d.write(
        "p.json",
        &PHASES.replace(
            r#"{ "contact": "l.sole" } ] },"#,
            r#"{ "contact": "l.sole", "rolling": false } ] },"#,
        ),
    );
    assert_invalid(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        "phases[1] ('strike').contacts",
        &["l.sole (not rolling)", "got r.sole, l.sole (not rolling)"],
    );
}

#[test]
fn a_contact_mistyped_in_a_phase_is_named_beside_the_impacts_spelling() {
    let d = Scratch::new();
    let text = std::fs::read_to_string(root().join("phases/ellipse_walk.json")).unwrap();
    let typo = text.replacen(
        r#""name": "2e", "contacts": [ { "contact": "r.sole" }, { "contact": "l.sole" } ]"#,
        r#""name": "2e", "contacts": [ { "contact": "r.sole" }, { "contact": "l.sloe" } ]"#,
        1,
    );
    assert_ne!(typo, text, "the edit did not apply");
    let p = d.write("typo.json", &typo);
    assert_invalid(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        "phases[0] ('1e*').contacts",
        &[
            "the impact has 'l.sole' where the next phase '2e' has 'l.sloe'",
            "correct whichever name is mistyped",
        ],
    );
}

#[test]
fn last_impact_of_a_periodic_cycle_must_mirror_the_first_phase() {
    let d = Scratch::new();
    let p = d.write(
        "walk.json",
        &walk_with_impacts(
            "double_circle_walk.json",
            "r.forefoot,l.heel",
            "r.forefoot,l.heel",
        ),
    );
    let msg = assert_invalid(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        "phases[6] ('7c*').contacts",
        &[
            "the first continuous phase '2c' mirrored",
            "l.forefoot, r.heel",
            "got r.forefoot, l.heel",
        ],
    );
    eprintln!("{msg}");
}

#[test]
fn impact_that_adds_no_contact_or_is_followed_by_an_impact_is_refused() {
    let d = Scratch::new();
    let p = d.write(
        "p.json",
        &PHASES.replace(
            r#""contact": "r.sole" } ], "duration": 0.3"#,
            r#""contact": "r.sole" }, { "contact": "l.sole" } ], "duration": 0.3"#,
        ),
    );
    let msg = assert_invalid(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        "phases[1] ('strike').contacts",
        &["must add a contact", "'stance': r.sole, l.sole"],
    );
    eprintln!("{msg}");
    let p = d.write(
        "p.json",
        &PHASES.replace(
            r#"{ "type": "continuous", "name": "double""#,
            r#"{ "type": "impact", "name": "again", "contacts": [ { "contact": "r.sole" }, { "contact": "l.sole" } ] },
    { "type": "continuous", "name": "double""#,
        ),
    );
    let msg = assert_invalid(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        "phases[1] ('strike').contacts",
        &["followed by a continuous phase", "'again'"],
    );
    eprintln!("{msg}");
}

#[test]
fn negative_interval_count_is_a_type_error() {
    let d = Scratch::new();
    let p = d.write(
        "phases.json",
        &PHASES.replace("\"duration\": 0.3", "\"duration\": 0.3, \"intervals\": -2"),
    );
    let msg = assert_json(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        4,
        "field 'phases[0].intervals'",
        &["invalid value: integer `-2`", "usize"],
    );
    eprintln!("{msg}");
}

#[test]
fn unknown_enum_value_is_named() {
    let d = Scratch::new();
    let m = d.write(
        "model.json",
        "{ \"name\": \"x\",\n  \"body\": { \"preset\": \"de_leva\", \"mass\": 80.0, \"height\": 1.8, \"sex\": \"mal\" },\n  \
         \"actuators\": { \"type\": \"joint_torques\" } }",
    );
    let msg = assert_json(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        2,
        "field 'body.sex'",
        &["unknown variant `mal`", "`male` or `female`"],
    );
    eprintln!("{msg}");
}

#[test]
fn phase_with_bad_duration_is_refused() {
    let d = Scratch::new();
    let p = d.write(
        "phases.json",
        &PHASES.replace("\"duration\": 0.1", "\"duration\": -0.1"),
    );
    let msg = assert_invalid(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        "phases[2] ('double').duration",
        &["positive", "-0.1"],
    );
    eprintln!("{msg}");
    let p = d.write(
        "phases2.json",
        &PHASES.replace("\"duration\": 0.1", "\"duration\": \"0.1 s\""),
    );
    let msg = assert_json(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        6,
        "field 'phases[2].duration'",
        &["invalid type: string \"0.1 s\"", "number of seconds"],
    );
    eprintln!("{msg}");
}

#[test]
fn duplicate_phase_names_are_refused() {
    let d = Scratch::new();
    let p = d.write(
        "phases.json",
        &PHASES.replace("\"name\": \"double\"", "\"name\": \"stance\""),
    );
    let msg = assert_invalid(
        PhaseSequence::load(&p).unwrap_err(),
        &p,
        "phases[2] ('stance').name",
        &["already used by phases[0]", "unique"],
    );
    eprintln!("{msg}");
}

#[test]
fn unknown_contact_names_the_phase() {
    let d = Scratch::new();
    let p = d.write(
        "phases.json",
        // in the impact and the phase after it, which must list the same contacts
        &PHASES.replace("\"l.sole\"", "\"l.heel\""),
    );
    let seq = PhaseSequence::load(&p).unwrap();
    let err = seq.resolve(&reference_model(), &p).unwrap_err();
    let msg = assert_invalid(
        err,
        &p,
        "phases[1] ('strike').contacts[1].contact",
        &[
            "phase 'strike'",
            "unknown contact 'l.heel'",
            "r.sole, l.sole",
        ],
    );
    eprintln!("{msg}");
}

#[test]
fn contact_listed_twice_is_refused() {
    let d = Scratch::new();
    let p = d.write(
        "phases.json",
        &PHASES.replace(
            "\"contact\": \"r.sole\" } ], \"duration\": 0.3",
            "\"contact\": \"r.sole\" }, { \"contact\": \"r.sole\" } ], \"duration\": 0.3",
        ),
    );
    let seq = PhaseSequence::load(&p).unwrap();
    let err = seq.resolve(&reference_model(), &p).unwrap_err();
    let msg = assert_invalid(
        err,
        &p,
        "phases[0] ('stance').contacts[1].contact",
        &["phase 'stance'", "twice"],
    );
    eprintln!("{msg}");
}

#[test]
fn initial_state_of_wrong_size_is_refused() {
    let d = Scratch::new();
    let p = d.write(
        "phases.json",
        &PHASES.replace("\"name\": \"p\",", "\"name\": \"p\", \"initial_state\": { \"q\": [0,1,0,0,0,0,0,0], \"qd\": [0,0,0,0,0,0,0,0,0] },"),
    );
    let seq = PhaseSequence::load(&p).unwrap();
    let msg = assert_invalid(
        seq.resolve(&reference_model(), &p).unwrap_err(),
        &p,
        "initial_state.q",
        &["8 values", "9", "pelvis_x"],
    );
    eprintln!("{msg}");
}

#[test]
fn absurd_initial_state_is_refused_with_short_numbers() {
    // found by tests/fuzz.rs: these loaded, and the dynamics then returned NaN
    let d = Scratch::new();
    for (q, qd, field, words) in [
        (
            "[0,1e308,0,0,0,0,0,0,0]",
            "[0,0,0,0,0,0,0,0,0]",
            "initial_state.q[1]",
            ["1e308", "at most 100 m or rad"],
        ),
        (
            "[0,1,0,0,0,0,0,0,0]",
            "[0,0,0,-1e308,0,0,0,0,0]",
            "initial_state.qd[3]",
            ["-1e308", "at most 1000 m/s or rad/s"],
        ),
    ] {
        let p = d.write(
            "phases.json",
            &PHASES.replace(
                "\"name\": \"p\",",
                &format!("\"name\": \"p\", \"initial_state\": {{ \"q\": {q}, \"qd\": {qd} }},"),
            ),
        );
        let seq = PhaseSequence::load(&p).unwrap();
        let msg = assert_invalid(
            seq.resolve(&reference_model(), &p).unwrap_err(),
            &p,
            field,
            &words,
        );
        assert!(msg.len() < 300, "{msg}");
    }
}

#[test]
fn absurd_contact_and_damping_values_are_refused() {
    let d = Scratch::new();
    for (extra, field, words) in [
        (
            r#", "contact": { "ground_height": 1e308 }"#,
            "contact.ground_height",
            ["1e308 m", "±10 m"],
        ),
        (
            r#", "contact": { "baumgarte_beta": 1e308 }"#,
            "contact.baumgarte_beta",
            ["1e308", "[0, 10000] 1/s"],
        ),
    ] {
        let m = d.write("model.json", &explicit_model(GOOD_THIGH, extra));
        assert_invalid(ModelSpec::load(&m).unwrap_err(), &m, field, &words);
    }
    let m = d.write(
        "mtg.json",
        r#"{ "name": "x", "body": { "preset": "de_leva", "mass": 80.0, "height": 1.8, "sex": "male" },
             "actuators": { "type": "muscle_torque_generators", "eta": 1e308 } }"#,
    );
    assert_invalid(
        ModelSpec::load(&m).unwrap_err(),
        &m,
        "actuators.eta",
        &["1e308", "[0, 1000]"],
    );
}

// ---------------------------------------------------------------------------------------
// Control tables

fn names() -> Vec<String> {
    vec!["hip_r".into(), "knee_r".into()]
}

#[test]
fn control_csv_with_missing_column_is_refused() {
    let p = Path::new("controls.csv");
    let err = ControlTable::parse_csv("time,hip_r\n0,1\n", p, &names()).unwrap_err();
    let msg = assert_invalid(
        err,
        p,
        "header",
        &["missing control column `knee_r`", "hip_r, knee_r"],
    );
    eprintln!("{msg}");
    // the real model's names, read from a file
    let d = Scratch::new();
    let f = d.write("controls.csv", "time,hip_r_flexor_excitation\n0,0.1\n");
    let err = ControlTable::load_csv(&f, &reference_model().control_names()).unwrap_err();
    assert_invalid(
        err,
        &f,
        "header",
        &["missing control column `hip_r_extensor_excitation`"],
    );
}

#[test]
fn control_csv_with_unknown_column_or_wrong_first_column_is_refused() {
    let p = Path::new("controls.csv");
    let err =
        ControlTable::parse_csv("time,hip_r,knee_r,elbow\n0,1,2,3\n", p, &names()).unwrap_err();
    assert_invalid(err, p, "header", &["unknown column `elbow`"]);
    let err = ControlTable::parse_csv("t,hip_r,knee_r\n0,1,2\n", p, &names()).unwrap_err();
    assert_invalid(err, p, "header", &["first column must be `time`"]);
    let err = ControlTable::parse_csv("\n# nothing\n", p, &names()).unwrap_err();
    assert_invalid(err, p, "header", &["empty"]);
    let err = ControlTable::parse_csv("time,hip_r,knee_r\n", p, &names()).unwrap_err();
    assert_invalid(err, p, "rows", &["no data rows"]);
}

#[test]
fn non_monotonic_control_time_names_the_line() {
    let p = Path::new("controls.csv");
    let err = ControlTable::parse_csv("time,hip_r,knee_r\n0,1,2\n0.2,1,2\n0.1,1,2\n", p, &names())
        .unwrap_err();
    let msg = assert_invalid(
        err,
        p,
        "row at line 4, column `time`",
        &["does not increase", "previous 0.2"],
    );
    eprintln!("{msg}");
}

#[test]
fn non_number_control_cell_names_line_and_column() {
    let p = Path::new("controls.csv");
    let err =
        ControlTable::parse_csv("time,hip_r,knee_r\n0,1,2\n0.1,1,abc\n", p, &names()).unwrap_err();
    let msg = assert_invalid(
        err,
        p,
        "row at line 3, column `knee_r`",
        &["`abc` is not a number"],
    );
    eprintln!("{msg}");
    let err = ControlTable::parse_csv("time,hip_r,knee_r\n0,inf,2\n", p, &names()).unwrap_err();
    assert_invalid(err, p, "row at line 2, column `hip_r`", &["finite"]);
    let err = ControlTable::parse_csv("time,hip_r,knee_r\n0,,2\n", p, &names()).unwrap_err();
    assert_invalid(err, p, "row at line 2, column `hip_r`", &["empty"]);
    let err = ControlTable::parse_csv("time,hip_r,knee_r\n0,1\n", p, &names()).unwrap_err();
    assert_invalid(err, p, "line 2", &["2 values", "header has 3"]);
}

#[test]
fn hand_built_control_table_does_not_panic() {
    let t = ControlTable {
        names: names(),
        times: vec![],
        values: vec![],
    };
    assert!(t.validate().is_err());
    let mut out = [7.0, 7.0];
    t.at(0.5, &mut out);
    assert_eq!(out, [7.0, 7.0]);
    let t = ControlTable::constant(names(), vec![1.0]);
    assert!(t
        .validate()
        .unwrap_err()
        .to_string()
        .contains("1 values for 2 controls"));
    t.at(0.5, &mut out);
}

// ---------------------------------------------------------------------------------------
// Integrator

fn simulation_inputs() -> (
    GaitModel,
    PhaseSequence,
    Vec<footfall::model::ConstraintSet>,
    Vec<f64>,
    ControlTable,
) {
    let model = reference_model();
    let p = root().join("phases/sim_ellipse_step.json");
    let seq = PhaseSequence::load(&p).unwrap();
    let sets = seq.resolve(&model, &p).unwrap();
    let init = seq.initial_state.clone().unwrap();
    let mut x0 = init.q.clone();
    x0.extend(&init.qd);
    x0.extend(vec![0.01; model.na()]);
    let controls = ControlTable::constant(model.control_names(), vec![0.025; model.nu()]);
    (model, seq, sets, x0, controls)
}

#[test]
fn integrator_failure_names_phase_and_time() {
    let (model, seq, sets, x0, controls) = simulation_inputs();
    let settings = SimulationSettings {
        output_step: 0.1,
        integrator: IntegratorSettings {
            max_steps: 5,
            ..Default::default()
        },
    };
    let err = simulate(
        &model,
        &seq,
        &sets,
        &x0,
        &controls,
        &model.theta0(),
        &settings,
    )
    .unwrap_err();
    let msg = format!(
        "{err} / {}",
        std::error::Error::source(&err)
            .map(|s| s.to_string())
            .unwrap_or_default()
    );
    match &err {
        SimulationError::Integrator {
            phase,
            source: IntegratorError::Failed { t, flag_name, .. },
        } => {
            assert_eq!(phase, "single_stance_r");
            assert_eq!(flag_name, "CV_TOO_MUCH_WORK");
            assert!(*t >= 0.0 && *t < 0.1, "{msg}");
        }
        other => panic!("expected an integrator failure, got {other:?}"),
    }
    assert!(
        msg.contains("phase 'single_stance_r'") && msg.contains("t = "),
        "{msg}"
    );
    eprintln!("{msg}");
}

#[test]
fn bad_integrator_settings_are_refused() {
    let (model, seq, sets, x0, controls) = simulation_inputs();
    let settings = SimulationSettings {
        output_step: 1e-3,
        integrator: IntegratorSettings {
            rtol: 0.0,
            ..Default::default()
        },
    };
    let err = simulate(
        &model,
        &seq,
        &sets,
        &x0,
        &controls,
        &model.theta0(),
        &settings,
    )
    .unwrap_err();
    match &err {
        SimulationError::Integrator {
            source: IntegratorError::BadSettings { field, .. },
            ..
        } => assert_eq!(*field, "rtol"),
        other => panic!("expected BadSettings, got {other:?}"),
    }
    eprintln!("{err}: {}", std::error::Error::source(&err).unwrap());
    let bad = IntegratorSettings {
        max_steps: 0,
        ..Default::default()
    };
    assert!(matches!(
        bad.validate(),
        Err(IntegratorError::BadSettings {
            field: "max_steps",
            ..
        })
    ));
}

#[test]
fn wrong_initial_state_size_or_output_step_is_refused() {
    let (model, seq, sets, x0, controls) = simulation_inputs();
    let theta = model.theta0();
    let err = simulate(
        &model,
        &seq,
        &sets,
        &x0[..10],
        &controls,
        &theta,
        &SimulationSettings::default(),
    )
    .unwrap_err();
    assert!(
        matches!(&err, SimulationError::Input(m) if m.contains("10 values")),
        "{err:?}"
    );
    let settings = SimulationSettings {
        output_step: -1.0,
        ..Default::default()
    };
    let err = simulate(&model, &seq, &sets, &x0, &controls, &theta, &settings).unwrap_err();
    assert!(
        matches!(&err, SimulationError::Input(m) if m.contains("output step")),
        "{err:?}"
    );
}

// ---------------------------------------------------------------------------------------
// Robustness

/// Every one-character deletion, and every replacement of a character by a quote or a
/// letter, in the bundled model, foot and phase files gives a result or a typed error
/// naming the file, never a panic.
#[test]
fn mutated_files_never_panic() {
    use footfall::model::spec::parse_json;
    let files = [
        "models/gait9dof.json",
        "models/opensim_subject01.json",
        "models/feet/ellipse.json",
        "models/feet/double_circle.json",
        "phases/sim_ellipse_step.json",
    ];
    let mut errors = 0;
    for f in files {
        let p = root().join(f);
        let text = std::fs::read_to_string(&p).unwrap();
        let chars: Vec<(usize, char)> = text.char_indices().collect();
        for &(i, c) in &chars {
            let next = i + c.len_utf8();
            for repl in ["", "\"", "x", "-", "}"] {
                let bad = format!("{}{repl}{}", &text[..i], &text[next..]);
                let msg = if f.starts_with("models/feet") {
                    parse_json::<FootSpec>(&bad, &p)
                        .and_then(|s| s.validate(&p).map(|_| ()))
                        .err()
                } else if f.starts_with("models") {
                    parse_json::<ModelSpec>(&bad, &p)
                        .and_then(|s| s.validate(&p).map(|_| ()))
                        .err()
                } else {
                    parse_json::<PhaseSequence>(&bad, &p)
                        .and_then(|s| s.validate(&p).map(|_| ()))
                        .err()
                };
                if let Some(e) = msg {
                    errors += 1;
                    let m = e.to_string();
                    assert!(m.contains(&p.display().to_string()), "{m}");
                    if let ModelError::Json { line, column, .. } = e {
                        // (serde_json reports column 0 right after a newline)
                        assert!(
                            line >= 1 && line <= bad.lines().count() + 1,
                            "{m} ({column})"
                        );
                    }
                }
            }
        }
    }
    assert!(errors > 1000, "only {errors} mutations were refused");
}

#[test]
fn an_excitation_outside_zero_to_one_is_refused_naming_line_and_column() {
    let s = Scratch::new();
    let names: Vec<String> = vec!["hip_r_flexor_excitation".into(), "hip_r_residual".into()];
    let ranges = [Some((0.0, 1.0, "an excitation")), None];
    let ok = s.write(
        "ok.csv",
        "time,hip_r_flexor_excitation,hip_r_residual\n0,0.2,-3\n0.1,1,5\n",
    );
    ControlTable::load_csv_within(&ok, &names, &ranges).unwrap();
    let bad = s.write(
        "bad.csv",
        "time,hip_r_flexor_excitation,hip_r_residual\n0,0.2,-3\n0.1,1.3,5\n",
    );
    let e = ControlTable::load_csv_within(&bad, &names, &ranges).unwrap_err();
    assert_invalid(
        e,
        &bad,
        "row at line 3, column `hip_r_flexor_excitation`",
        &["1.3 is outside [0, 1]", "an excitation"],
    );
}
