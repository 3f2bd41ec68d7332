//! The robot in the loop of seed 004: a 3-DoF PUMA-type robot with joint
//! friction holds the spring array and applies random force perturbations F_Δ
//! under
//!
//! - **IMBIC** with time-delay estimation, eq. (11)-(14), with the paper's
//!   gains (M_rd, B_rd, K_rd, M̄_φ, Γ; L = one sample), or
//! - a **plain PD** (impedance) law F_u = F_Δ − B_rd ẋ − K_rd x with no
//!   friction compensation,
//!
//! so that a user can see why the paper uses IMBIC: under PD the friction
//! makes the response to F_Δ nonlinear and the multiple coherence drops.
//!
//! Model choices (the seed leaves them open):
//! - task coordinates x_r = [X, Z, θ_y] (the rows vx, vz, ωy of the geometric
//!   Jacobian; Y motion and tilt neglected, as the seed does). Three task
//!   coordinates in the X-Z plane need three joints about axes parallel to Y
//!   (a PUMA's shoulder, elbow and wrist pitch): the virtual robot is that
//!   vertical-plane chain, links 0.35, 0.35 and 0.10 m (seed 004's Table I is
//!   partly illegible in the copy we have; its first joint is vertical, which
//!   cannot move X, Z or θ_y at a posture in the X-Z plane);
//! - joint inertia: reflected rotor inertia dominates behind 100-120:1
//!   harmonic drives, so M_φ is constant and diagonal, 1.5 x the known part
//!   M̄_φ (the seed's M̄_φ times its voltage-to-torque ratios, in kg m²);
//!   velocity-product terms are neglected (millimetre motions);
//! - joint friction τ_f = F_c tanh(φ̇/ε) + F_v φ̇ (Coulomb smoothed over
//!   ε = 0.01 rad/s, plus viscous);
//! - the plant is integrated at 10 kHz (semi-implicit Euler), the controller
//!   runs at 1 kHz with its output held; it measures positions at the
//!   samples and differentiates them numerically (velocity by backward
//!   difference, ẍ(t − L) by a second difference), as the seed's robot did.

use nalgebra::{Matrix3, Vector3};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};

use crate::rig::{stochastic_input, RigExperiment};
use limpid_core::{Error, Recording, Result};
use limpid_robot::{Convention, Joint, Robot};

/// The robot's dynamics and friction.
#[derive(Debug, Clone)]
pub struct RobotDynamics {
    /// Kinematics of the robot.
    pub robot: Robot,
    /// Joint angles of the test location (rad).
    pub posture: Vec<f64>,
    /// True joint inertia (kg m², diagonal).
    pub joint_inertia: [f64; 3],
    /// Known part M̄_φ used by IMBIC (kg m², diagonal).
    pub known_inertia: [f64; 3],
    /// Coulomb (N m) and viscous (N m s/rad) joint friction.
    pub coulomb: [f64; 3],
    /// Viscous joint friction (N m s/rad).
    pub viscous: [f64; 3],
}

impl RobotDynamics {
    /// The vertical-plane PUMA-type chain at an elbow-bent test location, with
    /// M̄_φ = diag(0.00713, 0.00614, 0.00835) V s²/rad x (25.45, 12.71, 10.62) N m/V
    /// and harmonic-drive friction of 5 / 3 / 1.5 N m Coulomb (about 7 % of the
    /// drives' rated output torque), 2 / 1.5 / 0.8
    /// N m s/rad viscous.
    pub fn seed004() -> Self {
        let known = [0.00713 * 25.45, 0.00614 * 12.71, 0.00835 * 10.62];
        RobotDynamics {
            robot: vertical_plane_chain(),
            posture: vec![-0.5, 1.2, 0.9],
            joint_inertia: known.map(|m| 1.5 * m),
            known_inertia: known,
            coulomb: [5.0, 3.0, 1.5],
            viscous: [2.0, 1.5, 0.8],
        }
    }

    /// Task pose [X, Z, θ_y] and the 3 x 3 task Jacobian.
    fn task(&self, q: &[f64], r0: &Matrix3<f64>) -> (Vector3<f64>, Matrix3<f64>) {
        let (t, j6) = self.robot.pose_and_jacobian(q);
        let r: Matrix3<f64> = t.fixed_view::<3, 3>(0, 0).into();
        let rel = r * r0.transpose();
        let theta = rel[(0, 2)].atan2(rel[(2, 2)]);
        let rows = [0, 2, 4];
        let j = Matrix3::from_fn(|i, c| j6[(rows[i], c)]);
        (Vector3::new(t[(0, 3)], t[(2, 3)], theta), j)
    }

    fn friction(&self, qd: &Vector3<f64>) -> Vector3<f64> {
        Vector3::from_fn(|i, _| self.coulomb[i] * (qd[i] / 0.01).tanh() + self.viscous[i] * qd[i])
    }
}

/// Three revolute joints about parallel axes (Craig's DH, α = 0), based
/// with roll -90° so that the axes lie along the lab's Y and the arm moves in X-Z.
pub fn vertical_plane_chain() -> Robot {
    let joint = |a: f64| Joint {
        a,
        alpha: 0.0,
        d: 0.0,
        theta_offset: 0.0,
        min: -std::f64::consts::PI,
        max: std::f64::consts::PI,
        max_speed: 3.0,
    };
    let mut robot = Robot::from_dh(
        "PUMA-type vertical-plane chain (shoulder, elbow, wrist pitch)",
        Convention::Modified,
        &[joint(0.0), joint(0.35), joint(0.35)],
    )
    .placed([0.0; 3], [-std::f64::consts::FRAC_PI_2, 0.0, 0.0]);
    // the handle: 0.10 m beyond the wrist axis
    robot.tip[(0, 3)] = 0.10;
    robot
}

/// The controller holding the rig.
#[derive(Debug, Clone, Copy)]
pub enum Controller {
    /// Seed 004 eq. (11)-(14) with desired impedance M_rd, B_rd, K_rd and forgetting Γ.
    Imbic {
        /// Desired inertia M_rd.
        m_rd: Vector3<f64>,
        /// Desired damping B_rd.
        b_rd: Vector3<f64>,
        /// Desired stiffness K_rd.
        k_rd: Vector3<f64>,
        /// Forgetting Γ of the time-delay estimate.
        gamma: Vector3<f64>,
    },
    /// F_u = F_Δ − B ẋ − K x.
    Pd {
        /// Damping B.
        b: Vector3<f64>,
        /// Stiffness K.
        k: Vector3<f64>,
    },
}

impl Controller {
    /// The paper's IMBIC gains (§IV-B).
    pub fn imbic_seed004() -> Self {
        Controller::Imbic {
            m_rd: Vector3::new(1.0, 1.0, 1.0),
            b_rd: Vector3::new(40.0, 60.0, 20.0),
            k_rd: Vector3::new(100.0, 100.0, 100.0),
            gamma: Vector3::new(0.9, 0.81, 0.9),
        }
    }

    /// A PD law with the same damping and stiffness as IMBIC's desired impedance.
    pub fn pd_seed004() -> Self {
        Controller::Pd {
            b: Vector3::new(40.0, 60.0, 20.0),
            k: Vector3::new(100.0, 100.0, 100.0),
        }
    }
}

/// Simulate the spring array `rig` (its inertia, damping and stiffness; its
/// `seconds`, `sample_rate`, `peak` and `cutoff_hz` drive the inputs) held by the
/// robot under `controller`. Columns as [`crate::rig::simulate_rig`]:
/// `t, x, z, theta, fx, fz, tauy, ux, uz, utheta`, force on the rig.
pub fn simulate_robot_rig(
    rig: &RigExperiment,
    dynamics: &RobotDynamics,
    controller: &Controller,
    noise_std: [f64; 2],
    seed: u64,
) -> Result<Recording> {
    if dynamics.robot.dof() != 3 || dynamics.posture.len() != 3 {
        return Err(Error::invalid(
            "robot",
            "the rig experiment needs a 3-joint robot",
        ));
    }
    let fs = rig.sample_rate;
    let dt = 1.0 / fs;
    const SUBSTEPS: usize = 10;
    let h = dt / SUBSTEPS as f64;
    let pre = (5.0 * fs) as usize;
    let n = (rig.seconds * fs).round() as usize + 1;
    let inputs = stochastic_input(n + pre, fs, &rig.peak, rig.cutoff_hz, seed)?;
    let r0: Matrix3<f64> = dynamics
        .robot
        .fk(&dynamics.posture)
        .fixed_view::<3, 3>(0, 0)
        .into();
    let (x_eq, _) = dynamics.task(&dynamics.posture, &r0);
    let m_phi = Matrix3::from_diagonal(&Vector3::from(dynamics.joint_inertia));
    let m_bar_phi = Matrix3::from_diagonal(&Vector3::from(dynamics.known_inertia));

    let mut q = Vector3::from_column_slice(&dynamics.posture);
    let mut qd = Vector3::zeros();
    let mut memory = ControllerMemory::default();
    let mut rng = StdRng::seed_from_u64(seed.wrapping_add(1));
    let unit = Normal::new(0.0, 1.0).expect("unit normal is valid");
    let mut cols: Vec<Vec<f64>> = (0..10).map(|_| Vec::with_capacity(n)).collect();
    // force on the rig just before the sample instant (the sensor's reading for the controller)
    let mut f_sa_left = Vector3::zeros();
    let mut f_left_before = Vector3::zeros();
    let perturbations =
        (0..n + pre).map(|k| Vector3::new(inputs[0][k], inputs[1][k], inputs[2][k]));
    for (k, f_delta) in perturbations.enumerate() {
        let (pose, j) = dynamics.task(q.as_slice(), &r0);
        let x = pose - x_eq;
        let f_u = memory.force(controller, (x, j), (f_delta, f_sa_left), m_bar_phi, dt)?;
        // the plant between two samples, input held
        let (f_sa_right, f_sa_end) = plant_between_samples(
            rig,
            dynamics,
            (&mut q, &mut qd),
            (x_eq, &r0, m_phi),
            f_u,
            (h, SUBSTEPS),
        )?;
        f_sa_left = f_sa_end;
        // the force jumps with the held input at the sample instant: record
        // the mean of its limits before and after it (as crate::rig does)
        let f_sample = (f_sa_right + f_left_before) * 0.5;
        f_left_before = f_sa_left;
        if k >= pre {
            let i = k - pre;
            cols[0].push(i as f64 * dt);
            cols[1].push(x[0] + noise_std[0] * unit.sample(&mut rng));
            cols[2].push(x[1] + noise_std[0] * unit.sample(&mut rng));
            cols[3].push(x[2] + noise_std[1] * unit.sample(&mut rng));
            for c in 0..3 {
                cols[4 + c].push(f_sample[c]);
                cols[7 + c].push(f_delta[c]);
            }
        }
        if !q.iter().all(|v| v.is_finite()) {
            return Err(Error::invalid(
                "robot",
                format!(
                    "the closed loop went unstable at t = {:.3} s",
                    k as f64 * dt - 5.0
                ),
            ));
        }
    }
    let names = [
        "t", "x", "z", "theta", "fx", "fz", "tauy", "ux", "uz", "utheta",
    ]
    .map(String::from)
    .to_vec();
    Recording::new("virtual:robot-spring-array", names, cols, 2)
}

/// The controller's memory: samples t-1, t-2 of the measured pose, and v, F_u at t-1.
#[derive(Default)]
struct ControllerMemory {
    x_hist: [Vector3<f64>; 2],
    v_prev: Vector3<f64>,
    fu_prev: Vector3<f64>,
}

impl ControllerMemory {
    /// The controller's force at this sample from the pose deviation `x`
    /// (Jacobian `j`), the perturbation `f_delta` and the rig's force
    /// `f_sa_left` measured just before (seed 004 eq. (11)-(14) for IMBIC).
    fn force(
        &mut self,
        controller: &Controller,
        (x, j): (Vector3<f64>, Matrix3<f64>),
        (f_delta, f_sa_left): (Vector3<f64>, Vector3<f64>),
        m_bar_phi: Matrix3<f64>,
        dt: f64,
    ) -> Result<Vector3<f64>> {
        // the controller's numerical derivatives (one-sample backward differences)
        let xd = (x - self.x_hist[0]) / dt;
        let xd_prev = (self.x_hist[0] - self.x_hist[1]) / dt;
        let xdd_prev = (x - 2.0 * self.x_hist[0] + self.x_hist[1]) / (dt * dt);
        let f_u = match *controller {
            Controller::Imbic {
                m_rd,
                b_rd,
                k_rd,
                gamma,
            } => {
                let m_rd_inv = m_rd.map(|m| 1.0 / m);
                let desired = |xd: &Vector3<f64>, x: &Vector3<f64>| {
                    m_rd_inv.component_mul(&(b_rd.component_mul(xd) + k_rd.component_mul(x)))
                };
                // eq. (13) with x_rd = 0
                let v = m_rd_inv.component_mul(&(f_delta - f_sa_left))
                    + gamma.component_mul(
                        &(-(xdd_prev + desired(&xd_prev, &self.x_hist[0])) + self.v_prev),
                    );
                // eq. (12)
                let u = v - desired(&xd, &x);
                // eq. (14): M̄_x = J^-T M̄_φ J^-1
                let j_inv = j.try_inverse().ok_or_else(|| {
                    Error::invalid("robot", "singular Jacobian at the test location")
                })?;
                let m_bar_x = j_inv.transpose() * m_bar_phi * j_inv;
                // eq. (11): TDE of everything but M̄_x ẍ
                let f_u = m_bar_x * u + self.fu_prev - m_bar_x * xdd_prev;
                self.v_prev = v;
                f_u
            }
            Controller::Pd { b, k: kk } => f_delta - b.component_mul(&xd) - kk.component_mul(&x),
        };
        self.fu_prev = f_u;
        self.x_hist = [x, self.x_hist[0]];
        Ok(f_u)
    }
}

/// Integrate the robot holding the rig over one sample period in `substeps`
/// steps of `h`, the input `f_u` held: the rig's force after the first
/// substep (just after the sample instant) and after the last (just before the next).
fn plant_between_samples(
    rig: &RigExperiment,
    dynamics: &RobotDynamics,
    (q, qd): (&mut Vector3<f64>, &mut Vector3<f64>),
    (x_eq, r0, m_phi): (Vector3<f64>, &Matrix3<f64>, Matrix3<f64>),
    f_u: Vector3<f64>,
    (h, substeps): (f64, usize),
) -> Result<(Vector3<f64>, Vector3<f64>)> {
    let mut f_sa_right = None;
    let mut f_sa_left = Vector3::zeros();
    for _ in 0..substeps {
        let (pose, j) = dynamics.task(q.as_slice(), r0);
        let xs = pose - x_eq;
        let xsd = j * *qd;
        let spring = rig.damping * xsd + rig.stiffness * xs;
        let m_total = m_phi + j.transpose() * rig.inertia * j;
        let rhs = j.transpose() * (f_u - spring) - dynamics.friction(qd);
        let qdd = m_total
            .lu()
            .solve(&rhs)
            .ok_or_else(|| Error::invalid("robot", "singular inertia"))?;
        let f_sa = rig.inertia * (j * qdd) + spring;
        f_sa_right.get_or_insert(f_sa);
        f_sa_left = f_sa;
        *qd += qdd * h;
        *q += *qd * h;
    }
    Ok((f_sa_right.unwrap_or(f_sa_left), f_sa_left))
}
