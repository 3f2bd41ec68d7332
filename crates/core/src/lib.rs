//! limpid-core: the recording every method reads (FORMAT.md v1), its trials,
//! frame changes, and the shared error type.
//!
//! Conventions pinned here for the whole workspace: SI units; force is the
//! force applied **to the limb** (FORMAT.md sign convention), so the model is
//! `M x'' + B x' + K (x - x_eq) = f`; matrices are row-major `[row][col]`.

#![warn(missing_docs)]

pub mod arm;
pub mod criteria;
pub mod error;
pub mod files;
pub mod frame;
pub mod linalg;
pub mod matrix;
pub mod payload;
pub mod recording;
pub mod threads;
pub mod trial;
pub mod truth;
pub mod warning;

pub use error::{
    display_round, short_number, significant, with_standard_error, CsvNumber, Error, Result,
};
pub use frame::{FrameTransform, GravityCompensation};
pub use matrix::Matrix;
pub use payload::PayloadCalibration;
pub use recording::Recording;
pub use trial::Window;
pub use truth::Truth;
pub use warning::{Warning, WarningCode};
