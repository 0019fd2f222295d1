//! `eigenmpc simulate`: closed loop of the EigenMPC controller against the
//! accurate plant integrator; prints the summary, writes CSV and plots.

use super::{ModelArgs, Robot};
use anyhow::{Context, bail};
use clap::Args;
use eigenmpc::adapt::{AdaptOptions, Adaptation};
use eigenmpc::identify::BaseParameters;
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams, Vector};
use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::{Chart, ChartFamily, Family, FamilyOptions, linear_modes};
use eigenmpc::mpc::closed_loop::{
    GaussianNoise, Summary, energy_tail, mode_and_chart, rms_friction_torque, run_measured_with,
    summarise,
};
use eigenmpc::mpc::{
    Controller, EstimatorConfig, FrictionSmoothing, MpcConfig, PREDICTION_SUBSTEPS, QpBackend,
    Reference, Variant, prediction_coulomb_sharpness, prediction_substeps,
};
use eigenmpc_cli::adaptation::{self, AdaptationSample, base_parameter_names};
use eigenmpc_cli::report::{
    PlotInfo, number, plot_run, summary_text, window_label, write_csv_with,
};
use nalgebra::SVector;
use std::path::{Path, PathBuf};

/// Arguments of `eigenmpc simulate`.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Cost variant.
    #[arg(long, default_value = "curved", value_parser = super::variant_parser())]
    variant: Variant,
    /// Mode family: `in-phase` or `anti-phase`.
    #[arg(long, default_value = "in-phase")]
    family: String,
    /// Reference energy E_ref (J).
    #[arg(long, default_value_t = 14.0, allow_negative_numbers = true)]
    energy: f64,
    /// Initial state q1,..,qN,qd1,..,qdN (rad, rad/s); default: 0.05 rad on every joint, at
    /// rest.
    #[arg(long, allow_hyphen_values = true)]
    x0: Option<String>,
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
    /// RK4 substeps per interval, the most (default: 1, or as many as the model's Coulomb friction needs with a joint at rest; an interval in which no joint can stop takes fewer).
    #[arg(long)]
    substeps: Option<usize>,
    /// Torque bound (N m).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    tau_max: f64,
    /// Energy weight w_E (default: 25 curved, 5 straight).
    #[arg(long, allow_negative_numbers = true)]
    w_e: Option<f64>,
    /// Energy scale E_s (J): below it the energy residual is r_E = (E_ref - E) sqrt(E_s / E_ref),
    /// so that a low E_ref is pulled towards as E_s is (w_E was tuned at 14 J, the default); from
    /// E_s up, and with 0, the paper's r_E = E_ref - E.
    #[arg(long, default_value_t = eigenmpc::mpc::PAPER_ENERGY_SCALE, allow_negative_numbers = true)]
    e_scale: f64,
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
    /// Curved: degree of the computed chart(s) (the paper: 9).
    #[arg(long, default_value_t = 9)]
    chart_degree: usize,
    /// Curved: compute the mode family over energy at start-up and follow
    /// E_ref along it (implied by --e-ref-at); default: the chart at E_ref.
    #[arg(long)]
    chart_family: bool,
    /// Top of the family's energy range (J; default max(0.5 V_up, 1.25 E_ref, tuned E_ref),
    /// V_up the potential with every link upright).
    #[arg(long, allow_negative_numbers = true)]
    family_energy_max: Option<f64>,
    /// Tuned E_ref during the run: `T:E[,T:E...]` (s:J), as an FMU master sets the tunable.
    #[arg(long, value_name = "T:E,...")]
    e_ref_at: Option<String>,
    /// Coulomb slope k of the controller's prediction model (s/rad; default: the plant's,
    /// lowered so that an RK4 step resolves the friction, see docs/book/src/robots.md).
    #[arg(long, allow_negative_numbers = true)]
    model_coulomb_sharpness: Option<f64>,
    /// Penalise the whole torque tau instead of tau - tau_f(qd) (friction fought, not compensated).
    #[arg(long)]
    no_friction_compensation: bool,
    /// Measurement noise: standard deviation added to every measured angle
    /// (rad) and speed (rad/s), Gaussian, deterministic (see --seed).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    noise: f64,
    /// The speeds' measurement noise when it differs from the angles'
    /// (rad/s; default: --noise), e.g. `--noise 0.005 --speed-noise 0.05`
    /// as the laboratory robots' sensors.
    #[arg(long, allow_negative_numbers = true)]
    speed_noise: Option<f64>,
    /// Seed of the measurement noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Switch the stall supervisor off (it releases the torque of a joint
    /// held still by a large torque while the energy is off target; the
    /// FMU's `supervisor`).
    #[arg(long)]
    no_supervisor: bool,
    /// Filter the measurement with the controller's extended Kalman filter:
    /// `ANGLE,SPEED,ACCELERATION` noise levels (rad, rad/s, rad/s^2), e.g.
    /// `0.05,0.05,0.3`.
    #[arg(long, value_name = "ANGLE,SPEED,ACCEL")]
    ekf: Option<String>,
    /// Plant side: the controller sees the state of this many samples ago
    /// (before t = 0: the initial state).
    #[arg(long, default_value_t = 0)]
    delay_samples: usize,
    /// Controller: the age of the measurement it gets (s), predicted forward
    /// with the torques it sent since (0: none; at most 1 s and N dt).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    measurement_delay: f64,
    /// Controller: time constant of the motor's first-order lag (s; 0: none;
    /// at most 1 s and N dt).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    actuator_time_constant: f64,
    /// Online adaptation of the controller's model, as the controller FMU's `adapt`: base
    /// parameters identified from the energy balance, a new model (and mode family) taken from
    /// a steady loop when it explains the motion better; adds the estimate, the model in use and
    /// the counts to the CSV and the summary, and a figure FILE_adaptation next to --plot FILE.
    #[arg(long)]
    adapt: bool,
    /// The plant: a robot parameter file (as --model, the same number of joints) that differs
    /// from the controller's model; default: the plant is the model.
    #[arg(long, value_name = "FILE")]
    plant: Option<PathBuf>,
    #[command(flatten)]
    model: ModelArgs,
}

/// The robot for a caption: its file, or the point masses.
fn robot_name<const N: usize>(robot: &Robot<N>) -> String {
    match &robot.file {
        Some(f) => f.path().display().to_string(),
        None if *robot.system.params() == PlanarChainParams::default() => {
            "the paper's pendulum".into()
        }
        None => {
            let links = &robot.system.params().links;
            let list = |f: fn(&eigenmpc::mechanics::Link) -> f64| {
                links
                    .iter()
                    .map(|l| number(f(l)))
                    .collect::<Vec<_>>()
                    .join(" / ")
            };
            format!(
                "point masses {} kg, l {} m",
                list(|l| l.mass),
                list(|l| l.length)
            )
        }
    }
}

/// The plant of `--plant FILE`: a chain with the model's number of joints.
fn plant_from_file<const N: usize>(path: &Path, model: &Robot<N>) -> anyhow::Result<Robot<N>> {
    let file = RobotFile::load(path).context("--plant")?;
    let joints = N;
    if file.links() != joints {
        bail!(
            "--plant {}: the plant has {} joints, the controller's model ({}) has {joints}: \
             give a plant with as many",
            path.display(),
            file.links(),
            robot_name(model)
        );
    }
    Ok(Robot {
        system: file.chain::<N>().context("--plant")?,
        file: Some(file),
    })
}

/// Reads the chart of the mode closest to `energy` from `eigenmpc modes`
/// JSON; the file's modes must be of `family`.
fn chart_from_json<const N: usize>(
    path: &Path,
    energy: f64,
    family: Family,
) -> anyhow::Result<Chart<N>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let doc: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let vec2 = |v: &serde_json::Value, what: &str| -> anyhow::Result<Vector<N>> {
        let a: Vec<f64> = serde_json::from_value(v.clone())
            .with_context(|| format!("{what} must be a list of numbers"))?;
        if a.len() != N {
            bail!("{what} must have {N} entries (one per joint)");
        }
        Ok(Vector::<N>::from_column_slice(&a))
    };
    let eigenvector = vec2(&doc["linear"]["eigenvector"], "linear.eigenvector")?;
    if let Some(name) = doc["family"].as_str() {
        let theirs: Family = name
            .parse()
            .map_err(|e: String| anyhow::anyhow!("--chart {}: family: {e}", path.display()))?;
        if theirs != family {
            bail!(
                "--chart {}: its modes are of the {theirs} family, this run follows the {family} family \
                 (give --family {theirs}, or a chart from `eigenmpc modes --family {family}`)",
                path.display()
            );
        }
    }
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
    let per_joint: [Vec<f64>; N] = coefficients
        .try_into()
        .map_err(|_| anyhow::anyhow!("chart.coefficients must have one list per joint ({N})"))?;
    Ok(Chart::from_coefficients(
        eigenvector,
        Vector::<N>::zeros(),
        per_joint,
    )?)
}

/// Parses `T:E,T:E,...` into (time, energy) pairs in time order.
fn parse_schedule(text: &str) -> anyhow::Result<Vec<(f64, f64)>> {
    let mut out = vec![];
    for item in text.split(',') {
        let (t, e) = item
            .split_once(':')
            .with_context(|| format!("--e-ref-at: '{item}' is not T:E"))?;
        let t: f64 = t
            .trim()
            .parse()
            .with_context(|| format!("--e-ref-at: time '{t}'"))?;
        let e: f64 = e
            .trim()
            .parse()
            .with_context(|| format!("--e-ref-at: energy '{e}'"))?;
        if !(t.is_finite() && t >= 0.0 && e.is_finite() && e > 0.0) {
            bail!("--e-ref-at: {t}:{e} needs a time >= 0 and an energy > 0");
        }
        out.push((t, e));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(out)
}

/// Runs the subcommand for the robot's joint count.
pub fn run_simulate(args: &SimulateArgs) -> anyhow::Result<()> {
    let n = args.model.joint_count()?;
    eigenmpc::with_joint_count!(
        n,
        |N, S, NP| run_simulate_for::<N, S, NP>(args),
        otherwise Err(anyhow::anyhow!(eigenmpc::joints::unsupported(n)))
    )
}

fn run_simulate_for<const N: usize, const S: usize, const NP: usize>(
    args: &SimulateArgs,
) -> anyhow::Result<()> {
    let variant = args.variant;
    let family: Family = args.family.parse().map_err(anyhow::Error::msg)?;
    let backend: QpBackend = args.qp.parse().map_err(anyhow::Error::msg)?;
    let x0 = match &args.x0 {
        Some(text) => super::parse_list("x0", text)?,
        None => (0..S).map(|i| if i < N { 0.05 } else { 0.0 }).collect(),
    };
    if x0.len() != S || x0.iter().any(|v| !v.is_finite()) {
        bail!("--x0 needs {S} finite numbers q1..q{N},qd1..qd{N} (the robot has {N} joints)");
    }
    if !(args.duration.is_finite() && args.duration > 0.0 && args.duration <= 3600.0) {
        bail!("--duration must be in (0, 3600] s");
    }
    if !(args.energy.is_finite() && args.energy > 0.0) {
        bail!("--energy must be finite and > 0");
    }
    // Output paths are checked now, not after the run.
    if let Some(path) = &args.plot {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        if !ext.eq_ignore_ascii_case("png") && !ext.eq_ignore_ascii_case("svg") {
            bail!(
                "--plot {}: the plot is written as PNG or SVG: give a name ending in .png or .svg",
                path.display()
            );
        }
    }
    let adapt_plot = args
        .plot
        .as_ref()
        .filter(|_| args.adapt)
        .map(|p| adaptation::figure_path(p));
    for (flag, path) in [
        ("csv", &args.csv),
        ("plot", &args.plot),
        ("plot", &adapt_plot),
    ] {
        if let Some(path) = path {
            std::fs::File::create(path)
                .with_context(|| format!("--{flag} {}: cannot write", path.display()))?;
        }
    }
    let schedule = match &args.e_ref_at {
        Some(text) => parse_schedule(text)?,
        None => vec![],
    };
    let robot = args.model.robot_of::<N>()?;
    // The controller's model (before its prediction's Coulomb slope) and
    // the plant it drives: the same robot unless --plant says otherwise.
    let system: PlanarChain<N> = robot.system;
    let plant_robot = match &args.plant {
        Some(path) => Some(plant_from_file(path, &robot)?),
        None => None,
    };
    let plant = plant_robot.as_ref().map_or(system, |r| r.system);
    for r in std::iter::once(&robot).chain(&plant_robot) {
        let limits = r.file.as_ref().and_then(|f| f.torque_limits());
        if let Some(tl) = limits.iter().flatten().find(|&&tl| args.tau_max > tl) {
            bail!(
                "--tau-max {} exceeds the motor torque limit {tl} N m of {}",
                args.tau_max,
                robot_name(r)
            );
        }
    }
    let mut config = MpcConfig::paper(variant);
    config.horizon = args.horizon;
    config.dt = args.dt;
    config.substeps = args
        .substeps
        .unwrap_or_else(|| prediction_substeps(&system, args.dt).min(PREDICTION_SUBSTEPS));
    config.tau_max = args.tau_max;
    config.iterations_per_sample = args.iterations;
    config.qp = backend;
    config.cost.e_ref = args.energy;
    config.cost.alpha = args.alpha;
    config.cost.beta = args.beta;
    config.cost.compensate_friction = !args.no_friction_compensation;
    config.measurement_delay = args.measurement_delay;
    config.actuator_time_constant = args.actuator_time_constant;
    config.supervisor.enabled = !args.no_supervisor;
    if let Some(text) = &args.ekf {
        let levels = super::parse_list("ekf", text)?;
        let [angle_noise, speed_noise, acceleration_noise] = levels[..] else {
            bail!("--ekf needs three noise levels ANGLE,SPEED,ACCEL");
        };
        config.estimator = Some(EstimatorConfig {
            angle_noise,
            speed_noise,
            acceleration_noise,
        });
    }
    if !(args.noise.is_finite() && args.noise >= 0.0) {
        bail!("--noise must be finite and >= 0");
    }
    if args
        .speed_noise
        .is_some_and(|v| !(v.is_finite() && v >= 0.0))
    {
        bail!("--speed-noise must be finite and >= 0");
    }
    if let Some(w) = args.w_e {
        config.cost.weights.energy = w;
    }
    config.cost.energy_scale = args.e_scale;
    config.cost.weights.position = args.w_x;
    config.cost.weights.velocity = args.w_xd;
    config.cost.weights.torque = args.w_f;
    config.validate()?;
    let sharpness = match args.model_coulomb_sharpness {
        Some(k) => k,
        None => prediction_coulomb_sharpness(&system, config.dt / config.substeps as f64),
    };
    let model = system.with_coulomb_sharpness(sharpness)?;
    if args.adapt {
        // Refused before the mode family is computed, not after.
        BaseParameters::<N, NP>::of(model.params()).context("--adapt")?;
    }
    let e_final = schedule.last().map_or(args.energy, |s| s.1);
    // With --adapt a chart variant follows its model's mode family, as the
    // FMU's default (chart_source = computed): each new model brings its
    // own charts. A chart from --chart stays (as chart_source = parameters).
    let use_family = variant.uses_chart()
        && (args.chart_family || !schedule.is_empty() || (args.adapt && args.chart.is_none()));
    let mut controller = if use_family {
        if args.chart.is_some() {
            bail!("--chart and a chart family (--chart-family, --e-ref-at) exclude each other");
        }
        let asked: Vec<f64> = schedule.iter().map(|s| s.1).chain([args.energy]).collect();
        let defaults = match args.family_energy_max {
            Some(e) => FamilyOptions::up_to(e),
            None => FamilyOptions::for_system(&system, &asked),
        };
        let e_max = defaults.energy_max;
        let opts = FamilyOptions {
            degree: args.chart_degree,
            ..defaults
        };
        let chart_family = ChartFamily::compute::<_, S>(&model, family.index(), &opts)
            .with_context(|| format!("{family} mode family up to {e_max} J"))?;
        let (lo, hi) = chart_family.energy_range();
        eprintln!("{family} mode family: charts for {lo:.4} .. {hi:.4} J");
        if let Some(why) = chart_family.ended_early() {
            eprintln!("  (ends below {e_max} J: {why})");
        }
        Controller::<_, N, S>::with_family_as(model, config, chart_family, variant)?
    } else {
        let reference = Reference::of::<anyhow::Error>(
            variant,
            || {
                Ok(linear_modes(&model)?
                    .get(family.index())
                    .with_context(|| format!("a {N}-joint chain has no {family} family"))?
                    .eigenvector)
            },
            || match &args.chart {
                Some(path) => chart_from_json(path, args.energy, family),
                None => Ok(mode_and_chart::<_, N, S>(
                    &model,
                    family.index(),
                    args.energy,
                    args.chart_degree,
                )
                .with_context(|| format!("{family} eigenmode at {} J", args.energy))?
                .1),
            },
        )?;
        Controller::<_, N, S>::new(model, config, reference)?
    };
    let (mode, _) = mode_and_chart::<_, N, S>(&plant, family.index(), e_final, 9)
        .with_context(|| format!("{family} eigenmode of the plant at {e_final} J"))?;
    let mut adaptation = if args.adapt {
        let options = AdaptOptions {
            // Wait for each new model: the same numbers on every machine.
            synchronous: true,
            family_energy_max: args.family_energy_max.unwrap_or(0.0),
            ..AdaptOptions::default()
        };
        Some(
            Adaptation::<N, S, NP>::new(controller.system().params(), options)
                .context("--adapt")?,
        )
    } else {
        None
    };
    let mut adapted: Vec<AdaptationSample<NP>> = vec![];
    let z0 = SVector::<f64, S>::from_column_slice(&x0);
    let mut next = 0;
    let mut noise = GaussianNoise::new(args.seed);
    // Before the first sample the plant rested at z0.
    let mut history: std::collections::VecDeque<SVector<f64, S>> =
        std::iter::repeat_n(z0, args.delay_samples).collect();
    let dt = config.dt;
    let trace = run_measured_with(
        &mut controller,
        &plant,
        &z0,
        args.duration,
        |t, c| {
            while next < schedule.len() && schedule[next].0 <= t + 1e-9 {
                // Validated above: finite and > 0.
                let _ = c.set_e_ref(schedule[next].1);
                next += 1;
            }
        },
        |_, z| {
            history.push_back(*z);
            let seen = history.pop_front().unwrap_or(*z);
            let speed_noise = args.speed_noise.unwrap_or(args.noise);
            if args.noise > 0.0 || speed_noise > 0.0 {
                noise.measure(&seen, args.noise, speed_noise)
            } else {
                seen
            }
        },
        |_, c, measured| {
            let Some(a) = adaptation.as_mut() else {
                return;
            };
            // As the FMU and the robustness runs feed it: the measured
            // state (not the EKF's estimate, which leans towards the model
            // being corrected) and the torque that acted over the sample
            // before the measurement.
            let q = Vector::<N>::from_fn(|j, _| measured[j]);
            let qd = Vector::<N>::from_fn(|j, _| measured[N + j]);
            let felt = c.torque_before_measurement();
            a.sample(c, &q, &qd, &felt, dt);
            adapted.push(AdaptationSample {
                estimate: a.identification().estimate().theta,
                in_use: a.in_use().theta,
                status: a.status(),
                model_updates: a.model_updates(),
                refusals: a.refusals(),
                reverts: a.reverts(),
            });
        },
    )?;
    let summary = summarise(&trace, e_final, Some(&mode.path), 5.0);
    let setup = plant_robot.as_ref().map(|p| {
        format!(
            "plant {}, controller's model {}",
            robot_name(p),
            robot_name(&robot)
        )
    });
    print_summary(args, variant, family, &x0, setup.as_deref(), &summary);
    let (mean, rms) = energy_tail(&trace, e_final, 5.0);
    let window = window_label(summary.window);
    println!(
        "energy, {window}:{:pad$}mean {mean:.4} J ({:+.2} %), RMS error {rms:.4} J",
        "",
        100.0 * (mean - e_final) / e_final,
        pad = 23usize.saturating_sub(window.len()).max(1)
    );
    if plant.params().has_friction() {
        let f = rms_friction_torque(&trace, &plant, 5.0);
        let t = summary.rms_torque;
        let per_joint = |v: &dyn Fn(usize) -> f64, digits: usize| {
            (0..N)
                .map(|j| format!("{:.digits$}", v(j)))
                .collect::<Vec<_>>()
                .join(" / ")
        };
        println!(
            "RMS friction torque along the final orbit, {window}: {} N m (torque / friction: {}, combined {:.2})",
            per_joint(&|j| f[j], 4),
            per_joint(&|j| t[j] / f[j], 2),
            t.norm() / f.norm()
        );
        println!(
            "prediction model:               {} RK4 substeps, {}",
            config.substeps,
            FrictionSmoothing::new(system.params().coulomb_sharpness, sharpness).describe()
        );
    }
    // The plant's base parameters (None with joint springs: its energy is
    // not linear in them) and the model's before any adaptation.
    let truth = BaseParameters::<N, NP>::of(plant.params())
        .ok()
        .map(|b| b.theta);
    let names = base_parameter_names::<N>();
    if args.adapt {
        let start = BaseParameters::<N, NP>::of(system.params())
            .context("--adapt")?
            .theta;
        print!(
            "{}",
            adaptation::summary_text::<N, NP>(
                &names,
                &adapted,
                &start,
                truth.as_ref(),
                system.params().joints[0].gear_ratio
            )
        );
        let gears = |p: &PlanarChain<N>| p.params().joints.map(|j| j.gear_ratio);
        if gears(&plant) != gears(&system) {
            println!(
                "  (the plant's gear ratios differ from the model's, which the identification \
                 takes as known: its rotor inertias Ir are not comparable)"
            );
        }
    }
    if let Some(path) = &args.csv {
        let columns = if args.adapt {
            adaptation::csv_columns(&names)
        } else {
            vec![]
        };
        write_csv_with(path, &trace, &columns, |i| {
            adapted.get(i).map_or(vec![], adaptation::csv_cells)
        })
        .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &args.plot {
        let info = PlotInfo {
            caption: format!(
                "{variant} EigenMPC, {family}, E_ref = {} J, x0 = ({}), |\u{3c4}| \u{2264} {} N m, N = {}, dt = {} s",
                number(e_final),
                x0.iter().map(|v| number(*v)).collect::<Vec<_>>().join(", "),
                number(args.tau_max),
                args.horizon,
                number(args.dt)
            ),
            tau_max: Some(args.tau_max),
        };
        plot_run(path, &trace, &mode.path, e_final, &info)
            .with_context(|| format!("plotting {}", path.display()))?;
    }
    if let Some(path) = &adapt_plot {
        let caption = format!(
            "online adaptation, {variant} EigenMPC, E_ref = {} J: plant {}, model {}",
            number(e_final),
            robot_name(plant_robot.as_ref().unwrap_or(&robot)),
            robot_name(&robot)
        );
        let times: Vec<f64> = trace.iter().map(|s| s.time).collect();
        adaptation::plot_adaptation(path, &caption, &names, &times, &adapted, truth.as_ref())
            .with_context(|| format!("plotting {}", path.display()))?;
    }
    Ok(())
}

fn print_summary<const N: usize>(
    args: &SimulateArgs,
    variant: Variant,
    family: Family,
    x0: &[f64],
    setup: Option<&str>,
    s: &Summary<N>,
) {
    println!(
        "{variant} EigenMPC, {family}, E_ref = {} J, x0 = {}, {} s, N = {}, dt = {} s, QP {}",
        args.energy,
        x0.iter().map(|v| number(*v)).collect::<Vec<_>>().join(","),
        args.duration,
        args.horizon,
        args.dt,
        args.qp.trim().to_ascii_lowercase()
    );
    if let Some(setup) = setup {
        println!("{setup}");
    }
    print!("{}", summary_text(s));
}
