//! The paper's commented-out "Hybrid EigenMPC" experiment: the chart (and
//! `c`) of the cost come from a double pendulum with `m2` 20 % higher than
//! the plant (the prediction model is the plant's), `alpha = 0.01`; curved
//! alone against hybrid, in-phase and anti-phase, from q = (0.05, 0.05) at
//! rest. Prints the RMS distance of the final path to the plant's true
//! eigenmode, the final energy and the RMS torque. Run with
//! `cargo run --release --example hybrid -- [E_ref] [duration] [beta]`.

use eigenmpc::mechanics::{DoublePendulum, PlanarChainParams};
use eigenmpc::modes::Family;
use eigenmpc::mpc::closed_loop::{energy_tail, mode_and_chart, run, summarise};
use eigenmpc::mpc::{Controller, MpcConfig, Reference, Variant};
use nalgebra::SVector;

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let e_ref = args.first().copied().unwrap_or(14.0);
    let duration = args.get(1).copied().unwrap_or(60.0);
    let beta = args.get(2).copied().unwrap_or(0.1);
    let plant = DoublePendulum::default();
    let heavier = DoublePendulum::new(PlanarChainParams::point_masses(
        [1.0, 1.2],
        [1.0, 1.0],
        9.81,
    ))
    .expect("model");
    println!(
        "chart of a pendulum with m2 +20 %, plant m = l = 1, E_ref = {e_ref} J, alpha = 0.01, beta = {beta}, {duration} s"
    );
    println!(
        "| family | variant | RMS distance to the plant's mode (rad) | chart's mode to the plant's (rad) | energy last 5 s (J) | RMS torque last 5 s (N m) |"
    );
    println!("|---|---|---|---|---|---|");
    for family in [Family::InPhase, Family::AntiPhase] {
        let (true_mode, _) =
            mode_and_chart::<_, 2, 4>(&plant, family.index(), e_ref, 9).expect("plant's mode");
        let (wrong_mode, wrong_chart) =
            mode_and_chart::<_, 2, 4>(&heavier, family.index(), e_ref, 9).expect("chart");
        let offset = rms_distance(&wrong_mode.path, &true_mode.path);
        for variant in [Variant::Curved, Variant::Hybrid] {
            let mut config = MpcConfig::paper(variant);
            config.cost.e_ref = e_ref;
            config.cost.alpha = 0.01;
            config.cost.beta = beta;
            let reference = Reference::with_chart(variant, wrong_chart.clone());
            let mut ctrl =
                Controller::<_, 2, 4>::new(plant, config, reference).expect("controller");
            let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
            let trace = run(&mut ctrl, &plant, &z0, duration).expect("closed loop");
            let s = summarise(&trace, e_ref, Some(&true_mode.path), 5.0);
            let (mean, _) = energy_tail(&trace, e_ref, 5.0);
            println!(
                "| {family} | {variant} | {:.4} | {offset:.4} | {mean:.3} | {:.4} / {:.4} |",
                s.rms_distance.unwrap_or(f64::NAN),
                s.rms_torque[0],
                s.rms_torque[1]
            );
        }
    }
}

/// RMS over `a`'s points of the distance to the path `b`.
fn rms_distance(a: &[eigenmpc::mechanics::Vector<2>], b: &[eigenmpc::mechanics::Vector<2>]) -> f64 {
    let sum: f64 = a
        .iter()
        .map(|q| eigenmpc::mpc::closed_loop::distance_to_path(q, b).powi(2))
        .sum();
    (sum / a.len() as f64).sqrt()
}
