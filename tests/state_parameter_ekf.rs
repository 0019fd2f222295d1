//! State and parameters estimated together (src/state_parameter_ekf.rs):
//! the filter finds the plant's base parameters from a rough model's
//! under the lab's sensor noise, where the energy balance's least squares
//! is left with the noise's bias and variance.

#[path = "common/rough.rs"]
mod rough_model;
use eigenmpc::adapt::{AdaptOptions, Adaptation};
use eigenmpc::identify::{BaseParameters, EnergyBalanceRls, RlsOptions};
use eigenmpc::integrate::{Dopri5, Tolerances};
use eigenmpc::math;
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams, Vector, state_derivative};
use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::{ChartFamily, FamilyOptions};
use eigenmpc::mpc::closed_loop::{GaussianNoise, energy_tail, robot_controller, summarise};
use eigenmpc::mpc::{Controller, EstimatorConfig, MpcConfig, Variant, prediction_substeps};
use eigenmpc::robustness::{Imperfections, run_imperfect};
use eigenmpc::state_parameter_ekf::{StateParameterEkf, StateParameterOptions};
use nalgebra::SVector;
use rough_model::{probing_torque, rough};

fn robot(name: &str) -> PlanarChainParams<2> {
    let path = format!("{}/robots/{name}.yml", env!("CARGO_MANIFEST_DIR"));
    RobotFile::load(path).unwrap().params::<2>().unwrap()
}

fn robot_a0() -> PlanarChainParams<2> {
    robot("lab-double-pendulum-A0")
}

/// The relative errors of the energy parameters (A, G, rotor) against the
/// plant's, and of the energy along the plant's states.
fn errors(estimate: &SVector<f64, 11>, truth: &SVector<f64, 11>) -> Vec<f64> {
    (0..7)
        .map(|i| {
            if truth[i] == 0.0 {
                estimate[i]
            } else {
                estimate[i] / truth[i] - 1.0
            }
        })
        .collect()
}

/// A0 driven by a torque held per sample, measured with Gaussian noise;
/// the filter and the energy balance both start from the rough model and
/// see the same data. In open loop the torque is a fixed sum of sines; in
/// closed loop it is the curved EigenMPC's of the rough model at 2 J and
/// 0.5 N m given the noisy measurements (the torque answers the noise).
/// Returns their final estimates and the filter's restarts.
fn identify(
    closed_loop: bool,
    angle_noise: f64,
    speed_noise: f64,
    seconds: f64,
    seed: u64,
) -> (SVector<f64, 11>, SVector<f64, 11>, usize) {
    let plant = robot_a0();
    let energy = closed_loop.then_some(2.0);
    let (ekf, rls) = identify_with(
        &plant,
        &rough(&plant),
        energy,
        (angle_noise, speed_noise),
        seconds,
        seed,
    );
    (ekf.parameters().theta, rls.estimate().theta, ekf.restarts())
}

/// [`identify`] of `plant` from the model `prior`, in closed loop at
/// `energy` (J) when given; returns the filter and the energy balance.
fn identify_with(
    plant: &PlanarChainParams<2>,
    prior: &PlanarChainParams<2>,
    energy: Option<f64>,
    (angle_noise, speed_noise): (f64, f64),
    seconds: f64,
    seed: u64,
) -> (StateParameterEkf<2, 4, 11, 15>, EnergyBalanceRls<2, 11>) {
    let plant = *plant;
    let system = PlanarChain::new(plant).unwrap();
    let dt = 0.025;
    let options = StateParameterOptions {
        angle_noise,
        speed_noise,
        ..StateParameterOptions::default()
    };
    let mut ekf = StateParameterEkf::<2, 4, 11, 15>::new(prior, options, dt).unwrap();
    let mut rls = EnergyBalanceRls::<2, 11>::new(
        prior,
        RlsOptions {
            angle_noise,
            speed_noise,
            ..RlsOptions::default()
        },
    )
    .unwrap();
    let mut rng = GaussianNoise::new(seed);
    let tol = Tolerances {
        rtol: 1e-10,
        atol: 1e-10,
    };
    let mut ode = Dopri5::new(0.0, SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0), tol);
    let mut controller = energy.map(|energy| {
        let model = PlanarChain::new(*prior).unwrap();
        robot_controller::<2, 4>(&model, Variant::Curved, energy, 0.5)
            .unwrap()
            .0
    });
    let mut tau = Vector::<2>::zeros();
    for k in 0..(seconds / dt) as usize {
        let z = rng.measure(ode.state(), angle_noise, speed_noise);
        ekf.step(&z, &tau);
        rls.add_sample(
            &Vector::<2>::new(z[0], z[1]),
            &Vector::<2>::new(z[2], z[3]),
            &tau,
            dt,
        );
        tau = match controller.as_mut() {
            Some(c) => c.step(&z).tau,
            None => probing_torque(k as f64 * dt),
        };
        ode.advance_to(
            |_, z| state_derivative::<_, 2, 4>(&system, z, &tau),
            (k + 1) as f64 * dt,
        )
        .unwrap();
    }
    (ekf, rls)
}

/// Runs [`identify`] at the lab's noise and at twice it, two seeds each;
/// prints both estimates' errors (%) and checks the filter's: the link
/// parameters (A, G) within `tolerance`, better than the energy balance's
/// worst, and the Coulomb friction (unknown to the rough model) within 3 %.
fn check(closed_loop: bool, seconds: f64, tolerance: f64) {
    let truth = BaseParameters::<2, 11>::of(&robot_a0()).unwrap().theta;
    let percent = |v: &[f64]| {
        v.iter()
            .map(|e| format!("{:+.2}", 100.0 * e))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let worst = |e: &[f64]| e[..5].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut runs = vec![];
    for (a, s) in [(0.005, 0.05), (0.01, 0.1)] {
        for seed in 1..=2 {
            let (ekf, rls, restarts) = identify(closed_loop, a, s, seconds, seed);
            let (filter, balance) = (errors(&ekf, &truth), errors(&rls, &truth));
            eprintln!(
                "closed loop {closed_loop}, noise {a} rad / {s} rad/s, seed {seed}: A, G, Ir off by \
                 {} % (filter; Coulomb {:.4} / {:.4} N m, plant {:.3} / {:.3}), {} % (energy balance)",
                percent(&filter),
                ekf[9],
                ekf[10],
                truth[9],
                truth[10],
                percent(&balance)
            );
            runs.push((ekf, filter, balance, restarts));
        }
    }
    for (ekf, filter, balance, restarts) in runs {
        assert_eq!(restarts, 0);
        assert!(worst(&filter) < tolerance, "{}", percent(&filter));
        assert!(worst(&filter) < worst(&balance));
        for i in [9, 10] {
            assert!((ekf[i] / truth[i] - 1.0).abs() < 0.03, "cf {}", ekf[i]);
        }
    }
}

/// Open loop (a sum of sines), 60 s: the link parameters within 3 %
/// (measured: at most 1.8 % at the lab's noise, 1.9 % at twice it; the
/// energy balance's worst per run 12-26 %).
#[test]
fn the_filter_finds_the_plants_parameters_under_noise_in_open_loop() {
    check(false, 60.0, 0.03);
}

/// Closed loop (the rough model's EigenMPC answers the noise), 120 s: the
/// link parameters within 6 % (measured: at most 5.0 %, `A_12`, one seed
/// at the lab's noise; 1.7 % in the other three runs; the energy balance's
/// worst per run 4.6-26 %).
#[test]
fn the_filter_finds_the_plants_parameters_under_noise_in_closed_loop() {
    check(true, 120.0, 0.06);
}

/// Bad settings are refused with their name; a non-finite measurement or
/// torque is skipped (the estimate stays).
#[test]
fn bad_input_is_refused_or_skipped() {
    let plant = robot_a0();
    let options = StateParameterOptions::default();
    for (bad, name) in [
        (
            StateParameterOptions {
                angle_noise: 0.0,
                ..options
            },
            "angle_noise",
        ),
        (
            StateParameterOptions {
                drift: f64::NAN,
                ..options
            },
            "drift",
        ),
        (
            StateParameterOptions {
                substeps: 0,
                ..options
            },
            "substeps",
        ),
    ] {
        let e = StateParameterEkf::<2, 4, 11, 15>::new(&plant, bad, 0.025).unwrap_err();
        assert!(e.to_string().contains(name), "{e}");
    }
    assert!(StateParameterEkf::<2, 4, 11, 15>::new(&plant, options, 0.0).is_err());
    let mut springy = plant;
    springy.joints[0].stiffness = 1.0;
    assert!(StateParameterEkf::<2, 4, 11, 15>::new(&springy, options, 0.025).is_err());
    let mut ekf = StateParameterEkf::<2, 4, 11, 15>::new(&plant, options, 0.025).unwrap();
    let z = SVector::<f64, 4>::new(0.1, 0.0, 0.0, 0.0);
    assert!(ekf.step(&z, &Vector::<2>::zeros()));
    let before = (ekf.state(), ekf.parameters());
    assert!(!ekf.step(
        &SVector::<f64, 4>::new(f64::NAN, 0.0, 0.0, 0.0),
        &Vector::<2>::zeros()
    ));
    assert!(!ekf.step(&z, &Vector::<2>::new(f64::INFINITY, 0.0)));
    assert_eq!((ekf.state(), ekf.parameters()), before);
    assert_eq!(ekf.restarts(), 0);
}

/// A saved filter continues bit for bit in a fresh one (the FMU's saved
/// state); a state of another size is refused and changes nothing.
#[test]
fn a_saved_filter_continues_bit_for_bit() {
    let plant = robot_a0();
    let options = StateParameterOptions::default();
    let mut noise = GaussianNoise::new(5);
    let measured: Vec<SVector<f64, 4>> = (0..80)
        .map(|k| {
            let t = k as f64 * 0.025;
            let z = SVector::<f64, 4>::new(
                0.3 * math::sin(t),
                0.2 * math::cos(t),
                0.3 * math::cos(t),
                -0.2 * math::sin(t),
            );
            noise.measure(&z, 0.005, 0.05)
        })
        .collect();
    let torque = |k: usize| probing_torque(k as f64 * 0.025);
    let mut first = StateParameterEkf::<2, 4, 11, 15>::new(&plant, options, 0.025).unwrap();
    for (k, z) in measured[..40].iter().enumerate() {
        first.step(z, &torque(k));
    }
    let saved = first.save_state();
    let mut second = StateParameterEkf::<2, 4, 11, 15>::new(&plant, options, 0.025).unwrap();
    second.restore_state(&saved).unwrap();
    for (k, z) in measured.iter().enumerate().skip(40) {
        first.step(z, &torque(k));
        second.step(z, &torque(k));
    }
    assert_eq!(first.state(), second.state());
    assert_eq!(first.parameters(), second.parameters());
    assert_eq!(first.parameter_covariance(), second.parameter_covariance());
    // A three-joint filter's state does not fit a two-joint one.
    let three = PlanarChainParams::<3>::default();
    let other = StateParameterEkf::<3, 6, 18, 24>::new(&three, options, 0.025).unwrap();
    let before = second.save_state();
    let e = second.restore_state(&other.save_state()).unwrap_err();
    assert!(e.contains("for 15"), "{e}");
    assert_eq!(second.save_state(), before);
}

/// The lab pendulum B0 from its own model (friction known), in closed loop
/// at 1.5 J under the lab's noise: its second joint starts held by Coulomb
/// friction, which the smooth friction model cannot predict. Counted as
/// process noise near rest, this keeps the link parameters within 4 % and
/// five of their standard deviations after 30 s (measured: 3.2 % and 4.1
/// sd on one seed, 1.3 % and 0.9 sd on the other; without it 7.1 % and
/// 7.7 sd, and on the adaptation's rough-model loop the first half second
/// moved them 10-20 %). The filter is not yet consistent in closed loop:
/// its linearisation leaves up to 4 sd.
#[test]
fn a_joint_held_by_friction_does_not_move_the_parameters() {
    let b0 = robot("lab-double-pendulum-B0");
    let truth = BaseParameters::<2, 11>::of(&b0).unwrap().theta;
    for seed in 1..=2 {
        let (ekf, _) = identify_with(&b0, &b0, Some(1.5), (0.005, 0.05), 30.0, seed);
        let theta = ekf.parameters().theta;
        let covariance = ekf.parameter_covariance();
        for i in 0..5 {
            let (error, sd) = (theta[i] - truth[i], covariance[(i, i)].sqrt());
            eprintln!(
                "B0 seed {seed}: theta[{i}] off by {:+.2} % ({:+.1} sd), consistency {:.2} cf {:.4} {:.4}",
                100.0 * error / truth[i],
                error / sd,
                ekf.consistency(),
                theta[9],
                theta[10]
            );
        }
        for i in 0..5 {
            let (error, sd) = (theta[i] - truth[i], covariance[(i, i)].sqrt());
            assert!(error.abs() < 5.0 * sd && error.abs() < 0.04 * truth[i]);
        }
        // The innovations are as large as the filter expects (measured 0.95).
        assert!((0.8..1.25).contains(&ekf.consistency()));
    }
}

/// The paper's pendulum, its controller given a rough model (masses +15 /
/// -15 %, centres of mass -12 / +12 %), the lab's sensor noise and the EKF
/// told it, adaptation on, 120 s at 14 J and 1 N m: the robustness
/// report's rough model + noise, where the energy balance's estimate leaves
/// the orbit forced (0 of 21 in the report). With the filter as the source
/// of candidates the plant ends within 1 % of E_ref with at most 0.1 N m
/// of torque (measured: +0.23 %, 0.030 / 0.032 N m, 2 models, excited
/// over the first 40 s; -0.28 %, 0.041 / 0.064 N m, 7 models before the
/// excitation); with the energy balance it does not (+4.1 %, 0.30 / 0.49
/// N m).
#[test]
fn the_filter_brings_a_roughly_modelled_pendulum_under_noise_to_its_mode() {
    let truth = PlanarChainParams::<2>::default();
    let prior = rough(&truth);
    let (e_ref, seconds, (angle_noise, speed_noise)) = (14.0, 120.0, (0.005, 0.05));
    let run = |filtered: bool| {
        let model = PlanarChain::new(prior).unwrap();
        let mut family = FamilyOptions::for_system(&model, &[e_ref]);
        family.degree = 9;
        let family = ChartFamily::compute::<_, 4>(&model, 0, &family).unwrap();
        let mut config = MpcConfig::paper(Variant::Curved);
        config.cost.e_ref = e_ref;
        config.substeps = prediction_substeps(&model, config.dt);
        config.estimator = Some(EstimatorConfig {
            angle_noise,
            speed_noise,
            acceleration_noise: 0.3,
        });
        let mut controller = Controller::<_, 2, 4>::with_family(model, config, family).unwrap();
        let options = AdaptOptions {
            synchronous: true,
            rls: RlsOptions {
                angle_noise,
                speed_noise,
                ..RlsOptions::default()
            },
            ..AdaptOptions::default()
        };
        let mut adaptation = Adaptation::<2, 4, 11>::new(&prior, options).unwrap();
        if filtered {
            let filter_options = StateParameterOptions {
                angle_noise,
                speed_noise,
                ..StateParameterOptions::default()
            };
            let filter =
                StateParameterEkf::<2, 4, 11, 15>::new(&prior, filter_options, config.dt).unwrap();
            adaptation.set_filter(Box::new(filter));
        }
        let plant = PlanarChain::new(truth).unwrap();
        let imperfections = Imperfections {
            measurement_noise: angle_noise,
            speed_noise: Some(speed_noise),
            seed: 3,
            ..Imperfections::default()
        };
        let out = run_imperfect(
            &mut controller,
            Some(&mut adaptation),
            &plant,
            &SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0),
            seconds,
            &imperfections,
        )
        .unwrap();
        let (energy, _) = energy_tail(&out.samples, e_ref, 5.0);
        let torque = summarise(&out.samples, e_ref, None, 5.0).rms_torque;
        let error = (energy - e_ref) / e_ref;
        eprintln!(
            "filter {filtered}: {:+.2} %, tau {:.3} / {:.3} N m, {} models",
            100.0 * error,
            torque[0],
            torque[1],
            adaptation.model_updates()
        );
        (error, torque.max())
    };
    let (error, torque) = run(true);
    assert!(error.abs() < 0.01 && torque <= 0.1, "{error} {torque}");
    let (error, torque) = run(false);
    assert!(error.abs() >= 0.01 || torque > 0.1, "{error} {torque}");
}
