//! The EigenMPC controller: multiple-shooting NMPC of the straight or curved
//! EigenMPC cost (paper, section IV), solved by real-time iterations (RTI,
//! Diehl) with a Gauss-Newton Hessian.
//!
//! Each sample is split as in acados/MATMPC:
//! - **preparation** ([`Controller::prepare`]): shift the previous solution by
//!   one interval, integrate every shooting interval with RK4 and exact
//!   sensitivities, evaluate the residual Jacobians and write the QP in the
//!   step variables `(dx_k, du_k)`;
//! - **feedback** ([`Controller::feedback`]): embed the measured state as
//!   `dx_0 = z - x_0`, solve the QP, take the full step and return `tau_0`.
//!
//! Optionally several iterations per sample, and a converged SQP with an
//! L1-merit backtracking line search ([`Controller::solve_to_convergence`]),
//! used by default for the very first sample. Everything is sized at
//! creation; the per-sample path does not allocate.

pub mod closed_loop;
pub mod cost;
pub mod prediction;

pub use cost::{CostParams, Reference, Variant, Weights};
pub use prediction::{prediction_coulomb_sharpness, prediction_substeps};

use crate::integrate::rk4_step_sensitivity;
use crate::mechanics::{MechanicalSystem, Vector, state_energy};
use crate::modes::ChartFamily;
pub use crate::qp::QpBackend;
use crate::qp::{OcpQp, QpSolution, QpSolver, QpStatus};
use cost::{stage_cost, stage_model};
use nalgebra::{SMatrix, SVector};
use std::time::Instant;
use thiserror::Error;

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
    /// RK4 substeps per shooting interval.
    pub substeps: usize,
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
    /// Solve the first sample to convergence (else start from a zero-torque guess).
    pub converge_first_sample: bool,
    /// Converged-SQP settings.
    pub sqp: SqpOptions,
    /// QP solver built by [`Controller::new`] (default riccati, see docs/results.md).
    pub qp: QpBackend,
}

impl MpcConfig {
    /// The paper's setting (section V-A): N = 80, dt = 25 ms, |tau| <= 1 N m,
    /// w_x = 50, w_xd = 2500, w_F = 225, w_E = 25 (curved) / 5 (straight),
    /// alpha = beta = 0.1, E_ref = 14 J.
    pub fn paper(variant: Variant) -> Self {
        Self {
            horizon: 80,
            dt: 0.025,
            substeps: 1,
            tau_max: 1.0,
            cost: CostParams {
                e_ref: 14.0,
                alpha: 0.1,
                beta: 0.1,
                weights: Weights::paper(variant),
                compensate_friction: true,
            },
            terminal_scale: 0.0,
            q_max: f64::INFINITY,
            qd_max: f64::INFINITY,
            soft_l1: 1e3,
            soft_l2: 1e3,
            iterations_per_sample: 1,
            converge_first_sample: true,
            sqp: SqpOptions::default(),
            qp: QpBackend::default(),
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

fn validate_cost(c: &CostParams) -> Result<(), MpcError> {
    let checks = [
        ("e_ref", c.e_ref),
        ("alpha", c.alpha),
        ("beta", c.beta),
        ("w_E", c.weights.energy),
        ("w_x", c.weights.position),
        ("w_xd", c.weights.velocity),
        ("w_F", c.weights.torque),
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
}

/// What happened in one control step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ControlStatus {
    /// The QP(s) were solved; `tau` is the optimal first control.
    Solved,
    /// The converged-SQP mode hit its iteration limit; `tau` is from the last iterate.
    NotConverged,
    /// A QP failed; `tau` is the shifted previous plan's control, clipped.
    QpFailed(QpStatus),
    /// The measured state was NaN/Inf; `tau` is the shifted previous plan's control, clipped.
    InvalidState,
}

impl ControlStatus {
    /// True when `tau` comes from a successful optimisation.
    pub fn is_ok(self) -> bool {
        matches!(self, ControlStatus::Solved | ControlStatus::NotConverged)
    }

    /// Integer code for C/FMI callers: 0 solved, 1 not converged, 2 QP
    /// failed, 3 invalid state.
    pub fn code(self) -> i32 {
        match self {
            ControlStatus::Solved => 0,
            ControlStatus::NotConverged => 1,
            ControlStatus::QpFailed(_) => 2,
            ControlStatus::InvalidState => 3,
        }
    }

    /// Inverse of [`ControlStatus::code`] for statuses read back from C/FMI
    /// (the code does not carry the QP status: a QP failure comes back as
    /// `QpFailed(QpStatus::NumericalError)`).
    pub fn from_code(code: i32) -> Option<Self> {
        match code {
            0 => Some(ControlStatus::Solved),
            1 => Some(ControlStatus::NotConverged),
            2 => Some(ControlStatus::QpFailed(QpStatus::NumericalError)),
            3 => Some(ControlStatus::InvalidState),
            _ => None,
        }
    }
}

impl std::fmt::Display for ControlStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ControlStatus::Solved => f.write_str("solved"),
            ControlStatus::NotConverged => f.write_str("SQP not converged (iteration limit)"),
            ControlStatus::QpFailed(s) => {
                write!(f, "QP failed ({s:?}): holding the shifted previous plan")
            }
            ControlStatus::InvalidState => {
                f.write_str("measured state is NaN/Inf: holding the shifted previous plan")
            }
        }
    }
}

/// Result of one control step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlOutput<const N: usize> {
    /// Torque to apply over the next sample (always finite and within bounds).
    pub tau: Vector<N>,
    /// What happened.
    pub status: ControlStatus,
    /// QP (interior-point) iterations summed over this sample.
    pub qp_iterations: usize,
    /// SQP iterations in this sample (1 for plain RTI).
    pub sqp_iterations: usize,
    /// Preparation time of this sample (s).
    pub preparation_time: f64,
    /// Feedback time of this sample (s).
    pub feedback_time: f64,
}

/// The EigenMPC controller for a system with `N` joints (`NX = 2 N`).
pub struct Controller<S, const N: usize, const NX: usize> {
    system: S,
    config: MpcConfig,
    reference: Reference<N>,
    /// Current plan: states `x_0..=x_N` and controls `u_0..u_N-1`.
    xs: Vec<SVector<f64, NX>>,
    us: Vec<Vector<N>>,
    /// Line-search trial iterate.
    xs_trial: Vec<SVector<f64, NX>>,
    us_trial: Vec<Vector<N>>,
    qp: OcpQp,
    solution: QpSolution,
    solver: Box<dyn QpSolver + Send>,
    initialised: bool,
    /// The QP holds a linearisation at the current plan.
    prepared: bool,
    /// The plan was applied for one sample and must be shifted.
    shift_pending: bool,
    /// L1 merit penalty parameter (grows monotonically until a reset).
    merit_penalty: f64,
    /// Preparation time already spent for the coming sample.
    pending_preparation_time: f64,
    /// The last sample's QP solution may seed the next one (warm start).
    warm_start_usable: bool,
    /// QP failures in a row; the plan is rebuilt after [`MAX_QP_FAILURES`].
    consecutive_qp_failures: usize,
    /// The eigenmanifold the curved chart follows `E_ref` on (None: fixed chart).
    family: Option<ChartFamily<N>>,
}

/// Largest accepted horizon `N` (the FMU's `horizon` parameter and the C
/// API share it; memory and time grow linearly in `N`).
pub const MAX_HORIZON: usize = 1000;

/// QP failures in a row after which the plan is discarded and the next
/// sample starts afresh (zero-torque rollout, converged SQP): a plan that
/// made the QPs fail once is likely to keep doing so.
pub const MAX_QP_FAILURES: usize = 2;

impl<S, const N: usize, const NX: usize> Controller<S, N, NX>
where
    S: MechanicalSystem<N>,
{
    /// Builds the controller with the QP backend chosen by `config.qp`.
    pub fn new(system: S, config: MpcConfig, reference: Reference<N>) -> Result<Self, MpcError> {
        // Validate before sizing the solver: a bad horizon must not allocate.
        config.validate()?;
        let solver = config.qp.create(2 * N, N, config.horizon);
        Self::with_solver(system, config, reference, solver)
    }

    /// Builds the controller with a given QP backend (sized for `2N`, `N`, `config.horizon`).
    pub fn with_solver(
        system: S,
        config: MpcConfig,
        reference: Reference<N>,
        solver: Box<dyn QpSolver + Send>,
    ) -> Result<Self, MpcError> {
        const { assert!(NX == 2 * N, "NX must equal 2 N") };
        config.validate()?;
        reference.validate().map_err(MpcError::InvalidReference)?;
        let nh = config.horizon;
        let mut qp = OcpQp::new(NX, N, nh);
        for k in 0..nh {
            qp.u_lower[k].fill(-config.tau_max);
            qp.u_upper[k].fill(config.tau_max);
        }
        qp.soft_l1.fill(config.soft_l1);
        qp.soft_l2.fill(config.soft_l2);
        Ok(Self {
            system,
            config,
            reference,
            xs: vec![SVector::zeros(); nh + 1],
            us: vec![Vector::zeros(); nh],
            xs_trial: vec![SVector::zeros(); nh + 1],
            us_trial: vec![Vector::zeros(); nh],
            qp,
            solution: QpSolution::new(NX, N, nh),
            solver,
            initialised: false,
            prepared: false,
            shift_pending: false,
            merit_penalty: 1.0,
            pending_preparation_time: 0.0,
            warm_start_usable: false,
            consecutive_qp_failures: 0,
            family: None,
        })
    }

    /// Builds a curved controller whose chart follows `E_ref` along the
    /// mode family `family`: the chart at `config.cost.e_ref` now, and at
    /// every tuned `E_ref` from the next sample on (interpolated, no
    /// allocation). An `E_ref` outside [`ChartFamily::energy_range`] uses
    /// the chart at the nearest end of the range (see
    /// [`Controller::chart_energy`]) while the energy residual keeps the
    /// true `E_ref`.
    pub fn with_family(
        system: S,
        config: MpcConfig,
        family: ChartFamily<N>,
    ) -> Result<Self, MpcError> {
        config.validate()?;
        let reference = Reference::Curved(family.chart(config.cost.e_ref));
        let mut controller = Self::new(system, config, reference)?;
        controller.family = Some(family);
        Ok(controller)
    }

    /// The mode family the chart follows, if any.
    pub fn family(&self) -> Option<&ChartFamily<N>> {
        self.family.as_ref()
    }

    /// Energy of the chart in use: `E_ref` clamped to the family's range
    /// (None for a fixed chart or the straight variant).
    pub fn chart_energy(&self) -> Option<f64> {
        self.family
            .as_ref()
            .map(|f| f.clamp(self.config.cost.e_ref))
    }

    /// The configuration (cost parameters reflect the latest tuning).
    pub fn config(&self) -> &MpcConfig {
        &self.config
    }

    /// The system model.
    pub fn system(&self) -> &S {
        &self.system
    }

    /// The reference (eigenvector or chart).
    pub fn reference(&self) -> &Reference<N> {
        &self.reference
    }

    /// Name of the QP backend.
    pub fn qp_solver_name(&self) -> &'static str {
        self.solver.name()
    }

    /// Predicted states of the current plan.
    pub fn predicted_states(&self) -> &[SVector<f64, NX>] {
        &self.xs
    }

    /// Controls of the current plan.
    pub fn planned_controls(&self) -> &[Vector<N>] {
        &self.us
    }

    /// The last QP and its solution (diagnostics, tests).
    pub fn last_qp(&self) -> (&OcpQp, &QpSolution) {
        (&self.qp, &self.solution)
    }

    /// Sets all tunable cost parameters at once (no rebuild, no allocation).
    pub fn set_cost(&mut self, cost: CostParams) -> Result<(), MpcError> {
        validate_cost(&cost)?;
        if let (Some(family), Reference::Curved(chart)) = (&self.family, &mut self.reference)
            && cost.e_ref != self.config.cost.e_ref
        {
            family.write_chart(cost.e_ref, chart);
        }
        self.config.cost = cost;
        self.prepared = false;
        Ok(())
    }

    /// Sets the reference energy `E_ref` (J).
    pub fn set_e_ref(&mut self, e_ref: f64) -> Result<(), MpcError> {
        self.set_cost(CostParams {
            e_ref,
            ..self.config.cost
        })
    }

    /// Sets the exploration gain `alpha`.
    pub fn set_alpha(&mut self, alpha: f64) -> Result<(), MpcError> {
        self.set_cost(CostParams {
            alpha,
            ..self.config.cost
        })
    }

    /// Sets the torque-weight offset `beta`.
    pub fn set_beta(&mut self, beta: f64) -> Result<(), MpcError> {
        self.set_cost(CostParams {
            beta,
            ..self.config.cost
        })
    }

    /// Sets the residual weights.
    pub fn set_weights(&mut self, weights: Weights) -> Result<(), MpcError> {
        self.set_cost(CostParams {
            weights,
            ..self.config.cost
        })
    }

    /// Forgets the plan: the next feedback starts afresh.
    pub fn reset(&mut self) {
        self.initialised = false;
        self.prepared = false;
        self.shift_pending = false;
        self.pending_preparation_time = 0.0;
        self.merit_penalty = 1.0;
        self.warm_start_usable = false;
        self.consecutive_qp_failures = 0;
    }

    /// One control step: preparation (unless already done) and feedback.
    pub fn step(&mut self, z: &SVector<f64, NX>) -> ControlOutput<N> {
        self.prepare();
        self.feedback(z)
    }

    /// Preparation phase: shift the previous plan and linearise around it.
    /// Call between samples (before the measurement arrives) to cut latency.
    pub fn prepare(&mut self) {
        if !self.initialised {
            return;
        }
        let start = Instant::now();
        if self.shift_pending {
            self.shift();
            self.solver.shift_warm_start(self.warm_start_usable);
            self.shift_pending = false;
            self.prepared = false;
        }
        if !self.prepared {
            self.linearise();
            self.prepared = true;
        }
        self.pending_preparation_time += start.elapsed().as_secs_f64();
    }

    /// Feedback phase: embed the measured state, solve, return `tau_0`.
    pub fn feedback(&mut self, z: &SVector<f64, NX>) -> ControlOutput<N> {
        let start = Instant::now();
        let preparation_time = std::mem::take(&mut self.pending_preparation_time);
        let mut out = if !z.iter().all(|v| v.is_finite()) {
            self.fallback(ControlStatus::InvalidState)
        } else if !self.initialised {
            self.initialise(z);
            if self.config.converge_first_sample {
                self.solve_to_convergence(z)
            } else {
                self.iterate(z, self.config.iterations_per_sample)
            }
        } else {
            self.iterate(z, self.config.iterations_per_sample)
        };
        if self.initialised {
            self.shift_pending = true;
        }
        // Only a solved sample seeds the next QP; after a fallback the
        // solver's stored iterate no longer matches the shifted plan.
        self.warm_start_usable = out.status.is_ok();
        match out.status {
            ControlStatus::QpFailed(_) => {
                self.consecutive_qp_failures += 1;
                let plan_finite = self.xs.iter().all(|x| x.iter().all(|v| v.is_finite()))
                    && self.us.iter().all(|u| u.iter().all(|v| v.is_finite()));
                if !plan_finite || self.consecutive_qp_failures >= MAX_QP_FAILURES {
                    self.reset();
                }
            }
            ControlStatus::Solved | ControlStatus::NotConverged => {
                self.consecutive_qp_failures = 0;
            }
            ControlStatus::InvalidState => {}
        }
        out.preparation_time = preparation_time;
        out.feedback_time = start.elapsed().as_secs_f64();
        out
    }

    /// Full SQP at `z` to convergence (Gauss-Newton, L1-merit backtracking
    /// line search) from the current plan. Returns the first control.
    pub fn solve_to_convergence(&mut self, z: &SVector<f64, NX>) -> ControlOutput<N> {
        if !z.iter().all(|v| v.is_finite()) {
            return self.fallback(ControlStatus::InvalidState);
        }
        if !self.initialised {
            self.initialise(z);
        }
        let mut qp_iterations = 0;
        for it in 0..self.config.sqp.max_iterations {
            if !self.prepared {
                self.linearise();
            }
            self.set_initial_state(z);
            let status = self.solver.solve(&self.qp, &mut self.solution);
            qp_iterations += self.solution.iterations;
            if !status.is_usable() {
                return self.fallback(ControlStatus::QpFailed(status));
            }
            let step = self.line_search(z);
            self.prepared = false;
            if step.1 == 0.0 {
                // No step length decreased the merit: stop rather than creep.
                return self.output(ControlStatus::NotConverged, qp_iterations, it + 1);
            }
            if step.1 == 1.0 && step.0 < self.config.sqp.tolerance {
                return self.output(ControlStatus::Solved, qp_iterations, it + 1);
            }
        }
        let n = self.config.sqp.max_iterations;
        self.output(ControlStatus::NotConverged, qp_iterations, n)
    }

    /// `iterations` full-step Gauss-Newton iterations at `z` (RTI for 1).
    fn iterate(&mut self, z: &SVector<f64, NX>, iterations: usize) -> ControlOutput<N> {
        let mut qp_iterations = 0;
        for _ in 0..iterations {
            if !self.prepared {
                self.linearise();
            }
            self.set_initial_state(z);
            let status = self.solver.solve(&self.qp, &mut self.solution);
            qp_iterations += self.solution.iterations;
            if !status.is_usable() {
                return self.fallback(ControlStatus::QpFailed(status));
            }
            self.apply_step(1.0);
            self.prepared = false;
        }
        self.output(ControlStatus::Solved, qp_iterations, iterations)
    }

    fn output(&self, status: ControlStatus, qp_iterations: usize, sqp: usize) -> ControlOutput<N> {
        ControlOutput {
            tau: self.clip(&self.us[0]),
            status,
            qp_iterations,
            sqp_iterations: sqp,
            preparation_time: 0.0,
            feedback_time: 0.0,
        }
    }

    /// The shifted previous plan's first control (zero without a plan).
    fn fallback(&self, status: ControlStatus) -> ControlOutput<N> {
        let tau = if self.initialised {
            self.clip(&self.us[0])
        } else {
            Vector::zeros()
        };
        ControlOutput {
            tau,
            status,
            qp_iterations: 0,
            sqp_iterations: 0,
            preparation_time: 0.0,
            feedback_time: 0.0,
        }
    }

    fn clip(&self, u: &Vector<N>) -> Vector<N> {
        let m = self.config.tau_max;
        u.map(|v| if v.is_finite() { v.clamp(-m, m) } else { 0.0 })
    }

    /// Zero-torque rollout from `z` as the first guess.
    fn initialise(&mut self, z: &SVector<f64, NX>) {
        self.xs[0] = *z;
        for k in 0..self.config.horizon {
            self.us[k] = Vector::zeros();
            self.xs[k + 1] = self.simulate_interval(&self.xs[k], &self.us[k]);
        }
        self.initialised = true;
        self.prepared = false;
        self.shift_pending = false;
    }

    /// Drops the first interval; the last control is repeated and the new
    /// terminal state simulated.
    fn shift(&mut self) {
        let nh = self.config.horizon;
        self.xs.copy_within(1.., 0);
        self.us.copy_within(1.., 0);
        let last = self.simulate_interval(&self.xs[nh - 1], &self.us[nh - 1]);
        self.xs[nh] = if last.iter().all(|v| v.is_finite()) {
            last
        } else {
            self.xs[nh - 1]
        };
    }

    fn simulate_interval(&self, z: &SVector<f64, NX>, u: &Vector<N>) -> SVector<f64, NX> {
        let h = self.config.dt / self.config.substeps as f64;
        let mut x = *z;
        for _ in 0..self.config.substeps {
            x = crate::integrate::rk4_step::<S, N, NX>(&self.system, &x, u, h);
        }
        x
    }

    /// Integration with sensitivities over one shooting interval.
    fn interval_sensitivity(
        &self,
        z: &SVector<f64, NX>,
        u: &Vector<N>,
    ) -> (SVector<f64, NX>, SMatrix<f64, NX, NX>, SMatrix<f64, NX, N>) {
        let h = self.config.dt / self.config.substeps as f64;
        let mut x = *z;
        let mut a = SMatrix::<f64, NX, NX>::identity();
        let mut b = SMatrix::<f64, NX, N>::zeros();
        for _ in 0..self.config.substeps {
            let s = rk4_step_sensitivity::<S, N, NX>(&self.system, &x, u, h);
            x = s.z_next;
            b = s.d_z * b + s.d_tau;
            a = s.d_z * a;
        }
        (x, a, b)
    }

    /// Writes the QP in the step variables at the current plan.
    fn linearise(&mut self) {
        let nh = self.config.horizon;
        let cost = self.config.cost;
        let dt = self.config.dt;
        let q_eq = self.system.equilibrium();
        for k in 0..nh {
            let (x_next, a, b) = self.interval_sensitivity(&self.xs[k], &self.us[k]);
            let m = stage_model::<S, N, NX>(
                &self.system,
                &self.reference,
                &cost,
                &self.xs[k],
                &self.us[k],
                dt,
            );
            self.qp.a[k].copy_from(&a);
            self.qp.b[k].copy_from(&b);
            self.qp.c[k].copy_from(&(x_next - self.xs[k + 1]));
            self.qp.q[k].copy_from(&m.q);
            self.qp.s[k].copy_from(&m.s);
            self.qp.r[k].copy_from(&m.r);
            self.qp.q_lin[k].copy_from(&m.gz);
            self.qp.r_lin[k].copy_from(&m.gu);
            for i in 0..N {
                self.qp.u_lower[k][i] = -self.config.tau_max - self.us[k][i];
                self.qp.u_upper[k][i] = self.config.tau_max - self.us[k][i];
            }
        }
        let scale = dt * self.config.terminal_scale;
        if scale > 0.0 {
            let m = stage_model::<S, N, NX>(
                &self.system,
                &self.reference,
                &cost,
                &self.xs[nh],
                &Vector::zeros(),
                scale,
            );
            self.qp.q[nh].copy_from(&m.q);
            self.qp.q_lin[nh].copy_from(&m.gz);
        } else {
            self.qp.q[nh].fill(0.0);
            self.qp.q_lin[nh].fill(0.0);
        }
        for k in 1..=nh {
            for i in 0..N {
                let x = &self.xs[k];
                self.qp.x_lower[k][i] = q_eq[i] - self.config.q_max - x[i];
                self.qp.x_upper[k][i] = q_eq[i] + self.config.q_max - x[i];
                self.qp.x_lower[k][N + i] = -self.config.qd_max - x[N + i];
                self.qp.x_upper[k][N + i] = self.config.qd_max - x[N + i];
            }
        }
    }

    fn set_initial_state(&mut self, z: &SVector<f64, NX>) {
        self.qp.x0.copy_from(&(z - self.xs[0]));
    }

    fn apply_step(&mut self, alpha: f64) {
        for (k, x) in self.xs.iter_mut().enumerate() {
            for i in 0..NX {
                *x.index_mut(i) += alpha * self.solution.x[k][i];
            }
        }
        for (k, u) in self.us.iter_mut().enumerate() {
            for i in 0..N {
                u[i] += alpha * self.solution.u[k][i];
            }
        }
    }

    /// Objective plus soft-bound penalty plus `penalty` times the L1 norm of
    /// the constraint violations (initial state and continuity).
    fn merit(
        &self,
        xs: &[SVector<f64, NX>],
        us: &[Vector<N>],
        z: &SVector<f64, NX>,
        penalty: f64,
    ) -> f64 {
        let nh = self.config.horizon;
        let cost = &self.config.cost;
        let dt = self.config.dt;
        let mut objective = 0.0;
        let mut violation = (z - xs[0]).lp_norm(1);
        for k in 0..nh {
            objective +=
                stage_cost::<S, N, NX>(&self.system, &self.reference, cost, &xs[k], &us[k], dt);
            violation += (self.simulate_interval(&xs[k], &us[k]) - xs[k + 1]).lp_norm(1);
        }
        if self.config.terminal_scale > 0.0 {
            objective += stage_cost::<S, N, NX>(
                &self.system,
                &self.reference,
                cost,
                &xs[nh],
                &Vector::zeros(),
                dt * self.config.terminal_scale,
            );
        }
        objective + self.soft_penalty(xs) + penalty * violation
    }

    fn soft_penalty(&self, xs: &[SVector<f64, NX>]) -> f64 {
        if self.config.q_max.is_infinite() && self.config.qd_max.is_infinite() {
            return 0.0;
        }
        let q_eq = self.system.equilibrium();
        let mut p = 0.0;
        for x in &xs[1..] {
            for i in 0..NX {
                let (centre, bound) = if i < N {
                    (q_eq[i], self.config.q_max)
                } else {
                    (0.0, self.config.qd_max)
                };
                let v = ((x[i] - centre).abs() - bound).max(0.0);
                p += self.config.soft_l1 * v + 0.5 * self.config.soft_l2 * v * v;
            }
        }
        p
    }

    /// Backtracking on the L1 merit along the QP step; applies the accepted
    /// step and returns (step infinity norm, accepted step length), the
    /// length 0 when no tested length decreased the merit (nothing applied).
    fn line_search(&mut self, z: &SVector<f64, NX>) -> (f64, f64) {
        let nh = self.config.horizon;
        let mut max_pi: f64 = 0.0;
        for pi in &self.solution.pi {
            max_pi = max_pi.max(pi.amax());
        }
        // The multiplier of the initial-state constraint, from stationarity at x_0.
        let (qp, sol) = (&self.qp, &self.solution);
        for i in 0..NX {
            let mut lam = qp.q_lin[0][i];
            for j in 0..NX {
                lam += qp.q[0][(i, j)] * sol.x[0][j] + qp.a[0][(j, i)] * sol.pi[0][j];
            }
            for j in 0..N {
                lam += qp.s[0][(j, i)] * sol.u[0][j];
            }
            max_pi = max_pi.max(lam.abs());
        }
        self.merit_penalty = self.merit_penalty.max(1.5 * max_pi + 1e-3);
        let mu = self.merit_penalty;

        let mut step_norm: f64 = 0.0;
        let mut slope = 0.0;
        let mut violation = self.qp.x0.lp_norm(1);
        for k in 0..nh {
            step_norm = step_norm
                .max(self.solution.x[k].amax())
                .max(self.solution.u[k].amax());
            slope += self.qp.q_lin[k].dot(&self.solution.x[k])
                + self.qp.r_lin[k].dot(&self.solution.u[k]);
            violation += self.qp.c[k].lp_norm(1);
        }
        step_norm = step_norm.max(self.solution.x[nh].amax());
        slope += self.qp.q_lin[nh].dot(&self.solution.x[nh]);
        let slope = slope - mu * violation;

        let base = self.merit(&self.xs, &self.us, z, mu);
        let mut alpha = 1.0;
        let mut accepted = false;
        while alpha > 1e-4 {
            for k in 0..=nh {
                let mut x = self.xs[k];
                for i in 0..NX {
                    x[i] += alpha * self.solution.x[k][i];
                }
                self.xs_trial[k] = x;
                if k < nh {
                    let mut u = self.us[k];
                    for i in 0..N {
                        u[i] += alpha * self.solution.u[k][i];
                    }
                    self.us_trial[k] = u;
                }
            }
            let trial = self.merit(&self.xs_trial, &self.us_trial, z, mu);
            // Armijo on the merit, with room for round-off in its evaluation
            // (near the solution the decrease is below the noise).
            let noise = 1e-12 * base.abs().max(1.0);
            if trial <= base + 1e-4 * alpha * slope.min(0.0) + noise || step_norm < 1e-12 {
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if !accepted {
            return (step_norm, 0.0);
        }
        self.apply_step(alpha);
        (step_norm, alpha)
    }

    /// Energy of a state under the controller's model.
    pub fn energy(&self, z: &SVector<f64, NX>) -> f64 {
        state_energy::<S, N, NX>(&self.system, z)
    }
}
