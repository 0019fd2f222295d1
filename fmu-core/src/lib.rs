//! # fmu-core
//!
//! The half of the FMU plumbing that does not depend on the FMI version: what
//! a model is and what it is called with, its values and variables, the
//! declarative variable table with its generators, the FMU-state codec,
//! logging and resource folders. An FMI version is a sibling crate on top
//! (`fmi2-slave`: the FMI 2.0 state machine, C functions, XML and headers;
//! `fmi3-slave` the same for FMI 3.0), so a model written against this crate
//! runs under either.
//!
//! - [`model`]: the [`Model`] trait, its [`Context`] and errors;
//! - [`variables`]: [`ModelDescription`], [`Variable`] and their types;
//! - [`values`]: the current values of an instance, by value reference;
//! - [`table`]: declarative tables parameterised by the number of joints,
//!   from which the variables, value references, settings, C constants and
//!   Markdown tables follow;
//! - [`abi`]: the C entry points' helpers (slices, panics caught, FMU-state
//!   pointers);
//! - [`instance`]: the version-neutral half of an instance ([`instance::Core`]):
//!   values, life-cycle state, model and clock, the transitions both
//!   versions share and FMU state save / restore;
//! - [`state`]: FMU state save and restore, and its versioned byte form;
//! - [`logger`]: the log categories and their filter, over a [`LogSink`]
//!   that each FMI version implements with its host callback;
//! - [`resources`]: the resource location URI as a folder.

pub mod abi;
pub mod instance;
pub mod logger;
pub mod model;
pub mod resources;
pub mod state;
pub mod table;
pub mod values;
pub mod variables;

pub use logger::{Category, LOG_CATEGORIES, LogSink, Logger, Status};
pub use model::{Context, Experiment, Model, ModelError, State};
pub use values::Values;
pub use variables::{
    BaseType, Causality, DefaultExperiment, EnumerationType, Initial, ModelDescription, Unit,
    Value, VarType, Variability, Variable,
};
