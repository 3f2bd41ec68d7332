//! `limpid calibrate`: the coverage and verdict study of
//! [`limpid_app::calibrate`], printed as a table (or JSON).

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use limpid_analysis::result::{Document, Estimate};
use limpid_app::calibrate::{calibrate, sweeps_for, METHODS, SWEEP_SETS};

use crate::context::CliResult;

#[derive(Args)]
pub struct CalibrateArgs {
    /// Virtual recordings per method (at least 10).
    #[arg(long, default_value_t = 200)]
    pub recordings: usize,
    /// Random seed of the subjects and the sensor noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print one JSON document instead of the table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: CalibrateArgs) -> CliResult {
    if !(10..=100_000).contains(&args.recordings) {
        return Err(format!(
            "--recordings: expected 10 to 100000, found {}",
            args.recordings
        )
        .into());
    }
    let total = METHODS * args.recordings + SWEEP_SETS * sweeps_for(args.recordings);
    let bar = ProgressBar::new(total as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} recordings ({elapsed})")
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
    );
    bar.set_message("simulating and estimating");
    let started = std::time::Instant::now();
    let result = calibrate(args.recordings, args.seed, &|| bar.inc(1))?;
    bar.finish_and_clear();
    let seconds = started.elapsed().as_secs_f64();
    if args.json {
        println!(
            "{}",
            Document::new(Estimate::Calibration(result))
                .with_run(limpid_analysis::result::Run::of_this_process(&[]))
                .to_json_pretty()
        );
        return Ok(());
    }
    let (header, rows) = result.table();
    println!(
        "limpid calibrate: {} virtual recordings per method, seed {}, {seconds:.1} s",
        result.recordings_per_method, result.seed
    );
    println!("| {} |", header.join(" | "));
    println!("|{}", "---|".repeat(header.len()));
    for r in &rows {
        println!("| {} |", r.join(" | "));
    }
    print_sweeps(
        "window sweep (Lakatos et al. 2011, 50-400 ms), their session",
        &result.window_sweep,
    );
    if let Some(w) = &result.window_sweep_varied {
        print_sweeps(
            "window sweep on varied subjects (end-point data, 20-60 trials, T_k 150-250 ms, cuffs)",
            w,
        );
    }
    let r = &result.varying_reflex;
    println!(
        "parameter-varying ankle: a reflex claimed in {} of {} subjects without one, detected in {} of {} with one",
        r.claimed_without, r.without_reflex, r.detected, r.with_reflex
    );
    let designs = [
        ("linear", &result.design, ["K", "B", "M"]),
        ("stochastic", &result.stochastic_design, ["K", "B", "M"]),
        ("planar", &result.planar_design, ["K", "D", "ξ"]),
    ];
    for (method, d, [k, b, m]) in designs
        .iter()
        .filter_map(|(method, d, names)| d.as_ref().map(|d| (method, d, names)))
    {
        println!(
            "protocol design ({method}, {}): predicted/achieved spread {k} {:.2}, {b} {:.2}, {m} {:.2} over {} subjects; {k} within 5 % and {b} within 20 %, both identifiable: {:.0} % ({:.1} s)",
            d.prior,
            d.ratio[0],
            d.ratio[1],
            d.ratio[2],
            d.recordings,
            100.0 * d.within_tolerance_share,
            d.seconds
        );
    }
    Ok(())
}

/// The text lines of one set of window sweeps.
fn print_sweeps(title: &str, w: &limpid_analysis::result::calibration::SweepCalibration) {
    println!(
        "\n{title}: {} sweeps ({} with a stretch reflex, {} on end-point data, {} through a cuff, {} refused); {} windows trusted, {} of them beyond K 10 % or D 25 % of the truth; {} windows were within both; sweeps trusting some window: {} of {} without reflex, {} of {} with",
        w.sweeps,
        w.with_reflex,
        w.endpoint_sweeps,
        w.cuff_sweeps,
        w.refused,
        w.trusted_windows,
        w.trusted_but_wrong,
        w.correct_windows,
        w.sweeps_with_a_trusted_window[0],
        w.without_reflex(),
        w.sweeps_with_a_trusted_window[1],
        w.with_reflex
    );
    let cuff_without = w.cuff_sweeps.saturating_sub(w.cuff_with_reflex);
    println!(
        "  change scan (a reflex?): claimed in {} of {} reflex-free sweeps (false alarms; {} of {} without a cuff), in {} of {} with a reflex (detections; {} of {} without a cuff); put down to soft tissue in series in {} and {} of them",
        w.changes_claimed[0],
        w.without_reflex(),
        w.changes_claimed[0].saturating_sub(w.cuff_changes_claimed[0]),
        w.without_reflex().saturating_sub(cuff_without),
        w.changes_claimed[1],
        w.with_reflex,
        w.changes_claimed[1].saturating_sub(w.cuff_changes_claimed[1]),
        w.with_reflex.saturating_sub(w.cuff_with_reflex),
        w.tissue_named[0],
        w.tissue_named[1],
    );
}
