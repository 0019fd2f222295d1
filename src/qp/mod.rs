//! The structured QP that one real-time iteration of the multiple-shooting
//! NMPC produces, and the seam between it and the QP solvers.
//!
//! Stage-wise form (all vectors are the *steps* `dx_k`, `du_k` of one SQP
//! iteration, or absolute values, whichever the caller linearises in):
//!
//! ```text
//! min  sum_{k=0}^{N-1} ( 1/2 [x;u]' [Q_k S_k'; S_k R_k] [x;u] + q_k' x + r_k' u )
//!        + 1/2 x_N' Q_N x_N + q_N' x_N
//!        + sum_k sum_i ( soft_l1_i s_ki + 1/2 soft_l2_i s_ki^2 )
//! s.t. x_0 = x0
//!      x_{k+1} = A_k x_k + B_k u_k + c_k
//!      u_lower_k <= u_k <= u_upper_k
//!      x_lower_k - s_k <= x_k <= x_upper_k + s_k,  s_k >= 0   (soft; +-inf = none)
//! ```
//!
//! Every matrix is allocated once by [`OcpQp::new`] and overwritten in place
//! at each sample, so the real-time loop does not allocate.

#[cfg(feature = "clarabel")]
pub mod clarabel;

use nalgebra::{DMatrix, DVector};

#[cfg(feature = "tooling")]
pub mod kkt;
#[cfg(feature = "tooling")]
pub mod record;
pub mod riccati;
pub mod stages;
#[cfg(feature = "tooling")]
pub mod synthetic;

#[cfg(feature = "tooling")]
pub use kkt::{KktResiduals, kkt_residuals};
pub use riccati::{RiccatiInfo, RiccatiSettings, RiccatiSolver};
pub use stages::{AnyStageQp, QpStage, StageQp};

/// Stage-wise optimal-control QP (see the module documentation).
#[derive(Clone, Debug)]
pub struct OcpQp {
    /// State dimension `nx`.
    pub nx: usize,
    /// Control dimension `nu`.
    pub nu: usize,
    /// Number of shooting intervals `N`.
    pub horizon: usize,
    /// `Q_k`, `k = 0..=N` (`nx x nx`, symmetric PSD).
    pub q: Vec<DMatrix<f64>>,
    /// `S_k`, `k = 0..N` (`nu x nx`).
    pub s: Vec<DMatrix<f64>>,
    /// `R_k`, `k = 0..N` (`nu x nu`, symmetric PD after regularisation).
    pub r: Vec<DMatrix<f64>>,
    /// Linear state cost `q_k`, `k = 0..=N`.
    pub q_lin: Vec<DVector<f64>>,
    /// Linear control cost `r_k`, `k = 0..N`.
    pub r_lin: Vec<DVector<f64>>,
    /// Dynamics `A_k`, `k = 0..N`.
    pub a: Vec<DMatrix<f64>>,
    /// Dynamics `B_k`, `k = 0..N`.
    pub b: Vec<DMatrix<f64>>,
    /// Dynamics offset `c_k`, `k = 0..N`.
    pub c: Vec<DVector<f64>>,
    /// Initial state (equality constraint on `x_0`).
    pub x0: DVector<f64>,
    /// Control lower bounds, `k = 0..N`.
    pub u_lower: Vec<DVector<f64>>,
    /// Control upper bounds, `k = 0..N`.
    pub u_upper: Vec<DVector<f64>>,
    /// Soft state lower bounds, `k = 0..=N` (`-inf` = none; `x_0` is fixed and its bounds are ignored).
    pub x_lower: Vec<DVector<f64>>,
    /// Soft state upper bounds, `k = 0..=N` (`+inf` = none).
    pub x_upper: Vec<DVector<f64>>,
    /// Exact-penalty (L1) weight per state component for bound violations.
    pub soft_l1: DVector<f64>,
    /// Quadratic weight per state component for bound violations.
    pub soft_l2: DVector<f64>,
}

impl OcpQp {
    /// Allocates a QP with zero data, unbounded controls and no state bounds.
    pub fn new(nx: usize, nu: usize, horizon: usize) -> Self {
        let m = |r, c, n| vec![DMatrix::zeros(r, c); n];
        let v = |r, n, val: f64| vec![DVector::from_element(r, val); n];
        Self {
            nx,
            nu,
            horizon,
            q: m(nx, nx, horizon + 1),
            s: m(nu, nx, horizon),
            r: m(nu, nu, horizon),
            q_lin: v(nx, horizon + 1, 0.0),
            r_lin: v(nu, horizon, 0.0),
            a: m(nx, nx, horizon),
            b: m(nx, nu, horizon),
            c: v(nx, horizon, 0.0),
            x0: DVector::zeros(nx),
            u_lower: v(nu, horizon, f64::NEG_INFINITY),
            u_upper: v(nu, horizon, f64::INFINITY),
            x_lower: v(nx, horizon + 1, f64::NEG_INFINITY),
            x_upper: v(nx, horizon + 1, f64::INFINITY),
            soft_l1: DVector::zeros(nx),
            soft_l2: DVector::zeros(nx),
        }
    }
}

/// Outcome of a QP solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QpStatus {
    /// Solved to the requested tolerances.
    Solved,
    /// Solved to reduced tolerances (usable, but say so).
    AlmostSolved,
    /// Iteration limit reached; the iterate is returned but not trusted.
    MaxIterations,
    /// The QP was proven (primal or dual) infeasible.
    Infeasible,
    /// Factorisation or step failure.
    NumericalError,
    /// NaN/Inf or inconsistent dimensions in the data; nothing was solved.
    InvalidInput,
}

impl QpStatus {
    /// True when the solution may be applied.
    pub fn is_usable(self) -> bool {
        matches!(self, QpStatus::Solved | QpStatus::AlmostSolved)
    }
}

/// Primal-dual solution of an [`OcpQp`], preallocated by [`QpSolution::new`].
///
/// Multiplier conventions (Lagrangian `L = f + sum_k pi_k' (A_k x_k + B_k u_k +
/// c_k - x_{k+1}) + ...`): `pi` for the dynamics, `lam_u_lower/upper >= 0` for
/// the control bounds.
#[derive(Clone, Debug)]
pub struct QpSolution {
    /// States `x_k`, `k = 0..=N`.
    pub x: Vec<DVector<f64>>,
    /// Controls `u_k`, `k = 0..N`.
    pub u: Vec<DVector<f64>>,
    /// Dynamics multipliers `pi_k`, `k = 0..N`.
    pub pi: Vec<DVector<f64>>,
    /// Multipliers of `u_k >= u_lower_k`.
    pub lam_u_lower: Vec<DVector<f64>>,
    /// Multipliers of `u_k <= u_upper_k`.
    pub lam_u_upper: Vec<DVector<f64>>,
    /// Objective value at the solution.
    pub objective: f64,
    /// Interior-point (or other) iterations used.
    pub iterations: usize,
    /// Solver status.
    pub status: QpStatus,
    /// Infinity norm of the primal residual reported by the solver.
    pub primal_residual: f64,
    /// Infinity norm of the dual residual reported by the solver.
    pub dual_residual: f64,
}

impl QpSolution {
    /// Allocates a zero solution of the given dimensions.
    pub fn new(nx: usize, nu: usize, horizon: usize) -> Self {
        let v = |r, n| vec![DVector::zeros(r); n];
        Self {
            x: v(nx, horizon + 1),
            u: v(nu, horizon),
            pi: v(nx, horizon),
            lam_u_lower: v(nu, horizon),
            lam_u_upper: v(nu, horizon),
            objective: 0.0,
            iterations: 0,
            status: QpStatus::InvalidInput,
            primal_residual: f64::INFINITY,
            dual_residual: f64::INFINITY,
        }
    }
}

/// Which [`QpSolver`] the controller builds: the structure-exploiting
/// [`RiccatiSolver`] (the default: it matches clarabel on 1300 recorded RTI
/// QPs and takes about a tenth of its time per RTI sample, see
/// docs/speed.md) or the general-purpose clarabel (the reference).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum QpBackend {
    /// [`clarabel::ClarabelQpSolver`] with [`clarabel::rti_settings`].
    Clarabel,
    /// [`RiccatiSolver`] with [`RiccatiSettings::default`].
    #[default]
    Riccati,
}

impl QpBackend {
    /// Both backends, in table order.
    pub const ALL: [QpBackend; 2] = [QpBackend::Clarabel, QpBackend::Riccati];

    /// Name used by the CLI, FMU parameters and logs (`clarabel`, `riccati`).
    pub fn name(self) -> &'static str {
        match self {
            QpBackend::Clarabel => "clarabel",
            QpBackend::Riccati => "riccati",
        }
    }

    /// Whether this build has the backend (clarabel is the core's feature
    /// `clarabel`), or why not.
    pub fn available(self) -> Result<(), String> {
        match self {
            QpBackend::Clarabel if !cfg!(feature = "clarabel") => Err(
                "qp = clarabel: this library was built without clarabel (the core's feature \
                 `clarabel`); use riccati"
                    .into(),
            ),
            _ => Ok(()),
        }
    }

    /// Creates the solver for QPs with `nx` states, `nu` controls and
    /// horizon `horizon` (allocates; call once at set-up).
    pub fn create(self, nx: usize, nu: usize, horizon: usize) -> Box<dyn QpSolver + Send> {
        match self {
            #[cfg(feature = "clarabel")]
            QpBackend::Clarabel => Box::new(self::clarabel::ClarabelQpSolver::new(
                nx,
                nu,
                horizon,
                self::clarabel::rti_settings(),
            )),
            // Unreachable through a validated config (`available` refuses
            // it); the Riccati solver rather than a panic otherwise.
            #[cfg(not(feature = "clarabel"))]
            QpBackend::Clarabel => Box::new(RiccatiSolver::new(
                nx,
                nu,
                horizon,
                RiccatiSettings::default(),
            )),
            QpBackend::Riccati => Box::new(RiccatiSolver::new(
                nx,
                nu,
                horizon,
                RiccatiSettings::default(),
            )),
        }
    }
}

impl std::fmt::Display for QpBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for QpBackend {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "clarabel" => Ok(QpBackend::Clarabel),
            "riccati" => Ok(QpBackend::Riccati),
            other => Err(format!(
                "unknown QP backend `{other}` (expected `clarabel` or `riccati`)"
            )),
        }
    }
}

/// A solver for [`OcpQp`]s of fixed dimensions, created once and reused at
/// every sample (its symbolic set-up is done at creation).
pub trait QpSolver {
    /// Short name for logs and tables (`"clarabel"`, `"riccati"`).
    fn name(&self) -> &'static str;
    /// Solves `qp` into `solution` (overwritten in place); returns the status
    /// that is also stored in `solution.status`. Never panics on bad data.
    fn solve(&mut self, qp: &OcpQp, solution: &mut QpSolution) -> QpStatus;
    /// [`QpSolver::solve`] of a QP stored stage by stage ([`StageQp`]),
    /// the controller's form. Default: converted into `scratch` (allocated
    /// once at the right sizes, so the conversion does not allocate) and
    /// solved; a solver with a typed path for these sizes reads the stages
    /// directly and leaves `scratch` alone.
    fn solve_stages(
        &mut self,
        qp: &dyn AnyStageQp,
        scratch: &mut OcpQp,
        solution: &mut QpSolution,
    ) -> QpStatus {
        qp.write_ocp(scratch);
        self.solve(scratch, solution)
    }
    /// Whether the last solve was finished by a warm or active-set start
    /// without the solver's main method (riccati: its active-set start,
    /// no interior point); `None` for a solver without one. Diagnostics
    /// and benchmarks.
    fn last_solved_by_start(&self) -> Option<bool> {
        None
    }
    /// Tells the solver that the next QP is the last one shifted by one
    /// stage (RTI), so it may start from the shifted previous solution;
    /// `previous_usable` is false when the last solve failed. Default: ignored.
    fn shift_warm_start(&mut self, previous_usable: bool) {
        let _ = previous_usable;
    }
    /// What a later solve reads of the earlier ones (the warm start), for a
    /// saved controller state ([`crate::mpc::Controller::save_state`]).
    /// Default: nothing (a solver without memory between solves).
    fn save_warm_start(&self) -> Vec<f64> {
        Vec::new()
    }
    /// Restores [`QpSolver::save_warm_start`] of a solver of the same kind
    /// and dimensions; an error if `saved` does not fit.
    fn restore_warm_start(&mut self, saved: &[f64]) -> Result<(), String> {
        if saved.is_empty() {
            Ok(())
        } else {
            Err(format!(
                "the {} solver keeps no warm start, {} values given",
                self.name(),
                saved.len()
            ))
        }
    }
}
