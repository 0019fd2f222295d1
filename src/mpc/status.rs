//! What one control step reports.

use crate::mechanics::Vector;
use crate::qp::QpStatus;

/// What happened in one control step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ControlStatus {
    /// The QP(s) were solved; `tau` is the optimal first control.
    Solved,
    /// The converged start-up ([`super::Startup::Converge`]) hit its
    /// iteration limit; `tau` is from the last iterate.
    NotConverged,
    /// A QP failed; `tau` is the shifted previous plan's control, clipped.
    QpFailed(QpStatus),
    /// The measured state was NaN/Inf; `tau` is the shifted previous plan's control, clipped.
    InvalidState,
    /// The stall supervisor released the torque: `tau` is zero (a torque
    /// had been held at its bound without motion, see
    /// [`super::SupervisorOptions`]).
    Released,
}

impl ControlStatus {
    /// True when `tau` comes from a successful optimisation.
    pub fn is_ok(self) -> bool {
        matches!(self, ControlStatus::Solved | ControlStatus::NotConverged)
    }

    /// Integer code for C/FMI callers: 0 solved, 1 not converged, 2 QP
    /// failed, 3 invalid state, 4 released by the stall supervisor.
    pub fn code(self) -> i32 {
        match self {
            ControlStatus::Solved => 0,
            ControlStatus::NotConverged => 1,
            ControlStatus::QpFailed(_) => 2,
            ControlStatus::InvalidState => 3,
            ControlStatus::Released => 4,
        }
    }

    /// Inverse of [`ControlStatus::code`] for statuses read back from C/FMI
    /// (the code does not carry the QP status: a QP failure comes back as
    /// `QpFailed(QpStatus::NumericalError)`).
    pub fn from_code(code: i32) -> Option<Self> {
        match code {
            0 => Some(ControlStatus::Solved),
            1 => Some(ControlStatus::NotConverged),
            2 => Some(ControlStatus::QpFailed(QpStatus::NumericalError)),
            3 => Some(ControlStatus::InvalidState),
            4 => Some(ControlStatus::Released),
            _ => None,
        }
    }
}

impl std::fmt::Display for ControlStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ControlStatus::Solved => f.write_str("solved"),
            ControlStatus::NotConverged => {
                f.write_str("start-up SQP not converged (iteration limit)")
            }
            ControlStatus::QpFailed(s) => {
                write!(f, "QP failed ({s:?}): holding the shifted previous plan")
            }
            ControlStatus::InvalidState => {
                f.write_str("measured state is NaN/Inf: holding the shifted previous plan")
            }
            ControlStatus::Released => {
                f.write_str("stall: the supervisor released the torque (zero)")
            }
        }
    }
}

/// Result of one control step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlOutput<const N: usize> {
    /// Torque to apply over the next sample (always finite and within bounds).
    pub tau: Vector<N>,
    /// What happened.
    pub status: ControlStatus,
    /// QP (interior-point) iterations summed over this sample.
    pub qp_iterations: usize,
    /// SQP iterations in this sample (1 for plain RTI).
    pub sqp_iterations: usize,
    /// Preparation time of this sample (s).
    pub preparation_time: f64,
    /// Feedback time of this sample (s).
    pub feedback_time: f64,
}
