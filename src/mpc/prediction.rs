//! The controller's prediction model of a robot with Coulomb friction.
//!
//! The smooth Coulomb law `cf atan(k qd)` is stiff near zero speed: its
//! slope there, `cf k`, damps a joint with the rate `lambda = k cf / M`
//! (the largest eigenvalue of `M^-1 diag(cf) k`). With the shared robots'
//! `k = 100` that is ~800 1/s, and one RK4 step of 25 ms (`h lambda` ~ 20)
//! is unstable (RK4's limit on the negative real axis is 2.79).
//!
//! The prediction model ([`prediction_model`]) takes at most
//! [`PREDICTION_SUBSTEPS`] RK4 substeps per interval and lowers the slope
//! `k` until `h lambda <= PREDICTION_FRICTION_STEP_LIMIT` with a joint at
//! rest ([`prediction_coulomb_sharpness`]): a step-aware smoothing. It
//! underestimates the friction only at low speeds; [`FrictionSmoothing`]
//! bounds the error and says up to which speed it exceeds 1 %. Measured on
//! the laboratory robots A0 and B0 (`docs/book/src/robots.md`, issue 22), three substeps (`k`
//! 37 and 22 where the law has 100) against the exact law with 9 and 14:
//! band times within 3 %, tail energy within 1 % of E_ref of the exact
//! law's (B0 at 2 J: -0.40 against +0.54 %; at 4 J: -0.70 against -0.49
//! %), RMS torque up to 6 % lower, at half the per-sample time.
//! Two substeps left B0 at 4 J 1.2 % low (outside a 1 % band the exact law
//! keeps), one 1.2 % and A0 at 1 J 0.6 %; the slope `k` ~ 5 an older
//! model took for one step kept A0 from starting at 1 J. An interval in
//! which every joint stays fast
//! takes fewer substeps still ([`super::MpcConfig::substeps_where_stiff`]).
//! The exact law stays available: `prediction_model(chain, dt,
//! prediction_substeps(chain, dt))` (up to [`MAX_PREDICTION_SUBSTEPS`]).

use crate::math;
use crate::mechanics::{Matrix, MechanicalSystem, PlanarChain, Vector};

/// `h lambda` allowed for the stiffest friction mode in one RK4 step (just
/// inside RK4's stability limit 2.79: the decay is predicted, not resolved).
pub const PREDICTION_FRICTION_STEP_LIMIT: f64 = 2.5;

/// Most RK4 substeps per shooting interval chosen for friction.
pub const MAX_PREDICTION_SUBSTEPS: usize = 20;

/// RK4 substeps per interval the default prediction model takes at most
/// (its Coulomb slope lowered to fit; see the module documentation).
pub const PREDICTION_SUBSTEPS: usize = 3;

/// How far a prediction model's smoothed Coulomb law `cf atan(k' v)` is from
/// the robot's `cf atan(k v)` (`k' <= k`): the model underestimates the
/// friction at low speed only.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionSmoothing {
    /// The robot's slope `k` (s/rad).
    pub sharpness: f64,
    /// The model's slope `k'` (s/rad).
    pub model_sharpness: f64,
    /// The largest error, as a fraction of the Coulomb level `cf pi/2`:
    /// `(atan(sqrt(k/k')) - atan(sqrt(k'/k))) / (pi/2)`.
    pub largest: f64,
    /// The speed of the largest error, `1/sqrt(k k')` (rad/s).
    pub largest_at: f64,
    /// Above this speed the error is below 1 % of the Coulomb level (rad/s);
    /// zero when the model keeps the law.
    pub one_percent_above: f64,
}

impl FrictionSmoothing {
    /// The error of the slope `model_sharpness` against `sharpness`.
    pub fn new(sharpness: f64, model_sharpness: f64) -> Self {
        let (k, km) = (sharpness, model_sharpness.min(sharpness));
        let error = |v: f64| (math::atan(k * v) - math::atan(km * v)) / std::f64::consts::FRAC_PI_2;
        if !(km > 0.0 && k.is_finite()) || km == k {
            return Self {
                sharpness,
                model_sharpness,
                largest: 0.0,
                largest_at: 0.0,
                one_percent_above: 0.0,
            };
        }
        let largest_at = 1.0 / (k * km).sqrt();
        // The error falls monotonically above its peak: bisection (set-up only).
        let (mut lo, mut hi) = (largest_at, largest_at);
        while error(hi) > 0.01 && hi < 1e12 {
            hi *= 2.0;
        }
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if error(mid) > 0.01 {
                lo = mid
            } else {
                hi = mid
            }
        }
        Self {
            sharpness,
            model_sharpness,
            largest: error(largest_at),
            largest_at,
            one_percent_above: if error(largest_at) > 0.01 { hi } else { 0.0 },
        }
    }

    /// One line for a log or a summary.
    pub fn describe(&self) -> String {
        if self.largest == 0.0 {
            return format!(
                "Coulomb slope k = {:.4} s/rad, the robot's law",
                self.sharpness
            );
        }
        format!(
            "Coulomb slope k = {:.4} s/rad (the robot's {}): friction underestimated by at most \
             {:.0} % of the Coulomb level (at {:.3} rad/s), by more than 1 % below {:.2} rad/s",
            self.model_sharpness,
            self.sharpness,
            100.0 * self.largest,
            self.largest_at,
            self.one_percent_above
        )
    }
}

/// The controller's prediction model of `chain` with shooting intervals of
/// `dt`: at most `most_substeps` RK4 substeps per interval (the default
/// [`PREDICTION_SUBSTEPS`]) and the Coulomb slope they can take; with the
/// substeps, the smoothing's error. A model without Coulomb friction is the
/// chain itself with one substep.
pub fn prediction_model<const N: usize>(
    chain: &PlanarChain<N>,
    dt: f64,
    most_substeps: usize,
) -> (PlanarChain<N>, usize, FrictionSmoothing) {
    let substeps = prediction_substeps(chain, dt).min(most_substeps.max(1));
    let k = chain.params().coulomb_sharpness;
    let sharpness = prediction_coulomb_sharpness(chain, dt / substeps as f64);
    // Lowering a finite, positive slope keeps the parameters valid.
    let model = chain.with_coulomb_sharpness(sharpness).unwrap_or(*chain);
    let smoothing = FrictionSmoothing::new(k, model.params().coulomb_sharpness);
    (model, substeps, smoothing)
}

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

    #[test]
    fn the_default_model_takes_its_substeps_and_the_slope_they_allow() {
        let chain = rough_chain();
        assert!(prediction_substeps(&chain, 0.025) > PREDICTION_SUBSTEPS);
        let (model, substeps, smoothing) = prediction_model(&chain, 0.025, PREDICTION_SUBSTEPS);
        assert_eq!(substeps, PREDICTION_SUBSTEPS);
        let k = model.params().coulomb_sharpness;
        assert_eq!(
            k,
            prediction_coulomb_sharpness(&chain, 0.025 / PREDICTION_SUBSTEPS as f64)
        );
        assert_eq!(smoothing.model_sharpness, k);
        // Everything but the slope is the robot's.
        let mut back = *model.params();
        back.coulomb_sharpness = 100.0;
        assert_eq!(back, *chain.params());
        // The exact law: as many substeps as it needs, the slope kept.
        let exact = prediction_substeps(&chain, 0.025);
        let (model, substeps, smoothing) = prediction_model(&chain, 0.025, exact);
        assert_eq!((substeps, model.params().coulomb_sharpness), (exact, 100.0));
        assert_eq!(smoothing.largest, 0.0);
        // A frictionless chain: itself, one substep.
        let paper = DoublePendulum::default();
        let (model, substeps, _) = prediction_model(&paper, 0.025, PREDICTION_SUBSTEPS);
        assert_eq!((substeps, *model.params()), (1, *paper.params()));
    }

    #[test]
    fn the_smoothing_error_is_measured_where_it_says() {
        let (k, km) = (100.0, 25.0);
        let s = FrictionSmoothing::new(k, km);
        let error = |v: f64| (math::atan(k * v) - math::atan(km * v)) / std::f64::consts::FRAC_PI_2;
        // The peak: atan 2 - atan 1/2 at 1/sqrt(k k') = 0.02 rad/s.
        assert!((s.largest_at - 0.02).abs() < 1e-15);
        assert!(
            (s.largest - (math::atan(2.0) - math::atan(0.5)) / std::f64::consts::FRAC_PI_2).abs()
                < 1e-15
        );
        for v in [0.001, 0.01, 0.019, 0.021, 0.1, 1.0] {
            assert!(error(v) <= s.largest, "{v}");
        }
        // 1 % of the Coulomb level at the speed reported, less above it.
        assert!((error(s.one_percent_above) - 0.01).abs() < 1e-9);
        assert!(error(1.01 * s.one_percent_above) < 0.01);
        assert!(error(0.99 * s.one_percent_above) > 0.01);
        assert!(
            s.describe().contains("by more than 1 % below"),
            "{}",
            s.describe()
        );
        assert_eq!(FrictionSmoothing::new(100.0, 100.0).largest, 0.0);
    }
}
