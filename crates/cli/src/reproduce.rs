//! `limpid reproduce`: each paper's experiment on the virtual lab, its numbers
//! beside the paper's ([`limpid_app::reproduce`]).

use std::path::PathBuf;

use clap::Args;
use limpid_analysis::result::reproduction::Seed;
use limpid_app::reproduce::reproduce;
use limpid_report::text::reproduction_text as text;

use crate::context::CliResult;

#[derive(Args)]
pub struct ReproduceArgs {
    /// Which paper: artemiadis2010 (Artemiadis et al. 2010), patel2013
    /// (Patel, O'Neill & Artemiadis), lakatos2011 (Lakatos, Petit & van der
    /// Smagt), park2011 (Park & Chang) or all; 000, 001, 003, 004 are aliases.
    #[arg(value_name = "PAPER")]
    pub seed: String,
    /// Print one JSON object {"rows": [...], "findings": [...]}.
    #[arg(long)]
    pub json: bool,
    /// Also write reproduce.json and reproduce.txt into this directory.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Also write the tables and findings as one HTML page.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Random seed of the virtual subjects' noise.
    #[arg(long, default_value_t = 1)]
    pub random_seed: u64,
}

pub fn run(args: ReproduceArgs) -> CliResult {
    let seeds: Vec<Seed> = if args.seed == "all" {
        Seed::ALL.to_vec()
    } else {
        vec![Seed::parse(&args.seed).ok_or_else(|| {
            limpid_core::Error::invalid(
                "paper",
                format!(
                    "unknown paper {:?}; expected artemiadis2010, patel2013, lakatos2011, park2011 or all",
                    args.seed
                ),
            )
        })?]
    };
    let r = reproduce(&seeds, args.random_seed)?;
    let json = serde_json::to_string_pretty(&r).expect("rows serialise");
    let table = text(&r);
    if let Some(dir) = &args.out {
        limpid_core::files::create_dir(dir)?;
        limpid_core::files::write_file(&dir.join("reproduce.json"), json.as_bytes())?;
        limpid_core::files::write_file(&dir.join("reproduce.txt"), table.as_bytes())?;
    }
    if let Some(path) = &args.report {
        let title = format!(
            "limpid reproduce {}: the papers' numbers beside limpid's",
            args.seed
        );
        let page = limpid_report::reproduce::reproduction_page(&r, &title);
        limpid_core::files::write_file(path, page.as_bytes())?;
    }
    if args.json {
        println!("{json}");
    } else {
        print!("{table}");
    }
    Ok(())
}
