//! Criterion benchmark of the parallel-cascade reflex estimator (issue 17):
//! one 60 s, 1 kHz ankle recording: the real `pf.csv` of Kearney's laboratory
//! under `$LIMPID_REAL_DATA/reklab_ankle` when set, else limpid's virtual ankle,
//! from the loaded recording to the estimate (decimation, alternating IRFs,
//! cross-validation, joint parametric delay scan, jackknife).

use criterion::{criterion_group, criterion_main, Criterion};
use limpid_ident::reflex::{estimate_reflex, ReflexParams};

fn bench(c: &mut Criterion) {
    let path = limpid_testkit::real_data("reklab_ankle")
        .map(|dir| dir.join("pf.csv"))
        .unwrap_or_else(|| limpid_testkit::examples("ankle").join("ex_ankle.csv"));
    let rec = limpid_io::read_recording(&path).expect("ankle recording");
    let mut group = c.benchmark_group("reflex");
    group.sample_size(20);
    group.bench_function("parallel_cascade_60s_1kHz", |b| {
        b.iter(|| estimate_reflex(&rec, &ReflexParams::default()).expect("estimate"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
