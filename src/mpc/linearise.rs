//! Preparation phase: integration of every shooting interval with RK4 and
//! exact sensitivities, and the QP in the step variables at the current plan.

use super::Controller;
use super::cost::{stage_model, stage_model_at};
use crate::integrate::{rk4_step_sensitivity, rk4_step_sensitivity_from};
use crate::mechanics::{DynamicsJacobian, MechanicalSystem, Vector, unpack_state};
use nalgebra::{SMatrix, SVector};

/// How far a joint's speed may move within an interval, in units of its
/// acceleration at the interval's start times `dt` (the acceleration
/// changes within the interval: a margin). Measured on the laboratory
/// robots (docs/speed.md, `tests/substeps.rs`): 1.0-2.0 give the same
/// closed loops and 1.0 the fewest substeps (A0 6 % fewer instructions),
/// but below 1.5 some intervals in which a joint stops take too few: their
/// prediction is off from the one with every substep by up to 2e-3 (1.25)
/// and 1.1e-2 (1.0) against 4e-4 here.
pub const SPEED_REACH: f64 = 1.5;

/// The largest friction slope of `system` with every joint at rest, where
/// its Coulomb law is steepest (zero without friction).
pub(super) fn steepest_friction_slope<S: MechanicalSystem<N>, const N: usize>(system: &S) -> f64 {
    system.friction_slope(&Vector::zeros()).max()
}

impl<S, const N: usize, const NX: usize> Controller<S, N, NX>
where
    S: MechanicalSystem<N>,
{
    /// RK4 substeps of the interval from `z` under `u`. `config.substeps`
    /// is what the model's Coulomb friction needs with a joint at rest,
    /// where its slope `cf k` is steepest; with
    /// `config.substeps_where_stiff` only an interval in which a joint may
    /// come to rest takes them all. Elsewhere every joint's slope is
    /// flatter, `cf k / (1 + (k v)^2)` at its slowest speed `v` in reach
    /// (its speed plus or minus [`SPEED_REACH`] times its acceleration
    /// times `dt`), and the substeps shrink in proportion: the same
    /// stability margin per substep, at least one.
    pub fn interval_substeps(&self, z: &SVector<f64, NX>, u: &Vector<N>) -> usize {
        if let Some(every) = self.substeps_everywhere() {
            // Skips the forward dynamics.
            return every;
        }
        let (q, qd) = unpack_state::<N, NX>(z);
        let qdd = self.system.forward_dynamics(&q, &qd, u);
        self.substeps_at(&qd, &qdd)
    }

    /// The substeps of every interval when they do not depend on the
    /// state: one, or all of them without `substeps_where_stiff`.
    fn substeps_everywhere(&self) -> Option<usize> {
        let most = self.config.substeps;
        (most == 1 || !self.config.substeps_where_stiff).then_some(most)
    }

    /// [`Self::interval_substeps`] from the joint speeds and accelerations
    /// at the interval's start.
    fn substeps_at(&self, qd: &Vector<N>, qdd: &Vector<N>) -> usize {
        if let Some(every) = self.substeps_everywhere() {
            return every;
        }
        let most = self.config.substeps;
        let steepest = self.steepest_friction_slope;
        if steepest.is_nan() || steepest <= 0.0 {
            return most;
        }
        let reach = SPEED_REACH * self.config.dt;
        let slowest = Vector::<N>::from_fn(|j, _| {
            let (lo, hi) = (qd[j] - reach * qdd[j].abs(), qd[j] + reach * qdd[j].abs());
            if lo <= 0.0 && hi >= 0.0 {
                0.0
            } else {
                lo.abs().min(hi.abs())
            }
        });
        let slope = self.system.friction_slope(&slowest).max();
        if !slope.is_finite() {
            return most;
        }
        // The ceiling of a finite, non-negative share below 2^53, without
        // `f64::ceil` (a libm call on baseline x86-64).
        let share = most as f64 * slope / steepest;
        let whole = share as usize;
        (whole + usize::from((whole as f64) < share)).clamp(1, most)
    }

    pub(super) fn simulate_interval(
        &self,
        z: &SVector<f64, NX>,
        u: &Vector<N>,
    ) -> SVector<f64, NX> {
        let substeps = self.interval_substeps(z, u);
        let h = self.config.dt / substeps as f64;
        let mut x = *z;
        for _ in 0..substeps {
            x = crate::integrate::rk4_step::<S, N, NX>(&self.system, &x, u, h);
        }
        x
    }

    /// Integration with sensitivities over one shooting interval, in
    /// `substeps` RK4 steps.
    pub(super) fn interval_sensitivity(
        &self,
        z: &SVector<f64, NX>,
        u: &Vector<N>,
        substeps: usize,
    ) -> (SVector<f64, NX>, SMatrix<f64, NX, NX>, SMatrix<f64, NX, N>) {
        let (q, qd) = unpack_state::<N, NX>(z);
        let first = self.system.dynamics_jacobian(&q, &qd, u);
        self.interval_sensitivity_from(z, u, substeps, &first)
    }

    /// [`Self::interval_sensitivity`] given the dynamics Jacobian at `z`.
    fn interval_sensitivity_from(
        &self,
        z: &SVector<f64, NX>,
        u: &Vector<N>,
        substeps: usize,
        first: &DynamicsJacobian<N>,
    ) -> (SVector<f64, NX>, SMatrix<f64, NX, NX>, SMatrix<f64, NX, N>) {
        let h = self.config.dt / substeps as f64;
        let s = rk4_step_sensitivity_from::<S, N, NX>(&self.system, z, u, h, first);
        let (mut x, mut a, mut b) = (s.z_next, s.d_z, s.d_tau);
        for _ in 1..substeps {
            let s = rk4_step_sensitivity::<S, N, NX>(&self.system, &x, u, h);
            x = s.z_next;
            b = s.d_z * b + s.d_tau;
            a = s.d_z * a;
        }
        (x, a, b)
    }

    /// Writes the QP in the step variables at the current plan.
    pub(super) fn linearise(&mut self) {
        let nh = self.config.horizon;
        let cost = self.config.cost;
        let dt = self.config.dt;
        let q_eq = self.system.equilibrium();
        let mut substeps_taken = 0;
        let applied = self.history.entry(1).0;
        let mut bounds = super::response::StageBounds::<N>::new(
            self.config.torque_response,
            self.config.tau_max,
            &applied,
        );
        for k in 0..nh {
            // The Jacobian at the interval's start is the first RK4 stage's
            // and its acceleration chooses the substeps: computed once.
            let (z, u) = (&self.xs[k], &self.us[k]);
            let (q, qd) = unpack_state::<N, NX>(z);
            // The node's energy shares the Jacobian's trigonometry.
            let (first, energy) = self.system.dynamics_jacobian_with_energy(&q, &qd, u);
            let substeps = self.substeps_at(&qd, &first.acceleration);
            substeps_taken += substeps;
            let (x_next, a, b) = self.interval_sensitivity_from(z, u, substeps, &first);
            let m =
                stage_model_at::<S, N, NX>(&self.system, &self.reference, &cost, z, u, dt, &energy);
            // Stage k may apply what the motor reaches from the torque it
            // applies now ([`super::response`]; |tau| <= tau_max without a response).
            let (lower, upper) = bounds.next().expect("one per stage");
            let st = &mut self.stages.stages[k];
            st.a = a;
            st.b = b;
            st.c = x_next - self.xs[k + 1];
            st.q = m.q;
            st.s = m.s;
            st.r = m.r;
            st.q_lin = m.gz;
            st.r_lin = m.gu;
            st.u_lower = lower - self.us[k];
            st.u_upper = upper - self.us[k];
        }
        self.substeps_taken = substeps_taken;
        let scale = dt * self.config.terminal_scale;
        if scale > 0.0 {
            let m = stage_model::<S, N, NX>(
                &self.system,
                &self.reference,
                &cost,
                &self.xs[nh],
                &Vector::zeros(),
                scale,
            );
            self.stages.stages[nh].q = m.q;
            self.stages.stages[nh].q_lin = m.gz;
        } else {
            self.stages.stages[nh].q.fill(0.0);
            self.stages.stages[nh].q_lin.fill(0.0);
        }
        for k in 1..=nh {
            let (x, st) = (&self.xs[k], &mut self.stages.stages[k]);
            for i in 0..N {
                st.x_lower[i] = q_eq[i] - self.config.q_max - x[i];
                st.x_upper[i] = q_eq[i] + self.config.q_max - x[i];
                st.x_lower[N + i] = -self.config.qd_max - x[N + i];
                st.x_upper[N + i] = self.config.qd_max - x[N + i];
            }
        }
    }
}
