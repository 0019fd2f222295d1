//! Planar serial chain of `N` rigid links with geared joint motors, joint
//! friction and optional joint springs; relative joint angles, gravity along
//! `-y`. The paper's double pendulum (section V) is the 2-link chain with
//! point masses at the link tips ([`PlanarChainParams::point_masses`]).
//!
//! The closed form works in absolute link angles `phi = L theta` (`L` lower
//! triangular ones) where the link inertia is `Mt_jl = A_jl cos(phi_j -
//! phi_l)` with constant amplitudes `A` (masses, lengths, centre-of-mass
//! distances and link inertias), plus the constant inertia the motor rotors
//! add; relative quantities follow by `M = L' Mt L`. All derivatives are
//! exact.
//!
//! Motors (as the identified laboratory pendulums of `shared/robots`): joint
//! `j`'s rotor (inertia `Ir_j` before a gearbox of ratio `gr_j`) sits on link
//! `j - 1` (the base for `j = 1`) and turns at `phid_{j-1} - gr_j qd_j`, so it
//! adds `Ir_j w_j w_j'` to `M` with `w_j = sum_{i<j} e_i - gr_j e_j`: for two
//! joints `M11 += gr1^2 Ir1 + Ir2`, `M12 += -gr2 Ir2`, `M22 += gr2^2 Ir2`.
//!
//! Friction per joint: viscous `b qd` plus the smooth Coulomb law
//! `cf atan(k qd)` (`k` = [`PlanarChainParams::coulomb_sharpness`], 100 1/(rad/s)
//! in the shared parameter files; it tends to `cf pi/2` at speed).

use super::{DynamicsJacobian, EnergyWithGradient, Matrix, MechanicalSystem, Vector, sin_cos};
use crate::math;
use nalgebra::SMatrix;
use thiserror::Error;

/// One rigid link.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Link {
    /// Mass `m` (kg).
    pub mass: f64,
    /// Length `l`, joint to next joint (m). The last link's length does not
    /// enter the dynamics.
    pub length: f64,
    /// Distance `r` from the link's joint to its centre of mass along the link (m).
    pub com: f64,
    /// Inertia **about the centre of mass** (kg m^2). The inertia about the
    /// joint axis is `inertia + mass com^2` ([`Link::inertia_about_joint`]).
    pub inertia: f64,
}

impl Link {
    /// A point mass at the link tip (the paper's model): `r = l`, no inertia about the COM.
    pub fn point_mass(mass: f64, length: f64) -> Self {
        Self {
            mass,
            length,
            com: length,
            inertia: 0.0,
        }
    }

    /// A rigid link given, as identified robots usually are, by its inertia
    /// **about the joint axis** `I = I_com + m r^2` (converted to `I_com`).
    pub fn with_inertia_about_joint(mass: f64, length: f64, com: f64, inertia: f64) -> Self {
        Self {
            mass,
            length,
            com,
            inertia: inertia - mass * com * com,
        }
    }

    /// Inertia about the joint axis, `I_com + m r^2` (kg m^2).
    pub fn inertia_about_joint(&self) -> f64 {
        self.inertia + self.mass * self.com * self.com
    }
}

/// One actuated joint: motor, friction and an optional spring.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Joint {
    /// Rotor inertia of the joint's motor before the gearbox, `Ir` (kg m^2).
    pub rotor_inertia: f64,
    /// Gear ratio `gr` (motor turns per joint turn, > 0).
    pub gear_ratio: f64,
    /// Viscous friction `b` (N m s/rad).
    pub viscous: f64,
    /// Coulomb friction `cf` (N m) of the law `cf atan(k qd)`.
    pub coulomb: f64,
    /// Spring stiffness (N m/rad); zero: no spring.
    pub stiffness: f64,
    /// Spring rest angle (rad).
    pub rest_angle: f64,
}

impl Default for Joint {
    /// A frictionless direct drive without rotor inertia or spring.
    fn default() -> Self {
        Self {
            rotor_inertia: 0.0,
            gear_ratio: 1.0,
            viscous: 0.0,
            coulomb: 0.0,
            stiffness: 0.0,
            rest_angle: 0.0,
        }
    }
}

/// Physical parameters of a [`PlanarChain`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlanarChainParams<const N: usize> {
    /// Links, from the base outwards.
    #[serde(with = "serde_big_array::BigArray")]
    pub links: [Link; N],
    /// Joints; joint `j` drives link `j` and its motor sits on link `j - 1`.
    #[serde(with = "serde_big_array::BigArray")]
    pub joints: [Joint; N],
    /// Gravitational acceleration `g` (m/s^2).
    pub gravity: f64,
    /// Slope `k` of the smooth Coulomb law `cf atan(k qd)` (s/rad).
    pub coulomb_sharpness: f64,
}

impl<const N: usize> Default for PlanarChainParams<N> {
    /// The paper's values: 1 kg point masses at the tips of 1 m links,
    /// g = 9.81, frictionless direct drives, no springs.
    fn default() -> Self {
        Self::point_masses([1.0; N], [1.0; N], 9.81)
    }
}

impl<const N: usize> PlanarChainParams<N> {
    /// Point masses at the link tips, frictionless direct drives (the paper's model).
    pub fn point_masses(masses: [f64; N], lengths: [f64; N], gravity: f64) -> Self {
        Self {
            links: std::array::from_fn(|j| Link::point_mass(masses[j], lengths[j])),
            joints: [Joint::default(); N],
            gravity,
            coulomb_sharpness: DEFAULT_COULOMB_SHARPNESS,
        }
    }

    /// The same chain with viscous and Coulomb friction removed.
    pub fn without_friction(mut self) -> Self {
        for j in &mut self.joints {
            j.viscous = 0.0;
            j.coulomb = 0.0;
        }
        self
    }

    /// True when some joint has viscous or Coulomb friction.
    pub fn has_friction(&self) -> bool {
        self.joints
            .iter()
            .any(|j| j.viscous > 0.0 || j.coulomb > 0.0)
    }
}

/// Slope `k` of `cf atan(k qd)` the shared robot files were identified with (s/rad).
pub const DEFAULT_COULOMB_SHARPNESS: f64 = 100.0;

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
    /// Gravity and springs do not hold the chain at a strict minimum of the potential.
    #[error("no stable equilibrium: {0}")]
    NoEquilibrium(String),
}

/// A planar serial chain of rigid links with geared motors and joint friction.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlanarChain<const N: usize> {
    params: PlanarChainParams<N>,
    /// `A_jl`, the amplitudes of the absolute link inertia `A_jl cos(phi_j - phi_l)`.
    coupling: Matrix<N>,
    /// Constant inertia of the motor rotors in absolute angles, `L^-T M_r L^-1`.
    rotor_absolute: Matrix<N>,
    /// Constant inertia of the motor rotors in joint angles, `M_r`.
    rotor_joint: Matrix<N>,
    /// `g (m_j r_j + l_j sum_{i>j} m_i)`, the amplitudes of the gravity torques on absolute angles.
    gravity_amplitude: Vector<N>,
    /// The stable equilibrium `q_eq` (zero unless springs have rest angles).
    equilibrium: Vector<N>,
    /// Gravity and spring energy at `q_eq`, subtracted so that `V(q_eq) = 0`.
    potential_offset: f64,
    /// No viscous or Coulomb friction at any joint.
    frictionless: bool,
}

/// The paper's double pendulum: `theta_1` absolute, `theta_2` relative.
pub type DoublePendulum = PlanarChain<2>;

impl<const N: usize> Default for PlanarChain<N> {
    fn default() -> Self {
        Self::new(PlanarChainParams::default()).expect("default parameters are valid")
    }
}

/// Checks a parameter; its `name` is only made for the error, so that
/// building a valid chain allocates nothing (online identification rebuilds
/// chains in a real-time path).
fn check(name: impl FnOnce() -> String, value: f64, positive: bool) -> Result<(), ParamsError> {
    let ok = value.is_finite() && if positive { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(())
    } else {
        Err(ParamsError::Invalid {
            name: name(),
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
    /// Builds the chain, refusing non-physical parameters (the message
    /// names the parameter: `m1`, `r2`, `I1`, `Ir2`, `gr1`, `b1`, `cf2`, ...).
    pub fn new(params: PlanarChainParams<N>) -> Result<Self, ParamsError> {
        for (j, link) in params.links.iter().enumerate() {
            let n = j + 1;
            check(|| format!("m{n}"), link.mass, true)?;
            check(|| format!("l{n}"), link.length, true)?;
            if !link.com.is_finite() {
                return Err(ParamsError::Invalid {
                    name: format!("r{n}"),
                    value: link.com,
                    reason: "must be finite",
                });
            }
            // Identified robots give base parameters: the inertia about the
            // joint and the first moment m r independently, so I < m r^2
            // (a negative inertia about the COM) occurs (robots/...-B0.yml)
            // and is accepted while M(q) stays positive definite (below).
            if !(link.inertia.is_finite() && link.inertia_about_joint() > 0.0) {
                return Err(ParamsError::Invalid {
                    name: format!("I{n}"),
                    value: link.inertia_about_joint(),
                    reason: "the inertia about the joint must be finite and > 0",
                });
            }
        }
        for (j, joint) in params.joints.iter().enumerate() {
            let n = j + 1;
            check(|| format!("Ir{n}"), joint.rotor_inertia, false)?;
            check(|| format!("gr{n}"), joint.gear_ratio, true)?;
            check(|| format!("b{n}"), joint.viscous, false)?;
            check(|| format!("cf{n}"), joint.coulomb, false)?;
            check(|| format!("k{n}"), joint.stiffness, false)?;
            if !joint.rest_angle.is_finite() {
                return Err(ParamsError::Invalid {
                    name: format!("q_rest{n}"),
                    value: joint.rest_angle,
                    reason: "must be finite",
                });
            }
        }
        check(|| "g".into(), params.gravity, false)?;
        check(
            || "coulomb_sharpness".into(),
            params.coulomb_sharpness,
            true,
        )?;

        let links = &params.links;
        // Lever arm of link j's length or COM in the position of link i's COM.
        let arm = |j: usize, i: usize| {
            if j < i {
                links[j].length
            } else if j == i {
                links[j].com
            } else {
                0.0
            }
        };
        let coupling = Matrix::<N>::from_fn(|j, l| {
            let translation: f64 = (j.max(l)..N)
                .map(|i| links[i].mass * arm(j, i) * arm(l, i))
                .sum();
            translation + if j == l { links[j].inertia } else { 0.0 }
        });
        let gravity_amplitude = Vector::<N>::from_fn(|j, _| {
            let carried: f64 = links[j + 1..].iter().map(|l| l.mass).sum();
            params.gravity * (links[j].mass * links[j].com + carried * links[j].length)
        });
        let mut rotor_joint = Matrix::<N>::zeros();
        for (j, joint) in params.joints.iter().enumerate() {
            let w = Vector::<N>::from_fn(|i, _| {
                if i < j {
                    1.0
                } else if i == j {
                    -joint.gear_ratio
                } else {
                    0.0
                }
            });
            rotor_joint += w * w.transpose() * joint.rotor_inertia;
        }
        let l_inv = Self::l_inverse();
        let rotor_absolute = l_inv.transpose() * rotor_joint * l_inv;
        let mut chain = Self {
            params,
            coupling,
            rotor_absolute,
            rotor_joint,
            gravity_amplitude,
            equilibrium: Vector::<N>::zeros(),
            potential_offset: 0.0,
            frictionless: !params.has_friction(),
        };
        chain.check_inertia()?;
        chain.equilibrium = chain.find_equilibrium()?;
        chain.potential_offset = chain.raw_potential(&chain.equilibrium);
        if chain
            .potential_hessian(&chain.equilibrium)
            .cholesky()
            .is_none()
        {
            return Err(ParamsError::NoEquilibrium(format!(
                "the potential's Hessian at q_eq = {:?} is not positive definite \
                 (gravity and joint springs do not hold the chain)",
                chain.equilibrium.as_slice()
            )));
        }
        Ok(chain)
    }

    /// The parameters the chain was built from.
    pub fn params(&self) -> &PlanarChainParams<N> {
        &self.params
    }

    /// The same chain with another Coulomb slope `k` (e.g. a smoother law
    /// for a prediction model with long integration steps).
    pub fn with_coulomb_sharpness(&self, k: f64) -> Result<Self, ParamsError> {
        Self::new(PlanarChainParams {
            coulomb_sharpness: k,
            ..self.params
        })
    }

    /// `M(q)` must be positive definite everywhere. It depends on the
    /// relative angles through `cos(phi_j - phi_l)` only; for two links its
    /// determinant is concave in `cos q2`, so `q2 = 0, pi` decide; for more,
    /// a grid of 12 angles per joint is checked.
    fn check_inertia(&self) -> Result<(), ParamsError> {
        let per_joint: usize = if N <= 2 { 2 } else { 12 };
        let total = per_joint.pow(N.saturating_sub(1) as u32);
        for index in 0..total {
            let mut rest = index;
            let q = Vector::<N>::from_fn(|j, _| {
                if j == 0 {
                    return 0.0;
                }
                let k = rest % per_joint;
                rest /= per_joint;
                std::f64::consts::TAU * k as f64 / per_joint as f64
            });
            if self.mass_matrix(&q).cholesky().is_none() {
                let j = (1..=N)
                    .min_by(|&a, &b| {
                        self.params.links[a - 1]
                            .inertia
                            .total_cmp(&self.params.links[b - 1].inertia)
                    })
                    .unwrap_or(1);
                return Err(ParamsError::Invalid {
                    name: format!("I{j}"),
                    value: self.params.links[j - 1].inertia_about_joint(),
                    reason: "the inertias about the joints are too small for the masses and COM distances: M(q) is not positive definite",
                });
            }
        }
        Ok(())
    }

    /// Stable equilibrium: `q = 0` unless a spring has a rest angle, then
    /// Newton on `dV/dq = 0` from the rest angles' hanging configuration.
    fn find_equilibrium(&self) -> Result<Vector<N>, ParamsError> {
        if self
            .params
            .joints
            .iter()
            .all(|j| j.rest_angle == 0.0 || j.stiffness == 0.0)
        {
            return Ok(Vector::<N>::zeros());
        }
        let mut q = Vector::<N>::zeros();
        for _ in 0..100 {
            let g = self.potential_gradient(&q);
            if g.amax() < 1e-13 {
                return Ok(q);
            }
            let step = match self.potential_hessian(&q).cholesky() {
                Some(ch) => ch.solve(&g),
                None => break,
            };
            // Damped Newton: never more than 0.5 rad per iteration.
            let scale = (0.5 / step.amax().max(1e-300)).min(1.0);
            q -= step * scale;
        }
        Err(ParamsError::NoEquilibrium(
            "Newton on dV/dq = 0 from the hanging configuration did not converge".into(),
        ))
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

    /// `x L`: column `j` is the sum of the columns `j..N` of `x`.
    #[inline(always)]
    fn times_l(x: &Matrix<N>) -> Matrix<N> {
        let mut out = *x;
        for j in (0..N.saturating_sub(1)).rev() {
            for i in 0..N {
                out[(i, j)] += out[(i, j + 1)];
            }
        }
        out
    }

    /// `L^-1 x` (`x` a vector or a matrix): row `j` less row `j - 1`.
    #[inline(always)]
    fn l_inverse_times<const C: usize>(x: &SMatrix<f64, N, C>) -> SMatrix<f64, N, C> {
        let mut out = *x;
        for j in 1..N {
            for c in 0..C {
                out[(j, c)] -= x[(j - 1, c)];
            }
        }
        out
    }

    /// `x L^-T`: column `j` less column `j - 1`.
    #[inline(always)]
    fn times_l_inverse_t(x: &Matrix<N>) -> Matrix<N> {
        let mut out = *x;
        for j in 1..N {
            for i in 0..N {
                out[(i, j)] -= x[(i, j - 1)];
            }
        }
        out
    }

    /// Centrifugal forces in absolute angles `h_j = sum_l a_jl sin(phi_j - phi_l) phid_l^2`.
    fn absolute_centrifugal(&self, phi: &Vector<N>, phid: &Vector<N>) -> Vector<N> {
        Vector::<N>::from_fn(|j, _| {
            (0..N)
                .map(|l| self.coupling[(j, l)] * math::sin(phi[j] - phi[l]) * phid[l] * phid[l])
                .sum()
        })
    }

    fn spring_forces(&self, q: &Vector<N>) -> Vector<N> {
        Vector::<N>::from_fn(|j, _| {
            let joint = &self.params.joints[j];
            joint.stiffness * (q[j] - joint.rest_angle)
        })
    }

    fn stiffness(&self) -> Vector<N> {
        Vector::<N>::from_fn(|j, _| self.params.joints[j].stiffness)
    }

    /// Gravity and spring energy before the offset that puts `V(q_eq) = 0`.
    fn raw_potential(&self, q: &Vector<N>) -> f64 {
        let phi = Self::absolute(q);
        let gravity: f64 = (0..N)
            .map(|j| self.gravity_amplitude[j] * (1.0 - math::cos(phi[j])))
            .sum();
        let springs: f64 = (0..N)
            .map(|j| {
                let joint = &self.params.joints[j];
                let d = q[j] - joint.rest_angle;
                0.5 * joint.stiffness * d * d
            })
            .sum();
        gravity + springs
    }
}

impl<const N: usize> MechanicalSystem<N> for PlanarChain<N> {
    fn mass_matrix(&self, q: &Vector<N>) -> Matrix<N> {
        let phi = Self::absolute(q);
        let l = Self::l_matrix();
        let links = self.coupling.component_mul(&relative_sin_cos(&phi).1);
        l.transpose() * links * l + self.rotor_joint
    }

    fn potential(&self, q: &Vector<N>) -> f64 {
        self.raw_potential(q) - self.potential_offset
    }

    fn potential_gradient(&self, q: &Vector<N>) -> Vector<N> {
        let phi = Self::absolute(q);
        let g_abs = Vector::<N>::from_fn(|j, _| self.gravity_amplitude[j] * math::sin(phi[j]));
        Self::to_joint_forces(&g_abs) + self.spring_forces(q)
    }

    fn potential_hessian(&self, q: &Vector<N>) -> Matrix<N> {
        let phi = Self::absolute(q);
        let l = Self::l_matrix();
        let diag = Vector::<N>::from_fn(|j, _| self.gravity_amplitude[j] * math::cos(phi[j]));
        l.transpose() * Matrix::<N>::from_diagonal(&diag) * l
            + Matrix::<N>::from_diagonal(&self.stiffness())
    }

    fn coriolis_forces(&self, q: &Vector<N>, qd: &Vector<N>) -> Vector<N> {
        let phi = Self::absolute(q);
        let phid = Self::absolute(qd);
        Self::to_joint_forces(&self.absolute_centrifugal(&phi, &phid))
    }

    fn equilibrium(&self) -> Vector<N> {
        self.equilibrium
    }

    fn has_friction(&self) -> bool {
        !self.frictionless
    }

    fn friction(&self, qd: &Vector<N>) -> Vector<N> {
        if self.frictionless {
            // The per-sample path of a frictionless model skips the atan.
            return Vector::<N>::zeros();
        }
        let k = self.params.coulomb_sharpness;
        // The `libm` crate's arctangent (musl's, from fdlibm, under 1 ulp):
        // glibc's saves and restores the floating-point environment on
        // every call, 22 k instructions a sample on the laboratory robots.
        Vector::<N>::from_fn(|j, _| {
            let joint = &self.params.joints[j];
            joint.viscous * qd[j] + joint.coulomb * libm::atan(k * qd[j])
        })
    }

    fn friction_slope(&self, qd: &Vector<N>) -> Vector<N> {
        if self.frictionless {
            return Vector::<N>::zeros();
        }
        let k = self.params.coulomb_sharpness;
        Vector::<N>::from_fn(|j, _| {
            let joint = &self.params.joints[j];
            let kv = k * qd[j];
            joint.viscous + joint.coulomb * k / (1.0 + kv * kv)
        })
    }

    fn conservative_forward_dynamics(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> Vector<N> {
        // Solved in absolute angles, Mt phidd = L^-T (tau - K (q - q_rest)) - h - G,
        // which avoids forming L' Mt L; the same arithmetic as the
        // Jacobian's acceleration, so both give the same bits.
        let trig = trigonometry(&Self::absolute(q));
        let phid = Self::absolute(qd);
        let (phidd, _) = self.absolute_acceleration(&trig, &phid, &(tau - self.spring_forces(q)));
        Self::l_inverse_times(&phidd)
    }

    fn conservative_dynamics_jacobian(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> DynamicsJacobian<N> {
        self.jacobian_from(
            &trigonometry(&Self::absolute(q)),
            qd,
            &(tau - self.spring_forces(q)),
        )
    }

    fn conservative_dynamics_jacobian_with_energy(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> (DynamicsJacobian<N>, EnergyWithGradient<N>) {
        let trig = trigonometry(&Self::absolute(q));
        let springs = self.spring_forces(q);
        (
            self.jacobian_from(&trig, qd, &(tau - springs)),
            self.energy_from(&trig, q, qd, &springs),
        )
    }

    fn energy_gradient(&self, q: &Vector<N>, qd: &Vector<N>) -> (Vector<N>, Vector<N>) {
        let phi = Self::absolute(q);
        let phid = Self::absolute(qd);
        let a_sin = self.coupling.component_mul(&relative_sin_cos(&phi).0);
        // dT/dphi_k = -phid_k sum_l a_kl s_kl phid_l
        let d_kinetic = -phid.component_mul(&(a_sin * phid));
        let d_e_dq = Self::to_joint_forces(&d_kinetic) + self.potential_gradient(q);
        let d_e_dqd = self.mass_matrix(q) * qd;
        (d_e_dq, d_e_dqd)
    }

    fn energy_with_gradient(&self, q: &Vector<N>, qd: &Vector<N>) -> EnergyWithGradient<N> {
        let trig = trigonometry(&Self::absolute(q));
        self.energy_from(&trig, q, qd, &self.spring_forces(q))
    }
}

/// The sines and cosines of the absolute angles and of their differences
/// ([`trigonometry`]), which the dynamics Jacobian and the energy share.
type Trigonometry<const N: usize> = (Vector<N>, Vector<N>, Matrix<N>, Matrix<N>);

impl<const N: usize> PlanarChain<N> {
    /// The conservative dynamics Jacobian from the absolute angles'
    /// trigonometry, at the joint torques net of the springs' `joint`.
    #[inline(always)]
    fn jacobian_from(
        &self,
        trig: &Trigonometry<N>,
        qd: &Vector<N>,
        joint: &Vector<N>,
    ) -> DynamicsJacobian<N> {
        let phid = Self::absolute(qd);
        let (phidd, mt_inv) = self.absolute_acceleration(trig, &phid, joint);
        let (dw_dq, dw_dqd) = if N == 2 {
            self.two_link_force_derivatives(trig, &phid, &phidd)
        } else {
            self.force_derivatives(trig, &phid, &phidd)
        };
        // L, L^-1 and L^-T are sums and differences of neighbours: applied
        // as such, not as dense products (a third of the arithmetic here).
        let response = Self::l_inverse_times(&mt_inv);
        DynamicsJacobian {
            acceleration: Self::l_inverse_times(&phidd),
            d_q: response * dw_dq,
            d_qd: response * dw_dqd,
            d_tau: Self::times_l_inverse_t(&response),
        }
    }

    /// The derivatives of the absolute-angle balance `w - Mt phidd` with
    /// respect to the joint angles and speeds, at the accelerations
    /// `phidd`: `Mt^-1` times them, in joint terms, is the Jacobian.
    #[inline(always)]
    fn force_derivatives(
        &self,
        trig: &Trigonometry<N>,
        phid: &Vector<N>,
        phidd: &Vector<N>,
    ) -> (Matrix<N>, Matrix<N>) {
        let (_, cos_phi, sin, cos) = *trig;
        let a_cos = self.coupling.component_mul(&cos);
        let a_sin = self.coupling.component_mul(&sin);
        let phid_sq = phid.component_mul(phid);
        // d(Mt phidd)/d phi: -diag(sum_l a_jl s_jl phidd_l) + a_jk s_jk phidd_k
        // (the rotor inertia is constant and drops out).
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
        let d_grav = Matrix::<N>::from_diagonal(&self.gravity_amplitude.component_mul(&cos_phi));

        // dw/dq = (-dh/dphi - dG/dphi - d(Mt phidd)/dphi) L - L^-T K.
        let mut dw_dq = Self::times_l(&(-d_cent_phi - d_grav - d_mass));
        let springs = self.stiffness();
        for j in 0..N {
            dw_dq[(j, j)] -= springs[j];
            if j + 1 < N {
                dw_dq[(j, j + 1)] += springs[j + 1];
            }
        }
        (dw_dq, -Self::times_l(&d_cent_phid))
    }

    /// [`Self::force_derivatives`] for two links, written out: the same
    /// formulas without the products with the zeros and ones of the
    /// relative angle's sines and cosines on the diagonal (a sample of the
    /// paper pendulum evaluates them 400 times).
    #[inline(always)]
    fn two_link_force_derivatives(
        &self,
        trig: &Trigonometry<N>,
        phid: &Vector<N>,
        phidd: &Vector<N>,
    ) -> (Matrix<N>, Matrix<N>) {
        let (_, cos_phi, sin, cos) = trig;
        let (s, c) = (sin[(0, 1)], cos[(0, 1)]);
        let a = &self.coupling;
        let (a01, a10) = (a[(0, 1)], a[(1, 0)]);
        let (p0, p1) = (phid[0], phid[1]);
        let (dd0, dd1) = (phidd[0], phidd[1]);
        let (sq0, sq1) = (p0 * p0, p1 * p1);
        // The generic form's d_mass, d_cent_phi and d_grav: the relative
        // angle's terms appear in pairs of opposite sign in each row
        // (a_sin = [0 a01 s; -a10 s 0]).
        let mass01 = a01 * s * dd1;
        let mass10 = -(a10 * s) * dd0;
        let cent01 = a01 * c * sq1;
        let cent10 = a10 * c * sq0;
        let g0 = self.gravity_amplitude[0] * cos_phi[0];
        let g1 = self.gravity_amplitude[1] * cos_phi[1];
        // -(d_cent_phi + d_grav + d_mass) in absolute angles, then times L
        // (column 0 is the sum of both columns) and the springs.
        let m00 = -(cent01 + g0 - mass01);
        let m01 = cent01 - mass01;
        let m10 = cent10 - mass10;
        let m11 = -(cent10 + g1 - mass10);
        let springs = self.stiffness();
        let dw_dq = Matrix::<N>::from_fn(|j, k| match (j, k) {
            (0, 0) => m00 + m01 - springs[0],
            (0, _) => m01 + springs[1],
            (_, 0) => m10 + m11,
            _ => m11 - springs[1],
        });
        // -(dh/d phid) L: dh_0/d phid_1 = 2 a01 s p1, dh_1/d phid_0 = -2 a10 s p0.
        let (h01, h10) = (2.0 * a01 * s * p1, -2.0 * a10 * s * p0);
        let dw_dqd = Matrix::<N>::from_fn(|j, k| match (j, k) {
            (0, _) => -h01,
            (_, 0) => -h10,
            _ => 0.0,
        });
        (dw_dq, dw_dqd)
    }

    /// The absolute angles' accelerations `phidd = Mt^-1 w` and `Mt^-1`,
    /// from the angles' trigonometry, the absolute speeds `phid` and the
    /// joint torques net of the springs' `joint`.
    #[inline(always)]
    fn absolute_acceleration(
        &self,
        trig: &Trigonometry<N>,
        phid: &Vector<N>,
        joint: &Vector<N>,
    ) -> (Vector<N>, Matrix<N>) {
        let (sin_phi, _, sin, cos) = trig;
        let mt = self.coupling.component_mul(cos) + self.rotor_absolute;
        let centrifugal = self.coupling.component_mul(sin) * phid.component_mul(phid);
        let gravity = self.gravity_amplitude.component_mul(sin_phi);
        let w = Self::to_absolute_forces(joint) - centrifugal - gravity;
        // One inverse and four products: cheaper than a Cholesky solve for
        // each of the 3 N + 1 right-hand sides of the Jacobian (issue 22),
        // and for two links the inverse is closed-form.
        let mt_inv = spd_inverse(&mt).unwrap_or(Matrix::<N>::repeat(f64::NAN));
        (mt_inv * w, mt_inv)
    }

    /// The energy with its gradient from the absolute angles'
    /// trigonometry and the springs' torques.
    #[inline]
    fn energy_from(
        &self,
        trig: &Trigonometry<N>,
        q: &Vector<N>,
        qd: &Vector<N>,
        springs: &Vector<N>,
    ) -> EnergyWithGradient<N> {
        // In absolute angles, `qd' M qd = phid' Mt phid` (`M = L' Mt L`),
        // from one set of sines and cosines.
        let phid = Self::absolute(qd);
        let (sin_phi, cos_phi, sin, cos) = *trig;
        let momentum = (self.coupling.component_mul(&cos) + self.rotor_absolute) * phid;
        let mut energy = 0.5 * phid.dot(&momentum) - self.potential_offset;
        for j in 0..N {
            let d = q[j] - self.params.joints[j].rest_angle;
            energy += self.gravity_amplitude[j] * (1.0 - cos_phi[j]) + 0.5 * springs[j] * d;
        }
        // dT/dphi_k = -phid_k sum_l a_kl s_kl phid_l, dV/dphi_k = G_k sin phi_k.
        let a_sin = self.coupling.component_mul(&sin);
        let d_phi =
            self.gravity_amplitude.component_mul(&sin_phi) - phid.component_mul(&(a_sin * phid));
        (
            energy,
            Self::to_joint_forces(&d_phi) + springs,
            Self::to_joint_forces(&momentum),
        )
    }
}

/// The inverse of a symmetric positive definite `m`, `None` when it is not
/// (numerically) positive definite. Two and three links: the closed form
/// (the adjugate over the determinant; a generic Cholesky factor and
/// inverse cost several times more at these sizes).
#[inline]
fn spd_inverse<const N: usize>(m: &Matrix<N>) -> Option<Matrix<N>> {
    if N == 3 {
        let (a, b, c) = (m[(0, 0)], m[(0, 1)], m[(0, 2)]);
        let (d, e, f) = (m[(1, 1)], m[(1, 2)], m[(2, 2)]);
        // The cofactors of the symmetric matrix [a b c; b d e; c e f].
        let (c00, c01, c02) = (d * f - e * e, c * e - b * f, b * e - c * d);
        let (c11, c12, c22) = (a * f - c * c, b * c - a * e, a * d - b * b);
        let det = a * c00 + b * c01 + c * c02;
        // Sylvester's test, the leading minors positive: what a Cholesky
        // factorisation's positive pivots say.
        if !(a > 0.0 && c22 > 0.0 && det > 0.0) {
            return None;
        }
        let s = 1.0 / det;
        let mut inv = Matrix::<N>::zeros();
        for (i, j, v) in [
            (0, 0, c00),
            (0, 1, c01),
            (0, 2, c02),
            (1, 1, c11),
            (1, 2, c12),
            (2, 2, c22),
        ] {
            inv[(i, j)] = v * s;
            inv[(j, i)] = v * s;
        }
        return Some(inv);
    }
    if N == 2 {
        let (a, b, d) = (m[(0, 0)], m[(0, 1)], m[(1, 1)]);
        let det = a * d - b * b;
        // The same test a Cholesky factorisation makes (both pivots > 0).
        if !(a > 0.0 && det > 0.0) {
            return None;
        }
        let s = 1.0 / det;
        let mut inv = Matrix::<N>::zeros();
        inv[(0, 0)] = d * s;
        inv[(0, 1)] = -b * s;
        inv[(1, 0)] = -b * s;
        inv[(1, 1)] = a * s;
        return Some(inv);
    }
    m.cholesky().map(|c| c.inverse())
}

/// `sin phi_j`, `cos phi_j` and the relative `sin(phi_j - phi_l)`,
/// `cos(phi_j - phi_l)` from N sine-cosine pairs: the relative ones by
/// the difference formulas (to a few ulps of the direct values). The libm
/// calls were 12 % of an RTI sample on the orbit (issue 12); the pairs are
/// [`sin_cos`]'s (about half of libm's instructions).
#[inline(always)]
fn trigonometry<const N: usize>(phi: &Vector<N>) -> Trigonometry<N> {
    let mut sin_phi = Vector::<N>::zeros();
    let mut cos_phi = Vector::<N>::zeros();
    for j in 0..N {
        (sin_phi[j], cos_phi[j]) = sin_cos(phi[j]);
    }
    let mut sin = Matrix::<N>::zeros();
    let mut cos = Matrix::<N>::identity();
    for j in 0..N {
        for l in j + 1..N {
            let s = sin_phi[j] * cos_phi[l] - cos_phi[j] * sin_phi[l];
            let c = cos_phi[j] * cos_phi[l] + sin_phi[j] * sin_phi[l];
            sin[(j, l)] = s;
            sin[(l, j)] = -s;
            cos[(j, l)] = c;
            cos[(l, j)] = c;
        }
    }
    (sin_phi, cos_phi, sin, cos)
}

/// `sin(phi_j - phi_l)` and `cos(phi_j - phi_l)` for all pairs: one
/// sine-cosine pair per `j < l` (antisymmetric and symmetric, 0 and 1 on
/// the diagonal, exactly as the direct formulas give them).
#[inline]
fn relative_sin_cos<const N: usize>(phi: &Vector<N>) -> (Matrix<N>, Matrix<N>) {
    let mut sin = Matrix::<N>::zeros();
    let mut cos = Matrix::<N>::identity();
    for j in 0..N {
        for l in j + 1..N {
            let (s, c) = sin_cos(phi[j] - phi[l]);
            sin[(j, l)] = s;
            sin[(l, j)] = -s;
            cos[(j, l)] = c;
            cos[(l, j)] = c;
        }
    }
    (sin, cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_trigonometry_equals_the_direct_formulas() {
        let phi = Vector::<3>::new(0.3, -1.7, 2.9);
        let (sin, cos) = relative_sin_cos(&phi);
        for j in 0..3 {
            for l in 0..3 {
                assert_eq!(sin[(j, l)], math::sin(phi[j] - phi[l]));
                assert_eq!(cos[(j, l)], math::cos(phi[j] - phi[l]));
            }
        }
    }

    #[test]
    fn trigonometry_from_absolute_angles_matches_the_direct_formulas() {
        let phi = Vector::<3>::new(0.3, -1.7, 2.9);
        let (sin_phi, cos_phi, sin, cos) = trigonometry(&phi);
        for j in 0..3 {
            assert!((sin_phi[j] - math::sin(phi[j])).abs() <= 2.3e-16);
            assert!((cos_phi[j] - math::cos(phi[j])).abs() <= 2.3e-16);
            for l in 0..3 {
                assert!((sin[(j, l)] - math::sin(phi[j] - phi[l])).abs() < 4.0 * f64::EPSILON);
                assert!((cos[(j, l)] - math::cos(phi[j] - phi[l])).abs() < 4.0 * f64::EPSILON);
            }
        }
    }

    /// The chain of `p` with a motor, a spring, viscous and Coulomb
    /// friction on every joint, each joint's different.
    fn with_every_joint_term<const N: usize>(mut p: PlanarChainParams<N>) -> PlanarChain<N> {
        for (j, joint) in p.joints.iter_mut().enumerate() {
            let f = (j + 1) as f64;
            joint.rotor_inertia = 1e-5 * f;
            joint.gear_ratio = 20.0 * f;
            joint.viscous = 0.02 * f;
            joint.coulomb = 0.05 * f;
            joint.stiffness = 0.8 * f;
            joint.rest_angle = 0.1 * f;
        }
        PlanarChain::new(p).unwrap()
    }

    /// The shared-trigonometry path gives exactly what the two separate
    /// calls give, with motors, springs and friction on every joint.
    #[test]
    fn jacobian_with_energy_is_the_jacobian_and_the_energy() {
        let p = PlanarChainParams::<3>::point_masses([1.3, 0.7, 0.4], [0.9, 1.2, 0.6], 9.81);
        let chain = with_every_joint_term(p);
        for (q, qd) in [
            ([0.3, -1.7, 2.9], [0.4, -0.2, 1.1]),
            ([-2.5, 0.01, -0.6], [0.0, 3.0, -0.004]),
        ] {
            let (q, qd) = (Vector::<3>::from(q), Vector::<3>::from(qd));
            let tau = Vector::<3>::new(0.2, -0.1, 0.05);
            let (jac, energy) = chain.dynamics_jacobian_with_energy(&q, &qd, &tau);
            assert_eq!(jac, chain.dynamics_jacobian(&q, &qd, &tau));
            assert_eq!(energy, chain.energy_with_gradient(&q, &qd));
            // And the energy is the energy (the springs included once).
            assert!((energy.0 - chain.energy(&q, &qd)).abs() < 1e-12);
        }
    }

    /// The closed-form inverses of two and three links are the Cholesky
    /// one's to rounding, over the mass matrices of a rigid chain with
    /// motors and of point masses, and refuse what the Cholesky refuses.
    #[test]
    fn closed_form_inverses_match_the_cholesky_one() {
        fn check<const N: usize>(m: &Matrix<N>) {
            let reference = m.cholesky().unwrap().inverse();
            let inv = spd_inverse(m).unwrap();
            let scale = reference.amax() * m.amax();
            assert!(
                (inv - reference).amax() <= 1e-14 * reference.amax() * scale,
                "{m}"
            );
            assert_eq!(inv, inv.transpose());
        }
        let p3 = PlanarChainParams::<3>::point_masses([1.3, 0.7, 0.4], [0.9, 1.2, 0.6], 9.81);
        let p2 = PlanarChainParams::<2>::point_masses([1.3, 0.7], [0.9, 1.2], 9.81);
        for chain in [PlanarChain::new(p3).unwrap(), with_every_joint_term(p3)] {
            for q in [[0.0, 0.0, 0.0], [0.3, -1.7, 2.9], [3.1, 3.1, -3.1]] {
                check(&chain.mass_matrix(&Vector::<3>::from(q)));
            }
        }
        let chain = PlanarChain::new(p2).unwrap();
        check(&chain.mass_matrix(&Vector::<2>::new(0.4, -2.0)));
        // Indefinite, singular and NaN: refused, as the Cholesky does.
        for m in [
            Matrix::<3>::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            Matrix::<3>::new(1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 1.0),
            Matrix::<3>::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1e-3),
            Matrix::<3>::repeat(f64::NAN),
        ] {
            assert!(m.cholesky().is_none() && spd_inverse(&m).is_none(), "{m}");
        }
    }

    /// A frictionless chain says so, and its dynamics skip the friction
    /// with the same bits as the conservative ones; a chain with friction
    /// on one joint only says it has friction.
    #[test]
    fn only_a_frictionless_chain_skips_the_friction() {
        let p = PlanarChainParams::<3>::point_masses([1.3, 0.7, 0.4], [0.9, 1.2, 0.6], 9.81);
        let plain = PlanarChain::new(p).unwrap();
        assert!(!plain.has_friction());
        assert!(!crate::mechanics::Conservative(&plain).has_friction());
        let (q, qd) = (
            Vector::<3>::new(0.3, -1.7, 2.9),
            Vector::<3>::new(0.4, -0.2, 1.1),
        );
        let tau = Vector::<3>::new(0.2, -0.1, 0.05);
        assert_eq!(
            plain.dynamics_jacobian(&q, &qd, &tau),
            plain.conservative_dynamics_jacobian(&q, &qd, &tau)
        );
        assert_eq!(
            plain.forward_dynamics(&q, &qd, &tau),
            plain.conservative_forward_dynamics(&q, &qd, &tau)
        );
        let mut rough = p;
        rough.joints[2].coulomb = 0.01;
        let rough = PlanarChain::new(rough).unwrap();
        assert!(rough.has_friction());
        assert_ne!(
            rough.dynamics_jacobian(&q, &qd, &tau),
            rough.conservative_dynamics_jacobian(&q, &qd, &tau)
        );
        assert!(with_every_joint_term(p).has_friction());
    }

    /// The two-link Jacobian written out equals the generic one to
    /// rounding, on a chain with rigid links, motors, springs and friction
    /// (the laboratory robots' kind), and both match finite differences.
    #[test]
    fn two_link_jacobian_is_the_generic_one() {
        let mut p = PlanarChainParams::<2>::point_masses([1.3, 0.7], [0.9, 1.2], 9.81);
        p.links[0] = Link::with_inertia_about_joint(0.8, 0.25, 0.11, 0.021);
        p.links[1] = Link::with_inertia_about_joint(0.4, 0.3, 0.17, 0.019);
        let chain = with_every_joint_term(p);
        for (q, qd, tau) in [
            ([0.3, -1.7], [0.4, -0.2], [0.2, -0.1]),
            ([-2.5, 0.01], [0.0, 3.0], [-0.3, 0.05]),
            ([3.1, 2.9], [-7.0, 11.0], [0.0, 0.0]),
        ] {
            let (q, qd, tau) = (
                Vector::<2>::from(q),
                Vector::<2>::from(qd),
                Vector::<2>::from(tau),
            );
            let joint = tau - chain.friction(&qd) - chain.spring_forces(&q);
            let trig = trigonometry(&PlanarChain::<2>::absolute(&q));
            let phid = PlanarChain::<2>::absolute(&qd);
            let (phidd, _) = chain.absolute_acceleration(&trig, &phid, &joint);
            let two = chain.two_link_force_derivatives(&trig, &phid, &phidd);
            let any = chain.force_derivatives(&trig, &phid, &phidd);
            let close = |a: &Matrix<2>, b: &Matrix<2>| (a - b).amax() <= 1e-12 * (1.0 + b.amax());
            assert!(close(&two.0, &any.0), "{} {}", two.0, any.0);
            assert!(close(&two.1, &any.1), "{} {}", two.1, any.1);
            // The forward dynamics gives the Jacobian's acceleration, and
            // central differences of it give the Jacobian.
            let full = chain.dynamics_jacobian(&q, &qd, &tau);
            assert_eq!(full.acceleration, chain.forward_dynamics(&q, &qd, &tau));
            let eps = 1e-6;
            for i in 0..2 {
                let e = Vector::<2>::from_fn(|j, _| if i == j { eps } else { 0.0 });
                let fd_q = (chain.forward_dynamics(&(q + e), &qd, &tau)
                    - chain.forward_dynamics(&(q - e), &qd, &tau))
                    / (2.0 * eps);
                let fd_qd = (chain.forward_dynamics(&q, &(qd + e), &tau)
                    - chain.forward_dynamics(&q, &(qd - e), &tau))
                    / (2.0 * eps);
                let fd_tau = (chain.forward_dynamics(&q, &qd, &(tau + e))
                    - chain.forward_dynamics(&q, &qd, &(tau - e)))
                    / (2.0 * eps);
                for (fd, exact) in [(fd_q, full.d_q), (fd_qd, full.d_qd), (fd_tau, full.d_tau)] {
                    let col = exact.column(i).into_owned();
                    assert!((fd - col).amax() <= 1e-6 * (1.0 + col.amax()), "{fd} {col}");
                }
            }
        }
    }

    fn pendulum() -> DoublePendulum {
        DoublePendulum::default()
    }

    #[test]
    fn mass_matrix_matches_paper_formula() {
        let p = PlanarChain::<2>::new(PlanarChainParams::point_masses(
            [1.3, 0.7],
            [0.9, 1.2],
            9.81,
        ))
        .unwrap();
        let (m1, m2, l1, l2): (f64, f64, f64, f64) = (1.3, 0.7, 0.9, 1.2);
        for &t2 in &[0.0, 0.4, -1.7, 3.0] {
            let q = Vector::<2>::new(0.3, t2);
            let m = p.mass_matrix(&q);
            let m11 =
                m1 * l1 * l1 + m2 * (l1 + l2).powi(2) - 2.0 * m2 * l1 * l2 * (1.0 - math::cos(t2));
            let m21 = m2 * (l2 * l2 + l1 * l2 * math::cos(t2));
            assert!((m[(0, 0)] - m11).abs() < 1e-12);
            assert!((m[(1, 0)] - m21).abs() < 1e-12);
            assert!((m[(0, 1)] - m21).abs() < 1e-12);
            assert!((m[(1, 1)] - m2 * l2 * l2).abs() < 1e-12);
        }
    }

    #[test]
    fn potential_matches_paper_formula() {
        let p = pendulum();
        let vstar = |q: &Vector<2>| {
            -9.81 * math::cos(q[0]) - 9.81 * (math::cos(q[0]) + math::cos(q[0] + q[1]))
        };
        let zero = Vector::<2>::zeros();
        for q in [Vector::<2>::new(0.3, -0.2), Vector::<2>::new(2.0, 1.0)] {
            assert!((p.potential(&q) - (vstar(&q) - vstar(&zero))).abs() < 1e-12);
        }
        assert_eq!(p.potential(&zero), 0.0);
    }

    #[test]
    fn refuses_bad_parameters() {
        let bad = PlanarChainParams::<2>::point_masses([-1.0, 1.0], [1.0; 2], 9.81);
        let err = DoublePendulum::new(bad).unwrap_err();
        assert!(err.to_string().contains("m1"), "{err}");
        let nan = PlanarChainParams::<2>::point_masses([1.0; 2], [1.0; 2], f64::NAN);
        assert!(DoublePendulum::new(nan).is_err());
        let free = PlanarChainParams::<2>::point_masses([1.0; 2], [1.0; 2], 0.0);
        assert!(matches!(
            DoublePendulum::new(free).unwrap_err(),
            ParamsError::NoEquilibrium(_)
        ));
    }
}
