//! Helpers of the study tests (quick's `study` and suite's `study_runs`).

use super::root;
use std::path::{Path, PathBuf};

/// `text` written to `dir/name`; its path.
pub fn file(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const S4: &str = "models/opencap_s4.json";
const S01: &str = "models/opensim_subject01.json";

/// The study's trials: two recordings of one subject untouched (session lab-a), the same
/// two with the right plate's clock made 20 ms late (session lab-b: every trial of the
/// session carries the edit; its subject is named apart, the body being the same two
/// recordings'), a second subject untouched and with its left plate 20 ms early (a
/// session each), and a trial whose file is damaged.
pub fn study_manifest(dir: &Path) -> PathBuf {
    let r = root();
    let trial = |p: &str| r.join(p).display().to_string();
    let damaged = file(dir, "damaged.csv", "time,pelvis_tx\n0,nan,3\n");
    let rows = [
        (
            "w1",
            "s4",
            "lab-a",
            "untouched",
            trial("data/opencap_s4_walking1_sagittal.csv"),
            S4,
        ),
        (
            "w2",
            "s4",
            "lab-a",
            "untouched",
            trial("data/opencap_s4_walking2_sagittal.csv"),
            S4,
        ),
        (
            "w1-clock",
            "s4-edited",
            "lab-b",
            "clock_r+20ms",
            trial("tests/data/check/trials/opencap_s4_walking1/clock_r+20ms/trial.csv"),
            S4,
        ),
        (
            "w2-clock",
            "s4-edited",
            "lab-b",
            "clock_r+20ms",
            trial("tests/data/check/trials/opencap_s4_walking2/clock_r+20ms/trial.csv"),
            S4,
        ),
        (
            "s01",
            "subject01",
            "lab-c",
            "untouched",
            trial("tests/data/check/opensim_subject01_600hz.csv"),
            S01,
        ),
        (
            "s01-clock",
            "subject01-edited",
            "lab-d",
            "clock_l-20ms",
            trial("tests/data/check/trials/opensim_subject01/clock_l-20ms/trial.csv"),
            S01,
        ),
        (
            "damaged",
            "subject01",
            "lab-c",
            "damaged",
            damaged.display().to_string(),
            S01,
        ),
    ];
    let mut text = String::from("id,subject,session,condition,data,model\n");
    for (id, subject, session, condition, data, model) in rows {
        text.push_str(&format!(
            "{id},{subject},{session},{condition},{data},{}\n",
            r.join(model).display()
        ));
    }
    file(dir, "study.csv", &text)
}

/// Every file under `dir`, relative, with its bytes.
pub fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            if e.file_type().unwrap().is_dir() {
                stack.push(e.path());
            } else {
                out.push((
                    e.path().strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(e.path()).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
}

/// The trials' folders, which must not differ between two runs of one study.
pub fn trial_files(out: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    files(&out.join("trials"))
}
