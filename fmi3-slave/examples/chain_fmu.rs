//! The test chain of masses (tests/common) as a real shared library that
//! is an FMI 2.0 and an FMI 3.0 FMU at once: both export macros in one
//! module, as a model crate would write them. The tests check its exported
//! symbols and run it under fmpy (tests/cdylib.rs).

#[path = "../tests/common/mod.rs"]
mod common;

/// The FMI functions of the chain, both versions.
pub mod fmi_exports {
    fmi2_slave::export_fmi2!(crate::common::Chain);
    fmi3_slave::export_fmi3!(crate::common::Chain);
}
