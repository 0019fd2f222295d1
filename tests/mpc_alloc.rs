//! The per-sample control step allocates nothing of its own (counting
//! global allocator). clarabel's `solve` itself allocates once per call (its
//! timer map is rebuilt by `Info::reset`); that is measured separately and
//! bounded, so a regression on either side fails.

use eigenmpc::mechanics::DoublePendulum;
use eigenmpc::modes::{ChartFamily, FamilyOptions, linear_modes};
use eigenmpc::mpc::Guide;
use eigenmpc::mpc::closed_loop::mode_and_chart;
use eigenmpc::mpc::{Controller, EstimatorConfig, MpcConfig, QpBackend, Reference, Variant};
use eigenmpc::qp::clarabel::{ClarabelQpSolver, rti_settings};
use eigenmpc::qp::{OcpQp, QpSolution, QpSolver, QpStatus};
use nalgebra::SVector;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
/// Allocations outside the QP backend.
static OURS: AtomicUsize = AtomicUsize::new(0);
/// Allocations inside the QP backend's `solve`.
static BACKEND: AtomicUsize = AtomicUsize::new(0);
static IN_BACKEND: AtomicUsize = AtomicUsize::new(0);

fn count() {
    if IN_BACKEND.load(Ordering::SeqCst) > 0 {
        BACKEND.fetch_add(1, Ordering::SeqCst);
    } else {
        OURS.fetch_add(1, Ordering::SeqCst);
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// clarabel, with its allocations attributed to the backend.
struct Attributed(ClarabelQpSolver);
impl QpSolver for Attributed {
    fn name(&self) -> &'static str {
        self.0.name()
    }
    fn solve(&mut self, qp: &OcpQp, solution: &mut QpSolution) -> QpStatus {
        IN_BACKEND.fetch_add(1, Ordering::SeqCst);
        let status = self.0.solve(qp, solution);
        IN_BACKEND.fetch_sub(1, Ordering::SeqCst);
        status
    }
}

#[test]
fn control_steps_do_not_allocate() {
    let sys = DoublePendulum::default();
    let (_, chart) = mode_and_chart::<_, 2, 4>(&sys, 0, 14.0, 9).unwrap();
    let references = [
        Reference::new(
            Variant::Straight,
            Guide::Line(linear_modes(&sys).unwrap()[0].eigenvector),
        )
        .unwrap(),
        Reference::with_chart(Variant::Curved, chart),
    ];
    for reference in references {
        let variant = reference.variant();
        let mut config = MpcConfig::paper(variant);
        config.horizon = 40;
        let solver = Attributed(ClarabelQpSolver::new(4, 2, 40, rti_settings()));
        let mut ctrl =
            Controller::<_, 2, 4>::with_solver(sys, config, reference, Box::new(solver)).unwrap();
        let mut z = SVector::<f64, 4>::new(0.3, 0.2, 0.0, 0.0);
        // First samples: set-up of the QP solver (pattern, symbolic factorisation).
        for _ in 0..3 {
            let tau = ctrl.step(&z).tau;
            z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&sys, &z, &tau, 0.025);
        }
        let ours = OURS.load(Ordering::SeqCst);
        let backend = BACKEND.load(Ordering::SeqCst);
        let samples = 50;
        for _ in 0..samples {
            ctrl.prepare();
            let out = ctrl.feedback(&z);
            assert!(out.status.is_ok());
            z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&sys, &z, &out.tau, 0.025);
        }
        // Tuning between samples does not allocate either.
        ctrl.set_e_ref(12.0).unwrap();
        ctrl.set_alpha(0.2).unwrap();
        ctrl.step(&z);
        let ours = OURS.load(Ordering::SeqCst) - ours;
        let backend = BACKEND.load(Ordering::SeqCst) - backend;
        assert_eq!(ours, 0, "{variant}: controller allocated {ours} times");
        assert!(
            backend <= samples + 1,
            "{variant}: clarabel allocated {backend} times in {} solves",
            samples + 1
        );
        eprintln!(
            "{variant}: clarabel allocations per solve: {}",
            backend as f64 / (samples + 1) as f64
        );

        // The Riccati backend, built by `Controller::new` from the config:
        // no allocation at all after the first sample. (Same test function:
        // the counters are global, parallel tests would disturb them.)
        config.qp = QpBackend::Riccati;
        let mut ctrl = Controller::<_, 2, 4>::new(sys, config, ctrl.reference().clone()).unwrap();
        let mut z = SVector::<f64, 4>::new(0.3, 0.2, 0.0, 0.0);
        z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&sys, &z, &ctrl.step(&z).tau, 0.025);
        let before = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst);
        for _ in 0..samples {
            ctrl.prepare();
            let out = ctrl.feedback(&z);
            assert!(out.status.is_ok());
            z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&sys, &z, &out.tau, 0.025);
        }
        ctrl.set_e_ref(12.0).unwrap();
        ctrl.step(&z);
        let total = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst) - before;
        assert_eq!(
            total, 0,
            "{variant}: riccati controller allocated {total} times"
        );
    }

    // A curved controller on a mode family: a tuned E_ref rewrites the
    // chart in place, without allocating.
    let family = ChartFamily::compute::<_, 4>(&sys, 0, &FamilyOptions::up_to(20.0)).unwrap();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.horizon = 40;
    let mut ctrl = Controller::<_, 2, 4>::with_family(sys, config, family).unwrap();
    let mut z = SVector::<f64, 4>::new(0.3, 0.2, 0.0, 0.0);
    z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&sys, &z, &ctrl.step(&z).tau, 0.025);
    let before = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst);
    for k in 0..50 {
        ctrl.set_e_ref(8.0 + 0.1 * k as f64).unwrap();
        let out = ctrl.step(&z);
        assert!(out.status.is_ok());
        z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&sys, &z, &out.tau, 0.025);
    }
    let total = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst) - before;
    assert_eq!(total, 0, "family controller allocated {total} times");

    // A model's family of a higher degree (the adaptation refits a curved
    // mode's charts, `ChartFamily::compute_accurate`) is written into the
    // chart the controller has, without allocating.
    let higher = ChartFamily::compute::<_, 4>(
        &sys,
        0,
        &FamilyOptions {
            degree: 13,
            ..FamilyOptions::up_to(20.0)
        },
    )
    .unwrap();
    let before = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst);
    let old = ctrl.replace_model(sys, Some(higher)).unwrap();
    for _ in 0..10 {
        let out = ctrl.step(&z);
        assert!(out.status.is_ok());
        z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&sys, &z, &out.tau, 0.025);
    }
    let total = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst) - before;
    assert_eq!(total, 0, "a degree-13 family allocated {total} times");
    assert_eq!(ctrl.reference().chart().unwrap().degree, 13);
    drop(old);

    // A state saved with a degree-9 chart and restored has the same room:
    // a degree-13 family goes into it without allocating.
    let nine = ChartFamily::compute::<_, 4>(&sys, 0, &FamilyOptions::up_to(20.0)).unwrap();
    let thirteen = ctrl.replace_model(sys, Some(nine)).unwrap();
    let saved = ctrl.save_state();
    ctrl.restore_state(saved).unwrap();
    assert_eq!(ctrl.reference().chart().unwrap().degree, 9);
    let before = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst);
    let old = ctrl.replace_model(sys, thirteen).unwrap();
    let out = ctrl.step(&z);
    assert!(out.status.is_ok());
    let total = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst) - before;
    assert_eq!(total, 0, "a family after a restore allocated {total} times");
    assert_eq!(ctrl.reference().chart().unwrap().degree, 13);
    drop(old);

    // With the state estimator: predict and correct allocate nothing.
    let (_, chart) = mode_and_chart::<_, 2, 4>(&sys, 0, 14.0, 9).unwrap();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.horizon = 40;
    config.estimator = Some(EstimatorConfig {
        angle_noise: 0.05,
        speed_noise: 0.05,
        acceleration_noise: 0.3,
    });
    let mut ctrl =
        Controller::<_, 2, 4>::new(sys, config, Reference::with_chart(Variant::Curved, chart))
            .unwrap();
    let mut z = SVector::<f64, 4>::new(0.3, 0.2, 0.0, 0.0);
    z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&sys, &z, &ctrl.step(&z).tau, 0.025);
    let before = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst);
    for k in 0..50 {
        let noisy = z.map(|v| v + 0.01 * ((k * 7919) % 13) as f64 / 13.0);
        let out = ctrl.step(&noisy);
        assert!(out.status.is_ok());
        assert!(ctrl.state_estimate().is_some());
        z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&sys, &z, &out.tau, 0.025);
    }
    let total = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst) - before;
    assert_eq!(
        total, 0,
        "controller with estimator allocated {total} times"
    );

    // With a measurement delay (fractional: 2.5 samples), an actuator lag
    // and the estimator: the forward prediction and the command history
    // allocate nothing either.
    config.measurement_delay = 0.0625;
    config.actuator_time_constant = 0.05;
    let mut ctrl = Controller::<_, 2, 4>::new(sys, config, ctrl.reference().clone()).unwrap();
    let mut z = SVector::<f64, 4>::new(0.3, 0.2, 0.0, 0.0);
    z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&sys, &z, &ctrl.step(&z).tau, 0.025);
    let before = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst);
    for _ in 0..50 {
        let out = ctrl.step(&z);
        assert!(out.status.is_ok());
        assert!(ctrl.predicted_current_state().is_some());
        z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&sys, &z, &out.tau, 0.025);
    }
    let total = OURS.load(Ordering::SeqCst) + BACKEND.load(Ordering::SeqCst) - before;
    assert_eq!(
        total, 0,
        "controller with delay, lag and estimator allocated {total} times"
    );
}
