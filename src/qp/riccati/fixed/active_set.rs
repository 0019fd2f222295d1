//! The active-set start of the compile-time-sized core (see
//! [`RiccatiSettings::active_set_start`](super::RiccatiSettings::active_set_start)):
//! a primal-dual active-set method (Hintermüller, Ito and Kunisch 2002) on
//! the control bounds, warm-started from the previous solution's active set
//! shifted by one stage.
//!
//! Each guess fixes the guessed-active controls at their bounds and solves
//! the remaining equality-constrained QP exactly by one Riccati recursion
//! (`u_k = K_k x_k + k_k`, the fixed rows of `K_k` zero). The guess is the
//! QP's optimum when every free control lies within its bounds and every
//! fixed one has a multiplier of the right sign; otherwise the next guess
//! frees the fixed controls whose multiplier has the wrong sign and fixes
//! the free ones beyond a bound. In RTI the active set moves by a few
//! stages from one sample to the next, so one or two guesses usually
//! suffice; when they do not, the interior point runs from its untouched
//! warm start. The empty guess is the inactive-set start: on an eigenmode
//! the torques are far from their bounds and one recursion solves the QP.

use super::{Core, FixedCore, Mat, Residuals, RiccatiInfo, Vecn, fmax, nan_probe};
use crate::qp::{QpSolution, QpStatus};

/// A previous multiplier above this marks an active bound of the guess.
/// Inactive slots of a converged interior point have multipliers near
/// `tol_complementarity / t`, active ones on the scale of the gradient.
const ACTIVE_MULTIPLIER: f64 = 1e-5;

/// Where a control component is in a guess.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Bound {
    Free,
    Lower,
    Upper,
}

/// One stage of the active-set recursion: its guess, policy and cost-to-go.
#[derive(Clone, Debug)]
pub(super) struct GuessStage<const NX: usize, const NU: usize> {
    guess: [Bound; NU],
    /// Policy `u = gain x + feed`.
    gain: Mat<NU, NX>,
    feed: Vecn<NU>,
    /// Cost-to-go `1/2 x' p_mat x + p_vec' x` from this stage on.
    p_mat: Mat<NX, NX>,
    p_vec: Vecn<NX>,
}

impl<const NX: usize, const NU: usize> GuessStage<NX, NU> {
    pub(super) fn new() -> Self {
        Self {
            guess: [Bound::Free; NU],
            gain: Mat::zeros(),
            feed: Vecn::zeros(),
            p_mat: Mat::zeros(),
            p_vec: Vecn::zeros(),
        }
    }
}

impl<const NX: usize, const NU: usize, const M: usize> FixedCore<NX, NU, M> {
    /// The active-set start. Returns the status when a guess is the QP's
    /// optimum (checked again by the interior point's own residuals);
    /// `None` leaves the warm-start multipliers as they were for the
    /// interior point.
    pub(in crate::qp::riccati) fn solve_active_set(
        &mut self,
        sol: &mut QpSolution,
    ) -> Option<QpStatus> {
        let max_guesses = self.set.active_set_guesses;
        if !self.set.active_set_start || max_guesses == 0 || self.soft_any || self.m_on == 0 {
            return None;
        }
        // The interior point's warm start reads these if no guess is right.
        // The sweeps overwrite the costates; the multipliers change only
        // once a guess is accepted.
        for (st, kept) in self.st.iter().zip(self.kept.iter_mut()) {
            *kept = st.pi;
        }
        self.first_guess();
        let mut guesses = 0;
        // The stages whose policy the next recursion computes: all at
        // first, then those up to the last changed guess (the cost-to-go
        // of a stage depends only on the guesses after it).
        let mut last = self.n - 1;
        let optimal = loop {
            guesses += 1;
            if !self.policy(last) {
                break false;
            }
            match self.simulate_and_update() {
                None => break true,
                Some(changed) => last = changed,
            }
            if guesses >= max_guesses {
                break false;
            }
        };
        // An optimal guess's solution and multipliers become the iterate,
        // checked against the interior point's tolerances.
        let accepted = optimal && {
            let res = self.guess_residuals();
            let set = &self.set;
            let tol_stat = set
                .tol_stationarity
                .max(set.tol_stationarity_relative * res.scale);
            self.info.stationarity = res.stationarity;
            self.info.feasibility = res.feasibility;
            self.info.complementarity = res.complementarity;
            res.stationarity <= tol_stat && res.feasibility <= set.tol_feasibility
        };
        if !accepted {
            for (st, kept) in self.st.iter_mut().zip(&self.kept) {
                st.pi = *kept;
            }
            self.info = RiccatiInfo::default();
            return None;
        }
        self.set_multipliers();
        self.info.iterations = guesses;
        self.info.active_set_start = true;
        self.write_solution(sol);
        sol.iterations = guesses;
        sol.primal_residual = self.info.feasibility;
        sol.dual_residual = self.info.stationarity;
        sol.status = QpStatus::Solved;
        Some(QpStatus::Solved)
    }

    /// The previous solution's active bounds shifted by one stage (the last
    /// stage keeps its own), or none after a cold start.
    fn first_guess(&mut self) {
        let n = self.n;
        for k in 0..n {
            let from = &self.st[(k + 1).min(n - 1)];
            let st = &self.st[k];
            let mut guess = [Bound::Free; NU];
            if self.warm {
                for j in 0..NU {
                    if st.mask[j] > 0.0 && from.lam[j] > ACTIVE_MULTIPLIER {
                        guess[j] = Bound::Lower;
                    } else if st.mask[NU + j] > 0.0 && from.lam[NU + j] > ACTIVE_MULTIPLIER {
                        guess[j] = Bound::Upper;
                    }
                }
            }
            self.guess[k].guess = guess;
        }
    }

    /// Bound of control `j` of stage `k` in the guess `b` (not `Free`).
    #[inline(always)]
    fn bound_value(&self, k: usize, j: usize, b: Bound) -> f64 {
        match b {
            Bound::Lower => -self.st[k].off[j],
            _ => self.st[k].off[NU + j],
        }
    }

    /// Backward recursion of the current guess: the policy and cost-to-go
    /// of stages `last` down to 0 (the later ones' are the last
    /// recursion's, which the guess did not change there; `last = N - 1`:
    /// all). False when a free control block is not clearly positive
    /// definite (the interior point then regularises it).
    fn policy(&mut self, last: usize) -> bool {
        let n = self.n;
        let tol = self.set.pivot_tolerance;
        if last + 1 == n {
            self.guess[n].p_mat = self.st[n].q;
            self.guess[n].p_vec = self.st[n].ql;
        }
        for k in (0..=last).rev() {
            let (p_next, pv_next) = (self.guess[k + 1].p_mat, self.guess[k + 1].p_vec);
            let st = &self.st[k];
            let pa = p_next * st.a;
            let pb = p_next * st.b;
            let h = p_next * st.c + pv_next;
            let qux = st.s + st.b.tr_mul(&pa);
            let quu = st.r + st.b.tr_mul(&pb);
            let qx = st.ql + st.a.tr_mul(&h);
            let qu = st.rl + st.b.tr_mul(&h);
            // Free rows: the stationarity of the free controls with the
            // fixed ones moved to the right; fixed rows: u_j = bound.
            let guess = self.guess[k].guess;
            let any_fixed = guess.iter().any(|&b| b != Bound::Free);
            let mut fixed = Vecn::<NU>::zeros();
            let mut hm = quu;
            let mut g = qux;
            let mut rhs = -qu;
            // The common stage, nothing fixed, skips the elimination.
            for j in (0..NU).filter(|_| any_fixed) {
                if guess[j] != Bound::Free {
                    fixed[j] = self.bound_value(k, j, guess[j]);
                }
            }
            if any_fixed {
                rhs = -(qu + quu * fixed);
            }
            for j in (0..NU).filter(|_| any_fixed) {
                if guess[j] != Bound::Free {
                    for i in 0..NU {
                        hm[(i, j)] = 0.0;
                        hm[(j, i)] = 0.0;
                    }
                    hm[(j, j)] = 1.0;
                    for c in 0..NX {
                        g[(j, c)] = 0.0;
                    }
                    rhs[j] = fixed[j];
                }
            }
            // The core's fixed-size Cholesky (a generic factor and solve
            // cost several times more at these sizes); a pivot it would
            // lift is one that is not clearly positive.
            let diag = hm.diagonal();
            let mut inv = Vecn::<NU>::zeros();
            if Self::cholesky(&mut hm, &mut inv, &diag, Some(0.0), tol) > 0 {
                return false;
            }
            let gain = -llt_solve(&hm, &inv, &g);
            let mut feed = llt_solve(&hm, &inv, &rhs);
            for j in (0..NU).filter(|_| any_fixed) {
                if guess[j] != Bound::Free {
                    feed[j] = fixed[j];
                }
            }
            // V(x) = Q(x, gain x + feed). The free rows of the policy solve
            // Quu_FF gain_F = -Qux_F and Quu_FF feed_F = -(qu_F + Quu_Fa b_a),
            // and the fixed rows of gain are zero, so gain' Quu gain =
            // -gain' Qux and gain' Quu feed = -gain' qu: the quadratic and
            // linear terms reduce to the familiar Riccati update.
            // P = Q + A' P' A + Qux' gain: its lower triangle, mirrored
            // (symmetric by construction, and half the products).
            let mut p_mat = Mat::<NX, NX>::zeros();
            for c in 0..NX {
                for r in c..NX {
                    let mut v = st.q[(r, c)];
                    for i in 0..NX {
                        v += st.a[(i, r)] * pa[(i, c)];
                    }
                    for j in 0..NU {
                        v += qux[(j, r)] * gain[(j, c)];
                    }
                    p_mat[(r, c)] = v;
                    p_mat[(c, r)] = v;
                }
            }
            let p_vec = qx + qux.tr_mul(&feed);
            let gs = &mut self.guess[k];
            gs.gain = gain;
            gs.feed = feed;
            gs.p_mat = p_mat;
            gs.p_vec = p_vec;
        }
        true
    }

    /// Forward sweep of the current policy into the iterate (`x`, `u`,
    /// `pi`), then the next guess; returns the last stage whose guess
    /// changed, `None` when none did (the guess is optimal).
    fn simulate_and_update(&mut self) -> Option<usize> {
        let n = self.n;
        let (tol_stat, tol_feas) = (self.set.tol_stationarity, self.set.tol_feasibility);
        let mut changed = None;
        let mut scale = 0.0f64;
        self.st[0].x = self.x0;
        for k in 0..n {
            let gs = &self.guess[k];
            let (p_next, pv_next) = (self.guess[k + 1].p_mat, self.guess[k + 1].p_vec);
            let st = &self.st[k];
            let u = gs.gain * st.x + gs.feed;
            let x_next = st.a * st.x + st.b * u + st.c;
            let pi = p_next * x_next + pv_next;
            // Gradient of the Lagrangian without the bound multipliers:
            // lam_lower = grad, lam_upper = -grad on the fixed controls.
            let (h, e) = (st.r * u + st.s * st.x, st.b.tr_mul(&pi));
            let grad = h + st.rl + e;
            for j in 0..NU {
                // The stationarity's scale, as the interior point's residuals
                // take it (guess_residuals adds the multipliers).
                let terms = fmax(fmax(st.rl[j].abs(), h[j].abs()), e[j].abs());
                scale = fmax(scale, terms);
            }
            let mut guess = gs.guess;
            for j in 0..NU {
                let next = match guess[j] {
                    Bound::Lower if grad[j] < -tol_stat => Bound::Free,
                    Bound::Upper if grad[j] > tol_stat => Bound::Free,
                    Bound::Free if st.mask[j] > 0.0 && u[j] + st.off[j] < -tol_feas => Bound::Lower,
                    Bound::Free if st.mask[NU + j] > 0.0 && st.off[NU + j] - u[j] < -tol_feas => {
                        Bound::Upper
                    }
                    b => b,
                };
                if next != guess[j] {
                    changed = Some(k);
                }
                guess[j] = next;
            }
            self.guess[k].guess = guess;
            let st = &mut self.st[k];
            st.u = u;
            st.pi = pi;
            st.ru = grad;
            self.st[k + 1].x = x_next;
        }
        self.guess_scale = scale;
        changed
    }

    /// The optimality residuals the interior point's [`Core::residuals`]
    /// finds at an optimal guess with [`Self::set_multipliers`]'
    /// multipliers, from what the last sweep left (a third of the work):
    /// each `x_{k+1}` came from the dynamics, so they hold exactly; no
    /// state bound has a slot (`soft_any` is false); the controls'
    /// gradients are in `ru`. What remains is the stationarity of the
    /// controls (the gradient less the multiplier of a fixed bound, which
    /// is the gradient clipped at zero) and of the states, and the
    /// controls' bound violation.
    fn guess_residuals(&self) -> Residuals {
        let n = self.n;
        let (mut stat_u, mut stat_x, mut feas) = ([0.0f64; NU], [0.0f64; NX], [0.0f64; NU]);
        let (mut scale, mut probe) = (self.guess_scale, 0.0);
        for k in 0..=n {
            let st = &self.st[k];
            if k < n {
                let guess = &self.guess[k].guess;
                for j in 0..NU {
                    let grad = st.ru[j];
                    let (v, multiplier) = match guess[j] {
                        Bound::Lower => (grad.min(0.0), grad.max(0.0)),
                        Bound::Upper => (grad.max(0.0), (-grad).max(0.0)),
                        Bound::Free => (grad, 0.0),
                    };
                    scale = fmax(scale, multiplier);
                    stat_u[j] = fmax(stat_u[j], v.abs());
                    probe += nan_probe(v);
                    let below = -st.mask[j] * (st.u[j] + st.off[j]);
                    let above = st.mask[NU + j] * (st.u[j] - st.off[NU + j]);
                    feas[j] = fmax(feas[j], fmax(below, above));
                }
            }
            if k >= 1 {
                // x_0 is fixed: its row is not a condition; the last stage
                // has no costate of its own.
                let prev = self.st[k - 1].pi;
                let h = st.q * st.x + st.s.tr_mul(&st.u);
                let e = if k < n {
                    st.a.tr_mul(&st.pi)
                } else {
                    Vecn::zeros()
                };
                for i in 0..NX {
                    let v = st.ql[i] + h[i] + e[i] - prev[i];
                    let terms = fmax(fmax(st.ql[i].abs(), h[i].abs()), e[i].abs());
                    scale = fmax(scale, fmax(terms, prev[i].abs()));
                    stat_x[i] = fmax(stat_x[i], v.abs());
                    probe += nan_probe(v);
                }
            }
        }
        let max = |v: &[f64]| v.iter().fold(0.0, |a, &b| fmax(a, b));
        Residuals {
            stationarity: fmax(max(&stat_u), max(&stat_x)) + probe,
            scale,
            feasibility: max(&feas),
            complementarity: 0.0,
            mu: 0.0,
        }
    }

    /// Slacks and multipliers of the optimal guess: multipliers from the
    /// gradient on the fixed controls (clipped at zero within the
    /// tolerance), zero elsewhere; slacks the constraint values.
    fn set_multipliers(&mut self) {
        let n = self.n;
        for k in 0..=n {
            let st = &mut self.st[k];
            st.sl = Vecn::zeros();
            // No state bound has a slot (`soft_any` is false): their
            // slack and multiplier are the absent slots' 1 and 0.
            st.t = [1.0; M];
            st.lam = [0.0; M];
            if k == n {
                continue;
            }
            for j in 0..NU {
                let (lower, upper) = (j, NU + j);
                match self.guess[k].guess[j] {
                    Bound::Lower => {
                        st.lam[lower] = st.ru[j].max(0.0);
                        st.t[lower] = 0.0;
                    }
                    _ if st.mask[lower] > 0.0 => {
                        st.t[lower] = (st.u[j] + st.off[lower]).max(0.0);
                    }
                    _ => {}
                }
                match self.guess[k].guess[j] {
                    Bound::Upper => {
                        st.lam[upper] = (-st.ru[j]).max(0.0);
                        st.t[upper] = 0.0;
                    }
                    _ if st.mask[upper] > 0.0 => {
                        st.t[upper] = (st.off[upper] - st.u[j]).max(0.0);
                    }
                    _ => {}
                }
            }
        }
    }
}

/// `(L L')^-1 b` for the lower factor `l` with reciprocal pivots `inv`
/// (as [`FixedCore::cholesky`] leaves them).
#[inline(always)]
fn llt_solve<const D: usize, const C: usize>(
    l: &Mat<D, D>,
    inv: &Vecn<D>,
    b: &Mat<D, C>,
) -> Mat<D, C> {
    let mut y = *b;
    for j in 0..D {
        for c in 0..C {
            let mut v = y[(j, c)];
            for i in 0..j {
                v -= l[(j, i)] * y[(i, c)];
            }
            y[(j, c)] = v * inv[j];
        }
    }
    for j in (0..D).rev() {
        for c in 0..C {
            let mut v = y[(j, c)];
            for i in j + 1..D {
                v -= l[(i, j)] * y[(i, c)];
            }
            y[(j, c)] = v * inv[j];
        }
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math;
    use crate::qp::OcpQp;
    use crate::qp::riccati::RiccatiSettings;
    use nalgebra::{DMatrix, DVector};

    /// Two coupled double integrators pushed from far away with bounded
    /// forces: the controls saturate over the first stages.
    fn saturating_qp(horizon: usize) -> OcpQp {
        let mut qp = OcpQp::new(4, 2, horizon);
        for k in 0..horizon {
            let wobble = |i: usize, j: usize| 0.02 * math::sin((i + 2 * j + k) as f64);
            qp.a[k] = DMatrix::from_fn(4, 4, |i, j| match (i, j) {
                _ if i == j => 1.0,
                _ if j == i + 2 => 0.1,
                _ => wobble(i, j),
            });
            qp.b[k] = DMatrix::from_fn(4, 2, |i, j| if i == j + 2 { 0.1 } else { 0.0 });
            qp.c[k] = DVector::from_fn(4, |i, _| 0.001 * i as f64);
            qp.r[k] = DMatrix::identity(2, 2) * 0.1;
            qp.s[k] = DMatrix::from_fn(2, 4, |i, j| 0.01 * (i + j) as f64);
            qp.r_lin[k] = DVector::from_vec(vec![0.01, -0.02]);
            qp.u_lower[k].fill(-0.5);
            qp.u_upper[k].fill(0.5);
        }
        for k in 0..=horizon {
            qp.q[k] = DMatrix::identity(4, 4);
            qp.q_lin[k] = DVector::from_vec(vec![0.0, 0.1, 0.0, -0.1]);
        }
        qp.x0 = DVector::from_vec(vec![2.0, -1.5, 0.0, 0.3]);
        qp
    }

    #[test]
    fn an_accepted_guess_has_the_residuals_the_interior_point_would_find() {
        let horizon = 20;
        let qp = saturating_qp(horizon);
        let mut core = FixedCore::<4, 2, 16>::new(horizon);
        let set = RiccatiSettings {
            active_set_guesses: 30,
            ..RiccatiSettings::default()
        };
        assert!(core.load(&qp, &set));
        let mut sol = QpSolution::new(4, 2, horizon);
        assert_eq!(core.solve_active_set(&mut sol), Some(QpStatus::Solved));
        let fixed = core.guess[..horizon]
            .iter()
            .flat_map(|g| g.guess)
            .filter(|&b| b != Bound::Free)
            .count();
        assert!(fixed >= 4, "the test wants saturated controls: {fixed}");
        // guess_residuals first: the full pass overwrites `ru`.
        let own = core.guess_residuals();
        let full = Core::residuals(&mut core);
        let round_off = 1e-12 * (1.0 + full.scale);
        assert!(
            (own.stationarity - full.stationarity).abs() <= round_off,
            "{} against {}",
            own.stationarity,
            full.stationarity
        );
        assert!(own.stationarity <= 1e-9, "{}", own.stationarity);
        assert!((own.feasibility - full.feasibility).abs() <= 1e-12);
        assert!((own.scale - full.scale).abs() <= 1e-12 * full.scale);
        assert_eq!(full.complementarity, 0.0);
        assert_eq!(sol.dual_residual, own.stationarity);
    }
}
