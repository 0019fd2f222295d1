//! # DoublePendulum FMU
//!
//! The paper's double pendulum (section V; by default point masses at the
//! link tips, optionally rigid links, geared motors, friction and springs)
//! as an FMI 2.0 Co-Simulation FMU: joint torques in, joint angles, speeds
//! and energy out. The model and its variable table are the 2-link product
//! of the generic plant in `eigenmpc_fmu_models::plant`; this crate adds the
//! exported symbols.

pub use eigenmpc_fmu_models::plant::settings::PlantSettings;
pub use eigenmpc_fmu_models::products::DoublePendulumFmu;

/// Introduction of the FMU's documentation page.
pub fn documentation_html() -> String {
    eigenmpc_fmu_models::plant::docs::documentation_html(2)
}

/// The 34 FMI 2.0 functions of this FMU.
pub mod fmi2_exports {
    fmi2_slave::export_fmi2!(crate::DoublePendulumFmu);
}
