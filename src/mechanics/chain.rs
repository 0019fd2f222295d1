//! Planar serial chain of `N` links with point masses at the link tips,
//! relative joint angles, gravity along `-y`, optional joint springs and
//! viscous joint damping. `N = 2` is the paper's double pendulum (section V).
//!
//! The closed form works in absolute link angles `phi = L theta` (`L` lower
//! triangular ones) where the inertia is `Mt_jl = mu_max(j,l) l_j l_l
//! cos(phi_j - phi_l)` with `mu_j` the mass carried by link `j`; relative
//! quantities follow by `M = L' Mt L`. All derivatives are exact.

use super::{DynamicsJacobian, Matrix, MechanicalSystem, Vector};
use thiserror::Error;

/// Physical parameters of a [`PlanarChain`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarChainParams<const N: usize> {
    /// Tip masses `m_j` (kg).
    pub masses: [f64; N],
    /// Link lengths `l_j` (m).
    pub lengths: [f64; N],
    /// Gravitational acceleration `g` (m/s^2).
    pub gravity: f64,
    /// Joint spring stiffness (N m / rad), rest at zero angle.
    pub stiffness: [f64; N],
    /// Viscous joint damping (N m s / rad).
    pub damping: [f64; N],
}

impl<const N: usize> Default for PlanarChainParams<N> {
    /// The paper's values: 1 kg, 1 m, g = 9.81, no springs, no damping.
    fn default() -> Self {
        Self {
            masses: [1.0; N],
            lengths: [1.0; N],
            gravity: 9.81,
            stiffness: [0.0; N],
            damping: [0.0; N],
        }
    }
}

/// Why a set of chain parameters was refused.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ParamsError {
    /// A parameter is NaN, infinite or outside its range.
    #[error("parameter {name} = {value} is invalid: {reason}")]
    Invalid {
        /// Parameter name as the user knows it (e.g. `m1`).
        name: String,
        /// The offending value.
        value: f64,
        /// What range was expected.
        reason: &'static str,
    },
    /// Neither gravity nor springs hold the chain: no stable equilibrium.
    #[error("no stable equilibrium: gravity and all joint springs are zero")]
    NoEquilibrium,
}

/// A planar serial chain with point masses at the link tips.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarChain<const N: usize> {
    params: PlanarChainParams<N>,
    /// `a_jl = mu_max(j,l) l_j l_l`, the amplitudes of the absolute inertia.
    coupling: Matrix<N>,
    /// `g mu_j l_j`, the amplitudes of the gravity torques on absolute angles.
    gravity_amplitude: Vector<N>,
}

/// The paper's double pendulum: `theta_1` absolute, `theta_2` relative.
pub type DoublePendulum = PlanarChain<2>;

impl<const N: usize> Default for PlanarChain<N> {
    fn default() -> Self {
        Self::new(PlanarChainParams::default()).expect("default parameters are valid")
    }
}

fn check(name: String, value: f64, positive: bool) -> Result<(), ParamsError> {
    let ok = value.is_finite() && if positive { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(())
    } else {
        Err(ParamsError::Invalid {
            name,
            value,
            reason: if positive {
                "must be finite and > 0"
            } else {
                "must be finite and >= 0"
            },
        })
    }
}

impl<const N: usize> PlanarChain<N> {
    /// Builds the chain, refusing non-physical parameters.
    pub fn new(params: PlanarChainParams<N>) -> Result<Self, ParamsError> {
        for j in 0..N {
            check(format!("m{}", j + 1), params.masses[j], true)?;
            check(format!("l{}", j + 1), params.lengths[j], true)?;
            check(format!("stiffness{}", j + 1), params.stiffness[j], false)?;
            check(format!("damping{}", j + 1), params.damping[j], false)?;
        }
        check("g".into(), params.gravity, false)?;
        if params.gravity == 0.0 && params.stiffness.contains(&0.0) {
            return Err(ParamsError::NoEquilibrium);
        }
        let carried = |j: usize| params.masses[j..].iter().sum::<f64>();
        let coupling =
            Matrix::<N>::from_fn(|j, l| carried(j.max(l)) * params.lengths[j] * params.lengths[l]);
        let gravity_amplitude =
            Vector::<N>::from_fn(|j, _| params.gravity * carried(j) * params.lengths[j]);
        Ok(Self {
            params,
            coupling,
            gravity_amplitude,
        })
    }

    /// The parameters the chain was built from.
    pub fn params(&self) -> &PlanarChainParams<N> {
        &self.params
    }

    /// Absolute link angles `phi = L theta`.
    fn absolute(theta: &Vector<N>) -> Vector<N> {
        let mut phi = *theta;
        for j in 1..N {
            phi[j] += phi[j - 1];
        }
        phi
    }

    /// `L' y`: suffix sums (maps absolute-angle forces to joint torques).
    fn to_joint_forces(y: &Vector<N>) -> Vector<N> {
        let mut out = *y;
        for j in (0..N.saturating_sub(1)).rev() {
            out[j] += out[j + 1];
        }
        out
    }

    /// `L^-T y` (maps joint torques to absolute-angle forces).
    fn to_absolute_forces(y: &Vector<N>) -> Vector<N> {
        Vector::<N>::from_fn(|j, _| if j + 1 < N { y[j] - y[j + 1] } else { y[j] })
    }

    /// `L`, the lower triangular matrix of ones.
    fn l_matrix() -> Matrix<N> {
        Matrix::<N>::from_fn(|i, j| if j <= i { 1.0 } else { 0.0 })
    }

    /// `L^-1`: ones on the diagonal, minus ones below it.
    fn l_inverse() -> Matrix<N> {
        Matrix::<N>::from_fn(|i, j| match i as isize - j as isize {
            0 => 1.0,
            1 => -1.0,
            _ => 0.0,
        })
    }

    /// Inertia in absolute angles `Mt(phi)`.
    fn absolute_mass_matrix(&self, phi: &Vector<N>) -> Matrix<N> {
        Matrix::<N>::from_fn(|j, l| self.coupling[(j, l)] * (phi[j] - phi[l]).cos())
    }

    /// Centrifugal forces in absolute angles `h_j = sum_l a_jl sin(phi_j - phi_l) phid_l^2`.
    fn absolute_centrifugal(&self, phi: &Vector<N>, phid: &Vector<N>) -> Vector<N> {
        Vector::<N>::from_fn(|j, _| {
            (0..N)
                .map(|l| self.coupling[(j, l)] * (phi[j] - phi[l]).sin() * phid[l] * phid[l])
                .sum()
        })
    }

    fn spring_forces(&self, q: &Vector<N>) -> Vector<N> {
        Vector::<N>::from_fn(|j, _| self.params.stiffness[j] * q[j])
    }
}

impl<const N: usize> MechanicalSystem<N> for PlanarChain<N> {
    fn mass_matrix(&self, q: &Vector<N>) -> Matrix<N> {
        let l = Self::l_matrix();
        l.transpose() * self.absolute_mass_matrix(&Self::absolute(q)) * l
    }

    fn potential(&self, q: &Vector<N>) -> f64 {
        let phi = Self::absolute(q);
        let gravity: f64 = (0..N)
            .map(|j| self.gravity_amplitude[j] * (1.0 - phi[j].cos()))
            .sum();
        let springs: f64 = (0..N)
            .map(|j| 0.5 * self.params.stiffness[j] * q[j] * q[j])
            .sum();
        gravity + springs
    }

    fn potential_gradient(&self, q: &Vector<N>) -> Vector<N> {
        let phi = Self::absolute(q);
        let g_abs = Vector::<N>::from_fn(|j, _| self.gravity_amplitude[j] * phi[j].sin());
        Self::to_joint_forces(&g_abs) + self.spring_forces(q)
    }

    fn potential_hessian(&self, q: &Vector<N>) -> Matrix<N> {
        let phi = Self::absolute(q);
        let l = Self::l_matrix();
        let diag = Vector::<N>::from_fn(|j, _| self.gravity_amplitude[j] * phi[j].cos());
        let springs = Vector::<N>::from(self.params.stiffness);
        l.transpose() * Matrix::<N>::from_diagonal(&diag) * l + Matrix::<N>::from_diagonal(&springs)
    }

    fn coriolis_forces(&self, q: &Vector<N>, qd: &Vector<N>) -> Vector<N> {
        let phi = Self::absolute(q);
        let phid = Self::absolute(qd);
        Self::to_joint_forces(&self.absolute_centrifugal(&phi, &phid))
    }

    fn damping(&self) -> Vector<N> {
        Vector::<N>::from(self.params.damping)
    }

    fn equilibrium(&self) -> Vector<N> {
        Vector::<N>::zeros()
    }

    fn forward_dynamics(&self, q: &Vector<N>, qd: &Vector<N>, tau: &Vector<N>) -> Vector<N> {
        // Solve in absolute angles, Mt phidd = L^-T (tau - D qd - K q) - h - G,
        // which avoids forming L' Mt L.
        let phi = Self::absolute(q);
        let phid = Self::absolute(qd);
        let joint = tau - self.damping().component_mul(qd) - self.spring_forces(q);
        let w = Self::to_absolute_forces(&joint)
            - self.absolute_centrifugal(&phi, &phid)
            - Vector::<N>::from_fn(|j, _| self.gravity_amplitude[j] * phi[j].sin());
        let phidd = super::solve_spd(&self.absolute_mass_matrix(&phi), &w);
        Self::l_inverse() * phidd
    }

    fn dynamics_jacobian(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> DynamicsJacobian<N> {
        let phi = Self::absolute(q);
        let phid = Self::absolute(qd);
        let a = &self.coupling;
        let sin = Matrix::<N>::from_fn(|j, l| (phi[j] - phi[l]).sin());
        let cos = Matrix::<N>::from_fn(|j, l| (phi[j] - phi[l]).cos());
        let mt = a.component_mul(&cos);
        let a_sin = a.component_mul(&sin);
        let a_cos = mt;

        let joint = tau - self.damping().component_mul(qd) - self.spring_forces(q);
        let centrifugal = a_sin * phid.component_mul(&phid);
        let gravity = Vector::<N>::from_fn(|j, _| self.gravity_amplitude[j] * phi[j].sin());
        let w = Self::to_absolute_forces(&joint) - centrifugal - gravity;

        let chol = mt.cholesky();
        let solve = |b: &Matrix<N>| match &chol {
            Some(ch) => ch.solve(b),
            None => Matrix::<N>::repeat(f64::NAN),
        };
        let phidd = match &chol {
            Some(ch) => ch.solve(&w),
            None => Vector::<N>::repeat(f64::NAN),
        };

        let phid_sq = phid.component_mul(&phid);
        // d(Mt phidd)/d phi: -diag(sum_l a_jl s_jl phidd_l) + a_jk s_jk phidd_k
        let row_mass = a_sin * phidd;
        let d_mass = Matrix::<N>::from_fn(|j, k| {
            let diag = if j == k { -row_mass[j] } else { 0.0 };
            diag + a_sin[(j, k)] * phidd[k]
        });
        // dh/dphi: diag(sum_l a_jl c_jl phid_l^2) - a_jk c_jk phid_k^2
        let row_cent = a_cos * phid_sq;
        let d_cent_phi = Matrix::<N>::from_fn(|j, k| {
            let diag = if j == k { row_cent[j] } else { 0.0 };
            diag - a_cos[(j, k)] * phid_sq[k]
        });
        let d_cent_phid = Matrix::<N>::from_fn(|j, k| 2.0 * a_sin[(j, k)] * phid[k]);
        let d_grav = Matrix::<N>::from_diagonal(&Vector::<N>::from_fn(|j, _| {
            self.gravity_amplitude[j] * phi[j].cos()
        }));

        let l = Self::l_matrix();
        let l_inv = Self::l_inverse();
        let l_inv_t = l_inv.transpose();
        let springs = Matrix::<N>::from_diagonal(&Vector::<N>::from(self.params.stiffness));
        let damping = Matrix::<N>::from_diagonal(&self.damping());

        let dw_dq = (-d_cent_phi - d_grav - d_mass) * l - l_inv_t * springs;
        let dw_dqd = -d_cent_phid * l - l_inv_t * damping;

        DynamicsJacobian {
            acceleration: l_inv * phidd,
            d_q: l_inv * solve(&dw_dq),
            d_qd: l_inv * solve(&dw_dqd),
            d_tau: l_inv * solve(&l_inv_t),
        }
    }

    fn energy_gradient(&self, q: &Vector<N>, qd: &Vector<N>) -> (Vector<N>, Vector<N>) {
        let phi = Self::absolute(q);
        let phid = Self::absolute(qd);
        let a_sin = Matrix::<N>::from_fn(|j, l| self.coupling[(j, l)] * (phi[j] - phi[l]).sin());
        // dT/dphi_k = -phid_k sum_l a_kl s_kl phid_l
        let d_kinetic = -phid.component_mul(&(a_sin * phid));
        let d_e_dq = Self::to_joint_forces(&d_kinetic) + self.potential_gradient(q);
        let d_e_dqd = self.mass_matrix(q) * qd;
        (d_e_dq, d_e_dqd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pendulum() -> DoublePendulum {
        DoublePendulum::default()
    }

    #[test]
    fn mass_matrix_matches_paper_formula() {
        let p = PlanarChain::<2>::new(PlanarChainParams {
            masses: [1.3, 0.7],
            lengths: [0.9, 1.2],
            ..Default::default()
        })
        .unwrap();
        let (m1, m2, l1, l2): (f64, f64, f64, f64) = (1.3, 0.7, 0.9, 1.2);
        for &t2 in &[0.0, 0.4, -1.7, 3.0] {
            let q = Vector::<2>::new(0.3, t2);
            let m = p.mass_matrix(&q);
            let m11 = m1 * l1 * l1 + m2 * (l1 + l2).powi(2) - 2.0 * m2 * l1 * l2 * (1.0 - t2.cos());
            let m21 = m2 * (l2 * l2 + l1 * l2 * t2.cos());
            assert!((m[(0, 0)] - m11).abs() < 1e-12);
            assert!((m[(1, 0)] - m21).abs() < 1e-12);
            assert!((m[(0, 1)] - m21).abs() < 1e-12);
            assert!((m[(1, 1)] - m2 * l2 * l2).abs() < 1e-12);
        }
    }

    #[test]
    fn potential_matches_paper_formula() {
        let p = pendulum();
        let vstar = |q: &Vector<2>| -9.81 * q[0].cos() - 9.81 * (q[0].cos() + (q[0] + q[1]).cos());
        let zero = Vector::<2>::zeros();
        for q in [Vector::<2>::new(0.3, -0.2), Vector::<2>::new(2.0, 1.0)] {
            assert!((p.potential(&q) - (vstar(&q) - vstar(&zero))).abs() < 1e-12);
        }
        assert_eq!(p.potential(&zero), 0.0);
    }

    #[test]
    fn refuses_bad_parameters() {
        let bad = PlanarChainParams::<2> {
            masses: [-1.0, 1.0],
            ..Default::default()
        };
        let err = DoublePendulum::new(bad).unwrap_err();
        assert!(err.to_string().contains("m1"), "{err}");
        let nan = PlanarChainParams::<2> {
            gravity: f64::NAN,
            ..Default::default()
        };
        assert!(DoublePendulum::new(nan).is_err());
        let free = PlanarChainParams::<2> {
            gravity: 0.0,
            ..Default::default()
        };
        assert_eq!(
            DoublePendulum::new(free).unwrap_err(),
            ParamsError::NoEquilibrium
        );
    }
}
