//! The machinery behind the variant table in `cost/mod.rs`: what a row says
//! ([`VariantInfo`]), the interface each variant's file implements
//! ([`CostVariant`]) and the macro that turns the rows into [`Variant`],
//! [`VARIANTS`](super::VARIANTS) and the dispatch. The FMU enumeration, the C constants and
//! the CLI's values are all read from [`VARIANTS`](super::VARIANTS).

use super::{CostParams, Guide, Residuals};
use crate::mechanics::{MechanicalSystem, Vector};
use nalgebra::SVector;

/// One stage as the distance terms see it.
#[derive(Clone, Copy, Debug)]
pub struct StagePoint<const N: usize, const NX: usize> {
    /// Joint angles `q`.
    pub q: Vector<N>,
    /// Joint velocities `qd`.
    pub qd: Vector<N>,
    /// Mechanical energy `E(q, qd)`.
    pub energy: f64,
    /// `dE/dz`, `z = (q, qd)`.
    pub energy_gradient: SVector<f64, NX>,
}

/// One cost variant: what it adds to the residuals every variant shares
/// (energy and torque). A new variant is a file implementing this plus a
/// row of the table in `cost/mod.rs`.
pub trait CostVariant {
    /// Writes the position and velocity distances to `guide` (and their
    /// Jacobians) into `r`, then reshapes any residual the variant weighs
    /// differently. `guide` is of the kind the variant's row declares
    /// ([`crate::mpc::Reference::new`] checks it).
    fn distance<S, const N: usize, const NX: usize>(
        r: &mut Residuals<N, NX>,
        system: &S,
        guide: &Guide<N>,
        stage: &StagePoint<N, NX>,
        params: &CostParams,
    ) where
        S: MechanicalSystem<N> + ?Sized;
}

/// What is known about a variant: its row of the table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VariantInfo {
    /// The variant.
    pub variant: Variant,
    /// Name on the command line, in files and FMU items.
    pub name: &'static str,
    /// The paper's energy weight `w_E` for it (section V-A).
    pub paper_energy_weight: f64,
    /// Whether it measures the distance to a chart `X(s)` (else to the
    /// eigenvector line).
    pub uses_chart: bool,
    /// One line for documentation (FMU item, C header, `--help`).
    pub description: &'static str,
}

/// Turns the rows of the variant table into the `Variant` enum, the
/// `VARIANTS` table (FMU/C items 1, 2, ... in row order: append only) and
/// the dispatch of `distance` to each variant's file.
macro_rules! cost_variant_table {
    ($(
        $(#[doc = $doc:literal])*
        $variant:ident in $module:ident {
            name: $name:literal,
            paper_energy_weight: $weight:literal,
            uses_chart: $chart:literal,
            description: $description:literal $(,)?
        }
    )*) => {
        $( mod $module; )*

        /// Which EigenMPC cost: one row of the table in `cost/mod.rs` each.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
        pub enum Variant {
            $( $(#[doc = $doc])* $variant, )*
        }

        /// Every variant, in the order of their FMU/C API items (1, 2, ...).
        pub const VARIANTS: &[VariantInfo] = &[$(
            VariantInfo {
                variant: Variant::$variant,
                name: $name,
                paper_energy_weight: $weight,
                uses_chart: $chart,
                description: $description,
            },
        )*];

        /// The distance terms of `variant` (its file's [`CostVariant`]).
        pub(super) fn distance<S, const N: usize, const NX: usize>(
            variant: Variant,
            r: &mut Residuals<N, NX>,
            system: &S,
            guide: &Guide<N>,
            stage: &StagePoint<N, NX>,
            params: &CostParams,
        ) where
            S: MechanicalSystem<N> + ?Sized,
        {
            match variant {
                $( Variant::$variant => {
                    <$module::$variant as CostVariant>::distance(r, system, guide, stage, params)
                } )*
            }
        }
    };
}
pub(super) use cost_variant_table;

use super::Variant;

impl Variant {
    /// The variant's row of [`super::VARIANTS`].
    pub fn info(self) -> &'static VariantInfo {
        super::VARIANTS
            .iter()
            .find(|v| v.variant == self)
            .expect("every variant has a row")
    }

    /// Its name (`straight`, `curved`, `hybrid`).
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// Whether the cost measures the distance to a chart (curved, hybrid).
    pub fn uses_chart(self) -> bool {
        self.info().uses_chart
    }
}

impl std::str::FromStr for Variant {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        super::VARIANTS
            .iter()
            .find(|v| v.name == s)
            .map(|v| v.variant)
            .ok_or_else(|| {
                let names: Vec<&str> = super::VARIANTS.iter().map(|v| v.name).collect();
                format!("unknown variant '{s}' (expected {})", names.join(", "))
            })
    }
}

impl std::fmt::Display for Variant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::super::VARIANTS;
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_list_the_known_ones() {
        for v in VARIANTS {
            assert_eq!(v.name.parse::<Variant>().unwrap(), v.variant);
            assert_eq!(v.variant.to_string(), v.name);
            assert_eq!(v.variant.info(), v);
        }
        let err = "bent".parse::<Variant>().unwrap_err();
        assert!(err.contains("straight, curved, hybrid"), "{err}");
    }
}
