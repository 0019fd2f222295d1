//! The preallocated iterate and workspace of a solve (sized at creation).

/// Flat, preallocated iterate and workspace (stage-major).
#[derive(Clone, Debug)]
pub(super) struct Workspace {
    // Iterate.
    pub(super) x: Vec<f64>,
    pub(super) u: Vec<f64>,
    pub(super) s: Vec<f64>,
    pub(super) pi: Vec<f64>,
    pub(super) t: Vec<f64>,
    pub(super) lam: Vec<f64>,
    /// Which inequality slots exist for the current data.
    pub(super) on: Vec<bool>,
    /// Which state components carry a soft bound.
    pub(super) soft: Vec<bool>,
    // Residuals.
    pub(super) rx: Vec<f64>,
    pub(super) ru: Vec<f64>,
    pub(super) rs: Vec<f64>,
    pub(super) re: Vec<f64>,
    pub(super) rp: Vec<f64>,
    /// Complementarity right-hand side (`t lam`, then the corrector's).
    pub(super) rc: Vec<f64>,
    // Stage-wise elimination of the slacks and of the inequalities.
    pub(super) diag_u: Vec<f64>,
    pub(super) diag_x: Vec<f64>,
    pub(super) cross: Vec<f64>,
    pub(super) hss: Vec<f64>,
    /// `2 Sigma_u + h` and `2 Sigma_l + h`: the slack-bound rows' direction
    /// `dx + ds` and `ds - dx` without cancellation.
    pub(super) coef_l: Vec<f64>,
    pub(super) coef_u: Vec<f64>,
    pub(super) gx: Vec<f64>,
    pub(super) gu: Vec<f64>,
    pub(super) gs: Vec<f64>,
    // Riccati factors: per stage the lower Cholesky factor of M_k (u first).
    pub(super) lm: Vec<f64>,
    pub(super) inv_diag: Vec<f64>,
    pub(super) p: Vec<f64>,
    pub(super) yu: Vec<f64>,
    pub(super) bal: Vec<f64>,
    pub(super) tmp_v: Vec<f64>,
    pub(super) tmp_w: Vec<f64>,
    pub(super) tmp_g: Vec<f64>,
    // Newton direction.
    pub(super) dx: Vec<f64>,
    pub(super) du: Vec<f64>,
    pub(super) ds: Vec<f64>,
    pub(super) dpi: Vec<f64>,
    pub(super) dt: Vec<f64>,
    pub(super) dlam: Vec<f64>,
}

impl Workspace {
    pub(super) fn new(nx: usize, nu: usize, n: usize) -> Self {
        let nv = nx + nu;
        let m = 2 * nu + 3 * nx;
        let z = |len: usize| vec![0.0; len];
        Self {
            x: z((n + 1) * nx),
            u: z(n * nu),
            s: z((n + 1) * nx),
            pi: z(n * nx),
            t: z((n + 1) * m),
            lam: z((n + 1) * m),
            on: vec![false; (n + 1) * m],
            soft: vec![false; (n + 1) * nx],
            rx: z((n + 1) * nx),
            ru: z(n * nu),
            rs: z((n + 1) * nx),
            re: z(n * nx),
            rp: z((n + 1) * m),
            rc: z((n + 1) * m),
            diag_u: z(n * nu),
            diag_x: z((n + 1) * nx),
            cross: z((n + 1) * nx),
            hss: z((n + 1) * nx),
            coef_l: z((n + 1) * nx),
            coef_u: z((n + 1) * nx),
            gx: z((n + 1) * nx),
            gu: z(n * nu),
            gs: z((n + 1) * nx),
            lm: z((n + 1) * nv * nv),
            inv_diag: z((n + 1) * nv),
            p: z((n + 1) * nx),
            yu: z(n * nu),
            bal: z(nv * nx),
            tmp_v: z(nx),
            tmp_w: z(nx),
            tmp_g: z(nv),
            dx: z((n + 1) * nx),
            du: z(n * nu),
            ds: z((n + 1) * nx),
            dpi: z(n * nx),
            dt: z((n + 1) * m),
            dlam: z((n + 1) * m),
        }
    }
}
