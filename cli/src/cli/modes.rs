//! `eigenmpc modes`: eigenmode family at given energies, with charts, as JSON.

use super::{ModelArgs, Robot, parse_list};
use anyhow::Context;
use clap::Args;
use eigenmpc::mechanics::{MechanicalSystem, Vector};
use eigenmpc::modes::{
    Chart, ContinuationOptions, Family, eigenmode_family_with_progress, linear_modes,
};
use eigenmpc_fmu_models::controller::start_values::start_values;
use fmi2_slave::Value;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;
use std::io::Write;

/// Arguments of `eigenmpc modes`.
#[derive(Args, Debug)]
pub struct ModesArgs {
    /// Mode family: `in-phase` or `anti-phase`.
    #[arg(long, default_value = "in-phase")]
    family: String,
    /// Comma-separated energies in J, e.g. `2,8,14`.
    #[arg(long, allow_hyphen_values = true)]
    energies: String,
    /// Degree of the chart polynomials X(s).
    #[arg(long, default_value_t = 9)]
    degree: usize,
    /// Path samples from one turning point to the other.
    #[arg(long, default_value_t = 200)]
    samples: usize,
    /// Also write the controller FMU's start values (model, eigenvector,
    /// `E_ref`, chart coefficients, `chart_source = parameters` so that the
    /// FMU uses this chart) for the single requested energy to FILE, as a
    /// JSON object `{"variable name": value}` (e.g. for fmpy's
    /// `simulate_fmu(..., start_values=json.load(f))`).
    #[arg(long, value_name = "FILE")]
    fmu_start_values: Option<std::path::PathBuf>,
    #[command(flatten)]
    model: ModelArgs,
}

/// Start values of the controller FMU for one eigenmode and its chart,
/// generated from the FMU's own variable table (names, ranges, defaults).
fn fmu_start_values<const N: usize>(
    robot: &Robot<N>,
    eigenvector: &Vector<N>,
    energy: f64,
    chart: &Chart<N>,
) -> anyhow::Result<serde_json::Map<String, serde_json::Value>> {
    let values = start_values::<N>(
        robot.system.params(),
        energy,
        &std::array::from_fn(|j| eigenvector[j]),
        &chart.coefficients,
    )
    .map_err(|e| anyhow::anyhow!("--fmu-start-values: {e}"))?;
    Ok(values
        .into_iter()
        .map(|(name, value)| {
            let json = match value {
                Value::Real(v) => serde_json::Value::from(v),
                Value::Integer(i) => serde_json::Value::from(i),
                Value::Boolean(b) => serde_json::Value::from(b),
            };
            (name, json)
        })
        .collect())
}

#[derive(Serialize)]
struct LinearJson {
    omega: f64,
    eigenvector: Vec<f64>,
    mass_normalised_eigenvector: Vec<f64>,
}

#[derive(Serialize)]
struct ChartJson {
    degree: usize,
    coefficients: Vec<Vec<f64>>,
    max_residual: f64,
    /// Chart coordinate range covered by the path.
    s_range: [f64; 2],
}

#[derive(Serialize)]
struct ModeJson {
    energy: f64,
    turning_point: Vec<f64>,
    other_turning_point: Vec<f64>,
    half_period: f64,
    closing_error: f64,
    turning_speed: f64,
    newton_iterations: usize,
    path: Vec<Vec<f64>>,
    chart: ChartJson,
}

/// The whole JSON document printed by `eigenmpc modes`.
#[derive(Serialize)]
struct ModesJson {
    model: serde_json::Value,
    family: String,
    linear: LinearJson,
    modes: Vec<ModeJson>,
}

fn vec2<const N: usize>(v: &Vector<N>) -> Vec<f64> {
    v.as_slice().to_vec()
}

/// Runs the subcommand for the robot's joint count: prints the JSON
/// document on stdout.
pub fn run(args: &ModesArgs) -> anyhow::Result<()> {
    let n = args.model.joint_count()?;
    eigenmpc::with_joint_count!(
        n,
        |N, S, NP| run_for::<N, S>(args),
        otherwise Err(anyhow::anyhow!(eigenmpc::joints::unsupported(n)))
    )
}

fn run_for<const N: usize, const S: usize>(args: &ModesArgs) -> anyhow::Result<()> {
    let family: Family = args.family.parse().map_err(anyhow::Error::msg)?;
    let energies = parse_list("energies", &args.energies)?;
    if args.fmu_start_values.is_some() && energies.len() != 1 {
        anyhow::bail!("--fmu-start-values needs exactly one energy in --energies");
    }
    if args.samples < 2 * (args.degree + 1) {
        anyhow::bail!(
            "--samples {} is too few for --degree {} (need at least {})",
            args.samples,
            args.degree,
            2 * (args.degree + 1)
        );
    }
    let robot = args.model.robot_of::<N>()?;
    let system = robot.system;
    let linear = *linear_modes(&system)?
        .get(family.index())
        .with_context(|| format!("a {N}-joint chain has no {family} family"))?;
    let opts = ContinuationOptions {
        samples: args.samples,
        ..Default::default()
    };
    let bar =
        ProgressBar::with_draw_target(Some(energies.len() as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} energies")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(format!("{family} eigenmodes"));
    let orbits = eigenmode_family_with_progress::<_, N, S>(
        &system,
        family.index(),
        &energies,
        &opts,
        |done| bar.set_position(done as u64),
    );
    bar.finish_and_clear();
    let orbits = orbits.with_context(|| format!("{family} eigenmodes"))?;
    let q_eq = system.equilibrium();
    let modes = orbits
        .iter()
        .map(|m| {
            let chart = Chart::fit(&m.path, &linear.eigenvector, &q_eq, args.degree)
                .with_context(|| format!("chart of the {} J mode", m.energy))?;
            if let Some(path) = &args.fmu_start_values {
                let values = fmu_start_values(&robot, &linear.eigenvector, m.energy, &chart)?;
                let text = serde_json::to_string_pretty(&values)?;
                std::fs::write(path, text + "\n")
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            let s0 = chart.coordinate(&m.turning_point);
            let s1 = chart.coordinate(&m.other_turning_point);
            Ok(ModeJson {
                energy: m.energy,
                turning_point: vec2(&m.turning_point),
                other_turning_point: vec2(&m.other_turning_point),
                half_period: m.half_period,
                closing_error: m.closing_error,
                turning_speed: m.turning_speed,
                newton_iterations: m.newton_iterations,
                path: m.path.iter().map(vec2).collect(),
                chart: ChartJson {
                    degree: chart.degree,
                    coefficients: chart.coefficients.to_vec(),
                    max_residual: chart.max_residual,
                    s_range: [s0.min(s1), s0.max(s1)],
                },
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let doc = ModesJson {
        model: robot.json(),
        family: family.to_string(),
        linear: LinearJson {
            omega: linear.omega,
            eigenvector: vec2(&linear.eigenvector),
            mass_normalised_eigenvector: vec2(&linear.mass_normalised),
        },
        modes,
    };
    let mut out = std::io::stdout().lock();
    serde_json::to_writer(&mut out, &doc)?;
    writeln!(out)?;
    Ok(())
}
