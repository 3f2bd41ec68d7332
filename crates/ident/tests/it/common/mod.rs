//! Helpers shared by limpid-ident's integration tests: the workspace's testkit.
#![allow(unused_imports)]

pub use limpid_testkit::{example_sets, examples, mat, read_json as truth, real_data, rel_err};
