//! Sine and cosine of one angle for the chain's per-sample kernels.
//!
//! A control sample evaluates the chain's dynamics Jacobian four times per
//! shooting interval (RK4) and its energy once: about 800 sine-cosine
//! pairs a sample on the paper pendulum, 13 % of its instructions through
//! libm's `sincos` (about 126 instructions a call with the call overhead,
//! against about 70 here, on x86-64 without FMA). The kernels are fdlibm's
//! (`__kernel_sin`, `__kernel_cos`: minimax polynomials on `[-pi/4, pi/4]`,
//! under 1 ulp there) after a two-term Cody-Waite reduction by `pi/2`,
//! exact for `|x| < LIMIT` (the quadrant times the leading 33 bits of
//! `pi/2` is exact). Beyond it, and for NaN and infinities, libm answers.

/// Largest `|x|` reduced here: `x / (pi/2)` stays below `2^17`, so the
/// quadrant times the 33-bit head of `pi/2` is exact.
const LIMIT: f64 = 1.0e5;
/// Adding and subtracting `1.5 2^52` rounds to the nearest integer (ties
/// to even) in the default rounding mode, without SSE4.1's `roundsd`.
const TO_INTEGER: f64 = 1.5 / f64::EPSILON;
const INV_PIO2: f64 = std::f64::consts::FRAC_2_PI;
// The constants by their bits, as fdlibm gives them (e_rem_pio2.c,
// k_sin.c, k_cos.c): decimal literals would depend on their rounding.
/// The first 33 bits of `pi/2`, and `pi/2` minus them.
const PIO2_HEAD: f64 = f64::from_bits(0x3ff9_21fb_5440_0000);
const PIO2_TAIL: f64 = f64::from_bits(0x3dd0_b461_1a62_6331);
const S1: f64 = f64::from_bits(0xbfc5_5555_5555_5549);
const S2: f64 = f64::from_bits(0x3f81_1111_1110_f8a6);
const S3: f64 = f64::from_bits(0xbf2a_01a0_19c1_61d5);
const S4: f64 = f64::from_bits(0x3ec7_1de3_57b1_fe7d);
const S5: f64 = f64::from_bits(0xbe5a_e5e6_8a2b_9ceb);
const S6: f64 = f64::from_bits(0x3de5_d93a_5acf_d57c);
const C1: f64 = f64::from_bits(0x3fa5_5555_5555_554c);
const C2: f64 = f64::from_bits(0xbf56_c16c_16c1_5177);
const C3: f64 = f64::from_bits(0x3efa_01a0_19cb_1590);
const C4: f64 = f64::from_bits(0xbe92_7e4f_809c_52ad);
const C5: f64 = f64::from_bits(0x3e21_ee9e_bdb4_b1c4);
const C6: f64 = f64::from_bits(0xbda8_fae9_be88_38d4);

/// `(sin x, cos x)`, within 2.3e-16 of libm's for `|x| < 1e5` (tested
/// below over that range and near the multiples of `pi/2`), libm's own
/// beyond it and for NaN and infinities.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    // NaN fails the comparison too.
    if x.abs().partial_cmp(&LIMIT) != Some(std::cmp::Ordering::Less) {
        return crate::math::sin_cos(x);
    }
    let shifted = x * INV_PIO2 + TO_INTEGER;
    // The quadrant sits in the low bits of the shifted value.
    let quadrant = shifted.to_bits();
    let n = shifted - TO_INTEGER;
    let r = (x - n * PIO2_HEAD) - n * PIO2_TAIL;
    let z = r * r;
    let sin_r = r + z * r * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
    let tail = z * z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    // 1 - z/2 + tail with the rounding error of 1 - z/2 added back (fdlibm).
    let half = 0.5 * z;
    let w = 1.0 - half;
    let cos_r = w + (((1.0 - w) - half) + tail);
    let (s, c) = if quadrant & 1 == 0 {
        (sin_r, cos_r)
    } else {
        (cos_r, sin_r)
    };
    // Quadrants 2, 3 negate the sine, quadrants 1, 2 the cosine.
    let sin_sign = (quadrant & 2) << 62;
    let cos_sign = (quadrant.wrapping_add(1) & 2) << 62;
    (
        f64::from_bits(s.to_bits() ^ sin_sign),
        f64::from_bits(c.to_bits() ^ cos_sign),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math;
    use std::f64::consts::FRAC_PI_2;

    /// The largest difference from libm over `xs`, and where.
    fn worst(xs: impl Iterator<Item = f64>) -> (f64, f64) {
        let mut worst = (0.0f64, 0.0);
        for x in xs {
            let (s, c) = sin_cos(x);
            let (s0, c0) = math::sin_cos(x);
            let e = (s - s0).abs().max((c - c0).abs());
            assert!(e.is_finite(), "{x}: ({s}, {c}) against ({s0}, {c0})");
            if e > worst.0 {
                worst = (e, x);
            }
        }
        worst
    }

    /// Uniform samples of `[-half, half]` from a fixed LCG.
    fn uniform(count: usize, half: f64, seed: u64) -> impl Iterator<Item = f64> {
        let mut state = seed;
        (0..count).map(move |_| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0 * half
        })
    }

    #[test]
    fn agrees_with_libm_over_the_reduced_range() {
        // Joint angles, many turns, the whole range up to the limit: one
        // ulp of a value near 1 is 2.2e-16, and both sides round.
        for (half, seed) in [(4.0, 1), (100.0, 2), (LIMIT, 3)] {
            let (e, x) = worst(uniform(200_000, half, seed));
            assert!(e <= 2.3e-16, "|x| <= {half}: {e:e} at {x}");
        }
    }

    #[test]
    fn agrees_with_libm_near_the_quadrant_boundaries() {
        // The reduction cancels most there: absolute error still within an
        // ulp of 1, and the quadrant's signs right on both sides.
        let xs = (-2000..=2000).flat_map(|k| {
            let centre = k as f64 * FRAC_PI_2;
            [-1e-9, -1e-15, 0.0, 1e-15, 1e-9].map(move |d| centre + d)
        });
        let (e, x) = worst(xs);
        assert!(e <= 2.3e-16, "{e:e} at {x}");
    }

    #[test]
    fn small_angles_keep_their_relative_accuracy() {
        for x in [1e-300, -1e-12, 3e-8, -2e-4, 1e-3] {
            let (s, c) = sin_cos(x);
            assert!(
                ((s - math::sin(x)) / math::sin(x)).abs() <= 2.3e-16,
                "sin {x}"
            );
            assert_eq!(c, math::cos(x), "cos {x}");
        }
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        assert_eq!(sin_cos(-0.0), (0.0, 1.0));
    }

    #[test]
    fn beyond_the_limit_and_non_finite_are_libm() {
        for x in [LIMIT, -LIMIT * 3.0, 1e300] {
            assert_eq!(sin_cos(x), math::sin_cos(x));
        }
        let (s, c) = sin_cos(f64::NAN);
        assert!(s.is_nan() && c.is_nan());
        let (s, c) = sin_cos(f64::INFINITY);
        assert!(s.is_nan() && c.is_nan());
    }
}
