//! Checks of a QP before it is solved and of a solution after: dimensions,
//! finite data, symmetric Hessian blocks, consistent bounds.

use super::*;

pub(super) fn valid_dimensions(qp: &OcpQp, nx: usize, nu: usize, n: usize) -> bool {
    let mat = |m: &nalgebra::DMatrix<f64>, r, c| m.nrows() == r && m.ncols() == c;
    let vecs = |v: &[nalgebra::DVector<f64>], len, count| {
        v.len() == count && v.iter().all(|x| x.len() == len)
    };
    qp.nx == nx
        && qp.nu == nu
        && qp.horizon == n
        && n >= 1
        && nx >= 1
        && nu >= 1
        && qp.q.len() == n + 1
        && qp.q.iter().all(|m| mat(m, nx, nx))
        && qp.s.len() == n
        && qp.s.iter().all(|m| mat(m, nu, nx))
        && qp.r.len() == n
        && qp.r.iter().all(|m| mat(m, nu, nu))
        && qp.a.len() == n
        && qp.a.iter().all(|m| mat(m, nx, nx))
        && qp.b.len() == n
        && qp.b.iter().all(|m| mat(m, nx, nu))
        && vecs(&qp.q_lin, nx, n + 1)
        && vecs(&qp.r_lin, nu, n)
        && vecs(&qp.c, nx, n)
        && vecs(&qp.u_lower, nu, n)
        && vecs(&qp.u_upper, nu, n)
        && vecs(&qp.x_lower, nx, n + 1)
        && vecs(&qp.x_upper, nx, n + 1)
        && qp.x0.len() == nx
        && qp.soft_l1.len() == nx
        && qp.soft_l2.len() == nx
}

pub(super) fn valid_solution(sol: &QpSolution, nx: usize, nu: usize, n: usize) -> bool {
    let vecs = |v: &[nalgebra::DVector<f64>], len, count| {
        v.len() == count && v.iter().all(|x| x.len() == len)
    };
    vecs(&sol.x, nx, n + 1)
        && vecs(&sol.u, nu, n)
        && vecs(&sol.pi, nx, n)
        && vecs(&sol.lam_u_lower, nu, n)
        && vecs(&sol.lam_u_upper, nu, n)
}

/// Largest asymmetry of a Hessian block accepted, relative to its largest
/// entry (the solver reads the lower triangles).
pub(super) const SYMMETRY_TOLERANCE: f64 = 1e-10;

/// A lower bound may be `-inf` (none), not NaN or `+inf`.
pub(super) fn lower_bound_ok(l: f64) -> bool {
    !l.is_nan() && l != f64::INFINITY
}

/// An upper bound may be `+inf` (none), not NaN or `-inf`.
pub(super) fn upper_bound_ok(u: f64) -> bool {
    !u.is_nan() && u != f64::NEG_INFINITY
}

/// Finite data, consistent bounds, nonnegative penalties and symmetric
/// Hessian blocks (the solver reads their lower triangles).
pub(super) fn valid_data(qp: &OcpQp) -> bool {
    // It runs on every solve: four independent lanes instead of one serial
    // chain of dependent operations (and no early exits that block it).
    let finite = |s: &[f64]| {
        // v * 0 is 0 for finite v and NaN otherwise.
        let mut lanes = [0.0; 4];
        let chunks = s.chunks_exact(4);
        let rest = chunks.remainder();
        for c in chunks {
            for (l, v) in lanes.iter_mut().zip(c) {
                *l += v * 0.0;
            }
        }
        for (l, v) in lanes.iter_mut().zip(rest) {
            *l += v * 0.0;
        }
        lanes.iter().sum::<f64>() == 0.0
    };
    let symmetric = |m: &nalgebra::DMatrix<f64>| {
        let n = m.nrows();
        let v = m.as_slice();
        let (mut scale, mut asym) = ([0.0f64; 4], [0.0f64; 4]);
        for (i, &x) in v.iter().enumerate() {
            scale[i % 4] = scale[i % 4].max(x.abs());
        }
        for i in 0..n {
            for j in 0..i {
                asym[j % 4] = asym[j % 4].max((v[i + j * n] - v[j + i * n]).abs());
            }
        }
        let max = |l: [f64; 4]| l[0].max(l[1]).max(l[2].max(l[3]));
        max(asym) <= SYMMETRY_TOLERANCE * max(scale)
    };
    let mats = [&qp.q, &qp.s, &qp.r, &qp.a, &qp.b];
    if !mats.iter().all(|v| v.iter().all(|m| finite(m.as_slice()))) {
        return false;
    }
    let vecs = [&qp.q_lin, &qp.r_lin, &qp.c];
    if !vecs.iter().all(|v| v.iter().all(|x| finite(x.as_slice()))) {
        return false;
    }
    if !finite(qp.x0.as_slice()) || !finite(qp.soft_l1.as_slice()) || !finite(qp.soft_l2.as_slice())
    {
        return false;
    }
    if qp.soft_l1.iter().chain(qp.soft_l2.iter()).any(|&w| w < 0.0) {
        return false;
    }
    if !qp.q.iter().chain(qp.r.iter()).all(symmetric) {
        return false;
    }
    let u_ok = qp.u_lower.iter().zip(&qp.u_upper).all(|(l, u)| {
        l.iter()
            .zip(u.iter())
            .all(|(&l, &u)| lower_bound_ok(l) && upper_bound_ok(u) && l <= u)
    });
    let x_ok = qp.x_lower.iter().zip(&qp.x_upper).all(|(l, u)| {
        l.iter()
            .zip(u.iter())
            .all(|(&l, &u)| lower_bound_ok(l) && upper_bound_ok(u))
    });
    u_ok && x_ok
}
