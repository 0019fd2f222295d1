//! Everything that defines one plant run, filled from the FMU's parameters
//! through the variable table.

use crate::chain::{ChainParameters, HasChain};
use eigenmpc::integrate::Tolerances;
use eigenmpc::mechanics::PlanarChain;

/// The plant's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct PlantSettings<const N: usize> {
    /// The chain (its viscous friction `b[j]` included).
    pub model: ChainParameters<N>,
    /// `damping[j]`: the original name of the viscous friction `b[j]`.
    pub damping: [f64; N],
    /// Initial angles `q0[j]` (rad).
    pub q0: [f64; N],
    /// Initial speeds `qd0[j]` (rad/s).
    pub qd0: [f64; N],
    /// Tolerances of the adaptive integrator.
    pub tolerances: Tolerances,
}

impl<const N: usize> Default for PlantSettings<N> {
    /// The paper's chain at rest, hanging down; the integrator's default tolerances.
    fn default() -> Self {
        Self {
            model: ChainParameters::default(),
            damping: [0.0; N],
            q0: [0.0; N],
            qd0: [0.0; N],
            tolerances: Tolerances::default(),
        }
    }
}

impl<const N: usize> HasChain<N> for PlantSettings<N> {
    fn chain(&self) -> &ChainParameters<N> {
        &self.model
    }
    fn chain_mut(&mut self) -> &mut ChainParameters<N> {
        &mut self.model
    }
}

impl<const N: usize> PlantSettings<N> {
    /// The chain with `damping[j]` resolved: it is an alias of `b[j]`, so
    /// setting either works; both set to different nonzero values is refused.
    pub fn system(&self) -> Result<PlanarChain<N>, String> {
        let mut model = self.model;
        for (j, (joint, &d)) in model.joints.iter_mut().zip(&self.damping).enumerate() {
            let b = joint.viscous;
            if d != 0.0 && b != 0.0 && d != b {
                return Err(format!(
                    "b[{n}] = {b} and damping[{n}] = {d}: damping[{n}] is the former name of the \
                     viscous friction b[{n}]; set one of them",
                    n = j + 1
                ));
            }
            if b == 0.0 {
                joint.viscous = d;
            }
        }
        model.build()
    }
}
