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

use super::{Core, FixedCore, Mat, RiccatiInfo, Vecn};
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
        for (st, kept) in self.st.iter().zip(self.kept.iter_mut()) {
            *kept = (st.pi, st.lam);
        }
        self.first_guess();
        let mut guesses = 0;
        let optimal = loop {
            guesses += 1;
            if !self.policy() {
                break false;
            }
            if self.simulate_and_update() == 0 {
                break true;
            }
            if guesses >= max_guesses {
                break false;
            }
        };
        // An optimal guess's solution and multipliers become the iterate,
        // checked by the same residuals as the interior point's.
        let accepted = optimal && {
            self.set_multipliers();
            let res = Core::residuals(self);
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
                st.pi = kept.0;
                st.lam = kept.1;
            }
            self.info = RiccatiInfo::default();
            return None;
        }
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
    /// of every stage. False when a free control block is not clearly
    /// positive definite (the interior point then regularises it).
    fn policy(&mut self) -> bool {
        let n = self.n;
        let tol = self.set.pivot_tolerance;
        self.guess[n].p_mat = self.st[n].q;
        self.guess[n].p_vec = self.st[n].ql;
        for k in (0..n).rev() {
            let (p_next, pv_next) = (self.guess[k + 1].p_mat, self.guess[k + 1].p_vec);
            let st = &self.st[k];
            let pa = p_next * st.a;
            let pb = p_next * st.b;
            let h = p_next * st.c + pv_next;
            let qxx = st.q + st.a.tr_mul(&pa);
            let qux = st.s + st.b.tr_mul(&pa);
            let quu = st.r + st.b.tr_mul(&pb);
            let qx = st.ql + st.a.tr_mul(&h);
            let qu = st.rl + st.b.tr_mul(&h);
            // Free rows: the stationarity of the free controls with the
            // fixed ones moved to the right; fixed rows: u_j = bound.
            let guess = self.guess[k].guess;
            let mut fixed = Vecn::<NU>::zeros();
            for j in 0..NU {
                if guess[j] != Bound::Free {
                    fixed[j] = self.bound_value(k, j, guess[j]);
                }
            }
            let mut hm = quu;
            let mut g = qux;
            let mut rhs = -(qu + quu * fixed);
            for j in 0..NU {
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
            let Some(chol) = hm.cholesky() else {
                return false;
            };
            let l = chol.l_dirty();
            for j in 0..NU {
                let pivot = l[(j, j)] * l[(j, j)];
                if pivot.is_nan() || pivot <= tol * hm[(j, j)].abs() {
                    return false;
                }
            }
            let gain = -chol.solve(&g);
            let mut feed = chol.solve(&rhs);
            for j in 0..NU {
                if guess[j] != Bound::Free {
                    feed[j] = fixed[j];
                }
            }
            // V(x) = Q(x, gain x + feed). The free rows of the policy solve
            // Quu_FF gain_F = -Qux_F and Quu_FF feed_F = -(qu_F + Quu_Fa b_a),
            // and the fixed rows of gain are zero, so gain' Quu gain =
            // -gain' Qux and gain' Quu feed = -gain' qu: the quadratic and
            // linear terms reduce to the familiar Riccati update.
            let p_mat = qxx + qux.tr_mul(&gain);
            let p_vec = qx + qux.tr_mul(&feed);
            let gs = &mut self.guess[k];
            gs.gain = gain;
            gs.feed = feed;
            gs.p_mat = 0.5 * (p_mat + p_mat.transpose());
            gs.p_vec = p_vec;
        }
        true
    }

    /// Forward sweep of the current policy into the iterate (`x`, `u`,
    /// `pi`), then the next guess; returns how many components changed.
    fn simulate_and_update(&mut self) -> usize {
        let n = self.n;
        let (tol_stat, tol_feas) = (self.set.tol_stationarity, self.set.tol_feasibility);
        let mut changed = 0;
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
            let grad = st.r * u + st.s * st.x + st.rl + st.b.tr_mul(&pi);
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
                changed += usize::from(next != guess[j]);
                guess[j] = next;
            }
            self.guess[k].guess = guess;
            let st = &mut self.st[k];
            st.u = u;
            st.pi = pi;
            st.ru = grad;
            self.st[k + 1].x = x_next;
        }
        changed
    }

    /// Slacks and multipliers of the optimal guess: multipliers from the
    /// gradient on the fixed controls (clipped at zero within the
    /// tolerance), zero elsewhere; slacks the constraint values.
    fn set_multipliers(&mut self) {
        let n = self.n;
        for k in 0..=n {
            let st = &mut self.st[k];
            st.sl = Vecn::zeros();
            let cv = st.constraint_values();
            for i in 0..M {
                st.t[i] = if st.mask[i] > 0.0 {
                    cv[i].max(0.0)
                } else {
                    1.0
                };
                st.lam[i] = 0.0;
            }
            if k < n {
                for j in 0..NU {
                    match self.guess[k].guess[j] {
                        Bound::Lower => {
                            st.lam[j] = st.ru[j].max(0.0);
                            st.t[j] = 0.0;
                        }
                        Bound::Upper => {
                            st.lam[NU + j] = (-st.ru[j]).max(0.0);
                            st.t[NU + j] = 0.0;
                        }
                        Bound::Free => {}
                    }
                }
            }
        }
    }
}
