//! The EigenMPC running costs (paper, eqs. 10 and 12) in least-squares form
//! `l = w_E r_E^2 + w_x |r_x|^2 + w_xd |r_xd|^2 + w_F |r_F|^2`, their exact
//! residual Jacobians and the Gauss-Newton Hessian blocks they give.
//!
//! Below the energy scale `E_s` the energy residual is scaled by
//! `sqrt(E_s / E_ref)` ([`CostParams::energy_scale`]): the paper's
//! `r_E = E_ref - E` values a joule gained at a given fraction of the climb
//! in proportion to `E_ref`, so its weights, tuned at 14 J, pull towards
//! 3 J with a fifth of that.
//!
//! The energy and torque residuals are shared; what differs between the
//! variants is the distance to the a-priori knowledge, one file each
//! (`straight.rs`, `curved.rs`, `hybrid.rs`) behind [`CostVariant`], listed
//! once in the table below.

mod reference;
mod variant;

pub use reference::{Guide, Reference, ReferenceError};
pub use variant::{CostVariant, StagePoint, VariantInfo};

use crate::mechanics::{EnergyWithGradient, Matrix, MechanicalSystem, Vector, unpack_state};
use nalgebra::{SMatrix, SVector};
use variant::cost_variant_table;

// The cost variants. A new one is a row here and its file (`module.rs`,
// implementing `CostVariant`): the FMU enumeration, the C constants, the
// CLI's values and the paper weights follow from the row.
cost_variant_table! {
    /// Distance to the linear eigenvector line, blended by `tanh(alpha E)`.
    Straight in straight {
        name: "straight",
        paper_energy_weight: 5.0,
        uses_chart: false,
        description: "distance to the linear eigenvector line, blended by tanh(alpha E) (paper eq. 10)",
    }
    /// Distance to a precomputed eigenmode chart `X(s)`.
    Curved in curved {
        name: "curved",
        paper_energy_weight: 25.0,
        uses_chart: true,
        description: "distance to the eigenmode chart X(s) (paper eq. 12)",
    }
    /// The curved distance blended by `tanh(alpha E)` as the straight one
    /// (the paper's commented-out "Hybrid EigenMPC"): the chart's stiffness
    /// with some exploration, for a chart of a slightly different model.
    Hybrid in hybrid {
        name: "hybrid",
        paper_energy_weight: 25.0,
        uses_chart: true,
        description: "distance to the chart X(s), blended by tanh(alpha E) (paper, Hybrid EigenMPC)",
    }
}

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
    let energy = system.energy_with_gradient(&q, &qd);
    residuals_at(system, reference, params, z, tau, &energy)
}

/// [`residuals`] given the energy with its gradient at `z` (inlined: the
/// residuals are a large value to return).
#[inline(always)]
fn residuals_at<S, const N: usize, const NX: usize>(
    system: &S,
    reference: &Reference<N>,
    params: &CostParams,
    z: &SVector<f64, NX>,
    tau: &Vector<N>,
    &(energy, de_dq, de_dqd): &EnergyWithGradient<N>,
) -> Residuals<N, NX>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let (q, qd) = unpack_state::<N, NX>(z);
    let mut grad_e = SVector::<f64, NX>::zeros();
    grad_e.fixed_rows_mut::<N>(0).copy_from(&de_dq);
    grad_e.fixed_rows_mut::<N>(N).copy_from(&de_dqd);
    let eye = Matrix::<N>::identity();
    // Torque beyond what friction takes: holding an eigenmode against
    // friction costs nothing (for a frictionless model this is `tau`).
    let (torque, torque_z) = if params.compensate_friction && system.has_friction() {
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
    let stage = StagePoint {
        q,
        qd,
        energy,
        energy_gradient: grad_e,
    };
    distance(
        reference.variant(),
        &mut r,
        system,
        reference.guide(),
        &stage,
        params,
    );
    r
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
    let (q, qd) = unpack_state::<N, NX>(z);
    let energy = system.energy_with_gradient(&q, &qd);
    stage_model_at(system, reference, params, z, tau, scale, &energy)
}

/// [`stage_model`] given the energy with its gradient at `z` (the
/// linearisation has it from the dynamics Jacobian's trigonometry).
pub(crate) fn stage_model_at<S, const N: usize, const NX: usize>(
    system: &S,
    reference: &Reference<N>,
    params: &CostParams,
    z: &SVector<f64, NX>,
    tau: &Vector<N>,
    scale: f64,
    energy: &EnergyWithGradient<N>,
) -> StageModel<N, NX>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let r = residuals_at::<S, N, NX>(system, reference, params, z, tau, energy);
    let w = &params.weights;
    let two = 2.0 * scale;
    let q = (r.energy_z * r.energy_z.transpose()) * w.energy
        + gram(&r.position_z) * w.position
        + gram(&r.velocity_z) * w.velocity
        + gram(&r.torque_z) * w.torque;
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

/// `a' a`, written out: nalgebra's product is an outlined call from 3
/// joints up (with the transpose materialised first). Each entry sums its
/// terms by ascending row as nalgebra's `a.transpose() * a` does: the same
/// bits.
#[inline(always)]
fn gram<const R: usize, const C: usize>(a: &SMatrix<f64, R, C>) -> SMatrix<f64, C, C> {
    let mut out = SMatrix::<f64, C, C>::zeros();
    for c in 0..C {
        for r in 0..C {
            let mut v = a[(0, r)] * a[(0, c)];
            for i in 1..R {
                v += a[(i, r)] * a[(i, c)];
            }
            out[(r, c)] = v;
        }
    }
    out
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
