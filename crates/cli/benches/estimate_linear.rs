//! Criterion benchmark of `estimate linear` (issues 2 and 16), stage by
//! stage: load from Parquet, find the windows (`plan`: noise, onsets, rest
//! offsets), filter + differentiate + QR + fit window by window (the CLI's
//! path), and the whole command; `prepare` and `fit` time the materialised
//! path that the Python `prepare` and the other estimators use. Simulated
//! 500 Hz 3-D recordings of 1 and 60 minutes (seed 000 cubic trials back to
//! back, fixed seed).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use limpid_ident::{fit_linear, fit_linear_plan, plan, prepare, LinearParams, PrepareParams};

/// A recording of `minutes` of 3.2 s cubic trials at 500 Hz.
pub fn long_recording(minutes: f64) -> limpid_core::Recording {
    limpid_lab::back_to_back_cubic_trials(minutes).expect("simulation")
}

fn bench(c: &mut Criterion) {
    let dir = std::env::temp_dir().join("limpid-bench");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let mut group = c.benchmark_group("estimate_linear");
    group.sample_size(10);
    for minutes in [1.0, 60.0] {
        let rec = long_recording(minutes);
        let path = dir.join(format!("cubic_{minutes}min.parquet"));
        limpid_io::write_recording(&rec, &path).expect("write parquet");
        group.throughput(Throughput::Elements(rec.len() as u64));
        let id = format!("{minutes}min_{}samples", rec.len());
        group.bench_with_input(BenchmarkId::new("load_parquet", &id), &path, |b, p| {
            b.iter(|| limpid_io::read_recording(p).expect("read"))
        });
        group.bench_with_input(BenchmarkId::new("plan", &id), &rec, |b, r| {
            b.iter(|| plan(r, &PrepareParams::default()).expect("plan"))
        });
        let the_plan = plan(&rec, &PrepareParams::default()).expect("plan");
        group.bench_with_input(
            BenchmarkId::new("fit_window_by_window", &id),
            &the_plan,
            |b, p| b.iter(|| fit_linear_plan(p, &LinearParams::default()).expect("fit")),
        );
        group.bench_with_input(BenchmarkId::new("prepare", &id), &rec, |b, r| {
            b.iter(|| prepare(r, &PrepareParams::default()).expect("prepare"))
        });
        let prepared = prepare(&rec, &PrepareParams::default()).expect("prepare");
        group.bench_with_input(BenchmarkId::new("fit", &id), &prepared, |b, p| {
            b.iter(|| fit_linear(p, &LinearParams::default()).expect("fit"))
        });
        group.bench_with_input(BenchmarkId::new("whole_command", &id), &path, |b, p| {
            b.iter(|| {
                let r = limpid_io::read_recording(p).expect("read");
                let d = plan(&r, &PrepareParams::default()).expect("plan");
                fit_linear_plan(&d, &LinearParams::default()).expect("fit")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
