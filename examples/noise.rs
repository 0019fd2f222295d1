//! Measurement noise against the state estimator: the paper's pendulum,
//! curved at 14 J from q = (0.05, 0.05), 60 s, every measured angle and
//! speed with Gaussian noise of standard deviation `sigma` (rad, rad/s);
//! without the estimator and with it for several process-noise levels.
//! Run with `cargo run --release --example noise -- [sigma] [duration]`.

use eigenmpc::mechanics::DoublePendulum;
use eigenmpc::mpc::closed_loop::{
    GaussianNoise, energy_tail, mode_and_chart, run_measured, summarise,
};
use eigenmpc::mpc::{Controller, EstimatorConfig, MpcConfig, Reference, Variant};
use nalgebra::SVector;

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let sigma = args.first().copied().unwrap_or(0.05);
    let duration = args.get(1).copied().unwrap_or(60.0);
    let sys = DoublePendulum::default();
    let (mode, chart) = mode_and_chart::<_, 2, 4>(&sys, 0, 14.0, 9).expect("mode");
    println!("curved 14 J, measurement noise {sigma} rad, rad/s, {duration} s");
    println!(
        "| estimator | acceleration noise (rad/s^2) | energy last 5 s (J) | RMS torque last 5 s (N m) | RMS distance (rad) | median solve (ms) |"
    );
    println!("|---|---|---|---|---|---|");
    for accel in [None, Some(0.3), Some(1.0), Some(3.0), Some(10.0)] {
        let mut config = MpcConfig::paper(Variant::Curved);
        config.estimator = accel.map(|a| EstimatorConfig {
            angle_noise: sigma,
            speed_noise: sigma,
            acceleration_noise: a,
        });
        let mut ctrl = Controller::<_, 2, 4>::new(
            sys,
            config,
            Reference::with_chart(Variant::Curved, chart.clone()),
        )
        .expect("controller");
        let mut noise = GaussianNoise::new(1);
        let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
        let trace = run_measured(
            &mut ctrl,
            &sys,
            &z0,
            duration,
            |_, _| {},
            |_, z| noise.measure(z, sigma, sigma),
        )
        .expect("closed loop");
        let s = summarise(&trace, 14.0, Some(&mode.path), 5.0);
        let (mean, _) = energy_tail(&trace, 14.0, 5.0);
        println!(
            "| {} | {} | {mean:.3} | {:.4} / {:.4} | {:.4} | {:.3} |",
            if accel.is_some() { "EKF" } else { "none" },
            accel.map_or("-".into(), |a| a.to_string()),
            s.rms_torque[0],
            s.rms_torque[1],
            s.rms_distance.unwrap_or(f64::NAN),
            s.solve_time[0] * 1e3
        );
    }
}
