//! `limpid inspect FILE` and `limpid convert FILE --map M -o REC`: lab files
//! (XDF, C3D, TDMS, MAT, ROS 2 bags, and any table) seen as streams and channels, and turned into
//! FORMAT.md recordings by a channel map (limpid-io `sources`, `map`).

use std::path::PathBuf;

use clap::Args;

use crate::context::{CliResult, Context};

/// `limpid inspect`.
#[derive(Args)]
pub struct InspectArgs {
    /// The file (XDF, C3D, TDMS, MAT, a ROS 2 bag: .mcap, .db3 or a rosbag2 folder, CSV, Parquet).
    pub file: PathBuf,
    /// Print JSON instead of text.
    #[arg(long, conflicts_with = "map_template")]
    pub json: bool,
    /// Print only the proposed channel map (TOML), to save and pass with --map: `limpid inspect lab.csv --map-template > rig.toml`.
    #[arg(long)]
    pub map_template: bool,
}

/// `limpid convert`.
#[derive(Args)]
pub struct ConvertArgs {
    /// The file (XDF, C3D, TDMS, MAT, a ROS 2 bag: .mcap, .db3 or a rosbag2 folder, CSV, Parquet).
    pub file: PathBuf,
    /// Output recording (.csv or .parquet).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print a JSON summary instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Print what is in a file.
pub fn run_inspect(args: InspectArgs) -> CliResult {
    let source = limpid_io::sources::read_source(&args.file)?;
    let found = limpid_io::inspect::inspect(&source);
    if args.json {
        println!("{}", serde_json::to_string(&found)?);
        return Ok(());
    }
    if args.map_template {
        return match &found.proposed_map {
            Some(map) => {
                print!("{map}");
                Ok(())
            }
            None => Err(format!(
                "{}: no channel name says what it is; write the map by hand (docs: reference/lab-files.md) or name the columns with --column t=<time column> --column q1=<angle column> ...",
                args.file.display()
            )
            .into()),
        };
    }
    let mut out = format!("{} ({})\n", found.file, found.format);
    for s in &found.streams {
        let title = if s.name.is_empty() {
            "table".to_string()
        } else {
            format!("stream {:?}", s.name)
        };
        out.push_str(&format!(
            "\n{title}{}: {} samples",
            s.kind
                .as_ref()
                .map(|k| format!(" (type {k})"))
                .unwrap_or_default(),
            s.samples
        ));
        if let Some(r) = s.nominal_rate_hz {
            out.push_str(&format!(
                ", nominal {} Hz",
                limpid_core::error::short_number(r)
            ));
        } else if s.duration_s.is_some() {
            out.push_str(", irregular");
        }
        if let Some(r) = s.effective_rate_hz {
            out.push_str(&format!(
                ", effective {} Hz",
                limpid_core::error::significant(r, 6)
            ));
        }
        if let (Some(t0), Some(d)) = (s.start_s, s.duration_s) {
            out.push_str(&format!(
                ", from {} s for {} s",
                limpid_core::error::significant(t0, 9),
                limpid_core::error::significant(d, 6)
            ));
        }
        if s.clock_offsets > 0 {
            out.push_str(&format!(", {} clock offsets applied", s.clock_offsets));
        }
        if let Some(clock) = &s.clock {
            out.push_str(&format!(", time from {clock}"));
        }
        out.push('\n');
        if s.gaps > 0 {
            out.push_str(&format!(
                "  {} gap(s), the longest {} s\n",
                s.gaps,
                limpid_core::error::significant(s.longest_gap_s.unwrap_or(0.0), 3)
            ));
        }
        let width = s
            .channels
            .iter()
            .map(|c| c.name.chars().count())
            .max()
            .unwrap_or(0)
            .clamp(24, 60);
        for c in &s.channels {
            let range = match (c.min, c.max) {
                (Some(a), Some(b)) => format!(
                    "{} .. {}",
                    limpid_core::error::significant(a, 4),
                    limpid_core::error::significant(b, 4)
                ),
                _ => "no finite value".into(),
            };
            out.push_str(&format!(
                "  {:<width$} {:<8} {range}{}{}\n",
                c.name,
                c.unit.as_deref().unwrap_or("-"),
                if c.non_finite > 0 {
                    format!("  ({} NaN/inf)", c.non_finite)
                } else {
                    String::new()
                },
                c.also
                    .as_ref()
                    .map(|a| format!("  (also {a})"))
                    .unwrap_or_default()
            ));
        }
        for m in &s.markers {
            out.push_str(&format!("  marker {:?} x {}\n", m.text, m.count));
        }
    }
    for n in &found.notes {
        out.push_str(&format!("\nnote: {n}"));
    }
    match &found.proposed_map {
        Some(map) => out.push_str(&format!("\n\nproposed channel map (check it; `limpid inspect {0} --map-template > rig.toml` saves it; then pass --map rig.toml):\n\n{map}", args.file.display())),
        None => out.push_str("\n\nno channel name says what it is: name the columns on the command line (--column t=<time column> --column q1=<angle column> ...) or write a channel map by hand (docs: reference/lab-files.md)\n"),
    }
    print!("{out}");
    Ok(())
}

/// Convert a file to a FORMAT.md recording.
pub fn run_convert(args: ConvertArgs, cx: &Context) -> CliResult {
    cx.refuse_overwriting_inputs(
        &[(&args.output, "the output (-o)")],
        &[(&args.file, "the file to convert")],
    )?;
    let converted = limpid_io::convert(&args.file, cx.channel_map())?;
    let rec = &converted.recording;
    limpid_io::write_recording(rec, &args.output)?;
    if args.json {
        let v = serde_json::json!({
            "input": args.file.display().to_string(),
            "output": args.output.display().to_string(),
            "samples": rec.len(),
            "sample_rate_hz": rec.sample_rate(),
            "columns": rec.names(),
            "notes": converted.notes,
        });
        println!("{}", serde_json::to_string(&v)?);
    } else {
        println!(
            "{}: {} samples at {} Hz, columns {}",
            args.output.display(),
            rec.len(),
            limpid_core::error::significant(rec.sample_rate(), 6),
            rec.names().join(", ")
        );
        for n in &converted.notes {
            println!("note: {n}");
        }
    }
    // what the reader left out of the file (messages of an undeclared
    // topic, ones that did not decode) is said, not only recorded
    for w in rec.warnings() {
        eprintln!("limpid: warning: {}: {w}", args.file.display());
    }
    Ok(())
}
