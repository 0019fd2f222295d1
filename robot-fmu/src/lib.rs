//! # The exported robots' FMU binary
//!
//! `eigenmpc export --model FILE` writes a controller FMU and a plant FMU of
//! a user's robot without compiling anything: both carry this one binary
//! (renamed to their `modelIdentifier`) and tell it what they are in
//! `resources/eigenmpc-export.json`
//! ([`eigenmpc_fmu_models::exported::ExportSpec`]: kind, joint count, name,
//! the robot's parameters as start values). The model is
//! [`eigenmpc_fmu_models::exported::ExportedFmu`]; this crate adds the
//! exported symbols.

pub use eigenmpc_fmu_models::exported::ExportedFmu;

/// The 34 FMI 2.0 functions of the exported robots' FMUs.
pub mod fmi2_exports {
    fmi2_slave::export_fmi2!(crate::ExportedFmu);
}
