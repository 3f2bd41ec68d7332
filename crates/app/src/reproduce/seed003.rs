//! `limpid reproduce 003`: Lakatos, Petit & van der Smagt's planar
//! experiment with a spinal reflex: the shortest trusted windows with known
//! and unknown inertia, and Table I's conditioning ratios (quintic against a
//! sixth-order polynomial).

#![allow(clippy::needless_range_loop)]

use super::{row, sig, Finding, Reproduction};
use limpid_core::Result;
use nalgebra::{Matrix4, Vector4};
// the paper's tables and limpid's are indexed in step

/// s(τ) = a3 τ³ + a4 τ⁴ + a5 τ⁵ + a6 τ⁶ with s(0) = s'(0) = s''(0) = 0,
/// s(1) = 1, s'(1) = s''(1) = s'''(1) = 0 (seed 003 §III-B's sixth-order
/// comparison polynomial).
fn sextic_coefficients() -> [f64; 4] {
    let a = Matrix4::new(
        1.0, 1.0, 1.0, 1.0, //
        3.0, 4.0, 5.0, 6.0, //
        6.0, 12.0, 20.0, 30.0, //
        6.0, 24.0, 60.0, 120.0,
    );
    let x = a
        .lu()
        .solve(&Vector4::new(1.0, 0.0, 0.0, 0.0))
        .expect("the boundary conditions are independent");
    [x[0], x[1], x[2], x[3]]
}

/// Seed 003 eq. (17) for a polynomial s(τ) = Σ c_k τ^k over `duration`.
fn polynomial_ratios(coef: &[(i32, f64)], duration: f64) -> [f64; 3] {
    let derivative = |tau: f64, order: i32| -> f64 {
        coef.iter()
            .map(|(k, c)| {
                if *k < order {
                    return 0.0;
                }
                let falling: f64 = (0..order).map(|j| (k - j) as f64).product();
                c * falling * tau.powi(k - order) / duration.powi(order)
            })
            .sum()
    };
    let n = 4000;
    let (mut m1, mut m2, mut m3) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let tau = (i as f64 + 0.5) / n as f64;
        m1 += derivative(tau, 1).powi(2);
        m2 += derivative(tau, 2).powi(2);
        m3 += derivative(tau, 3).powi(2);
    }
    [m1 / m2, m1 / m3, m2 / m3]
}

/// Torque noise of the seed 003 subject (N m, s.d.).
const PLANAR_TORQUE_NOISE_NM: f64 = 0.15;

pub(super) fn seed003(seed: u64) -> Result<Reproduction> {
    use limpid_ident::planar::{prepare_planar, window_sweep, PlanarPrepare};
    use limpid_lab::design::PlanarDesign;
    let design = PlanarDesign::seed003();
    let (arm, rec) = simulate_subject(&design, seed)?;
    let data = prepare_planar(
        &rec,
        &PlanarPrepare::new(design.link_lengths_m[0], design.link_lengths_m[1]),
    )?;
    let longest = (data.max_window_s() * 1e3).floor().min(450.0);
    let full = window_sweep(&data, SHORTEST_MS, longest, 10.0, None)?;
    let known = window_sweep(&data, SHORTEST_MS, longest, 10.0, Some(arm.xi))?;
    let mut out = Reproduction::default();
    let both = paper_required_window;
    window_rows(&mut out, (&full, &known), longest);
    table_i(&mut out, &design);
    let order = |v: Option<f64>| v.unwrap_or(f64::INFINITY);
    let shown = |v: Option<f64>| v.map_or("none".into(), |v| format!("{v} ms"));
    out.findings.push(Finding {
        seed: "003".into(),
        claim: "the full model needs an observation window of a few hundred ms (~370 ms) to meet the paper's criteria (K positive definite, K and D quasi-symmetric); known inertia shortens it".into(),
        holds: both(&full).is_some_and(|v| v >= 150.0)
            && order(both(&known)) <= order(both(&full)),
        evidence: format!(
            "from {} (full model), {} (inertia known), with a cuff of {} N/m, {} N s/m between robot and arm; limpid's stricter trust (precision, no change of K or D within the window): full model {}, inertia known {}",
            shown(both(&full)),
            shown(both(&known)),
            limpid_lab::planar::SEED003_CUFF.0,
            limpid_lab::planar::SEED003_CUFF.1,
            shown(full.shortest_trusted_ms),
            shown(known.shortest_trusted_ms)
        ),
    });
    Ok(out)
}

/// The shortest observation window of the sweeps (ms).
const SHORTEST_MS: f64 = 50.0;

/// Seed 003 §V's "required" window: K positive definite and K, D
/// quasi-symmetric from here on.
fn paper_required_window(s: &limpid_ident::planar::Sweep) -> Option<f64> {
    match (s.min_positive_definite_ms, s.min_quasi_symmetric_ms) {
        (Some(a), Some(b)) => Some(a.max(b)),
        _ => None,
    }
}

/// The nominal subject in the robot's cuff, with a spinal reflex, holding
/// 5 N distal: its recording of the design's perturbations.
fn simulate_subject(
    design: &limpid_lab::design::PlanarDesign,
    seed: u64,
) -> Result<(limpid_lab::planar::PlanarSubject, limpid_core::Recording)> {
    use limpid_lab::planar::{simulate_planar, Cuff, Reflex};
    let mut arm = design.nominal_subject();
    // seed 003 §IV-A: the robot holds the forearm in a plastic cuff; the soft
    // tissue in between is a spring and damper in series (values: ours)
    let links = limpid_core::arm::Arm {
        l1: design.link_lengths_m[0],
        l2: design.link_lengths_m[1],
        shoulder: [0.0, 0.0],
    };
    arm.cuff = Some(Cuff::seed003(&links, arm.q0));
    // the spinal reflex of seed 003 §I (latency 70-110 ms): K and D rise after it
    arm.reflex = Some(Reflex {
        latency_s: 0.09,
        stiffness_gain: 0.3,
        damping_gain: 0.3,
    });
    // the subject holds 5 N distal (seed 003 §IV): force fluctuation of about
    // 0.5 N at the hand, 0.15 N m at the joints, white (sensor and fast
    // fluctuation) ...
    let mut rec = simulate_planar(
        &arm,
        &design.simulation(),
        PLANAR_TORQUE_NOISE_NM,
        2e-5,
        seed,
    )?;
    // ... which is slow (below 3 Hz, the physiological tremor-free band of
    // force fluctuation): within a window it acts as a drifting offset
    limpid_lab::planar::add_torque_fluctuation(
        &mut rec,
        PLANAR_TORQUE_NOISE_NM,
        3.0,
        seed ^ 0x5eed,
    )?;
    Ok((arm, rec))
}

/// The shortest observation windows by each criterion, the paper's beside
/// limpid's, and where the sweep found a change within the trials.
fn window_rows(
    out: &mut Reproduction,
    (full, known): (&limpid_ident::planar::Sweep, &limpid_ident::planar::Sweep),
    longest: f64,
) {
    let ms = "ms";
    let both = paper_required_window;
    for (item, paper, value) in [
        (
            "shortest T_obs with K positive definite",
            Some(320.0),
            full.min_positive_definite_ms,
        ),
        (
            "shortest T_obs with K and D quasi-symmetric",
            Some(370.0),
            full.min_quasi_symmetric_ms,
        ),
        (
            "shortest T_obs with every parameter quasi-constant",
            Some(400.0),
            full.min_quasi_constant_ms,
        ),
        (
            "shortest T_obs with K positive definite and K, D quasi-symmetric, full model",
            Some(370.0),
            both(full),
        ),
        (
            "shortest T_obs with K positive definite and K, D quasi-symmetric, inertia known (reduced model eq. 23)",
            Some(300.0),
            both(known),
        ),
        (
            "shortest trusted T_obs (limpid's criterion), full model",
            None,
            full.shortest_trusted_ms,
        ),
        (
            "shortest trusted T_obs (limpid's criterion), inertia known",
            None,
            known.shortest_trusted_ms,
        ),
    ] {
        out.rows.push(row("003", item.into(), paper, value, ms).with_note(match value {
            None => format!("no window up to {longest} ms meets it"),
            Some(_) if item.starts_with("shortest trusted") => {
                "not the paper's criterion: 2 SE of K within 10 %, of D within 25 %, and no change of K or D within the window".into()
            }
            Some(v) if item == "shortest T_obs with K and D quasi-symmetric" && v <= SHORTEST_MS => {
                "from the shortest window scanned: the virtual cuff is symmetric (J^T k J); the paper's asymmetry at short windows has another source".into()
            }
            Some(_) if item.contains("quasi-symmetric, ") => {
                "the paper's 'required' window (§V: 370 ms, about 300 ms with the inertia known); both of its criteria hold from here on".into()
            }
            Some(_) => String::new(),
        }));
    }
    out.rows.push(row(
        "003",
        "change of K or D within the trials detected after onset".into(),
        None,
        full.impedance_change.as_ref().map(|c| c.onset_ms),
        ms,
    ).with_note("the cuff's fast dynamics in the first tens of ms and the virtual subject's reflex (K and D +30 % after 90 ms) are changes the rigid model does not hold through; Lakatos, Petit & van der Smagt (2011) §I: reflexes act after 25-110 ms, the paper's windows include them"));
}

/// Table I: the C_ij ratios of the fifth-order (minimum-jerk) and the
/// sixth-order polynomials, and the claim that the quintic's are nearer 1.
fn table_i(out: &mut Reproduction, design: &limpid_lab::design::PlanarDesign) {
    let q = polynomial_ratios(&[(3, 10.0), (4, -15.0), (5, 6.0)], design.interpolation_s);
    let c6 = sextic_coefficients();
    let s = polynomial_ratios(
        &[(3, c6[0]), (4, c6[1]), (5, c6[2]), (6, c6[3])],
        design.interpolation_s,
    );
    let labels = ["C_12", "C_13", "C_23"];
    let mut closer = 0;
    for i in 0..3 {
        for (name, v) in [("fifth-order", q[i]), ("sixth-order", s[i])] {
            out.rows.push(
                row(
                    "003",
                    format!(
                        "Table I, {} of the {name} polynomial (T_k = {} ms)",
                        labels[i],
                        design.interpolation_s * 1e3
                    ),
                    None,
                    Some(v),
                    if i == 1 { "s^4" } else { "s^2" },
                )
                .with_note("Table I's cells are garbled in the text"),
            );
        }
        if q[i].ln().abs() < s[i].ln().abs() {
            closer += 1;
        }
    }
    out.findings.push(Finding {
        seed: "003".into(),
        claim: "every C_ij of the fifth-order polynomial is closer to 1 than the sixth-order one's"
            .into(),
        holds: closer == 3,
        evidence: format!(
            "closer (in log) in {closer} of 3: quintic {}, sextic {}",
            q.map(sig).join(" / "),
            s.map(sig).join(" / ")
        ),
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use limpid_lab::profile::Profile;

    #[test]
    fn sextic_meets_its_boundary_conditions() {
        let c = sextic_coefficients();
        let at1: f64 = c.iter().sum();
        assert!((at1 - 1.0).abs() < 1e-12);
        let d3: f64 = 6.0 * c[0] + 24.0 * c[1] + 60.0 * c[2] + 120.0 * c[3];
        assert!(d3.abs() < 1e-9);
    }

    #[test]
    fn polynomial_ratios_match_the_profile_module_for_the_quintic() {
        let ours = polynomial_ratios(&[(3, 10.0), (4, -15.0), (5, 6.0)], 0.2);
        let lab = limpid_lab::protocol::conditioning_ratios(Profile::Quintic, 0.2, 1.0);
        for i in 0..3 {
            assert!((ours[i] / lab[i] - 1.0).abs() < 1e-3, "{ours:?} vs {lab:?}");
        }
    }
}
