//! Modes of a simple mechanical system around its stable equilibrium:
//! linear modes (generalised eigenproblem `K c = w^2 M c`), nonlinear
//! eigenmodes (line-shaped brake orbits of the free system, continued in
//! energy from the linear modes) and the polynomial mode chart `X(s)`.

mod chart;
mod eigenmode;
mod family;
mod linear;

pub use chart::{Chart, ChartPoint};
pub use eigenmode::{
    ContinuationOptions, Eigenmode, continue_family, eigenmode_family,
    eigenmode_family_with_progress,
};
pub use family::{CHART_TOLERANCE, ChartFamily, FamilyOptions, MAX_FAMILY_DEGREE};
pub use linear::{Family, LinearMode, linear_modes};

use crate::integrate::IntegrationError;

/// The name of the family of linear mode `mode_index` (ascending frequency)
/// of an `n`-joint system in messages: the 2-link chain's by [`Family`]
/// (in-phase, anti-phase), others by index.
pub fn family_name(n: usize, mode_index: usize) -> String {
    match (n, mode_index) {
        (2, 0) => format!("{} family", Family::InPhase),
        (2, 1) => format!("{} family", Family::AntiPhase),
        _ => format!("family of linear mode {mode_index} (ascending frequency)"),
    }
}

use thiserror::Error;

/// Why a mode, family or chart could not be computed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ModeError {
    /// The equilibrium is not a strict minimum of the potential.
    #[error("equilibrium is not stable: stiffness eigenvalue {eigenvalue:e} <= 0")]
    UnstableEquilibrium {
        /// The offending eigenvalue `w^2`.
        eigenvalue: f64,
    },
    /// No mode with that index (the system has fewer degrees of freedom).
    #[error("mode index {index} out of range: the system has {dof} modes")]
    NoSuchMode {
        /// Requested index.
        index: usize,
        /// Number of modes.
        dof: usize,
    },
    /// A requested energy is not a positive finite number.
    #[error("energy {0} J is invalid: must be finite and > 0")]
    InvalidEnergy(f64),
    /// Continuation stopped before the requested energy.
    #[error(
        "the {family} cannot be continued beyond E = {reached:.4} J (requested {requested} J): {reason}"
    )]
    ContinuationFailed {
        /// Family name or mode index.
        family: String,
        /// Highest energy for which an orbit was found.
        reached: f64,
        /// The energy that was asked for.
        requested: f64,
        /// Fold, singular Jacobian, non-convergence, ...
        reason: String,
    },
    /// The continuation used up its work limit
    /// ([`ContinuationOptions::max_evaluations`]).
    #[error(
        "the {family} cannot be continued beyond E = {reached:.4} J: it stopped at its work limit \
         ({limit} integrator evaluations); its orbits need more integration than that (time \
         scales far apart: a very light, heavy, long or stiff link; or an energy near the top of \
         the potential, where the period grows without bound)"
    )]
    WorkLimit {
        /// Family name.
        family: String,
        /// Highest energy for which an orbit was found (J).
        reached: f64,
        /// The limit.
        limit: usize,
    },
    /// An orbit was found but does not verify (closing error or turning speed too large).
    #[error("orbit at E = {energy} J fails verification: {reason}")]
    VerificationFailed {
        /// Energy of the orbit.
        energy: f64,
        /// What was too large.
        reason: String,
    },
    /// The chart coordinate is not monotone along the path.
    #[error(
        "chart coordinate s = c'(q - q_eq) is not monotone along the path (sample {index}): the chart would be ill-defined"
    )]
    NotMonotone {
        /// First sample where the direction reverses.
        index: usize,
    },
    /// The chart cannot be fitted (too few samples, bad degree, bad numbers).
    #[error("chart fit failed: {0}")]
    ChartFit(String),
    /// The integrator failed.
    #[error(transparent)]
    Integration(#[from] IntegrationError),
}
