//! The converged SQP mode (first sample): Gauss-Newton iterations with a
//! backtracking line search on the L1 merit function.

use super::cost::stage_cost;
use super::{ControlOutput, ControlStatus, Controller};
use crate::mechanics::{MechanicalSystem, Vector};
use nalgebra::SVector;

impl<S, const N: usize, const NX: usize> Controller<S, N, NX>
where
    S: MechanicalSystem<N>,
{
    /// Full SQP at `z` to convergence (Gauss-Newton, L1-merit backtracking
    /// line search) from the current plan. Returns the first control.
    pub fn solve_to_convergence(&mut self, z: &SVector<f64, NX>) -> ControlOutput<N> {
        if !z.iter().all(|v| v.is_finite()) {
            return self.fallback(ControlStatus::InvalidState);
        }
        if !self.initialised {
            self.initialise(z);
        }
        let mut qp_iterations = 0;
        for it in 0..self.config.sqp.max_iterations {
            if !self.prepared {
                self.linearise();
            }
            self.set_initial_state(z);
            let status = self.solve_qp();
            qp_iterations += self.solution.iterations;
            if !status.is_usable() {
                return self.fallback(ControlStatus::QpFailed(status));
            }
            let step = self.line_search(z);
            self.prepared = false;
            if step.1 == 0.0 {
                // No step length decreased the merit: stop rather than creep.
                return self.output(ControlStatus::NotConverged, qp_iterations, it + 1);
            }
            if step.1 == 1.0 && step.0 < self.config.sqp.tolerance {
                return self.output(ControlStatus::Solved, qp_iterations, it + 1);
            }
        }
        let n = self.config.sqp.max_iterations;
        self.output(ControlStatus::NotConverged, qp_iterations, n)
    }

    /// Objective plus soft-bound penalty plus `penalty` times the L1 norm of
    /// the constraint violations (initial state and continuity).
    pub(super) fn merit(
        &self,
        xs: &[SVector<f64, NX>],
        us: &[Vector<N>],
        z: &SVector<f64, NX>,
        penalty: f64,
    ) -> f64 {
        let nh = self.config.horizon;
        let cost = &self.config.cost;
        let dt = self.config.dt;
        let mut objective = 0.0;
        let mut violation = (z - xs[0]).lp_norm(1);
        for k in 0..nh {
            objective +=
                stage_cost::<S, N, NX>(&self.system, &self.reference, cost, &xs[k], &us[k], dt);
            violation += (self.simulate_interval(&xs[k], &us[k]) - xs[k + 1]).lp_norm(1);
        }
        if self.config.terminal_scale > 0.0 {
            objective += stage_cost::<S, N, NX>(
                &self.system,
                &self.reference,
                cost,
                &xs[nh],
                &Vector::zeros(),
                dt * self.config.terminal_scale,
            );
        }
        objective + self.soft_penalty(xs) + penalty * violation
    }

    pub(super) fn soft_penalty(&self, xs: &[SVector<f64, NX>]) -> f64 {
        if self.config.q_max.is_infinite() && self.config.qd_max.is_infinite() {
            return 0.0;
        }
        let q_eq = self.system.equilibrium();
        let mut p = 0.0;
        for x in &xs[1..] {
            for i in 0..NX {
                let (centre, bound) = if i < N {
                    (q_eq[i], self.config.q_max)
                } else {
                    (0.0, self.config.qd_max)
                };
                let v = ((x[i] - centre).abs() - bound).max(0.0);
                p += self.config.soft_l1 * v + 0.5 * self.config.soft_l2 * v * v;
            }
        }
        p
    }

    /// Backtracking on the L1 merit along the QP step; applies the accepted
    /// step and returns (step infinity norm, accepted step length), the
    /// length 0 when no tested length decreased the merit (nothing applied).
    pub(super) fn line_search(&mut self, z: &SVector<f64, NX>) -> (f64, f64) {
        let nh = self.config.horizon;
        let mut max_pi: f64 = 0.0;
        for pi in &self.solution.pi {
            max_pi = max_pi.max(pi.amax());
        }
        // The multiplier of the initial-state constraint, from stationarity at x_0.
        let (first, sol) = (&self.stages.stages[0], &self.solution);
        for i in 0..NX {
            let mut lam = first.q_lin[i];
            for j in 0..NX {
                lam += first.q[(i, j)] * sol.x[0][j] + first.a[(j, i)] * sol.pi[0][j];
            }
            for j in 0..N {
                lam += first.s[(j, i)] * sol.u[0][j];
            }
            max_pi = max_pi.max(lam.abs());
        }
        self.merit_penalty = self.merit_penalty.max(1.5 * max_pi + 1e-3);
        let mu = self.merit_penalty;

        let mut step_norm: f64 = 0.0;
        let mut slope = 0.0;
        let stages = &self.stages.stages;
        let mut violation = self.stages.x0.lp_norm(1);
        for (k, st) in stages[..nh].iter().enumerate() {
            step_norm = step_norm
                .max(self.solution.x[k].amax())
                .max(self.solution.u[k].amax());
            slope += st.q_lin.dot(&self.solution.x[k]) + st.r_lin.dot(&self.solution.u[k]);
            violation += st.c.lp_norm(1);
        }
        step_norm = step_norm.max(self.solution.x[nh].amax());
        slope += stages[nh].q_lin.dot(&self.solution.x[nh]);
        let slope = slope - mu * violation;

        let base = self.merit(&self.xs, &self.us, z, mu);
        let mut alpha = 1.0;
        let mut accepted = false;
        while alpha > 1e-4 {
            for k in 0..=nh {
                let mut x = self.xs[k];
                for i in 0..NX {
                    x[i] += alpha * self.solution.x[k][i];
                }
                self.xs_trial[k] = x;
                if k < nh {
                    let mut u = self.us[k];
                    for i in 0..N {
                        u[i] += alpha * self.solution.u[k][i];
                    }
                    self.us_trial[k] = u;
                }
            }
            let trial = self.merit(&self.xs_trial, &self.us_trial, z, mu);
            // Armijo on the merit, with room for round-off in its evaluation
            // (near the solution the decrease is below the noise).
            let noise = 1e-12 * base.abs().max(1.0);
            if trial <= base + 1e-4 * alpha * slope.min(0.0) + noise || step_norm < 1e-12 {
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if !accepted {
            return (step_norm, 0.0);
        }
        self.apply_step(alpha);
        (step_norm, alpha)
    }
}
