//! limpid-lab: the virtual lab — perturbation profiles, target directions,
//! virtual subjects with known impedance, and simulated recordings.
//!
//! Protocols of all four seeds ([`design`]), robots (`limpid_robot`, [`imbic`]),
//! subjects and rigs ([`subject`], [`planar`], [`rig`], [`cocontraction`]),
//! and [`session`], which runs a protocol on a subject; each module names the
//! seed and equation it implements.

#![warn(missing_docs)]

pub mod ankle;
pub mod cocontraction;
pub mod design;
pub mod export;
pub mod follow;
pub mod gravity;
pub mod imbic;
pub mod periodic;
pub mod planar;
pub mod profile;
pub mod protocol;
pub mod realistic;
pub mod rig;
pub mod session;
pub mod simulate;
pub mod sphere;
pub mod subject;
pub mod validate;
pub mod varying;

pub use profile::Profile;
pub use simulate::{back_to_back_cubic_trials, simulate_centre_out, CentreOut, NoiseModel};
pub use subject::{seed000_subject1, Posture};
