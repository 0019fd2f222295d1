//! The first sample's start-up (`Startup`): bounded Gauss-Newton
//! iterations by default, measured against the converged SQP they replaced
//! on the laboratory robots, where their exact Coulomb law keeps the SQP
//! from converging (docs/speed.md, "The first sample").

use eigenmpc::model_file::RobotFile;
use eigenmpc::mpc::closed_loop::{
    START_ANGLE, robot_controller, robot_controller_with, run, summarise,
};
use eigenmpc::mpc::{
    ControlStatus, Controller, MpcConfig, MpcError, PREDICTION_SUBSTEPS, Startup, Variant,
    prediction_substeps,
};
use nalgebra::SVector;

fn lab_robot(name: &str) -> eigenmpc::mechanics::PlanarChain<2> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("robots")
        .join(name);
    RobotFile::load(path).unwrap().chain::<2>().unwrap()
}

/// Band time, first-sample QP iterations and SQP iterations of 30 s from
/// rest with `startup`.
fn closed_loop(
    name: &str,
    startup: Startup,
    exact_law: bool,
) -> (f64, usize, usize, ControlStatus) {
    let robot = lab_robot(name);
    let most = if exact_law {
        prediction_substeps(&robot, 0.025)
    } else {
        PREDICTION_SUBSTEPS
    };
    let (built, _) =
        robot_controller_with::<2, 4>(&robot, Variant::Curved, 2.0, 0.5, most).unwrap();
    let mut config = *built.config();
    config.startup = startup;
    let mut ctrl =
        Controller::<_, 2, 4>::new(*built.system(), config, built.reference().clone()).unwrap();
    let z0 = SVector::<f64, 4>::new(START_ANGLE, START_ANGLE, 0.0, 0.0);
    let mut first = (0, 0, ControlStatus::Solved);
    let trace = eigenmpc::mpc::closed_loop::run_with(&mut ctrl, &robot, &z0, 30.0, |i, _, out| {
        if i == 0 {
            first = (out.qp_iterations, out.sqp_iterations, out.status);
        }
    })
    .unwrap();
    let band = summarise(&trace, 2.0, None, 5.0).time_to_5_percent.unwrap();
    (band, first.0, first.1, first.2)
}

#[test]
fn the_bounded_start_up_reaches_the_band_as_the_converged_sqp_on_the_lab_robots() {
    for name in ["lab-double-pendulum-A0.yml", "lab-double-pendulum-B0.yml"] {
        // The robots' exact Coulomb law (the converged SQP's worst case).
        let (band, qp, sqp, status) =
            closed_loop(name, Startup::Iterations(Startup::DEFAULT_ITERATIONS), true);
        let (converged_band, converged_qp, converged_sqp, converged_status) =
            closed_loop(name, Startup::Converge, true);
        // The converged SQP runs into its iteration limit here (friction);
        // the bounded start takes its ten iterations and is done.
        assert_eq!(converged_status, ControlStatus::NotConverged, "{name}");
        assert_eq!(
            converged_sqp,
            MpcConfig::paper(Variant::Curved).sqp.max_iterations
        );
        assert_eq!((sqp, status), (10, ControlStatus::Solved), "{name}");
        // A third of the QP work or less (each of its iterations solves one
        // QP; the SQP's also halve their steps).
        assert!(3 * qp < converged_qp, "{name}: {qp} against {converged_qp}");
        // Measured: A0 3.950 against 3.925 s, B0 5.225 against 5.350 s.
        assert!(
            band <= 1.02 * converged_band,
            "{name}: band {band} s, converged start {converged_band} s"
        );
        // The default model (its slope smoothed for its substeps): the
        // converged SQP takes 17-72 ms there (docs/speed.md), and the
        // bounded start is as good.
        let (band, _, sqp, status) = closed_loop(
            name,
            Startup::Iterations(Startup::DEFAULT_ITERATIONS),
            false,
        );
        let (converged_band, _, _, _) = closed_loop(name, Startup::Converge, false);
        assert_eq!((sqp, status), (10, ControlStatus::Solved), "{name}");
        assert!(
            band <= 1.02 * converged_band,
            "{name}: band {band} s, converged start {converged_band} s (default model)"
        );
    }
}

#[test]
fn the_first_sample_takes_the_configured_iterations_and_no_more() {
    let robot = lab_robot("lab-double-pendulum-A0.yml");
    let (built, _) = robot_controller::<2, 4>(&robot, Variant::Curved, 2.0, 0.5).unwrap();
    let z0 = SVector::<f64, 4>::new(START_ANGLE, START_ANGLE, 0.0, 0.0);
    for n in [1, 3, 7] {
        let mut config = *built.config();
        config.startup = Startup::Iterations(n);
        let mut ctrl =
            Controller::<_, 2, 4>::new(*built.system(), config, built.reference().clone()).unwrap();
        let first = ctrl.step(&z0);
        assert_eq!(
            (first.sqp_iterations, first.status),
            (n, ControlStatus::Solved)
        );
        // Then one RTI iteration a sample.
        let second = ctrl.step(&z0);
        assert_eq!(second.sqp_iterations, 1);
    }
    // A closed loop from rest after a reset starts the same way again.
    let mut ctrl =
        Controller::<_, 2, 4>::new(*built.system(), *built.config(), built.reference().clone())
            .unwrap();
    let trace = run(&mut ctrl, &robot, &z0, 0.1).unwrap();
    assert!(trace.iter().all(|s| s.status == ControlStatus::Solved));
    ctrl.reset();
    assert_eq!(ctrl.step(&z0).sqp_iterations, Startup::DEFAULT_ITERATIONS);
}

#[test]
fn start_up_iterations_out_of_range_are_refused() {
    for n in [0, eigenmpc::mpc::MAX_STARTUP_ITERATIONS + 1] {
        let mut config = MpcConfig::paper(Variant::Curved);
        config.startup = Startup::Iterations(n);
        match config.validate() {
            Err(MpcError::InvalidParameter { name, .. }) => {
                assert_eq!(name, "startup iterations")
            }
            other => panic!("{n} start-up iterations: {other:?}"),
        }
    }
}
