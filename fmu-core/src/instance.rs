//! The FMI-version-neutral half of one FMU instance: its values, life-cycle
//! state, model and clock, and every transition FMI 2.0 and FMI 3.0 share
//! (instantiation checks, the experiment, initialization, a step of the
//! model, terminate, reset, and FMU state save / restore). `fmi2-slave` and
//! `fmi3-slave` each wrap a [`Core`] in their state machine and C functions;
//! a [`Dialect`] gives the words of their version, so the log reads in the
//! standard's terms.

use crate::logger::{Category, Logger, Status};
use crate::model::{Context, Experiment, Model, ModelError, State};
use crate::state::{self, FmuState, ModelSnapshot, Snapshot};
use crate::values::Values;
use crate::variables::{ModelDescription, Value, compact};
use std::path::PathBuf;

/// Largest `|startTime|` accepted (s): time steps of 1 us still resolve.
pub const MAX_START_TIME: f64 = 1e9;

/// The words of one FMI version in the messages of a [`Core`].
#[derive(Debug)]
pub struct Dialect {
    /// A state's name (FMI 2.0 `stepComplete`, FMI 3.0 `Step Mode`).
    pub state_name: fn(State) -> &'static str,
    /// Put before a state's name in a sentence (`"state "` or `""`).
    pub state_word: &'static str,
    /// The model description attribute that allows FMU states.
    pub can_save_state: &'static str,
    /// The instantiation token's name (`GUID`, `instantiationToken`).
    pub token_name: &'static str,
    /// What the log says at the end of initialization.
    pub initialized: &'static str,
}

/// The result of a call before it is concluded: a status, or the message of
/// an error.
pub type CallResult = Result<Status, String>;

/// One instance of model `M`, apart from the FMI version: fields are public
/// to the state machines built on it, which keep their invariants.
pub struct Core<M: Model> {
    /// The instance's logger (the host's callback).
    pub log: Logger,
    /// The variable table.
    pub description: ModelDescription,
    /// The FMU's `resources/` folder.
    pub resources: Option<PathBuf>,
    /// The instantiation token (FMI 2.0 GUID) the state bytes carry.
    pub token: String,
    /// The current values.
    pub values: Values,
    /// The life-cycle state.
    pub state: State,
    /// The model, once initialized.
    pub model: Option<M>,
    /// The values `model` was initialized from (a saved state rebuilds the
    /// model from them in a fresh instance).
    pub initial_values: Option<Vec<Value>>,
    /// In initialization mode: `model` reflects the current values.
    pub model_current: bool,
    /// The experiment (tolerance, start and stop time).
    pub experiment: Experiment,
    /// The communication time.
    pub time: f64,
    /// The end of the last successful step.
    pub last_successful_time: f64,
    /// The model asked to stop (after a discarded step).
    pub terminate_requested: bool,
    dialect: &'static Dialect,
}

// Instances (a core and what the FMI version adds) may be driven from any
// thread, one at a time.
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
    assert_send::<Core<Probe>>();
};

impl<M: Model> Core<M> {
    /// A new instance of `M` for an FMU unpacked with its `resources/`
    /// folder at `resources`: the description is
    /// [`Model::description_for`] it, `token` must be its instantiation
    /// token (`expected_token` of the description). Logs under `func` and
    /// returns `None` otherwise.
    pub fn new(
        func: &str,
        log: Logger,
        token: &str,
        resources: Option<PathBuf>,
        expected_token: fn(&ModelDescription) -> String,
        dialect: &'static Dialect,
    ) -> Option<Self> {
        let description = match M::description_for(resources.as_deref()) {
            Ok(d) => d,
            Err(e) => {
                log.error(&format!("{func}: {e}"));
                return None;
            }
        };
        if let Err(e) = description.validate() {
            log.error(&format!("{func}: invalid variable table: {e}"));
            return None;
        }
        let expected = expected_token(&description);
        if token != expected {
            log.error(&format!(
                "{func}: {} {token} does not match this binary's {expected} \
                 (modelDescription.xml and binary come from different builds)",
                dialect.token_name
            ));
            return None;
        }
        log.event(&format!(
            "{func}: instance of {} created",
            description.model_name
        ));
        let values = Values::new(&description);
        Some(Self {
            log,
            description,
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
            dialect,
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

    /// A state in this version's words, for a sentence.
    fn named(&self, s: State) -> String {
        format!(
            "{}{}",
            self.dialect.state_word,
            (self.dialect.state_name)(s)
        )
    }

    /// Finishes a call: an error is logged and moves the instance to the
    /// error state; a warning logged during the call upgrades OK.
    pub fn conclude(&mut self, result: CallResult) -> Status {
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

    /// `func` is allowed in the current state if it is one of `allowed`.
    pub fn require(&self, func: &str, allowed: &[State]) -> Result<(), String> {
        if allowed.contains(&self.state) {
            Ok(())
        } else {
            let names: Vec<&str> = allowed
                .iter()
                .map(|&s| (self.dialect.state_name)(s))
                .collect();
            Err(format!(
                "{func}: not allowed in {} (allowed in: {})",
                self.named(self.state),
                names.join(", ")
            ))
        }
    }

    /// A function this FMU does not support: an error.
    pub fn unsupported(&mut self, func: &str, why: &str) -> Status {
        self.conclude(Err(format!("{func}: not supported: {why}")))
    }

    /// `*SetDebugLogging`.
    pub fn set_debug_logging(&mut self, func: &str, on: bool, categories: &[&str]) -> Status {
        let r = self
            .log
            .set_debug_logging(on, categories)
            .map(|()| Status::Ok)
            .map_err(|e| format!("{func}: {e}"));
        self.conclude(r)
    }

    /// Checks and keeps the experiment (`fmi2SetupExperiment`, the
    /// arguments of `fmi3EnterInitializationMode`); allowed when
    /// instantiated.
    pub fn set_experiment(
        &mut self,
        func: &str,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Result<(), String> {
        self.require(func, &[State::Instantiated])?;
        self.log.trace(|| {
            format!(
                "{func}(tolerance = {tolerance:?}, startTime = {start_time}, stopTime = {stop_time:?})"
            )
        });
        if !(start_time.is_finite() && start_time.abs() <= MAX_START_TIME) {
            return Err(format!(
                "{func}: startTime = {start} must be finite and within \
                 +-{MAX_START_TIME:e} s (beyond, a double cannot resolve the FMUs' time steps)",
                start = compact(start_time)
            ));
        }
        if let Some(tol) = tolerance
            && !(tol.is_finite() && tol > 0.0)
        {
            return Err(format!(
                "{func}: tolerance = {} must be finite and > 0",
                compact(tol)
            ));
        }
        if let Some(stop) = stop_time
            && !(stop.is_finite() && stop >= start_time)
        {
            return Err(format!(
                "{func}: stopTime = {} must be finite and >= startTime = {}",
                compact(stop),
                compact(start_time)
            ));
        }
        self.experiment = Experiment {
            tolerance,
            start_time,
            stop_time,
        };
        Ok(())
    }

    /// Enters initialization mode (allowed when instantiated) at the
    /// experiment's start time.
    pub fn enter_initialization(&mut self, func: &str) -> Result<(), String> {
        self.require(func, &[State::Instantiated])?;
        self.state = State::InitializationMode;
        self.time = self.experiment.start_time;
        self.last_successful_time = self.time;
        self.model_current = false;
        self.log.event(&format!(
            "entered {}",
            (self.dialect.state_name)(State::InitializationMode)
        ));
        Ok(())
    }

    /// Builds the model from the current values (parameter validation) and
    /// computes the outputs.
    pub fn compute_initial(&mut self, func: &str) -> Result<(), String> {
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

    /// `*ExitInitializationMode`: builds the model unless current, then
    /// ready to step.
    pub fn exit_initialization_mode(&mut self, func: &str) -> Status {
        let r = (|| {
            self.require(func, &[State::InitializationMode])?;
            if !self.model_current {
                self.compute_initial(func)?;
            }
            self.state = State::StepComplete;
            self.terminate_requested = false;
            self.log.event(self.dialect.initialized);
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// `*Terminate`.
    pub fn terminate(&mut self, func: &str) -> Status {
        let r = self
            .require(func, &[State::StepComplete, State::StepFailed])
            .map(|()| {
                self.state = State::Terminated;
                self.log.event("terminated");
                Status::Ok
            });
        self.conclude(r)
    }

    /// `*Reset`: back to the instantiated state with the start values.
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

    /// The model with the values and the context to run it in (after
    /// initialization), or an error naming `func`.
    fn running(&mut self, func: &str) -> Result<(&mut M, &mut Values, Context<'_>), String> {
        let ctx = Context {
            log: &self.log,
            experiment: &self.experiment,
            resources: self.resources.as_deref(),
        };
        let model = self.model.as_mut().ok_or_else(|| {
            format!(
                "{func}: no model in {}",
                (self.dialect.state_name)(State::StepComplete)
            )
        })?;
        Ok((model, &mut self.values, ctx))
    }

    /// Tells the model of tunable parameters just set (between steps);
    /// if it rejects them, the values in `backup` (index, old value) are
    /// put back.
    pub fn apply_tunables(
        &mut self,
        func: &str,
        backup: Vec<(usize, Value)>,
    ) -> Result<(), String> {
        let (model, values, ctx) = self.running(func)?;
        if let Err(e) = model.update_tunables(values, &ctx) {
            for (i, old) in backup {
                values.set_at(i, old);
            }
            return Err(format!("{func}: tunable parameter change rejected: {e}"));
        }
        self.log
            .event(&format!("{func}: tunable parameters updated"));
        Ok(())
    }

    /// `*DoStep`: the model advances from `t` to `t + h` (a discarded step
    /// is `Discard` with the model's message, the instance then asks to
    /// terminate). Not concluded: the caller adds its version's outputs.
    pub fn step(&mut self, func: &str, t: f64, h: f64) -> CallResult {
        self.require(func, &[State::StepComplete])?;
        self.log.trace(|| {
            format!("{func}(currentCommunicationPoint = {t}, communicationStepSize = {h})")
        });
        if !(h.is_finite() && h > 0.0) {
            return Err(format!(
                "{func}: communicationStepSize = {} must be finite and > 0",
                compact(h)
            ));
        }
        if t + h == t {
            return Err(format!(
                "{func}: communicationStepSize = {} does not advance the time t = {} \
                 in double precision",
                compact(h),
                compact(t)
            ));
        }
        if !t.is_finite() || (t - self.time).abs() > 1e-8 * t.abs().max(1.0) {
            return Err(format!(
                "{func}: currentCommunicationPoint = {} differs from the FMU's time {} \
                 (rolling back is not supported)",
                compact(t),
                compact(self.time)
            ));
        }
        let (model, values, ctx) = self.running(func)?;
        match model.do_step(values, t, h, &ctx) {
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
                    &format!("{func}: step discarded at t = {last_successful_time}: {message}"),
                );
                Ok(Status::Discard)
            }
            Err(ModelError::Error(message)) => Err(format!("{func}: {message}")),
        }
    }
}

/// FMU state save and restore ([`crate::state`] has the byte form, the same
/// under every FMI version).
impl<M: Model> Core<M> {
    fn require_state_support(&self, func: &str) -> Result<(), String> {
        if self.description.can_save_state {
            Ok(())
        } else {
            Err(format!(
                "{func}: not supported: {} is false",
                self.dialect.can_save_state
            ))
        }
    }

    /// `*GetFMUState` (and the state `*SerializeFMUState` writes): the
    /// serialized state of this instance. Allowed in every state.
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
                self.named(snapshot.state)
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

    /// `*DeserializeFMUState`: a state from its serialized form, checked (a
    /// buffer of another FMU, format version, or a corrupt one is an error).
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

    /// `*SetFMUState`: continues from `saved` (also after an error). The
    /// model is restored in place when it was initialized from the same
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
                self.named(self.state)
            ));
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// A state call with a bad argument (NULL, a pointer that is not a live
    /// state, a buffer too small): an error with `message`.
    pub fn state_argument_error(&mut self, message: &str) -> Status {
        self.conclude(Err(message.to_string()))
    }

    /// A successful call that needs no instance data (`*FreeFMUState`,
    /// `*SerializedFMUStateSize`, `*SerializeFMUState`).
    pub fn state_call_ok(&mut self, func: &str) -> Status {
        let r = self.require_state_support(func).map(|()| Status::Ok);
        self.conclude(r)
    }
}
