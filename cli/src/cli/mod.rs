//! Command-line interface. Errors are printed as one line on stderr with a
//! non-zero exit code, never as a panic trace.

mod export;
mod modes;
mod paper;
mod robustness;
mod simulate;
mod sweep;

use clap::{Args, Parser, Subcommand};
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams};
use eigenmpc::model_file::RobotFile;
use eigenmpc_fmu_models::controller::named::check_named;
use eigenmpc_fmu_models::products::EigenMpc2;
use std::path::PathBuf;
use std::process::ExitCode;

/// EigenMPC: eigenmodes and eigenmanifold-inspired NMPC for the double pendulum.
#[derive(Parser, Debug)]
#[command(name = "eigenmpc", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Compute nonlinear eigenmodes (brake orbits) and their charts; prints JSON.
    Modes(modes::ModesArgs),
    /// Closed loop of the EigenMPC controller against the accurate plant; prints a summary.
    Simulate(Box<simulate::SimulateArgs>),
    /// Robustness report: the controller against plants and set-ups that differ from its model
    /// (each parameter, noise, motor lag, delay), without and with online adaptation.
    Robustness(Box<robustness::RobustnessArgs>),
    /// Closed loops over a grid or a random sample of controller, plant and set-up parameters,
    /// on all cores; CSV, JSON and a plot of one metric.
    Sweep(Box<sweep::SweepArgs>),
    /// The paper's section V figures and the hybrid experiment from this engine, and
    /// report.md with each claim of the paper next to the measured figure and a verdict.
    Paper(paper::PaperArgs),
    /// A robot file (1 to 6 joints) as a controller FMU, a plant FMU and the SSP that couples
    /// them, each validated; no compiler needed.
    Export(export::ExportArgs),
}

/// The robot: a parameter file, or the paper's point-mass double pendulum
/// with the given masses and lengths.
#[derive(Args, Debug, Clone)]
pub struct ModelArgs {
    /// Robot parameter file (JSON or YAML, flat keys m1 m2 l1 l2 r1 r2 I1 I2 Ir gr b1 b2 cf1
    /// cf2 g ...; see the book, docs/book/src/robots.md). Replaces --m1 .. --g.
    #[arg(long, value_name = "FILE")]
    pub model: Option<PathBuf>,
    /// Mass at the tip of link 1 (kg).
    #[arg(
        long,
        default_value_t = 1.0,
        allow_negative_numbers = true,
        conflicts_with = "model"
    )]
    pub m1: f64,
    /// Mass at the tip of link 2 (kg).
    #[arg(
        long,
        default_value_t = 1.0,
        allow_negative_numbers = true,
        conflicts_with = "model"
    )]
    pub m2: f64,
    /// Length of link 1 (m).
    #[arg(
        long,
        default_value_t = 1.0,
        allow_negative_numbers = true,
        conflicts_with = "model"
    )]
    pub l1: f64,
    /// Length of link 2 (m).
    #[arg(
        long,
        default_value_t = 1.0,
        allow_negative_numbers = true,
        conflicts_with = "model"
    )]
    pub l2: f64,
    /// Gravitational acceleration (m/s^2).
    #[arg(
        long,
        default_value_t = 9.81,
        allow_negative_numbers = true,
        conflicts_with = "model"
    )]
    pub g: f64,
}

/// The robot a command works on.
pub struct Robot<const N: usize = 2> {
    /// The model (plant and, unless told otherwise, controller).
    pub system: PlanarChain<N>,
    /// The parameter file it came from, if any.
    pub file: Option<RobotFile>,
}

impl ModelArgs {
    /// The robot of the parameter file `path`.
    pub fn for_file(path: &std::path::Path) -> Self {
        Self {
            model: Some(path.to_path_buf()),
            m1: 1.0,
            m2: 1.0,
            l1: 1.0,
            l2: 1.0,
            g: 9.81,
        }
    }

    /// The robot's joint count: the parameter file's links, or 2 for the
    /// point-mass pendulum of `--m1 .. --g`. A count outside the joint-count
    /// table is an error.
    pub fn joint_count(&self) -> anyhow::Result<usize> {
        Ok(eigenmpc::model_file::joint_count(self.model.as_deref())?)
    }

    /// Builds the `N`-joint robot, refusing non-physical parameters, bad
    /// files and a file of another joint count.
    pub fn robot_of<const N: usize>(&self) -> anyhow::Result<Robot<N>> {
        Ok(match &self.model {
            Some(path) => {
                let file = RobotFile::load(path)?;
                Robot {
                    system: file.chain::<N>()?,
                    file: Some(file),
                }
            }
            None => {
                if N != 2 {
                    anyhow::bail!(
                        "--m1 .. --g describe the 2-joint pendulum: give a {N}-joint robot with --model FILE"
                    );
                }
                // The controller FMU's ranges for the same parameters: one
                // set of limits for every entry point (m in [1e-6, 1e6] kg,
                // l in [1e-3, 1e3] m, g in [0, 1e3] m/s^2).
                for (flag, name, value) in [
                    ("--m1", "m[1]", self.m1),
                    ("--m2", "m[2]", self.m2),
                    ("--l1", "l[1]", self.l1),
                    ("--l2", "l[2]", self.l2),
                    ("--g", "g", self.g),
                ] {
                    check_named::<EigenMpc2, 2>(name, value)
                        .map_err(|e| anyhow::anyhow!("{flag}: {e}"))?;
                }
                let (mass, length) = ([self.m1, self.m2], [self.l1, self.l2]);
                Robot {
                    system: PlanarChain::new(PlanarChainParams::point_masses(
                        std::array::from_fn(|j| mass[j]),
                        std::array::from_fn(|j| length[j]),
                        self.g,
                    ))?,
                    file: None,
                }
            }
        })
    }
}

impl<const N: usize> Robot<N> {
    /// The `model` object of the JSON outputs: the paper's keys for the
    /// point-mass pendulum, the file and its entries for a parameter file.
    pub fn json(&self) -> serde_json::Value {
        match &self.file {
            None => {
                let p = self.system.params();
                let mut map = serde_json::Map::new();
                map.insert("kind".into(), "double-pendulum".into());
                for (j, link) in p.links.iter().enumerate() {
                    map.insert(format!("m{}", j + 1), link.mass.into());
                    map.insert(format!("l{}", j + 1), link.length.into());
                }
                map.insert("g".into(), p.gravity.into());
                serde_json::Value::Object(map)
            }
            Some(f) => {
                let mut map = serde_json::Map::new();
                map.insert("kind".into(), "planar-chain".into());
                map.insert("file".into(), f.path().display().to_string().into());
                if let Some(name) = f.name() {
                    map.insert("name".into(), name.into());
                }
                for (k, v) in f.entries() {
                    map.insert(k.clone(), (*v).into());
                }
                serde_json::Value::Object(map)
            }
        }
    }
}

/// Creates the output folder `dir` and checks that it is writable, so that
/// a bad `--out` is found before any run, not after.
pub fn prepare_out_dir(dir: &std::path::Path) -> anyhow::Result<()> {
    use anyhow::Context;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let probe = dir.join(".eigenmpc-write-test");
    std::fs::write(&probe, b"").with_context(|| format!("cannot write into {}", dir.display()))?;
    std::fs::remove_file(&probe).ok();
    Ok(())
}

/// `--variant`: its values, and their help, are the rows of the core's
/// variant table (a new variant shows up here by itself).
pub fn variant_parser() -> impl clap::builder::TypedValueParser<Value = eigenmpc::mpc::Variant> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(
        eigenmpc::mpc::VARIANTS
            .iter()
            .map(|v| PossibleValue::new(v.name).help(v.description)),
    )
    .map(|name| {
        name.parse::<eigenmpc::mpc::Variant>()
            .expect("every value offered is a row of the table")
    })
}

/// Parses a comma-separated list of numbers (`"2,8,14"`).
pub fn parse_list(name: &str, text: &str) -> anyhow::Result<Vec<f64>> {
    text.split(',')
        .map(|item| {
            item.trim()
                .parse::<f64>()
                .map_err(|_| anyhow::anyhow!("--{name}: '{}' is not a number", item.trim()))
        })
        .collect()
}

/// Runs the CLI and maps errors to a one-line message and exit code 1.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help, --version: clap's text on stdout, success.
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            // A flag error: clap's first line (what is wrong), exit code 1
            // like every other error.
            // The first paragraph (e.g. "required arguments were not
            // provided:" and the list of them), on one line.
            let text = e.render().to_string();
            let first: Vec<&str> = text
                .lines()
                .take_while(|l| !l.trim().is_empty())
                .map(str::trim)
                .collect();
            let first = first.join(" ");
            let first = first.strip_prefix("error: ").unwrap_or(&first);
            eprintln!("error: {first} (see --help)");
            return ExitCode::FAILURE;
        }
    };
    let result = match cli.command {
        Command::Modes(args) => modes::run(&args),
        Command::Simulate(args) => simulate::run_simulate(&args),
        Command::Robustness(args) => robustness::run(&args),
        Command::Sweep(args) => sweep::run_sweep(&args),
        Command::Paper(args) => paper::run(&args),
        Command::Export(args) => export::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let text = format!("{e:#}").replace('\n', " ");
            eprintln!("error: {text}");
            ExitCode::FAILURE
        }
    }
}
