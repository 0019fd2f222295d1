//! Closed loops of the controller for instruction counting (issue 12):
//! `valgrind --tool=callgrind --toggle-collect='*Controller*step*'
//! target/release/examples/rti_profile -- [rest|orbit] [SECONDS] [riccati|clarabel] [curved|straight] [ROBOT.yml ENERGY TAU_MAX]`
//! counts the instructions of the control steps alone; two durations
//! subtracted give the per-sample count without the first (start-up)
//! sample. `scripts/bench.sh` does that and prints the tables.
//!
//! `rest`: the paper's start at q = (0.05, 0.05) (torque-limited transient,
//! then the orbit); `orbit`: from the 14 J in-phase mode's turning point at
//! rest, on the eigenmode from the first sample (the steady state). With a
//! robot file, its energy and torque bound: that robot from rest (every
//! joint at 0.05 rad), with the controller `eigenmpc simulate --model FILE`
//! builds.

use eigenmpc::mechanics::DoublePendulum;
use eigenmpc::model_file::RobotFile;
use eigenmpc::mpc::closed_loop::{
    START_ANGLE, Sample, mode_and_chart, reference_for, robot_controller, run,
};
use eigenmpc::mpc::{Controller, MpcConfig, QpBackend, Variant};
use nalgebra::SVector;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let start = args.first().map_or("rest", String::as_str);
    let duration: f64 = args.get(1).and_then(|d| d.parse().ok()).unwrap_or(30.0);
    let backend: QpBackend = args
        .get(2)
        .map_or(Ok(QpBackend::default()), |b| b.parse())
        .expect("riccati or clarabel");
    let variant: Variant = args
        .get(3)
        .map_or(Ok(Variant::Curved), |v| v.parse())
        .expect("curved or straight");
    if let Some(path) = args.get(4) {
        let number = |i: usize, what: &str| -> f64 {
            args.get(i)
                .and_then(|v| v.parse().ok())
                .unwrap_or_else(|| panic!("{what} after the robot file"))
        };
        let (energy, tau_max) = (number(5, "ENERGY"), number(6, "TAU_MAX"));
        let file = RobotFile::load(path).expect("robot file");
        let energies: Vec<f64> = match file.links() {
            2 => robot::<2, 4>(&file, variant, backend, energy, tau_max, duration),
            3 => robot::<3, 6>(&file, variant, backend, energy, tau_max, duration),
            n => panic!("{path}: {n} links: add its line"),
        };
        println!(
            "{path}: {} samples, final energy {:.4} J",
            energies.len(),
            energies.last().copied().unwrap_or(f64::NAN)
        );
        return;
    }
    let sys = DoublePendulum::default();
    let reference = reference_for::<_, 2, 4>(&sys, variant, 0, 14.0).expect("mode");
    let mut config = MpcConfig::paper(variant);
    config.qp = backend;
    let mut ctrl = Controller::<_, 2, 4>::new(sys, config, reference).expect("controller");
    let z0 = match start {
        "orbit" => {
            let (mode, _) = mode_and_chart::<_, 2, 4>(&sys, 0, 14.0, 9).expect("14 J mode");
            let q = mode.turning_point;
            SVector::<f64, 4>::new(q[0], q[1], 0.0, 0.0)
        }
        _ => SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0),
    };
    let trace = run(&mut ctrl, &sys, &z0, duration).expect("closed loop");
    let mut histogram = std::collections::BTreeMap::new();
    for s in &trace[1..] {
        *histogram.entry(s.qp_iterations).or_insert(0usize) += 1;
    }
    println!(
        "{start}: {} samples, final energy {:.4} J, QP iterations per sample (count): {histogram:?}",
        trace.len(),
        trace.last().map_or(f64::NAN, |s| s.energy)
    );
}

/// The closed loop of the robot in `file` from rest; the plant energy at
/// every sample.
fn robot<const N: usize, const NX: usize>(
    file: &RobotFile,
    variant: Variant,
    backend: QpBackend,
    energy: f64,
    tau_max: f64,
    duration: f64,
) -> Vec<f64> {
    let robot = file.chain::<N>().expect("chain");
    let (built, _) =
        robot_controller::<N, NX>(&robot, variant, energy, tau_max).expect("controller");
    // The same controller with the QP backend asked for.
    let mut config = *built.config();
    config.qp = backend;
    let mut ctrl =
        Controller::new(*built.system(), config, built.reference().clone()).expect("controller");
    let z0 = SVector::<f64, NX>::from_fn(|i, _| if i < N { START_ANGLE } else { 0.0 });
    let trace: Vec<Sample<N, NX>> = run(&mut ctrl, &robot, &z0, duration).expect("closed loop");
    trace.iter().map(|s| s.energy).collect()
}
