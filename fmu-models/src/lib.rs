//! # EigenMPC FMU models
//!
//! The controller ([`controller`]) and plant ([`plant`]) FMUs generic in the
//! number of joints `N`, each defined by one declarative variable table
//! ([`fmi2_slave::table`]) from which the value references, the
//! `modelDescription.xml`, the documentation page, the book's variable tables, the C
//! header's constants and the start-value files follow.
//!
//! This crate exports no symbols: the one FMU binary (`robot-fmu`) invokes
//! `fmi2_slave::export_fmi2!` for [`exported`]'s model, which is the
//! controller or the plant of any supported joint count as its resources
//! say; the C library (`controller-fmu`) for the 2-joint product of
//! [`products`]. The shipped FMUs are exports of robot files (fmu-build);
//! [`products`] keeps their names and defaults (the C API's defaults, the
//! tests).
//!
//! - [`enums`]: the `variant` and `qp_solver` enumerations (name, item,
//!   description), one table used by the FMU and the C API;
//! - [`exported`]: the model of every robot `eigenmpc export` writes (one
//!   binary, any joint count, controller or plant, told by its resources);
//! - [`chain`]: the rigid-link parameters shared by controller and plant;
//! - [`units`]: unit definitions;
//! - [`readme`]: the FMU variable tables of the book (`docs/book/`).

pub mod chain;
pub mod controller;
pub mod enums;
#[cfg(feature = "export")]
pub mod exported;
pub mod plant;
pub mod products;
pub mod readme;
pub mod units;
