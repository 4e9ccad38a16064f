//! Criterion benchmarks of whole tracks, as `footfall track` runs them with its defaults
//! (check points, the run folder written): the bundled trial and every shared recording,
//! with each bundled foot, started from the data and from the trial's inverse dynamics
//! (`--guess inverse-dynamics`). Before its measurement each track prints its stop,
//! iterations and time split (integration and sensitivities, QP, the rest: the run
//! folder, the fine-grid re-integration, the problem's set-up).
//!
//! A track takes tens of seconds, and criterion takes at least ten samples: pick one with
//! a filter, e.g. `cargo bench --bench track -- bundled/ellipse/data`.

use criterion::{criterion_group, criterion_main, Criterion};
use footfall::problems::track::start::Guess;
use footfall::runfolder::RunFolder;
use footfall::workflows::track::{track, TrackRequest};
use footfall::workflows::Quiet;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The tracks: (name, data file (None: the bundled trial), model file).
const TRACKS: [(&str, Option<&str>, &str); 4] = [
    ("bundled", None, "models/opensim_subject01.json"),
    (
        "opencap_s4_walking1",
        Some("data/opencap_s4_walking1_sagittal.csv"),
        "models/opencap_s4.json",
    ),
    (
        "opencap_s4_walking2",
        Some("data/opencap_s4_walking2_sagittal.csv"),
        "models/opencap_s4.json",
    ),
    (
        "pig_c3dorg_D123",
        Some("data/pig_c3dorg_D123_sagittal.csv"),
        "models/pig_c3dorg_D123.json",
    ),
];

/// One track into a fresh folder under `dir`; its stop and time split if `report`.
fn run(req: &TrackRequest, dir: &Path, report: bool) {
    let out = dir.join("run");
    let folder = RunFolder::create(&out, true).expect("run folder");
    let start = Instant::now();
    let run = track(req, folder, &Quiet).expect("track");
    let wall = start.elapsed().as_secs_f64();
    if report {
        let r = &run.result;
        let (integration, qp) = (r.timings.evaluation_s, r.timings.qp_s);
        eprintln!(
            "{}: {} after {} iterations, J = {:.9}, KKT {:.2e}; {wall:.1} s: integration {integration:.1} s, QP {qp:.1} s, other {:.1} s",
            out.display(),
            r.status,
            r.history.len().saturating_sub(1),
            r.objective,
            r.kkt,
            wall - integration - qp
        );
    }
}

fn tracks(c: &mut Criterion) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    std::env::set_current_dir(&root).expect("repository root");
    for (name, data, model) in TRACKS {
        let mut g = c.benchmark_group(name);
        g.sample_size(10).measurement_time(Duration::from_secs(60));
        for foot in ["ellipse", "double-circle"] {
            for (start, guess) in [
                ("data", Guess::Data),
                ("inverse_dynamics", Guess::InverseDynamics),
            ] {
                let mut req = TrackRequest::new(foot);
                req.run.data = data.map(PathBuf::from);
                req.run.model = PathBuf::from(model);
                req.run.guess = guess;
                let dir = tempfile::tempdir().expect("temporary folder");
                // criterion calls the routine again for each round of samples: the
                // first run of the case reports
                let reported = std::cell::Cell::new(false);
                g.bench_function(format!("{foot}/{start}"), |b| {
                    b.iter(|| run(&req, dir.path(), !reported.replace(true)))
                });
            }
        }
        g.finish();
    }
}

criterion_group!(benches, tracks);
criterion_main!(benches);
