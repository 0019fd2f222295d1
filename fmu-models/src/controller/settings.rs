//! Everything that defines one controller, shared by the FMU (filled from
//! its parameters through the variable table) and the plain C API (filled
//! from its config struct), so both build the controller the same way.

use super::precomputed::PrecomputedFamily;
use crate::chain::{ChainParameters, HasChain};
use eigenmpc::adapt::{AdaptOptions, Adaptation};
use eigenmpc::identify::RlsOptions;
use eigenmpc::mechanics::{MechanicalSystem, PlanarChain, PlanarChainParams, Vector};
use eigenmpc::modes::{Chart, ChartFamily, FamilyOptions, linear_modes};
use eigenmpc::mpc::{
    Controller, CostParams, EstimatorConfig, Guide, MpcConfig, PREDICTION_SUBSTEPS, QpBackend,
    Reference, Variant, Weights, prediction_model,
};
use eigenmpc::state_parameter_ekf::{StateParameterEkf, StateParameterOptions};

/// Longest horizon the clarabel QP backend is offered for.
pub const CLARABEL_MAX_HORIZON: usize = 200;

/// Number of chart coefficients per joint (powers `0..=9`, the paper's degree).
pub const CHART_COEFFICIENTS: usize = 10;

/// The controller behind an `N`-joint FMU (`NX = 2 N`).
pub type ChainController<const N: usize, const NX: usize> = Controller<PlanarChain<N>, N, NX>;

/// The energy weight actually used: a negative `w_E` selects the paper's
/// value for the variant (25 curved, 5 straight).
pub fn effective_energy_weight(w_e: f64, variant: Variant) -> f64 {
    if w_e < 0.0 {
        Weights::paper(variant).energy
    } else {
        w_e
    }
}

/// Tunable cost parameters as the FMU and C API take them (`w_E < 0`: paper default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tuning {
    /// Reference energy `E_ref` (J).
    pub e_ref: f64,
    /// Exploration gain `alpha` (1/J).
    pub alpha: f64,
    /// Torque-weight offset `beta`.
    pub beta: f64,
    /// Energy weight `w_E` (negative: paper default of the variant).
    pub w_e: f64,
    /// Position weight `w_x`.
    pub w_x: f64,
    /// Velocity weight `w_xd`.
    pub w_xd: f64,
    /// Torque weight `w_F`.
    pub w_f: f64,
    /// Energy scale `E_s` (J): below it the energy residual is
    /// `r_E = (E_ref - E) sqrt(E_s / E_ref)` ([`CostParams::energy_scale`];
    /// from `E_s` up, and with 0, the paper's `E_ref - E`).
    pub e_scale: f64,
}

impl Tuning {
    /// The paper's tuning with `w_E` left to the variant's default.
    pub fn paper() -> Self {
        let p = MpcConfig::paper(Variant::Curved).cost;
        Self {
            e_ref: p.e_ref,
            alpha: p.alpha,
            beta: p.beta,
            w_e: -1.0,
            w_x: p.weights.position,
            w_xd: p.weights.velocity,
            w_f: p.weights.torque,
            e_scale: p.energy_scale,
        }
    }

    /// The controller's cost parameters for `variant` (what is not exposed:
    /// the library's paper defaults).
    pub fn cost(&self, variant: Variant) -> CostParams {
        CostParams {
            e_ref: self.e_ref,
            alpha: self.alpha,
            beta: self.beta,
            weights: Weights {
                energy: effective_energy_weight(self.w_e, variant),
                position: self.w_x,
                velocity: self.w_xd,
                torque: self.w_f,
            },
            energy_scale: self.e_scale,
            ..MpcConfig::paper(variant).cost
        }
    }
}

/// Where the controller's reference (eigenvector line, chart) comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChartSource {
    /// Computed from the controller's model at creation: the linear mode
    /// `mode` (straight) or its eigenmode family over energy, a chart for
    /// every `E_ref` in the family's range (curved).
    Computed,
    /// The `c[j]` and `chart.coef[j,k]` parameters: one fixed chart.
    Parameters,
}

/// Which state estimator filters the measured state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StateEstimator {
    /// None: the measurement is used as it is.
    None,
    /// Extended Kalman filter on the controller's model.
    Ekf,
}

/// Where the online adaptation's candidate models come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdaptEstimator {
    /// The energy balance over windows (recursive least squares,
    /// [`eigenmpc::identify::EnergyBalanceRls`]).
    EnergyBalance,
    /// The state and the base parameters estimated together every sample
    /// ([`eigenmpc::state_parameter_ekf::StateParameterEkf`]), the loop
    /// excited while it learns ([`AdaptOptions::excitation`]).
    StateAndParameters,
}

/// One controller's full definition.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings<const N: usize> {
    /// Straight or curved EigenMPC.
    pub variant: Variant,
    /// QP solver of the real-time iteration.
    pub qp: QpBackend,
    /// Tunable cost parameters.
    pub tuning: Tuning,
    /// Torque bound `|tau_i| <= tau_max` (N m).
    pub tau_max: f64,
    /// Shooting intervals `N`.
    pub horizon: usize,
    /// Sample period and shooting interval `dt` (s).
    pub sample_period: f64,
    /// The controller's model.
    pub model: ChainParameters<N>,
    /// Linear eigenvector `c` (normalised when the controller is built).
    pub eigenvector: [f64; N],
    /// Chart coefficients (curved): joint, power.
    pub chart: [[f64; CHART_COEFFICIENTS]; N],
    /// Reference computed from the model, or `eigenvector` and `chart`.
    pub chart_source: ChartSource,
    /// Linear mode of the computed reference, 0-based in ascending
    /// frequency (0: in-phase).
    pub mode: usize,
    /// Top of the computed family's energy range (J); `<= 0`: the default
    /// of [`FamilyOptions::for_system`] (half the upright potential, at
    /// least 1.25 `E_ref`).
    pub family_energy_max: f64,
    /// State estimator on the measured state.
    pub state_estimator: StateEstimator,
    /// Its noise levels (used with [`StateEstimator::Ekf`]).
    pub noise: EstimatorConfig,
    /// Online identification of the model, which the model, its energy
    /// and its mode family then follow ([`eigenmpc::adapt`]).
    pub adapt: bool,
    /// Time between two looks at the estimate (s): a new model is taken
    /// or requested at most this often.
    pub adapt_period: f64,
    /// Where the adaptation's candidates come from.
    pub adapt_estimator: AdaptEstimator,
    /// Real-time adaptation: a sample never waits for the worker thread's
    /// new model (it is taken at the first look after it is ready, so the
    /// closed loop depends on the machine's speed). Off: the next look
    /// waits for it, and every run gives the same numbers.
    pub adapt_realtime: bool,
    /// Age of the measured state when it arrives (s; see
    /// [`MpcConfig::measurement_delay`]).
    pub measurement_delay: f64,
    /// Time constant of the actuator's first-order lag (s; see
    /// [`MpcConfig::actuator_time_constant`]).
    pub actuator_time_constant: f64,
    /// The motor's response per sample `u += a (tau - u)` (1: immediate;
    /// see [`MpcConfig::torque_response`]).
    pub torque_response: f64,
    /// The stall supervisor ([`eigenmpc::mpc::SupervisorOptions`]): a
    /// joint held still at a large torque, off the target energy, gets its
    /// torque released.
    pub supervisor: bool,
}

impl<const N: usize> HasChain<N> for Settings<N> {
    fn chain(&self) -> &ChainParameters<N> {
        &self.model
    }
    fn chain_mut(&mut self) -> &mut ChainParameters<N> {
        &mut self.model
    }
}

impl<const N: usize> Settings<N> {
    /// The paper's setting for `variant` on the default model, with the
    /// given reference (energy, eigenvector, chart).
    pub fn paper(
        variant: Variant,
        e_ref: f64,
        eigenvector: [f64; N],
        chart: [[f64; CHART_COEFFICIENTS]; N],
    ) -> Self {
        let config = MpcConfig::paper(variant);
        Self {
            variant,
            qp: config.qp,
            tuning: Tuning {
                e_ref,
                ..Tuning::paper()
            },
            tau_max: config.tau_max,
            horizon: config.horizon,
            sample_period: config.dt,
            model: ChainParameters::default(),
            eigenvector,
            chart,
            chart_source: ChartSource::Computed,
            mode: 0,
            family_energy_max: -1.0,
            state_estimator: StateEstimator::None,
            noise: EstimatorConfig {
                angle_noise: 0.05,
                speed_noise: 0.05,
                acceleration_noise: 0.3,
            },
            adapt: false,
            adapt_period: 1.0,
            adapt_estimator: AdaptEstimator::EnergyBalance,
            adapt_realtime: false,
            measurement_delay: config.measurement_delay,
            actuator_time_constant: config.actuator_time_constant,
            torque_response: config.torque_response,
            supervisor: config.supervisor.enabled,
        }
    }

    /// The adaptation's options (with [`Settings::adapt`]).
    pub fn adapt_options(&self) -> AdaptOptions {
        AdaptOptions {
            period: ((self.adapt_period / self.sample_period).round() as usize).max(1),
            family_energy_max: self.family_energy_max,
            synchronous: !self.adapt_realtime,
            rls: self.rls_options(),
            ..AdaptOptions::default()
        }
    }

    /// The online adaptation of a controller whose model is `prior`, with
    /// the filter of [`AdaptEstimator::StateAndParameters`] when set
    /// (`NX = 2 N`, `NP` = the base parameters, `NA = NX + NP`). Set-up:
    /// allocates and starts the worker thread.
    pub fn adaptation<const NX: usize, const NP: usize, const NA: usize>(
        &self,
        prior: &PlanarChainParams<N>,
    ) -> Result<Adaptation<N, NX, NP>, String> {
        let mut adaptation = Adaptation::new(prior, self.adapt_options())
            .map_err(|e| format!("adapt = true: {e}"))?;
        if self.adapt_estimator == AdaptEstimator::StateAndParameters {
            let filter = StateParameterEkf::<N, NX, NP, NA>::new(
                prior,
                self.filter_options(),
                self.sample_period,
            )
            .map_err(|e| format!("adapt_estimator = state_and_parameters: {e}"))?;
            adaptation.set_filter(Box::new(filter));
        }
        Ok(adaptation)
    }

    /// The state and parameter filter's settings
    /// ([`AdaptEstimator::StateAndParameters`]): the sensors' noise as the
    /// state estimator is told it, else the laboratory robots' (0.005 rad,
    /// 0.05 rad/s).
    pub fn filter_options(&self) -> StateParameterOptions {
        let options = StateParameterOptions::default();
        match self.state_estimator {
            StateEstimator::None => options,
            StateEstimator::Ekf => StateParameterOptions {
                angle_noise: self.noise.angle_noise,
                speed_noise: self.noise.speed_noise,
                ..options
            },
        }
    }

    /// The identification's settings: the sensors' noise as the state
    /// estimator is told it (none without the estimator).
    fn rls_options(&self) -> RlsOptions {
        let rls = RlsOptions::default();
        match self.state_estimator {
            StateEstimator::None => rls,
            StateEstimator::Ekf => RlsOptions {
                angle_noise: self.noise.angle_noise,
                speed_noise: self.noise.speed_noise,
                ..rls
            },
        }
    }

    /// The controller configuration (paper defaults for what is not exposed).
    pub fn config(&self) -> MpcConfig {
        let mut config = MpcConfig::paper(self.variant);
        config.horizon = self.horizon;
        config.dt = self.sample_period;
        config.tau_max = self.tau_max;
        config.cost = self.tuning.cost(self.variant);
        config.qp = self.qp;
        config.estimator = match self.state_estimator {
            StateEstimator::None => None,
            StateEstimator::Ekf => Some(self.noise),
        };
        config.measurement_delay = self.measurement_delay;
        config.actuator_time_constant = self.actuator_time_constant;
        config.torque_response = self.torque_response;
        config.supervisor.enabled = self.supervisor;
        config
    }

    /// The controller's model; the message names the FMU parameter.
    pub fn system(&self) -> Result<PlanarChain<N>, String> {
        self.model.build()
    }

    /// The reference of the variant on `system`: the eigenvector line
    /// (straight) or the chart (curved, hybrid), checked to belong together.
    pub fn reference(&self, system: &PlanarChain<N>) -> Result<Reference<N>, String> {
        let c = Vector::<N>::from(self.eigenvector);
        if !c.iter().all(|v| v.is_finite()) || c.norm() < 1e-6 {
            let list: Vec<String> = c.iter().map(|x| x.to_string()).collect();
            return Err(format!(
                "eigenvector c = ({}) must be finite and nonzero",
                list.join(", ")
            ));
        }
        let c = c.normalize();
        Reference::of(
            self.variant,
            || Ok(c),
            || {
                let chart = Chart::from_coefficients(
                    c,
                    system.equilibrium(),
                    self.chart.map(|row| row.to_vec()),
                )
                .map_err(|e| format!("invalid chart: {e}"))?;
                // A chart fitted in s = c'q has c'X'(0) = 1 along its path; a
                // chart of another mode (or another c) does not, and s would
                // then silently mean something else.
                let slope = c.dot(&chart.eval(0.0).dx);
                if !(0.8..=1.25).contains(&slope) {
                    return Err(format!(
                        "chart and eigenvector c do not belong together: c'X'(0) = {slope:.3} \
                         (a chart fitted in s = c'q has 1); pass the c[j] written with the chart"
                    ));
                }
                Ok(chart)
            },
        )
    }

    /// Builds the controller (`NX = 2 N`); the message names what is wrong.
    /// A computed curved reference continues the mode family at creation
    /// (tens of milliseconds for 2 links, see `cargo bench --bench modes`).
    pub fn build<const NX: usize>(&self) -> Result<ChainController<N, NX>, String> {
        self.build_with::<NX>(None)
            .map(|(controller, _)| controller)
    }

    /// [`Settings::build`] taking `precomputed` as its mode family when it
    /// is the one it would compute. Also returns why a given family was not
    /// taken (None: taken, or none given, or not needed).
    pub fn build_with<const NX: usize>(
        &self,
        precomputed: Option<&PrecomputedFamily<N>>,
    ) -> Result<(ChainController<N, NX>, Option<String>), String> {
        if self.qp == QpBackend::Clarabel && self.horizon > CLARABEL_MAX_HORIZON {
            // Its sparse solves grow faster than N: seconds per sample at
            // N = 1000, an unbounded call for a real-time controller.
            return Err(format!(
                "horizon = {} with qp_solver = clarabel: at most {CLARABEL_MAX_HORIZON} \
                 (clarabel's time per sample grows faster than the horizon; riccati is linear \
                 in it and takes up to {})",
                self.horizon,
                eigenmpc::mpc::MAX_HORIZON
            ));
        }
        let system = self.system()?;
        let mut config = self.config();
        // A model with Coulomb friction predicts with RK4 substeps and a
        // slope they can take (the robot itself without it); the reference
        // and the mode family are the robot's (friction does not enter).
        let (model, substeps, _) = prediction_model(&system, config.dt, PREDICTION_SUBSTEPS);
        config.substeps = substeps;
        match self.chart_source {
            ChartSource::Parameters => {
                let reference = self.reference(&system)?;
                let c = Controller::new(model, config, reference).map_err(|e| e.to_string())?;
                Ok((c, None))
            }
            // A chart variant follows the family over E_ref.
            ChartSource::Computed if self.variant.uses_chart() => {
                let (family, refused) = match precomputed {
                    Some(p) => match p.mismatch(self, &system) {
                        None => (p.family.clone(), None),
                        Some(why) => (self.family::<NX>(&system)?, Some(why)),
                    },
                    None => (self.family::<NX>(&system)?, None),
                };
                let c = Controller::with_family_as(model, config, family, self.variant)
                    .map_err(|e| e.to_string())?;
                Ok((c, refused))
            }
            ChartSource::Computed => {
                let eigenvector = self.linear_mode(&system)?;
                let reference = Reference::new(self.variant, Guide::Line(eigenvector))?;
                let c = Controller::new(model, config, reference).map_err(|e| e.to_string())?;
                Ok((c, None))
            }
        }
    }

    /// The unit eigenvector of linear mode `mode` of `system`.
    fn linear_mode(&self, system: &PlanarChain<N>) -> Result<Vector<N>, String> {
        let modes = linear_modes(system).map_err(|e| format!("linear modes of the model: {e}"))?;
        modes
            .get(self.mode)
            .map(|m| m.eigenvector)
            .ok_or_else(|| format!("mode = {} must be 1..={N}", self.mode + 1))
    }

    /// The family options of the computed chart.
    pub fn family_options(&self, system: &PlanarChain<N>) -> FamilyOptions {
        let mut opts = if self.family_energy_max > 0.0 {
            FamilyOptions::up_to(self.family_energy_max)
        } else {
            FamilyOptions::for_system(system, &[self.tuning.e_ref])
        };
        opts.degree = CHART_COEFFICIENTS - 1;
        opts
    }

    /// The eigenmode family of linear mode `mode` of `system` (curved,
    /// computed), with charts of the FMU's degree.
    pub fn family<const NX: usize>(
        &self,
        system: &PlanarChain<N>,
    ) -> Result<ChartFamily<N>, String> {
        self.linear_mode(system)?;
        let opts = self.family_options(system);
        ChartFamily::compute::<_, NX>(system, self.mode, &opts).map_err(|e| {
            format!(
                "the mode family of mode {} up to {} J could not be computed: {e} (lower \
                 family_energy_max, or bring a chart with chart_source = parameters)",
                self.mode + 1,
                opts.energy_max
            )
        })
    }
}

/// Why `E_ref` does not get its own chart (None: it does): outside the
/// computed family's range it is clamped to the chart at the range end.
pub fn chart_clamp_warning<const N: usize, const NX: usize>(
    controller: &ChainController<N, NX>,
) -> Option<String> {
    let family = controller.family()?;
    let e_ref = controller.config().cost.e_ref;
    let (lo, hi) = family.energy_range();
    if (lo..=hi).contains(&e_ref) {
        return None;
    }
    let ended = family
        .ended_early()
        .map(|why| format!("; the family ends there: {why}"))
        .unwrap_or_default();
    Some(format!(
        "E_ref = {e_ref} J is outside the chart family's range {lo:.6} .. {hi:.6} J: the chart \
         of {:.6} J is used (raise family_energy_max for a higher E_ref){ended}",
        family.clamp(e_ref)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use eigenmpc::mechanics::{Joint, PlanarChainParams};

    /// A controller model with Coulomb friction predicts with its substeps
    /// and the slope they take;
    /// the paper's frictionless model keeps one RK4 step per interval.
    #[test]
    fn a_friction_model_gets_prediction_substeps() {
        let mut s = Settings::<2>::paper(
            Variant::Straight,
            2.0,
            [0.92, 0.38],
            [[0.0; CHART_COEFFICIENTS]; 2],
        );
        assert_eq!(s.build::<4>().unwrap().config().substeps, 1);
        let mut p = PlanarChainParams::<2>::point_masses([0.6, 0.6], [0.3, 0.2], 9.81);
        p.joints = [Joint {
            coulomb: 0.09,
            ..Joint::default()
        }; 2];
        s.model = ChainParameters::from_params(&p).unwrap();
        let c = s.build::<4>().unwrap();
        assert_eq!(c.config().substeps, PREDICTION_SUBSTEPS);
        // The slope lowered to what its substeps take: the stiffest
        // friction mode at RK4's margin, not beyond it.
        let k = c.system().params().coulomb_sharpness;
        let h = c.config().dt / PREDICTION_SUBSTEPS as f64;
        let rate = eigenmpc::mpc::prediction::coulomb_rate_per_slope(c.system());
        assert!(k < 100.0, "{k}");
        assert!(
            (h * rate * k - eigenmpc::mpc::prediction::PREDICTION_FRICTION_STEP_LIMIT).abs() < 1e-9
        );
    }
}
