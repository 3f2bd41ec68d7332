//! One request, run: recordings in, a result [`Document`] out.

use limpid_analysis::linear::{linear_result, shoulder_impedance, ShoulderPosture};
use limpid_analysis::result::{Document, Estimate};
use limpid_core::{Error, Recording, Result};
use limpid_ident::request::{
    Axis, Checked, CocontractionRequest, LinearRequest, PlanarRequest, PrepareRequest, Settings,
    StochasticRequest, SweepRequest, ValidArm, ValidPrepared,
};

/// A result and what its text rendering needs beyond it.
#[derive(Debug)]
pub struct Estimated {
    /// The result (no run block: the front-end adds how it was made).
    pub document: Document,
    /// Planar methods: the trials came from end-point data (inverse kinematics).
    pub from_endpoint: Option<bool>,
    /// Planar methods: the number of trials.
    pub trials: Option<usize>,
    /// The shoulder posture the estimate was turned into joint space at.
    pub posture: Option<ShoulderPosture>,
}

impl Estimated {
    fn of(estimate: Estimate) -> Self {
        Estimated {
            document: Document::new(estimate),
            from_endpoint: None,
            trials: None,
            posture: None,
        }
    }
}

/// Run a checked request on its recordings: the recording (co-contraction:
/// then the MVC recording; stochastic: one or more, pooled).
pub fn run(checked: &Checked, mut recordings: Vec<Recording>) -> Result<Estimated> {
    let request = checked.request();
    let (least, most) = request.inputs_expected();
    if recordings.len() < least || recordings.len() > most {
        return Err(Error::invalid(
            "recordings",
            format!(
                "{} reads {}, found {}",
                request.command(),
                if least == most {
                    format!("{least}")
                } else {
                    format!("at least {least}")
                },
                recordings.len()
            ),
        ));
    }
    match checked.settings() {
        Settings::Linear(r) => {
            let rec = with_robot(recordings.swap_remove(0), &r.prepare)?;
            linear(r, &rec)
        }
        Settings::Cocontraction(r) => {
            let mvc = recordings.pop().expect("two recordings counted above");
            let rec = with_robot(recordings.pop().expect("counted"), &r.prepare)?;
            cocontraction(r, &rec, &mvc)
        }
        Settings::Planar(r) => planar(r, &recordings[0]),
        Settings::WindowSweep(r) => sweep(r, &recordings[0]),
        Settings::Stochastic(r) => stochastic(r, recordings),
        Settings::Reflex(p) => Ok(Estimated::of(Estimate::Reflex(
            limpid_ident::reflex::estimate_reflex(&recordings[0], p)?,
        ))),
        Settings::Varying(p) => Ok(Estimated::of(Estimate::Varying(
            limpid_ident::varying::estimate_varying(&recordings[0], p)?,
        ))),
        Settings::Spectra(r) => {
            let rec = &recordings[0];
            let result = match r.period_s {
                Some(period_s) => {
                    limpid_ident::spectra::periodic_spectra(rec, &r.inputs, &r.outputs, period_s)?
                }
                None => {
                    let welch = r.welch(rec.len(), rec.sample_rate());
                    limpid_ident::spectra::spectra(rec, &r.inputs, &r.outputs, &welch)?
                }
            };
            Ok(Estimated::of(Estimate::Spectra(result)))
        }
    }
}

/// The end-effector pose from the robot's joint angles, when the request names a robot.
pub fn with_robot(mut rec: Recording, prepare: &PrepareRequest) -> Result<Recording> {
    let Some(name) = &prepare.robot else {
        return Ok(rec);
    };
    let robot = placed_robot(name, prepare.robot_base.as_deref())?;
    let poses = robot.poses(&rec, "robot joint angles for the robot's kinematics")?;
    for (a, column) in ["x", "y", "z"].iter().enumerate() {
        rec.set_column(column, poses.iter().map(|t| t[(a, 3)]).collect())?;
    }
    Ok(rec)
}

/// A robot by name (`kuka-lwr4`, `puma3` or a `.urdf` file), its base
/// placed at X,Y,Z (m) or X,Y,Z,ROLL,PITCH,YAW (rad) when given.
pub fn placed_robot(name: &str, base: Option<&[f64]>) -> Result<limpid_robot::Robot> {
    let robot = limpid_robot::Robot::by_name(name)?;
    match base {
        None => Ok(robot),
        Some(base) => robot.placed_at(base),
    }
}

/// The shoulder posture of a request's six numbers.
pub fn shoulder_posture(v: &[f64; 6]) -> ShoulderPosture {
    let [upper_arm_m, forearm_m, elbow_deg, flexion, abduction, rotation] = *v;
    ShoulderPosture {
        upper_arm_m,
        forearm_m,
        elbow_deg,
        angles_deg: [flexion, abduction, rotation],
    }
}

fn linear(r: &ValidPrepared<LinearRequest>, rec: &Recording) -> Result<Estimated> {
    // window by window: the prepared signals are never held whole (issue 16)
    let plan = limpid_ident::plan(rec, r.derived())?;
    let est = limpid_ident::fit_linear_plan(
        &plan,
        &limpid_ident::LinearParams {
            equilibrium: r.equilibrium,
            ..limpid_ident::LinearParams::default()
        },
    )?;
    let mut result = linear_result(&est, &plan.meta);
    let up = match r.vertical {
        Axis::X => nalgebra::Vector3::x(),
        Axis::Y => nalgebra::Vector3::y(),
        Axis::Z => nalgebra::Vector3::z(),
    };
    result.arm_configuration = limpid_analysis::markers::from_markers(rec, up)?;
    if let Some(v) = &r.shoulder {
        if result.stiffness.shape() != (3, 3) {
            return Err(Error::invalid("shoulder", "needs a 3-D estimate (x, y, z)"));
        }
        result.shoulder = Some(shoulder_impedance(&result, &shoulder_posture(v))?);
    }
    Ok(Estimated::of(Estimate::Linear(result)))
}

fn cocontraction(
    r: &ValidPrepared<CocontractionRequest>,
    rec: &Recording,
    mvc: &Recording,
) -> Result<Estimated> {
    let emg = limpid_analysis::emg::EmgParams {
        tolerance: r.tolerance,
        ..limpid_analysis::emg::EmgParams::default()
    };
    Ok(Estimated::of(Estimate::Cocontraction(
        limpid_analysis::cocontraction::estimate_cocontraction(rec, mvc, r.derived(), &emg)?,
    )))
}

fn planar(r: &ValidArm<PlanarRequest>, rec: &Recording) -> Result<Estimated> {
    let data = limpid_ident::planar::prepare_planar(rec, r.derived())?;
    let window = match r.window_ms {
        None => usize::MAX,
        Some(ms) => (ms * data.fs / 1000.0).round() as usize,
    };
    let est = limpid_ident::planar::estimate_planar(&data, window, r.arm.inertial_parameters)?;
    Ok(Estimated {
        from_endpoint: Some(data.from_endpoint),
        trials: Some(data.trials.len()),
        ..Estimated::of(Estimate::Planar(est))
    })
}

fn sweep(r: &ValidArm<SweepRequest>, rec: &Recording) -> Result<Estimated> {
    let data = limpid_ident::planar::prepare_planar(rec, r.derived())?;
    let sweep = limpid_ident::planar::window_sweep(
        &data,
        r.from_ms,
        r.to_ms,
        r.step_ms,
        r.arm.inertial_parameters,
    )?;
    Ok(Estimated {
        from_endpoint: Some(data.from_endpoint),
        trials: Some(data.trials.len()),
        ..Estimated::of(Estimate::WindowSweep(sweep))
    })
}

fn stochastic(r: &StochasticRequest, recordings: Vec<Recording>) -> Result<Estimated> {
    let posture = r.shoulder.as_ref().map(shoulder_posture);
    let recordings = match &posture {
        // Park & Chang (2011) §II-B: the shoulder's joint space before estimation
        Some(p) => recordings
            .iter()
            .map(|rec| limpid_analysis::shoulder::joint_space_recording(rec, p))
            .collect::<Result<Vec<_>>>()?,
        None => recordings,
    };
    let first = &recordings[0];
    let params = r.params(first.len(), first.sample_rate());
    let mut est = limpid_ident::stochastic::estimate_stochastic_pooled(&recordings, &params)?;
    if let Some(path) = &r.expected {
        let path = std::path::Path::new(path);
        let expected = limpid_ident::stochastic::ExpectedModel::from_json(
            path,
            &limpid_core::files::read_text(path)?,
        )?;
        est.accuracy = Some(limpid_ident::stochastic::accuracy(
            &est,
            &expected,
            params.band_hz,
        )?);
    }
    Ok(Estimated {
        posture,
        ..Estimated::of(Estimate::Stochastic(est))
    })
}
