//! The motor's response per sample in the prediction (issue 37, item 4):
//! the plant's motor applies `u += a (tau - u)` per sample (the lab
//! benchmark's torque response, `a` from 0.1 to 2.0), and the controller is
//! told `a` (`MpcConfig::torque_response`) or not.
//!
//! `cargo test --release --test mpc_torque_response measure_table --
//! --ignored --nocapture` prints the table of docs/delay.md.

use eigenmpc::mechanics::{MechanicalSystem, PlanarChain, PlanarChainParams};
use eigenmpc::model_file::RobotFile;
use eigenmpc::mpc::closed_loop::{energy_tail, reference_for, rms_friction_torque};
use eigenmpc::mpc::{
    Controller, MpcConfig, MpcError, PREDICTION_SUBSTEPS, Variant, prediction_model,
};
use eigenmpc::robustness::{Imperfections, run_imperfect};
use nalgebra::SVector;

const WINDOW: f64 = 5.0;

fn lab_a0() -> PlanarChain<2> {
    let path = format!(
        "{}/robots/lab-double-pendulum-A0.yml",
        env!("CARGO_MANIFEST_DIR")
    );
    PlanarChain::new(RobotFile::load(path).unwrap().params::<2>().unwrap()).unwrap()
}

/// The curved controller `eigenmpc simulate --model` builds for `robot`
/// (its prediction model), told the motor's response `declared`.
fn controller(
    robot: &PlanarChain<2>,
    e_ref: f64,
    tau_max: f64,
    declared: f64,
) -> Controller<PlanarChain<2>, 2, 4> {
    let mut config = MpcConfig::paper(Variant::Curved);
    let (model, substeps, _) = prediction_model(robot, config.dt, PREDICTION_SUBSTEPS);
    config.substeps = substeps;
    config.tau_max = tau_max;
    config.cost.e_ref = e_ref;
    config.torque_response = declared;
    let reference = reference_for::<_, 2, 4>(&model, Variant::Curved, 0, e_ref).unwrap();
    Controller::new(model, config, reference).unwrap()
}

/// What one closed loop ends with.
#[derive(Debug)]
struct Outcome {
    /// Mean energy of the last 5 s relative to E_ref (%).
    energy_error_percent: f64,
    /// RMS applied torque over the last 5 s per joint (N m).
    rms_torque: [f64; 2],
    /// The plant's RMS friction torque along the last 5 s per joint (N m).
    friction: [f64; 2],
    /// Largest difference between the torque the controller expected the
    /// motor to apply and the one it applied, over the run (N m).
    expectation_error: f64,
}

/// `plant` driven from q = (0.05, 0.05) at rest for `duration` s by the
/// curved controller on `model` (E_ref, tau_max), the plant's motor with
/// response `a`, the controller told `declared`.
fn run(
    model: &PlanarChain<2>,
    plant: &PlanarChain<2>,
    e_ref: f64,
    tau_max: f64,
    a: f64,
    declared: f64,
    duration: f64,
) -> Outcome {
    let mut controller = controller(model, e_ref, tau_max, declared);
    let imperfections = Imperfections {
        responsiveness: a,
        ..Imperfections::default()
    };
    let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
    let result =
        run_imperfect::<2, 4, 11>(&mut controller, None, plant, &z0, duration, &imperfections)
            .unwrap();
    let samples = &result.samples;
    let (mean, _) = energy_tail(samples, e_ref, WINDOW);
    let t_end = samples.last().unwrap().time;
    let tail: Vec<_> = result
        .motor_torque
        .iter()
        .zip(samples)
        .filter(|(_, s)| s.time > t_end - WINDOW + 1e-9)
        .map(|(u, _)| *u)
        .collect();
    let rms = |j: usize| (tail.iter().map(|u| u[j] * u[j]).sum::<f64>() / tail.len() as f64).sqrt();
    let friction = rms_friction_torque(samples, plant, WINDOW);
    Outcome {
        energy_error_percent: 100.0 * (mean - e_ref) / e_ref,
        rms_torque: [rms(0), rms(1)],
        friction: [friction[0], friction[1]],
        expectation_error: expectation_error(model, plant, e_ref, tau_max, a, declared),
    }
}

/// The largest gap between [`Controller::applied_torque`] and the plant's
/// motor over 10 s of the same loop, stepped by hand.
fn expectation_error(
    model: &PlanarChain<2>,
    plant: &PlanarChain<2>,
    e_ref: f64,
    tau_max: f64,
    a: f64,
    declared: f64,
) -> f64 {
    let mut controller = controller(model, e_ref, tau_max, declared);
    let mut z = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
    let mut motor = eigenmpc::mechanics::Vector::<2>::zeros();
    let mut worst: f64 = 0.0;
    for _ in 0..400 {
        let out = controller.step(&z);
        assert!(
            out.tau.amax() <= tau_max,
            "command {} beyond the bound",
            out.tau
        );
        motor = out.tau * a + motor * (1.0 - a);
        worst = worst.max((controller.applied_torque() - motor).amax());
        // One RK4 step per sample is enough here: the plant's state only
        // feeds the next command.
        let h = 0.025;
        let f = |x: &SVector<f64, 4>| {
            eigenmpc::mechanics::state_derivative::<PlanarChain<2>, 2, 4>(plant, x, &motor)
        };
        let k1 = f(&z);
        let k2 = f(&(z + k1 * (0.5 * h)));
        let k3 = f(&(z + k2 * (0.5 * h)));
        let k4 = f(&(z + k3 * h));
        z += (k1 + (k2 + k3) * 2.0 + k4) * (h / 6.0);
    }
    worst
}

fn pendulum() -> PlanarChain<2> {
    PlanarChain::new(PlanarChainParams::default()).unwrap()
}

/// The paper's pendulum (14 J, |tau| <= 1 N m, no friction) holds its mode
/// across the lab benchmark's range of `a` when told it: within 1 % of
/// E_ref with at most 0.03 N m of torque, the motor applying exactly what
/// the controller expects. Undeclared, an overshooting motor (a = 1.9)
/// makes the same loop oscillate at the torque bound.
#[test]
fn the_paper_pendulum_holds_its_mode_for_every_declared_response() {
    let p = pendulum();
    for a in [0.1, 0.25, 0.5, 1.5, 1.9, 2.0] {
        let o = run(&p, &p, 14.0, 1.0, a, a, 40.0);
        println!("a = {a}: {o:?}");
        assert!(o.energy_error_percent.abs() < 1.0, "a = {a}: {o:?}");
        assert!(o.rms_torque.iter().all(|&t| t <= 0.03), "a = {a}: {o:?}");
        assert!(o.expectation_error < 1e-12, "a = {a}: {o:?}");
    }
    let undeclared = run(&p, &p, 14.0, 1.0, 1.9, 1.0, 40.0);
    println!("a = 1.9 undeclared: {undeclared:?}");
    assert!(
        undeclared.energy_error_percent.abs() > 10.0 || undeclared.rms_torque[0] > 0.5,
        "{undeclared:?}"
    );
}

/// The lab pendulum A0 (2 J, |tau| <= 0.5 N m, its friction), told the
/// response: within 1 % of E_ref, torque at most the friction torque +
/// 0.03 N m (the robustness report's rule), from a quarter to twice the
/// command per sample. (At a = 0.1 it is not: -11.8 %, docs/delay.md; the
/// motor's memory is not a state of the plan.)
#[test]
fn lab_pendulum_a0_holds_its_mode_for_every_declared_response() {
    let a0 = lab_a0();
    for a in [0.25, 0.5, 1.5, 1.75, 2.0] {
        let o = run(&a0, &a0, 2.0, 0.5, a, a, 60.0);
        println!("A0, a = {a}: {o:?}");
        assert!(o.energy_error_percent.abs() < 1.0, "a = {a}: {o:?}");
        for j in 0..2 {
            assert!(o.rms_torque[j] <= o.friction[j] + 0.03, "a = {a}: {o:?}");
        }
    }
}

/// An immediate response declared is no response: the same commands, bit
/// for bit, as a controller that knows nothing of it.
#[test]
fn an_immediate_response_changes_nothing() {
    let p = pendulum();
    let reference = reference_for::<_, 2, 4>(&p, Variant::Curved, 0, 14.0).unwrap();
    let plain = MpcConfig::paper(Variant::Curved);
    let declared = MpcConfig {
        torque_response: 1.0,
        ..plain
    };
    let mut a = Controller::new(p, plain, reference.clone()).unwrap();
    let mut b = Controller::new(p, declared, reference).unwrap();
    let mut z = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
    for _ in 0..200 {
        let (ta, tb) = (a.step(&z).tau, b.step(&z).tau);
        assert_eq!(ta, tb);
        assert_eq!(a.applied_torque(), ta);
        let q = eigenmpc::mechanics::Vector::<2>::new(z[0], z[1]);
        // A crude plant is enough: both see the same states.
        let g = p.potential_gradient(&q);
        z[2] += 0.025 * (ta[0] - g[0]) * 0.1;
        z[3] += 0.025 * (ta[1] - g[1]) * 0.1;
        z[0] += 0.025 * z[2];
        z[1] += 0.025 * z[3];
    }
}

/// A response outside (0, 2], or declared together with a first-order lag,
/// is refused with the field's name.
#[test]
fn a_bad_response_is_refused() {
    let p = pendulum();
    for a in [0.0, -0.5, 2.01, f64::NAN, f64::INFINITY] {
        let reference = reference_for::<_, 2, 4>(&p, Variant::Curved, 0, 14.0).unwrap();
        let config = MpcConfig {
            torque_response: a,
            ..MpcConfig::paper(Variant::Curved)
        };
        match Controller::<_, 2, 4>::new(p, config, reference) {
            Err(MpcError::InvalidParameter { name, .. }) => assert_eq!(name, "torque_response"),
            other => panic!("a = {a}: {:?}", other.err()),
        }
    }
    let reference = reference_for::<_, 2, 4>(&p, Variant::Curved, 0, 14.0).unwrap();
    let both = MpcConfig {
        torque_response: 0.5,
        actuator_time_constant: 0.05,
        ..MpcConfig::paper(Variant::Curved)
    };
    let err = Controller::<_, 2, 4>::new(p, both, reference)
        .err()
        .unwrap();
    assert!(err.to_string().contains("not both"), "{err}");
}

#[test]
#[ignore = "measurement table (about a minute)"]
fn measure_table() {
    println!(
        "| robot | a (plant) | declared | mean E err 5 s % | RMS tau 5 s (N m) | friction (N m) |"
    );
    println!("|---|---|---|---|---|---|");
    let p = pendulum();
    let a0 = lab_a0();
    for (name, robot, e, t, duration) in
        [("paper", &p, 14.0, 1.0, 40.0), ("A0", &a0, 2.0, 0.5, 60.0)]
    {
        for a in [0.1, 0.25, 0.5, 1.0, 1.5, 1.75, 1.9, 2.0] {
            for declared in [1.0, a] {
                if declared == 1.0 && a == 1.0 && declared != a {
                    continue;
                }
                let o = run(robot, robot, e, t, a, declared, duration);
                println!(
                    "| {name} | {a} | {} | {:+.2} | {:.3} / {:.3} | {:.3} / {:.3} |",
                    if declared == a { "yes" } else { "no" },
                    o.energy_error_percent,
                    o.rms_torque[0],
                    o.rms_torque[1],
                    o.friction[0],
                    o.friction[1]
                );
                if a == 1.0 {
                    break;
                }
            }
        }
    }
}
