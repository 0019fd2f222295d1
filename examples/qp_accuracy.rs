//! How accurate must the RTI's QP be? Runs the paper's curved 14 J scenario
//! (30 s from q = (0.05, 0.05)) with the clarabel backend at several
//! tolerances, and the Riccati backend at several tolerances, and compares
//! each closed loop with a reference run (clarabel, accurate settings):
//! largest energy difference over the run, time to 5 %, RMS torque over the
//! last 5 s, median QP iterations and median feedback time.
//!
//! `cargo run --release --example qp_accuracy`. Prints a markdown table.

use eigenmpc::mechanics::DoublePendulum;
use eigenmpc::modes::Family;
use eigenmpc::mpc::closed_loop::{Sample, mode_and_chart, quantile, run, summarise};
use eigenmpc::mpc::{Controller, MpcConfig, Reference, Variant};
use eigenmpc::qp::clarabel::{ClarabelQpSolver, accurate_settings, rti_settings};
use eigenmpc::qp::{QpSolver, RiccatiSettings, RiccatiSolver};
use nalgebra::SVector;

fn closed_loop(solver: Box<dyn QpSolver + Send>) -> Vec<Sample<2, 4>> {
    let sys = DoublePendulum::default();
    let (_, chart) =
        mode_and_chart::<_, 2, 4>(&sys, Family::InPhase.index(), 14.0, 9).expect("mode");
    let config = MpcConfig::paper(Variant::Curved);
    let mut ctrl = Controller::<_, 2, 4>::with_solver(
        sys,
        config,
        Reference::with_chart(Variant::Curved, chart),
        solver,
    )
    .expect("controller");
    let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
    run(&mut ctrl, &sys, &z0, 30.0).expect("plant")
}

fn main() {
    let (nx, nu, n) = (4, 2, MpcConfig::paper(Variant::Curved).horizon);
    let reference = closed_loop(Box::new(ClarabelQpSolver::new(
        nx,
        nu,
        n,
        accurate_settings(),
    )));
    let sys = DoublePendulum::default();
    let (mode, _) = mode_and_chart::<_, 2, 4>(&sys, 0, 14.0, 9).expect("mode");
    println!(
        "| QP backend | tolerance | max abs(E - E_reference) over 30 s (J) | time to 5 % (s) | RMS tau last 5 s (N m) | RMS distance (rad) | QP iterations median | feedback median (ms) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let mut cases: Vec<(&str, f64, Box<dyn QpSolver + Send>)> = Vec::new();
    for tol in [1e-3, 1e-4, 1e-6, 1e-8] {
        let mut s = rti_settings();
        s.tol_gap_abs = tol;
        s.tol_gap_rel = tol;
        s.tol_feas = tol;
        s.tol_ktratio = (10.0 * tol).min(1e-2);
        cases.push((
            "clarabel",
            tol,
            Box::new(ClarabelQpSolver::new(nx, nu, n, s)),
        ));
    }
    for tol in [1e-4, 1e-6, 1e-8, 1e-10] {
        let s = RiccatiSettings {
            tol_stationarity: tol,
            tol_feasibility: tol,
            tol_complementarity: tol,
            ..Default::default()
        };
        cases.push(("riccati", tol, Box::new(RiccatiSolver::new(nx, nu, n, s))));
    }
    for (name, tol, solver) in cases {
        let trace = closed_loop(solver);
        let diff = trace
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a.energy - b.energy).abs())
            .fold(0.0, f64::max);
        let s = summarise(&trace, 14.0, Some(&mode.path), 5.0);
        let mut iters: Vec<f64> = trace[1..].iter().map(|s| s.qp_iterations as f64).collect();
        iters.sort_by(f64::total_cmp);
        let mut fb: Vec<f64> = trace[1..]
            .iter()
            .map(|s| s.solve_time - s.preparation_time)
            .collect();
        fb.sort_by(f64::total_cmp);
        println!(
            "| {name} | {tol:.0e} | {diff:.1e} | {} | {:.4} / {:.4} | {:.4} | {} | {:.3} |",
            s.time_to_5_percent
                .map_or("not reached".into(), |t| format!("{t:.3}")),
            s.rms_torque[0],
            s.rms_torque[1],
            s.rms_distance.unwrap_or(f64::NAN),
            quantile(&iters, 0.5),
            quantile(&fb, 0.5) * 1e3
        );
    }
}
