//! The integration tests of this crate, gathered into one test binary
//! (one link instead of one per file); each module is one former file.

mod closed_loop;
mod common;
mod examples;
mod few_trials;
mod gait;
mod noiseless;
mod planar;
mod reflex;
mod stochastic;
mod unidentified_inertia;
mod varying;
