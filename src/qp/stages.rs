//! The same QP as [`OcpQp`], stored stage by stage in compile-time sizes:
//! what the controller's linearisation writes, laid out as the Riccati
//! solver's compile-time-sized cores read it (issue 22). The heap-sized
//! [`OcpQp`] cost as much to fill, check and copy as the Riccati recursion
//! that solves it (about 100 k instructions a sample on the paper's
//! pendulum); solvers without a typed path get it converted
//! ([`AnyStageQp::write_ocp`], [`super::QpSolver::solve_stages`]).

use super::OcpQp;
use nalgebra::{SMatrix, SVector};
use std::any::Any;

/// One stage `k` of a [`StageQp`] (the notation of the [`super`] module).
/// The last stage (`k = N`) has no dynamics, control or cross terms: only
/// its `q`, `q_lin`, `x_lower` and `x_upper` are read.
#[derive(Clone, Debug, PartialEq)]
pub struct QpStage<const NX: usize, const NU: usize> {
    /// `Q_k` (symmetric positive semidefinite).
    pub q: SMatrix<f64, NX, NX>,
    /// `S_k`.
    pub s: SMatrix<f64, NU, NX>,
    /// `R_k` (symmetric).
    pub r: SMatrix<f64, NU, NU>,
    /// Linear state cost `q_k`.
    pub q_lin: SVector<f64, NX>,
    /// Linear control cost `r_k`.
    pub r_lin: SVector<f64, NU>,
    /// Dynamics `A_k`.
    pub a: SMatrix<f64, NX, NX>,
    /// Dynamics `B_k`.
    pub b: SMatrix<f64, NX, NU>,
    /// Dynamics offset `c_k`.
    pub c: SVector<f64, NX>,
    /// Control lower bounds (`-inf`: none).
    pub u_lower: SVector<f64, NU>,
    /// Control upper bounds (`+inf`: none).
    pub u_upper: SVector<f64, NU>,
    /// Soft state lower bounds (`-inf`: none; ignored at `k = 0`).
    pub x_lower: SVector<f64, NX>,
    /// Soft state upper bounds (`+inf`: none; ignored at `k = 0`).
    pub x_upper: SVector<f64, NX>,
}

impl<const NX: usize, const NU: usize> QpStage<NX, NU> {
    /// Zero data, unbounded controls and no state bounds.
    pub fn new() -> Self {
        Self {
            q: SMatrix::zeros(),
            s: SMatrix::zeros(),
            r: SMatrix::zeros(),
            q_lin: SVector::zeros(),
            r_lin: SVector::zeros(),
            a: SMatrix::zeros(),
            b: SMatrix::zeros(),
            c: SVector::zeros(),
            u_lower: SVector::repeat(f64::NEG_INFINITY),
            u_upper: SVector::repeat(f64::INFINITY),
            x_lower: SVector::repeat(f64::NEG_INFINITY),
            x_upper: SVector::repeat(f64::INFINITY),
        }
    }
}

impl<const NX: usize, const NU: usize> Default for QpStage<NX, NU> {
    fn default() -> Self {
        Self::new()
    }
}

/// An [`OcpQp`] with `NX` states and `NU` controls stored stage by stage:
/// `stages[k]` for `k = 0..=N`, allocated once by [`StageQp::new`] and
/// overwritten in place at each sample.
#[derive(Clone, Debug, PartialEq)]
pub struct StageQp<const NX: usize, const NU: usize> {
    /// Stages `0..=N`.
    pub stages: Vec<QpStage<NX, NU>>,
    /// Initial state (equality constraint on `x_0`).
    pub x0: SVector<f64, NX>,
    /// Exact-penalty (L1) weight per state component for bound violations.
    pub soft_l1: SVector<f64, NX>,
    /// Quadratic weight per state component for bound violations.
    pub soft_l2: SVector<f64, NX>,
}

impl<const NX: usize, const NU: usize> StageQp<NX, NU> {
    /// Allocates a QP of horizon `horizon` with zero data, unbounded
    /// controls and no state bounds.
    pub fn new(horizon: usize) -> Self {
        Self {
            stages: vec![QpStage::new(); horizon + 1],
            x0: SVector::zeros(),
            soft_l1: SVector::zeros(),
            soft_l2: SVector::zeros(),
        }
    }

    /// Number of shooting intervals `N`.
    pub fn horizon(&self) -> usize {
        self.stages.len().saturating_sub(1)
    }

    /// The same QP as an [`OcpQp`] (allocates; diagnostics and tests).
    pub fn to_ocp(&self) -> OcpQp {
        let mut out = OcpQp::new(NX, NU, self.horizon());
        self.write_ocp(&mut out);
        out
    }

    /// The QP of `qp`, or `None` when its dimensions are not `NX`, `NU`
    /// with consistent stage counts.
    pub fn from_ocp(qp: &OcpQp) -> Option<Self> {
        let n = qp.horizon;
        let fits = qp.nx == NX
            && qp.nu == NU
            && qp.q.len() == n + 1
            && [qp.s.len(), qp.r.len(), qp.a.len(), qp.b.len()] == [n; 4]
            && [
                qp.r_lin.len(),
                qp.c.len(),
                qp.u_lower.len(),
                qp.u_upper.len(),
            ] == [n; 4]
            && [qp.q_lin.len(), qp.x_lower.len(), qp.x_upper.len()] == [n + 1; 3];
        if !fits {
            return None;
        }
        let mut out = Self::new(n);
        let copy = |dst: &mut [f64], src: &[f64]| {
            (dst.len() == src.len()).then(|| dst.copy_from_slice(src))
        };
        copy(out.x0.as_mut_slice(), qp.x0.as_slice())?;
        copy(out.soft_l1.as_mut_slice(), qp.soft_l1.as_slice())?;
        copy(out.soft_l2.as_mut_slice(), qp.soft_l2.as_slice())?;
        for (k, st) in out.stages.iter_mut().enumerate() {
            copy(st.q.as_mut_slice(), qp.q[k].as_slice())?;
            copy(st.q_lin.as_mut_slice(), qp.q_lin[k].as_slice())?;
            copy(st.x_lower.as_mut_slice(), qp.x_lower[k].as_slice())?;
            copy(st.x_upper.as_mut_slice(), qp.x_upper[k].as_slice())?;
            if k < n {
                copy(st.s.as_mut_slice(), qp.s[k].as_slice())?;
                copy(st.r.as_mut_slice(), qp.r[k].as_slice())?;
                copy(st.r_lin.as_mut_slice(), qp.r_lin[k].as_slice())?;
                copy(st.a.as_mut_slice(), qp.a[k].as_slice())?;
                copy(st.b.as_mut_slice(), qp.b[k].as_slice())?;
                copy(st.c.as_mut_slice(), qp.c[k].as_slice())?;
                copy(st.u_lower.as_mut_slice(), qp.u_lower[k].as_slice())?;
                copy(st.u_upper.as_mut_slice(), qp.u_upper[k].as_slice())?;
            }
        }
        Some(out)
    }
}

/// A [`StageQp`] of any sizes behind one interface: a solver with a typed
/// path for its sizes finds it with [`AnyStageQp::as_any`], the others
/// read the converted [`OcpQp`].
pub trait AnyStageQp: Any + Send + Sync {
    /// `(nx, nu, N)`.
    fn dimensions(&self) -> (usize, usize, usize);
    /// Writes the QP into `out`, resizing it when its dimensions differ
    /// (allocates only then).
    fn write_ocp(&self, out: &mut OcpQp);
    /// For the downcast to the concrete [`StageQp`].
    fn as_any(&self) -> &dyn Any;
}

impl<const NX: usize, const NU: usize> AnyStageQp for StageQp<NX, NU> {
    fn dimensions(&self) -> (usize, usize, usize) {
        (NX, NU, self.horizon())
    }

    fn write_ocp(&self, out: &mut OcpQp) {
        let n = self.horizon();
        if (out.nx, out.nu, out.horizon) != (NX, NU, n) || out.q.len() != n + 1 || out.a.len() != n
        {
            *out = OcpQp::new(NX, NU, n);
        }
        out.x0.copy_from(&self.x0);
        out.soft_l1.copy_from(&self.soft_l1);
        out.soft_l2.copy_from(&self.soft_l2);
        for (k, st) in self.stages.iter().enumerate() {
            out.q[k].copy_from(&st.q);
            out.q_lin[k].copy_from(&st.q_lin);
            out.x_lower[k].copy_from(&st.x_lower);
            out.x_upper[k].copy_from(&st.x_upper);
            if k < n {
                out.s[k].copy_from(&st.s);
                out.r[k].copy_from(&st.r);
                out.r_lin[k].copy_from(&st.r_lin);
                out.a[k].copy_from(&st.a);
                out.b[k].copy_from(&st.b);
                out.c[k].copy_from(&st.c);
                out.u_lower[k].copy_from(&st.u_lower);
                out.u_upper[k].copy_from(&st.u_upper);
            }
        }
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    #[test]
    fn the_ocp_form_round_trips() {
        let n = 3;
        let mut qp = OcpQp::new(4, 2, n);
        let mut v = 0.0;
        let mut next = || {
            v += 0.37;
            v
        };
        for k in 0..n {
            qp.a[k] = DMatrix::from_fn(4, 4, |_, _| next());
            qp.b[k] = DMatrix::from_fn(4, 2, |_, _| next());
            qp.c[k] = DVector::from_fn(4, |_, _| next());
            qp.s[k] = DMatrix::from_fn(2, 4, |_, _| next());
            qp.r[k] = DMatrix::from_fn(2, 2, |_, _| next());
            qp.r_lin[k] = DVector::from_fn(2, |_, _| next());
            qp.u_lower[k] = DVector::from_fn(2, |_, _| -next());
            qp.u_upper[k] = DVector::from_fn(2, |_, _| next());
        }
        for k in 0..=n {
            qp.q[k] = DMatrix::from_fn(4, 4, |_, _| next());
            qp.q_lin[k] = DVector::from_fn(4, |_, _| next());
            qp.x_lower[k][1] = -next();
            qp.x_upper[k][3] = next();
        }
        qp.x0 = DVector::from_fn(4, |_, _| next());
        qp.soft_l1 = DVector::from_fn(4, |_, _| next());
        qp.soft_l2 = DVector::from_fn(4, |_, _| next());
        let typed = StageQp::<4, 2>::from_ocp(&qp).expect("fits");
        assert_eq!(typed.dimensions(), (4, 2, n));
        assert_eq!(typed.stages[1].b[(3, 1)], qp.b[1][(3, 1)]);
        assert_eq!(typed.stages[2].x_upper[3], qp.x_upper[2][3]);
        // Back through a QP of other sizes: resized, then equal throughout.
        let mut back = OcpQp::new(2, 1, 7);
        typed.write_ocp(&mut back);
        assert_eq!(StageQp::<4, 2>::from_ocp(&back), Some(typed.clone()));
        assert_eq!(format!("{back:?}"), format!("{qp:?}"));
        assert!(StageQp::<4, 1>::from_ocp(&qp).is_none());
        assert!(StageQp::<6, 2>::from_ocp(&qp).is_none());
    }
}
