//! # EigenMPC FMU
//!
//! The EigenMPC controller (paper, section IV; `eigenmpc::mpc::Controller`)
//! for the double pendulum as an FMI 2.0 Co-Simulation FMU, plus a plain C
//! API ([`capi`]) for embedding the controller without FMI. Both are in the
//! same shared library (`libeigenmpc_fmu.so`, packaged as `EigenMPC.so`).
//!
//! The model, its variable table and its timing are the 2-joint product of
//! the generic controller in `eigenmpc_fmu_models::controller`; this crate
//! adds the exported symbols and the C API.

pub mod capi;
mod status;

pub use eigenmpc_fmu_models::controller::settings::{self, ChainController, Settings, Tuning};
pub use eigenmpc_fmu_models::controller::start_values::start_values;
pub use eigenmpc_fmu_models::controller::{ControllerProduct, description};
pub use eigenmpc_fmu_models::enums::{
    CHART_SOURCE, CHART_SOURCE_COMPUTED, CHART_SOURCE_PARAMETERS, QP_SOLVER, QP_SOLVER_CLARABEL,
    QP_SOLVER_RICCATI, STATE_ESTIMATOR, STATE_ESTIMATOR_EKF, STATE_ESTIMATOR_NONE, VARIANT,
    VARIANT_CURVED, VARIANT_HYBRID, VARIANT_STRAIGHT,
};
pub use eigenmpc_fmu_models::products::{
    DEFAULT_CHART_14J, DEFAULT_EIGENVECTOR, EigenMpc2, EigenMpcFmu,
};
pub use status::*;

/// The controller behind the FMU and the C API.
pub type PendulumController = ChainController<2, 4>;

/// Introduction of the FMU's documentation page.
pub fn documentation_html() -> String {
    eigenmpc_fmu_models::controller::docs::documentation_html(2)
}

/// The 34 FMI 2.0 functions of this FMU.
pub mod fmi2_exports {
    fmi2_slave::export_fmi2!(crate::EigenMpcFmu);
}
