//! limpid-app's integration tests: one binary (see docs/src/contributing.md).

mod accuracy;
mod demo;
mod design;
mod live_coverage;
mod requests;
