//! The EigenMPC controller: multiple-shooting NMPC of the straight or curved
//! EigenMPC cost (paper, section IV), solved by real-time iterations (RTI,
//! Diehl) with a Gauss-Newton Hessian.
//!
//! Each sample is split as in acados/MATMPC:
//! - **preparation** ([`Controller::prepare`]): shift the previous solution by
//!   one interval, integrate every shooting interval with RK4 and exact
//!   sensitivities, evaluate the residual Jacobians and write the QP in the
//!   step variables `(dx_k, du_k)`;
//! - **feedback** ([`Controller::feedback`]): embed the measured state
//!   (predicted over a declared measurement delay and actuator lag, a few
//!   RK4 steps, `src/mpc/delay.rs`) as `dx_0 = z - x_0`, solve the QP,
//!   take the full step and return `tau_0`.
//!
//! Optionally several iterations per sample. The first sample starts from a
//! zero-torque guess and takes ten full Gauss-Newton iterations
//! ([`Startup`]): bounded work, where the converged SQP with an L1-merit
//! backtracking line search ([`Controller::solve_to_convergence`],
//! `Startup::Converge`) took 90-180 ms on robots with Coulomb friction.
//! Everything is sized at creation; the per-sample path does not allocate.

#[cfg(feature = "tooling")]
pub mod closed_loop;
mod config;
pub mod cost;
mod delay;
mod estimator;
mod linearise;
pub use linearise::SPEED_REACH;
pub mod prediction;
mod response;
mod saved;
mod sqp;
mod status;
mod supervisor;

pub use config::{
    MAX_COMPENSATED_TIME, MAX_HORIZON, MAX_STARTUP_ITERATIONS, MpcConfig, MpcError, SqpOptions,
    Startup,
};
pub use cost::{
    CostParams, CostVariant, Guide, PAPER_ENERGY_SCALE, Reference, ReferenceError, VARIANTS,
    Variant, VariantInfo, Weights,
};
pub use estimator::EstimatorConfig;
pub(crate) use estimator::held_acceleration_noise;
pub use prediction::{
    FrictionSmoothing, PREDICTION_SUBSTEPS, prediction_coulomb_sharpness, prediction_model,
    prediction_substeps,
};
pub use saved::ControllerState;
pub use status::{ControlOutput, ControlStatus};
pub use supervisor::SupervisorOptions;

use crate::mechanics::{MechanicalSystem, Vector, state_energy};
use crate::modes::ChartFamily;
pub use crate::qp::QpBackend;
use crate::qp::{AnyStageQp, OcpQp, QpSolution, QpSolver, StageQp};
use config::validate_cost;
use nalgebra::SVector;
use std::time::Instant;

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
    /// The QP of the current linearisation, stage by stage (what the
    /// linearisation writes and the Riccati solver reads).
    stages: StageQp<NX, N>,
    /// The same QP for a solver without a typed path (clarabel, the
    /// run-time-sized Riccati core): converted into this at each solve.
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
    /// RK4 substeps of the last linearisation, over all intervals.
    substeps_taken: usize,
    /// The model's steepest friction slope, every joint at rest (the
    /// substeps' reference: [`Self::interval_substeps`]); set with the model.
    steepest_friction_slope: f64,
    /// Preparation time already spent for the coming sample.
    pending_preparation_time: f64,
    /// The last sample's QP solution may seed the next one (warm start).
    warm_start_usable: bool,
    /// QP failures in a row; the plan is rebuilt after [`MAX_QP_FAILURES`].
    consecutive_qp_failures: usize,
    /// The eigenmanifold the curved chart follows `E_ref` on (None: fixed chart).
    family: Option<ChartFamily<N>>,
    /// State estimator (None: the measured state is used as it is).
    estimator: Option<estimator::Ekf<N, NX>>,
    /// Torques returned by the past feedbacks (the last one is applied
    /// over the last sample), for the measurement delay, the actuator lag
    /// and the estimator's propagation ([`delay`]).
    history: delay::CommandHistory<N>,
    /// The state the last feedback embedded as the plan's start (the
    /// measurement, filtered and predicted over delay and lag).
    embedded: Option<SVector<f64, NX>>,
    /// The stall supervisor ([`supervisor`]).
    supervisor: supervisor::Supervisor<N>,
    /// Torque added to every solved command ([`Controller::set_excitation`]).
    excitation: Vector<N>,
}

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
        let mut stages = StageQp::<NX, N>::new(nh);
        for st in &mut stages.stages[..nh] {
            st.u_lower.fill(-config.tau_max);
            st.u_upper.fill(config.tau_max);
        }
        stages.soft_l1.fill(config.soft_l1);
        stages.soft_l2.fill(config.soft_l2);
        let mut qp = OcpQp::new(NX, N, nh);
        stages.write_ocp(&mut qp);
        let steepest_friction_slope = linearise::steepest_friction_slope(&system);
        Ok(Self {
            system,
            config,
            reference,
            xs: vec![SVector::zeros(); nh + 1],
            us: vec![Vector::zeros(); nh],
            xs_trial: vec![SVector::zeros(); nh + 1],
            us_trial: vec![Vector::zeros(); nh],
            stages,
            qp,
            solution: QpSolution::new(NX, N, nh),
            solver,
            initialised: false,
            prepared: false,
            shift_pending: false,
            merit_penalty: 1.0,
            substeps_taken: 0,
            steepest_friction_slope,
            pending_preparation_time: 0.0,
            warm_start_usable: false,
            consecutive_qp_failures: 0,
            family: None,
            estimator: config.estimator.map(|e| estimator::Ekf::new(&e, config.dt)),
            history: delay::CommandHistory::new(delay::history_length(
                config.measurement_delay,
                config.actuator_time_constant,
                config.dt,
            )),
            embedded: None,
            supervisor: supervisor::Supervisor::new(),
            excitation: Vector::zeros(),
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
        Self::with_family_as(system, config, family, Variant::Curved)
    }

    /// [`Controller::with_family`] for a chart variant (curved or hybrid).
    pub fn with_family_as(
        system: S,
        config: MpcConfig,
        family: ChartFamily<N>,
        variant: Variant,
    ) -> Result<Self, MpcError> {
        config.validate()?;
        if !variant.uses_chart() {
            return Err(MpcError::InvalidReference(format!(
                "a chart family needs a chart variant (curved, hybrid), not {variant}"
            )));
        }
        let reference = Reference::with_chart(variant, family.chart(config.cost.e_ref));
        let mut controller = Self::new(system, config, reference)?;
        controller.family = Some(family);
        Ok(controller)
    }

    /// Replaces the controller's model (an identified one, say) and, for a
    /// controller on a mode family, the family computed for it (its chart
    /// degree may differ, up to what the controller's chart has room for:
    /// [`crate::modes::MAX_FAMILY_DEGREE`] for a controller made
    /// [`Controller::with_family`]); the plan is kept as the warm start.
    /// Returns the old family, so that the caller can drop it outside a
    /// real-time path; nothing is allocated here.
    pub fn replace_model(
        &mut self,
        system: S,
        family: Option<ChartFamily<N>>,
    ) -> Result<Option<ChartFamily<N>>, MpcError> {
        match (&family, self.reference.chart()) {
            (Some(f), Some(chart))
                if chart
                    .coefficients
                    .iter()
                    .any(|c| c.capacity() <= f.degree()) =>
            {
                return Err(MpcError::InvalidReference(format!(
                    "the new family's charts have degree {}, more than the controller's chart \
                     (degree {}) has room for",
                    f.degree(),
                    chart.degree
                )));
            }
            (Some(_), None) => {
                return Err(MpcError::InvalidReference(
                    "a family needs a chart variant (curved, hybrid)".into(),
                ));
            }
            (None, _) if self.family.is_some() => {
                return Err(MpcError::InvalidReference(
                    "a controller on a mode family needs the new model's family".into(),
                ));
            }
            _ => {}
        }
        self.set_system(system);
        let old = std::mem::replace(&mut self.family, family);
        if let (Some(f), Some(chart)) = (&self.family, self.reference.chart_mut()) {
            f.write_chart(self.config.cost.e_ref, chart);
        }
        self.prepared = false;
        Ok(old)
    }

    /// The model, with what the per-sample path derives from it once (the
    /// steepest friction slope the substeps are chosen against): every
    /// change of the model goes through here.
    fn set_system(&mut self, system: S) {
        self.steepest_friction_slope = linearise::steepest_friction_slope(&system);
        self.system = system;
    }

    /// Sets the RK4 substeps per shooting interval (a new model with other
    /// friction may need others: [`prediction_substeps`]); the next
    /// preparation uses them. Allocation-free.
    pub fn set_substeps(&mut self, substeps: usize) -> Result<(), MpcError> {
        let mut config = self.config;
        config.substeps = substeps;
        config.validate()?;
        self.config.substeps = substeps;
        self.prepared = false;
        Ok(())
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

    /// The last QP and its solution (diagnostics, tests; the QP converted
    /// from the stage-wise form, which allocates).
    pub fn last_qp(&self) -> (OcpQp, &QpSolution) {
        (self.stages.to_ocp(), &self.solution)
    }

    /// The last QP as the controller holds it, stage by stage.
    pub fn last_stage_qp(&self) -> &StageQp<NX, N> {
        &self.stages
    }

    /// RK4 substeps the last linearisation took over all `N` intervals
    /// (`N` times `substeps` without `substeps_where_stiff`; benchmarks).
    pub fn last_linearisation_substeps(&self) -> usize {
        self.substeps_taken
    }

    /// Whether the QP solver's start (riccati: the active-set start)
    /// solved the last QP without its main method; `None` for a solver
    /// without one (benchmarks).
    pub fn last_qp_solved_by_start(&self) -> Option<bool> {
        self.solver.last_solved_by_start()
    }

    /// Sets all tunable cost parameters at once (no rebuild, no allocation).
    pub fn set_cost(&mut self, cost: CostParams) -> Result<(), MpcError> {
        validate_cost(&cost)?;
        if let (Some(family), Some(chart)) = (&self.family, self.reference.chart_mut())
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
        if let Some(ekf) = &mut self.estimator {
            ekf.reset();
        }
    }

    /// The state estimate of the last sample (None without an estimator
    /// or before the first sample): the filtered state **at the time the
    /// measurement was taken**, `measurement_delay` before the sample.
    /// That is what an identification pairs with the torque acting then
    /// ([`Controller::torque_before_measurement`]); the state the plan
    /// started from is [`Controller::predicted_current_state`].
    pub fn state_estimate(&self) -> Option<&SVector<f64, NX>> {
        self.estimator.as_ref().and_then(|e| e.estimate())
    }

    /// The state the last feedback started its plan from (None before the
    /// first sample): the measurement (filtered, with the estimator)
    /// predicted forward over `measurement_delay` to the sample time and,
    /// with an actuator lag, over `actuator_time_constant` more (see
    /// [`MpcConfig::actuator_time_constant`]). Without either it is the
    /// (filtered) measurement.
    pub fn predicted_current_state(&self) -> Option<&SVector<f64, NX>> {
        self.embedded.as_ref()
    }

    /// Propagates the state estimate over the sample before the coming
    /// measurement with the torque that acted then (once per sample; part
    /// of the preparation).
    fn predict_estimate(&mut self) {
        let Some(ekf) = &self.estimator else { return };
        if !ekf.needs_prediction() {
            return;
        }
        let from = *ekf.estimate().expect("started");
        let (next, a) = self.propagate_delayed(&from);
        if let Some(ekf) = &mut self.estimator {
            ekf.predict(&next, &a);
        }
    }

    /// Adds `torque` (N m) to every solved command from the next one on
    /// (clipped to `tau_max`), as the motor applies it: the estimator,
    /// the delay compensation and [`Controller::torque_before_measurement`]
    /// know it. The adaptation's excitation: a torque the loop does not
    /// make from its own state, so that the identification can tell the
    /// model's scale from its friction (under feedback alone the torque is
    /// a function of the state).
    pub fn set_excitation(&mut self, torque: &Vector<N>) {
        self.excitation = torque.map(|v| if v.is_finite() { v } else { 0.0 });
    }

    /// The torque added to every solved command (N m).
    pub fn excitation(&self) -> &Vector<N> {
        &self.excitation
    }

    /// One control step: preparation (unless already done) and feedback.
    pub fn step(&mut self, z: &SVector<f64, NX>) -> ControlOutput<N> {
        self.prepare();
        self.feedback(z)
    }

    /// Preparation phase: shift the previous plan and linearise around it.
    /// Call between samples (before the measurement arrives) to cut latency.
    pub fn prepare(&mut self) {
        let start = Instant::now();
        self.predict_estimate();
        if !self.initialised {
            self.pending_preparation_time += start.elapsed().as_secs_f64();
            return;
        }
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
        let measured = z.iter().all(|v| v.is_finite());
        // The supervisor judges motion on the measurement itself: an
        // estimator filtering with a wrong model sees the robot move where
        // the model says the torque moves it, while it rests (a stall under
        // the EKF went unnoticed that way).
        let raw = *z;
        // A prediction not made in `prepare` (feedback called alone) is made here.
        self.predict_estimate();
        let estimate;
        let z = match &mut self.estimator {
            Some(ekf) if measured => {
                estimate = ekf.update(z);
                &estimate
            }
            Some(ekf) => {
                ekf.skip_update();
                z
            }
            None => z,
        };
        // The plan starts where the command takes effect: the measured
        // (filtered) state predicted over delay and lag; a diverged
        // prediction falls back to the measurement.
        let predicted;
        let z = if measured && self.compensates() {
            let p = self.predict_measured(z);
            predicted = if p.iter().all(|v| v.is_finite()) {
                p
            } else {
                *z
            };
            &predicted
        } else {
            z
        };
        if measured {
            self.embedded = Some(*z);
        }
        let preparation_time = std::mem::take(&mut self.pending_preparation_time);
        // A release after a stall commands zero torque without solving (the
        // plan was dropped; the estimator keeps following the measurements).
        let releasing = measured && self.supervisor.release_sample();
        let mut out = if releasing {
            self.released()
        } else if !measured {
            self.fallback(ControlStatus::InvalidState)
        } else if !self.initialised {
            self.initialise(z);
            match self.config.startup {
                Startup::Iterations(n) => self.iterate(z, n),
                Startup::Converge => self.solve_to_convergence(z),
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
            ControlStatus::InvalidState | ControlStatus::Released => {}
        }
        if measured && !releasing {
            self.supervise(&raw, &mut out);
        }
        if out.status.is_ok() && self.excitation.iter().any(|v| *v != 0.0) {
            out.tau = self.clip(&(out.tau + self.excitation));
        }
        // The plan's first control is the torque to apply; with a declared
        // motor response the command is the one that makes the motor apply
        // it, and the history keeps what the motor applies ([`response`]).
        let (command, applied) = response::command(
            self.config.torque_response,
            self.config.tau_max,
            &self.history.entry(1).0,
            &out.tau,
        );
        out.tau = command;
        let decay = self.lag_decay();
        self.history.push(&applied, decay);
        out.preparation_time = preparation_time;
        out.feedback_time = start.elapsed().as_secs_f64();
        out
    }

    /// `iterations` full-step Gauss-Newton iterations at `z` (RTI for 1).
    fn iterate(&mut self, z: &SVector<f64, NX>, iterations: usize) -> ControlOutput<N> {
        let mut qp_iterations = 0;
        for _ in 0..iterations {
            if !self.prepared {
                self.linearise();
            }
            self.set_initial_state(z);
            let status = self.solve_qp();
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

    /// Zero torque: the supervisor's release after a stall.
    fn released(&self) -> ControlOutput<N> {
        ControlOutput {
            tau: Vector::zeros(),
            status: ControlStatus::Released,
            qp_iterations: 0,
            sqp_iterations: 0,
            preparation_time: 0.0,
            feedback_time: 0.0,
        }
    }

    /// The stall supervisor's look at this sample (the measured state,
    /// not the estimate, and the torque about to be sent); on a stall the plan
    /// and the state estimate are dropped and the torque released.
    fn supervise(&mut self, z: &SVector<f64, NX>, out: &mut ControlOutput<N>) {
        let e_ref = self.config.cost.e_ref;
        let energy_error = self.energy(z) - e_ref;
        let verdict = self.supervisor.observe(
            &self.config.supervisor,
            self.config.dt,
            z,
            energy_error,
            e_ref,
            &out.tau,
            self.config.tau_max,
        );
        if verdict == supervisor::Verdict::Stall {
            self.reset();
            *out = ControlOutput {
                preparation_time: out.preparation_time,
                feedback_time: out.feedback_time,
                ..self.released()
            };
            // This sample is the release's first.
            self.supervisor.release_sample();
        }
    }

    /// The torque the motor applies over the sample since the last
    /// feedback, as the controller expects it: the last command, or with a
    /// declared [`MpcConfig::torque_response`] the motor's response to it
    /// (with an [`MpcConfig::actuator_time_constant`] the command, which
    /// the lag follows).
    pub fn applied_torque(&self) -> Vector<N> {
        self.history.entry(1).0
    }

    /// Stalls the supervisor called so far (a torque held at its bound
    /// without motion, off the target energy; each one released the
    /// torque and dropped the plan and the state estimate).
    pub fn supervisor_events(&self) -> usize {
        self.supervisor.events()
    }

    /// Whether the supervisor is releasing the torque after a stall.
    pub fn supervisor_releasing(&self) -> bool {
        self.supervisor.releasing()
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

    fn set_initial_state(&mut self, z: &SVector<f64, NX>) {
        self.stages.x0 = z - self.xs[0];
    }

    /// Solves the linearisation's QP into `solution`.
    fn solve_qp(&mut self) -> crate::qp::QpStatus {
        self.solver
            .solve_stages(&self.stages, &mut self.qp, &mut self.solution)
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

    /// Energy of a state under the controller's model.
    pub fn energy(&self, z: &SVector<f64, NX>) -> f64 {
        state_energy::<S, N, NX>(&self.system, z)
    }
}
