//! Model-based state estimation: an extended Kalman filter on the
//! controller's own prediction model, so that measurement noise is averaged
//! out by the dynamics instead of becoming torque.
//!
//! Between samples the estimate is propagated with the torque actually
//! applied, through the same RK4 interval (and its sensitivity) the
//! prediction uses; at a sample the measured `z = (q, qd)` corrects it.
//! Process noise is a piecewise-constant unmodelled acceleration per joint
//! (`acceleration_noise`, rad/s^2, constant over a sample), measurement noise
//! independent per angle and speed. Sized at creation: nothing allocates.

use super::MpcError;
use nalgebra::{SMatrix, SVector};

/// Noise levels of the state estimator (standard deviations).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimatorConfig {
    /// Measurement noise of each joint angle (rad).
    pub angle_noise: f64,
    /// Measurement noise of each joint speed (rad/s).
    pub speed_noise: f64,
    /// Unmodelled acceleration per joint, constant over a sample (rad/s^2):
    /// larger trusts the measurement more, smaller the model.
    pub acceleration_noise: f64,
}

impl EstimatorConfig {
    /// Checks the levels; the message names the offending one.
    pub fn validate(&self) -> Result<(), MpcError> {
        for (name, value) in [
            ("angle_noise", self.angle_noise),
            ("speed_noise", self.speed_noise),
            ("acceleration_noise", self.acceleration_noise),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(MpcError::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and > 0",
                });
            }
        }
        Ok(())
    }
}

/// The process noise of an acceleration with covariance `acceleration`
/// (rad^2/s^4, `N x N`) held constant over a sample of `dt` s, on the
/// leading `(q, qd)` block of an `M`-dimensional state (the rest zero): a
/// constant acceleration a over dt moves q by a dt^2/2 and qd by a dt.
pub(crate) fn held_acceleration_noise<const N: usize, const M: usize>(
    acceleration: &SMatrix<f64, N, N>,
    dt: f64,
) -> SMatrix<f64, M, M> {
    let mut noise = SMatrix::<f64, M, M>::zeros();
    for j in 0..N {
        for l in 0..N {
            let a = acceleration[(j, l)];
            noise[(j, l)] = a * dt.powi(4) / 4.0;
            noise[(j, N + l)] = a * dt.powi(3) / 2.0;
            noise[(N + j, l)] = a * dt.powi(3) / 2.0;
            noise[(N + j, N + l)] = a * dt * dt;
        }
    }
    noise
}

/// The extended Kalman filter of a controller (`NX = 2 N`).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct Ekf<const N: usize, const NX: usize> {
    estimate: SVector<f64, NX>,
    covariance: SMatrix<f64, NX, NX>,
    process: SMatrix<f64, NX, NX>,
    measurement: SMatrix<f64, NX, NX>,
    /// An estimate exists (first measurement taken).
    started: bool,
    /// The estimate was propagated to the coming sample.
    predicted: bool,
}

impl<const N: usize, const NX: usize> Ekf<N, NX> {
    /// A filter for sample period `dt`.
    pub(super) fn new(config: &EstimatorConfig, dt: f64) -> Self {
        let acceleration = SMatrix::<f64, N, N>::identity() * config.acceleration_noise.powi(2);
        let process = held_acceleration_noise::<N, NX>(&acceleration, dt);
        let mut measurement = SMatrix::<f64, NX, NX>::zeros();
        for j in 0..N {
            measurement[(j, j)] = config.angle_noise.powi(2);
            measurement[(N + j, N + j)] = config.speed_noise.powi(2);
        }
        Self {
            estimate: SVector::zeros(),
            covariance: measurement,
            process,
            measurement,
            started: false,
            predicted: false,
        }
    }

    /// Forgets the estimate (the next measurement starts it afresh).
    pub(super) fn reset(&mut self) {
        self.started = false;
        self.predicted = false;
        self.covariance = self.measurement;
    }

    /// The current estimate, if any.
    pub(super) fn estimate(&self) -> Option<&SVector<f64, NX>> {
        self.started.then_some(&self.estimate)
    }

    /// Whether the estimate still needs propagating to the coming sample.
    pub(super) fn needs_prediction(&self) -> bool {
        self.started && !self.predicted
    }

    /// Propagation over one sample: `next` is the model's state after it
    /// from the estimate under the applied torque, `a` its sensitivity.
    pub(super) fn predict(&mut self, next: &SVector<f64, NX>, a: &SMatrix<f64, NX, NX>) {
        self.estimate = *next;
        self.covariance = a * self.covariance * a.transpose() + self.process;
        self.predicted = true;
    }

    /// No usable measurement this sample: the prediction is the estimate.
    pub(super) fn skip_update(&mut self) {
        self.predicted = false;
    }

    /// Corrects the estimate with the measured state and returns it. A
    /// non-finite prediction (a diverged model) restarts from `z`.
    pub(super) fn update(&mut self, z: &SVector<f64, NX>) -> SVector<f64, NX> {
        let finite = self.estimate.iter().all(|v| v.is_finite())
            && self.covariance.iter().all(|v| v.is_finite());
        if !self.started || !finite {
            self.estimate = *z;
            self.covariance = self.measurement;
            self.started = true;
            self.predicted = false;
            return *z;
        }
        let innovation = z - self.estimate;
        let s = self.covariance + self.measurement;
        let Some(chol) = s.cholesky() else {
            self.reset();
            return self.update(z);
        };
        // K = P S^-1, S and P symmetric: K' = S^-1 P.
        let gain = chol.solve(&self.covariance).transpose();
        self.estimate += gain * innovation;
        // Joseph form: stays symmetric positive definite in floating point.
        let i_k = SMatrix::<f64, NX, NX>::identity() - gain;
        self.covariance =
            i_k * self.covariance * i_k.transpose() + gain * self.measurement * gain.transpose();
        self.predicted = false;
        self.estimate
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A constant state measured with noise: the estimate converges to it
    /// and its covariance falls like 1/k (static model, no process noise
    /// to speak of).
    #[test]
    fn averages_noise_on_a_static_state() {
        let config = EstimatorConfig {
            angle_noise: 0.1,
            speed_noise: 0.1,
            acceleration_noise: 1e-9,
        };
        let mut ekf = Ekf::<1, 2>::new(&config, 0.025);
        let truth = SVector::<f64, 2>::new(0.3, 0.0);
        let mut seed = 12345u64;
        let mut noise = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            // uniform with standard deviation 0.1
            (seed as f64 / u64::MAX as f64 - 0.5) * 0.2 * 3f64.sqrt()
        };
        let mut x = SVector::zeros();
        for _ in 0..400 {
            if ekf.needs_prediction() {
                let e = *ekf.estimate().unwrap();
                ekf.predict(&e, &SMatrix::identity());
            }
            let z = truth + SVector::<f64, 2>::new(noise(), noise());
            x = ekf.update(&z);
        }
        assert!((x - truth).amax() < 0.02, "{x}");
        let p = ekf.covariance[(0, 0)];
        assert!((p - 0.01 / 400.0).abs() < 0.1 * 0.01 / 400.0, "{p}");
    }
}
