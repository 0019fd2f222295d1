//! Closed loops of the controller for instruction counting (issue 12):
//! `valgrind --tool=callgrind --toggle-collect='*Controller*step*'
//! target/release/examples/rti_profile -- [rest|orbit] [SECONDS] [riccati|clarabel] [curved|straight]`
//! counts the instructions of the control steps alone; two durations
//! subtracted give the per-sample count without the first (converged SQP)
//! sample. `scripts/bench.sh` does that and prints the table.
//!
//! `rest`: the paper's start at q = (0.05, 0.05) (torque-limited transient,
//! then the orbit); `orbit`: from the 14 J in-phase mode's turning point at
//! rest, on the eigenmode from the first sample (the steady state).

use eigenmpc::mechanics::DoublePendulum;
use eigenmpc::mpc::closed_loop::{mode_and_chart, reference_for, run};
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
