//! Periodic perturbation protocols (issue 59): a multisine or a pseudo-random
//! binary sequence on a joint (`q1`, ...) or an end point (`x, y, z`),
//! repeated for whole periods after a transient period, faded in over the
//! transient and out over one more period so that the robot starts and ends
//! at rest at the posture. The signals are `limpid_dsp::excitation`'s.
//!
//! Protocol fields (TOML, `kind = "multisine"` or `kind = "prbs"`):
//! `coordinates = "joint" | "endpoint"`, `channels` (column names; default
//! `["q1"]` or `["x", "y", "z"]`), `sample_rate_hz`, `periods` (recorded
//! after the transient), `seed`, and a `[limits]` table with the names of
//! the planar preset (joint: `max_joint_displacement_rad`,
//! `max_joint_velocity_rad_s`, `max_joint_acceleration_rad_s2`,
//! `max_torque_nm`, `nominal_joint_stiffness_nm_per_rad`) or of the
//! centre-out preset (end point: `max_displacement_m`, `max_velocity_m_s`,
//! `max_acceleration_m_s2`, `max_force_n`, `nominal_stiffness_n_per_m`).
//! Multisine: `period_s`, `band_hz = [lo, hi]`, `rms = [...]` per channel
//! (rad or m over one period), `lines = "full" | "odd" | "random-odd"`,
//! `phases = "optimised" | "schroeder" | "random"`, `amplitude_shape =
//! "flat" | "1/f" | "1/f^2"` or `amplitude_points = [[hz, a], ...]`; several channels take
//! every n-th line in turn (zippered), so that no line is excited by two
//! inputs and their coherence is zero at every excited line. PRBS: `order`
//! (period 2^order - 1 switching intervals; with `ternary = true` a
//! pseudo-random ternary sequence of 3^order - 1, odd lines only), `switch_interval_s`,
//! `amplitude = [...]` per channel (levels ± amplitude about the posture),
//! `edge_s` (each level change a raised-cosine ramp of this length centred
//! on the switching instant: the spectrum is the PRBS's times the ramp's,
//! which falls off above 1 / edge_s; default the shortest ramp within the
//! velocity and acceleration limits, at least one sample); channels after
//! the first are the first sequence shifted by a third of a period each.
//!
//! The commanded force or torque is predicted as the nominal stiffness
//! times the displacement (the limits' `nominal_*`); `check` verifies every
//! sample of every channel against every limit.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use limpid_core::{Error, Result};
use limpid_dsp::excitation::{
    crest_factor, mls, multisine, multisine_lines, optimise_phases, period_spectrum, prts,
    random_phases, schroeder_phases_for, LineSet, PRTS_ORDERS,
};

/// Joint or end-point coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Coordinates {
    /// Joint angles (rad), torques (N m).
    Joint,
    /// End-point positions (m), forces (N).
    Endpoint,
}

/// The limits of a periodic protocol, by the presets' names.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeriodicLimits {
    /// Joint: largest displacement from the posture (rad).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_joint_displacement_rad: Option<f64>,
    /// Joint: largest velocity (rad/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_joint_velocity_rad_s: Option<f64>,
    /// Joint: largest acceleration (rad/s²).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_joint_acceleration_rad_s2: Option<f64>,
    /// Joint: largest torque the nominal stiffness would need (N m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_torque_nm: Option<f64>,
    /// Joint: nominal stiffness (N m/rad).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nominal_joint_stiffness_nm_per_rad: Option<f64>,
    /// End point: largest displacement (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_displacement_m: Option<f64>,
    /// End point: largest velocity (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_velocity_m_s: Option<f64>,
    /// End point: largest acceleration (m/s²).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_acceleration_m_s2: Option<f64>,
    /// End point: largest force the nominal stiffness would need (N).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_force_n: Option<f64>,
    /// End point: nominal stiffness (N/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nominal_stiffness_n_per_m: Option<f64>,
}

/// The limits in the protocol's coordinates: displacement, velocity,
/// acceleration, force or torque, nominal stiffness.
#[derive(Debug, Clone, Copy)]
struct Limits {
    displacement: f64,
    velocity: f64,
    acceleration: f64,
    force: f64,
    stiffness: f64,
}

/// The signal of a periodic protocol.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Signal {
    /// A multisine.
    Multisine(MultisineSignal),
    /// A pseudo-random binary sequence.
    Prbs(PrbsSignal),
}

/// A multisine's fields.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MultisineSignal {
    /// Period (s); the frequency resolution is 1 / period.
    pub period_s: f64,
    /// Band (Hz): every line of the set inside it is excited.
    pub band_hz: [f64; 2],
    /// RMS per channel over one period (rad or m).
    pub rms: Vec<f64>,
    /// `full`, `odd` or `random-odd`.
    #[serde(default = "default_lines")]
    pub lines: String,
    /// `optimised`, `schroeder` or `random`.
    #[serde(default = "default_phases")]
    pub phases: String,
    /// Amplitude across the lines: `flat` (the default), `1/f` (equal
    /// velocity at every line) or `1/f^2` (equal acceleration).
    #[serde(default = "default_shape", skip_serializing_if = "is_flat")]
    pub amplitude_shape: String,
    /// Relative amplitudes at frequencies, `[[hz, amplitude], ...]` in
    /// increasing frequency, interpolated linearly in log-log between them
    /// and held beyond the first and last: a spectrum given point by point
    /// (one point per line gives every line its own); replaces the shape.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub amplitude_points: Vec<[f64; 2]>,
}

/// A name a recording's column can have: a letter, then letters, digits and `_`.
fn is_column_name(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

fn default_shape() -> String {
    "flat".into()
}

fn is_flat(shape: &str) -> bool {
    shape == "flat"
}

impl MultisineSignal {
    /// A flat random-odd multisine with optimised phases (the presets').
    pub fn random_odd(period_s: f64, band_hz: [f64; 2], rms: Vec<f64>) -> Self {
        MultisineSignal {
            period_s,
            band_hz,
            rms,
            lines: "random-odd".into(),
            phases: default_phases(),
            amplitude_shape: default_shape(),
            amplitude_points: Vec::new(),
        }
    }

    /// The relative amplitudes of `lines` (indices of 1 / period), the
    /// largest 1: points of 1e155 or 1e-170 overflowed or underflowed the
    /// RMS into an all-zero or infinite command (issue 76).
    pub fn line_amplitudes(&self, lines: &[usize]) -> Vec<f64> {
        let raw: Vec<f64> = lines
            .iter()
            .map(|&k| self.relative_amplitude(k as f64 / self.period_s))
            .collect();
        let top = raw.iter().copied().fold(0.0f64, f64::max);
        raw.iter().map(|a| a / top).collect()
    }

    /// The relative amplitude of a line at `hz` (the points, else the shape).
    pub fn relative_amplitude(&self, hz: f64) -> f64 {
        let p = &self.amplitude_points;
        if let (Some(first), Some(last)) = (p.first(), p.last()) {
            if hz <= first[0] {
                return first[1];
            }
            if hz >= last[0] {
                return last[1];
            }
            let k = p.iter().position(|q| q[0] > hz).unwrap_or(p.len() - 1);
            let (a, b) = (p[k - 1], p[k]);
            let t = (hz / a[0]).ln() / (b[0] / a[0]).ln();
            return (a[1].ln() + t * (b[1] / a[1]).ln()).exp();
        }
        match self.amplitude_shape.as_str() {
            "1/f" => 1.0 / hz,
            "1/f^2" => 1.0 / (hz * hz),
            _ => 1.0,
        }
    }
}

fn default_lines() -> String {
    "full".into()
}
fn default_phases() -> String {
    "optimised".into()
}

/// A PRBS's fields.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrbsSignal {
    /// Register order: the period is 2^order - 1 switching intervals
    /// (ternary: 3^order - 1).
    pub order: usize,
    /// A pseudo-random ternary sequence (levels -amplitude, 0, +amplitude)
    /// instead of a binary one: its second half-period is the first
    /// inverted, so it excites the odd lines of its period only and the
    /// even lines show even nonlinear distortion.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub ternary: bool,
    /// Switching interval (s).
    pub switch_interval_s: f64,
    /// Half-swing per channel (rad or m).
    pub amplitude: Vec<f64>,
    /// Raised-cosine edge length (s); default the shortest within the limits.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edge_s: Option<f64>,
}

impl PrbsSignal {
    /// Switching intervals in a period: 2^order - 1, or 3^order - 1 for a
    /// ternary sequence (orders beyond the generators' saturate; `validate` refuses them).
    pub fn chips(&self) -> usize {
        if self.ternary {
            3usize.pow(self.order.min(*PRTS_ORDERS.end()) as u32) - 1
        } else {
            (1usize << self.order.min(24)) - 1
        }
    }
}

/// A periodic protocol.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PeriodicDesign {
    /// Protocol name.
    pub name: String,
    /// Joint or end point.
    pub coordinates: Coordinates,
    /// Column names of the commanded coordinates.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<String>,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Periods recorded after the transient period.
    pub periods: usize,
    /// Seed of random choices (random-odd lines, random phases).
    #[serde(default)]
    pub seed: u64,
    /// The signal.
    #[serde(flatten)]
    pub signal: Signal,
    /// Safety limits.
    pub limits: PeriodicLimits,
}

/// The commanded coordinates of a periodic protocol, sample by sample.
#[derive(Debug, Clone)]
pub struct Command {
    /// Column names.
    pub channels: Vec<String>,
    /// Time (s) from the first sample.
    pub t: Vec<f64>,
    /// Displacement from the posture per channel.
    pub values: Vec<Vec<f64>>,
    /// Period index per sample: -1 for the fade-in and fade-out periods.
    pub period: Vec<i64>,
    /// Samples per period.
    pub period_samples: usize,
}

/// What `check` found in a periodic protocol, per channel.
#[derive(Debug, Clone, Serialize)]
pub struct PeriodicReport {
    /// Samples of the whole command (fade-in, periods, fade-out).
    pub samples: usize,
    /// Its duration (s).
    pub duration_s: f64,
    /// Period (s).
    pub period_s: f64,
    /// Peak displacement per channel.
    pub peak_displacement: Vec<f64>,
    /// Peak velocity per channel.
    pub peak_velocity: Vec<f64>,
    /// Peak acceleration per channel.
    pub peak_acceleration: Vec<f64>,
    /// Peak force or torque the nominal stiffness would need, per channel.
    pub peak_force: Vec<f64>,
    /// Crest factor of one period, per channel.
    pub crest_factor: Vec<f64>,
    /// Excited lines of one period, per channel.
    pub excited_lines: Vec<usize>,
    /// Lines between the lowest and highest excited line that no channel excites (detection lines).
    pub detection_lines: usize,
    /// Largest coherence between two channels at any line either excites (0 for zippered multisines).
    pub max_input_coherence: f64,
}

impl PeriodicDesign {
    /// A flat random-odd multisine on the ankle (0.5-20 Hz, 10 s period, 0.01 rad RMS).
    pub fn multisine_joint() -> Self {
        PeriodicDesign {
            name: "random-odd multisine, 0.5-20 Hz, 10 s period, on the ankle".into(),
            coordinates: Coordinates::Joint,
            channels: vec!["q1".into()],
            sample_rate_hz: 1000.0,
            periods: 6,
            seed: 1,
            signal: Signal::Multisine(MultisineSignal::random_odd(10.0, [0.5, 20.0], vec![0.01])),
            limits: joint_limits(),
        }
    }

    /// REKLAB's ankle PRBS: 0.03 rad, 150 ms switching, order 7 (19 s period).
    pub fn prbs_joint() -> Self {
        PeriodicDesign {
            name: "PRBS 0.03 rad, 150 ms switching, order 7, on the ankle".into(),
            coordinates: Coordinates::Joint,
            channels: vec!["q1".into()],
            sample_rate_hz: 1000.0,
            periods: 3,
            seed: 1,
            signal: Signal::Prbs(PrbsSignal {
                order: 7,
                switch_interval_s: 0.15,
                amplitude: vec![0.03],
                ternary: false,
                edge_s: None,
            }),
            limits: joint_limits(),
        }
    }

    /// A zippered random-odd multisine on the 3-D end point (x, y, z; 0.2-6
    /// Hz, 20 s period, 2 mm RMS each), with the centre-out preset's limits
    /// but for velocity (0.2 m/s) and acceleration (5 m/s²): inertia needs
    /// the hand accelerated.
    pub fn multisine_endpoint() -> Self {
        PeriodicDesign {
            name: "zippered random-odd multisine, 0.2-6 Hz, 20 s period, at the end point".into(),
            coordinates: Coordinates::Endpoint,
            channels: vec!["x".into(), "y".into(), "z".into()],
            sample_rate_hz: 500.0,
            periods: 6,
            seed: 1,
            signal: Signal::Multisine(MultisineSignal::random_odd(
                20.0,
                [0.2, 6.0],
                vec![0.002; 3],
            )),
            limits: PeriodicLimits {
                max_displacement_m: Some(0.02),
                max_velocity_m_s: Some(0.2),
                max_acceleration_m_s2: Some(5.0),
                max_force_n: Some(60.0),
                nominal_stiffness_n_per_m: Some(1000.0),
                ..PeriodicLimits::default()
            },
        }
    }

    /// A zippered random-odd multisine on the planar arm's two joints (q1,
    /// q2; 0.5-10 Hz, 10 s period, 0.01 rad RMS each).
    pub fn multisine_planar() -> Self {
        PeriodicDesign {
            name: "zippered random-odd multisine, 0.5-10 Hz, 10 s period, on the planar arm".into(),
            coordinates: Coordinates::Joint,
            channels: vec!["q1".into(), "q2".into()],
            sample_rate_hz: 1000.0,
            periods: 6,
            seed: 1,
            signal: Signal::Multisine(MultisineSignal::random_odd(
                10.0,
                [0.5, 10.0],
                vec![0.01; 2],
            )),
            limits: joint_limits(),
        }
    }

    /// The column names (the given ones, else `q1` or `x, y, z` for as many channels as amplitudes).
    pub fn channel_names(&self) -> Vec<String> {
        if !self.channels.is_empty() {
            return self.channels.clone();
        }
        let count = match &self.signal {
            Signal::Multisine(m) => m.rms.len(),
            Signal::Prbs(p) => p.amplitude.len(),
        };
        let names: &[&str] = match self.coordinates {
            Coordinates::Joint => &["q1", "q2", "q3"],
            Coordinates::Endpoint => &["x", "y", "z"],
        };
        names.iter().take(count).map(|s| s.to_string()).collect()
    }

    /// Samples per period.
    pub fn period_samples(&self) -> usize {
        let period_s = match &self.signal {
            Signal::Multisine(m) => m.period_s,
            Signal::Prbs(p) => p.switch_interval_s * p.chips() as f64,
        };
        (period_s * self.sample_rate_hz).round() as usize
    }

    fn limits(&self) -> std::result::Result<Limits, String> {
        let l = &self.limits;
        let need = |v: Option<f64>, name: &str| -> std::result::Result<f64, String> {
            match v {
                Some(v) if v.is_finite() && v > 0.0 => Ok(v),
                Some(v) => Err(format!(
                    "limits.{name}: expected a positive number, found {}",
                    limpid_core::error::Num(v)
                )),
                None => Err(format!("limits.{name} is missing")),
            }
        };
        Ok(match self.coordinates {
            Coordinates::Joint => Limits {
                displacement: need(l.max_joint_displacement_rad, "max_joint_displacement_rad")?,
                velocity: need(l.max_joint_velocity_rad_s, "max_joint_velocity_rad_s")?,
                acceleration: need(
                    l.max_joint_acceleration_rad_s2,
                    "max_joint_acceleration_rad_s2",
                )?,
                force: need(l.max_torque_nm, "max_torque_nm")?,
                stiffness: need(
                    l.nominal_joint_stiffness_nm_per_rad,
                    "nominal_joint_stiffness_nm_per_rad",
                )?,
            },
            Coordinates::Endpoint => Limits {
                displacement: need(l.max_displacement_m, "max_displacement_m")?,
                velocity: need(l.max_velocity_m_s, "max_velocity_m_s")?,
                acceleration: need(l.max_acceleration_m_s2, "max_acceleration_m_s2")?,
                force: need(l.max_force_n, "max_force_n")?,
                stiffness: need(l.nominal_stiffness_n_per_m, "nominal_stiffness_n_per_m")?,
            },
        })
    }

    /// Refuse fields that cannot make a signal (before any sample is made).
    pub fn validate(&self) -> std::result::Result<(), String> {
        let fs = self.sample_rate_hz;
        if !(fs.is_finite() && fs > 0.0 && fs <= 1e6) {
            return Err(format!(
                "sample_rate_hz: expected 0 to 1e6 Hz, found {}",
                limpid_core::error::Num(fs)
            ));
        }
        if !(1..=1000).contains(&self.periods) {
            return Err(format!(
                "periods: expected 1 to 1000, found {}",
                self.periods
            ));
        }
        self.limits()?;
        let channels = self.channel_names();
        let count = match &self.signal {
            Signal::Multisine(m) => m.rms.len(),
            Signal::Prbs(p) => p.amplitude.len(),
        };
        if let Some(bad) = channels.iter().find(|c| !is_column_name(c)) {
            return Err(format!(
                "channels: {bad:?} is not a column name (letters, digits and _, starting with a letter)"
            ));
        }
        if let Some((i, c)) = channels
            .iter()
            .enumerate()
            .find(|(i, c)| channels[..*i].contains(c))
        {
            return Err(format!(
                "channels: {c:?} is named twice (channel {})",
                i + 1
            ));
        }
        if count == 0 || count > 3 || channels.len() != count {
            return Err(format!(
                "expected 1 to 3 channels with one {} each, found {count} for channels [{}]",
                match self.signal {
                    Signal::Multisine(_) => "rms",
                    Signal::Prbs(_) => "amplitude",
                },
                channels.join(", ")
            ));
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        match &self.signal {
            Signal::Multisine(m) => {
                if !positive(m.period_s) || m.period_s * fs > 1e7 {
                    return Err(
                        "period_s: expected a positive period of at most 1e7 samples".into(),
                    );
                }
                if ((m.period_s * fs) - (m.period_s * fs).round()).abs() > 1e-6 {
                    return Err(format!(
                        "period_s: {} s at {} Hz is not a whole number of samples",
                        limpid_core::error::Num(m.period_s),
                        limpid_core::error::Num(fs)
                    ));
                }
                if m.band_hz[1] >= 0.5 * fs {
                    return Err("band_hz: the band must lie below half the sample rate".into());
                }
                if !m.rms.iter().all(|v| positive(*v)) {
                    return Err("rms: expected positive values".into());
                }
                LineSet::parse(&m.lines).map_err(|e| e.to_string())?;
                if !matches!(m.amplitude_shape.as_str(), "flat" | "1/f" | "1/f^2") {
                    return Err(format!(
                        "amplitude_shape: expected flat, 1/f or 1/f^2, found {:?}",
                        m.amplitude_shape
                    ));
                }
                let p = &m.amplitude_points;
                if p.iter().any(|q| !(positive(q[0]) && positive(q[1])))
                    || p.windows(2).any(|w| w[1][0] <= w[0][0])
                {
                    return Err(
                        "amplitude_points: expected [hz, amplitude] pairs of positive numbers in increasing frequency".into(),
                    );
                }
                let (low, high) = p.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), q| {
                    (lo.min(q[1]), hi.max(q[1]))
                });
                if !p.is_empty() && high / low > 1e6 {
                    return Err(format!(
                        "amplitude_points: the amplitudes span {} to {}, more than 10^6 (the weakest lines would be below the command's resolution)",
                        limpid_core::error::Num(low),
                        limpid_core::error::Num(high)
                    ));
                }
                if !matches!(m.phases.as_str(), "optimised" | "schroeder" | "random") {
                    return Err(format!(
                        "phases: expected optimised, schroeder or random, found {:?}",
                        m.phases
                    ));
                }
                multisine_lines(m.period_s, m.band_hz, LineSet::Full, 0)
                    .map_err(|e| e.to_string())?;
            }
            Signal::Prbs(p) => {
                let orders = if p.ternary { PRTS_ORDERS } else { 2..=16 };
                if !orders.contains(&p.order) {
                    return Err(format!(
                        "order: expected {} to {}{}, found {}",
                        orders.start(),
                        orders.end(),
                        if p.ternary {
                            " for a ternary sequence"
                        } else {
                            ""
                        },
                        p.order
                    ));
                }
                let chip = p.switch_interval_s * fs;
                if !positive(p.switch_interval_s)
                    || (chip - chip.round()).abs() > 1e-6
                    || chip.round() < 2.0
                {
                    return Err(format!(
                        "switch_interval_s: expected a whole number (at least 2) of samples at {} Hz, found {} s",
                        limpid_core::error::Num(fs),
                        limpid_core::error::Num(p.switch_interval_s)
                    ));
                }
                if !p.amplitude.iter().all(|v| positive(*v)) {
                    return Err("amplitude: expected positive values".into());
                }
                if let Some(e) = p.edge_s {
                    if !(e.is_finite() && e >= 0.0 && e <= p.switch_interval_s) {
                        return Err("edge_s: expected 0 to switch_interval_s".into());
                    }
                }
            }
        }
        let samples = self.period_samples() * (self.periods + 2) * count;
        crate::validate::check_size(samples as f64, "periods x period x channels")
            .map_err(|e| e.to_string())?;
        Ok(())
    }

    /// One period per channel (displacement from the posture).
    fn one_period(&self) -> Result<Vec<Vec<f64>>> {
        let n = self.period_samples();
        match &self.signal {
            Signal::Multisine(m) => {
                let set = LineSet::parse(&m.lines)?;
                let lines = multisine_lines(m.period_s, m.band_hz, set, self.seed)?;
                let channels = m.rms.len();
                Ok((0..channels)
                    .map(|c| {
                        // zippered: channel c takes every channels-th line from the c-th
                        let own: Vec<usize> =
                            lines.iter().copied().skip(c).step_by(channels).collect();
                        let amplitudes = m.line_amplitudes(&own);
                        let phases = match m.phases.as_str() {
                            "schroeder" => schroeder_phases_for(&amplitudes),
                            "random" => random_phases(own.len(), self.seed.wrapping_add(c as u64)),
                            _ => optimise_phases(n, &own, &amplitudes),
                        };
                        let x = multisine(n, &own, &amplitudes, &phases);
                        let rms = (x.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
                        x.iter().map(|v| v * m.rms[c] / rms).collect()
                    })
                    .collect())
            }
            Signal::Prbs(p) => {
                let chips = if p.ternary {
                    prts(p.order)?
                } else {
                    mls(p.order)?
                };
                let chip = (p.switch_interval_s * self.sample_rate_hz).round() as usize;
                let edge = self.prbs_edge_samples(p)?;
                Ok(p.amplitude
                    .iter()
                    .enumerate()
                    .map(|(c, &a)| {
                        let shift = c * chips.len() / 3;
                        let level = |j: usize| a * chips[(j + shift) % chips.len()];
                        (0..n)
                            .map(|i| {
                                let j = i / chip;
                                if edge == 0 {
                                    return level(j);
                                }
                                // a raised-cosine ramp centred on each switching instant:
                                // the chip whose end this sample's ramp starts at, and
                                // the sample's place in that ramp (0 to 1)
                                let half = edge as f64 / 2.0;
                                let offset = (i % chip) as f64;
                                let (before, s) = if offset < half {
                                    (j + chips.len() - 1, (offset + half) / edge as f64)
                                } else if (chip as f64 - offset) <= half {
                                    (j, (offset - (chip as f64 - half)) / edge as f64)
                                } else {
                                    return level(j);
                                };
                                let (from, to) = (
                                    level(before % chips.len()),
                                    level((before + 1) % chips.len()),
                                );
                                let w = 0.5 - 0.5 * (PI * s.clamp(0.0, 1.0)).cos();
                                from + (to - from) * w
                            })
                            .collect()
                    })
                    .collect())
            }
        }
    }

    /// A multisine whose RMS displacement, velocity, acceleration or force
    /// (from its lines' amplitudes, before any phase is chosen) exceeds a
    /// limit cannot pass, whatever the phases: refused before the phase
    /// optimisation (a period of 10^4 s optimised for 518 s, then was
    /// refused; issue 76). A peak is at least the RMS.
    fn rms_within_limits(&self) -> Result<()> {
        let Signal::Multisine(m) = &self.signal else {
            return Ok(());
        };
        let l = self.limits().map_err(|e| Error::invalid("limits", e))?;
        let set = LineSet::parse(&m.lines)?;
        let lines = multisine_lines(m.period_s, m.band_hz, set, self.seed)?;
        let names = self.channel_names();
        let channels = m.rms.len();
        for (c, name) in names.iter().enumerate().take(channels) {
            let own: Vec<usize> = lines.iter().copied().skip(c).step_by(channels).collect();
            let a = m.line_amplitudes(&own);
            // the gain of the sampled derivative `check` takes, at most 2πf
            let n = self.period_samples() as f64;
            let fs = self.sample_rate_hz;
            let power = |order: i32| -> f64 {
                own.iter()
                    .zip(&a)
                    .map(|(&k, &a)| a * a * (2.0 * fs * (PI * k as f64 / n).sin()).powi(2 * order))
                    .sum()
            };
            let total = power(0);
            if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                continue;
            }
            let rms = m.rms[c];
            for (what, value, limit) in [
                ("displacement", rms, l.displacement),
                ("velocity", rms * (power(1) / total).sqrt(), l.velocity),
                (
                    "acceleration",
                    rms * (power(2) / total).sqrt(),
                    l.acceleration,
                ),
                (
                    "force or torque (nominal stiffness x displacement)",
                    l.stiffness * rms,
                    l.force,
                ),
            ] {
                if value > limit {
                    return Err(Error::invalid(
                        "protocol",
                        format!(
                            "channel {name}: its RMS {what} {} already exceeds the limit {} (a peak is at least the RMS): lower rms or the band",
                            limpid_core::error::Num(value),
                            limpid_core::error::Num(limit)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The ramp length of a PRBS edge in samples: the given one, else the
    /// shortest whose peak velocity (π Δ / 2T) and acceleration (π² Δ / 2T²),
    /// for a step Δ of twice the amplitude, are within the limits.
    fn prbs_edge_samples(&self, p: &PrbsSignal) -> Result<usize> {
        let fs = self.sample_rate_hz;
        if let Some(e) = p.edge_s {
            return Ok((e * fs).round() as usize);
        }
        let l = self.limits().map_err(|m| Error::invalid("limits", m))?;
        let step = 2.0 * p.amplitude.iter().fold(0.0f64, |m, a| m.max(*a));
        let t_velocity = PI * step / (2.0 * l.velocity);
        let t_acceleration = (PI * PI * step / (2.0 * l.acceleration)).sqrt();
        // one sample more than the continuous bound, for the sampled derivatives
        Ok(((t_velocity.max(t_acceleration) * fs).ceil() as usize + 1).max(1))
    }

    /// The whole command: a fade-in period, `periods` periods, a fade-out
    /// period (period index -1 for both), each channel's displacement from the posture.
    pub fn command(&self) -> Result<Command> {
        self.validate().map_err(|m| Error::invalid("protocol", m))?;
        let n = self.period_samples();
        let one = self.one_period()?;
        let total = n * (self.periods + 2);
        let fs = self.sample_rate_hz;
        // a raised cosine over the first and last periods: the robot starts and ends at rest
        let envelope = |i: usize| -> f64 {
            if i < n {
                0.5 - 0.5 * (PI * i as f64 / n as f64).cos()
            } else if i >= n * (self.periods + 1) {
                let k = (total - 1 - i) as f64;
                0.5 - 0.5 * (PI * k / n as f64).cos()
            } else {
                1.0
            }
        };
        let values = one
            .iter()
            .map(|x| (0..total).map(|i| envelope(i) * x[i % n]).collect())
            .collect();
        let period = (0..total)
            .map(|i| {
                if i < n || i >= n * (self.periods + 1) {
                    -1
                } else {
                    (i / n - 1) as i64
                }
            })
            .collect();
        Ok(Command {
            channels: self.channel_names(),
            t: (0..total).map(|i| i as f64 / fs).collect(),
            values,
            period,
            period_samples: n,
        })
    }

    /// Every sample against every limit, and what the signal excites.
    pub fn check(&self) -> Result<PeriodicReport> {
        self.validate().map_err(|m| Error::invalid("protocol", m))?;
        self.rms_within_limits()?;
        let command = self.command()?;
        let l = self.limits().map_err(|m| Error::invalid("limits", m))?;
        let fs = self.sample_rate_hz;
        let n = command.period_samples;
        let peak = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let derivative =
            |x: &[f64]| -> Vec<f64> { x.windows(2).map(|w| (w[1] - w[0]) * fs).collect() };
        let mut report = PeriodicReport {
            samples: command.t.len(),
            duration_s: command.t.len() as f64 / fs,
            period_s: n as f64 / fs,
            peak_displacement: Vec::new(),
            peak_velocity: Vec::new(),
            peak_acceleration: Vec::new(),
            peak_force: Vec::new(),
            crest_factor: Vec::new(),
            excited_lines: Vec::new(),
            detection_lines: 0,
            max_input_coherence: 0.0,
        };
        let (unit, force_unit) = match self.coordinates {
            Coordinates::Joint => ("rad", "N m"),
            Coordinates::Endpoint => ("m", "N"),
        };
        let mut spectra = Vec::new();
        for (name, x) in command.channels.iter().zip(&command.values) {
            let v = derivative(x);
            let a = derivative(&v);
            let (pd, pv, pa) = (peak(x), peak(&v), peak(&a));
            let pf = l.stiffness * pd;
            for (what, value, limit, u) in [
                ("displacement", pd, l.displacement, unit.to_string()),
                ("velocity", pv, l.velocity, format!("{unit}/s")),
                ("acceleration", pa, l.acceleration, format!("{unit}/s²")),
                (
                    "force or torque (nominal stiffness x displacement)",
                    pf,
                    l.force,
                    force_unit.to_string(),
                ),
            ] {
                if value > limit {
                    return Err(Error::invalid(
                        "protocol",
                        format!(
                            "channel {name}: peak {what} {} {u} exceeds the limit {} {u}",
                            limpid_core::error::Num(value),
                            limpid_core::error::Num(limit)
                        ),
                    ));
                }
            }
            report.peak_displacement.push(pd);
            report.peak_velocity.push(pv);
            report.peak_acceleration.push(pa);
            report.peak_force.push(pf);
            let period = &x[n..2 * n];
            report.crest_factor.push(crest_factor(period));
            spectra.push(period_spectrum(period));
        }
        let lines = n / 2 + 1;
        let excited: Vec<Vec<bool>> = spectra
            .iter()
            .map(|s| {
                let top = s
                    .iter()
                    .skip(1)
                    .map(|c| c.norm_sqr())
                    .fold(0.0f64, f64::max);
                s.iter()
                    .enumerate()
                    .map(|(k, c)| k > 0 && c.norm_sqr() > 1e-3 * top)
                    .collect()
            })
            .collect();
        report.excited_lines = excited
            .iter()
            .map(|e| e.iter().filter(|x| **x).count())
            .collect();
        let any = |k: usize| excited.iter().any(|e| e[k]);
        if let (Some(first), Some(last)) = (
            (0..lines).find(|&k| any(k)),
            (0..lines).rev().find(|&k| any(k)),
        ) {
            report.detection_lines = (first..=last).filter(|&k| !any(k)).count();
        }
        for i in 0..spectra.len() {
            for j in i + 1..spectra.len() {
                for k in 1..lines {
                    if excited[i][k] || excited[j][k] {
                        let (a, b) = (spectra[i][k], spectra[j][k]);
                        let denominator = a.norm_sqr() * b.norm_sqr();
                        // a line only one channel excites carries the other's rounding only
                        if excited[i][k] && excited[j][k] && denominator > 0.0 {
                            let c = (a * b.conj()).norm_sqr() / denominator;
                            report.max_input_coherence = report.max_input_coherence.max(c);
                        }
                    }
                }
            }
        }
        Ok(report)
    }
}

/// The planar preset's joint limits, for an ankle-sized joint.
fn joint_limits() -> PeriodicLimits {
    PeriodicLimits {
        max_joint_displacement_rad: Some(0.1),
        max_joint_velocity_rad_s: Some(2.0),
        max_joint_acceleration_rad_s2: Some(200.0),
        max_torque_nm: Some(20.0),
        nominal_joint_stiffness_nm_per_rad: Some(100.0),
        ..PeriodicLimits::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_multisine_preset_is_periodic_within_limits_and_fades() {
        let d = PeriodicDesign::multisine_joint();
        let c = d.command().unwrap();
        let n = c.period_samples;
        assert_eq!(n, 10_000);
        let x = &c.values[0];
        assert_eq!(x.len(), n * 8);
        assert_eq!(x[0], 0.0);
        assert!(x.last().unwrap().abs() < 1e-6);
        // whole periods repeat exactly
        assert!((0..n).all(|i| (x[n + i] - x[2 * n + i]).abs() < 1e-12));
        assert_eq!(c.period[n - 1], -1);
        assert_eq!(c.period[n], 0);
        assert_eq!(*c.period.last().unwrap(), -1);
        let r = d.check().unwrap();
        assert!(r.crest_factor[0] < 1.6, "{:?}", r.crest_factor);
        assert!(r.detection_lines > 50, "{}", r.detection_lines);
    }

    #[test]
    fn the_prbs_preset_switches_on_its_grid_as_a_maximum_length_sequence() {
        let d = PeriodicDesign::prbs_joint();
        let c = d.command().unwrap();
        let n = c.period_samples;
        assert_eq!(n, 127 * 150);
        let x = &c.values[0][n..2 * n];
        // mid-chip levels are ± amplitude in the MLS order
        let levels: Vec<f64> = (0..127).map(|j| x[j * 150 + 75].signum()).collect();
        let sequence = mls(7).unwrap();
        assert_eq!(levels, sequence);
        assert!(d.check().is_ok());
        // a tighter velocity limit is refused naming the channel and the limit
        let mut tight = d.clone();
        tight.limits.max_joint_velocity_rad_s = Some(0.5);
        if let Signal::Prbs(p) = &mut tight.signal {
            p.edge_s = Some(0.01);
        }
        let e = tight.check().unwrap_err().to_string();
        assert!(e.contains("channel q1: peak velocity"), "{e}");
    }

    #[test]
    fn a_ternary_sequence_switches_among_three_levels_and_excites_odd_lines_only() {
        let mut d = PeriodicDesign::prbs_joint();
        if let Signal::Prbs(p) = &mut d.signal {
            (p.ternary, p.order, p.switch_interval_s) = (true, 4, 0.1);
        }
        let c = d.command().unwrap();
        let n = c.period_samples;
        assert_eq!(n, 80 * 100);
        let x = &c.values[0][n..2 * n];
        let levels: Vec<f64> = (0..80).map(|j| (x[j * 100 + 50] / 0.03).round()).collect();
        assert_eq!(levels, prts(4).unwrap());
        // the raised-cosine edges keep the inverse repeat: even lines empty
        let spectrum = period_spectrum(x);
        let peak = spectrum.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for k in (2..n / 2).step_by(2) {
            assert!(spectrum[k].norm() < 1e-9 * peak, "even line {k}");
        }
        let r = d.check().unwrap();
        assert!(r.detection_lines > 0, "{r:?}");
        // orders beyond the ternary generator are refused by name
        if let Signal::Prbs(p) = &mut d.signal {
            p.order = 13;
        }
        let e = d.check().unwrap_err().to_string();
        assert!(e.contains("2 to 12 for a ternary sequence"), "{e}");
    }

    #[test]
    fn a_shaped_multisine_has_its_amplitude_at_every_line() {
        let mut d = PeriodicDesign::multisine_joint();
        if let Signal::Multisine(m) = &mut d.signal {
            m.lines = "odd".into();
            m.amplitude_shape = "1/f".into();
        }
        let c = d.command().unwrap();
        let n = c.period_samples;
        let spectrum = period_spectrum(&c.values[0][n..2 * n]);
        // equal velocity: |X_k| k constant over the excited lines (0.5-20 Hz at 0.1 Hz)
        let velocity: Vec<f64> = (5..=200)
            .filter(|k| k % 2 == 1)
            .map(|k| spectrum[k].norm() * k as f64)
            .collect();
        let (lo, hi) = velocity
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), v| (a.min(*v), b.max(*v)));
        assert!(hi / lo - 1.0 < 1e-9, "{lo} .. {hi}");
        // points: 1 at 1 Hz to 0.25 at 4 Hz, log-log: 0.5 at 2 Hz, held beyond
        if let Signal::Multisine(m) = &mut d.signal {
            m.amplitude_points = vec![[1.0, 1.0], [4.0, 0.25]];
            assert!((m.relative_amplitude(2.0) - 0.5).abs() < 1e-12);
            assert_eq!(m.relative_amplitude(0.5), 1.0);
            assert_eq!(m.relative_amplitude(10.0), 0.25);
        }
        let c = d.command().unwrap();
        let spectrum = period_spectrum(&c.values[0][n..2 * n]);
        // line 5 (0.5 Hz) held at 1, line 41 (4.1 Hz) at 0.25, line 21 (2.1 Hz) at 1/2.1
        let ratio = |k: usize| spectrum[k].norm() / spectrum[5].norm();
        assert!((ratio(41) - 0.25).abs() < 1e-9, "{}", ratio(41));
        assert!((ratio(21) - 1.0 / 2.1).abs() < 1e-9, "{}", ratio(21));
        // bad shapes and points are refused by name
        for (shape, points) in [
            ("pink", vec![]),
            ("flat", vec![[2.0, 1.0], [1.0, 1.0]]),
            ("flat", vec![[1.0, -1.0]]),
        ] {
            if let Signal::Multisine(m) = &mut d.signal {
                m.amplitude_shape = shape.into();
                m.amplitude_points = points;
            }
            let e = d.check().unwrap_err().to_string();
            assert!(e.contains("amplitude_"), "{e}");
        }
    }

    #[test]
    fn zippered_channels_share_no_line() {
        let mut d = PeriodicDesign::multisine_joint();
        d.channels = vec!["q1".into(), "q2".into()];
        if let Signal::Multisine(m) = &mut d.signal {
            m.rms = vec![0.008, 0.008];
        }
        let r = d.check().unwrap();
        assert_eq!(r.max_input_coherence, 0.0);
        assert_eq!(r.excited_lines.len(), 2);
    }
}
