//! limpid-ident: from a recording to impedance estimates with their quality.
//!
//! - [`prepare`](mod@prepare): windows, offsets, filtering, derivatives (seed 000 §II-C,
//!   seed 001 "Data Processing"); [`Plan`] for estimators that go window by window.
//! - [`linear`]: the linear model `M x'' + B x' + K (x - x_eq) = f` by least
//!   squares (seed 000 eq. (3)-(8), seed 001 eq. (3)-(10)).
//! - [`planar`]: the planar 2-link arm in joint space (seed 003).
//! - [`stochastic`]: Z(f) = T R^-1 from Welch spectra (seed 004).
//! - [`reflex`]: intrinsic and reflex stiffness, parallel cascade (Kearney et al. 1997).
//! - [`online`]: per-perturbation impedance for the live display.
//! - [`closed_loop`]: the commanded reference as an instrument (issue 79).
//! - [`request`]: one typed request per method, shared by every front-end.
//! - [`units`]: units from what a column is (joint angle or displacement).
//! - [`estimator`]: the one shape they share (settings -> check -> fit -> result).

#![warn(missing_docs)]

pub mod closed_loop;
pub mod estimator;
pub mod linear;
pub mod lsq;
pub mod online;
pub mod periodic_fit;
pub mod periodic_stochastic;
pub mod planar;
pub mod prepare;
pub mod reflex;
pub mod request;
pub mod spectra;
pub mod stochastic;
pub mod units;
pub mod varying;

pub use estimator::{Estimator, PlanarParams};
pub use linear::{fit_linear, fit_linear_plan, LinearEstimate, LinearParams};
pub use prepare::{plan, prepare, Derivative, Offsets, Plan, PrepareParams, Prepared, Windowing};

/// `n` uniform numbers in [-0.5, 0.5) from a fixed linear congruential
/// sequence seeded by `seed`: test signals without a random-number crate.
#[cfg(test)]
pub(crate) fn uniform_noise(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect()
}
