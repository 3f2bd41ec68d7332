//! The window sweep's part of `limpid calibrate` alone: on seed 003's session
//! and on the varied subjects, trusted windows, wrong ones, and how often the
//! change scan claims a reflex with and without one (issue 37), for tuning
//! the scan without the other methods:
//! `cargo run --profile ci -p limpid-app --example sweep_alarms -- 60 1`
fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(60);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    for varied in [false, true] {
        let w = limpid_app::calibrate::calibrate_sweeps(n, seed, varied, &|| {});
        println!(
            "{}: {}",
            if varied {
                "varied subjects"
            } else {
                "seed 003 session"
            },
            serde_json::to_string(&w).unwrap_or_default()
        );
    }
}
