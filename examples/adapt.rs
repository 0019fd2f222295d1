//! The robustness issue's scenario: the plant has m2 +20 %, l1 +10 % and
//! viscous damping 0.05 N m s on both joints, the controller's model is the
//! paper's pendulum. Curved EigenMPC on the model's mode family at 14 J from
//! (0.05, 0.05), with and without online adaptation (`eigenmpc::adapt`:
//! energy-balance identification every sample, the model and its family
//! recomputed on a worker thread and swapped in, looked at every `period`
//! s). Run with `cargo run --release --example adapt -- [duration] [period]`.

use eigenmpc::adapt::{AdaptOptions, Adaptation};
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams, Vector};
use eigenmpc::modes::{ChartFamily, FamilyOptions};
use eigenmpc::mpc::closed_loop::{Sample, distance_to_path, mode_and_chart};
use eigenmpc::mpc::{Controller, MpcConfig, Variant};
use eigenmpc::robustness::{Imperfections, run_imperfect};
use nalgebra::SVector;

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let duration = args.first().copied().unwrap_or(60.0);
    let period = args.get(1).copied().unwrap_or(2.0);
    let mut plant_params = PlanarChainParams::<2>::point_masses([1.0, 1.2], [1.1, 1.0], 9.81);
    plant_params.joints[0].viscous = 0.05;
    plant_params.joints[1].viscous = 0.05;
    let plant = PlanarChain::new(plant_params).unwrap();
    let prior = PlanarChainParams::<2>::default();
    let (true_mode, _) = mode_and_chart::<_, 2, 4>(&plant, 0, 14.0, 9).expect("the plant's mode");
    println!(
        "plant m2 +20 %, l1 +10 %, b 0.05; model: the paper's pendulum; curved 14 J, {duration} s"
    );
    println!(
        "| adapt | energy at the end (J) | mean energy last 5 s (J) | RMS torque last 5 s (N m) | RMS damping torque (N m) | RMS distance to the plant's mode (rad) | model updates |"
    );
    println!("|---|---|---|---|---|---|---|");
    for adapt in [false, true] {
        let model = PlanarChain::new(prior).unwrap();
        let family =
            ChartFamily::compute::<_, 4>(&model, 0, &FamilyOptions::for_system(&model, &[14.0]))
                .unwrap();
        let config = MpcConfig::paper(Variant::Curved);
        let mut ctrl = Controller::<_, 2, 4>::with_family(model, config, family).unwrap();
        let mut adaptation = Adaptation::<2, 4, 11>::new(
            &prior,
            AdaptOptions {
                period: (period / config.dt).round() as usize,
                // reproducible figures: wait for each model (offline only)
                synchronous: true,
                ..AdaptOptions::default()
            },
        )
        .unwrap();
        let run = run_imperfect(
            &mut ctrl,
            adapt.then_some(&mut adaptation),
            &plant,
            &SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0),
            duration,
            &Imperfections::default(),
        )
        .unwrap();
        let tail: Vec<_> = run
            .samples
            .iter()
            .filter(|s| s.time > duration - 5.0 + 1e-9)
            .collect();
        let n = tail.len() as f64;
        let mean_e = tail.iter().map(|s| s.energy).sum::<f64>() / n;
        let rms = |f: &dyn Fn(&Sample<2, 4>) -> f64| {
            (tail.iter().map(|s| f(s).powi(2)).sum::<f64>() / n).sqrt()
        };
        let tau_rms = [rms(&|s| s.tau[0]), rms(&|s| s.tau[1])];
        let damping = [rms(&|s| 0.05 * s.state[2]), rms(&|s| 0.05 * s.state[3])];
        let dist =
            rms(&|s| distance_to_path(&Vector::<2>::new(s.state[0], s.state[1]), &true_mode.path));
        println!(
            "| {} | {:.4} | {mean_e:.4} | {:.4} / {:.4} | {:.4} / {:.4} | {dist:.4} | {} |",
            if adapt { "on" } else { "off" },
            run.samples.last().unwrap().energy,
            tau_rms[0],
            tau_rms[1],
            damping[0],
            damping[1],
            run.model_updates
        );
    }
}
