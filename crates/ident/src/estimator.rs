//! One shape for every estimator (the linfa pattern): settings are checked
//! before any data is read, then fitted on their data to a result that
//! carries its own quality.
//!
//! | settings | data | result |
//! |---|---|---|
//! | [`LinearParams`] | [`Prepared`] windows | [`LinearEstimate`] (seed 000 eq. (3)-(8)) |
//! | [`PlanarParams`] | [`PlanarData`] trials | [`PlanarEstimate`] (seed 003) |
//! | [`StochasticParams`] | a [`Recording`] with `u*` inputs | [`StochasticEstimate`] (seed 004) |

use limpid_core::{Error, Recording, Result};

use crate::linear::{fit_linear, LinearEstimate, LinearParams};
use crate::planar::{estimate_planar, PlanarData, PlanarEstimate};
use crate::prepare::Prepared;
use crate::stochastic::{estimate_stochastic, StochasticEstimate, StochasticParams};

/// Settings that fit data to a result.
pub trait Estimator {
    /// What the estimator reads.
    type Data: ?Sized;
    /// What it returns.
    type Fitted;

    /// Refuse settings that cannot give an honest result, before any data is read.
    fn check(&self) -> Result<()>;

    /// The estimate from data, with settings already checked.
    fn fit_checked(&self, data: &Self::Data) -> Result<Self::Fitted>;

    /// Check the settings, then fit.
    fn fit(&self, data: &Self::Data) -> Result<Self::Fitted> {
        self.check()?;
        self.fit_checked(data)
    }
}

/// `v` finite and above zero, or an error naming `name`.
pub(crate) fn positive(name: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(
            name,
            format!(
                "expected a positive number, found {}",
                limpid_core::error::Num(v)
            ),
        ))
    }
}

impl Estimator for LinearParams {
    type Data = Prepared;
    type Fitted = LinearEstimate;

    fn check(&self) -> Result<()> {
        positive("identifiable ratio", self.identifiable_ratio)
    }

    fn fit_checked(&self, data: &Prepared) -> Result<LinearEstimate> {
        fit_linear(data, self)
    }
}

/// Settings of seed 003's planar-arm estimator.
#[derive(Debug, Clone, Default)]
pub struct PlanarParams {
    /// Samples after each onset (the observation window); `None`: all.
    pub window_samples: Option<usize>,
    /// Known inertial parameters ξ1..ξ3 (kg m²): the reduced model of
    /// seed 003 eq. (23)-(25); `None`: estimated with the rest.
    pub inertial_parameters: Option<[f64; 3]>,
}

impl Estimator for PlanarParams {
    type Data = PlanarData;
    type Fitted = PlanarEstimate;

    fn check(&self) -> Result<()> {
        if self.window_samples == Some(0) {
            return Err(Error::invalid("window_ms", "expected at least one sample"));
        }
        if let Some(xi) = self.inertial_parameters {
            for v in xi {
                positive("inertial_parameters", v)?;
            }
        }
        Ok(())
    }

    fn fit_checked(&self, data: &PlanarData) -> Result<PlanarEstimate> {
        estimate_planar(
            data,
            self.window_samples.unwrap_or(usize::MAX),
            self.inertial_parameters,
        )
    }
}

impl Estimator for StochasticParams {
    type Data = Recording;
    type Fitted = StochasticEstimate;

    fn check(&self) -> Result<()> {
        let (lo, hi) = self.band_hz;
        if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo < hi) {
            return Err(Error::invalid(
                "band_hz",
                format!("expected 0 < LO < HI in Hz, found {lo}, {hi}"),
            ));
        }
        Ok(())
    }

    fn fit_checked(&self, rec: &Recording) -> Result<StochasticEstimate> {
        estimate_stochastic(rec, self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_are_refused_before_any_data_is_read() {
        let bad = LinearParams {
            identifiable_ratio: f64::NAN,
            ..LinearParams::default()
        };
        assert!(bad
            .check()
            .unwrap_err()
            .to_string()
            .contains("identifiable ratio"));
        let bad = StochasticParams {
            band_hz: (10.0, 0.5),
            ..StochasticParams::default()
        };
        assert!(bad.check().is_err());
        assert!(PlanarParams {
            window_samples: Some(0),
            ..PlanarParams::default()
        }
        .check()
        .is_err());
    }
}
