//! The main job: the `EigenMPC` controller FMU drives the `DoublePendulum`
//! plant FMU in the paper's nominal scenario (curved EigenMPC, in-phase
//! eigenmode at 14 J, from q = (0.05, 0.05) at rest, 30 s).
//!
//! Both FMUs are loaded from their `.fmu` files with the `fmi` crate's
//! importer, exactly as a co-simulation tool would, and coupled by a fixed-step
//! master (controller, then plant, every sample period). By default the FMUs
//! are (re)built first with `fmu-build`. Prints the summary and writes CSV and
//! the paper-style plots under `target/demo/`.

use anyhow::{Context, Result, anyhow, bail};
use clap::Parser;
use eigenmpc::mechanics::{DoublePendulum, PlanarChainParams};
use eigenmpc::modes::Family;
use eigenmpc::mpc::ControlStatus;
use eigenmpc::mpc::closed_loop::{Sample, mode_and_chart, summarise};
use eigenmpc_cli::report::{plot_run, summary_text, write_csv};
use fmi::fmi2::Fmi2Res;
use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS};
use fmi::traits::FmiImport;
use nalgebra::{SVector, Vector2};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Co-simulation demo of the two FMUs.
#[derive(Parser, Debug)]
#[command(name = "eigenmpc-demo", version, about)]
struct Args {
    /// Directory holding EigenMPC.fmu and DoublePendulum.fmu.
    #[arg(long, default_value = "target/fmu")]
    fmu_dir: PathBuf,
    /// Output directory for the CSV and the plots.
    #[arg(long, default_value = "target/demo")]
    out_dir: PathBuf,
    /// Use the .fmu files as they are instead of rebuilding them first.
    #[arg(long)]
    no_build: bool,
    /// Reference energy E_ref (J); the in-phase chart at this energy is
    /// computed and passed to the controller FMU.
    #[arg(long, default_value_t = 14.0)]
    energy: f64,
    /// Simulated time (s).
    #[arg(long, default_value_t = 30.0)]
    duration: f64,
    /// Initial joint angles q1,q2 (rad), at rest.
    #[arg(long, default_value = "0.05,0.05", allow_hyphen_values = true)]
    q0: String,
}

/// One loaded FMU instance and its value references by name.
struct Slave {
    // Field order matters: the instance must be dropped (fmi2FreeInstance)
    // before the import removes the extracted library.
    instance: InstanceCS,
    import: Fmi2Import,
    name: &'static str,
}

impl Slave {
    fn load(path: &Path, name: &'static str) -> Result<Self> {
        let import: Fmi2Import =
            fmi::import::from_path(path).with_context(|| format!("loading {}", path.display()))?;
        let instance = import
            .instantiate_cs(name, false, true)
            .with_context(|| format!("instantiating {name}"))?;
        Ok(Self {
            instance,
            import,
            name,
        })
    }

    fn vr(&self, variable: &str) -> Result<u32> {
        Ok(self
            .import
            .model_description()
            .model_variable_by_name(variable)
            .with_context(|| format!("{}: no variable {variable}", self.name))?
            .value_reference)
    }

    fn vrs(&self, variables: &[&str]) -> Result<Vec<u32>> {
        variables.iter().map(|v| self.vr(v)).collect()
    }

    fn check(&self, what: &str, r: Result<Fmi2Res, fmi::fmi2::Fmi2Error>) -> Result<()> {
        r.map(|_| ())
            .map_err(|e| anyhow!("{}: {what} failed: {e:?}", self.name))
    }

    fn set(&mut self, vrs: &[u32], values: &[f64]) -> Result<()> {
        let r = self.instance.set_real(vrs, values);
        self.check("fmi2SetReal", r)
    }

    fn get(&mut self, vrs: &[u32], values: &mut [f64]) -> Result<()> {
        let r = self.instance.get_real(vrs, values);
        self.check("fmi2GetReal", r)
    }

    fn initialize(&mut self, start: f64, stop: Option<f64>) -> Result<()> {
        let r = self.instance.setup_experiment(None, start, stop);
        self.check("fmi2SetupExperiment", r)?;
        let r = self.instance.enter_initialization_mode();
        self.check("fmi2EnterInitializationMode", r)
    }

    fn exit_initialization(&mut self) -> Result<()> {
        let r = self.instance.exit_initialization_mode();
        self.check("fmi2ExitInitializationMode", r)
    }

    fn step(&mut self, t: f64, h: f64) -> Result<()> {
        let r = self.instance.do_step(t, h, true);
        self.check("fmi2DoStep", r)
    }
}

fn build_fmus() -> Result<()> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .args(["run", "--quiet", "--release", "-p", "fmu-build"])
        .status()
        .context("running fmu-build")?;
    if !status.success() {
        bail!("fmu-build failed ({status})");
    }
    Ok(())
}

fn main() -> std::process::ExitCode {
    match run(&Args::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", format!("{e:#}").replace('\n', " "));
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(args: &Args) -> Result<()> {
    let q0: Vec<f64> = args
        .q0
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .context("--q0 needs two numbers q1,q2")?;
    if q0.len() != 2 || q0.iter().any(|v| !v.is_finite()) {
        bail!("--q0 needs two finite numbers q1,q2");
    }
    if !(args.duration > 0.0 && args.duration <= 3600.0) {
        bail!("--duration must be in (0, 3600] s");
    }
    if !args.no_build {
        build_fmus()?;
    }
    let model = DoublePendulum::new(PlanarChainParams::default())?;
    // The true eigenmode (for the plot overlay and the distance metric) and
    // the chart the curved controller needs at this energy.
    let (mode, chart) = mode_and_chart::<_, 2, 4>(&model, Family::InPhase.index(), args.energy, 9)
        .with_context(|| format!("in-phase eigenmode at {} J", args.energy))?;

    let mut controller = Slave::load(&args.fmu_dir.join("EigenMPC.fmu"), "EigenMPC")?;
    let mut plant = Slave::load(&args.fmu_dir.join("DoublePendulum.fmu"), "DoublePendulum")?;

    let plant_out = plant.vrs(&["q[1]", "q[2]", "qd[1]", "qd[2]", "energy"])?;
    let plant_in = plant.vrs(&["tau[1]", "tau[2]"])?;
    let ctrl_in = controller.vrs(&["q[1]", "q[2]", "qd[1]", "qd[2]"])?;
    let ctrl_out = controller.vrs(&["tau[1]", "tau[2]", "solve_time"])?;
    let ctrl_diag = controller.vrs(&["solver_status", "qp_iterations"])?;

    // No stop time: the controller also steps at the last sample to report its torque.
    plant.initialize(0.0, None)?;
    plant.set(&plant.vrs(&["q0[1]", "q0[2]"])?, &q0)?;
    plant.exit_initialization()?;

    controller.initialize(0.0, None)?;
    controller.set(&[controller.vr("E_ref")?], &[args.energy])?;
    for j in 0..2 {
        for (k, a) in chart.coefficients[j].iter().enumerate() {
            let vr = controller.vr(&format!("chart.coef[{},{k}]", j + 1))?;
            controller.set(&[vr], &[*a])?;
        }
    }
    let mut dt = [0.0];
    controller.get(&[controller.vr("sample_period")?], &mut dt)?;
    let h = dt[0];
    // Inputs for the first solve, done at exitInitializationMode.
    let mut y = [0.0; 5];
    plant.get(&plant_out, &mut y)?;
    controller.set(&ctrl_in, &y[..4])?;
    controller.exit_initialization()?;

    let steps = (args.duration / h).round() as usize;
    let mut trace = Vec::with_capacity(steps + 1);
    let wall = Instant::now();
    for k in 0..=steps {
        let t = k as f64 * h;
        plant.get(&plant_out, &mut y)?;
        if k > 0 {
            // At t_start the inputs were set during initialization (first solve).
            controller.set(&ctrl_in, &y[..4])?;
        }
        // The controller solves at the communication point t with the inputs
        // just set; its torque is the output when doStep returns, held over
        // [t, t + h] (see README, "Timing").
        controller.step(t, h)?;
        let mut out = [0.0; 3];
        controller.get(&ctrl_out, &mut out)?;
        let mut diag = [0; 2];
        let r = controller.instance.get_integer(&ctrl_diag, &mut diag);
        controller.check("fmi2GetInteger", r)?;
        trace.push(Sample {
            time: t,
            state: SVector::<f64, 4>::from_column_slice(&y[..4]),
            tau: Vector2::new(out[0], out[1]),
            energy: y[4],
            solve_time: out[2],
            preparation_time: 0.0,
            status: ControlStatus::from_code(diag[0])
                .ok_or_else(|| anyhow!("unknown solver_status {}", diag[0]))?,
            qp_iterations: diag[1].max(0) as usize,
        });
        if k == steps {
            break;
        }
        plant.set(&plant_in, &out[..2])?;
        plant.step(t, h)?;
    }
    let wall = wall.elapsed().as_secs_f64();

    let summary = summarise(&trace, args.energy, Some(&mode.path), 5.0);
    println!(
        "EigenMPC.fmu drives DoublePendulum.fmu: curved, in-phase, E_ref = {} J, q0 = ({}, {}), {} s, sample period {} s",
        args.energy, q0[0], q0[1], args.duration, h
    );
    print!("{}", summary_text(&summary));
    println!("co-simulation wall time:         {wall:.2} s");
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    let csv = args.out_dir.join("demo.csv");
    write_csv(&csv, &trace).with_context(|| format!("writing {}", csv.display()))?;
    for name in ["demo.png", "demo.svg"] {
        let path = args.out_dir.join(name);
        plot_run(&path, &trace, &mode.path, args.energy)?;
    }
    println!(
        "wrote {}, {} and {}",
        csv.display(),
        args.out_dir.join("demo.png").display(),
        args.out_dir.join("demo.svg").display()
    );
    Ok(())
}
