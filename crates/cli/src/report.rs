//! `limpid report RESULT.json... -o report.html [--figures DIR]` and the
//! `--report FILE` option of the other commands (limpid-report).

use std::path::{Path, PathBuf};

use clap::Args;
use limpid_analysis::result::Document;

use crate::context::CliResult;

#[derive(Args)]
pub struct ReportArgs {
    /// JSON results: `estimate ... --json`, `demo.json`, `window-sweep --json`.
    #[arg(required = true)]
    pub results: Vec<PathBuf>,
    /// The HTML file to write.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write every figure into this folder as SVG and PNG, sized for a journal column (for papers).
    #[arg(long, value_name = "DIR")]
    pub figures: Option<PathBuf>,
}

/// `--report FILE` of the other commands: the result of this run.
pub fn write(doc: &Document, path: &Path) -> CliResult {
    limpid_core::files::write_file(path, limpid_report::page(doc).as_bytes())?;
    eprintln!("report: {}", path.display());
    Ok(())
}

pub fn run(args: ReportArgs) -> CliResult {
    let mut outputs = vec![(args.output.as_path(), "the report (-o)")];
    if let Some(dir) = &args.figures {
        outputs.push((dir.as_path(), "the figures folder (--figures)"));
    }
    let inputs: Vec<(&Path, &str)> = args
        .results
        .iter()
        .map(|p| (p.as_path(), "a result to report"))
        .collect();
    limpid_core::files::refuse_overwriting_inputs(&outputs, &inputs)?;
    let mut docs = Vec::new();
    for p in &args.results {
        let text = limpid_core::files::read_text(p)?;
        let name = p.display().to_string();
        docs.push((name.clone(), Document::from_json(&name, &text)?));
    }
    let named: Vec<(String, &Document)> = docs.iter().map(|(n, d)| (n.clone(), d)).collect();
    let report = limpid_report::build_documents(&named);
    // the page and its figures are one set: a figures folder that cannot be
    // made or written leaves no page behind either (issue 36)
    let mut outputs = limpid_core::files::OutputSet::new();
    outputs.add(&args.output, limpid_report::to_html(&report).as_bytes())?;
    let mut figures = 0;
    if let Some(dir) = &args.figures {
        outputs.create_dir(dir)?;
        let files = limpid_report::figure_files(&report);
        // the bitmaps in parallel: rasterising is the slow part
        use rayon::prelude::*;
        let pngs: Vec<(String, Vec<u8>)> = files
            .par_iter()
            .map(|(stem, svg)| {
                limpid_report::png::svg_to_png(svg).map(|png| (format!("{stem}.png"), png))
            })
            .collect::<Result<_, String>>()?;
        for (stem, svg) in &files {
            outputs.add(&dir.join(format!("{stem}.svg")), svg.as_bytes())?;
        }
        for (name, png) in &pngs {
            outputs.add(&dir.join(name), png)?;
        }
        figures = files.len();
    }
    outputs.commit()?;
    println!("wrote {}", args.output.display());
    if let Some(dir) = &args.figures {
        println!(
            "wrote {} figures to {} (SVG, and PNG at {} x)",
            figures,
            dir.display(),
            limpid_report::png::SCALE
        );
    }
    Ok(())
}
