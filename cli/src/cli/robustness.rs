//! `eigenmpc robustness`: the robustness report v2 of the controller FMU's
//! default controller on a nominal robot (see `eigenmpc_cli::robustness`),
//! every case without and with online adaptation, on all local cores.

use super::ModelArgs;
use anyhow::{Context, bail};
use clap::Args;
use eigenmpc_cli::report::number;
use eigenmpc_cli::robustness::report::{RunPair, csv, markdown, plot};
use eigenmpc_cli::robustness::{CATEGORIES, Setup, Sweep, default_cases, run_case};
use indicatif::{ParallelProgressIterator, ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::path::PathBuf;

/// Arguments of `eigenmpc robustness`.
#[derive(Args, Debug)]
pub struct RobustnessArgs {
    /// The nominal robot: the controller's model, which every case perturbs.
    #[command(flatten)]
    model: ModelArgs,
    /// Reference energy E_ref (J).
    #[arg(long, default_value_t = 14.0, allow_negative_numbers = true)]
    energy: f64,
    /// Torque bound (N m).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    tau_max: f64,
    /// Simulated time of each run (s); the last 5 s are scored.
    #[arg(long, default_value_t = 60.0, allow_negative_numbers = true)]
    duration: f64,
    /// Values per swept range, ends included (the benchmark's 21).
    #[arg(long, default_value_t = 21)]
    steps: usize,
    /// Random torque-pulse profiles (the benchmark's 50).
    #[arg(long, default_value_t = 50)]
    pulses: usize,
    /// Only these categories (comma-separated, e.g. `mass,measurement delay`).
    #[arg(long)]
    categories: Option<String>,
    /// Output folder: robustness.md, robustness.csv, robustness.png and .svg.
    #[arg(long, default_value = "target/robustness")]
    out: PathBuf,
    /// Filter the measurements with the controller's extended Kalman filter in every case (without
    /// this flag only where the sensors are noisy), told each case's measurement noise (at least
    /// 0.005 rad, rad/s).
    #[arg(long)]
    ekf: bool,
    /// Do not tell the controller the case's motor response and measurement delay (by default
    /// it is told them, as its filter is told the noise): robustness to them unmodelled.
    #[arg(long)]
    undeclared: bool,
    /// Where the adaptation's candidate models come from (the controller FMU's
    /// `adapt_estimator`): `energy_balance` or `state_and_parameters`.
    #[arg(long, default_value = "energy_balance")]
    adapt_estimator: String,
    /// Worker threads (default: all local cores); the numbers do not depend on it.
    #[arg(long)]
    threads: Option<usize>,
}

/// How the cases are made and scored, for the report's reader.
fn definitions(sweep: Sweep, declared: bool) -> String {
    use eigenmpc_cli::robustness::*;
    format!(
        "One thing differs from the controller's set-up per run, {steps} values per range (ends included). \
         **Model parameters** (the plant; the controller keeps the nominal model): masses, centre-of-mass \
         distances, inertias about the joint, viscous and Coulomb friction and rotor inertia (every joint \
         at once), each times 0.75 .. 1.25. An inertia factor that would need a negative inertia about \
         the centre of mass is left out (a point mass has none: the paper's pendulum has only 1 .. 1.25). \
         Friction or rotor inertia that is zero on every joint cannot be scaled: absolute values 0 .. \
         {share} % of a scale are added instead (Coulomb: tau_max N m; viscous: tau_max N m s/rad; \
         rotor inertia: link 1's inertia about its joint over gr^2). \
         **Measurement noise**: Gaussian, 0 .. {an} rad on the angles with 10x that in rad/s on the \
         speeds; the controller then filters with its EKF told the noise. \
         **Torque noise**: Gaussian per sample and joint, 0 .. {tn} % of tau_max. \
         **Torque response** a = {a0} .. {a1}: the applied torque moves u += a (tau - u) per sample \
         (a > 1 overshoots). \
         **Measurement delay** 0 .. {d} ms: the controller sees the state of exactly that long ago \
         (a delay that is not a whole number of samples is integrated to the instant, not rounded). \
         {declared} \
         **Torque pulses**: {pulses} random profiles (seeded by their number, the same on every machine), \
         {ppj} rectangular pulses per joint, start uniform in [5 s, duration - 15 s], length uniform \
         {l0} .. {l1} s, torque uniform in +-{mp} % of tau_max, held over the samples that start within \
         the pulse and added to the motor's torque. \
         **Score**: the share of runs whose mean plant energy over the last 5 s is within {e} % of E_ref \
         and whose RMS motor torque over the last 5 s is, per joint, at most the plant's RMS friction \
         torque along that stretch + {ta} N m ({tn_a} N m where the set-up adds noise: measurement \
         noise, torque noise, rough model + noise). \
         **Rough model + noise**: {steps} seeded random models of the robot as the controller's model \
         (each link's mass, centre-of-mass distance and inertia about the centre of mass off by up to \
         {rough} %, uniformly, no friction), the plant the robot itself, sensors with {rn} rad / {rs} \
         rad/s of noise and the EKF told it.",
        steps = sweep.steps,
        share = 100.0 * ZERO_NOMINAL_SHARE,
        an = MAX_MEASUREMENT_NOISE.0,
        tn = 100.0 * MAX_TORQUE_NOISE,
        declared = if declared {
            "The controller is told the case's torque response and measurement delay \
             (`torque_response`, `measurement_delay`), as its filter is told the noise."
        } else {
            "The controller is not told the torque response or the measurement delay \
             (`--undeclared`): it assumes an immediate motor and a current measurement."
        },
        a0 = RESPONSE_RANGE.0,
        a1 = RESPONSE_RANGE.1,
        d = 1000.0 * MAX_DELAY,
        pulses = sweep.pulses,
        ppj = PULSES_PER_JOINT,
        l0 = PULSE_DURATION.0,
        l1 = PULSE_DURATION.1,
        mp = 100.0 * MAX_PULSE,
        e = 100.0 * ENERGY_TOLERANCE,
        ta = TORQUE_ALLOWANCE,
        tn_a = NOISY_TORQUE_ALLOWANCE,
        rough = 100.0 * ROUGH_MODEL_ERROR,
        rn = ROUGH_NOISE.0,
        rs = ROUGH_NOISE.1,
    )
}

/// Runs the sweep and writes the report, for the robot's joint count.
pub fn run(args: &RobustnessArgs) -> anyhow::Result<()> {
    let n = args.model.joint_count()?;
    eigenmpc::with_joint_count!(
        n,
        |N, S, NP, NA| run_for::<N, S, NP, NA>(args),
        otherwise Err(anyhow::anyhow!(eigenmpc::joints::unsupported(n)))
    )
}

fn run_for<const N: usize, const S: usize, const NP: usize, const NA: usize>(
    args: &RobustnessArgs,
) -> anyhow::Result<()> {
    if !(args.duration.is_finite() && args.duration > 5.0) {
        bail!(
            "--duration {} must be more than the 5 s scored at the end",
            args.duration
        );
    }
    if args.steps < 2 {
        bail!(
            "--steps {} must be at least 2 (the ends of each range)",
            args.steps
        );
    }
    let robot = args.model.robot_of::<N>()?;
    let nominal = *robot.system.params();
    let mut setup = Setup::new(&nominal, args.energy, args.tau_max, args.duration)
        .map_err(anyhow::Error::msg)?;
    setup.ekf = args.ekf;
    setup.declared = !args.undeclared;
    setup.settings.adapt_estimator = eigenmpc_fmu_models::enums::ADAPT_ESTIMATOR
        .named(&args.adapt_estimator)
        .map_err(anyhow::Error::msg)?;
    // Refuse a configuration the controller cannot build before the sweep.
    setup.settings.build::<S>().map_err(anyhow::Error::msg)?;
    let sweep = Sweep {
        steps: args.steps,
        pulses: args.pulses,
    };
    let mut cases = default_cases(&nominal, args.tau_max, sweep);
    if let Some(list) = &args.categories {
        let wanted: Vec<&str> = list.split(',').map(str::trim).collect();
        for w in &wanted {
            if !CATEGORIES.contains(w) {
                bail!(
                    "--categories: unknown category '{w}' (known: {})",
                    CATEGORIES.join(", ")
                );
            }
        }
        cases.retain(|c| wanted.contains(&c.category));
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("thread pool")?;
    let bar =
        ProgressBar::with_draw_target(Some(2 * cases.len() as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(
            "robustness [{bar:30}] {pos}/{len} runs, {elapsed} ({eta} left)",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let jobs: Vec<(usize, bool)> = (0..cases.len())
        .flat_map(|i| [(i, false), (i, true)])
        .collect();
    // Each run has its own seed (the case's index): the same numbers
    // whatever the number of threads.
    let outcomes: Vec<_> = pool.install(|| {
        jobs.par_iter()
            .progress_with(bar.clone())
            .map(|&(i, adapt)| run_case::<N, S, NP, NA>(&setup, &cases[i], 1 + i as u64, adapt))
            .collect()
    });
    bar.finish_and_clear();
    let mut rows = Vec::with_capacity(cases.len());
    for (case, pair) in cases.iter().zip(outcomes.chunks(2)) {
        let off = pair[0].clone().map_err(anyhow::Error::msg)?;
        let on = pair[1].clone().map_err(anyhow::Error::msg)?;
        rows.push(RunPair {
            case: case.clone(),
            off,
            on,
        });
    }
    let title = format!(
        "# EigenMPC robustness v2: curved, E_ref = {} J, |tau| <= {} N m, N = {}, dt = {} s, {} s per run, every joint from {} rad at rest; model {}{}{}\n\n{}",
        args.energy,
        args.tau_max,
        setup.settings.horizon,
        setup.settings.sample_period,
        args.duration,
        eigenmpc_cli::robustness::START_ANGLE,
        args.model
            .model
            .as_ref()
            .map_or("the paper's double pendulum".to_string(), |p| p
                .display()
                .to_string()),
        if args.ekf {
            "; state estimator: EKF in every case, told the case's measurement noise"
        } else {
            "; state estimator: EKF where the sensors are noisy"
        },
        if args.adapt_estimator == "energy_balance" {
            String::new()
        } else {
            format!(
                "; adaptation's candidates: {} (adapt_estimator)",
                args.adapt_estimator
            )
        },
        definitions(sweep, setup.declared),
    );
    let md = args.out.join("robustness.md");
    std::fs::write(&md, markdown(&title, &rows))
        .with_context(|| format!("writing {}", md.display()))?;
    let table = args.out.join("robustness.csv");
    std::fs::write(&table, csv(&rows)).with_context(|| format!("writing {}", table.display()))?;
    let caption = format!(
        "EigenMPC robustness v2 (curved, E_ref = {} J, \u{3c4}max = {} N m{}): mean energy error of the last 5 s; \u{25cf} success, \u{2715} failure; score without / with adaptation",
        number(args.energy),
        number(args.tau_max),
        args.model
            .model
            .as_ref()
            .and_then(|p| p.file_stem())
            .map_or(String::new(), |s| format!(", {}", s.to_string_lossy())),
    );
    for ext in ["png", "svg"] {
        let path = args.out.join(format!("robustness.{ext}"));
        plot(&path, &caption, &rows).with_context(|| format!("writing {}", path.display()))?;
    }
    let scores: Vec<String> = CATEGORIES
        .iter()
        .filter_map(|c| {
            let (off, on, n) = eigenmpc_cli::robustness::report::score(&rows, c);
            (n > 0).then(|| format!("{c}: {off:.2} -> {on:.2}"))
        })
        .collect();
    println!("score without -> with adaptation: {}", scores.join("; "));
    println!(
        "wrote {}, robustness.csv, robustness.png, robustness.svg",
        md.display()
    );
    Ok(())
}
