//! What the cost measures distances to: a variant and its guide (the
//! eigenvector line or a chart), and [`Reference::of`], the one place a
//! variant becomes a reference.

use super::Variant;
use crate::mechanics::Vector;
use crate::modes::Chart;
use serde::{Deserialize, Serialize};

/// A reference that does not fit its variant, or is not finite.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ReferenceError(pub String);

impl From<ReferenceError> for String {
    fn from(e: ReferenceError) -> Self {
        e.0
    }
}

/// The a-priori knowledge a variant's distance is measured to.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Guide<const N: usize> {
    /// The unit linear eigenvector `c`: the line `q_eq + c s`.
    Line(Vector<N>),
    /// A chart `X(s)` of the eigenmode.
    Chart(Chart<N>),
}

impl<const N: usize> Guide<N> {
    /// The unit eigenvector: the line's, or the one the chart is fitted in.
    pub fn eigenvector(&self) -> &Vector<N> {
        match self {
            Guide::Line(c) => c,
            Guide::Chart(chart) => &chart.eigenvector,
        }
    }

    /// The chart, if this guide is one.
    pub fn chart(&self) -> Option<&Chart<N>> {
        match self {
            Guide::Line(_) => None,
            Guide::Chart(chart) => Some(chart),
        }
    }
}

/// A cost variant with the guide its row asks for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reference<const N: usize> {
    variant: Variant,
    guide: Guide<N>,
}

impl<const N: usize> Reference<N> {
    /// `variant` measured to `guide`; refused when the guide is not of the
    /// kind the variant's row declares, or is not finite.
    pub fn new(variant: Variant, guide: Guide<N>) -> Result<Self, ReferenceError> {
        let reference = Self { variant, guide };
        reference.validate().map_err(ReferenceError)?;
        Ok(reference)
    }

    /// The reference of `variant`, taking the eigenvector line or the chart
    /// as its row says (the other is never computed). Every caller that
    /// turns a variant into a reference comes through here.
    pub fn of<E>(
        variant: Variant,
        eigenvector: impl FnOnce() -> Result<Vector<N>, E>,
        chart: impl FnOnce() -> Result<Chart<N>, E>,
    ) -> Result<Self, E>
    where
        E: From<ReferenceError>,
    {
        let guide = if variant.uses_chart() {
            Guide::Chart(chart()?)
        } else {
            Guide::Line(eigenvector()?)
        };
        Ok(Self::new(variant, guide)?)
    }

    /// The reference of `variant` from `chart`: the chart itself, or for a
    /// line variant the eigenvector the chart is fitted in.
    pub fn with_chart(variant: Variant, chart: Chart<N>) -> Self {
        let guide = if variant.uses_chart() {
            Guide::Chart(chart)
        } else {
            Guide::Line(chart.eigenvector)
        };
        Self { variant, guide }
    }

    /// The cost variant.
    pub fn variant(&self) -> Variant {
        self.variant
    }

    /// What the variant measures distances to.
    pub fn guide(&self) -> &Guide<N> {
        &self.guide
    }

    /// The chart the cost follows (curved, hybrid).
    pub fn chart(&self) -> Option<&Chart<N>> {
        self.guide.chart()
    }

    /// The chart, mutable (rewritten in place from a family).
    pub fn chart_mut(&mut self) -> Option<&mut Chart<N>> {
        match &mut self.guide {
            Guide::Line(_) => None,
            Guide::Chart(chart) => Some(chart),
        }
    }

    /// The unit eigenvector of the line or of the chart.
    pub fn eigenvector(&self) -> &Vector<N> {
        self.guide.eigenvector()
    }

    /// Checks that the guide is of the variant's kind and finite, and the
    /// eigenvector nonzero (a saved state is checked as a new reference is).
    pub fn validate(&self) -> Result<(), String> {
        if self.variant.uses_chart() != self.guide.chart().is_some() {
            return Err(format!(
                "the {} cost measures to {}, not to {}",
                self.variant,
                if self.variant.uses_chart() {
                    "a chart"
                } else {
                    "the eigenvector line"
                },
                if self.guide.chart().is_some() {
                    "a chart"
                } else {
                    "a line"
                },
            ));
        }
        if let Some(chart) = self.guide.chart()
            && (chart.coefficients.iter().flatten().any(|v| !v.is_finite())
                || chart.equilibrium.iter().any(|v| !v.is_finite()))
        {
            return Err("chart coefficients must be finite".into());
        }
        let c = self.eigenvector();
        if c.iter().any(|v| !v.is_finite()) || c.norm() < 1e-12 {
            return Err("the eigenvector must be finite and nonzero".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mpc::VARIANTS;

    fn chart() -> Chart<2> {
        let c = Vector::<2>::new(1.0, 1.0).normalize();
        Chart::from_coefficients(c, Vector::zeros(), [vec![0.0, c[0]], vec![0.0, c[1]]]).unwrap()
    }

    #[test]
    fn each_variant_takes_the_guide_its_row_declares() {
        for v in VARIANTS {
            let from_chart = Reference::with_chart(v.variant, chart());
            assert_eq!(from_chart.chart().is_some(), v.uses_chart);
            assert_eq!(from_chart.eigenvector(), &chart().eigenvector);
            let line = Reference::new(v.variant, Guide::Line(chart().eigenvector));
            let with_chart = Reference::new(v.variant, Guide::Chart(chart()));
            assert_eq!(line.is_ok(), !v.uses_chart, "{}", v.name);
            assert_eq!(with_chart.is_ok(), v.uses_chart, "{}", v.name);
            // `of` computes only what the row asks for.
            let built = Reference::<2>::of::<ReferenceError>(
                v.variant,
                || {
                    if v.uses_chart {
                        Err(ReferenceError("line computed".into()))
                    } else {
                        Ok(chart().eigenvector)
                    }
                },
                || {
                    if v.uses_chart {
                        Ok(chart())
                    } else {
                        Err(ReferenceError("chart computed".into()))
                    }
                },
            )
            .unwrap();
            assert_eq!(built.variant(), v.variant);
        }
        let err = Reference::new(Variant::Curved, Guide::Line(Vector::<2>::x())).unwrap_err();
        assert_eq!(err.0, "the curved cost measures to a chart, not to a line");
        let err = Reference::new(Variant::Straight, Guide::Line(Vector::<2>::zeros())).unwrap_err();
        assert!(err.0.contains("nonzero"), "{err}");
    }
}
