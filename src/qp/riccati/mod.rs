//! Structure-exploiting QP solver for the RTI: a primal-dual interior-point
//! method with Mehrotra's predictor-corrector whose Newton systems are solved
//! by a backward Riccati recursion and a forward sweep (Rao, Wright and
//! Rawlings 1998; the factorised form follows HPIPM). Cost per iteration is
//! linear in the horizon `N` and cubic only in the stage size `nx + nu`.
//!
//! Inequalities, each `c(z) >= 0` with a slack `t >= 0` and a multiplier
//! `lam >= 0` (per stage, in this order):
//!
//! ```text
//! u - u_lower >= 0,  u_upper - u >= 0,                 (k < N, finite bounds)
//! x + s - x_lower >= 0,  x_upper + s - x >= 0,  s >= 0  (k >= 1, soft components)
//! ```
//!
//! The soft slacks `s` are eliminated stage-wise (they are coupled to one
//! state component only), so the Riccati recursion sees `nx x nx` and
//! `nu x nu` blocks only. A component is soft when it has a finite bound and a
//! positive L1 or L2 weight; a bound whose weights are both zero costs nothing
//! to violate and is ignored (as in the [`kkt`](super::kkt) checker).
//!
//! The per-stage matrix `M_k = [R S; S' Q] + [B A]' P_{k+1} [B A]` is factored
//! by one Cholesky factorisation whose trailing block is the factor of the
//! next cost-to-go `P_k = L_k L_k'` (the square-root Riccati recursion), so
//! `P` is never formed. Tiny or negative control pivots are lifted (static
//! regularisation, counted in [`RiccatiInfo::regularised_pivots`]); zero
//! state pivots (a semidefinite `Q`) are truncated, which is exact for a
//! positive-semidefinite block.
//!
//! Everything is sized at creation; `solve` does not touch the heap. The
//! inner kernels are generic over the stage dimensions, and the common chain
//! sizes (the joint-count table) get compile-time dimensions so the loops
//! unroll.
//!
//! Files: this one has the settings, the report and the solver;
//! `dims.rs` the stage sizes and slot layout, `workspace.rs` the
//! preallocated iterate, `engine.rs` which core runs, `checks.rs` the input
//! and output checks, `ipm.rs` the run-time-sized interior point and Riccati
//! recursion, `cholesky.rs` the stage factorisation, `fixed.rs` the
//! compile-time-sized cores (and their active-set start).

use super::{AnyStageQp, OcpQp, QpSolution, QpSolver, QpStatus, StageQp};

mod checks;
mod cholesky;
mod dims;
mod engine;
mod fixed;
mod ipm;
mod workspace;

use checks::*;
use cholesky::cholesky;
use dims::{Dims, Runtime, Slots};
use engine::Engine;
use fixed::FixedCore;
use ipm::*;
use workspace::Workspace;

/// Settings of [`RiccatiSolver`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RiccatiSettings {
    /// Infinity-norm tolerance on the stationarity residual.
    pub tol_stationarity: f64,
    /// Infinity-norm tolerance on the dynamics and inequality residuals.
    pub tol_feasibility: f64,
    /// Tolerance on the largest complementarity product `t_i lam_i`.
    pub tol_complementarity: f64,
    /// Tolerance for [`QpStatus::AlmostSolved`] when the iteration stops early.
    pub reduced_tol: f64,
    /// Iteration limit.
    pub max_iterations: usize,
    /// Fraction of the step to the boundary of `t, lam >= 0` that is taken.
    pub fraction_to_boundary: f64,
    /// A Cholesky pivot at most this times its diagonal entry counts as zero.
    pub pivot_tolerance: f64,
    /// Lift of a zero control pivot, relative to the largest diagonal entry
    /// of the stage matrix.
    pub regularisation: f64,
    /// Lower bound of the initial inequality slacks.
    pub initial_slack: f64,
    /// Initial multipliers are this times `max(1, |q|, |r|) / t`.
    pub initial_multiplier: f64,
    /// Relative stationarity tolerance: the residual may also be this times
    /// the largest term of the stationarity sums (round-off floor when the
    /// costate is large).
    pub tol_stationarity_relative: f64,
    /// Start from Mehrotra's point (one Newton step from the plain start,
    /// then shifted into the interior; counted as an iteration). Fewer
    /// iterations and no stalls on long horizons with unstable
    /// linearisations; `false` keeps the plain start. Not used after a warm
    /// start (see [`RiccatiSettings::warm_start`]).
    pub mehrotra_start: bool,
    /// After [`QpSolver::shift_warm_start`] (the controller calls it at each
    /// RTI shift), start from the shifted previous dynamics and bound
    /// multipliers instead of the cold multipliers. Measured on the paper's
    /// closed loops at N = 80: median iterations 12 -> 7 (curved) and
    /// 10 -> 6 (straight), see docs/results.md.
    pub warm_start: bool,
    /// Floor of the warm-started slacks and multipliers: the previous
    /// solution sits on the boundary (products ~1e-11), where the Newton
    /// steps would be cut to nothing; 1e-2 measured best of 1e-1..1e-4.
    pub warm_start_floor: f64,
    /// Before the interior point, guess which control bounds are active (the
    /// previous solution's, shifted by one stage; none after a cold start),
    /// fix those controls at their bounds and solve the rest exactly by one
    /// Riccati recursion; the guess is the QP's optimum when the free
    /// controls are within their bounds and the fixed ones have multipliers
    /// of the right sign, else a primal-dual active-set step makes the next
    /// guess (at most [`RiccatiSettings::active_set_guesses`]). RTI on an
    /// eigenmode runs torque-free, far from the bounds, so one recursion
    /// with nothing fixed solves most samples (the inactive-set start); in
    /// the torque-limited climb the saturated stages move little between
    /// samples. When no guess is right the interior point runs from its
    /// untouched warm start. Only the compile-time-sized cores (1-3 joints)
    /// without soft state bounds take this path (issue 12).
    pub active_set_start: bool,
    /// Most guesses of the active-set start before the interior point takes
    /// over.
    pub active_set_guesses: usize,
}

impl Default for RiccatiSettings {
    fn default() -> Self {
        Self {
            tol_stationarity: 1e-10,
            tol_feasibility: 1e-10,
            tol_complementarity: 1e-10,
            reduced_tol: 1e-6,
            max_iterations: 50,
            fraction_to_boundary: 0.995,
            pivot_tolerance: 1e-13,
            regularisation: 1e-11,
            initial_slack: 1.0,
            initial_multiplier: 1.0,
            tol_stationarity_relative: 1e-14,
            mehrotra_start: true,
            warm_start: true,
            warm_start_floor: 1e-2,
            active_set_start: true,
            active_set_guesses: 4,
        }
    }
}

/// What happened in the last [`RiccatiSolver::solve`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RiccatiInfo {
    /// Interior-point iterations, or the active-set start's guesses when
    /// it gave the solution.
    pub iterations: usize,
    /// The active-set start gave the solution (no interior point ran).
    pub active_set_start: bool,
    /// Control pivots lifted by regularisation over all factorisations of the
    /// solve (nonzero means an ill-conditioned or singular Hessian block).
    pub regularised_pivots: usize,
    /// State pivots truncated as zero (semidefinite `Q`; harmless).
    pub truncated_pivots: usize,
    /// Final stationarity residual (infinity norm).
    pub stationarity: f64,
    /// Final dynamics and inequality residual (infinity norm).
    pub feasibility: f64,
    /// Final largest complementarity product.
    pub complementarity: f64,
}

/// Riccati-based primal-dual interior-point solver for [`OcpQp`]s of fixed
/// dimensions `(nx, nu, N)`.
#[derive(Clone, Debug)]
pub struct RiccatiSolver {
    nx: usize,
    nu: usize,
    horizon: usize,
    /// Settings used by the next solve.
    pub settings: RiccatiSettings,
    info: RiccatiInfo,
    total_regularised: u64,
    engine: Engine,
    /// The next solve starts from the shifted last iterate.
    warm_next: bool,
}

impl RiccatiSolver {
    /// Allocates the solver for QPs with `nx` states, `nu` controls and
    /// horizon `horizon` (all at least 1).
    pub fn new(nx: usize, nu: usize, horizon: usize, settings: RiccatiSettings) -> Self {
        Self {
            nx,
            nu,
            horizon,
            settings,
            info: RiccatiInfo::default(),
            total_regularised: 0,
            warm_next: false,
            engine: Engine::new(nx, nu, horizon),
        }
    }

    /// Diagnostics of the last solve.
    pub fn info(&self) -> &RiccatiInfo {
        &self.info
    }

    /// Control pivots regularised since creation (a running count for logs:
    /// nonzero means some QP had an ill-conditioned control Hessian).
    pub fn total_regularised_pivots(&self) -> u64 {
        self.total_regularised
    }

    /// Dimensions `(nx, nu, N)` this solver was created for.
    pub fn dimensions(&self) -> (usize, usize, usize) {
        (self.nx, self.nu, self.horizon)
    }

    fn run(&mut self, qp: &OcpQp, sol: &mut QpSolution) -> QpStatus {
        let (nx, nu) = (self.nx, self.nu);
        let set = &self.settings;
        let (status, info) = match &mut self.engine {
            Engine::Runtime(ws) => {
                let mut core = Ipm {
                    qp,
                    ws,
                    set,
                    n: self.horizon,
                    d: Runtime { nx, nu },
                    info: RiccatiInfo::default(),
                    warm: self.warm_next,
                };
                (
                    interior_point(&mut core, set, self.warm_next, sol),
                    core.info,
                )
            }
            Engine::Fixed(core) => core.run(qp, set, self.warm_next, sol),
        };
        self.info = info;
        self.total_regularised += self.info.regularised_pivots as u64;
        status
    }
}

impl QpSolver for RiccatiSolver {
    fn name(&self) -> &'static str {
        "riccati"
    }

    fn last_solved_by_start(&self) -> Option<bool> {
        Some(self.info.active_set_start)
    }

    fn save_warm_start(&self) -> Vec<f64> {
        let mut out = vec![
            f64::from(u8::from(self.warm_next)),
            self.total_regularised as f64,
        ];
        match &self.engine {
            Engine::Runtime(ws) => {
                out.extend_from_slice(&ws.pi);
                out.extend_from_slice(&ws.lam);
            }
            Engine::Fixed(core) => core.save_multipliers(&mut out),
        }
        out
    }

    fn restore_warm_start(&mut self, saved: &[f64]) -> Result<(), String> {
        let fits = match saved {
            [warm, regularised, data @ ..]
                if (*warm == 0.0 || *warm == 1.0) && *regularised >= 0.0 =>
            {
                let ok = match &mut self.engine {
                    Engine::Runtime(ws) => {
                        let (np, nl) = (ws.pi.len(), ws.lam.len());
                        if data.len() == np + nl {
                            ws.pi.copy_from_slice(&data[..np]);
                            ws.lam.copy_from_slice(&data[np..]);
                            true
                        } else {
                            false
                        }
                    }
                    Engine::Fixed(core) => core.restore_multipliers(data),
                };
                if ok {
                    self.warm_next = *warm == 1.0;
                    self.total_regularised = *regularised as u64;
                }
                ok
            }
            _ => false,
        };
        if fits {
            Ok(())
        } else {
            Err(format!(
                "{} warm-start values do not fit the riccati solver for nx = {}, nu = {}, N = {}",
                saved.len(),
                self.nx,
                self.nu,
                self.horizon
            ))
        }
    }

    fn shift_warm_start(&mut self, previous_usable: bool) {
        let floor = self.settings.warm_start_floor;
        // A floor that is not positive would start on the boundary.
        self.warm_next =
            previous_usable && self.settings.warm_start && floor.is_finite() && floor > 0.0;
    }

    fn solve(&mut self, qp: &OcpQp, solution: &mut QpSolution) -> QpStatus {
        self.info = RiccatiInfo::default();
        // The compile-time-sized cores check the data while loading it.
        let runtime = matches!(self.engine, Engine::Runtime(_));
        let status = if !valid_dimensions(qp, self.nx, self.nu, self.horizon)
            || !valid_solution(solution, self.nx, self.nu, self.horizon)
            || (runtime && !valid_data(qp))
        {
            QpStatus::InvalidInput
        } else {
            self.run(qp, solution)
        };
        self.finish(status, solution)
    }

    fn solve_stages(
        &mut self,
        qp: &dyn AnyStageQp,
        scratch: &mut OcpQp,
        solution: &mut QpSolution,
    ) -> QpStatus {
        // The compile-time-sized core of these sizes reads the stages as
        // they are; any other core gets the converted QP.
        let typed = match &mut self.engine {
            Engine::Fixed(core) if qp.dimensions() == (self.nx, self.nu, self.horizon) => {
                if valid_solution(solution, self.nx, self.nu, self.horizon) {
                    self.info = RiccatiInfo::default();
                    core.run_stages(qp.as_any(), &self.settings, self.warm_next, solution)
                } else {
                    Some((QpStatus::InvalidInput, RiccatiInfo::default()))
                }
            }
            _ => None,
        };
        let Some((status, info)) = typed else {
            qp.write_ocp(scratch);
            return self.solve(scratch, solution);
        };
        self.info = info;
        self.total_regularised += self.info.regularised_pivots as u64;
        self.finish(status, solution)
    }
}

impl RiccatiSolver {
    /// The end of every solve: the warm start is used up, the status
    /// stored, and an invalid QP's solution marked as such.
    fn finish(&mut self, status: QpStatus, solution: &mut QpSolution) -> QpStatus {
        self.warm_next = false;
        solution.status = status;
        if status == QpStatus::InvalidInput {
            solution.iterations = 0;
            solution.objective = f64::NAN;
            solution.primal_residual = f64::INFINITY;
            solution.dual_residual = f64::INFINITY;
        }
        status
    }
}
