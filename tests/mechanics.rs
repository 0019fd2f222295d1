//! Physics checks of the mechanics core: exact derivatives against central
//! finite differences, energy conservation of the free system, and the
//! Coriolis terms against the Christoffel symbols of M.

use eigenmpc::integrate::{Dopri5, Tolerances, rk4_step, rk4_step_sensitivity};
use eigenmpc::mechanics::{
    DoublePendulum, MechanicalSystem, PlanarChain, PlanarChainParams, Vector, state_derivative,
};
use nalgebra::{SMatrix, SVector};

/// Central difference of a vector function along each coordinate.
fn fd_jacobian<const R: usize, const C: usize>(
    f: impl Fn(&SVector<f64, C>) -> SVector<f64, R>,
    x: &SVector<f64, C>,
) -> SMatrix<f64, R, C> {
    let h = 1e-6;
    SMatrix::<f64, R, C>::from_fn(|i, j| {
        let mut xp = *x;
        let mut xm = *x;
        xp[j] += h;
        xm[j] -= h;
        (f(&xp)[i] - f(&xm)[i]) / (2.0 * h)
    })
}

fn assert_close<const R: usize, const C: usize>(
    what: &str,
    exact: &SMatrix<f64, R, C>,
    approx: &SMatrix<f64, R, C>,
    tol: f64,
) {
    let err = (exact - approx).abs().max();
    let scale = exact.abs().max().max(1.0);
    assert!(
        err <= tol * scale,
        "{what}: max error {err:e} (scale {scale})\nexact {exact}\nfd {approx}"
    );
}

fn damped_chain3() -> PlanarChain<3> {
    PlanarChain::new(PlanarChainParams {
        masses: [1.2, 0.8, 0.5],
        lengths: [0.9, 0.7, 1.1],
        gravity: 9.81,
        stiffness: [2.0, 0.0, 1.5],
        damping: [0.1, 0.2, 0.05],
    })
    .unwrap()
}

fn check_dynamics_jacobian<const N: usize, S: MechanicalSystem<N>>(sys: &S, points: &[[f64; 3]]) {
    for p in points {
        let q = Vector::<N>::from_fn(|i, _| p[0] * (i as f64 + 1.0).sin() + 0.1 * i as f64);
        let qd = Vector::<N>::from_fn(|i, _| p[1] * (2.0 * i as f64 + 0.5).cos());
        let tau = Vector::<N>::from_fn(|i, _| p[2] * (1.0 - 0.3 * i as f64));
        let jac = sys.dynamics_jacobian(&q, &qd, &tau);
        assert_close(
            "acceleration",
            &jac.acceleration,
            &sys.forward_dynamics(&q, &qd, &tau),
            1e-12,
        );
        let d_q = fd_jacobian(|x| sys.forward_dynamics(x, &qd, &tau), &q);
        let d_qd = fd_jacobian(|x| sys.forward_dynamics(&q, x, &tau), &qd);
        let d_tau = fd_jacobian(|x| sys.forward_dynamics(&q, &qd, x), &tau);
        assert_close("d qdd/d q", &jac.d_q, &d_q, 1e-7);
        assert_close("d qdd/d qd", &jac.d_qd, &d_qd, 1e-7);
        assert_close("d qdd/d tau", &jac.d_tau, &d_tau, 1e-7);
        assert_close(
            "d tau = M^-1",
            &jac.d_tau,
            &sys.mass_matrix(&q).try_inverse().unwrap(),
            1e-12,
        );

        let (e_q, e_qd) = sys.energy_gradient(&q, &qd);
        let fe_q = fd_jacobian(|x| SVector::<f64, 1>::new(sys.energy(x, &qd)), &q);
        let fe_qd = fd_jacobian(|x| SVector::<f64, 1>::new(sys.energy(&q, x)), &qd);
        assert_close("dE/dq", &e_q.transpose(), &fe_q, 1e-7);
        assert_close("dE/dqd", &e_qd.transpose(), &fe_qd, 1e-7);

        let grad = fd_jacobian(|x| SVector::<f64, 1>::new(sys.potential(x)), &q);
        assert_close(
            "dV/dq",
            &sys.potential_gradient(&q).transpose(),
            &grad,
            1e-7,
        );
        let hess = fd_jacobian(|x| sys.potential_gradient(x), &q);
        assert_close("d2V/dq2", &sys.potential_hessian(&q), &hess, 1e-7);
    }
}

const POINTS: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [0.4, 1.3, 0.7],
    [-1.7, -2.5, -1.0],
    [2.9, 4.0, 0.3],
];

#[test]
fn double_pendulum_derivatives_match_finite_differences() {
    check_dynamics_jacobian(&DoublePendulum::default(), &POINTS);
}

#[test]
fn three_link_chain_with_springs_and_damping_derivatives_match_finite_differences() {
    check_dynamics_jacobian(&damped_chain3(), &POINTS);
}

/// `C(q, qd) qd` must equal the Christoffel form `qd' Gamma_k qd` built from
/// finite differences of `M`.
#[test]
fn coriolis_forces_match_christoffel_symbols() {
    let sys = damped_chain3();
    let q = Vector::<3>::new(0.3, -1.1, 2.0);
    let qd = Vector::<3>::new(1.5, -0.7, 2.2);
    let h = 1e-6;
    let dm = |k: usize| {
        let mut qp = q;
        let mut qm = q;
        qp[k] += h;
        qm[k] -= h;
        (sys.mass_matrix(&qp) - sys.mass_matrix(&qm)) / (2.0 * h)
    };
    let dms: Vec<_> = (0..3).map(dm).collect();
    let mut expected = Vector::<3>::zeros();
    for k in 0..3 {
        for i in 0..3 {
            for j in 0..3 {
                let gamma = 0.5 * (dms[j][(k, i)] + dms[i][(k, j)] - dms[k][(i, j)]);
                expected[k] += gamma * qd[i] * qd[j];
            }
        }
    }
    let got = sys.coriolis_forces(&q, &qd);
    assert!((got - expected).abs().max() < 1e-7, "{got} vs {expected}");
}

#[test]
fn free_double_pendulum_conserves_energy_to_1e9_over_10s() {
    let sys = DoublePendulum::default();
    let z0 = SVector::<f64, 4>::new(1.0, -0.5, 0.0, 0.0);
    let tau = Vector::<2>::zeros();
    let e0 = sys.energy(&Vector::<2>::new(1.0, -0.5), &Vector::<2>::zeros());
    let mut ode = Dopri5::new(0.0, z0, Tolerances::default());
    let mut worst: f64 = 0.0;
    for k in 1..=100 {
        let z = *ode
            .advance_to(|_, z| state_derivative(&sys, z, &tau), 0.1 * k as f64)
            .unwrap();
        let e = sys.energy(&Vector::<2>::new(z[0], z[1]), &Vector::<2>::new(z[2], z[3]));
        worst = worst.max(((e - e0) / e0).abs());
    }
    println!(
        "worst relative energy drift over 10 s: {worst:e} ({} steps)",
        ode.steps()
    );
    assert!((ode.time() - 10.0).abs() < 1e-15);
    assert!(worst < 1e-9, "relative energy drift {worst:e}");
    // The motion is genuinely nonlinear (chaotic regime), not a trivial rest.
    assert!(ode.state()[2].abs() + ode.state()[3].abs() > 0.1);
}

#[test]
fn damping_dissipates_exactly_the_damping_power() {
    // dE/dt = tau' qd - qd' D qd: integrate and compare.
    let sys = damped_chain3();
    let tau = Vector::<3>::new(0.3, -0.2, 0.1);
    let z0 = SVector::<f64, 6>::new(0.5, -0.3, 0.2, 0.0, 0.4, -0.1);
    // Augment with the integral of the power balance.
    let d = sys.damping();
    let rhs = |z: &SVector<f64, 7>| {
        let zz = SVector::<f64, 6>::from_fn(|i, _| z[i]);
        let dz = state_derivative(&sys, &zz, &tau);
        let qd = Vector::<3>::new(z[3], z[4], z[5]);
        let power = tau.dot(&qd) - qd.dot(&d.component_mul(&qd));
        SVector::<f64, 7>::from_fn(|i, _| if i < 6 { dz[i] } else { power })
    };
    let y0 = SVector::<f64, 7>::from_fn(|i, _| if i < 6 { z0[i] } else { 0.0 });
    let mut ode = Dopri5::new(0.0, y0, Tolerances::default());
    let y = *ode.advance_to(|_, y| rhs(y), 3.0).unwrap();
    let energy = |y: &SVector<f64, 7>| {
        sys.energy(
            &Vector::<3>::new(y[0], y[1], y[2]),
            &Vector::<3>::new(y[3], y[4], y[5]),
        )
    };
    let balance = energy(&y) - energy(&y0) - y[6];
    assert!(balance.abs() < 1e-9, "energy balance error {balance:e}");
}

#[test]
fn rk4_sensitivities_match_finite_differences() {
    let sys = DoublePendulum::default();
    let z = SVector::<f64, 4>::new(0.8, -0.4, 1.2, -2.0);
    let tau = Vector::<2>::new(0.6, -0.9);
    let h = 0.025;
    let s = rk4_step_sensitivity(&sys, &z, &tau, h);
    assert_close("rk4 z", &s.z_next, &rk4_step(&sys, &z, &tau, h), 1e-14);
    let dz = fd_jacobian(|x| rk4_step(&sys, x, &tau, h), &z);
    let du = fd_jacobian(|u| rk4_step(&sys, &z, u, h), &tau);
    assert_close("rk4 d/dz", &s.d_z, &dz, 1e-8);
    assert_close("rk4 d/dtau", &s.d_tau, &du, 1e-8);
}

#[test]
fn rk4_converges_with_fourth_order() {
    let sys = DoublePendulum::default();
    let z0 = SVector::<f64, 4>::new(1.0, -0.5, 0.0, 0.0);
    let tau = Vector::<2>::new(0.2, -0.1);
    let mut reference = Dopri5::new(
        0.0,
        z0,
        Tolerances {
            rtol: 1e-13,
            atol: 1e-13,
        },
    );
    let exact = *reference
        .advance_to(|_, z| state_derivative(&sys, z, &tau), 1.0)
        .unwrap();
    let err = |steps: usize| {
        let h = 1.0 / steps as f64;
        let mut z = z0;
        for _ in 0..steps {
            z = rk4_step(&sys, &z, &tau, h);
        }
        (z - exact).norm()
    };
    let ratio = err(40) / err(80);
    assert!(
        (12.0..20.0).contains(&ratio),
        "error ratio {ratio} (expect ~16)"
    );
}
