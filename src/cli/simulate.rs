//! `eigenmpc simulate`: closed loop of the EigenMPC controller against the
//! accurate plant integrator; prints the summary, writes CSV and plots.

use super::ModelArgs;
use anyhow::{Context, bail};
use clap::Args;
use eigenmpc::mechanics::Vector;
use eigenmpc::modes::{Chart, Family, linear_modes};
use eigenmpc::mpc::closed_loop::{Summary, mode_and_chart, run, summarise};
use eigenmpc::mpc::{Controller, MpcConfig, QpBackend, Reference, Variant};
use eigenmpc::report::{plot_run, summary_text, write_csv};
use nalgebra::SVector;
use std::path::{Path, PathBuf};

/// Arguments of `eigenmpc simulate`.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Cost variant: `straight` or `curved`.
    #[arg(long, default_value = "curved")]
    variant: String,
    /// Mode family: `in-phase` or `anti-phase`.
    #[arg(long, default_value = "in-phase")]
    family: String,
    /// Reference energy E_ref (J).
    #[arg(long, default_value_t = 14.0, allow_negative_numbers = true)]
    energy: f64,
    /// Initial state q1,q2,qd1,qd2 (rad, rad/s).
    #[arg(long, default_value = "0.05,0.05,0,0", allow_hyphen_values = true)]
    x0: String,
    /// Simulated time (s).
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
    duration: f64,
    /// Write the trajectory as CSV.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Write the paper-style plots (PNG, or SVG if the name ends in .svg).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Chart JSON from `eigenmpc modes` (curved; default: computed at E_ref).
    #[arg(long)]
    chart: Option<PathBuf>,
    /// Shooting intervals N.
    #[arg(long = "N", default_value_t = 80)]
    horizon: usize,
    /// Shooting interval and sample period (s).
    #[arg(long, default_value_t = 0.025, allow_negative_numbers = true)]
    dt: f64,
    /// RK4 substeps per interval.
    #[arg(long, default_value_t = 1)]
    substeps: usize,
    /// Torque bound (N m).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    tau_max: f64,
    /// Energy weight w_E (default: 25 curved, 5 straight).
    #[arg(long, allow_negative_numbers = true)]
    w_e: Option<f64>,
    /// Position weight w_x.
    #[arg(long, default_value_t = 50.0, allow_negative_numbers = true)]
    w_x: f64,
    /// Velocity weight w_xd.
    #[arg(long, default_value_t = 2500.0, allow_negative_numbers = true)]
    w_xd: f64,
    /// Torque weight w_F.
    #[arg(long, default_value_t = 225.0, allow_negative_numbers = true)]
    w_f: f64,
    /// Exploration gain alpha (straight).
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    alpha: f64,
    /// Torque-weight offset beta (straight).
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    beta: f64,
    /// SQP iterations per sample (1 = RTI).
    #[arg(long, default_value_t = 1)]
    iterations: usize,
    /// QP solver: `riccati` (structure-exploiting, default) or `clarabel` (reference).
    #[arg(long, default_value_t = QpBackend::default().to_string())]
    qp: String,
    #[command(flatten)]
    model: ModelArgs,
}

/// Reads the chart of the mode closest to `energy` from `eigenmpc modes` JSON.
fn chart_from_json(path: &Path, energy: f64) -> anyhow::Result<Chart<2>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let doc: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let vec2 = |v: &serde_json::Value, what: &str| -> anyhow::Result<Vector<2>> {
        let a: Vec<f64> = serde_json::from_value(v.clone())
            .with_context(|| format!("{what} must be a list of numbers"))?;
        if a.len() != 2 {
            bail!("{what} must have 2 entries");
        }
        Ok(Vector::<2>::new(a[0], a[1]))
    };
    let eigenvector = vec2(&doc["linear"]["eigenvector"], "linear.eigenvector")?;
    let modes = doc["modes"]
        .as_array()
        .context("the chart file has no `modes` list")?;
    let best = modes
        .iter()
        .filter_map(|m| m["energy"].as_f64().map(|e| (e, m)))
        .min_by(|a, b| (a.0 - energy).abs().total_cmp(&(b.0 - energy).abs()))
        .context("the chart file lists no mode")?;
    if (best.0 - energy).abs() > 1e-6 * energy.abs().max(1.0) {
        eprintln!(
            "warning: chart file has no mode at {energy} J; using the {} J mode",
            best.0
        );
    }
    let coefficients: Vec<Vec<f64>> =
        serde_json::from_value(best.1["chart"]["coefficients"].clone())
            .context("modes[].chart.coefficients must be lists of numbers")?;
    let [c1, c2]: [Vec<f64>; 2] = coefficients
        .try_into()
        .map_err(|_| anyhow::anyhow!("chart.coefficients must have one list per joint (2)"))?;
    Ok(Chart::from_coefficients(
        eigenvector,
        Vector::<2>::zeros(),
        [c1, c2],
    )?)
}

/// Runs the subcommand.
pub fn run_simulate(args: &SimulateArgs) -> anyhow::Result<()> {
    let variant: Variant = args.variant.parse().map_err(anyhow::Error::msg)?;
    let family: Family = args.family.parse().map_err(anyhow::Error::msg)?;
    let backend: QpBackend = args.qp.parse().map_err(anyhow::Error::msg)?;
    let x0 = super::parse_list("x0", &args.x0)?;
    if x0.len() != 4 || x0.iter().any(|v| !v.is_finite()) {
        bail!("--x0 needs 4 finite numbers q1,q2,qd1,qd2");
    }
    if !(args.duration.is_finite() && args.duration > 0.0 && args.duration <= 3600.0) {
        bail!("--duration must be in (0, 3600] s");
    }
    if !(args.energy.is_finite() && args.energy > 0.0) {
        bail!("--energy must be finite and > 0");
    }
    let system = args.model.pendulum()?;
    let (mode, chart) = mode_and_chart::<_, 2, 4>(&system, family.index(), args.energy, 9)
        .with_context(|| format!("{family} eigenmode at {} J", args.energy))?;
    let reference = match variant {
        Variant::Straight => Reference::Straight {
            eigenvector: linear_modes(&system)?[family.index()].eigenvector,
        },
        Variant::Curved => Reference::Curved(match &args.chart {
            Some(path) => chart_from_json(path, args.energy)?,
            None => chart,
        }),
    };
    let mut config = MpcConfig::paper(variant);
    config.horizon = args.horizon;
    config.dt = args.dt;
    config.substeps = args.substeps;
    config.tau_max = args.tau_max;
    config.iterations_per_sample = args.iterations;
    config.qp = backend;
    config.cost.e_ref = args.energy;
    config.cost.alpha = args.alpha;
    config.cost.beta = args.beta;
    if let Some(w) = args.w_e {
        config.cost.weights.energy = w;
    }
    config.cost.weights.position = args.w_x;
    config.cost.weights.velocity = args.w_xd;
    config.cost.weights.torque = args.w_f;
    let mut controller = Controller::<_, 2, 4>::new(system, config, reference)?;
    let z0 = SVector::<f64, 4>::from_column_slice(&x0);
    let trace = run(&mut controller, &system, &z0, args.duration)?;
    let summary = summarise(&trace, args.energy, Some(&mode.path), 5.0);
    print_summary(args, variant, family, &summary);
    if let Some(path) = &args.csv {
        write_csv(path, &trace).with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &args.plot {
        plot_run(path, &trace, &mode.path, args.energy)
            .with_context(|| format!("plotting {}", path.display()))?;
    }
    Ok(())
}

fn print_summary(args: &SimulateArgs, variant: Variant, family: Family, s: &Summary<2>) {
    println!(
        "{variant} EigenMPC, {family}, E_ref = {} J, x0 = {}, {} s, N = {}, dt = {} s, QP {}",
        args.energy,
        args.x0,
        args.duration,
        args.horizon,
        args.dt,
        args.qp.trim().to_ascii_lowercase()
    );
    print!("{}", summary_text(s));
}
