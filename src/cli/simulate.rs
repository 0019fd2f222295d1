//! `eigenmpc simulate`: closed loop of the EigenMPC controller against the
//! accurate plant integrator; prints the summary, writes CSV and plots.

use super::ModelArgs;
use anyhow::{Context, bail};
use clap::Args;
use eigenmpc::mechanics::{DoublePendulum, Vector};
use eigenmpc::modes::{Chart, Family, linear_modes};
use eigenmpc::mpc::closed_loop::{Sample, Summary, mode_and_chart, run, summarise};
use eigenmpc::mpc::{Controller, MpcConfig, QpBackend, Reference, Variant};
use nalgebra::SVector;
use plotters::prelude::*;
use std::io::Write;
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
    /// QP solver: `clarabel` (default) or `riccati` (structure-exploiting).
    #[arg(long, default_value = "clarabel")]
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
        plot(path, &trace, &mode.path, args.energy, &system)
            .with_context(|| format!("plotting {}", path.display()))?;
    }
    Ok(())
}

fn print_summary(args: &SimulateArgs, variant: Variant, family: Family, s: &Summary<2>) {
    let ms = |t: f64| t * 1e3;
    println!(
        "{variant} EigenMPC, {family}, E_ref = {} J, x0 = {}, {} s, N = {}, dt = {} s, QP {}",
        args.energy,
        args.x0,
        args.duration,
        args.horizon,
        args.dt,
        args.qp.trim().to_ascii_lowercase()
    );
    match s.time_to_5_percent {
        Some(t) => println!("time to |E - E_ref| < 5 % for good: {t:.3} s"),
        None => println!("time to |E - E_ref| < 5 % for good: not reached"),
    }
    println!(
        "final energy error:              {:+.4} J",
        s.final_energy_error
    );
    println!(
        "RMS torque, last 5 s:            {:.4} / {:.4} N m",
        s.rms_torque[0], s.rms_torque[1]
    );
    if let Some(d) = s.rms_distance {
        println!("RMS distance to the mode, last 5 s: {d:.4} rad");
    }
    println!(
        "solve time per sample:           median {:.3} ms, p95 {:.3} ms, p99 {:.3} ms, max {:.3} ms",
        ms(s.solve_time[0]),
        ms(s.solve_time[1]),
        ms(s.solve_time[2]),
        ms(s.solve_time[3])
    );
    if s.failures > 0 {
        println!("samples with a failed solve:     {}", s.failures);
    }
}

fn write_csv(path: &Path, trace: &[Sample<2, 4>]) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(f, "time,q1,q2,qd1,qd2,tau1,tau2,energy,solve_ms")?;
    for s in trace {
        let z = &s.state;
        writeln!(
            f,
            "{},{},{},{},{},{},{},{},{}",
            s.time,
            z[0],
            z[1],
            z[2],
            z[3],
            s.tau[0],
            s.tau[1],
            s.energy,
            s.solve_time * 1e3
        )?;
    }
    f.flush()
}

/// One plotted quantity of a sample.
type SampleValue = fn(&Sample<2, 4>) -> f64;

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

fn plot(
    path: &Path,
    trace: &[Sample<2, 4>],
    mode: &[Vector<2>],
    e_ref: f64,
    system: &DoublePendulum,
) -> anyhow::Result<()> {
    // The font ships with the binary: no system fontconfig needed.
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| anyhow::anyhow!("embedded font is invalid"))?;
    let size = (1500, 900);
    let svg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if svg {
        draw(
            SVGBackend::new(path, size).into_drawing_area(),
            trace,
            mode,
            e_ref,
            system,
        )
    } else {
        draw(
            BitMapBackend::new(path, size).into_drawing_area(),
            trace,
            mode,
            e_ref,
            system,
        )
    }
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    trace: &[Sample<2, 4>],
    mode: &[Vector<2>],
    e_ref: f64,
    _system: &DoublePendulum,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("{e:?}");
    root.fill(&WHITE).map_err(err)?;
    let panels = root.split_evenly((2, 3));
    let t_end = trace.last().map_or(1.0, |s| s.time).max(1e-9);
    let range = |vals: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        let pad = ((hi - lo) * 0.05).max(1e-3);
        (lo - pad)..(hi + pad)
    };

    // Joint-space path with the true eigenmode (both branches of the orbit).
    {
        let xs = range(
            &mut trace
                .iter()
                .map(|s| s.state[0])
                .chain(mode.iter().map(|q| q[0])),
        );
        let ys = range(
            &mut trace
                .iter()
                .map(|s| s.state[1])
                .chain(mode.iter().map(|q| q[1])),
        );
        let mut chart = ChartBuilder::on(&panels[0])
            .caption("joint-space path", ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(xs, ys)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("theta1 (rad)")
            .y_desc("theta2 (rad)")
            .draw()
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new(
                trace.iter().map(|s| (s.state[0], s.state[1])),
                BLUE.mix(0.6),
            ))
            .map_err(err)?
            .label("EigenMPC")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 15, y)], BLUE));
        chart
            .draw_series(LineSeries::new(
                mode.iter().map(|q| (q[0], q[1])),
                RED.stroke_width(2),
            ))
            .map_err(err)?
            .label("eigenmode at E_ref")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 15, y)], RED));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
    }

    let series: [(&str, &str, SampleValue); 5] = [
        ("energy", "E (J)", |s| s.energy),
        ("theta1", "theta1 (rad)", |s| s.state[0]),
        ("theta2", "theta2 (rad)", |s| s.state[1]),
        ("tau1", "tau1 (N m)", |s| s.tau[0]),
        ("tau2", "tau2 (N m)", |s| s.tau[1]),
    ];
    for (panel, (title, label, f)) in panels[1..].iter().zip(series.iter()) {
        let mut ys = range(&mut trace.iter().map(f));
        if *title == "energy" {
            ys = ys.start.min(e_ref * 0.9)..ys.end.max(e_ref * 1.1);
        }
        let mut chart = ChartBuilder::on(panel)
            .caption(*title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(0.0..t_end, ys)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc(*label)
            .draw()
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new(trace.iter().map(|s| (s.time, f(s))), BLUE))
            .map_err(err)?;
        if *title == "energy" {
            chart
                .draw_series(LineSeries::new([(0.0, e_ref), (t_end, e_ref)], RED))
                .map_err(err)?;
        }
    }
    root.present().map_err(err)?;
    Ok(())
}
