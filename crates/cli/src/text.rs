//! The text an estimate prints for people: one exhaustive match over the
//! result kinds, so a new kind does not compile until it has its text.

use std::path::PathBuf;

use limpid_analysis::result::Estimate;
use limpid_app::estimate::Estimated;
use limpid_ident::request::Request;

use crate::context::CliResult;

/// Print `e`, the result of `request` on the recordings at `paths`; `csv`:
/// the table as CSV where the method has one.
pub fn print(e: &Estimated, request: &Request, paths: &[PathBuf], csv: bool) -> CliResult {
    match &e.document.estimate {
        Estimate::Linear(r) => crate::estimate::linear_text(r),
        Estimate::Cocontraction(r) => crate::estimate::cocontraction_text(r),
        Estimate::Planar(r) => crate::planar::planar_text(r, e, paths),
        Estimate::WindowSweep(r) => crate::planar::sweep_text(r, e, paths, csv),
        Estimate::Stochastic(r) => match request {
            Request::Stochastic(settings) => {
                crate::stochastic::stochastic_text(r, e, settings, paths)
            }
            other => Err(disagree("stochastic", other)),
        },
        Estimate::Spectra(r) => crate::stochastic::spectra_text(r),
        Estimate::Reflex(r) => crate::reflex::reflex_text(r, paths),
        Estimate::Varying(r) => crate::varying::varying_text(r, paths),
        Estimate::Study(r) => {
            println!("{}", limpid_report::text::study_markdown(r));
            Ok(())
        }
        Estimate::Demo(_)
        | Estimate::Calibration(_)
        | Estimate::Design(_)
        | Estimate::ReflexDesign(_)
        | Estimate::PlanarDesign(_) => Err(format!(
            "a {} result is printed by its own command (`limpid {}`), not by an estimate",
            e.document.estimate.kind(),
            match e.document.estimate {
                Estimate::Demo(_) => "demo",
                Estimate::Design(_) | Estimate::ReflexDesign(_) | Estimate::PlanarDesign(_) => {
                    "protocol design"
                }
                _ => "calibrate",
            }
        )
        .into()),
    }
}

fn disagree(kind: &str, request: &Request) -> Box<dyn std::error::Error + Send + Sync> {
    format!(
        "internal error, please report it: a {kind} result from a `{}` request",
        request.command()
    )
    .into()
}
