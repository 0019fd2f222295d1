//! The variable tables: valid FMI 2.0 descriptions, the original 2-joint
//! value references kept, the 3-joint layout, C constants and the book's tables.

use eigenmpc_fmu_models::enums::CHART_SOURCE_PARAMETERS;
use eigenmpc_fmu_models::products::*;
use fmi2_slave::{BaseType, Model, ModelDescription, Value};

fn descriptions() -> Vec<ModelDescription> {
    vec![
        EigenMpcFmu::description(),
        EigenMpc3Fmu::description(),
        DoublePendulumFmu::description(),
        TriplePendulumFmu::description(),
    ]
}

#[test]
fn every_description_is_valid() {
    for d in descriptions() {
        if let Err(e) = d.validate() {
            panic!("{}: {e}", d.model_name);
        }
    }
}

fn vr(d: &ModelDescription, name: &str) -> (BaseType, u32) {
    let v = d
        .variable(name)
        .unwrap_or_else(|| panic!("{}: no {name}", d.model_name));
    (v.var_type.base(), v.value_reference)
}

/// Every variable of the original `EigenMPC.fmu` keeps its name and value
/// reference (existing start-value files and hosts keep working).
#[test]
fn the_two_joint_controller_keeps_the_original_value_references() {
    let d = EigenMpcFmu::description();
    let real = [
        ("q[1]", 0),
        ("q[2]", 1),
        ("qd[1]", 2),
        ("qd[2]", 3),
        ("tau[1]", 4),
        ("tau[2]", 5),
        ("energy", 6),
        ("solve_time", 7),
        ("E_ref", 8),
        ("alpha", 9),
        ("beta", 10),
        ("w_E", 11),
        ("w_x", 12),
        ("w_xd", 13),
        ("w_F", 14),
        ("tau_max", 15),
        ("sample_period", 16),
        ("m[1]", 17),
        ("m[2]", 18),
        ("l[1]", 19),
        ("l[2]", 20),
        ("g", 21),
        ("c[1]", 22),
        ("c[2]", 23),
    ];
    for (name, r) in real {
        assert_eq!(vr(&d, name), (BaseType::Real, r), "{name}");
    }
    for j in 1..=2 {
        for k in 0..10 {
            let name = format!("chart.coef[{j},{k}]");
            assert_eq!(
                vr(&d, &name),
                (BaseType::Real, 100 + 10 * (j - 1) + k),
                "{name}"
            );
        }
    }
    let integer = [
        ("qp_iterations", 0),
        ("solver_status", 1),
        ("variant", 2),
        ("horizon", 3),
        ("qp_solver", 4),
    ];
    for (name, r) in integer {
        assert_eq!(vr(&d, name), (BaseType::Integer, r), "{name}");
    }
    // the new rigid-link parameters follow the chart block
    assert_eq!(vr(&d, "r[1]"), (BaseType::Real, 120));
    assert_eq!(vr(&d, "I[1]"), (BaseType::Real, 122));
    assert_eq!(vr(&d, "coulomb_sharpness"), (BaseType::Real, 136));
    // then the computed reference
    assert_eq!(vr(&d, "chart_source"), (BaseType::Integer, 5));
    assert_eq!(vr(&d, "mode"), (BaseType::Integer, 6));
    assert_eq!(vr(&d, "family_energy_max"), (BaseType::Real, 137));
    assert_eq!(vr(&d, "chart_energy_max"), (BaseType::Real, 140));
    // then the state estimator
    assert_eq!(vr(&d, "state_estimator"), (BaseType::Integer, 7));
    assert_eq!(vr(&d, "acceleration_noise"), (BaseType::Real, 143));
    // then the adaptation: Booleans from 0, the estimate after the noise levels
    assert_eq!(vr(&d, "adapt"), (BaseType::Boolean, 0));
    assert_eq!(vr(&d, "adapt_realtime"), (BaseType::Boolean, 1));
    assert_eq!(vr(&d, "adapt_period"), (BaseType::Real, 144));
    assert_eq!(vr(&d, "estimate.A[1,1]"), (BaseType::Real, 145));
    assert_eq!(vr(&d, "estimate.A[2,2]"), (BaseType::Real, 147));
    assert_eq!(vr(&d, "estimate.cf[2]"), (BaseType::Real, 155));
    assert_eq!(vr(&d, "model_updates"), (BaseType::Integer, 8));
    // then the energy scale, the measurement delay and the actuator lag
    // (issue 19)
    assert_eq!(vr(&d, "E_scale"), (BaseType::Real, 156));
    assert_eq!(vr(&d, "measurement_delay"), (BaseType::Real, 157));
    assert_eq!(vr(&d, "actuator_time_constant"), (BaseType::Real, 158));
    // then what the adaptation did
    assert_eq!(vr(&d, "adapt_refused"), (BaseType::Integer, 9));
    assert_eq!(vr(&d, "adapt_reverts"), (BaseType::Integer, 10));
    assert_eq!(vr(&d, "adaptation_status"), (BaseType::Integer, 11));
    // then the stall supervisor (issue 37)
    assert_eq!(vr(&d, "supervisor"), (BaseType::Boolean, 2));
    assert_eq!(vr(&d, "supervisor_events"), (BaseType::Integer, 12));
    // then the motor's response per sample (issue 37)
    assert_eq!(vr(&d, "torque_response"), (BaseType::Real, 159));
    // then the adaptation's source (issue 37)
    assert_eq!(vr(&d, "adapt_estimator"), (BaseType::Integer, 13));
    assert_eq!(
        d.variables.len(),
        24 + 20 + 5 + 17 + 6 + 4 + 3 + 11 + 1 + 1 + 2 + 3 + 2 + 1 + 1
    );
}

/// Every variable of the original `DoublePendulum.fmu` keeps its name and
/// value reference.
#[test]
fn the_two_link_plant_keeps_the_original_value_references() {
    let d = DoublePendulumFmu::description();
    let real = [
        "tau[1]",
        "tau[2]",
        "q[1]",
        "q[2]",
        "qd[1]",
        "qd[2]",
        "energy",
        "m[1]",
        "m[2]",
        "l[1]",
        "l[2]",
        "g",
        "damping[1]",
        "damping[2]",
        "q0[1]",
        "q0[2]",
        "qd0[1]",
        "qd0[2]",
        "rtol",
        "atol",
    ];
    for (r, name) in real.iter().enumerate() {
        assert_eq!(vr(&d, name), (BaseType::Real, r as u32), "{name}");
    }
    assert_eq!(vr(&d, "r[1]"), (BaseType::Real, 20));
    assert_eq!(vr(&d, "b[2]"), (BaseType::Real, 29));
    assert_eq!(vr(&d, "coulomb_sharpness"), (BaseType::Real, 36));
    assert_eq!(d.variables.len(), 37);
}

/// The 3-joint layout follows the same function: blocks of 3.
#[test]
fn the_three_joint_layout() {
    let d = EigenMpc3Fmu::description();
    for (name, r) in [
        ("q[3]", 2),
        ("qd[1]", 3),
        ("tau[3]", 8),
        ("energy", 9),
        ("E_ref", 11),
        ("sample_period", 19),
        ("m[1]", 20),
        ("g", 26),
        ("c[3]", 29),
        ("chart.coef[3,9]", 129),
        ("r[1]", 130),
    ] {
        assert_eq!(vr(&d, name), (BaseType::Real, r), "{name}");
    }
    assert_eq!(vr(&d, "qp_solver"), (BaseType::Integer, 4));
    let d = TriplePendulumFmu::description();
    for (name, r) in [
        ("tau[3]", 2),
        ("q[1]", 3),
        ("energy", 9),
        ("g", 16),
        ("damping[3]", 19),
        ("atol", 27),
        ("r[1]", 28),
    ] {
        assert_eq!(vr(&d, name), (BaseType::Real, r), "{name}");
    }
}

#[test]
fn c_header_constants_follow_the_tables() {
    let h = c_defines("DoublePendulum", "DOUBLE_PENDULUM_").unwrap();
    for line in [
        "#define DOUBLE_PENDULUM_VR_TAU1 0\n",
        "#define DOUBLE_PENDULUM_VR_ENERGY 6\n",
        "#define DOUBLE_PENDULUM_VR_Q0_1 14\n",
        "#define DOUBLE_PENDULUM_VR_Q0_2 15\n",
        "#define DOUBLE_PENDULUM_VR_ATOL 19\n",
        "#define DOUBLE_PENDULUM_VR_Q_REST2 35\n",
    ] {
        assert!(h.contains(line), "{line} missing in\n{h}");
    }
    let h = c_defines("EigenMPC", "EIGENMPC_").unwrap();
    for line in [
        "#define EIGENMPC_VR_E_REF 8\n",
        "#define EIGENMPC_VR_CHART_COEF 100\n",
        "#define EIGENMPC_VR_CHART_COEF_JK(j, k) (100 + 10 * ((j) - 1) + (k))\n",
        "#define EIGENMPC_VR_QP_SOLVER 4\n",
        "#define EIGENMPC_VARIANT_STRAIGHT 1\n",
        "#define EIGENMPC_VARIANT_CURVED 2\n",
        "#define EIGENMPC_QP_SOLVER_CLARABEL 1\n",
        "#define EIGENMPC_QP_SOLVER_RICCATI 2\n",
        "#define EIGENMPC_VR_I1 122\n",
    ] {
        assert!(h.contains(line), "{line} missing in\n{h}");
    }
    let h = c_defines("EigenMPC3", "EIGENMPC3_").unwrap();
    assert!(h.contains("#define EIGENMPC3_VR_Q3 2\n"), "{h}");
    assert!(
        c_defines("TriplePendulum", "TRIPLE_PENDULUM_")
            .unwrap()
            .contains("#define TRIPLE_PENDULUM_VR_TAU3 2\n")
    );
}

/// The book's FMU variable tables (`readme::TABLES_FILE`) are the generated
/// ones (`cargo run -p fmu-build` rewrites them).
#[test]
fn readme_tables_match_the_variable_tables() {
    let file = eigenmpc_fmu_models::readme::TABLES_FILE;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(file);
    let readme = std::fs::read_to_string(&path).unwrap();
    let generated = eigenmpc_fmu_models::readme::update(&readme).unwrap();
    assert!(
        generated == readme,
        "the FMU variable tables of {file} are out of date with the variable tables: run \
         `cargo run --release -p fmu-build -- --update-checked-in` and commit {file}"
    );
    // and the check can fail: a drifted row is noticed
    let drifted = readme.replacen("| `E_ref` |", "| `E_reference` |", 1);
    assert_ne!(
        eigenmpc_fmu_models::readme::update(&drifted).unwrap(),
        drifted
    );
}

/// `start_values` of the default model with the default reference gives
/// exactly the FMU's start values of those variables.
#[test]
fn start_values_of_the_default_model_are_the_fmu_defaults() {
    use eigenmpc::mechanics::PlanarChainParams;
    use eigenmpc_fmu_models::controller::start_values::start_values;
    let chart = DEFAULT_CHART_14J.map(|r| r.to_vec());
    let values = start_values(
        &PlanarChainParams::<2>::default(),
        14.0,
        &DEFAULT_EIGENVECTOR,
        &chart,
    )
    .unwrap();
    let d = EigenMpcFmu::description();
    assert_eq!(values.len(), 1 + (10 * 2 + 2) + 2 + 20 + 1);
    for (name, value) in &values {
        if name == "chart_source" {
            // the file's chart is used, not a computed one
            assert_eq!(*value, Value::Integer(CHART_SOURCE_PARAMETERS));
            continue;
        }
        assert_eq!(d.variable(name).unwrap().start, Some(*value), "{name}");
    }
    // refused: a model the FMU cannot express, too many coefficients
    let mut behind = PlanarChainParams::<2>::default();
    behind.links[0].com = -0.2;
    let e = start_values(&behind, 14.0, &DEFAULT_EIGENVECTOR, &chart).unwrap_err();
    assert!(e.contains("r[1] = -0.2 < 0"), "{e}");
    let mut long = chart.clone();
    long[1].push(0.0);
    let e = start_values(
        &PlanarChainParams::default(),
        14.0,
        &DEFAULT_EIGENVECTOR,
        &long,
    )
    .unwrap_err();
    assert!(e.contains("joint 2 has 11 coefficients"), "{e}");
    let e = start_values(
        &PlanarChainParams::default(),
        -1.0,
        &DEFAULT_EIGENVECTOR,
        &chart,
    )
    .unwrap_err();
    assert!(e.contains("E_ref = -1 is below its minimum"), "{e}");
}

/// The model start values name variables of both the controller and the
/// plant FMU (the demo sets one list on both), with the values of the model.
#[test]
fn model_start_values_fit_controller_and_plant() {
    use eigenmpc::mechanics::{Joint, PlanarChainParams};
    use eigenmpc_fmu_models::controller::start_values::model_start_values;
    let mut p = PlanarChainParams::<2>::point_masses([0.6, 0.5], [0.3, 0.2], 9.81);
    p.joints[1] = Joint {
        viscous: 0.01,
        coulomb: 0.08,
        ..Joint::default()
    };
    let values = model_start_values(&p).unwrap();
    assert_eq!(values.len(), 22);
    let controller = EigenMpcFmu::description();
    let plant = DoublePendulumFmu::description();
    for (name, _) in &values {
        assert!(controller.variable(name).is_some(), "controller: {name}");
        assert!(plant.variable(name).is_some(), "plant: {name}");
    }
    let get = |n: &str| values.iter().find(|(name, _)| name == n).unwrap().1;
    assert_eq!(get("m[1]"), Value::Real(0.6));
    assert_eq!(get("cf[2]"), Value::Real(0.08));
    assert_eq!(get("b[2]"), Value::Real(0.01));
    let mut bad = p;
    bad.links[0].mass = -1.0;
    let e = model_start_values(&bad).unwrap_err();
    assert!(e.contains("m[1]"), "{e}");
}
