//! Criterion benchmark of the periodic analysis (issue 59): 16 periods of
//! 10 s at 1 kHz, 3 zippered multisine inputs and 3 outputs, from the
//! signals to the response at every excited line and the distortion levels.

use criterion::{criterion_group, criterion_main, Criterion};
use limpid_dsp::excitation::{multisine, multisine_lines, schroeder_phases, LineSet};
use limpid_dsp::periodic::{analyse, PeriodSpectra};

fn bench(c: &mut Criterion) {
    let (n, periods) = (10_000usize, 16usize);
    let lines = multisine_lines(10.0, [0.5, 20.0], LineSet::RandomOdd, 1).unwrap();
    let inputs: Vec<Vec<f64>> = (0..3)
        .map(|j| {
            let own: Vec<usize> = lines.iter().copied().skip(j).step_by(3).collect();
            let one = multisine(n, &own, &vec![1.0; own.len()], &schroeder_phases(own.len()));
            (0..n * periods).map(|i| one[i % n]).collect()
        })
        .collect();
    let mut state = 1u64;
    let mut noise = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let outputs: Vec<Vec<f64>> = (0..3)
        .map(|o| {
            (0..n * periods)
                .map(|i| inputs[o][i] + 0.5 * inputs[(o + 1) % 3][i] + 0.01 * noise())
                .collect()
        })
        .collect();
    let signals: Vec<&[f64]> = inputs.iter().chain(&outputs).map(Vec::as_slice).collect();
    c.bench_function("periodic_16x10s_1kHz_3x3", |b| {
        b.iter(|| {
            let s = PeriodSpectra::new(&signals, n).unwrap();
            analyse(&s, 3).unwrap()
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
