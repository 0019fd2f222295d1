//! `eigenmpc robustness`: the robustness report of the controller FMU's
//! default controller on a nominal robot (see `eigenmpc_cli::robustness`),
//! every case without and with online adaptation, on all local cores.

use super::ModelArgs;
use anyhow::{Context, bail};
use clap::Args;
use eigenmpc_cli::report::number;
use eigenmpc_cli::robustness::report::{RunPair, csv, markdown, plot};
use eigenmpc_cli::robustness::{CATEGORIES, Setup, default_cases, run_case};
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
    /// Simulated time of each run (s); success needs the band reached before the end.
    #[arg(long, default_value_t = 60.0, allow_negative_numbers = true)]
    duration: f64,
    /// Only these categories (comma-separated, e.g. `mass,measurement delay`).
    #[arg(long)]
    categories: Option<String>,
    /// Output folder: robustness.md, robustness.csv, robustness.png and .svg.
    #[arg(long, default_value = "target/robustness")]
    out: PathBuf,
    /// Filter the measurements with the controller's extended Kalman filter, told each case's
    /// measurement noise (at least 0.005 rad, rad/s).
    #[arg(long)]
    ekf: bool,
    /// Worker threads (default: all local cores); the numbers do not depend on it.
    #[arg(long)]
    threads: Option<usize>,
}

/// Runs the sweep and writes the report.
pub fn run(args: &RobustnessArgs) -> anyhow::Result<()> {
    if !(args.duration.is_finite() && args.duration > 5.0) {
        bail!(
            "--duration {} must be more than the 5 s scored at the end",
            args.duration
        );
    }
    let robot = args.model.robot()?;
    let nominal = *robot.system.params();
    let mut setup = Setup::new(&nominal, args.energy, args.tau_max, args.duration)
        .map_err(anyhow::Error::msg)?;
    setup.ekf = args.ekf;
    // Refuse a configuration the controller cannot build before the sweep.
    setup.settings.build::<4>().map_err(anyhow::Error::msg)?;
    let mut cases = default_cases(setup.settings.sample_period);
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
            .map(|&(i, adapt)| run_case(&setup, &cases[i], 1 + i as u64, adapt))
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
        "# EigenMPC robustness: curved, E_ref = {} J, |tau| <= {} N m, N = {}, dt = {} s, {} s per run, from (0.05, 0.05) at rest; model {}{}",
        args.energy,
        args.tau_max,
        setup.settings.horizon,
        setup.settings.sample_period,
        args.duration,
        args.model
            .model
            .as_ref()
            .map_or("the paper's double pendulum".to_string(), |p| p
                .display()
                .to_string()),
        if args.ekf {
            "; state estimator: EKF told each case's measurement noise"
        } else {
            ""
        },
    );
    let md = args.out.join("robustness.md");
    std::fs::write(&md, markdown(&title, &rows))
        .with_context(|| format!("writing {}", md.display()))?;
    let table = args.out.join("robustness.csv");
    std::fs::write(&table, csv(&rows)).with_context(|| format!("writing {}", table.display()))?;
    let caption = format!(
        "EigenMPC robustness (curved, E_ref = {} J): mean energy error of the last 5 s; \u{25cf} success, \u{2715} failure; success share without / with adaptation",
        number(args.energy)
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
    println!(
        "success share without -> with adaptation: {}",
        scores.join("; ")
    );
    println!(
        "wrote {}, robustness.csv, robustness.png, robustness.svg",
        md.display()
    );
    Ok(())
}
