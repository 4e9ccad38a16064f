//! Criterion benchmark of the default diagnosis of the bundled trial's ellipse track, every
//! step run: the measurement stage, the model stage (the default candidates, of which the
//! MTG damping is found there), the model's own trial made and tracked (the model null),
//! the held-out half cycle tracked, and one verifying re-fit. The track itself is made
//! once, outside the measurement.

use criterion::{criterion_group, criterion_main, Criterion};
use footfall::runfolder::RunFolder;
use footfall::workflows::diagnose::{run, DiagnoseRequest};
use footfall::workflows::track::{track, TrackRequest};
use footfall::workflows::Quiet;

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("a scratch folder");
    let tracked = dir.path().join("track");
    let req = TrackRequest::new("ellipse");
    let result = track(
        &req,
        RunFolder::create(&tracked, false).expect("run folder"),
        &Quiet,
    )
    .expect("the bundled track");
    assert!(result.converged);
    let diagnosis = DiagnoseRequest {
        verify: 1,
        overwrite: true,
        ..DiagnoseRequest::new(tracked)
    };
    c.bench_function(
        "diagnose the bundled track by default: both stages, model null, held-out half cycle, one re-fit",
        |b| b.iter(|| run(&diagnosis, &Quiet).expect("diagnose")),
    );
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
