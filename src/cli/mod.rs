//! Command-line interface. Errors are printed as one line on stderr with a
//! non-zero exit code, never as a panic trace.

mod modes;
mod simulate;

use clap::{Args, Parser, Subcommand};
use eigenmpc::mechanics::{DoublePendulum, PlanarChainParams};
use serde::Serialize;
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
    Simulate(simulate::SimulateArgs),
}

/// Parameters of the double pendulum (paper, section V).
#[derive(Args, Debug, Clone, Copy)]
pub struct ModelArgs {
    /// Mass at the tip of link 1 (kg).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub m1: f64,
    /// Mass at the tip of link 2 (kg).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub m2: f64,
    /// Length of link 1 (m).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub l1: f64,
    /// Length of link 2 (m).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub l2: f64,
    /// Gravitational acceleration (m/s^2).
    #[arg(long, default_value_t = 9.81, allow_negative_numbers = true)]
    pub g: f64,
}

/// The `model` object of the JSON outputs.
#[derive(Serialize, Debug, Clone, Copy)]
pub struct ModelJson {
    kind: &'static str,
    m1: f64,
    m2: f64,
    l1: f64,
    l2: f64,
    g: f64,
}

impl ModelArgs {
    /// Builds the pendulum, refusing non-physical parameters.
    pub fn pendulum(&self) -> anyhow::Result<DoublePendulum> {
        Ok(DoublePendulum::new(PlanarChainParams::point_masses(
            [self.m1, self.m2],
            [self.l1, self.l2],
            self.g,
        ))?)
    }

    /// The JSON description of the model.
    pub fn json(&self) -> ModelJson {
        ModelJson {
            kind: "double-pendulum",
            m1: self.m1,
            m2: self.m2,
            l1: self.l1,
            l2: self.l2,
            g: self.g,
        }
    }
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
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Modes(args) => modes::run(&args),
        Command::Simulate(args) => simulate::run_simulate(&args),
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
