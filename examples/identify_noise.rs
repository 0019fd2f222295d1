//! The energy-balance identification under sensor noise (issue 37): the lab
//! pendulum A0 in closed loop with its exact controller (curved, 1 J,
//! 0.5 N m, 120 s from 0.05 rad), measured with Gaussian noise; the
//! identification starts from a rough prior (masses, centres of mass and
//! inertias 10-20 % off, no friction) and is fed the measurements and the
//! torque, as the adaptation feeds it. Printed: the identified model's
//! energy error along the plant's orbit (the second half of the run, a
//! share of E_ref), mean and standard deviation over 4 noise seeds, for the
//! default windows and for the windows of before (20 samples, ends of 5).
//!
//! On an orbit the energy scale has almost no signal, so noise in the
//! windows' ends (the regressors) shrinks it: errors in variables.
//! Run with `cargo run --release --example identify_noise`.

use eigenmpc::identify::{BaseParameters, EnergyBalanceRls, RlsOptions, energy_features};
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams, Vector};
use eigenmpc::model_file::RobotFile;
use eigenmpc::mpc::Variant;
use eigenmpc::mpc::closed_loop::{GaussianNoise, robot_controller, run_measured};
use nalgebra::SVector;

const E_REF: f64 = 1.0;
const SEEDS: u64 = 4;

/// The robot with masses, centres of mass and inertias off and no friction.
fn rough(robot: &PlanarChainParams<2>) -> PlanarChainParams<2> {
    let mut p = *robot;
    for ((link, joint), f) in p
        .links
        .iter_mut()
        .zip(&mut p.joints)
        .zip([[1.15, 0.88, 1.2], [0.85, 1.12, 0.9]])
    {
        link.mass *= f[0];
        link.com *= f[1];
        link.inertia *= f[2];
        joint.viscous = 0.0;
        joint.coulomb = 0.0;
    }
    p
}

/// The identified model's mean energy error along the second half of one
/// seeded closed loop, per window setting (a share of E_ref).
fn orbit_errors(
    robot: &PlanarChainParams<2>,
    noise: (f64, f64),
    seed: u64,
    settings: &[RlsOptions],
) -> Vec<f64> {
    let plant = PlanarChain::new(*robot).unwrap();
    let (mut controller, _) =
        robot_controller::<2, 4>(&plant, Variant::Curved, E_REF, 0.5).unwrap();
    let mut rng = GaussianNoise::new(seed);
    let mut measured = Vec::new();
    let trace = run_measured(
        &mut controller,
        &plant,
        &SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0),
        120.0,
        |_, _| {},
        |_, z| {
            let m = rng.measure(z, noise.0, noise.1);
            measured.push(m);
            m
        },
    )
    .unwrap();
    let truth = BaseParameters::<2, 11>::of(robot).unwrap().theta;
    let prior = rough(robot);
    settings
        .iter()
        .map(|options| {
            let mut rls = EnergyBalanceRls::<2, 11>::new(&prior, *options).unwrap();
            // The torque paired with a measurement acted over the sample before it.
            let mut tau = Vector::<2>::zeros();
            for (sample, z) in trace.iter().zip(&measured) {
                let q = Vector::<2>::new(z[0], z[1]);
                let qd = Vector::<2>::new(z[2], z[3]);
                let _ = rls.add_sample(&q, &qd, &tau, 0.025);
                tau = sample.tau;
            }
            let error = rls.estimate().theta - truth;
            let orbit = &trace[trace.len() / 2..];
            orbit
                .iter()
                .map(|s| {
                    let q = Vector::<2>::new(s.state[0], s.state[1]);
                    let qd = Vector::<2>::new(s.state[2], s.state[3]);
                    error.dot(&energy_features::<2, 11>(&prior, &q, &qd))
                })
                .sum::<f64>()
                / orbit.len() as f64
                / E_REF
        })
        .collect()
}

fn main() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/robots/lab-double-pendulum-A0.yml"
    );
    let robot = RobotFile::load(path).unwrap().params::<2>().unwrap();
    let settings = [
        RlsOptions::default(),
        RlsOptions {
            window: 20,
            end_samples: 5,
            ..RlsOptions::default()
        },
    ];
    println!(
        "A0, exact controller, rough prior, 120 s closed loop: the identified model's energy error \
         along the orbit (mean ± sd over {SEEDS} seeds)"
    );
    println!(
        "| noise (rad, rad/s) | windows of 40, ends of 40 (default) | windows of 20, ends of 5 |"
    );
    println!("|---|---|---|");
    for noise in [(0.0, 0.0), (0.005, 0.05), (0.01, 0.1)] {
        let runs: Vec<Vec<f64>> = (1..=SEEDS)
            .map(|seed| orbit_errors(&robot, noise, seed, &settings))
            .collect();
        let cell = |k: usize| {
            let e: Vec<f64> = runs.iter().map(|r| 100.0 * r[k]).collect();
            let mean = e.iter().sum::<f64>() / e.len() as f64;
            let sd = (e.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / e.len() as f64).sqrt();
            format!("{mean:+.2} % ± {sd:.2}")
        };
        println!("| {} / {} | {} | {} |", noise.0, noise.1, cell(0), cell(1));
    }
}
