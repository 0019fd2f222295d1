//! Preparation phase: integration of every shooting interval with RK4 and
//! exact sensitivities, and the QP in the step variables at the current plan.

use super::Controller;
use super::cost::stage_model;
use crate::integrate::rk4_step_sensitivity;
use crate::mechanics::{MechanicalSystem, Vector};
use nalgebra::{SMatrix, SVector};

impl<S, const N: usize, const NX: usize> Controller<S, N, NX>
where
    S: MechanicalSystem<N>,
{
    pub(super) fn simulate_interval(
        &self,
        z: &SVector<f64, NX>,
        u: &Vector<N>,
    ) -> SVector<f64, NX> {
        let h = self.config.dt / self.config.substeps as f64;
        let mut x = *z;
        for _ in 0..self.config.substeps {
            x = crate::integrate::rk4_step::<S, N, NX>(&self.system, &x, u, h);
        }
        x
    }

    /// Integration with sensitivities over one shooting interval.
    pub(super) fn interval_sensitivity(
        &self,
        z: &SVector<f64, NX>,
        u: &Vector<N>,
    ) -> (SVector<f64, NX>, SMatrix<f64, NX, NX>, SMatrix<f64, NX, N>) {
        let h = self.config.dt / self.config.substeps as f64;
        let mut x = *z;
        let mut a = SMatrix::<f64, NX, NX>::identity();
        let mut b = SMatrix::<f64, NX, N>::zeros();
        for _ in 0..self.config.substeps {
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
        for k in 0..nh {
            let (x_next, a, b) = self.interval_sensitivity(&self.xs[k], &self.us[k]);
            let m = stage_model::<S, N, NX>(
                &self.system,
                &self.reference,
                &cost,
                &self.xs[k],
                &self.us[k],
                dt,
            );
            self.qp.a[k].copy_from(&a);
            self.qp.b[k].copy_from(&b);
            self.qp.c[k].copy_from(&(x_next - self.xs[k + 1]));
            self.qp.q[k].copy_from(&m.q);
            self.qp.s[k].copy_from(&m.s);
            self.qp.r[k].copy_from(&m.r);
            self.qp.q_lin[k].copy_from(&m.gz);
            self.qp.r_lin[k].copy_from(&m.gu);
            for i in 0..N {
                self.qp.u_lower[k][i] = -self.config.tau_max - self.us[k][i];
                self.qp.u_upper[k][i] = self.config.tau_max - self.us[k][i];
            }
        }
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
            self.qp.q[nh].copy_from(&m.q);
            self.qp.q_lin[nh].copy_from(&m.gz);
        } else {
            self.qp.q[nh].fill(0.0);
            self.qp.q_lin[nh].fill(0.0);
        }
        for k in 1..=nh {
            for i in 0..N {
                let x = &self.xs[k];
                self.qp.x_lower[k][i] = q_eq[i] - self.config.q_max - x[i];
                self.qp.x_upper[k][i] = q_eq[i] + self.config.q_max - x[i];
                self.qp.x_lower[k][N + i] = -self.config.qd_max - x[N + i];
                self.qp.x_upper[k][N + i] = self.config.qd_max - x[N + i];
            }
        }
    }
}
