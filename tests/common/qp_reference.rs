//! Independent references for the QP solver tests and the QP bench: the
//! OCP QP assembled as one sparse QP for clarabel, and a dense KKT solve for
//! problems without inequalities.
#![allow(dead_code)]

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
};
use eigenmpc::qp::OcpQp;
use nalgebra::{DMatrix, DVector};

/// A reference solution.
#[derive(Clone, Debug)]
pub struct Reference {
    /// States `x_0..=x_N`.
    pub x: Vec<DVector<f64>>,
    /// Controls `u_0..u_N`.
    pub u: Vec<DVector<f64>>,
    /// Objective (no constant term, like `OcpQp`).
    pub objective: f64,
    /// Whether the reference solver reports success.
    pub solved: bool,
    /// Iterations of the reference solver.
    pub iterations: u32,
}

/// True when component `i` of stage `k` has a soft bound (same rule as the
/// solver and the KKT checker).
fn is_soft(qp: &OcpQp, k: usize, i: usize) -> bool {
    k >= 1
        && (qp.x_lower[k][i].is_finite() || qp.x_upper[k][i].is_finite())
        && (qp.soft_l1[i] > 0.0 || qp.soft_l2[i] > 0.0)
}

/// Column layout of the stacked variable `(x_0..x_N, u_0..u_{N-1}, s..)`.
struct Layout {
    nx: usize,
    nu: usize,
    n: usize,
    /// Column of the slack of (k, i), if soft.
    slack: Vec<Option<usize>>,
    total: usize,
}

impl Layout {
    fn new(qp: &OcpQp) -> Self {
        let (nx, nu, n) = (qp.nx, qp.nu, qp.horizon);
        let mut next = (n + 1) * nx + n * nu;
        let mut slack = vec![None; (n + 1) * nx];
        for k in 0..=n {
            for i in 0..nx {
                if is_soft(qp, k, i) {
                    slack[k * nx + i] = Some(next);
                    next += 1;
                }
            }
        }
        Self {
            nx,
            nu,
            n,
            slack,
            total: next,
        }
    }
    fn x(&self, k: usize, i: usize) -> usize {
        k * self.nx + i
    }
    fn u(&self, k: usize, j: usize) -> usize {
        (self.n + 1) * self.nx + k * self.nu + j
    }
}

/// Triplet accumulator.
#[derive(Default)]
struct Triplets {
    rows: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<f64>,
}

impl Triplets {
    fn push(&mut self, r: usize, c: usize, v: f64) {
        if v != 0.0 {
            self.rows.push(r);
            self.cols.push(c);
            self.vals.push(v);
        }
    }
    fn csc(self, m: usize, n: usize) -> CscMatrix<f64> {
        CscMatrix::new_from_triplets(m, n, self.rows, self.cols, self.vals)
    }
}

/// Hessian (upper triangle) and gradient of the stacked QP.
fn cost(qp: &OcpQp, lay: &Layout) -> (Triplets, Vec<f64>) {
    let (nx, nu, n) = (lay.nx, lay.nu, lay.n);
    let mut p = Triplets::default();
    let mut g = vec![0.0; lay.total];
    for k in 0..=n {
        for i in 0..nx {
            for j in i..nx {
                p.push(lay.x(k, i), lay.x(k, j), qp.q[k][(i, j)]);
            }
            g[lay.x(k, i)] = qp.q_lin[k][i];
            if let Some(c) = lay.slack[k * nx + i] {
                p.push(c, c, qp.soft_l2[i]);
                g[c] = qp.soft_l1[i];
            }
        }
        if k < n {
            for a in 0..nu {
                for b in a..nu {
                    p.push(lay.u(k, a), lay.u(k, b), qp.r[k][(a, b)]);
                }
                // S couples u_k (rows) and x_k (columns); x columns come
                // first, so the upper triangle holds (x, u) = S'.
                for i in 0..nx {
                    p.push(lay.x(k, i), lay.u(k, a), qp.s[k][(a, i)]);
                }
                g[lay.u(k, a)] = qp.r_lin[k][a];
            }
        }
    }
    (p, g)
}

/// Solves `qp` with clarabel (fresh set-up, tight tolerances).
pub fn clarabel_solve(qp: &OcpQp) -> Reference {
    clarabel_solve_with(qp, 1e-12)
}

/// Solves `qp` with clarabel at tolerance `tol` (gap and feasibility).
pub fn clarabel_solve_with(qp: &OcpQp, tol: f64) -> Reference {
    let lay = Layout::new(qp);
    let (nx, nu, n) = (lay.nx, lay.nu, lay.n);
    let (p, g) = cost(qp, &lay);
    let mut a = Triplets::default();
    let mut b = Vec::new();
    let mut row = 0;
    // Equalities: x_0 = x0, dynamics.
    for i in 0..nx {
        a.push(row, lay.x(0, i), 1.0);
        b.push(qp.x0[i]);
        row += 1;
    }
    for k in 0..n {
        for i in 0..nx {
            for j in 0..nx {
                a.push(row, lay.x(k, j), qp.a[k][(i, j)]);
            }
            for j in 0..nu {
                a.push(row, lay.u(k, j), qp.b[k][(i, j)]);
            }
            a.push(row, lay.x(k + 1, i), -1.0);
            b.push(-qp.c[k][i]);
            row += 1;
        }
    }
    let equalities = row;
    // Inequalities b - A z >= 0.
    for k in 0..n {
        for j in 0..nu {
            if qp.u_lower[k][j].is_finite() {
                a.push(row, lay.u(k, j), -1.0);
                b.push(-qp.u_lower[k][j]);
                row += 1;
            }
            if qp.u_upper[k][j].is_finite() {
                a.push(row, lay.u(k, j), 1.0);
                b.push(qp.u_upper[k][j]);
                row += 1;
            }
        }
    }
    for k in 1..=n {
        for i in 0..nx {
            let Some(s) = lay.slack[k * nx + i] else {
                continue;
            };
            if qp.x_lower[k][i].is_finite() {
                a.push(row, lay.x(k, i), -1.0);
                a.push(row, s, -1.0);
                b.push(-qp.x_lower[k][i]);
                row += 1;
            }
            if qp.x_upper[k][i].is_finite() {
                a.push(row, lay.x(k, i), 1.0);
                a.push(row, s, -1.0);
                b.push(qp.x_upper[k][i]);
                row += 1;
            }
            a.push(row, s, -1.0);
            b.push(0.0);
            row += 1;
        }
    }
    let cones = [ZeroConeT(equalities), NonnegativeConeT(row - equalities)];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(tol)
        .tol_gap_rel(tol)
        .tol_feas(tol)
        .tol_ktratio(tol.sqrt())
        .max_iter(200)
        .build()
        .expect("valid clarabel settings");
    let pm = p.csc(lay.total, lay.total);
    let am = a.csc(row, lay.total);
    let mut solver =
        DefaultSolver::new(&pm, &g, &am, &b, &cones, settings).expect("clarabel set-up");
    solver.solve();
    let sol = &solver.solution;
    let x = (0..=n)
        .map(|k| DVector::from_fn(nx, |i, _| sol.x[lay.x(k, i)]))
        .collect();
    let u = (0..n)
        .map(|k| DVector::from_fn(nu, |j, _| sol.x[lay.u(k, j)]))
        .collect();
    Reference {
        x,
        u,
        objective: sol.obj_val,
        solved: matches!(
            sol.status,
            SolverStatus::Solved | SolverStatus::AlmostSolved
        ),
        iterations: sol.iterations,
    }
}

/// Dense KKT solve (LU) of a QP without inequalities: returns the reference
/// and the dynamics multipliers `pi_k`.
pub fn dense_kkt_solve(qp: &OcpQp) -> (Reference, Vec<DVector<f64>>) {
    let lay = Layout::new(qp);
    assert_eq!(
        lay.total,
        (lay.n + 1) * lay.nx + lay.n * lay.nu,
        "no soft bounds"
    );
    let (nx, nu, n) = (lay.nx, lay.nu, lay.n);
    let nz = lay.total;
    let ne = (n + 1) * nx;
    let mut kkt = DMatrix::<f64>::zeros(nz + ne, nz + ne);
    let mut rhs = DVector::<f64>::zeros(nz + ne);
    let (p, g) = cost(qp, &lay);
    for ((&r, &c), &v) in p.rows.iter().zip(&p.cols).zip(&p.vals) {
        kkt[(r, c)] = v;
        kkt[(c, r)] = v;
    }
    for i in 0..nz {
        rhs[i] = -g[i];
    }
    // Constraint rows E z = e with the Lagrangian L = f + mu'(x_0 - x0) +
    // sum pi_k'(A x + B u + c - x_{k+1}).
    for i in 0..nx {
        let r = nz + i;
        kkt[(r, lay.x(0, i))] = 1.0;
        kkt[(lay.x(0, i), r)] = 1.0;
        rhs[r] = qp.x0[i];
    }
    for k in 0..n {
        for i in 0..nx {
            let r = nz + nx + k * nx + i;
            let mut set = |c: usize, v: f64| {
                kkt[(r, c)] = v;
                kkt[(c, r)] = v;
            };
            for j in 0..nx {
                set(lay.x(k, j), qp.a[k][(i, j)]);
            }
            for j in 0..nu {
                set(lay.u(k, j), qp.b[k][(i, j)]);
            }
            set(lay.x(k + 1, i), -1.0);
            rhs[r] = -qp.c[k][i];
        }
    }
    let z = kkt.lu().solve(&rhs).expect("nonsingular KKT matrix");
    let x: Vec<_> = (0..=n)
        .map(|k| DVector::from_fn(nx, |i, _| z[lay.x(k, i)]))
        .collect();
    let u: Vec<_> = (0..n)
        .map(|k| DVector::from_fn(nu, |j, _| z[lay.u(k, j)]))
        .collect();
    let pi = (0..n)
        .map(|k| DVector::from_fn(nx, |i, _| z[nz + nx + k * nx + i]))
        .collect();
    let objective = eigenmpc::qp::kkt::objective(qp, &x, &u);
    (
        Reference {
            x,
            u,
            objective,
            solved: true,
            iterations: 1,
        },
        pi,
    )
}
