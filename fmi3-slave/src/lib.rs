//! # fmi3-slave
//!
//! The FMI 3.0 Co-Simulation plumbing, the sibling of `fmi2-slave` on the
//! version-neutral `fmu-core`: any [`Model`] that is exported with
//! `fmi2_slave::export_fmi2!` is exported as an FMI 3.0 Co-Simulation FMU
//! with [`export_fmi3!`], unchanged. Both macros may be used in the same
//! cdylib (the symbols are `fmi2*` and `fmi3*`).
//!
//! - [`layout`]: the FMI 3.0 view of a model's variables: FMI 2.0 scalars
//!   named `q[1]`, `q[2]`, ... (or `chart.coef[1,0]`, ...) become one array
//!   variable (`q`, `chart.coef`), the value references become unique over
//!   all types, and the independent variable `time` is added;
//! - [`instance`]: the FMI 3.0 Co-Simulation state machine (instantiated,
//!   initialization mode, step mode, terminated, error; no event mode) and
//!   argument checks around a [`Model`], on fmu-core's version-neutral
//!   instance core;
//! - [`xml`]: `modelDescription.xml` (FMI 3.0 schema);
//! - [`sink`]: the host's `fmi3LogMessageCallback` as the core logger's sink;
//! - [`abi`]: the C entry points, generic over the model, with null checks
//!   and `catch_unwind` (no panic crosses the C ABI);
//! - [`export_fmi3!`]: generates all 75 functions of
//!   `fmi3Functions.h` as `#[no_mangle]` symbols (Model Exchange, Scheduled
//!   Execution, event mode, clocks and the types the models do not use
//!   answer `fmi3Error` with a log line);
//! - [`testing`]: a host-side log capture for tests.
//!
//! `#[no_mangle]` functions are exported from every cdylib that links the
//! rlib defining them, so this crate defines none: each FMU crate invokes
//! [`export_fmi3!`] exactly once.

/// The FMI 3.0 C types, constants and function typedefs: bindgen output of
/// the standard headers in `fmi-standard3/headers`, checked in (see
/// `src/ffi/types.rs` and `scripts/fmi3-bindings.sh`).
#[allow(
    non_upper_case_globals,
    non_camel_case_types,
    non_snake_case,
    missing_docs,
    clippy::all
)]
pub mod ffi {
    include!("ffi/types.rs");
}

pub mod abi;
mod export;
pub mod instance;
pub mod layout;
pub mod sink;
pub mod testing;
pub mod xml;

pub use fmu_core::{
    BaseType, Category, Causality, Context, DefaultExperiment, EnumerationType, Experiment,
    Initial, LOG_CATEGORIES, LogSink, Logger, Model, ModelDescription, ModelError, State, Status,
    Unit, Value, Values, VarType, Variability, Variable,
};
pub use instance::Instance;
pub use layout::{Fmi3Type, Fmi3Variable, Layout};

/// Names of the 75 functions of `fmi3Functions.h`, all exported by
/// [`export_fmi3!`].
pub const FMI3_FUNCTIONS: [&str; 75] = [
    "fmi3GetVersion",
    "fmi3SetDebugLogging",
    "fmi3InstantiateModelExchange",
    "fmi3InstantiateCoSimulation",
    "fmi3InstantiateScheduledExecution",
    "fmi3FreeInstance",
    "fmi3EnterInitializationMode",
    "fmi3ExitInitializationMode",
    "fmi3EnterEventMode",
    "fmi3Terminate",
    "fmi3Reset",
    "fmi3GetFloat32",
    "fmi3GetFloat64",
    "fmi3GetInt8",
    "fmi3GetUInt8",
    "fmi3GetInt16",
    "fmi3GetUInt16",
    "fmi3GetInt32",
    "fmi3GetUInt32",
    "fmi3GetInt64",
    "fmi3GetUInt64",
    "fmi3GetBoolean",
    "fmi3GetString",
    "fmi3GetBinary",
    "fmi3GetClock",
    "fmi3SetFloat32",
    "fmi3SetFloat64",
    "fmi3SetInt8",
    "fmi3SetUInt8",
    "fmi3SetInt16",
    "fmi3SetUInt16",
    "fmi3SetInt32",
    "fmi3SetUInt32",
    "fmi3SetInt64",
    "fmi3SetUInt64",
    "fmi3SetBoolean",
    "fmi3SetString",
    "fmi3SetBinary",
    "fmi3SetClock",
    "fmi3GetNumberOfVariableDependencies",
    "fmi3GetVariableDependencies",
    "fmi3GetFMUState",
    "fmi3SetFMUState",
    "fmi3FreeFMUState",
    "fmi3SerializedFMUStateSize",
    "fmi3SerializeFMUState",
    "fmi3DeserializeFMUState",
    "fmi3GetDirectionalDerivative",
    "fmi3GetAdjointDerivative",
    "fmi3EnterConfigurationMode",
    "fmi3ExitConfigurationMode",
    "fmi3GetIntervalDecimal",
    "fmi3GetIntervalFraction",
    "fmi3GetShiftDecimal",
    "fmi3GetShiftFraction",
    "fmi3SetIntervalDecimal",
    "fmi3SetIntervalFraction",
    "fmi3SetShiftDecimal",
    "fmi3SetShiftFraction",
    "fmi3EvaluateDiscreteStates",
    "fmi3UpdateDiscreteStates",
    "fmi3EnterContinuousTimeMode",
    "fmi3CompletedIntegratorStep",
    "fmi3SetTime",
    "fmi3SetContinuousStates",
    "fmi3GetContinuousStateDerivatives",
    "fmi3GetEventIndicators",
    "fmi3GetContinuousStates",
    "fmi3GetNominalsOfContinuousStates",
    "fmi3GetNumberOfEventIndicators",
    "fmi3GetNumberOfContinuousStates",
    "fmi3EnterStepMode",
    "fmi3GetOutputDerivatives",
    "fmi3DoStep",
    "fmi3ActivateModelPartition",
];
