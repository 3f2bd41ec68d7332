//! limpid-app: a typed request ([`limpid_ident::request::Request`]) run end
//! to end: the robot's kinematics and the shoulder's joint space applied to
//! the recordings, the estimator, and what the result says
//! (`limpid-analysis`). The CLI, Python and `limpid rerun` all run requests
//! through [`estimate::run`]; none of them maps options to settings itself.

#![warn(missing_docs)]

pub mod estimate;
