//! Elementary functions with the same bits on every machine.
//!
//! `f64::sin`, `exp`, `atan`, ... call the platform's C library, and its
//! answer depends on the machine: glibc picks an FMA-compiled variant of
//! `sin`, `cos`, `exp`, `pow`, `atan`, ... at run time on CPUs with FMA and
//! AVX2 (the SSE2 one elsewhere, and another code base on aarch64, Windows
//! and macOS). They round differently in the last bit, and a mode family is
//! sensitive enough to carry that bit into its chart: the shipped model
//! descriptions' defaults, and so their GUIDs, came out different on
//! different machines (issue 36). Everything the library computes goes
//! through these instead: the `libm` crate (rust-lang's port of musl's
//! fdlibm-derived code, pure Rust, under 1 ulp), which makes the same IEEE
//! operations in the same order on every target. `clippy.toml` refuses the
//! `std` methods in the workspace, so that none comes back.
//!
//! Exact operations (`sqrt`, `abs`, `mul_add`, `floor`, ...) need no
//! wrapper: IEEE 754 fixes their result.

/// `sin x`.
#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

/// `cos x`.
#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

/// `tan x`.
#[inline]
pub fn tan(x: f64) -> f64 {
    libm::tan(x)
}

/// `acos x`.
#[inline]
pub fn acos(x: f64) -> f64 {
    libm::acos(x)
}

/// `atan x`.
#[inline]
pub fn atan(x: f64) -> f64 {
    libm::atan(x)
}

/// `atan2(y, x)`, the angle of `(x, y)`.
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

/// `tanh x`.
#[inline]
pub fn tanh(x: f64) -> f64 {
    libm::tanh(x)
}

/// `e^x`.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// The natural logarithm.
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// The decimal logarithm.
#[inline]
pub fn log10(x: f64) -> f64 {
    libm::log10(x)
}

/// `x^y` for a real `y` (`f64::powi`'s repeated multiplication is the
/// same everywhere and needs no wrapper).
#[inline]
pub fn powf(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

/// `sqrt(x^2 + y^2)` without overflow.
#[inline]
pub fn hypot(x: f64, y: f64) -> f64 {
    libm::hypot(x, y)
}

#[cfg(test)]
mod tests {
    // The comparisons with the platform's functions are what the wrappers
    // replace, so they are allowed here.
    #![allow(clippy::disallowed_methods)]
    use super::*;

    /// Each wrapper is its function to within an ulp or two of the
    /// platform's (which differs by machine in the last bit), on a sweep
    /// of arguments, and the same at the special values.
    #[test]
    fn the_wrappers_are_their_functions() {
        let ulps = |a: f64, b: f64| {
            if a == b {
                0.0
            } else {
                (a - b).abs() / (f64::EPSILON * a.abs().max(b.abs()).max(f64::MIN_POSITIVE))
            }
        };
        for i in 0..20_000 {
            let x = -50.0 + 100.0 * i as f64 / 20_000.0 + 1e-3;
            assert!(ulps(sin(x), x.sin()) <= 2.0, "sin {x}");
            assert!(ulps(cos(x), x.cos()) <= 2.0, "cos {x}");
            assert_eq!(sin_cos(x), (sin(x), cos(x)), "sin_cos {x}");
            assert!(ulps(atan(x), x.atan()) <= 2.0, "atan {x}");
            let c = x / 50.0;
            assert!(ulps(acos(c), c.acos()) <= 2.0, "acos {c}");
            assert!(ulps(atan2(x, 1.5), x.atan2(1.5)) <= 2.0, "atan2 {x}");
            assert!(ulps(tanh(x), x.tanh()) <= 2.0, "tanh {x}");
            assert!(ulps(exp(x / 5.0), (x / 5.0).exp()) <= 2.0, "exp {x}");
            let p = x.abs() + 0.1;
            assert!(ulps(ln(p), p.ln()) <= 2.0, "ln {p}");
            assert!(ulps(log10(p), p.log10()) <= 2.0, "log10 {p}");
            assert!(ulps(powf(p, -0.2), p.powf(-0.2)) <= 2.0, "powf {p}");
            assert!(ulps(hypot(x, 0.3), x.hypot(0.3)) <= 2.0, "hypot {x}");
            if x.abs() < 1.5 {
                assert!(ulps(tan(x), x.tan()) <= 2.0, "tan {x}");
            }
        }
        assert!(sin(f64::NAN).is_nan() && exp(f64::INFINITY) == f64::INFINITY);
        assert_eq!(exp(f64::NEG_INFINITY), 0.0);
        assert_eq!(ln(0.0), f64::NEG_INFINITY);
        assert!(ln(-1.0).is_nan());
        assert_eq!(atan(f64::INFINITY), std::f64::consts::FRAC_PI_2);
    }

    /// The bits of a few values, as musl's algorithms give them on every
    /// target (a change of the `libm` crate that moved them would move the
    /// shipped charts: this test names the cause).
    #[test]
    fn the_bits_are_pinned() {
        assert_eq!(sin(1.0).to_bits(), 0x3fea_ed54_8f09_0cee);
        assert_eq!(cos(1.0).to_bits(), 0x3fe1_4a28_0fb5_068c);
        assert_eq!(exp(1.0).to_bits(), 0x4005_bf0a_8b14_576a);
        assert_eq!(atan(1.0).to_bits(), 0x3fe9_21fb_5444_2d18);
        assert_eq!(powf(2.0, 0.2).to_bits(), 0x3ff2_6111_86ba_e675);
        assert_eq!(tanh(0.5).to_bits(), 0x3fdd_9353_d756_8af3);
        assert_eq!(ln(10.0).to_bits(), 0x4002_6bb1_bbb5_5516);
    }
}
