//! The EigenMPC cost variants, one table: a new variant is a row here plus
//! its residuals in `cost.rs`.

/// Which EigenMPC cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// Distance to the linear eigenvector line, blended by `tanh(alpha E)`.
    Straight,
    /// Distance to a precomputed eigenmode chart `X(s)`.
    Curved,
    /// The curved distance blended by `tanh(alpha E)` as the straight one
    /// (the paper's commented-out "Hybrid EigenMPC"): the chart's stiffness
    /// with some exploration, for a chart of a slightly different model.
    Hybrid,
}

/// What is known about a variant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VariantInfo {
    /// The variant.
    pub variant: Variant,
    /// Name on the command line, in files and FMU items.
    pub name: &'static str,
    /// The paper's energy weight `w_E` for it (section V-A).
    pub paper_energy_weight: f64,
    /// One line for documentation.
    pub description: &'static str,
}

/// Every variant, in the order of their FMU/C API items (1, 2, ...).
pub const VARIANTS: [VariantInfo; 3] = [
    VariantInfo {
        variant: Variant::Straight,
        name: "straight",
        paper_energy_weight: 5.0,
        description: "distance to the linear eigenvector line, blended by tanh(alpha E) (paper eq. 10)",
    },
    VariantInfo {
        variant: Variant::Curved,
        name: "curved",
        paper_energy_weight: 25.0,
        description: "distance to the eigenmode chart X(s) (paper eq. 12)",
    },
    VariantInfo {
        variant: Variant::Hybrid,
        name: "hybrid",
        paper_energy_weight: 25.0,
        description: "distance to the chart X(s), blended by tanh(alpha E) (paper, Hybrid EigenMPC)",
    },
];

impl Variant {
    /// The variant's row of [`VARIANTS`].
    pub fn info(self) -> &'static VariantInfo {
        VARIANTS
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
        !matches!(self, Variant::Straight)
    }
}

impl std::str::FromStr for Variant {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        VARIANTS
            .iter()
            .find(|v| v.name == s)
            .map(|v| v.variant)
            .ok_or_else(|| {
                let names: Vec<&str> = VARIANTS.iter().map(|v| v.name).collect();
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
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_list_the_known_ones() {
        for v in VARIANTS {
            assert_eq!(v.name.parse::<Variant>().unwrap(), v.variant);
            assert_eq!(v.variant.to_string(), v.name);
        }
        let err = "bent".parse::<Variant>().unwrap_err();
        assert!(err.contains("straight, curved, hybrid"), "{err}");
    }
}
