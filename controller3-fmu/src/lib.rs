//! # EigenMPC3 FMU
//!
//! The EigenMPC controller for a planar chain of three links (by default
//! 1 kg point masses at the tips of 1 m links, g = 9.81; rigid links,
//! motors and friction as parameters) as an FMI 2.0 Co-Simulation FMU: the
//! 3-joint product of `eigenmpc_fmu_models::controller`. Its default chart is
//! the in-phase eigenmode of the default chain at 14 J.

pub use eigenmpc_fmu_models::products::{EigenMpc3, EigenMpc3Fmu};

/// Introduction of the FMU's documentation page.
pub fn documentation_html() -> String {
    eigenmpc_fmu_models::controller::docs::documentation_html(3)
}

/// The 34 FMI 2.0 functions of this FMU.
pub mod fmi2_exports {
    fmi2_slave::export_fmi2!(crate::EigenMpc3Fmu);
}
