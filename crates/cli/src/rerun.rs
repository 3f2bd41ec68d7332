//! `limpid rerun RESULT.json`: the request a result's run block holds, run
//! again on the files it names (a check that a result can be made again, or
//! the same analysis with a newer limpid).

use std::path::PathBuf;

use clap::Args;
use limpid_analysis::result::Document;

use crate::context::{CliResult, Context};
use crate::emit::Output;

#[derive(Args)]
pub struct RerunArgs {
    /// A JSON result written by `limpid estimate ... --json` or `limpid window-sweep --json`.
    pub result: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Also write the HTML report to this file.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
}

pub fn run(args: RerunArgs, cx: &Context) -> CliResult {
    if let Some(report) = &args.report {
        limpid_core::files::refuse_overwriting_inputs(
            &[(report, "the report (--report)")],
            &[(&args.result, "the result to rerun")],
        )?;
    }
    let name = args.result.display().to_string();
    let text = limpid_core::files::read_text(&args.result)?;
    let doc = Document::from_json(&name, &text)?;
    let Some(run) = doc.run else {
        return Err(format!(
            "{name}: has no run block (written by the library or Python); nothing says how it was made"
        )
        .into());
    };
    let Some(request) = run.request else {
        return Err(format!(
            "{name}: its run block holds no request (made by a workflow, or before results recorded their request); its command line was: {}",
            run.command_line
        )
        .into());
    };
    // a relative path is taken from here, else from the result's folder
    let folder = args.result.parent().unwrap_or(std::path::Path::new(""));
    // the recordings are read through the map the result was made with
    let cx = match &run.channel_map {
        Some(map) => {
            let p = PathBuf::from(&map.path);
            let p = if p.is_relative() && !p.exists() && folder.join(&p).exists() {
                folder.join(p)
            } else {
                p
            };
            cx.with_map(&p)?
        }
        None => cx.without_map(),
    };
    let cx = cx.with_columns(run.columns.clone().into_iter().collect());
    let paths: Vec<PathBuf> = run
        .inputs
        .iter()
        .map(|f| {
            let p = PathBuf::from(&f.path);
            if p.is_relative() && !p.exists() && folder.join(&p).exists() {
                folder.join(p)
            } else {
                p
            }
        })
        .collect();
    if let Some(p) = paths.iter().find(|p| !limpid_io::named_like_a_recording(p)) {
        return Err(format!(
            "{name}: its run block names {} as an input, which is not named like a recording (.csv, .parquet, .mat, .xdf, .c3d, .tdms); not read",
            p.display()
        )
        .into());
    }
    for (file, path) in run.inputs.iter().zip(&paths) {
        let meta = std::fs::metadata(path).ok();
        let bytes = meta.as_ref().map(|m| m.len());
        if file.bytes.is_some() && bytes.is_some() && file.bytes != bytes {
            eprintln!(
                "limpid: warning: {}: {} bytes now, {} when the result was made",
                path.display(),
                bytes.unwrap_or_default(),
                file.bytes.unwrap_or_default()
            );
        }
    }
    let out = Output {
        json: args.json,
        report: args.report.as_deref(),
        print_request: false,
        csv: false,
    };
    crate::emit::estimate(&cx, request, &paths, out)
}
