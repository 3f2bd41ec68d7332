//! What a protocol will give before it is run (seed 003 §IV-B): the
//! condition number the estimator's scaled regressor will have on a nominal,
//! noise-free subject, found by simulating the protocol once and estimating.

use limpid_core::Result;
use limpid_ident::planar::{fit_planar, prepare_planar, PlanarPrepare};
use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};
use limpid_lab::design::Design;
use limpid_lab::planar::simulate_planar;
use limpid_lab::{seed000_subject1, simulate_centre_out, NoiseModel};

/// The condition number of seed 000's scaled regressor on the first start
/// point (seed 000 Table I posture 1), or of the planar regressor W of seed
/// 003 eq. (19) with unit-RMS columns on the seed 003 subject. None for
/// stochastic protocols (their conditioning is the input coherence of the
/// protocol check).
pub fn predicted_condition(d: &Design) -> Result<Option<f64>> {
    match d {
        Design::CentreOut(p) => {
            let mut posture = seed000_subject1().remove(0);
            posture.start = p.start_points()[0];
            let rec = simulate_centre_out(&posture, &p.centre_out(), &NoiseModel::none(), 1)?;
            let prepared = prepare(&rec, &PrepareParams::default())?;
            let est = fit_linear(&prepared, &LinearParams::default())?;
            Ok(Some(est.condition_number))
        }
        Design::Planar(p) => {
            let subject = p.nominal_subject();
            let rec = simulate_planar(&subject, &p.simulation(), 0.0, 0.0, p.seed)?;
            let setup = PlanarPrepare::new(p.link_lengths_m[0], p.link_lengths_m[1]);
            let data = prepare_planar(&rec, &setup)?;
            let all: Vec<usize> = (0..data.trials.len()).collect();
            let est = fit_planar(&data, usize::MAX, Some(subject.xi), &all)?;
            Ok(Some(est.criteria.condition_number_scaled))
        }
        Design::Stochastic(_)
        | Design::Ensemble(_)
        | Design::RampAndHold(_)
        | Design::Walking(_)
        | Design::Periodic(_) => Ok(None),
    }
}
