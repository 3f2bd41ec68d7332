//! One module per result kind: the report section it makes.

pub(crate) mod calibration;
pub(crate) mod cocontraction;
pub(crate) mod demo;
pub(crate) mod design;
pub(crate) mod linear;
pub(crate) mod planar;
pub(crate) mod reflex;
pub(crate) mod spectra;
pub(crate) mod stochastic;
pub(crate) mod study;
pub(crate) mod varying;
