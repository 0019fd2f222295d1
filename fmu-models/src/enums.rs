//! The enumeration parameters (`variant`, `qp_solver`, `chart_source`): one table each of
//! (name, item, library value, description), used by the FMU variable
//! tables, the C API and the C header.

use crate::controller::settings::{AdaptEstimator, ChartSource, StateEstimator};
use eigenmpc::adapt::AdaptationStatus;
use eigenmpc::mpc::{QpBackend, VARIANTS, Variant};
use fmi2_slave::EnumerationType;

/// One item of an enumeration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Item<T> {
    /// Item name (`curved`).
    pub name: &'static str,
    /// Integer value of the item in the FMU and the C API.
    pub item: i32,
    /// The library value it selects.
    pub value: T,
    /// One-line description.
    pub description: &'static str,
}

/// An enumeration: its FMI type name, the parameter that uses it and the items.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Enumeration<T: 'static> {
    /// FMI `SimpleType` name (`Variant`).
    pub type_name: &'static str,
    /// Name of the parameter (`variant`).
    pub parameter: &'static str,
    /// The items.
    pub items: &'static [Item<T>],
}

impl<T: Copy + PartialEq + std::fmt::Debug + 'static> Enumeration<T> {
    /// The library value of `item`; the message lists the items.
    pub fn value(&self, item: i32) -> Result<T, String> {
        self.items
            .iter()
            .find(|i| i.item == item)
            .map(|i| i.value)
            .ok_or_else(|| {
                let list: Vec<String> = self
                    .items
                    .iter()
                    .map(|i| format!("{} {}", i.item, i.name))
                    .collect();
                format!(
                    "{} = {item} is not an item of {} ({})",
                    self.parameter,
                    self.type_name,
                    list.join(", ")
                )
            })
    }

    /// The library value of the item called `name`; the message lists the
    /// names (a command line's `--adapt-estimator state_and_parameters`).
    pub fn named(&self, name: &str) -> Result<T, String> {
        self.items
            .iter()
            .find(|i| i.name == name)
            .map(|i| i.value)
            .ok_or_else(|| {
                let names: Vec<&str> = self.items.iter().map(|i| i.name).collect();
                format!(
                    "{} = {name} is not one of {}",
                    self.parameter,
                    names.join(", ")
                )
            })
    }

    /// The item of `value` (every library value has one: tested).
    pub fn item(&self, value: T) -> i32 {
        self.items
            .iter()
            .find(|i| i.value == value)
            .map(|i| i.item)
            .unwrap_or_else(|| panic!("{value:?} has no item in {}", self.type_name))
    }

    /// The FMI enumeration type.
    pub fn fmi_type(&self) -> EnumerationType {
        EnumerationType {
            name: self.type_name.into(),
            items: self
                .items
                .iter()
                .map(|i| (i.name.into(), i.item, i.description.into()))
                .collect(),
        }
    }
}

/// The `variant` items, one per row of the core's variant table
/// ([`VARIANTS`]: items 1, 2, ... in its order, its names and descriptions).
const VARIANT_ITEMS: [Item<Variant>; VARIANTS.len()] = {
    let mut items = [Item {
        name: "",
        item: 0,
        value: Variant::Curved,
        description: "",
    }; VARIANTS.len()];
    let mut i = 0;
    while i < VARIANTS.len() {
        let row = &VARIANTS[i];
        items[i] = Item {
            name: row.name,
            item: i as i32 + 1,
            value: row.variant,
            description: row.description,
        };
        i += 1;
    }
    items
};

/// `variant`: which EigenMPC cost.
pub const VARIANT: Enumeration<Variant> = Enumeration {
    type_name: "Variant",
    parameter: "variant",
    items: &VARIANT_ITEMS,
};

/// `qp_solver`: the QP solver of the real-time iteration.
pub const QP_SOLVER: Enumeration<QpBackend> = Enumeration {
    type_name: "QpSolver",
    parameter: "qp_solver",
    items: &[
        Item {
            name: "clarabel",
            item: 1,
            value: QpBackend::Clarabel,
            description: "clarabel: general-purpose interior point (reference)",
        },
        Item {
            name: "riccati",
            item: 2,
            value: QpBackend::Riccati,
            description: "Riccati-recursion interior point exploiting the stage structure",
        },
    ],
};

/// `chart_source`: where the reference (eigenvector, chart) comes from.
pub const CHART_SOURCE: Enumeration<ChartSource> = Enumeration {
    type_name: "ChartSource",
    parameter: "chart_source",
    items: &[
        Item {
            name: "computed",
            item: 1,
            value: ChartSource::Computed,
            description: "From the model: linear mode `mode`, its eigenmode family over energy",
        },
        Item {
            name: "parameters",
            item: 2,
            value: ChartSource::Parameters,
            description: "The c[j] and chart.coef[j,k] parameters (one fixed chart)",
        },
    ],
};

/// `state_estimator`: what filters the measured state.
pub const STATE_ESTIMATOR: Enumeration<StateEstimator> = Enumeration {
    type_name: "StateEstimator",
    parameter: "state_estimator",
    items: &[
        Item {
            name: "none",
            item: 1,
            value: StateEstimator::None,
            description: "The measured q, qd are used as they are",
        },
        Item {
            name: "ekf",
            item: 2,
            value: StateEstimator::Ekf,
            description: "Extended Kalman filter on the controller's model and the applied torque",
        },
    ],
};

/// `adapt_estimator`: where the adaptation's candidate models come from.
pub const ADAPT_ESTIMATOR: Enumeration<AdaptEstimator> = Enumeration {
    type_name: "AdaptEstimator",
    parameter: "adapt_estimator",
    items: &[
        Item {
            name: "energy_balance",
            item: 1,
            value: AdaptEstimator::EnergyBalance,
            description: "The energy balance over windows (recursive least squares)",
        },
        Item {
            name: "state_and_parameters",
            item: 2,
            value: AdaptEstimator::StateAndParameters,
            description: "The state and the base parameters estimated together every sample, \
                          the loop excited over the first 40 s",
        },
    ],
};

/// `adaptation_status`: what the online adaptation is doing (an output).
pub const ADAPTATION_STATUS: Enumeration<AdaptationStatus> = Enumeration {
    type_name: "AdaptationStatus",
    parameter: "adaptation_status",
    items: &[
        Item {
            name: "idle",
            item: 1,
            value: AdaptationStatus::Idle,
            description: "adapt = false, or no window has informed the estimate yet",
        },
        Item {
            name: "excitation",
            item: 2,
            value: AdaptationStatus::Excitation,
            description: "Gathering the information the estimate lacks",
        },
        Item {
            name: "learning",
            item: 3,
            value: AdaptationStatus::Learning,
            description: "Estimating; a candidate model is validated or a new model supervised",
        },
        Item {
            name: "converged",
            item: 4,
            value: AdaptationStatus::Converged,
            description: "The estimate agrees with the model in use",
        },
        Item {
            name: "reverted",
            item: 5,
            value: AdaptationStatus::Reverted,
            description: "The supervisor took the last model back (the loop did worse with it)",
        },
        Item {
            name: "supervisor",
            item: 6,
            value: AdaptationStatus::Supervisor,
            description: "The stall supervisor released the torque: the last model taken went \
                          back, or the estimate is being tried",
        },
    ],
};

/// `variant` item: straight EigenMPC.
pub const VARIANT_STRAIGHT: i32 = VARIANT.items[0].item;
/// `variant` item: curved EigenMPC.
pub const VARIANT_CURVED: i32 = VARIANT.items[1].item;
/// `variant` item: hybrid EigenMPC.
pub const VARIANT_HYBRID: i32 = VARIANT.items[2].item;
/// `qp_solver` item: clarabel.
pub const QP_SOLVER_CLARABEL: i32 = QP_SOLVER.items[0].item;
/// `qp_solver` item: Riccati (default).
pub const QP_SOLVER_RICCATI: i32 = QP_SOLVER.items[1].item;
/// `state_estimator` item: none (default).
pub const STATE_ESTIMATOR_NONE: i32 = STATE_ESTIMATOR.items[0].item;
/// `state_estimator` item: extended Kalman filter.
pub const STATE_ESTIMATOR_EKF: i32 = STATE_ESTIMATOR.items[1].item;
/// `adapt_estimator` item: the energy balance (default).
pub const ADAPT_ESTIMATOR_ENERGY_BALANCE: i32 = ADAPT_ESTIMATOR.items[0].item;
/// `adapt_estimator` item: the state and parameters estimated together.
pub const ADAPT_ESTIMATOR_STATE_AND_PARAMETERS: i32 = ADAPT_ESTIMATOR.items[1].item;
/// `chart_source` item: computed from the model (default).
pub const CHART_SOURCE_COMPUTED: i32 = CHART_SOURCE.items[0].item;
/// `chart_source` item: the chart parameters.
pub const CHART_SOURCE_PARAMETERS: i32 = CHART_SOURCE.items[1].item;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_library_value_has_one_item_and_back() {
        for row in VARIANTS {
            assert_eq!(VARIANT.value(VARIANT.item(row.variant)), Ok(row.variant));
            assert_eq!(
                VARIANT.items[VARIANT.item(row.variant) as usize - 1].name,
                row.name
            );
        }
        for b in QpBackend::ALL {
            assert_eq!(QP_SOLVER.value(QP_SOLVER.item(b)), Ok(b));
        }
        assert_eq!((VARIANT_STRAIGHT, VARIANT_CURVED), (1, 2));
        assert_eq!((QP_SOLVER_CLARABEL, QP_SOLVER_RICCATI), (1, 2));
        for c in [ChartSource::Computed, ChartSource::Parameters] {
            assert_eq!(CHART_SOURCE.value(CHART_SOURCE.item(c)), Ok(c));
        }
        assert_eq!((CHART_SOURCE_COMPUTED, CHART_SOURCE_PARAMETERS), (1, 2));
        for e in [StateEstimator::None, StateEstimator::Ekf] {
            assert_eq!(STATE_ESTIMATOR.value(STATE_ESTIMATOR.item(e)), Ok(e));
        }
        assert_eq!((STATE_ESTIMATOR_NONE, STATE_ESTIMATOR_EKF), (1, 2));
        for e in [
            AdaptEstimator::EnergyBalance,
            AdaptEstimator::StateAndParameters,
        ] {
            assert_eq!(ADAPT_ESTIMATOR.value(ADAPT_ESTIMATOR.item(e)), Ok(e));
        }
        assert_eq!(
            (
                ADAPT_ESTIMATOR_ENERGY_BALANCE,
                ADAPT_ESTIMATOR_STATE_AND_PARAMETERS
            ),
            (1, 2)
        );
        assert_eq!(
            ADAPT_ESTIMATOR.named("state_and_parameters"),
            Ok(AdaptEstimator::StateAndParameters)
        );
        assert_eq!(
            ADAPT_ESTIMATOR.named("ekf"),
            Err("adapt_estimator = ekf is not one of energy_balance, state_and_parameters".into())
        );
        for a in [
            AdaptationStatus::Idle,
            AdaptationStatus::Excitation,
            AdaptationStatus::Learning,
            AdaptationStatus::Converged,
            AdaptationStatus::Reverted,
            AdaptationStatus::Supervisor,
        ] {
            assert_eq!(ADAPTATION_STATUS.value(ADAPTATION_STATUS.item(a)), Ok(a));
        }
        assert_eq!(VARIANT_HYBRID, 3);
        assert_eq!(
            VARIANT.value(4),
            Err("variant = 4 is not an item of Variant (1 straight, 2 curved, 3 hybrid)".into())
        );
        assert_eq!(
            QP_SOLVER.value(0),
            Err("qp_solver = 0 is not an item of QpSolver (1 clarabel, 2 riccati)".into())
        );
    }
}
