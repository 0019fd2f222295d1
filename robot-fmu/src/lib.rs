//! # The exported robots' FMU binary
//!
//! `eigenmpc export --model FILE` writes a controller FMU and a plant FMU of
//! a user's robot without compiling anything: both carry this one binary
//! (renamed to their `modelIdentifier`) and tell it what they are in
//! `resources/eigenmpc-export.json`
//! ([`eigenmpc_fmu_models::exported::ExportSpec`]: kind, joint count, name,
//! the robot's parameters as start values). The model is
//! [`eigenmpc_fmu_models::exported::ExportedFmu`]; this crate adds the
//! exported symbols of both FMI versions: an FMI 2.0 archive and an FMI 3.0
//! archive of the same robot carry the same binary (the functions are
//! `fmi2*` and `fmi3*`).

pub use eigenmpc_fmu_models::exported::ExportedFmu;

/// The 34 FMI 2.0 functions of the exported robots' FMUs.
pub mod fmi2_exports {
    fmi2_slave::export_fmi2!(crate::ExportedFmu);
}

/// The 75 FMI 3.0 functions of the exported robots' FMUs (Co-Simulation;
/// the others answer fmi3Error with a message).
pub mod fmi3_exports {
    fmi3_slave::export_fmi3!(crate::ExportedFmu);
}
