//! `eigenmpc paper`: the paper's section V figures and `report.md` with a
//! verdict per claim, in one command.

use anyhow::Context;
use clap::Args;
use eigenmpc_cli::paper::claims::{claims, markdown};
use eigenmpc_cli::paper::figures::write_all;
use eigenmpc_cli::paper::{Extent, Modes, RUNS, Runs, compute_mode, mode_keys, run_one};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `eigenmpc paper`.
#[derive(Args, Debug)]
pub struct PaperArgs {
    /// Output folder: one PNG and one SVG per figure, report.md.
    #[arg(long, default_value = "target/paper")]
    out: PathBuf,
    /// Reduced run: every closed loop 3 s long (checks the pipeline; the
    /// verdicts are then about 3 s runs, not the paper's).
    #[arg(long)]
    quick: bool,
    /// Worker threads (default: all local cores); the numbers do not depend on it.
    #[arg(long)]
    threads: Option<usize>,
}

/// Runs the subcommand.
pub fn run(args: &PaperArgs) -> anyhow::Result<()> {
    let extent = if args.quick {
        Extent::Quick
    } else {
        Extent::Full
    };
    // An unwritable output folder is found now, not after the runs.
    super::prepare_out_dir(&args.out)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("thread pool")?;
    let keys = mode_keys();
    let bar = ProgressBar::with_draw_target(
        Some((keys.len() + RUNS.len() + 1) as u64),
        ProgressDrawTarget::stderr(),
    );
    bar.set_style(
        ProgressStyle::with_template("paper [{bar:30}] {pos}/{len} {msg}, {elapsed} ({eta} left)")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let start = Instant::now();
    bar.set_message("eigenmodes");
    let modes = pool.install(|| {
        keys.par_iter()
            .map(|&k| {
                let m = compute_mode(k);
                bar.inc(1);
                m
            })
            .collect::<Result<Vec<_>, String>>()
    });
    let modes = Modes(modes.map_err(anyhow::Error::msg)?);
    bar.set_message("closed loops");
    // Longest runs first: the threads finish together.
    let mut order: Vec<usize> = (0..RUNS.len()).collect();
    order.sort_by(|&a, &b| {
        extent
            .duration(&RUNS[b])
            .total_cmp(&extent.duration(&RUNS[a]))
    });
    let mut results = pool
        .install(|| {
            order
                .par_iter()
                .map(|&i| {
                    let r = run_one(&RUNS[i], &modes, extent.duration(&RUNS[i])).map(|r| (i, r));
                    bar.inc(1);
                    r
                })
                .collect::<Result<Vec<_>, String>>()
        })
        .map_err(anyhow::Error::msg)?;
    results.sort_by_key(|r| r.0);
    let runs = Runs(results.into_iter().map(|r| r.1).collect());
    bar.set_message("figures");
    let figures = write_all(&args.out, &runs, &modes)?;
    bar.inc(1);
    bar.finish_and_clear();
    let list = claims(&runs, &modes);
    let wall = start.elapsed().as_secs_f64();
    let threads = pool.current_num_threads();
    let report = markdown(&list, &runs, &figures, extent, wall, threads);
    let path = args.out.join("report.md");
    std::fs::write(&path, report).with_context(|| format!("writing {}", path.display()))?;
    for c in &list {
        println!(
            "{:>3} {:<8} {}: {}",
            c.id,
            c.verdict.word(),
            c.figure,
            c.measured
        );
    }
    println!(
        "{} figures (PNG + SVG) and report.md in {} in {wall:.1} s on {threads} thread(s)",
        figures.len(),
        args.out.display()
    );
    Ok(())
}
