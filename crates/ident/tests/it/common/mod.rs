//! Helpers shared by limpid-ident's integration tests: the workspace's testkit.
#![allow(unused_imports)]

pub use limpid_testkit::{examples, mat, read_json as truth, rel_err};
