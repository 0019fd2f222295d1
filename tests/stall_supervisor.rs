//! The stall (issue 37): a rough model of a laboratory pendulum (masses,
//! centres of mass and inertias 10-20 % off, friction unknown) made the
//! closed loop rest with a torque at its bound for the rest of the run, a
//! stalled motor on hardware. The supervisor must release it, and with the
//! adaptation the run must end on its target.
//!
//! The models: A0's is the one `../shared/reproductions.md` measured (section
//! 2: at rest at q = (-0.296, 0.773) rad with tau = (-0.5, +0.5) N m from
//! 20 s on, 73 % low). B0's was found by a seeded search: 60 models, each
//! of m1, m2, r2, I1, I2 scaled by 1 +- U(0.1, 0.2) with a random sign and
//! the friction zeroed (Python's `random.Random(k)`), run 120 s with
//! `eigenmpc simulate --adapt --no-supervisor` at 1.5 J and 0.5 N m; model
//! 52 held a torque at its bound without motion for 22 s and ended 92 %
//! low (a loop off its target for 30 s then has the adaptation try its
//! estimate, which got two others out; with the identification's 1 s
//! windows it now gets model 52 out too, after a 19.4 s stall, and 8.4 s
//! since the off-target count is taken on the energy error's 2 s mean). With the
//! supervisor, 52 of
//! the 53 valid models of that search end within 2 % (the other -2.3 %),
//! and every one of the same search on A0.

use eigenmpc::adapt::{AdaptOptions, Adaptation};
use eigenmpc::mechanics::{Link, PlanarChain, PlanarChainParams};
use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::{ChartFamily, FamilyOptions};
use eigenmpc::mpc::closed_loop::energy_tail;
use eigenmpc::mpc::{ControlStatus, Controller, MpcConfig, Variant, prediction_substeps};
use eigenmpc::robustness::{ImperfectRun, Imperfections, run_imperfect};
use nalgebra::SVector;

const TAU_MAX: f64 = 0.5;
const SECONDS: f64 = 120.0;

fn robot(file: &str) -> PlanarChainParams<2> {
    let path = format!("{}/robots/{file}", env!("CARGO_MANIFEST_DIR"));
    RobotFile::load(path).unwrap().params::<2>().unwrap()
}

/// `plant` with the factors `[m1, m2, r2, I1, I2]` applied to its robot
/// file's numbers (`I<j>` is about the joint axis) and no friction.
fn rough(plant: &PlanarChainParams<2>, f: [f64; 5]) -> PlanarChainParams<2> {
    let mut p = *plant;
    let about_joint = [0, 1].map(|j| p.links[j].inertia_about_joint() * f[3 + j]);
    p.links[0].mass *= f[0];
    p.links[1].mass *= f[1];
    p.links[1].com *= f[2];
    for (j, link) in p.links.iter_mut().enumerate() {
        *link = Link::with_inertia_about_joint(link.mass, link.length, link.com, about_joint[j]);
    }
    for joint in &mut p.joints {
        joint.viscous = 0.0;
        joint.coulomb = 0.0;
    }
    p
}

/// 120 s from 0.05 rad at rest, curved, the model's mode family.
fn run(
    plant: &PlanarChainParams<2>,
    prior: &PlanarChainParams<2>,
    e_ref: f64,
    supervisor: bool,
) -> (ImperfectRun<2, 4>, usize) {
    let model = PlanarChain::new(*prior).unwrap();
    let mut options = FamilyOptions::for_system(&model, &[e_ref]);
    options.degree = 9;
    let family = ChartFamily::compute::<_, 4>(&model, 0, &options).unwrap();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.cost.e_ref = e_ref;
    config.tau_max = TAU_MAX;
    config.substeps = prediction_substeps(&model, config.dt);
    config.supervisor.enabled = supervisor;
    let mut controller = Controller::<_, 2, 4>::with_family(model, config, family).unwrap();
    let mut adaptation = Adaptation::<2, 4, 11>::new(
        prior,
        AdaptOptions {
            synchronous: true,
            ..AdaptOptions::default()
        },
    )
    .unwrap();
    let out = run_imperfect(
        &mut controller,
        Some(&mut adaptation),
        &PlanarChain::new(*plant).unwrap(),
        &SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0),
        SECONDS,
        &Imperfections::default(),
    )
    .unwrap();
    (out, controller.supervisor_events())
}

/// The longest time a joint's torque sat at its bound while that joint
/// did not move (|qd| < 0.05 rad/s), s.
fn longest_stall(out: &ImperfectRun<2, 4>) -> f64 {
    let mut longest = 0usize;
    for j in 0..2 {
        let mut run = 0;
        for s in &out.samples {
            if s.tau[j].abs() >= 0.98 * TAU_MAX && s.state[2 + j].abs() < 0.05 {
                run += 1;
                longest = longest.max(run);
            } else {
                run = 0;
            }
        }
    }
    longest as f64 * 0.025
}

fn check(plant_file: &str, factors: [f64; 5], e_ref: f64) {
    let plant = robot(plant_file);
    let prior = rough(&plant, factors);
    let (without, _) = run(&plant, &prior, e_ref, false);
    let (with, stalls) = run(&plant, &prior, e_ref, true);
    let error =
        |out: &ImperfectRun<2, 4>| (energy_tail(&out.samples, e_ref, 5.0).0 - e_ref) / e_ref;
    let released = with
        .samples
        .iter()
        .filter(|s| s.status == ControlStatus::Released)
        .count();
    eprintln!(
        "{plant_file}: without the supervisor stalled {:.1} s, {:+.2} %; with it {:.1} s, \
         {:+.2} %, {stalls} stalls, {released} samples released",
        longest_stall(&without),
        100.0 * error(&without),
        longest_stall(&with),
        100.0 * error(&with)
    );
    // The stall is there without the supervisor (the test can fail). (How
    // the run ends without it varies: the adaptation tries its estimate
    // after 30 s off the band, which ends the B0 stall after 8.4 s; 19.4 s
    // while a limit cycle's passes through the band reset that count.)
    assert!(longest_stall(&without) > 5.0, "no stall to recover from");
    // ...and gone with it: released, and the adaptation takes the model
    // the motion before the stall identified.
    assert!(stalls >= 1);
    assert!(longest_stall(&with) <= 2.0, "{}", longest_stall(&with));
    assert!(error(&with).abs() < 0.02, "{}", error(&with));
}

#[test]
fn a0_stall_is_released_and_the_run_ends_on_target() {
    check(
        "lab-double-pendulum-A0.yml",
        [1.19, 1.178, 1.13, 0.813, 1.182],
        1.0,
    );
}

#[test]
fn b0_stall_is_released_and_the_run_ends_on_target() {
    check(
        "lab-double-pendulum-B0.yml",
        [1.105, 1.186, 1.141, 0.884, 1.183],
        1.5,
    );
}
