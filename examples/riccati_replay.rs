//! Replays the RTI QPs of a closed loop through the Riccati solver with the
//! controller's warm start, for profiling the QP alone (e.g. under
//! `valgrind --tool=callgrind --toggle-collect='*riccati*replay_solve*'`)
//! and timing it without the rest of the control step.
//!
//! `cargo run --release --example riccati_replay [-- SECONDS [REPEATS]]`

use eigenmpc::mechanics::DoublePendulum;
use eigenmpc::mpc::closed_loop::{reference_for, run_with};
use eigenmpc::mpc::{Controller, MpcConfig, QpBackend, Variant};
use eigenmpc::qp::{OcpQp, QpSolution, QpSolver, RiccatiSettings, RiccatiSolver};
use nalgebra::SVector;
use std::time::Instant;

fn record(variant: Variant, seconds: f64) -> Vec<OcpQp> {
    let sys = DoublePendulum::default();
    let reference = reference_for::<_, 2, 4>(&sys, variant, 0, 14.0).unwrap();
    let mut config = MpcConfig::paper(variant);
    config.qp = QpBackend::Riccati;
    let mut ctrl = Controller::<_, 2, 4>::new(sys, config, reference).unwrap();
    let mut qps = Vec::new();
    let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
    let duration = seconds - config.dt;
    run_with(&mut ctrl, &sys, &z0, duration, |_, ctrl, _| {
        qps.push(ctrl.last_qp().0)
    })
    .unwrap();
    qps
}

#[inline(never)]
fn replay_solve(solver: &mut RiccatiSolver, qp: &OcpQp, sol: &mut QpSolution) {
    solver.solve(qp, sol);
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seconds: f64 = args.get(1).and_then(|v| v.parse().ok()).unwrap_or(10.0);
    let repeats: usize = args.get(2).and_then(|v| v.parse().ok()).unwrap_or(1);
    for variant in [Variant::Curved, Variant::Straight] {
        let qps = record(variant, seconds);
        let mut times = Vec::new();
        let (mut iters, mut check) = (0usize, 0.0f64);
        for rep in 0..repeats {
            let mut set = RiccatiSettings::default();
            let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
            if let Some(t) = env("TOL") {
                set.tol_stationarity = t;
                set.tol_feasibility = t;
                set.tol_complementarity = t;
            }
            if let Some(f) = env("FLOOR") {
                set.warm_start_floor = f;
            }
            if let Some(m) = env("MEHROTRA") {
                set.mehrotra_start = m > 0.0;
            }
            let mut solver = RiccatiSolver::new(4, 2, 80, set);
            let mut sol = QpSolution::new(4, 2, 80);
            for (i, qp) in qps.iter().enumerate() {
                solver.shift_warm_start(i > 0);
                let start = Instant::now();
                replay_solve(&mut solver, qp, &mut sol);
                times.push(start.elapsed().as_secs_f64());
                if rep == 0 {
                    iters += sol.iterations;
                    check += sol.u[0].iter().map(|v| v.abs()).sum::<f64>() + sol.objective;
                }
            }
        }
        times.sort_by(f64::total_cmp);
        println!(
            "{variant}: {} QPs, iterations {iters} ({:.2}/QP), median {:.4} ms, checksum {check:.12e}",
            qps.len(),
            iters as f64 / qps.len() as f64,
            times[times.len() / 2] * 1e3
        );
    }
}
