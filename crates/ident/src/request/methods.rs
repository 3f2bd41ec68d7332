//! The request of each method: its fields (with units), defaults and the
//! estimator settings they make.

use limpid_core::{Error, FrameTransform, Result};
use limpid_dsp::spectral::{Welch, Window};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::options::{boolean_names, field_names};
use super::{Method, DEFAULT_BAND_HZ, DEFAULT_SWEEP_MS, DEFAULT_TOLERANCE};
use crate::estimator::positive;
use crate::planar::{Arm, PlanarPrepare};
use crate::prepare::{Derivative, Offsets, PrepareParams, Windowing};
use crate::stochastic::StochasticParams;

/// Fixed-length lists of numbers read with a message people understand
/// ("expected 6 numbers, found 5") from any front-end.
mod numbers {
    use serde::{Deserialize, Deserializer};

    fn sized<E: serde::de::Error, const N: usize>(v: Vec<f64>) -> Result<[f64; N], E> {
        <[f64; N]>::try_from(v.as_slice())
            .map_err(|_| E::custom(format!("expected {N} numbers, found {}", v.len())))
    }

    pub fn exact<'de, D: Deserializer<'de>, const N: usize>(d: D) -> Result<[f64; N], D::Error> {
        sized(Vec::<f64>::deserialize(d)?)
    }

    pub fn optional<'de, D: Deserializer<'de>, const N: usize>(
        d: D,
    ) -> Result<Option<[f64; N]>, D::Error> {
        Option::<Vec<f64>>::deserialize(d)?
            .map(sized::<D::Error, N>)
            .transpose()
    }

    /// `N` numbers separated by commas, as a flag takes them (`--band 0.5,10`).
    #[cfg(any(feature = "clap", test))]
    pub fn parse<const N: usize>(text: &str) -> Result<[f64; N], String> {
        let values = text
            .split(',')
            .map(|v| {
                v.trim()
                    .parse::<f64>()
                    .map_err(|_| format!("'{}' is not a number", v.trim()))
            })
            .collect::<Result<Vec<f64>, String>>()?;
        <[f64; N]>::try_from(values.as_slice()).map_err(|_| {
            format!(
                "expected {N} numbers separated by commas, found {}",
                values.len()
            )
        })
    }
}

/// The default band of the stochastic fit as its flag writes it.
pub const DEFAULT_BAND_TEXT: &str = "0.5,10";

/// Frame change applied to `x,y,z` and `fx,fy,fz` before anything else.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Frame {
    /// Keep the recording's frame.
    #[default]
    Identity,
    /// Artemiadis et al. (2010) eq. (1): robot axes [X_R Y_R Z_R] = [-Y_H Z_H -X_H] to the human frame.
    #[serde(alias = "artemiadis2010")]
    Seed000,
}

/// The upward vertical axis of the recording's frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// x up (Patel et al. 2013's frame).
    X,
    /// y up.
    Y,
    /// z up.
    #[default]
    Z,
}

/// Window applied to each Welch segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum SegmentWindow {
    /// Periodic Hann.
    #[default]
    Hann,
    /// Periodic Hamming.
    Hamming,
    /// Rectangular.
    Boxcar,
}

/// How a recording is read and prepared for the linear estimators
/// (Artemiadis et al. 2010 §II-C; Patel et al. 2013 "Data Processing").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(default, deny_unknown_fields)]
pub struct PrepareRequest {
    /// Low-pass cut-off (Hz) [default: 30 Hz, at most 0.4 x the sample rate].
    #[cfg_attr(feature = "clap", arg(long = "cutoff", value_name = "HZ"))]
    pub cutoff_hz: Option<f64>,
    /// Butterworth order per pass.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = PrepareRequest::default().order))]
    pub order: usize,
    /// How velocity and acceleration are computed.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = PrepareRequest::default().derivative))]
    pub derivative: Derivative,
    /// How per-trial force offsets are handled.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = PrepareRequest::default().offsets))]
    pub offsets: Offsets,
    /// How the recording is cut into windows.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = PrepareRequest::default().window))]
    pub window: Windowing,
    /// Frame change applied to positions (`x,y,z`) and forces (`fx,fy,fz`).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = Frame::Identity))]
    pub frame: Frame,
    /// General transform r11,r12,..,r33,tx,ty,tz (m), applied after `frame`.
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            value_delimiter = ',',
            allow_hyphen_values = true,
            value_name = "R11,..,R33,TX,TY,TZ"
        )
    )]
    pub transform: Option<Vec<f64>>,
    /// The force columns hold the hand's force on the sensor: negate them.
    #[cfg_attr(feature = "clap", arg(long))]
    pub negate_force: bool,
    /// The end-effector pose from the `robot_q1..n` columns by this robot's
    /// forward kinematics (`kuka-lwr4`, `puma3` or a `.urdf` file), as
    /// Artemiadis et al. (2010) does.
    #[cfg_attr(feature = "clap", arg(long, value_name = "ROBOT"))]
    pub robot: Option<String>,
    /// Where the robot's base sits in the lab frame: X,Y,Z (m) or X,Y,Z,ROLL,PITCH,YAW (rad), as a protocol's `robot_base`.
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            value_name = "POSE",
            value_delimiter = ',',
            requires = "robot",
            allow_hyphen_values = true
        )
    )]
    pub robot_base: Option<Vec<f64>>,
    /// Use only windows of this condition level (the `level` column).
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    pub level: Option<f64>,
    /// Regress on the measured motion even when commanded reference columns (`rx, ry, rz` for `x, y, z`; `r1` for `q1`) are recorded: right only when the robot imposed the motion; by default a reference makes the estimate closed-loop (fitted on the motion the reference predicts).
    #[cfg_attr(feature = "clap", arg(long = "open-loop"))]
    pub open_loop: bool,
}

impl Default for PrepareRequest {
    fn default() -> Self {
        let p = PrepareParams::default();
        PrepareRequest {
            cutoff_hz: p.cutoff_hz,
            order: p.filter_order,
            derivative: p.derivative,
            offsets: p.offsets,
            window: p.windowing,
            frame: Frame::Identity,
            transform: None,
            negate_force: p.negate_force,
            robot: None,
            robot_base: None,
            level: p.level,
            open_loop: p.open_loop,
        }
    }
}

impl PrepareRequest {
    /// The preparation settings (the robot is applied by whoever reads the recording).
    pub fn params(&self) -> Result<PrepareParams> {
        if self.robot.is_none() && self.robot_base.is_some() {
            return Err(Error::invalid("robot_base", "needs a robot"));
        }
        let mut transform = match self.frame {
            Frame::Identity => None,
            Frame::Seed000 => Some(FrameTransform::seed000_robot_to_human()),
        };
        if let Some(values) = &self.transform {
            let t = FrameTransform::from_values(values)?;
            transform = Some(match transform {
                Some(first) => FrameTransform {
                    rotation: t.rotation * first.rotation,
                    translation: t.rotation * first.translation + t.translation,
                },
                None => t,
            });
        }
        Ok(PrepareParams {
            windowing: self.window,
            cutoff_hz: self.cutoff_hz,
            filter_order: self.order,
            derivative: self.derivative,
            offsets: self.offsets,
            negate_force: self.negate_force,
            transform,
            level: self.level,
            open_loop: self.open_loop,
            ..PrepareParams::default()
        })
    }
}

/// Artemiadis et al. (2010)'s linear model `M x'' + B x' + K (x - x_eq) = f`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(default, deny_unknown_fields)]
pub struct LinearRequest {
    /// Reading and preparation.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub prepare: PrepareRequest,
    /// Fit the equilibrium constant (false: the 9-column form P = F Y^+ of Patel et al. 2013).
    #[cfg_attr(
        feature = "clap",
        arg(
            long = "no-equilibrium",
            action = clap::ArgAction::SetFalse,
            help = "Fit without the equilibrium constant (the 9-column form P = F Y^+ of Patel et al. 2013)"
        )
    )]
    pub equilibrium: bool,
    /// The upward axis of the frame, for the arm configuration from
    /// `elbow_*`/`wrist_*` markers (Patel et al. 2013's frame has x up).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = Axis::Z))]
    pub vertical: Axis,
    /// Also the shoulder's joint-space stiffness and damping J_h^T Z J_h (Park & Chang 2011):
    /// upper arm (m), forearm (m), elbow, flexion, abduction, rotation (deg).
    ///
    /// Frame: x forward, y left, z up, origin at the shoulder; right arm. The
    /// hand's position cannot sense rotation about the shoulder-hand line:
    /// these matrices are singular along it (rank 2).
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            value_name = "L1,L2,E,F,A,R",
            value_parser = numbers::parse::<6>,
            allow_hyphen_values = true
        )
    )]
    #[serde(deserialize_with = "numbers::optional")]
    pub shoulder: Option<[f64; 6]>,
}

impl Default for LinearRequest {
    fn default() -> Self {
        LinearRequest {
            prepare: PrepareRequest::default(),
            equilibrium: true,
            vertical: Axis::Z,
            shoulder: None,
        }
    }
}

/// Patel, O'Neill & Artemiadis (2013)'s co-contraction analysis (the MVC
/// recording is the second input).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(default, deny_unknown_fields)]
pub struct CocontractionRequest {
    /// Reading and preparation.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub prepare: PrepareRequest,
    /// Half-width of the band around the target level counted as "on target".
    #[cfg_attr(feature = "clap", arg(long, default_value_t = DEFAULT_TOLERANCE))]
    pub tolerance: f64,
}

impl Default for CocontractionRequest {
    fn default() -> Self {
        CocontractionRequest {
            prepare: PrepareRequest::default(),
            tolerance: DEFAULT_TOLERANCE,
        }
    }
}

/// The planar two-link arm (Lakatos et al. 2011).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(deny_unknown_fields)]
pub struct ArmRequest {
    /// Upper-arm and forearm lengths (m).
    #[cfg_attr(feature = "clap", arg(long, value_name = "L1,L2", value_parser = numbers::parse::<2>))]
    #[serde(deserialize_with = "numbers::exact")]
    pub link_lengths: [f64; 2],
    /// Shoulder position in the recording's frame (m).
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            value_name = "X,Y",
            value_parser = numbers::parse::<2>,
            default_value = "0,0",
            allow_hyphen_values = true
        )
    )]
    #[serde(default, deserialize_with = "numbers::exact")]
    pub shoulder: [f64; 2],
    /// Inverse-kinematics branch for end-point data: the elbow angle q2 negative.
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default)]
    pub elbow_negative: bool,
    /// Low-pass cut-off (Hz) [default: 30 Hz, at most 0.4 x the sample rate].
    #[cfg_attr(feature = "clap", arg(long = "cutoff", value_name = "HZ"))]
    #[serde(default)]
    pub cutoff_hz: Option<f64>,
    /// Known base inertial parameters xi1..xi3 (kg m²): the reduced 8-parameter model (eq. 23-25).
    #[cfg_attr(feature = "clap", arg(long, value_name = "A,B,C", value_parser = numbers::parse::<3>))]
    #[serde(default, deserialize_with = "numbers::optional")]
    pub inertial_parameters: Option<[f64; 3]>,
}

impl ArmRequest {
    /// An arm of these link lengths (m), every other field at its default.
    pub fn new(link_lengths: [f64; 2]) -> Self {
        ArmRequest {
            link_lengths,
            shoulder: [0.0; 2],
            elbow_negative: false,
            cutoff_hz: None,
            inertial_parameters: None,
        }
    }

    /// The preparation of the planar trials.
    pub fn prepare(&self) -> PlanarPrepare {
        let [l1, l2] = self.link_lengths;
        PlanarPrepare {
            arm: Arm {
                l1,
                l2,
                shoulder: self.shoulder,
            },
            cutoff_hz: self.cutoff_hz,
            elbow_positive: !self.elbow_negative,
            ..PlanarPrepare::new(l1, l2)
        }
    }
}

/// One planar estimate (Lakatos et al. 2011).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(deny_unknown_fields)]
pub struct PlanarRequest {
    /// The arm.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub arm: ArmRequest,
    /// Observation window after the perturbation onset (ms) [default: every sample of every trial].
    #[cfg_attr(feature = "clap", arg(long, value_name = "T"))]
    #[serde(default)]
    pub window_ms: Option<f64>,
}

/// Planar estimates over a range of observation windows (Lakatos et al. 2011).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(deny_unknown_fields)]
pub struct SweepRequest {
    /// The arm.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub arm: ArmRequest,
    /// Shortest observation window (ms).
    #[cfg_attr(feature = "clap", arg(long = "from", default_value_t = sweep_from(), value_name = "MS"))]
    #[serde(default = "sweep_from")]
    pub from_ms: f64,
    /// Longest observation window (ms).
    #[cfg_attr(feature = "clap", arg(long = "to", default_value_t = sweep_to(), value_name = "MS"))]
    #[serde(default = "sweep_to")]
    pub to_ms: f64,
    /// Step (ms).
    #[cfg_attr(feature = "clap", arg(long = "step", default_value_t = sweep_step(), value_name = "MS"))]
    #[serde(default = "sweep_step")]
    pub step_ms: f64,
}

fn sweep_from() -> f64 {
    DEFAULT_SWEEP_MS[0]
}
fn sweep_to() -> f64 {
    DEFAULT_SWEEP_MS[1]
}
fn sweep_step() -> f64 {
    DEFAULT_SWEEP_MS[2]
}

impl SweepRequest {
    /// A sweep of this arm over the default windows.
    pub fn new(arm: ArmRequest) -> Self {
        SweepRequest {
            arm,
            from_ms: sweep_from(),
            to_ms: sweep_to(),
            step_ms: sweep_step(),
        }
    }
}

/// Park & Chang (2011)'s stochastic MIMO estimate (several inputs are pooled).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(default, deny_unknown_fields)]
pub struct StochasticRequest {
    /// Samples per segment (= FFT length) [default: about 4 s, a power of two].
    #[cfg_attr(feature = "clap", arg(long = "nfft", value_name = "N"))]
    pub nperseg: Option<usize>,
    /// Overlapping samples [default: half a segment].
    #[cfg_attr(feature = "clap", arg(long = "overlap", value_name = "N"))]
    pub noverlap: Option<usize>,
    /// Segment window.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = SegmentWindow::Hann))]
    pub window: SegmentWindow,
    /// Band of the parametric fit and accuracy measures (Hz).
    #[cfg_attr(
        feature = "clap",
        arg(
            long = "band",
            value_name = "LO,HI",
            value_parser = numbers::parse::<2>,
            default_value = DEFAULT_BAND_TEXT
        )
    )]
    #[serde(deserialize_with = "numbers::exact")]
    pub band_hz: [f64; 2],
    /// The shoulder's joint space before estimation (Park & Chang 2011 eq. (3)):
    /// upper arm (m), forearm (m), elbow, flexion, abduction, rotation (deg).
    ///
    /// Hand X, Z (with F and u) become flexion and abduction (τ = J_h^T F)
    /// and theta, tauy, utheta internal rotation. Frame: x forward, y left,
    /// z up, origin at the shoulder; right arm; the recording's mean X, Z is
    /// the hand at this posture.
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            value_name = "L1,L2,E,F,A,R",
            value_parser = numbers::parse::<6>,
            allow_hyphen_values = true
        )
    )]
    #[serde(deserialize_with = "numbers::optional")]
    pub shoulder: Option<[f64; 6]>,
    /// A truth or expected model (JSON with inertia, damping, stiffness): accuracy phi_T, phi_ij (eq. 15-16).
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE"))]
    pub expected: Option<String>,
    /// Period (s) of a periodic command (multisine, PRBS): whole periods are
    /// averaged instead of Welch segments (a `period` column numbers them,
    /// -1 the transient; without it the first period is left out); M, B, K
    /// are fitted at the excited lines with errors from the period-to-period
    /// scatter, and Z on groups of lines holding every command.
    #[cfg_attr(feature = "clap", arg(long = "period", value_name = "S"))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period_s: Option<f64>,
}

impl Default for StochasticRequest {
    fn default() -> Self {
        StochasticRequest {
            nperseg: None,
            noverlap: None,
            window: SegmentWindow::Hann,
            band_hz: DEFAULT_BAND_HZ,
            shoulder: None,
            expected: None,
            period_s: None,
        }
    }
}

impl StochasticRequest {
    /// The estimator's settings for a recording of `n` samples at `fs` Hz.
    pub fn params(&self, n: usize, fs: f64) -> StochasticParams {
        StochasticParams {
            welch: Some(welch(self.nperseg, self.noverlap, self.window, n, fs)),
            band_hz: (self.band_hz[0], self.band_hz[1]),
            period_s: self.period_s,
        }
    }
}

/// Welch segments for `n` samples at `fs` Hz: the given length and overlap,
/// else about 4 s (a power of two) overlapping by half.
fn welch(
    nperseg: Option<usize>,
    noverlap: Option<usize>,
    window: SegmentWindow,
    n: usize,
    fs: f64,
) -> Welch {
    let mut w = crate::stochastic::default_welch(n, fs);
    if let Some(nperseg) = nperseg {
        w.nperseg = nperseg;
    }
    w.noverlap = noverlap;
    w.window = match window {
        SegmentWindow::Hann => Window::Hann,
        SegmentWindow::Hamming => Window::Hamming,
        SegmentWindow::Boxcar => Window::Boxcar,
    };
    w
}

/// Welch spectra, ordinary, multiple and partial coherences of named columns
/// (Park & Chang 2011 §III, eq. 3-6), as `limpid spectra` computes them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(deny_unknown_fields)]
pub struct SpectraRequest {
    /// Input columns.
    #[cfg_attr(feature = "clap", arg(long, value_delimiter = ',', required = true))]
    pub inputs: Vec<String>,
    /// Output columns.
    #[cfg_attr(feature = "clap", arg(long, value_delimiter = ',', required = true))]
    pub outputs: Vec<String>,
    /// Samples per segment (= FFT length) [default: about 4 s, a power of two].
    #[cfg_attr(feature = "clap", arg(long = "nfft", value_name = "N"))]
    #[serde(default)]
    pub nperseg: Option<usize>,
    /// Overlapping samples [default: half a segment].
    #[cfg_attr(feature = "clap", arg(long = "overlap", value_name = "N"))]
    #[serde(default)]
    pub noverlap: Option<usize>,
    /// Segment window.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = SegmentWindow::Hann))]
    #[serde(default)]
    pub window: SegmentWindow,
    /// Period of a periodic excitation (s): spectra over whole periods
    /// (no window, no overlap), the response at the excited lines and the
    /// nonlinear distortion at the detection lines (issue 59).
    ///
    /// A `period` column numbers the periods (-1: transient, left out);
    /// without it the first period is left out. The response's standard
    /// errors come from the period-to-period scatter.
    #[cfg_attr(feature = "clap", arg(long = "period", value_name = "S"))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period_s: Option<f64>,
}

impl SpectraRequest {
    /// The spectra of these columns, every other field at its default.
    pub fn new(inputs: Vec<String>, outputs: Vec<String>) -> Self {
        SpectraRequest {
            inputs,
            outputs,
            nperseg: None,
            noverlap: None,
            window: SegmentWindow::default(),
            period_s: None,
        }
    }

    /// The Welch settings for a recording of `n` samples at `fs` Hz (the stochastic request's rule).
    pub fn welch(&self, n: usize, fs: f64) -> Welch {
        welch(self.nperseg, self.noverlap, self.window, n, fs)
    }
}

/// A period (s) must be positive and comes without Welch segments: a
/// periodic analysis takes whole periods as its segments.
fn check_period(
    period_s: Option<f64>,
    nperseg: Option<usize>,
    noverlap: Option<usize>,
) -> Result<()> {
    if let Some(p) = period_s {
        positive("period_s", p)?;
        if nperseg.is_some() || noverlap.is_some() {
            return Err(Error::invalid(
                "period_s",
                "a periodic analysis takes whole periods as its segments: leave out the segment length and overlap",
            ));
        }
    }
    Ok(())
}

/// The checks shared by the methods that prepare a recording or a planar arm.
fn finite(name: &str, v: f64) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Error::invalid(
            name,
            format!(
                "expected a finite number, found {}",
                limpid_core::error::Num(v)
            ),
        ))
    }
}

/// A request that passed its method's check, with what is derived from it
/// once (the preparation's settings, the planar arm); only the check makes
/// one, and it reads as its request.
#[derive(Debug, Clone)]
pub struct Valid<R, D> {
    request: R,
    derived: D,
}

impl<R, D> std::ops::Deref for Valid<R, D> {
    type Target = R;

    fn deref(&self) -> &R {
        &self.request
    }
}

impl<R, D> Valid<R, D> {
    /// What the check derived from the request.
    pub fn derived(&self) -> &D {
        &self.derived
    }
}

/// The settings of the linear and co-contraction methods once checked.
pub type ValidPrepared<R> = Valid<R, PrepareParams>;
/// The settings of the planar methods once checked.
pub type ValidArm<R> = Valid<R, PlanarPrepare>;

pub(crate) fn check_prepare(p: &PrepareRequest) -> Result<PrepareParams> {
    if !(1..=20).contains(&p.order) {
        return Err(Error::invalid(
            "order",
            format!(
                "expected a Butterworth order from 1 to 20, found {}",
                p.order
            ),
        ));
    }
    if let Some(c) = p.cutoff_hz {
        positive("cutoff_hz", c)?;
    }
    if let Some(l) = p.level {
        finite("level", l)?;
    }
    p.params()
}

pub(crate) fn check_arm(a: &ArmRequest) -> Result<PlanarPrepare> {
    for v in a.link_lengths {
        positive("link_lengths", v)?;
    }
    for v in a.shoulder {
        finite("shoulder", v)?;
    }
    if let Some(c) = a.cutoff_hz {
        positive("cutoff_hz", c)?;
    }
    if let Some(xi) = a.inertial_parameters {
        crate::planar::check_inertial_parameters(&xi)?;
    }
    Ok(a.prepare())
}

impl Method for LinearRequest {
    const COMMAND: &'static str = "estimate linear";
    type Valid = ValidPrepared<LinearRequest>;

    fn check_settings(&self) -> Result<Self::Valid> {
        // the posture itself is checked where it is used, with reasons
        Ok(Valid {
            derived: check_prepare(&self.prepare)?,
            request: self.clone(),
        })
    }

    fn nesting() -> Option<(&'static str, Vec<String>)> {
        Some(("prepare", field_names::<PrepareRequest>()))
    }

    fn booleans() -> Vec<String> {
        [
            boolean_names::<LinearRequest>(),
            boolean_names::<PrepareRequest>(),
        ]
        .concat()
    }
}

impl Method for CocontractionRequest {
    const COMMAND: &'static str = "estimate cocontraction";
    const INPUTS: (usize, usize) = (2, 2);
    type Valid = ValidPrepared<CocontractionRequest>;

    fn check_settings(&self) -> Result<Self::Valid> {
        let prepare = check_prepare(&self.prepare)?;
        // the preparation's level filter is the linear method's: this one
        // estimates every level (it was ignored without a word)
        if let Some(level) = self.prepare.level {
            return Err(Error::invalid(
                "level",
                format!(
                    "the co-contraction analysis estimates every level and compares each with the lowest, so it takes no level ({level}); `estimate linear --level L` estimates one"
                ),
            ));
        }
        // finite too: an infinite band counts every sample "on target" (issue 56)
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(Error::invalid(
                "tolerance",
                format!(
                    "expected a positive, finite band half-width, found {}",
                    limpid_core::error::Num(self.tolerance)
                ),
            ));
        }
        Ok(Valid {
            derived: prepare,
            request: self.clone(),
        })
    }

    fn nesting() -> Option<(&'static str, Vec<String>)> {
        Some(("prepare", field_names::<PrepareRequest>()))
    }

    fn booleans() -> Vec<String> {
        boolean_names::<PrepareRequest>()
    }
}

impl Method for PlanarRequest {
    const COMMAND: &'static str = "estimate planar";
    type Valid = ValidArm<PlanarRequest>;

    fn check_settings(&self) -> Result<Self::Valid> {
        let arm = check_arm(&self.arm)?;
        if let Some(ms) = self.window_ms {
            // finite too: an infinite window was stored as null and
            // refused by `rerun` (issue 56)
            if !(ms.is_finite() && ms > 0.0) {
                return Err(Error::invalid(
                    "window_ms",
                    format!(
                        "expected a positive, finite duration in ms, found {}",
                        limpid_core::error::Num(ms)
                    ),
                ));
            }
        }
        Ok(Valid {
            derived: arm,
            request: self.clone(),
        })
    }

    fn nesting() -> Option<(&'static str, Vec<String>)> {
        Some(("arm", field_names::<ArmRequest>()))
    }

    fn booleans() -> Vec<String> {
        boolean_names::<ArmRequest>()
    }
}

impl Method for SweepRequest {
    const COMMAND: &'static str = "window-sweep";
    type Valid = ValidArm<SweepRequest>;

    fn check_settings(&self) -> Result<Self::Valid> {
        let arm = check_arm(&self.arm)?;
        positive("from_ms", self.from_ms)?;
        positive("to_ms", self.to_ms)?;
        positive("step_ms", self.step_ms)?;
        Ok(Valid {
            derived: arm,
            request: self.clone(),
        })
    }

    fn nesting() -> Option<(&'static str, Vec<String>)> {
        Some(("arm", field_names::<ArmRequest>()))
    }

    fn booleans() -> Vec<String> {
        boolean_names::<ArmRequest>()
    }
}

impl Method for StochasticRequest {
    const COMMAND: &'static str = "estimate stochastic";
    const INPUTS: (usize, usize) = (1, usize::MAX);
    const LONG_ARRAYS: bool = true;
    type Valid = StochasticRequest;

    fn check_settings(&self) -> Result<Self> {
        crate::Estimator::check(&self.params(0, 1.0))?;
        check_period(self.period_s, self.nperseg, self.noverlap)?;
        Ok(self.clone())
    }

    fn booleans() -> Vec<String> {
        boolean_names::<StochasticRequest>()
    }
}

impl Method for SpectraRequest {
    const COMMAND: &'static str = "spectra";
    const LONG_ARRAYS: bool = true;
    type Valid = SpectraRequest;

    // the segments are checked against the recording's length when it is read
    fn check_settings(&self) -> Result<Self> {
        crate::spectra::check_columns(&self.inputs, &self.outputs)?;
        check_period(self.period_s, self.nperseg, self.noverlap)?;
        Ok(self.clone())
    }

    fn booleans() -> Vec<String> {
        boolean_names::<SpectraRequest>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_band_flag_s_default_is_the_default_band() {
        assert_eq!(numbers::parse::<2>(DEFAULT_BAND_TEXT), Ok(DEFAULT_BAND_HZ));
        assert_eq!(
            numbers::parse::<2>("1, x"),
            Err("'x' is not a number".to_string())
        );
        assert_eq!(
            numbers::parse::<6>("1,2,3"),
            Err("expected 6 numbers separated by commas, found 3".to_string())
        );
    }
}
