//! Closed-loop simulation of the controller against the accurate plant
//! (adaptive Dormand-Prince, torque held over each sample) and the summary
//! figures of the paper's scenarios.

use super::{ControlOutput, ControlStatus, Controller};
use crate::integrate::{Dopri5, IntegrationError, Tolerances};
use crate::mechanics::{MechanicalSystem, Vector, state_derivative, state_energy};
use nalgebra::SVector;

/// One sample of a closed-loop run (state at the sample time, torque applied after it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample<const N: usize, const NX: usize> {
    /// Time (s).
    pub time: f64,
    /// Measured state `z = (q, qd)`.
    pub state: SVector<f64, NX>,
    /// Torque applied over the following sample.
    pub tau: Vector<N>,
    /// Plant energy (J).
    pub energy: f64,
    /// Controller compute time, preparation + feedback (s).
    pub solve_time: f64,
    /// Preparation part of `solve_time` (s).
    pub preparation_time: f64,
    /// Controller status.
    pub status: ControlStatus,
    /// QP iterations in this sample.
    pub qp_iterations: usize,
}

/// Runs `duration` seconds of closed loop from `z0`; the plant is `plant`
/// (which may differ from the controller's model).
pub fn run<S, P, const N: usize, const NX: usize>(
    controller: &mut Controller<S, N, NX>,
    plant: &P,
    z0: &SVector<f64, NX>,
    duration: f64,
) -> Result<Vec<Sample<N, NX>>, IntegrationError>
where
    S: MechanicalSystem<N>,
    P: MechanicalSystem<N>,
{
    run_with(controller, plant, z0, duration, |_, _, _| {})
}

/// [`run`], calling `on_sample(i, controller, output)` right after the
/// controller's step at sample `i` (e.g. to inspect or record its QP).
pub fn run_with<S, P, const N: usize, const NX: usize>(
    controller: &mut Controller<S, N, NX>,
    plant: &P,
    z0: &SVector<f64, NX>,
    duration: f64,
    mut on_sample: impl FnMut(usize, &Controller<S, N, NX>, &ControlOutput<N>),
) -> Result<Vec<Sample<N, NX>>, IntegrationError>
where
    S: MechanicalSystem<N>,
    P: MechanicalSystem<N>,
{
    run_inner(
        controller,
        plant,
        z0,
        duration,
        |_, _| {},
        |i, c, _, out| on_sample(i, &*c, out),
        |_, z| *z,
    )
}

/// [`run_tuned`] with a measurement: the controller gets `measure(t, z)`
/// instead of the plant's state `z` (noise, delay, ...); the samples record
/// the true state and energy.
pub fn run_measured<S, P, const N: usize, const NX: usize>(
    controller: &mut Controller<S, N, NX>,
    plant: &P,
    z0: &SVector<f64, NX>,
    duration: f64,
    tune: impl FnMut(f64, &mut Controller<S, N, NX>),
    measure: impl FnMut(f64, &SVector<f64, NX>) -> SVector<f64, NX>,
) -> Result<Vec<Sample<N, NX>>, IntegrationError>
where
    S: MechanicalSystem<N>,
    P: MechanicalSystem<N>,
{
    run_inner(
        controller,
        plant,
        z0,
        duration,
        tune,
        |_, _, _, _| {},
        measure,
    )
}

/// [`run_measured`], calling `after_step(t, controller, measured)` right
/// after the controller's step at time `t` with the measurement it was
/// given: the place to feed an online adaptation
/// ([`crate::adapt::Adaptation::sample`]), whose new model then serves from
/// the next sample on, as in a real loop.
pub fn run_measured_with<S, P, const N: usize, const NX: usize>(
    controller: &mut Controller<S, N, NX>,
    plant: &P,
    z0: &SVector<f64, NX>,
    duration: f64,
    tune: impl FnMut(f64, &mut Controller<S, N, NX>),
    measure: impl FnMut(f64, &SVector<f64, NX>) -> SVector<f64, NX>,
    mut after_step: impl FnMut(f64, &mut Controller<S, N, NX>, &SVector<f64, NX>),
) -> Result<Vec<Sample<N, NX>>, IntegrationError>
where
    S: MechanicalSystem<N>,
    P: MechanicalSystem<N>,
{
    let dt = controller.config().dt;
    run_inner(
        controller,
        plant,
        z0,
        duration,
        tune,
        |i, c, measured, _| after_step(i as f64 * dt, c, measured),
        measure,
    )
}

/// [`run`], calling `tune(t, controller)` right before the controller's
/// step at time `t` (e.g. a tuned `E_ref`, as a master sets a tunable
/// parameter between communication steps).
pub fn run_tuned<S, P, const N: usize, const NX: usize>(
    controller: &mut Controller<S, N, NX>,
    plant: &P,
    z0: &SVector<f64, NX>,
    duration: f64,
    tune: impl FnMut(f64, &mut Controller<S, N, NX>),
) -> Result<Vec<Sample<N, NX>>, IntegrationError>
where
    S: MechanicalSystem<N>,
    P: MechanicalSystem<N>,
{
    run_inner(
        controller,
        plant,
        z0,
        duration,
        tune,
        |_, _, _, _| {},
        |_, z| *z,
    )
}

fn run_inner<S, P, const N: usize, const NX: usize>(
    controller: &mut Controller<S, N, NX>,
    plant: &P,
    z0: &SVector<f64, NX>,
    duration: f64,
    mut tune: impl FnMut(f64, &mut Controller<S, N, NX>),
    mut on_sample: impl FnMut(usize, &mut Controller<S, N, NX>, &SVector<f64, NX>, &ControlOutput<N>),
    mut measure: impl FnMut(f64, &SVector<f64, NX>) -> SVector<f64, NX>,
) -> Result<Vec<Sample<N, NX>>, IntegrationError>
where
    S: MechanicalSystem<N>,
    P: MechanicalSystem<N>,
{
    let dt = controller.config().dt;
    let steps = (duration / dt).round() as usize;
    let mut trace = Vec::with_capacity(steps + 1);
    let tol = Tolerances {
        rtol: 1e-10,
        atol: 1e-10,
    };
    let mut ode = Dopri5::new(0.0, *z0, tol);
    for i in 0..=steps {
        let t = i as f64 * dt;
        let z = *ode.state();
        tune(t, controller);
        let measured = measure(t, &z);
        let out = controller.step(&measured);
        on_sample(i, controller, &measured, &out);
        trace.push(Sample {
            time: t,
            state: z,
            tau: out.tau,
            energy: state_energy::<P, N, NX>(plant, &z),
            solve_time: out.preparation_time + out.feedback_time,
            preparation_time: out.preparation_time,
            status: out.status,
            qp_iterations: out.qp_iterations,
        });
        if i == steps {
            break;
        }
        let tau = out.tau;
        ode.advance_to(
            |_, z| state_derivative::<P, N, NX>(plant, z, &tau),
            (i + 1) as f64 * dt,
        )?;
    }
    Ok(trace)
}

/// The cost reference of `variant` for the family `mode_index` at `energy`:
/// the unit linear eigenvector (straight) or the degree-9 chart of the true
/// eigenmode (curved, hybrid).
pub fn reference_for<S, const N: usize, const NX: usize>(
    system: &S,
    variant: super::Variant,
    mode_index: usize,
    energy: f64,
) -> Result<super::Reference<N>, String>
where
    S: MechanicalSystem<N>,
{
    super::Reference::of(
        variant,
        || {
            crate::modes::linear_modes(system)
                .map_err(|e| e.to_string())?
                .get(mode_index)
                .map(|m| m.eigenvector)
                .ok_or_else(|| {
                    crate::modes::ModeError::NoSuchMode {
                        index: mode_index,
                        dof: N,
                    }
                    .to_string()
                })
        },
        || {
            mode_and_chart::<S, N, NX>(system, mode_index, energy, 9)
                .map(|(_, chart)| chart)
                .map_err(|e| e.to_string())
        },
    )
}

pub use crate::noise::GaussianNoise;

/// Summary figures of a run (issue 3 / paper section V).
#[derive(Clone, Debug, PartialEq)]
pub struct Summary<const N: usize> {
    /// First time after which `|E - E_ref| < 5 % E_ref` holds for good (None: never).
    pub time_to_5_percent: Option<f64>,
    /// `E - E_ref` at the end (J).
    pub final_energy_error: f64,
    /// RMS torque per joint over the last `window` seconds (N m).
    pub rms_torque: Vector<N>,
    /// RMS distance of the last `window` seconds of the path to the mode path (rad), if given.
    pub rms_distance: Option<f64>,
    /// Per-sample compute time: median, p95, p99, max (s).
    pub solve_time: [f64; 4],
    /// Samples whose solve failed (a QP, or an invalid state).
    pub failures: usize,
    /// Samples whose torque the stall supervisor released.
    pub released: usize,
    /// Releases (stalls the supervisor called).
    pub stalls: usize,
    /// The window the RMS figures cover (s): the requested one, or the
    /// whole run when it is shorter.
    pub window: f64,
}

/// Quantile of sorted data (nearest rank).
pub fn quantile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let idx = ((p * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1;
    sorted[idx]
}

/// Distance from `q` to the polyline `path`.
pub fn distance_to_path<const N: usize>(q: &Vector<N>, path: &[Vector<N>]) -> f64 {
    let mut best = f64::INFINITY;
    for w in path.windows(2) {
        let d = w[1] - w[0];
        let len2 = d.norm_squared();
        let t = if len2 > 0.0 {
            ((q - w[0]).dot(&d) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        best = best.min((q - (w[0] + d * t)).norm());
    }
    if path.len() == 1 {
        best = (q - path[0]).norm();
    }
    best
}

/// RMS per joint of the friction torque `tau_f(qd)` of `plant` along the
/// last `window` seconds of a run: what holding that orbit against friction
/// takes at least.
pub fn rms_friction_torque<P, const N: usize, const NX: usize>(
    trace: &[Sample<N, NX>],
    plant: &P,
    window: f64,
) -> Vector<N>
where
    P: MechanicalSystem<N>,
{
    let t_end = trace.last().map_or(0.0, |s| s.time);
    let mut sum = Vector::<N>::zeros();
    let mut n = 0usize;
    for s in trace.iter().filter(|s| s.time > t_end - window + 1e-9) {
        let qd = s.state.fixed_rows::<N>(N).into_owned();
        let f = plant.friction(&qd);
        sum += f.component_mul(&f);
        n += 1;
    }
    (sum / n.max(1) as f64).map(f64::sqrt)
}

/// Mean and RMS deviation of the plant energy from `e_ref` over the last
/// `window` seconds (J).
pub fn energy_tail<const N: usize, const NX: usize>(
    trace: &[Sample<N, NX>],
    e_ref: f64,
    window: f64,
) -> (f64, f64) {
    let t_end = trace.last().map_or(0.0, |s| s.time);
    let tail: Vec<f64> = trace
        .iter()
        .filter(|s| s.time > t_end - window + 1e-9)
        .map(|s| s.energy)
        .collect();
    let n = tail.len().max(1) as f64;
    let mean = tail.iter().sum::<f64>() / n;
    let rms = (tail.iter().map(|e| (e - e_ref).powi(2)).sum::<f64>() / n).sqrt();
    (mean, rms)
}

/// Computes the [`Summary`] of a run over its last `window` seconds.
pub fn summarise<const N: usize, const NX: usize>(
    trace: &[Sample<N, NX>],
    e_ref: f64,
    mode_path: Option<&[Vector<N>]>,
    window: f64,
) -> Summary<N> {
    let band = 0.05 * e_ref.abs();
    let last_outside = trace
        .iter()
        .rposition(|s| (s.energy - e_ref).abs() >= band || !s.energy.is_finite());
    let time_to_5_percent = match last_outside {
        None => trace.first().map(|s| s.time),
        Some(i) if i + 1 < trace.len() => Some(trace[i + 1].time),
        Some(_) => None,
    };
    let t_end = trace.last().map_or(0.0, |s| s.time);
    let tail: Vec<&Sample<N, NX>> = trace
        .iter()
        .filter(|s| s.time > t_end - window + 1e-9)
        .collect();
    let n = tail.len().max(1) as f64;
    let mut rms_torque = Vector::<N>::zeros();
    for s in &tail {
        rms_torque += s.tau.component_mul(&s.tau);
    }
    let rms_torque = (rms_torque / n).map(f64::sqrt);
    let rms_distance = mode_path.map(|path| {
        let sum: f64 = tail
            .iter()
            .map(|s| {
                let q = s.state.fixed_rows::<N>(0).into_owned();
                distance_to_path(&q, path).powi(2)
            })
            .sum();
        (sum / n).sqrt()
    });
    let mut times: Vec<f64> = trace.iter().map(|s| s.solve_time).collect();
    times.sort_by(f64::total_cmp);
    Summary {
        time_to_5_percent,
        final_energy_error: trace.last().map_or(f64::NAN, |s| s.energy - e_ref),
        rms_torque,
        rms_distance,
        solve_time: [
            quantile(&times, 0.5),
            quantile(&times, 0.95),
            quantile(&times, 0.99),
            times.last().copied().unwrap_or(f64::NAN),
        ],
        failures: trace
            .iter()
            .filter(|s| !s.status.is_ok() && s.status != ControlStatus::Released)
            .count(),
        released: trace
            .iter()
            .filter(|s| s.status == ControlStatus::Released)
            .count(),
        stalls: trace
            .iter()
            .enumerate()
            .filter(|(i, s)| {
                s.status == ControlStatus::Released
                    && (*i == 0 || trace[i - 1].status != ControlStatus::Released)
            })
            .count(),
        window: window.min(t_end - trace.first().map_or(0.0, |s| s.time)),
    }
}

/// Start angle of every joint (rad), at rest: the paper's scenario (and
/// that of the sweeps, the robustness runs and the shipped SSPs).
pub const START_ANGLE: f64 = 0.05;

/// The true eigenmode of family `mode_index` at `energy` and its chart of
/// the given degree (the paper uses 9): what the curved cost and the
/// distance metric need.
pub fn mode_and_chart<S, const N: usize, const NX: usize>(
    system: &S,
    mode_index: usize,
    energy: f64,
    degree: usize,
) -> Result<(crate::modes::Eigenmode<N>, crate::modes::Chart<N>), crate::modes::ModeError>
where
    S: MechanicalSystem<N>,
{
    use crate::modes::{Chart, ContinuationOptions, eigenmode_family, linear_modes};
    let linear = linear_modes(system)?;
    let eigenvector = linear
        .get(mode_index)
        .ok_or(crate::modes::ModeError::NoSuchMode {
            index: mode_index,
            dof: N,
        })?
        .eigenvector;
    let mode = eigenmode_family::<S, N, NX>(
        system,
        mode_index,
        &[energy],
        &ContinuationOptions::default(),
    )?
    .remove(0);
    let chart = Chart::fit(&mode.path, &eigenvector, &system.equilibrium(), degree)?;
    Ok((mode, chart))
}

/// The controller `eigenmpc simulate --model FILE` builds for a robot: the
/// paper's set-up (in-phase family, `E_ref = energy`, `|tau| <= tau_max`)
/// with the robot's prediction model ([`super::prediction_model`], at most
/// [`super::PREDICTION_SUBSTEPS`] RK4 substeps and the Coulomb slope they
/// take); and the model's eigenmode at `energy` (the distance metric's path).
pub fn robot_controller<const N: usize, const NX: usize>(
    robot: &crate::mechanics::PlanarChain<N>,
    variant: super::Variant,
    energy: f64,
    tau_max: f64,
) -> Result<RobotController<N, NX>, String> {
    robot_controller_with(robot, variant, energy, tau_max, super::PREDICTION_SUBSTEPS)
}

/// A controller of [`robot_controller`] and the eigenmode it follows.
pub type RobotController<const N: usize, const NX: usize> = (
    Controller<crate::mechanics::PlanarChain<N>, N, NX>,
    crate::modes::Eigenmode<N>,
);

/// [`robot_controller`] with at most `most_substeps` RK4 substeps per
/// interval ([`super::prediction_substeps`] of the robot: its exact law).
pub fn robot_controller_with<const N: usize, const NX: usize>(
    robot: &crate::mechanics::PlanarChain<N>,
    variant: super::Variant,
    energy: f64,
    tau_max: f64,
    most_substeps: usize,
) -> Result<RobotController<N, NX>, String> {
    let mut config = super::MpcConfig::paper(variant);
    let (model, substeps, _) = super::prediction_model(robot, config.dt, most_substeps);
    config.substeps = substeps;
    config.tau_max = tau_max;
    config.cost.e_ref = energy;
    let (mode, chart) =
        mode_and_chart::<_, N, NX>(&model, 0, energy, 9).map_err(|e| e.to_string())?;
    let reference = super::Reference::with_chart(variant, chart);
    let controller = Controller::new(model, config, reference).map_err(|e| e.to_string())?;
    Ok((controller, mode))
}
