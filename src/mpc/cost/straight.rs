//! Straight EigenMPC (paper, eq. 10): the distance to the line through the
//! equilibrium along the linear eigenvector `c`, faded out by
//! `1 - tanh(alpha E)` as the energy grows while the torque is weighed by
//! `tanh(alpha E) + beta` (exploration at low energy).

use super::{CostParams, CostVariant, Guide, Residuals, StagePoint};
use crate::math;
use crate::mechanics::{Matrix, MechanicalSystem};
use nalgebra::SVector;

/// The straight cost.
pub struct Straight;

impl CostVariant for Straight {
    fn distance<S, const N: usize, const NX: usize>(
        r: &mut Residuals<N, NX>,
        system: &S,
        guide: &Guide<N>,
        stage: &StagePoint<N, NX>,
        params: &CostParams,
    ) where
        S: MechanicalSystem<N> + ?Sized,
    {
        let c = guide.eigenvector();
        let perp = Matrix::<N>::identity() - c * c.transpose();
        r.position = perp * (stage.q - system.equilibrium());
        r.position_z.fixed_view_mut::<N, N>(0, 0).copy_from(&perp);
        r.velocity = perp * stage.qd;
        r.velocity_z.fixed_view_mut::<N, N>(0, N).copy_from(&perp);
        blend(r, params, stage.energy, &stage.energy_gradient);
    }
}

/// The straight cost's blending (paper, eq. 10): distances times
/// `1 - tanh(alpha E)`, torque times `tanh(alpha E) + beta`, with the
/// product rule through `E(z)`. Also the hybrid cost's.
pub(super) fn blend<const N: usize, const NX: usize>(
    r: &mut Residuals<N, NX>,
    params: &CostParams,
    energy: f64,
    grad_e: &SVector<f64, NX>,
) {
    let t = math::tanh(params.alpha * energy);
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
