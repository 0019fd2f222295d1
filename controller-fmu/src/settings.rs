//! Everything that defines one controller, shared by the FMU (filled from its
//! parameters) and the plain C API (filled from `EigenMpcConfig`), so both
//! build the controller the same way.

use eigenmpc::mechanics::{DoublePendulum, PlanarChainParams, Vector};
use eigenmpc::modes::{Chart, FMU_CHART_DEGREE};
use eigenmpc::mpc::{Controller, CostParams, MpcConfig, QpBackend, Reference, Variant, Weights};

/// Number of chart coefficients per joint (powers `0..=9`, the library's
/// `FMU_CHART_DEGREE`; a literal so that the C header can use it).
pub const CHART_COEFFICIENTS: usize = 10;
const _: () = assert!(CHART_COEFFICIENTS == FMU_CHART_DEGREE + 1);

/// The controller type behind the FMU and the C API.
pub type PendulumController = Controller<DoublePendulum, 2, 4>;

/// Unit in-phase eigenvector of the paper's double pendulum
/// (m = l = 1, g = 9.81): `eigenmpc modes --energies 14`, `linear.eigenvector`.
///
/// cbindgen:ignore
pub const DEFAULT_EIGENVECTOR: [f64; 2] = [0.923879532511287, 0.38268343236508934];

/// Chart of the paper's 14 J in-phase eigenmode (degree 9) of the default
/// model, per joint the coefficients of `s^0..s^9`: pasted from
/// `eigenmpc modes --energies 14 --fmu-start-values FILE`; a test recomputes
/// it. (The even powers vanish up to fitting noise: the mode is symmetric.)
///
/// cbindgen:ignore
pub const DEFAULT_CHART_14J: [[f64; CHART_COEFFICIENTS]; 2] = [
    [
        -1.5052159046577842e-13,
        0.5531221059476479,
        -5.491549575986848e-13,
        0.9749828065062158,
        4.2307952497462395e-12,
        -1.0166322311774332,
        -6.984272799679647e-12,
        0.9510679594842322,
        4.29172769845075e-12,
        -0.37213572933988365,
    ],
    [
        3.632493802496032e-13,
        1.2777710399255753,
        1.3263274688716941e-12,
        -2.353816714547903,
        -1.0200914851325364e-11,
        2.454367320454213,
        1.6821919178875235e-11,
        -2.296081166525384,
        -1.0333171867907603e-11,
        0.8984151248159734,
    ],
];

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
        }
    }

    /// The controller's cost parameters for `variant`.
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
            compensate_friction: true,
        }
    }
}

/// One controller's full definition.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
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
    /// The controller's pendulum model (no damping, as the paper's).
    pub model: PlanarChainParams<2>,
    /// Linear eigenvector `c` (normalised when the controller is built).
    pub eigenvector: [f64; 2],
    /// Chart coefficients (curved): joint, power.
    pub chart: [[f64; CHART_COEFFICIENTS]; 2],
}

impl Settings {
    /// The paper's setting for `variant` on the default model with the 14 J chart.
    pub fn paper(variant: Variant) -> Self {
        let config = MpcConfig::paper(variant);
        Self {
            variant,
            qp: config.qp,
            tuning: Tuning::paper(),
            tau_max: config.tau_max,
            horizon: config.horizon,
            sample_period: config.dt,
            model: PlanarChainParams::default(),
            eigenvector: DEFAULT_EIGENVECTOR,
            chart: DEFAULT_CHART_14J,
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
        config
    }

    /// Builds the controller; the message names what is wrong.
    pub fn build(&self) -> Result<PendulumController, String> {
        let system = DoublePendulum::new(self.model)
            .map_err(|e| format!("invalid pendulum parameters: {e}"))?;
        let c = Vector::<2>::from(self.eigenvector);
        if !c.iter().all(|v| v.is_finite()) || c.norm() < 1e-6 {
            return Err(format!(
                "eigenvector c = ({}, {}) must be finite and nonzero",
                c[0], c[1]
            ));
        }
        let c = c.normalize();
        let reference = match self.variant {
            Variant::Straight => Reference::Straight { eigenvector: c },
            Variant::Curved => {
                let chart = Chart::from_coefficients(
                    c,
                    eigenmpc::mechanics::MechanicalSystem::equilibrium(&system),
                    self.chart.map(|row| row.to_vec()),
                )
                .map_err(|e| format!("invalid chart: {e}"))?;
                // A chart fitted in s = c'q has c'X'(s) = 1 along its path; a
                // chart of another mode (or another c) does not, and s would
                // then silently mean something else.
                let slope = c.dot(&chart.eval(0.0).dx);
                if !(0.8..=1.25).contains(&slope) {
                    return Err(format!(
                        "chart and eigenvector c do not belong together: c'X'(0) = {slope:.3} \
                         (a chart fitted in s = c'q has 1); pass the c[j] written with the chart"
                    ));
                }
                Reference::Curved(chart)
            }
        };
        Controller::new(system, self.config(), reference).map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_settings_build_and_a_foreign_eigenvector_is_refused() {
        assert!(Settings::paper(Variant::Curved).build().is_ok());
        assert!(Settings::paper(Variant::Straight).build().is_ok());
        // The anti-phase direction with the in-phase 14 J chart.
        let mut s = Settings::paper(Variant::Curved);
        s.eigenvector = [0.3827, -0.9239];
        let err = s.build().err().expect("refused");
        assert!(err.contains("do not belong together"), "{err}");
        // Straight ignores the chart: any direction is fine.
        let mut s = Settings::paper(Variant::Straight);
        s.eigenvector = [0.3827, -0.9239];
        assert!(s.build().is_ok());
    }
}
