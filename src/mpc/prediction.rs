//! The controller's prediction model of a robot with Coulomb friction.
//!
//! The smooth Coulomb law `cf atan(k qd)` is stiff near zero speed: its
//! slope there, `cf k`, damps a joint with the rate `lambda = k cf / M`
//! (the largest eigenvalue of `M^-1 diag(cf) k`). With the shared robots'
//! `k = 100` that is ~800 1/s, and one RK4 step of 25 ms (`h lambda` ~ 20)
//! is unstable (RK4's limit on the negative real axis is 2.79).
//!
//! The prediction model keeps the plant's law and takes RK4 substeps
//! ([`prediction_substeps`]) until `h lambda <= PREDICTION_FRICTION_STEP_LIMIT`,
//! with a joint at rest; an interval in which every joint stays fast, where
//! the law is flat, takes fewer
//! ([`super::MpcConfig::substeps_where_stiff`]).
//! Measured on the A0 robot (`robots/`): lowering the slope instead (to
//! `k` ~ 5 for one 25 ms step) makes the model underestimate friction at
//! moderate speeds (`atan(5) = 0.87 pi/2`), the energy settles 1-2 % low
//! and at 1 J the pendulum never starts; the exact law with substeps holds
//! the energy to 0.1 % at 4x the per-sample time (0.15 -> 0.55 ms). Only
//! when the substeps would exceed [`MAX_PREDICTION_SUBSTEPS`] is the slope
//! lowered ([`prediction_coulomb_sharpness`]).

use crate::mechanics::{Matrix, MechanicalSystem, PlanarChain, Vector};

/// `h lambda` allowed for the stiffest friction mode in one RK4 step (just
/// inside RK4's stability limit 2.79: the decay is predicted, not resolved).
pub const PREDICTION_FRICTION_STEP_LIMIT: f64 = 2.5;

/// Most RK4 substeps per shooting interval chosen for friction.
pub const MAX_PREDICTION_SUBSTEPS: usize = 20;

/// Largest friction damping rate per unit Coulomb slope, the largest
/// eigenvalue of `M^-1 diag(cf)` at the equilibrium (1/(s^2 rad^-1)); zero
/// without Coulomb friction.
pub fn coulomb_rate_per_slope<const N: usize>(chain: &PlanarChain<N>) -> f64 {
    let p = chain.params();
    let cf = Vector::<N>::from_fn(|j, _| p.joints[j].coulomb);
    if cf.iter().all(|&c| c == 0.0) {
        return 0.0;
    }
    let m = chain.mass_matrix(&chain.equilibrium());
    let Some(ch) = m.cholesky() else {
        return 0.0;
    };
    // Eigenvalues of M^-1 diag(cf) = those of L^-1 diag(cf) L^-T.
    let l_inv = ch.l().try_inverse().unwrap_or_else(Matrix::<N>::zeros);
    let a = l_inv * Matrix::<N>::from_diagonal(&cf) * l_inv.transpose();
    let a = (a + a.transpose()) * 0.5;
    // (Set-up only: the dynamic matrix is fine here.)
    nalgebra::DMatrix::from_column_slice(N, N, a.as_slice())
        .symmetric_eigenvalues()
        .max()
        .max(0.0)
}

/// RK4 substeps per shooting interval `dt` that resolve the chain's own
/// Coulomb law (at least 1, at most [`MAX_PREDICTION_SUBSTEPS`]).
pub fn prediction_substeps<const N: usize>(chain: &PlanarChain<N>, dt: f64) -> usize {
    let rate = coulomb_rate_per_slope(chain) * chain.params().coulomb_sharpness;
    if !(dt.is_finite() && dt > 0.0) || rate == 0.0 {
        return 1;
    }
    ((dt * rate / PREDICTION_FRICTION_STEP_LIMIT).ceil() as usize).clamp(1, MAX_PREDICTION_SUBSTEPS)
}

/// The Coulomb slope `k` (s/rad) for a prediction model of `chain`
/// integrated with RK4 steps of `h` seconds: the chain's own slope, lowered
/// only as far as `h lambda_max <= PREDICTION_FRICTION_STEP_LIMIT` needs.
pub fn prediction_coulomb_sharpness<const N: usize>(chain: &PlanarChain<N>, h: f64) -> f64 {
    let k = chain.params().coulomb_sharpness;
    let rate = coulomb_rate_per_slope(chain);
    if rate == 0.0 || !(h.is_finite() && h > 0.0) {
        return k;
    }
    k.min(PREDICTION_FRICTION_STEP_LIMIT / (h * rate))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::{DoublePendulum, Joint, PlanarChainParams};

    fn rough_chain() -> PlanarChain<2> {
        let mut p = PlanarChainParams::<2>::point_masses([0.5, 0.5], [0.3, 0.2], 9.81);
        p.joints = [Joint {
            coulomb: 0.09,
            ..Joint::default()
        }; 2];
        PlanarChain::new(p).unwrap()
    }

    #[test]
    fn a_frictionless_chain_needs_no_substeps_or_smoothing() {
        let paper = DoublePendulum::default();
        assert_eq!(prediction_substeps(&paper, 0.025), 1);
        assert_eq!(prediction_coulomb_sharpness(&paper, 0.025), 100.0);
    }

    #[test]
    fn substeps_and_slope_put_the_stiffest_friction_mode_at_the_limit() {
        let chain = rough_chain();
        let m = chain.mass_matrix(&Vector::<2>::zeros());
        let rate_at = |k: f64| {
            let d = Matrix::<2>::from_diagonal(&Vector::<2>::new(0.09 * k, 0.09 * k));
            (m.try_inverse().unwrap() * d)
                .complex_eigenvalues()
                .iter()
                .map(|c| c.re)
                .fold(0.0, f64::max)
        };
        let k = prediction_coulomb_sharpness(&chain, 0.025);
        assert!(k < 100.0, "{k}");
        assert!((0.025 * rate_at(k) - PREDICTION_FRICTION_STEP_LIMIT).abs() < 1e-9);
        let n = prediction_substeps(&chain, 0.025);
        let h = 0.025 / n as f64;
        assert!(h * rate_at(100.0) <= PREDICTION_FRICTION_STEP_LIMIT);
        assert!(0.025 / (n - 1) as f64 * rate_at(100.0) > PREDICTION_FRICTION_STEP_LIMIT);
        assert_eq!(prediction_coulomb_sharpness(&chain, h), 100.0);
    }
}
