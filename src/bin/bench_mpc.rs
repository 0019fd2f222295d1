//! Benchmark of the EigenMPC control step (issues 3 and 5), both QP backends
//! side by side: per-sample compute time in closed loop on the paper's 14 J
//! scenarios, split into preparation
//! (shift + RK4 sensitivities + residual Jacobians + QP assembly) and
//! feedback (QP solve and step), its growth with the horizon N, and the
//! online adaptation's share (identification every sample, new models and
//! families swapped in while a worker thread computes them).
//!
//! The robots users have come first: the paper's pendulum beside the
//! laboratory pendulums of `robots/` (friction, geared motors, rigid links)
//! and two 3-link chains, each with the controller `eigenmpc simulate
//! --model FILE` builds.
//!
//! `cargo run --release --bin bench_mpc [-- --duration 30]`. Prints
//! markdown tables (`--list-robots`: the robots, one `FILE ENERGY TAU_MAX`
//! line each, for `scripts/bench.sh`'s instruction counts; `--robots-only`:
//! the robots' table alone, a few seconds). The first sample (the start-up from a zero-torque
//! guess) is reported separately and excluded from the per-sample
//! statistics.

use eigenmpc::adapt::{AdaptOptions, Adaptation};
use eigenmpc::mechanics::{DoublePendulum, PlanarChain, PlanarChainParams};
use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::{ChartFamily, FamilyOptions};
use eigenmpc::mpc::closed_loop::{
    START_ANGLE, Sample, mode_and_chart, quantile, reference_for, robot_controller, run, run_with,
    summarise,
};
use eigenmpc::mpc::{Controller, MpcConfig, QpBackend, Variant};
use eigenmpc::robustness::{Imperfections, run_imperfect};
use eigenmpc::state_parameter_ekf::{StateParameterEkf, StateParameterOptions};
use nalgebra::SVector;

fn stats(mut v: Vec<f64>) -> [f64; 4] {
    v.sort_by(f64::total_cmp);
    [
        quantile(&v, 0.5),
        quantile(&v, 0.95),
        quantile(&v, 0.99),
        *v.last().unwrap_or(&f64::NAN),
    ]
}

fn ms(x: [f64; 4]) -> String {
    format!(
        "{:.3} | {:.3} | {:.3} | {:.3}",
        x[0] * 1e3,
        x[1] * 1e3,
        x[2] * 1e3,
        x[3] * 1e3
    )
}

/// Where a closed loop starts: the paper's near-rest start, or on the
/// 14 J in-phase eigenmode (its turning point at rest: the steady state).
#[derive(Clone, Copy, PartialEq)]
enum Start {
    Rest,
    Orbit,
}

fn run_case(
    variant: Variant,
    horizon: usize,
    duration: f64,
    backend: QpBackend,
) -> Vec<Sample<2, 4>> {
    run_from(Start::Rest, variant, horizon, duration, backend)
}

fn run_from(
    start: Start,
    variant: Variant,
    horizon: usize,
    duration: f64,
    backend: QpBackend,
) -> Vec<Sample<2, 4>> {
    let sys = DoublePendulum::default();
    let reference = reference_for::<_, 2, 4>(&sys, variant, 0, 14.0).expect("14 J mode");
    let mut config = MpcConfig::paper(variant);
    config.horizon = horizon;
    config.qp = backend;
    // Keep the simulated dynamics identical across N: same sample period.
    let mut ctrl = Controller::<_, 2, 4>::new(sys, config, reference).expect("controller");
    let z0 = match start {
        Start::Rest => SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0),
        Start::Orbit => {
            let (mode, _) = mode_and_chart::<_, 2, 4>(&sys, 0, 14.0, 9).expect("14 J mode");
            SVector::<f64, 4>::new(mode.turning_point[0], mode.turning_point[1], 0.0, 0.0)
        }
    };
    run(&mut ctrl, &sys, &z0, duration).expect("closed loop")
}

/// The CPU's model name (Linux), for the tables' headings.
fn cpu() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

fn main() {
    let mut duration = 30.0;
    let args: Vec<String> = std::env::args().collect();
    if args.iter().any(|a| a == "--list-robots") {
        // For scripts/bench.sh's instruction counts: the same robots.
        for case in ROBOTS {
            println!("{} {} {}", case.file, case.energy, case.tau_max);
        }
        return;
    }
    if let Some(i) = args.iter().position(|a| a == "--duration") {
        duration = args
            .get(i + 1)
            .and_then(|v| v.parse().ok())
            .filter(|d: &f64| *d > 0.0)
            .unwrap_or_else(|| {
                eprintln!("error: --duration needs a positive number of seconds");
                std::process::exit(2)
            });
    }
    robots_table(duration);
    if args.iter().any(|a| a == "--robots-only") {
        return;
    }
    println!(
        "\n## EigenMPC control step, N = 80, dt = 25 ms, {duration} s closed loop, both QP backends\n"
    );
    println!(
        "Measured on {} ({} threads). The ratio column divides the sample median by clarabel's in the same run (same process, same machine state): it moves less between machines than the times. QP iterations are Riccati recursions per sample: the guesses of riccati's active-set start where it solves the QP, the interior point's iterations otherwise (clarabel: its interior-point iterations).\n",
        cpu(),
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );
    println!(
        "| scenario | QP | phase | median ms | p95 ms | p99 ms | max ms | QP iter. median / max | sample median / clarabel's |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (start, variant, name) in [
        (
            Start::Rest,
            Variant::Curved,
            "curved 14 J in-phase, from rest",
        ),
        (
            Start::Rest,
            Variant::Straight,
            "straight 14 J in-phase, from rest",
        ),
        (
            Start::Orbit,
            Variant::Curved,
            "curved 14 J in-phase, on the orbit",
        ),
    ] {
        let traces: Vec<(QpBackend, Vec<Sample<2, 4>>)> = QpBackend::ALL
            .into_iter()
            .map(|b| (b, run_from(start, variant, 80, duration, b)))
            .collect();
        let median_total =
            |trace: &[Sample<2, 4>]| stats(trace[1..].iter().map(|s| s.solve_time).collect())[0];
        let clarabel = traces
            .iter()
            .find(|(b, _)| *b == QpBackend::Clarabel)
            .map_or(f64::NAN, |(_, t)| median_total(t));
        for (backend, trace) in &traces {
            let rest = &trace[1..];
            let prep: Vec<f64> = rest.iter().map(|s| s.preparation_time).collect();
            let feedback: Vec<f64> = rest
                .iter()
                .map(|s| s.solve_time - s.preparation_time)
                .collect();
            let total: Vec<f64> = rest.iter().map(|s| s.solve_time).collect();
            let iters = stats(rest.iter().map(|s| s.qp_iterations as f64).collect());
            let failures = rest.iter().filter(|s| !s.status.is_ok()).count();
            println!(
                "| {name} | {backend} | preparation | {} | | |",
                ms(stats(prep))
            );
            println!(
                "| {name} | {backend} | feedback (QP) | {} | {:.0} / {:.0} | |",
                ms(stats(feedback)),
                iters[0],
                iters[3]
            );
            println!(
                "| {name} | {backend} | total | {} | | {:.3} |",
                ms(stats(total)),
                median_total(trace) / clarabel
            );
            println!(
                "| {name} | {backend} | first sample (start-up, cold start) | {:.3} | | | | {failures} failed samples | |",
                trace[0].solve_time * 1e3
            );
        }
    }
    println!("\n## Growth with the horizon (curved 14 J, {duration} s closed loop)\n");
    println!(
        "| N | QP | total median ms | p95 | p99 | max | preparation median ms | feedback median ms | median per interval us | QP iter. median |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for n in [20, 40, 80, 160, 320] {
        for backend in QpBackend::ALL {
            let trace = run_case(Variant::Curved, n, duration, backend);
            let rest = &trace[1..];
            let total = stats(rest.iter().map(|s| s.solve_time).collect());
            let prep = stats(rest.iter().map(|s| s.preparation_time).collect());
            let fb = stats(
                rest.iter()
                    .map(|s| s.solve_time - s.preparation_time)
                    .collect(),
            );
            let iters = stats(rest.iter().map(|s| s.qp_iterations as f64).collect());
            println!(
                "| {n} | {backend} | {} | {:.3} | {:.3} | {:.1} | {:.0} |",
                ms(total),
                prep[0] * 1e3,
                fb[0] * 1e3,
                total[0] * 1e6 / n as f64,
                iters[0]
            );
        }
    }
    three_link_table(duration.max(40.0));
    adaptation_table(duration.max(60.0));
}

/// A robot of the benchmark: its file (under the workspace root), the
/// reference energy and the torque bound.
struct RobotCase {
    file: &'static str,
    energy: f64,
    tau_max: f64,
    /// Closed-loop length (s): at least the benchmark's, long enough to
    /// reach the band.
    duration: f64,
}

/// The robots of [`robots_table`]: the paper's pendulum and 3-link chain
/// (point masses, no friction), the laboratory pendulums at the set-up of
/// the book's speed chapter (`docs/book/src/performance.md`), and a 3-link
/// rigid chain with friction.
const ROBOTS: &[RobotCase] = &[
    RobotCase {
        file: "robots/paper-double-pendulum.yml",
        energy: 14.0,
        tau_max: 1.0,
        duration: 30.0,
    },
    RobotCase {
        file: "robots/lab-double-pendulum-A0.yml",
        energy: 2.0,
        tau_max: 0.5,
        duration: 30.0,
    },
    RobotCase {
        file: "robots/lab-double-pendulum-B0.yml",
        energy: 2.0,
        tau_max: 0.5,
        duration: 30.0,
    },
    RobotCase {
        file: "robots/three-link-point-masses.yml",
        energy: 14.0,
        tau_max: 1.0,
        duration: 60.0,
    },
    RobotCase {
        file: "robots/examples/three-link-rigid.yml",
        energy: 1.0,
        tau_max: 1.0,
        duration: 30.0,
    },
];

/// Per-sample cost on each robot of [`ROBOTS`]: curved, riccati, N = 80,
/// from every joint at 0.05 rad at rest, the controller `eigenmpc simulate
/// --model FILE --energy E --tau-max T` builds.
fn robots_table(duration: f64) {
    println!(
        "## The control step on each robot (curved, riccati, N = 80, dt = 25 ms, from rest, at least {duration} s; on {})\n",
        cpu()
    );
    println!(
        "Times in ms; the first sample (the start-up from a zero-torque guess) apart, the others' statistics without it. RK4 substeps: the most an interval takes (what the friction needs with a joint at rest) and the mean over the intervals of all samples (only intervals in which a joint may stop take the most). Preparation is the shift and the linearisation (RK4 substeps with sensitivities, cost Jacobians, the QP's stages), feedback the QP solve. QP recursions: the Riccati recursions of the active-set start where it solves the QP, else the interior point's iterations; \"active-set start\": the share of samples it solved. The last column divides the median by the paper pendulum's (the first row) in the same run.\n"
    );
    println!(
        "| robot | E_ref J | s | RK4 substeps most / mean | band s | first sample | median | p95 | p99 | max | preparation median | feedback median | QP recursions median / max | active-set start | median / paper's |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut paper_median = None;
    for case in ROBOTS {
        let file = RobotFile::load(root.join(case.file)).expect("robot file");
        let (median, row) = match file.links() {
            2 => robot_row::<2, 4>(&file, case, duration.max(case.duration)),
            3 => robot_row::<3, 6>(&file, case, duration.max(case.duration)),
            n => panic!("{}: {n} links: add its row", case.file),
        };
        let paper = *paper_median.get_or_insert(median);
        println!("{row} {:.2} |", median / paper);
    }
}

/// One row of [`robots_table`] but its last cell, and the sample median (s).
fn robot_row<const N: usize, const NX: usize>(
    file: &RobotFile,
    case: &RobotCase,
    duration: f64,
) -> (f64, String) {
    let robot = file.chain::<N>().expect("chain");
    let (mut ctrl, _) =
        robot_controller::<N, NX>(&robot, Variant::Curved, case.energy, case.tau_max)
            .expect("controller");
    let substeps = ctrl.config().substeps;
    let z0 = SVector::<f64, NX>::from_fn(|i, _| if i < N { START_ANGLE } else { 0.0 });
    let mut by_start = Vec::new();
    let mut substeps_taken = 0;
    let trace = run_with(&mut ctrl, &robot, &z0, duration, |i, c, _| {
        if i > 0 {
            by_start.push(c.last_qp_solved_by_start() == Some(true));
            substeps_taken += c.last_linearisation_substeps();
        }
    })
    .expect("closed loop");
    let band = summarise(&trace, case.energy, None, 5.0)
        .time_to_5_percent
        .map_or("never".to_string(), |t| format!("{t:.3}"));
    let rest = &trace[1..];
    let total = stats(rest.iter().map(|s| s.solve_time).collect());
    let prep = stats(rest.iter().map(|s| s.preparation_time).collect());
    let feedback = stats(
        rest.iter()
            .map(|s| s.solve_time - s.preparation_time)
            .collect(),
    );
    let iters = stats(rest.iter().map(|s| s.qp_iterations as f64).collect());
    let share = by_start.iter().filter(|&&b| b).count() as f64 / by_start.len().max(1) as f64;
    let name = case.file.rsplit('/').next().unwrap_or(case.file);
    let horizon = ctrl.config().horizon;
    let mean_substeps = substeps_taken as f64 / (by_start.len().max(1) * horizon) as f64;
    let row = format!(
        "| {name} | {} | {duration} | {substeps} / {mean_substeps:.2} | {band} | {:.3} | {} | {:.3} | {:.3} | {:.0} / {:.0} | {:.0} % |",
        case.energy,
        trace[0].solve_time * 1e3,
        ms(total),
        prep[0] * 1e3,
        feedback[0] * 1e3,
        iters[0],
        iters[3],
        share * 100.0
    );
    (total[0], row)
}

/// The 3-link point-mass chain (1 kg, 1 m), curved on its in-phase family
/// at 20 J, N = 80: from rest, and on the orbit (the mode's turning point).
fn three_link_table(duration: f64) {
    println!(
        "\n## Three links (curved, in-phase family, E_ref = 20 J, N = 80, {duration} s; on {})\n",
        cpu()
    );
    println!(
        "| start | QP | median ms | p95 ms | p99 ms | max ms | QP iter. median / max | sample median / clarabel's |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let sys = PlanarChain::<3>::default();
    let family = ChartFamily::compute::<_, 6>(&sys, 0, &FamilyOptions::up_to(25.0))
        .expect("3-link in-phase family");
    let (mode, _) = mode_and_chart::<_, 3, 6>(&sys, 0, 20.0, 9).expect("20 J mode");
    for (name, z0) in [
        (
            "rest",
            SVector::<f64, 6>::new(0.05, 0.05, 0.05, 0.0, 0.0, 0.0),
        ),
        (
            "orbit",
            SVector::<f64, 6>::new(
                mode.turning_point[0],
                mode.turning_point[1],
                mode.turning_point[2],
                0.0,
                0.0,
                0.0,
            ),
        ),
    ] {
        let mut rows = vec![];
        for backend in QpBackend::ALL {
            let mut config = MpcConfig::paper(Variant::Curved);
            config.cost.e_ref = 20.0;
            config.qp = backend;
            let mut ctrl = Controller::<_, 3, 6>::with_family(sys, config, family.clone())
                .expect("controller");
            let trace = run(&mut ctrl, &sys, &z0, duration).expect("closed loop");
            let rest = &trace[1..];
            let total = stats(rest.iter().map(|s| s.solve_time).collect());
            let iters = stats(rest.iter().map(|s| s.qp_iterations as f64).collect());
            rows.push((backend, total, iters));
        }
        let clarabel = rows
            .iter()
            .find(|r| r.0 == QpBackend::Clarabel)
            .map_or(f64::NAN, |r| r.1[0]);
        for (backend, total, iters) in rows {
            println!(
                "| {name} | {backend} | {} | {:.0} / {:.0} | {:.3} |",
                ms(total),
                iters[0],
                iters[3],
                total[0] / clarabel
            );
        }
    }
}

/// The robustness issue's plant (m2 +20 %, l1 +10 %, 0.05 N m s damping)
/// under the paper's model, curved on its 14 J family, with and without
/// real-time adaptation (the sample never waits: the worker runs on the
/// other core).
fn adaptation_table(duration: f64) {
    println!(
        "\n## Online adaptation, real-time (curved 14 J, N = 80, plant m2 +20 %, l1 +10 %, b 0.05; {duration} s)\n"
    );
    println!(
        "| adapt | phase | median ms | p95 ms | p99 ms | max ms | models swapped in | final energy J |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let mut plant_params = PlanarChainParams::<2>::point_masses([1.0, 1.2], [1.1, 1.0], 9.81);
    plant_params.joints[0].viscous = 0.05;
    plant_params.joints[1].viscous = 0.05;
    let plant = PlanarChain::new(plant_params).expect("plant");
    let prior = PlanarChainParams::<2>::default();
    // Off; on with the energy balance; on with the state and parameters
    // estimated together (its excitation over the first 40 s).
    for (adapt, filtered) in [(false, false), (true, false), (true, true)] {
        let model = PlanarChain::new(prior).expect("model");
        let family =
            ChartFamily::compute::<_, 4>(&model, 0, &FamilyOptions::for_system(&model, &[14.0]))
                .expect("family");
        let config = MpcConfig::paper(Variant::Curved);
        let mut ctrl = Controller::<_, 2, 4>::with_family(model, config, family).expect("ctrl");
        let mut adaptation =
            Adaptation::<2, 4, 11>::new(&prior, AdaptOptions::default()).expect("adaptation");
        if filtered {
            let filter = StateParameterEkf::<2, 4, 11, 15>::new(
                &prior,
                StateParameterOptions::default(),
                config.dt,
            )
            .expect("filter");
            adaptation.set_filter(Box::new(filter));
        }
        let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
        let run = run_imperfect(
            &mut ctrl,
            adapt.then_some(&mut adaptation),
            &plant,
            &z0,
            duration,
            &Imperfections::default(),
        )
        .expect("closed loop");
        let rest = &run.samples[1..];
        let adapt_time = &run.adaptation_time[1..];
        let prep: Vec<f64> = rest.iter().map(|s| s.preparation_time).collect();
        let feedback: Vec<f64> = rest
            .iter()
            .map(|s| s.solve_time - s.preparation_time)
            .collect();
        let total: Vec<f64> = rest
            .iter()
            .zip(adapt_time)
            .map(|(s, a)| s.solve_time + a)
            .collect();
        let label = match (adapt, filtered) {
            (false, _) => "off",
            (true, false) => "on",
            (true, true) => "on, state and parameters",
        };
        let energy = run.samples.last().map_or(f64::NAN, |s| s.energy);
        if adapt {
            println!(
                "| {label} | identification + model swap | {} | | |",
                ms(stats(adapt_time.to_vec()))
            );
        }
        println!("| {label} | preparation | {} | | |", ms(stats(prep)));
        println!("| {label} | feedback (QP) | {} | | |", ms(stats(feedback)));
        println!(
            "| {label} | total | {} | {} | {energy:.4} |",
            ms(stats(total)),
            run.model_updates
        );
    }
}
