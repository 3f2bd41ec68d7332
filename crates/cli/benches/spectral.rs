//! Criterion benchmark of the stochastic method (issue 6): Welch spectral
//! matrix of 9 channels x 50 s at 1 kHz and the impedance Z = T R^-1 with its
//! parametric fit, on the ex_sa3 spring-array example limpid's lab makes.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use limpid_dsp::spectral::SegmentSpectra;
use limpid_ident::stochastic::{default_welch, estimate_stochastic, StochasticParams};

fn bench(c: &mut Criterion) {
    let path = limpid_testkit::examples("stochastic").join("ex_sa3.csv");
    let rec = limpid_io::read_recording(&path).expect("example recording");
    let names = ["ux", "uz", "utheta", "x", "z", "theta", "fx", "fz", "tauy"];
    let signals: Vec<&[f64]> = names
        .iter()
        .map(|n| rec.column(n).expect("column"))
        .collect();
    let welch = default_welch(rec.len(), rec.sample_rate());
    let mut group = c.benchmark_group("stochastic");
    group.sample_size(20);
    group.bench_with_input(
        BenchmarkId::new("spectral_matrix", "9ch_50s_1kHz"),
        &signals,
        |b, s| b.iter(|| SegmentSpectra::new(s, &welch).expect("spectra").matrix()),
    );
    group.bench_with_input(
        BenchmarkId::new("impedance_and_fit", "9ch_50s_1kHz"),
        &rec,
        |b, r| b.iter(|| estimate_stochastic(r, &StochasticParams::default()).expect("estimate")),
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
