//! One FMU instance: the FMI 3.0 Co-Simulation state machine, argument
//! checks and value-reference dispatch (over the array [`Layout`]) around a
//! [`Model`]. This is the safe Rust API; [`crate::abi`] wraps it for C.
//!
//! The states are fmu-core's [`State`] (so that a saved FMU state is the same
//! byte form under FMI 2.0 and 3.0), named as FMI 3.0 names them:
//! `StepComplete` is Step Mode, `StepFailed` is Step Mode after a discarded
//! step (only `fmi3Terminate`, the FMU-state functions, getters and
//! `fmi3Reset` are accepted, as in fmi2-slave). There is no Event Mode
//! (`hasEventMode = false`) and no Configuration Mode (no structural
//! parameters): those calls are errors.

use crate::layout::{self, Fmi3Type, Layout};
use fmu_core::logger::{Category, Logger, Status};
pub use fmu_core::model::{Context, Experiment, Model, ModelError, State};
use fmu_core::state::{self, FmuState, ModelSnapshot, Snapshot};
use fmu_core::values::Values;
use fmu_core::variables::compact;
use fmu_core::variables::{Causality, Initial, ModelDescription, Value, Variability};
use std::path::PathBuf;

/// Largest `|startTime|` accepted (s): time steps of 1 us still resolve.
pub const MAX_START_TIME: f64 = 1e9;

/// The FMI 3.0 name of a state, for messages.
pub fn state_name(s: State) -> &'static str {
    match s {
        State::Instantiated => "Instantiated",
        State::InitializationMode => "Initialization Mode",
        State::StepComplete => "Step Mode",
        State::StepFailed => "Step Mode after a discarded step",
        State::Terminated => "Terminated",
        State::Error => "error",
    }
}

/// The outputs of `fmi3DoStep` besides its status.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepOutcome {
    /// `terminateSimulation`: the FMU cannot continue (after a discarded step).
    pub terminate_simulation: bool,
    /// `lastSuccessfulTime`.
    pub last_successful_time: f64,
}

/// One instance of model `M` with its state machine.
pub struct Instance<M: Model> {
    log: Logger,
    description: ModelDescription,
    layout: Layout,
    /// The FMU's `resources/` folder (from `resourcePath`).
    resources: Option<PathBuf>,
    token: String,
    values: Values,
    state: State,
    model: Option<M>,
    /// The values `model` was initialized from (a saved state rebuilds the
    /// model from them in a fresh instance).
    initial_values: Option<Vec<Value>>,
    /// In initialization mode: `model` reflects the current values.
    model_current: bool,
    experiment: Experiment,
    time: f64,
    last_successful_time: f64,
    terminate_requested: bool,
}

// Instances may be driven from any thread (one at a time).
const _: () = {
    const fn assert_send<T: Send>() {}
    struct Probe;
    impl Model for Probe {
        fn description() -> ModelDescription {
            unreachable!()
        }
        fn initialize(_: &mut Values, _: &Context) -> Result<Self, ModelError> {
            unreachable!()
        }
        fn do_step(
            &mut self,
            _: &mut Values,
            _: f64,
            _: f64,
            _: &Context,
        ) -> Result<(), ModelError> {
            unreachable!()
        }
    }
    assert_send::<Instance<Probe>>();
};

type CallResult = Result<Status, String>;

const READABLE: &[State] = &[
    State::InitializationMode,
    State::StepComplete,
    State::StepFailed,
    State::Terminated,
    State::Error,
];

const WRITABLE: &[State] = &[
    State::Instantiated,
    State::InitializationMode,
    State::StepComplete,
];

/// The model's instantiation token: its FMI 2.0 GUID (a hash of its table).
pub fn instantiation_token(d: &ModelDescription) -> String {
    fmi2_slave::xml::guid(d)
}

impl<M: Model> Instance<M> {
    /// `fmi3InstantiateCoSimulation` of an FMU unpacked with its
    /// `resources/` folder at `resources`: the description is
    /// [`Model::description_for`] it, `token` must be its instantiation
    /// token. Logs and returns `None` otherwise.
    pub fn new(log: Logger, token: &str, resources: Option<PathBuf>) -> Option<Self> {
        const F: &str = "fmi3InstantiateCoSimulation";
        let description = match M::description_for(resources.as_deref()) {
            Ok(d) => d,
            Err(e) => {
                log.error(&format!("{F}: {e}"));
                return None;
            }
        };
        if let Err(e) = description.validate() {
            log.error(&format!("{F}: invalid variable table: {e}"));
            return None;
        }
        let expected = instantiation_token(&description);
        if token != expected {
            log.error(&format!(
                "{F}: instantiationToken {token} does not match this binary's {expected} \
                 (modelDescription.xml and binary come from different builds)"
            ));
            return None;
        }
        log.event(&format!(
            "{F}: instance of {} created",
            description.model_name
        ));
        let values = Values::new(&description);
        let layout = Layout::new(&description);
        Some(Self {
            log,
            description,
            layout,
            resources,
            token: expected,
            values,
            state: State::Instantiated,
            model: None,
            initial_values: None,
            model_current: false,
            experiment: Experiment::default(),
            time: 0.0,
            last_successful_time: 0.0,
            terminate_requested: false,
        })
    }

    /// The current state.
    pub fn state(&self) -> State {
        self.state
    }

    /// The logger (for messages outside a call).
    pub fn logger(&self) -> &Logger {
        &self.log
    }

    /// The variable table.
    pub fn description(&self) -> &ModelDescription {
        &self.description
    }

    /// The FMI 3.0 variables.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The model, once initialized.
    pub fn model(&self) -> Option<&M> {
        self.model.as_ref()
    }

    /// Current communication time.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Finishes a call: an error is logged and moves the instance to the
    /// error state; a warning logged during the call upgrades `fmi3OK`.
    fn conclude(&mut self, result: CallResult) -> Status {
        let warned = self.log.take_warned();
        match result {
            Ok(Status::Ok) if warned => Status::Warning,
            Ok(s) => s,
            Err(message) => {
                self.log.error(&message);
                self.state = State::Error;
                Status::Error
            }
        }
    }

    /// Reports a failure found outside the instance methods (null pointer,
    /// panic): logs it and enters the error state.
    pub fn fail(&mut self, message: &str) -> Status {
        self.conclude(Err(message.to_string()))
    }

    fn require(&self, func: &str, allowed: &[State]) -> Result<(), String> {
        if allowed.contains(&self.state) {
            Ok(())
        } else {
            let names: Vec<&str> = allowed.iter().map(|&s| state_name(s)).collect();
            Err(format!(
                "{func}: not allowed in {} (allowed in: {})",
                state_name(self.state),
                names.join(", ")
            ))
        }
    }

    /// `fmi3SetDebugLogging`.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Status {
        let r = self
            .log
            .set_debug_logging(on, categories)
            .map(|()| Status::Ok)
            .map_err(|e| format!("fmi3SetDebugLogging: {e}"));
        self.conclude(r)
    }

    /// `fmi3EnterInitializationMode`: the experiment (FMI 2.0's
    /// `fmi2SetupExperiment`, with its checks) and the transition.
    pub fn enter_initialization_mode(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Status {
        const F: &str = "fmi3EnterInitializationMode";
        let r = (|| {
            self.require(F, &[State::Instantiated])?;
            self.log.trace(|| {
                format!("{F}(tolerance = {tolerance:?}, startTime = {start_time}, stopTime = {stop_time:?})")
            });
            if !(start_time.is_finite() && start_time.abs() <= MAX_START_TIME) {
                return Err(format!(
                    "{F}: startTime = {start} must be finite and within \
                     +-{MAX_START_TIME:e} s (beyond, a double cannot resolve the FMUs' time steps)",
                    start = compact(start_time)
                ));
            }
            if let Some(tol) = tolerance
                && !(tol.is_finite() && tol > 0.0)
            {
                return Err(format!(
                    "{F}: tolerance = {} must be finite and > 0",
                    compact(tol)
                ));
            }
            if let Some(stop) = stop_time
                && !(stop.is_finite() && stop >= start_time)
            {
                return Err(format!(
                    "{F}: stopTime = {} must be finite and >= startTime = {}",
                    compact(stop),
                    compact(start_time)
                ));
            }
            self.experiment = Experiment {
                tolerance,
                start_time,
                stop_time,
            };
            self.state = State::InitializationMode;
            self.time = start_time;
            self.last_successful_time = start_time;
            self.model_current = false;
            self.log.event("entered Initialization Mode");
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    fn compute_initial(&mut self, func: &str) -> Result<(), String> {
        let ctx = Context {
            log: &self.log,
            experiment: &self.experiment,
            resources: self.resources.as_deref(),
        };
        let initial_values = self.values.all().to_vec();
        let model = M::initialize(&mut self.values, &ctx).map_err(|e| format!("{func}: {e}"))?;
        self.model = Some(model);
        self.initial_values = Some(initial_values);
        self.model_current = true;
        Ok(())
    }

    /// `fmi3ExitInitializationMode`: builds the model (parameter
    /// validation), computes the outputs and enters Step Mode.
    pub fn exit_initialization_mode(&mut self) -> Status {
        const F: &str = "fmi3ExitInitializationMode";
        let r = (|| {
            self.require(F, &[State::InitializationMode])?;
            if !self.model_current {
                self.compute_initial(F)?;
            }
            self.state = State::StepComplete;
            self.terminate_requested = false;
            self.log.event("initialization done, entered Step Mode");
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// `fmi3Terminate`.
    pub fn terminate(&mut self) -> Status {
        let r = self
            .require("fmi3Terminate", &[State::StepComplete, State::StepFailed])
            .map(|()| {
                self.state = State::Terminated;
                self.log.event("terminated");
                Status::Ok
            });
        self.conclude(r)
    }

    /// `fmi3Reset`: back to Instantiated with the start values.
    pub fn reset(&mut self) -> Status {
        self.values = Values::new(&self.description);
        self.model = None;
        self.initial_values = None;
        self.model_current = false;
        self.experiment = Experiment::default();
        self.time = 0.0;
        self.last_successful_time = 0.0;
        self.terminate_requested = false;
        self.state = State::Instantiated;
        self.log.event("reset to the start values");
        self.conclude(Ok(Status::Ok))
    }

    /// The variable of `vr` if it has type `ty` (index into the layout).
    fn lookup(&self, func: &str, ty: Fmi3Type, vr: u32) -> Result<usize, String> {
        let k = self
            .layout
            .find(vr)
            .ok_or_else(|| format!("{func}: unknown value reference {vr}"))?;
        let v = &self.layout.variables[k];
        if v.fmi3_type != ty {
            return Err(format!(
                "{func}: {} (value reference {vr}) is a {} variable (fmi3Get{} / fmi3Set{})",
                v.name,
                v.fmi3_type.xml_name(),
                v.fmi3_type.access_name(),
                v.fmi3_type.access_name()
            ));
        }
        Ok(k)
    }

    /// Generic getter: `write(k, value)` receives value number `k` of the
    /// flattened result (arrays in row-major order); `n_values` must be
    /// the total number of values of `vrs`.
    pub fn get(
        &mut self,
        func: &'static str,
        ty: Fmi3Type,
        vrs: &[u32],
        n_values: usize,
        mut write: impl FnMut(usize, Value),
    ) -> Status {
        let r = (|| {
            self.require(func, READABLE)?;
            let mut total = 0usize;
            let mut needs_model = false;
            for &vr in vrs {
                let v = &self.layout.variables[self.lookup(func, ty, vr)?];
                total += v.len();
                needs_model |= v
                    .first(&self.description)
                    .is_some_and(|first| first.effective_initial() == Some(Initial::Calculated));
            }
            if total != n_values {
                return Err(format!(
                    "{func}: nValues = {n_values}, the value references have {total} values"
                ));
            }
            if self.state == State::InitializationMode && needs_model && !self.model_current {
                self.compute_initial(func)?;
            }
            let mut k = 0;
            for &vr in vrs {
                let v = &self.layout.variables[self.lookup(func, ty, vr)?];
                if v.is_time() {
                    write(k, Value::Real(self.time));
                    k += 1;
                }
                for i in v.elements.clone() {
                    write(k, self.values.at(i));
                    k += 1;
                }
            }
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// Generic setter: `value(k)` is value number `k` of the flattened
    /// input (arrays in row-major order; an error for a value the type
    /// cannot hold). All values are checked before any is stored, so a
    /// rejected call changes nothing.
    pub fn set(
        &mut self,
        func: &'static str,
        ty: Fmi3Type,
        vrs: &[u32],
        n_values: usize,
        value: impl Fn(usize) -> Result<Value, String>,
    ) -> Status {
        let r = (|| {
            self.require(func, WRITABLE)?;
            let mut total = 0usize;
            for &vr in vrs {
                total += self.layout.variables[self.lookup(func, ty, vr)?].len();
            }
            if total != n_values {
                return Err(format!(
                    "{func}: nValues = {n_values}, the value references have {total} values"
                ));
            }
            let mut tunables = false;
            let mut k = 0;
            for &vr in vrs {
                let v = &self.layout.variables[self.lookup(func, ty, vr)?];
                let Some(first) = v.first(&self.description) else {
                    return Err(format!(
                        "{func}: {} (value reference {vr}) is the independent variable: \
                         it cannot be set",
                        v.name
                    ));
                };
                if !layout::settable(first, self.state) {
                    return Err(format!(
                        "{func}: {} (value reference {vr}, causality {:?}, variability {:?}) \
                         cannot be set in {}",
                        v.name,
                        first.causality,
                        first.variability,
                        state_name(self.state)
                    ));
                }
                for i in v.elements.clone() {
                    let x = value(k).map_err(|e| {
                        format!(
                            "{func}: rejected: {}: {e}",
                            self.description.variables[i].name
                        )
                    })?;
                    self.description.variables[i]
                        .check_value(x)
                        .map_err(|e| format!("{func}: rejected: {e}"))?;
                    k += 1;
                }
                tunables |= self.state == State::StepComplete
                    && first.causality == Causality::Parameter
                    && first.variability == Variability::Tunable;
            }
            // Only a tunable change (rare, between steps) may allocate the backup.
            let mut backup: Vec<(usize, Value)> = Vec::new();
            if tunables {
                for &vr in vrs {
                    let v = &self.layout.variables[self.lookup(func, ty, vr)?];
                    backup.extend(v.elements.clone().map(|i| (i, self.values.at(i))));
                }
            }
            let mut k = 0;
            for &vr in vrs {
                let elements = self.layout.variables[self.lookup(func, ty, vr)?]
                    .elements
                    .clone();
                for i in elements {
                    self.values.set_at(i, value(k)?);
                    k += 1;
                }
            }
            self.model_current &= self.state == State::StepComplete;
            if tunables {
                let ctx = Context {
                    log: &self.log,
                    experiment: &self.experiment,
                    resources: self.resources.as_deref(),
                };
                let model = self
                    .model
                    .as_mut()
                    .ok_or_else(|| format!("{func}: no model in Step Mode"))?;
                if let Err(e) = model.update_tunables(&mut self.values, &ctx) {
                    for (i, old) in backup {
                        self.values.set_at(i, old);
                    }
                    return Err(format!("{func}: tunable parameter change rejected: {e}"));
                }
                self.log
                    .event(&format!("{func}: tunable parameters updated"));
            }
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// A getter or setter of a type this FMU has no variables of
    /// (`type_name`: Float32, Int8, String, Binary, Clock, ...): `fmi3OK`
    /// for no value references, else `fmi3Error` naming the first.
    pub fn other_type_access(
        &mut self,
        func: &'static str,
        type_name: &str,
        vrs: &[u32],
        setter: bool,
    ) -> Status {
        // The state check comes first, also for an empty call: the states
        // are those of the other getters and setters.
        let states = if setter { WRITABLE } else { READABLE };
        let r = self.require(func, states).and_then(|()| match vrs.first() {
            None => Ok(Status::Ok),
            Some(&vr) => Err(match self.layout.find(vr) {
                Some(k) => {
                    let v = &self.layout.variables[k];
                    format!(
                        "{func}: {} (value reference {vr}) is a {} variable, not {type_name} \
                         (use fmi3Get{} / fmi3Set{})",
                        v.name,
                        v.fmi3_type.xml_name(),
                        v.fmi3_type.access_name(),
                        v.fmi3_type.access_name()
                    )
                }
                None => format!(
                    "{func}: unknown value reference {vr} (this FMU has no {type_name} variables)"
                ),
            }),
        });
        self.conclude(r)
    }

    /// `fmi3DoStep`: advances from `t` to `t + h`.
    pub fn do_step(&mut self, t: f64, h: f64) -> (Status, StepOutcome) {
        const F: &str = "fmi3DoStep";
        let r = (|| {
            self.require(F, &[State::StepComplete])?;
            self.log.trace(|| {
                format!("{F}(currentCommunicationPoint = {t}, communicationStepSize = {h})")
            });
            if !(h.is_finite() && h > 0.0) {
                return Err(format!(
                    "{F}: communicationStepSize = {} must be finite and > 0",
                    compact(h)
                ));
            }
            if t + h == t {
                return Err(format!(
                    "{F}: communicationStepSize = {} does not advance the time t = {} \
                     in double precision",
                    compact(h),
                    compact(t)
                ));
            }
            if !t.is_finite() || (t - self.time).abs() > 1e-8 * t.abs().max(1.0) {
                return Err(format!(
                    "{F}: currentCommunicationPoint = {} differs from the FMU's time {} \
                     (rolling back is not supported)",
                    compact(t),
                    compact(self.time)
                ));
            }
            let ctx = Context {
                log: &self.log,
                experiment: &self.experiment,
                resources: self.resources.as_deref(),
            };
            let model = self
                .model
                .as_mut()
                .ok_or_else(|| format!("{F}: no model in Step Mode"))?;
            match model.do_step(&mut self.values, t, h, &ctx) {
                Ok(()) => {
                    self.time = t + h;
                    self.last_successful_time = self.time;
                    Ok(Status::Ok)
                }
                Err(ModelError::Discard {
                    message,
                    last_successful_time,
                }) => {
                    self.state = State::StepFailed;
                    self.time = last_successful_time;
                    self.last_successful_time = last_successful_time;
                    self.terminate_requested = true;
                    self.log.log(
                        Category::StatusWarning,
                        Status::Discard,
                        &format!("{F}: step discarded at t = {last_successful_time}: {message}"),
                    );
                    Ok(Status::Discard)
                }
                Err(ModelError::Error(message)) => Err(format!("{F}: {message}")),
            }
        })();
        let status = self.conclude(r);
        (
            status,
            StepOutcome {
                terminate_simulation: self.terminate_requested,
                last_successful_time: self.last_successful_time,
            },
        )
    }

    /// A function this FMU does not support: `fmi3Error`.
    pub fn unsupported(&mut self, func: &str, why: &str) -> Status {
        self.conclude(Err(format!("{func}: not supported: {why}")))
    }
}

/// FMU state save and restore (fmu-core's `state` has the byte form, the
/// same as under FMI 2.0).
impl<M: Model> Instance<M> {
    fn require_state_support(&self, func: &str) -> Result<(), String> {
        if self.description.can_save_state {
            Ok(())
        } else {
            Err(format!(
                "{func}: not supported: canGetAndSetFMUState is false"
            ))
        }
    }

    /// `fmi3GetFMUState` (and the state `fmi3SerializeFMUState` writes):
    /// the serialized state of this instance. Allowed in every state.
    pub fn save_state(&mut self, func: &str) -> Result<FmuState, Status> {
        let r = (|| {
            self.require_state_support(func)?;
            // In initialization mode the model is rebuilt when needed (it
            // is a function of the values); after it, it carries the run.
            let model = match (&self.model, &self.initial_values) {
                (Some(model), Some(initial)) if self.state != State::InitializationMode => {
                    Some(ModelSnapshot {
                        initial_values: initial.clone(),
                        state: model.save_state().map_err(|e| format!("{func}: {e}"))?,
                    })
                }
                _ => None,
            };
            let snapshot = Snapshot {
                state: self.state,
                values: self.values.all().to_vec(),
                experiment: self.experiment,
                time: self.time,
                last_successful_time: self.last_successful_time,
                terminate_requested: self.terminate_requested,
                model,
            };
            let bytes = state::encode_snapshot(&self.token, &snapshot)
                .map_err(|e| format!("{func}: {e}"))?;
            Ok(FmuState { bytes })
        })();
        match r {
            Ok(saved) => {
                self.log.event(&format!(
                    "{func}: state at t = {} saved ({} bytes)",
                    self.time,
                    saved.bytes.len()
                ));
                self.conclude(Ok(Status::Ok));
                Ok(saved)
            }
            Err(e) => Err(self.conclude(Err(e))),
        }
    }

    /// Decodes and checks a serialized state of this FMU (header, payload,
    /// the values against the variable table).
    fn decode_state(&self, bytes: &[u8]) -> Result<(Snapshot, Values), String> {
        let snapshot: Snapshot = state::decode_snapshot(&self.token, bytes)?;
        let values = Values::from_saved(&self.description, &snapshot.values)
            .map_err(|e| format!("malformed state values: {e}"))?;
        let needs_model = matches!(
            snapshot.state,
            State::StepComplete | State::StepFailed | State::Terminated
        );
        if needs_model && snapshot.model.is_none() {
            return Err(format!(
                "malformed state: {} without its model",
                state_name(snapshot.state)
            ));
        }
        if let Some(m) = &snapshot.model {
            Values::from_saved(&self.description, &m.initial_values)
                .map_err(|e| format!("malformed initial values: {e}"))?;
        }
        if !(snapshot.time.is_finite() && snapshot.last_successful_time.is_finite()) {
            return Err("malformed state: time is not finite".into());
        }
        Ok((snapshot, values))
    }

    /// `fmi3DeserializeFMUState`: a state from its serialized form, checked
    /// (a buffer of another FMU, format version, or a corrupt one is an error).
    pub fn deserialize_state(&mut self, func: &str, bytes: &[u8]) -> Result<FmuState, Status> {
        let r = self
            .require_state_support(func)
            .and_then(|()| self.decode_state(bytes).map_err(|e| format!("{func}: {e}")));
        match r {
            Ok(_) => {
                self.conclude(Ok(Status::Ok));
                Ok(FmuState {
                    bytes: bytes.to_vec(),
                })
            }
            Err(e) => Err(self.conclude(Err(e))),
        }
    }

    /// `fmi3SetFMUState`: continues from `saved` (also after `fmi3Error`).
    /// The model is restored in place when it was initialized from the same
    /// values in the same experiment, else rebuilt from them first.
    pub fn restore_state(&mut self, func: &str, saved: &FmuState) -> Status {
        let r = (|| {
            self.require_state_support(func)?;
            let (snapshot, values) = self
                .decode_state(&saved.bytes)
                .map_err(|e| format!("{func}: {e}"))?;
            let ctx = Context {
                log: &self.log,
                experiment: &snapshot.experiment,
                resources: self.resources.as_deref(),
            };
            let model = match &snapshot.model {
                None => None,
                Some(m) => {
                    let same = self.initial_values.as_ref() == Some(&m.initial_values)
                        && self.experiment == snapshot.experiment;
                    let mut model = match self.model.take() {
                        Some(model) if same => model,
                        current => {
                            // A failed rebuild leaves the current model.
                            self.model = current;
                            let mut initial =
                                Values::from_saved(&self.description, &m.initial_values)?;
                            M::initialize(&mut initial, &ctx)
                                .map_err(|e| format!("{func}: rebuilding the model: {e}"))?
                        }
                    };
                    if let Err(e) = model.restore_state(&m.state, &values, &ctx) {
                        // Keep the model so that the instance can still be
                        // reset; the error state forbids stepping it.
                        self.model = Some(model);
                        self.initial_values = Some(m.initial_values.clone());
                        return Err(format!("{func}: {e}"));
                    }
                    Some(model)
                }
            };
            self.model_current = model.is_some();
            self.model = model;
            self.initial_values = snapshot.model.map(|m| m.initial_values);
            self.values = values;
            self.state = snapshot.state;
            self.experiment = snapshot.experiment;
            self.time = snapshot.time;
            self.last_successful_time = snapshot.last_successful_time;
            self.terminate_requested = snapshot.terminate_requested;
            self.log.event(&format!(
                "{func}: state at t = {} restored ({})",
                self.time,
                state_name(self.state)
            ));
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// A state call with a bad argument (NULL, a pointer that is not a live
    /// state, a buffer too small): `fmi3Error` with `message`.
    pub fn state_argument_error(&mut self, message: &str) -> Status {
        self.conclude(Err(message.to_string()))
    }

    /// A successful call that needs no instance data (`fmi3FreeFMUState`,
    /// `fmi3SerializedFMUStateSize`, `fmi3SerializeFMUState`).
    pub fn state_call_ok(&mut self, func: &str) -> Status {
        let r = self.require_state_support(func).map(|()| Status::Ok);
        self.conclude(r)
    }
}
