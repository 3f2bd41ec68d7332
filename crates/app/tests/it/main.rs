//! limpid-app's integration tests: one binary (see docs/src/contributing.md).

mod demo;
mod live_coverage;
mod requests;
