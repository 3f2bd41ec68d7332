//! Time each stage of `estimate linear` on one file (development aid).
use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};
use std::time::Instant;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("usage: stage_times FILE")?;
    let t0 = Instant::now();
    let rec = limpid_io::read_recording(&path)?;
    let t1 = Instant::now();
    let prepared = prepare(&rec, &PrepareParams::default())?;
    let t2 = Instant::now();
    let est = fit_linear(&prepared, &LinearParams::default())?;
    let t3 = Instant::now();
    let _ = limpid_analysis::linear::linear_result(&est, &prepared);
    let t4 = Instant::now();
    println!(
        "load {:?} prepare {:?} fit {:?} analyse {:?}",
        t1 - t0,
        t2 - t1,
        t3 - t2,
        t4 - t3
    );
    Ok(())
}
