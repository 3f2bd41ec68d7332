//! Criterion benchmark of a whole co-contraction study (issue 4): the virtual
//! seed 001 study of 4 subjects x 7 configurations x 4 levels x 18
//! perturbations (28 Parquet recordings + MVC files), run in parallel.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use limpid_app::study::{load_manifest, run_study};
use limpid_lab::cocontraction::{
    seed001_population, simulate_cocontraction, CocontractionProtocol,
};
use limpid_lab::NoiseModel;

fn write_study(dir: &std::path::Path, subjects: usize) -> std::path::PathBuf {
    std::fs::create_dir_all(dir).expect("dir");
    let protocol = CocontractionProtocol::seed001();
    let mut manifest = String::from("[study]\nname = \"bench\"\n");
    for (s, c, subject) in seed001_population(subjects, 1) {
        let (rec, mvc) = simulate_cocontraction(
            &subject,
            &protocol,
            &NoiseModel::default(),
            (s * 100 + c) as u64,
        )
        .expect("sim");
        let file = format!("s{s}_c{c}.parquet");
        let mvc_file = format!("s{s}_c{c}.mvc.parquet");
        limpid_io::write_recording(&rec, dir.join(&file)).expect("write");
        limpid_io::write_recording(&mvc, dir.join(&mvc_file)).expect("write");
        manifest.push_str(&format!("\n[[recording]]\nsubject = \"{s}\"\nconfiguration = \"{c}\"\nfile = \"{file}\"\nmvc = \"{mvc_file}\"\n"));
    }
    let path = dir.join("study.toml");
    std::fs::write(&path, manifest).expect("manifest");
    path
}

fn bench(c: &mut Criterion) {
    let path = write_study(&std::env::temp_dir().join("limpid-bench-study"), 4);
    let manifest = load_manifest(&path).expect("manifest");
    let mut group = c.benchmark_group("study_run");
    group.sample_size(10);
    group.bench_with_input(
        BenchmarkId::new("virtual_seed001", "4x7x4x18"),
        &manifest,
        |b, m| b.iter(|| run_study(m, &|| {})),
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
