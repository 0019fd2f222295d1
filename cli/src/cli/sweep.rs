//! `eigenmpc sweep`: closed loops over a grid or a random sample of any
//! controller, plant and set-up parameter (see `eigenmpc_cli::sweep`), in
//! parallel on all local cores; CSV, JSON and a plot of one metric.

use anyhow::{Context, bail};
use clap::Args;
use eigenmpc_cli::sweep::report::{Row, check_metric, csv, json, plot};
use eigenmpc_cli::sweep::{Axis, RandomSample, RunSetup, Spec, Uniform, run};
use indicatif::{ParallelProgressIterator, ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `eigenmpc sweep`.
#[derive(Args, Debug)]
pub struct SweepArgs {
    /// Spec file, TOML (`.toml`) or JSON: `duration`, `model`, `fixed`, `grid`, `random`,
    /// `noise_seed`, `metric` (README "Parameter sweeps"). The options below add to it.
    #[arg(long, value_name = "FILE")]
    spec: Option<PathBuf>,
    /// A grid axis `NAME=V1,V2,...` or `NAME=FROM:TO:COUNT`; names are
    /// `controller.<FMU parameter>`, `plant.<FMU parameter>`, `model.<chain parameter>` (both)
    /// or `imperfections.<measurement_noise|torque_noise|responsiveness|delay>`. Repeatable.
    #[arg(long = "grid", value_name = "NAME=VALUES")]
    grid: Vec<String>,
    /// A fixed value `NAME=VALUE` (names as for --grid). Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// A random sample of this many runs over the --range parameters (per grid point).
    #[arg(long, value_name = "RUNS")]
    random: Option<usize>,
    /// A uniformly sampled parameter `NAME=FROM:TO` (with --random). Repeatable.
    #[arg(long = "range", value_name = "NAME=FROM:TO")]
    range: Vec<String>,
    /// Seed of the random sample.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Robot parameter file for both FMUs (as `eigenmpc simulate --model`).
    #[arg(long, value_name = "FILE")]
    model: Option<PathBuf>,
    /// Simulated time of each run (s; default 30, or the spec's).
    #[arg(long, allow_negative_numbers = true)]
    duration: Option<f64>,
    /// Metric of the plot (default time_to_band): a metric column of the CSV.
    #[arg(long)]
    metric: Option<String>,
    /// Output folder: sweep.csv, sweep.json, sweep.png, sweep.svg.
    #[arg(long, default_value = "target/sweep")]
    out: PathBuf,
    /// Worker threads (default: all local cores); the numbers do not depend on it.
    #[arg(long)]
    threads: Option<usize>,
}

fn split_assignment<'a>(flag: &str, text: &'a str) -> anyhow::Result<(&'a str, &'a str)> {
    text.split_once('=')
        .map(|(n, v)| (n.trim(), v.trim()))
        .with_context(|| format!("--{flag} {text}: expected NAME=VALUE"))
}

fn number(flag: &str, name: &str, text: &str) -> anyhow::Result<f64> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("--{flag} {name}: '{}' is not a number", text.trim()))?;
    if !v.is_finite() {
        bail!("--{flag} {name}: {v} is not finite");
    }
    Ok(v)
}

/// `FROM:TO:COUNT` or a comma-separated list.
fn axis(name: &str, text: &str) -> anyhow::Result<Axis> {
    let parts: Vec<&str> = text.split(':').collect();
    match parts.as_slice() {
        [from, to, count] => Ok(Axis::Range {
            from: number("grid", name, from)?,
            to: number("grid", name, to)?,
            count: count.trim().parse().map_err(|_| {
                anyhow::anyhow!(
                    "--grid {name}: count '{}' is not a whole number",
                    count.trim()
                )
            })?,
        }),
        [list] => Ok(Axis::List(
            list.split(',')
                .map(|v| number("grid", name, v))
                .collect::<anyhow::Result<_>>()?,
        )),
        _ => bail!("--grid {name}={text}: expected V1,V2,... or FROM:TO:COUNT"),
    }
}

/// The spec of the file and the options.
fn spec(args: &SweepArgs) -> anyhow::Result<Spec> {
    let mut spec = match &args.spec {
        Some(path) => Spec::load(path).map_err(anyhow::Error::msg)?,
        None => Spec::default(),
    };
    if let Some(d) = args.duration {
        spec.duration = d;
    }
    if let Some(m) = &args.model {
        spec.model = Some(m.clone());
    }
    if let Some(m) = &args.metric {
        spec.metric = Some(m.clone());
    }
    for text in &args.set {
        let (name, value) = split_assignment("set", text)?;
        spec.fixed.insert(name.into(), number("set", name, value)?);
    }
    for text in &args.grid {
        let (name, values) = split_assignment("grid", text)?;
        spec.grid.insert(name.into(), axis(name, values)?);
    }
    if !args.range.is_empty() || args.random.is_some() {
        let samples = args
            .random
            .context("--range needs --random RUNS (the number of sampled runs)")?;
        let mut ranges = spec.random.take().map(|r| r.ranges).unwrap_or_default();
        for text in &args.range {
            let (name, bounds) = split_assignment("range", text)?;
            let (from, to) = bounds
                .split_once(':')
                .with_context(|| format!("--range {text}: expected NAME=FROM:TO"))?;
            ranges.insert(
                name.into(),
                Uniform {
                    from: number("range", name, from)?,
                    to: number("range", name, to)?,
                },
            );
        }
        if ranges.is_empty() {
            bail!("--random needs at least one --range NAME=FROM:TO");
        }
        spec.random = Some(RandomSample {
            samples,
            seed: args.seed,
            ranges,
        });
    }
    Ok(spec)
}

/// Runs the sweep and writes its outputs.
pub fn run_sweep(args: &SweepArgs) -> anyhow::Result<()> {
    let spec = spec(args)?;
    let metric = spec.metric.clone().unwrap_or("time_to_band".into());
    check_metric(&metric).map_err(anyhow::Error::msg)?;
    let runs = spec.runs().map_err(anyhow::Error::msg)?;
    let swept = spec.swept();
    // Every run's set-up is checked before the first closed loop starts.
    let setups = runs
        .iter()
        .enumerate()
        .map(|(i, run)| {
            RunSetup::new(&spec, run).map_err(|e| {
                let values: Vec<String> = run.iter().map(|(n, v)| format!("{n} = {v}")).collect();
                anyhow::anyhow!("run {i} ({}): {e}", values.join(", "))
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    // An unwritable output folder is found now, not after the sweep.
    super::prepare_out_dir(&args.out)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("thread pool")?;
    let bar = ProgressBar::with_draw_target(Some(runs.len() as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("sweep [{bar:30}] {pos}/{len} runs, {elapsed} ({eta} left)")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let start = Instant::now();
    let outcomes: Vec<_> = pool.install(|| {
        setups
            .par_iter()
            .progress_with(bar.clone())
            .map(|setup| run(setup, spec.duration))
            .collect()
    });
    let wall = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let rows: Vec<Row> = runs
        .into_iter()
        .zip(outcomes)
        .map(|(values, outcome)| Row { values, outcome })
        .collect();
    let write = |name: &str, text: String| -> anyhow::Result<()> {
        let path = args.out.join(name);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
    };
    write("sweep.csv", csv(&swept, &rows))?;
    write(
        "sweep.json",
        serde_json::to_string_pretty(&json(&rows))? + "\n",
    )?;
    let title = format!(
        "EigenMPC sweep: {metric} over {}, {} runs of {} s",
        if swept.is_empty() {
            "nothing".to_string()
        } else {
            swept.join(", ")
        },
        rows.len(),
        spec.duration
    );
    for ext in ["png", "svg"] {
        let path = args.out.join(format!("sweep.{ext}"));
        plot(&path, &title, &swept, &rows, &metric)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let failed = rows.iter().filter(|r| r.outcome.is_err()).count();
    let successes = rows
        .iter()
        .filter(|r| r.outcome.as_ref().is_ok_and(|m| m.success))
        .count();
    let threads = pool.current_num_threads();
    println!(
        "{} runs of {} s in {wall:.2} s on {threads} thread(s): {:.2} runs/s per thread; {successes} \
         reached the 5 % band and held it{}",
        rows.len(),
        spec.duration,
        rows.len() as f64 / wall / threads as f64,
        if failed > 0 {
            format!("; {failed} failed (see the error column)")
        } else {
            String::new()
        }
    );
    println!(
        "wrote {}/sweep.csv, sweep.json, sweep.png, sweep.svg",
        args.out.display()
    );
    Ok(())
}
