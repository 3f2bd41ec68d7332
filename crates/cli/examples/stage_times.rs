//! Time each stage of `estimate linear` on one file (development aid).
use limpid_ident::{fit_linear_plan, plan, LinearParams, PrepareParams};
use std::time::Instant;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("usage: stage_times FILE")?;
    let t0 = Instant::now();
    let rec = limpid_io::read_recording(&path)?;
    let t1 = Instant::now();
    let plan = plan(&rec, &PrepareParams::default())?;
    let t2 = Instant::now();
    let est = fit_linear_plan(&plan, &LinearParams::default())?;
    let t3 = Instant::now();
    let result = limpid_analysis::linear::linear_result(&est, &plan.meta);
    let t4 = Instant::now();
    let json =
        limpid_analysis::result::Document::new(limpid_analysis::result::Estimate::Linear(result))
            .to_json_pretty();
    let t5 = Instant::now();
    println!(
        "load {:?}, windows (noise, onsets, offsets) {:?}, filter + derivatives + QR + fit {:?}, result {:?}, JSON {:?} ({} bytes)",
        t1 - t0,
        t2 - t1,
        t3 - t2,
        t4 - t3,
        t5 - t4,
        json.len()
    );
    Ok(())
}
