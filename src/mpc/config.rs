//! Controller configuration (sized at creation, validated as a whole) and
//! its errors.

use super::Variant;
use super::cost::{CostParams, PAPER_ENERGY_SCALE, Weights};
use super::estimator::EstimatorConfig;
use super::supervisor::SupervisorOptions;
use crate::qp::QpBackend;
use thiserror::Error;

/// Largest accepted horizon `N` (the FMU's `horizon` parameter and the C
/// API share it; memory and time grow linearly in `N`).
pub const MAX_HORIZON: usize = 1000;

/// Most first-sample Gauss-Newton iterations ([`Startup::Iterations`]).
pub const MAX_STARTUP_ITERATIONS: usize = 100;

/// How the first sample solves, from the zero-torque guess.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Startup {
    /// This many full Gauss-Newton iterations (RTI steps, no line search)
    /// in the first sample: its work is bounded, one linearisation and one
    /// QP each, about ten RTI samples for the default
    /// [`Startup::DEFAULT_ITERATIONS`]. The samples after it continue as
    /// RTI.
    Iterations(usize),
    /// The SQP with an L1-merit line search to convergence
    /// ([`MpcConfig::sqp`]; the paper's converged first sample): its time is
    /// not bounded, 90-180 ms on the laboratory robots on the benchmark's
    /// machine (two to three times that with the machine busy), whose
    /// Coulomb friction keeps it from converging within its iteration
    /// limit.
    Converge,
}

impl Startup {
    /// The default first sample's Gauss-Newton iterations: on the paper's
    /// pendulum and the laboratory robots the band time of the converged
    /// start or better (docs/speed.md, "The first sample").
    pub const DEFAULT_ITERATIONS: usize = 10;
}

impl Default for Startup {
    fn default() -> Self {
        Startup::Iterations(Self::DEFAULT_ITERATIONS)
    }
}

/// Settings of the converged SQP mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SqpOptions {
    /// Iteration limit.
    pub max_iterations: usize,
    /// Stop when the step's infinity norm is below this (after a full step).
    pub tolerance: f64,
}

impl Default for SqpOptions {
    fn default() -> Self {
        Self {
            max_iterations: 30,
            tolerance: 1e-5,
        }
    }
}

/// Controller configuration. [`MpcConfig::paper`] gives the paper's values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MpcConfig {
    /// Shooting intervals `N`.
    pub horizon: usize,
    /// Shooting interval and sample period `dt` (s).
    pub dt: f64,
    /// RK4 substeps per shooting interval (the most, with
    /// `substeps_where_stiff`).
    pub substeps: usize,
    /// Take all `substeps` only in intervals where a joint may come to rest
    /// (the Coulomb friction's slope is steep there), fewer elsewhere
    /// (default true; false: all of them in every interval).
    pub substeps_where_stiff: bool,
    /// Torque bound `|tau_i| <= tau_max` (N m).
    pub tau_max: f64,
    /// Cost parameters (tunable between samples).
    pub cost: CostParams,
    /// Terminal cost `terminal_scale * l(z_N, 0)` (0: none, as the paper).
    pub terminal_scale: f64,
    /// Soft joint-angle bound `|q_i - q_eq,i| <= q_max` (`inf`: none).
    pub q_max: f64,
    /// Soft joint-speed bound `|qd_i| <= qd_max` (`inf`: none).
    pub qd_max: f64,
    /// Exact (L1) penalty on soft-bound violations.
    pub soft_l1: f64,
    /// Quadratic penalty on soft-bound violations.
    pub soft_l2: f64,
    /// SQP iterations per sample (1 = plain RTI).
    pub iterations_per_sample: usize,
    /// How the first sample solves (from a zero-torque guess).
    pub startup: Startup,
    /// Converged-SQP settings.
    pub sqp: SqpOptions,
    /// QP solver built by [`Controller::new`](super::Controller::new) (default riccati, see docs/results.md).
    pub qp: QpBackend,
    /// State estimator on the measured state (None, the default: the
    /// measurement is used as it is).
    pub estimator: Option<EstimatorConfig>,
    /// Age of the measured state when it reaches the controller (s; 0, the
    /// default: current). The controller predicts it forward over the
    /// delay with the torques it sent meanwhile (docs/delay.md);
    /// at most [`MAX_COMPENSATED_TIME`] and the horizon's length.
    pub measurement_delay: f64,
    /// Time constant `T` of the actuator's first-order lag
    /// `da/dt = (tau - a) / T` between the commanded torque `tau` and the
    /// applied one `a` (s; 0, the default: immediate); same bounds as
    /// [`MpcConfig::measurement_delay`].
    pub actuator_time_constant: f64,
    /// The motor's response per sample, `u += a (tau - u)`: the torque
    /// applied over a sample moves from the last one's by `a` times its
    /// distance to the command (1, the default: immediate; `a < 1` lags,
    /// `1 < a <= 2` overshoots, 2 oscillates without decay). The plan's
    /// controls are the applied torques, bounded per stage by what the
    /// motor can reach from the last one; the command is the one that
    /// makes the motor apply the plan's first ([`MpcConfig::torque_response`]
    /// and [`MpcConfig::actuator_time_constant`] are alternatives: one of
    /// them at most).
    pub torque_response: f64,
    /// The stall supervisor (on by default): a torque held at its bound
    /// without motion, off the target energy, is released
    /// ([`SupervisorOptions`]).
    pub supervisor: SupervisorOptions,
}

/// Longest measurement delay or actuator time constant the controller
/// compensates (s): its history of commands is sized for it at creation.
pub const MAX_COMPENSATED_TIME: f64 = 1.0;

impl MpcConfig {
    /// The paper's setting (section V-A): N = 80, dt = 25 ms, |tau| <= 1 N m,
    /// w_x = 50, w_xd = 2500, w_F = 225, w_E = 25 (curved) / 5 (straight),
    /// alpha = beta = 0.1, E_ref = 14 J; below 14 J the energy residual
    /// scaled by sqrt(14 J / E_ref) ([`CostParams::energy_scale`]), from
    /// 14 J up the paper's residual exactly.
    pub fn paper(variant: Variant) -> Self {
        Self {
            horizon: 80,
            dt: 0.025,
            substeps: 1,
            substeps_where_stiff: true,
            tau_max: 1.0,
            cost: CostParams {
                e_ref: 14.0,
                alpha: 0.1,
                beta: 0.1,
                weights: Weights::paper(variant),
                energy_scale: PAPER_ENERGY_SCALE,
                compensate_friction: true,
            },
            terminal_scale: 0.0,
            q_max: f64::INFINITY,
            qd_max: f64::INFINITY,
            soft_l1: 1e3,
            soft_l2: 1e3,
            iterations_per_sample: 1,
            startup: Startup::default(),
            sqp: SqpOptions::default(),
            qp: QpBackend::default(),
            estimator: None,
            measurement_delay: 0.0,
            actuator_time_constant: 0.0,
            torque_response: 1.0,
            supervisor: SupervisorOptions::default(),
        }
    }

    /// Checks every field; the message names the offending one.
    pub fn validate(&self) -> Result<(), MpcError> {
        let bad = |name: &'static str, value: f64, reason: &'static str| {
            Err(MpcError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        if self.horizon == 0 || self.horizon > MAX_HORIZON {
            return bad("horizon", self.horizon as f64, "must be in 1..=1000");
        }
        if self.qp.available().is_err() {
            return bad(
                "qp_solver",
                0.0,
                "clarabel is not in this build (the core's feature `clarabel`): use riccati",
            );
        }
        if !(self.dt.is_finite() && self.dt > 0.0) {
            return bad("dt", self.dt, "must be finite and > 0");
        }
        if self.substeps == 0 || self.substeps > 1000 {
            return bad("substeps", self.substeps as f64, "must be in 1..=1000");
        }
        if !(self.tau_max.is_finite() && self.tau_max > 0.0) {
            return bad("tau_max", self.tau_max, "must be finite and > 0");
        }
        validate_cost(&self.cost)?;
        if !(self.terminal_scale.is_finite() && self.terminal_scale >= 0.0) {
            return bad(
                "terminal_scale",
                self.terminal_scale,
                "must be finite and >= 0",
            );
        }
        for (name, v) in [("q_max", self.q_max), ("qd_max", self.qd_max)] {
            if v.is_nan() || v <= 0.0 {
                return bad(name, v, "must be > 0 (inf: no bound)");
            }
        }
        for (name, v) in [("soft_l1", self.soft_l1), ("soft_l2", self.soft_l2)] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, v, "must be finite and >= 0");
            }
        }
        if self.iterations_per_sample == 0 || self.iterations_per_sample > 100 {
            return bad(
                "iterations_per_sample",
                self.iterations_per_sample as f64,
                "must be in 1..=100",
            );
        }
        if let Some(e) = &self.estimator {
            e.validate()?;
        }
        self.supervisor.validate()?;
        for (name, v) in [
            ("measurement_delay", self.measurement_delay),
            ("actuator_time_constant", self.actuator_time_constant),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, v, "must be finite and >= 0");
            }
            if v > MAX_COMPENSATED_TIME {
                return bad(name, v, "must be at most 1 s");
            }
            // Checked after dt: the horizon's length is finite here.
            if v > self.horizon as f64 * self.dt {
                return bad(name, v, "must be at most the horizon's length (horizon dt)");
            }
        }
        // Beyond 2 the motor's own response diverges (|1 - a| > 1).
        if !(self.torque_response > 0.0 && self.torque_response <= 2.0) {
            return bad("torque_response", self.torque_response, "must be in (0, 2]");
        }
        if self.torque_response != 1.0 && self.actuator_time_constant > 0.0 {
            return bad(
                "torque_response",
                self.torque_response,
                "describes the motor's lag per sample: declare it or actuator_time_constant, not both",
            );
        }
        if let Startup::Iterations(n) = self.startup
            && !(1..=MAX_STARTUP_ITERATIONS).contains(&n)
        {
            return bad(
                "startup iterations",
                n as f64,
                "must be in 1..=100 (Startup::Converge for a converged first sample)",
            );
        }
        if self.sqp.max_iterations == 0 {
            return bad("sqp.max_iterations", 0.0, "must be >= 1");
        }
        if !(self.sqp.tolerance.is_finite() && self.sqp.tolerance > 0.0) {
            return bad(
                "sqp.tolerance",
                self.sqp.tolerance,
                "must be finite and > 0",
            );
        }
        Ok(())
    }
}

pub(crate) fn validate_cost(c: &CostParams) -> Result<(), MpcError> {
    let checks = [
        ("e_ref", c.e_ref),
        ("alpha", c.alpha),
        ("beta", c.beta),
        ("w_E", c.weights.energy),
        ("w_x", c.weights.position),
        ("w_xd", c.weights.velocity),
        ("w_F", c.weights.torque),
        ("energy_scale", c.energy_scale),
    ];
    for (name, value) in checks {
        if !(value.is_finite() && value >= 0.0) {
            return Err(MpcError::InvalidParameter {
                name,
                value,
                reason: "must be finite and >= 0",
            });
        }
    }
    if c.energy_scale > 0.0 && c.e_ref == 0.0 {
        // The scaled residual divides by E_ref.
        return Err(MpcError::InvalidParameter {
            name: "e_ref",
            value: 0.0,
            reason: "must be > 0 with a scaled energy residual (energy_scale > 0; 0: the paper's)",
        });
    }
    if c.weights.torque == 0.0 {
        // Without a torque weight the QP Hessian is singular in tau.
        return Err(MpcError::InvalidParameter {
            name: "w_F",
            value: 0.0,
            reason: "must be > 0",
        });
    }
    Ok(())
}

/// Why a controller could not be built or tuned.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MpcError {
    /// A configuration or tuning value is out of range.
    #[error("parameter {name} = {value} is invalid: {reason}")]
    InvalidParameter {
        /// Parameter name (`w_E`, `dt`, ...).
        name: &'static str,
        /// The offending value.
        value: f64,
        /// The expected range.
        reason: &'static str,
    },
    /// The eigenvector or chart is unusable.
    #[error("invalid reference: {0}")]
    InvalidReference(String),
    /// A saved state does not fit this controller ([`super::Controller::restore_state`]).
    #[error("saved state does not fit: {0}")]
    InvalidState(String),
}

impl From<super::ReferenceError> for MpcError {
    fn from(e: super::ReferenceError) -> Self {
        MpcError::InvalidReference(e.0)
    }
}
