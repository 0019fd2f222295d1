//! The in-place Cholesky factorisation of a stage block, with the pivot
//! lifting and truncation the Riccati recursion relies on.

use super::*;

/// In-place lower Cholesky factorisation of rows/columns `from..to` of the
/// column-major `nv x nv` block `lm` (lower triangle holds the matrix).
/// Control pivots (`< nu`) that are not clearly positive are lifted
/// (regularisation); state pivots are truncated to a zero column
/// (semidefinite). Returns (regularised, truncated) counts.
#[inline(always)]
pub(super) fn cholesky<D: Dims>(
    d: D,
    lm: &mut [f64],
    inv: &mut [f64],
    from: usize,
    to: usize,
    set: &RiccatiSettings,
) -> (usize, usize) {
    let (nu, nv) = (d.nu(), d.nv());
    let mut scale = 0.0f64;
    for j in from..to {
        scale = scale.max(lm[j + j * nv]);
    }
    if scale.is_nan() || scale <= 0.0 {
        scale = 1.0;
    }
    let (mut regularised, mut truncated) = (0, 0);
    for j in from..to {
        let mjj = lm[j + j * nv];
        let mut djj = mjj;
        for c in from..j {
            djj -= lm[j + c * nv] * lm[j + c * nv];
        }
        let threshold = set.pivot_tolerance * mjj.abs().max(f64::MIN_POSITIVE);
        if djj.is_nan() || djj <= threshold {
            if j < nu {
                djj = djj.max(0.0) + set.regularisation * scale;
                regularised += 1;
            } else {
                lm[j + j * nv] = 0.0;
                inv[j] = 0.0;
                for i in j + 1..to {
                    lm[i + j * nv] = 0.0;
                }
                truncated += 1;
                continue;
            }
        }
        let ljj = djj.sqrt();
        lm[j + j * nv] = ljj;
        let r = 1.0 / ljj;
        inv[j] = r;
        for i in j + 1..to {
            let mut v = lm[i + j * nv];
            for c in from..j {
                v -= lm[i + c * nv] * lm[j + c * nv];
            }
            lm[i + j * nv] = v * r;
        }
    }
    (regularised, truncated)
}
