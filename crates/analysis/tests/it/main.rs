//! The integration tests of this crate, gathered into one test binary
//! (one link instead of one per file); each module is one former file.

mod lab_files;
mod schema;
mod shoulder;
