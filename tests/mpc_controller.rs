//! Controller correctness: residual Jacobians against finite differences,
//! KKT conditions of the clarabel QP solutions, RTI against the converged
//! SQP, failure handling and tuning.

use eigenmpc::math;
use eigenmpc::mechanics::{DoublePendulum, MechanicalSystem, Vector};
use eigenmpc::modes::linear_modes;
use eigenmpc::mpc::Guide;
use eigenmpc::mpc::closed_loop::mode_and_chart;
use eigenmpc::mpc::cost::{CostParams, Reference, residuals, stage_model};
use eigenmpc::mpc::{ControlStatus, Controller, MpcConfig, MpcError, Startup, Variant};
use eigenmpc::qp::clarabel::{ClarabelQpSolver, accurate_settings};
use eigenmpc::qp::{OcpQp, QpSolution, QpSolver, QpStatus, kkt_residuals};
use nalgebra::{DVector, SVector};

type Z = SVector<f64, 4>;

fn straight() -> Reference<2> {
    Reference::new(
        Variant::Straight,
        Guide::Line(linear_modes(&DoublePendulum::default()).unwrap()[0].eigenvector),
    )
    .unwrap()
}

fn curved() -> Reference<2> {
    let (_, chart) = mode_and_chart::<_, 2, 4>(&DoublePendulum::default(), 0, 14.0, 9).unwrap();
    Reference::with_chart(Variant::Curved, chart)
}

fn hybrid() -> Reference<2> {
    Reference::with_chart(Variant::Hybrid, curved().chart().unwrap().clone())
}

/// The three variants with their references; hybrid with a larger alpha
/// than the paper's so that the blend's derivative terms matter.
fn variants() -> [(Reference<2>, Variant, CostParams); 3] {
    let mut hybrid_params = params(Variant::Hybrid);
    hybrid_params.alpha = 0.3;
    [
        (straight(), Variant::Straight, params(Variant::Straight)),
        (curved(), Variant::Curved, params(Variant::Curved)),
        (hybrid(), Variant::Hybrid, hybrid_params),
    ]
}

/// [`variants`] at the paper's 14 J, with the energy residual relative to
/// a 3 J `E_ref` (factor 14/3) and absolute at 3 J: every form of `r_E`.
fn scaled_variants() -> Vec<(Reference<2>, Variant, CostParams)> {
    let mut out = vec![];
    for (reference, variant, p) in variants() {
        for (e_ref, energy_scale) in [(14.0, 14.0), (3.0, 14.0), (3.0, 0.0)] {
            let p = CostParams {
                e_ref,
                energy_scale,
                ..p
            };
            out.push((reference.clone(), variant, p));
        }
    }
    out
}

fn params(variant: Variant) -> CostParams {
    MpcConfig::paper(variant).cost
}

/// Stacked residual vector (r_E; r_x; r_xd; r_F).
fn stacked(reference: &Reference<2>, p: &CostParams, z: &Z, tau: &Vector<2>) -> DVector<f64> {
    let r = residuals::<_, 2, 4>(&DoublePendulum::default(), reference, p, z, tau);
    DVector::from_iterator(
        7,
        [r.energy]
            .into_iter()
            .chain(r.position.iter().copied())
            .chain(r.velocity.iter().copied())
            .chain(r.torque.iter().copied()),
    )
}

#[test]
fn residual_jacobians_match_finite_differences() {
    let sys = DoublePendulum::default();
    let states = [
        Z::new(0.3, -0.2, 0.5, 1.1),
        Z::new(-0.9, 1.2, -2.0, 0.7),
        Z::new(0.05, 0.05, 0.0, 0.0),
    ];
    let tau = Vector::<2>::new(0.4, -0.7);
    for (reference, variant, p) in scaled_variants() {
        for z in &states {
            let r = residuals::<_, 2, 4>(&sys, &reference, &p, z, &tau);
            let h = 1e-6;
            for j in 0..4 {
                let mut zp = *z;
                let mut zm = *z;
                zp[j] += h;
                zm[j] -= h;
                let fd = (stacked(&reference, &p, &zp, &tau) - stacked(&reference, &p, &zm, &tau))
                    / (2.0 * h);
                let exact = [
                    r.energy_z[j],
                    r.position_z[(0, j)],
                    r.position_z[(1, j)],
                    r.velocity_z[(0, j)],
                    r.velocity_z[(1, j)],
                    r.torque_z[(0, j)],
                    r.torque_z[(1, j)],
                ];
                for i in 0..7 {
                    assert!(
                        (fd[i] - exact[i]).abs() < 1e-6 * (1.0 + exact[i].abs()),
                        "{variant} z {z:?} d r_{i}/d z_{j}: fd {} exact {}",
                        fd[i],
                        exact[i]
                    );
                }
            }
            for j in 0..2 {
                let mut tp = tau;
                let mut tm = tau;
                tp[j] += 1e-6;
                tm[j] -= 1e-6;
                let fd = (stacked(&reference, &p, z, &tp) - stacked(&reference, &p, z, &tm)) / 2e-6;
                for i in 0..2 {
                    assert!((fd[5 + i] - r.torque_u[(i, j)]).abs() < 1e-7);
                }
                assert!(fd.rows(0, 5).amax() < 1e-8, "only r_F depends on tau");
            }
        }
    }
}

/// Hybrid = the curved distances times `1 - tanh(alpha E)` and the torque
/// times `tanh(alpha E) + beta` (the straight cost's blend); alpha = 0 and
/// beta = 1 give the curved cost exactly.
#[test]
fn hybrid_is_the_curved_cost_blended_as_straight() {
    let sys = DoublePendulum::default();
    let z = Z::new(0.4, 0.3, -1.0, 0.5);
    let tau = Vector::<2>::new(0.2, 0.1);
    let mut p = params(Variant::Hybrid);
    p.alpha = 0.3;
    let c = residuals::<_, 2, 4>(&sys, &curved(), &p, &z, &tau);
    let h = residuals::<_, 2, 4>(&sys, &hybrid(), &p, &z, &tau);
    let (q, qd) = (Vector::<2>::new(z[0], z[1]), Vector::<2>::new(z[2], z[3]));
    let t = math::tanh(p.alpha * sys.energy(&q, &qd));
    assert!((h.position - c.position * (1.0 - t)).amax() < 1e-15);
    assert!((h.velocity - c.velocity * (1.0 - t)).amax() < 1e-15);
    assert!((h.torque - c.torque * (t + p.beta)).amax() < 1e-15);
    assert_eq!(h.energy, c.energy);
    p.alpha = 0.0;
    p.beta = 1.0;
    let c = stacked(&curved(), &p, &z, &tau);
    assert_eq!(stacked(&hybrid(), &p, &z, &tau), c);
}

#[test]
fn gauss_newton_model_is_psd_and_consistent_with_cost() {
    let sys = DoublePendulum::default();
    let z = Z::new(0.4, 0.3, -1.0, 0.5);
    let tau = Vector::<2>::new(0.2, 0.1);
    for (reference, variant, p) in scaled_variants() {
        let m = stage_model::<_, 2, 4>(&sys, &reference, &p, &z, &tau, 0.025);
        let mut h = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        h.fixed_view_mut::<4, 4>(0, 0).copy_from(&m.q);
        h.fixed_view_mut::<2, 4>(4, 0).copy_from(&m.s);
        h.fixed_view_mut::<4, 2>(0, 4).copy_from(&m.s.transpose());
        h.fixed_view_mut::<2, 2>(4, 4).copy_from(&m.r);
        let min_eig = h.symmetric_eigenvalues().min();
        assert!(
            min_eig > -1e-9 * h.amax(),
            "{variant}: min eigenvalue {min_eig}"
        );
        // Gradient of the cost by finite differences.
        let r = stacked(&reference, &p, &z, &tau);
        let w = p.weights;
        let wv = [
            w.energy, w.position, w.position, w.velocity, w.velocity, w.torque, w.torque,
        ];
        let cost: f64 = (0..7).map(|i| wv[i] * r[i] * r[i]).sum::<f64>() * 0.025;
        assert!((cost - m.cost).abs() < 1e-12 * (1.0 + cost));
        for j in 0..4 {
            let mut zp = z;
            let mut zm = z;
            zp[j] += 1e-6;
            zm[j] -= 1e-6;
            let f = |zz: &Z| {
                let r = stacked(&reference, &p, zz, &tau);
                (0..7).map(|i| wv[i] * r[i] * r[i]).sum::<f64>() * 0.025
            };
            let fd = (f(&zp) - f(&zm)) / 2e-6;
            assert!(
                (fd - m.gz[j]).abs() < 1e-6 * (1.0 + fd.abs()),
                "{variant} grad {j}"
            );
        }
    }
}

fn controller(
    reference: Reference<2>,
    config: MpcConfig,
    accurate: bool,
) -> Controller<DoublePendulum, 2, 4> {
    let sys = DoublePendulum::default();
    if accurate {
        let solver = ClarabelQpSolver::new(4, 2, config.horizon, accurate_settings());
        Controller::with_solver(sys, config, reference, Box::new(solver)).unwrap()
    } else {
        Controller::new(sys, config, reference).unwrap()
    }
}

#[test]
fn clarabel_qp_solutions_satisfy_kkt() {
    // Inactive bounds (near rest), active bounds (large state, small tau_max).
    for (tau_max, z) in [
        (1.0, Z::new(0.05, 0.05, 0.0, 0.0)),
        (0.2, Z::new(-1.1, 1.1, 0.0, 0.0)),
    ] {
        for (reference, variant) in [(straight(), Variant::Straight), (curved(), Variant::Curved)] {
            let mut config = MpcConfig::paper(variant);
            config.tau_max = tau_max;
            config.startup = Startup::Iterations(1);
            for accurate in [false, true] {
                let mut ctrl = controller(reference.clone(), config, accurate);
                let mut zz = z;
                for _ in 0..3 {
                    let out = ctrl.step(&zz);
                    assert_eq!(out.status, ControlStatus::Solved);
                    assert!(out.tau.amax() <= tau_max + 1e-12);
                    zz[2] += 0.1;
                }
                let (qp, sol) = ctrl.last_qp();
                let kkt = kkt_residuals(&qp, sol);
                let (stat, prim, bound, comp) = (
                    kkt.stationarity,
                    kkt.primal_feasibility,
                    kkt.dual_feasibility,
                    kkt.complementarity,
                );
                let scale = if accurate { 1e-8 } else { 1e-5 };
                assert!(
                    stat < scale && prim < scale && bound < scale && comp < scale,
                    "{variant} tau_max {tau_max} accurate {accurate}: {stat:e} {prim:e} {bound:e} {comp:e}"
                );
                if tau_max == 0.2 {
                    let active = sol
                        .lam_u_lower
                        .iter()
                        .chain(&sol.lam_u_upper)
                        .flat_map(|l| l.iter())
                        .filter(|&&l| l > 1e-4)
                        .count();
                    assert!(active > 0, "scenario meant to activate bounds");
                }
            }
        }
    }
}

#[test]
fn rti_iterations_converge_to_the_sqp_solution_on_the_first_sample() {
    let z = Z::new(0.05, 0.05, 0.0, 0.0);
    for (reference, variant) in [(straight(), Variant::Straight), (curved(), Variant::Curved)] {
        let mut config = MpcConfig::paper(variant);
        config.horizon = 40;
        config.sqp.tolerance = 1e-10;
        config.sqp.max_iterations = 60;
        config.startup = Startup::Converge;
        let mut sqp = controller(reference.clone(), config, true);
        let reference_out = sqp.step(&z);
        assert_eq!(reference_out.status, ControlStatus::Solved, "{variant}");
        // At convergence the next QP step vanishes: the NLP's KKT conditions hold.
        let (qp, sol) = sqp.last_qp();
        let step: f64 = sol.u.iter().map(|u| u.amax()).fold(0.0, f64::max);
        assert!(step < 1e-10, "{variant}: last SQP step {step:e}");
        assert!(kkt_residuals(&qp, sol).max() < 1e-8);

        let mut rti_config = config;
        rti_config.startup = Startup::Iterations(1);
        let mut rti = controller(reference, rti_config, true);
        let first = rti.step(&z);
        // One RTI from the zero-torque guess is already a useful step...
        assert!(first.tau.amax() > 0.0);
        // ...and repeated RTIs at the same state converge to the SQP solution.
        rti_config.startup = Startup::Iterations(30);
        let mut rti = controller(rti.reference().clone(), rti_config, true);
        let out = rti.step(&z);
        let diff = (out.tau - reference_out.tau).amax();
        assert!(
            diff < 1e-6,
            "{variant}: RTI {:?} SQP {:?}",
            out.tau,
            reference_out.tau
        );
    }
}

/// A QP backend that always fails (failure handling).
struct Failing;
impl QpSolver for Failing {
    fn name(&self) -> &'static str {
        "failing"
    }
    fn solve(&mut self, _qp: &OcpQp, sol: &mut QpSolution) -> QpStatus {
        sol.status = QpStatus::NumericalError;
        QpStatus::NumericalError
    }
}

#[test]
fn failures_return_the_shifted_plan_clipped() {
    let sys = DoublePendulum::default();
    let mut config = MpcConfig::paper(Variant::Straight);
    config.horizon = 20;
    let mut ctrl = Controller::<_, 2, 4>::new(sys, config, straight()).unwrap();
    // No plan yet and a NaN state: zero torque.
    let out = ctrl.step(&Z::new(f64::NAN, 0.0, 0.0, 0.0));
    assert_eq!(out.status, ControlStatus::InvalidState);
    assert_eq!(out.tau, Vector::<2>::zeros());
    let z = Z::new(0.3, 0.1, 0.0, 0.0);
    let first = ctrl.step(&z);
    assert!(first.status.is_ok());
    let plan: Vec<Vector<2>> = ctrl.planned_controls().to_vec();
    let out = ctrl.step(&Z::new(0.3, f64::INFINITY, 0.0, 0.0));
    assert_eq!(out.status, ControlStatus::InvalidState);
    assert_eq!(out.tau, plan[1].map(|v| v.clamp(-1.0, 1.0)));
    assert!(out.status.to_string().contains("NaN/Inf"));

    // A failing QP: the shifted plan's control, clipped; never a panic.
    let mut ctrl =
        Controller::<_, 2, 4>::with_solver(sys, config, straight(), Box::new(Failing)).unwrap();
    let out = ctrl.step(&z);
    assert_eq!(
        out.status,
        ControlStatus::QpFailed(QpStatus::NumericalError)
    );
    assert_eq!(out.tau, Vector::<2>::zeros(), "zero-torque initial plan");
    assert_eq!(out.status.code(), 2);
}

/// A backend that fails for the first `failures` solves, then delegates.
struct FailingFirst {
    failures: usize,
    inner: Box<dyn QpSolver + Send>,
}
impl QpSolver for FailingFirst {
    fn name(&self) -> &'static str {
        "failing-first"
    }
    fn solve(&mut self, qp: &OcpQp, sol: &mut QpSolution) -> QpStatus {
        if self.failures > 0 {
            self.failures -= 1;
            sol.status = QpStatus::NumericalError;
            return QpStatus::NumericalError;
        }
        self.inner.solve(qp, sol)
    }
}

#[test]
fn repeated_qp_failures_discard_the_plan_and_the_controller_recovers() {
    let sys = DoublePendulum::default();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.horizon = 40;
    let z = Z::new(0.3, 0.1, 0.0, 0.0);
    let reference_tau = Controller::<_, 2, 4>::new(sys, config, curved())
        .unwrap()
        .step(&z)
        .tau;
    // First sample solved, then MAX_QP_FAILURES failures in a row.
    let inner = eigenmpc::mpc::QpBackend::default().create(4, 2, config.horizon);
    let solver = FailingFirst { failures: 0, inner };
    let mut ctrl =
        Controller::<_, 2, 4>::with_solver(sys, config, curved(), Box::new(solver)).unwrap();
    assert!(ctrl.step(&z).status.is_ok());
    let mut failing = Controller::<_, 2, 4>::with_solver(
        sys,
        config,
        curved(),
        Box::new(FailingFirst {
            failures: eigenmpc::mpc::MAX_QP_FAILURES,
            inner: eigenmpc::mpc::QpBackend::default().create(4, 2, config.horizon),
        }),
    )
    .unwrap();
    for _ in 0..eigenmpc::mpc::MAX_QP_FAILURES {
        let out = failing.step(&z);
        assert!(
            matches!(out.status, ControlStatus::QpFailed(_)),
            "{:?}",
            out.status
        );
        assert!(out.tau.iter().all(|t| t.is_finite() && t.abs() <= 1.0));
    }
    // The plan was discarded: the next sample starts afresh from the measured
    // state, solved to convergence, exactly like a fresh controller.
    let out = failing.step(&z);
    assert_eq!(out.status, ControlStatus::Solved);
    assert!(
        out.sqp_iterations > 1,
        "converged SQP, not a single RTI step"
    );
    assert!(
        (out.tau - reference_tau).amax() < 1e-6,
        "{} vs {}",
        out.tau,
        reference_tau
    );
    // A non-finite plan is discarded at the first failure: a huge speed drives
    // the RK4 rollout to overflow and the QP data to NaN.
    let wild = Z::new(0.3, 0.1, 1e200, -1e200);
    let out = ctrl.step(&wild);
    assert!(!out.status.is_ok(), "{:?}", out.status);
    let out = ctrl.step(&z);
    assert!(out.status.is_ok(), "recovered: {:?}", out.status);
}

#[test]
fn bad_configuration_and_tuning_are_refused() {
    let sys = DoublePendulum::default();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.dt = f64::NAN;
    assert!(matches!(
        Controller::<_, 2, 4>::new(sys, config, straight()),
        Err(MpcError::InvalidParameter { name: "dt", .. })
    ));
    assert!(Reference::new(Variant::Straight, Guide::Line(Vector::<2>::zeros())).is_err());
    let mut nan_chart = curved().chart().unwrap().clone();
    nan_chart.coefficients[0][1] = f64::NAN;
    let bad_ref = Reference::with_chart(Variant::Curved, nan_chart);
    assert!(Controller::<_, 2, 4>::new(sys, MpcConfig::paper(Variant::Curved), bad_ref).is_err());
    let mut ctrl =
        Controller::<_, 2, 4>::new(sys, MpcConfig::paper(Variant::Straight), straight()).unwrap();
    assert!(ctrl.set_e_ref(f64::NAN).is_err());
    assert!(ctrl.set_alpha(-1.0).is_err());
    assert_eq!(
        ctrl.config().cost.e_ref,
        14.0,
        "a refused value leaves the old one"
    );
    ctrl.set_e_ref(8.0).unwrap();
    assert_eq!(ctrl.config().cost.e_ref, 8.0);
}

#[test]
fn e_ref_change_between_samples_changes_the_plan() {
    let sys = DoublePendulum::default();
    let mut config = MpcConfig::paper(Variant::Straight);
    config.horizon = 30;
    let z = Z::new(0.3, 0.3, 0.0, 0.0);
    let mut a = Controller::<_, 2, 4>::new(sys, config, straight()).unwrap();
    let mut b = Controller::<_, 2, 4>::new(sys, config, straight()).unwrap();
    a.step(&z);
    b.step(&z);
    a.prepare();
    b.prepare();
    b.set_e_ref(3.0).unwrap(); // after preparation: the controller re-linearises
    let ta = a.step(&z).tau;
    let tb = b.step(&z).tau;
    assert!((ta - tb).amax() > 1e-3, "{ta:?} vs {tb:?}");
}

/// Hybrid EigenMPC on an exact chart: pumps the paper's pendulum to 14 J
/// (5 % band) and ends with small torque, as curved does.
#[test]
fn hybrid_closed_loop_reaches_the_mode() {
    use eigenmpc::mpc::closed_loop::{run, summarise};
    let sys = DoublePendulum::default();
    let (mode, chart) = mode_and_chart::<_, 2, 4>(&sys, 0, 14.0, 9).unwrap();
    let mut config = MpcConfig::paper(Variant::Hybrid);
    config.cost.alpha = 0.01;
    config.cost.beta = 0.9;
    let mut ctrl =
        Controller::<_, 2, 4>::new(sys, config, Reference::with_chart(Variant::Hybrid, chart))
            .unwrap();
    let trace = run(&mut ctrl, &sys, &Z::new(0.05, 0.05, 0.0, 0.0), 30.0).unwrap();
    let s = summarise(&trace, 14.0, Some(&mode.path), 5.0);
    assert!(s.time_to_5_percent.is_some_and(|t| t < 25.0), "{s:?}");
    assert!(s.rms_distance.unwrap() < 0.01, "{s:?}");
    assert!(s.rms_torque.amax() < 0.05, "{s:?}");
    assert_eq!(s.failures, 0);
}
