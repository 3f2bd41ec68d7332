//! Perturbation protocols as TOML files (seed 000 §II-B, seed 001
//! "Procedure and Tasks"): start points, target directions, profile and phase
//! durations, and the safety limits that `limpid protocol check` enforces.
//!
//! This first version covers centre-out protocols in Cartesian space
//! (presets `artemiadis-3d` and `patel-cocontraction`). The limits are
//! checked on the exact kinematics of every trial: displacement from the
//! start point, speed, acceleration, the force a nominal stiffness would
//! need (`nominal_stiffness_n_per_m` times the displacement) and the
//! workspace box.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::profile::Profile;
use crate::sphere::{even_directions, min_separation_deg, octahedron_points};
use limpid_core::{Error, Result};

/// A centre-out protocol.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Protocol {
    /// Protocol name.
    pub name: String,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Where the perturbations start.
    pub start_points: StartPoints,
    /// Where they go.
    pub targets: Targets,
    /// Timing and profile.
    pub phases: Phases,
    /// Safety limits.
    pub limits: Limits,
    /// Where the robot's base sits in the protocol frame (for `protocol export`
    /// and `--robot`); absent: the robot's base frame is the protocol frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot_base: Option<Placement>,
}

/// A rigid placement: translation (m) and URDF roll-pitch-yaw (rad).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Placement {
    /// Translation (m).
    pub xyz_m: [f64; 3],
    #[serde(default)]
    /// Roll, pitch, yaw (rad).
    pub rpy_rad: [f64; 3],
}

/// Start points: explicit, or `count` (6: octahedron) on a sphere.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartPoints {
    /// Explicit points (m); when given, the sphere fields are ignored.
    #[serde(default)]
    pub points: Vec<[f64; 3]>,
    #[serde(default)]
    /// Centre of the sphere of start points (m).
    pub centre_m: [f64; 3],
    #[serde(default)]
    /// Radius of that sphere (m).
    pub radius_m: f64,
}

/// Target directions spread evenly on a sphere around each start point.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Targets {
    /// Number of target directions.
    pub count: usize,
    /// Distance from start to target (m).
    pub radius_m: f64,
}

/// Phase durations (s) and the profile of the centre-out motion.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Phases {
    /// Profile of the centre-out motion.
    pub profile: Profile,
    /// Rest recorded before each perturbation.
    pub rest_s: f64,
    /// Duration of the centre-out motion.
    pub centre_out_s: f64,
    /// Hold at the target, return duration, relax after the return (not recorded).
    pub hold_s: f64,
    /// Duration of the return.
    pub return_s: f64,
    /// Relax after the return (not recorded).
    pub relax_s: f64,
    /// Record the hold and the return too (seed 001 style); otherwise only the
    /// rest and the centre-out motion are recorded (seed 000, where the subject
    /// relaxes after it).
    #[serde(default)]
    pub record_hold_and_return: bool,
    /// Trials are given in sets of this many (seed 001: 6), with
    /// `set_rest_s` between sets; 0: one set.
    #[serde(default)]
    pub trials_per_set: usize,
    #[serde(default)]
    /// Rest between sets (s).
    pub set_rest_s: f64,
}

/// Safety limits.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Limits {
    /// Largest displacement (m).
    pub max_displacement_m: f64,
    /// Largest velocity (m/s).
    pub max_velocity_m_s: f64,
    /// Largest acceleration (m/s^2).
    pub max_acceleration_m_s2: f64,
    /// Largest predicted force (N).
    pub max_force_n: f64,
    /// Stiffness used to predict the force (N/m).
    pub nominal_stiffness_n_per_m: f64,
    /// Lower corner of the allowed workspace (m).
    pub workspace_min_m: [f64; 3],
    /// Upper corner of the allowed workspace (m).
    pub workspace_max_m: [f64; 3],
}

/// The presets, as TOML text.
pub fn preset(name: &str) -> Result<Protocol> {
    let p = match name {
        "artemiadis-3d" => Protocol {
            name: "Artemiadis et al. (2010): 6 start points on a 20 cm sphere, 16 targets at 3 cm, 3 s centre-out".into(),
            sample_rate_hz: 500.0,
            start_points: StartPoints { points: vec![], centre_m: [0.40, 0.0, 0.0], radius_m: 0.20 },
            targets: Targets { count: 16, radius_m: 0.03 },
            phases: Phases { profile: Profile::Cubic, rest_s: 0.2, centre_out_s: 3.0, hold_s: 2.0, return_s: 2.0, relax_s: 2.0, record_hold_and_return: false, trials_per_set: 0, set_rest_s: 0.0 },
            limits: Limits {
                max_displacement_m: 0.05,
                max_velocity_m_s: 0.1,
                max_acceleration_m_s2: 1.0,
                max_force_n: 60.0,
                nominal_stiffness_n_per_m: 1000.0,
                workspace_min_m: [0.1, -0.35, -0.35],
                workspace_max_m: [0.7, 0.35, 0.35],
            },
            // the KUKA LWR4+ below and behind the workspace, facing it: reaches every
            // start point and target with the home orientation held (robot.rs tests)
            robot_base: Some(Placement { xyz_m: [-0.05, 0.0, -0.6], rpy_rad: [0.0, 0.0, std::f64::consts::PI] }),
        },
        "patel-cocontraction" => Protocol {
            name: "Patel, O'Neill & Artemiadis (2013): 18 targets at 8 mm, 100 ms out, 500 ms hold, 100 ms back, 1 s rest".into(),
            sample_rate_hz: 1000.0,
            start_points: StartPoints { points: vec![[0.30, -0.20, 0.05]], centre_m: [0.0; 3], radius_m: 0.0 },
            targets: Targets { count: 18, radius_m: 0.008 },
            phases: Phases { profile: Profile::Cubic, rest_s: 0.05, centre_out_s: 0.1, hold_s: 0.5, return_s: 0.1, relax_s: 1.0, record_hold_and_return: true, trials_per_set: 6, set_rest_s: 10.0 },
            limits: Limits {
                max_displacement_m: 0.015,
                max_velocity_m_s: 0.2,
                max_acceleration_m_s2: 8.0,
                max_force_n: 60.0,
                nominal_stiffness_n_per_m: 3500.0,
                workspace_min_m: [0.0, -0.6, -0.4],
                workspace_max_m: [0.7, 0.3, 0.5],
            },
            robot_base: Some(Placement { xyz_m: [-0.05, 0.0, -0.6], rpy_rad: [0.0, 0.0, std::f64::consts::PI] }),
        },
        other => {
            return Err(Error::invalid(
                "preset",
                format!("{other:?} is not a centre-out preset; centre-out presets: artemiadis-3d, patel-cocontraction"),
            ))
        }
    };
    Ok(p)
}

impl Protocol {
    /// Parse and check the structure of a TOML protocol.
    pub fn from_toml(text: &str, path: &std::path::Path) -> Result<Self> {
        crate::validate::check_numbers(text, path)?;
        let p: Protocol = crate::validate::parse_settings(text, path)?;
        if p.start_points.points.len() > crate::validate::MAX_TARGETS as usize
            || p.targets.count > crate::validate::MAX_TARGETS as usize
        {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "{} start points and {} targets; a protocol has at most {} of each",
                    p.start_points.points.len(),
                    p.targets.count,
                    crate::validate::MAX_TARGETS
                ),
            });
        }
        if p.sample_rate_hz <= 0.0
            || p.targets.count == 0
            || p.targets.radius_m <= 0.0
            || p.phases.centre_out_s <= 0.0
        {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: "sample_rate_hz, targets.count, targets.radius_m and phases.centre_out_s must be positive".into(),
            });
        }
        Ok(p)
    }

    /// TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// The start points (m).
    pub fn start_points(&self) -> Vec<Vector3<f64>> {
        if !self.start_points.points.is_empty() {
            return self
                .start_points
                .points
                .iter()
                .map(|p| Vector3::new(p[0], p[1], p[2]))
                .collect();
        }
        octahedron_points(
            Vector3::from(self.start_points.centre_m),
            self.start_points.radius_m,
        )
    }

    /// The unit target directions.
    pub fn directions(&self) -> Vec<Vector3<f64>> {
        even_directions(self.targets.count)
    }

    /// The recorded part of each trial, for [`crate::simulate_centre_out`]:
    /// rest and centre-out, plus hold and return when they are recorded.
    pub fn centre_out(&self) -> crate::CentreOut {
        let recorded = |v: f64| {
            if self.phases.record_hold_and_return {
                v
            } else {
                0.0
            }
        };
        crate::CentreOut {
            profile: self.phases.profile,
            radius_m: self.targets.radius_m,
            directions: self.directions(),
            rest_s: self.phases.rest_s,
            motion_s: self.phases.centre_out_s,
            hold_s: recorded(self.phases.hold_s),
            return_s: recorded(self.phases.return_s),
            sample_rate: self.sample_rate_hz,
        }
    }
}

/// What `check` found.
#[derive(Debug, Clone, Serialize)]
pub struct CheckReport {
    /// Trials in the protocol.
    pub trials: usize,
    /// Samples per recorded trial.
    pub samples_per_trial: usize,
    /// Smallest angle between two target directions (deg).
    pub min_separation_deg: f64,
    /// Largest displacement (m).
    pub peak_displacement_m: f64,
    /// Largest velocity (m/s).
    pub peak_velocity_m_s: f64,
    /// Largest acceleration (m/s^2).
    pub peak_acceleration_m_s2: f64,
    /// Largest predicted force (N).
    pub peak_force_n: f64,
    /// Seed 003 eq. (17) ratios of the profile: [C_12, C_13, C_23] (mean squares of
    /// velocity/acceleration/jerk, over the centre-out phase).
    pub conditioning_ratios: [f64; 3],
}

/// Check every sample of every trial against the limits; the first breach is an error naming the limit and the sample.
pub fn check(p: &Protocol) -> Result<CheckReport> {
    let dirs = p.directions();
    let starts = p.start_points();
    let fs = p.sample_rate_hz;
    let l = &p.limits;
    let d = p.targets.radius_m;
    let per = ((p.phases.rest_s + p.phases.centre_out_s) * fs).round() as usize;
    let mut report = CheckReport {
        trials: dirs.len() * starts.len(),
        samples_per_trial: per,
        min_separation_deg: min_separation_deg(&dirs),
        peak_displacement_m: 0.0,
        peak_velocity_m_s: 0.0,
        peak_acceleration_m_s2: 0.0,
        peak_force_n: 0.0,
        // the ratios do not depend on the amplitude; 1 keeps a tiny radius from underflowing to 0/0
        conditioning_ratios: conditioning_ratios(p.phases.profile, p.phases.centre_out_s, 1.0),
    };
    let breach = |limit: &str, value: f64, max: f64, s: usize, t: usize, time: f64| {
        Err(Error::invalid(
            "protocol",
            format!("{limit} {value:.4} exceeds the limit {max} at start point {}, target {}, t = {time:.3} s after the onset", s + 1, t + 1),
        ))
    };
    for (si, s) in starts.iter().enumerate() {
        for (ti, dir) in dirs.iter().enumerate() {
            for i in 0..per {
                let time = i as f64 / fs - p.phases.rest_s;
                let (x, v, a) = p.phases.profile.eval(time, p.phases.centre_out_s);
                let (disp, vel, acc) = (d * x.abs(), d * v.abs(), d * a.abs());
                let force = l.nominal_stiffness_n_per_m * disp;
                report.peak_displacement_m = report.peak_displacement_m.max(disp);
                report.peak_velocity_m_s = report.peak_velocity_m_s.max(vel);
                report.peak_acceleration_m_s2 = report.peak_acceleration_m_s2.max(acc);
                report.peak_force_n = report.peak_force_n.max(force);
                if disp > l.max_displacement_m {
                    return breach("displacement (m)", disp, l.max_displacement_m, si, ti, time);
                }
                if vel > l.max_velocity_m_s {
                    return breach("velocity (m/s)", vel, l.max_velocity_m_s, si, ti, time);
                }
                if acc > l.max_acceleration_m_s2 {
                    return breach(
                        "acceleration (m/s^2)",
                        acc,
                        l.max_acceleration_m_s2,
                        si,
                        ti,
                        time,
                    );
                }
                if force > l.max_force_n {
                    return breach("expected force (N)", force, l.max_force_n, si, ti, time);
                }
                let pos = s + dir * (d * x);
                for k in 0..3 {
                    if pos[k] < l.workspace_min_m[k] || pos[k] > l.workspace_max_m[k] {
                        return Err(Error::invalid(
                            "protocol",
                            format!(
                                "position {:.4} m on axis {} leaves the workspace [{}, {}] at start point {}, target {}, t = {time:.3} s after the onset",
                                pos[k], ["x", "y", "z"][k], l.workspace_min_m[k], l.workspace_max_m[k], si + 1, ti + 1
                            ),
                        ));
                    }
                }
            }
        }
    }
    // between samples: the continuous profile's peaks (a motion shorter than a
    // sample period would otherwise pass with peak velocity 0)
    let (_, v, a) = p.phases.profile.peaks(p.phases.centre_out_s);
    for (limit, value, max) in [
        ("velocity (m/s)", d * v, l.max_velocity_m_s),
        ("acceleration (m/s^2)", d * a, l.max_acceleration_m_s2),
    ] {
        if value > max {
            return Err(Error::invalid(
                "protocol",
                format!("{limit} {value:.4} exceeds the limit {max} during the centre-out motion (peak of the continuous profile)"),
            ));
        }
    }
    Ok(report)
}

/// Seed 003 eq. (17): C_ij = mean(q^(i)^2) / mean(q^(j)^2) over the motion,
/// for (i, j) = (1, 2), (1, 3), (2, 3); derivatives by the profile's exact
/// first two and a central difference for the third.
pub fn conditioning_ratios(profile: Profile, duration: f64, amplitude: f64) -> [f64; 3] {
    let n = 2000;
    let h = duration / n as f64;
    let (mut m1, mut m2, mut m3) = (0.0, 0.0, 0.0);
    for k in 0..n {
        let t = (k as f64 + 0.5) * h;
        let (_, v, a) = profile.eval(t, duration);
        let jerk = (profile.eval(t + 1e-6 * duration, duration).2
            - profile.eval(t - 1e-6 * duration, duration).2)
            / (2e-6 * duration);
        m1 += (amplitude * v).powi(2);
        m2 += (amplitude * a).powi(2);
        m3 += (amplitude * jerk).powi(2);
    }
    [m1 / m2, m1 / m3, m2 / m3]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_round_trip_and_pass_their_own_check() {
        for name in ["artemiadis-3d", "patel-cocontraction"] {
            let p = preset(name).unwrap();
            let back = Protocol::from_toml(&p.to_toml(), std::path::Path::new("p.toml")).unwrap();
            assert_eq!(back.targets.count, p.targets.count);
            let r = check(&back).unwrap();
            assert!(r.peak_displacement_m <= p.targets.radius_m * (1.0 + 1e-12));
        }
    }

    #[test]
    fn over_fast_protocol_is_refused_naming_the_limit() {
        let mut p = preset("artemiadis-3d").unwrap();
        p.phases.centre_out_s = 0.2; // 3 cm in 200 ms: 4.5 m/s^2 at the start of a cubic
        let e = check(&p).unwrap_err().to_string();
        assert_eq!(e, "invalid protocol: acceleration (m/s^2) 4.4100 exceeds the limit 1 at start point 1, target 1, t = 0.002 s after the onset");
    }

    #[test]
    fn quintic_is_closer_to_one_than_a_sixth_order_polynomial() {
        // seed 003 Table I: the 5th-order profile's C_ij lie nearer 1 than those of the
        // 6th-order polynomial with the extra boundary condition q'''(tf) = 0
        let quintic = conditioning_ratios(Profile::Quintic, 1.0, 1.0);
        // the 6th-order polynomial with q(0) = q'(0) = q''(0) = 0 and q(1) = 1,
        // q'(1) = q''(1) = q'''(1) = 0: q = 20 t^3 - 45 t^4 + 36 t^5 - 10 t^6
        let sixth = |t: f64| {
            let q = 20.0 * t.powi(3) - 45.0 * t.powi(4) + 36.0 * t.powi(5) - 10.0 * t.powi(6);
            let v = 60.0 * t.powi(2) - 180.0 * t.powi(3) + 180.0 * t.powi(4) - 60.0 * t.powi(5);
            let a = 120.0 * t - 540.0 * t.powi(2) + 720.0 * t.powi(3) - 300.0 * t.powi(4);
            let j = 120.0 - 1080.0 * t + 2160.0 * t.powi(2) - 1200.0 * t.powi(3);
            (q, v, a, j)
        };
        // boundary conditions of the 6th-order polynomial
        let (q0, v0, a0, _) = sixth(0.0);
        let (q1, v1, a1, j1) = sixth(1.0);
        assert!(
            q0 == 0.0
                && v0 == 0.0
                && a0 == 0.0
                && (q1 - 1.0).abs() < 1e-12
                && v1.abs() < 1e-9
                && a1.abs() < 1e-9
                && j1.abs() < 1e-9
        );
        let n = 2000;
        let (mut m1, mut m2, mut m3) = (0.0, 0.0, 0.0);
        for k in 0..n {
            let (_, v, a, j) = sixth((k as f64 + 0.5) / n as f64);
            m1 += v * v;
            m2 += a * a;
            m3 += j * j;
        }
        let six = [m1 / m2, m1 / m3, m2 / m3];
        for k in 0..3 {
            assert!(
                (quintic[k].ln()).abs() < (six[k].ln()).abs(),
                "C[{k}]: quintic {} vs sixth {}",
                quintic[k],
                six[k]
            );
        }
    }
}
