//! The curved EigenMPC controller on a 3-link point-mass chain (1 kg, 1 m
//! links): from q = (0.05, 0.05, 0.05) at rest onto the in-phase eigenmode
//! at E_ref, and the torque it ends with. Run with
//! `cargo run --release --example three_link -- [E_ref] [duration]`.

use eigenmpc::mechanics::PlanarChain;
use eigenmpc::modes::{ChartFamily, FamilyOptions};
use eigenmpc::mpc::closed_loop::{energy_tail, mode_and_chart, run, summarise};
use eigenmpc::mpc::{Controller, MpcConfig, Variant};
use nalgebra::SVector;

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let e_ref = args.first().copied().unwrap_or(20.0);
    let duration = args.get(1).copied().unwrap_or(40.0);
    let sys = PlanarChain::<3>::default();
    let t = std::time::Instant::now();
    let family = ChartFamily::compute::<_, 6>(&sys, 0, &FamilyOptions::up_to(1.25 * e_ref))
        .expect("in-phase family");
    let created = t.elapsed().as_secs_f64() * 1e3;
    let mut config = MpcConfig::paper(Variant::Curved);
    config.cost.e_ref = e_ref;
    let mut ctrl = Controller::<_, 3, 6>::with_family(sys, config, family).expect("controller");
    let (mode, _) = mode_and_chart::<_, 3, 6>(&sys, 0, e_ref, 9).expect("mode");
    let z0 = SVector::<f64, 6>::new(0.05, 0.05, 0.05, 0.0, 0.0, 0.0);
    let trace = run(&mut ctrl, &sys, &z0, duration).expect("closed loop");
    let s = summarise(&trace, e_ref, Some(&mode.path), 5.0);
    let (mean, rms) = energy_tail(&trace, e_ref, 5.0);
    println!("3-link point-mass chain, curved, in-phase, E_ref = {e_ref} J, {duration} s");
    println!("family computed in {created:.1} ms");
    println!(
        "time to 5 %: {:?} s, energy last 5 s: mean {mean:.4} J, RMS error {rms:.4} J",
        s.time_to_5_percent
    );
    println!(
        "RMS torque last 5 s: {:.4} / {:.4} / {:.4} N m, RMS distance to the mode {:.4} rad",
        s.rms_torque[0],
        s.rms_torque[1],
        s.rms_torque[2],
        s.rms_distance.unwrap_or(f64::NAN)
    );
    println!(
        "solve time median {:.3} ms, p99 {:.3} ms, failures {}",
        s.solve_time[0] * 1e3,
        s.solve_time[2] * 1e3,
        s.failures
    );
}
