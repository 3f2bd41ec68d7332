//! Criterion benchmark of the virtual lab (issue 3): simulating seed 000's
//! study (6 start points x 16 cubic trials, 500 Hz) and simulating plus
//! estimating every start point, as `limpid demo` does.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};
use limpid_lab::{seed000_subject1, simulate_centre_out, CentreOut, NoiseModel, Profile};

fn bench(c: &mut Criterion) {
    let protocol = CentreOut::seed000(Profile::Cubic);
    let subject = seed000_subject1();
    let samples = (protocol.samples_per_trial() * protocol.directions.len() * subject.len()) as u64;
    let mut group = c.benchmark_group("virtual_lab");
    group.sample_size(20);
    group.throughput(Throughput::Elements(samples));
    group.bench_function(BenchmarkId::new("simulate", "seed000_6x16"), |b| {
        b.iter(|| {
            for (i, p) in subject.iter().enumerate() {
                simulate_centre_out(p, &protocol, &NoiseModel::default(), i as u64)
                    .expect("simulate");
            }
        })
    });
    group.bench_function(
        BenchmarkId::new("simulate_and_estimate", "seed000_6x16"),
        |b| {
            b.iter(|| {
                for (i, p) in subject.iter().enumerate() {
                    let rec = simulate_centre_out(p, &protocol, &NoiseModel::default(), i as u64)
                        .expect("simulate");
                    let d = prepare(&rec, &PrepareParams::default()).expect("prepare");
                    fit_linear(&d, &LinearParams::default()).expect("fit");
                }
            })
        },
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
