//! Criterion benchmark of the parallel-cascade reflex estimator (issue 17):
//! one 60 s, 1 kHz real ankle recording (../shared/real/reklab_ankle/pf.csv),
//! from the loaded recording to the estimate (decimation, alternating IRFs,
//! cross-validation, joint parametric delay scan, jackknife).

use criterion::{criterion_group, criterion_main, Criterion};
use limpid_ident::reflex::{estimate_reflex, ReflexParams};

fn bench(c: &mut Criterion) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/real/reklab_ankle/pf.csv");
    let rec = limpid_io::read_recording(&path).expect("real recording");
    let mut group = c.benchmark_group("reflex");
    group.sample_size(20);
    group.bench_function("parallel_cascade_60s_1kHz", |b| {
        b.iter(|| estimate_reflex(&rec, &ReflexParams::default()).expect("estimate"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
