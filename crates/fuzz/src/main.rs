//! `limpid-fuzz`: run the mutation fuzzer (see the library docs).
//!
//! ```text
//! cargo run --release -p limpid-fuzz -- [--executions N] [--seed S] [--threads T] [--only mcap,db3 | --only rig-mcos]
//! ```
//!
//! Prints executions per kind of input, refused / accepted counts and every
//! finding; a finding's input is written to `corpus/findings/` (move it to
//! `corpus/regressions/` once fixed, where the tests replay it). An execution
//! that runs over 10 s is a hang: its input is written and the process exits
//! with status 3. Exit status 1 when there were findings.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use limpid_fuzz::{corpus, corpus_dir, execute, is_text, mutate, Outcome};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

const HANG: Duration = Duration::from_secs(10);

fn arg(name: &str, default: u64) -> u64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(|v| {
            v.replace('_', "")
                .parse()
                .unwrap_or_else(|_| panic!("{name}: expected a number, found {v}"))
        })
        .unwrap_or(default)
}

/// What a worker counted (refused, accepted, findings per kind) and its findings.
type WorkerStats = (BTreeMap<String, [usize; 3]>, Vec<(String, String, Vec<u8>)>);

/// Per worker: the input running now and when it started (ms since start; 0 = idle).
struct Running {
    started_ms: AtomicU64,
    input: Mutex<(String, Vec<u8>)>,
}

fn main() {
    // caught panics (a decoder's, turned into errors) would print a backtrace each
    std::panic::set_hook(Box::new(|_| {}));
    let executions = arg("--executions", 1_000_000) as usize;
    let seed = arg("--seed", 1);
    let threads = arg(
        "--threads",
        std::thread::available_parallelism().map_or(1, |n| n.get()) as u64,
    ) as usize;
    // --only EXT[,EXT]: the inputs of those kinds alone (a campaign on one reader)
    let args: Vec<String> = std::env::args().collect();
    let only: Option<Vec<String>> = args
        .iter()
        .position(|a| a == "--only")
        .and_then(|i| args.get(i + 1))
        .map(|list| list.split(',').map(str::to_string).collect());
    let inputs = Arc::new(
        corpus()
            .into_iter()
            .filter(|(name, _)| {
                only.as_ref().is_none_or(|kinds| {
                    // an extension (mcap) or the start of a seed's name (rig-mcos)
                    kinds.iter().any(|k| {
                        name.rsplit('.').next() == Some(k.as_str()) || name.starts_with(k.as_str())
                    })
                })
            })
            .collect::<Vec<_>>(),
    );
    assert!(
        !inputs.is_empty(),
        "no corpus in {}",
        corpus_dir().display()
    );
    let findings_dir = corpus_dir().join("findings");
    let clock = Instant::now();
    let done = Arc::new(AtomicUsize::new(0));
    let running: Arc<Vec<Running>> = Arc::new(
        (0..threads)
            .map(|_| Running {
                started_ms: AtomicU64::new(0),
                input: Mutex::new((String::new(), Vec::new())),
            })
            .collect(),
    );
    spawn_watchdog(Arc::clone(&running), findings_dir.clone(), clock);
    let per_thread = executions.div_ceil(threads);
    let stats: Vec<WorkerStats> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|w| {
                let inputs = Arc::clone(&inputs);
                let running = Arc::clone(&running);
                let done = Arc::clone(&done);
                scope.spawn(move || {
                    let mut rng = StdRng::seed_from_u64(seed.wrapping_mul(1_000_003) + w as u64);
                    let me = &running[w];
                    work(&mut rng, &inputs, me, &done, (per_thread, clock))
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("worker"))
            .collect()
    });
    // a panic message from a caught panic goes to the default hook's stderr; the count is what matters
    let mut total: BTreeMap<String, [usize; 3]> = BTreeMap::new();
    let mut findings = Vec::new();
    for (counts, found) in stats {
        for (k, v) in counts {
            let t = total.entry(k).or_default();
            for i in 0..3 {
                t[i] += v[i];
            }
        }
        findings.extend(found);
    }
    let all: usize = total.values().map(|v| v.iter().sum::<usize>()).sum();
    println!(
        "{all} executions in {:.1} s on {threads} threads (seed {seed}), corpus of {} inputs",
        clock.elapsed().as_secs_f64(),
        inputs.len()
    );
    println!(
        "{:<10} {:>12} {:>12} {:>9}",
        "input", "refused", "accepted", "findings"
    );
    for (k, v) in &total {
        println!("{k:<10} {:>12} {:>12} {:>9}", v[0], v[1], v[2]);
    }
    let n_findings: usize = total.values().map(|v| v[2]).sum();
    println!("findings: {n_findings} (panics, non-finite or null results); hangs over {HANG:?}: 0");
    if !findings.is_empty() {
        let _ = std::fs::create_dir_all(&findings_dir);
        for (i, (name, what, input)) in findings.iter().enumerate() {
            let path = findings_dir.join(format!("{i:03}-{name}"));
            let _ = std::fs::write(&path, input);
            println!("  {what}: {}", path.display());
        }
        std::process::exit(1);
    }
}

/// The watchdog: an execution over HANG is written out and ends the run.
fn spawn_watchdog(running: Arc<Vec<Running>>, dir: std::path::PathBuf, clock: Instant) {
    std::thread::spawn(move || loop {
        std::thread::sleep(Duration::from_millis(500));
        let now = clock.elapsed().as_millis() as u64;
        for r in running.iter() {
            let s = r.started_ms.load(Ordering::Relaxed);
            if s > 0 && now.saturating_sub(s) > HANG.as_millis() as u64 {
                let (name, bytes) = r.input.lock().map(|g| g.clone()).unwrap_or_default();
                let _ = std::fs::create_dir_all(&dir);
                let path = dir.join(format!("hang-{name}"));
                let _ = std::fs::write(&path, &bytes);
                eprintln!(
                    "HANG: an execution ran over {HANG:?}; input written to {}",
                    path.display()
                );
                std::process::exit(3);
            }
        }
    });
}

/// One worker's executions: random corpus inputs, mutated and executed, the
/// outcomes counted by file extension, the first 20 findings kept.
fn work(
    rng: &mut StdRng,
    inputs: &[(String, Vec<u8>)],
    me: &Running,
    done: &AtomicUsize,
    (executions, clock): (usize, Instant),
) -> WorkerStats {
    let mut counts: BTreeMap<String, [usize; 3]> = BTreeMap::new();
    let mut found = Vec::new();
    for _ in 0..executions {
        let (name, base) = &inputs[rng.random_range(0..inputs.len())];
        let input = mutate(rng, base, is_text(name));
        if let Ok(mut g) = me.input.lock() {
            g.0.clone_from(name);
            g.1.clone_from(&input);
        }
        me.started_ms
            .store(clock.elapsed().as_millis() as u64 + 1, Ordering::Relaxed);
        let outcome = execute(name, &input);
        me.started_ms.store(0, Ordering::Relaxed);
        let ext = name.rsplit('.').next().unwrap_or("").to_string();
        let c = counts.entry(ext).or_default();
        match outcome {
            Outcome::Refused => c[0] += 1,
            Outcome::Accepted => c[1] += 1,
            Outcome::Finding(what) => {
                c[2] += 1;
                if found.len() < 20 {
                    found.push((name.clone(), what, input));
                }
            }
        }
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        if n.is_multiple_of(1_000_000) {
            eprintln!("{n} executions, {:.0} s", clock.elapsed().as_secs_f64());
        }
    }
    (counts, found)
}
