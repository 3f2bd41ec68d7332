//! Online impedance for the live display (seed 001 Fig. 3 shows the
//! feedback bar; the online estimator is limpid's). It fits seed 000's model
//! `f = M x'' + B x' + K x + c_j` (eq. 1 with a force offset per
//! perturbation, the offline path's `offsets = fit`) to the last completed
//! perturbations, so inertial and viscous forces of short perturbations are
//! modelled instead of leaking into K.
//!
//! Per sample (constant time, no allocation): positions and forces through
//! one causal Butterworth low-pass at 15 Hz (the same filter on both keeps
//! the linear model exact between the filtered signals, as offline; half the
//! offline cut-off, see [`LIVE_CUTOFF_HZ`]), velocity and
//! acceleration by central differences (one sample late), and the regression
//! sums of the perturbation in progress. Perturbations are segmented online:
//! one starts when the limb leaves its rest by 0.3 mm and takes the 25 ms of
//! rest before it along (its force offset, as offline's rest offsets); it
//! ends when the limb, having moved at least 0.5 mm, is back within 10 % of
//! its largest displacement at under 10 % of its peak speed, or after
//! `max_trial_s`. Rest between perturbations is left out, so a force offset
//! that changes there does not enter. Closed segments keep their centred
//! sums (the per-perturbation offset eliminated); the estimate solves the
//! sums of the last `window_trials` segments since the last level reset.
//!
//! Honesty: no number before `min_trials` perturbations whose directions
//! span the space (scaled condition number below 1e6); standard errors from
//! the spread of the least-squares scores over 250 ms blocks of the
//! perturbations (a batch-means sandwich `A⁻¹ (Σ_b s_b s_bᵀ) A⁻¹`, with the
//! neighbouring blocks' positive covariance, so the filtered, coloured
//! residuals count as often as they are independent, and model error counts
//! as noise). Measured (`cargo run --profile ci -p limpid-app --example
//! live_coverage -- 20 2`, seed-001 sessions with five noise models): the
//! true diagonal K lies within ±2 SE in 93-99 % of the estimates after each
//! perturbation; on noise-free data the SE shrinks to the model error and
//! covers less. A VAF only when in
//! [0, 100] %; a sample no limb gives (non-finite, beyond 10 m or 1e4 N) is
//! refused before the filters and drops the segment it falls in, as does a
//! displacement over 0.5 m within a segment.

use std::collections::VecDeque;

use nalgebra::{SMatrix, SVector};

use limpid_core::{Error, Result};
use limpid_dsp::{LowPass, StreamingFilter};

/// Regressors per force axis: acceleration, velocity, position (3 each).
const P: usize = 9;
/// Rest kept before an onset (s): the perturbation's own force offset.
const PRE_ONSET_S: f64 = 0.025;
/// Displacement from rest that starts a perturbation (m).
const ONSET_M: f64 = 3e-4;
/// Displacement a perturbation must reach to count (m).
const MOVED_M: f64 = 5e-4;
/// Length of the blocks whose score sums give the standard errors (s):
/// longer than the residuals' correlation (drift, filtered noise); 50 ms
/// covered 66-83 %, 300 ms 94-99 % (see the module doc).
const SE_BLOCK_S: f64 = 0.25;
/// Weight of the covariance of neighbouring blocks in the standard errors.
const SE_NEIGHBOUR_WEIGHT: f64 = 1.0;
/// Default low-pass cut-off of the live estimate (Hz). Lower than offline's
/// 30 Hz: the one causal pass and the second differences leave more sensor
/// noise in the acceleration regressor, which biased K by -2 % at 30 Hz on
/// seed-001 subjects with 20 µm position noise (+0.8 % at 15 Hz; -28 % vs
/// -1.3 % with 100 µm), while their perturbations carry little above 15 Hz.
pub const LIVE_CUTOFF_HZ: f64 = 15.0;
/// Samples beyond these are refused (counted in `rejected`).
const POSITION_LIMIT_M: f64 = 10.0;
const FORCE_LIMIT_N: f64 = 1e4;

/// Settings of [`OnlineImpedance`].
#[derive(Debug, Clone)]
pub struct OnlineSettings {
    /// Sample rate (Hz).
    pub fs: f64,
    /// Low-pass cut-off for positions and forces (Hz); default
    /// [`LIVE_CUTOFF_HZ`] (half the offline one).
    pub cutoff_hz: f64,
    /// Butterworth order (one causal pass).
    pub order: usize,
    /// Perturbations in the estimate (the most recent ones).
    pub window_trials: usize,
    /// Perturbations needed before a number is shown.
    pub min_trials: usize,
    /// Longest segment (s): a perturbation that does not return is closed here.
    pub max_trial_s: f64,
}

impl OnlineSettings {
    /// Defaults at sample rate `fs`: 15 Hz cut-off (at most 0.4 `fs`), order
    /// 4, the last 8 perturbations, a number from 3 on, segments of at most 3 s.
    pub fn new(fs: f64) -> Self {
        OnlineSettings {
            fs,
            cutoff_hz: LIVE_CUTOFF_HZ.min(0.4 * fs),
            order: 4,
            window_trials: 8,
            min_trials: 3,
            max_trial_s: 3.0,
        }
    }
}

/// Centred regression sums of one closed segment (or of several, added).
#[derive(Debug, Clone, Copy)]
struct Sums {
    n: f64,
    xtx: SMatrix<f64, P, P>,
    xtf: SMatrix<f64, P, 3>,
    ftf: SVector<f64, 3>,
}

impl Sums {
    fn zero() -> Self {
        Sums {
            n: 0.0,
            xtx: SMatrix::zeros(),
            xtf: SMatrix::zeros(),
            ftf: SVector::zeros(),
        }
    }
    fn add(&mut self, o: &Sums) {
        self.n += o.n;
        self.xtx += o.xtx;
        self.xtf += o.xtf;
        self.ftf += o.ftf;
    }
}

/// Raw sums of the segment in progress (centred when it closes).
#[derive(Debug, Clone)]
struct Segment {
    /// Samples so far.
    n: f64,
    ftf: SVector<f64, 3>,
    start: [f64; 3],
    max_disp: f64,
    max_speed: f64,
    plausible: bool,
    discard: bool,
    /// Sample count at the onset (the first rest sample taken along).
    onset: u64,
    /// Raw sums of the closed blocks and of the block in progress (the
    /// segment's own sums are theirs added up when it closes).
    blocks: Vec<Block>,
    block: Block,
    block_len: f64,
}

/// Raw regression sums of a segment or of one block of it (the blocks give
/// the standard errors).
#[derive(Debug, Clone, Copy)]
struct Block {
    n: f64,
    sx: SVector<f64, P>,
    sf: SVector<f64, 3>,
    xtx: SMatrix<f64, P, P>,
    xtf: SMatrix<f64, P, 3>,
}

impl Block {
    fn zero() -> Self {
        Block {
            n: 0.0,
            sx: SVector::zeros(),
            sf: SVector::zeros(),
            xtx: SMatrix::zeros(),
            xtf: SMatrix::zeros(),
        }
    }

    fn add(&mut self, row: &SVector<f64, P>, force: &SVector<f64, 3>) {
        self.n += 1.0;
        self.sx += row;
        self.sf += force;
        // the full matrix (`syger` fills only the lower triangle): `score` multiplies it
        self.xtx.ger(1.0, row, row, 1.0);
        self.xtf.ger(1.0, row, force, 1.0);
    }

    fn merge(&mut self, o: &Block) {
        self.n += o.n;
        self.sx += o.sx;
        self.sf += o.sf;
        self.xtx += o.xtx;
        self.xtf += o.xtf;
    }

    /// The block's least-squares score `Σ (x - x̄)(f - f̄ - (x - x̄)ᵀθ)` about
    /// its segment's means `x̄`, `f̄`, per force axis (columns).
    fn score(
        &self,
        mx: &SVector<f64, P>,
        mf: &SVector<f64, 3>,
        theta: &SMatrix<f64, P, 3>,
    ) -> SMatrix<f64, P, 3> {
        let xtf = self.xtf - mx * self.sf.transpose() - self.sx * mf.transpose()
            + self.n * mx * mf.transpose();
        let xtx = self.xtx - mx * self.sx.transpose() - self.sx * mx.transpose()
            + self.n * mx * mx.transpose();
        xtf - xtx * theta
    }
}

/// A closed segment: its centred sums, its means and its blocks.
#[derive(Debug, Clone)]
struct Closed {
    sums: Sums,
    mean_x: SVector<f64, P>,
    mean_f: SVector<f64, 3>,
    blocks: Vec<Block>,
}

impl Segment {
    fn new(start: [f64; 3], onset: u64, block_len: f64, max_blocks: usize) -> Self {
        Segment {
            n: 0.0,
            ftf: SVector::zeros(),
            start,
            max_disp: 0.0,
            max_speed: 0.0,
            plausible: true,
            discard: false,
            onset,
            blocks: Vec::with_capacity(max_blocks),
            block: Block::zero(),
            block_len,
        }
    }

    fn add(&mut self, row: &SVector<f64, P>, force: &SVector<f64, 3>) {
        self.n += 1.0;
        self.ftf += force.component_mul(force);
        self.block.add(row, force);
        if self.block.n >= self.block_len {
            self.blocks.push(self.block);
            self.block = Block::zero();
        }
    }

    /// Sums about the segment's own means (its force offset fitted away),
    /// with its blocks (a short last one joins the one before).
    fn close(mut self) -> Closed {
        if self.block.n > 0.0 {
            match self.blocks.last_mut() {
                Some(last) if self.block.n < 0.5 * self.block_len => last.merge(&self.block),
                _ => self.blocks.push(self.block),
            }
        }
        let mut raw = Block::zero();
        for b in &self.blocks {
            raw.merge(b);
        }
        let n = raw.n.max(1.0);
        let mx = raw.sx / n;
        let mf = raw.sf / n;
        Closed {
            sums: Sums {
                n: raw.n,
                xtx: raw.xtx - mx * raw.sx.transpose(),
                xtf: raw.xtf - mx * raw.sf.transpose(),
                ftf: self.ftf - mf.component_mul(&raw.sf),
            },
            mean_x: mx,
            mean_f: mf,
            blocks: self.blocks,
        }
    }
}

/// What the live display may show.
#[derive(Debug, Clone, PartialEq)]
pub enum OnlineState {
    /// No number: why not (e.g. "waiting for perturbations: 1 of 3").
    Waiting(String),
    /// An estimate from the last perturbations.
    Estimating,
}

/// One estimate of the online model.
#[derive(Debug, Clone)]
pub struct OnlineEstimate {
    /// Stiffness (N/m): row = force axis, column = position axis.
    pub stiffness: [[f64; 3]; 3],
    /// Standard errors of the stiffness entries (N/m).
    pub stiffness_se: [[f64; 3]; 3],
    /// Damping (N s/m).
    pub damping: [[f64; 3]; 3],
    /// Inertia (kg).
    pub inertia: [[f64; 3]; 3],
    /// Variance accounted for per force axis (%), where it lies in [0, 100].
    pub vaf: [Option<f64>; 3],
    /// Perturbations in the estimate.
    pub trials: usize,
}

/// The online estimator (see the module documentation).
#[derive(Debug, Clone)]
pub struct OnlineImpedance {
    settings: OnlineSettings,
    lowpass: LowPass,
    filters: Option<Vec<StreamingFilter>>,
    /// Filtered samples n-1 and n-2 (x, y, z, fx, fy, fz).
    previous: [[f64; 6]; 2],
    filtered_samples: u64,
    segment: Option<Segment>,
    /// The last samples at rest (row, force, position), while no segment is open.
    rest: VecDeque<(SVector<f64, P>, SVector<f64, 3>, [f64; 3])>,
    closed: VecDeque<Closed>,
    estimate: Option<OnlineEstimate>,
    state: OnlineState,
    /// Samples taken.
    pub samples: u64,
    /// Samples refused: non-finite, a position beyond 10 m or a force beyond 1e4 N.
    pub rejected: u64,
    /// Perturbations (segments with movement) since the start.
    pub perturbations: u64,
    /// Segments dropped for implausible values.
    pub dropped: u64,
}

impl OnlineImpedance {
    /// A new estimator; errors for settings no filter can be designed for.
    pub fn new(settings: OnlineSettings) -> Result<Self> {
        if settings.min_trials == 0 || settings.window_trials < settings.min_trials {
            return Err(Error::invalid(
                "online window",
                format!(
                    "expected 1 <= min_trials <= window_trials, found {} and {}",
                    settings.min_trials, settings.window_trials
                ),
            ));
        }
        let lowpass = LowPass::butterworth(settings.order, settings.cutoff_hz, settings.fs)?;
        let waiting = OnlineState::Waiting(format!(
            "waiting for perturbations: 0 of {}",
            settings.min_trials
        ));
        Ok(OnlineImpedance {
            settings,
            lowpass,
            filters: None,
            previous: [[0.0; 6]; 2],
            filtered_samples: 0,
            segment: None,
            rest: VecDeque::new(),
            closed: VecDeque::new(),
            estimate: None,
            state: waiting,
            samples: 0,
            rejected: 0,
            perturbations: 0,
            dropped: 0,
        })
    }

    /// The settings in use.
    pub fn settings(&self) -> &OnlineSettings {
        &self.settings
    }

    /// What may be shown now.
    pub fn state(&self) -> &OnlineState {
        &self.state
    }

    /// The estimate, only while [`OnlineState::Estimating`].
    pub fn estimate(&self) -> Option<&OnlineEstimate> {
        match self.state {
            OnlineState::Estimating => self.estimate.as_ref(),
            OnlineState::Waiting(_) => None,
        }
    }

    /// Perturbations in the current window.
    pub fn window_trials(&self) -> usize {
        self.closed.len()
    }

    /// Forget every perturbation (a new co-contraction level): the estimate
    /// restarts from the next perturbation. The filters keep running.
    pub fn reset(&mut self) {
        self.reset_from(u64::MAX);
    }

    /// [`OnlineImpedance::reset`] for a change that happened at sample
    /// `first` (a count of [`OnlineImpedance::samples`]): a perturbation in
    /// progress that started at or after it is kept; one that started
    /// before is followed to its end (so the next one is recognised) but not
    /// used, since part of it belongs to the old level.
    pub fn reset_from(&mut self, first: u64) {
        self.closed.clear();
        if let Some(seg) = &mut self.segment {
            seg.discard = seg.onset < first;
        }
        self.estimate = None;
        self.state = OnlineState::Waiting(format!(
            "waiting for perturbations: 0 of {}",
            self.settings.min_trials
        ));
    }

    /// One sample: position (m) and force on the limb (N).
    #[inline]
    pub fn update(&mut self, x: [f64; 3], f: [f64; 3]) {
        // a value no limb gives never reaches the filters (it would ring in
        // them for seconds); the segment it interrupts is dropped
        let within = |v: &f64, limit: f64| v.is_finite() && v.abs() <= limit;
        let implausible = !x.iter().all(|v| within(v, POSITION_LIMIT_M))
            || !f.iter().all(|v| within(v, FORCE_LIMIT_N));
        if implausible {
            self.rejected += 1;
            if let Some(seg) = &mut self.segment {
                seg.plausible = false;
            }
            return;
        }
        self.samples += 1;
        let raw = [x[0], x[1], x[2], f[0], f[1], f[2]];
        let lowpass = &self.lowpass;
        let filters = self
            .filters
            .get_or_insert_with(|| raw.iter().map(|&v| lowpass.streaming_from(v)).collect());
        let mut y = [0.0; 6];
        for ((out, filter), v) in y.iter_mut().zip(filters.iter_mut()).zip(raw) {
            *out = filter.step(v);
        }
        let [p1, p2] = self.previous;
        self.previous = [y, p1];
        self.filtered_samples += 1;
        if self.filtered_samples < 3 {
            return;
        }
        // central differences at the previous sample
        let fs = self.settings.fs;
        let mut row = SVector::<f64, P>::zeros();
        let mut force = SVector::<f64, 3>::zeros();
        let mut pos = [0.0; 3];
        let mut speed2 = 0.0;
        for i in 0..3 {
            let v = (y[i] - p2[i]) * 0.5 * fs;
            row[i] = (y[i] - 2.0 * p1[i] + p2[i]) * fs * fs;
            row[3 + i] = v;
            row[6 + i] = p1[i];
            pos[i] = p1[i];
            force[i] = p1[3 + i];
            speed2 += v * v;
        }
        self.accumulate(row, force, pos, speed2.sqrt());
    }

    fn accumulate(
        &mut self,
        row: SVector<f64, P>,
        force: SVector<f64, 3>,
        pos: [f64; 3],
        speed: f64,
    ) {
        let fs = self.settings.fs;
        let Some(seg) = self.segment.as_mut() else {
            // at rest: keep the last PRE_ONSET_S of samples; an onset takes them
            // as the perturbation's own rest (its force offset), as offline
            let cap = ((PRE_ONSET_S * fs).round() as usize).max(2);
            self.rest.push_back((row, force, pos));
            while self.rest.len() > cap {
                self.rest.pop_front();
            }
            let origin = self.rest.front().map_or(pos, |r| r.2);
            if distance(pos, origin) > ONSET_M {
                let first = self.samples.saturating_sub(self.rest.len() as u64);
                let block_len = (SE_BLOCK_S * fs).round().max(2.0);
                let max_blocks = (self.settings.max_trial_s / SE_BLOCK_S).ceil() as usize + 2;
                let mut seg = Segment::new(origin, first, block_len, max_blocks);
                for (r, f, _) in self.rest.drain(..) {
                    seg.add(&r, &f);
                }
                self.segment = Some(seg);
            }
            return;
        };
        seg.add(&row, &force);
        let disp = distance(pos, seg.start);
        if disp > 0.5 {
            seg.plausible = false;
        }
        seg.max_disp = seg.max_disp.max(disp);
        seg.max_speed = seg.max_speed.max(speed);
        let moved = seg.max_disp >= MOVED_M;
        // back where it started and nearly still: the perturbation is over
        let back = moved && disp < 0.1 * seg.max_disp && speed < 0.1 * seg.max_speed;
        let too_long = seg.n >= self.settings.max_trial_s * fs;
        if !(back || too_long) {
            return;
        }
        let seg = self.segment.take().expect("matched above");
        if !seg.plausible {
            self.dropped += 1;
        } else if moved && !seg.discard {
            self.perturbations += 1;
            self.closed.push_back(seg.close());
            while self.closed.len() > self.settings.window_trials {
                self.closed.pop_front();
            }
            self.refit();
        }
    }

    /// Solve the window's sums; decide what may be shown.
    fn refit(&mut self) {
        let s = &self.settings;
        if self.closed.len() < s.min_trials {
            self.state = OnlineState::Waiting(format!(
                "waiting for perturbations: {} of {}",
                self.closed.len(),
                s.min_trials
            ));
            return;
        }
        match solve(&self.closed) {
            Ok(e) => {
                self.estimate = Some(e);
                self.state = OnlineState::Estimating;
            }
            Err(why) => {
                self.estimate = None;
                self.state = OnlineState::Waiting(why);
            }
        }
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Least squares on the sums, scaled to unit diagonal (so the condition
/// number compares directions, not units).
fn solve(closed: &VecDeque<Closed>) -> std::result::Result<OnlineEstimate, String> {
    let trials = closed.len();
    let mut sum = Sums::zero();
    for c in closed {
        sum.add(&c.sums);
    }
    let d: SVector<f64, P> = sum
        .xtx
        .diagonal()
        .map(|v| if v > 0.0 { 1.0 / v.sqrt() } else { 0.0 });
    if d.iter().any(|v| *v == 0.0 || !v.is_finite()) {
        return Err(format!(
            "waiting for perturbations in more directions ({trials} so far moved not every axis)"
        ));
    }
    let scaled = SMatrix::<f64, P, P>::from_fn(|i, j| sum.xtx[(i, j)] * d[i] * d[j]);
    let eig = scaled.symmetric_eigenvalues();
    let (lo, hi) = (eig.min(), eig.max());
    if !(lo > 0.0 && hi / lo < 1e6) {
        return Err(format!(
            "waiting for perturbations in more directions ({trials} so far do not identify K, B and M)"
        ));
    }
    let Some(chol) = scaled.cholesky() else {
        return Err("waiting for perturbations in more directions".into());
    };
    let inverse = chol.inverse();
    let rhs = SMatrix::<f64, P, 3>::from_fn(|i, o| sum.xtf[(i, o)] * d[i]);
    let theta_scaled = inverse * rhs;
    let theta = SMatrix::<f64, P, 3>::from_fn(|i, o| theta_scaled[(i, o)] * d[i]);
    let mut out = OnlineEstimate {
        stiffness: [[0.0; 3]; 3],
        stiffness_se: [[0.0; 3]; 3],
        damping: [[0.0; 3]; 3],
        inertia: [[0.0; 3]; 3],
        vaf: [None; 3],
        trials,
    };
    for o in 0..3 {
        let explained: f64 = (0..P).map(|i| theta[(i, o)] * sum.xtf[(i, o)]).sum();
        let sse = (sum.ftf[o] - explained).max(0.0);
        let sst = sum.ftf[o];
        let vaf = 100.0 * (1.0 - sse / sst);
        out.vaf[o] = (sst > 0.0 && (0.0..=100.0).contains(&vaf)).then_some(vaf);
        for j in 0..3 {
            out.inertia[o][j] = theta[(j, o)];
            out.damping[o][j] = theta[(3 + j, o)];
            out.stiffness[o][j] = theta[(6 + j, o)];
        }
    }
    // the sandwich A⁻¹ (Σ s_b s_bᵀ + neighbours) A⁻¹ for the stiffness
    // entries: only the rows of A⁻¹ for the positions are needed
    let rows: [SVector<f64, P>; 3] = std::array::from_fn(|j| {
        SVector::<f64, P>::from_fn(|i, _| inverse[(6 + j, i)] * d[6 + j] * d[i])
    });
    let mut var = [[0.0f64; 3]; 3];
    let mut blocks = 0usize;
    for c in closed {
        let scores: Vec<SMatrix<f64, P, 3>> = c
            .blocks
            .iter()
            .map(|b| b.score(&c.mean_x, &c.mean_f, &theta))
            .collect();
        blocks += scores.len();
        for (o, var_o) in var.iter_mut().enumerate() {
            for (a, v) in rows.iter().zip(var_o.iter_mut()) {
                let u: Vec<f64> = scores.iter().map(|s| a.dot(&s.column(o))).collect();
                let own: f64 = u.iter().map(|v| v * v).sum();
                let next: f64 = u.windows(2).map(|w| w[0] * w[1]).sum();
                // a negative neighbour covariance is not trusted to shrink the SE
                *v += own + 2.0 * SE_NEIGHBOUR_WEIGHT * next.max(0.0);
            }
        }
    }
    // small-sample correction: blocks, less the parameters fitted per axis
    let dof = blocks as f64 / (blocks as f64 - P as f64).max(1.0);
    for (se_row, var_row) in out.stiffness_se.iter_mut().zip(&var) {
        for (se, v) in se_row.iter_mut().zip(var_row) {
            *se = (v * dof).max(0.0).sqrt();
        }
    }
    let finite = out
        .stiffness
        .iter()
        .chain(&out.damping)
        .chain(&out.inertia)
        .chain(&out.stiffness_se)
        .flatten()
        .all(|v| v.is_finite());
    if !finite {
        return Err("waiting: the last perturbations gave no finite estimate".into());
    }
    Ok(out)
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // 3 x 3 matrices indexed as in the equations
mod tests;
