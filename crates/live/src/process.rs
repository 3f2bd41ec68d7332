//! Per-sample processing of the live stream: seed 001's co-contraction index
//! with the causal envelope (rectify, 2nd-order Butterworth 8 Hz, one causal
//! pass, divided by the MVC maximum; mean over muscles — the same chain as
//! `limpid_analysis::emg` with `causal = true`, so live and offline agree to
//! rounding), live MVC capture, and the online impedance
//! (`limpid_ident::online`: M, B, K per completed perturbation), restarted
//! when the co-contraction level changes.

use limpid_analysis::emg::EmgParams;
use limpid_core::{Error, Result};
use limpid_dsp::{LowPass, StreamingFilter};

pub use limpid_ident::online::{OnlineEstimate, OnlineImpedance, OnlineSettings, OnlineState};

/// A level change: the index averaged over [`LEVEL_AVERAGE_S`] differs from
/// the level's mean by more than this (fraction of MVC) for [`LEVEL_HOLD_S`].
pub const LEVEL_STEP: f64 = 0.1;
/// Averaging time of the index for level-change detection (s).
pub const LEVEL_AVERAGE_S: f64 = 0.2;
/// How long the change must last (s).
pub const LEVEL_HOLD_S: f64 = 0.2;

/// The online stiffness of one co-contraction level, kept when the level changes.
#[derive(Debug, Clone)]
pub struct LevelStiffness {
    /// Mean co-contraction index over the level (fraction of MVC).
    pub index: f64,
    /// The last estimate of the level.
    pub estimate: OnlineEstimate,
}

/// The live state machine: envelopes, index, MVC capture, level tracking, online impedance.
#[derive(Debug, Clone)]
pub struct Processor {
    filters: Vec<StreamingFilter>,
    maxima: Option<Vec<f64>>,
    capture: Option<Vec<f64>>,
    /// Envelope per muscle (V) and normalised activation (fraction of MVC).
    pub envelopes: Vec<f64>,
    /// Normalised activation per muscle (fraction of MVC).
    pub activations: Vec<f64>,
    /// Co-contraction index (fraction of MVC); NaN until an MVC is known.
    pub index: f64,
    /// The index averaged for display (exponential, 1 s time constant): what
    /// the bar shows, since the raw 8 Hz envelope flickers at display rate.
    pub index_display: f64,
    display_weight: f64,
    /// The online impedance of the current level.
    pub online: OnlineImpedance,
    /// Earlier levels' last estimates (most recent last, at most 32).
    pub history: Vec<LevelStiffness>,
    /// Level changes seen.
    pub level_changes: u64,
    level_sum: f64,
    level_n: f64,
    index_fast: f64,
    fast_weight: f64,
    away_samples: usize,
    away_since: u64,
    hold_samples: usize,
}

impl Processor {
    /// `channels` EMG channels at `fs`; `maxima` from an MVC recording (or None: capture live).
    pub fn new(channels: usize, fs: f64, maxima: Option<Vec<f64>>) -> Result<Self> {
        if channels == 0 {
            return Err(Error::invalid("channels", "at least one EMG channel"));
        }
        if let Some(m) = &maxima {
            if m.len() != channels {
                return Err(Error::invalid(
                    "MVC",
                    format!("{} maxima for {channels} channels", m.len()),
                ));
            }
        }
        let p = EmgParams::default();
        let lp = LowPass::butterworth(p.order, p.cutoff_hz, fs)?;
        Ok(Processor {
            filters: vec![lp.streaming(); channels],
            maxima,
            capture: None,
            envelopes: vec![0.0; channels],
            activations: vec![0.0; channels],
            index: f64::NAN,
            index_display: f64::NAN,
            display_weight: 1.0 / fs,
            online: OnlineImpedance::new(OnlineSettings::new(fs))?,
            history: Vec::new(),
            level_changes: 0,
            level_sum: 0.0,
            level_n: 0.0,
            index_fast: f64::NAN,
            fast_weight: 1.0 / (LEVEL_AVERAGE_S * fs).max(1.0),
            away_samples: 0,
            away_since: 0,
            hold_samples: ((LEVEL_HOLD_S * fs).round() as usize).max(1),
        })
    }

    /// One sample.
    #[inline]
    pub fn update(&mut self, emg: &[f64], kinematics: Option<&[f64; 6]>) {
        for ((f, e), raw) in self
            .filters
            .iter_mut()
            .zip(self.envelopes.iter_mut())
            .zip(emg)
        {
            *e = f.step(raw.abs());
        }
        if let Some(c) = &mut self.capture {
            for (m, e) in c.iter_mut().zip(&self.envelopes) {
                *m = m.max(*e);
            }
        }
        if let Some(max) = &self.maxima {
            let mut sum = 0.0;
            for ((a, e), m) in self.activations.iter_mut().zip(&self.envelopes).zip(max) {
                *a = e / m;
                sum += *a;
            }
            self.index = sum / self.activations.len() as f64;
            self.index_display = if self.index_display.is_finite() {
                self.index_display + self.display_weight * (self.index - self.index_display)
            } else {
                self.index
            };
        }
        if self.index.is_finite() {
            self.track_level();
        }
        if let Some(k) = kinematics {
            self.online.update([k[0], k[1], k[2]], [k[3], k[4], k[5]]);
        }
    }

    /// The mean index of the current level (fraction of MVC), once known.
    pub fn level_index(&self) -> Option<f64> {
        (self.level_n > 0.0).then(|| self.level_sum / self.level_n)
    }

    /// Restart the online impedance when the index leaves its level.
    fn track_level(&mut self) {
        self.index_fast = if self.index_fast.is_finite() {
            self.index_fast + self.fast_weight * (self.index - self.index_fast)
        } else {
            self.index
        };
        let mean = self.level_sum / self.level_n.max(1.0);
        let settled = self.level_n as usize >= self.hold_samples;
        if settled && (self.index_fast - mean).abs() > LEVEL_STEP {
            if self.away_samples == 0 {
                self.away_since = self.online.samples;
            }
            self.away_samples += 1;
        } else {
            self.away_samples = 0;
        }
        if self.away_samples >= self.hold_samples {
            if let Some(e) = self.online.estimate() {
                if self.history.len() == 32 {
                    self.history.remove(0);
                }
                self.history.push(LevelStiffness {
                    index: mean,
                    estimate: e.clone(),
                });
            }
            // the index crossed the step about one averaging time after the change
            let lag = (LEVEL_AVERAGE_S * self.online.settings().fs) as u64;
            self.online.reset_from(self.away_since.saturating_sub(lag));
            self.level_changes += 1;
            self.level_sum = 0.0;
            self.level_n = 0.0;
            self.away_samples = 0;
            return;
        }
        self.level_sum += self.index;
        self.level_n += 1.0;
    }

    /// Start capturing an MVC: the maxima of the envelopes from now on.
    pub fn start_capture(&mut self) {
        self.capture = Some(vec![0.0; self.filters.len()]);
    }

    /// Stop capturing and use the captured maxima; an error if a channel stayed at zero.
    pub fn stop_capture(&mut self) -> Result<()> {
        let c = self
            .capture
            .take()
            .ok_or_else(|| Error::invalid("MVC capture", "not capturing"))?;
        if c.iter().any(|m| *m <= 0.0) {
            return Err(Error::invalid("MVC capture", "a channel had no activity"));
        }
        self.maxima = Some(c);
        Ok(())
    }

    /// True while MVC maxima are being captured.
    pub fn capturing(&self) -> bool {
        self.capture.is_some()
    }

    /// True once MVC maxima are known.
    pub fn has_mvc(&self) -> bool {
        self.maxima.is_some()
    }
}
