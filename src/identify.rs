//! Online identification of a planar chain from its energy balance (no
//! measured accelerations): the energy of a spring-free chain is linear in
//! a small set of base parameters, and so is the friction power, so over a
//! window `[t_a, t_b]`
//!
//! `theta' (phi_E(t_b) - phi_E(t_a)) + theta_F' int phi_F dt = int tau' qd dt`
//!
//! is one linear equation in the parameters, estimated by least squares
//! over all windows (with forgetting) and a prior, solved again at each
//! window from fixed-size sums.
//!
//! Base parameters ([`BaseParameters`]), with absolute link angles
//! `phi = L q` and speeds `w = L qd`:
//! - `A_jl` (`j <= l`): the link inertia amplitudes, `T_links = 1/2 sum_jl
//!   A_jl cos(phi_j - phi_l) w_j w_l`;
//! - `G_j`: the gravity amplitudes, `V = sum_j G_j (1 - cos phi_j)`;
//! - `Ir_j`: rotor inertias (gear ratios known), `T_rotors = 1/2 sum_j Ir_j
//!   (sum_{i<j} qd_i - gr_j qd_j)^2`;
//! - `b_j`, `cf_j`: viscous and Coulomb friction, power `b qd^2 + cf qd
//!   atan(k qd)` (the sharpness `k` known).
//!
//! Masses, lengths, centres of mass and inertias are not identifiable
//! separately (only these combinations act on the motion);
//! [`BaseParameters::chain_params`] maps an estimate back to a physical chain
//! that has exactly these base parameters.
//! Directions the motion does not excite receive no information: a window
//! whose regressor carries too little is skipped, and the prior is never
//! forgotten, so the estimate there stays at the prior.

use crate::math;
use crate::mechanics::{PlanarChain, PlanarChainParams, Vector};
use nalgebra::{SMatrix, SVector};

/// Number of base parameters of an `N`-joint chain: `N (N + 1) / 2`
/// inertia amplitudes, `N` gravity amplitudes, `N` rotor inertias, `2 N`
/// friction coefficients.
pub const fn base_parameter_count(n: usize) -> usize {
    n * (n + 1) / 2 + 4 * n
}

/// Why a chain cannot be identified or an estimate not mapped back.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IdentifyError {
    /// The energy is not linear in the base parameters with springs.
    #[error("identification needs a chain without joint springs (k{0} = {1})")]
    Spring(usize, f64),
    /// The estimate is not a physical chain.
    #[error("the estimate is not a physical chain: {0}")]
    NotPhysical(String),
}

/// Why an estimate is not a physical chain (allocation-free).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Unphysical {
    /// A non-finite parameter.
    #[error("non-finite estimate")]
    NonFinite,
    /// The amplitudes give no positive length of this link (1-based).
    #[error("no positive length of link {0}")]
    Length(usize),
    /// This link's inertia about its joint is not positive.
    #[error("link {0} has no positive inertia about its joint")]
    InertiaAboutJoint(usize),
    /// This link's mass is not positive.
    #[error("link {0} has no positive mass")]
    Mass(usize),
    /// A negative rotor inertia or friction coefficient at this joint.
    #[error("negative rotor inertia or friction at joint {0}")]
    Joint(usize),
}

/// The base parameters of an `N`-joint chain (`NP` =
/// [`base_parameter_count`]`(N)`), in the order `A_jl` (row by row, `j <=
/// l`), `G_j`, `Ir_j`, `b_j`, `cf_j`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaseParameters<const N: usize, const NP: usize> {
    /// The parameter vector.
    pub theta: SVector<f64, NP>,
}

impl<const N: usize, const NP: usize> BaseParameters<N, NP> {
    const CHECK: () = assert!(
        NP == base_parameter_count(N),
        "NP must be base_parameter_count(N)"
    );

    /// Index of `A_jl`, upper triangle row by row.
    fn a_index(j: usize, l: usize) -> usize {
        let (j, l) = (j.min(l), j.max(l));
        // rows 0..j hold N, N - 1, ..., N - j + 1 entries
        j * N - j * j.saturating_sub(1) / 2 + (l - j)
    }

    const fn g_index(j: usize) -> usize {
        N * (N + 1) / 2 + j
    }

    const fn rotor_index(j: usize) -> usize {
        N * (N + 1) / 2 + N + j
    }

    /// Index of the first parameter that is never negative: the rotor
    /// inertias and the friction coefficients follow.
    pub(crate) const NOT_NEGATIVE_FROM: usize = Self::rotor_index(0);

    const fn viscous_index(j: usize) -> usize {
        N * (N + 1) / 2 + 2 * N + j
    }

    const fn coulomb_index(j: usize) -> usize {
        N * (N + 1) / 2 + 3 * N + j
    }

    /// `A_jl` (0-based joints, either order): the link inertia amplitude
    /// (kg m^2).
    pub fn inertia_amplitude(&self, j: usize, l: usize) -> f64 {
        self.theta[Self::a_index(j, l)]
    }

    /// `G_j` (0-based): the gravity amplitude (N m).
    pub fn gravity_amplitude(&self, j: usize) -> f64 {
        self.theta[Self::g_index(j)]
    }

    /// `Ir_j` (0-based): the motor's rotor inertia before the gearbox
    /// (kg m^2, as [`crate::mechanics::Joint::rotor_inertia`]).
    pub fn rotor_inertia(&self, j: usize) -> f64 {
        self.theta[Self::rotor_index(j)]
    }

    /// `b_j` (0-based): the viscous friction (N m s).
    pub fn viscous(&self, j: usize) -> f64 {
        self.theta[Self::viscous_index(j)]
    }

    /// `cf_j` (0-based): the Coulomb friction (N m).
    pub fn coulomb(&self, j: usize) -> f64 {
        self.theta[Self::coulomb_index(j)]
    }

    /// The nearest parameters whose rotor inertias and friction
    /// coefficients are not negative (an unconstrained estimate of a
    /// frictionless joint scatters around zero).
    ///
    /// The first joint's rotor turns at `gr_1 qd_1`, so its energy and the
    /// link inertia amplitude `A_11` act only as `A_11 + gr_1^2 Ir_1`; the
    /// least squares puts a change of that sum mostly into `Ir_1` (its
    /// regressor is `gr_1^2` times larger). A negative `Ir_1` is therefore
    /// moved into `A_11`, keeping the sum, not cut off (cut off, a link 1
    /// 25 % lighter than the model was refused as not better).
    pub fn projected(&self, prior: &PlanarChainParams<N>) -> Self {
        let mut theta = self.theta;
        let rotor = Self::rotor_index(0);
        if theta[rotor] < 0.0 {
            let gr = prior.joints[0].gear_ratio;
            theta[Self::a_index(0, 0)] += gr * gr * theta[rotor];
            theta[rotor] = 0.0;
        }
        for v in theta.iter_mut().skip(rotor) {
            *v = v.max(0.0);
        }
        Self { theta }
    }

    /// The base parameters of a chain (refused: joint springs).
    pub fn of(params: &PlanarChainParams<N>) -> Result<Self, IdentifyError> {
        let () = Self::CHECK;
        if let Some((j, joint)) = params
            .joints
            .iter()
            .enumerate()
            .find(|(_, joint)| joint.stiffness != 0.0)
        {
            return Err(IdentifyError::Spring(j + 1, joint.stiffness));
        }
        let links = &params.links;
        let carried = |j: usize| -> f64 { links[j + 1..].iter().map(|l| l.mass).sum() };
        let mut theta = SVector::<f64, NP>::zeros();
        for j in 0..N {
            let lj = &links[j];
            // A_jj: the link's inertia about its joint plus what it carries at its tip.
            theta[Self::a_index(j, j)] =
                lj.inertia_about_joint() + lj.length * lj.length * carried(j);
            for l in j + 1..N {
                let ll = &links[l];
                theta[Self::a_index(j, l)] =
                    lj.length * (ll.mass * ll.com + ll.length * carried(l));
            }
            theta[Self::g_index(j)] = params.gravity * (lj.mass * lj.com + lj.length * carried(j));
            let joint = &params.joints[j];
            theta[Self::rotor_index(j)] = joint.rotor_inertia;
            theta[Self::viscous_index(j)] = joint.viscous;
            theta[Self::coulomb_index(j)] = joint.coulomb;
        }
        Ok(Self { theta })
    }

    /// A physical chain with exactly these base parameters: the lengths
    /// `l_j = A_jl / (G_l / g)` (least squares over `l > j`; the last link's
    /// from `prior`), the lightest masses that have them (each link's
    /// inertia about its centre of mass zero: equivalent point masses; the
    /// prior's mass for a link whose centre of mass is at its joint), gear
    /// ratios, gravity and the Coulomb sharpness of `prior`.
    pub fn chain_params(
        &self,
        prior: &PlanarChainParams<N>,
    ) -> Result<PlanarChainParams<N>, IdentifyError> {
        let out = self
            .physical(prior)
            .map_err(|u| IdentifyError::NotPhysical(u.to_string()))?;
        PlanarChain::new(out).map_err(|e| IdentifyError::NotPhysical(e.to_string()))?;
        Ok(out)
    }

    /// [`BaseParameters::chain_params`] without the chain's own checks and
    /// without allocating (the projection of the per-sample estimate): the
    /// lengths, inertias about the joints and masses positive, rotor
    /// inertias and friction not negative (then the inertia is positive
    /// definite: every link is a positive point mass).
    pub fn physical(
        &self,
        prior: &PlanarChainParams<N>,
    ) -> Result<PlanarChainParams<N>, Unphysical> {
        let theta = &self.theta;
        if !theta.iter().all(|v| v.is_finite()) {
            return Err(Unphysical::NonFinite);
        }
        let g = prior.gravity;
        let mut out = *prior;
        for j in 0..N.saturating_sub(1) {
            let (num, den) = (j + 1..N).fold((0.0, 0.0), |(n, d), l| {
                let gl = theta[Self::g_index(l)] / g;
                (n + theta[Self::a_index(j, l)] * gl, d + gl * gl)
            });
            if !(den > 0.0 && num > 0.0) {
                return Err(Unphysical::Length(j + 1));
            }
            out.links[j].length = num / den;
        }
        for j in (0..N).rev() {
            let carried: f64 = out.links[j + 1..].iter().map(|l| l.mass).sum();
            let link = &mut out.links[j];
            let first_moment = theta[Self::g_index(j)] / g - link.length * carried;
            let about_joint = theta[Self::a_index(j, j)] - link.length * link.length * carried;
            if about_joint.is_nan() || about_joint <= 0.0 {
                return Err(Unphysical::InertiaAboutJoint(j + 1));
            }
            // The lightest link with this first moment and inertia about
            // the joint, m = (m r)^2 / I_joint (no inertia about its COM):
            // every heavier choice of the carried masses can make an inner
            // link's inertia about its joint negative.
            if first_moment.abs() > 1e-12 * about_joint {
                link.mass = first_moment * first_moment / about_joint;
            }
            if !(link.mass > 0.0 && link.mass.is_finite()) {
                return Err(Unphysical::Mass(j + 1));
            }
            link.com = first_moment / link.mass;
            link.inertia = about_joint - link.mass * link.com * link.com;
            let joint = &mut out.joints[j];
            joint.rotor_inertia = theta[Self::rotor_index(j)];
            joint.viscous = theta[Self::viscous_index(j)];
            joint.coulomb = theta[Self::coulomb_index(j)];
            if joint.rotor_inertia < 0.0 || joint.viscous < 0.0 || joint.coulomb < 0.0 {
                return Err(Unphysical::Joint(j + 1));
            }
        }
        Ok(out)
    }
}

/// Each link's absolute angle and speed (the sums of the joints' up to it).
fn absolute_angles_and_speeds<const N: usize>(
    q: &Vector<N>,
    qd: &Vector<N>,
) -> (Vector<N>, Vector<N>) {
    let mut phi_abs = Vector::<N>::zeros();
    let mut w = Vector::<N>::zeros();
    let (mut a, mut b) = (0.0, 0.0);
    for j in 0..N {
        a += q[j];
        b += qd[j];
        phi_abs[j] = a;
        w[j] = b;
    }
    (phi_abs, w)
}

/// The energy features `phi_E(q, qd)`: `E = theta' phi_E` (friction entries 0).
pub fn energy_features<const N: usize, const NP: usize>(
    params: &PlanarChainParams<N>,
    q: &Vector<N>,
    qd: &Vector<N>,
) -> SVector<f64, NP> {
    type B<const N: usize, const NP: usize> = BaseParameters<N, NP>;
    let (phi_abs, w) = absolute_angles_and_speeds(q, qd);
    let mut f = SVector::<f64, NP>::zeros();
    for j in 0..N {
        f[B::<N, NP>::a_index(j, j)] = 0.5 * w[j] * w[j];
        for l in j + 1..N {
            f[B::<N, NP>::a_index(j, l)] = math::cos(phi_abs[j] - phi_abs[l]) * w[j] * w[l];
        }
        f[B::<N, NP>::g_index(j)] = 1.0 - math::cos(phi_abs[j]);
        let before: f64 = qd.iter().take(j).sum();
        let rotor = before - params.joints[j].gear_ratio * qd[j];
        f[B::<N, NP>::rotor_index(j)] = 0.5 * rotor * rotor;
    }
    f
}

/// The variance the sensors' noise gives the energy features at `(q, qd)`:
/// `J_q J_q' angle_noise^2 + J_qd J_qd' speed_noise^2`, with `J` the
/// features' derivatives ([`energy_features`]; white noise of these
/// standard deviations on every angle and speed, to first order). Only
/// the energy entries are non-zero.
pub fn energy_feature_noise<const N: usize, const NP: usize>(
    params: &PlanarChainParams<N>,
    q: &Vector<N>,
    qd: &Vector<N>,
    angle_noise: f64,
    speed_noise: f64,
) -> SMatrix<f64, NP, NP> {
    let (dq, dqd) = energy_feature_derivatives::<N, NP>(params, q, qd);
    let (a2, s2) = (angle_noise * angle_noise, speed_noise * speed_noise);
    let mut c = SMatrix::<f64, NP, NP>::zeros();
    let e = NP - 2 * N;
    // Sums by index over the energy block (views sized at run time would
    // allocate).
    for k in 0..N {
        for i in 0..e {
            let (gi, hi) = (dq[(i, k)] * a2, dqd[(i, k)] * s2);
            if gi == 0.0 && hi == 0.0 {
                continue;
            }
            for l in 0..e {
                c[(i, l)] += gi * dq[(l, k)] + hi * dqd[(l, k)];
            }
        }
    }
    c
}

/// The derivatives of the energy features ([`energy_features`]) with
/// respect to the angles and to the speeds (`NP x N` each).
pub fn energy_feature_derivatives<const N: usize, const NP: usize>(
    params: &PlanarChainParams<N>,
    q: &Vector<N>,
    qd: &Vector<N>,
) -> (SMatrix<f64, NP, N>, SMatrix<f64, NP, N>) {
    type B<const N: usize, const NP: usize> = BaseParameters<N, NP>;
    let (phi_abs, w) = absolute_angles_and_speeds(q, qd);
    let mut dq = SMatrix::<f64, NP, N>::zeros();
    let mut dqd = SMatrix::<f64, NP, N>::zeros();
    // The absolute angle and speed of link j depend on joints 0..=j.
    for j in 0..N {
        let jj = B::<N, NP>::a_index(j, j);
        for k in 0..=j {
            dqd[(jj, k)] = w[j];
        }
        for l in j + 1..N {
            let i = B::<N, NP>::a_index(j, l);
            let (s, c) = (
                math::sin(phi_abs[j] - phi_abs[l]),
                math::cos(phi_abs[j] - phi_abs[l]),
            );
            for k in 0..=l {
                let in_j = if k <= j { 1.0 } else { 0.0 };
                // d(phi_j - phi_l)/dq_k = [k <= j] - 1 (k <= l)
                dq[(i, k)] = -s * w[j] * w[l] * (in_j - 1.0);
                dqd[(i, k)] = c * (w[l] * in_j + w[j]);
            }
        }
        let g = B::<N, NP>::g_index(j);
        for k in 0..=j {
            dq[(g, k)] = math::sin(phi_abs[j]);
        }
        let before: f64 = qd.iter().take(j).sum();
        let gear = params.joints[j].gear_ratio;
        let rotor = before - gear * qd[j];
        let r = B::<N, NP>::rotor_index(j);
        for k in 0..j {
            dqd[(r, k)] = rotor;
        }
        dqd[(r, j)] = -gear * rotor;
    }
    (dq, dqd)
}

/// The dynamics' regressor `Y(q, qd, qdd)` (`N x NP`): `Y theta` is the
/// torque `M(q) qdd + C(q, qd) qd + dV/dq + tau_f(qd)` that the chain of
/// base parameters `theta` needs for the acceleration `qdd`. It is
/// Lagrange's equation applied to each energy feature
/// ([`energy_features`]): `d/dt (d phi/d qd) - d phi/d q` for a kinetic
/// one, `d phi/d q` for a potential one, and each friction feature's torque
/// (`qd_j`, `atan(k qd_j)`). Every feature's speed derivative is linear in
/// the speeds, so its rate along the motion is exact in closed form.
pub fn dynamic_regressor<const N: usize, const NP: usize>(
    params: &PlanarChainParams<N>,
    q: &Vector<N>,
    qd: &Vector<N>,
    qdd: &Vector<N>,
) -> SMatrix<f64, N, NP> {
    type B<const N: usize, const NP: usize> = BaseParameters<N, NP>;
    let (dq, _) = energy_feature_derivatives::<N, NP>(params, q, qd);
    let (phi_abs, w) = absolute_angles_and_speeds(q, qd);
    // Each link's absolute acceleration.
    let (_, wd) = absolute_angles_and_speeds(q, qdd);
    let mut y = SMatrix::<f64, N, NP>::zeros();
    for j in 0..N {
        // A_jj: d phi/d qd_k = w_j for k <= j, no angle dependence.
        let jj = B::<N, NP>::a_index(j, j);
        for k in 0..=j {
            y[(k, jj)] = wd[j];
        }
        for l in j + 1..N {
            let i = B::<N, NP>::a_index(j, l);
            let (s, c) = (
                math::sin(phi_abs[j] - phi_abs[l]),
                math::cos(phi_abs[j] - phi_abs[l]),
            );
            let relative = w[j] - w[l];
            for k in 0..=l {
                let in_j = if k <= j { 1.0 } else { 0.0 };
                // d/dt of d phi/d qd_k = c (w_l [k <= j] + w_j)
                let rate = -s * relative * (w[l] * in_j + w[j]) + c * (wd[l] * in_j + wd[j]);
                y[(k, i)] = rate - dq[(i, k)];
            }
        }
        let g = B::<N, NP>::g_index(j);
        for k in 0..=j {
            y[(k, g)] = dq[(g, k)];
        }
        // The rotor's speed (before - gear qd_j) has no angle dependence.
        let gear = params.joints[j].gear_ratio;
        let before: f64 = qdd.iter().take(j).sum();
        let rotor_rate = before - gear * qdd[j];
        let r = B::<N, NP>::rotor_index(j);
        for k in 0..j {
            y[(k, r)] = rotor_rate;
        }
        y[(j, r)] = -gear * rotor_rate;
        y[(j, B::<N, NP>::viscous_index(j))] = qd[j];
        y[(j, B::<N, NP>::coulomb_index(j))] = libm::atan(params.coulomb_sharpness * qd[j]);
    }
    y
}

/// The friction power features `phi_F(qd)`: friction power `= theta'
/// phi_F` (energy entries 0).
pub fn friction_features<const N: usize, const NP: usize>(
    params: &PlanarChainParams<N>,
    qd: &Vector<N>,
) -> SVector<f64, NP> {
    type B<const N: usize, const NP: usize> = BaseParameters<N, NP>;
    let mut f = SVector::<f64, NP>::zeros();
    for j in 0..N {
        f[B::<N, NP>::viscous_index(j)] = qd[j] * qd[j];
        f[B::<N, NP>::coulomb_index(j)] = qd[j] * libm::atan(params.coulomb_sharpness * qd[j]);
    }
    f
}

/// Degrees of freedom the fit's residual has at least before it weighs the
/// windows (its variance is then known within about +-50 %).
pub const RESIDUAL_DOF: usize = 8;

/// Settings of the energy-balance least squares.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RlsOptions {
    /// Forgetting factor per window, in (0, 1] (1: no forgetting).
    pub forgetting: f64,
    /// Prior standard deviation of each parameter, relative to its prior
    /// value (absolute for a zero prior: `prior_floor`).
    pub prior_relative: f64,
    /// Prior standard deviation of a parameter whose prior is 0.
    pub prior_floor: f64,
    /// Under sensor noise, the tightest prior standard deviation of each
    /// link inertia amplitude `A_jl`, relative to its prior value: a rough
    /// model's inertias are off by 10-20 %. The prior narrows to it as the
    /// noise grows (see `EnergyBalanceRls`'s prior information); with
    /// `prior_relative` and `prior_floor` alone (0.05 kg m^2 for the lab
    /// pendulum A0's `A_22` of 0.024), noise pushed `A_22` below zero.
    #[serde(default = "default_inertia_relative")]
    pub inertia_relative: f64,
    /// Under sensor noise, the tightest prior standard deviation of each
    /// rotor inertia, relative to its prior value (a zero prior, no motor
    /// data, keeps `prior_floor`): the data sheet's number. The rotor's
    /// energy moves nearly with the link's along an orbit, so the two trade
    /// against each other as the `A_jl` do (with `prior_floor` alone, 650
    /// times A0's rotor inertia, noise moved link 2's inertia into its
    /// rotor).
    #[serde(default = "default_rotor_relative")]
    pub rotor_relative: f64,
    /// Standard deviation of the sensors' white noise on the angles (rad)
    /// and on the speeds (rad/s), as the state estimator is told it; 0:
    /// not known. Known noise is taken out of the windows' normal
    /// equations (bias-compensated least squares, sized by the noise the
    /// balance measures: [`EnergyBalanceRls::noise_share`]): noise in the
    /// ends of a window (the regressors) otherwise shrinks the estimate,
    /// the energy scale most (errors in the variables).
    #[serde(default)]
    pub angle_noise: f64,
    /// See [`RlsOptions::angle_noise`].
    #[serde(default)]
    pub speed_noise: f64,
    /// Share of the sensors' noise covariance taken out, in `[0, 1]`
    /// ([`EnergyBalanceRls::noise_share`]). 1 is exact where the noise
    /// does not reach the torque. In closed loop the controller answers
    /// the noise, which correlates it with the motion and offsets part of
    /// the shrinking; measured on the lab pendulum A0 (its exact
    /// controller at 1 J, `examples/identify_noise`, 4 seeds) at 0.005 rad
    /// / 0.05 rad/s: none -0.7 %, half +0.25 %, all +1.2 %; at twice the
    /// noise -1.1 %, +1.7 %, +4.6 %. The robustness report's rough model +
    /// noise (A0 at 2 J and B0 at 1.5 J, adaptation, 120 s; runs within 2 %
    /// of 21 each): none 14 and 9, half 19 and 8, all 20 and 8; the stalling
    /// rough model of A0 under noise (`tests/python`) ended -1.5 %, -0.02 %
    /// and -2.2 %.
    #[serde(default = "default_noise_compensation")]
    pub noise_compensation: f64,
    /// Samples per window.
    pub window: usize,
    /// Most samples averaged at each end of a window (`1..=window`): the
    /// balance holds at every sample, so averaging its ends is exact for
    /// the model and divides the measurement noise of the ends by this.
    /// Each end's length is chosen from the measured noise, between
    /// `min_end_samples` and this ([`EnergyBalanceRls::end_samples`]).
    pub end_samples: usize,
    /// Fewest samples averaged at each end (`1..=end_samples`): the length
    /// for quiet sensors. Short ends keep the motion's detail (the ratios
    /// of the parameters); long ends average the noise that would
    /// otherwise shrink the energy scale (errors in the variables).
    pub min_end_samples: usize,
    /// White noise of the energy balance per sample, relative to the RMS
    /// energy of the motion, at which `min_end_samples` still suffice; an
    /// end is `min_end_samples (noise / quiet_noise)^2` long (the scale's
    /// shrinking goes with the ends' noise variance).
    pub quiet_noise: f64,
    /// Smallest standard deviation of one window's equation error (J): the
    /// integration error of the work and friction integrals. The error the
    /// measurements add is estimated online ([`EnergyBalanceRls::noise`]).
    pub equation_noise: f64,
    /// A window whose information `h' P h / R` (`R` its error variance) is
    /// below this is skipped (not exciting).
    pub min_information: f64,
    /// Samples over which the measurement noise estimate averages.
    pub noise_memory: usize,
    /// Effective windows (forgotten) after which the window variance is
    /// the residual of their fit; at least the number of base parameters
    /// plus [`RESIDUAL_DOF`] (the fit's residual needs degrees of freedom:
    /// a chain of 4-6 joints waits longer than the default).
    pub residual_windows: usize,
}

fn default_inertia_relative() -> f64 {
    0.3
}

fn default_rotor_relative() -> f64 {
    0.2
}

fn default_noise_compensation() -> f64 {
    0.5
}

impl Default for RlsOptions {
    fn default() -> Self {
        Self {
            forgetting: 0.999,
            prior_relative: 0.5,
            prior_floor: 0.05,
            inertia_relative: default_inertia_relative(),
            rotor_relative: default_rotor_relative(),
            angle_noise: 0.0,
            speed_noise: 0.0,
            noise_compensation: default_noise_compensation(),
            window: 40,
            end_samples: 40,
            min_end_samples: 5,
            quiet_noise: 1e-3,
            equation_noise: 2e-4,
            min_information: 1e-4,
            noise_memory: 1200,
            residual_windows: 24,
        }
    }
}

impl RlsOptions {
    /// Checks the settings; the message names the offending one.
    pub fn validate(&self) -> Result<(), IdentifyError> {
        let bad = |what: String| Err(IdentifyError::NotPhysical(what));
        if !(self.forgetting > 0.0 && self.forgetting <= 1.0) {
            return bad(format!(
                "forgetting = {} must be in (0, 1]",
                self.forgetting
            ));
        }
        for (name, v) in [
            ("prior_relative", self.prior_relative),
            ("prior_floor", self.prior_floor),
            ("inertia_relative", self.inertia_relative),
            ("rotor_relative", self.rotor_relative),
            ("equation_noise", self.equation_noise),
            ("quiet_noise", self.quiet_noise),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{name} = {v} must be finite and > 0"));
            }
        }
        for (name, v) in [
            ("angle_noise", self.angle_noise),
            ("speed_noise", self.speed_noise),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{name} = {v} must be finite and >= 0"));
            }
        }
        if !(0.0..=1.0).contains(&self.noise_compensation) {
            return bad(format!(
                "noise_compensation = {} must be in [0, 1]",
                self.noise_compensation
            ));
        }
        if !(self.min_information.is_finite() && self.min_information >= 0.0) {
            return bad(format!(
                "min_information = {} must be finite and >= 0",
                self.min_information
            ));
        }
        if self.min_end_samples == 0
            || self.min_end_samples > self.end_samples
            || self.end_samples > self.window
        {
            return bad(format!(
                "window = {}, end_samples = {} and min_end_samples = {} must satisfy \
                 1 <= min_end_samples <= end_samples <= window",
                self.window, self.end_samples, self.min_end_samples
            ));
        }
        if self.noise_memory == 0 {
            return bad("noise_memory must be >= 1".into());
        }
        Ok(())
    }
}

/// One window's energy balance `h' theta = y`, with the variance `R` of
/// its error (J^2) as the measurements make it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WindowEquation<const NP: usize> {
    /// Change of the energy features plus the friction integrals.
    pub h: SVector<f64, NP>,
    /// Work of the applied torque (J).
    pub y: f64,
    /// Variance of the equation error (J^2).
    pub variance: f64,
    /// Whether it updated the estimate (else: not exciting enough, or not
    /// finite).
    pub used: bool,
}

impl<const NP: usize> WindowEquation<NP> {
    /// The squared error of `theta` on this window in units of its
    /// variance.
    pub fn normalised_error(&self, theta: &SVector<f64, NP>) -> f64 {
        (self.y - self.h.dot(theta)).powi(2) / self.variance
    }
}

/// Online estimate of the measurement noise in the energy balance, from
/// the second and third differences of the balance's running residual
/// `r_k = theta' Phi_k - W_k` (constant for the true parameters): white
/// noise of the measured state gives `r` white noise (variance `level`),
/// noise of the applied torque a random walk (`walk` per sample). The
/// smooth motion hardly enters differences of this order at the sample
/// rate.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
struct NoiseEstimate {
    /// The last two residual increments.
    increments: [f64; 2],
    /// Increments seen since the last gap (up to 3 matter).
    seen: usize,
    /// Running means of the squared second and third differences of `r`.
    second: f64,
    third: f64,
    /// Samples in the running means (up to the memory).
    count: usize,
}

impl NoiseEstimate {
    fn new() -> Self {
        Self {
            increments: [0.0; 2],
            seen: 0,
            second: 0.0,
            third: 0.0,
            count: 0,
        }
    }

    fn gap(&mut self) {
        self.seen = 0;
    }

    fn add(&mut self, increment: f64, memory: usize) {
        if !increment.is_finite() {
            self.seen = 0;
            return;
        }
        let [d1, d2] = self.increments;
        self.increments = [increment, d1];
        self.seen += 1;
        if self.seen < 3 {
            return;
        }
        let second = increment - d1;
        let third = increment - 2.0 * d1 + d2;
        self.count = (self.count + 1).min(memory);
        let w = 1.0 / self.count as f64;
        self.second += w * (second * second - self.second);
        self.third += w * (third * third - self.third);
    }

    /// `(level, walk)`: the variance of the white noise on `r` and of the
    /// random walk's steps. Second differences: `6 level + 2 walk`, third:
    /// `20 level + 6 walk`.
    fn variances(&self) -> (f64, f64) {
        if self.count < 10 {
            return (0.0, 0.0);
        }
        let level = ((self.third - 3.0 * self.second) / 2.0).max(0.0);
        let walk = ((self.second - 6.0 * level) / 2.0).max(0.0);
        (level, walk)
    }
}

/// The white noise of the energy balance under the *prior's* parameters,
/// from the fourth differences of its running residual `r` (variance
/// `70 level + 20 walk` for white noise and a random walk, counted as
/// white), and the motion's RMS energy under them. Fixed parameters keep
/// `r` smooth (the estimate's steps at each window would show as noise),
/// and a smooth motion enters fourth differences `(omega dt)^4` weaker than
/// itself (2e-4 for the lab pendulum A0 at 25 ms), so a wrong prior hardly
/// does. Sizes the windows' ends ([`EnergyBalanceRls::end_samples`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
struct SensorNoise {
    /// The last three increments of `r`.
    increments: [f64; 3],
    /// Increments seen since the last gap (4 are needed).
    seen: usize,
    /// Running mean of the squared fourth differences, and its count.
    fourth: f64,
    count: usize,
    /// Running mean of the squared energy (J^2), and its count.
    energy_square: f64,
    energy_count: usize,
    /// Running mean of the white noise's variance per sample the declared
    /// sensor noise predicts (J^2, [`RlsOptions::angle_noise`]).
    predicted: f64,
}

impl SensorNoise {
    fn new() -> Self {
        Self {
            increments: [0.0; 3],
            seen: 0,
            fourth: 0.0,
            count: 0,
            energy_square: 0.0,
            energy_count: 0,
            predicted: 0.0,
        }
    }

    fn gap(&mut self) {
        self.seen = 0;
    }

    /// One sample's energy, the white noise's variance the declared noise
    /// predicts for it, and the increment of `r` since the last.
    fn add(&mut self, energy: f64, predicted: f64, increment: Option<f64>, memory: usize) {
        if energy.is_finite() && predicted.is_finite() {
            self.energy_count = (self.energy_count + 1).min(memory);
            let n = self.energy_count as f64;
            self.energy_square += (energy * energy - self.energy_square) / n;
            self.predicted += (predicted - self.predicted) / n;
        }
        let Some(increment) = increment.filter(|d| d.is_finite()) else {
            self.seen = 0;
            return;
        };
        let [d1, d2, d3] = self.increments;
        self.increments = [increment, d1, d2];
        self.seen += 1;
        if self.seen < 4 {
            return;
        }
        let fourth = increment - 3.0 * d1 + 3.0 * d2 - d3;
        self.count = (self.count + 1).min(memory);
        self.fourth += (fourth * fourth - self.fourth) / self.count as f64;
    }

    /// The white noise's standard deviation per sample relative to the
    /// RMS energy; `None` until 10 fourth differences.
    fn relative(&self) -> Option<f64> {
        let energy = self.energy_square.sqrt();
        (self.count >= 10 && energy > 0.0).then(|| (self.fourth / 70.0).sqrt() / energy)
    }

    /// The measured white noise's variance over the one the declared noise
    /// predicts, at most 1 (0 until measured or without a prediction).
    fn declared_share(&self) -> f64 {
        if self.count < 10 || self.predicted.is_nan() || self.predicted <= 0.0 {
            return 0.0;
        }
        (self.fourth / 70.0 / self.predicted).min(1.0)
    }
}

/// Standard deviations of a window's predicted error beyond which it is
/// down-weighted (Huber's k).
const HUBER: f64 = 3.0;

/// Energy-balance identification by least squares, fed one sample at a
/// time (the state `q`, `qd` and the torque applied over the previous
/// sample); fixed size, no allocation (an `NP x NP` Cholesky per window).
///
/// The windows' equations are kept as forgotten sums, and the estimate is
/// solved from them and the prior with the window variance their own
/// residual shows ([`EnergyBalanceRls::window_variance`]): noisy sensors
/// make the estimate move slowly instead of chasing the noise, and the
/// information of the climb (the only work that gives the energy scale) is
/// weighted by what is known now, not held back by what a wrong early
/// estimate made the noise look like. The estimate is the unconstrained
/// least-squares one; a model is made of it only through
/// [`BaseParameters::physical`]. (The name is kept from the recursive
/// form this replaced.)
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct EnergyBalanceRls<const N: usize, const NP: usize> {
    prior: PlanarChainParams<N>,
    options: RlsOptions,
    estimate: SVector<f64, NP>,
    covariance: SMatrix<f64, NP, NP>,
    /// The prior's base parameters and information (inverse variances):
    /// never forgotten, so they bound the covariance.
    prior_theta: SVector<f64, NP>,
    prior_information: SVector<f64, NP>,
    /// Forgotten sums of the windows' equations `h' theta = y`: `sum h h'`,
    /// `sum h y`, `sum y^2` and the effective count of windows. The
    /// estimate is solved from them with the variance they show, so every
    /// window, the climb's too, is weighted by what the residual of all
    /// windows says, not by what was known when it closed.
    normal: SMatrix<f64, NP, NP>,
    rhs: SVector<f64, NP>,
    sum_y2: f64,
    count: f64,
    /// Forgotten sum of the windows' regressor noise covariances (known
    /// sensor noise, [`RlsOptions::angle_noise`]), taken out of `normal`.
    noise_normal: SMatrix<f64, NP, NP>,
    /// Sum over the current end block of the features' noise covariance,
    /// and the anchor block's mean's.
    block_noise: SMatrix<f64, NP, NP>,
    anchor_noise: SMatrix<f64, NP, NP>,
    /// Variance of one window's equation error (J^2) last solved with.
    variance: f64,
    /// Running energy-balance sums since the anchor: features plus friction
    /// integrals, and work.
    features: SVector<f64, NP>,
    work: f64,
    /// Sums over the current end block of the window.
    block_features: SVector<f64, NP>,
    block_work: f64,
    /// The previous block's average, relative to the anchor (None: the
    /// first block after a gap is still open).
    anchor: Option<(SVector<f64, NP>, f64)>,
    /// Samples since the last gap.
    position: usize,
    /// The position at which the open end block closes, and its length.
    block_end: usize,
    block_len: usize,
    /// The previous block's length (the next window's start).
    anchor_len: usize,
    /// `1 / start length + 1 / end length` of the last window closed: the
    /// share of the sample-level white noise its ends keep.
    ends_weight: f64,
    /// The sensors' noise relative to the motion's energy.
    sensor_noise: SensorNoise,
    /// The previous sample: state, and its energy features.
    last: Option<(Vector<N>, Vector<N>, SVector<f64, NP>)>,
    noise: NoiseEstimate,
    updates: usize,
    skipped: usize,
}

impl<const N: usize, const NP: usize> EnergyBalanceRls<N, NP> {
    /// Starts at the prior chain's base parameters.
    pub fn new(prior: &PlanarChainParams<N>, options: RlsOptions) -> Result<Self, IdentifyError> {
        options.validate()?;
        let theta = BaseParameters::<N, NP>::of(prior)?.theta;
        let variance = theta.map(|v| {
            (options.prior_relative * v.abs())
                .max(options.prior_floor)
                .powi(2)
        });
        Ok(Self {
            prior: *prior,
            options,
            estimate: theta,
            covariance: SMatrix::from_diagonal(&variance),
            prior_theta: theta,
            prior_information: variance.map(|v| 1.0 / v),
            normal: SMatrix::zeros(),
            rhs: SVector::zeros(),
            sum_y2: 0.0,
            count: 0.0,
            noise_normal: SMatrix::zeros(),
            block_noise: SMatrix::zeros(),
            anchor_noise: SMatrix::zeros(),
            variance: options.equation_noise.powi(2),
            features: SVector::zeros(),
            work: 0.0,
            block_features: SVector::zeros(),
            block_work: 0.0,
            anchor: None,
            position: 0,
            block_end: options.min_end_samples - 1,
            block_len: options.min_end_samples,
            anchor_len: options.min_end_samples,
            ends_weight: 2.0 / options.min_end_samples as f64,
            sensor_noise: SensorNoise::new(),
            last: None,
            noise: NoiseEstimate::new(),
            updates: 0,
            skipped: 0,
        })
    }

    /// The current estimate (unconstrained: see
    /// [`BaseParameters::physical`]).
    pub fn estimate(&self) -> BaseParameters<N, NP> {
        BaseParameters {
            theta: self.estimate,
        }
    }

    /// The estimate's covariance (base parameters squared).
    pub fn covariance(&self) -> &SMatrix<f64, NP, NP> {
        &self.covariance
    }

    /// The settings.
    pub fn options(&self) -> &RlsOptions {
        &self.options
    }

    /// Relative standard deviation of the estimate's scale: of `s` in
    /// `theta_E = s theta_E,estimate` over the inertia and gravity
    /// amplitudes and rotor inertias. Free motion gives their ratios; only
    /// work done on the robot gives this.
    pub fn scale_uncertainty(&self) -> f64 {
        let energy = NP - 2 * N;
        let mut num = 0.0;
        let mut den = 0.0;
        for i in 0..energy {
            for k in 0..energy {
                num += self.estimate[i] * self.covariance[(i, k)] * self.estimate[k];
            }
            den += self.estimate[i] * self.estimate[i];
        }
        if den > 0.0 {
            num.max(0.0).sqrt() / den
        } else {
            f64::INFINITY
        }
    }

    /// Standard deviations of the measurement noise in the energy balance
    /// at the sample level: the white part (J) and the random walk's
    /// per-sample step (J, e.g. noise of the applied torque). Read off the
    /// differences of the running residual under the current estimate, so
    /// an upper bound: the estimate's error enters them too. Used for the
    /// window variance only until enough windows have closed.
    pub fn noise(&self) -> (f64, f64) {
        let (level, walk) = self.noise.variances();
        (level.sqrt(), walk.sqrt())
    }

    /// Variance of one window's equation error (J^2). Once enough windows
    /// have closed ([`RlsOptions::residual_windows`]), the residual of
    /// their least-squares fit: it holds every error source (sensor and
    /// torque noise, integration, an imperfect friction law) and no
    /// parameter error, which the fit absorbs. Before, the integration
    /// floor plus what the sample-level noise estimate gives a window
    /// ([`EnergyBalanceRls::noise`]), an upper bound: a wrong estimate
    /// leaks into those differences when the motion is fast against the
    /// sample rate (measured on the lab pendulum A0: 30-150 times the
    /// residual of the true parameters).
    pub fn window_variance(&self) -> f64 {
        if self.count >= self.residual_windows() {
            return self.variance;
        }
        self.sample_level_variance()
    }

    fn sample_level_variance(&self) -> f64 {
        let (level, walk) = self.noise.variances();
        let o = &self.options;
        o.equation_noise.powi(2) + level * self.ends_weight + walk * o.window as f64
    }

    /// Samples the next end block averages: `min_end_samples` while the
    /// balance's white noise per sample (read off the fourth differences of
    /// its running residual under the prior's parameters,
    /// [`EnergyBalanceRls::relative_noise`]) is at most `quiet_noise` of
    /// the motion's RMS energy, growing with the noise's variance up to
    /// `end_samples`.
    /// Measured (120 s closed loops of the lab pendulum A0 at 1-2 J): ends of 5
    /// let sensor noise of 0.005 rad / 0.05 rad/s shrink the identified
    /// energy along the orbit by 34 %, ends of 40 by 1.5 %; but on exact
    /// sensors ends of 40 blur the orbit's exchange of kinetic and
    /// potential energy that gives the parameters' ratios (a centre of
    /// mass 25 % off was no longer identified, ends of 10 already lost
    /// one case in six).
    pub fn end_samples(&self) -> usize {
        let o = &self.options;
        let Some(ratio) = self.measured_noise_ratio() else {
            return o.end_samples;
        };
        let wanted = o.min_end_samples as f64 * ratio * ratio;
        if wanted >= o.end_samples as f64 {
            o.end_samples
        } else {
            (wanted.ceil() as usize).clamp(o.min_end_samples, o.end_samples)
        }
    }

    /// The balance's white noise per sample relative to the motion's RMS
    /// energy (see [`EnergyBalanceRls::end_samples`]); `None` until
    /// measured.
    pub fn relative_noise(&self) -> Option<f64> {
        self.sensor_noise.relative()
    }

    /// The balance's white noise against quiet sensors' (`relative_noise /
    /// quiet_noise`); `None` until measured.
    fn measured_noise_ratio(&self) -> Option<f64> {
        self.relative_noise()
            .filter(|r| r.is_finite())
            .map(|r| r / self.options.quiet_noise)
    }

    /// The share of the declared sensor noise's covariance
    /// ([`RlsOptions::angle_noise`]) taken out of the normal equations:
    /// none on quiet sensors (the balance's measured white noise at most
    /// `quiet_noise`: exactly the plain least squares there), else the
    /// white noise's variance measured in the balance over the one the
    /// declaration predicts, at most 1, times
    /// [`RlsOptions::noise_compensation`]. The declaration gives the noise's
    /// shape (which features it enters, angles against speeds), the
    /// measurement its size: a filter told ten times the sensors' noise
    /// (the FMU's default is 0.05 rad) gives the same correction.
    ///
    /// Measured (`tests/identify.rs`, the lab pendulum A0 on its mode,
    /// noise that does not reach the torque, 4 seeds, all of it taken
    /// out): the energy scale's shrinking -1.9 % -> -0.1 % at 0.005 rad /
    /// 0.05 rad/s, -5.7 % -> -0.3 % at twice that. In closed loop see
    /// [`RlsOptions::noise_compensation`].
    pub fn noise_share(&self) -> f64 {
        if !self.compensates() || self.measured_noise_ratio().is_none_or(|r| r <= 1.0) {
            return 0.0;
        }
        self.sensor_noise.declared_share() * self.options.noise_compensation
    }

    /// [`Self::measured_noise_ratio`], at least 1 (1 until measured).
    fn noise_ratio(&self) -> f64 {
        self.measured_noise_ratio().map_or(1.0, |r| r.max(1.0))
    }

    /// The prior's information on parameter `i` (1 / its variance) when the
    /// balance's noise is `ratio` times quiet ([`Self::noise_ratio`]).
    ///
    /// On quiet sensors it is the prior as built. Under noise the
    /// directions an orbit hardly excites are left to the prior, not to the
    /// noise (errors in the variables bias them, and the energy scale with
    /// them): the prior's standard deviation of each viscous coefficient is
    /// divided by `ratio`; that of each link inertia amplitude `A_jl` and
    /// each rotor inertia goes geometrically (weight `1 / ratio` on the
    /// quiet one) towards [`RlsOptions::inertia_relative`] and
    /// [`RlsOptions::rotor_relative`] of its value.
    ///
    /// Along an orbit viscous and Coulomb friction take nearly the same
    /// energy per period, and the joints move nearly in proportion, so
    /// which friction and which combination of the `A_jl` it is are the
    /// orbit's weakest directions. Speed noise of variance `s^2` adds `s^2`
    /// to the viscous feature `qd^2` and hardly changes the Coulomb one at
    /// orbit speeds. Measured on the lab pendulum A0 with 0.005 rad / 0.05
    /// rad/s (`ratio` 17-19): the identified energy scale's bias went from
    /// -1.6 % to -0.7 % (`examples/identify_noise`), and the robustness
    /// report's "rough model + noise" at 2 J from 0.43 to 0.52 in 60 s. With
    /// the viscous prior alone a rough model's `A_22` went below zero under
    /// noise: every candidate was unphysical, and the run ended 47 % low.
    /// On quiet sensors the looser prior stays: a viscous plant's friction
    /// and a 2.5 % heavier link are found (with the rotor prior narrowed
    /// there too, the latter was no longer told apart from the model in
    /// 60 s).
    fn prior_information(&self, i: usize, ratio: f64) -> f64 {
        let information = self.prior_information[i];
        if ratio <= 1.0 {
            return information;
        }
        let quiet = information.recip().sqrt();
        type B<const N: usize, const NP: usize> = BaseParameters<N, NP>;
        // The blocks of the base parameters: A_jl, G_j, Ir_j, b_j, cf_j.
        let relative = if i < B::<N, NP>::g_index(0) {
            self.options.inertia_relative
        } else if (B::<N, NP>::rotor_index(0)..B::<N, NP>::viscous_index(0)).contains(&i) {
            self.options.rotor_relative
        } else if (B::<N, NP>::viscous_index(0)..B::<N, NP>::coulomb_index(0)).contains(&i) {
            0.0
        } else {
            return information;
        };
        let sd = if relative == 0.0 {
            quiet / ratio
        } else {
            // Geometrically from the quiet prior (ratio 1) to the tight one.
            let tight = (relative * self.prior_theta[i].abs()).min(quiet);
            if tight == 0.0 {
                return information;
            }
            // (libm's pow: the same bits on every platform.)
            math::powf(quiet, ratio.recip()) * math::powf(tight, 1.0 - ratio.recip())
        };
        sd.powi(-2)
    }

    /// The estimate and covariance from the sums and the prior for a window
    /// variance `variance`; `None` when the system is not positive definite.
    fn solve(&self, variance: f64) -> Option<(SVector<f64, NP>, SMatrix<f64, NP, NP>)> {
        let mut system = self.normal;
        let share = self.noise_share();
        if share > 0.0 {
            system -= self.noise_normal * share;
        }
        let mut rhs = self.rhs;
        let ratio = self.noise_ratio();
        for i in 0..NP {
            let w = variance * self.prior_information(i, ratio);
            system[(i, i)] += w;
            rhs[i] += w * self.prior_theta[i];
        }
        let cholesky = system.cholesky()?;
        let estimate = cholesky.solve(&rhs);
        let covariance = cholesky.inverse() * variance;
        Some((estimate, (covariance + covariance.transpose()) * 0.5))
    }

    /// Residual variance of the windows under `theta` (J^2 per window).
    fn residual_variance(&self, theta: &SVector<f64, NP>) -> f64 {
        let rss = self.sum_y2 - 2.0 * theta.dot(&self.rhs) + theta.dot(&(self.normal * theta));
        rss.max(0.0) / (self.count - NP as f64).max(1.0)
    }

    /// Whether `saved` (a saved state) belongs to an identification with
    /// this prior and these options, with a finite estimate.
    pub fn check_compatible(&self, saved: &Self) -> Result<(), IdentifyError> {
        if saved.prior != self.prior || saved.options != self.options {
            return Err(IdentifyError::NotPhysical(
                "the saved identification has another prior or other options".into(),
            ));
        }
        if !(saved.estimate.iter().all(|v| v.is_finite())
            && saved.covariance.iter().all(|v| v.is_finite()))
        {
            return Err(IdentifyError::NotPhysical(
                "the saved identification is not finite".into(),
            ));
        }
        Ok(())
    }

    /// Drops the open window (a gap in the measurements, a restart): the
    /// next sample starts a new one. The estimate is kept.
    pub fn restart_window(&mut self) {
        self.last = None;
    }

    /// Effective windows after which the window variance is the fit's
    /// residual ([`RlsOptions::residual_windows`], at least the base
    /// parameters + [`RESIDUAL_DOF`]).
    fn residual_windows(&self) -> f64 {
        self.options.residual_windows.max(NP + RESIDUAL_DOF) as f64
    }

    /// Windows that updated the estimate so far.
    pub fn updates(&self) -> usize {
        self.updates
    }

    /// Windows skipped so far (too little information, or not finite).
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// One sample: the state `(q, qd)` now and the torque `tau` applied
    /// since the previous sample, `dt` seconds ago. Returns the window's
    /// equation when one closed (updating the estimate when it carries
    /// information).
    pub fn add_sample(
        &mut self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
        dt: f64,
    ) -> Option<WindowEquation<NP>> {
        if !(q.iter().chain(qd).chain(tau).all(|v| v.is_finite()) && dt > 0.0) {
            // A gap: start a new window at the next good sample.
            self.last = None;
            return None;
        }
        let phi = energy_features::<N, NP>(&self.prior, q, qd);
        let noise = self.feature_noise(q, qd);
        let Some((q_prev, qd_prev, phi_prev)) = self.last else {
            self.last = Some((*q, *qd, phi));
            self.features.fill(0.0);
            self.work = 0.0;
            self.block_features.fill(0.0);
            self.block_work = 0.0;
            self.block_noise.fill(0.0);
            self.anchor = None;
            self.position = 0;
            self.block_len = self.end_samples();
            self.block_end = self.block_len - 1;
            self.noise.gap();
            self.sensor_noise.gap();
            return self.close_block_if_due(&noise);
        };
        // The torque is held over the sample: its work is exactly
        // tau' (q - q_prev); the friction power by the trapezoid rule.
        let fp = friction_features::<N, NP>(&self.prior, &qd_prev);
        let fc = friction_features::<N, NP>(&self.prior, qd);
        let d_features = phi - phi_prev + (fp + fc) * (0.5 * dt);
        let d_work = tau.dot(&(q - q_prev));
        self.features += d_features;
        self.work += d_work;
        self.noise.add(
            self.estimate.dot(&d_features) - d_work,
            self.options.noise_memory,
        );
        let energy: f64 = (0..NP - 2 * N).map(|i| self.prior_theta[i] * phi[i]).sum();
        self.sensor_noise.add(
            energy,
            self.prior_theta.dot(&(noise * self.prior_theta)),
            Some(self.prior_theta.dot(&d_features) - d_work),
            self.options.noise_memory,
        );
        self.last = Some((*q, *qd, phi));
        self.position += 1;
        self.close_block_if_due(&noise)
    }

    /// Whether the sensors' noise is known ([`RlsOptions::angle_noise`]).
    fn compensates(&self) -> bool {
        self.options.angle_noise > 0.0 || self.options.speed_noise > 0.0
    }

    /// The features' noise covariance at this sample (zero when the noise
    /// is not known).
    fn feature_noise(&self, q: &Vector<N>, qd: &Vector<N>) -> SMatrix<f64, NP, NP> {
        if !self.compensates() {
            return SMatrix::zeros();
        }
        energy_feature_noise::<N, NP>(
            &self.prior,
            q,
            qd,
            self.options.angle_noise,
            self.options.speed_noise,
        )
    }

    /// Adds the sample to the end block when it is in one; at a block's
    /// end, closes the window it ends (if any) and makes it the anchor.
    fn close_block_if_due(&mut self, noise: &SMatrix<f64, NP, NP>) -> Option<WindowEquation<NP>> {
        // Blocks end `window` samples apart and hold the `block_len`
        // samples up to their end (chosen when the block before closed:
        // the balance is exact for any ends).
        let m = self.block_len;
        if self.position + m <= self.block_end {
            return None;
        }
        self.block_features += self.features;
        self.block_work += self.work;
        self.block_noise += noise;
        if self.position < self.block_end {
            return None;
        }
        let average = (self.block_features / m as f64, self.block_work / m as f64);
        // The mean of m samples' independent noise.
        let end_noise = self.block_noise / (m * m) as f64;
        self.block_features.fill(0.0);
        self.block_work = 0.0;
        self.block_noise.fill(0.0);
        let start_noise = std::mem::replace(&mut self.anchor_noise, end_noise);
        // The variance for this window's ends, before the next block is
        // sized.
        self.ends_weight = 1.0 / self.anchor_len as f64 + 1.0 / m as f64;
        let variance = self.window_variance();
        self.anchor_len = m;
        self.block_end += self.options.window;
        self.block_len = self.end_samples();
        // Rebase the running sums on this block (small numbers forever).
        self.features -= average.0;
        self.work -= average.1;
        let anchor = self.anchor.replace((SVector::zeros(), 0.0));
        let (start_features, start_work) = anchor?;
        let h = average.0 - start_features;
        let y = average.1 - start_work;
        let used = self.update(&h, y, variance, &(end_noise + start_noise));
        Some(WindowEquation {
            h,
            y,
            variance,
            used,
        })
    }

    fn update(
        &mut self,
        h: &SVector<f64, NP>,
        y: f64,
        variance: f64,
        noise: &SMatrix<f64, NP, NP>,
    ) -> bool {
        let lambda = self.options.forgetting;
        let information = h.dot(&(self.covariance * h)) / variance;
        if !(information.is_finite() && y.is_finite()) || information < self.options.min_information
        {
            self.skipped += 1;
            return false;
        }
        // A window the estimate cannot explain by 3 standard deviations of
        // its prediction (an external push, a knock: not the robot) gets
        // Huber's weight, once the variance is the windows' own; before,
        // the prediction's spread is the prior's and nothing is an outlier.
        let weight = if self.count >= self.residual_windows() {
            let spread = (variance + h.dot(&(self.covariance * h))).sqrt();
            let error = (y - h.dot(&self.estimate)).abs();
            if error > HUBER * spread {
                HUBER * spread / error
            } else {
                1.0
            }
        } else {
            1.0
        };
        self.normal = self.normal * lambda + h * h.transpose() * weight;
        self.noise_normal = self.noise_normal * lambda + noise * weight;
        self.rhs = self.rhs * lambda + h * (y * weight);
        self.sum_y2 = self.sum_y2 * lambda + y * y * weight;
        self.count = self.count * lambda + weight;
        // The variance and the estimate depend on each other: a few fixed-
        // point steps from the last variance (the prior's pull is small
        // against the windows', so they settle at once).
        let floor = self.options.equation_noise.powi(2);
        let residual = self.count >= self.residual_windows();
        let mut v = if residual {
            self.variance.max(floor)
        } else {
            self.sample_level_variance()
        };
        for _ in 0..3 {
            let Some((estimate, covariance)) = self.solve(v) else {
                self.skipped += 1;
                return false;
            };
            self.estimate = estimate;
            self.covariance = covariance;
            if !residual {
                break;
            }
            let next = self.residual_variance(&estimate).max(floor);
            let settled = (next - v).abs() <= 1e-3 * v;
            v = next;
            if settled {
                break;
            }
        }
        self.variance = v;
        self.updates += 1;
        true
    }
}
