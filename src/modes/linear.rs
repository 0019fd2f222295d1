//! Linear modes: `K c = w^2 M(q_eq) c` with `K` the Hessian of `V` at `q_eq`.

use super::ModeError;
use crate::mechanics::{MechanicalSystem, Vector};
use nalgebra::DMatrix;
use std::fmt;
use std::str::FromStr;

/// One linear mode of the system linearised at its equilibrium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearMode<const N: usize> {
    /// Angular frequency `w` (rad/s).
    pub omega: f64,
    /// Unit-norm eigenvector `c`, first nonzero component positive.
    pub eigenvector: Vector<N>,
    /// The same direction scaled so that `c' M c = 1`.
    pub mass_normalised: Vector<N>,
}

/// Named mode families of a two-joint chain (in order of frequency).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// Lower frequency: both joints move in the same direction.
    InPhase,
    /// Higher frequency: the joints move against each other.
    AntiPhase,
}

impl Family {
    /// Index into [`linear_modes`] (ascending frequency).
    pub fn index(self) -> usize {
        match self {
            Family::InPhase => 0,
            Family::AntiPhase => 1,
        }
    }
}

impl fmt::Display for Family {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Family::InPhase => "in-phase",
            Family::AntiPhase => "anti-phase",
        })
    }
}

impl FromStr for Family {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "in-phase" => Ok(Family::InPhase),
            "anti-phase" => Ok(Family::AntiPhase),
            other => Err(format!(
                "unknown family '{other}' (expected 'in-phase' or 'anti-phase')"
            )),
        }
    }
}

/// Fixes the sign so that the first nonzero component is positive.
pub(crate) fn fix_sign<const N: usize>(v: Vector<N>) -> Vector<N> {
    let scale = v.amax();
    match v.iter().find(|x| x.abs() > 1e-12 * scale) {
        Some(&first) if first < 0.0 => -v,
        _ => v,
    }
}

/// All linear modes, sorted by ascending frequency.
pub fn linear_modes<S, const N: usize>(system: &S) -> Result<Vec<LinearMode<N>>, ModeError>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let q_eq = system.equilibrium();
    let m = DMatrix::from_column_slice(N, N, system.mass_matrix(&q_eq).as_slice());
    let k = DMatrix::from_column_slice(N, N, system.potential_hessian(&q_eq).as_slice());
    // M = L L'; L^-1 K L^-T y = w^2 y; c = L^-T y is then mass-normalised.
    let chol = m
        .cholesky()
        .ok_or_else(|| ModeError::ChartFit("mass matrix not positive definite".into()))?;
    let l = chol.l();
    let l_inv = l
        .clone()
        .try_inverse()
        .ok_or_else(|| ModeError::ChartFit("singular mass matrix".into()))?;
    let a = &l_inv * k * l_inv.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let eig = a.symmetric_eigen();
    let mut order: Vec<usize> = (0..N).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    order
        .into_iter()
        .map(|i| {
            let lambda = eig.eigenvalues[i];
            if lambda <= 0.0 || !lambda.is_finite() {
                return Err(ModeError::UnstableEquilibrium { eigenvalue: lambda });
            }
            let y = eig.eigenvectors.column(i);
            let c = l_inv.transpose() * y;
            let mass_normalised = fix_sign(Vector::<N>::from_iterator(c.iter().copied()));
            Ok(LinearMode {
                omega: lambda.sqrt(),
                eigenvector: mass_normalised.normalize(),
                mass_normalised,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::DoublePendulum;

    #[test]
    fn double_pendulum_frequencies_are_the_textbook_ones() {
        let g: f64 = 9.81;
        let modes = linear_modes(&DoublePendulum::default()).unwrap();
        let sqrt2 = 2f64.sqrt();
        assert!((modes[0].omega - (g * (2.0 - sqrt2)).sqrt()).abs() < 1e-12);
        assert!((modes[1].omega - (g * (2.0 + sqrt2)).sqrt()).abs() < 1e-12);
        // In-phase: both positive; anti-phase: opposite signs.
        let c0 = modes[0].eigenvector;
        let c1 = modes[1].eigenvector;
        assert!(c0[0] > 0.0 && c0[1] > 0.0);
        assert!(c1[0] > 0.0 && c1[1] < 0.0);
        assert!((c0.norm() - 1.0).abs() < 1e-14);
        // Closed form: in-phase direction (1, sqrt 2 - 1) normalised.
        let expected = Vector::<2>::new(1.0, sqrt2 - 1.0).normalize();
        assert!((c0 - expected).norm() < 1e-12, "{c0}");
        let m = crate::mechanics::MechanicalSystem::mass_matrix(
            &DoublePendulum::default(),
            &Vector::<2>::zeros(),
        );
        for mode in &modes {
            let v = mode.mass_normalised;
            assert!((v.dot(&(m * v)) - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn family_parses_and_prints() {
        assert_eq!("in-phase".parse::<Family>().unwrap(), Family::InPhase);
        assert_eq!(Family::AntiPhase.to_string(), "anti-phase");
        assert!(
            "sideways"
                .parse::<Family>()
                .unwrap_err()
                .contains("sideways")
        );
    }
}
