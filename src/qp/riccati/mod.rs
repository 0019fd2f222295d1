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
//! sizes (1-3 joints) get compile-time dimensions so the loops unroll.

use super::{OcpQp, QpSolution, QpSolver, QpStatus};

mod fixed;

use fixed::FixedCore;

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

/// Stage dimensions, either runtime values or compile-time constants (the
/// latter let the compiler unroll the small dense kernels).
trait Dims: Copy {
    fn nx(self) -> usize;
    fn nu(self) -> usize;
    #[inline(always)]
    fn nv(self) -> usize {
        self.nx() + self.nu()
    }
    /// Inequality slots per stage.
    #[inline(always)]
    fn m(self) -> usize {
        2 * self.nu() + 3 * self.nx()
    }
}

#[derive(Clone, Copy)]
struct Runtime {
    nx: usize,
    nu: usize,
}

impl Dims for Runtime {
    #[inline(always)]
    fn nx(self) -> usize {
        self.nx
    }
    #[inline(always)]
    fn nu(self) -> usize {
        self.nu
    }
}

/// Flat, preallocated iterate and workspace (stage-major).
#[derive(Clone, Debug)]
struct Workspace {
    // Iterate.
    x: Vec<f64>,
    u: Vec<f64>,
    s: Vec<f64>,
    pi: Vec<f64>,
    t: Vec<f64>,
    lam: Vec<f64>,
    /// Which inequality slots exist for the current data.
    on: Vec<bool>,
    /// Which state components carry a soft bound.
    soft: Vec<bool>,
    // Residuals.
    rx: Vec<f64>,
    ru: Vec<f64>,
    rs: Vec<f64>,
    re: Vec<f64>,
    rp: Vec<f64>,
    /// Complementarity right-hand side (`t lam`, then the corrector's).
    rc: Vec<f64>,
    // Stage-wise elimination of the slacks and of the inequalities.
    diag_u: Vec<f64>,
    diag_x: Vec<f64>,
    cross: Vec<f64>,
    hss: Vec<f64>,
    /// `2 Sigma_u + h` and `2 Sigma_l + h`: the slack-bound rows' direction
    /// `dx + ds` and `ds - dx` without cancellation.
    coef_l: Vec<f64>,
    coef_u: Vec<f64>,
    gx: Vec<f64>,
    gu: Vec<f64>,
    gs: Vec<f64>,
    // Riccati factors: per stage the lower Cholesky factor of M_k (u first).
    lm: Vec<f64>,
    inv_diag: Vec<f64>,
    p: Vec<f64>,
    yu: Vec<f64>,
    bal: Vec<f64>,
    tmp_v: Vec<f64>,
    tmp_w: Vec<f64>,
    tmp_g: Vec<f64>,
    // Newton direction.
    dx: Vec<f64>,
    du: Vec<f64>,
    ds: Vec<f64>,
    dpi: Vec<f64>,
    dt: Vec<f64>,
    dlam: Vec<f64>,
}

impl Workspace {
    fn new(nx: usize, nu: usize, n: usize) -> Self {
        let nv = nx + nu;
        let m = 2 * nu + 3 * nx;
        let z = |len: usize| vec![0.0; len];
        Self {
            x: z((n + 1) * nx),
            u: z(n * nu),
            s: z((n + 1) * nx),
            pi: z(n * nx),
            t: z((n + 1) * m),
            lam: z((n + 1) * m),
            on: vec![false; (n + 1) * m],
            soft: vec![false; (n + 1) * nx],
            rx: z((n + 1) * nx),
            ru: z(n * nu),
            rs: z((n + 1) * nx),
            re: z(n * nx),
            rp: z((n + 1) * m),
            rc: z((n + 1) * m),
            diag_u: z(n * nu),
            diag_x: z((n + 1) * nx),
            cross: z((n + 1) * nx),
            hss: z((n + 1) * nx),
            coef_l: z((n + 1) * nx),
            coef_u: z((n + 1) * nx),
            gx: z((n + 1) * nx),
            gu: z(n * nu),
            gs: z((n + 1) * nx),
            lm: z((n + 1) * nv * nv),
            inv_diag: z((n + 1) * nv),
            p: z((n + 1) * nx),
            yu: z(n * nu),
            bal: z(nv * nx),
            tmp_v: z(nx),
            tmp_w: z(nx),
            tmp_g: z(nv),
            dx: z((n + 1) * nx),
            du: z(n * nu),
            ds: z((n + 1) * nx),
            dpi: z(n * nx),
            dt: z((n + 1) * m),
            dlam: z((n + 1) * m),
        }
    }
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

/// The core for the solver's dimensions: compile-time-sized for the chains
/// of the joint-count table (`nx = 2 nu`, `nu` = 1 .. 6, see
/// [`crate::joints`]), runtime-sized otherwise.
#[derive(Debug)]
enum Engine {
    Runtime(Box<Workspace>),
    Fixed(Box<dyn FixedEngine>),
}

impl Clone for Engine {
    fn clone(&self) -> Self {
        match self {
            Engine::Runtime(ws) => Engine::Runtime(ws.clone()),
            Engine::Fixed(core) => Engine::Fixed(core.boxed_clone()),
        }
    }
}

impl Engine {
    fn new(nx: usize, nu: usize, horizon: usize) -> Self {
        let runtime = || Engine::Runtime(Box::new(Workspace::new(nx, nu, horizon)));
        crate::with_joint_count!(
            nu,
            |N, S, NP| if nx == S {
                // Slots per stage: 2 nu input bounds, 3 nx state rows.
                Engine::Fixed(Box::new(FixedCore::<S, N, { 2 * N + 3 * S }>::new(
                    horizon,
                )))
            } else {
                runtime()
            },
            otherwise runtime()
        )
    }
}

/// A compile-time-sized core behind one interface (one virtual call per
/// solve), so that its sizes come from the joint-count table.
trait FixedEngine: std::fmt::Debug + Send + Sync {
    fn run(
        &mut self,
        qp: &OcpQp,
        set: &RiccatiSettings,
        warm: bool,
        sol: &mut QpSolution,
    ) -> (QpStatus, RiccatiInfo);
    fn save_multipliers(&self, out: &mut Vec<f64>);
    fn restore_multipliers(&mut self, data: &[f64]) -> bool;
    fn boxed_clone(&self) -> Box<dyn FixedEngine>;
}

impl<const NX: usize, const NU: usize, const M: usize> FixedEngine for FixedCore<NX, NU, M> {
    fn run(
        &mut self,
        qp: &OcpQp,
        set: &RiccatiSettings,
        warm: bool,
        sol: &mut QpSolution,
    ) -> (QpStatus, RiccatiInfo) {
        run_fixed(self, qp, set, warm, sol)
    }
    fn save_multipliers(&self, out: &mut Vec<f64>) {
        FixedCore::save_multipliers(self, out);
    }
    fn restore_multipliers(&mut self, data: &[f64]) -> bool {
        FixedCore::restore_multipliers(self, data)
    }
    fn boxed_clone(&self) -> Box<dyn FixedEngine> {
        Box::new(self.clone())
    }
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

/// One solve on a compile-time-sized core: the active-set start when it
/// applies, the interior point otherwise.
fn run_fixed<const NX: usize, const NU: usize, const M: usize>(
    core: &mut FixedCore<NX, NU, M>,
    qp: &OcpQp,
    set: &RiccatiSettings,
    warm: bool,
    sol: &mut QpSolution,
) -> (QpStatus, RiccatiInfo) {
    if !core.load(qp, set) {
        return (QpStatus::InvalidInput, core.info);
    }
    core.warm = warm;
    let status = match core.solve_active_set(sol) {
        Some(status) => status,
        None => interior_point(core, set, warm, sol),
    };
    (status, core.info)
}

impl QpSolver for RiccatiSolver {
    fn name(&self) -> &'static str {
        "riccati"
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

fn valid_dimensions(qp: &OcpQp, nx: usize, nu: usize, n: usize) -> bool {
    let mat = |m: &nalgebra::DMatrix<f64>, r, c| m.nrows() == r && m.ncols() == c;
    let vecs = |v: &[nalgebra::DVector<f64>], len, count| {
        v.len() == count && v.iter().all(|x| x.len() == len)
    };
    qp.nx == nx
        && qp.nu == nu
        && qp.horizon == n
        && n >= 1
        && nx >= 1
        && nu >= 1
        && qp.q.len() == n + 1
        && qp.q.iter().all(|m| mat(m, nx, nx))
        && qp.s.len() == n
        && qp.s.iter().all(|m| mat(m, nu, nx))
        && qp.r.len() == n
        && qp.r.iter().all(|m| mat(m, nu, nu))
        && qp.a.len() == n
        && qp.a.iter().all(|m| mat(m, nx, nx))
        && qp.b.len() == n
        && qp.b.iter().all(|m| mat(m, nx, nu))
        && vecs(&qp.q_lin, nx, n + 1)
        && vecs(&qp.r_lin, nu, n)
        && vecs(&qp.c, nx, n)
        && vecs(&qp.u_lower, nu, n)
        && vecs(&qp.u_upper, nu, n)
        && vecs(&qp.x_lower, nx, n + 1)
        && vecs(&qp.x_upper, nx, n + 1)
        && qp.x0.len() == nx
        && qp.soft_l1.len() == nx
        && qp.soft_l2.len() == nx
}

fn valid_solution(sol: &QpSolution, nx: usize, nu: usize, n: usize) -> bool {
    let vecs = |v: &[nalgebra::DVector<f64>], len, count| {
        v.len() == count && v.iter().all(|x| x.len() == len)
    };
    vecs(&sol.x, nx, n + 1)
        && vecs(&sol.u, nu, n)
        && vecs(&sol.pi, nx, n)
        && vecs(&sol.lam_u_lower, nu, n)
        && vecs(&sol.lam_u_upper, nu, n)
}

/// Largest asymmetry of a Hessian block accepted, relative to its largest
/// entry (the solver reads the lower triangles).
const SYMMETRY_TOLERANCE: f64 = 1e-10;

/// A lower bound may be `-inf` (none), not NaN or `+inf`.
fn lower_bound_ok(l: f64) -> bool {
    !l.is_nan() && l != f64::INFINITY
}

/// An upper bound may be `+inf` (none), not NaN or `-inf`.
fn upper_bound_ok(u: f64) -> bool {
    !u.is_nan() && u != f64::NEG_INFINITY
}

/// Finite data, consistent bounds, nonnegative penalties and symmetric
/// Hessian blocks (the solver reads their lower triangles).
fn valid_data(qp: &OcpQp) -> bool {
    // It runs on every solve: four independent lanes instead of one serial
    // chain of dependent operations (and no early exits that block it).
    let finite = |s: &[f64]| {
        // v * 0 is 0 for finite v and NaN otherwise.
        let mut lanes = [0.0; 4];
        let chunks = s.chunks_exact(4);
        let rest = chunks.remainder();
        for c in chunks {
            for (l, v) in lanes.iter_mut().zip(c) {
                *l += v * 0.0;
            }
        }
        for (l, v) in lanes.iter_mut().zip(rest) {
            *l += v * 0.0;
        }
        lanes.iter().sum::<f64>() == 0.0
    };
    let symmetric = |m: &nalgebra::DMatrix<f64>| {
        let n = m.nrows();
        let v = m.as_slice();
        let (mut scale, mut asym) = ([0.0f64; 4], [0.0f64; 4]);
        for (i, &x) in v.iter().enumerate() {
            scale[i % 4] = scale[i % 4].max(x.abs());
        }
        for i in 0..n {
            for j in 0..i {
                asym[j % 4] = asym[j % 4].max((v[i + j * n] - v[j + i * n]).abs());
            }
        }
        let max = |l: [f64; 4]| l[0].max(l[1]).max(l[2].max(l[3]));
        max(asym) <= SYMMETRY_TOLERANCE * max(scale)
    };
    let mats = [&qp.q, &qp.s, &qp.r, &qp.a, &qp.b];
    if !mats.iter().all(|v| v.iter().all(|m| finite(m.as_slice()))) {
        return false;
    }
    let vecs = [&qp.q_lin, &qp.r_lin, &qp.c];
    if !vecs.iter().all(|v| v.iter().all(|x| finite(x.as_slice()))) {
        return false;
    }
    if !finite(qp.x0.as_slice()) || !finite(qp.soft_l1.as_slice()) || !finite(qp.soft_l2.as_slice())
    {
        return false;
    }
    if qp.soft_l1.iter().chain(qp.soft_l2.iter()).any(|&w| w < 0.0) {
        return false;
    }
    if !qp.q.iter().chain(qp.r.iter()).all(symmetric) {
        return false;
    }
    let u_ok = qp.u_lower.iter().zip(&qp.u_upper).all(|(l, u)| {
        l.iter()
            .zip(u.iter())
            .all(|(&l, &u)| lower_bound_ok(l) && upper_bound_ok(u) && l <= u)
    });
    let x_ok = qp.x_lower.iter().zip(&qp.x_upper).all(|(l, u)| {
        l.iter()
            .zip(u.iter())
            .all(|(&l, &u)| lower_bound_ok(l) && upper_bound_ok(u))
    });
    u_ok && x_ok
}

/// One solve: borrows the data, the workspace and the settings.
struct Ipm<'a> {
    qp: &'a OcpQp,
    ws: &'a mut Workspace,
    set: &'a RiccatiSettings,
    n: usize,
    d: Runtime,
    info: RiccatiInfo,
    /// Start from the shifted last multipliers.
    warm: bool,
}

/// Slot offsets inside a stage's inequality block.
#[derive(Clone, Copy)]
struct Slots {
    ul: usize,
    uu: usize,
    xl: usize,
    xu: usize,
    sl: usize,
}

impl Slots {
    #[inline(always)]
    fn of<D: Dims>(d: D) -> Self {
        let (nx, nu) = (d.nx(), d.nu());
        Self {
            ul: 0,
            uu: nu,
            xl: 2 * nu,
            xu: 2 * nu + nx,
            sl: 2 * nu + 2 * nx,
        }
    }
}

/// Norms of the current residuals.
#[derive(Clone, Copy)]
struct Residuals {
    stationarity: f64,
    /// Largest term of the stationarity sums (its round-off scale).
    scale: f64,
    feasibility: f64,
    complementarity: f64,
    mu: f64,
}

/// The steps of one interior-point solve, implemented by the runtime-size
/// and the compile-time-size cores; the iteration itself is
/// [`interior_point`].
trait Core {
    /// Diagnostics of the solve (pivot counts are added by `factor`).
    fn info_mut(&mut self) -> &mut RiccatiInfo;
    /// Starting point.
    fn initialise(&mut self);
    /// Residuals of the current iterate (stored for the Newton systems).
    fn residuals(&mut self) -> Residuals;
    /// Eliminates the inequalities and factors the Riccati recursion.
    fn factor(&mut self);
    /// Predictor right-hand side; returns the number of inequalities.
    fn prepare_affine(&mut self) -> usize;
    /// Corrector right-hand side with centring target `sigma_mu`.
    fn prepare_corrector(&mut self, sigma_mu: f64);
    /// Newton direction for the current right-hand side and factors.
    fn newton_direction(&mut self);
    /// Largest step in (0, 1] keeping `t, lam >= (1 - fraction) * current`.
    fn max_step(&self, fraction: f64) -> f64;
    /// Duality gap after a step `alpha`.
    fn gap_after(&self, alpha: f64) -> f64;
    /// Moves the iterate by `alpha` times the direction.
    fn take_step(&mut self, alpha: f64);
    /// Copies the iterate out and evaluates the objective.
    fn write_solution(&self, sol: &mut QpSolution);
    /// Moves the slacks and multipliers of the existing inequalities back
    /// into the interior after the starting Newton step: `v <- max(v, 0) +
    /// shift` (see [`StartShift`]).
    fn recentre(&mut self, shift: &StartShift);
    /// Sums over the existing inequalities: (min t, min lam, t'lam, sum t,
    /// sum lam).
    fn slot_sums(&self) -> (f64, f64, f64, f64, f64);
}

/// Uniform shifts of the starting slacks and multipliers (Mehrotra 1992,
/// as in OOQP): first enough to make them positive, then half the average
/// complementarity so that no product starts far from the others.
#[derive(Clone, Copy, Debug)]
struct StartShift {
    t: f64,
    lam: f64,
}

/// Mehrotra predictor-corrector iteration on any [`Core`]; `warm` tells
/// that the core starts from the shifted previous multipliers.
fn interior_point<C: Core>(
    core: &mut C,
    set: &RiccatiSettings,
    warm: bool,
    sol: &mut QpSolution,
) -> QpStatus {
    core.initialise();
    let mut status = QpStatus::MaxIterations;
    let mut res = core.residuals();
    let mut iterations = 0;
    // A warm start already has multipliers on the costate's scale: the
    // starting Newton step would only cost an iteration (RTI closed loops
    // at N = 80: 6.8-7.2 -> 6.4-6.5 iterations a QP).
    if set.mehrotra_start
        && !warm
        && res.stationarity.is_finite()
        && res.feasibility.is_finite()
        && set.max_iterations > 0
    {
        // Mehrotra's starting point: one full Newton (affine-scaling) step
        // makes the equalities hold and gives the multipliers the scale of
        // the costate (|pi| ~ 1e7 on unstable linearisations, where a
        // start on the scale of the cost gradient stalls); the slacks and
        // multipliers are then shifted back into the interior.
        iterations += 1;
        core.factor();
        core.prepare_affine();
        core.newton_direction();
        core.take_step(1.0);
        let (min_t, min_lam, _, _, _) = core.slot_sums();
        let shift = StartShift {
            t: (-1.5 * min_t).max(0.0),
            lam: (-1.5 * min_lam).max(0.0),
        };
        core.recentre(&shift);
        let (_, _, tl, sum_t, sum_lam) = core.slot_sums();
        if sum_t > 0.0 && sum_lam > 0.0 {
            core.recentre(&StartShift {
                t: 0.5 * tl / sum_lam,
                lam: 0.5 * tl / sum_t,
            });
        }
        res = core.residuals();
    }
    loop {
        if !(res.stationarity.is_finite() && res.feasibility.is_finite() && res.mu.is_finite()) {
            status = QpStatus::NumericalError;
            break;
        }
        let tol_stat = set
            .tol_stationarity
            .max(set.tol_stationarity_relative * res.scale);
        if res.stationarity <= tol_stat
            && res.feasibility <= set.tol_feasibility
            && res.complementarity <= set.tol_complementarity
        {
            status = QpStatus::Solved;
            break;
        }
        if iterations >= set.max_iterations {
            break;
        }
        iterations += 1;
        core.factor();
        // Predictor (affine-scaling) direction.
        let m_on = core.prepare_affine();
        core.newton_direction();
        let alpha_aff = core.max_step(1.0);
        let mut alpha = alpha_aff;
        if m_on > 0 {
            // Corrector with centring: sigma from the predicted gap.
            let mu_aff = core.gap_after(alpha_aff) / m_on as f64;
            let sigma = if res.mu > 0.0 {
                (mu_aff / res.mu).clamp(0.0, 1.0).powi(3)
            } else {
                0.0
            };
            // The centring target never goes far below the tolerance:
            // smaller t_i only makes the Newton systems ill-conditioned.
            let target = (sigma * res.mu).max(0.1 * set.tol_complementarity);
            core.prepare_corrector(target);
            core.newton_direction();
            alpha = core.max_step(set.fraction_to_boundary);
        }
        if !(alpha.is_finite() && alpha > 0.0) {
            status = QpStatus::NumericalError;
            break;
        }
        core.take_step(alpha);
        res = core.residuals();
    }
    if status == QpStatus::MaxIterations
        && res.stationarity <= set.reduced_tol
        && res.feasibility <= set.reduced_tol
        && res.complementarity <= set.reduced_tol
    {
        status = QpStatus::AlmostSolved;
    }
    core.info_mut().iterations = iterations;
    core.info_mut().stationarity = res.stationarity;
    core.info_mut().feasibility = res.feasibility;
    core.info_mut().complementarity = res.complementarity;
    core.write_solution(sol);
    sol.iterations = iterations;
    sol.primal_residual = res.feasibility;
    sol.dual_residual = res.stationarity;
    sol.status = status;
    status
}

impl Core for Ipm<'_> {
    fn info_mut(&mut self) -> &mut RiccatiInfo {
        &mut self.info
    }
    fn initialise(&mut self) {
        Ipm::initialise(self, self.d)
    }
    fn residuals(&mut self) -> Residuals {
        Ipm::residuals(self, self.d)
    }
    fn factor(&mut self) {
        Ipm::factor(self, self.d)
    }
    fn prepare_affine(&mut self) -> usize {
        Ipm::prepare_affine(self, self.d)
    }
    fn prepare_corrector(&mut self, sigma_mu: f64) {
        Ipm::prepare_corrector(self, self.d, sigma_mu)
    }
    fn newton_direction(&mut self) {
        Ipm::newton_direction(self, self.d)
    }
    fn max_step(&self, fraction: f64) -> f64 {
        Ipm::max_step(self, self.d, fraction)
    }
    fn gap_after(&self, alpha: f64) -> f64 {
        Ipm::gap_after(self, self.d, alpha)
    }
    fn take_step(&mut self, alpha: f64) {
        Ipm::take_step(self, self.d, alpha)
    }
    fn write_solution(&self, sol: &mut QpSolution) {
        Ipm::write_solution(self, self.d, sol)
    }
    fn recentre(&mut self, shift: &StartShift) {
        let ws = &mut *self.ws;
        for idx in 0..ws.t.len() {
            if ws.on[idx] {
                ws.t[idx] = recentred(ws.t[idx], shift.t);
                ws.lam[idx] = recentred(ws.lam[idx], shift.lam);
            }
        }
    }
    fn slot_sums(&self) -> (f64, f64, f64, f64, f64) {
        let ws = &*self.ws;
        let mut sums = (f64::INFINITY, f64::INFINITY, 0.0, 0.0, 0.0);
        for idx in 0..ws.t.len() {
            if ws.on[idx] {
                sums = add_slot(sums, ws.t[idx], ws.lam[idx]);
            }
        }
        sums
    }
}

/// `max(v, 0) + shift`.
fn recentred(v: f64, shift: f64) -> f64 {
    v.max(0.0) + shift
}

/// Accumulates one slot into [`Core::slot_sums`].
fn add_slot(s: (f64, f64, f64, f64, f64), t: f64, lam: f64) -> (f64, f64, f64, f64, f64) {
    (s.0.min(t), s.1.min(lam), s.2 + t * lam, s.3 + t, s.4 + lam)
}

impl Ipm<'_> {
    /// Marks the existing inequalities and sets a primal point (controls
    /// inside their box, states simulated, slacks covering the violations)
    /// with slacks and multipliers bounded away from zero.
    fn initialise<D: Dims>(&mut self, d: D) {
        let (nx, nu, m, n) = (d.nx(), d.nu(), d.m(), self.n);
        let sl = Slots::of(d);
        let qp = self.qp;
        let ws = &mut *self.ws;
        let t0 = self.set.initial_slack;
        // Multipliers on the scale of the cost gradient: too small ones let
        // the first steps run far out of the box and stall.
        let mut lam0 = 1.0f64;
        for v in qp.r_lin.iter().chain(&qp.q_lin) {
            lam0 = lam0.max(v.amax());
        }
        lam0 *= self.set.initial_multiplier;
        ws.on.fill(false);
        ws.soft.fill(false);
        ws.s.fill(0.0);
        let (warm, floor) = (self.warm, self.set.warm_start_floor);
        if warm {
            // RTI: the new QP is the previous one shifted by one stage.
            ws.pi.copy_within(nx.., 0);
            ws.lam.copy_within(m.., 0);
        } else {
            ws.pi.fill(0.0);
        }
        ws.x[..nx].copy_from_slice(qp.x0.as_slice());
        for k in 0..n {
            let (lb, ub) = (qp.u_lower[k].as_slice(), qp.u_upper[k].as_slice());
            for j in 0..nu {
                let (l, h) = (lb[j], ub[j]);
                ws.on[k * m + sl.ul + j] = l.is_finite();
                ws.on[k * m + sl.uu + j] = h.is_finite();
                ws.u[k * nu + j] = match (l.is_finite(), h.is_finite()) {
                    (true, true) => 0.5 * (l + h),
                    (true, false) => l.max(0.0),
                    (false, true) => h.min(0.0),
                    (false, false) => 0.0,
                };
            }
            // Simulate so the dynamics hold at the start.
            let (a, b, c) = (qp.a[k].as_slice(), qp.b[k].as_slice(), qp.c[k].as_slice());
            let (xk, xn) = ws.x.split_at_mut((k + 1) * nx);
            let xk = &xk[k * nx..];
            let xn = &mut xn[..nx];
            let uk = &ws.u[k * nu..(k + 1) * nu];
            for i in 0..nx {
                let mut v = c[i];
                for j in 0..nx {
                    v += a[i + j * nx] * xk[j];
                }
                for j in 0..nu {
                    v += b[i + j * nx] * uk[j];
                }
                xn[i] = v;
            }
        }
        for k in 1..=n {
            let (xl, xu) = (qp.x_lower[k].as_slice(), qp.x_upper[k].as_slice());
            for i in 0..nx {
                let weighted = qp.soft_l1[i] > 0.0 || qp.soft_l2[i] > 0.0;
                let (lo, hi) = (xl[i].is_finite(), xu[i].is_finite());
                if weighted && (lo || hi) {
                    ws.soft[k * nx + i] = true;
                    ws.on[k * m + sl.xl + i] = lo;
                    ws.on[k * m + sl.xu + i] = hi;
                    ws.on[k * m + sl.sl + i] = true;
                    let xv = ws.x[k * nx + i];
                    let mut viol = 0.0f64;
                    if lo {
                        viol = viol.max(xl[i] - xv);
                    }
                    if hi {
                        viol = viol.max(xv - xu[i]);
                    }
                    ws.s[k * nx + i] = viol + t0;
                }
            }
        }
        // Slacks of the inequalities: the constraint value, at least t0.
        for k in 0..=n {
            for i in 0..m {
                let idx = k * m + i;
                if ws.on[idx] && warm {
                    ws.t[idx] = constraint_value(d, qp, ws, k, i).max(floor);
                    ws.lam[idx] = ws.lam[idx].max(floor);
                } else if ws.on[idx] {
                    let c = constraint_value(d, qp, ws, k, i);
                    ws.t[idx] = c.max(t0);
                    ws.lam[idx] = lam0 / ws.t[idx];
                } else {
                    ws.t[idx] = 1.0;
                    ws.lam[idx] = 0.0;
                }
            }
        }
    }

    /// Computes all residuals of the current iterate into the workspace.
    fn residuals<D: Dims>(&mut self, d: D) -> Residuals {
        let (nx, nu, m, n) = (d.nx(), d.nu(), d.m(), self.n);
        let sl = Slots::of(d);
        let qp = self.qp;
        let ws = &mut *self.ws;
        let mut stat = 0.0f64;
        let mut scale = 0.0f64;
        let mut feas = 0.0f64;
        // Controls and dynamics.
        for k in 0..n {
            let (rm, sm, bm, am) = (
                qp.r[k].as_slice(),
                qp.s[k].as_slice(),
                qp.b[k].as_slice(),
                qp.a[k].as_slice(),
            );
            let (xk, uk, pik) = (
                &ws.x[k * nx..(k + 1) * nx],
                &ws.u[k * nu..(k + 1) * nu],
                &ws.pi[k * nx..(k + 1) * nx],
            );
            let rl = qp.r_lin[k].as_slice();
            for j in 0..nu {
                let mut h = 0.0;
                for i in 0..nu {
                    h += rm[j + i * nu] * uk[i];
                }
                for i in 0..nx {
                    h += sm[j + i * nu] * xk[i];
                }
                let mut e = 0.0;
                for i in 0..nx {
                    e += bm[i + j * nx] * pik[i];
                }
                let (ll, lu) = (ws.lam[k * m + sl.ul + j], ws.lam[k * m + sl.uu + j]);
                let v = rl[j] + h + e - ll + lu;
                scale = scale.max(rl[j].abs().max(h.abs()).max(e.abs()).max(ll.max(lu)));
                ws.ru[k * nu + j] = v;
                stat = stat.max(v.abs());
            }
            let c = qp.c[k].as_slice();
            let xn = &ws.x[(k + 1) * nx..(k + 2) * nx];
            for i in 0..nx {
                let mut v = c[i] - xn[i];
                for j in 0..nx {
                    v += am[i + j * nx] * xk[j];
                }
                for j in 0..nu {
                    v += bm[i + j * nx] * uk[j];
                }
                ws.re[k * nx + i] = v;
                feas = feas.max(v.abs());
            }
        }
        // States and slacks (x_0 is fixed: its row is not a condition).
        for k in 1..=n {
            let qm = qp.q[k].as_slice();
            let ql = qp.q_lin[k].as_slice();
            let xk = &ws.x[k * nx..(k + 1) * nx];
            for i in 0..nx {
                let mut h = 0.0;
                for j in 0..nx {
                    h += qm[i + j * nx] * xk[j];
                }
                let mut e = 0.0;
                if k < n {
                    let sm = qp.s[k].as_slice();
                    let am = qp.a[k].as_slice();
                    let uk = &ws.u[k * nu..(k + 1) * nu];
                    let pik = &ws.pi[k * nx..(k + 1) * nx];
                    for j in 0..nu {
                        h += sm[j + i * nu] * uk[j];
                    }
                    for j in 0..nx {
                        e += am[j + i * nx] * pik[j];
                    }
                }
                let prev = ws.pi[(k - 1) * nx + i];
                let (ll, lu) = (ws.lam[k * m + sl.xl + i], ws.lam[k * m + sl.xu + i]);
                let v = ql[i] + h + e - prev - ll + lu;
                scale = scale.max(
                    ql[i]
                        .abs()
                        .max(h.abs())
                        .max(e.abs())
                        .max(prev.abs())
                        .max(ll.max(lu)),
                );
                ws.rx[k * nx + i] = v;
                stat = stat.max(v.abs());
                if ws.soft[k * nx + i] {
                    let w = qp.soft_l1[i] + qp.soft_l2[i] * ws.s[k * nx + i]
                        - ws.lam[k * m + sl.xl + i]
                        - ws.lam[k * m + sl.xu + i]
                        - ws.lam[k * m + sl.sl + i];
                    ws.rs[k * nx + i] = w;
                    stat = stat.max(w.abs());
                } else {
                    ws.rs[k * nx + i] = 0.0;
                }
            }
        }
        // Inequalities.
        let mut gap = 0.0;
        let mut comp = 0.0f64;
        let mut count = 0usize;
        for k in 0..=n {
            for i in 0..m {
                let idx = k * m + i;
                if ws.on[idx] {
                    let r = constraint_value(d, qp, ws, k, i) - ws.t[idx];
                    ws.rp[idx] = r;
                    feas = feas.max(r.abs());
                    let tl = ws.t[idx] * ws.lam[idx];
                    gap += tl;
                    comp = comp.max(tl);
                    count += 1;
                } else {
                    ws.rp[idx] = 0.0;
                }
            }
        }
        Residuals {
            stationarity: stat,
            scale,
            feasibility: feas,
            complementarity: comp,
            mu: if count > 0 { gap / count as f64 } else { 0.0 },
        }
    }

    /// Eliminates inequalities and slacks into the stage Hessians and
    /// factors the Riccati recursion (square-root form).
    fn factor<D: Dims>(&mut self, d: D) {
        let (nx, nu, nv, m, n) = (d.nx(), d.nu(), d.nv(), d.m(), self.n);
        let sl = Slots::of(d);
        let qp = self.qp;
        let set = self.set;
        let ws = &mut *self.ws;
        let sigma = |ws: &Workspace, idx: usize| {
            if ws.on[idx] {
                ws.lam[idx] / ws.t[idx]
            } else {
                0.0
            }
        };
        for k in 0..n {
            for j in 0..nu {
                let base = k * m;
                ws.diag_u[k * nu + j] = sigma(ws, base + sl.ul + j) + sigma(ws, base + sl.uu + j);
            }
        }
        for k in 1..=n {
            for i in 0..nx {
                let idx = k * nx + i;
                if ws.soft[idx] {
                    let base = k * m;
                    let a = sigma(ws, base + sl.xl + i);
                    let b = sigma(ws, base + sl.xu + i);
                    let h = qp.soft_l2[i] + sigma(ws, base + sl.sl + i);
                    let hss = a + b + h;
                    ws.hss[idx] = hss;
                    ws.cross[idx] = a - b;
                    ws.coef_l[idx] = 2.0 * b + h;
                    ws.coef_u[idx] = 2.0 * a + h;
                    // (a + b) - (a - b)^2 / (a + b + h) without cancellation.
                    ws.diag_x[idx] = (4.0 * a * b + (a + b) * h) / hss;
                } else {
                    ws.hss[idx] = 1.0;
                    ws.cross[idx] = 0.0;
                    ws.diag_x[idx] = 0.0;
                }
            }
        }
        let nn = nv * nv;
        let mut regularised = 0;
        let mut truncated = 0;
        // Terminal stage: factor Q_N + diag.
        {
            let lm = &mut ws.lm[n * nn..(n + 1) * nn];
            let qm = qp.q[n].as_slice();
            for j in 0..nx {
                for i in j..nx {
                    let mut v = qm[i + j * nx];
                    if i == j {
                        v += ws.diag_x[n * nx + i];
                    }
                    lm[(nu + i) + (nu + j) * nv] = v;
                }
            }
            let inv = &mut ws.inv_diag[n * nv..(n + 1) * nv];
            let (r, t) = cholesky(d, lm, inv, nu, nv, set);
            regularised += r;
            truncated += t;
        }
        for k in (0..n).rev() {
            let (head, tail) = ws.lm.split_at_mut((k + 1) * nn);
            let lnext = &tail[..nn];
            let lm = &mut head[k * nn..];
            let (am, bm) = (qp.a[k].as_slice(), qp.b[k].as_slice());
            // Rows of the stage matrix that are needed: all, but at k = 0
            // only the controls (x_0 is fixed).
            let rows = if k == 0 { nu } else { nv };
            // bal = [B A]' L_{k+1}  (rows x nx), L lower triangular.
            let bal = &mut ws.bal;
            for a in 0..rows {
                let col = |i: usize| {
                    if a < nu {
                        bm[i + a * nx]
                    } else {
                        am[i + (a - nu) * nx]
                    }
                };
                for c in 0..nx {
                    let mut v = 0.0;
                    for i in c..nx {
                        v += col(i) * lnext[(nu + i) + (nu + c) * nv];
                    }
                    bal[a + c * nv] = v;
                }
            }
            // M = [R S; S' Q] + diag + bal bal' (lower triangle).
            let (rm, sm, qm) = (qp.r[k].as_slice(), qp.s[k].as_slice(), qp.q[k].as_slice());
            for b in 0..rows {
                for a in b..rows {
                    let mut v = if a < nu {
                        rm[a + b * nu] + if a == b { ws.diag_u[k * nu + a] } else { 0.0 }
                    } else if b < nu {
                        sm[b + (a - nu) * nu]
                    } else {
                        qm[(a - nu) + (b - nu) * nx]
                            + if a == b {
                                ws.diag_x[k * nx + a - nu]
                            } else {
                                0.0
                            }
                    };
                    for c in 0..nx {
                        v += bal[a + c * nv] * bal[b + c * nv];
                    }
                    lm[a + b * nv] = v;
                }
            }
            let inv = &mut ws.inv_diag[k * nv..(k + 1) * nv];
            let (r, t) = cholesky(d, &mut lm[..nn], inv, 0, rows, set);
            regularised += r;
            truncated += t;
        }
        self.info.regularised_pivots += regularised;
        self.info.truncated_pivots += truncated;
    }

    /// Right-hand side of the predictor: complementarity `t lam`.
    fn prepare_affine<D: Dims>(&mut self, d: D) -> usize {
        let (m, n) = (d.m(), self.n);
        let ws = &mut *self.ws;
        let mut count = 0;
        for idx in 0..(n + 1) * m {
            if ws.on[idx] {
                ws.rc[idx] = ws.t[idx] * ws.lam[idx];
                count += 1;
            } else {
                ws.rc[idx] = 0.0;
            }
        }
        count
    }

    /// Right-hand side of the corrector: `t lam + dt_aff dlam_aff - sigma mu`.
    fn prepare_corrector<D: Dims>(&mut self, d: D, sigma_mu: f64) {
        let (m, n) = (d.m(), self.n);
        let ws = &mut *self.ws;
        for idx in 0..(n + 1) * m {
            if ws.on[idx] {
                ws.rc[idx] = ws.t[idx] * ws.lam[idx] + ws.dt[idx] * ws.dlam[idx] - sigma_mu;
            }
        }
    }

    /// Solves the Newton system for the current `rc` with the current
    /// factorisation: gradient assembly, backward and forward sweeps, and
    /// recovery of the slack and inequality directions.
    fn newton_direction<D: Dims>(&mut self, d: D) {
        let (nx, nu, nv, m, n) = (d.nx(), d.nu(), d.nv(), d.m(), self.n);
        let sl = Slots::of(d);
        let qp = self.qp;
        let ws = &mut *self.ws;
        // w_i = (rc_i + lam_i rp_i) / t_i enters the gradient through D'.
        let w = |ws: &Workspace, idx: usize| {
            if ws.on[idx] {
                (ws.rc[idx] + ws.lam[idx] * ws.rp[idx]) / ws.t[idx]
            } else {
                0.0
            }
        };
        for k in 0..n {
            for j in 0..nu {
                let base = k * m;
                ws.gu[k * nu + j] =
                    ws.ru[k * nu + j] + w(ws, base + sl.ul + j) - w(ws, base + sl.uu + j);
            }
        }
        for k in 1..=n {
            for i in 0..nx {
                let idx = k * nx + i;
                let base = k * m;
                let wl = w(ws, base + sl.xl + i);
                let wu = w(ws, base + sl.xu + i);
                let gx = ws.rx[idx] + wl - wu;
                if ws.soft[idx] {
                    let gs = ws.rs[idx] + wl + wu + w(ws, base + sl.sl + i);
                    ws.gs[idx] = gs;
                    ws.gx[idx] = gx - ws.cross[idx] * gs / ws.hss[idx];
                } else {
                    ws.gs[idx] = 0.0;
                    ws.gx[idx] = gx;
                }
            }
        }
        // Backward sweep: p_N = g_N; p_k = g_x - Lxu yu with g = [gu; gx] +
        // [B A]' (P_{k+1} c_k + p_{k+1}) and yu = Luu^{-1} g_u.
        let nn = nv * nv;
        ws.p[n * nx..(n + 1) * nx].copy_from_slice(&ws.gx[n * nx..(n + 1) * nx]);
        for k in (0..n).rev() {
            let lnext = &ws.lm[(k + 1) * nn..(k + 2) * nn];
            let ck = &ws.re[k * nx..(k + 1) * nx];
            // v = L (L' c) + p_{k+1}
            let tw = &mut ws.tmp_w;
            for c in 0..nx {
                let mut v = 0.0;
                for i in c..nx {
                    v += lnext[(nu + i) + (nu + c) * nv] * ck[i];
                }
                tw[c] = v;
            }
            let tv = &mut ws.tmp_v;
            for i in 0..nx {
                let mut v = ws.p[(k + 1) * nx + i];
                for c in 0..=i {
                    v += lnext[(nu + i) + (nu + c) * nv] * tw[c];
                }
                tv[i] = v;
            }
            let (am, bm) = (qp.a[k].as_slice(), qp.b[k].as_slice());
            let g = &mut ws.tmp_g;
            for j in 0..nu {
                let mut v = ws.gu[k * nu + j];
                for i in 0..nx {
                    v += bm[i + j * nx] * tv[i];
                }
                g[j] = v;
            }
            let lm = &ws.lm[k * nn..(k + 1) * nn];
            let inv = &ws.inv_diag[k * nv..(k + 1) * nv];
            // yu = Luu^{-1} g_u
            for j in 0..nu {
                let mut v = g[j];
                for c in 0..j {
                    v -= lm[j + c * nv] * ws.yu[k * nu + c];
                }
                ws.yu[k * nu + j] = v * inv[j];
            }
            if k > 0 {
                for i in 0..nx {
                    let mut v = ws.gx[k * nx + i];
                    for j in 0..nx {
                        v += am[j + i * nx] * tv[j];
                    }
                    for c in 0..nu {
                        v -= lm[(nu + i) + c * nv] * ws.yu[k * nu + c];
                    }
                    ws.p[k * nx + i] = v;
                }
            }
        }
        // Forward sweep.
        ws.dx[..nx].fill(0.0);
        for k in 0..n {
            let lm = &ws.lm[k * nn..(k + 1) * nn];
            let inv = &ws.inv_diag[k * nv..(k + 1) * nv];
            // du = -Luu^{-T} (Lxu' dx + yu)
            let (dxk, dxn) = ws.dx.split_at_mut((k + 1) * nx);
            let dxk = &dxk[k * nx..];
            let dxn = &mut dxn[..nx];
            let du = &mut ws.du[k * nu..(k + 1) * nu];
            for j in (0..nu).rev() {
                let mut v = ws.yu[k * nu + j];
                if k > 0 {
                    for i in 0..nx {
                        v += lm[(nu + i) + j * nv] * dxk[i];
                    }
                }
                for c in j + 1..nu {
                    v += lm[c + j * nv] * du[c];
                }
                du[j] = -v * inv[j];
            }
            let (am, bm) = (qp.a[k].as_slice(), qp.b[k].as_slice());
            let ck = &ws.re[k * nx..(k + 1) * nx];
            for i in 0..nx {
                let mut v = ck[i];
                for j in 0..nx {
                    v += am[i + j * nx] * dxk[j];
                }
                for j in 0..nu {
                    v += bm[i + j * nx] * du[j];
                }
                dxn[i] = v;
            }
            // dpi_k = L (L' dx_{k+1}) + p_{k+1}
            let lnext = &ws.lm[(k + 1) * nn..(k + 2) * nn];
            let tw = &mut ws.tmp_w;
            for c in 0..nx {
                let mut v = 0.0;
                for i in c..nx {
                    v += lnext[(nu + i) + (nu + c) * nv] * dxn[i];
                }
                tw[c] = v;
            }
            for i in 0..nx {
                let mut v = ws.p[(k + 1) * nx + i];
                for c in 0..=i {
                    v += lnext[(nu + i) + (nu + c) * nv] * tw[c];
                }
                ws.dpi[k * nx + i] = v;
            }
        }
        // Slack directions, then inequality slacks and multipliers.
        for k in 1..=n {
            for i in 0..nx {
                let idx = k * nx + i;
                ws.ds[idx] = if ws.soft[idx] {
                    -(ws.gs[idx] + ws.cross[idx] * ws.dx[idx]) / ws.hss[idx]
                } else {
                    0.0
                };
            }
        }
        for k in 0..=n {
            for i in 0..m {
                let idx = k * m + i;
                if !ws.on[idx] {
                    continue;
                }
                let dc = if i < sl.uu {
                    ws.du[k * nu + i]
                } else if i < sl.xl {
                    -ws.du[k * nu + i - sl.uu]
                } else if i < sl.xu {
                    // dx + ds, formed without cancelling the large terms
                    // of an active bound (it must be accurate relative to t).
                    let j = k * nx + i - sl.xl;
                    (ws.coef_l[j] * ws.dx[j] - ws.gs[j]) / ws.hss[j]
                } else if i < sl.sl {
                    let j = k * nx + i - sl.xu;
                    (-ws.coef_u[j] * ws.dx[j] - ws.gs[j]) / ws.hss[j]
                } else {
                    ws.ds[k * nx + i - sl.sl]
                };
                let dt = dc + ws.rp[idx];
                ws.dt[idx] = dt;
                ws.dlam[idx] = -(ws.rc[idx] + ws.lam[idx] * dt) / ws.t[idx];
            }
        }
    }

    /// Largest step in (0, 1] keeping `t, lam >= (1 - fraction) * current`.
    fn max_step<D: Dims>(&self, d: D, fraction: f64) -> f64 {
        let (m, n) = (d.m(), self.n);
        let ws = &*self.ws;
        let mut alpha = 1.0f64;
        for idx in 0..(n + 1) * m {
            if ws.on[idx] {
                if ws.dt[idx] < 0.0 {
                    alpha = alpha.min(-fraction * ws.t[idx] / ws.dt[idx]);
                }
                if ws.dlam[idx] < 0.0 {
                    alpha = alpha.min(-fraction * ws.lam[idx] / ws.dlam[idx]);
                }
            }
        }
        alpha
    }

    /// Duality gap `sum (t + alpha dt)(lam + alpha dlam)`.
    fn gap_after<D: Dims>(&self, d: D, alpha: f64) -> f64 {
        let (m, n) = (d.m(), self.n);
        let ws = &*self.ws;
        let mut gap = 0.0;
        for idx in 0..(n + 1) * m {
            if ws.on[idx] {
                gap += (ws.t[idx] + alpha * ws.dt[idx]) * (ws.lam[idx] + alpha * ws.dlam[idx]);
            }
        }
        gap
    }

    fn take_step<D: Dims>(&mut self, d: D, alpha: f64) {
        let (nx, m, n) = (d.nx(), d.m(), self.n);
        let ws = &mut *self.ws;
        let axpy = |y: &mut [f64], x: &[f64]| {
            for (y, x) in y.iter_mut().zip(x) {
                *y += alpha * x;
            }
        };
        axpy(&mut ws.x[nx..], &ws.dx[nx..]);
        axpy(&mut ws.u, &ws.du);
        axpy(&mut ws.s, &ws.ds);
        axpy(&mut ws.pi, &ws.dpi);
        for idx in 0..(n + 1) * m {
            if ws.on[idx] {
                ws.t[idx] += alpha * ws.dt[idx];
                ws.lam[idx] += alpha * ws.dlam[idx];
            }
        }
    }

    /// Copies the iterate out and evaluates the objective.
    fn write_solution<D: Dims>(&self, d: D, sol: &mut QpSolution) {
        let (nx, nu, m, n) = (d.nx(), d.nu(), d.m(), self.n);
        let sl = Slots::of(d);
        let qp = self.qp;
        let ws = &*self.ws;
        for k in 0..=n {
            sol.x[k]
                .as_mut_slice()
                .copy_from_slice(&ws.x[k * nx..(k + 1) * nx]);
        }
        for k in 0..n {
            sol.u[k]
                .as_mut_slice()
                .copy_from_slice(&ws.u[k * nu..(k + 1) * nu]);
            sol.pi[k]
                .as_mut_slice()
                .copy_from_slice(&ws.pi[k * nx..(k + 1) * nx]);
            for j in 0..nu {
                sol.lam_u_lower[k][j] = ws.lam[k * m + sl.ul + j];
                sol.lam_u_upper[k][j] = ws.lam[k * m + sl.uu + j];
            }
        }
        let mut obj = 0.0;
        for k in 0..=n {
            let xk = &ws.x[k * nx..(k + 1) * nx];
            let (qm, ql) = (qp.q[k].as_slice(), qp.q_lin[k].as_slice());
            for i in 0..nx {
                let mut v = 0.5 * qm[i + i * nx] * xk[i];
                for j in 0..i {
                    v += qm[i + j * nx] * xk[j];
                }
                obj += xk[i] * v + ql[i] * xk[i];
            }
            if k < n {
                let uk = &ws.u[k * nu..(k + 1) * nu];
                let (rm, sm, rl) = (
                    qp.r[k].as_slice(),
                    qp.s[k].as_slice(),
                    qp.r_lin[k].as_slice(),
                );
                for j in 0..nu {
                    let mut v = 0.5 * rm[j + j * nu] * uk[j] + rl[j];
                    for i in 0..j {
                        v += rm[j + i * nu] * uk[i];
                    }
                    for i in 0..nx {
                        v += sm[j + i * nu] * xk[i];
                    }
                    obj += uk[j] * v;
                }
            }
            for i in 0..nx {
                if ws.soft[k * nx + i] {
                    let s = ws.s[k * nx + i];
                    obj += qp.soft_l1[i] * s + 0.5 * qp.soft_l2[i] * s * s;
                }
            }
        }
        sol.objective = obj;
    }
}

/// Value of inequality slot `i` of stage `k` at the current iterate.
#[inline(always)]
fn constraint_value<D: Dims>(d: D, qp: &OcpQp, ws: &Workspace, k: usize, i: usize) -> f64 {
    let (nx, nu) = (d.nx(), d.nu());
    let sl = Slots::of(d);
    if i < sl.uu {
        ws.u[k * nu + i] - qp.u_lower[k][i]
    } else if i < sl.xl {
        let j = i - sl.uu;
        qp.u_upper[k][j] - ws.u[k * nu + j]
    } else if i < sl.xu {
        let j = i - sl.xl;
        ws.x[k * nx + j] + ws.s[k * nx + j] - qp.x_lower[k][j]
    } else if i < sl.sl {
        let j = i - sl.xu;
        qp.x_upper[k][j] + ws.s[k * nx + j] - ws.x[k * nx + j]
    } else {
        ws.s[k * nx + i - sl.sl]
    }
}

/// In-place lower Cholesky factorisation of rows/columns `from..to` of the
/// column-major `nv x nv` block `lm` (lower triangle holds the matrix).
/// Control pivots (`< nu`) that are not clearly positive are lifted
/// (regularisation); state pivots are truncated to a zero column
/// (semidefinite). Returns (regularised, truncated) counts.
#[inline(always)]
fn cholesky<D: Dims>(
    d: D,
    lm: &mut [f64],
    inv: &mut [f64],
    from: usize,
    to: usize,
    set: &RiccatiSettings,
) -> (usize, usize) {
    let (nu, nv) = (d.nu(), d.nv());
    let mut scale = 0.0f64;
    for j in from..to {
        scale = scale.max(lm[j + j * nv]);
    }
    if scale.is_nan() || scale <= 0.0 {
        scale = 1.0;
    }
    let (mut regularised, mut truncated) = (0, 0);
    for j in from..to {
        let mjj = lm[j + j * nv];
        let mut djj = mjj;
        for c in from..j {
            djj -= lm[j + c * nv] * lm[j + c * nv];
        }
        let threshold = set.pivot_tolerance * mjj.abs().max(f64::MIN_POSITIVE);
        if djj.is_nan() || djj <= threshold {
            if j < nu {
                djj = djj.max(0.0) + set.regularisation * scale;
                regularised += 1;
            } else {
                lm[j + j * nv] = 0.0;
                inv[j] = 0.0;
                for i in j + 1..to {
                    lm[i + j * nv] = 0.0;
                }
                truncated += 1;
                continue;
            }
        }
        let ljj = djj.sqrt();
        lm[j + j * nv] = ljj;
        let r = 1.0 / ljj;
        inv[j] = r;
        for i in j + 1..to {
            let mut v = lm[i + j * nv];
            for c in from..j {
                v -= lm[i + c * nv] * lm[j + c * nv];
            }
            lm[i + j * nv] = v * r;
        }
    }
    (regularised, truncated)
}
