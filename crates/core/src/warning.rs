//! Typed warnings: what an estimator or analysis wants its reader to know
//! about a result it still returns. Each carries a [`WarningCode`] a program
//! can act on and a sentence for people.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// What a warning is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum WarningCode {
    /// Fitted per-trial force offsets absorb the equilibrium position.
    EquilibriumAbsorbed,
    /// The stiffness matrix is singular, so no equilibrium is reported.
    EquilibriumSingular,
    /// A regressor is dominated by propagated position noise (errors in variables).
    NoisyRegressors,
    /// A diagonal element is below its identifiability threshold.
    NotIdentifiable,
    /// Inertial forces are below the noise.
    InertiaBelowNoise,
    /// The scaled regressor is ill-conditioned.
    IllConditioned,
    /// The model explains little of the measured force.
    PoorFit,
    /// The symmetric part of an identified matrix is not positive definite.
    NotPositiveDefinite,
    /// Multiple coherence falls low in the band (seed 004).
    LowCoherence,
    /// Frequencies were left out because a spectral matrix is singular there.
    SingularFrequencies,
    /// The inputs are correlated (seed 004 asks ordinary coherence < 0.6).
    CorrelatedInputs,
    /// Marker-derived segment lengths vary: markers may have slipped.
    MarkersSlipped,
    /// A co-contraction level had no complete trial and was skipped.
    LevelSkipped,
    /// The EMG envelopes came with the recording (`env_` columns made at the
    /// EMG's native rate by a channel map), not from raw EMG.
    EnvelopesGiven,
    /// Too few trials for the standard errors to be taken at ±2 SE = 95 %.
    FewTrials,
    /// A signal was logged faster than it was measured (held or linearly
    /// interpolated samples): its derivatives are the logging's, not the limb's.
    ResampledSignal,
    /// EMG envelopes peak well above the MVC maxima (the MVC was not
    /// maximal, or the recording and the MVC file are swapped).
    EmgAboveMvc,
    /// A column's quantity was not said and its name is not a
    /// recording-format name: the units printed were assumed.
    UnitsAssumed,
    /// A position column moves further than a limb can (a hand by metres, a
    /// joint by turns): it is probably in other units (cm, mm, degrees).
    ImplausibleUnits,
    /// The robot did not impose the motion (a commanded reference was
    /// recorded): the estimate used the reference as its instrument, or the
    /// reference drives too little of the motion to pin it down.
    ClosedLoop,
}

/// A warning attached to a result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Warning {
    /// What it is about.
    pub code: WarningCode,
    /// The warning in words, with the numbers behind it.
    pub message: String,
}

impl Warning {
    /// A warning with its code and message.
    pub fn new(code: WarningCode, message: impl Into<String>) -> Self {
        Warning {
            code,
            message: message.into(),
        }
    }
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}
