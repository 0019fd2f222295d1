//! Time integrators: fixed-step RK4 with exact sensitivities (the NMPC's
//! shooting map) and adaptive Dormand-Prince 5(4) (the plant and the orbit
//! computations).

use crate::math;
use crate::mechanics::{
    DynamicsJacobian, MechanicalSystem, Vector, pack_state, state_derivative, state_jacobian,
    unpack_state,
};
use nalgebra::{SMatrix, SVector};
use std::ops::{Add, Mul};
use thiserror::Error;

/// A value an ODE integrator can advance: a vector space with a weighted norm.
///
/// Implemented for stacked-allocated `nalgebra` vectors and matrices, and for
/// [`Variational`] (state plus sensitivity matrix), so no integration step
/// touches the heap.
pub trait OdeState: Copy + Add<Output = Self> + Mul<f64, Output = Self> {
    /// Number of scalar components (for the RMS error norm).
    fn component_count(&self) -> usize;
    /// Sum over components of `(err_i / (atol + rtol max(|a_i|, |b_i|)))^2`.
    fn weighted_sq_error(&self, a: &Self, b: &Self, atol: f64, rtol: f64) -> f64;
    /// True when every component is finite.
    fn is_finite(&self) -> bool;
}

impl<const R: usize, const C: usize> OdeState for SMatrix<f64, R, C> {
    fn component_count(&self) -> usize {
        R * C
    }
    fn weighted_sq_error(&self, a: &Self, b: &Self, atol: f64, rtol: f64) -> f64 {
        let mut sum = 0.0;
        for i in 0..R * C {
            let scale = atol + rtol * a[i].abs().max(b[i].abs());
            let e = self[i] / scale;
            sum += e * e;
        }
        sum
    }
    fn is_finite(&self) -> bool {
        self.iter().all(|x| x.is_finite())
    }
}

/// A state `z` with its sensitivity `Phi = dz/dz0` (variational equations).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variational<const NX: usize> {
    /// The state.
    pub z: SVector<f64, NX>,
    /// Sensitivity of the state w.r.t. the initial state.
    pub phi: SMatrix<f64, NX, NX>,
}

impl<const NX: usize> Add for Variational<NX> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            z: self.z + o.z,
            phi: self.phi + o.phi,
        }
    }
}

impl<const NX: usize> Mul<f64> for Variational<NX> {
    type Output = Self;
    fn mul(self, s: f64) -> Self {
        Self {
            z: self.z * s,
            phi: self.phi * s,
        }
    }
}

impl<const NX: usize> OdeState for Variational<NX> {
    fn component_count(&self) -> usize {
        NX + NX * NX
    }
    fn weighted_sq_error(&self, a: &Self, b: &Self, atol: f64, rtol: f64) -> f64 {
        self.z.weighted_sq_error(&a.z, &b.z, atol, rtol)
            + self.phi.weighted_sq_error(&a.phi, &b.phi, atol, rtol)
    }
    fn is_finite(&self) -> bool {
        self.z.is_finite() && self.phi.is_finite()
    }
}

/// Free (or constant-torque) dynamics with variational equations:
/// `zd = f(z)`, `Phid = (df/dz) Phi`.
pub fn variational_rhs<S, const N: usize, const NX: usize>(
    system: &S,
    tau: &Vector<N>,
    v: &Variational<NX>,
) -> Variational<NX>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let (zd, a, _) = state_jacobian::<S, N, NX>(system, &v.z, tau);
    Variational {
        z: zd,
        phi: a * v.phi,
    }
}

/// One classical RK4 step of length `h` with the torque held constant.
pub fn rk4_step<S, const N: usize, const NX: usize>(
    system: &S,
    z: &SVector<f64, NX>,
    tau: &Vector<N>,
    h: f64,
) -> SVector<f64, NX>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let f = |z: &SVector<f64, NX>| state_derivative::<S, N, NX>(system, z, tau);
    let k1 = f(z);
    let k2 = f(&(z + k1 * (0.5 * h)));
    let k3 = f(&(z + k2 * (0.5 * h)));
    let k4 = f(&(z + k3 * h));
    z + (k1 + (k2 + k3) * 2.0 + k4) * (h / 6.0)
}

/// Result of an RK4 step with its exact derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rk4Sensitivity<const N: usize, const NX: usize> {
    /// The state after the step.
    pub z_next: SVector<f64, NX>,
    /// `d z_next / d z`.
    pub d_z: SMatrix<f64, NX, NX>,
    /// `d z_next / d tau`.
    pub d_tau: SMatrix<f64, NX, N>,
}

/// One RK4 step of length `h` (torque held) with exact sensitivities,
/// obtained by differentiating the four stages (internal numerical
/// differentiation would cost accuracy, not speed).
pub fn rk4_step_sensitivity<S, const N: usize, const NX: usize>(
    system: &S,
    z: &SVector<f64, NX>,
    tau: &Vector<N>,
    h: f64,
) -> Rk4Sensitivity<N, NX>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let (q, qd) = unpack_state::<N, NX>(z);
    let first = system.dynamics_jacobian(&q, &qd, tau);
    rk4_step_sensitivity_from(system, z, tau, h, &first)
}

/// [`rk4_step_sensitivity`] given the dynamics Jacobian at `z` (the first
/// stage's, which does not depend on `h`): a caller that needs the
/// acceleration at `z` anyway, to choose the substeps, computes it once.
pub fn rk4_step_sensitivity_from<S, const N: usize, const NX: usize>(
    system: &S,
    z: &SVector<f64, NX>,
    tau: &Vector<N>,
    h: f64,
    first: &DynamicsJacobian<N>,
) -> Rk4Sensitivity<N, NX>
where
    S: MechanicalSystem<N> + ?Sized,
{
    // A stage's Jacobian is [0 I; Dq Dqd] (and [0; Dtau] for the torque):
    // products with it take the lower block rows only, half of a dense
    // product (issue 12).
    let eye = SMatrix::<f64, NX, NX>::identity();
    let stage = |x: &SVector<f64, NX>| {
        let (q, qd) = unpack_state::<N, NX>(x);
        let jac = system.dynamics_jacobian(&q, &qd, tau);
        (pack_state::<N, NX>(&qd, &jac.acceleration), jac)
    };
    let (_, qd) = unpack_state::<N, NX>(z);
    let (k1, j1) = (pack_state::<N, NX>(&qd, &first.acceleration), *first);
    let (dk1_z, dk1_u) = (state_jacobian_of(&j1), torque_column::<N, NX>(&j1));

    let z2 = z + k1 * (0.5 * h);
    let (k2, j2) = stage(&z2);
    let dk2_z = jacobian_times::<N, NX, NX>(&j2, &(eye + dk1_z * (0.5 * h)));
    let dk2_u = jacobian_times::<N, NX, N>(&j2, &(dk1_u * (0.5 * h))) + torque_column::<N, NX>(&j2);

    let z3 = z + k2 * (0.5 * h);
    let (k3, j3) = stage(&z3);
    let dk3_z = jacobian_times::<N, NX, NX>(&j3, &(eye + dk2_z * (0.5 * h)));
    let dk3_u = jacobian_times::<N, NX, N>(&j3, &(dk2_u * (0.5 * h))) + torque_column::<N, NX>(&j3);

    let z4 = z + k3 * h;
    let (k4, j4) = stage(&z4);
    let dk4_z = jacobian_times::<N, NX, NX>(&j4, &(eye + dk3_z * h));
    let dk4_u = jacobian_times::<N, NX, N>(&j4, &(dk3_u * h)) + torque_column::<N, NX>(&j4);

    let w = h / 6.0;
    Rk4Sensitivity {
        z_next: z + (k1 + (k2 + k3) * 2.0 + k4) * w,
        d_z: eye + (dk1_z + (dk2_z + dk3_z) * 2.0 + dk4_z) * w,
        d_tau: (dk1_u + (dk2_u + dk3_u) * 2.0 + dk4_u) * w,
    }
}

/// `[0 I; Dq Dqd] x`: the state Jacobian of the first-order dynamics times `x`.
#[inline(always)]
fn jacobian_times<const N: usize, const NX: usize, const C: usize>(
    jac: &DynamicsJacobian<N>,
    x: &SMatrix<f64, NX, C>,
) -> SMatrix<f64, NX, C> {
    // Written out: nalgebra's products are outlined calls from 3 joints
    // up, each with its temporary. The same sums in the same order as its
    // `d_q * top + d_qd * bottom` (each product's terms by ascending
    // index), so the same bits.
    let mut out = SMatrix::<f64, NX, C>::zeros();
    for c in 0..C {
        for r in 0..N {
            out[(r, c)] = x[(N + r, c)];
            let mut from_q = jac.d_q[(r, 0)] * x[(0, c)];
            let mut from_qd = jac.d_qd[(r, 0)] * x[(N, c)];
            for i in 1..N {
                from_q += jac.d_q[(r, i)] * x[(i, c)];
                from_qd += jac.d_qd[(r, i)] * x[(N + i, c)];
            }
            out[(N + r, c)] = from_q + from_qd;
        }
    }
    out
}

/// `[0 I; Dq Dqd]` itself (its product with the identity, without the
/// products).
#[inline(always)]
fn state_jacobian_of<const N: usize, const NX: usize>(
    jac: &DynamicsJacobian<N>,
) -> SMatrix<f64, NX, NX> {
    let mut out = SMatrix::<f64, NX, NX>::zeros();
    out.fixed_view_mut::<N, N>(0, N).fill_with_identity();
    out.fixed_view_mut::<N, N>(N, 0).copy_from(&jac.d_q);
    out.fixed_view_mut::<N, N>(N, N).copy_from(&jac.d_qd);
    out
}

/// `[0; Dtau]`: the torque Jacobian of the first-order dynamics.
#[inline(always)]
fn torque_column<const N: usize, const NX: usize>(
    jac: &DynamicsJacobian<N>,
) -> SMatrix<f64, NX, N> {
    let mut out = SMatrix::<f64, NX, N>::zeros();
    out.fixed_rows_mut::<N>(N).copy_from(&jac.d_tau);
    out
}

/// Tolerances of the adaptive integrator.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Tolerances {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
}

impl Default for Tolerances {
    /// Tight enough that orbit closing errors stay near 1e-10.
    fn default() -> Self {
        Self {
            rtol: 1e-12,
            atol: 1e-12,
        }
    }
}

/// Why an adaptive integration stopped.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum IntegrationError {
    /// The state or its derivative became NaN or infinite.
    #[error("integration produced a non-finite state at t = {t}")]
    NonFinite {
        /// Time reached.
        t: f64,
    },
    /// The step size fell below what the floating-point time can resolve.
    #[error("step size underflow at t = {t} (stiff or singular dynamics)")]
    StepSizeUnderflow {
        /// Time reached.
        t: f64,
    },
    /// More steps than allowed.
    #[error("exceeded {max_steps} steps at t = {t}")]
    TooManySteps {
        /// Time reached.
        t: f64,
        /// The limit.
        max_steps: usize,
    },
}

// Dormand-Prince 5(4) tableau (Hairer, Norsett, Wanner; DOPRI5).
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;

/// Adaptive Dormand-Prince 5(4) integrator that keeps its state between
/// calls, so a caller can advance it in chunks (co-simulation steps, path
/// samples) without losing the step size or the FSAL stage. Serializable
/// (an FMU's saved state): a restored integrator continues bit for bit.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Dopri5<S: OdeState> {
    t: f64,
    y: S,
    /// Derivative at `(t, y)` (first-same-as-last stage).
    dy: Option<S>,
    h: f64,
    tol: Tolerances,
    /// Step budget per `advance_to` call.
    pub max_steps: usize,
    steps: usize,
    evaluations: usize,
}

impl<S: OdeState> Dopri5<S> {
    /// Starts at `(t0, y0)` with the given tolerances.
    pub fn new(t0: f64, y0: S, tol: Tolerances) -> Self {
        Self {
            t: t0,
            y: y0,
            dy: None,
            h: 0.0,
            tol,
            max_steps: 1_000_000,
            steps: 0,
            evaluations: 0,
        }
    }

    /// Current time.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Current state.
    pub fn state(&self) -> &S {
        &self.y
    }

    /// Accepted steps so far.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Right-hand-side evaluations so far.
    pub fn evaluations(&self) -> usize {
        self.evaluations
    }

    /// Replaces the state (e.g. after an input change); keeps the step size.
    pub fn reset(&mut self, t: f64, y: S) {
        self.t = t;
        self.y = y;
        self.dy = None;
    }

    fn error_norm(&self, err: &S, y0: &S, y1: &S) -> f64 {
        (err.weighted_sq_error(y0, y1, self.tol.atol, self.tol.rtol) / err.component_count() as f64)
            .sqrt()
    }

    /// Initial step guess (Hairer, Norsett & Wanner, Solving ODEs I, II.4).
    ///
    /// When the state or its derivative is below the tolerance scale (a
    /// start from rest with `atol = 1e-12`), `d0 / d1` says nothing about the
    /// time scale, and the rule falls back to `h0 = 1e-6` instead of the
    /// ratio (which collapses to ~1e-17 s and underflows).
    fn initial_step(&mut self, f: &mut impl FnMut(f64, &S) -> S, dy0: &S, span: f64) -> f64 {
        let zero = self.y * 0.0;
        let d0 = self.error_norm(&self.y, &zero, &zero);
        let d1 = self.error_norm(dy0, &self.y, &self.y);
        let h0 = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        }
        .min(span.abs());
        let y1 = self.y + *dy0 * h0;
        let dy1 = f(self.t + h0, &y1);
        self.evaluations += 1;
        let d2 = self.error_norm(&(dy1 + *dy0 * -1.0), &self.y, &self.y) / h0;
        let h1 = if d1.max(d2) <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            math::powf(0.01 / d1.max(d2), 0.2)
        };
        (100.0 * h0).min(h1).min(span.abs())
    }

    /// Integrates `y' = f(t, y)` up to exactly `t_end` (forward or backward).
    pub fn advance_to(
        &mut self,
        mut f: impl FnMut(f64, &S) -> S,
        t_end: f64,
    ) -> Result<&S, IntegrationError> {
        let span = t_end - self.t;
        if span == 0.0 {
            return Ok(&self.y);
        }
        let dir = span.signum();
        let mut dy = match self.dy {
            Some(d) => d,
            None => {
                self.evaluations += 1;
                f(self.t, &self.y)
            }
        };
        if !dy.is_finite() || !self.y.is_finite() {
            return Err(IntegrationError::NonFinite { t: self.t });
        }
        if self.h == 0.0 || self.h.is_nan() {
            self.h = self.initial_step(&mut f, &dy, span);
        }
        let mut h = self.h.abs().min(span.abs());
        let mut budget = self.max_steps;
        loop {
            let remaining = (t_end - self.t) * dir;
            if remaining <= 0.0 {
                break;
            }
            // Take the last step exactly to t_end (avoid a tiny leftover step).
            let last = h >= remaining * (1.0 - 1e-12);
            let hs = if last { remaining } else { h } * dir;
            if hs.abs() <= 1e-14 * self.t.abs().max(1.0) {
                return Err(IntegrationError::StepSizeUnderflow { t: self.t });
            }
            if budget == 0 {
                return Err(IntegrationError::TooManySteps {
                    t: self.t,
                    max_steps: self.max_steps,
                });
            }
            budget -= 1;
            let (t, y) = (self.t, self.y);
            let k1 = dy;
            let k2 = f(t + C2 * hs, &(y + k1 * (A21 * hs)));
            let k3 = f(t + C3 * hs, &(y + (k1 * A31 + k2 * A32) * hs));
            let k4 = f(t + C4 * hs, &(y + (k1 * A41 + k2 * A42 + k3 * A43) * hs));
            let k5 = f(
                t + C5 * hs,
                &(y + (k1 * A51 + k2 * A52 + k3 * A53 + k4 * A54) * hs),
            );
            let k6 = f(
                t + hs,
                &(y + (k1 * A61 + k2 * A62 + k3 * A63 + k4 * A64 + k5 * A65) * hs),
            );
            let y_new = y + (k1 * A71 + k3 * A73 + k4 * A74 + k5 * A75 + k6 * A76) * hs;
            let k7 = f(t + hs, &y_new);
            self.evaluations += 6;
            let err = (k1 * E1 + k3 * E3 + k4 * E4 + k5 * E5 + k6 * E6 + k7 * E7) * hs;
            let en = self.error_norm(&err, &y, &y_new);
            if !en.is_finite() {
                // Retry smaller: a NaN from a too-large step is common near
                // singular configurations; a genuinely non-finite state is not.
                if !y.is_finite() {
                    return Err(IntegrationError::NonFinite { t });
                }
                h = hs.abs() * 0.1;
                continue;
            }
            let factor = if en == 0.0 {
                5.0
            } else {
                (0.9 * math::powf(en, -0.2)).clamp(0.2, 5.0)
            };
            if en <= 1.0 {
                self.t = if last { t_end } else { t + hs };
                self.y = y_new;
                dy = k7;
                self.steps += 1;
                if !last {
                    h = hs.abs() * factor;
                } else {
                    // Keep the natural step for the next call, not the clipped one.
                    h = h.max(hs.abs() * factor.min(1.0));
                }
            } else {
                h = hs.abs() * factor.min(1.0);
            }
        }
        self.h = h;
        self.dy = Some(dy);
        Ok(&self.y)
    }
}

/// Integrates the system with constant torque from `z0` over `duration`
/// with the adaptive integrator; returns the final state.
pub fn simulate_accurate<S, const N: usize, const NX: usize>(
    system: &S,
    z0: &SVector<f64, NX>,
    tau: &Vector<N>,
    duration: f64,
    tol: Tolerances,
) -> Result<SVector<f64, NX>, IntegrationError>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let mut ode = Dopri5::new(0.0, *z0, tol);
    ode.advance_to(
        |_, z| state_derivative::<S, N, NX>(system, z, tau),
        duration,
    )
    .copied()
}
