//! Physics checks of the mechanics core: exact derivatives against central
//! finite differences, energy conservation of the free system, and the
//! Coriolis terms against the Christoffel symbols of M.

use eigenmpc::integrate::{Dopri5, Tolerances, rk4_step, rk4_step_sensitivity};
use eigenmpc::math;
use eigenmpc::mechanics::{
    Conservative, DoublePendulum, Joint, Link, MechanicalSystem, PlanarChain, PlanarChainParams,
    Vector, state_derivative,
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

/// Point masses with springs (one with a rest angle) and viscous damping.
fn damped_chain3() -> PlanarChain<3> {
    let mut p = PlanarChainParams::point_masses([1.2, 0.8, 0.5], [0.9, 0.7, 1.1], 9.81);
    for (j, (k, b)) in [(2.0, 0.1), (0.0, 0.2), (1.5, 0.05)]
        .into_iter()
        .enumerate()
    {
        p.joints[j].stiffness = k;
        p.joints[j].viscous = b;
    }
    p.joints[2].rest_angle = 0.3;
    PlanarChain::new(p).unwrap()
}

/// A geared joint with viscous and smooth Coulomb friction.
fn motor(rotor: f64, gear: f64, b: f64, cf: f64) -> Joint {
    Joint {
        rotor_inertia: rotor,
        gear_ratio: gear,
        viscous: b,
        coulomb: cf,
        ..Joint::default()
    }
}

/// The identified laboratory pendulum of `shared/robots/lab-double-pendulum-A0.yml`.
fn robot_a0() -> PlanarChain<2> {
    let ir = 7.659297952841183e-05;
    PlanarChain::new(PlanarChainParams {
        links: [
            Link::with_inertia_about_joint(0.5593806151425046, 0.3, 0.3, 0.053470810264216295),
            Link::with_inertia_about_joint(
                0.6043459469186889,
                0.2,
                0.18377686083653508,
                0.02392374528789766,
            ),
        ],
        joints: [motor(ir, 6.0, 0.001, 0.093), motor(ir, 6.0, 0.001, 0.078)],
        gravity: 9.81,
        coulomb_sharpness: 100.0,
    })
    .unwrap()
}

fn rigid_link1() -> PlanarChain<1> {
    PlanarChain::new(PlanarChainParams {
        links: [Link {
            mass: 0.7,
            length: 0.4,
            com: 0.25,
            inertia: 0.004,
        }],
        joints: [motor(1e-4, 10.0, 0.01, 0.05)],
        gravity: 9.81,
        coulomb_sharpness: 100.0,
    })
    .unwrap()
}

/// Rigid links (one COM beyond the tip, one short of it), geared motors on
/// the previous link, viscous and Coulomb friction, a spring with a rest angle.
fn rigid_chain3() -> PlanarChain<3> {
    let mut joints = [
        motor(8e-5, 6.0, 0.002, 0.09),
        motor(5e-5, 9.0, 0.004, 0.07),
        motor(3e-5, 4.0, 0.001, 0.05),
    ];
    joints[1].stiffness = 0.8;
    joints[1].rest_angle = -0.2;
    PlanarChain::new(PlanarChainParams {
        links: [
            Link::with_inertia_about_joint(0.6, 0.3, 0.31, 0.06),
            Link::with_inertia_about_joint(0.5, 0.25, 0.12, 0.012),
            Link::with_inertia_about_joint(0.3, 0.2, 0.15, 0.009),
        ],
        joints,
        gravity: 9.81,
        coulomb_sharpness: 100.0,
    })
    .unwrap()
}

fn check_dynamics_jacobian<const N: usize, S: MechanicalSystem<N>>(sys: &S, points: &[[f64; 3]]) {
    for p in points {
        let q = Vector::<N>::from_fn(|i, _| p[0] * math::sin(i as f64 + 1.0) + 0.1 * i as f64);
        let qd = Vector::<N>::from_fn(|i, _| p[1] * math::cos(2.0 * i as f64 + 0.5));
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
        // The cost's fused evaluation: the same energy and gradient.
        let (e, fused_q, fused_qd) = sys.energy_with_gradient(&q, &qd);
        let scale = 1.0 + sys.energy(&q, &qd).abs();
        assert!(
            (e - sys.energy(&q, &qd)).abs() < 1e-13 * scale,
            "fused energy {e}"
        );
        assert_close("fused dE/dq", &fused_q, &e_q, 1e-12);
        assert_close("fused dE/dqd", &fused_qd, &e_qd, 1e-12);

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

#[test]
fn rigid_link_chains_with_motors_and_friction_derivatives_match_finite_differences() {
    check_dynamics_jacobian(&rigid_link1(), &POINTS);
    check_dynamics_jacobian(&robot_a0(), &POINTS);
    check_dynamics_jacobian(&rigid_chain3(), &POINTS);
    // The conservative part of the same chains (what the eigenmodes use).
    check_dynamics_jacobian(&Conservative(&robot_a0()), &POINTS);
    check_dynamics_jacobian(&Conservative(&rigid_chain3()), &POINTS);
}

/// The inertia of `shared/robots/README.md`, written out for the A0 robot.
#[test]
fn robot_mass_matrix_matches_the_published_model() {
    let sys = robot_a0();
    let (m2, l1, r2) = (0.6043459469186889, 0.3, 0.18377686083653508);
    let (i1, i2, ir, gr) = (
        0.053470810264216295,
        0.02392374528789766,
        7.659297952841183e-05,
        6.0,
    );
    for q2 in [0.0f64, 0.7, -2.1, 3.1] {
        let m = sys.mass_matrix(&Vector::<2>::new(0.4, q2));
        let c2 = math::cos(q2);
        let m11 = i1 + i2 + m2 * l1 * l1 + 2.0 * m2 * l1 * r2 * c2 + gr * gr * ir + ir;
        let m12 = i2 + m2 * l1 * r2 * c2 - gr * ir;
        let m22 = i2 + gr * gr * ir;
        assert!((m[(0, 0)] - m11).abs() < 1e-15, "{m}");
        assert!((m[(0, 1)] - m12).abs() < 1e-15 && (m[(1, 0)] - m12).abs() < 1e-15);
        assert!((m[(1, 1)] - m22).abs() < 1e-15);
    }
    // V = -(m1 r1 + m2 l1) g cos q1 - m2 r2 g cos(q1 + q2) + const, V(0) = 0.
    let q = Vector::<2>::new(0.8, -1.3);
    let v = -(0.5593806151425046 * 0.3 + m2 * l1) * 9.81 * (math::cos(q[0]) - 1.0)
        - m2 * r2 * 9.81 * (math::cos(q[0] + q[1]) - 1.0);
    assert!((sys.potential(&q) - v).abs() < 1e-14);
    // tau_f = b qd + cf atan(100 qd).
    let qd = Vector::<2>::new(0.02, -1.5);
    let f = sys.friction(&qd);
    assert!((f[0] - (0.001 * 0.02 + 0.093 * math::atan(2.0))).abs() < 1e-15);
    assert!((f[1] - (0.001 * -1.5 + 0.078 * math::atan(-150.0f64))).abs() < 1e-15);
}

/// A rigid link with the inertia of a point mass is the paper's point-mass
/// chain, to round-off.
#[test]
fn point_mass_chain_is_the_rigid_link_chain_with_point_inertia() {
    let (m, l) = ([1.3, 0.7], [0.9, 1.2]);
    let point = PlanarChain::new(PlanarChainParams::point_masses(m, l, 9.81)).unwrap();
    let rigid = PlanarChain::new(PlanarChainParams {
        links: std::array::from_fn(|j| {
            Link::with_inertia_about_joint(m[j], l[j], l[j], m[j] * l[j] * l[j])
        }),
        ..PlanarChainParams::point_masses(m, l, 9.81)
    })
    .unwrap();
    for p in POINTS {
        let q = Vector::<2>::new(p[0], p[1] - 0.3);
        let qd = Vector::<2>::new(p[1], -p[0]);
        let tau = Vector::<2>::new(p[2], 0.5);
        let (a, b) = (
            point.dynamics_jacobian(&q, &qd, &tau),
            rigid.dynamics_jacobian(&q, &qd, &tau),
        );
        assert!((a.acceleration - b.acceleration).amax() < 1e-12);
        assert!((a.d_q - b.d_q).amax() < 1e-12 && (a.d_qd - b.d_qd).amax() < 1e-12);
        assert!((point.energy(&q, &qd) - rigid.energy(&q, &qd)).abs() < 1e-12);
    }
}

#[test]
fn spring_rest_angles_move_the_equilibrium_and_keep_v_zero_there() {
    let sys = rigid_chain3();
    let q_eq = sys.equilibrium();
    assert!(sys.potential_gradient(&q_eq).amax() < 1e-12);
    assert!(sys.potential(&q_eq).abs() < 1e-14);
    assert!(
        q_eq[1] < -1e-3,
        "the spring pulls joint 2 towards -0.2: {q_eq}"
    );
    assert!(sys.potential_hessian(&q_eq).cholesky().is_some());
}

#[test]
fn non_physical_rigid_link_parameters_are_refused_by_name() {
    let mut p = PlanarChainParams::<2>::default();
    p.links[1] = Link::with_inertia_about_joint(1.0, 1.0, 1.0, 0.0);
    let err = PlanarChain::new(p).unwrap_err().to_string();
    assert!(err.contains("I2"), "{err}");
    // Below m r^2 (identified base parameters) is fine while M stays
    // positive definite; far below it, M(q2 = 0) is singular.
    p.links[1] = Link::with_inertia_about_joint(1.0, 1.0, 1.0, 0.9);
    assert!(PlanarChain::new(p).is_ok());
    let mut p = PlanarChainParams::<2>::default();
    p.links[0] = Link::with_inertia_about_joint(1.0, 1.0, 0.9, 0.01);
    p.links[1] = Link::with_inertia_about_joint(3.0, 1.0, 1.0, 0.05);
    let err = PlanarChain::new(p).unwrap_err().to_string();
    assert!(err.contains("not positive definite"), "{err}");
    let mut p = PlanarChainParams::<2>::default();
    p.joints[0].coulomb = -0.1;
    assert!(PlanarChain::new(p).unwrap_err().to_string().contains("cf1"));
    let mut p = PlanarChainParams::<2>::default();
    p.joints[1].gear_ratio = 0.0;
    assert!(PlanarChain::new(p).unwrap_err().to_string().contains("gr2"));
    let mut p = PlanarChainParams::<2>::default();
    p.links[0].com = f64::NAN;
    assert!(PlanarChain::new(p).unwrap_err().to_string().contains("r1"));
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

/// Integrates the system together with `int (tau' qd - tau_f' qd) dt`
/// and returns `E(T) - E(0) - that integral` (zero by the power balance).
fn power_balance_error<const N: usize, S: MechanicalSystem<N>>(
    sys: &S,
    tau: Vector<N>,
    q0: Vector<N>,
    qd0: Vector<N>,
    duration: f64,
) -> (f64, f64) {
    // State (q, qd, work, friction loss) as a dynamic vector-free fixed array.
    let n = N;
    let pack = |q: &Vector<N>, qd: &Vector<N>, w: f64, loss: f64| {
        let mut y = [0.0; 8];
        y[..n].copy_from_slice(q.as_slice());
        y[n..2 * n].copy_from_slice(qd.as_slice());
        y[2 * n] = w;
        y[2 * n + 1] = loss;
        SVector::<f64, 8>::from(y)
    };
    let split = |y: &SVector<f64, 8>| {
        (
            Vector::<N>::from_fn(|i, _| y[i]),
            Vector::<N>::from_fn(|i, _| y[n + i]),
        )
    };
    let rhs = |y: &SVector<f64, 8>| {
        let (q, qd) = split(y);
        let qdd = sys.forward_dynamics(&q, &qd, &tau);
        pack(&qd, &qdd, tau.dot(&qd), sys.friction_power(&qd))
    };
    let y0 = pack(&q0, &qd0, 0.0, 0.0);
    let mut ode = Dopri5::new(0.0, y0, Tolerances::default());
    let y = *ode.advance_to(|_, y| rhs(y), duration).unwrap();
    let (q, qd) = split(&y);
    let de = sys.energy(&q, &qd) - sys.energy(&q0, &qd0);
    (de - (y[2 * n] - y[2 * n + 1]), y[2 * n + 1])
}

#[test]
fn energy_changes_by_the_torque_work_minus_the_friction_loss_for_1_2_and_3_links() {
    // dE/dt = tau' qd - tau_f(qd)' qd.
    let (err, loss) = power_balance_error(
        &damped_chain3(),
        Vector::<3>::new(0.3, -0.2, 0.1),
        Vector::<3>::new(0.5, -0.3, 0.2),
        Vector::<3>::new(0.0, 0.4, -0.1),
        3.0,
    );
    assert!(err.abs() < 1e-9 && loss > 0.01, "{err:e}, loss {loss}");
    let (err, loss) = power_balance_error(
        &rigid_link1(),
        Vector::<1>::new(0.2),
        Vector::<1>::new(1.0),
        Vector::<1>::new(0.0),
        3.0,
    );
    assert!(
        err.abs() < 1e-9 && loss > 0.01,
        "1 link: {err:e}, loss {loss}"
    );
    let (err, loss) = power_balance_error(
        &robot_a0(),
        Vector::<2>::new(0.3, -0.1),
        Vector::<2>::new(1.2, -0.6),
        Vector::<2>::new(0.0, 0.0),
        3.0,
    );
    assert!(
        err.abs() < 1e-9 && loss > 0.01,
        "2 links: {err:e}, loss {loss}"
    );
    let (err, loss) = power_balance_error(
        &rigid_chain3(),
        Vector::<3>::new(0.1, 0.05, -0.02),
        Vector::<3>::new(0.9, -0.4, 0.6),
        Vector::<3>::new(0.5, 0.0, -1.0),
        3.0,
    );
    assert!(
        err.abs() < 1e-9 && loss > 0.01,
        "3 links: {err:e}, loss {loss}"
    );
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

/// A start from rest (state exactly zero) under zero or saturated torque
/// must integrate for every tolerance a plant accepts (the initial step
/// guess used to collapse to ~1e-17 s when the state is zero).
#[test]
fn adaptive_integrator_starts_from_rest_for_every_tolerance() {
    fn run<const N: usize, const NX: usize, S: MechanicalSystem<N>>(sys: &S, tau: Vector<N>) {
        let z0 = SVector::<f64, NX>::zeros();
        let mut reference = Dopri5::new(
            0.0,
            z0,
            Tolerances {
                rtol: 1e-13,
                atol: 1e-13,
            },
        );
        let exact = *reference
            .advance_to(|_, z| state_derivative::<S, N, NX>(sys, z, &tau), 0.5)
            .unwrap();
        for tol in [1e-14, 1e-12, 1e-10, 1e-8, 1e-6, 1e-4, 1e-2] {
            let mut ode = Dopri5::new(
                0.0,
                z0,
                Tolerances {
                    rtol: tol,
                    atol: tol,
                },
            );
            let z = *ode
                .advance_to(|_, z| state_derivative::<S, N, NX>(sys, z, &tau), 0.5)
                .unwrap_or_else(|e| panic!("tol {tol:e}, tau {tau}: {e}"));
            let err = (z - exact).amax();
            // Accuracy is checked where the motion is not spun up into chaos
            // (a saturated 3-link chain reaches ~800 rad/s in 0.5 s).
            let scale = exact.amax().max(1.0);
            assert!(
                scale > 50.0 || err <= 1e3 * tol.max(1e-12) * scale,
                "tol {tol:e}, tau {tau}: error {err:e}, scale {scale}"
            );
        }
    }
    for t in [0.0, 1e-9, 0.5, 10.0] {
        run::<2, 4, _>(&DoublePendulum::default(), Vector::<2>::new(t, -t));
        run::<2, 4, _>(&robot_a0(), Vector::<2>::new(t, 0.5 * t));
        run::<3, 6, _>(&rigid_chain3(), Vector::<3>::new(0.0, t, -t));
    }
}
