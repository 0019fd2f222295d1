//! One FMU instance: the FMI 2.0 Co-Simulation state machine, argument
//! checks and value-reference dispatch around a [`Model`]. This is the safe
//! Rust API; [`crate::abi`] wraps it for C.

use crate::logger::{Logger, Status};
pub use crate::model::{Context, Experiment, Model, ModelError, State};
use crate::state::{self, FmuState, ModelSnapshot, Snapshot};
use crate::values::Values;
use crate::variables::compact;
use crate::variables::{BaseType, Causality, Initial, ModelDescription, Value, Variability};
use std::path::PathBuf;

/// One instance of model `M` with its state machine.
pub struct Instance<M: Model> {
    log: Logger,
    description: ModelDescription,
    /// The FMU's `resources/` folder (from `fmuResourceLocation`).
    resources: Option<PathBuf>,
    guid: String,
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

/// States in which `fmi2Get*Status` may be called.
/// Largest `|startTime|` accepted (s): time steps of 1 us still resolve.
pub const MAX_START_TIME: f64 = 1e9;

const STATUS_READABLE: &[State] = &[State::StepComplete, State::StepFailed, State::Terminated];

impl<M: Model> Instance<M> {
    /// `fmi2Instantiate`: checks the GUID against the model's; logs and
    /// returns `None` on mismatch or an invalid variable table.
    pub fn new(log: Logger, guid: &str) -> Option<Self> {
        Self::with_resources(log, guid, None)
    }

    /// `fmi2Instantiate` of an FMU unpacked with its `resources/` folder at
    /// `resources`: the description is [`Model::description_for`] it.
    pub fn with_resources(log: Logger, guid: &str, resources: Option<PathBuf>) -> Option<Self> {
        let description = match M::description_for(resources.as_deref()) {
            Ok(d) => d,
            Err(e) => {
                log.error(&format!("fmi2Instantiate: {e}"));
                return None;
            }
        };
        if let Err(e) = description.validate() {
            log.error(&format!("fmi2Instantiate: invalid variable table: {e}"));
            return None;
        }
        let expected = crate::xml::guid(&description);
        if guid != expected {
            log.error(&format!(
                "fmi2Instantiate: GUID {guid} does not match this binary's {expected} \
                 (modelDescription.xml and binary come from different builds)"
            ));
            return None;
        }
        log.event(&format!(
            "fmi2Instantiate: instance of {} created",
            description.model_name
        ));
        let values = Values::new(&description);
        Some(Self {
            log,
            description,
            resources,
            guid: expected,
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

    /// The model, once initialized.
    pub fn model(&self) -> Option<&M> {
        self.model.as_ref()
    }

    /// Current communication time.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Finishes a call: an error is logged and moves the instance to the
    /// error state; a warning logged during the call upgrades `fmi2OK`.
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
            let names: Vec<String> = allowed.iter().map(|s| s.to_string()).collect();
            Err(format!(
                "{func}: not allowed in state {} (allowed in: {})",
                self.state,
                names.join(", ")
            ))
        }
    }

    /// `fmi2SetDebugLogging`.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Status {
        let r = self
            .log
            .set_debug_logging(on, categories)
            .map(|()| Status::Ok)
            .map_err(|e| format!("fmi2SetDebugLogging: {e}"));
        self.conclude(r)
    }

    /// `fmi2SetupExperiment`.
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Status {
        let r = (|| {
            self.require("fmi2SetupExperiment", &[State::Instantiated])?;
            self.log.trace(|| {
                format!("fmi2SetupExperiment(tolerance = {tolerance:?}, start = {start_time}, stop = {stop_time:?})")
            });
            if !(start_time.is_finite() && start_time.abs() <= MAX_START_TIME) {
                return Err(format!(
                    "fmi2SetupExperiment: startTime = {start} must be finite and within \
                     +-{MAX_START_TIME:e} s (beyond, a double cannot resolve the FMUs' time steps)",
                    start = compact(start_time)
                ));
            }
            if let Some(tol) = tolerance
                && !(tol.is_finite() && tol > 0.0)
            {
                return Err(format!(
                    "fmi2SetupExperiment: tolerance = {} must be finite and > 0",
                    compact(tol)
                ));
            }
            if let Some(stop) = stop_time
                && !(stop.is_finite() && stop >= start_time)
            {
                return Err(format!(
                    "fmi2SetupExperiment: stopTime = {} must be finite and >= startTime = {}",
                    compact(stop),
                    compact(start_time)
                ));
            }
            self.experiment = Experiment {
                tolerance,
                start_time,
                stop_time,
            };
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization_mode(&mut self) -> Status {
        let r = self
            .require("fmi2EnterInitializationMode", &[State::Instantiated])
            .map(|()| {
                self.state = State::InitializationMode;
                self.time = self.experiment.start_time;
                self.last_successful_time = self.time;
                self.model_current = false;
                self.log.event("entered initialization mode");
                Status::Ok
            });
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

    /// `fmi2ExitInitializationMode`: builds the model (parameter validation)
    /// and computes the outputs.
    pub fn exit_initialization_mode(&mut self) -> Status {
        let r = (|| {
            self.require("fmi2ExitInitializationMode", &[State::InitializationMode])?;
            if !self.model_current {
                self.compute_initial("fmi2ExitInitializationMode")?;
            }
            self.state = State::StepComplete;
            self.terminate_requested = false;
            self.log.event("initialization done, ready to step");
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Status {
        let r = self
            .require("fmi2Terminate", &[State::StepComplete, State::StepFailed])
            .map(|()| {
                self.state = State::Terminated;
                self.log.event("terminated");
                Status::Ok
            });
        self.conclude(r)
    }

    /// `fmi2Reset`: back to the instantiated state with the start values.
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

    /// Generic getter: `write(k, value)` receives the value of `vrs[k]`.
    pub fn get(
        &mut self,
        func: &'static str,
        base: BaseType,
        vrs: &[u32],
        mut write: impl FnMut(usize, Value),
    ) -> Status {
        let r = (|| {
            self.require(func, READABLE)?;
            let mut indices_ok = true;
            let mut needs_model = false;
            for &vr in vrs {
                match self.values.index(base, vr) {
                    Some(i) => {
                        let v = &self.description.variables[i];
                        needs_model |= v.effective_initial() == Some(Initial::Calculated);
                    }
                    None => indices_ok = false,
                }
            }
            if !indices_ok {
                let vr = vrs
                    .iter()
                    .find(|&&vr| self.values.index(base, vr).is_none())
                    .copied()
                    .unwrap_or_default();
                return Err(format!("{func}: unknown {base:?} value reference {vr}"));
            }
            if self.state == State::InitializationMode && needs_model && !self.model_current {
                self.compute_initial(func)?;
            }
            for (k, &vr) in vrs.iter().enumerate() {
                let i = self.values.index(base, vr).expect("checked above");
                write(k, self.values.at(i));
            }
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// Generic setter: `value(k)` is the value for `vrs[k]`. All values are
    /// checked before any is stored, so a rejected call changes nothing.
    pub fn set(
        &mut self,
        func: &'static str,
        base: BaseType,
        vrs: &[u32],
        value: impl Fn(usize) -> Value,
    ) -> Status {
        let r = (|| {
            self.require(
                func,
                &[
                    State::Instantiated,
                    State::InitializationMode,
                    State::StepComplete,
                ],
            )?;
            let mut tunables = false;
            for (k, &vr) in vrs.iter().enumerate() {
                let i = self
                    .values
                    .index(base, vr)
                    .ok_or_else(|| format!("{func}: unknown {base:?} value reference {vr}"))?;
                let var = &self.description.variables[i];
                let settable = var.variability != Variability::Constant
                    && match self.state {
                        State::Instantiated => {
                            var.causality == Causality::Input
                                || matches!(
                                    var.effective_initial(),
                                    Some(Initial::Exact | Initial::Approx)
                                )
                        }
                        State::InitializationMode => {
                            var.causality == Causality::Input
                                || var.effective_initial() == Some(Initial::Exact)
                        }
                        _ => {
                            var.causality == Causality::Input
                                || (var.causality == Causality::Parameter
                                    && var.variability == Variability::Tunable)
                        }
                    };
                if !settable {
                    return Err(format!(
                        "{func}: {} (value reference {vr}, causality {:?}, variability {:?}) cannot be set in state {}",
                        var.name, var.causality, var.variability, self.state
                    ));
                }
                var.check_value(value(k))
                    .map_err(|e| format!("{func}: rejected: {e}"))?;
                tunables |=
                    self.state == State::StepComplete && var.causality == Causality::Parameter;
            }
            // Only a tunable change (rare, between steps) may allocate the backup.
            let backup: Vec<(usize, Value)> = if tunables {
                vrs.iter()
                    .map(|&vr| {
                        let i = self.values.index(base, vr).expect("checked above");
                        (i, self.values.at(i))
                    })
                    .collect()
            } else {
                Vec::new()
            };
            for (k, &vr) in vrs.iter().enumerate() {
                let i = self.values.index(base, vr).expect("checked above");
                self.values.set_at(i, value(k));
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
                    .ok_or_else(|| format!("{func}: no model in step mode"))?;
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

    /// `fmi2GetReal`.
    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Status {
        if vrs.len() != out.len() {
            return self.fail("fmi2GetReal: value array length differs from vr array length");
        }
        self.get("fmi2GetReal", BaseType::Real, vrs, |k, v| {
            if let Value::Real(x) = v {
                out[k] = x;
            }
        })
    }

    /// `fmi2SetReal`.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        if vrs.len() != values.len() {
            return self.fail("fmi2SetReal: value array length differs from vr array length");
        }
        self.set("fmi2SetReal", BaseType::Real, vrs, |k| {
            Value::Real(values[k])
        })
    }

    /// `fmi2GetInteger`.
    pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Status {
        if vrs.len() != out.len() {
            return self.fail("fmi2GetInteger: value array length differs from vr array length");
        }
        self.get("fmi2GetInteger", BaseType::Integer, vrs, |k, v| {
            if let Value::Integer(x) = v {
                out[k] = x;
            }
        })
    }

    /// `fmi2SetInteger`.
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Status {
        if vrs.len() != values.len() {
            return self.fail("fmi2SetInteger: value array length differs from vr array length");
        }
        self.set("fmi2SetInteger", BaseType::Integer, vrs, |k| {
            Value::Integer(values[k])
        })
    }

    /// `fmi2GetBoolean`.
    pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [bool]) -> Status {
        if vrs.len() != out.len() {
            return self.fail("fmi2GetBoolean: value array length differs from vr array length");
        }
        self.get("fmi2GetBoolean", BaseType::Boolean, vrs, |k, v| {
            if let Value::Boolean(x) = v {
                out[k] = x;
            }
        })
    }

    /// `fmi2SetBoolean`.
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Status {
        if vrs.len() != values.len() {
            return self.fail("fmi2SetBoolean: value array length differs from vr array length");
        }
        self.set("fmi2SetBoolean", BaseType::Boolean, vrs, |k| {
            Value::Boolean(values[k])
        })
    }

    /// `fmi2GetString` / `fmi2SetString`: the models have no String
    /// variables, so any value reference is unknown.
    pub fn string_access(&mut self, func: &'static str, vrs: &[u32], setter: bool) -> Status {
        // The state check comes first, also for an empty call (nvr = 0):
        // the states are those of the other getters and setters.
        let states: &[State] = if setter {
            &[
                State::Instantiated,
                State::InitializationMode,
                State::StepComplete,
            ]
        } else {
            READABLE
        };
        let r = self.require(func, states).and_then(|()| match vrs.first() {
            None => Ok(Status::Ok),
            Some(vr) => Err(format!(
                "{func}: unknown String value reference {vr} (this FMU has no String variables)"
            )),
        });
        self.conclude(r)
    }

    /// `fmi2DoStep`: advances from `t` to `t + h`.
    pub fn do_step(&mut self, t: f64, h: f64) -> Status {
        let r = (|| {
            self.require("fmi2DoStep", &[State::StepComplete])?;
            self.log.trace(|| {
                format!("fmi2DoStep(currentCommunicationPoint = {t}, communicationStepSize = {h})")
            });
            if !(h.is_finite() && h > 0.0) {
                return Err(format!(
                    "fmi2DoStep: communicationStepSize = {} must be finite and > 0",
                    compact(h)
                ));
            }
            if t + h == t {
                return Err(format!(
                    "fmi2DoStep: communicationStepSize = {} does not advance the time t = {} \
                     in double precision",
                    compact(h),
                    compact(t)
                ));
            }
            if !t.is_finite() || (t - self.time).abs() > 1e-8 * t.abs().max(1.0) {
                return Err(format!(
                    "fmi2DoStep: currentCommunicationPoint = {} differs from the FMU's time {} \
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
                .ok_or_else(|| "fmi2DoStep: no model in step mode".to_string())?;
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
                        crate::logger::Category::StatusWarning,
                        Status::Discard,
                        &format!(
                            "fmi2DoStep: step discarded at t = {last_successful_time}: {message}"
                        ),
                    );
                    Ok(Status::Discard)
                }
                Err(ModelError::Error(message)) => Err(format!("fmi2DoStep: {message}")),
            }
        })();
        self.conclude(r)
    }

    /// `fmi2GetRealStatus(fmi2LastSuccessfulTime)`.
    pub fn last_successful_time(&mut self) -> Result<f64, Status> {
        let r = self.require("fmi2GetRealStatus", STATUS_READABLE);
        match r {
            Ok(()) => Ok(self.last_successful_time),
            Err(e) => Err(self.conclude(Err(e))),
        }
    }

    /// `fmi2GetBooleanStatus(fmi2Terminated)`: whether the slave asks to stop
    /// (after a discarded step it cannot continue).
    pub fn terminate_requested(&mut self) -> Result<bool, Status> {
        let r = self.require("fmi2GetBooleanStatus", STATUS_READABLE);
        match r {
            Ok(()) => Ok(self.terminate_requested),
            Err(e) => Err(self.conclude(Err(e))),
        }
    }

    /// A function this FMU does not support: `fmi2Error`.
    pub fn unsupported(&mut self, func: &str, why: &str) -> Status {
        self.conclude(Err(format!("{func}: not supported: {why}")))
    }

    /// A status (`fmi2Get*Status`) this FMU cannot provide: `fmi2Discard`
    /// with a warning line and no state change, as FMI 2.0 section 4.2.3
    /// prescribes ("If a status is required which cannot be retrieved by the
    /// slave it returns fmi2Discard"). Calls in a state where no status may
    /// be queried stay errors.
    pub fn status_unavailable(&mut self, func: &str, why: &str) -> Status {
        let r = self.require(func, STATUS_READABLE).map(|()| {
            self.log.log(
                crate::logger::Category::StatusWarning,
                Status::Discard,
                &format!("{func}: status not available: {why}"),
            );
            Status::Discard
        });
        self.conclude(r)
    }
}

/// FMU state save and restore ([`crate::state`] has the byte form).
impl<M: Model> Instance<M> {
    fn require_state_support(&self, func: &str) -> Result<(), String> {
        if self.description.can_save_state {
            Ok(())
        } else {
            Err(format!(
                "{func}: not supported: canGetAndSetFMUstate is false"
            ))
        }
    }

    /// `fmi2GetFMUstate` (and the state `fmi2SerializeFMUstate` writes):
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
            let bytes = state::encode_snapshot(&self.guid, &snapshot)
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
        let snapshot: Snapshot = state::decode_snapshot(&self.guid, bytes)?;
        let values = Values::from_saved(&self.description, &snapshot.values)
            .map_err(|e| format!("malformed state values: {e}"))?;
        let needs_model = matches!(
            snapshot.state,
            State::StepComplete | State::StepFailed | State::Terminated
        );
        if needs_model && snapshot.model.is_none() {
            return Err(format!(
                "malformed state: state {} without its model",
                snapshot.state
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

    /// `fmi2DeSerializeFMUstate`: a state from its serialized form, checked
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

    /// `fmi2SetFMUstate`: continues from `saved` (also after `fmi2Error`).
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
                "{func}: state at t = {} restored (state {})",
                self.time, self.state
            ));
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// A state call with a bad argument (NULL, a pointer that is not a live
    /// state, a buffer too small): `fmi2Error` with `message`.
    pub fn state_argument_error(&mut self, message: &str) -> Status {
        self.conclude(Err(message.to_string()))
    }

    /// A successful call that needs no instance data (`fmi2FreeFMUstate`,
    /// `fmi2SerializedFMUstateSize`, `fmi2SerializeFMUstate`).
    pub fn state_call_ok(&mut self, func: &str) -> Status {
        let r = self.require_state_support(func).map(|()| Status::Ok);
        self.conclude(r)
    }
}
