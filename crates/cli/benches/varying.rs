//! Criterion benchmarks of `estimate varying` (issue 38), from a recording in
//! memory to the estimate: an ensemble of 200 repetitions x 2 s at 1 kHz
//! (one joint), and 180 s of parameter-varying ankle data at 1 kHz with the
//! reflex scan. Both recordings come from limpid's virtual lab.

use criterion::{criterion_group, criterion_main, Criterion};
use limpid_ident::varying::{estimate_varying, VaryingParams, VaryingRequest};
use limpid_lab::varying::{
    simulate_ensemble, simulate_scheduled_ankle, EnsembleExperiment, EnsembleSubject, RampAndHold,
    ScheduledAnkle,
};

fn bench(c: &mut Criterion) {
    let mut subject = EnsembleSubject::joint();
    subject.change.centre_s = 1.0;
    let ensemble = simulate_ensemble(
        &subject,
        &EnsembleExperiment {
            repetitions: 200,
            duration_s: 2.0,
            ..EnsembleExperiment::default()
        },
        1,
    )
    .expect("ensemble");
    let ankle = simulate_scheduled_ankle(
        &ScheduledAnkle::default(),
        &RampAndHold {
            hold_s: 14.0,
            ..RampAndHold::default()
        },
        1,
    )
    .expect("ankle");
    assert!(ankle.len() >= 179_000, "{} samples", ankle.len());
    let mut group = c.benchmark_group("varying");
    group.sample_size(10);
    group.bench_function("ensemble_200x2s_1kHz", |b| {
        b.iter(|| estimate_varying(&ensemble, &VaryingParams::default()).expect("estimate"))
    });
    let pv = VaryingRequest {
        schedule: "sv".into(),
        reflex: true,
        ..VaryingRequest::default()
    }
    .check()
    .expect("valid settings");
    group.bench_function("parameter_varying_reflex_180s_1kHz", |b| {
        b.iter(|| estimate_varying(&ankle, &pv).expect("estimate"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
