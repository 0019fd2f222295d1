//! The EigenMPC running costs (paper, eqs. 10 and 12) in least-squares form
//! `l = w_E r_E^2 + w_x |r_x|^2 + w_xd |r_xd|^2 + w_F |r_F|^2`, their exact
//! residual Jacobians and the Gauss-Newton Hessian blocks they give.
//!
//! Below the energy scale `E_s` the energy residual is scaled by
//! `sqrt(E_s / E_ref)` ([`CostParams::energy_scale`]): the paper's
//! `r_E = E_ref - E` values a joule gained at a given fraction of the climb
//! in proportion to `E_ref`, so its weights, tuned at 14 J, pull towards
//! 3 J with a fifth of that.

use super::Variant;
use crate::mechanics::{Matrix, MechanicalSystem, Vector, unpack_state};
use crate::modes::Chart;
use nalgebra::{SMatrix, SVector};

/// The paper's weights `W_z = diag(w_E, w_x, w_x, w_xd, w_xd)`, `W_F = w_F I`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Weights {
    /// Energy error weight `w_E`.
    pub energy: f64,
    /// Position-distance weight `w_x`.
    pub position: f64,
    /// Velocity-distance weight `w_xd`.
    pub velocity: f64,
    /// Torque weight `w_F`.
    pub torque: f64,
}

impl Weights {
    /// The paper's tuning (section V-A): `w_x = 50`, `w_xd = 2500`,
    /// `w_F = 225`, `w_E = 25` (curved) or `5` (straight).
    pub fn paper(variant: Variant) -> Self {
        Self {
            energy: variant.info().paper_energy_weight,
            position: 50.0,
            velocity: 2500.0,
            torque: 225.0,
        }
    }
}

/// The a-priori knowledge the cost measures distances to.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Reference<const N: usize> {
    /// Straight EigenMPC: the unit linear eigenvector `c`.
    Straight {
        /// Unit eigenvector of the linearised system.
        eigenvector: Vector<N>,
    },
    /// Curved EigenMPC: a chart of the eigenmode at `E_ref`.
    Curved(Chart<N>),
    /// Hybrid EigenMPC: the curved distance to the chart, blended by
    /// `tanh(alpha E)` as in the straight cost.
    Hybrid(Chart<N>),
}

impl<const N: usize> Reference<N> {
    /// The cost variant this reference selects.
    pub fn variant(&self) -> Variant {
        match self {
            Reference::Straight { .. } => Variant::Straight,
            Reference::Curved(_) => Variant::Curved,
            Reference::Hybrid(_) => Variant::Hybrid,
        }
    }

    /// The chart of `variant` (curved or hybrid); a straight variant gets
    /// the chart's linear eigenvector.
    pub fn with_chart(variant: Variant, chart: Chart<N>) -> Self {
        match variant {
            Variant::Straight => Reference::Straight {
                eigenvector: chart.eigenvector,
            },
            Variant::Curved => Reference::Curved(chart),
            Variant::Hybrid => Reference::Hybrid(chart),
        }
    }

    /// The chart the cost follows (curved, hybrid).
    pub fn chart(&self) -> Option<&Chart<N>> {
        match self {
            Reference::Straight { .. } => None,
            Reference::Curved(chart) | Reference::Hybrid(chart) => Some(chart),
        }
    }

    /// The chart, mutable (rewritten in place from a family).
    pub fn chart_mut(&mut self) -> Option<&mut Chart<N>> {
        match self {
            Reference::Straight { .. } => None,
            Reference::Curved(chart) | Reference::Hybrid(chart) => Some(chart),
        }
    }

    /// Checks for non-finite or degenerate data.
    pub fn validate(&self) -> Result<(), String> {
        let c = match self {
            Reference::Straight { eigenvector } => eigenvector,
            Reference::Curved(chart) | Reference::Hybrid(chart) => {
                if chart.coefficients.iter().flatten().any(|v| !v.is_finite())
                    || chart.equilibrium.iter().any(|v| !v.is_finite())
                {
                    return Err("chart coefficients must be finite".into());
                }
                &chart.eigenvector
            }
        };
        if c.iter().any(|v| !v.is_finite()) || c.norm() < 1e-12 {
            return Err("the eigenvector must be finite and nonzero".into());
        }
        Ok(())
    }
}

/// The energy at which the paper tuned `w_E` (its `E_ref`, section V-A):
/// the default [`CostParams::energy_scale`], at which the scaled energy
/// residual is exactly the paper's.
pub const PAPER_ENERGY_SCALE: f64 = 14.0;

/// Tunable cost parameters (may change between samples).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CostParams {
    /// Reference energy `E_ref` (J).
    pub e_ref: f64,
    /// Exploration gain `alpha` of the straight cost (1/J).
    pub alpha: f64,
    /// Torque-weight offset `beta` of the straight cost.
    pub beta: f64,
    /// Residual weights.
    pub weights: Weights,
    /// Energy scale `E_s` (J): below it the energy residual is
    /// `r_E = (E_ref - E) sqrt(E_s / E_ref)`, from it up the paper's
    /// `E_ref - E`. What the energy term trades against the torque is the
    /// value of a joule gained, `d(w_E r_E^2)/dE`: with the paper's residual
    /// `-2 w_E E_ref (1 - E/E_ref)`, which at a low `E_ref` is a fraction of
    /// what `w_E` was tuned for, so a low `E_ref` is approached slowly.
    /// Scaled, it is `-2 w_E E_s (1 - E/E_ref)`: the same function of the
    /// climb's progress as at `E_ref = E_s`. The scale only lifts: it never
    /// pulls less than the paper's residual, and at and above `E_s` (default
    /// [`PAPER_ENERGY_SCALE`], where `w_E` was tuned) the residual is the
    /// paper's exactly. 0: the paper's residual at every `E_ref` (and what
    /// a saved state without this field computed). With `E_s > 0`, `E_ref`
    /// must be > 0.
    #[serde(default)]
    pub energy_scale: f64,
    /// Penalise the torque beyond the model's friction, `tau - tau_f(qd)`,
    /// instead of `tau` (no effect on a frictionless model).
    pub compensate_friction: bool,
}

impl CostParams {
    /// The factor `k` of the energy residual: `sqrt(E_s / E_ref)` below
    /// `E_s`, exactly 1 from `E_s` up (so also with `energy_scale = 0`).
    pub fn energy_residual_factor(&self) -> f64 {
        if self.e_ref < self.energy_scale {
            (self.energy_scale / self.e_ref).sqrt()
        } else {
            1.0
        }
    }
}

/// Residuals of one stage and their Jacobians w.r.t. `z = (q, qd)` and `tau`.
#[derive(Clone, Copy, Debug)]
pub struct Residuals<const N: usize, const NX: usize> {
    /// `(E_ref - E) k`, `k` = [`CostParams::energy_residual_factor`].
    pub energy: f64,
    /// `d r_E / dz = -k dE/dz`.
    pub energy_z: SVector<f64, NX>,
    /// Position distance `r_x`.
    pub position: Vector<N>,
    /// `d r_x / dz`.
    pub position_z: SMatrix<f64, N, NX>,
    /// Velocity distance `r_xd`.
    pub velocity: Vector<N>,
    /// `d r_xd / dz`.
    pub velocity_z: SMatrix<f64, N, NX>,
    /// Torque residual `r_F` (`tau`, or `tau - tau_f(qd)` when compensating friction).
    pub torque: Vector<N>,
    /// `d r_F / dz`.
    pub torque_z: SMatrix<f64, N, NX>,
    /// `d r_F / dtau`.
    pub torque_u: Matrix<N>,
}

/// Evaluates the residuals of the chosen cost, literally as in the paper.
pub fn residuals<S, const N: usize, const NX: usize>(
    system: &S,
    reference: &Reference<N>,
    params: &CostParams,
    z: &SVector<f64, NX>,
    tau: &Vector<N>,
) -> Residuals<N, NX>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let (q, qd) = unpack_state::<N, NX>(z);
    let energy = system.energy(&q, &qd);
    let (de_dq, de_dqd) = system.energy_gradient(&q, &qd);
    let mut grad_e = SVector::<f64, NX>::zeros();
    grad_e.fixed_rows_mut::<N>(0).copy_from(&de_dq);
    grad_e.fixed_rows_mut::<N>(N).copy_from(&de_dqd);
    let eye = Matrix::<N>::identity();
    // Torque beyond what friction takes: holding an eigenmode against
    // friction costs nothing (for a frictionless model this is `tau`).
    let (torque, torque_z) = if params.compensate_friction {
        let slope = system.friction_slope(&qd);
        let mut dz = SMatrix::<f64, N, NX>::zeros();
        for j in 0..N {
            dz[(j, N + j)] = -slope[j];
        }
        (tau - system.friction(&qd), dz)
    } else {
        (*tau, SMatrix::zeros())
    };
    // k = 1 exactly at the paper's set-up (E_ref >= E_s, or E_s = 0), so
    // the paper's runs are unchanged to the last bit.
    let k = params.energy_residual_factor();
    let mut r = Residuals {
        energy: (params.e_ref - energy) * k,
        energy_z: -grad_e * k,
        position: Vector::<N>::zeros(),
        position_z: SMatrix::zeros(),
        velocity: Vector::<N>::zeros(),
        velocity_z: SMatrix::zeros(),
        torque,
        torque_z,
        torque_u: eye,
    };
    match reference {
        Reference::Straight { eigenvector } => {
            let c = eigenvector;
            let perp = eye - c * c.transpose();
            r.position = perp * (q - system.equilibrium());
            r.position_z.fixed_view_mut::<N, N>(0, 0).copy_from(&perp);
            r.velocity = perp * qd;
            r.velocity_z.fixed_view_mut::<N, N>(0, N).copy_from(&perp);
            blend(&mut r, params, energy, &grad_e);
        }
        Reference::Curved(chart) => chart_distance(&mut r, chart, &q, &qd),
        Reference::Hybrid(chart) => {
            chart_distance(&mut r, chart, &q, &qd);
            blend(&mut r, params, energy, &grad_e);
        }
    }
    r
}

/// The curved distance (paper, eq. 12): position and velocity errors to
/// the chart point at `s = c'(q - q_eq)`, across the chart's tangent.
fn chart_distance<const N: usize, const NX: usize>(
    r: &mut Residuals<N, NX>,
    chart: &Chart<N>,
    q: &Vector<N>,
    qd: &Vector<N>,
) {
    let eye = Matrix::<N>::identity();
    let c0 = chart.eigenvector;
    let s = chart.coordinate(q);
    let sd = c0.dot(qd);
    let p = chart.eval(s);
    let norm = p.dx.norm().max(1e-12);
    let c = p.dx / norm;
    let dc = (p.ddx - c * c.dot(&p.ddx)) / norm;
    let perp = eye - c * c.transpose();
    let dperp = -(dc * c.transpose() + c * dc.transpose());
    let along = eye - p.dx * c0.transpose();
    let ex = q - p.x;
    let ev = qd - p.dx * sd;
    r.position = perp * ex;
    r.position_z
        .fixed_view_mut::<N, N>(0, 0)
        .copy_from(&(perp * along + dperp * ex * c0.transpose()));
    r.velocity = perp * ev;
    r.velocity_z
        .fixed_view_mut::<N, N>(0, 0)
        .copy_from(&(-(perp * p.ddx) * (sd * c0.transpose()) + dperp * ev * c0.transpose()));
    r.velocity_z
        .fixed_view_mut::<N, N>(0, N)
        .copy_from(&(perp * along));
}

/// The straight cost's blending (paper, eq. 10): distances times
/// `1 - tanh(alpha E)`, torque times `tanh(alpha E) + beta`, with the
/// product rule through `E(z)`.
fn blend<const N: usize, const NX: usize>(
    r: &mut Residuals<N, NX>,
    params: &CostParams,
    energy: f64,
    grad_e: &SVector<f64, NX>,
) {
    let t = (params.alpha * energy).tanh();
    let dt_dz = grad_e * (params.alpha * (1.0 - t * t));
    let g = 1.0 - t;
    r.position_z = r.position_z * g - r.position * dt_dz.transpose();
    r.position *= g;
    r.velocity_z = r.velocity_z * g - r.velocity * dt_dz.transpose();
    r.velocity *= g;
    let w = t + params.beta;
    r.torque_z = r.torque * dt_dz.transpose() + r.torque_z * w;
    r.torque *= w;
    r.torque_u = Matrix::<N>::identity() * w;
}

/// Gauss-Newton model of `scale * l(z, tau)`: value, gradient and Hessian
/// blocks (`2 scale J' W J`, positive semidefinite by construction).
#[derive(Clone, Copy, Debug)]
pub struct StageModel<const N: usize, const NX: usize> {
    /// `scale * l`.
    pub cost: f64,
    /// Hessian block `d2/dz2`.
    pub q: SMatrix<f64, NX, NX>,
    /// Hessian block `d2/(dtau dz)`.
    pub s: SMatrix<f64, N, NX>,
    /// Hessian block `d2/dtau2`.
    pub r: Matrix<N>,
    /// Gradient w.r.t. `z`.
    pub gz: SVector<f64, NX>,
    /// Gradient w.r.t. `tau`.
    pub gu: Vector<N>,
}

/// Value, gradient and Gauss-Newton Hessian of `scale * l(z, tau)`.
pub fn stage_model<S, const N: usize, const NX: usize>(
    system: &S,
    reference: &Reference<N>,
    params: &CostParams,
    z: &SVector<f64, NX>,
    tau: &Vector<N>,
    scale: f64,
) -> StageModel<N, NX>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let r = residuals::<S, N, NX>(system, reference, params, z, tau);
    let w = &params.weights;
    let two = 2.0 * scale;
    let q = (r.energy_z * r.energy_z.transpose()) * w.energy
        + r.position_z.transpose() * r.position_z * w.position
        + r.velocity_z.transpose() * r.velocity_z * w.velocity
        + r.torque_z.transpose() * r.torque_z * w.torque;
    let gz = r.energy_z * (r.energy * w.energy)
        + r.position_z.transpose() * r.position * w.position
        + r.velocity_z.transpose() * r.velocity * w.velocity
        + r.torque_z.transpose() * r.torque * w.torque;
    StageModel {
        cost: scale * weighted_square_sum(&r, w),
        q: q * two,
        s: r.torque_u.transpose() * r.torque_z * (two * w.torque),
        r: r.torque_u.transpose() * r.torque_u * (two * w.torque),
        gz: gz * two,
        gu: r.torque_u.transpose() * r.torque * (two * w.torque),
    }
}

/// `l = sum_i w_i r_i^2` of one stage's residuals.
fn weighted_square_sum<const N: usize, const NX: usize>(r: &Residuals<N, NX>, w: &Weights) -> f64 {
    w.energy * r.energy * r.energy
        + w.position * r.position.norm_squared()
        + w.velocity * r.velocity.norm_squared()
        + w.torque * r.torque.norm_squared()
}

/// `scale * l(z, tau)` only (line search, reporting).
pub fn stage_cost<S, const N: usize, const NX: usize>(
    system: &S,
    reference: &Reference<N>,
    params: &CostParams,
    z: &SVector<f64, NX>,
    tau: &Vector<N>,
    scale: f64,
) -> f64
where
    S: MechanicalSystem<N> + ?Sized,
{
    let r = residuals::<S, N, NX>(system, reference, params, z, tau);
    scale * weighted_square_sum(&r, &params.weights)
}
