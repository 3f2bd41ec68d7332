//! limpid-lab: the virtual lab — perturbation profiles, target directions,
//! virtual subjects with known impedance, and simulated recordings.
//!
//! This first part covers seed 000's centre-out protocol (§II-B) on a
//! linear subject; see each module for the seed and equation it implements.

pub mod cocontraction;
pub mod design;
pub mod imbic;
pub mod planar;
pub mod profile;
pub mod protocol;
pub mod rig;
pub mod robot;
pub mod simulate;
pub mod sphere;
pub mod subject;

pub use profile::Profile;
pub use simulate::{simulate_centre_out, CentreOut, NoiseModel};
pub use subject::{seed000_subject1, Posture};
