//! Per-sample processing of the live stream: seed 001's co-contraction index
//! with the causal envelope (rectify, 2nd-order Butterworth 8 Hz, one causal
//! pass, divided by the MVC maximum; mean over muscles — the same chain as
//! `limpid_analysis::emg` with `causal = true`, so live and offline agree to
//! rounding), live MVC capture, and an online stiffness estimate by
//! recursive least squares with forgetting on f = K (x - x_ref) + c.

use limpid_analysis::emg::EmgParams;
use limpid_core::{Error, Result};
use limpid_dsp::{LowPass, StreamingFilter};

/// Recursive least squares with exponential forgetting, one regressor
/// [x - x_ref, y - y_ref, z - z_ref, 1] shared by the three force outputs.
#[derive(Debug, Clone)]
pub struct Rls {
    lambda: f64,
    theta: [[f64; 3]; 4],
    p: [[f64; 4]; 4],
    x_ref: Option<[f64; 3]>,
    /// Exponentially weighted a-priori error power and force variance per axis.
    err_power: [f64; 3],
    f_mean: [f64; 3],
    f_power: [f64; 3],
    pub updates: u64,
}

/// The covariance is not allowed to grow past this trace while nothing excites it.
const P_TRACE_CAP: f64 = 1e10;

impl Rls {
    /// Forgetting factor λ (memory of about 1 / (1 - λ) samples).
    pub fn new(lambda: f64) -> Self {
        let mut p = [[0.0; 4]; 4];
        for (i, row) in p.iter_mut().enumerate() {
            row[i] = if i < 3 { 1e8 } else { 1e4 };
        }
        Rls {
            lambda,
            theta: [[0.0; 3]; 4],
            p,
            x_ref: None,
            err_power: [0.0; 3],
            f_mean: [0.0; 3],
            f_power: [0.0; 3],
            updates: 0,
        }
    }

    /// One sample of position (m) and force on the limb (N).
    // index loops mirror the RLS equations on these 4 x 4 and 4 x 3 arrays
    #[allow(clippy::needless_range_loop)]
    #[inline]
    pub fn update(&mut self, x: [f64; 3], f: [f64; 3]) {
        let r = *self.x_ref.get_or_insert(x);
        let phi = [x[0] - r[0], x[1] - r[1], x[2] - r[2], 1.0];
        let mut p_phi = [0.0; 4];
        for i in 0..4 {
            p_phi[i] = (0..4).map(|j| self.p[i][j] * phi[j]).sum();
        }
        let denom = self.lambda + (0..4).map(|i| phi[i] * p_phi[i]).sum::<f64>();
        let gain = p_phi.map(|v| v / denom);
        let w = 1.0 - self.lambda;
        for o in 0..3 {
            let pred: f64 = (0..4).map(|i| self.theta[i][o] * phi[i]).sum();
            let e = f[o] - pred;
            for i in 0..4 {
                self.theta[i][o] += gain[i] * e;
            }
            self.err_power[o] += w * (e * e - self.err_power[o]);
            self.f_mean[o] += w * (f[o] - self.f_mean[o]);
            let d = f[o] - self.f_mean[o];
            self.f_power[o] += w * (d * d - self.f_power[o]);
        }
        let trace: f64 = (0..4).map(|i| self.p[i][i]).sum();
        let forget = if trace > P_TRACE_CAP {
            1.0
        } else {
            self.lambda
        };
        for i in 0..4 {
            for j in 0..4 {
                self.p[i][j] = (self.p[i][j] - gain[i] * p_phi[j]) / forget;
            }
        }
        self.updates += 1;
    }

    /// K (N/m): row = force axis, column = position axis.
    pub fn stiffness(&self) -> [[f64; 3]; 3] {
        let mut k = [[0.0; 3]; 3];
        for (o, row) in k.iter_mut().enumerate() {
            for (i, v) in row.iter_mut().enumerate() {
                *v = self.theta[i][o];
            }
        }
        k
    }

    /// Variance accounted for by the one-step prediction, per axis (%);
    /// None before the first 100 samples.
    pub fn vaf(&self) -> Option<[f64; 3]> {
        (self.updates >= 100).then(|| {
            [0, 1, 2].map(|o| {
                if self.f_power[o] > 0.0 {
                    100.0 * (1.0 - self.err_power[o] / self.f_power[o])
                } else {
                    0.0
                }
            })
        })
    }
}

/// The live state machine: envelopes, index, MVC capture, RLS.
#[derive(Debug, Clone)]
pub struct Processor {
    filters: Vec<StreamingFilter>,
    maxima: Option<Vec<f64>>,
    capture: Option<Vec<f64>>,
    /// Envelope per muscle (V) and normalised activation (fraction of MVC).
    pub envelopes: Vec<f64>,
    pub activations: Vec<f64>,
    /// Co-contraction index (fraction of MVC); NaN until an MVC is known.
    pub index: f64,
    /// The index averaged for display (exponential, 1 s time constant): what
    /// the bar shows, since the raw 8 Hz envelope flickers at display rate.
    pub index_display: f64,
    display_weight: f64,
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

    pub fn capturing(&self) -> bool {
        self.capture.is_some()
    }

    pub fn has_mvc(&self) -> bool {
        self.maxima.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::needless_range_loop)]
    fn rls_recovers_a_static_stiffness() {
        let k = [[800.0, 40.0, 10.0], [30.0, 500.0, 20.0], [5.0, 25.0, 300.0]];
        let mut rls = Rls::new(0.999);
        let mut s = 1u64;
        let mut rand = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for n in 0..20_000 {
            let t = n as f64 * 1e-3;
            let x = [
                0.3 + 0.004 * (3.1 * t).sin(),
                -0.2 + 0.004 * (4.3 * t).cos(),
                0.05 + 0.004 * (5.7 * t + 1.0).sin(),
            ];
            let mut f = [2.0, -1.0, 0.5];
            for (o, fo) in f.iter_mut().enumerate() {
                for i in 0..3 {
                    *fo += k[o][i] * (x[i] - [0.3, -0.2, 0.05][i]);
                }
                *fo += 0.01 * rand();
            }
            rls.update(x, f);
        }
        let est = rls.stiffness();
        for o in 0..3 {
            for i in 0..3 {
                assert!(
                    (est[o][i] - k[o][i]).abs() < 0.01 * 800.0,
                    "K[{o}][{i}] = {}",
                    est[o][i]
                );
            }
        }
        assert!(rls.vaf().unwrap().iter().all(|v| *v > 99.0));
    }
}
