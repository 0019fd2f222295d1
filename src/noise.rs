//! A deterministic Gaussian noise generator: the same seed gives the same
//! sequence on every machine (the measured closed loops' sensor noise, the
//! robustness report's seeded models, the adaptation's excitation).

use crate::math;
use nalgebra::SVector;

/// Deterministic Gaussian noise (xorshift64* and Box-Muller).
#[derive(Clone, Debug)]
pub struct GaussianNoise(u64);

impl GaussianNoise {
    /// A generator with `seed` (0 is replaced by a fixed nonzero seed).
    pub fn new(seed: u64) -> Self {
        Self(if seed == 0 {
            0x9e37_79b9_7f4a_7c15
        } else {
            seed
        })
    }

    /// The generator's state: `GaussianNoise::new(state)` continues the
    /// sequence from here (the state is never 0).
    pub fn state(&self) -> u64 {
        self.0
    }

    /// Uniform in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// One standard normal sample.
    pub fn sample(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * math::ln(u)).sqrt() * math::cos(2.0 * std::f64::consts::PI * v)
    }

    /// `z` with independent noise of standard deviation `angle` (rad) on
    /// the angles and `speed` (rad/s) on the speeds.
    pub fn measure<const NX: usize>(
        &mut self,
        z: &SVector<f64, NX>,
        angle: f64,
        speed: f64,
    ) -> SVector<f64, NX> {
        SVector::from_fn(|i, _| z[i] + if i < NX / 2 { angle } else { speed } * self.sample())
    }
}
