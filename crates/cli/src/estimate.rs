//! `limpid estimate linear`: flags -> preparation and estimator settings.

use std::path::PathBuf;

use clap::{Args, Subcommand, ValueEnum};
use limpid_ident::request::{
    Axis, CocontractionRequest, Frame, LinearRequest, PrepareRequest, Request,
};
use limpid_ident::{Derivative, Offsets, Windowing};

use limpid_analysis::cocontraction::CocontractionResult;
use limpid_analysis::linear::LinearResult;

use crate::context::{CliResult, Context};
use crate::table;

#[derive(Subcommand)]
pub enum Method {
    /// Linear model M x'' + B x' + K (x - x_eq) = f by least squares (Artemiadis et al. 2010; Patel et al. 2013).
    Linear(LinearArgs),
    /// Co-contraction index and impedance per level, compared with the lowest level (Patel et al. 2013).
    Cocontraction(CocontractionArgs),
    /// Planar two-link arm in joint space: inertial parameters, K, D, confidence criteria (Lakatos et al. 2011).
    Planar(crate::planar::PlanarArgs),
    /// Stochastic MIMO impedance Z = T R^-1 from Welch spectra, with a parametric fit (Park & Chang 2011).
    Stochastic(crate::stochastic::StochasticArgs),
    /// Intrinsic and reflex joint stiffness by the parallel cascade (Kearney et al. 1997): IRFs, delay, gain, VAF split.
    Reflex(crate::reflex::ReflexArgs),
    /// Impedance that varies: against time within repeated trials (ensemble) or a measured schedule column (parameter-varying, optional reflex gain).
    Varying(crate::varying::VaryingArgs),
}

#[derive(Clone, Copy, ValueEnum)]
pub enum DerivativeArg {
    /// Butterworth zero-phase low-pass, then central differences.
    Central,
    /// Savitzky-Golay (cubic) smoothing and derivatives.
    Savgol,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum OffsetsArg {
    /// Fitted for trials longer than 2 s (slow perturbations), rest mean otherwise.
    Auto,
    /// Fit one force offset per trial (robust to slow drift; no equilibrium).
    Fit,
    /// Subtract the pre-onset rest mean (Artemiadis et al. 2010; Patel et al. 2013); equilibrium estimated.
    Rest,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum WindowArg {
    /// The trial column if present, else one continuous window.
    Auto,
    /// The trial column.
    Trials,
    /// Detect perturbation onsets from the motion.
    Onsets,
    /// One continuous window with a constant term.
    Continuous,
    /// The trial column, each trial a continuous window with its own offset (holds of a continuous perturbation; no rest needed).
    ContinuousTrials,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum FrameArg {
    /// Keep the recording's frame.
    Identity,
    /// Artemiadis et al. (2010) eq. (1): robot axes [X_R Y_R Z_R] = [-Y_H Z_H -X_H] to the human frame.
    Seed000,
}

/// Preparation flags shared by the estimators.
#[derive(Args)]
pub struct PrepareArgs {
    /// Low-pass cut-off in Hz (default: 30, at most 0.4 x sample rate).
    #[arg(long = "cutoff", value_name = "HZ")]
    pub cutoff_hz: Option<f64>,
    /// Butterworth order per pass.
    #[arg(long, default_value_t = PrepareRequest::default().order)]
    pub order: usize,
    /// How velocity and acceleration are computed.
    #[arg(long, value_enum, default_value_t = DerivativeArg::Central)]
    pub derivative: DerivativeArg,
    /// How per-trial force offsets are handled.
    #[arg(long, value_enum, default_value_t = OffsetsArg::Auto)]
    pub offsets: OffsetsArg,
    /// How the recording is cut into windows.
    #[arg(long, value_enum, default_value_t = WindowArg::Auto)]
    pub window: WindowArg,
    /// Frame change applied to x,y,z and fx,fy,fz.
    #[arg(long, value_enum, default_value_t = FrameArg::Identity)]
    pub frame: FrameArg,
    /// General transform: r11,r12,...,r33,tx,ty,tz (applied after --frame).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_name = "R11,..,R33,TX,TY,TZ"
    )]
    pub transform: Option<Vec<f64>>,
    /// The force columns hold the hand's force on the sensor: negate them.
    #[arg(long)]
    pub negate_force: bool,
    #[command(flatten)]
    pub robot: RobotArgs,
}

/// `--robot` and `--robot-base`: a robot whose `robot_q1..n` columns give the
/// end-effector pose by forward kinematics.
#[derive(Args)]
pub struct RobotArgs {
    /// Compute the end-effector pose from the robot_q1..n columns by this robot's forward kinematics (kuka-lwr4, puma3 or a .urdf file), as Artemiadis et al. (2010) does.
    #[arg(long, value_name = "ROBOT")]
    pub robot: Option<String>,
    /// Where the robot's base sits in the lab frame: X,Y,Z (m) or X,Y,Z,ROLL,PITCH,YAW (rad), as a protocol's `robot_base`.
    #[arg(
        long,
        value_name = "POSE",
        value_delimiter = ',',
        requires = "robot",
        allow_hyphen_values = true
    )]
    pub robot_base: Option<Vec<f64>>,
}

impl RobotArgs {
    /// The robot, placed as `--robot-base` says, if `--robot` is given.
    pub fn robot(&self) -> CliResult<Option<limpid_robot::Robot>> {
        let Some(name) = &self.robot else {
            return Ok(None);
        };
        Ok(Some(limpid_app::estimate::placed_robot(
            name,
            self.robot_base.as_deref(),
        )?))
    }
}

#[derive(Args)]
pub struct LinearArgs {
    /// Recording (CSV, Parquet or MATLAB .mat; the recording format: docs/src/format.md).
    pub recording: PathBuf,
    #[command(flatten)]
    pub prepare: PrepareArgs,
    /// Fit without the equilibrium constant (the 9-column form P = F Y^+ of Patel et al. 2013).
    #[arg(long)]
    pub no_equilibrium: bool,
    /// Use only trials of this condition level (the `level` column).
    #[arg(long)]
    pub level: Option<f64>,
    /// The upward vertical axis of the frame, for the arm configuration from
    /// `elbow_*`/`wrist_*` markers (Patel et al. 2013's frame has x vertical).
    #[arg(long, value_enum, default_value_t = AxisArg::Z)]
    pub vertical: AxisArg,
    /// Also give the shoulder's joint-space stiffness and damping J_h^T Z J_h (Park & Chang 2011's
    /// 3-DoF shoulder): UPPER_ARM_M,FOREARM_M,ELBOW_DEG,FLEXION_DEG,ABDUCTION_DEG,ROTATION_DEG
    /// (frame: x forward, y left, z up, origin at the shoulder; right arm). The hand's
    /// position cannot sense rotation about the shoulder-hand line: these matrices are
    /// singular along it (rank 2).
    #[arg(
        long,
        value_name = "L1,L2,E,F,A,R",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub shoulder: Option<Vec<f64>>,
    #[command(flatten)]
    pub output: crate::emit::OutputArgs,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum AxisArg {
    X,
    Y,
    Z,
}

#[derive(Args)]
pub struct CocontractionArgs {
    /// Recording with `level` and `emg_*` columns (Patel et al. 2013).
    pub recording: PathBuf,
    /// Maximum voluntary co-contraction recording with the same EMG channels.
    #[arg(long)]
    pub mvc: PathBuf,
    #[command(flatten)]
    pub prepare: PrepareArgs,
    /// Half-width of the band around the target level counted as "on target".
    #[arg(long, default_value_t = limpid_ident::request::DEFAULT_TOLERANCE)]
    pub tolerance: f64,
    #[command(flatten)]
    pub output: crate::emit::OutputArgs,
}

impl PrepareArgs {
    /// The preparation part of a request.
    pub fn request(&self, level: Option<f64>) -> PrepareRequest {
        PrepareRequest {
            cutoff_hz: self.cutoff_hz,
            order: self.order,
            derivative: match self.derivative {
                DerivativeArg::Central => Derivative::Central,
                DerivativeArg::Savgol => Derivative::Savgol,
            },
            offsets: match self.offsets {
                OffsetsArg::Fit => Offsets::Fit,
                OffsetsArg::Rest => Offsets::Rest,
                OffsetsArg::Auto => Offsets::Auto,
            },
            window: match self.window {
                WindowArg::Auto => Windowing::Auto,
                WindowArg::Trials => Windowing::Trials,
                WindowArg::Onsets => Windowing::Onsets,
                WindowArg::Continuous => Windowing::Continuous,
                WindowArg::ContinuousTrials => Windowing::ContinuousTrials,
            },
            frame: match self.frame {
                FrameArg::Identity => Frame::Identity,
                FrameArg::Seed000 => Frame::Seed000,
            },
            transform: self.transform.clone(),
            negate_force: self.negate_force,
            robot: self.robot.robot.clone(),
            robot_base: self.robot.robot_base.clone(),
            level,
        }
    }
}

/// Six numbers of `--shoulder`, or what is wrong with them.
pub(crate) fn shoulder_numbers(v: Option<&[f64]>) -> CliResult<Option<[f64; 6]>> {
    let Some(v) = v else { return Ok(None) };
    <[f64; 6]>::try_from(v).map(Some).map_err(|_| {
        limpid_core::Error::invalid(
            "--shoulder",
            format!(
                "expected 6 numbers (L1,L2,ELBOW,FLEXION,ABDUCTION,ROTATION), found {}",
                v.len()
            ),
        )
        .into()
    })
}

impl LinearArgs {
    /// The request these flags make.
    pub fn request(&self) -> CliResult<Request> {
        Ok(Request::Linear(LinearRequest {
            prepare: self.prepare.request(self.level),
            equilibrium: !self.no_equilibrium,
            vertical: match self.vertical {
                AxisArg::X => Axis::X,
                AxisArg::Y => Axis::Y,
                AxisArg::Z => Axis::Z,
            },
            shoulder: shoulder_numbers(self.shoulder.as_deref())?,
        }))
    }
}

impl CocontractionArgs {
    /// The request these flags make.
    pub fn request(&self) -> Request {
        Request::Cocontraction(CocontractionRequest {
            prepare: self.prepare.request(None),
            tolerance: self.tolerance,
        })
    }
}

pub fn run(method: Method, cx: &Context) -> CliResult {
    match method {
        Method::Linear(args) => crate::emit::estimate(
            cx,
            args.request()?,
            std::slice::from_ref(&args.recording),
            args.output.output(),
        ),
        Method::Planar(args) => crate::planar::run_estimate(args, cx),
        Method::Stochastic(args) => crate::stochastic::run_estimate(args, cx),
        Method::Reflex(args) => crate::reflex::run(args, cx),
        Method::Varying(args) => crate::varying::run(args, cx),
        Method::Cocontraction(args) => crate::emit::estimate(
            cx,
            args.request(),
            &[args.recording.clone(), args.mvc.clone()],
            args.output.output(),
        ),
    }
}

/// `limpid estimate cocontraction`'s text.
pub fn cocontraction_text(result: &CocontractionResult) -> CliResult {
    print!("{}", table::cocontraction_text(result));
    Ok(())
}

/// `limpid estimate linear`'s text: the matrices, the arm, the shoulder.
pub fn linear_text(result: &LinearResult) -> CliResult {
    print!("{}", table::linear_text(result));
    if let Some(a) = &result.arm_configuration {
        print!("{}", table::arm_configuration_text(a));
    }
    if let Some(s) = &result.shoulder {
        let row = |m: &limpid_core::Matrix, i: usize| {
            (0..3)
                .map(|j| table::num(m[(i, j)]))
                .collect::<Vec<_>>()
                .join(", ")
        };
        println!("shoulder joint stiffness J_h^T K J_h (N m/rad; flexion, abduction, rotation):");
        for i in 0..3 {
            println!("  [{}]", row(&s.stiffness, i));
        }
        println!("shoulder joint damping J_h^T B J_h (N m s/rad):");
        for i in 0..3 {
            println!("  [{}]", row(&s.damping, i));
        }
        println!("note: {}", s.note);
    }
    Ok(())
}
