//! Write a simulated recording of N minutes (seed 000 cubic trials, 500 Hz, 3-D)
//! for timing the CLI: `cargo run --release --example long_recording -- 60 /tmp/long.parquet`.

use limpid_lab::{seed000_subject1, simulate_centre_out, sphere, CentreOut, NoiseModel, Profile};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let minutes: f64 = args.get(1).map_or(Ok(60.0), |s| s.parse())?;
    let out = args
        .get(2)
        .cloned()
        .unwrap_or_else(|| "long.parquet".into());
    let mut protocol = CentreOut::seed000(Profile::Cubic);
    let trials = (minutes * 60.0 / (protocol.rest_s + protocol.motion_s)).ceil() as usize;
    let dirs = sphere::even_directions(16);
    protocol.directions = (0..trials).map(|i| dirs[i % dirs.len()]).collect();
    let rec = simulate_centre_out(
        &seed000_subject1()[0],
        &protocol,
        &NoiseModel::default(),
        42,
    )?;
    limpid_io::write_recording(&rec, &out)?;
    println!("wrote {out}: {} samples", rec.len());
    Ok(())
}
