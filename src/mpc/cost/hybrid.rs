//! Hybrid EigenMPC (the paper's commented-out variant): the curved
//! distance to the chart, blended by `tanh(alpha E)` as the straight cost
//! is. The chart's stiffness with some exploration, for a chart of a
//! slightly different model.

use super::curved::chart_distance;
use super::straight::blend;
use super::{CostParams, CostVariant, Guide, Residuals, StagePoint};
use crate::mechanics::MechanicalSystem;

/// The hybrid cost.
pub struct Hybrid;

impl CostVariant for Hybrid {
    fn distance<S, const N: usize, const NX: usize>(
        r: &mut Residuals<N, NX>,
        _system: &S,
        guide: &Guide<N>,
        stage: &StagePoint<N, NX>,
        params: &CostParams,
    ) where
        S: MechanicalSystem<N> + ?Sized,
    {
        if let Some(chart) = guide.chart() {
            chart_distance(r, chart, &stage.q, &stage.qd);
        }
        blend(r, params, stage.energy, &stage.energy_gradient);
    }
}
