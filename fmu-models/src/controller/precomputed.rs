//! A mode family computed ahead of time (`eigenmpc export` writes one into
//! the archive's `resources/`): the controller takes it instead of
//! continuing the family at `fmi2ExitInitializationMode`, which for 4 to 6
//! joints takes 0.5 to 2.5 s. It is taken only when it is exactly the family
//! the controller would compute (same model, linear mode and options);
//! otherwise the controller computes its own and says why.

use super::settings::Settings;
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams};
use eigenmpc::modes::{ChartFamily, FamilyOptions};
use serde::{Deserialize, Serialize};

/// The file name inside `resources/`.
pub const FAMILY_FILE: &str = "eigenmpc-family.json";

/// A family with what it was computed from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PrecomputedFamily<const N: usize> {
    /// The model.
    pub model: PlanarChainParams<N>,
    /// The linear mode it continues (0-based, ascending frequency).
    pub mode: usize,
    /// How it was computed.
    pub options: FamilyOptions,
    /// The charts.
    pub family: ChartFamily<N>,
}

impl<const N: usize> PrecomputedFamily<N> {
    /// The family the controller of `settings` would compute (`NX = 2 N`).
    pub fn compute<const NX: usize>(settings: &Settings<N>) -> Result<Self, String> {
        let system = settings.system()?;
        Ok(Self {
            model: *system.params(),
            mode: settings.mode,
            options: settings.family_options(&system),
            family: settings.family::<NX>(&system)?,
        })
    }

    /// Why this is not the family of `settings` on `system` (None: it is).
    pub fn mismatch(&self, settings: &Settings<N>, system: &PlanarChain<N>) -> Option<String> {
        let wanted = settings.family_options(system);
        if self.model != *system.params() {
            Some("the model's parameters differ from the exported robot's".into())
        } else if self.mode != settings.mode {
            Some(format!(
                "it continues mode {}, the controller mode {}",
                self.mode + 1,
                settings.mode + 1
            ))
        } else if self.options != wanted {
            Some(format!(
                "it was computed up to {} J, the controller needs {} J (E_ref or \
                 family_energy_max changed)",
                self.options.energy_max, wanted.energy_max
            ))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::ControllerProduct;
    use crate::products::EigenMpc2;
    use eigenmpc::mpc::Variant;

    #[test]
    fn a_family_is_taken_only_where_it_is_the_one_to_compute() {
        let settings = EigenMpc2::settings(Variant::Curved);
        let precomputed = PrecomputedFamily::compute::<4>(&settings).unwrap();
        let system = settings.system().unwrap();
        assert_eq!(precomputed.mismatch(&settings, &system), None);
        let (controller, refused) = settings.build_with::<4>(Some(&precomputed)).unwrap();
        assert_eq!(refused, None);
        assert_eq!(controller.family(), Some(&precomputed.family));
        // Another mode, energy range or model: computed, with the reason.
        let mut anti = settings.clone();
        anti.mode = 1;
        let (controller, refused) = anti.build_with::<4>(Some(&precomputed)).unwrap();
        assert!(refused.unwrap().contains("mode 1, the controller mode 2"));
        assert_ne!(controller.family(), Some(&precomputed.family));
        let mut higher = settings.clone();
        higher.family_energy_max = 30.0;
        let (_, refused) = higher.build_with::<4>(Some(&precomputed)).unwrap();
        assert!(refused.unwrap().contains("needs 30 J"));
        let mut heavier = settings.clone();
        heavier.model.mass[1] *= 1.1;
        let system = heavier.system().unwrap();
        assert!(
            precomputed
                .mismatch(&heavier, &system)
                .unwrap()
                .contains("parameters")
        );
    }
}
