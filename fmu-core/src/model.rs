//! What a model is to the FMU plumbing, apart from any one instance: the
//! [`Model`] trait a model implements, the [`Context`] it is called with,
//! its errors, the run's [`Experiment`] and the instance [`State`]s. The
//! state machine ([`crate::instance`]) and the FMU-state codec
//! ([`crate::state`]) both build on this module and not on each other.

use crate::logger::Logger;
use crate::values::Values;
use crate::variables::ModelDescription;
use std::fmt;
use std::path::Path;

/// The FMI 2.0 Co-Simulation states an instance can be in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum State {
    /// After `fmi2Instantiate` or `fmi2Reset`.
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    InitializationMode,
    /// Ready for `fmi2DoStep`.
    StepComplete,
    /// The last `fmi2DoStep` returned `fmi2Discard`.
    StepFailed,
    /// After `fmi2Terminate`.
    Terminated,
    /// A call returned `fmi2Error`: only getters (for diagnostics),
    /// `fmi2Reset` and `fmi2FreeInstance` are allowed.
    Error,
}

impl State {
    /// The FMI 2.0 name of the state (`stepComplete`, ...).
    pub fn name(self) -> &'static str {
        match self {
            State::Instantiated => "instantiated",
            State::InitializationMode => "initializationMode",
            State::StepComplete => "stepComplete",
            State::StepFailed => "stepFailed",
            State::Terminated => "terminated",
            State::Error => "error",
        }
    }
}

impl fmt::Display for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Settings of `fmi2SetupExperiment`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Experiment {
    /// Tolerance requested by the host, if any.
    pub tolerance: Option<f64>,
    /// Start time (s).
    pub start_time: f64,
    /// Stop time (s), if defined.
    pub stop_time: Option<f64>,
}

impl Default for Experiment {
    fn default() -> Self {
        Self {
            tolerance: None,
            start_time: 0.0,
            stop_time: None,
        }
    }
}

/// What a model sees of its environment during a call.
pub struct Context<'a> {
    /// The host's logger (use `warning` to make the call return `fmi2Warning`).
    pub log: &'a Logger,
    /// The experiment set up by the host.
    pub experiment: &'a Experiment,
    /// The FMU's unpacked `resources/` folder, when the host gave one.
    pub resources: Option<&'a Path>,
}

/// Why a model call failed.
#[derive(Clone, Debug, PartialEq)]
pub enum ModelError {
    /// Invalid parameters or a failed computation: `fmi2Error`.
    Error(String),
    /// `fmi2DoStep` only reached `last_successful_time`: `fmi2Discard`.
    Discard {
        /// What went wrong.
        message: String,
        /// Time up to which the outputs are valid.
        last_successful_time: f64,
    },
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ModelError::Error(m) => f.write_str(m),
            ModelError::Discard {
                message,
                last_successful_time,
            } => write!(f, "{message} (valid up to t = {last_successful_time})"),
        }
    }
}

/// A co-simulation model behind the FMI 2.0 plumbing.
///
/// The plumbing owns the [`Values`]: it checks every value the host sets
/// (type, value reference, state, causality, finiteness, min/max) before it
/// reaches the store, so a model only validates relations between values.
pub trait Model: Sized + Send + 'static {
    /// The model's identity and variable table (drives dispatch and XML).
    fn description() -> ModelDescription;

    /// The description of an instance whose FMU has its `resources/` folder
    /// at `resources` (`None`: the host gave none). A model whose variables
    /// or start values come from its archive (a robot exported by `eigenmpc
    /// export`) reads them there; an error makes `fmi2Instantiate` fail with
    /// that message. The default is [`Model::description`].
    fn description_for(resources: Option<&Path>) -> Result<ModelDescription, String> {
        let _ = resources;
        Ok(Self::description())
    }

    /// Builds the model from the parameters and inputs in `values` and writes
    /// the outputs for them. Called at `fmi2ExitInitializationMode`, and
    /// earlier when the host reads a calculated value in initialization mode.
    fn initialize(values: &mut Values, ctx: &Context) -> Result<Self, ModelError>;

    /// Advances from `t` to `t + h` with the current inputs and writes the
    /// outputs at `t + h`. Must not allocate (real-time discipline).
    fn do_step(
        &mut self,
        values: &mut Values,
        t: f64,
        h: f64,
        ctx: &Context,
    ) -> Result<(), ModelError>;

    /// Everything a later step depends on beyond the values (the FMU state
    /// of `fmi2GetFMUstate`), as bytes for [`Model::restore_state`]. Only
    /// called when the description sets `can_save_state`. May allocate.
    fn save_state(&self) -> Result<Vec<u8>, ModelError> {
        Err(ModelError::Error("this model cannot save its state".into()))
    }

    /// Takes over a state from [`Model::save_state`] of a model that was
    /// initialized from the same values (this one, or one just built from
    /// them); `values` are the restored values. After it, the model
    /// continues bit for bit as the one that saved the state. Bad bytes
    /// (a crafted buffer: the plumbing has checked the checksum) are an error.
    fn restore_state(
        &mut self,
        state: &[u8],
        values: &Values,
        ctx: &Context,
    ) -> Result<(), ModelError> {
        let _ = (state, values, ctx);
        Err(ModelError::Error(
            "this model cannot restore a state".into(),
        ))
    }

    /// Tunable parameters changed between steps: validate and take them over.
    /// On error the plumbing restores the previous values.
    fn update_tunables(&mut self, values: &mut Values, ctx: &Context) -> Result<(), ModelError> {
        let _ = (values, ctx);
        Ok(())
    }
}
