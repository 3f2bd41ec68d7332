//! Per-sample processing of the live stream: seed 001's co-contraction index
//! with the causal envelope (rectify, 2nd-order Butterworth 8 Hz, one causal
//! pass, divided by the MVC maximum; mean over muscles — the same chain as
//! `limpid_analysis::emg` with `causal = true`, so live and offline agree to
//! rounding), live MVC capture, and an online stiffness estimate by
//! recursive least squares with forgetting on f = K (x - x_ref) + c.

use limpid_analysis::emg::EmgParams;
use limpid_core::{Error, Result};
use limpid_dsp::{LowPass, StreamingFilter};

pub use limpid_ident::online::Rls;

/// The live state machine: envelopes, index, MVC capture, RLS.
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
    /// The online stiffness estimate.
    pub rls: Rls,
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
            rls: Rls::new(0.9995),
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
        if let Some(k) = kinematics {
            self.rls.update([k[0], k[1], k[2]], [k[3], k[4], k[5]]);
        }
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
