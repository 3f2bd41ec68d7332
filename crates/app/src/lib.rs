//! limpid-app: a typed request ([`limpid_ident::request::Request`]) run end
//! to end: the robot's kinematics and the shoulder's joint space applied to
//! the recordings, the estimator, and what the result says
//! (`limpid-analysis`). The CLI, Python and `limpid rerun` all run requests
//! through [`estimate::run`]; none of them maps options to settings itself.
//!
//! It also holds the workflows that simulate with `limpid-lab` and read or
//! write files: [`demo`], [`reproduce`], [`calibrate`], [`study`] and the
//! protocol's predicted conditioning ([`protocol`]). Their result types stay
//! in `limpid-analysis` (the result contract), which no longer depends on the
//! lab.

#![warn(missing_docs)]

pub mod calibrate;
pub mod demo;
pub mod design;
pub mod estimate;
pub mod live_check;
pub mod protocol;
pub mod reproduce;
pub mod study;
