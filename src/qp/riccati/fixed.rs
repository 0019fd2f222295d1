//! Compile-time-sized core of the Riccati interior point for the common
//! chain sizes: the stage data is copied once per solve into contiguous
//! per-stage blocks of nalgebra static matrices, absent inequalities are
//! switched off by 0/1 masks instead of per-slot branches, and the passes
//! over the horizon are fused (gradient assembly into the backward sweep,
//! slack and multiplier recovery and the step-length ratio test into the
//! forward sweep). Same mathematics as the runtime-size core in the parent
//! module (see its documentation for the formulation).
//!
//! Slot layout of a stage's `M = 2 NU + 3 NX` inequalities: `u - u_lower`
//! (`0..NU`), `u_upper - u` (`NU..2NU`), `x + s - x_lower`, `x_upper + s - x`,
//! `s` (`NX` each).

// The kernels walk several parallel per-slot arrays by index: clearer than
// nested zips, and the constant bounds let the loops unroll.
#![allow(clippy::needless_range_loop)]

use super::{
    Core, Residuals, RiccatiInfo, RiccatiSettings, SYMMETRY_TOLERANCE, StartShift, add_slot,
    lower_bound_ok, recentred, upper_bound_ok,
};
use crate::qp::{OcpQp, QpSolution, StageQp};
use nalgebra::{SMatrix, SVector};

/// One stage's data as [`FixedCore::load_with`] reads it: column-major
/// slices of the stage's sizes.
struct StageData<'a> {
    q: &'a [f64],
    q_lin: &'a [f64],
    x_lower: &'a [f64],
    x_upper: &'a [f64],
    a: &'a [f64],
    b: &'a [f64],
    s: &'a [f64],
    r: &'a [f64],
    c: &'a [f64],
    r_lin: &'a [f64],
    u_lower: &'a [f64],
    u_upper: &'a [f64],
}

mod active_set;

use active_set::GuessStage;

type Mat<const R: usize, const C: usize> = SMatrix<f64, R, C>;
type Vecn<const R: usize> = SVector<f64, R>;

/// Data, iterate, residuals, factors and direction of one stage.
#[derive(Clone, Debug)]
struct Stage<const NX: usize, const NU: usize, const M: usize> {
    // Data (zero where a stage has no such block, e.g. `A_N`).
    a: Mat<NX, NX>,
    b: Mat<NX, NU>,
    c: Vecn<NX>,
    q: Mat<NX, NX>,
    s: Mat<NU, NX>,
    r: Mat<NU, NU>,
    ql: Vecn<NX>,
    rl: Vecn<NU>,
    /// Constraint offsets: slot value = `D z + off` (0 for absent slots).
    off: [f64; M],
    /// 1 for an existing slot, 0 otherwise.
    mask: [f64; M],
    /// 1 for a soft state component, 0 otherwise.
    soft: Vecn<NX>,
    // Iterate.
    x: Vecn<NX>,
    u: Vecn<NU>,
    sl: Vecn<NX>,
    pi: Vecn<NX>,
    t: [f64; M],
    lam: [f64; M],
    /// `1 / t` and `1 / lam` on existing slots, 0 elsewhere (set by
    /// `factor`: divisions are the slowest operations of the kernels).
    inv_t: [f64; M],
    inv_lam: [f64; M],
    // Residuals.
    ru: Vecn<NU>,
    re: Vecn<NX>,
    rx: Vecn<NX>,
    rs: Vecn<NX>,
    rp: [f64; M],
    rc: [f64; M],
    // Eliminated inequalities and slacks.
    diag_u: Vecn<NU>,
    diag_x: Vecn<NX>,
    cross: Vecn<NX>,
    hss: Vecn<NX>,
    inv_hss: Vecn<NX>,
    coef_l: Vecn<NX>,
    coef_u: Vecn<NX>,
    // Factor of M_k = [Luu 0; Lxu Lxx] [Luu 0; Lxu Lxx]'.
    luu: Mat<NU, NU>,
    lxu: Mat<NX, NU>,
    lxx: Mat<NX, NX>,
    inv_u: Vecn<NU>,
    // Newton direction.
    gu: Vecn<NU>,
    gx: Vecn<NX>,
    gs: Vecn<NX>,
    p: Vecn<NX>,
    yu: Vecn<NU>,
    dx: Vecn<NX>,
    du: Vecn<NU>,
    ds: Vecn<NX>,
    dpi: Vecn<NX>,
    dt: [f64; M],
    dlam: [f64; M],
}

impl<const NX: usize, const NU: usize, const M: usize> Stage<NX, NU, M> {
    fn zeroed() -> Self {
        let (m0, mx, vx, vu) = ([0.0; M], Mat::zeros(), Vecn::zeros(), Vecn::zeros());
        Self {
            a: mx,
            b: Mat::zeros(),
            c: vx,
            q: mx,
            s: Mat::zeros(),
            r: Mat::zeros(),
            ql: vx,
            rl: vu,
            off: m0,
            mask: m0,
            soft: vx,
            x: vx,
            u: vu,
            sl: vx,
            pi: vx,
            t: m0,
            lam: m0,
            inv_t: m0,
            inv_lam: m0,
            ru: vu,
            re: vx,
            rx: vx,
            rs: vx,
            rp: m0,
            rc: m0,
            diag_u: vu,
            diag_x: vx,
            cross: vx,
            hss: vx,
            inv_hss: vx,
            coef_l: vx,
            coef_u: vx,
            luu: Mat::zeros(),
            lxu: Mat::zeros(),
            lxx: mx,
            inv_u: vu,
            gu: vu,
            gx: vx,
            gs: vx,
            p: vx,
            yu: vu,
            dx: vx,
            du: vu,
            ds: vx,
            dpi: vx,
            dt: m0,
            dlam: m0,
        }
    }

    /// Slot values `D z + off` at the current iterate.
    #[inline(always)]
    fn constraint_values(&self) -> [f64; M] {
        let mut v = [0.0; M];
        for j in 0..NU {
            v[j] = self.u[j] + self.off[j];
            v[NU + j] = self.off[NU + j] - self.u[j];
        }
        for i in 0..NX {
            let (x, s) = (self.x[i], self.sl[i]);
            v[2 * NU + i] = x + s + self.off[2 * NU + i];
            v[2 * NU + NX + i] = s - x + self.off[2 * NU + NX + i];
            v[2 * NU + 2 * NX + i] = s;
        }
        v
    }

    /// `w = (rc + lam rp) / t` on existing slots (the Newton system's
    /// inequality term of the gradient).
    #[inline(always)]
    fn slot_gradient(&self) -> [f64; M] {
        let mut w = [0.0; M];
        for i in 0..M {
            w[i] = (self.rc[i] + self.lam[i] * self.rp[i]) * self.inv_t[i];
        }
        w
    }

    /// Slack and multiplier directions of the inequalities from `dx`, `du`
    /// (and `gs`); returns the smallest ratio `-v / dv` over decreasing
    /// slacks and multipliers, accumulated per slot into `decrease` (the
    /// largest relative decrease `-dv / v`; its inverse is the ratio).
    /// Per-slot accumulators keep the maximum from being one serial chain
    /// of dependent comparisons over the whole horizon.
    #[inline(always)]
    fn recover(&mut self, decrease: &mut [f64; M]) {
        let inv_hss = self.inv_hss;
        let mut dc = [0.0; M];
        for j in 0..NU {
            dc[j] = self.du[j];
            dc[NU + j] = -self.du[j];
        }
        for i in 0..NX {
            // dx + ds and ds - dx formed without cancelling the large terms
            // of an active bound (they must be accurate relative to t).
            let (dx, gs, h) = (self.dx[i], self.gs[i], inv_hss[i]);
            let ds = -(gs + self.cross[i] * dx) * h;
            self.ds[i] = ds;
            dc[2 * NU + i] = (self.coef_l[i] * dx - gs) * h;
            dc[2 * NU + NX + i] = (-self.coef_u[i] * dx - gs) * h;
            dc[2 * NU + 2 * NX + i] = ds;
        }
        for i in 0..M {
            let dt = self.mask[i] * (dc[i] + self.rp[i]);
            let dlam = -(self.rc[i] + self.lam[i] * dt) * self.inv_t[i];
            self.dt[i] = dt;
            self.dlam[i] = dlam;
            decrease[i] = fmax(
                fmax(decrease[i], -dt * self.inv_t[i]),
                -dlam * self.inv_lam[i],
            );
        }
    }
}

/// Workspace and iterate of the compile-time-sized core (allocated once).
#[derive(Clone, Debug)]
pub(super) struct FixedCore<const NX: usize, const NU: usize, const M: usize> {
    st: Vec<Stage<NX, NU, M>>,
    n: usize,
    l1: Vecn<NX>,
    l2: Vecn<NX>,
    x0: Vecn<NX>,
    /// Number of existing inequality slots.
    m_on: usize,
    /// Smallest step ratio of the last direction.
    ratio: f64,
    set: RiccatiSettings,
    pub(super) info: RiccatiInfo,
    /// Start the next solve from the shifted previous multipliers.
    pub(super) warm: bool,
    /// Some state component has a soft bound (no active-set start).
    soft_any: bool,
    /// Per stage: the costates kept aside while the active-set start runs
    /// (with the untouched multipliers, the interior point's warm start
    /// when it fails).
    kept: Vec<Vecn<NX>>,
    /// Per stage: the active-set start's guess, policy and cost-to-go.
    guess: Vec<GuessStage<NX, NU>>,
    /// The controls' stationarity scale of the active-set start's last sweep.
    guess_scale: f64,
}

impl<const NX: usize, const NU: usize, const M: usize> FixedCore<NX, NU, M> {
    pub(super) fn new(horizon: usize) -> Self {
        assert_eq!(M, 2 * NU + 3 * NX, "slot count of the fixed core");
        Self {
            st: vec![Stage::zeroed(); horizon + 1],
            n: horizon,
            l1: Vecn::zeros(),
            l2: Vecn::zeros(),
            x0: Vecn::zeros(),
            m_on: 0,
            ratio: f64::INFINITY,
            set: RiccatiSettings::default(),
            info: RiccatiInfo::default(),
            warm: false,
            soft_any: false,
            kept: vec![Vecn::zeros(); horizon + 1],
            guess: vec![GuessStage::new(); horizon + 1],
            guess_scale: 0.0,
        }
    }

    /// The multipliers a warm start reads (`pi`, `lam` per stage), appended to `out`.
    pub(super) fn save_multipliers(&self, out: &mut Vec<f64>) {
        for st in &self.st {
            out.extend_from_slice(st.pi.as_slice());
            out.extend_from_slice(&st.lam);
        }
    }

    /// Restores what [`FixedCore::save_multipliers`] wrote; false if the
    /// length does not fit this core.
    pub(super) fn restore_multipliers(&mut self, data: &[f64]) -> bool {
        let per = NX + M;
        if data.len() != per * self.st.len() {
            return false;
        }
        for (st, d) in self.st.iter_mut().zip(data.chunks_exact(per)) {
            st.pi.as_mut_slice().copy_from_slice(&d[..NX]);
            st.lam.copy_from_slice(&d[NX..]);
        }
        true
    }

    /// Copies the QP (of checked dimensions) into the stage blocks and
    /// marks the existing inequalities, checking the data on the way (one
    /// pass instead of a separate validation): false, and nothing to solve,
    /// for a non-finite entry, a NaN or wrong-way infinite bound, crossed
    /// control bounds, a negative penalty or an asymmetric `Q` or `R` (the
    /// same rules as the runtime-size core's `valid_data`).
    pub(super) fn load(&mut self, qp: &OcpQp, set: &RiccatiSettings) -> bool {
        self.load_with(
            qp.soft_l1.as_slice(),
            qp.soft_l2.as_slice(),
            qp.x0.as_slice(),
            set,
            |k| {
                // The last stage has no control or dynamics blocks.
                fn pick(v: &[nalgebra::DMatrix<f64>], k: usize) -> &[f64] {
                    v.get(k).map_or(&[], |m| m.as_slice())
                }
                fn pick_v(v: &[nalgebra::DVector<f64>], k: usize) -> &[f64] {
                    v.get(k).map_or(&[], |m| m.as_slice())
                }
                StageData {
                    q: qp.q[k].as_slice(),
                    q_lin: qp.q_lin[k].as_slice(),
                    x_lower: qp.x_lower[k].as_slice(),
                    x_upper: qp.x_upper[k].as_slice(),
                    a: pick(&qp.a, k),
                    b: pick(&qp.b, k),
                    s: pick(&qp.s, k),
                    r: pick(&qp.r, k),
                    c: pick_v(&qp.c, k),
                    r_lin: pick_v(&qp.r_lin, k),
                    u_lower: pick_v(&qp.u_lower, k),
                    u_upper: pick_v(&qp.u_upper, k),
                }
            },
        )
    }

    /// [`FixedCore::load`] from the stage-wise form of the same sizes (no
    /// dimension checks: the types hold them; false for another horizon).
    pub(super) fn load_stages(&mut self, qp: &StageQp<NX, NU>, set: &RiccatiSettings) -> bool {
        if qp.stages.len() != self.st.len() {
            return false;
        }
        self.load_with(
            qp.soft_l1.as_slice(),
            qp.soft_l2.as_slice(),
            qp.x0.as_slice(),
            set,
            |k| {
                let st = &qp.stages[k];
                StageData {
                    q: st.q.as_slice(),
                    q_lin: st.q_lin.as_slice(),
                    x_lower: st.x_lower.as_slice(),
                    x_upper: st.x_upper.as_slice(),
                    a: st.a.as_slice(),
                    b: st.b.as_slice(),
                    s: st.s.as_slice(),
                    r: st.r.as_slice(),
                    c: st.c.as_slice(),
                    r_lin: st.r_lin.as_slice(),
                    u_lower: st.u_lower.as_slice(),
                    u_upper: st.u_upper.as_slice(),
                }
            },
        )
    }

    /// The loader of [`FixedCore::load`] and [`FixedCore::load_stages`]:
    /// `stage(k)` gives stage `k`'s data (its control and dynamics slices
    /// are read for `k < N` only).
    #[inline(always)]
    fn load_with<'a>(
        &mut self,
        l1: &[f64],
        l2: &[f64],
        x0: &[f64],
        set: &RiccatiSettings,
        stage: impl Fn(usize) -> StageData<'a>,
    ) -> bool {
        let n = self.n;
        self.set = *set;
        self.info = RiccatiInfo::default();
        // Four lanes of NaN probes keep the sums independent chains; each
        // lane by a constant index, so that they stay in registers (lanes
        // indexed `i & 3` went through memory for the 6 x 6 blocks of three
        // links: a store and a reload per value, 4 % of the sample's time).
        let mut probe = [0.0f64; 4];
        let mut tail = 0.0;
        let mut copy = |dst: &mut [f64], src: &[f64]| {
            dst.copy_from_slice(src);
            let quads = src.chunks_exact(4);
            for &v in quads.remainder() {
                tail += nan_probe(v);
            }
            for quad in quads {
                probe[0] += nan_probe(quad[0]);
                probe[1] += nan_probe(quad[1]);
                probe[2] += nan_probe(quad[2]);
                probe[3] += nan_probe(quad[3]);
            }
        };
        copy(self.l1.as_mut_slice(), l1);
        copy(self.l2.as_mut_slice(), l2);
        copy(self.x0.as_mut_slice(), x0);
        let mut ok = self.l1.iter().chain(self.l2.iter()).all(|&w| w >= 0.0);
        // A bound whose weights are both zero costs nothing to violate:
        // ignored (as in the KKT checker).
        let weighted: [bool; NX] = std::array::from_fn(|i| self.l1[i] > 0.0 || self.l2[i] > 0.0);
        let any_weighted = weighted.iter().any(|&w| w);
        let mut m_on = 0.0;
        self.soft_any = false;
        for (k, st) in self.st.iter_mut().enumerate() {
            let data = stage(k);
            copy(st.q.as_mut_slice(), data.q);
            copy(st.ql.as_mut_slice(), data.q_lin);
            ok &= symmetric(&st.q);
            st.mask = [0.0; M];
            st.off = [0.0; M];
            if k < n {
                copy(st.a.as_mut_slice(), data.a);
                copy(st.b.as_mut_slice(), data.b);
                copy(st.c.as_mut_slice(), data.c);
                copy(st.s.as_mut_slice(), data.s);
                copy(st.r.as_mut_slice(), data.r);
                copy(st.rl.as_mut_slice(), data.r_lin);
                ok &= symmetric(&st.r);
                let (lo, hi) = (data.u_lower, data.u_upper);
                for j in 0..NU {
                    ok &= lower_bound_ok(lo[j]) && upper_bound_ok(hi[j]) && lo[j] <= hi[j];
                    if lo[j].is_finite() {
                        st.mask[j] = 1.0;
                        st.off[j] = -lo[j];
                    }
                    if hi[j].is_finite() {
                        st.mask[NU + j] = 1.0;
                        st.off[NU + j] = hi[j];
                    }
                }
            }
            st.soft = Vecn::zeros();
            // x_0 is fixed: its bounds are ignored, but must be valid too.
            let (lo, hi) = (data.x_lower, data.x_upper);
            for i in 0..NX {
                ok &= lower_bound_ok(lo[i]) && upper_bound_ok(hi[i]);
            }
            if k >= 1 && any_weighted {
                for i in 0..NX {
                    let (fl, fh) = (lo[i].is_finite(), hi[i].is_finite());
                    if weighted[i] && (fl || fh) {
                        self.soft_any = true;
                        st.soft[i] = 1.0;
                        st.mask[2 * NU + 2 * NX + i] = 1.0;
                        if fl {
                            st.mask[2 * NU + i] = 1.0;
                            st.off[2 * NU + i] = -lo[i];
                        }
                        if fh {
                            st.mask[2 * NU + NX + i] = 1.0;
                            st.off[2 * NU + NX + i] = hi[i];
                        }
                    }
                }
            }
            m_on += st.mask.iter().sum::<f64>();
        }
        self.m_on = m_on as usize;
        ok && probe.iter().sum::<f64>() + tail == 0.0
    }

    /// Lower Cholesky factor in place with the parent module's pivot rules:
    /// pivots not clearly positive are lifted by `lift` (control block) or,
    /// with `lift = None`, truncated to a zero column (state block).
    /// `diag` holds the original diagonal for the relative pivot threshold.
    /// Returns the number of lifted or truncated pivots.
    #[inline(always)]
    fn cholesky<const D: usize>(
        m: &mut Mat<D, D>,
        inv: &mut Vecn<D>,
        diag: &Vecn<D>,
        lift: Option<f64>,
        tol: f64,
    ) -> usize {
        let mut count = 0;
        for j in 0..D {
            let mut djj = m[(j, j)];
            for c in 0..j {
                djj -= m[(j, c)] * m[(j, c)];
            }
            let threshold = tol * diag[j].abs().max(f64::MIN_POSITIVE);
            if djj.is_nan() || djj <= threshold {
                count += 1;
                match lift {
                    Some(l) => djj = djj.max(0.0) + l,
                    None => {
                        for i in j..D {
                            m[(i, j)] = 0.0;
                            m[(j, i)] = 0.0;
                        }
                        inv[j] = 0.0;
                        continue;
                    }
                }
            }
            // sqrt(d) and 1/d issue in parallel (1/sqrt(d) would chain the
            // division after the square root): the factorisation is a serial
            // chain over pivots and stages, bound by their latency.
            let inv_d = 1.0 / djj;
            let ljj = djj.sqrt();
            let r = ljj * inv_d;
            m[(j, j)] = ljj;
            // The factor is used as a full matrix: clear the upper triangle.
            for c in j + 1..D {
                m[(j, c)] = 0.0;
            }
            inv[j] = r;
            for i in j + 1..D {
                let mut v = m[(i, j)];
                for c in 0..j {
                    v -= m[(i, c)] * m[(j, c)];
                }
                m[(i, j)] = v * r;
            }
        }
        count
    }
}

/// Maximum by one comparison (`f64::max` spends several instructions on
/// NaN rules; NaN is detected separately with [`nan_probe`]).
#[inline(always)]
fn fmax(a: f64, b: f64) -> f64 {
    if b > a { b } else { a }
}

/// 0 for a finite `v`, NaN otherwise: summed over the residuals it tells
/// whether any of them is not finite.
#[inline(always)]
fn nan_probe(v: f64) -> f64 {
    v * 0.0
}

/// A Hessian block symmetric to round-off (the kernels read its lower
/// triangle): as the runtime-size core's check, relative to its largest
/// entry. Not finite entries are left to the NaN probe.
#[inline(always)]
fn symmetric<const D: usize>(m: &Mat<D, D>) -> bool {
    // The common case first: an exactly symmetric block (a Gauss-Newton
    // `J' W J` is), one comparison a pair and no scale.
    let mut exact = true;
    for j in 0..D {
        for i in j + 1..D {
            exact &= m[(i, j)] == m[(j, i)];
        }
    }
    if exact {
        return true;
    }
    let (mut scale, mut asym) = (0.0f64, 0.0f64);
    for j in 0..D {
        for i in 0..D {
            scale = fmax(scale, m[(i, j)].abs());
        }
        for i in j + 1..D {
            asym = fmax(asym, (m[(i, j)] - m[(j, i)]).abs());
        }
    }
    asym <= SYMMETRY_TOLERANCE * scale
}

/// `L (L' v) + p` for a lower-triangular `L` (the cost-to-go Hessian times
/// `v`, plus `p`); full-range loops over the zero upper triangle unroll.
#[inline(always)]
fn llt_mul<const NX: usize>(l: &Mat<NX, NX>, v: &Vecn<NX>, p: &Vecn<NX>) -> Vecn<NX> {
    let mut w = Vecn::<NX>::zeros();
    for c in 0..NX {
        let mut s = 0.0;
        for i in 0..NX {
            s += l[(i, c)] * v[i];
        }
        w[c] = s;
    }
    let mut out = *p;
    for i in 0..NX {
        for c in 0..NX {
            out[i] += l[(i, c)] * w[c];
        }
    }
    out
}

impl<const NX: usize, const NU: usize, const M: usize> Core for FixedCore<NX, NU, M> {
    fn info_mut(&mut self) -> &mut RiccatiInfo {
        &mut self.info
    }

    fn initialise(&mut self) {
        let n = self.n;
        let t0 = self.set.initial_slack;
        // Multipliers on the scale of the cost gradient: too small ones let
        // the first steps run far out of the box and stall.
        let mut lam0 = 1.0f64;
        for st in &self.st {
            lam0 = lam0.max(st.ql.amax()).max(st.rl.amax());
        }
        lam0 *= self.set.initial_multiplier;
        let warm = self.warm;
        let floor = self.set.warm_start_floor;
        if warm {
            // RTI: the new QP is the previous one shifted by one stage; the
            // last stage keeps its multipliers. The primal start stays the
            // plain one (in step variables the shifted solution is ~0).
            for k in 0..n {
                self.st[k].pi = self.st[k + 1].pi;
                self.st[k].lam = self.st[k + 1].lam;
            }
        }
        self.st[0].x = self.x0;
        for k in 0..=n {
            let st = &mut self.st[k];
            if !warm {
                st.pi = Vecn::zeros();
            }
            st.sl = Vecn::zeros();
            st.u = Vecn::zeros();
            if k < n {
                for j in 0..NU {
                    let (lo, hi) = (st.mask[j] > 0.0, st.mask[NU + j] > 0.0);
                    let (l, h) = (-st.off[j], st.off[NU + j]);
                    st.u[j] = match (lo, hi) {
                        (true, true) => 0.5 * (l + h),
                        (true, false) => l.max(0.0),
                        (false, true) => h.min(0.0),
                        (false, false) => 0.0,
                    };
                }
                // Simulate so the dynamics hold at the start.
                let next = st.a * st.x + st.b * st.u + st.c;
                self.st[k + 1].x = next;
            }
            let st = &mut self.st[k];
            if k >= 1 {
                for i in 0..NX {
                    if st.soft[i] > 0.0 {
                        let xv = st.x[i];
                        let mut viol = 0.0f64;
                        if st.mask[2 * NU + i] > 0.0 {
                            viol = viol.max(-st.off[2 * NU + i] - xv);
                        }
                        if st.mask[2 * NU + NX + i] > 0.0 {
                            viol = viol.max(xv - st.off[2 * NU + NX + i]);
                        }
                        st.sl[i] = viol + t0;
                    }
                }
            }
            let cv = st.constraint_values();
            for i in 0..M {
                if st.mask[i] > 0.0 && warm {
                    st.t[i] = cv[i].max(floor);
                    st.lam[i] = st.lam[i].max(floor);
                } else if st.mask[i] > 0.0 {
                    st.t[i] = cv[i].max(t0);
                    st.lam[i] = lam0 / st.t[i];
                } else {
                    st.t[i] = 1.0;
                    st.lam[i] = 0.0;
                }
            }
        }
    }

    fn residuals(&mut self) -> Residuals {
        let n = self.n;
        // Per-component accumulators (maxima, sums and NaN probes): the
        // reductions are independent chains instead of one long chain of
        // dependent operations over the horizon.
        let (mut stat_u, mut scale_u, mut probe_u) = ([0.0f64; NU], [0.0f64; NU], [0.0; NU]);
        let (mut stat_x, mut scale_x, mut probe_x) = ([0.0f64; NX], [0.0f64; NX], [0.0; NX]);
        let (mut feas_x, mut probe_e) = ([0.0f64; NX], [0.0; NX]);
        let (mut feas, mut gap, mut comp) = ([0.0f64; M], [0.0; M], [0.0f64; M]);
        let (l1, l2) = (self.l1, self.l2);
        for k in 0..=n {
            let pi_prev = if k > 0 {
                self.st[k - 1].pi
            } else {
                Vecn::zeros()
            };
            let x_next = if k < n {
                self.st[k + 1].x
            } else {
                Vecn::zeros()
            };
            let st = &mut self.st[k];
            let (ll, lu) = (&st.lam[..NU], &st.lam[NU..2 * NU]);
            if k < n {
                let h = st.r * st.u + st.s * st.x;
                let e = st.b.tr_mul(&st.pi);
                for j in 0..NU {
                    let v = st.rl[j] + h[j] + e[j] - ll[j] + lu[j];
                    let terms = fmax(fmax(st.rl[j].abs(), h[j].abs()), e[j].abs());
                    scale_u[j] = fmax(scale_u[j], fmax(terms, fmax(ll[j], lu[j])));
                    st.ru[j] = v;
                    stat_u[j] = fmax(stat_u[j], v.abs());
                    probe_u[j] += nan_probe(v);
                }
                st.re = st.a * st.x + st.b * st.u + st.c - x_next;
                for i in 0..NX {
                    feas_x[i] = fmax(feas_x[i], st.re[i].abs());
                    probe_e[i] += nan_probe(st.re[i]);
                }
            }
            if k >= 1 {
                // x_0 is fixed: its row is not a condition.
                let h = st.q * st.x + st.s.tr_mul(&st.u);
                let e = st.a.tr_mul(&st.pi);
                let (xl, xu, xs) = (
                    &st.lam[2 * NU..2 * NU + NX],
                    &st.lam[2 * NU + NX..2 * NU + 2 * NX],
                    &st.lam[2 * NU + 2 * NX..],
                );
                for i in 0..NX {
                    let prev = pi_prev[i];
                    let v = st.ql[i] + h[i] + e[i] - prev - xl[i] + xu[i];
                    let terms = fmax(fmax(st.ql[i].abs(), h[i].abs()), e[i].abs());
                    scale_x[i] = fmax(
                        scale_x[i],
                        fmax(fmax(terms, prev.abs()), fmax(xl[i], xu[i])),
                    );
                    st.rx[i] = v;
                    let w = st.soft[i] * (l1[i] + l2[i] * st.sl[i] - xl[i] - xu[i] - xs[i]);
                    st.rs[i] = w;
                    stat_x[i] = fmax(stat_x[i], fmax(v.abs(), w.abs()));
                    probe_x[i] += nan_probe(v) + nan_probe(w);
                }
            }
            let cv = st.constraint_values();
            for i in 0..M {
                let r = st.mask[i] * (cv[i] - st.t[i]);
                st.rp[i] = r;
                feas[i] = fmax(feas[i], r.abs());
                let tl = st.t[i] * st.lam[i];
                gap[i] += tl;
                comp[i] = fmax(comp[i], tl);
            }
        }
        let max = |v: &[f64]| v.iter().fold(0.0, |a, &b| fmax(a, b));
        let sum = |v: &[f64]| v.iter().sum::<f64>();
        let probe = sum(&probe_u) + sum(&probe_x) + sum(&probe_e);
        let gap = sum(&gap);
        Residuals {
            // NaN anywhere makes the residual NaN (the iteration stops).
            stationarity: fmax(max(&stat_u), max(&stat_x)) + probe,
            scale: fmax(max(&scale_u), max(&scale_x)),
            feasibility: fmax(max(&feas_x), max(&feas)),
            complementarity: max(&comp),
            mu: if self.m_on > 0 {
                gap / self.m_on as f64
            } else {
                0.0
            },
        }
    }

    fn factor(&mut self) {
        let n = self.n;
        let set = self.set;
        let l2 = self.l2;
        let (mut regularised, mut truncated) = (0, 0);
        for k in (0..=n).rev() {
            let lnext = if k < n {
                self.st[k + 1].lxx
            } else {
                Mat::zeros()
            };
            let st = &mut self.st[k];
            let mut sig = [0.0; M];
            for i in 0..M {
                // One division per slot: 1/t = lam/(t lam), 1/lam = t/(t lam)
                // (divisions bound the throughput of this loop); absent slots
                // (t = 1, lam = 0, mask 0) get 0.
                let (t, lam, on) = (st.t[i], st.lam[i], st.mask[i]);
                let inv_tl = on / (t * lam + (1.0 - on));
                st.inv_t[i] = lam * inv_tl;
                st.inv_lam[i] = t * inv_tl;
                sig[i] = lam * st.inv_t[i];
            }
            for j in 0..NU {
                st.diag_u[j] = sig[j] + sig[NU + j];
            }
            for i in 0..NX {
                if st.soft[i] > 0.0 {
                    let a = sig[2 * NU + i];
                    let b = sig[2 * NU + NX + i];
                    let h = l2[i] + sig[2 * NU + 2 * NX + i];
                    let hss = a + b + h;
                    st.hss[i] = hss;
                    st.inv_hss[i] = 1.0 / hss;
                    st.cross[i] = a - b;
                    st.coef_l[i] = 2.0 * b + h;
                    st.coef_u[i] = 2.0 * a + h;
                    // (a + b) - (a - b)^2 / (a + b + h) without cancellation.
                    st.diag_x[i] = (4.0 * a * b + (a + b) * h) / hss;
                } else {
                    st.hss[i] = 1.0;
                    st.inv_hss[i] = 1.0;
                    st.cross[i] = 0.0;
                    st.coef_l[i] = 0.0;
                    st.coef_u[i] = 0.0;
                    st.diag_x[i] = 0.0;
                }
            }
            let mut inv_x = Vecn::<NX>::zeros();
            if k == n {
                // Terminal stage: P_N = Q_N + diag.
                let mut mxx = st.q;
                for i in 0..NX {
                    mxx[(i, i)] += st.diag_x[i];
                }
                let diag = mxx.diagonal();
                truncated += Self::cholesky(&mut mxx, &mut inv_x, &diag, None, set.pivot_tolerance);
                st.lxx = mxx;
                continue;
            }
            // M = [R S; S' Q] + diag + W'W with W = L' [B A], written as
            // full-range fixed loops (the upper triangle of L is zero): a
            // triangular loop nest does not unroll and costs more than the
            // multiplications by zero it saves. At k = 0 only the control
            // block is needed (x_0 is fixed).
            let mut wb = Mat::<NX, NU>::zeros();
            let mut wa = Mat::<NX, NX>::zeros();
            for i in 0..NX {
                for r in 0..NX {
                    let l = lnext[(r, i)];
                    for j in 0..NU {
                        wb[(i, j)] += l * st.b[(r, j)];
                    }
                }
            }
            let mut muu = st.r;
            for j in 0..NU {
                for c in 0..NU {
                    let mut v = muu[(j, c)];
                    for i in 0..NX {
                        v += wb[(i, j)] * wb[(i, c)];
                    }
                    muu[(j, c)] = v;
                }
                muu[(j, j)] += st.diag_u[j];
            }
            let du = muu.diagonal();
            let (mut mxx, mut mxu, dx) = if k > 0 {
                for i in 0..NX {
                    for r in 0..NX {
                        let l = lnext[(r, i)];
                        for j in 0..NX {
                            wa[(i, j)] += l * st.a[(r, j)];
                        }
                    }
                }
                let mut mxx = st.q;
                for j in 0..NX {
                    for c in 0..NX {
                        let mut v = mxx[(j, c)];
                        for i in 0..NX {
                            v += wa[(i, j)] * wa[(i, c)];
                        }
                        mxx[(j, c)] = v;
                    }
                    mxx[(j, j)] += st.diag_x[j];
                }
                let mut mxu = Mat::<NX, NU>::zeros();
                for j in 0..NU {
                    for i in 0..NX {
                        let mut v = st.s[(j, i)];
                        for r in 0..NX {
                            v += wa[(r, i)] * wb[(r, j)];
                        }
                        mxu[(i, j)] = v;
                    }
                }
                let dx = mxx.diagonal();
                (mxx, mxu, dx)
            } else {
                (Mat::zeros(), Mat::zeros(), Vecn::zeros())
            };
            let mut scale = du.max();
            if k > 0 {
                scale = scale.max(dx.max());
            }
            if scale.is_nan() || scale <= 0.0 {
                scale = 1.0;
            }
            regularised += Self::cholesky(
                &mut muu,
                &mut st.inv_u,
                &du,
                Some(set.regularisation * scale),
                set.pivot_tolerance,
            );
            st.luu = muu;
            if k > 0 {
                // Lxu = Mxu Luu^{-T}, then the Schur complement's factor.
                for j in 0..NU {
                    for c in 0..j {
                        let l = muu[(j, c)];
                        for i in 0..NX {
                            mxu[(i, j)] -= mxu[(i, c)] * l;
                        }
                    }
                    let r = st.inv_u[j];
                    for i in 0..NX {
                        mxu[(i, j)] *= r;
                    }
                }
                for j in 0..NX {
                    for c in 0..NX {
                        let mut v = mxx[(j, c)];
                        for i in 0..NU {
                            v -= mxu[(j, i)] * mxu[(c, i)];
                        }
                        mxx[(j, c)] = v;
                    }
                }
                truncated += Self::cholesky(&mut mxx, &mut inv_x, &dx, None, set.pivot_tolerance);
                st.lxu = mxu;
                st.lxx = mxx;
            }
        }
        self.info.regularised_pivots += regularised;
        self.info.truncated_pivots += truncated;
    }

    fn prepare_affine(&mut self) -> usize {
        for st in &mut self.st {
            for i in 0..M {
                st.rc[i] = st.t[i] * st.lam[i];
            }
        }
        self.m_on
    }

    fn prepare_corrector(&mut self, sigma_mu: f64) {
        for st in &mut self.st {
            for i in 0..M {
                st.rc[i] = st.mask[i] * (st.t[i] * st.lam[i] + st.dt[i] * st.dlam[i] - sigma_mu);
            }
        }
    }

    fn newton_direction(&mut self) {
        let n = self.n;
        // Backward sweep with the gradient assembly: p_N = g_N; p_k = g_x +
        // A' v - Lxu yu with v = P_{k+1} c_k + p_{k+1}, yu = Luu^{-1} (g_u + B' v).
        let mut p_next = Vecn::<NX>::zeros();
        let mut l_next = Mat::<NX, NX>::zeros();
        for k in (0..=n).rev() {
            let st = &mut self.st[k];
            let w = st.slot_gradient();
            for j in 0..NU {
                st.gu[j] = st.ru[j] + w[j] - w[NU + j];
            }
            for i in 0..NX {
                let (wl, wu) = (w[2 * NU + i], w[2 * NU + NX + i]);
                let gs = st.soft[i] * (st.rs[i] + wl + wu + w[2 * NU + 2 * NX + i]);
                st.gs[i] = gs;
                st.gx[i] = st.rx[i] + wl - wu - st.cross[i] * gs * st.inv_hss[i];
            }
            if k == n {
                st.p = st.gx;
            } else {
                let v = llt_mul(&l_next, &st.re, &p_next);
                for j in 0..NU {
                    let mut y = st.gu[j];
                    for i in 0..NX {
                        y += st.b[(i, j)] * v[i];
                    }
                    for c in 0..j {
                        y -= st.luu[(j, c)] * st.yu[c];
                    }
                    st.yu[j] = y * st.inv_u[j];
                }
                if k > 0 {
                    for i in 0..NX {
                        let mut p = st.gx[i];
                        for r in 0..NX {
                            p += st.a[(r, i)] * v[r];
                        }
                        for j in 0..NU {
                            p -= st.lxu[(i, j)] * st.yu[j];
                        }
                        st.p[i] = p;
                    }
                }
            }
            p_next = st.p;
            l_next = st.lxx;
        }
        // Forward sweep with the recovery of the inequality directions.
        let mut decrease = [0.0f64; M];
        let mut dx = Vecn::<NX>::zeros();
        for k in 0..=n {
            let (head, tail) = self.st.split_at_mut(k + 1);
            let st = &mut head[k];
            st.dx = dx;
            if k < n {
                // du = -Luu^{-T} (Lxu' dx + yu)
                for j in (0..NU).rev() {
                    let mut v = st.yu[j];
                    for i in 0..NX {
                        v += st.lxu[(i, j)] * dx[i];
                    }
                    for c in j + 1..NU {
                        v += st.luu[(c, j)] * st.du[c];
                    }
                    st.du[j] = -v * st.inv_u[j];
                }
                let mut dn = st.re;
                for j in 0..NX {
                    let d = dx[j];
                    for i in 0..NX {
                        dn[i] += st.a[(i, j)] * d;
                    }
                }
                for j in 0..NU {
                    let d = st.du[j];
                    for i in 0..NX {
                        dn[i] += st.b[(i, j)] * d;
                    }
                }
                dx = dn;
                let next = &tail[0];
                st.dpi = llt_mul(&next.lxx, &dx, &next.p);
            }
            st.recover(&mut decrease);
        }
        self.ratio = 1.0 / decrease.iter().fold(0.0, |a, &d| fmax(a, d));
    }

    fn max_step(&self, fraction: f64) -> f64 {
        (fraction * self.ratio).min(1.0)
    }

    fn gap_after(&self, alpha: f64) -> f64 {
        // One partial sum per slot: independent chains instead of one.
        let mut gap = [0.0; M];
        for st in &self.st {
            for i in 0..M {
                gap[i] += (st.t[i] + alpha * st.dt[i]) * (st.lam[i] + alpha * st.dlam[i]);
            }
        }
        gap.iter().sum()
    }

    fn take_step(&mut self, alpha: f64) {
        for (k, st) in self.st.iter_mut().enumerate() {
            if k > 0 {
                st.x += alpha * st.dx;
            }
            st.u += alpha * st.du;
            st.sl += alpha * st.ds;
            st.pi += alpha * st.dpi;
            for i in 0..M {
                st.t[i] += alpha * st.dt[i];
                st.lam[i] += alpha * st.dlam[i];
            }
        }
    }

    fn write_solution(&self, sol: &mut QpSolution) {
        let n = self.n;
        let (l1, l2) = (self.l1, self.l2);
        let mut obj = 0.0;
        for (k, st) in self.st.iter().enumerate() {
            sol.x[k].as_mut_slice().copy_from_slice(st.x.as_slice());
            obj += 0.5 * st.x.dot(&(st.q * st.x)) + st.ql.dot(&st.x);
            if k < n {
                sol.u[k].as_mut_slice().copy_from_slice(st.u.as_slice());
                sol.pi[k].as_mut_slice().copy_from_slice(st.pi.as_slice());
                sol.lam_u_lower[k]
                    .as_mut_slice()
                    .copy_from_slice(&st.lam[..NU]);
                sol.lam_u_upper[k]
                    .as_mut_slice()
                    .copy_from_slice(&st.lam[NU..2 * NU]);
                obj += st.u.dot(&(0.5 * (st.r * st.u) + st.s * st.x + st.rl));
            }
            if self.soft_any {
                for i in 0..NX {
                    let s = st.sl[i];
                    obj += st.soft[i] * (l1[i] * s + 0.5 * l2[i] * s * s);
                }
            }
        }
        sol.objective = obj;
    }

    fn recentre(&mut self, shift: &StartShift) {
        for st in &mut self.st {
            for i in 0..M {
                if st.mask[i] > 0.0 {
                    st.t[i] = recentred(st.t[i], shift.t);
                    st.lam[i] = recentred(st.lam[i], shift.lam);
                }
            }
        }
    }

    fn slot_sums(&self) -> (f64, f64, f64, f64, f64) {
        let mut sums = (f64::INFINITY, f64::INFINITY, 0.0, 0.0, 0.0);
        for st in &self.st {
            for i in 0..M {
                if st.mask[i] > 0.0 {
                    sums = add_slot(sums, st.t[i], st.lam[i]);
                }
            }
        }
        sums
    }
}
