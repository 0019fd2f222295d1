//! The mode chart: per joint a polynomial `X_j(s)` in the chart coordinate
//! `s = c'(q - q_eq)`, fitted by least squares to an eigenmode's path. The
//! curved EigenMPC cost measures distances to `X(s)` normal to the unit
//! tangent `X'(s)/|X'(s)|`.

use super::ModeError;
use crate::mechanics::Vector;
use nalgebra::{DMatrix, DVector};

/// A polynomial chart `X(s)` of an eigenmode (paper, definition 4).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Chart<const N: usize> {
    /// Polynomial degree (the paper uses 9).
    pub degree: usize,
    /// Unit linear eigenvector `c` defining the coordinate `s`.
    pub eigenvector: Vector<N>,
    /// Equilibrium `q_eq` the coordinate is measured from.
    pub equilibrium: Vector<N>,
    /// Per joint `j`, coefficients of `s^k`, `k = 0..=degree`.
    #[serde(with = "serde_big_array::BigArray")]
    pub coefficients: [Vec<f64>; N],
    /// Largest `|X_j(s_i) - q_ij|` over the fitted samples (rad).
    pub max_residual: f64,
}

/// The chart and its first two derivatives at one coordinate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChartPoint<const N: usize> {
    /// `X(s)`.
    pub x: Vector<N>,
    /// `X'(s)` (so that `Xdot = X'(s) sd`).
    pub dx: Vector<N>,
    /// `X''(s)`.
    pub ddx: Vector<N>,
}

impl<const N: usize> ChartPoint<N> {
    /// Unit tangent `c(s) = X'(s) / |X'(s)|`.
    pub fn unit_tangent(&self) -> Vector<N> {
        self.dx.normalize()
    }
}

impl<const N: usize> Chart<N> {
    /// Fits `X_j(s)` of the given degree to the path samples.
    ///
    /// Refuses a path along which `s` is not strictly monotone (the chart
    /// would not be a function of `s`).
    pub fn fit(
        path: &[Vector<N>],
        eigenvector: &Vector<N>,
        equilibrium: &Vector<N>,
        degree: usize,
    ) -> Result<Self, ModeError> {
        if degree == 0 || degree > 20 {
            return Err(ModeError::ChartFit(format!(
                "degree {degree} out of range 1..=20"
            )));
        }
        if path.len() < 2 * (degree + 1) {
            return Err(ModeError::ChartFit(format!(
                "{} samples are too few for degree {degree} (need >= {})",
                path.len(),
                2 * (degree + 1)
            )));
        }
        if path.iter().any(|q| !q.iter().all(|x| x.is_finite())) {
            return Err(ModeError::ChartFit("path contains NaN or Inf".into()));
        }
        let c = eigenvector.normalize();
        let s: Vec<f64> = path.iter().map(|q| c.dot(&(q - equilibrium))).collect();
        let direction = (s[s.len() - 1] - s[0]).signum();
        if let Some(i) = s.windows(2).position(|w| (w[1] - w[0]) * direction <= 0.0) {
            return Err(ModeError::NotMonotone { index: i + 1 });
        }
        // Fit in the scaled coordinate s / sigma (Vandermonde conditioning),
        // then map back to powers of s.
        let sigma = s.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-12);
        let vander = DMatrix::from_fn(s.len(), degree + 1, |i, k| (s[i] / sigma).powi(k as i32));
        let svd = vander.svd(true, true);
        let coefficients: [Vec<f64>; N] = std::array::from_fn(|j| {
            let rhs = DVector::from_iterator(path.len(), path.iter().map(|q| q[j]));
            let scaled = svd
                .solve(&rhs, 1e-14)
                .unwrap_or_else(|_| DVector::from_element(degree + 1, f64::NAN));
            (0..=degree)
                .map(|k| scaled[k] / sigma.powi(k as i32))
                .collect()
        });
        let mut chart = Self::from_coefficients(c, *equilibrium, coefficients)?;
        chart.max_residual = path
            .iter()
            .zip(&s)
            .map(|(q, &si)| (chart.eval(si).x - q).amax())
            .fold(0.0, f64::max);
        Ok(chart)
    }

    /// Builds a chart from given coefficients (e.g. FMU parameters or JSON).
    pub fn from_coefficients(
        eigenvector: Vector<N>,
        equilibrium: Vector<N>,
        coefficients: [Vec<f64>; N],
    ) -> Result<Self, ModeError> {
        let degree = coefficients[0].len().saturating_sub(1);
        if coefficients
            .iter()
            .any(|c| c.len() != degree + 1 || c.is_empty())
        {
            return Err(ModeError::ChartFit(
                "every joint needs the same number (>= 1) of coefficients".into(),
            ));
        }
        let finite = |v: &Vector<N>| v.iter().all(|x| x.is_finite());
        if coefficients.iter().flatten().any(|x| !x.is_finite())
            || !finite(&eigenvector)
            || !finite(&equilibrium)
            || eigenvector.norm() == 0.0
        {
            return Err(ModeError::ChartFit(
                "non-finite coefficient, eigenvector or equilibrium, or zero eigenvector".into(),
            ));
        }
        Ok(Self {
            degree,
            eigenvector: eigenvector.normalize(),
            equilibrium,
            coefficients,
            max_residual: 0.0,
        })
    }

    /// Chart coordinate `s = c'(q - q_eq)`.
    pub fn coordinate(&self, q: &Vector<N>) -> f64 {
        self.eigenvector.dot(&(q - self.equilibrium))
    }

    /// `X(s)`, `X'(s)`, `X''(s)` by Horner's scheme (no allocation).
    pub fn eval(&self, s: f64) -> ChartPoint<N> {
        let mut p = ChartPoint {
            x: Vector::<N>::zeros(),
            dx: Vector::<N>::zeros(),
            ddx: Vector::<N>::zeros(),
        };
        for (j, coef) in self.coefficients.iter().enumerate() {
            let (mut x, mut dx, mut ddx) = (0.0, 0.0, 0.0);
            for &a in coef.iter().rev() {
                ddx = ddx * s + 2.0 * dx;
                dx = dx * s + x;
                x = x * s + a;
            }
            p.x[j] = x;
            p.dx[j] = dx;
            p.ddx[j] = ddx;
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize) -> Vec<Vector<2>> {
        (0..n)
            .map(|i| {
                let s = -1.0 + 2.0 * i as f64 / (n - 1) as f64;
                Vector::<2>::new(s, 0.3 * s + 0.2 * s * s * s)
            })
            .collect()
    }

    #[test]
    fn fits_a_polynomial_path_exactly_and_differentiates_it() {
        let c = Vector::<2>::new(1.0, 0.0);
        let chart = Chart::fit(&line(50), &c, &Vector::<2>::zeros(), 5).unwrap();
        assert!(chart.max_residual < 1e-12, "{}", chart.max_residual);
        let p = chart.eval(0.5);
        assert!((p.x[1] - (0.15 + 0.025)).abs() < 1e-12);
        assert!((p.dx[1] - (0.3 + 0.6 * 0.25)).abs() < 1e-12);
        assert!((p.ddx[1] - 1.2 * 0.5).abs() < 1e-11);
        assert!((p.dx[0] - 1.0).abs() < 1e-12);
        assert!((p.unit_tangent().norm() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn refuses_a_path_that_turns_back() {
        let mut path = line(40);
        path.extend(line(40).into_iter().rev());
        let err =
            Chart::fit(&path, &Vector::<2>::new(1.0, 0.0), &Vector::<2>::zeros(), 3).unwrap_err();
        assert!(matches!(err, ModeError::NotMonotone { index: 40 }), "{err}");
    }

    #[test]
    fn refuses_bad_degrees_and_coefficients() {
        let c = Vector::<2>::new(1.0, 0.0);
        assert!(Chart::fit(&line(10), &c, &Vector::<2>::zeros(), 9).is_err());
        assert!(Chart::fit(&line(50), &c, &Vector::<2>::zeros(), 0).is_err());
        let bad =
            Chart::<2>::from_coefficients(c, Vector::<2>::zeros(), [vec![0.0, 1.0], vec![0.0]]);
        assert!(bad.is_err());
        let nan =
            Chart::<2>::from_coefficients(c, Vector::<2>::zeros(), [vec![f64::NAN], vec![0.0]]);
        assert!(nan.is_err());
    }
}
