//! Seed 004's shoulder joint space before estimation: a virtual hand whose
//! impedance is a known shoulder impedance seen through J = diag(J_h, 1).

use limpid_analysis::linear::ShoulderPosture;
use limpid_analysis::shoulder::joint_space_recording;
use limpid_ident::stochastic::{estimate_stochastic_pooled, StochasticParams};
use limpid_lab::rig::{simulate_rig, RigExperiment, SA1};
use nalgebra::Matrix3;

const POSTURE: ShoulderPosture = ShoulderPosture {
    upper_arm_m: 0.3,
    forearm_m: 0.35,
    elbow_deg: 90.0,
    angles_deg: [30.0, 20.0, 0.0],
};

/// J = diag(J_h, 1), written out from J_h here (not through `task_jacobian`).
fn task_jacobian_by_hand() -> Matrix3<f64> {
    let (s, q) = POSTURE.shoulder().unwrap();
    let jh = s.jacobian_xz(q);
    Matrix3::new(
        jh[(0, 0)],
        jh[(0, 1)],
        0.0,
        jh[(1, 0)],
        jh[(1, 1)],
        0.0,
        0.0,
        0.0,
        1.0,
    )
}

fn relative_error(a: &limpid_core::Matrix, b: &Matrix3<f64>) -> f64 {
    let a = a.to_matrix3().unwrap();
    (a - b).norm() / b.norm()
}

#[test]
fn shoulder_impedance_estimated_in_joint_space_matches_the_truth_and_the_hand_estimate_mapped() {
    // shoulder impedance (flexion, abduction, internal rotation), natural
    // frequencies 2-3 Hz inside the 0.5-10 Hz band
    let k_q = Matrix3::new(30.0, 4.0, 1.0, 4.0, 22.0, 0.5, 1.0, 0.5, 3.0);
    let b_q = Matrix3::new(0.8, 0.1, 0.0, 0.1, 0.6, 0.0, 0.0, 0.0, 0.08);
    let m_q = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.1, 0.08, 0.01));
    let j = task_jacobian_by_hand();
    assert_eq!(
        j,
        limpid_analysis::shoulder::task_jacobian(&POSTURE).unwrap()
    );
    let j_inv = j.try_inverse().unwrap();
    let to_hand = |z: &Matrix3<f64>| j_inv.transpose() * z * j_inv;
    let mut rig = RigExperiment::spring_array(&SA1);
    rig.stiffness = to_hand(&k_q);
    rig.damping = to_hand(&b_q);
    rig.inertia = to_hand(&m_q);
    rig.peak = [8.0, 8.0, 0.5];
    rig.seconds = 40.0;
    let hand: Vec<_> = (0..2)
        .map(|t| simulate_rig(&rig, [0.0, 0.0], 40 + t).unwrap())
        .collect();
    let joint: Vec<_> = hand
        .iter()
        .map(|r| joint_space_recording(r, &POSTURE).unwrap())
        .collect();
    assert_eq!(
        joint[0].names(),
        ["t", "q1", "q2", "tau1", "tau2", "u1", "u2", "q3", "tau3", "u3"]
    );
    let params = StochasticParams {
        welch: None,
        band_hz: (0.5, 10.0),
        period_s: None,
    };
    let est_joint = estimate_stochastic_pooled(&joint, &params).unwrap();
    assert_eq!(est_joint.coordinates, ["q1", "q2", "q3"]);
    let est_hand = estimate_stochastic_pooled(&hand, &params).unwrap();
    let k_joint = est_joint.stiffness.to_matrix3().unwrap();
    let k_after = j.transpose() * est_hand.stiffness.to_matrix3().unwrap() * j;
    let e_truth = relative_error(&est_joint.stiffness, &k_q);
    let e_after = (k_joint - k_after).norm() / k_after.norm();
    let e_damping = relative_error(&est_joint.damping, &b_q);
    eprintln!(
        "K joint vs truth {e_truth:.4}, vs hand mapped {e_after:.4}, B vs truth {e_damping:.4}"
    );
    assert!(e_truth < 0.03, "joint stiffness {k_joint} vs truth {k_q}");
    // not equal: J varies over the centimetre motions, and the fit is weighted by the joint coordinates' coherences
    assert!(
        e_after < 0.02,
        "joint-space {k_joint} vs mapped afterwards {k_after}"
    );
    assert!(
        e_damping < 0.1,
        "joint damping {:?} vs {b_q}",
        est_joint.damping
    );
    assert!(est_joint.criteria.min_multiple_coherence > 0.9);
}

#[test]
fn shoulder_joint_space_refuses_a_hand_out_of_reach_and_a_missing_torque() {
    let rig = RigExperiment::spring_array(&SA1);
    let mut rec = simulate_rig(
        &RigExperiment {
            seconds: 1.0,
            peak: [2.0, 2.0, 0.1],
            ..rig
        },
        [0.0, 0.0],
        3,
    )
    .unwrap();
    // a 2 m jump of X in one sample: out of the arm's reach
    let names = rec.names().to_vec();
    let mut cols: Vec<Vec<f64>> = names
        .iter()
        .map(|n| rec.column(n).unwrap().to_vec())
        .collect();
    let xi = names.iter().position(|n| n == "x").unwrap();
    cols[xi][500] = 2.0;
    rec = limpid_core::Recording::new("bad.csv", names.clone(), cols.clone(), 2).unwrap();
    let e = joint_space_recording(&rec, &POSTURE)
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad.csv: row 502, columns x,z"), "{e}");
    // theta without tauy
    let keep: Vec<usize> = (0..names.len()).filter(|&i| names[i] != "tauy").collect();
    let rec = limpid_core::Recording::new(
        "no_tauy.csv",
        keep.iter().map(|&i| names[i].clone()).collect(),
        keep.iter().map(|&i| cols[i].clone()).collect(),
        2,
    )
    .unwrap();
    let e = joint_space_recording(&rec, &POSTURE)
        .unwrap_err()
        .to_string();
    assert!(e.contains("tauy"), "{e}");
}
