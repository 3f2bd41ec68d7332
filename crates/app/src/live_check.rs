//! How far the live display's standard errors can be trusted (issue 37): a
//! simulated co-contraction session (Patel, O'Neill & Artemiadis 2013)
//! streamed sample by sample through [`OnlineImpedance`], restarted per
//! level, every estimate after a completed perturbation compared with the
//! level's true K. Used by the coverage test and `--example live_coverage`.

use limpid_ident::online::{OnlineImpedance, OnlineSettings};
use limpid_lab::cocontraction::{simulate_cocontraction, CocontractionProtocol};
use limpid_lab::NoiseModel;

/// One diagonal element of the live K against the truth.
#[derive(Debug, Clone, Copy)]
pub struct LiveCheck {
    /// (estimate - truth) / SE.
    pub z: f64,
    /// SE / |truth|.
    pub se_rel: f64,
    /// (estimate - truth) / |truth|.
    pub error_rel: f64,
}

/// The checks of one simulated session (subject and noise from `seed`).
pub fn live_stiffness_checks(
    noise: &NoiseModel,
    seed: u64,
) -> std::result::Result<Vec<LiveCheck>, String> {
    let subject = &crate::calibrate::cocontraction_subject(seed);
    let (rec, _) = simulate_cocontraction(subject, &CocontractionProtocol::seed001(), noise, seed)
        .map_err(|e| e.to_string())?;
    let col = |c: &str| {
        rec.column(c)
            .ok_or_else(|| format!("the simulation wrote no {c} column"))
    };
    let (x, y, z) = (col("x")?, col("y")?, col("z")?);
    let (fx, fy, fz) = (col("fx")?, col("fy")?, col("fz")?);
    let level = col("level")?;
    let mut est =
        OnlineImpedance::new(OnlineSettings::new(rec.sample_rate())).map_err(|e| e.to_string())?;
    let mut checks = Vec::new();
    let mut seen = 0;
    for i in 0..x.len() {
        if i > 0 && level[i] != level[i - 1] {
            est.reset();
            seen = 0;
        }
        est.update([x[i], y[i], z[i]], [fx[i], fy[i], fz[i]]);
        let Some(e) = est.estimate() else { continue };
        if est.perturbations == seen {
            continue;
        }
        seen = est.perturbations;
        let k = subject.stiffness(level[i]);
        for o in 0..3 {
            let (value, se, truth) = (e.stiffness[o][o], e.stiffness_se[o][o], k[(o, o)]);
            checks.push(LiveCheck {
                z: (value - truth) / se,
                se_rel: se / truth.abs(),
                error_rel: (value - truth) / truth.abs(),
            });
        }
    }
    Ok(checks)
}
