//! The FMUs this workspace ships: each pair is `eigenmpc export` of a robot
//! file in `robots/` under the pair's own names (the value references are
//! the variable table's, the same for every export of that joint count).
//! Adding a shipped pair is one row of [`SHIPPED`].

use eigenmpc_fmu_models::controller::ControllerProduct;
use eigenmpc_fmu_models::plant::PlantProduct;
use eigenmpc_fmu_models::products::{
    DoublePendulumPlant, EigenMpc2, EigenMpc3, TriplePendulumPlant,
};

/// One shipped FMU.
pub struct ShippedFmu {
    /// `modelIdentifier` (FMU and binary file name).
    pub model_identifier: &'static str,
    /// `description`.
    pub description: &'static str,
    /// Prefix of its constants (value references, enumeration items) in
    /// the C header.
    pub header_prefix: &'static str,
}

/// One shipped pair: a robot file, the energy of its reference, the two
/// FMUs and the SSP that couples them.
pub struct ShippedPair {
    /// The robot file, relative to the workspace root.
    pub robot: &'static str,
    /// `E_ref` (J) and the energy of the chart the controller starts with.
    pub energy: f64,
    /// The controller FMU.
    pub controller: ShippedFmu,
    /// The plant FMU.
    pub plant: ShippedFmu,
    /// The SSP archive's name.
    pub ssp: &'static str,
    /// Joints of the robot (checked against the file).
    pub joints: usize,
}

/// The shipped pairs: the paper's double pendulum and a 3-link chain, both
/// at 14 J.
pub const SHIPPED: &[ShippedPair] = &[
    ShippedPair {
        robot: "robots/paper-double-pendulum.yml",
        energy: 14.0,
        controller: ShippedFmu {
            model_identifier: <EigenMpc2 as ControllerProduct<2>>::MODEL_NAME,
            description: <EigenMpc2 as ControllerProduct<2>>::DESCRIPTION,
            header_prefix: "EIGENMPC_",
        },
        plant: ShippedFmu {
            model_identifier: <DoublePendulumPlant as PlantProduct<2>>::MODEL_NAME,
            description: <DoublePendulumPlant as PlantProduct<2>>::DESCRIPTION,
            header_prefix: "DOUBLE_PENDULUM_",
        },
        ssp: "EigenMPC-DoublePendulum",
        joints: 2,
    },
    ShippedPair {
        robot: "robots/three-link-point-masses.yml",
        energy: 14.0,
        controller: ShippedFmu {
            model_identifier: <EigenMpc3 as ControllerProduct<3>>::MODEL_NAME,
            description: <EigenMpc3 as ControllerProduct<3>>::DESCRIPTION,
            header_prefix: "EIGENMPC3_",
        },
        plant: ShippedFmu {
            model_identifier: <TriplePendulumPlant as PlantProduct<3>>::MODEL_NAME,
            description: <TriplePendulumPlant as PlantProduct<3>>::DESCRIPTION,
            header_prefix: "TRIPLE_PENDULUM_",
        },
        ssp: "EigenMPC3-TriplePendulum",
        joints: 3,
    },
];

impl ShippedPair {
    /// The SSP of this pair.
    pub fn ssp_spec(&self) -> crate::ssp::SspSpec<'static> {
        crate::ssp::SspSpec {
            name: self.ssp,
            controller: self.controller.model_identifier,
            plant: self.plant.model_identifier,
            joints: self.joints,
        }
    }

    /// The FMUs' names and descriptions.
    pub fn names(&self) -> crate::export::PairNames {
        let named = |f: &ShippedFmu| crate::export::Named {
            model_name: f.model_identifier.into(),
            description: f.description.into(),
        };
        crate::export::PairNames {
            controller: named(&self.controller),
            plant: named(&self.plant),
        }
    }
}
