//! # EigenMPC C library
//!
//! The plain C API ([`capi`]) for embedding the EigenMPC controller (paper,
//! section IV; `eigenmpc::mpc::Controller`) of any supported joint count
//! without FMI, in the shared library `libeigenmpc_fmu.so` (header
//! `include/eigenmpc.h`). The same library exports the FMI 2.0 functions of
//! the `EigenMPC` model (the 2-joint product of the generic controller in
//! `eigenmpc_fmu_models::controller`), for C programs that link an FMU's
//! functions directly. The packaged `EigenMPC.fmu` carries the one FMU
//! binary (`eigenmpc-robot-fmu`) instead, told by its resources that it is
//! this model.

pub mod capi;
mod status;

pub use eigenmpc_fmu_models::controller::settings::{self, ChainController, Settings, Tuning};
pub use eigenmpc_fmu_models::controller::start_values::start_values;
pub use eigenmpc_fmu_models::controller::{ControllerProduct, description};
pub use eigenmpc_fmu_models::enums::{
    ADAPT_ESTIMATOR, ADAPT_ESTIMATOR_ENERGY_BALANCE, ADAPT_ESTIMATOR_STATE_AND_PARAMETERS,
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

/// The 34 FMI 2.0 functions of this FMU.
pub mod fmi2_exports {
    fmi2_slave::export_fmi2!(crate::EigenMpcFmu);
}
