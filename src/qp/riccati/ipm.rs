//! The interior point: Mehrotra predictor-corrector iterations over a
//! [`Core`] (the run-time-sized one here, [`Ipm`]), the Riccati
//! factorisation of its Newton systems and the line search.

use super::*;

/// One solve: borrows the data, the workspace and the settings.
pub(super) struct Ipm<'a> {
    pub(super) qp: &'a OcpQp,
    pub(super) ws: &'a mut Workspace,
    pub(super) set: &'a RiccatiSettings,
    pub(super) n: usize,
    pub(super) d: Runtime,
    pub(super) info: RiccatiInfo,
    /// Start from the shifted last multipliers.
    pub(super) warm: bool,
}

/// Norms of the current residuals.
#[derive(Clone, Copy)]
pub(super) struct Residuals {
    pub(super) stationarity: f64,
    /// Largest term of the stationarity sums (its round-off scale).
    pub(super) scale: f64,
    pub(super) feasibility: f64,
    pub(super) complementarity: f64,
    pub(super) mu: f64,
}

/// The steps of one interior-point solve, implemented by the runtime-size
/// and the compile-time-size cores; the iteration itself is
/// [`interior_point`].
pub(super) trait Core {
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
pub(super) struct StartShift {
    pub(super) t: f64,
    pub(super) lam: f64,
}

/// Mehrotra predictor-corrector iteration on any [`Core`]; `warm` tells
/// that the core starts from the shifted previous multipliers.
pub(super) fn interior_point<C: Core>(
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
pub(super) fn recentred(v: f64, shift: f64) -> f64 {
    v.max(0.0) + shift
}

/// Accumulates one slot into [`Core::slot_sums`].
pub(super) fn add_slot(
    s: (f64, f64, f64, f64, f64),
    t: f64,
    lam: f64,
) -> (f64, f64, f64, f64, f64) {
    (s.0.min(t), s.1.min(lam), s.2 + t * lam, s.3 + t, s.4 + lam)
}

impl Ipm<'_> {
    /// Marks the existing inequalities and sets a primal point (controls
    /// inside their box, states simulated, slacks covering the violations)
    /// with slacks and multipliers bounded away from zero.
    pub(super) fn initialise<D: Dims>(&mut self, d: D) {
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
    pub(super) fn residuals<D: Dims>(&mut self, d: D) -> Residuals {
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
    pub(super) fn factor<D: Dims>(&mut self, d: D) {
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
    pub(super) fn prepare_affine<D: Dims>(&mut self, d: D) -> usize {
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
    pub(super) fn prepare_corrector<D: Dims>(&mut self, d: D, sigma_mu: f64) {
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
    pub(super) fn newton_direction<D: Dims>(&mut self, d: D) {
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
    pub(super) fn max_step<D: Dims>(&self, d: D, fraction: f64) -> f64 {
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
    pub(super) fn gap_after<D: Dims>(&self, d: D, alpha: f64) -> f64 {
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

    pub(super) fn take_step<D: Dims>(&mut self, d: D, alpha: f64) {
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
    pub(super) fn write_solution<D: Dims>(&self, d: D, sol: &mut QpSolution) {
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
pub(super) fn constraint_value<D: Dims>(
    d: D,
    qp: &OcpQp,
    ws: &Workspace,
    k: usize,
    i: usize,
) -> f64 {
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
