//! Criterion benchmark of zero-phase Butterworth filtering (issue 16):
//! limpid's in-place second-order-section cascade on 1e6 samples, orders 2
//! and 8, beside sci-rs's `sosfiltfilt_dyn` it replaced.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use limpid_dsp::LowPass;
use sci_rs::signal::filter::design::{butter_dyn, DigitalFilter, FilterBandType, FilterOutputType};

fn bench(c: &mut Criterion) {
    let n = 1_000_000;
    let x: Vec<f64> = (0..n)
        .map(|i| ((i as f64) * 0.013).sin() + ((i * 7919 % 1000) as f64) * 1e-3)
        .collect();
    let mut group = c.benchmark_group("filtfilt_1e6");
    group.sample_size(20);
    for order in [2usize, 8] {
        let lp = LowPass::butterworth(order, 30.0, 1000.0).unwrap();
        group.bench_with_input(BenchmarkId::new("limpid", order), &x, |b, x| {
            b.iter(|| lp.filtfilt(x).unwrap())
        });
        let DigitalFilter::Sos(sos) = butter_dyn(
            order,
            vec![30.0],
            Some(FilterBandType::Lowpass),
            Some(false),
            Some(FilterOutputType::Sos),
            Some(1000.0),
        ) else {
            unreachable!("a Butterworth low-pass has sections")
        };
        group.bench_with_input(BenchmarkId::new("sci-rs", order), &x, |b, x| {
            b.iter(|| sci_rs::signal::filter::sosfiltfilt_dyn(x.iter(), &sos.sos))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
