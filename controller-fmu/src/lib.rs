//! # EigenMPC FMU
//!
//! The EigenMPC controller (paper, section IV; `eigenmpc::mpc::Controller`)
//! for the double pendulum as an FMI 2.0 Co-Simulation FMU, plus a plain C
//! API ([`capi`]) for embedding the controller without FMI. Both are in the
//! same shared library (`libeigenmpc_fmu.so`, packaged as `EigenMPC.so`).
//!
//! Timing: the controller solves at the communication points that fall on
//! its sample grid `t_start + k * sample_period` (or, when a grid point falls
//! inside a communication step, at the first communication point after it).
//! A solve at `t` uses the inputs set for `t` (before `fmi2DoStep(t, h)`, or
//! in initialization mode for `t_start`); its torque is the output once that
//! call returns (`fmi2ExitInitializationMode` for the first solve) and is
//! held until the next solve. A master that steps the controller before the
//! plant thus applies the torque computed from the state at `t` over
//! `[t, t + h]`, like the native closed loop.

pub mod capi;
pub mod settings;

use eigenmpc::mechanics::PlanarChainParams;
use eigenmpc::modes::fmu_chart_coef_name;
use eigenmpc::mpc::{ControlOutput, MpcConfig, QpBackend, Variant};
use fmi2_slave::{
    Context, DefaultExperiment, EnumerationType, Model, ModelDescription, ModelError, Unit, Value,
    Values, Variable,
};
use nalgebra::SVector;
use settings::{
    CHART_COEFFICIENTS, DEFAULT_CHART_14J, DEFAULT_EIGENVECTOR, PendulumController, Settings,
    Tuning,
};

/// Value reference of input `q[1]` (rad).
pub const VR_Q1: u32 = 0;
/// Value reference of input `q[2]` (rad).
pub const VR_Q2: u32 = 1;
/// Value reference of input `qd[1]` (rad/s).
pub const VR_QD1: u32 = 2;
/// Value reference of input `qd[2]` (rad/s).
pub const VR_QD2: u32 = 3;
/// Value reference of output `tau[1]` (N.m).
pub const VR_TAU1: u32 = 4;
/// Value reference of output `tau[2]` (N.m).
pub const VR_TAU2: u32 = 5;
/// Value reference of output `energy` (J).
pub const VR_ENERGY: u32 = 6;
/// Value reference of output `solve_time` (s).
pub const VR_SOLVE_TIME: u32 = 7;
/// Value reference of tunable parameter `E_ref` (J).
pub const VR_E_REF: u32 = 8;
/// Value reference of tunable parameter `alpha` (1/J).
pub const VR_ALPHA: u32 = 9;
/// Value reference of tunable parameter `beta`.
pub const VR_BETA: u32 = 10;
/// Value reference of tunable parameter `w_E`.
pub const VR_W_E: u32 = 11;
/// Value reference of tunable parameter `w_x`.
pub const VR_W_X: u32 = 12;
/// Value reference of tunable parameter `w_xd`.
pub const VR_W_XD: u32 = 13;
/// Value reference of tunable parameter `w_F`.
pub const VR_W_F: u32 = 14;
/// Value reference of parameter `tau_max` (N.m).
pub const VR_TAU_MAX: u32 = 15;
/// Value reference of parameter `sample_period` (s).
pub const VR_SAMPLE_PERIOD: u32 = 16;
/// Value reference of parameter `m[1]` (kg).
pub const VR_M1: u32 = 17;
/// Value reference of parameter `m[2]` (kg).
pub const VR_M2: u32 = 18;
/// Value reference of parameter `l[1]` (m).
pub const VR_L1: u32 = 19;
/// Value reference of parameter `l[2]` (m).
pub const VR_L2: u32 = 20;
/// Value reference of parameter `g` (m/s2).
pub const VR_G: u32 = 21;
/// Value reference of parameter `c[1]` (eigenvector).
pub const VR_C1: u32 = 22;
/// Value reference of parameter `c[2]` (eigenvector).
pub const VR_C2: u32 = 23;
/// Value reference of `chart.coef[1,0]`; `chart.coef[j,k]` has
/// `VR_CHART_COEF + 10 (j - 1) + k`.
pub const VR_CHART_COEF: u32 = 100;
/// Integer value reference of output `qp_iterations`.
pub const VR_QP_ITERATIONS: u32 = 0;
/// Integer value reference of output `solver_status` (`STATUS_*`).
pub const VR_SOLVER_STATUS: u32 = 1;
/// Integer value reference of parameter `variant` (`VARIANT_*`).
pub const VR_VARIANT: u32 = 2;
/// Integer value reference of parameter `horizon`.
pub const VR_HORIZON: u32 = 3;
/// Integer value reference of parameter `qp_solver` (`QP_SOLVER_*`).
pub const VR_QP_SOLVER: u32 = 4;

/// `qp_solver`: clarabel, the general-purpose interior-point reference.
pub const QP_SOLVER_CLARABEL: i32 = 1;
/// `qp_solver`: the structure-exploiting Riccati interior point (default).
pub const QP_SOLVER_RICCATI: i32 = 2;

/// The `qp_solver` item of a backend.
pub fn qp_solver_item(backend: QpBackend) -> i32 {
    match backend {
        QpBackend::Clarabel => QP_SOLVER_CLARABEL,
        QpBackend::Riccati => QP_SOLVER_RICCATI,
    }
}

/// The variant of a `variant` item (FMU parameter and C API).
pub fn variant_from_item(item: i32) -> Result<Variant, String> {
    match item {
        VARIANT_STRAIGHT => Ok(Variant::Straight),
        VARIANT_CURVED => Ok(Variant::Curved),
        v => Err(format!(
            "variant = {v} is not an item of Variant (1 straight, 2 curved)"
        )),
    }
}

/// The backend of a `qp_solver` item.
pub fn qp_backend(item: i32) -> Result<QpBackend, String> {
    match item {
        QP_SOLVER_CLARABEL => Ok(QpBackend::Clarabel),
        QP_SOLVER_RICCATI => Ok(QpBackend::Riccati),
        v => Err(format!(
            "qp_solver = {v} is not an item of QpSolver (1 clarabel, 2 riccati)"
        )),
    }
}

/// `variant`: straight EigenMPC (distance to the linear eigenvector).
pub const VARIANT_STRAIGHT: i32 = 1;
/// `variant`: curved EigenMPC (distance to the eigenmode chart).
pub const VARIANT_CURVED: i32 = 2;

/// `solver_status` codes (equal to `eigenmpc::mpc::ControlStatus::code`):
/// the QP(s) were solved; the torque is optimal.
pub const STATUS_SOLVED: i32 = 0;
/// `solver_status`: the converged SQP of the first sample hit its iteration
/// limit; the torque is from the last iterate.
pub const STATUS_NOT_CONVERGED: i32 = 1;
/// `solver_status`: a QP failed; the torque is the fallback (the shifted
/// previous plan's control, clipped; zero without a plan).
pub const STATUS_QP_FAILED: i32 = 2;
/// `solver_status`: the state was NaN/Inf; the torque is the fallback.
/// C API only: the FMU refuses NaN/Inf inputs with `fmi2Error` before a solve.
pub const STATUS_INVALID_STATE: i32 = 3;
/// C API only: a null pointer or otherwise invalid argument; nothing was computed.
pub const STATUS_BAD_ARGUMENT: i32 = -1;

/// Value reference of `chart.coef[j,k]` (`j` = 1, 2; `k` = 0..=9).
pub fn chart_coef_vr(j: usize, k: usize) -> u32 {
    VR_CHART_COEF + (CHART_COEFFICIENTS * (j - 1) + k) as u32
}

/// Relative tolerance (in sample periods) for a communication point to count
/// as a grid point: absorbs the rounding of a master summing its steps.
const GRID_TOLERANCE: f64 = 1e-6;

/// Introduction of the FMU's documentation page.
pub const DOCUMENTATION_HTML: &str = "<p>The EigenMPC controller (Coelho et al., section IV) \
for the planar double pendulum: a multiple-shooting NMPC solved by real-time iterations that \
pumps energy into the pendulum until it oscillates along its nonlinear eigenmode at the \
reference energy <code>E_ref</code>, then lets it swing almost torque-free. Inputs are the \
measured joint angles <code>q[j]</code> and speeds <code>qd[j]</code>; outputs the joint \
torques <code>tau[j]</code> and diagnostics.</p>\
<p><b>Timing.</b> The controller solves at the communication points on its sample grid \
<code>t_start + k sample_period</code> (or at the first communication point after a grid \
point that falls inside a step) and holds the torque in between. A solve at <code>t</code> \
uses the inputs set for <code>t</code>: in initialization mode for the first solve (the \
outputs are valid after <code>fmi2ExitInitializationMode</code>), afterwards the inputs set \
before <code>fmi2DoStep(t, h)</code>; its torque is the output when that call returns. \
Stepping the controller before the plant therefore applies the torque computed from the \
state at <code>t</code> over <code>[t, t + h]</code>. A communication step longer than the \
sample period gets one solve per step and a warning (once).</p>\
<p><b>Variants.</b> <code>variant</code> = curved needs the chart <code>chart.coef[j,k]</code> \
of the eigenmode at <code>E_ref</code> (default: the 14 J in-phase mode of the default model); \
compute other charts with <code>eigenmpc modes --energies E --fmu-start-values FILE</code> \
and load FILE as start values. A negative <code>w_E</code> (the default) selects the paper's \
energy weight of the variant: 25 curved, 5 straight.</p>\
<p><b>solver_status.</b> 0 solved; 1 first-sample SQP not converged (torque from the last \
iterate); 2 QP failed: the torque is the fallback (the previous plan's next control, clipped) \
and a warning is logged. Code 3 (invalid state) belongs to the C API: this FMU refuses NaN/Inf \
inputs with fmi2Error before any solve.</p>\
<p><b>Refused values.</b> A value out of range (or NaN/Inf) is refused with fmi2Error; the old \
value stays in place and readable, and the instance is in the FMI error state: call \
fmi2Reset to continue.</p>";

fn units() -> Vec<Unit> {
    vec![
        Unit::new("rad", 0, 0, 0, 1),
        Unit::new("rad/s", 0, 0, -1, 1),
        Unit::new("N.m", 1, 2, -2, 0),
        Unit::new("J", 1, 2, -2, 0),
        Unit::new("1/J", -1, -2, 2, 0),
        Unit::new("s", 0, 0, 1, 0),
        Unit::new("kg", 1, 0, 0, 0),
        Unit::new("m", 0, 1, 0, 0),
        Unit::new("m/s2", 0, 1, -2, 0),
    ]
}

/// The EigenMPC controller FMU model.
pub struct EigenMpcFmu {
    controller: PendulumController,
    variant: Variant,
    sample_period: f64,
    start_time: f64,
    /// Index of the next grid point to solve at.
    next_sample: i64,
    /// State of the last solve (a changed state at `t_start` re-solves).
    solved_state: SVector<f64, 4>,
    warned_long_step: bool,
    warned_off_grid: bool,
}

fn inputs(values: &Values) -> SVector<f64, 4> {
    SVector::<f64, 4>::new(
        values.real(VR_Q1),
        values.real(VR_Q2),
        values.real(VR_QD1),
        values.real(VR_QD2),
    )
}

fn tuning(values: &Values) -> Tuning {
    Tuning {
        e_ref: values.real(VR_E_REF),
        alpha: values.real(VR_ALPHA),
        beta: values.real(VR_BETA),
        w_e: values.real(VR_W_E),
        w_x: values.real(VR_W_X),
        w_xd: values.real(VR_W_XD),
        w_f: values.real(VR_W_F),
    }
}

/// The controller settings held in the FMU's parameters.
fn settings(values: &Values) -> Result<Settings, String> {
    let variant = variant_from_item(values.integer(VR_VARIANT))?;
    let mut chart = [[0.0; CHART_COEFFICIENTS]; 2];
    for (j, row) in chart.iter_mut().enumerate() {
        for (k, a) in row.iter_mut().enumerate() {
            *a = values.real(chart_coef_vr(j + 1, k));
        }
    }
    Ok(Settings {
        variant,
        qp: qp_backend(values.integer(VR_QP_SOLVER))?,
        tuning: tuning(values),
        tau_max: values.real(VR_TAU_MAX),
        horizon: values.integer(VR_HORIZON) as usize,
        sample_period: values.real(VR_SAMPLE_PERIOD),
        model: PlanarChainParams::point_masses(
            [values.real(VR_M1), values.real(VR_M2)],
            [values.real(VR_L1), values.real(VR_L2)],
            values.real(VR_G),
        ),
        eigenvector: [values.real(VR_C1), values.real(VR_C2)],
        chart,
    })
}

impl Model for EigenMpcFmu {
    fn description() -> ModelDescription {
        let curved = MpcConfig::paper(Variant::Curved);
        let model = PlanarChainParams::<2>::default();
        let tuning = Tuning::paper();
        let r = Value::Real;
        let mut variables = vec![];
        let state = [
            (
                VR_Q1,
                "q[1]",
                "rad",
                "Measured angle of link 1 from the downward vertical",
            ),
            (
                VR_Q2,
                "q[2]",
                "rad",
                "Measured angle of link 2 relative to link 1",
            ),
            (VR_QD1, "qd[1]", "rad/s", "Measured speed of joint 1"),
            (VR_QD2, "qd[2]", "rad/s", "Measured speed of joint 2"),
        ];
        for (vr, name, unit, what) in state {
            variables.push(
                Variable::real(name, vr)
                    .input(r(0.0))
                    .unit(unit)
                    .describe(format!(
                        "{what}; a solve uses the value set for its communication point"
                    )),
            );
        }
        // Outputs: no direct feedthrough in step mode (a solve happens inside
        // fmi2DoStep with the inputs of the step's start; inputs set after it
        // do not change the outputs). At initialization they follow from the
        // inputs and all parameters (dependencies omitted: all knowns).
        for (j, vr) in [(1, VR_TAU1), (2, VR_TAU2)] {
            variables.push(
                Variable::real(format!("tau[{j}]"), vr)
                    .output()
                    .variability(fmi2_slave::Variability::Discrete)
                    .unit("N.m")
                    .describe(format!(
                        "Torque at joint {j} from the last solve, held until the next one"
                    ))
                    .depends_on(&[]),
            );
        }
        variables.push(
            Variable::real("energy", VR_ENERGY)
                .output()
                .variability(fmi2_slave::Variability::Discrete)
                .unit("J")
                .describe("Energy of the state the last solve used (controller's model)")
                .depends_on(&[])
                .initially_depends_on(&[
                    "q[1]", "q[2]", "qd[1]", "qd[2]", "m[1]", "m[2]", "l[1]", "l[2]", "g",
                ]),
        );
        variables.push(
            Variable::real("solve_time", VR_SOLVE_TIME)
                .output()
                .variability(fmi2_slave::Variability::Discrete)
                .unit("s")
                .describe("Wall-clock time of the last solve (preparation + feedback)")
                .depends_on(&[]),
        );
        variables.push(
            Variable::integer("qp_iterations", VR_QP_ITERATIONS)
                .output()
                .describe("Interior-point iterations of the last solve's QP(s)")
                .depends_on(&[]),
        );
        variables.push(
            Variable::integer("solver_status", VR_SOLVER_STATUS)
                .output()
                .describe(
                    "Status of the last solve: 0 solved; 1 first-sample SQP not converged \
                     (torque from the last iterate); 2 QP failed (torque = fallback: previous \
                     plan's next control, clipped). 3 (invalid state) only occurs through the \
                     C API: the FMU refuses NaN/Inf inputs with fmi2Error",
                )
                .depends_on(&[]),
        );
        variables.push(
            Variable::enumeration("variant", VR_VARIANT, "Variant")
                .parameter(Value::Integer(VARIANT_CURVED))
                .min(VARIANT_STRAIGHT as f64)
                .max(VARIANT_CURVED as f64)
                .describe("EigenMPC cost: straight (eigenvector line) or curved (eigenmode chart)"),
        );
        let tunables = [
            (
                VR_E_REF,
                "E_ref",
                Some("J"),
                tuning.e_ref,
                0.0,
                1e4,
                "Reference energy",
            ),
            (
                VR_ALPHA,
                "alpha",
                Some("1/J"),
                tuning.alpha,
                0.0,
                1e3,
                "Exploration gain of the straight cost (blend tanh(alpha E))",
            ),
            (
                VR_BETA,
                "beta",
                None,
                tuning.beta,
                0.0,
                1e3,
                "Torque-weight offset of the straight cost",
            ),
            (
                VR_W_E,
                "w_E",
                None,
                tuning.w_e,
                -1.0,
                1e8,
                "Energy weight; negative: the paper's value of the variant (25 curved, 5 straight)",
            ),
            (
                VR_W_X,
                "w_x",
                None,
                tuning.w_x,
                0.0,
                1e8,
                "Position-distance weight",
            ),
            (
                VR_W_XD,
                "w_xd",
                None,
                tuning.w_xd,
                0.0,
                1e8,
                "Velocity-distance weight",
            ),
            (
                VR_W_F,
                "w_F",
                None,
                tuning.w_f,
                1e-9,
                1e8,
                "Torque weight (> 0)",
            ),
        ];
        for (vr, name, unit, start, min, max, what) in tunables {
            let mut v = Variable::real(name, vr)
                .tunable(r(start))
                .min(min)
                .max(max)
                .describe(format!("{what}; tunable between steps"));
            if let Some(u) = unit {
                v = v.unit(u);
            }
            variables.push(v);
        }
        variables.push(
            Variable::real("tau_max", VR_TAU_MAX)
                .parameter(r(curved.tau_max))
                .unit("N.m")
                .min(1e-6)
                .max(1e6)
                .describe("Torque bound |tau[j]| <= tau_max"),
        );
        variables.push(
            Variable::integer("horizon", VR_HORIZON)
                .parameter(Value::Integer(curved.horizon as i32))
                .min(1.0)
                .max(eigenmpc::mpc::MAX_HORIZON as f64)
                .describe("Shooting intervals N of the prediction horizon"),
        );
        variables.push(
            Variable::real("sample_period", VR_SAMPLE_PERIOD)
                .parameter(r(curved.dt))
                .unit("s")
                .min(1e-4)
                .max(10.0)
                .describe("Sample period and shooting interval dt"),
        );
        for (j, vr) in [(1, VR_M1), (2, VR_M2)] {
            variables.push(
                Variable::real(format!("m[{j}]"), vr)
                    .parameter(r(model.links[j - 1].mass))
                    .unit("kg")
                    .min(1e-6)
                    .max(1e6)
                    .describe(format!(
                        "Controller model: point mass at the tip of link {j}"
                    )),
            );
        }
        for (j, vr) in [(1, VR_L1), (2, VR_L2)] {
            variables.push(
                Variable::real(format!("l[{j}]"), vr)
                    .parameter(r(model.links[j - 1].length))
                    .unit("m")
                    .min(1e-6)
                    .max(1e3)
                    .describe(format!("Controller model: length of link {j}")),
            );
        }
        variables.push(
            Variable::real("g", VR_G)
                .parameter(r(model.gravity))
                .unit("m/s2")
                .min(1e-6)
                .max(1e3)
                .describe("Controller model: gravitational acceleration"),
        );
        for (j, vr) in [(1, VR_C1), (2, VR_C2)] {
            variables.push(
                Variable::real(format!("c[{j}]"), vr)
                    .parameter(r(DEFAULT_EIGENVECTOR[j - 1]))
                    .min(-1.0)
                    .max(1.0)
                    .describe(format!(
                        "Linear eigenvector c, component {j} (normalised; default: in-phase \
                         mode of the default model); chart coordinate s = c'q"
                    )),
            );
        }
        for (j, row) in (1..).zip(DEFAULT_CHART_14J.iter()) {
            for (k, &a) in row.iter().enumerate() {
                // X_j and s are angles (rad): the coefficient of s^k has unit
                // rad^(1-k), which has no name; left without a unit.
                variables.push(
                    Variable::real(fmu_chart_coef_name(j, k), chart_coef_vr(j, k))
                        .parameter(r(a))
                        .describe(format!(
                            "Chart X_{j}(s) = sum_k chart.coef[{j},k] s^k (rad, s = c'q in rad), \
                             coefficient of s^{k} (curved; default: 14 J in-phase mode of the \
                             default model)"
                        )),
                );
            }
        }
        variables.push(
            Variable::enumeration("qp_solver", VR_QP_SOLVER, "QpSolver")
                .parameter(Value::Integer(qp_solver_item(QpBackend::default())))
                .min(QP_SOLVER_CLARABEL as f64)
                .max(QP_SOLVER_RICCATI as f64)
                .describe("QP solver of the real-time iteration: riccati (structure-exploiting) or clarabel"),
        );
        ModelDescription {
            model_name: "EigenMPC".into(),
            model_identifier: "EigenMPC".into(),
            description: "EigenMPC controller for the double pendulum: joint angles and speeds \
                          in, joint torques out; excites the nonlinear eigenmode at E_ref"
                .into(),
            version: env!("CARGO_PKG_VERSION").into(),
            author: "EigenMPC project".into(),
            generation_tool: format!("fmi2-slave (EigenMPC) {}", env!("CARGO_PKG_VERSION")),
            can_handle_variable_communication_step_size: true,
            default_experiment: Some(DefaultExperiment {
                start_time: 0.0,
                stop_time: 30.0,
                step_size: curved.dt,
            }),
            units: units(),
            enumerations: vec![
                EnumerationType {
                    name: "Variant".into(),
                    items: vec![
                        (
                            "straight".into(),
                            VARIANT_STRAIGHT,
                            "Distance to the linear eigenvector line".into(),
                        ),
                        (
                            "curved".into(),
                            VARIANT_CURVED,
                            "Distance to the eigenmode chart X(s)".into(),
                        ),
                    ],
                },
                EnumerationType {
                    name: "QpSolver".into(),
                    items: vec![
                        (
                            "clarabel".into(),
                            QP_SOLVER_CLARABEL,
                            "clarabel: general-purpose interior point (reference)".into(),
                        ),
                        (
                            "riccati".into(),
                            QP_SOLVER_RICCATI,
                            "Riccati-recursion interior point exploiting the stage structure"
                                .into(),
                        ),
                    ],
                },
            ],
            variables,
        }
    }

    fn initialize(values: &mut Values, ctx: &Context) -> Result<Self, ModelError> {
        let settings = settings(values).map_err(ModelError::Error)?;
        let controller = settings.build().map_err(ModelError::Error)?;
        let mut model = Self {
            controller,
            variant: settings.variant,
            sample_period: settings.sample_period,
            start_time: ctx.experiment.start_time,
            next_sample: 1,
            solved_state: SVector::zeros(),
            warned_long_step: false,
            warned_off_grid: false,
        };
        model.solve(values, ctx.experiment.start_time, ctx);
        Ok(model)
    }

    fn do_step(
        &mut self,
        values: &mut Values,
        t: f64,
        h: f64,
        ctx: &Context,
    ) -> Result<(), ModelError> {
        let dt = self.sample_period;
        if h > dt * (1.0 + GRID_TOLERANCE) && !self.warned_long_step {
            self.warned_long_step = true;
            ctx.log.warning(&format!(
                "communication step {h} s is longer than the sample period {dt} s: one solve \
                 per step (the prediction still assumes {dt} s intervals)"
            ));
        }
        let samples = (t - self.start_time) / dt;
        // Last grid point at or before t.
        let reached = (samples + GRID_TOLERANCE).floor() as i64;
        let on_grid = (samples - samples.round()).abs() <= GRID_TOLERANCE;
        if reached >= self.next_sample {
            if !on_grid && !self.warned_off_grid && h <= dt * (1.0 + GRID_TOLERANCE) {
                self.warned_off_grid = true;
                ctx.log.warning(&format!(
                    "communication point t = {t} s is not on the sample grid (start {} s, \
                     period {dt} s): solving at the first communication point after each grid \
                     point",
                    self.start_time
                ));
            }
            self.next_sample = reached + 1;
            self.solve(values, t, ctx);
        } else if reached == 0 && on_grid && inputs(values) != self.solved_state {
            // New inputs for t_start after initialization: solve t_start again.
            self.controller.reset();
            self.solve(values, t, ctx);
        }
        Ok(())
    }

    fn update_tunables(&mut self, values: &mut Values, _ctx: &Context) -> Result<(), ModelError> {
        self.controller
            .set_cost(tuning(values).cost(self.variant))
            .map_err(|e| ModelError::Error(e.to_string()))
    }
}

impl EigenMpcFmu {
    /// One controller sample with the current inputs; writes the outputs.
    fn solve(&mut self, values: &mut Values, t: f64, ctx: &Context) {
        let z = inputs(values);
        let out = self.controller.step(&z);
        self.solved_state = z;
        if !out.status.is_ok() {
            // Failure path only: the message allocates.
            ctx.log.warning(&format!(
                "t = {t} s: {}; tau = ({}, {}) N.m",
                out.status, out.tau[0], out.tau[1]
            ));
        }
        write_outputs(values, &out, self.controller.energy(&z));
    }

    /// The controller (diagnostics and tests).
    pub fn controller(&self) -> &PendulumController {
        &self.controller
    }
}

fn write_outputs(values: &mut Values, out: &ControlOutput<2>, energy: f64) {
    values.set_real(VR_TAU1, out.tau[0]);
    values.set_real(VR_TAU2, out.tau[1]);
    values.set_real(VR_ENERGY, energy);
    values.set_real(VR_SOLVE_TIME, out.preparation_time + out.feedback_time);
    values.set_integer(
        VR_QP_ITERATIONS,
        i32::try_from(out.qp_iterations).unwrap_or(i32::MAX),
    );
    values.set_integer(VR_SOLVER_STATUS, out.status.code());
}

/// The 34 FMI 2.0 functions of this FMU.
pub mod fmi2_exports {
    fmi2_slave::export_fmi2!(crate::EigenMpcFmu);
}
