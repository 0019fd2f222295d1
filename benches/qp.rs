//! QP solve times on double-pendulum RTI-shaped QPs (dt = 0.025, torque
//! boxes |tau| <= 1 and <= 0.2, soft velocity bounds): the Riccati
//! interior-point solver against a plain clarabel solve (assembly, set-up and
//! solve from scratch every time, as without a structure-aware backend).
//!
//! Run: `cargo bench --bench qp` (optionally `-- --quick`).

#[path = "../tests/common/qp_reference.rs"]
mod qp_reference;

use eigenmpc::qp::synthetic::{PendulumQpOptions, SplitMix64, pendulum_rti_qp};
use eigenmpc::qp::{OcpQp, QpSolution, QpSolver, RiccatiSettings, RiccatiSolver, kkt_residuals};
use std::hint::black_box;
use std::time::Instant;

/// Timing statistics in milliseconds.
struct Stats {
    median: f64,
    p95: f64,
    p99: f64,
    max: f64,
}

fn stats(mut t: Vec<f64>) -> Stats {
    t.sort_by(f64::total_cmp);
    // The same quantile definition as the closed-loop tables (nearest rank).
    let q = |p: f64| eigenmpc::mpc::closed_loop::quantile(&t, p);
    Stats {
        median: q(0.5),
        p95: q(0.95),
        p99: q(0.99),
        max: *t.last().expect("samples"),
    }
}

fn qp_set(horizon: usize, count: usize, seed: u64) -> Vec<OcpQp> {
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .map(|i| {
            let opts = PendulumQpOptions {
                horizon,
                tau_max: if i % 2 == 0 { 1.0 } else { 0.2 },
                initial_deviation: if i % 4 < 2 { 0.01 } else { 0.5 },
                ..Default::default()
            };
            pendulum_rti_qp(&mut rng, &opts)
        })
        .collect()
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let (n_riccati, n_clarabel) = if quick { (50, 10) } else { (400, 60) };
    println!(
        "QP solve time (ms) on double-pendulum RTI QPs, nx = 4, nu = 2; \
         {n_riccati} QPs per N for riccati, {n_clarabel} for clarabel"
    );
    println!(
        "| N | solver | median | p95 | p99 | max | median/N (us) | iterations (mean/max) | worst KKT (rel. stat.) | failed |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut linear = Vec::new();
    for &n in &[20, 40, 80, 160, 320] {
        let qps = qp_set(n, n_riccati, 1000 + n as u64);
        // The default (Mehrotra start) and the plain start, for comparison.
        let plain = RiccatiSettings {
            mehrotra_start: false,
            ..Default::default()
        };
        for (name, settings) in [
            ("riccati", RiccatiSettings::default()),
            ("riccati (plain start)", plain),
        ] {
            let per_stage = riccati_row(n, name, settings, &qps);
            if name == "riccati" {
                linear.push((n, per_stage));
            }
        }

        let (mut times, mut iters, mut failed) = (Vec::new(), Vec::new(), 0);
        for qp in qps.iter().take(n_clarabel) {
            let start = Instant::now();
            let reference = qp_reference::clarabel_solve_with(black_box(qp), 1e-8);
            times.push(start.elapsed().as_secs_f64() * 1e3);
            if reference.solved {
                iters.push(reference.iterations as usize);
            } else {
                failed += 1;
            }
        }
        print_row(
            n,
            "clarabel (fresh)",
            stats(times),
            &iters,
            f64::NAN,
            failed,
        );
    }
    // Linear growth: the cost of one interior-point iteration per stage.
    println!();
    println!("| N | riccati time per iteration per stage, median (ns) |");
    println!("|---|---|");
    for (n, t) in linear {
        println!("| {n} | {t:.0} |");
    }
}

/// Times the Riccati solver on `qps`, prints the row and returns the median
/// time per iteration per stage (ns).
fn riccati_row(n: usize, name: &str, settings: RiccatiSettings, qps: &[OcpQp]) -> f64 {
    let mut solver = RiccatiSolver::new(4, 2, n, settings);
    let mut sol = QpSolution::new(4, 2, n);
    // Warm the caches once.
    solver.solve(&qps[0], &mut sol);
    let (mut times, mut iters, mut worst_kkt) = (Vec::new(), Vec::new(), 0.0f64);
    let mut failed = 0;
    let mut per_stage_iter = Vec::new();
    for qp in qps {
        let start = Instant::now();
        let status = solver.solve(black_box(qp), &mut sol);
        times.push(start.elapsed().as_secs_f64() * 1e3);
        if !status.is_usable() {
            failed += 1;
            eprintln!("{name} N = {n}: {status:?} {:?}", solver.info());
            continue;
        }
        iters.push(sol.iterations);
        per_stage_iter
            .push(times.last().copied().unwrap_or(0.0) * 1e6 / (n * sol.iterations.max(1)) as f64);
        let kkt = kkt_residuals(qp, &sol);
        // Stationarity relative to its round-off scale when that is large.
        let stat = kkt.stationarity / kkt.stationarity_scale.max(1.0);
        worst_kkt = worst_kkt
            .max(stat)
            .max(kkt.primal_feasibility)
            .max(kkt.complementarity);
    }
    print_row(n, name, stats(times), &iters, worst_kkt, failed);
    stats(per_stage_iter).median
}

fn print_row(n: usize, name: &str, s: Stats, iters: &[usize], kkt: f64, failed: usize) {
    let mean = iters.iter().sum::<usize>() as f64 / iters.len() as f64;
    let max = iters.iter().max().copied().unwrap_or(0);
    let kkt = if kkt.is_nan() {
        "-".to_string()
    } else {
        format!("{kkt:.1e}")
    };
    println!(
        "| {n} | {name} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | {mean:.1}/{max} | {kkt} | {failed} |",
        s.median,
        s.p95,
        s.p99,
        s.max,
        s.median * 1e3 / n as f64
    );
}
