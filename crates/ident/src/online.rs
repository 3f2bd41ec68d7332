//! Online stiffness (seed 001 Fig. 3 shows its feedback bar; the estimator
//! is limpid's): recursive least squares with exponential forgetting on
//! `f = K (x - x_ref) + c`, one sample at a time, for the live display.
//! The offline estimators are in [`crate::linear`]; this one trades their
//! standard errors for constant time per sample.

/// Recursive least squares with exponential forgetting, one regressor
/// [x - x_ref, y - y_ref, z - z_ref, 1] shared by the three force outputs.
#[derive(Debug, Clone)]
pub struct Rls {
    lambda: f64,
    theta: [[f64; 3]; 4],
    p: [[f64; 4]; 4],
    x_ref: Option<[f64; 3]>,
    /// Exponentially weighted a-priori error power and force variance per axis.
    err_power: [f64; 3],
    f_mean: [f64; 3],
    f_power: [f64; 3],
    /// Samples processed.
    pub updates: u64,
}

/// The covariance is not allowed to grow past this trace while nothing excites it.
const P_TRACE_CAP: f64 = 1e10;

impl Rls {
    /// Forgetting factor λ (memory of about 1 / (1 - λ) samples).
    pub fn new(lambda: f64) -> Self {
        let mut p = [[0.0; 4]; 4];
        for (i, row) in p.iter_mut().enumerate() {
            row[i] = if i < 3 { 1e8 } else { 1e4 };
        }
        Rls {
            lambda,
            theta: [[0.0; 3]; 4],
            p,
            x_ref: None,
            err_power: [0.0; 3],
            f_mean: [0.0; 3],
            f_power: [0.0; 3],
            updates: 0,
        }
    }

    /// One sample of position (m) and force on the limb (N).
    // index loops mirror the RLS equations on these 4 x 4 and 4 x 3 arrays
    #[allow(clippy::needless_range_loop)]
    #[inline]
    pub fn update(&mut self, x: [f64; 3], f: [f64; 3]) {
        let r = *self.x_ref.get_or_insert(x);
        let phi = [x[0] - r[0], x[1] - r[1], x[2] - r[2], 1.0];
        let mut p_phi = [0.0; 4];
        for i in 0..4 {
            p_phi[i] = (0..4).map(|j| self.p[i][j] * phi[j]).sum();
        }
        let denom = self.lambda + (0..4).map(|i| phi[i] * p_phi[i]).sum::<f64>();
        let gain = p_phi.map(|v| v / denom);
        let w = 1.0 - self.lambda;
        for o in 0..3 {
            let pred: f64 = (0..4).map(|i| self.theta[i][o] * phi[i]).sum();
            let e = f[o] - pred;
            for i in 0..4 {
                self.theta[i][o] += gain[i] * e;
            }
            self.err_power[o] += w * (e * e - self.err_power[o]);
            self.f_mean[o] += w * (f[o] - self.f_mean[o]);
            let d = f[o] - self.f_mean[o];
            self.f_power[o] += w * (d * d - self.f_power[o]);
        }
        let trace: f64 = (0..4).map(|i| self.p[i][i]).sum();
        let forget = if trace > P_TRACE_CAP {
            1.0
        } else {
            self.lambda
        };
        for i in 0..4 {
            for j in 0..4 {
                self.p[i][j] = (self.p[i][j] - gain[i] * p_phi[j]) / forget;
            }
        }
        self.updates += 1;
    }

    /// K (N/m): row = force axis, column = position axis.
    pub fn stiffness(&self) -> [[f64; 3]; 3] {
        let mut k = [[0.0; 3]; 3];
        for (o, row) in k.iter_mut().enumerate() {
            for (i, v) in row.iter_mut().enumerate() {
                *v = self.theta[i][o];
            }
        }
        k
    }

    /// Variance accounted for by the one-step prediction, per axis (%);
    /// None before the first 100 samples.
    pub fn vaf(&self) -> Option<[f64; 3]> {
        (self.updates >= 100).then(|| {
            [0, 1, 2].map(|o| {
                if self.f_power[o] > 0.0 {
                    100.0 * (1.0 - self.err_power[o] / self.f_power[o])
                } else {
                    0.0
                }
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::needless_range_loop)]
    fn rls_recovers_a_static_stiffness() {
        let k = [[800.0, 40.0, 10.0], [30.0, 500.0, 20.0], [5.0, 25.0, 300.0]];
        let mut rls = Rls::new(0.999);
        let mut s = 1u64;
        let mut rand = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for n in 0..20_000 {
            let t = n as f64 * 1e-3;
            let x = [
                0.3 + 0.004 * (3.1 * t).sin(),
                -0.2 + 0.004 * (4.3 * t).cos(),
                0.05 + 0.004 * (5.7 * t + 1.0).sin(),
            ];
            let mut f = [2.0, -1.0, 0.5];
            for (o, fo) in f.iter_mut().enumerate() {
                for i in 0..3 {
                    *fo += k[o][i] * (x[i] - [0.3, -0.2, 0.05][i]);
                }
                *fo += 0.01 * rand();
            }
            rls.update(x, f);
        }
        let est = rls.stiffness();
        for o in 0..3 {
            for i in 0..3 {
                assert!(
                    (est[o][i] - k[o][i]).abs() < 0.01 * 800.0,
                    "K[{o}][{i}] = {}",
                    est[o][i]
                );
            }
        }
        assert!(rls.vaf().unwrap().iter().all(|v| *v > 99.0));
    }
}
