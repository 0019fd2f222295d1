//! # fmi2-slave
//!
//! The FMI 2.0 Co-Simulation plumbing, written once and shared by the
//! EigenMPC FMUs (like the Reference-FMUs' `src/`), on the version-neutral
//! `fmu-core` (the [`Model`] trait, values, variables, the variable table
//! and its generators, the state codec, logging and resources; re-exported
//! here under their old paths):
//!
//! - [`instance`]: the FMI 2.0 state machine (instantiated, initialization
//!   mode, step complete, step failed, terminated, error) and argument
//!   checks around a [`Model`], on fmu-core's version-neutral instance core;
//! - [`xml`]: `modelDescription.xml` (FMI 2.0 schema), the GUID and the
//!   documentation page;
//! - [`sink`]: the host's `fmi2CallbackLogger` as the core logger's sink;
//! - [`abi`]: the C entry points, generic over the model, with null checks
//!   and `catch_unwind` (no panic crosses the C ABI);
//! - [`export_fmi2!`]: generates all 34 FMI 2.0 common + Co-Simulation
//!   functions as `#[no_mangle]` symbols.
//!
//! `#[no_mangle]` functions are exported from every cdylib that links the
//! rlib defining them, so this crate defines none: each FMU crate invokes
//! [`export_fmi2!`] exactly once, and no FMU crate links another.

/// The FMI 2.0 C types and constants, and with the feature `loader` the
/// `Fmi2Binding` that loads a built FMU library (hosts, tests): bindgen output
/// of the standard headers in `fmi-standard2/headers`, checked in (see
/// `src/ffi/types.rs`).
#[allow(
    non_upper_case_globals,
    non_camel_case_types,
    non_snake_case,
    missing_docs,
    clippy::all
)]
pub mod ffi {
    include!("ffi/types.rs");
    #[cfg(feature = "loader")]
    include!("ffi/loader.rs");
}

pub mod abi;
mod export;
pub mod instance;
pub mod sink;
pub mod testing;
pub mod xml;

pub use fmu_core::{
    BaseType, Category, Causality, Context, DefaultExperiment, EnumerationType, Experiment,
    Initial, LOG_CATEGORIES, LogSink, Logger, Model, ModelDescription, ModelError, State, Status,
    Unit, Value, Values, VarType, Variability, Variable,
};
pub use fmu_core::{logger, model, resources, state, table, values, variables};
pub use instance::Instance;

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
