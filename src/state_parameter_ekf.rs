//! The state and the base parameters estimated together: an extended
//! Kalman filter on `(q, qd, theta)` (issue 37, item 2).
//!
//! A filter given a wrong model is biased towards it (the state estimator
//! of [`crate::mpc`] filters with the controller's model), and a least
//! squares fit of noisy regressors is biased towards zero (errors in the
//! variables, which [`crate::identify::EnergyBalanceRls`] compensates in
//! part). Here the model is part of the estimate: the base parameters
//! ([`BaseParameters`]) are states that drift slowly, the chain's dynamics
//! in them come from the dynamics' regressor ([`dynamic_regressor`]:
//! `M(q, theta) qdd = tau - Y(q, qd, 0) theta`), and every sample's
//! measured angles and speeds correct both. The filter uses all `2 N`
//! measured coordinates of every sample, where the energy balance uses one
//! scalar per window: the angles (the sensors' best signal) show the
//! period and the shape of the motion, which the energy does not.
//!
//! Propagation is RK4 over `substeps` per sample with the torque held;
//! its sensitivity is by central differences of that map (fixed cost:
//! `2 (NX + NP)` propagations). Sized at creation: nothing allocates.

use crate::identify::{
    BaseParameters, IdentifyError, dynamic_regressor, energy_feature_derivatives,
};
use crate::mechanics::{PlanarChainParams, Vector};
use crate::mpc::held_acceleration_noise;
use nalgebra::{SMatrix, SVector};

/// Share of a new sample in the mean of the normalised innovations squared
/// (about 2 s at 25 ms).
const CONSISTENCY_SHARE: f64 = 0.0125;

/// Noise levels and prior of the joint state and parameter filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateParameterOptions {
    /// Measurement noise of each joint angle (rad).
    pub angle_noise: f64,
    /// Measurement noise of each joint speed (rad/s).
    pub speed_noise: f64,
    /// Unmodelled acceleration per joint, constant over a sample (rad/s^2).
    pub acceleration_noise: f64,
    /// Prior standard deviation of each base parameter, relative to its
    /// prior value.
    pub prior_relative: f64,
    /// Prior standard deviation of a base parameter whose prior is 0 (in
    /// its own unit).
    pub prior_floor: f64,
    /// Drift of each parameter per square root of a second, relative to its
    /// prior standard deviation (0: constant parameters).
    pub drift: f64,
    /// RK4 steps per sample.
    pub substeps: usize,
}

impl Default for StateParameterOptions {
    fn default() -> Self {
        Self {
            angle_noise: 0.005,
            speed_noise: 0.05,
            acceleration_noise: 0.3,
            prior_relative: 0.3,
            prior_floor: 0.05,
            drift: 1e-3,
            substeps: 4,
        }
    }
}

impl StateParameterOptions {
    /// Checks the options; the message names the offending one.
    pub fn validate(&self) -> Result<(), IdentifyError> {
        for (name, v) in [
            ("angle_noise", self.angle_noise),
            ("speed_noise", self.speed_noise),
            ("acceleration_noise", self.acceleration_noise),
            ("prior_relative", self.prior_relative),
            ("prior_floor", self.prior_floor),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(IdentifyError::NotPhysical(format!(
                    "{name} = {v} must be finite and > 0"
                )));
            }
        }
        if !(self.drift.is_finite() && self.drift >= 0.0) {
            return Err(IdentifyError::NotPhysical(format!(
                "drift = {} must be finite and >= 0",
                self.drift
            )));
        }
        if self.substeps == 0 {
            return Err(IdentifyError::NotPhysical("substeps must be >= 1".into()));
        }
        Ok(())
    }
}

/// The extended Kalman filter on the state and the base parameters of an
/// `N`-joint chain (`NX = 2 N`, `NP` base parameters, `NA = NX + NP`).
#[derive(Clone, Debug)]
pub struct StateParameterEkf<const N: usize, const NX: usize, const NP: usize, const NA: usize> {
    prior: PlanarChainParams<N>,
    estimate: SVector<f64, NA>,
    covariance: SMatrix<f64, NA, NA>,
    process: SMatrix<f64, NA, NA>,
    measurement: SMatrix<f64, NX, NX>,
    /// The covariance at the start: the measurement's on the state, the
    /// prior's on the parameters (a restart's).
    initial_covariance: SMatrix<f64, NA, NA>,
    dt: f64,
    substeps: usize,
    started: bool,
    /// Samples whose propagation failed (a parameter estimate without a
    /// positive definite inertia): the parameters went back to the prior.
    restarts: usize,
    /// Exponential mean of the normalised innovations squared (`NX`
    /// expected).
    consistency: f64,
}

impl<const N: usize, const NX: usize, const NP: usize, const NA: usize>
    StateParameterEkf<N, NX, NP, NA>
{
    const CHECK: () = assert!(
        NX == 2 * N && NA == NX + NP,
        "NX must be 2 N and NA must be NX + NP"
    );

    /// A filter starting from the base parameters of `prior` (its
    /// spring-free chain) at sample period `dt` (s).
    pub fn new(
        prior: &PlanarChainParams<N>,
        options: StateParameterOptions,
        dt: f64,
    ) -> Result<Self, IdentifyError> {
        let () = Self::CHECK;
        options.validate()?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(IdentifyError::NotPhysical(format!(
                "dt = {dt} must be finite and > 0"
            )));
        }
        let theta = BaseParameters::<N, NP>::of(prior)?.theta;
        let mut estimate = SVector::<f64, NA>::zeros();
        let mut measurement = SMatrix::<f64, NX, NX>::zeros();
        let acceleration = SMatrix::<f64, N, N>::identity() * options.acceleration_noise.powi(2);
        let mut process = held_acceleration_noise::<N, NA>(&acceleration, dt);
        let mut initial_covariance = SMatrix::<f64, NA, NA>::zeros();
        for j in 0..N {
            measurement[(j, j)] = options.angle_noise.powi(2);
            measurement[(N + j, N + j)] = options.speed_noise.powi(2);
            initial_covariance[(j, j)] = measurement[(j, j)];
            initial_covariance[(N + j, N + j)] = measurement[(N + j, N + j)];
        }
        for i in 0..NP {
            estimate[NX + i] = theta[i];
            let sd = if theta[i] == 0.0 {
                options.prior_floor
            } else {
                options.prior_relative * theta[i].abs()
            };
            initial_covariance[(NX + i, NX + i)] = sd * sd;
            process[(NX + i, NX + i)] = (options.drift * sd).powi(2) * dt;
        }
        Ok(Self {
            prior: *prior,
            estimate,
            covariance: initial_covariance,
            process,
            measurement,
            initial_covariance,
            dt,
            substeps: options.substeps,
            started: false,
            restarts: 0,
            consistency: NX as f64,
        })
    }

    /// The estimated state `(q, qd)` (the last measurement's correction).
    pub fn state(&self) -> SVector<f64, NX> {
        self.estimate.fixed_rows::<NX>(0).into_owned()
    }

    /// The estimated base parameters.
    pub fn parameters(&self) -> BaseParameters<N, NP> {
        BaseParameters {
            theta: self.estimate.fixed_rows::<NP>(NX).into_owned(),
        }
    }

    /// The covariance of the estimated base parameters.
    pub fn parameter_covariance(&self) -> SMatrix<f64, NP, NP> {
        self.covariance.fixed_view::<NP, NP>(NX, NX).into_owned()
    }

    /// The mean normalised innovations squared per measured coordinate (1
    /// when the filter's covariance is right).
    pub fn consistency(&self) -> f64 {
        self.consistency / NX as f64
    }

    /// Samples whose propagation failed and restarted the parameters from
    /// the prior.
    pub fn restarts(&self) -> usize {
        self.restarts
    }

    /// The inertia `M(q, theta)` of the chain of base parameters `theta`.
    fn mass_matrix(&self, q: &Vector<N>, theta: &SVector<f64, NP>) -> SMatrix<f64, N, N> {
        // Each kinetic feature's speed derivative is K_i(q) qd: at qd = e_k
        // it is column k of K_i, so M(q, theta) = sum_i theta_i K_i(q).
        let mut mass = SMatrix::<f64, N, N>::zeros();
        for k in 0..N {
            let mut e = Vector::<N>::zeros();
            e[k] = 1.0;
            let (_, dqd) = energy_feature_derivatives::<N, NP>(&self.prior, q, &e);
            for r in 0..N {
                let mut m = 0.0;
                for i in 0..NP {
                    m += theta[i] * dqd[(i, r)];
                }
                mass[(r, k)] = m;
            }
        }
        mass
    }

    /// The process noise Coulomb friction adds near rest: the smooth
    /// `cf atan(k qd)` is a model of a friction that is set-valued at rest
    /// (sticking), so within about `1 / k` of zero speed its torque is known
    /// only within the friction level (the estimate plus its standard
    /// deviation), fading as `1 - 2/pi |atan(k qd)|`. Without it, a joint
    /// held by friction at the start moved the parameters 10-20 % within
    /// half a second (the lab pendulum B0, from its exact model).
    fn sticking_noise(&self) -> SMatrix<f64, NA, NA> {
        let q = Vector::<N>::from_fn(|j, _| self.estimate[j]);
        let theta: SVector<f64, NP> = self.estimate.fixed_rows::<NP>(NX).into_owned();
        let Some(chol) = self.mass_matrix(&q, &theta).cholesky() else {
            return SMatrix::zeros();
        };
        let mut torque = SMatrix::<f64, N, N>::zeros();
        for j in 0..N {
            let c = NX + NP - N + j;
            let level = self.estimate[c].max(0.0) + self.covariance[(c, c)].max(0.0).sqrt();
            let speed = self.estimate[N + j];
            let stick = 1.0
                - 2.0 / std::f64::consts::PI
                    * libm::atan(self.prior.coulomb_sharpness * speed).abs();
            torque[(j, j)] = (level * stick).powi(2);
        }
        // The acceleration's covariance M^-1 D M^-1, held over the sample.
        let inverse = chol.inverse();
        held_acceleration_noise::<N, NA>(&(inverse * torque * inverse), self.dt)
    }

    /// The acceleration of the chain of base parameters `theta` at `(q,
    /// qd)` under `tau`; `None` where its inertia is not positive definite.
    fn acceleration(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        theta: &SVector<f64, NP>,
        tau: &Vector<N>,
    ) -> Option<Vector<N>> {
        let mass = self.mass_matrix(q, theta);
        let rest = dynamic_regressor::<N, NP>(&self.prior, q, qd, &Vector::<N>::zeros()) * theta;
        let qdd = mass.cholesky()?.solve(&(tau - rest));
        qdd.iter().all(|v| v.is_finite()).then_some(qdd)
    }

    /// The augmented state after one sample under the held torque `tau`.
    fn propagate(&self, x: &SVector<f64, NA>, tau: &Vector<N>) -> Option<SVector<f64, NA>> {
        let theta: SVector<f64, NP> = x.fixed_rows::<NP>(NX).into_owned();
        let derivative = |z: &SVector<f64, NX>| -> Option<SVector<f64, NX>> {
            let q = Vector::<N>::from_fn(|j, _| z[j]);
            let qd = Vector::<N>::from_fn(|j, _| z[N + j]);
            let qdd = self.acceleration(&q, &qd, &theta, tau)?;
            Some(SVector::<f64, NX>::from_fn(|i, _| {
                if i < N { qd[i] } else { qdd[i - N] }
            }))
        };
        let h = self.dt / self.substeps as f64;
        let mut z: SVector<f64, NX> = x.fixed_rows::<NX>(0).into_owned();
        for _ in 0..self.substeps {
            let k1 = derivative(&z)?;
            let k2 = derivative(&(z + k1 * (0.5 * h)))?;
            let k3 = derivative(&(z + k2 * (0.5 * h)))?;
            let k4 = derivative(&(z + k3 * h))?;
            z += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
        }
        let mut next = *x;
        next.fixed_rows_mut::<NX>(0).copy_from(&z);
        Some(next)
    }

    /// One sample: propagates the estimate under `tau` (the torque that
    /// acted since the previous sample), then corrects it with the measured
    /// state `z = (q, qd)`. The first call only takes `z`. Returns false
    /// when the propagation failed (a parameter estimate without a positive
    /// definite inertia, or a non-finite input): the parameters then
    /// restart from the prior and the state from `z`.
    pub fn step(&mut self, z: &SVector<f64, NX>, tau: &Vector<N>) -> bool {
        if !z.iter().chain(tau.iter()).all(|v| v.is_finite()) {
            return false;
        }
        if !self.started {
            self.estimate.fixed_rows_mut::<NX>(0).copy_from(z);
            self.started = true;
            return true;
        }
        let Some(predicted) = self.propagate(&self.estimate, tau) else {
            self.restart(z);
            return false;
        };
        // The sensitivity by central differences, a step per coordinate
        // scaled to its size.
        let mut a = SMatrix::<f64, NA, NA>::zeros();
        for c in 0..NA {
            let step = 1e-6 * (1.0 + self.estimate[c].abs());
            let mut plus = self.estimate;
            plus[c] += step;
            let mut minus = self.estimate;
            minus[c] -= step;
            let (Some(p), Some(m)) = (self.propagate(&plus, tau), self.propagate(&minus, tau))
            else {
                self.restart(z);
                return false;
            };
            a.set_column(c, &((p - m) / (2.0 * step)));
        }
        let covariance = a * self.covariance * a.transpose() + self.process + self.sticking_noise();
        // The measurement is the state block: H = [I 0].
        let s = covariance.fixed_view::<NX, NX>(0, 0) + self.measurement;
        let Some(chol) = s.cholesky() else {
            self.restart(z);
            return false;
        };
        let pht: SMatrix<f64, NA, NX> = covariance.fixed_columns::<NX>(0).into_owned();
        // K = P H' S^-1, S symmetric: K' = S^-1 (P H')'.
        let gain: SMatrix<f64, NA, NX> = chol.solve(&pht.transpose()).transpose();
        let innovation = z - predicted.fixed_rows::<NX>(0);
        let nis = innovation.dot(&chol.solve(&innovation));
        if nis.is_finite() {
            self.consistency += (nis - self.consistency) * CONSISTENCY_SHARE;
        }
        self.estimate = predicted + gain * innovation;
        // Joseph form with H = [I 0].
        let mut i_kh = SMatrix::<f64, NA, NA>::identity();
        for r in 0..NA {
            for c in 0..NX {
                i_kh[(r, c)] -= gain[(r, c)];
            }
        }
        self.covariance =
            i_kh * covariance * i_kh.transpose() + gain * self.measurement * gain.transpose();
        self.project();
        true
    }

    /// Puts a negative rotor inertia or friction coefficient back on 0, as
    /// the most probable estimate under the covariance that satisfies the
    /// bound (estimate projection): the parameters correlated with it move
    /// too. A viscous friction left negative would pair with a Coulomb
    /// friction too large (measured on B0's rough model 4: b_1 -8 times
    /// its value, cf_1 +41 %). The covariance is kept, so the parameter may
    /// leave the bound again.
    fn project(&mut self) {
        for i in BaseParameters::<N, NP>::NOT_NEGATIVE_FROM..NP {
            let c = NX + i;
            let (value, variance) = (self.estimate[c], self.covariance[(c, c)]);
            if value < 0.0 && variance > 0.0 {
                let shift = self.covariance.column(c) * (value / variance);
                self.estimate -= shift;
            }
        }
        // Later projections may move an earlier one a little below 0.
        for c in NX + BaseParameters::<N, NP>::NOT_NEGATIVE_FROM..NA {
            self.estimate[c] = self.estimate[c].max(0.0);
        }
    }

    /// The state from `z`, the parameters and their covariance from the
    /// prior.
    fn restart(&mut self, z: &SVector<f64, NX>) {
        self.restarts += 1;
        let theta = BaseParameters::<N, NP>::of(&self.prior)
            .map(|b| b.theta)
            .unwrap_or_else(|_| self.estimate.fixed_rows::<NP>(NX).into_owned());
        self.estimate.fixed_rows_mut::<NX>(0).copy_from(z);
        self.estimate.fixed_rows_mut::<NP>(NX).copy_from(&theta);
        self.covariance = self.initial_covariance;
    }
}

/// What a [`StateParameterEkf`] carries from one sample to the next (an
/// FMU's saved state): its estimate and covariance, flattened.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FilterState {
    estimate: Vec<f64>,
    covariance: Vec<f64>,
    started: bool,
    restarts: usize,
    consistency: f64,
}

impl<const N: usize, const NX: usize, const NP: usize, const NA: usize>
    StateParameterEkf<N, NX, NP, NA>
{
    /// Everything the next samples depend on. Allocates (not for the
    /// sample path).
    pub fn save_state(&self) -> FilterState {
        FilterState {
            estimate: self.estimate.iter().copied().collect(),
            covariance: self.covariance.iter().copied().collect(),
            started: self.started,
            restarts: self.restarts,
            consistency: self.consistency,
        }
    }

    /// Continues from `state`, saved by a filter of the same size (the
    /// prior, noise and sample period are this filter's). Nothing changes
    /// when it does not fit.
    pub fn restore_state(&mut self, state: &FilterState) -> Result<(), String> {
        if state.estimate.len() != NA || state.covariance.len() != NA * NA {
            return Err(format!(
                "a filter state of {} values and {} covariances for {NA}",
                state.estimate.len(),
                state.covariance.len()
            ));
        }
        let finite = state
            .estimate
            .iter()
            .chain(&state.covariance)
            .chain([&state.consistency])
            .all(|v| v.is_finite());
        if !finite {
            return Err("a filter state with non-finite values".into());
        }
        self.estimate = SVector::<f64, NA>::from_column_slice(&state.estimate);
        self.covariance = SMatrix::<f64, NA, NA>::from_column_slice(&state.covariance);
        self.started = state.started;
        self.restarts = state.restarts;
        self.consistency = state.consistency;
        Ok(())
    }
}

/// A filter of the state and the base parameters, as the adaptation uses
/// one (its joint count `N`, state size `NX`, base parameter count `NP`):
/// the augmented size stays inside.
pub trait ParameterFilter<const N: usize, const NX: usize, const NP: usize>:
    Send + std::fmt::Debug
{
    /// One sample: the torque that acted since the previous one, then the
    /// measured state.
    fn step(&mut self, z: &SVector<f64, NX>, tau: &Vector<N>) -> bool;
    /// The estimated base parameters.
    fn parameters(&self) -> BaseParameters<N, NP>;
    /// Their covariance.
    fn parameter_covariance(&self) -> SMatrix<f64, NP, NP>;
    /// Everything the next samples depend on (allocates).
    fn save_state(&self) -> FilterState;
    /// Continues from `state`; nothing changes when it does not fit.
    fn restore_state(&mut self, state: &FilterState) -> Result<(), String>;
}

impl<const N: usize, const NX: usize, const NP: usize, const NA: usize> ParameterFilter<N, NX, NP>
    for StateParameterEkf<N, NX, NP, NA>
{
    fn step(&mut self, z: &SVector<f64, NX>, tau: &Vector<N>) -> bool {
        StateParameterEkf::step(self, z, tau)
    }

    fn parameters(&self) -> BaseParameters<N, NP> {
        StateParameterEkf::parameters(self)
    }

    fn parameter_covariance(&self) -> SMatrix<f64, NP, NP> {
        StateParameterEkf::parameter_covariance(self)
    }

    fn save_state(&self) -> FilterState {
        StateParameterEkf::save_state(self)
    }

    fn restore_state(&mut self, state: &FilterState) -> Result<(), String> {
        StateParameterEkf::restore_state(self, state)
    }
}
