//! Curved EigenMPC (paper, eq. 12): position and velocity errors to the
//! point of the eigenmode chart `X(s)` at `s = c'(q - q_eq)`, measured
//! across the chart's tangent.

use super::{CostParams, CostVariant, Guide, Residuals, StagePoint};
use crate::mechanics::{Matrix, MechanicalSystem, Vector};
use crate::modes::Chart;

/// The curved cost.
pub struct Curved;

impl CostVariant for Curved {
    fn distance<S, const N: usize, const NX: usize>(
        r: &mut Residuals<N, NX>,
        _system: &S,
        guide: &Guide<N>,
        stage: &StagePoint<N, NX>,
        _params: &CostParams,
    ) where
        S: MechanicalSystem<N> + ?Sized,
    {
        // `Reference::new` gives a chart variant a chart; a line would
        // leave the distances at zero, never a panic on the sample path.
        if let Some(chart) = guide.chart() {
            chart_distance(r, chart, &stage.q, &stage.qd);
        }
    }
}

/// The distance to `chart` (also the hybrid cost's), with its exact
/// Jacobians through the chart coordinate `s(q)` and the tangent `X'(s)`.
pub(super) fn chart_distance<const N: usize, const NX: usize>(
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
