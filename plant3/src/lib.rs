//! # TriplePendulum FMU
//!
//! A planar chain of three links (by default 1 kg point masses at the tips
//! of 1 m links; rigid links, motors, friction and springs as parameters) as
//! an FMI 2.0 Co-Simulation FMU: the 3-link product of
//! `eigenmpc_fmu_models::plant`.

pub use eigenmpc_fmu_models::products::TriplePendulumFmu;

/// Introduction of the FMU's documentation page.
pub fn documentation_html() -> String {
    eigenmpc_fmu_models::plant::docs::documentation_html(3)
}

/// The 34 FMI 2.0 functions of this FMU.
pub mod fmi2_exports {
    fmi2_slave::export_fmi2!(crate::TriplePendulumFmu);
}
