//! The EigenMPC controller (paper, section IV; `eigenmpc::mpc::Controller`)
//! for an `N`-joint planar chain as an FMI 2.0 Co-Simulation model.
//!
//! - [`table`]: the variable table (value references, start values, ...);
//! - [`settings`]: the controller definition the table fills in;
//! - [`timing`]: the sample grid (when to solve);
//! - [`docs`]: the documentation page's introduction;
//! - [`start_values`]: the start values of a given robot and reference;
//! - [`precomputed`]: a mode family computed ahead (an exported robot's).
//!
//! Timing: the controller solves at the communication points that fall on
//! its sample grid `t_start + k * sample_period` (or, when a grid point falls
//! inside a communication step, at the first communication point after it).
//! A solve at `t` uses the inputs set for `t` (before `fmi2DoStep(t, h)`, or
//! in initialization mode for `t_start`); its torque is the output once that
//! call returns (`fmi2ExitInitializationMode` for the first solve) and is
//! held until the next solve.

pub mod adaptive;
pub mod docs;
pub mod named;
pub mod precomputed;
pub mod settings;
pub mod start_values;
pub mod table;
pub mod timing;

use crate::enums::ADAPTATION_STATUS;
use crate::units;
use adaptive::AdaptiveController;
use eigenmpc::adapt::AdaptationEvent;
use eigenmpc::mpc::{ControlOutput, ControlStatus, FrictionSmoothing, MpcConfig, Variant};
use fmi2_slave::table::{Element, Table};
use fmi2_slave::{Context, DefaultExperiment, Model, ModelDescription, ModelError, Values};
use nalgebra::SVector;
use settings::{CHART_COEFFICIENTS, ChainController, ChartSource, Settings, chart_clamp_warning};
use std::marker::PhantomData;
use timing::{SampleClock, Tick};

/// One controller FMU product: its name and default reference (the
/// in-phase eigenmode of the default model at `E_REF`).
pub trait ControllerProduct<const N: usize>: 'static {
    /// `modelName` and `modelIdentifier`.
    const MODEL_NAME: &'static str;
    /// One-line description.
    const DESCRIPTION: &'static str;
    /// Default `E_ref` (J): the energy of the default chart.
    const E_REF: f64;
    /// Default eigenvector: the in-phase linear mode of the default model.
    const EIGENVECTOR: [f64; N];
    /// Default chart: the in-phase eigenmode of the default model at `E_REF`.
    const CHART: [[f64; CHART_COEFFICIENTS]; N];

    /// The paper's settings for `variant` with the default reference.
    fn settings(variant: Variant) -> Settings<N> {
        Settings::paper(variant, Self::E_REF, Self::EIGENVECTOR, Self::CHART)
    }
}

/// Unsuccessful solves between two logged ones.
pub const FAILURE_LOG_EVERY: usize = 100;

/// Value references the sample path reads and writes.
#[derive(Clone, Debug)]
struct Io<const N: usize> {
    q: [u32; N],
    qd: [u32; N],
    tau: [u32; N],
    energy: u32,
    solve_time: u32,
    qp_iterations: u32,
    solver_status: u32,
    chart_energy: [u32; 3],
    /// The base-parameter outputs, in the estimate's order (`NP`).
    estimate: Vec<u32>,
    model_updates: u32,
    adapt_refused: u32,
    adapt_reverts: u32,
    adaptation_status: u32,
    supervisor_events: u32,
}

impl<const N: usize> Io<N> {
    fn new(t: &Table<Settings<N>>) -> Result<Self, String> {
        let mut estimate = vec![];
        for name in table::ESTIMATE_ROWS {
            let i = t.row_index(name).ok_or_else(|| format!("no row {name}"))?;
            for e in t.rows[i].shape.elements(N) {
                estimate.push(t.vr_at(i, e));
            }
        }
        let joints = |name| {
            t.joint_vrs::<N>(name)
                .ok_or_else(|| format!("no row {name}"))
        };
        let scalar = |name| {
            t.vr(name, Element::default())
                .ok_or_else(|| format!("no row {name}"))
        };
        Ok(Self {
            q: joints("q")?,
            qd: joints("qd")?,
            tau: joints("tau")?,
            energy: scalar("energy")?,
            solve_time: scalar("solve_time")?,
            qp_iterations: scalar("qp_iterations")?,
            solver_status: scalar("solver_status")?,
            chart_energy: [
                scalar("chart_energy")?,
                scalar("chart_energy_min")?,
                scalar("chart_energy_max")?,
            ],
            estimate,
            model_updates: scalar("model_updates")?,
            adapt_refused: scalar("adapt_refused")?,
            adapt_reverts: scalar("adapt_reverts")?,
            adaptation_status: scalar("adaptation_status")?,
            supervisor_events: scalar("supervisor_events")?,
        })
    }
}

/// The EigenMPC controller FMU model for `N` joints (`NX = 2 N`, `NP` =
/// [`eigenmpc::identify::base_parameter_count`]`(N)` base parameters).
pub struct ControllerFmu<P, const N: usize, const NX: usize, const NP: usize, const NA: usize> {
    controller: AdaptiveController<N, NX, NP, NA>,
    /// Time of the last solve (the adaptation's sample interval).
    solved_at: f64,
    /// Model updates already reported.
    updates_reported: usize,
    /// Adaptation events already logged, and the refusal reasons logged
    /// (each once; later ones are counted in `adapt_refused`).
    events_logged: usize,
    refusals_logged: [bool; 3],
    /// Stalls of the supervisor already logged.
    stalls_logged: usize,
    /// Solves that did not succeed (logged: the first and every
    /// [`FAILURE_LOG_EVERY`]-th).
    failed_solves: usize,
    settings: Settings<N>,
    table: Table<Settings<N>>,
    io: Io<N>,
    clock: SampleClock,
    /// State of the last solve (a changed state at `t_start` re-solves).
    solved_state: SVector<f64, NX>,
    product: PhantomData<fn() -> P>,
}

/// What [`ControllerFmu`] saves as its FMU state (the settings and the
/// table follow from the values).
#[derive(serde::Serialize, serde::Deserialize)]
struct SavedController<const N: usize, const NX: usize, const NP: usize> {
    controller: adaptive::AdaptiveState<N, NX, NP>,
    solved_at: f64,
    updates_reported: usize,
    events_logged: usize,
    refusals_logged: [bool; 3],
    stalls_logged: usize,
    failed_solves: usize,
    clock: SampleClock,
    solved_state: SVector<f64, NX>,
}

/// The model description of product `P`.
pub fn description<P: ControllerProduct<N>, const N: usize>() -> ModelDescription {
    description_with(P::MODEL_NAME, P::DESCRIPTION, &P::settings(Variant::Curved))
}

/// The model description of an `N`-joint controller FMU called `name`
/// whose start values are `defaults` (a product's, or an exported robot's).
pub fn description_with<const N: usize>(
    name: &str,
    text: &str,
    defaults: &Settings<N>,
) -> ModelDescription {
    let t = table::table::<N>();
    let variables = t.variables(defaults);
    ModelDescription {
        model_name: name.into(),
        model_identifier: name.into(),
        description: text.into(),
        version: env!("CARGO_PKG_VERSION").into(),
        author: "EigenMPC project".into(),
        generation_tool: format!("fmi2-slave (EigenMPC) {}", env!("CARGO_PKG_VERSION")),
        can_handle_variable_communication_step_size: true,
        can_save_state: true,
        default_experiment: Some(DefaultExperiment {
            start_time: 0.0,
            stop_time: 30.0,
            step_size: MpcConfig::paper(Variant::Curved).dt,
            // No integrator: a master's tolerance does not apply.
            tolerance: None,
        }),
        units: units::used_by(&variables),
        enumerations: t.enumerations(),
        variables,
    }
}

impl<
    P: ControllerProduct<N> + Send,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NA: usize,
> ControllerFmu<P, N, NX, NP, NA>
{
    /// `fmi2ExitInitializationMode` with `defaults` under the values (an
    /// exported robot's start values; the product's otherwise) and a mode
    /// family computed ahead, taken when it is the one the settings would
    /// compute (the log says which).
    pub fn initialize_with(
        values: &mut Values,
        ctx: &Context,
        defaults: Settings<N>,
        precomputed: Option<&precomputed::PrecomputedFamily<N>>,
    ) -> Result<Self, ModelError> {
        let table = table::table::<N>();
        let io = Io::new(&table).map_err(ModelError::Error)?;
        if io.estimate.len() != NP {
            return Err(ModelError::Error(format!(
                "{} base-parameter outputs for NP = {NP}",
                io.estimate.len()
            )));
        }
        let mut settings = defaults.clone();
        table.read(values, &mut settings, |_| true);
        if settings.chart_source == ChartSource::Computed
            && (settings.eigenvector != defaults.eigenvector || settings.chart != defaults.chart)
        {
            ctx.log.notice(
                "c[j] / chart.coef[j,k] were set but are not used: chart_source = computed \
                 takes the reference from the model; set chart_source = parameters to use them",
            );
        }
        let (controller, refused) =
            AdaptiveController::with_family(&settings, precomputed).map_err(ModelError::Error)?;
        match (precomputed, refused) {
            (Some(_), None) if controller.controller().family().is_some() => ctx
                .log
                .event("mode family: the one computed at export (resources/), not recomputed"),
            (Some(_), Some(why)) => ctx.log.notice(&format!(
                "mode family: computed now, not the exported one: {why}"
            )),
            _ => {}
        }
        // The prediction model's smoothed Coulomb law, and its error bound.
        let predicted = controller.controller().system().params().coulomb_sharpness;
        if let Ok(robot) = settings.system() {
            let smoothing = FrictionSmoothing::new(robot.params().coulomb_sharpness, predicted);
            if smoothing.largest > 0.0 {
                ctx.log.event(&format!(
                    "prediction model: {} RK4 substeps, {}",
                    controller.controller().config().substeps,
                    smoothing.describe()
                ));
            }
        }
        let mut model = Self {
            controller,
            solved_at: ctx.experiment.start_time,
            updates_reported: 0,
            events_logged: 0,
            refusals_logged: [false; 3],
            stalls_logged: 0,
            failed_solves: 0,
            clock: SampleClock::new(ctx.experiment.start_time, settings.sample_period),
            settings,
            table,
            io,
            solved_state: SVector::zeros(),
            product: PhantomData,
        };
        model.report_chart(values, ctx);
        model.solve(values, ctx.experiment.start_time, ctx);
        Ok(model)
    }
}

impl<
    P: ControllerProduct<N> + Send,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NA: usize,
> Model for ControllerFmu<P, N, NX, NP, NA>
{
    fn description() -> ModelDescription {
        description::<P, N>()
    }

    fn initialize(values: &mut Values, ctx: &Context) -> Result<Self, ModelError> {
        Self::initialize_with(values, ctx, P::settings(Variant::Curved), None)
    }

    fn do_step(
        &mut self,
        values: &mut Values,
        t: f64,
        h: f64,
        ctx: &Context,
    ) -> Result<(), ModelError> {
        match self.clock.step(t, h, ctx.log) {
            Tick::Solve => self.solve(values, t, ctx),
            Tick::AtStart if self.inputs(values) != self.solved_state => {
                // New inputs for t_start after initialization: solve t_start again.
                self.controller.reset();
                self.solve(values, t, ctx);
            }
            Tick::AtStart | Tick::Hold => {}
        }
        Ok(())
    }

    fn save_state(&self) -> Result<Vec<u8>, ModelError> {
        fmi2_slave::state::encode_model(&SavedController {
            controller: self.controller.save_state(),
            solved_at: self.solved_at,
            updates_reported: self.updates_reported,
            events_logged: self.events_logged,
            refusals_logged: self.refusals_logged,
            stalls_logged: self.stalls_logged,
            failed_solves: self.failed_solves,
            clock: self.clock.clone(),
            solved_state: self.solved_state,
        })
    }

    fn restore_state(
        &mut self,
        state: &[u8],
        values: &Values,
        _ctx: &Context,
    ) -> Result<(), ModelError> {
        let saved: SavedController<N, NX, NP> = fmi2_slave::state::decode_model(state)?;
        if !(saved.solved_at.is_finite() && saved.solved_state.iter().all(|v| v.is_finite())) {
            return Err(ModelError::Error(
                "malformed controller state: non-finite time or state".into(),
            ));
        }
        // The tuning the controller was last given is in the values.
        let mut settings = self.settings.clone();
        self.table.read(values, &mut settings, |r| r.is_tunable());
        self.controller
            .restore_state(saved.controller)
            .map_err(|e| ModelError::Error(format!("malformed controller state: {e}")))?;
        self.settings = settings;
        self.solved_at = saved.solved_at;
        self.updates_reported = saved.updates_reported;
        self.events_logged = saved.events_logged;
        self.refusals_logged = saved.refusals_logged;
        self.stalls_logged = saved.stalls_logged;
        self.failed_solves = saved.failed_solves;
        self.clock = saved.clock;
        self.solved_state = saved.solved_state;
        Ok(())
    }

    fn update_tunables(&mut self, values: &mut Values, ctx: &Context) -> Result<(), ModelError> {
        let mut settings = self.settings.clone();
        self.table.read(values, &mut settings, |r| r.is_tunable());
        self.controller
            .controller_mut()
            .set_cost(settings.tuning.cost(settings.variant))
            .map_err(|e| ModelError::Error(e.to_string()))?;
        let moved = settings.tuning.e_ref != self.settings.tuning.e_ref;
        self.settings = settings;
        if moved {
            self.report_chart(values, ctx);
        }
        Ok(())
    }
}

impl<P, const N: usize, const NX: usize, const NP: usize, const NA: usize>
    ControllerFmu<P, N, NX, NP, NA>
{
    fn inputs(&self, values: &Values) -> SVector<f64, NX> {
        SVector::from_fn(|i, _| {
            if i < N {
                values.real(self.io.q[i])
            } else {
                values.real(self.io.qd[i - N])
            }
        })
    }

    /// Writes the chart-energy outputs and warns when `E_ref` is clamped to
    /// the computed family's range (set-up and tuning only: may allocate).
    fn report_chart(&self, values: &mut Values, ctx: &Context) {
        self.write_chart_energies(values);
        if let Some(warning) = chart_clamp_warning(self.controller.controller()) {
            ctx.log.notice(&warning);
        }
    }

    /// The chart-energy outputs (allocation-free).
    fn write_chart_energies(&self, values: &mut Values) {
        let controller = self.controller.controller();
        let range = controller.family().map(|f| f.energy_range());
        let (lo, hi) = range.unwrap_or((0.0, 0.0));
        let used = controller.chart_energy().unwrap_or(0.0);
        for (vr, v) in self.io.chart_energy.iter().zip([used, lo, hi]) {
            values.set_real(*vr, v);
        }
    }

    /// One controller sample with the current inputs; writes the outputs.
    fn solve(&mut self, values: &mut Values, t: f64, ctx: &Context) {
        let z = self.inputs(values);
        // On the grid the interval is the sample period (t carries the
        // master's rounding); the first solve has no previous sample, and
        // one period is a harmless stand-in (the identification only
        // starts its window there).
        let period = self.settings.sample_period;
        let elapsed = t - self.solved_at;
        let dt = if elapsed <= 0.0 || (elapsed - period).abs() < 1e-6 * period {
            period
        } else {
            elapsed
        };
        let out = self.controller.step(&z, dt);
        self.solved_at = t;
        self.solved_state = z;
        // A release is the supervisor's doing, logged as a stall below.
        if !out.status.is_ok() && out.status != ControlStatus::Released {
            self.failed_solves += 1;
            // A state no bounded torque recovers from can fail most
            // samples: log the first and then every FAILURE_LOG_EVERY-th
            // (failure path only: the message allocates).
            let n = self.failed_solves;
            if n == 1 || n.is_multiple_of(FAILURE_LOG_EVERY) {
                ctx.log.warning(&format!(
                    "t = {t} s: {}; tau = ({}) N.m; {n} unsuccessful solve(s) so far (logged: \
                     the first and every {FAILURE_LOG_EVERY}th; solver_status has each)",
                    out.status,
                    out.tau
                        .iter()
                        .map(|v| format!("{v:.6}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
        }
        let energy = self.controller.controller().energy(&z);
        self.write_outputs(values, &out, energy);
        self.log_stall(ctx, t, energy);
        self.log_adaptation(ctx, t);
        let updates = self.controller.model_updates();
        if updates != self.updates_reported {
            // A new model and family: their chart range (no message, no
            // allocation: the clamp is reported at set-up and tuning).
            self.updates_reported = updates;
            self.write_chart_energies(values);
        }
    }

    fn write_outputs(&self, values: &mut Values, out: &ControlOutput<N>, energy: f64) {
        for j in 0..N {
            values.set_real(self.io.tau[j], out.tau[j]);
        }
        values.set_real(self.io.energy, energy);
        values.set_real(self.io.solve_time, out.preparation_time + out.feedback_time);
        values.set_integer(
            self.io.qp_iterations,
            i32::try_from(out.qp_iterations).unwrap_or(i32::MAX),
        );
        values.set_integer(self.io.solver_status, out.status.code());
        let estimate = self.controller.estimate();
        for (i, vr) in self.io.estimate.iter().enumerate() {
            values.set_real(*vr, estimate.map_or(0.0, |p| p.theta[i]));
        }
        let count = |n: usize| i32::try_from(n).unwrap_or(i32::MAX);
        values.set_integer(
            self.io.model_updates,
            count(self.controller.model_updates()),
        );
        values.set_integer(
            self.io.adapt_refused,
            count(self.controller.refused_models()),
        );
        values.set_integer(
            self.io.adapt_reverts,
            count(self.controller.reverted_models()),
        );
        values.set_integer(
            self.io.adaptation_status,
            ADAPTATION_STATUS.item(self.controller.adaptation_status()),
        );
        values.set_integer(
            self.io.supervisor_events,
            count(self.controller.controller().supervisor_events()),
        );
    }

    /// Logs a stall the supervisor called at this sample (OK level under
    /// logEvents: the FMU did what it documents). Only then: a message
    /// allocates.
    fn log_stall(&mut self, ctx: &Context, t: f64, energy: f64) {
        let stalls = self.controller.controller().supervisor_events();
        if stalls == self.stalls_logged {
            return;
        }
        self.stalls_logged = stalls;
        let e_ref = self.controller.controller().config().cost.e_ref;
        ctx.log.event(&format!(
            "t = {t} s: stall {stalls}: a joint was held still by a large torque for 1 s with \
             the energy at {energy:.4} J (E_ref {e_ref} J, not coming closer); the torque is \
             released (zero, solver_status 4) and the plan and state estimate are dropped{}",
            if self.settings.adapt {
                "; the adaptation takes its last model back or tries its estimate"
            } else {
                ""
            }
        ));
    }

    /// Logs the adaptation's new event under logEvents (OK level: the FMU
    /// did what it documents): an accepted model and each revert with its
    /// figures, each refusal reason the first time (then counted in
    /// `adapt_refused`). Only when something happened: a message allocates.
    fn log_adaptation(&mut self, ctx: &Context, t: f64) {
        let Some((number, event)) = self.controller.adaptation_event() else {
            return;
        };
        if number == self.events_logged {
            return;
        }
        self.events_logged = number;
        let message = match event {
            AdaptationEvent::Accepted {
                improvement,
                windows,
            } => format!(
                "t = {t} s: adaptation took a new model (it explained {windows} windows \
                 measured after it better by {improvement:.1} in units of their variance)"
            ),
            AdaptationEvent::Refused(reason) => {
                let logged = &mut self.refusals_logged[reason as usize];
                if *logged {
                    return;
                }
                *logged = true;
                format!(
                    "t = {t} s: adaptation refused a candidate model: {}; further refusals \
                     for this reason are counted in adapt_refused",
                    reason.describe()
                )
            }
            AdaptationEvent::Reverted {
                torque_before,
                torque_after,
                energy_before,
                energy_after,
            } => format!(
                "t = {t} s: adaptation reverted to the previous model: with the new one the \
                 RMS torque went {torque_before:.4} -> {torque_after:.4} N.m and the RMS \
                 energy error {energy_before:.4} -> {energy_after:.4} J"
            ),
        };
        ctx.log.event(&message);
    }

    /// The controller (diagnostics and tests).
    pub fn controller(&self) -> &ChainController<N, NX> {
        self.controller.controller()
    }

    /// The controller with its adaptation.
    pub fn adaptive(&self) -> &AdaptiveController<N, NX, NP, NA> {
        &self.controller
    }

    /// The settings the controller was built from (tunables: the latest).
    pub fn settings(&self) -> &Settings<N> {
        &self.settings
    }
}
