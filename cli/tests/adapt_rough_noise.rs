//! Issue 37's first "done when", in the library: the lab pendulums A0 and
//! B0 as plants, each driven from 10 seeded rough models (the robustness
//! report's "rough model + noise": masses, centres of mass and inertias up
//! to 20 % off, no friction) under the lab's sensor noise (0.005 rad, 0.05
//! rad/s), with the EKF and the adaptation fed by the state and parameter
//! filter and its excitation, for 120 s: the plant ends within 2 % of E_ref
//! with an RMS torque per joint at most 1.3 times the friction torque +
//! 0.02 N m. With the energy balance as the source (the FMU's `adapt` today)
//! B0 does not.
//!
//! Measured (seeds 0-20, 120 s; runs meeting both rules, A0 / B0):
//! - the energy balance: 19 / 8 of 21 (B0 to -17 %);
//! - the filter without excitation: 20 / 13 (B0 to +13 %: under feedback
//!   alone the data cannot tell the model's scale from its friction);
//! - the filter excited with 0.3 tau_max for 40 s (the default): 21 / 20,
//!   worst 0.6 / 3.6 % (B0's rough model 17, A_22 37 % off); 0.7 / 3.9 %
//!   at 240 s.

use eigenmpc::adapt::Adaptation;
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams};
use eigenmpc::model_file::RobotFile;
use eigenmpc::mpc::closed_loop::{energy_tail, rms_friction_torque};
use eigenmpc::robustness::{Imperfections, run_imperfect};
use eigenmpc::state_parameter_ekf::{StateParameterEkf, StateParameterOptions};
use eigenmpc_cli::robustness::{ROUGH_NOISE, Setup, rough_model};
use eigenmpc_fmu_models::chain::ChainParameters;
use eigenmpc_fmu_models::controller::settings::StateEstimator;
use nalgebra::SVector;

fn robot(name: &str) -> PlanarChainParams<2> {
    let path = format!("{}/../robots/{name}.yml", env!("CARGO_MANIFEST_DIR"));
    *RobotFile::load(std::path::Path::new(&path))
        .unwrap()
        .chain::<2>()
        .unwrap()
        .params()
}

/// One run from rough model `seed` of `nominal`: the energy error at the
/// end (share of E_ref) and the worst joint's RMS torque beyond its
/// allowance (N m; <= 0 meets it).
fn run(nominal: &PlanarChainParams<2>, e_ref: f64, seed: u64, filtered: bool) -> (f64, f64) {
    let (duration, window) = (120.0, 5.0);
    let setup = Setup::new(nominal, e_ref, 0.5, duration).unwrap();
    let mut settings = setup.settings;
    settings.adapt = true;
    settings.model = ChainParameters::from_params(&rough_model(nominal, seed)).unwrap();
    settings.state_estimator = StateEstimator::Ekf;
    (settings.noise.angle_noise, settings.noise.speed_noise) = ROUGH_NOISE;
    let prior = settings.model.params();
    let mut controller = settings.build::<4>().unwrap();
    let mut adaptation = Adaptation::<2, 4, 11>::new(&prior, settings.adapt_options()).unwrap();
    if filtered {
        let options = StateParameterOptions {
            angle_noise: ROUGH_NOISE.0,
            speed_noise: ROUGH_NOISE.1,
            ..StateParameterOptions::default()
        };
        let filter =
            StateParameterEkf::<2, 4, 11, 15>::new(&prior, options, settings.sample_period)
                .unwrap();
        adaptation.set_filter(Box::new(filter));
    }
    let plant = PlanarChain::new(*nominal).unwrap();
    let imperfections = Imperfections {
        measurement_noise: ROUGH_NOISE.0,
        speed_noise: Some(ROUGH_NOISE.1),
        seed,
        ..Imperfections::default()
    };
    let z0 = SVector::<f64, 4>::new(setup.q0[0], setup.q0[1], 0.0, 0.0);
    let out = run_imperfect(
        &mut controller,
        Some(&mut adaptation),
        &plant,
        &z0,
        duration,
        &imperfections,
    )
    .unwrap();
    let (energy, _) = energy_tail(&out.samples, e_ref, window);
    let friction = rms_friction_torque(&out.samples, &plant, window);
    let tail = (window / settings.sample_period).round() as usize;
    let motor = &out.motor_torque[out.motor_torque.len() - tail..];
    let excess = (0..2)
        .map(|j| {
            let rms = (motor.iter().map(|t| t[j] * t[j]).sum::<f64>() / tail as f64).sqrt();
            rms - (1.3 * friction[j] + 0.02)
        })
        .fold(f64::MIN, f64::max);
    ((energy - e_ref) / e_ref, excess)
}

/// Runs seeds 0-9 (reported before any check); returns how many met both
/// rules.
fn passing(name: &str, e_ref: f64, filtered: bool) -> usize {
    let nominal = robot(name);
    let mut met = 0;
    for seed in 0..10 {
        let (error, excess) = run(&nominal, e_ref, seed, filtered);
        let ok = error.abs() <= 0.02 && excess <= 0.0;
        met += usize::from(ok);
        eprintln!(
            "{name} rough model {seed}, filter {filtered}: {:+.2} %, torque {:+.3} N m over its allowance{}",
            100.0 * error,
            excess,
            if ok { "" } else { "  <- fails" }
        );
    }
    met
}

#[test]
fn a0_from_ten_rough_models_under_noise_reaches_its_mode() {
    assert_eq!(passing("lab-double-pendulum-A0", 2.0, true), 10);
}

#[test]
fn b0_from_ten_rough_models_under_noise_reaches_its_mode() {
    assert_eq!(passing("lab-double-pendulum-B0", 1.5, true), 10);
    // The energy balance alone does not (5 of 10 measured).
    assert!(passing("lab-double-pendulum-B0", 1.5, false) <= 7);
}
