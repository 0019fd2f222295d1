//! Solver-independent optimality check of a [`QpSolution`] for an [`OcpQp`].
//!
//! Uses only the primal iterate `x, u`, the dynamics multipliers `pi` and the
//! control-bound multipliers. The soft state bounds' slacks and multipliers
//! are not part of [`QpSolution`]; they are recovered here: for fixed `x` the
//! best slack is the smallest one, `s = max(0, x_lower - x, x - x_upper)`,
//! and the bound multiplier is the one in its admissible range
//! `[0, l1 + l2 s]` that fits the stationarity condition best. A bound with a
//! zero L1 and L2 weight costs nothing to violate and is ignored.

use super::{OcpQp, QpSolution};
use nalgebra::DVector;

/// Infinity norms of the KKT conditions (Lagrangian sign convention of
/// [`QpSolution`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KktResiduals {
    /// Gradient of the Lagrangian w.r.t. `u_k` (`k < N`) and `x_k` (`k >= 1`).
    pub stationarity: f64,
    /// Largest term of those gradient sums (`|Hz|`, `|g|`, `|E' pi|`,
    /// multipliers): floating-point round-off alone makes the stationarity
    /// residual a few ulps of this.
    pub stationarity_scale: f64,
    /// `x_0 - x0` and `A_k x_k + B_k u_k + c_k - x_{k+1}`.
    pub dynamics: f64,
    /// Largest violation of a control bound.
    pub bound_violation: f64,
    /// `max(dynamics, bound_violation)` (soft state bounds cannot be violated).
    pub primal_feasibility: f64,
    /// Largest negative part of a control-bound multiplier.
    pub dual_feasibility: f64,
    /// Largest complementarity product `|lam c| / max(1, |lam|)`: the plain
    /// product for multipliers up to 1, the distance to the bound for larger
    /// ones (so it does not grow with the multipliers' scale).
    pub complementarity: f64,
    /// Objective at `(x, u)` with the smallest soft slacks.
    pub objective: f64,
}

impl KktResiduals {
    /// The largest of the stationarity, feasibility and complementarity
    /// residuals.
    pub fn max(&self) -> f64 {
        self.stationarity
            .max(self.primal_feasibility)
            .max(self.dual_feasibility)
            .max(self.complementarity)
    }

    /// True when feasibility and complementarity are within `tol` and the
    /// stationarity residual is within `tol` or, for badly scaled problems
    /// (huge costates), within `rel_tol * stationarity_scale`.
    pub fn within(&self, tol: f64, rel_tol: f64) -> bool {
        self.primal_feasibility
            .max(self.dual_feasibility)
            .max(self.complementarity)
            <= tol
            && self.stationarity <= tol.max(rel_tol * self.stationarity_scale)
    }
}

/// True when state component `i` carries a soft bound at stage `k`.
fn is_soft(qp: &OcpQp, k: usize, i: usize) -> bool {
    (qp.x_lower[k][i].is_finite() || qp.x_upper[k][i].is_finite())
        && (qp.soft_l1[i] > 0.0 || qp.soft_l2[i] > 0.0)
}

/// Smallest slack that satisfies the soft bounds of component `i` at stage `k`.
fn soft_slack(qp: &OcpQp, k: usize, i: usize, x: f64) -> f64 {
    let mut v = 0.0f64;
    if qp.x_lower[k][i].is_finite() {
        v = v.max(qp.x_lower[k][i] - x);
    }
    if qp.x_upper[k][i].is_finite() {
        v = v.max(x - qp.x_upper[k][i]);
    }
    v
}

/// Objective of `qp` at `(x, u)` including the soft-bound penalties with the
/// smallest slacks.
pub fn objective(qp: &OcpQp, x: &[DVector<f64>], u: &[DVector<f64>]) -> f64 {
    let n = qp.horizon;
    let mut obj = 0.0;
    for k in 0..=n {
        let xk = &x[k];
        obj += 0.5 * xk.dot(&(&qp.q[k] * xk)) + qp.q_lin[k].dot(xk);
        if k < n {
            let uk = &u[k];
            obj += 0.5 * uk.dot(&(&qp.r[k] * uk)) + uk.dot(&(&qp.s[k] * xk)) + qp.r_lin[k].dot(uk);
        }
        if k >= 1 {
            for i in 0..qp.nx {
                if is_soft(qp, k, i) {
                    let s = soft_slack(qp, k, i, xk[i]);
                    obj += qp.soft_l1[i] * s + 0.5 * qp.soft_l2[i] * s * s;
                }
            }
        }
    }
    obj
}

/// Complementarity residual of a multiplier and its constraint value.
fn natural(lam: f64, value: f64) -> f64 {
    (lam * value).abs() / lam.abs().max(1.0)
}

fn dimensions_match(qp: &OcpQp, sol: &QpSolution) -> bool {
    let (nx, nu, n) = (qp.nx, qp.nu, qp.horizon);
    let ok = |v: &[DVector<f64>], len, count| v.len() == count && v.iter().all(|x| x.len() == len);
    ok(&sol.x, nx, n + 1)
        && ok(&sol.u, nu, n)
        && ok(&sol.pi, nx, n)
        && ok(&sol.lam_u_lower, nu, n)
        && ok(&sol.lam_u_upper, nu, n)
}

/// KKT residuals of `sol` for `qp`, computed from the data alone (no solver
/// state). Mismatched dimensions give infinite residuals.
pub fn kkt_residuals(qp: &OcpQp, sol: &QpSolution) -> KktResiduals {
    if !dimensions_match(qp, sol) {
        return KktResiduals {
            stationarity: f64::INFINITY,
            stationarity_scale: f64::INFINITY,
            dynamics: f64::INFINITY,
            bound_violation: f64::INFINITY,
            primal_feasibility: f64::INFINITY,
            dual_feasibility: f64::INFINITY,
            complementarity: f64::INFINITY,
            objective: f64::NAN,
        };
    }
    let n = qp.horizon;
    let (x, u, pi) = (&sol.x, &sol.u, &sol.pi);
    let mut stat = 0.0f64;
    let mut scale = 0.0f64;
    let mut dynamics = (&x[0] - &qp.x0).amax();
    let mut violation = 0.0f64;
    let mut dual = 0.0f64;
    let mut comp = 0.0f64;
    for k in 0..n {
        let (ll, lu) = (&sol.lam_u_lower[k], &sol.lam_u_upper[k]);
        let h = &qp.r[k] * &u[k] + &qp.s[k] * &x[k];
        let e = qp.b[k].transpose() * &pi[k];
        let g = &h + &qp.r_lin[k] + &e - ll + lu;
        stat = stat.max(g.amax());
        scale = scale
            .max(h.amax())
            .max(e.amax())
            .max(qp.r_lin[k].amax())
            .max(ll.amax())
            .max(lu.amax());
        let e = &qp.a[k] * &x[k] + &qp.b[k] * &u[k] + &qp.c[k] - &x[k + 1];
        dynamics = dynamics.max(e.amax());
        for j in 0..qp.nu {
            let (lo, hi, uj) = (qp.u_lower[k][j], qp.u_upper[k][j], u[k][j]);
            // An infinite bound has no multiplier: a nonzero one is an error.
            let lower_gap = if lo.is_finite() { uj - lo } else { 1.0 };
            let upper_gap = if hi.is_finite() { hi - uj } else { 1.0 };
            violation = violation.max(-lower_gap).max(-upper_gap);
            dual = dual.max(-ll[j]).max(-lu[j]);
            comp = comp
                .max(natural(ll[j], lower_gap))
                .max(natural(lu[j], upper_gap));
        }
    }
    for k in 1..=n {
        let mut h = &qp.q[k] * &x[k];
        let mut e = -&pi[k - 1];
        scale = scale.max(e.amax()).max(qp.q_lin[k].amax());
        if k < n {
            h += qp.s[k].transpose() * &u[k];
            let ep = qp.a[k].transpose() * &pi[k];
            scale = scale.max(ep.amax());
            e += ep;
        }
        scale = scale.max(h.amax());
        let g = h + e + &qp.q_lin[k];
        for i in 0..qp.nx {
            if !is_soft(qp, k, i) {
                stat = stat.max(g[i].abs());
                continue;
            }
            let (lo, hi, xi) = (qp.x_lower[k][i], qp.x_upper[k][i], x[k][i]);
            let s = soft_slack(qp, k, i, xi);
            let cap = qp.soft_l1[i] + qp.soft_l2[i] * s;
            // Stationarity: g - lam_l + lam_u = 0 with lam_l + lam_u <= cap.
            // A violated bound (s > 0) forces lam_s = 0, so the violated
            // side's multiplier is exactly cap and any misfit shows up in
            // the (scale-aware) stationarity residual.
            // A violation within round-off of the bound (1e-9 relative)
            // counts as sitting on it, where lam_s may be positive. Otherwise
            // the multiplier is zero or the best fit to the stationarity
            // condition, whichever certifies optimality better (a tiny
            // multiplier of a far bound and a small one of a near bound are
            // both what interior-point solutions look like).
            let (mut lam_l, mut lam_u) = (0.0, 0.0);
            if s > 1e-9 * xi.abs().max(1.0) {
                // The tight side is the more violated one (infinite bounds
                // give -inf violations).
                if lo - xi >= xi - hi {
                    lam_l = cap;
                } else {
                    lam_u = cap;
                }
            } else {
                let (fit, gap) = if g[i] > 0.0 && lo.is_finite() {
                    (g[i].min(cap), xi + s - lo)
                } else if g[i] < 0.0 && hi.is_finite() {
                    ((-g[i]).min(cap), hi + s - xi)
                } else {
                    (0.0, 0.0)
                };
                let with_fit = (g[i].abs() - fit)
                    .max(natural(fit, gap))
                    .max(natural(cap - fit, s));
                if with_fit < g[i].abs() {
                    if g[i] > 0.0 {
                        lam_l = fit;
                    } else {
                        lam_u = fit;
                    }
                }
            }
            stat = stat.max((g[i] - lam_l + lam_u).abs());
            scale = scale.max(lam_l.max(lam_u));
            if lo.is_finite() {
                comp = comp.max(natural(lam_l, xi + s - lo));
            }
            if hi.is_finite() {
                comp = comp.max(natural(lam_u, hi + s - xi));
            }
            // lam_s = cap - lam_l - lam_u >= 0 multiplies s: zero by
            // construction when s > 0.
        }
    }
    KktResiduals {
        stationarity: stat,
        stationarity_scale: scale,
        dynamics,
        bound_violation: violation.max(0.0),
        primal_feasibility: dynamics.max(violation),
        dual_feasibility: dual.max(0.0),
        complementarity: comp,
        objective: objective(qp, x, u),
    }
}
