//! The speed guard `.ci/run` runs (issue 82): three hot paths timed against
//! reference work timed in the same run, their ratios compared with a stored
//! baseline; a ratio more than the baseline's threshold (15 %) above its
//! baseline fails, with the numbers.
//!
//!     perf_guard BASELINE.json            check (exit 1 when slower)
//!     perf_guard BASELINE.json --update   measure three times, write the medians
//!
//! The paths: the 60-minute pipeline (`estimate linear` on 1.8 M samples of
//! Parquet, read to JSON, in-process), the parallel-cascade reflex estimate
//! of 60 s of the virtual ankle at 1 kHz, and the Welch spectral matrix of 9
//! channels x 50 s at 1 kHz, each over a fixed arithmetic kernel (the
//! pipeline over a bare Parquet decode of the same file is printed too, not
//! guarded: the decode's best varies three times as much as the kernel's).
//! Ratios, not seconds, so that a slower or busier machine moves both
//! sides; each side is the best of several interleaved runs, and a ratio
//! over the threshold is measured once more with more runs before the guard
//! fails (a shared 2-core machine has seconds when another process takes a
//! core).

use limpid_ident::{fit_linear_plan, plan, LinearParams, PrepareParams};
use rayon::prelude::*;
use std::hint::black_box;
use std::time::{Duration, Instant};

type Timed = Box<dyn Fn() -> Result<(), Box<dyn std::error::Error>>>;

fn main() {
    if let Err(e) = run() {
        eprintln!("perf_guard: {e}");
        std::process::exit(2);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let baseline_path = args
        .first()
        .ok_or("usage: perf_guard BASELINE.json [--update]")?
        .clone();
    let update = args.iter().any(|a| a == "--update");
    // 4 kB pages only: transparent huge pages make a run 15 ms faster or,
    // when the kernel must compact memory for them, 100-300 ms slower, for
    // whole minutes at a time (the pipeline's best of 9 moved by 24 %)
    #[cfg(target_os = "linux")]
    // SAFETY: prctl with PR_SET_THP_DISABLE only sets a flag of this process.
    unsafe {
        libc::prctl(libc::PR_SET_THP_DISABLE, 1, 0, 0, 0);
    }
    let dir = tempfile::tempdir()?;
    let long = dir.path().join("long.parquet");
    write_long_recording(&long)?;
    let ankle = limpid_lab::ankle::simulate_ankle(
        &limpid_lab::ankle::AnkleSubject::default(),
        &limpid_lab::ankle::AnkleExperiment {
            duration_s: 60.0,
            ..Default::default()
        },
        1,
    )?;
    let channels = noise_channels(9, 50_000);
    let long_for_decode = long.clone();
    let decoded = std::sync::Mutex::new(Vec::new());
    let decode: Timed = Box::new(move || bare_decode(&long_for_decode, &decoded));
    let paths: Vec<(&str, Timed, Timed, usize)> = vec![
        (
            "linear_60min_pipeline / kernel",
            Box::new(move || linear_pipeline(&long)),
            Box::new(kernel),
            9,
        ),
        (
            "reflex_60s_1kHz / kernel",
            Box::new(move || {
                limpid_ident::reflex::estimate_reflex(
                    &ankle,
                    &limpid_ident::reflex::ReflexParams::default(),
                )?;
                Ok(())
            }),
            Box::new(kernel),
            9,
        ),
        (
            "welch_9ch_50s_1kHz / kernel",
            Box::new(move || {
                let signals: Vec<&[f64]> = channels.iter().map(Vec::as_slice).collect();
                let welch = limpid_ident::stochastic::default_welch(50_000, 1000.0);
                black_box(limpid_dsp::spectral::SegmentSpectra::new(&signals, &welch)?.matrix());
                Ok(())
            }),
            Box::new(kernel),
            15,
        ),
    ];
    let baseline: serde_json::Value = if update {
        serde_json::Value::Null
    } else {
        serde_json::from_str(&std::fs::read_to_string(&baseline_path).map_err(|e| {
            format!("{baseline_path}: {e} (make it with perf_guard {baseline_path} --update)")
        })?)
        .map_err(|e| format!("{baseline_path}: {e}"))?
    };
    let threshold = baseline["threshold"].as_f64().unwrap_or(1.15);
    let mut measured = serde_json::Map::new();
    let mut slower = Vec::new();
    for (name, path, reference, runs) in &paths {
        let mut ratio = if update {
            // the baseline: the median of three measurements
            let mut three = [
                measure(path, reference, *runs)?,
                measure(path, reference, *runs)?,
                measure(path, reference, *runs)?,
            ];
            three.sort_by(|a, b| a.0.total_cmp(&b.0));
            three[1]
        } else {
            measure(path, reference, *runs)?
        };
        let stored = baseline["ratios"][name].as_f64();
        if let Some(stored) = stored {
            if ratio.0 > stored * threshold {
                // once more, with more runs: a busy second is not a slower build
                ratio = measure(path, reference, 3 * runs)?;
            }
        }
        let (r, path_s, reference_s) = ratio;
        let verdict = match stored {
            Some(stored) if r > stored * threshold => {
                slower.push(format!(
                    "{name}: {r:.3} against the baseline's {stored:.3} (+{:.0} %, threshold +{:.0} %)",
                    100.0 * (r / stored - 1.0),
                    100.0 * (threshold - 1.0)
                ));
                "SLOWER"
            }
            Some(stored) if r < stored / threshold => "faster: update the baseline",
            Some(_) => "ok",
            None => "no baseline",
        };
        println!(
            "perf_guard: {name}: {:.1} ms / {:.1} ms = {r:.3} (baseline {}) {verdict}",
            path_s * 1e3,
            reference_s * 1e3,
            stored.map_or("none".into(), |s| format!("{s:.3}"))
        );
        measured.insert(name.to_string(), serde_json::json!((r * 1e3).round() / 1e3));
    }
    // issue 82's other measure, printed, not guarded: a bare decode's best
    // varies by 10 % from run to run, the kernel's by 3 %
    let (r, pipeline_s, decode_s) = measure(&paths[0].1, &decode, 5)?;
    println!(
        "perf_guard: (not guarded) linear_60min_pipeline / parquet_decode: {:.1} ms / {:.1} ms = {r:.2}",
        pipeline_s * 1e3,
        decode_s * 1e3
    );
    if update {
        let doc = serde_json::json!({
            "about": "perf_guard's baseline (crates/cli/examples/perf_guard.rs): each hot path's best time over its reference's best time in the same run, on the ci profile; made with --update",
            "threshold": threshold,
            "ratios": measured,
        });
        std::fs::write(&baseline_path, serde_json::to_string_pretty(&doc)? + "\n")?;
        println!("perf_guard: wrote {baseline_path}");
        return Ok(());
    }
    if !slower.is_empty() {
        eprintln!(
            "perf_guard: slower than the baseline ({baseline_path}):\n  {}",
            slower.join("\n  ")
        );
        std::process::exit(1);
    }
    Ok(())
}

/// The best times of `path` and `reference` over `runs` interleaved runs, and their ratio.
fn measure(path: &Timed, reference: &Timed, runs: usize) -> Result<(f64, f64, f64), String> {
    let time = |f: &Timed| -> Result<Duration, String> {
        let t0 = Instant::now();
        f().map_err(|e| e.to_string())?;
        Ok(t0.elapsed())
    };
    // a first run of each warms the page cache and the thread pool
    time(path)?;
    time(reference)?;
    let (mut best_path, mut best_reference) = (Duration::MAX, Duration::MAX);
    for _ in 0..runs {
        best_reference = best_reference.min(time(reference)?);
        best_path = best_path.min(time(path)?);
    }
    let (p, r) = (best_path.as_secs_f64(), best_reference.as_secs_f64());
    Ok((p / r, p, r))
}

/// `limpid estimate linear FILE --json` in-process: read, windows, fit, result, JSON.
fn linear_pipeline(path: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    let rec = limpid_io::read_recording(path)?;
    let plan = plan(&rec, &PrepareParams::default())?;
    let est = fit_linear_plan(&plan, &LinearParams::default())?;
    let result = limpid_analysis::linear::linear_result(&est, &plan.meta);
    let json =
        limpid_analysis::result::Document::new(limpid_analysis::result::Estimate::Linear(result))
            .to_json_pretty();
    black_box(json);
    Ok(())
}

/// Every column of a Parquet file of doubles decoded into `buffers`, one
/// per column, kept between runs (so that the reference has no page faults
/// to vary with), columns in parallel, with nothing checked: the least any
/// reader must do.
fn bare_decode(
    path: &std::path::Path,
    buffers: &std::sync::Mutex<Vec<Vec<f64>>>,
) -> Result<(), Box<dyn std::error::Error>> {
    use parquet::column::reader::ColumnReader;
    use parquet::file::reader::{FileReader, SerializedFileReader};
    let open = || SerializedFileReader::new(std::fs::File::open(path)?);
    let meta = open()?.metadata().clone();
    let (columns, rows) = (
        meta.file_metadata().schema_descr().num_columns(),
        meta.file_metadata().num_rows() as usize,
    );
    let mut buffers = buffers.lock().map_err(|_| "poisoned")?;
    buffers.resize_with(columns, || Vec::with_capacity(rows));
    buffers
        .par_iter_mut()
        .enumerate()
        .map(|(c, values)| -> Result<(), String> {
            values.clear();
            // a file of its own per task: a shared one shares its cursor
            let reader = open().map_err(|e| e.to_string())?;
            for g in 0..reader.num_row_groups() {
                let group = reader.get_row_group(g).map_err(|e| e.to_string())?;
                let column = group.get_column_reader(c).map_err(|e| e.to_string())?;
                let ColumnReader::DoubleColumnReader(mut r) = column else {
                    return Err("not a double column".into());
                };
                while r
                    .read_records(1 << 16, None, None, values)
                    .map_err(|e| e.to_string())?
                    .0
                    > 0
                {}
            }
            Ok(())
        })
        .collect::<Result<(), _>>()?;
    black_box(&*buffers);
    Ok(())
}

/// Fixed arithmetic on every core, as the hot paths run: a second-order
/// recursive filter over 8 blocks of 500 000 samples, twice (a chain of
/// dependent multiply-adds, as filters and fits have). On the thread pool,
/// so that a core taken by another process slows it as it slows the paths.
fn kernel() -> Result<(), Box<dyn std::error::Error>> {
    let sums: Vec<f64> = (0..8)
        .into_par_iter()
        .map(|block| {
            let mut x: Vec<f64> = (0..500_000)
                .map(|i| (((block * 500_000 + i) * 7919) % 1000) as f64)
                .collect();
            for _ in 0..2 {
                let (mut y1, mut y2) = (0.0, 0.0);
                for v in x.iter_mut() {
                    let y = 0.02 * *v + 1.6 * y1 - 0.64 * y2;
                    (y2, y1) = (y1, y);
                    *v = y;
                }
            }
            x.iter().sum()
        })
        .collect();
    black_box(sums);
    Ok(())
}

/// `count` channels of `n` pseudo-random samples (a fixed linear congruential sequence).
fn noise_channels(count: usize, n: usize) -> Vec<Vec<f64>> {
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    (0..count)
        .map(|_| {
            (0..n)
                .map(|_| {
                    state = state
                        .wrapping_mul(6_364_136_223_846_793_005)
                        .wrapping_add(1_442_695_040_888_963_407);
                    (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
                })
                .collect()
        })
        .collect()
}

/// The 60-minute recording of the performance page (`long_recording 60`).
fn write_long_recording(path: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    let rec = limpid_lab::back_to_back_cubic_trials(60.0)?;
    limpid_io::write_recording(&rec, path)?;
    Ok(())
}
