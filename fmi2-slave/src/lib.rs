//! # fmi2-slave
//!
//! Generic FMI 2.0 Co-Simulation plumbing, written once and shared by the
//! EigenMPC FMUs (like the Reference-FMUs' `src/`):
//!
//! - [`variables`]: the variable table ([`ModelDescription`], [`Variable`])
//!   that drives both value-reference dispatch and `modelDescription.xml`;
//! - [`instance`]: the state machine (instantiated, initialization mode,
//!   step complete, step failed, terminated, error), argument checks and the
//!   [`Model`] trait a model implements;
//! - [`logger`]: the host's logger callback with the categories
//!   `logStatusError`, `logStatusWarning`, `logEvents`, `logAll`;
//! - [`table`]: declarative tables parameterised by the number of joints,
//!   from which the variables, value references, settings, C constants and
//!   Markdown tables follow;
//! - [`resources`]: the `fmuResourceLocation` URI as a folder;
//! - [`state`]: FMU state save and restore, and its versioned byte form;
//! - [`abi`]: the C entry points, generic over the model, with null checks
//!   and `catch_unwind` (no panic crosses the C ABI);
//! - [`export_fmi2!`]: generates all 34 FMI 2.0 common + Co-Simulation
//!   functions as `#[no_mangle]` symbols.
//!
//! `#[no_mangle]` functions are exported from every cdylib that links the
//! rlib defining them, so this crate defines none: each FMU crate invokes
//! [`export_fmi2!`] exactly once, and no FMU crate links another.

/// The FMI 2.0 C types and constants (bindgen output of the standard
/// headers in `fmi-standard2/headers`, see `build.rs`).
#[allow(
    non_upper_case_globals,
    non_camel_case_types,
    non_snake_case,
    missing_docs,
    clippy::all
)]
pub mod ffi {
    include!(concat!(env!("OUT_DIR"), "/fmi2_bindings.rs"));
}

pub mod abi;
mod export;
pub mod instance;
pub mod logger;
pub mod model;
pub mod resources;
pub mod state;
pub mod table;
pub mod testing;
pub mod values;
pub mod variables;
pub mod xml;

pub use instance::Instance;
pub use logger::{Category, LOG_CATEGORIES, Logger, Status};
pub use model::{Context, Experiment, Model, ModelError, State};
pub use values::Values;
pub use variables::{
    BaseType, Causality, DefaultExperiment, EnumerationType, Initial, ModelDescription, Unit,
    Value, VarType, Variability, Variable,
};

/// Names of the 34 functions every FMI 2.0 Co-Simulation FMU exports.
pub const FMI2_CS_FUNCTIONS: [&str; 34] = [
    "fmi2GetTypesPlatform",
    "fmi2GetVersion",
    "fmi2SetDebugLogging",
    "fmi2Instantiate",
    "fmi2FreeInstance",
    "fmi2SetupExperiment",
    "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode",
    "fmi2Terminate",
    "fmi2Reset",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
    "fmi2GetFMUstate",
    "fmi2SetFMUstate",
    "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize",
    "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
];
