//! The first sample's start-up ([`Startup`]) on the benchmark's robots:
//! the converged SQP (the paper's, unbounded time) against full
//! Gauss-Newton iterations in the first sample (bounded work), and what
//! each does to the closed loop (band time, energy, torque).
//! `cargo run --release --example startup` prints a markdown table;
//! `scripts/bench.sh` puts it in docs/speed.md ("The first sample").

use eigenmpc::model_file::RobotFile;
use eigenmpc::mpc::closed_loop::{START_ANGLE, energy_tail, robot_controller, run, summarise};
use eigenmpc::mpc::{Controller, Startup, Variant};
use nalgebra::SVector;

/// The robots, energies and torque bounds compared (the benchmark's
/// 2-link set-ups, and the lab robots at a second energy).
const CASES: &[(&str, f64, f64)] = &[
    ("robots/paper-double-pendulum.yml", 14.0, 1.0),
    ("robots/paper-double-pendulum.yml", 2.0, 0.5),
    ("robots/lab-double-pendulum-A0.yml", 2.0, 0.5),
    ("robots/lab-double-pendulum-A0.yml", 1.0, 0.5),
    ("robots/lab-double-pendulum-B0.yml", 2.0, 0.5),
    ("robots/lab-double-pendulum-B0.yml", 4.0, 1.0),
];

const STARTUPS: &[Startup] = &[
    Startup::Converge,
    Startup::Iterations(1),
    Startup::Iterations(5),
    Startup::Iterations(Startup::DEFAULT_ITERATIONS),
    Startup::Iterations(20),
];

fn main() {
    println!(
        "| robot | E_ref J | start-up | first sample ms | its QP iterations | band s | energy error, last 5 s (mean, % of E_ref) | RMS torque, last 5 s (N m) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for &(file, energy, tau_max) in CASES {
        let robot = RobotFile::load(root.join(file))
            .and_then(|f| f.chain::<2>())
            .expect("a 2-link robot file");
        let (built, _) =
            robot_controller::<2, 4>(&robot, Variant::Curved, energy, tau_max).expect("controller");
        let name = file.rsplit('/').next().unwrap_or(file);
        for &startup in STARTUPS {
            let mut config = *built.config();
            config.startup = startup;
            let mut ctrl =
                Controller::<_, 2, 4>::new(*built.system(), config, built.reference().clone())
                    .expect("controller");
            let z0 = SVector::<f64, 4>::new(START_ANGLE, START_ANGLE, 0.0, 0.0);
            let trace = run(&mut ctrl, &robot, &z0, 30.0).expect("closed loop");
            let summary = summarise(&trace, energy, None, 5.0);
            let (mean, _) = energy_tail(&trace, energy, 5.0);
            let label = match startup {
                Startup::Converge => "converged SQP".to_string(),
                Startup::Iterations(n) => format!("{n} Gauss-Newton iterations"),
            };
            println!(
                "| {name} | {energy} | {label} | {:.2} | {} | {} | {:+.2} % | {:.4} / {:.4} |",
                trace[0].solve_time * 1e3,
                trace[0].qp_iterations,
                summary
                    .time_to_5_percent
                    .map_or("never".into(), |t| format!("{t:.3}")),
                (mean - energy) / energy * 100.0,
                summary.rms_torque[0],
                summary.rms_torque[1]
            );
        }
    }
}
