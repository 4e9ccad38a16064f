//! Criterion benchmark of the measurement check: `footfall check`'s reading of the bundled
//! trial with its forces at the plates' own 600 Hz (the whole trial and each half cycle on
//! its own, as the command reads them), without writing the run folder.

use criterion::{criterion_group, criterion_main, Criterion};
use footfall::problems::check::CheckSettings;
use footfall::workflows::check::{read, CheckRequest};
use footfall::workflows::trial::TrialFiles;
use std::path::PathBuf;

fn bench(c: &mut Criterion) {
    let req = CheckRequest {
        trial: TrialFiles {
            data: Some(PathBuf::from(
                "tests/data/check/opensim_subject01_600hz.csv",
            )),
            ..TrialFiles::default()
        },
        model: PathBuf::from("models/opensim_subject01.json"),
        out: None,
        overwrite: false,
        settings: CheckSettings::default(),
    };
    c.bench_function("check the bundled trial at 600 Hz", |b| {
        b.iter(|| read(&req).expect("check"))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
