//! The virtual experiment behind `limpid demo`: seed 000's 3-D study on a
//! subject whose matrices are known (seed 000 Table I, subject 1).
//!
//! Six start points, 16 centre-out perturbations each (3 cm, 3 s; 6 s for the
//! sinusoid), a position-controlled robot, an F/T sensor with per-trial
//! offset, drift and noise (`limpid_lab`). Every start point is estimated
//! with the linear estimator (seed 000 eq. (3)-(8)) and compared with the
//! subject's true matrices by the relative Frobenius error
//! ([`limpid_analysis::result::demo`] holds the result types).

use limpid_core::{Matrix, Result};
use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};
use limpid_lab::{seed000_subject1, simulate_centre_out, CentreOut, NoiseModel, Posture, Profile};
use rayon::prelude::*;

use limpid_analysis::linear::linear_result;
use limpid_analysis::result::demo::{
    relative_error_percent, DemoDesigned, DemoPoint, DemoResult, DemoSubject,
};

fn run_point(
    p: &Posture,
    protocol: &CentreOut,
    noise: &NoiseModel,
    seed: u64,
) -> Result<DemoPoint> {
    let rec = simulate_centre_out(p, protocol, noise, seed)?;
    let prepared = prepare(&rec, &PrepareParams::default())?;
    let est = fit_linear(&prepared, &LinearParams::default())?;
    let result = linear_result(&est, &prepared);
    let (k, b, m) = (
        Matrix::from(p.stiffness),
        Matrix::from(p.damping),
        Matrix::from(p.inertia),
    );
    Ok(DemoPoint {
        start_point: p.name.clone(),
        position: [p.start.x, p.start.y, p.start.z],
        stiffness_error_percent: relative_error_percent(&result.stiffness, &k),
        damping_error_percent: relative_error_percent(&result.damping, &b),
        inertia_error_percent: relative_error_percent(&result.inertia, &m),
        true_stiffness: k,
        true_damping: b,
        true_inertia: m,
        estimate: result,
    })
}

/// Recordings behind the demo design's prediction (the search itself uses
/// [`crate::design::RANKING_RUNS`] each).
const DEMO_DESIGN_RUNS: usize = 12;

/// `limpid protocol design` for the first start point on the realistic
/// subject, with the seed protocol's limits and its time at one start point,
/// then the designed protocol run like the seed's (same noise seed).
fn designed_point(noise: &NoiseModel, posture: &Posture, seed: u64) -> Result<DemoDesigned> {
    let seed_protocol = limpid_lab::protocol::preset("artemiadis-3d")?;
    let budget_s = crate::design::protocol_duration(&seed_protocol);
    let request = crate::design::DesignRequest {
        prior: crate::design::Prior::demo(0),
        limits: seed_protocol.limits.clone(),
        sample_rate_hz: seed_protocol.sample_rate_hz,
        budget_s,
        objective: crate::design::Objective::default(),
        runs: DEMO_DESIGN_RUNS,
        baseline: None,
        verify: 0,
        seed,
    };
    let designed = crate::design::design(&request)?;
    let mut at = posture.clone();
    at.start = designed.protocol.start_points()[0];
    let point = run_point(
        &at,
        &designed.protocol.centre_out(),
        noise,
        seed.wrapping_mul(1000),
    )?;
    let limpid_analysis::result::design::DesignChoice::CentreOut(chosen) = designed.result.chosen
    else {
        unreachable!("the linear method's designs are centre-out")
    };
    Ok(DemoDesigned {
        chosen,
        budget_s,
        predicted_se_percent: designed.result.predicted.pooled.se_percent,
        point,
    })
}

/// Simulate and estimate every start point (in parallel); `progress` is
/// called once per start point. With `design` (realistic subject only), the
/// first start point is also run with the protocol `limpid protocol design`
/// chooses for it ([`DemoResult::designed`]).
pub fn run_demo(
    profile: Profile,
    subject: DemoSubject,
    seed: u64,
    design: bool,
    progress: &(dyn Fn() + Sync),
) -> Result<DemoResult> {
    let protocol = CentreOut::seed000(profile);
    let mut postures = seed000_subject1();
    let noise = match subject {
        DemoSubject::Realistic => {
            for (p, max_a) in postures
                .iter_mut()
                .zip(limpid_lab::realistic::SEED000_K_MAX_A)
            {
                p.stiffness += limpid_lab::realistic::antisymmetric_part(max_a);
            }
            NoiseModel::realistic()
        }
        DemoSubject::Ideal => NoiseModel::default(),
    };
    let points = postures
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let r = run_point(p, &protocol, &noise, seed.wrapping_mul(1000) + i as u64);
            progress();
            r
        })
        .collect::<Result<Vec<_>>>()?;
    let designed = (design && subject == DemoSubject::Realistic)
        .then(|| designed_point(&noise, &postures[0], seed))
        .transpose()?;
    Ok(DemoResult {
        designed,
        subject,
        profile: format!("{profile:?}").to_lowercase(),
        directions: protocol.directions.len(),
        radius_m: protocol.radius_m,
        motion_s: protocol.motion_s,
        sample_rate_hz: protocol.sample_rate,
        seed,
        points,
    })
}
