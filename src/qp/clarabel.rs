//! [`QpSolver`] on the general-purpose interior-point solver clarabel.
//!
//! The OCP QP is written as one sparse conic problem
//! `min 1/2 v'Pv + p'v  s.t.  A v + s = b,  s in {0}^m_eq x R+^m_ineq` over
//! `v = (x_0, u_0, x_1, u_1, ..., x_{N-1}, u_{N-1}, x_N, slacks)`.
//! The sparsity pattern (dense stage blocks, every bound that is finite in the
//! first QP seen) is built once; later samples only overwrite the numerical
//! values with `update_P/q/A/b`, so clarabel keeps its symbolic factorisation
//! and each solve costs numeric refactorisations only. A QP whose set of
//! finite bounds differs from the pattern makes the solver rebuild (and
//! allocate) once; the controller never does that in its loop.

use super::{OcpQp, QpSolution, QpSolver, QpStatus};
use ::clarabel::algebra::CscMatrix;
use ::clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};

/// Settings tuned for the RTI QPs: reusable solver (presolve off, structural
/// zeros kept), no equilibration, no iterative refinement, 1e-6 tolerances
/// and the faer sparse LDL. A probe measured 1.25 ms per N = 80 QP with these,
/// against 4 ms for a fresh solver with defaults.
pub fn rti_settings() -> DefaultSettings<f64> {
    DefaultSettings {
        verbose: false,
        presolve_enable: false,
        input_sparse_dropzeros: false,
        equilibrate_enable: false,
        iterative_refinement_enable: false,
        tol_gap_abs: 1e-6,
        tol_gap_rel: 1e-6,
        tol_feas: 1e-6,
        tol_ktratio: 1e-5,
        direct_solve_method: "faer".to_string(),
        max_threads: 1,
        max_iter: 100,
        ..DefaultSettings::default()
    }
}

/// Settings for reference solves (tests, converged SQP): tight tolerances
/// with iterative refinement and equilibration, still reusable (data updates
/// reapply the first QP's equilibration). Without equilibration the RTI QPs'
/// costates (|pi| ~ 1e3) leave complementarity at ~1e-9 and the first control
/// off by up to 5e-6 on weakly active torque bounds.
pub fn accurate_settings() -> DefaultSettings<f64> {
    DefaultSettings {
        equilibrate_enable: true,
        tol_gap_abs: 1e-10,
        tol_gap_rel: 1e-10,
        tol_feas: 1e-10,
        tol_ktratio: 1e-8,
        iterative_refinement_enable: true,
        max_iter: 200,
        ..rti_settings()
    }
}

/// Which constraint rows exist (fixed at pattern build time).
#[derive(Clone, Debug, PartialEq)]
struct Pattern {
    /// `(k, i)` of every finite control lower / upper bound.
    u_lower: Vec<(usize, usize)>,
    u_upper: Vec<(usize, usize)>,
    /// `(k, i)` of every softened state component (either bound finite), `k >= 1`.
    soft: Vec<(usize, usize)>,
    /// Whether the soft component has a finite lower / upper bound.
    soft_has_lower: Vec<bool>,
    soft_has_upper: Vec<bool>,
}

impl Pattern {
    fn of(qp: &OcpQp) -> Self {
        let mut p = Pattern {
            u_lower: Vec::new(),
            u_upper: Vec::new(),
            soft: Vec::new(),
            soft_has_lower: Vec::new(),
            soft_has_upper: Vec::new(),
        };
        for k in 0..qp.horizon {
            for i in 0..qp.nu {
                if qp.u_lower[k][i].is_finite() {
                    p.u_lower.push((k, i));
                }
                if qp.u_upper[k][i].is_finite() {
                    p.u_upper.push((k, i));
                }
            }
        }
        for k in 1..=qp.horizon {
            for i in 0..qp.nx {
                let lo = qp.x_lower[k][i].is_finite();
                let hi = qp.x_upper[k][i].is_finite();
                if lo || hi {
                    p.soft.push((k, i));
                    p.soft_has_lower.push(lo);
                    p.soft_has_upper.push(hi);
                }
            }
        }
        p
    }

    /// Same set of finite bounds as `qp`, checked without allocating.
    fn matches(&self, qp: &OcpQp) -> bool {
        let (mut il, mut iu, mut is) = (0, 0, 0);
        for k in 0..qp.horizon {
            for i in 0..qp.nu {
                if qp.u_lower[k][i].is_finite() {
                    if self.u_lower.get(il) != Some(&(k, i)) {
                        return false;
                    }
                    il += 1;
                }
                if qp.u_upper[k][i].is_finite() {
                    if self.u_upper.get(iu) != Some(&(k, i)) {
                        return false;
                    }
                    iu += 1;
                }
            }
        }
        for k in 1..=qp.horizon {
            for i in 0..qp.nx {
                let lo = qp.x_lower[k][i].is_finite();
                let hi = qp.x_upper[k][i].is_finite();
                if lo || hi {
                    if self.soft.get(is) != Some(&(k, i))
                        || self.soft_has_lower[is] != lo
                        || self.soft_has_upper[is] != hi
                    {
                        return false;
                    }
                    is += 1;
                }
            }
        }
        il == self.u_lower.len() && iu == self.u_upper.len() && is == self.soft.len()
    }
}

/// Where every QP entry goes in clarabel's data (built with the pattern).
struct Layout {
    pattern: Pattern,
    /// Number of variables and of constraint rows.
    n: usize,
    /// Values of `P` (upper triangle, CSC order) and `A`, `q`, `b`.
    p_val: Vec<f64>,
    a_val: Vec<f64>,
    /// CSC structure of `A` (values are written through it).
    a_colptr: Vec<usize>,
    a_rowval: Vec<usize>,
    q_val: Vec<f64>,
    b_val: Vec<f64>,
    solver: DefaultSolver<f64>,
}

/// clarabel-backed [`QpSolver`] for [`OcpQp`]s of fixed dimensions.
pub struct ClarabelQpSolver {
    nx: usize,
    nu: usize,
    horizon: usize,
    settings: DefaultSettings<f64>,
    layout: Option<Layout>,
    /// How many times the conic problem was (re)built; 1 in a healthy loop.
    builds: usize,
}

impl ClarabelQpSolver {
    /// Creates the solver for QPs of the given dimensions. The conic problem
    /// is built on the first [`QpSolver::solve`] (the pattern of finite bounds
    /// is taken from that QP). `presolve_enable` and `input_sparse_dropzeros`
    /// are forced off because they forbid data updates.
    pub fn new(nx: usize, nu: usize, horizon: usize, mut settings: DefaultSettings<f64>) -> Self {
        settings.presolve_enable = false;
        settings.input_sparse_dropzeros = false;
        settings.verbose = false;
        Self {
            nx,
            nu,
            horizon,
            settings,
            layout: None,
            builds: 0,
        }
    }

    /// The settings in use.
    pub fn settings(&self) -> &DefaultSettings<f64> {
        &self.settings
    }

    /// Number of times the conic problem has been built (the set-up, plus one
    /// per change in the set of finite bounds).
    pub fn builds(&self) -> usize {
        self.builds
    }

    /// Variable offsets: `x_k` at `k (nx + nu)`, `u_k` after it, slacks last.
    fn x_off(&self, k: usize) -> usize {
        k * (self.nx + self.nu)
    }
    fn u_off(&self, k: usize) -> usize {
        k * (self.nx + self.nu) + self.nx
    }
    fn slack_off(&self) -> usize {
        self.horizon * (self.nx + self.nu) + self.nx
    }

    /// Builds the sparsity pattern and the clarabel solver for `qp`.
    fn build(&mut self, qp: &OcpQp) -> Result<(), QpStatus> {
        let (nx, nu, nh) = (self.nx, self.nu, self.horizon);
        let pattern = Pattern::of(qp);
        let ns = pattern.soft.len();
        let n = self.slack_off() + ns;

        // P: upper triangle of the stage blocks [Q S'; S R], Q_N and the slack
        // diagonal, column by column (all entries kept so the pattern is fixed).
        let mut colptr = vec![0usize];
        let mut rowval = Vec::new();
        for k in 0..=nh {
            let base = self.x_off(k);
            let width = if k < nh { nx + nu } else { nx };
            for j in 0..width {
                for i in 0..=j {
                    rowval.push(base + i);
                }
                colptr.push(rowval.len());
            }
        }
        for j in 0..ns {
            rowval.push(self.slack_off() + j);
            colptr.push(rowval.len());
        }
        let p_nnz = rowval.len();
        let p = CscMatrix::new(n, n, colptr, rowval, vec![0.0; p_nnz]);

        // A rows: [x_0 = x0 (nx)] [dynamics (N nx)] | [u upper] [u lower]
        // [soft upper] [soft lower] [slack >= 0]. Built from triplets with an
        // order-preserving column sort, then the value positions recorded by
        // recomputing the same order in `fill`.
        let m_eq = nx + nh * nx;
        let m = m_eq
            + pattern.u_upper.len()
            + pattern.u_lower.len()
            + pattern.soft_has_upper.iter().filter(|&&h| h).count()
            + pattern.soft_has_lower.iter().filter(|&&h| h).count()
            + ns;
        let triplets = self.a_triplets(qp, &pattern);
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for &(r, c, _) in &triplets {
            cols[c].push(r);
        }
        let mut colptr = vec![0usize];
        let mut rowval = Vec::new();
        for col in &mut cols {
            col.sort_unstable();
            rowval.extend_from_slice(col);
            colptr.push(rowval.len());
        }
        let a_nnz = rowval.len();
        let a = CscMatrix::new(m, n, colptr, rowval, vec![0.0; a_nnz]);
        let cones = [
            SupportedConeT::ZeroConeT(m_eq),
            SupportedConeT::NonnegativeConeT(m - m_eq),
        ];
        let mut layout_vals = (
            vec![0.0; p_nnz],
            vec![0.0; a_nnz],
            vec![0.0; n],
            vec![0.0; m],
        );
        let mut a_fill = a;
        let mut p_fill = p;
        self.fill_p(qp, &pattern, &mut p_fill.nzval);
        Self::fill_a_from_triplets(&triplets, &mut a_fill);
        layout_vals.0.copy_from_slice(&p_fill.nzval);
        layout_vals.1.copy_from_slice(&a_fill.nzval);
        self.fill_qb(qp, &pattern, &mut layout_vals.2, &mut layout_vals.3);
        let solver = DefaultSolver::new(
            &p_fill,
            &layout_vals.2,
            &a_fill,
            &layout_vals.3,
            &cones,
            self.settings.clone(),
        )
        .map_err(|_| QpStatus::InvalidInput)?;
        self.layout = Some(Layout {
            pattern,
            n,
            p_val: layout_vals.0,
            a_val: layout_vals.1,
            a_colptr: a_fill.colptr.clone(),
            a_rowval: a_fill.rowval.clone(),
            q_val: layout_vals.2,
            b_val: layout_vals.3,
            solver,
        });
        self.builds += 1;
        Ok(())
    }

    /// Constraint-matrix entries `(row, column, value)` in the fixed
    /// generation order of [`Self::for_each_a`].
    fn a_triplets(&self, qp: &OcpQp, pattern: &Pattern) -> Vec<(usize, usize, f64)> {
        let mut t = Vec::new();
        self.for_each_a(qp, pattern, |r, c, v| t.push((r, c, v)));
        t
    }

    /// Visits every entry of `A` in a fixed order.
    fn for_each_a(&self, qp: &OcpQp, pattern: &Pattern, mut f: impl FnMut(usize, usize, f64)) {
        let (nx, nu, nh) = (self.nx, self.nu, self.horizon);
        for i in 0..nx {
            f(i, self.x_off(0) + i, 1.0);
        }
        // A_k x_k + B_k u_k - x_{k+1} = -c_k
        for k in 0..nh {
            let row = nx + k * nx;
            for i in 0..nx {
                for j in 0..nx {
                    f(row + i, self.x_off(k) + j, qp.a[k][(i, j)]);
                }
                for j in 0..nu {
                    f(row + i, self.u_off(k) + j, qp.b[k][(i, j)]);
                }
                f(row + i, self.x_off(k + 1) + i, -1.0);
            }
        }
        let mut row = nx + nh * nx;
        for &(k, i) in &pattern.u_upper {
            f(row, self.u_off(k) + i, 1.0);
            row += 1;
        }
        for &(k, i) in &pattern.u_lower {
            f(row, self.u_off(k) + i, -1.0);
            row += 1;
        }
        let so = self.slack_off();
        for (j, &(k, i)) in pattern.soft.iter().enumerate() {
            if pattern.soft_has_upper[j] {
                f(row, self.x_off(k) + i, 1.0);
                f(row, so + j, -1.0);
                row += 1;
            }
        }
        for (j, &(k, i)) in pattern.soft.iter().enumerate() {
            if pattern.soft_has_lower[j] {
                f(row, self.x_off(k) + i, -1.0);
                f(row, so + j, -1.0);
                row += 1;
            }
        }
        for j in 0..pattern.soft.len() {
            f(row, so + j, -1.0);
            row += 1;
        }
    }

    fn fill_a_from_triplets(triplets: &[(usize, usize, f64)], a: &mut CscMatrix<f64>) {
        for &(r, c, v) in triplets {
            let start = a.colptr[c];
            let end = a.colptr[c + 1];
            let pos = start
                + a.rowval[start..end]
                    .binary_search(&r)
                    .expect("entry in pattern");
            a.nzval[pos] = v;
        }
    }

    /// Writes the values of `P` in CSC order (same order as the pattern).
    fn fill_p(&self, qp: &OcpQp, pattern: &Pattern, out: &mut [f64]) {
        let (nx, nu, nh) = (self.nx, self.nu, self.horizon);
        let mut pos = 0;
        for k in 0..=nh {
            let width = if k < nh { nx + nu } else { nx };
            for j in 0..width {
                for i in 0..=j {
                    out[pos] = if j < nx {
                        qp.q[k][(i, j)]
                    } else if i < nx {
                        qp.s[k][(j - nx, i)]
                    } else {
                        qp.r[k][(i - nx, j - nx)]
                    };
                    pos += 1;
                }
            }
        }
        for &(_, i) in &pattern.soft {
            out[pos] = qp.soft_l2[i];
            pos += 1;
        }
    }

    /// Writes the linear cost `q` and the right-hand side `b`.
    fn fill_qb(&self, qp: &OcpQp, pattern: &Pattern, q: &mut [f64], b: &mut [f64]) {
        let (nx, nu, nh) = (self.nx, self.nu, self.horizon);
        for k in 0..=nh {
            for i in 0..nx {
                q[self.x_off(k) + i] = qp.q_lin[k][i];
            }
            if k < nh {
                for i in 0..nu {
                    q[self.u_off(k) + i] = qp.r_lin[k][i];
                }
            }
        }
        let so = self.slack_off();
        for (j, &(_, i)) in pattern.soft.iter().enumerate() {
            q[so + j] = qp.soft_l1[i];
        }
        b[..nx].copy_from_slice(qp.x0.as_slice());
        for k in 0..nh {
            for i in 0..nx {
                b[nx + k * nx + i] = -qp.c[k][i];
            }
        }
        let mut row = nx + nh * nx;
        for &(k, i) in &pattern.u_upper {
            b[row] = qp.u_upper[k][i];
            row += 1;
        }
        for &(k, i) in &pattern.u_lower {
            b[row] = -qp.u_lower[k][i];
            row += 1;
        }
        for (j, &(k, i)) in pattern.soft.iter().enumerate() {
            if pattern.soft_has_upper[j] {
                b[row] = qp.x_upper[k][i];
                row += 1;
            }
        }
        for (j, &(k, i)) in pattern.soft.iter().enumerate() {
            if pattern.soft_has_lower[j] {
                b[row] = -qp.x_lower[k][i];
                row += 1;
            }
        }
        for _ in 0..pattern.soft.len() {
            b[row] = 0.0;
            row += 1;
        }
    }

    fn dimensions_match(&self, qp: &OcpQp) -> bool {
        qp.nx == self.nx
            && qp.nu == self.nu
            && qp.horizon == self.horizon
            && qp.q.len() == self.horizon + 1
            && qp.a.len() == self.horizon
    }

    fn solve_inner(&mut self, qp: &OcpQp, sol: &mut QpSolution) -> QpStatus {
        if !self.dimensions_match(qp) || !data_is_finite(qp) {
            return QpStatus::InvalidInput;
        }
        let rebuild = match &self.layout {
            Some(l) => !l.pattern.matches(qp),
            None => true,
        };
        if rebuild {
            if let Err(status) = self.build(qp) {
                return status;
            }
        } else {
            let mut layout = self.layout.take().expect("layout present");
            self.fill_p(qp, &layout.pattern, &mut layout.p_val);
            self.fill_a_values(
                qp,
                &layout.pattern,
                &layout.a_colptr,
                &layout.a_rowval,
                &mut layout.a_val,
            );
            self.fill_qb(qp, &layout.pattern, &mut layout.q_val, &mut layout.b_val);
            let s = &mut layout.solver;
            let ok = s.update_P(&layout.p_val).is_ok()
                && s.update_A(&layout.a_val).is_ok()
                && s.update_q(&layout.q_val).is_ok()
                && s.update_b(&layout.b_val).is_ok();
            self.layout = Some(layout);
            if !ok {
                return QpStatus::InvalidInput;
            }
        }
        let layout = self.layout.as_mut().expect("layout built");
        layout.solver.solve();
        let result = &layout.solver.solution;
        let status = match result.status {
            SolverStatus::Solved => QpStatus::Solved,
            SolverStatus::AlmostSolved => QpStatus::AlmostSolved,
            SolverStatus::MaxIterations | SolverStatus::MaxTime => QpStatus::MaxIterations,
            SolverStatus::PrimalInfeasible
            | SolverStatus::DualInfeasible
            | SolverStatus::AlmostPrimalInfeasible
            | SolverStatus::AlmostDualInfeasible => QpStatus::Infeasible,
            _ => QpStatus::NumericalError,
        };
        let (nx, nu, nh) = (self.nx, self.nu, self.horizon);
        let x = &result.x;
        let z = &result.z;
        for k in 0..=nh {
            let o = k * (nx + nu);
            for i in 0..nx {
                sol.x[k][i] = x[o + i];
            }
            if k < nh {
                for i in 0..nu {
                    sol.u[k][i] = x[o + nx + i];
                }
                for i in 0..nx {
                    sol.pi[k][i] = z[nx + k * nx + i];
                }
                sol.lam_u_lower[k].fill(0.0);
                sol.lam_u_upper[k].fill(0.0);
            }
        }
        let mut row = nx + nh * nx;
        for &(k, i) in &layout.pattern.u_upper {
            sol.lam_u_upper[k][i] = z[row];
            row += 1;
        }
        for &(k, i) in &layout.pattern.u_lower {
            sol.lam_u_lower[k][i] = z[row];
            row += 1;
        }
        debug_assert_eq!(layout.n, x.len());
        sol.objective = result.obj_val;
        sol.iterations = result.iterations as usize;
        sol.primal_residual = result.r_prim;
        sol.dual_residual = result.r_dual;
        status
    }

    /// Writes the values of `A` in the CSC order of the built solver.
    fn fill_a_values(
        &self,
        qp: &OcpQp,
        pattern: &Pattern,
        colptr: &[usize],
        rowval: &[usize],
        out: &mut [f64],
    ) {
        // Entries are visited in generation order; find each CSC position.
        self.for_each_a(qp, pattern, |r, c, v| {
            let start = colptr[c];
            let end = colptr[c + 1];
            if let Ok(p) = rowval[start..end].binary_search(&r) {
                out[start + p] = v;
            }
        });
    }
}

fn data_is_finite(qp: &OcpQp) -> bool {
    let mats =
        qp.q.iter()
            .chain(&qp.s)
            .chain(&qp.r)
            .chain(&qp.a)
            .chain(&qp.b);
    let vecs = qp
        .q_lin
        .iter()
        .chain(&qp.r_lin)
        .chain(&qp.c)
        .chain(std::iter::once(&qp.x0));
    mats.flat_map(|m| m.iter()).all(|v| v.is_finite())
        && vecs.flat_map(|v| v.iter()).all(|v| v.is_finite())
        && qp
            .soft_l1
            .iter()
            .chain(qp.soft_l2.iter())
            .all(|v| v.is_finite() && *v >= 0.0)
        && qp
            .u_lower
            .iter()
            .chain(&qp.u_upper)
            .chain(&qp.x_lower)
            .chain(&qp.x_upper)
            .flat_map(|v| v.iter())
            .all(|v| !v.is_nan())
}

impl QpSolver for ClarabelQpSolver {
    fn name(&self) -> &'static str {
        "clarabel"
    }

    fn solve(&mut self, qp: &OcpQp, solution: &mut QpSolution) -> QpStatus {
        let status = self.solve_inner(qp, solution);
        solution.status = status;
        status
    }
}
