//! The integration tests of this crate, gathered into one test binary
//! (one link instead of one per file); each module is one former file.

mod bags;
mod csv_numbers;
mod formats;
mod hostile;
mod mat;
