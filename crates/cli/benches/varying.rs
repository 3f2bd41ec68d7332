//! Criterion benchmarks of `estimate varying` (issue 38), from a recording in
//! memory to the estimate: an ensemble of 200 repetitions x 2 s at 1 kHz
//! (one joint), and 180 s of parameter-varying ankle data at 1 kHz with the
//! reflex scan, and walking (issue 61): 400 strides at 1 kHz with pulses on
//! a third of them, and with a perturbation on every stride. The recordings
//! come from limpid's virtual lab.

use criterion::{criterion_group, criterion_main, Criterion};
use limpid_ident::varying::{estimate_varying, VaryingParams, VaryingRequest};
use limpid_lab::varying::{
    simulate_ensemble, simulate_scheduled_ankle, simulate_walking, EnsembleExperiment,
    EnsembleSubject, RampAndHold, ScheduledAnkle, WalkingAnkle, WalkingExperiment,
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
    let walking = VaryingRequest {
        event: Some("heel_strike".into()),
        ..VaryingRequest::default()
    }
    .check()
    .expect("valid settings");
    for (name, perturbation) in [
        (
            "walking_pulses_400_strides_1kHz",
            WalkingExperiment::pulses(),
        ),
        (
            "walking_ensemble_400_strides_1kHz",
            WalkingExperiment::continuous(),
        ),
    ] {
        let walk = simulate_walking(
            &WalkingAnkle::default(),
            &WalkingExperiment {
                strides: 400,
                rate_hz: 1000.0,
                perturbation,
                ..WalkingExperiment::default()
            },
            1,
        )
        .expect("walk");
        group.bench_function(name, |b| {
            b.iter(|| estimate_varying(&walk, &walking).expect("estimate"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
