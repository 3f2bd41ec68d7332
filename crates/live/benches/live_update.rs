//! Per-sample cost of the live update: six EMG envelopes, the index, level
//! tracking and the online impedance step (target: under 1 µs per sample).

use criterion::{criterion_group, criterion_main, Criterion};
use limpid_live::process::Processor;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut p = Processor::new(6, 1000.0, Some(vec![1e-3; 6])).unwrap();
    let mut k = 0u64;
    c.bench_function("live update: 6 EMG + index + online impedance", |b| {
        b.iter(|| {
            k += 1;
            let t = k as f64 * 1e-3;
            let emg = [t.sin() * 1e-4, t.cos() * 1e-4, 2e-5, -3e-5, 1e-5, 4e-5];
            let kin = [
                0.3 + 1e-3 * (3.0 * t).sin(),
                -0.2,
                0.05,
                1.0 + (3.0 * t).sin(),
                0.5,
                0.1,
            ];
            p.update(black_box(&emg), Some(black_box(&kin)));
            black_box(p.index)
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
