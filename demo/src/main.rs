//! The main job: the `EigenMPC` controller FMU drives the `DoublePendulum`
//! plant FMU in the paper's nominal scenario (curved EigenMPC, in-phase
//! eigenmode at 14 J, from q = (0.05, 0.05) at rest, 30 s).
//!
//! Both FMUs are loaded from their `.fmu` files with the `fmi` crate's
//! importer, exactly as a co-simulation tool would, and coupled by a fixed-step
//! master (controller, then plant, every sample period). By default the FMUs
//! are (re)built first with `fmu-build`. Prints the summary and writes CSV and
//! the paper-style plots under `target/demo/`.
//!
//! `--model FILE` puts a robot parameter file (`robots/`) into both FMUs: the
//! controller computes that robot's eigenmode family itself (its default
//! `chart_source = computed`). `--links 3` runs the 3-link pair
//! `EigenMPC3.fmu` / `TriplePendulum.fmu`.

use anyhow::{Context, Result, anyhow, bail};
use clap::Parser;
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams, Vector};
use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::Family;
use eigenmpc::mpc::ControlStatus;
use eigenmpc::mpc::closed_loop::{Sample, mode_and_chart, summarise};
use eigenmpc_cli::export;
use eigenmpc_cli::report::{PlotInfo, plot_run, summary_text, write_csv};
use eigenmpc_fmu_models::controller::start_values::model_start_values;
use fmi::fmi2::Fmi2Res;
use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS};
use fmi::traits::FmiImport;
use fmi2_slave::Value;
use nalgebra::SVector;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Co-simulation demo of the controller and plant FMUs.
#[derive(Parser, Debug)]
#[command(name = "eigenmpc-demo", version, about)]
struct Args {
    /// Directory holding EigenMPC.fmu and DoublePendulum.fmu (and the 3-link pair).
    #[arg(long, default_value = "target/fmu")]
    fmu_dir: PathBuf,
    /// Output directory for the CSV and the plots.
    #[arg(long, default_value = "target/demo")]
    out_dir: PathBuf,
    /// Use the .fmu files as they are instead of rebuilding them first.
    #[arg(long)]
    no_build: bool,
    /// Reference energy E_ref (J); the controller FMU computes the chart.
    #[arg(long, default_value_t = 14.0)]
    energy: f64,
    /// Simulated time (s; default 30 for 2 links, 60 for 3).
    #[arg(long)]
    duration: Option<f64>,
    /// Initial joint angles `q1,q2[,q3]` (rad), at rest (default 0.05 each).
    #[arg(long, allow_hyphen_values = true)]
    q0: Option<String>,
    /// Number of links: 2 (EigenMPC.fmu, DoublePendulum.fmu) or 3
    /// (EigenMPC3.fmu, TriplePendulum.fmu); default 2, or the model file's
    /// (a file of 1, 4, 5 or 6 links is exported into OUT_DIR/fmu first).
    #[arg(long)]
    links: Option<usize>,
    /// Robot parameter file (JSON or YAML, see robots/README.md) for the
    /// controller's model and the plant; default: the paper's point masses.
    #[arg(long)]
    model: Option<PathBuf>,
    /// Torque bound |tau_j| <= tau_max (N m; default 1, or less where the
    /// model file's motor limits `tl<j>` are lower).
    #[arg(long)]
    tau_max: Option<f64>,
}

/// One loaded FMU instance and its value references by name.
struct Slave {
    // Field order matters: the instance must be dropped (fmi2FreeInstance)
    // before the import removes the extracted library.
    instance: InstanceCS,
    import: Fmi2Import,
    name: String,
}

impl Slave {
    fn load(path: &Path, name: &str) -> Result<Self> {
        let import: Fmi2Import =
            fmi::import::from_path(path).with_context(|| format!("loading {}", path.display()))?;
        let instance = import
            .instantiate_cs(name, false, true)
            .with_context(|| format!("instantiating {name}"))?;
        Ok(Self {
            instance,
            import,
            name: name.to_string(),
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

/// Builds the FMUs with fmu-build: for the host's platform only (the demo
/// runs there) unless `FMU_PLATFORMS` says otherwise; `tests/run.sh`
/// builds every platform. fmu-build is built together with the demo and the
/// CLI, as `tests/run.sh` builds them: one feature set for the shared
/// crates, so nothing is compiled twice (`cargo run -p fmu-build` alone
/// would resolve other features of syn, typenum, ... and rebuild most of
/// the workspace).
fn build_fmus() -> Result<()> {
    use fmu_build::platform::PLATFORMS_ENV;
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let platforms = std::env::var(PLATFORMS_ENV).unwrap_or_else(|_| "linux64".into());
    let status = Command::new(cargo)
        .args(["build", "--quiet", "--release"])
        .args([
            "-p",
            "fmu-build",
            "-p",
            "eigenmpc-demo",
            "-p",
            "eigenmpc-cli",
        ])
        .status()
        .context("building fmu-build")?;
    if !status.success() {
        bail!("building fmu-build failed ({status})");
    }
    let exe = std::env::current_exe().context("locating the demo's executable")?;
    let fmu_build = exe.with_file_name(format!("fmu-build{}", std::env::consts::EXE_SUFFIX));
    let status = Command::new(&fmu_build)
        .env(PLATFORMS_ENV, platforms)
        .status()
        .with_context(|| format!("running {}", fmu_build.display()))?;
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
    let file = args.model.as_ref().map(RobotFile::load).transpose()?;
    let links = match (args.links, &file) {
        (Some(n), Some(f)) if n != f.links() => bail!(
            "--links {n} but {} describes {} links",
            f.path().display(),
            f.links()
        ),
        (Some(n), _) => n,
        (None, Some(f)) => f.links(),
        (None, None) => 2,
    };
    // The shipped pairs for 2 and 3 links; any other count of the table is
    // a robot file exported as a pair (no shipped FMU to fall back on).
    let pair = match (links, &file) {
        (2, _) => Pair::Shipped("EigenMPC", "DoublePendulum"),
        (3, _) => Pair::Shipped("EigenMPC3", "TriplePendulum"),
        (n, None) => bail!(
            "--links {n}: the shipped FMUs have 2 or 3 links; give a robot file of {n} links \
             (--model FILE), which the demo exports as an FMU pair"
        ),
        (_, Some(_)) => Pair::Exported,
    };
    eigenmpc::with_joint_count!(
        links,
        |N, S, NP| co_simulate::<N, S>(args, file.as_ref(), pair),
        otherwise bail!("{}", eigenmpc::joints::unsupported(links))
    )
}

/// The controller and plant FMUs of a run.
#[derive(Clone, Copy)]
enum Pair {
    /// A shipped pair in `--fmu-dir`: controller and plant `modelIdentifier`.
    Shipped(&'static str, &'static str),
    /// The robot file exported (`eigenmpc export`) into `OUT_DIR/fmu`.
    Exported,
}

/// Sets every Real start value of `values` (the model rows are all Real).
fn set_values(slave: &mut Slave, values: &[(String, Value)]) -> Result<()> {
    for (name, value) in values {
        let Value::Real(v) = value else {
            bail!("{name}: a model parameter that is not Real");
        };
        let vr = slave.vr(name)?;
        slave.set(&[vr], &[*v])?;
    }
    Ok(())
}

fn co_simulate<const N: usize, const NX: usize>(
    args: &Args,
    file: Option<&RobotFile>,
    pair: Pair,
) -> Result<()> {
    let q0: Vec<f64> = match &args.q0 {
        Some(text) => text
            .split(',')
            .map(|s| s.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .with_context(|| format!("--q0 needs {N} numbers"))?,
        None => vec![0.05; N],
    };
    if q0.len() != N || q0.iter().any(|v| !v.is_finite()) {
        bail!("--q0 needs {N} finite numbers (one angle per joint)");
    }
    let duration = args.duration.unwrap_or(if N == 2 { 30.0 } else { 60.0 });
    if !(duration > 0.0 && duration <= 3600.0) {
        bail!("--duration must be in (0, 3600] s");
    }
    if !(args.energy.is_finite() && args.energy > 0.0) {
        bail!("--energy must be finite and > 0");
    }
    let params: PlanarChainParams<N> = match file {
        Some(f) => f.params::<N>()?,
        None => PlanarChainParams::default(),
    };
    let model = PlanarChain::new(params)?;
    let limit = file
        .and_then(|f| f.torque_limits())
        .map(|tl| tl.into_iter().fold(f64::INFINITY, f64::min));
    let tau_max = match (args.tau_max, limit) {
        (Some(t), Some(tl)) if t > tl => {
            bail!("--tau-max {t} exceeds the robot's motor torque limit {tl} N m")
        }
        (Some(t), _) => t,
        (None, tl) => tl.unwrap_or(1.0).min(1.0),
    };
    if !args.no_build {
        build_fmus()?;
    }
    // The true eigenmode, for the plot overlay and the distance metric (the
    // controller FMU computes its own chart family).
    let (mode, _) = mode_and_chart::<_, N, NX>(&model, Family::InPhase.index(), args.energy, 9)
        .with_context(|| format!("in-phase eigenmode at {} J", args.energy))?;
    let model_values = model_start_values(&params).map_err(|e| anyhow!("model: {e}"))?;

    let ((controller_name, controller_path), (plant_name, plant_path)) = match pair {
        Pair::Shipped(c, p) => (
            (c.to_string(), args.fmu_dir.join(format!("{c}.fmu"))),
            (p.to_string(), args.fmu_dir.join(format!("{p}.fmu"))),
        ),
        Pair::Exported => {
            let file = file.context("an exported pair needs a robot file")?;
            let stem = file
                .path()
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let binary = export::robot_binary_path(&args.fmu_dir);
            let source = file.path().display().to_string();
            let name = export::camel_case(&stem);
            let family = Family::InPhase;
            let options = export::ExportOptions {
                names: export::PairNames::of_robot(&name, &source, N, &family.to_string()),
                ssp: &name,
                energy: args.energy,
                family,
                tau_max,
                chart_degree: 9,
                binary: &export::find_binary(Some(&binary))?,
                fmi3: false,
            };
            let written = export::export::<N, NX>(&model, &options, &args.out_dir.join("fmu"))?;
            println!(
                "exported {} as {} and {}",
                source,
                written.controller.1.display(),
                written.plant.1.display()
            );
            (written.controller, written.plant)
        }
    };
    let mut controller = Slave::load(&controller_path, &controller_name)?;
    let mut plant = Slave::load(&plant_path, &plant_name)?;

    let joints = |base: &'static str| (1..=N).map(move |j| format!("{base}[{j}]"));
    let state_names: Vec<String> = joints("q").chain(joints("qd")).collect();
    let state_names: Vec<&str> = state_names.iter().map(String::as_str).collect();
    let tau_names: Vec<String> = joints("tau").collect();
    let tau_names: Vec<&str> = tau_names.iter().map(String::as_str).collect();
    let q0_names: Vec<String> = joints("q0").collect();
    let q0_names: Vec<&str> = q0_names.iter().map(String::as_str).collect();
    let plant_out = plant.vrs(&[state_names.as_slice(), &["energy"]].concat())?;
    let plant_in = plant.vrs(&tau_names)?;
    let ctrl_in = controller.vrs(&state_names)?;
    let ctrl_out = controller.vrs(&[tau_names.as_slice(), &["solve_time"]].concat())?;
    let ctrl_diag = controller.vrs(&["solver_status", "qp_iterations"])?;

    // No stop time: the controller also steps at the last sample to report its torque.
    plant.initialize(0.0, None)?;
    set_values(&mut plant, &model_values)?;
    plant.set(&plant.vrs(&q0_names)?, &q0)?;
    plant.exit_initialization()?;

    controller.initialize(0.0, None)?;
    set_values(&mut controller, &model_values)?;
    let reference = controller.vrs(&["E_ref", "tau_max"])?;
    controller.set(&reference, &[args.energy, tau_max])?;
    let mut dt = [0.0];
    controller.get(&[controller.vr("sample_period")?], &mut dt)?;
    let h = dt[0];
    // Inputs for the first solve, done at exitInitializationMode (where the
    // controller computes its chart family).
    let mut y = vec![0.0; 2 * N + 1];
    plant.get(&plant_out, &mut y)?;
    controller.set(&ctrl_in, &y[..2 * N])?;
    let created = Instant::now();
    controller.exit_initialization()?;
    let created = created.elapsed().as_secs_f64();
    let mut range = [0.0; 2];
    controller.get(
        &controller.vrs(&["chart_energy_min", "chart_energy_max"])?,
        &mut range,
    )?;

    let steps = (duration / h).round() as usize;
    let mut trace: Vec<Sample<N, NX>> = Vec::with_capacity(steps + 1);
    let mut out = vec![0.0; N + 1];
    let wall = Instant::now();
    for k in 0..=steps {
        let t = k as f64 * h;
        plant.get(&plant_out, &mut y)?;
        if k > 0 {
            // At t_start the inputs were set during initialization (first solve).
            controller.set(&ctrl_in, &y[..2 * N])?;
        }
        // The controller solves at the communication point t with the inputs
        // just set; its torque is the output when doStep returns, held over
        // [t, t + h] (see docs/book/src/fmu-variables.md, "Timing").
        controller.step(t, h)?;
        controller.get(&ctrl_out, &mut out)?;
        let mut diag = [0; 2];
        let r = controller.instance.get_integer(&ctrl_diag, &mut diag);
        controller.check("fmi2GetInteger", r)?;
        trace.push(Sample {
            time: t,
            state: SVector::<f64, NX>::from_column_slice(&y[..2 * N]),
            tau: Vector::<N>::from_column_slice(&out[..N]),
            energy: y[2 * N],
            solve_time: out[N],
            preparation_time: 0.0,
            status: ControlStatus::from_code(diag[0])
                .ok_or_else(|| anyhow!("unknown solver_status {}", diag[0]))?,
            qp_iterations: diag[1].max(0) as usize,
        });
        if k == steps {
            break;
        }
        plant.set(&plant_in, &out[..N])?;
        plant.step(t, h)?;
    }
    let wall = wall.elapsed().as_secs_f64();

    let summary = summarise(&trace, args.energy, Some(&mode.path), 5.0);
    let robot = match file {
        Some(f) => format!("{} ({})", f.name().unwrap_or("robot"), f.path().display()),
        None => format!("{N}-link point-mass chain (1 kg, 1 m)"),
    };
    let q0_text: Vec<String> = q0.iter().map(|q| q.to_string()).collect();
    println!(
        "{controller_name}.fmu drives {plant_name}.fmu: {robot}, curved, in-phase, E_ref = {} J, \
         |tau| <= {tau_max} N m, q0 = ({}), {duration} s, sample period {h} s",
        args.energy,
        q0_text.join(", ")
    );
    if range[1] > range[0] {
        println!(
            "chart family computed by the controller FMU: {:.4} .. {:.4} J in {:.0} ms",
            range[0],
            range[1],
            created * 1e3
        );
    } else {
        // An exported controller starts from its chart at E_ref
        // (chart_source = parameters): no family to compute.
        println!(
            "chart at E_ref from the exported start values; controller initialized in {:.0} ms",
            created * 1e3
        );
    }
    print!("{}", summary_text(&summary));
    println!("co-simulation wall time:         {wall:.2} s");
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    let csv = args.out_dir.join("demo.csv");
    write_csv(&csv, &trace).with_context(|| format!("writing {}", csv.display()))?;
    let info = PlotInfo {
        caption: format!(
            "{controller_name}.fmu drives {plant_name}.fmu: curved, in-phase, E_ref = {} J, \
             |\u{3c4}| \u{2264} {tau_max} N m, q0 = ({}), sample period {h} s",
            args.energy,
            q0_text.join(", ")
        ),
        tau_max: Some(tau_max),
    };
    for name in ["demo.png", "demo.svg"] {
        let path = args.out_dir.join(name);
        plot_run(&path, &trace, &mode.path, args.energy, &info)?;
    }
    println!(
        "wrote {}, {} and {}",
        csv.display(),
        args.out_dir.join("demo.png").display(),
        args.out_dir.join("demo.svg").display()
    );
    Ok(())
}
