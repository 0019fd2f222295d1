//! Adaptation on the laboratory pendulums of `robots/` given a rough model
//! (masses, centres of mass and inertias 10-20 % off, no friction), as a
//! user's CAD model is (issue 19): with adaptation the plant's energy ends
//! within 2 % of E_ref and the torque at most 1.3 times the friction torque
//! along the orbit + 0.02 N m. Without it, A0 ends 3.6 % and B0 9.0 % low;
//! before the identification weighted its windows by their fit's residual,
//! the energy scale of A0 stayed 9 % uncertain and A0 ended 6.5 % high.
//! The runs are 90 s: with the 1 s windows of issue 37 (noise-robust) B0
//! is 2.4-3.3 % low at 60 s.

#[path = "common/rough.rs"]
mod rough_model;
use eigenmpc::adapt::{AdaptOptions, Adaptation};
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams};
use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::{ChartFamily, FamilyOptions};
use eigenmpc::mpc::closed_loop::{energy_tail, rms_friction_torque};
use eigenmpc::mpc::{Controller, MpcConfig, Variant, prediction_substeps};
use eigenmpc::robustness::{Imperfections, run_imperfect};
use nalgebra::SVector;
use rough_model::rough;

fn robot(file: &str) -> PlanarChainParams<2> {
    let path = format!("{}/robots/{file}", env!("CARGO_MANIFEST_DIR"));
    RobotFile::load(path).unwrap().params::<2>().unwrap()
}

/// 90 s at E_ref = 2 J, |tau| <= 0.5 N m: the energy error (relative), the
/// RMS torque and the plant's friction torque over the last 5 s per joint.
fn run(
    plant: PlanarChainParams<2>,
    prior: PlanarChainParams<2>,
    adapt: bool,
) -> (f64, [f64; 2], [f64; 2]) {
    let (e_ref, seconds) = (2.0, 90.0);
    let model = PlanarChain::new(prior).unwrap();
    let mut options = FamilyOptions::for_system(&model, &[e_ref]);
    options.degree = 9;
    let family = ChartFamily::compute::<_, 4>(&model, 0, &options).unwrap();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.cost.e_ref = e_ref;
    config.tau_max = 0.5;
    config.substeps = prediction_substeps(&model, config.dt);
    let mut controller = Controller::<_, 2, 4>::with_family(model, config, family).unwrap();
    let mut adaptation = Adaptation::<2, 4, 11>::new(
        &prior,
        AdaptOptions {
            synchronous: true,
            ..AdaptOptions::default()
        },
    )
    .unwrap();
    let plant = PlanarChain::new(plant).unwrap();
    let out = run_imperfect(
        &mut controller,
        adapt.then_some(&mut adaptation),
        &plant,
        &SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0),
        seconds,
        &Imperfections::default(),
    )
    .unwrap();
    let (energy, _) = energy_tail(&out.samples, e_ref, 5.0);
    let tail: Vec<_> = out
        .samples
        .iter()
        .filter(|s| s.time > seconds - 5.0 + 1e-9)
        .collect();
    let rms =
        |j: usize| (tail.iter().map(|s| s.tau[j].powi(2)).sum::<f64>() / tail.len() as f64).sqrt();
    let friction = rms_friction_torque(&out.samples, &plant, 5.0);
    eprintln!(
        "adapt {adapt}: {:+.2} %, tau {:.3} / {:.3}, friction {:.3} / {:.3}, {} models, scale sd {:.4}",
        100.0 * (energy - e_ref) / e_ref,
        rms(0),
        rms(1),
        friction[0],
        friction[1],
        adaptation.model_updates(),
        adaptation.identification().scale_uncertainty()
    );
    (
        (energy - e_ref) / e_ref,
        [rms(0), rms(1)],
        [friction[0], friction[1]],
    )
}

#[test]
fn a_rough_model_of_the_lab_robots_is_corrected() {
    for file in ["lab-double-pendulum-A0.yml", "lab-double-pendulum-B0.yml"] {
        let plant = robot(file);
        corrected(file, plant, rough(&plant));
    }
}

#[test]
fn a_lighter_link_1_than_the_model_is_found() {
    // Link 1 25 % lighter than the robot file says. The first rotor's
    // inertia and link 1's act only as one sum, which the estimate first
    // puts into the rotor (negative); cut off at zero instead of moved
    // into link 1, every candidate was refused (A0 ended 6.3 % low).
    let nominal = robot("lab-double-pendulum-A0.yml");
    let mut lighter = nominal;
    lighter.links[0].mass *= 0.75;
    corrected("A0, m1 x0.75", lighter, nominal);
}

/// Without adaptation the plant ends more than 3 % off; with it within 2 %
/// at most 1.3 times the friction torque + 0.02 N m.
fn corrected(what: &str, plant: PlanarChainParams<2>, model: PlanarChainParams<2>) {
    let (off, _, _) = run(plant, model, false);
    let (error, torque, friction) = run(plant, model, true);
    assert!(off.abs() > 0.03, "{what}: the model alone is off by {off}");
    assert!(error.abs() < 0.02, "{what}: energy error {error}");
    for j in 0..2 {
        assert!(
            torque[j] <= 1.3 * friction[j] + 0.02,
            "{what}: joint {}: torque {} vs friction {}",
            j + 1,
            torque[j],
            friction[j]
        );
    }
}
