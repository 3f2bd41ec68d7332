//! Criterion benchmark of a full observation-window sweep (issue 5): 36
//! windows (50-400 ms) x 30 trials of the virtual planar arm at 1 kHz.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use limpid_ident::planar::{prepare_planar, window_sweep, Arm, PlanarPrepare};
use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject};

fn bench(c: &mut Criterion) {
    let rec = simulate_planar(
        &PlanarSubject::seed003(),
        &PlanarProtocol::seed003(),
        0.02,
        1e-5,
        1,
    )
    .expect("simulation");
    let arm = Arm {
        l1: 0.28,
        l2: 0.35,
        shoulder: [0.0, 0.0],
    };
    let data = prepare_planar(
        &rec,
        &PlanarPrepare {
            arm,
            cutoff_hz: None,
            order: 4,
            elbow_positive: true,
        },
    )
    .expect("prepare");
    let mut group = c.benchmark_group("window_sweep");
    group.sample_size(10);
    group.bench_with_input(
        BenchmarkId::new("sweep", "36windows_x_30trials"),
        &data,
        |b, d| b.iter(|| window_sweep(d, 50.0, 400.0, 10.0, None).expect("sweep")),
    );
    group.bench_with_input(BenchmarkId::new("prepare", "30trials"), &rec, |b, r| {
        b.iter(|| {
            prepare_planar(
                r,
                &PlanarPrepare {
                    arm,
                    cutoff_hz: None,
                    order: 4,
                    elbow_positive: true,
                },
            )
            .expect("prepare")
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
