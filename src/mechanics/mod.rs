//! Simple mechanical systems `M(q) qdd + C(q, qd) qd + dV/dq + tau_f(qd) = tau`
//! (paper, eq. 2) and their state-space form `z = (q, qd)`.
//!
//! The dimension is a const generic `N` (degrees of freedom) so that the
//! real-time code works on stack-allocated `nalgebra` matrices. State-space
//! helpers take a second const `NX` which must equal `2 N` (checked at compile
//! time), because stable Rust cannot yet write `2 * N` in a type.

mod chain;
mod trig;

pub use chain::{
    DEFAULT_COULOMB_SHARPNESS, DoublePendulum, Joint, Link, ParamsError, PlanarChain,
    PlanarChainParams,
};

pub use trig::sin_cos;

use nalgebra::{SMatrix, SVector};

/// Configuration-space vector (joint angles, speeds, accelerations or torques).
pub type Vector<const N: usize> = SVector<f64, N>;
/// Square configuration-space matrix (inertia, stiffness, Jacobian blocks).
pub type Matrix<const N: usize> = SMatrix<f64, N, N>;

/// The energy with its exact gradient, `(E, dE/dq, dE/dqd)`.
pub type EnergyWithGradient<const N: usize> = (f64, Vector<N>, Vector<N>);

/// Forward dynamics and its exact first derivatives at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DynamicsJacobian<const N: usize> {
    /// Joint accelerations `qdd`.
    pub acceleration: Vector<N>,
    /// `d qdd / d q`.
    pub d_q: Matrix<N>,
    /// `d qdd / d qd`.
    pub d_qd: Matrix<N>,
    /// `d qdd / d tau` (equals `M(q)^-1`).
    pub d_tau: Matrix<N>,
}

/// A simple mechanical system (paper, definition 1) in local coordinates,
/// `M(q) qdd + C(q, qd) qd + dV/dq + tau_f(qd) = tau`.
///
/// Implementors provide the inertia, the potential with its first two
/// derivatives, the Coriolis/centrifugal forces and exact first derivatives of
/// the conservative forward dynamics and of the energy; joint friction
/// `tau_f(qd)` (zero by default) is folded in generically, because it enters
/// only as a torque. Everything else (energy, state-space form, linear modes,
/// eigenmodes, NMPC) is built on these.
pub trait MechanicalSystem<const N: usize> {
    /// Inertia matrix `M(q)` (symmetric positive definite).
    fn mass_matrix(&self, q: &Vector<N>) -> Matrix<N>;
    /// Potential energy `V(q)`, zero at the stable equilibrium.
    fn potential(&self, q: &Vector<N>) -> f64;
    /// Potential forces `dV/dq`.
    fn potential_gradient(&self, q: &Vector<N>) -> Vector<N>;
    /// Stiffness `d^2 V / dq^2`.
    fn potential_hessian(&self, q: &Vector<N>) -> Matrix<N>;
    /// Coriolis and centrifugal forces `C(q, qd) qd`.
    fn coriolis_forces(&self, q: &Vector<N>, qd: &Vector<N>) -> Vector<N>;
    /// The stable equilibrium `q_eq` around which modes are defined.
    fn equilibrium(&self) -> Vector<N>;
    /// Conservative forward dynamics (`tau_f = 0`) with exact derivatives
    /// w.r.t. `(q, qd, tau)`.
    fn conservative_dynamics_jacobian(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> DynamicsJacobian<N>;
    /// Exact gradient of the energy: `(dE/dq, dE/dqd)`.
    fn energy_gradient(&self, q: &Vector<N>, qd: &Vector<N>) -> (Vector<N>, Vector<N>);

    /// The energy with its exact gradient, `(E, dE/dq, dE/dqd)`, as
    /// [`energy`](Self::energy) and [`energy_gradient`](Self::energy_gradient)
    /// give them. The cost evaluates both at every stage: an implementor
    /// shares their trigonometry here.
    fn energy_with_gradient(&self, q: &Vector<N>, qd: &Vector<N>) -> EnergyWithGradient<N> {
        let (d_q, d_qd) = self.energy_gradient(q, qd);
        (self.energy(q, qd), d_q, d_qd)
    }

    /// Joint friction torques `tau_f(qd)`, opposing the motion (zero for a
    /// conservative system). Each joint's friction depends on its own speed.
    fn friction(&self, _qd: &Vector<N>) -> Vector<N> {
        Vector::<N>::zeros()
    }

    /// Diagonal of `d tau_f / d qd`.
    fn friction_slope(&self, _qd: &Vector<N>) -> Vector<N> {
        Vector::<N>::zeros()
    }

    /// False only when [`friction`](Self::friction) is zero at every
    /// speed: the dynamics and their Jacobians then skip it and its slope
    /// (the same results). The default, true, is right for any system.
    fn has_friction(&self) -> bool {
        true
    }

    /// Power taken by friction, `tau_f(qd)' qd` (>= 0).
    fn friction_power(&self, qd: &Vector<N>) -> f64 {
        self.friction(qd).dot(qd)
    }

    /// Conservative forward dynamics `qdd = M^-1 (tau - C qd - dV/dq)`.
    fn conservative_forward_dynamics(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> Vector<N> {
        let rhs = tau - self.coriolis_forces(q, qd) - self.potential_gradient(q);
        solve_spd(&self.mass_matrix(q), &rhs)
    }

    /// Forward dynamics `qdd = M^-1 (tau - tau_f(qd) - C qd - dV/dq)`.
    fn forward_dynamics(&self, q: &Vector<N>, qd: &Vector<N>, tau: &Vector<N>) -> Vector<N> {
        if !self.has_friction() {
            return self.conservative_forward_dynamics(q, qd, tau);
        }
        self.conservative_forward_dynamics(q, qd, &(tau - self.friction(qd)))
    }

    /// Forward dynamics with exact derivatives w.r.t. `(q, qd, tau)`.
    ///
    /// Friction enters as the torque `tau - tau_f(qd)`, so its speed
    /// derivative is `-M^-1 diag(tau_f')`, i.e. `-d_tau diag(tau_f')`.
    fn dynamics_jacobian(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> DynamicsJacobian<N> {
        if !self.has_friction() {
            return self.conservative_dynamics_jacobian(q, qd, tau);
        }
        let mut jac = self.conservative_dynamics_jacobian(q, qd, &(tau - self.friction(qd)));
        add_friction_slope(&mut jac, &self.friction_slope(qd));
        jac
    }

    /// [`dynamics_jacobian`](Self::dynamics_jacobian) and
    /// [`energy_with_gradient`](Self::energy_with_gradient) at one state,
    /// exactly as they give them: the linearisation needs both at every
    /// shooting node.
    fn dynamics_jacobian_with_energy(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> (DynamicsJacobian<N>, EnergyWithGradient<N>) {
        if !self.has_friction() {
            return self.conservative_dynamics_jacobian_with_energy(q, qd, tau);
        }
        let (mut jac, energy) =
            self.conservative_dynamics_jacobian_with_energy(q, qd, &(tau - self.friction(qd)));
        add_friction_slope(&mut jac, &self.friction_slope(qd));
        (jac, energy)
    }

    /// [`conservative_dynamics_jacobian`](Self::conservative_dynamics_jacobian)
    /// and [`energy_with_gradient`](Self::energy_with_gradient) at one
    /// state: an implementor shares their trigonometry here.
    fn conservative_dynamics_jacobian_with_energy(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> (DynamicsJacobian<N>, EnergyWithGradient<N>) {
        (
            self.conservative_dynamics_jacobian(q, qd, tau),
            self.energy_with_gradient(q, qd),
        )
    }

    /// Kinetic energy `1/2 qd' M(q) qd`.
    fn kinetic_energy(&self, q: &Vector<N>, qd: &Vector<N>) -> f64 {
        0.5 * qd.dot(&(self.mass_matrix(q) * qd))
    }

    /// Total energy `E = 1/2 qd' M(q) qd + V(q)` (paper, eq. 3).
    fn energy(&self, q: &Vector<N>, qd: &Vector<N>) -> f64 {
        self.kinetic_energy(q, qd) + self.potential(q)
    }
}

/// Friction's speed derivative folded into a conservative Jacobian (taken
/// at `tau - tau_f(qd)`): `d_qd -= d_tau diag(slope)`, `slope = tau_f'(qd)`.
#[inline(always)]
fn add_friction_slope<const N: usize>(jac: &mut DynamicsJacobian<N>, slope: &Vector<N>) {
    for j in 0..N {
        if slope[j] != 0.0 {
            let column = jac.d_tau.column(j) * slope[j];
            let mut d = jac.d_qd.column_mut(j);
            d -= column;
        }
    }
}

/// The conservative part of a system (friction off): the system whose
/// eigenmodes EigenMPC follows. Borrows the system; friction reads zero.
#[derive(Clone, Copy, Debug)]
pub struct Conservative<'a, S: ?Sized>(pub &'a S);

impl<S, const N: usize> MechanicalSystem<N> for Conservative<'_, S>
where
    S: MechanicalSystem<N> + ?Sized,
{
    fn mass_matrix(&self, q: &Vector<N>) -> Matrix<N> {
        self.0.mass_matrix(q)
    }
    fn potential(&self, q: &Vector<N>) -> f64 {
        self.0.potential(q)
    }
    fn potential_gradient(&self, q: &Vector<N>) -> Vector<N> {
        self.0.potential_gradient(q)
    }
    fn potential_hessian(&self, q: &Vector<N>) -> Matrix<N> {
        self.0.potential_hessian(q)
    }
    fn coriolis_forces(&self, q: &Vector<N>, qd: &Vector<N>) -> Vector<N> {
        self.0.coriolis_forces(q, qd)
    }
    fn equilibrium(&self) -> Vector<N> {
        self.0.equilibrium()
    }
    fn has_friction(&self) -> bool {
        false
    }
    fn conservative_dynamics_jacobian(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> DynamicsJacobian<N> {
        self.0.conservative_dynamics_jacobian(q, qd, tau)
    }
    fn energy_gradient(&self, q: &Vector<N>, qd: &Vector<N>) -> (Vector<N>, Vector<N>) {
        self.0.energy_gradient(q, qd)
    }
    fn energy_with_gradient(&self, q: &Vector<N>, qd: &Vector<N>) -> EnergyWithGradient<N> {
        self.0.energy_with_gradient(q, qd)
    }
    fn conservative_dynamics_jacobian_with_energy(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> (DynamicsJacobian<N>, EnergyWithGradient<N>) {
        self.0
            .conservative_dynamics_jacobian_with_energy(q, qd, tau)
    }
    fn conservative_forward_dynamics(
        &self,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
    ) -> Vector<N> {
        self.0.conservative_forward_dynamics(q, qd, tau)
    }
    fn kinetic_energy(&self, q: &Vector<N>, qd: &Vector<N>) -> f64 {
        self.0.kinetic_energy(q, qd)
    }
}

/// Solves `M x = b` for a symmetric positive definite `M`.
///
/// Returns NaN when `M` is not positive definite (only a broken model or a
/// non-finite state can cause that), so callers see a non-finite result
/// rather than a panic.
pub fn solve_spd<const N: usize>(m: &Matrix<N>, b: &Vector<N>) -> Vector<N> {
    match m.cholesky() {
        Some(ch) => ch.solve(b),
        None => Vector::<N>::repeat(f64::NAN),
    }
}

/// State `z = (q, qd)` packed into one vector of length `NX = 2 N`.
pub fn pack_state<const N: usize, const NX: usize>(
    q: &Vector<N>,
    qd: &Vector<N>,
) -> SVector<f64, NX> {
    const { assert!(NX == 2 * N, "NX must equal 2 N") };
    let mut z = SVector::<f64, NX>::zeros();
    z.fixed_rows_mut::<N>(0).copy_from(q);
    z.fixed_rows_mut::<N>(N).copy_from(qd);
    z
}

/// Splits a packed state `z` into `(q, qd)`.
pub fn unpack_state<const N: usize, const NX: usize>(
    z: &SVector<f64, NX>,
) -> (Vector<N>, Vector<N>) {
    const { assert!(NX == 2 * N, "NX must equal 2 N") };
    (
        z.fixed_rows::<N>(0).into_owned(),
        z.fixed_rows::<N>(N).into_owned(),
    )
}

/// State derivative `zd = (qd, qdd)` of the forced system.
pub fn state_derivative<S, const N: usize, const NX: usize>(
    system: &S,
    z: &SVector<f64, NX>,
    tau: &Vector<N>,
) -> SVector<f64, NX>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let (q, qd) = unpack_state::<N, NX>(z);
    pack_state::<N, NX>(&qd, &system.forward_dynamics(&q, &qd, tau))
}

/// State derivative with its exact Jacobians `(zd, d zd/d z, d zd/d tau)`.
pub fn state_jacobian<S, const N: usize, const NX: usize>(
    system: &S,
    z: &SVector<f64, NX>,
    tau: &Vector<N>,
) -> (SVector<f64, NX>, SMatrix<f64, NX, NX>, SMatrix<f64, NX, N>)
where
    S: MechanicalSystem<N> + ?Sized,
{
    let (q, qd) = unpack_state::<N, NX>(z);
    let jac = system.dynamics_jacobian(&q, &qd, tau);
    let zd = pack_state::<N, NX>(&qd, &jac.acceleration);
    let mut a = SMatrix::<f64, NX, NX>::zeros();
    a.fixed_view_mut::<N, N>(0, N).fill_with_identity();
    a.fixed_view_mut::<N, N>(N, 0).copy_from(&jac.d_q);
    a.fixed_view_mut::<N, N>(N, N).copy_from(&jac.d_qd);
    let mut b = SMatrix::<f64, NX, N>::zeros();
    b.fixed_view_mut::<N, N>(N, 0).copy_from(&jac.d_tau);
    (zd, a, b)
}

/// Energy of a packed state.
pub fn state_energy<S, const N: usize, const NX: usize>(system: &S, z: &SVector<f64, NX>) -> f64
where
    S: MechanicalSystem<N> + ?Sized,
{
    let (q, qd) = unpack_state::<N, NX>(z);
    system.energy(&q, &qd)
}
