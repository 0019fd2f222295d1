//! `solver_status` codes of the FMU and return codes of the C API (equal to
//! `eigenmpc::mpc::ControlStatus::code`, tested).

/// The QP(s) were solved; the torque is optimal.
pub const STATUS_SOLVED: i32 = 0;
/// A converged start-up (`Startup::Converge` of the Rust API) hit its
/// iteration limit; the torque is from the last iterate. The C API and
/// the FMU start with bounded Gauss-Newton iterations and do not report
/// it.
pub const STATUS_NOT_CONVERGED: i32 = 1;
/// A QP failed; the torque is the fallback (the shifted previous plan's
/// control, clipped; zero without a plan).
pub const STATUS_QP_FAILED: i32 = 2;
/// The state was NaN/Inf; the torque is the fallback.
/// C API only: the FMU refuses NaN/Inf inputs with `fmi2Error` before a solve.
pub const STATUS_INVALID_STATE: i32 = 3;
/// The stall supervisor released the torque (zero): a joint had been held
/// still by a large torque, off the target energy.
pub const STATUS_RELEASED: i32 = 4;
/// C API only: a null pointer or otherwise invalid argument; nothing was computed.
pub const STATUS_BAD_ARGUMENT: i32 = -1;
