//! Reproducible synthetic OCP QPs for the QP solvers' tests and benchmarks:
//! generic random well-posed problems and RTI-shaped problems from random
//! linearisations of the paper's double pendulum (RK4 shooting with exact
//! sensitivities, Gauss-Newton stage costs, torque boxes, soft velocity
//! bounds).

use super::OcpQp;
use crate::integrate::rk4_step_sensitivity;
use crate::math;
use crate::mechanics::{DoublePendulum, Vector};
use nalgebra::{DMatrix, DVector, SVector};

/// Small deterministic generator (SplitMix64), so test and bench data do not
/// depend on a random-number crate's version.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// Generator with the given seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Standard normal (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.unit().max(1e-300);
        let u2 = self.unit();
        (-2.0 * math::ln(u1)).sqrt() * math::cos(std::f64::consts::TAU * u2)
    }

    /// Matrix with independent standard normal entries.
    pub fn normal_matrix(&mut self, rows: usize, cols: usize) -> DMatrix<f64> {
        DMatrix::from_fn(rows, cols, |_, _| self.normal())
    }

    /// Vector with independent standard normal entries.
    pub fn normal_vector(&mut self, len: usize) -> DVector<f64> {
        DVector::from_fn(len, |_, _| self.normal())
    }
}

/// Symmetrises `m` in place (removes round-off asymmetry of `J' W J`).
fn symmetrise(m: &mut DMatrix<f64>) {
    let t = m.transpose();
    *m += t;
    *m *= 0.5;
}

/// A random well-posed OCP QP: stable-ish dynamics `A = I + 0.1 G`, stage
/// Hessians `G'G / nv + 0.1 I` (coupled `S`), random gradients, offsets and
/// initial state; no bounds (add them as the test needs).
pub fn random_ocp_qp(rng: &mut SplitMix64, nx: usize, nu: usize, horizon: usize) -> OcpQp {
    let nv = nx + nu;
    let mut qp = OcpQp::new(nx, nu, horizon);
    for k in 0..horizon {
        qp.a[k] = DMatrix::identity(nx, nx) + rng.normal_matrix(nx, nx) * 0.1;
        qp.b[k] = rng.normal_matrix(nx, nu) * 0.5;
        qp.c[k] = rng.normal_vector(nx) * 0.05;
        let g = rng.normal_matrix(nv, nv);
        let mut h = g.transpose() * g / nv as f64 + DMatrix::identity(nv, nv) * 0.1;
        symmetrise(&mut h);
        qp.r[k] = h.view((0, 0), (nu, nu)).into_owned();
        qp.s[k] = h.view((0, nu), (nu, nx)).into_owned();
        qp.q[k] = h.view((nu, nu), (nx, nx)).into_owned();
        qp.q_lin[k] = rng.normal_vector(nx);
        qp.r_lin[k] = rng.normal_vector(nu);
    }
    let g = rng.normal_matrix(nx, nx);
    let mut qn = g.transpose() * g / nx as f64 + DMatrix::identity(nx, nx) * 0.1;
    symmetrise(&mut qn);
    qp.q[horizon] = qn;
    qp.q_lin[horizon] = rng.normal_vector(nx);
    qp.x0 = rng.normal_vector(nx);
    qp
}

/// Options of [`pendulum_rti_qp`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PendulumQpOptions {
    /// Horizon `N`.
    pub horizon: usize,
    /// Shooting interval (s).
    pub dt: f64,
    /// Torque bound `|tau| <= tau_max` (N m).
    pub tau_max: f64,
    /// Standard deviation of the measured-state deviation `x0`.
    pub initial_deviation: f64,
    /// Soft bound on the joint velocities `|qd| <= velocity_bound` (none if
    /// infinite), with L1 weight 100 and L2 weight 1000.
    pub velocity_bound: f64,
}

impl Default for PendulumQpOptions {
    fn default() -> Self {
        Self {
            horizon: 80,
            dt: 0.025,
            tau_max: 1.0,
            initial_deviation: 0.05,
            velocity_bound: 6.0,
        }
    }
}

/// An RTI-shaped QP (in step form) from a random linearisation of the
/// double pendulum: random shooting nodes along a trajectory from a random
/// state of the paper's swinging regime (angles within +-pi/2 of hanging,
/// velocities within +-2 rad/s) with small gaps, random nominal torques, RK4 sensitivities as
/// `A_k, B_k`, Gauss-Newton costs `J'WJ` (random `J` of rank at most 6) plus
/// `R = 225 I`-like torque weights, torque boxes shifted by the nominal
/// torques and soft velocity bounds.
pub fn pendulum_rti_qp(rng: &mut SplitMix64, opts: &PendulumQpOptions) -> OcpQp {
    let sys = DoublePendulum::default();
    let (nx, nu, n) = (4, 2, opts.horizon);
    let mut qp = OcpQp::new(nx, nu, n);
    let pi = std::f64::consts::PI;
    let mut z = SVector::<f64, 4>::new(
        rng.uniform(-0.5, 0.5) * pi,
        rng.uniform(-0.5, 0.5) * pi,
        rng.uniform(-2.0, 2.0),
        rng.uniform(-2.0, 2.0),
    );
    let residual_weights = |rng: &mut SplitMix64, cols: usize| {
        let rows = 1 + (rng.next_u64() % 6) as usize;
        let j = rng.normal_matrix(rows, cols);
        let w = DMatrix::from_diagonal(&DVector::from_fn(rows, |_, _| {
            math::powf(10.0, rng.uniform(0.0, 2.0))
        }));
        let y = rng.normal_vector(rows);
        let mut h = j.transpose() * &w * &j;
        symmetrise(&mut h);
        let g = j.transpose() * (&w * y);
        (h, g)
    };
    for k in 0..n {
        let tau = Vector::<2>::new(
            rng.uniform(-1.2, 1.2) * opts.tau_max,
            rng.uniform(-1.2, 1.2) * opts.tau_max,
        );
        let sens = rk4_step_sensitivity::<DoublePendulum, 2, 4>(&sys, &z, &tau, opts.dt);
        let next = sens.z_next + SVector::<f64, 4>::from_fn(|_, _| 0.01 * rng.normal());
        for i in 0..nx {
            for j in 0..nx {
                qp.a[k][(i, j)] = sens.d_z[(i, j)];
            }
            for j in 0..nu {
                qp.b[k][(i, j)] = sens.d_tau[(i, j)];
            }
            qp.c[k][i] = sens.z_next[i] - next[i];
        }
        let (mut h, g) = residual_weights(rng, nx + nu);
        for j in 0..nu {
            h[(j, j)] += 225.0 * rng.uniform(0.8, 1.2);
        }
        qp.r[k] = h.view((0, 0), (nu, nu)).into_owned();
        qp.s[k] = h.view((0, nu), (nu, nx)).into_owned();
        qp.q[k] = h.view((nu, nu), (nx, nx)).into_owned();
        qp.r_lin[k] = g.rows(0, nu).into_owned();
        qp.q_lin[k] = g.rows(nu, nx).into_owned();
        for j in 0..nu {
            qp.u_lower[k][j] = -opts.tau_max - tau[j];
            qp.u_upper[k][j] = opts.tau_max - tau[j];
        }
        if k > 0 {
            set_velocity_bounds(&mut qp, k, &z, opts.velocity_bound);
        }
        z = next;
    }
    let (h, g) = residual_weights(rng, nx);
    qp.q[n] = h;
    qp.q_lin[n] = g;
    set_velocity_bounds(&mut qp, n, &z, opts.velocity_bound);
    if opts.velocity_bound.is_finite() {
        qp.soft_l1 = DVector::from_vec(vec![0.0, 0.0, 100.0, 100.0]);
        qp.soft_l2 = DVector::from_vec(vec![0.0, 0.0, 1000.0, 1000.0]);
    }
    qp.x0 = rng.normal_vector(nx) * opts.initial_deviation;
    qp
}

/// Soft bounds `|qd| <= bound` on the step `dx` around the node `z`.
fn set_velocity_bounds(qp: &mut OcpQp, k: usize, z: &SVector<f64, 4>, bound: f64) {
    if bound.is_finite() {
        for i in 2..4 {
            qp.x_lower[k][i] = -bound - z[i];
            qp.x_upper[k][i] = bound - z[i];
        }
    }
}
