//! One way every estimate leaves the CLI: the request checked, the
//! recordings read, the request run (`limpid-app`), the run block attached
//! (with the request), then the report, the JSON or the text.

use std::path::{Path, PathBuf};

use limpid_analysis::result::{Document, Run};
use limpid_ident::request::Request;

use crate::context::{CliResult, Context};

/// Where an estimate goes.
pub struct Output<'a> {
    /// One JSON object on stdout instead of text.
    pub json: bool,
    /// The HTML report, when asked for.
    pub report: Option<&'a Path>,
    /// Print the request instead of running it.
    pub print_request: bool,
    /// The text as CSV, where the method has a table (`window-sweep --csv`).
    pub csv: bool,
}

/// The flags every estimating command shares: where its result goes.
#[derive(clap::Args)]
pub struct OutputArgs {
    /// Print one JSON object (the result document) instead of text.
    #[arg(long)]
    pub json: bool,
    /// Also write the HTML report (this method's tables and figures) to this file.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Print the request these flags make (JSON, as a result's run block and `limpid rerun` hold it) and stop.
    #[arg(long)]
    pub print_request: bool,
}

impl OutputArgs {
    /// Where the estimate goes.
    pub fn output(&self) -> Output<'_> {
        Output {
            json: self.json,
            report: self.report.as_deref(),
            print_request: self.print_request,
            csv: false,
        }
    }
}

/// Run `request` on the recordings at `paths` and emit the result (as text
/// for people: [`crate::text::print`]).
pub fn estimate(cx: &Context, request: Request, paths: &[PathBuf], out: Output<'_>) -> CliResult {
    let request_command = request.command();
    // checked before it is printed too: a request limpid would refuse to run is not printed
    let checked = request
        .check()
        .map_err(|e| cx.with_flag_names(request_command, e))?;
    if out.print_request {
        println!(
            "{}",
            serde_json::to_string_pretty(checked.request()).expect("requests serialise")
        );
        return Ok(());
    }
    if let Some(report) = out.report {
        let inputs: Vec<(&Path, &str)> = paths.iter().map(|p| (p.as_path(), "an input")).collect();
        cx.refuse_overwriting_inputs(&[(report, "the report (--report)")], &inputs)?;
    }
    // the MVC recording beside a co-contraction session records less (EMG only)
    let supporting = |i: usize| matches!(checked.request(), Request::Cocontraction(_)) && i > 0;
    let recordings = paths
        .iter()
        .enumerate()
        .map(|(i, p)| {
            if supporting(i) {
                cx.read_supporting_recording(p)
            } else {
                cx.read_recording(p)
            }
        })
        .collect::<limpid_core::Result<Vec<_>>>()?;
    // a periodic recording (multisine, PRBS) read by a time-domain method:
    // accepted as one continuous record, and said (issue 59)
    if matches!(checked.request(), Request::Linear(_) | Request::Reflex(_)) {
        if let Some(rec) = recordings.first().filter(|r| r.column("period").is_some()) {
            eprintln!(
                "limpid: note: {}: a periodic recording (period column): estimated as one continuous record, transient periods included; `limpid spectra --period S` analyses it period by period",
                rec.path().display()
            );
        }
    }
    let inputs: Vec<&Path> = paths.iter().map(PathBuf::as_path).collect();
    let run = Run::of_this_process(&inputs)
        .with_request(checked.request())
        .with_channel_map(cx.map_path())
        .with_columns(cx.columns())
        .with_recordings(&recordings);
    let mut estimated = limpid_app::estimate::run(&checked, recordings)
        .map_err(|e| cx.with_flag_names(request_command, e))?;
    estimated.document.run = Some(run);
    if let Some(path) = out.report {
        crate::report::write(&estimated.document, path)?;
    }
    if out.json {
        println!("{}", json(&estimated.document, checked.request()));
        return Ok(());
    }
    crate::text::print(&estimated, checked.request(), paths, out.csv)
}

/// The JSON text of a result: indented for the matrix methods, one line for
/// the long frequency and IRF arrays.
fn json(doc: &Document, request: &Request) -> String {
    if request.long_arrays() {
        doc.to_json()
    } else {
        doc.to_json_pretty()
    }
}
