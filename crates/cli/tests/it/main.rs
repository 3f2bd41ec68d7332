//! The integration tests of this crate, gathered into one test binary
//! (one link instead of one per file); each module is one former file.

mod bad_input;
mod cocontraction;
mod common;
mod coverage;
mod design;
mod examples;
mod first_hour;
mod gravity;
mod hostile;
mod lab_files;
mod live;
mod live_common;
mod live_load;
mod periodic;
mod planar;
mod protocol;
mod reflex;
mod report;
mod report_documents;
mod reproduce;
mod rerun;
mod robustness;
mod robustness4;
mod settings;
mod stochastic;
mod varying;
