//! Damaged C3D files: the shipped C3D file with random bytes flipped is read without a
//! panic reaching the caller, and every refusal names the file and speaks of the format's
//! sections and parameters, never of the C3D crate's internal error names; on the command
//! line a panic inside the crate prints nothing but footfall's own error.

use crate::common::{root, Rng};
use footfall::data::c3d::read_c3d_plates;
use std::path::{Path, PathBuf};

/// Damaged copies of the shipped C3D file: `FOOTFALL_FUZZ_CASES` (as the fuzz targets,
/// tests/fuzz.rs), else 400.
fn variants() -> usize {
    std::env::var("FOOTFALL_FUZZ_CASES")
        .map(|v| {
            v.parse()
                .unwrap_or_else(|_| panic!("FOOTFALL_FUZZ_CASES={v:?} is not a count"))
        })
        .unwrap_or(400)
}

/// The C3D crate's error names (its `C3dParseError` variants), which a message must not show.
const CRATE_NAMES: &[&str] = &[
    "C3dParseError",
    "InsufficientBlocks",
    "InvalidHeaderStartBlock",
    "InvalidParameterStartBlock",
    "InvalidParameterData",
    "InvalidDataStartBlock",
    "InvalidProcessorType",
    "InvalidDataType",
    "InvalidParametersOffset",
    "InvalidDescription",
    "InvalidGroupId",
    "MissingPointScale",
    "NotEnoughData",
    "InvalidNextParameter",
    "TooManyEvents",
    "NumFramesMismatch",
    "InvalidParameterFormat",
    "AnalogOffsetScaleMismatch",
    "InsufficientAnalogOffsets",
    "InvalidParameterDimensions",
    "InvalidParameterType",
    "AnalogBytesPerFrameMismatch",
    "FrameRateMismatch",
    "ScaleFactorMismatch",
    "HeaderNotParsed",
];

fn shipped() -> Vec<u8> {
    std::fs::read(root().join("tests/data/c3d/plate_type2.c3d")).unwrap()
}

/// Copy `k` of the file with 1–8 bytes replaced by random ones (seeded by `k`).
fn damaged(original: &[u8], k: usize) -> Vec<u8> {
    let mut rng = Rng::new(1000 + k as u64);
    let mut bytes = original.to_vec();
    let flips = 1 + (rng.uniform(0.0, 8.0) as usize);
    for _ in 0..flips {
        let at = rng.uniform(0.0, bytes.len() as f64) as usize;
        bytes[at] = rng.uniform(0.0, 256.0) as u8;
    }
    bytes
}

/// What is wrong with a refusal's message, if anything.
fn message_problem(path: &Path, message: &str) -> Option<String> {
    let name = path.file_name().unwrap().to_string_lossy();
    if !message.contains(name.as_ref()) {
        return Some(format!("does not name the file: {message}"));
    }
    CRATE_NAMES
        .iter()
        .find(|n| message.contains(*n))
        .map(|n| format!("shows the crate's error name {n}: {message}"))
}

#[test]
fn flipped_bytes_are_refused_in_the_formats_terms_without_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let original = shipped();
    let (mut refused, mut problems) = (0, Vec::new());
    let variants = variants();
    for k in 0..variants {
        let path = dir.path().join(format!("damaged_{k}.c3d"));
        std::fs::write(&path, damaged(&original, k)).unwrap();
        let read = std::panic::catch_unwind(|| read_c3d_plates(&path, 20.0));
        match read {
            Err(_) => problems.push(format!("variant {k}: panicked")),
            Ok(Ok(_)) => {}
            Ok(Err(e)) => {
                refused += 1;
                if let Some(p) = message_problem(&path, &e.to_string()) {
                    problems.push(format!("variant {k}: {p}"));
                }
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(
        refused >= variants / 10,
        "only {refused} of {variants} damaged files refused"
    );
    eprintln!("{variants} damaged C3D files: {refused} refused, the rest read");
}

/// The first damaged copy whose parse panics inside the crate (caught by the reader).
fn one_that_panics_in_the_crate(dir: &Path) -> Option<PathBuf> {
    let original = shipped();
    (0..variants()).find_map(|k| {
        let bytes = damaged(&original, k);
        let parsed = std::panic::catch_unwind(|| c3dio::C3d::from_bytes(&bytes));
        parsed.is_err().then(|| {
            let path = dir.join(format!("panics_{k}.c3d"));
            std::fs::write(&path, &bytes).unwrap();
            path
        })
    })
}

#[test]
fn a_panic_inside_the_c3d_crate_prints_only_footfalls_error() {
    let dir = tempfile::tempdir().unwrap();
    let Some(c3d) = one_that_panics_in_the_crate(dir.path()) else {
        panic!(
            "none of the {} damaged copies makes the crate panic: the test sees nothing",
            variants()
        );
    };
    let ik = root().join("data/raw/opensim_subject01/subject01_walk1_ik.mot");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_footfall"))
        .args([
            "track",
            "--overground",
            "--plate",
            "r=1",
            "--plate",
            "l=2",
            "--data",
        ])
        .arg(&ik)
        .arg("--forces")
        .arg(&c3d)
        .arg("--out")
        .arg(dir.path().join("run"))
        .env("RUST_BACKTRACE", "1")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        !stderr.contains("panicked") && !stderr.contains("backtrace"),
        "the crate's panic text is printed:\n{stderr}"
    );
    assert!(message_problem(&c3d, &stderr).is_none(), "{stderr}");
}
