//! Plain C API: the EigenMPC controller without FMI, for embedding in a C
//! control loop. Declared in `include/eigenmpc.h` (cbindgen).
//!
//! ```c
//! EigenMpcConfig cfg = eigenmpc_config_default(EIGENMPC_VARIANT_CURVED);
//! char err[256];
//! EigenMpc *mpc = eigenmpc_create(&cfg, NULL, err, sizeof err); /* NULL chart: 14 J default */
//! if (!mpc) { fprintf(stderr, "%s\n", err); return 1; }
//! double z[4] = {0.05, 0.05, 0, 0}, tau[2];
//! int status = eigenmpc_step(mpc, z, tau); /* every sample_period seconds */
//! eigenmpc_free(mpc);
//! ```
//!
//! Any robot, 1 to 6 joints (`eigenmpc::joints`): `eigenmpc_create_named` takes the controller
//! FMU's parameter names and values (`m[1]`, `r[1]`, `I[1]`, `cf[2]`,
//! `E_ref`, `chart_source`, ...; every rigid-link parameter), checked and
//! defaulted by the FMU's own variable table.
//!
//! Every function checks its pointers and catches panics: a failure is a
//! return value (NULL, a negative status) and a message, never an abort.
//! A handle may be used from any thread, one call at a time.

use crate::STATUS_BAD_ARGUMENT;
use eigenmpc::mpc::{ControlStatus, CostParams, Variant};
use eigenmpc_fmu_models::controller::ControllerProduct;
use eigenmpc_fmu_models::controller::adaptive::AdaptiveController;
use eigenmpc_fmu_models::controller::named::settings_from_named;
use eigenmpc_fmu_models::controller::settings::{ChartSource, Settings, Tuning};
use eigenmpc_fmu_models::enums::{ADAPTATION_STATUS, CHART_SOURCE, QP_SOLVER};
use eigenmpc_fmu_models::products::{self, EigenMpc2};
use nalgebra::SVector;
use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Number of chart coefficients per joint in [`eigenmpc_create`]'s
/// `chart_coef` (powers 0..9; a literal for the C header).
pub const CHART_COEFFICIENTS: usize = 10;
const _: () =
    assert!(CHART_COEFFICIENTS == eigenmpc_fmu_models::controller::settings::CHART_COEFFICIENTS);

/// Controller configuration for [`eigenmpc_create`]. Get the paper's values
/// from [`eigenmpc_config_default`] and change what you need.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EigenMpcConfig {
    /// An `EIGENMPC_VARIANT_*` item (straight 1, curved 2, hybrid 3: the variant table).
    pub variant: i32,
    /// Reference energy E_ref (J), >= 0.
    pub e_ref: f64,
    /// Exploration gain alpha of the straight cost (1/J), >= 0.
    pub alpha: f64,
    /// Torque-weight offset beta of the straight cost, >= 0.
    pub beta: f64,
    /// Energy weight w_E; negative: the paper's value of the variant (25 curved, 5 straight).
    pub w_e: f64,
    /// Position-distance weight w_x, >= 0.
    pub w_x: f64,
    /// Velocity-distance weight w_xd, >= 0.
    pub w_xd: f64,
    /// Torque weight w_F, > 0.
    pub w_f: f64,
    /// Torque bound |tau_j| <= tau_max (N m), > 0.
    pub tau_max: f64,
    /// Shooting intervals N of the horizon, 1..=1000 (`eigenmpc::mpc::MAX_HORIZON`; at most
    /// 200 with the clarabel QP solver).
    pub horizon: u32,
    /// Sample period and shooting interval (s), > 0.
    pub sample_period: f64,
    /// Controller model: point masses (kg).
    pub masses: [f64; 2],
    /// Controller model: link lengths (m).
    pub lengths: [f64; 2],
    /// Controller model: gravitational acceleration (m/s^2).
    pub gravity: f64,
    /// Linear eigenvector c (normalised by the controller).
    pub eigenvector: [f64; 2],
    /// QP solver: `EIGENMPC_QP_SOLVER_CLARABEL` (1) or `EIGENMPC_QP_SOLVER_RICCATI` (2, default).
    pub qp_solver: i32,
    /// Where the reference comes from: `EIGENMPC_CHART_SOURCE_COMPUTED` (1,
    /// default: linear mode `mode` of the model and its eigenmode family over
    /// energy, a chart for every E_ref) or `EIGENMPC_CHART_SOURCE_PARAMETERS`
    /// (2: `eigenvector` and the `chart_coef` of [`eigenmpc_create`]).
    pub chart_source: i32,
    /// Computed reference: linear mode, 1 = lowest frequency (in-phase), 2 = anti-phase.
    pub mode: i32,
    /// Computed curved reference: top of the family's energy range (J);
    /// <= 0: max(half the upright potential, 1.25 E_ref).
    pub family_energy_max: f64,
    /// Online adaptation (1) of the model to the identified robot, or none
    /// (0, default): as the FMU's `adapt`.
    pub adapt: i32,
    /// Adaptation: time between two looks at the estimate (s), as the FMU's
    /// `adapt_period`.
    pub adapt_period: f64,
    /// Adaptation: 1 = a step never waits for the worker thread's new
    /// model (real-time loops); 0 (default) = the next look waits for it
    /// (reproducible offline runs). As the FMU's `adapt_realtime`.
    pub adapt_realtime: i32,
    /// Energy scale E_s (J), >= 0: for E_ref < E_s the energy residual is
    /// r_E = (E_ref - E) sqrt(E_s / E_ref) (default 14, where w_E was tuned;
    /// from E_s up, and with 0, the paper's E_ref - E). As the FMU's
    /// `E_scale`; after the older fields, so that their offsets stay.
    pub e_scale: f64,
    /// Age of the measured state when it reaches the controller (s), 0..=1
    /// and at most horizon * sample_period; 0 (default): current. The
    /// controller predicts it forward with the torques it sent since. As the
    /// FMU's `measurement_delay`.
    pub measurement_delay: f64,
    /// Time constant of the motor's first-order lag (s), 0..=1 and at most
    /// horizon * sample_period; 0 (default): immediate. As the FMU's
    /// `actuator_time_constant`.
    pub actuator_time_constant: f64,
    /// The motor's response per sample, `u += a (tau - u)`, in (0, 2]; 1
    /// (default): immediate. The step's torque is then the command that
    /// makes the motor apply the plan's torque. Not together with
    /// `actuator_time_constant`. As the FMU's `torque_response`.
    pub torque_response: f64,
    /// The stall supervisor (1, default) or none (0): a joint held still by
    /// a large torque, off the target energy, gets its torque released
    /// (status `EIGENMPC_STATUS_RELEASED`). As the FMU's `supervisor`.
    pub supervisor: i32,
}

/// Diagnostics of the last [`eigenmpc_step`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EigenMpcStepInfo {
    /// Status code (`EIGENMPC_STATUS_*`), as returned by the step.
    pub status: i32,
    /// QP iterations of the step (riccati: the active-set start's Riccati
    /// recursions when it solved the QP, else interior-point iterations).
    pub qp_iterations: u32,
    /// Wall-clock time of the step: preparation + feedback (s).
    pub solve_time: f64,
    /// Energy of the step's state under the controller's model (J).
    pub energy: f64,
    /// Models taken from the identification so far (0 without adaptation).
    pub model_updates: u32,
    /// Candidate models the adaptation refused so far (as the FMU's
    /// `adapt_refused`).
    pub adapt_refused: u32,
    /// Models the adaptation's supervisor took back (as `adapt_reverts`).
    pub adapt_reverts: u32,
    /// What the adaptation is doing: the FMU's `adaptation_status` item (1
    /// idle, 2 excitation, 3 learning, 4 converged, 5 reverted, 6
    /// supervisor).
    pub adaptation_status: i32,
    /// Stalls the supervisor called so far (as the FMU's
    /// `supervisor_events`).
    pub supervisor_events: u32,
}

/// The controller behind a handle, whatever its number of joints.
trait JointController: Send {
    fn joints(&self) -> usize;
    /// The base parameters (estimate with adaptation), or None.
    fn estimate(&self, out: &mut [f64]) -> Option<usize>;
    /// One sample; `state` has `2 joints`, `tau` `joints` elements.
    fn step(&mut self, state: &[f64], tau: &mut [f64]) -> EigenMpcStepInfo;
    fn set_cost(&mut self, cost: CostParams) -> Result<(), String>;
    fn set_e_ref(&mut self, e_ref: f64) -> Result<(), String>;
    fn reset(&mut self);
}

impl<const N: usize, const NX: usize, const NP: usize, const NA: usize> JointController
    for AdaptiveController<N, NX, NP, NA>
{
    fn joints(&self) -> usize {
        N
    }

    fn estimate(&self, out: &mut [f64]) -> Option<usize> {
        let theta = AdaptiveController::estimate(self)?.theta;
        let n = out.len().min(NP);
        out[..n].copy_from_slice(&theta.as_slice()[..n]);
        Some(NP)
    }

    fn step(&mut self, state: &[f64], tau: &mut [f64]) -> EigenMpcStepInfo {
        let z = SVector::<f64, NX>::from_column_slice(state);
        let dt = self.controller().config().dt;
        let out = AdaptiveController::step(self, &z, dt);
        tau.copy_from_slice(out.tau.as_slice());
        let energy = if matches!(out.status, ControlStatus::InvalidState) {
            f64::NAN
        } else {
            self.controller().energy(&z)
        };
        EigenMpcStepInfo {
            status: out.status.code(),
            qp_iterations: u32::try_from(out.qp_iterations).unwrap_or(u32::MAX),
            solve_time: out.preparation_time + out.feedback_time,
            energy,
            model_updates: u32::try_from(self.model_updates()).unwrap_or(u32::MAX),
            adapt_refused: u32::try_from(self.refused_models()).unwrap_or(u32::MAX),
            adapt_reverts: u32::try_from(self.reverted_models()).unwrap_or(u32::MAX),
            adaptation_status: ADAPTATION_STATUS.item(self.adaptation_status()),
            supervisor_events: u32::try_from(self.controller().supervisor_events())
                .unwrap_or(u32::MAX),
        }
    }

    fn set_cost(&mut self, cost: CostParams) -> Result<(), String> {
        self.controller_mut()
            .set_cost(cost)
            .map_err(|e| e.to_string())
    }

    fn set_e_ref(&mut self, e_ref: f64) -> Result<(), String> {
        self.controller_mut()
            .set_e_ref(e_ref)
            .map_err(|e| e.to_string())
    }

    fn reset(&mut self) {
        AdaptiveController::reset(self);
    }
}

/// An EigenMPC controller (opaque). Create with [`eigenmpc_create`] (the
/// paper's double pendulum, point masses) or [`eigenmpc_create_named`] (any
/// robot, 1 to 6 joints), free with [`eigenmpc_free`].
pub struct EigenMpc {
    controller: Box<dyn JointController>,
    variant: Variant,
    info: EigenMpcStepInfo,
    /// Message of the last failed call ("" if none), NUL-terminated.
    last_error: CString,
}

impl EigenMpc {
    fn fail(&mut self, message: String) -> i32 {
        self.last_error = CString::new(message.replace('\0', " ")).unwrap_or_default();
        STATUS_BAD_ARGUMENT
    }
}

/// The config's fields as the controller FMU's parameters: `(C field,
/// FMU name, value)`. The FMU's variable table checks them, so the C API
/// and the FMU accept the same ranges.
fn named_fields(config: &EigenMpcConfig) -> [(&'static str, &'static str, f64); 30] {
    [
        ("variant", "variant", f64::from(config.variant)),
        ("e_ref", "E_ref", config.e_ref),
        ("alpha", "alpha", config.alpha),
        ("beta", "beta", config.beta),
        ("w_e", "w_E", config.w_e),
        ("w_x", "w_x", config.w_x),
        ("w_xd", "w_xd", config.w_xd),
        ("w_f", "w_F", config.w_f),
        ("tau_max", "tau_max", config.tau_max),
        ("horizon", "horizon", f64::from(config.horizon)),
        ("sample_period", "sample_period", config.sample_period),
        ("masses[0]", "m[1]", config.masses[0]),
        ("masses[1]", "m[2]", config.masses[1]),
        ("lengths[0]", "l[1]", config.lengths[0]),
        ("lengths[1]", "l[2]", config.lengths[1]),
        ("gravity", "g", config.gravity),
        ("eigenvector[0]", "c[1]", config.eigenvector[0]),
        ("eigenvector[1]", "c[2]", config.eigenvector[1]),
        ("qp_solver", "qp_solver", f64::from(config.qp_solver)),
        (
            "chart_source",
            "chart_source",
            f64::from(config.chart_source),
        ),
        ("mode", "mode", f64::from(config.mode)),
        (
            "family_energy_max",
            "family_energy_max",
            config.family_energy_max,
        ),
        ("adapt", "adapt", f64::from(config.adapt)),
        ("adapt_period", "adapt_period", config.adapt_period),
        (
            "adapt_realtime",
            "adapt_realtime",
            f64::from(config.adapt_realtime),
        ),
        ("e_scale", "E_scale", config.e_scale),
        (
            "measurement_delay",
            "measurement_delay",
            config.measurement_delay,
        ),
        (
            "actuator_time_constant",
            "actuator_time_constant",
            config.actuator_time_constant,
        ),
        ("supervisor", "supervisor", f64::from(config.supervisor)),
        ("torque_response", "torque_response", config.torque_response),
    ]
}

/// Names the config field of a message from the FMU's table.
fn in_config_terms(message: String, fields: &[(&str, &str, f64)]) -> String {
    match fields
        .iter()
        .find(|(_, name, _)| message.starts_with(&format!("{name} ")))
    {
        Some((field, name, _)) if field != name => format!("config.{field} ({name}): {message}"),
        Some((field, _, _)) => format!("config.{field}: {message}"),
        None => message,
    }
}

/// Checks a tunable as the controller FMU of `joints` joints does.
fn check_tunable(joints: usize, name: &str, v: f64) -> Result<(), String> {
    eigenmpc::with_joint_count!(
        joints,
        |N, S, NP| products::check_named::<N>(name, v),
        // Never a default: a handle of another joint count is a bug.
        otherwise Err(format!(
            "{name}: no {joints}-joint controller to check it against"
        ))
    )
}

fn settings_from(config: &EigenMpcConfig) -> Result<Settings<2>, String> {
    let fields = named_fields(config);
    let pairs: Vec<(&str, f64)> = fields.iter().map(|&(_, name, v)| (name, v)).collect();
    settings_from_named::<EigenMpc2, 2>(&pairs).map_err(|e| in_config_terms(e, &fields))
}

fn tuning_from(config: &EigenMpcConfig) -> Tuning {
    Tuning {
        e_ref: config.e_ref,
        alpha: config.alpha,
        beta: config.beta,
        w_e: config.w_e,
        w_x: config.w_x,
        w_xd: config.w_xd,
        w_f: config.w_f,
        e_scale: config.e_scale,
    }
}

/// Writes `message` into the caller's buffer (truncated, NUL-terminated).
///
/// # Safety
/// `buffer` is null or valid for `len` bytes.
unsafe fn write_error(buffer: *mut c_char, len: usize, message: &str) {
    if buffer.is_null() || len == 0 {
        return;
    }
    let bytes = message.as_bytes();
    let n = bytes.len().min(len - 1);
    // SAFETY: the caller guarantees `len` writable bytes; n + 1 <= len.
    unsafe {
        std::ptr::copy_nonoverlapping(bytes.as_ptr().cast::<c_char>(), buffer, n);
        *buffer.add(n) = 0;
    }
}

/// The paper's configuration (section V-A) for `variant` on the paper's
/// double pendulum (m = l = 1, g = 9.81): N = 80, dt = 25 ms, |tau| <= 1 N m,
/// E_ref = 14 J, w_E negative (paper default of the variant), in-phase
/// eigenvector. An unknown variant is kept and refused by [`eigenmpc_create`].
#[unsafe(no_mangle)]
pub extern "C" fn eigenmpc_config_default(variant: i32) -> EigenMpcConfig {
    let s = EigenMpc2::settings(Variant::Curved);
    EigenMpcConfig {
        variant,
        e_ref: s.tuning.e_ref,
        alpha: s.tuning.alpha,
        beta: s.tuning.beta,
        w_e: s.tuning.w_e,
        w_x: s.tuning.w_x,
        w_xd: s.tuning.w_xd,
        w_f: s.tuning.w_f,
        tau_max: s.tau_max,
        horizon: s.horizon as u32,
        sample_period: s.sample_period,
        masses: s.model.mass,
        lengths: s.model.length,
        gravity: s.model.gravity,
        eigenvector: s.eigenvector,
        qp_solver: QP_SOLVER.item(s.qp),
        chart_source: CHART_SOURCE.item(s.chart_source),
        mode: s.mode as i32 + 1,
        family_energy_max: s.family_energy_max,
        adapt: i32::from(s.adapt),
        adapt_period: s.adapt_period,
        adapt_realtime: i32::from(s.adapt_realtime),
        e_scale: s.tuning.e_scale,
        measurement_delay: s.measurement_delay,
        actuator_time_constant: s.actuator_time_constant,
        supervisor: i32::from(s.supervisor),
        torque_response: s.torque_response,
    }
}

/// Creates a controller (all memory is allocated here; steps do not allocate).
///
/// `chart_coef` (curved with `chart_source` = parameters only, may be
/// NULL): 20 numbers, the chart coefficients of joint 1 for powers 0..9,
/// then joint 2 (the FMU's `chart.coef[j,k]`, from `eigenmpc modes`); NULL
/// selects the 14 J in-phase chart of the default model. With the default
/// `chart_source` (computed) the chart family is computed here (about 20 ms)
/// and `chart_coef` must be NULL. On failure returns NULL and, if `error` is not
/// NULL, writes the reason into `error` (at most `error_len` bytes, NUL-terminated).
///
/// # Safety
/// `config` is NULL or points to an `EigenMpcConfig`; `chart_coef` is NULL or
/// points to 20 doubles; `error` is NULL or valid for `error_len` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn eigenmpc_create(
    config: *const EigenMpcConfig,
    chart_coef: *const f64,
    error: *mut c_char,
    error_len: usize,
) -> *mut EigenMpc {
    let result = catch_unwind(AssertUnwindSafe(|| -> Result<EigenMpc, String> {
        if config.is_null() {
            return Err("config is NULL".into());
        }
        // SAFETY: non-null, and the caller guarantees it points to a config.
        let config = unsafe { &*config };
        let mut settings = settings_from(config)?;
        if !chart_coef.is_null() && settings.chart_source != ChartSource::Parameters {
            return Err(
                "chart_coef given but chart_source is computed: set chart_source = \
                 EIGENMPC_CHART_SOURCE_PARAMETERS to use it"
                    .into(),
            );
        }
        if !chart_coef.is_null() {
            // SAFETY: the caller guarantees 2 * CHART_COEFFICIENTS doubles.
            let coef = unsafe { std::slice::from_raw_parts(chart_coef, 2 * CHART_COEFFICIENTS) };
            for (j, row) in settings.chart.iter_mut().enumerate() {
                row.copy_from_slice(&coef[j * CHART_COEFFICIENTS..(j + 1) * CHART_COEFFICIENTS]);
            }
        }
        handle::<2, 4, 11, 15>(&settings)
    }));
    // SAFETY: the caller's guarantee on `error`.
    unsafe { finish_create("eigenmpc_create", result, error, error_len) }
}

/// A handle for the controller `settings` define.
fn handle<const N: usize, const NX: usize, const NP: usize, const NA: usize>(
    settings: &Settings<N>,
) -> Result<EigenMpc, String> {
    let controller: Box<dyn JointController> =
        Box::new(AdaptiveController::<N, NX, NP, NA>::new(settings)?);
    Ok(EigenMpc {
        controller,
        variant: settings.variant,
        info: EigenMpcStepInfo::default(),
        last_error: CString::default(),
    })
}

/// The handle, or NULL and the message in `error`.
///
/// # Safety
/// `error` is NULL or valid for `error_len` bytes.
unsafe fn finish_create(
    function: &str,
    result: std::thread::Result<Result<EigenMpc, String>>,
    error: *mut c_char,
    error_len: usize,
) -> *mut EigenMpc {
    let message = match result {
        Ok(Ok(mpc)) => return Box::into_raw(Box::new(mpc)),
        Ok(Err(message)) => format!("{function}: {message}"),
        Err(_) => format!("{function}: internal error (panic caught)"),
    };
    // SAFETY: the caller's guarantee on `error`.
    unsafe { write_error(error, error_len, &message) };
    std::ptr::null_mut()
}

/// Creates a controller for `joints` = 1 to 6 (2: the `EigenMPC` FMU's
/// parameters and defaults, 3: `EigenMPC3`'s, others: an exported robot's,
/// whose chart is computed from the model) from parameter names and values: `count` pairs
/// `names[i]` = `values[i]`, any parameter of that FMU's variable table
/// (the book, `docs/book/src/fmu-variables.md`): the model (`m[j]`, `l[j]`, `g`,
/// `r[j]`, `I[j]`, `Ir[j]`, `gr[j]`, `b[j]`, `cf[j]`, `k[j]`, `q_rest[j]`,
/// `coulomb_sharpness`), the tuning (`E_ref`, `w_E`, ...), `variant`,
/// `qp_solver`, `horizon`, `chart_source`, `mode`, `c[j]`,
/// `chart.coef[j,k]`, ... (integer and enumeration parameters as integral
/// doubles). What is not named keeps the FMU's default; the names and values
/// of `eigenmpc modes --fmu-start-values` work as they are. Each value is
/// checked as the FMU checks it. On failure returns NULL and writes the
/// reason (naming the parameter) into `error` as [`eigenmpc_create`] does.
/// With the default `chart_source` (computed) the mode family is computed
/// here (tens of milliseconds).
///
/// # Safety
/// `names` is NULL or points to `count` NUL-terminated strings, `values` is
/// NULL or points to `count` doubles (both may be NULL when `count` is 0);
/// `error` is NULL or valid for `error_len` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn eigenmpc_create_named(
    joints: u32,
    names: *const *const c_char,
    values: *const f64,
    count: usize,
    error: *mut c_char,
    error_len: usize,
) -> *mut EigenMpc {
    let result = catch_unwind(AssertUnwindSafe(|| -> Result<EigenMpc, String> {
        if count > 0 && (names.is_null() || values.is_null()) {
            return Err("names or values is NULL".into());
        }
        let mut pairs = Vec::with_capacity(count);
        for i in 0..count {
            // SAFETY: the caller guarantees `count` names and values.
            let (name, value) = unsafe { (*names.add(i), *values.add(i)) };
            if name.is_null() {
                return Err(format!("names[{i}] is NULL"));
            }
            // SAFETY: non-null, NUL-terminated (caller's guarantee).
            let name = unsafe { CStr::from_ptr(name) }
                .to_str()
                .map_err(|_| format!("names[{i}] is not UTF-8"))?;
            pairs.push((name, value));
        }
        let n = joints as usize;
        eigenmpc::with_joint_count!(
            n,
            |N, S, NP, NA| handle::<N, S, NP, NA>(&products::settings_from_named::<N>(&pairs)?),
            otherwise Err(format!("joints = {n}: {}", eigenmpc::joints::unsupported(n)))
        )
    }));
    // SAFETY: the caller's guarantee on `error`.
    unsafe { finish_create("eigenmpc_create_named", result, error, error_len) }
}

/// Number of joints of the handle's controller (1 to 6), or
/// `EIGENMPC_STATUS_BAD_ARGUMENT` for a NULL handle.
///
/// # Safety
/// `mpc` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn eigenmpc_joints(mpc: *const EigenMpc) -> i32 {
    if mpc.is_null() {
        return STATUS_BAD_ARGUMENT;
    }
    // SAFETY: non-null live handle; joints() cannot panic.
    unsafe { (*mpc).controller.joints() as i32 }
}

/// Runs `body` on the handle under `catch_unwind`; NULL handle or panic:
/// `EIGENMPC_STATUS_BAD_ARGUMENT`.
///
/// # Safety
/// `mpc` is NULL or a live handle from [`eigenmpc_create`].
unsafe fn with_handle(mpc: *mut EigenMpc, body: impl FnOnce(&mut EigenMpc) -> i32) -> i32 {
    if mpc.is_null() {
        return STATUS_BAD_ARGUMENT;
    }
    // SAFETY: non-null live handle (caller's guarantee), used one call at a time.
    let handle = unsafe { &mut *mpc };
    match catch_unwind(AssertUnwindSafe(|| body(&mut *handle))) {
        Ok(code) => code,
        Err(_) => handle.fail("internal error (panic caught)".into()),
    }
}

/// Sets the reference energy E_ref (J) for the following steps. Returns 0,
/// or `EIGENMPC_STATUS_BAD_ARGUMENT` (value refused, see [`eigenmpc_last_error`]).
///
/// # Safety
/// `mpc` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn eigenmpc_set_e_ref(mpc: *mut EigenMpc, e_ref: f64) -> i32 {
    // SAFETY: forwarded caller guarantee.
    unsafe {
        with_handle(mpc, |h| {
            let checked = check_tunable(h.controller.joints(), "E_ref", e_ref)
                .and_then(|()| h.controller.set_e_ref(e_ref));
            match checked {
                Ok(()) => 0,
                Err(e) => h.fail(format!("eigenmpc_set_e_ref: {e}")),
            }
        })
    }
}

/// Takes over the tunable fields of `config` (e_ref, alpha, beta, w_e, w_x,
/// w_xd, w_f, e_scale) for the following steps; the other fields are ignored. Returns
/// 0, or `EIGENMPC_STATUS_BAD_ARGUMENT` (nothing changed).
///
/// # Safety
/// `mpc` is NULL or a live handle; `config` is NULL or points to a config.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn eigenmpc_set_tuning(
    mpc: *mut EigenMpc,
    config: *const EigenMpcConfig,
) -> i32 {
    // SAFETY: forwarded caller guarantees.
    unsafe {
        with_handle(mpc, |h| {
            if config.is_null() {
                return h.fail("eigenmpc_set_tuning: config is NULL".into());
            }
            let fields = named_fields(&*config);
            // The tunables: e_ref .. w_f and e_scale, checked by the FMU's table.
            for &(field, name, v) in fields[1..8].iter().chain(&fields[25..]) {
                if let Err(e) = check_tunable(h.controller.joints(), name, v) {
                    return h.fail(format!("eigenmpc_set_tuning: config.{field}: {e}"));
                }
            }
            let cost = tuning_from(&*config).cost(h.variant);
            match h.controller.set_cost(cost) {
                Ok(()) => 0,
                Err(e) => h.fail(format!("eigenmpc_set_tuning: {e}")),
            }
        })
    }
}

/// One control sample: measured `state` = (q1, .., qn, qd1, .., qdn) in rad,
/// rad/s, n = [`eigenmpc_joints`] (2 from [`eigenmpc_create`]); writes the
/// n torques to apply until the next sample to `tau_out` (N m, always
/// finite and within +-tau_max). Returns the status:
/// `EIGENMPC_STATUS_SOLVED` (0), `_NOT_CONVERGED` (1, first sample only),
/// `_QP_FAILED` (2) or `_INVALID_STATE` (3) (both with the fallback torque),
/// or `_BAD_ARGUMENT` (-1: NULL pointer; `tau_out` untouched). Call it every
/// `sample_period` seconds.
///
/// # Safety
/// `mpc` is NULL or a live handle; `state` is NULL or points to 2 n
/// doubles; `tau_out` is NULL or points to n writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn eigenmpc_step(
    mpc: *mut EigenMpc,
    state: *const f64,
    tau_out: *mut f64,
) -> i32 {
    // SAFETY: forwarded caller guarantees.
    unsafe {
        with_handle(mpc, |h| {
            if state.is_null() || tau_out.is_null() {
                return h.fail("eigenmpc_step: state or tau_out is NULL".into());
            }
            let n = h.controller.joints();
            let z = std::slice::from_raw_parts(state, 2 * n);
            let tau = std::slice::from_raw_parts_mut(tau_out, n);
            h.info = h.controller.step(z, tau);
            h.info.status
        })
    }
}

/// Diagnostics of the last [`eigenmpc_step`] (all zero before the first).
/// Returns 0, or `EIGENMPC_STATUS_BAD_ARGUMENT` for a NULL pointer.
///
/// # Safety
/// `mpc` is NULL or a live handle; `info` is NULL or points to a writable struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn eigenmpc_last_step(
    mpc: *mut EigenMpc,
    info: *mut EigenMpcStepInfo,
) -> i32 {
    // SAFETY: forwarded caller guarantees.
    unsafe {
        with_handle(mpc, |h| {
            if info.is_null() {
                return h.fail("eigenmpc_last_step: info is NULL".into());
            }
            *info = h.info;
            0
        })
    }
}

/// The controller's base parameters, in the order of the FMU's outputs
/// `estimate.A[j,l]` (j <= l, row by row), `estimate.G[j]`,
/// `estimate.Ir[j]`, `estimate.b[j]`, `estimate.cf[j]`: the
/// identification's estimate with `adapt`, else the model's. Writes at
/// most `len` of them to `out` and returns how many there are (11 for 2
/// joints, 18 for 3; call with `len` = 0 to ask), or
/// `EIGENMPC_STATUS_BAD_ARGUMENT` (NULL pointer with `len` > 0, or a model
/// with joint springs, which has none).
///
/// # Safety
/// `mpc` is NULL or a live handle; `out` is NULL or points to `len`
/// writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn eigenmpc_estimate(mpc: *mut EigenMpc, out: *mut f64, len: usize) -> i32 {
    // SAFETY: forwarded caller guarantees.
    unsafe {
        with_handle(mpc, |h| {
            if out.is_null() && len > 0 {
                return h.fail("eigenmpc_estimate: out is NULL".into());
            }
            let out = if len == 0 {
                &mut [][..]
            } else {
                std::slice::from_raw_parts_mut(out, len)
            };
            match h.controller.estimate(out) {
                Some(n) => n as i32,
                None => h.fail(
                    "eigenmpc_estimate: a model with joint springs has no base parameters".into(),
                ),
            }
        })
    }
}

/// Forgets the plan: the next step starts afresh (solved to convergence);
/// with adaptation also the identification's open window (the estimate and
/// the adapted model are kept). Returns 0, or `EIGENMPC_STATUS_BAD_ARGUMENT` for a NULL handle.
///
/// # Safety
/// `mpc` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn eigenmpc_reset(mpc: *mut EigenMpc) -> i32 {
    // SAFETY: forwarded caller guarantee.
    unsafe {
        with_handle(mpc, |h| {
            h.controller.reset();
            0
        })
    }
}

/// Message of the last failed call on this handle ("" if none; a static
/// message for a NULL handle). Valid until the next call on the handle.
///
/// # Safety
/// `mpc` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn eigenmpc_last_error(mpc: *const EigenMpc) -> *const c_char {
    if mpc.is_null() {
        return c"the EigenMpc handle is NULL".as_ptr();
    }
    // SAFETY: non-null live handle.
    unsafe { (*mpc).last_error.as_ptr() }
}

/// Frees a controller (NULL is ignored).
///
/// # Safety
/// `mpc` is NULL or a live handle from [`eigenmpc_create`], not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn eigenmpc_free(mpc: *mut EigenMpc) {
    if !mpc.is_null() {
        // SAFETY: the handle came from Box::into_raw in eigenmpc_create.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(mpc) })));
    }
}
