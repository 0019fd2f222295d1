//! The controller FMU's variable table for `N` joints: the single source of
//! its variables, value references, start values, XML, documentation,
//! table in the book, C constants and start-value files.
//!
//! Value references are laid out by [`fmi2_slave::table::Table::new`]: per
//! base type consecutive in row order, the chart block at 100. For two
//! joints this is the layout of the original `EigenMPC.fmu` (pinned by a
//! test). **Add new rows at the end** (after `qp_solver` and the chain rows)
//! so that existing value references stay; a row is its name, shape, type,
//! role with two accessors into [`Settings`], unit, range and description:
//!
//! ```ignore
//! // enums.rs: pub const CHART_SOURCE: Enumeration<ChartSource> = ...; Settings: a field
//! Rw::<N>::enumeration(CHART_SOURCE.parameter, Shape::Scalar, CHART_SOURCE.fmi_type())
//!     .parameter(Field::integer(
//!         |s, _| CHART_SOURCE.item(s.chart_source),
//!         |s, _, v| s.chart_source = CHART_SOURCE.value(v).unwrap_or(s.chart_source),
//!     ))
//!     .describe("Where the reference comes from"),
//! ```

use super::settings::{CHART_COEFFICIENTS, Settings};
use crate::chain::{point_mass_rows, rigid_rows};
use crate::enums::{
    ADAPT_ESTIMATOR, ADAPTATION_STATUS, CHART_SOURCE, QP_SOLVER, STATE_ESTIMATOR, VARIANT,
};
use fmi2_slave::table::{Deps, Field, Row, Shape, Table};

/// Group tag of the reference rows (`E_ref`, `c[j]`, `chart.coef[j,k]`),
/// written to start-value files with the model rows.
pub const REFERENCE_GROUP: &str = "reference";

/// First value reference of the chart block.
pub const CHART_VR: u32 = 100;

type Rw<const N: usize> = Row<Settings<N>>;

/// A tunable Real parameter of the tuning.
fn tunable<const N: usize>(
    name: &'static str,
    get: fn(&Settings<N>, fmi2_slave::table::Element) -> f64,
    set: fn(&mut Settings<N>, fmi2_slave::table::Element, f64),
    (min, max): (f64, f64),
    what: &str,
) -> Rw<N> {
    Rw::<N>::real(name, Shape::Scalar)
        .tunable(Field::real(get, set))
        .range(min, max)
        .describe(format!("{what}; tunable between steps"))
        .summary(what)
}

/// The variable table of the `N`-joint controller.
pub fn table<const N: usize>() -> Table<Settings<N>> {
    let mut rows = vec![
        Rw::<N>::real("q", Shape::Joints)
            .input(0.0)
            .unit("rad")
            .range(-1e9, 1e9)
            .describe(
                "Measured angle of joint {j} (q[1] from the downward vertical, q[j] of link j \
                 relative to link j-1); a solve uses the value set for its communication point",
            )
            .summary("measured joint angles (as the plant's outputs)"),
        Rw::<N>::real("qd", Shape::Joints)
            .input(0.0)
            .unit("rad/s")
            // Keeps the energy output finite (qd = 1e308 overflowed it).
            .range(-1e6, 1e6)
            .describe(
                "Measured speed of joint {j}; a solve uses the value set for its communication \
                 point",
            )
            .summary("measured joint speeds"),
        Rw::<N>::real("tau", Shape::Joints)
            .discrete_output()
            .unit("N.m")
            .describe("Torque at joint {j} from the last solve, held until the next one")
            .summary("torque of the last solve (within tau_max), held until the next"),
        Rw::<N>::real("energy", Shape::Scalar)
            .discrete_output()
            .unit("J")
            .describe("Energy of the state the last solve used (controller's model)")
            .summary("energy of the state the last solve used")
            .initially_depends_on(Deps::Rows(vec![
                "q", "qd", "m", "l", "g", "r", "I", "Ir", "gr", "k", "q_rest",
            ])),
        Rw::<N>::real("solve_time", Shape::Scalar)
            .discrete_output()
            .unit("s")
            .describe("Wall-clock time of the last solve (preparation + feedback)")
            .summary("wall time of the last solve"),
        Rw::<N>::integer("qp_iterations", Shape::Scalar)
            .output()
            .describe("QP iterations of the last solve (riccati: the active-set start's Riccati recursions when it solved the QP, else interior-point iterations)"),
        Rw::<N>::integer("solver_status", Shape::Scalar)
            .output()
            .describe(
                "Status of the last solve: 0 solved (also the first sample, and the first \
                 after a failed QP reset the plan: ten Gauss-Newton iterations from a \
                 zero-torque guess, bounded work); 1 not converged (reported only by the \
                 converged start-up of the Rust API, which the FMU does not use); 2 QP failed (torque = fallback: previous plan's next \
                 control, clipped; logged as a warning the first time and every 100th). 3 \
                 (invalid state) only occurs through the C API: the FMU refuses NaN/Inf \
                 inputs with fmi2Error. 4 released: the stall supervisor set the torque to \
                 zero (see supervisor)",
            )
            .summary(
                "0 solved (the first sample too: ten Gauss-Newton iterations from a \
                 zero-torque guess); 1 not converged (not reported by the FMU); 2 QP failed (fallback torque = previous plan's \
                 next control, clipped; warning logged the first time and every 100th); 3 \
                 invalid state occurs only through the C API: the FMU refuses NaN/Inf inputs \
                 with fmi2Error; 4 released by the stall supervisor (torque zero)",
            ),
        Rw::<N>::enumeration(VARIANT.parameter, Shape::Scalar, VARIANT.fmi_type())
            .parameter(Field::integer(
                |s, _| VARIANT.item(s.variant),
                |s, _, v| s.variant = VARIANT.value(v).unwrap_or(s.variant),
            ))
            .describe("EigenMPC cost: straight (eigenvector line) or curved (eigenmode chart)"),
        tunable(
            "E_ref",
            |s, _| s.tuning.e_ref,
            |s, _, v| s.tuning.e_ref = v,
            (0.0, 1e4),
            "reference energy",
        )
        .unit("J")
        .group(REFERENCE_GROUP),
        tunable(
            "alpha",
            |s, _| s.tuning.alpha,
            |s, _, v| s.tuning.alpha = v,
            (0.0, 1e3),
            "exploration gain of the straight cost (blend tanh(alpha E))",
        )
        .unit("1/J"),
        tunable(
            "beta",
            |s, _| s.tuning.beta,
            |s, _, v| s.tuning.beta = v,
            (0.0, 1e3),
            "torque-weight offset of the straight cost",
        ),
        tunable(
            "w_E",
            |s, _| s.tuning.w_e,
            |s, _, v| s.tuning.w_e = v,
            (-1.0, 1e8),
            "energy weight; **negative = the paper's value of the variant: 25 curved, 5 straight**",
        ),
        tunable(
            "w_x",
            |s, _| s.tuning.w_x,
            |s, _, v| s.tuning.w_x = v,
            (0.0, 1e8),
            "position-distance weight",
        ),
        tunable(
            "w_xd",
            |s, _| s.tuning.w_xd,
            |s, _, v| s.tuning.w_xd = v,
            (0.0, 1e8),
            "velocity-distance weight",
        ),
        tunable(
            "w_F",
            |s, _| s.tuning.w_f,
            |s, _, v| s.tuning.w_f = v,
            (1e-9, 1e8),
            "torque weight (> 0)",
        ),
        Rw::<N>::real("tau_max", Shape::Scalar)
            .parameter(Field::real(|s, _| s.tau_max, |s, _, v| s.tau_max = v))
            .unit("N.m")
            .range(1e-6, 1e6)
            .describe("Torque bound |tau[j]| <= tau_max"),
        Rw::<N>::integer("horizon", Shape::Scalar)
            .parameter(Field::integer(
                |s, _| s.horizon as i32,
                |s, _, v| s.horizon = v.max(0) as usize,
            ))
            .range(1.0, eigenmpc::mpc::MAX_HORIZON as f64)
            .describe(
                "Shooting intervals N of the prediction horizon (with qp_solver = clarabel at \
                 most 200)",
            ),
        Rw::<N>::real("sample_period", Shape::Scalar)
            .parameter(Field::real(
                |s, _| s.sample_period,
                |s, _, v| s.sample_period = v,
            ))
            .unit("s")
            .range(1e-4, 10.0)
            .describe("Sample period and shooting interval dt"),
    ];
    rows.extend(point_mass_rows::<Settings<N>, N>("Controller model: "));
    rows.extend([
        Rw::<N>::real("c", Shape::Joints)
            .parameter(Field::real(
                |s, e| s.eigenvector[e.j],
                |s, e, v| s.eigenvector[e.j] = v,
            ))
            .range(-1.0, 1.0)
            .describe(
                "Linear eigenvector c, component {j} (normalised; default: in-phase mode of the \
                 default model); chart coordinate s = c'q",
            )
            .summary("linear eigenvector (normalised, nonzero); chart coordinate s = c'q")
            .start_text("in-phase mode of the default model")
            .group(REFERENCE_GROUP),
        Rw::<N>::real("chart.coef", Shape::JointPowers(CHART_COEFFICIENTS))
            .parameter(Field::real(
                |s, e| s.chart[e.j][e.k],
                |s, e, v| s.chart[e.j][e.k] = v,
            ))
            .at(CHART_VR)
            // X_j and s are angles (rad): the coefficient of s^k has unit
            // rad^(1-k), which has no name; left without a unit.
            .describe(
                "Chart X_{j}(s) = sum_k chart.coef[{j},k] s^k (rad, s = c'q in rad), \
                 coefficient of s^{k} (curved; default: in-phase mode of the default model \
                 at the default E_ref)",
            )
            .summary(format!(
                "chart X_j(s) = sum_k chart.coef[j,k] s^k, k = 0..{} (curved)",
                CHART_COEFFICIENTS - 1
            ))
            .start_text("in-phase chart of the default model at the default E_ref")
            .group(REFERENCE_GROUP),
        Rw::<N>::enumeration(QP_SOLVER.parameter, Shape::Scalar, QP_SOLVER.fmi_type())
            .parameter(Field::integer(
                |s, _| QP_SOLVER.item(s.qp),
                |s, _, v| s.qp = QP_SOLVER.value(v).unwrap_or(s.qp),
            ))
            .describe(
                "QP solver of the real-time iteration: riccati (structure-exploiting) or clarabel",
            ),
    ]);
    rows.extend(rigid_rows::<Settings<N>, N>("Controller model: "));
    rows.extend(computed_reference_rows::<N>());
    rows.extend(estimator_rows::<N>());
    rows.extend(adaptation_rows::<N>());
    rows.push(
        tunable(
            "E_scale",
            |s, _| s.tuning.e_scale,
            |s, _, v| s.tuning.e_scale = v,
            (0.0, 1e4),
            "energy scale E_s: for E_ref < E_s the energy residual is r_E = (E_ref - E) \
             sqrt(E_s/E_ref), so that a low E_ref is pulled towards as E_s is (default 14 J, \
             the energy w_E was tuned at); from E_s up the paper's E_ref - E; **0 = the \
             paper's residual at every E_ref** (a low E_ref is then approached slowly); with \
             E_s > 0, E_ref must be > 0",
        )
        .unit("J"),
    );
    rows.extend(compensation_rows::<N>());
    rows.extend(adaptation_outcome_rows::<N>());
    rows.extend(supervisor_rows::<N>());
    rows.extend(response_rows::<N>());
    rows.extend(adapt_estimator_rows::<N>());
    Table::new(N, rows)
}

/// The rows of the measurement delay and actuator lag the controller
/// compensates.
fn compensation_rows<const N: usize>() -> Vec<Rw<N>> {
    vec![
        Rw::<N>::real("measurement_delay", Shape::Scalar)
            .parameter(Field::real(
                |s, _| s.measurement_delay,
                |s, _, v| s.measurement_delay = v,
            ))
            .unit("s")
            .range(0.0, eigenmpc::mpc::MAX_COMPENSATED_TIME)
            .describe(
                "Age of the measured q, qd when they reach the controller (0: current; at most \
                 1 s and horizon sample_period). The controller predicts them forward with \
                 its model and the torques it sent since (any delay, whole samples or not); \
                 the state estimator filters them at their own time",
            ),
        Rw::<N>::real("actuator_time_constant", Shape::Scalar)
            .parameter(Field::real(
                |s, _| s.actuator_time_constant,
                |s, _, v| s.actuator_time_constant = v,
            ))
            .unit("s")
            .range(0.0, eigenmpc::mpc::MAX_COMPENSATED_TIME)
            .describe(
                "Time constant T of the motor's first-order lag dtau_applied/dt = (tau - \
                 tau_applied) / T (0: immediate; at most 1 s and horizon sample_period). \
                 Integrated exactly over the measurement delay; over the horizon taken as a \
                 dead time of T (the plan starts at the state predicted T ahead)",
            ),
    ]
}

/// What the online adaptation did (after the older rows: their value
/// references stay).
fn adaptation_outcome_rows<const N: usize>() -> Vec<Rw<N>> {
    vec![
        Rw::<N>::integer("adapt_refused", Shape::Scalar)
            .output()
            .describe(
                "Candidate models the adaptation refused: not physical, not better than the \
                 model in use on the windows measured after them, or no model or family \
                 (each reason logged once under logEvents, then counted here)",
            ),
        Rw::<N>::integer("adapt_reverts", Shape::Scalar)
            .output()
            .describe(
                "Models the adaptation's supervisor took back because the loop did worse with \
                 them (torque or energy error up; each logged under logEvents)",
            ),
        Rw::<N>::enumeration(
            ADAPTATION_STATUS.parameter,
            Shape::Scalar,
            ADAPTATION_STATUS.fmi_type(),
        )
        .output()
        .describe("What the online adaptation is doing (idle with adapt = false)"),
    ]
}

/// The stall supervisor (after the older rows: their value references
/// stay).
fn supervisor_rows<const N: usize>() -> Vec<Rw<N>> {
    vec![
        Rw::<N>::boolean("supervisor", Shape::Scalar)
            .parameter(Field::boolean(
                |s, _| s.supervisor,
                |s, _, v| s.supervisor = v,
            ))
            .describe(
                "Stall supervisor: judged every 0.5 s over the last second. A stall: a still \
                 joint (mean speed below 0.1 rad/s, angle within 0.04 rad) with its torque at its \
                 bound, or the whole robot still with a torque of at least half of tau_max, while \
                 the energy is outside the 5 % band and not coming closer (a wrong model's fixed \
                 point, a stalled motor on hardware). The plan and the state estimate are dropped \
                 and the torque released to zero for 0.5 s, doubled on each repeat within 20 s up \
                 to 4 s (solver_status 4); with adapt = true the last model taken goes back, or \
                 the estimate is tried at once (adaptation_status = supervisor). Each stall is \
                 logged under logEvents and counted in supervisor_events",
            ),
        Rw::<N>::integer("supervisor_events", Shape::Scalar)
            .output()
            .describe(
                "Stalls the supervisor called so far (each released the torque; logged under \
                 logEvents)",
            ),
    ]
}

/// Names of the estimated base-parameter rows, in the order of
/// [`eigenmpc::identify::BaseParameters`]'s vector.
pub const ESTIMATE_ROWS: [&str; 5] = [
    "estimate.A",
    "estimate.G",
    "estimate.Ir",
    "estimate.b",
    "estimate.cf",
];

/// The rows of the online adaptation (`adapt`) and its estimate.
fn adaptation_rows<const N: usize>() -> Vec<Rw<N>> {
    let estimate = |name, shape, unit, what: &str| {
        Rw::<N>::real(name, shape)
            .discrete_output()
            .unit(unit)
            .describe(format!(
                "{what}: the identification's estimate with adapt = true, else the \
                 controller model's value (0 for a model with joint springs)"
            ))
            .summary(format!("{what} (estimate with adapt)"))
    };
    let [a, g, ir, b, cf] = ESTIMATE_ROWS;
    vec![
        Rw::<N>::boolean("adapt", Shape::Scalar)
            .parameter(Field::boolean(|s, _| s.adapt, |s, _, v| s.adapt = v))
            .describe(
                "Online adaptation: identify the robot's base parameters (inertia and \
                 gravity amplitudes, rotor inertias, viscous and Coulomb friction) from the \
                 measured motion and the torque applied, by the energy balance; the model, its \
                 energy and its mode family follow the estimate (new family computed on a \
                 worker thread). A new model is taken only from a steady loop, when it is \
                 physical, within 30 % of the model in use and explains the windows measured \
                 after it better; a supervisor takes it back when the loop does worse \
                 (adapt_refused, adapt_reverts, adaptation_status). Needs a model without \
                 joint springs",
            ),
        Rw::<N>::real("adapt_period", Shape::Scalar)
            .parameter(Field::real(
                |s, _| s.adapt_period,
                |s, _, v| s.adapt_period = v,
            ))
            .unit("s")
            .range(1e-4, 1e3)
            .describe(
                "Adaptation: time between two looks at the estimate; a new model is taken or \
                 requested at most this often",
            ),
        Rw::<N>::boolean("adapt_realtime", Shape::Scalar)
            .parameter(Field::boolean(
                |s, _| s.adapt_realtime,
                |s, _, v| s.adapt_realtime = v,
            ))
            .describe(
                "Adaptation for a real-time target: a solve never waits for the worker's new \
                 model (taken at the first look after it is ready: the closed loop then depends \
                 on the machine's speed). false: the next look waits for it, and every run \
                 gives the same numbers",
            ),
        estimate(
            a,
            Shape::JointPairs,
            "kg.m2",
            "Link inertia amplitude A[j,l] (j <= l) of the kinetic energy 1/2 sum A[j,l] \
             cos(phi_j - phi_l) w_j w_l, phi and w the absolute link angles and speeds",
        ),
        estimate(
            g,
            Shape::Joints,
            "N.m",
            "Gravity amplitude G[j] of the potential sum G[j] (1 - cos phi_j)",
        ),
        estimate(ir, Shape::Joints, "kg.m2", "Rotor inertia Ir[j]"),
        estimate(b, Shape::Joints, "N.m.s/rad", "Viscous friction b[j]"),
        estimate(cf, Shape::Joints, "N.m", "Coulomb friction cf[j]"),
        Rw::<N>::integer("model_updates", Shape::Scalar)
            .output()
            .describe("Models taken from the identification so far (0 with adapt = false)"),
    ]
}

/// The rows of the reference computed from the model (`chart_source`).
fn computed_reference_rows<const N: usize>() -> Vec<Rw<N>> {
    let chart_energy = |name, what: &str| {
        Rw::<N>::real(name, Shape::Scalar)
            .discrete_output()
            .unit("J")
            .describe(what.to_string())
    };
    vec![
        Rw::<N>::enumeration(
            CHART_SOURCE.parameter,
            Shape::Scalar,
            CHART_SOURCE.fmi_type(),
        )
        .parameter(Field::integer(
            |s, _| CHART_SOURCE.item(s.chart_source),
            |s, _, v| s.chart_source = CHART_SOURCE.value(v).unwrap_or(s.chart_source),
        ))
        .describe(
            "Where the reference comes from: computed (default) from the controller model \
             at creation, linear mode `mode` and its eigenmode family over energy, so that \
             every E_ref gets its own chart; or parameters: c[j] and chart.coef[j,k], one \
             fixed chart",
        )
        .group(REFERENCE_GROUP),
        Rw::<N>::integer("mode", Shape::Scalar)
            .parameter(Field::integer(
                |s, _| s.mode as i32 + 1,
                |s, _, v| s.mode = (v.max(1) - 1) as usize,
            ))
            .range(1.0, N as f64)
            .range_text("[1, number of joints]")
            .describe(
                "Computed reference: linear mode, 1 = lowest frequency (the in-phase mode of \
                 a pendulum), up to the number of joints",
            ),
        Rw::<N>::real("family_energy_max", Shape::Scalar)
            .parameter(Field::real(
                |s, _| s.family_energy_max,
                |s, _, v| s.family_energy_max = v,
            ))
            .unit("J")
            .range(-1.0, 1e4)
            .describe(
                "Computed curved reference: top of the mode family's energy range; \
                 **<= 0 = max(half the potential with every link upright, 1.25 E_ref)**",
            ),
        chart_energy(
            "chart_energy",
            "Energy of the chart in use: E_ref clamped to chart_energy_min..chart_energy_max \
             (an E_ref outside is logged as a warning); 0 for a fixed chart or straight",
        ),
        chart_energy(
            "chart_energy_min",
            "Lowest energy of the computed mode family (0 for a fixed chart or straight)",
        ),
        chart_energy(
            "chart_energy_max",
            "Highest energy of the computed mode family: where the continuation or the \
             chart fit ended, or family_energy_max (0 for a fixed chart or straight)",
        ),
    ]
}

/// The rows of the state estimator (`state_estimator`).
fn estimator_rows<const N: usize>() -> Vec<Rw<N>> {
    let level = |name,
                 get: fn(&Settings<N>, _) -> f64,
                 set: fn(&mut Settings<N>, _, f64),
                 unit,
                 what: &str| {
        Rw::<N>::real(name, Shape::Scalar)
            .parameter(Field::real(get, set))
            .unit(unit)
            .range(1e-9, 1e3)
            .describe(format!("State estimator: {what}"))
    };
    vec![
        Rw::<N>::enumeration(
            STATE_ESTIMATOR.parameter,
            Shape::Scalar,
            STATE_ESTIMATOR.fmi_type(),
        )
        .parameter(Field::integer(
            |s, _| STATE_ESTIMATOR.item(s.state_estimator),
            |s, _, v| s.state_estimator = STATE_ESTIMATOR.value(v).unwrap_or(s.state_estimator),
        ))
        .describe(
            "What filters the measured q, qd before a solve: none (default) or ekf, an \
             extended Kalman filter on the controller's model and the torque it applied",
        ),
        level(
            "angle_noise",
            |s, _| s.noise.angle_noise,
            |s, _, v| s.noise.angle_noise = v,
            "rad",
            "standard deviation of the measured angles' noise",
        ),
        level(
            "speed_noise",
            |s, _| s.noise.speed_noise,
            |s, _, v| s.noise.speed_noise = v,
            "rad/s",
            "standard deviation of the measured speeds' noise",
        ),
        level(
            "acceleration_noise",
            |s, _| s.noise.acceleration_noise,
            |s, _, v| s.noise.acceleration_noise = v,
            "rad/s2",
            "unmodelled acceleration per joint, constant over a sample (larger trusts the \
             measurement more, smaller the model)",
        ),
    ]
}

/// The motor's response per sample (issue 37; after the supervisor's rows:
/// the older value references stay).
/// Where the adaptation's candidates come from (after the older rows:
/// their value references stay).
fn adapt_estimator_rows<const N: usize>() -> Vec<Rw<N>> {
    vec![
        Rw::<N>::enumeration(
            ADAPT_ESTIMATOR.parameter,
            Shape::Scalar,
            ADAPT_ESTIMATOR.fmi_type(),
        )
        .parameter(Field::integer(
            |s, _| ADAPT_ESTIMATOR.item(s.adapt_estimator),
            |s, _, v| s.adapt_estimator = ADAPT_ESTIMATOR.value(v).unwrap_or(s.adapt_estimator),
        ))
        .describe(
            "Adaptation (adapt = true): where candidate models come from. energy_balance: the \
             energy balance over windows. state_and_parameters: the state and the base \
             parameters estimated together every sample by an extended Kalman filter told the \
             sensors' noise (angle_noise, speed_noise with state_estimator = ekf; else 0.005 \
             rad, 0.05 rad/s), and the torque carrying a Gaussian excitation of 0.3 tau_max \
             per joint over the first 40 s (adaptation_status = excitation), without which \
             closed-loop data cannot tell the model's scale from its friction. Under sensor \
             noise with a rough model it is the one that reaches the mode (the lab pendulums' \
             rough models: 41 of 42 within 2 %, against 27 of 42)",
        ),
    ]
}

fn response_rows<const N: usize>() -> Vec<Rw<N>> {
    vec![
        Rw::<N>::real("torque_response", Shape::Scalar)
            .parameter(Field::real(
                |s, _| s.torque_response,
                |s, _, v| s.torque_response = v,
            ))
            .range(0.0, 2.0)
            .range_text("(0, 2]")
            .describe(
                "The motor's response per sample, u += a (tau - u): the torque applied over a \
                 sample moves from the last one's by a times its distance to the command (1: \
                 immediate; a < 1 lags, 1 < a <= 2 overshoots). The plan's controls are the \
                 applied torques, bounded per stage by what the motor reaches; tau is the \
                 command that makes the motor apply the plan's first. Not together with \
                 actuator_time_constant",
            ),
    ]
}
