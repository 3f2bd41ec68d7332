//! The joint's frequency response from position to torque (issue 81): a
//! nonparametric picture of joint impedance beside the parallel cascade's
//! models, without a commanded input column.
//!
//! `Z(f) = G_q,tq / G_q,q` (the H1 estimator, Welch: Hann, half-overlapping
//! segments of 2^k decimated samples, about 0.2 Hz apart), its coherence,
//! and the random error of |Z| and of its phase by Bendat & Piersol's
//! (2010, Table 9.6) `sqrt(1 - γ²) / (|γ| sqrt(2 n_d))` with `n_d` the
//! segments averaged. Over it: the intrinsic I-B-K model `K + i 2πf B -
//! (2πf)² I` of the joint parametric fit. The measured position is the
//! input: right in open loop (a stiff servo imposes the motion); not made
//! for closed-loop recordings, where H1 is biased.

use limpid_dsp::spectral::{squared_coherence, SegmentSpectra, Welch};
use num_complex::Complex64;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::Ibk;

/// Position-to-torque frequency response of a joint recording.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct JointFrequencyResponse {
    /// Frequencies (Hz), from the second bin above 0 to 0.8 of the decimated Nyquist.
    pub frequency_hz: Vec<f64>,
    /// |Z| (N m/rad, or N/m).
    pub magnitude: Vec<f64>,
    /// Its standard error (Bendat & Piersol's random error).
    pub magnitude_se: Vec<f64>,
    /// Phase of Z (degrees, -180..180).
    pub phase_deg: Vec<f64>,
    /// Its standard error (degrees).
    pub phase_se_deg: Vec<f64>,
    /// Magnitude-squared coherence of position and torque.
    pub coherence: Vec<f64>,
    /// |Z| of the intrinsic I-B-K model at the same frequencies.
    pub intrinsic_model_magnitude: Vec<f64>,
    /// Its phase (degrees).
    pub intrinsic_model_phase_deg: Vec<f64>,
    /// Welch segments averaged.
    pub segments: usize,
}

/// The response of `torque` to `position` sampled at `fs`, or `None` when
/// the record is too short for 8 segments of at least 1 s.
pub(crate) fn joint_frequency_response(
    position: &[f64],
    torque: &[f64],
    fs: f64,
    intrinsic: &Ibk,
) -> Option<JointFrequencyResponse> {
    // segments of about 5 s (0.2 Hz), fewer samples when the record is short
    let mut nperseg = (5.0 * fs).round().max(2.0) as usize;
    while nperseg as f64 >= fs && position.len() < 4 * nperseg {
        nperseg /= 2;
    }
    if (nperseg as f64) < fs {
        return None;
    }
    let welch = Welch {
        nperseg,
        ..Welch::new(fs)
    };
    let s = SegmentSpectra::new(&[position, torque], &welch).ok()?;
    let segments = s.segments();
    let (gqq, gtt, gqt) = (s.cross(0, 0), s.cross(1, 1), s.cross(0, 1));
    let top = 0.4 * fs;
    let mut out = JointFrequencyResponse {
        frequency_hz: Vec::new(),
        magnitude: Vec::new(),
        magnitude_se: Vec::new(),
        phase_deg: Vec::new(),
        phase_se_deg: Vec::new(),
        coherence: Vec::new(),
        intrinsic_model_magnitude: Vec::new(),
        intrinsic_model_phase_deg: Vec::new(),
        segments,
    };
    for (k, &f) in s.frequencies.iter().enumerate() {
        // the first bin takes the Hann window's leakage from the removed mean (1-2 % on |Z|)
        if k < 2 || f > top || gqq[k].re <= 0.0 {
            continue;
        }
        let z = gqt[k] / gqq[k].re;
        let coherence = squared_coherence(gqq[k].re, gtt[k].re, gqt[k]);
        let relative =
            (1.0 - coherence).max(0.0).sqrt() / (coherence.sqrt() * (2.0 * segments as f64).sqrt());
        let w = 2.0 * std::f64::consts::PI * f;
        let model = Complex64::new(
            intrinsic.stiffness - w * w * intrinsic.inertia,
            w * intrinsic.damping,
        );
        out.frequency_hz.push(f);
        out.magnitude.push(z.norm());
        out.magnitude_se.push(relative * z.norm());
        out.phase_deg.push(z.arg().to_degrees());
        out.phase_se_deg
            .push(relative.min(std::f64::consts::PI).to_degrees());
        out.coherence.push(coherence);
        out.intrinsic_model_magnitude.push(model.norm());
        out.intrinsic_model_phase_deg.push(model.arg().to_degrees());
    }
    let finite = out
        .magnitude
        .iter()
        .chain(&out.magnitude_se)
        .chain(&out.phase_se_deg)
        .all(|v| v.is_finite());
    (!out.frequency_hz.is_empty() && finite).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spring_damper_mass_is_read_back_from_its_torque() {
        // tq = K q + B q' + I q'' on white-ish position, no noise: Z is the model
        let fs = 100.0;
        let q = crate::uniform_noise(20_000, 7);
        let (k, b, i) = (80.0, 0.8, 0.015);
        let dt = 1.0 / fs;
        let n = q.len();
        let tq: Vec<f64> = (0..n)
            .map(|t| {
                let (a, c) = (t.saturating_sub(1), (t + 1).min(n - 1));
                let v = (q[c] - q[a]) / (2.0 * dt);
                let acc = (q[c] - 2.0 * q[t] + q[a]) / (dt * dt);
                k * q[t] + b * v + i * acc
            })
            .collect();
        let ibk = Ibk {
            inertia: i,
            damping: b,
            stiffness: k,
        };
        let r = joint_frequency_response(&q, &tq, fs, &ibk).unwrap();
        // below 5 Hz the central differences are within 1 % of the continuous model
        for (j, &f) in r.frequency_hz.iter().enumerate().filter(|(_, f)| **f < 5.0) {
            let rel = (r.magnitude[j] - r.intrinsic_model_magnitude[j]).abs()
                / r.intrinsic_model_magnitude[j];
            assert!(
                rel < 0.01,
                "{f} Hz: {} vs {}",
                r.magnitude[j],
                r.intrinsic_model_magnitude[j]
            );
            assert!(r.coherence[j] > 0.999, "{f} Hz");
            assert!((r.phase_deg[j] - r.intrinsic_model_phase_deg[j]).abs() < 1.0);
        }
        assert!(r.frequency_hz.last().unwrap() <= &40.0);
    }
}
