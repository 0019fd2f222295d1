//! `eigenmpc export`: a user's robot as a controller FMU, a plant FMU and
//! the SSP that couples them ([`eigenmpc_cli::export`]).

use super::ModelArgs;
use anyhow::{Context, bail};
use clap::Args;
use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::Family;
use eigenmpc_cli::export::{
    ExportOptions, PairNames, camel_case, check_name, default_energy, export, find_binary,
};
use std::path::PathBuf;

/// Arguments of `eigenmpc export`.
#[derive(Args, Debug)]
pub struct ExportArgs {
    /// Robot parameter file (JSON or YAML, 1 to 6 joints; see the book,
    /// docs/book/src/robots.md).
    #[arg(long, value_name = "FILE")]
    model: PathBuf,
    /// Folder for `<NAME>EigenMPC.fmu`, `<NAME>Plant.fmu` and `<NAME>.ssp` (created if
    /// missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// E_ref (J) and the energy of the chart the controller starts with; default 10 % of the
    /// potential energy with every link upright.
    #[arg(long, allow_negative_numbers = true)]
    energy: Option<f64>,
    /// Mode family: `in-phase` or `anti-phase`.
    #[arg(long, default_value = "in-phase")]
    family: String,
    /// Torque bound (N m); default the file's smallest motor torque limit `tl<j>`, else 1.
    #[arg(long, allow_negative_numbers = true)]
    tau_max: Option<f64>,
    /// Base of the FMU names (letters, digits, `_`); default the file name in CamelCase.
    #[arg(long)]
    name: Option<String>,
    /// Degree of the chart polynomials.
    #[arg(long, default_value_t = 9)]
    chart_degree: usize,
    /// The exported robots' FMU binary (default: the one `fmu-build` writes, found from this
    /// executable's folder).
    #[arg(long, value_name = "FILE")]
    binary: Option<PathBuf>,
    /// FMI versions: 2 (always written: `<NAME>EigenMPC.fmu`, ..., coupled by the SSP) and 3
    /// (also `fmi3/<NAME>EigenMPC.fmu` and `fmi3/<NAME>Plant.fmu`, FMI 3.0 Co-Simulation).
    #[arg(long, value_delimiter = ',', default_value = "2", value_parser = clap::value_parser!(u8).range(2..=3))]
    fmi: Vec<u8>,
}

/// Runs the subcommand for the file's joint count.
pub fn run(args: &ExportArgs) -> anyhow::Result<()> {
    let model_args = ModelArgs::for_file(&args.model);
    let n = model_args.joint_count()?;
    eigenmpc::with_joint_count!(
        n,
        |N, S, NP| run_for::<N, S>(args, &model_args),
        otherwise Err(anyhow::anyhow!(eigenmpc::joints::unsupported(n)))
    )
}

fn run_for<const N: usize, const S: usize>(
    args: &ExportArgs,
    model_args: &ModelArgs,
) -> anyhow::Result<()> {
    let family: Family = args.family.parse().map_err(anyhow::Error::msg)?;
    let robot = model_args.robot_of::<N>()?;
    let file: &RobotFile = robot.file.as_ref().context("--model")?;
    let name = match &args.name {
        Some(name) => name.clone(),
        None => camel_case(
            &args
                .model
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
        ),
    };
    check_name(&name).map_err(|e| anyhow::anyhow!("--name {e}"))?;
    let binary = find_binary(args.binary.as_deref())?;
    let system = &robot.system;
    let energy = match args.energy {
        Some(e) if e.is_finite() && e > 0.0 => e,
        Some(e) => bail!("--energy {e}: must be finite and > 0"),
        None => default_energy(system),
    };
    let limits = file.torque_limits();
    let tau_max = match (args.tau_max, &limits) {
        (Some(t), Some(tl)) if tl.iter().any(|&l| t > l) => bail!(
            "--tau-max {t} exceeds the motor torque limit {} N m of {}",
            tl.iter().copied().fold(f64::INFINITY, f64::min),
            args.model.display()
        ),
        (Some(t), _) => t,
        (None, Some(tl)) => tl.iter().copied().fold(f64::INFINITY, f64::min),
        (None, None) => 1.0,
    };
    let source = args
        .model
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    super::prepare_out_dir(&args.out)?;
    let options = ExportOptions {
        names: PairNames::of_robot(&name, &source, N, &family.to_string()),
        ssp: &name,
        energy,
        family,
        tau_max,
        chart_degree: args.chart_degree,
        binary: &binary,
        fmi3: args.fmi.contains(&3),
    };
    let written = export::<N, S>(system, &options, &args.out)?;
    println!(
        "{} ({N} joints): {family} eigenmode at E_ref = {energy:.6} J, chart degree {}, \
         |tau| <= {tau_max} N m; binaries for {}",
        args.model.display(),
        args.chart_degree,
        written.platforms.join(", ")
    );
    for path in written.archives.iter().chain([&written.ssp]) {
        println!("wrote {}", path.display());
    }
    Ok(())
}
