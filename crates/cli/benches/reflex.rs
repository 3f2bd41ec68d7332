//! Criterion benchmark of the parallel-cascade reflex estimator (issue 17):
//! one 60 s, 1 kHz ankle recording: the real `pf.csv` of Kearney's laboratory
//! under `$LIMPID_REAL_DATA/reklab_ankle` when set, else limpid's virtual ankle,
//! from the loaded recording to the estimate (decimation, alternating IRFs,
//! cross-validation, joint parametric delay scan, jackknife); and 40
//! segments of 1 s of the virtual ankle (issue 80: each segment with its own
//! start, the reflex in flight at each cut fitted in every scan step); and
//! 120 s of the virtual ankle with a reflex on a servo of 1.5 x its K with
//! its reference recorded (issue 79: the reference's FIR projection and the
//! instrumental-variable scan; the issue asks under 1 s).

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
    let ankle = limpid_lab::ankle::AnkleSubject::default();
    let session = limpid_lab::ankle::AnkleExperiment {
        duration_s: 100.0,
        ..Default::default()
    };
    let long = limpid_lab::ankle::simulate_ankle(&ankle, &session, 1).expect("ankle");
    let cut = limpid_lab::ankle::cut_into_segments(&long, (1.0, 1.0), 1).expect("segments");
    let cut = limpid_lab::ankle::first_segments(&cut, 40).expect("forty segments");
    group.bench_function("segments_40x1s_1kHz", |b| {
        b.iter(|| estimate_reflex(&cut, &ReflexParams::default()).expect("estimate"))
    });
    let servo = limpid_lab::ankle::Servo::relative_to(&ankle, 1.5);
    let closed = limpid_lab::ankle::simulate_ankle_servo(
        &ankle,
        &limpid_lab::ankle::AnkleExperiment {
            duration_s: 120.0,
            amplitude_rad: 0.04,
            ..Default::default()
        },
        &servo,
        1,
    )
    .expect("servo ankle");
    group.bench_function("closed_loop_120s_1kHz", |b| {
        b.iter(|| estimate_reflex(&closed, &ReflexParams::default()).expect("estimate"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
