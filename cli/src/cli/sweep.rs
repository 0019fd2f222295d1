//! `eigenmpc sweep`: closed loops over a grid or a random sample of any
//! controller, plant and set-up parameter (see `eigenmpc_cli::sweep`), in
//! parallel on all local cores; CSV, JSON and a plot of one metric.

use anyhow::{Context, bail};
use clap::Args;
use eigenmpc_cli::sweep::report::{Row, check_metric, csv, json, plot};
use eigenmpc_cli::sweep::rows::{Record, merge, parse_range};
use eigenmpc_cli::sweep::{Axis, RandomSample, Spec, Uniform, setups};
use indicatif::{ParallelProgressIterator, ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `eigenmpc sweep`.
#[derive(Args, Debug)]
pub struct SweepArgs {
    /// Spec file, TOML (`.toml`) or JSON: `duration`, `model`, `fixed`, `grid`, `random`,
    /// `noise_seed`, `metric` (the book, docs/book/src/sweeps.md). The options below add to it.
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
    /// Print the sweep's plan as JSON (`runs`, `joints`, `swept`) and run nothing: what a
    /// distributed runner splits.
    #[arg(long, conflicts_with_all = ["only", "from_rows"])]
    plan: bool,
    /// Run only the runs FROM..TO (indices in the spec's order, TO excluded) and write their
    /// records (JSON) to --rows-out instead of the outputs: one worker's part of the sweep.
    #[arg(
        long,
        value_name = "FROM..TO",
        requires = "rows_out",
        conflicts_with = "from_rows"
    )]
    only: Option<String>,
    /// Where --only writes its records (`-`: standard output).
    #[arg(long, value_name = "FILE")]
    rows_out: Option<PathBuf>,
    /// Run nothing: merge these records (of every run, from the --only parts) into the
    /// outputs, as if the sweep had run here. Repeatable.
    #[arg(long = "from-rows", value_name = "FILE")]
    from_rows: Vec<PathBuf>,
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

/// The outcomes of runs in order, the wall time (s) and the thread count.
type Executed = (
    Vec<Result<eigenmpc_cli::sweep::Metrics, String>>,
    f64,
    usize,
);

/// Runs `setups` on the local cores with a progress bar: the outcomes in
/// order, the wall time (s) and the thread count.
fn execute(
    args: &SweepArgs,
    setups: &[Box<dyn eigenmpc_cli::sweep::SweepRun>],
    duration: f64,
) -> anyhow::Result<Executed> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("thread pool")?;
    let bar =
        ProgressBar::with_draw_target(Some(setups.len() as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("sweep [{bar:30}] {pos}/{len} runs, {elapsed} ({eta} left)")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let start = Instant::now();
    let outcomes: Vec<_> = pool.install(|| {
        setups
            .par_iter()
            .progress_with(bar.clone())
            .map(|setup| setup.run(duration))
            .collect()
    });
    bar.finish_and_clear();
    Ok((
        outcomes,
        start.elapsed().as_secs_f64(),
        pool.current_num_threads(),
    ))
}

/// Runs the sweep (or its part, or merges its parts) and writes its outputs.
pub fn run_sweep(args: &SweepArgs) -> anyhow::Result<()> {
    let spec = spec(args)?;
    let joints = spec.joint_count().map_err(anyhow::Error::msg)?;
    let metric = spec.metric.clone().unwrap_or("time_to_band".into());
    check_metric(&metric, joints).map_err(anyhow::Error::msg)?;
    let runs = spec.runs().map_err(anyhow::Error::msg)?;
    let swept = spec.swept();
    if args.plan {
        let plan = serde_json::json!({"runs": runs.len(), "joints": joints, "swept": swept});
        println!("{plan}");
        return Ok(());
    }
    // Every run's set-up is checked before the first closed loop starts
    // (also when merging: the records must be of a valid spec).
    let setups = setups(&spec, &runs).map_err(anyhow::Error::msg)?;
    if let Some(only) = &args.only {
        let part = parse_range(only, runs.len()).map_err(anyhow::Error::msg)?;
        let out = args.rows_out.as_ref().context("--only needs --rows-out")?;
        let (outcomes, _, _) = execute(args, &setups[part.clone()], spec.duration)?;
        let records: Vec<Record> = part
            .zip(outcomes)
            .map(|(i, outcome)| Record::new(i, &runs[i], &outcome))
            .collect();
        let text = serde_json::to_string(&records)? + "\n";
        if out.as_os_str() == "-" {
            print!("{text}");
        } else {
            std::fs::write(out, text).with_context(|| format!("writing {}", out.display()))?;
        }
        return Ok(());
    }
    // An unwritable output folder is found now, not after the sweep.
    super::prepare_out_dir(&args.out)?;
    let (rows, timing) = if args.from_rows.is_empty() {
        let (outcomes, wall, threads) = execute(args, &setups, spec.duration)?;
        let rows: Vec<Row> = runs
            .into_iter()
            .zip(outcomes)
            .map(|(values, outcome)| Row { values, outcome })
            .collect();
        (rows, Some((wall, threads)))
    } else {
        let mut records = Vec::new();
        for path in &args.from_rows {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            let part: Vec<Record> = serde_json::from_str(&text)
                .with_context(|| format!("{}: not sweep records", path.display()))?;
            records.extend(part);
        }
        (merge(&runs, records).map_err(anyhow::Error::msg)?, None)
    };
    let write = |name: &str, text: String| -> anyhow::Result<()> {
        let path = args.out.join(name);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
    };
    write("sweep.csv", csv(&swept, &rows, joints))?;
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
    let failures = if failed > 0 {
        format!("; {failed} failed (see the error column)")
    } else {
        String::new()
    };
    match timing {
        Some((wall, threads)) => println!(
            "{} runs of {} s in {wall:.2} s on {threads} thread(s): {:.2} runs/s per thread; \
             {successes} reached the 5 % band and held it{failures}",
            rows.len(),
            spec.duration,
            rows.len() as f64 / wall / threads as f64,
        ),
        None => println!(
            "{} runs of {} s merged from {} record file(s); {successes} reached the 5 % band \
             and held it{failures}",
            rows.len(),
            spec.duration,
            args.from_rows.len(),
        ),
    }
    println!(
        "wrote {}/sweep.csv, sweep.json, sweep.png, sweep.svg",
        args.out.display()
    );
    Ok(())
}
