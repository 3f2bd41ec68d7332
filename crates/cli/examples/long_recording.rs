//! Write a simulated recording of N minutes (seed 000 cubic trials, 500 Hz, 3-D)
//! for timing the CLI: `cargo run --release --example long_recording -- 60 /tmp/long.parquet`.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let minutes: f64 = args.get(1).map_or(Ok(60.0), |s| s.parse())?;
    let out = args
        .get(2)
        .cloned()
        .unwrap_or_else(|| "long.parquet".into());
    let rec = limpid_lab::back_to_back_cubic_trials(minutes)?;
    limpid_io::write_recording(&rec, &out)?;
    println!("wrote {out}: {} samples", rec.len());
    Ok(())
}
