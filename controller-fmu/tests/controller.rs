//! The EigenMPC FMU through its FMI 2.0 C functions (sampling and hold,
//! initialization, tunables, parameter checks), the plain C API's argument
//! handling, the default chart, the checked-in model description and the
//! built shared library.

use eigenmpc::mechanics::{DoublePendulum, Vector};
use eigenmpc::modes::Chart;
use eigenmpc::mpc::closed_loop::{mode_and_chart, run};
use eigenmpc::mpc::{ControlStatus, Variant};
use eigenmpc_fmu::capi::*;
use eigenmpc_fmu::fmi2_exports::*;
use eigenmpc_fmu::settings::CHART_COEFFICIENTS;
use eigenmpc_fmu::*;
use fmi2_slave::testing::TestInstance;
use fmi2_slave::{Model, Value, ffi, xml};
use nalgebra::SVector;
use std::ffi::CStr;
use std::path::PathBuf;
use std::ptr;

const OK: ffi::fmi2Status = ffi::fmi2Status_fmi2OK;
const WARNING: ffi::fmi2Status = ffi::fmi2Status_fmi2Warning;
const ERROR: ffi::fmi2Status = ffi::fmi2Status_fmi2Error;
/// Value reference of `name` in the FMU's variable table.
fn vref(name: &str) -> u32 {
    EigenMpcFmu::description()
        .variable(name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

fn state() -> [u32; 4] {
    [vref("q[1]"), vref("q[2]"), vref("qd[1]"), vref("qd[2]")]
}

struct Fmu {
    c: ffi::fmi2Component,
    instance: TestInstance,
    t: f64,
}

impl Fmu {
    fn instantiate() -> Self {
        let instance = TestInstance::new::<EigenMpcFmu>(Some(fmi2Instantiate), "controller");
        Self {
            c: instance.component,
            instance,
            t: 0.0,
        }
    }

    /// Instantiated, parameters and initial state set, initialized.
    fn start(params: &[(u32, f64)], integers: &[(u32, i32)], z0: [f64; 4]) -> Self {
        Self::start_with(params, integers, &[], z0)
    }

    /// [`Fmu::start`] with Boolean parameters too.
    fn start_with(
        params: &[(u32, f64)],
        integers: &[(u32, i32)],
        booleans: &[(u32, bool)],
        z0: [f64; 4],
    ) -> Self {
        let fmu = Self::instantiate();
        for &(vr, v) in booleans {
            let v = ffi::fmi2Boolean::from(v);
            assert_eq!(unsafe { fmi2SetBoolean(fmu.c, &vr, 1, &v) }, OK);
        }
        for &(vr, v) in params {
            assert_eq!(fmu.set(&[vr], &[v]), OK, "{:?}", fmu.instance.log.lines());
        }
        for &(vr, v) in integers {
            assert_eq!(
                fmu.set_int(&[vr], &[v]),
                OK,
                "{:?}",
                fmu.instance.log.lines()
            );
        }
        unsafe {
            assert_eq!(fmi2SetupExperiment(fmu.c, 0, 0.0, 0.0, 0, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
            assert_eq!(fmu.set(&state(), &z0), OK);
            assert_eq!(
                fmi2ExitInitializationMode(fmu.c),
                OK,
                "{:?}",
                fmu.instance.log.lines()
            );
        }
        fmu
    }

    fn set(&self, vr: &[u32], v: &[f64]) -> ffi::fmi2Status {
        unsafe { fmi2SetReal(self.c, vr.as_ptr(), vr.len(), v.as_ptr()) }
    }

    fn set_int(&self, vr: &[u32], v: &[i32]) -> ffi::fmi2Status {
        unsafe { fmi2SetInteger(self.c, vr.as_ptr(), vr.len(), v.as_ptr()) }
    }

    fn tau(&self) -> [f64; 2] {
        let mut v = [f64::NAN; 2];
        let vr = [vref("tau[1]"), vref("tau[2]")];
        assert_eq!(
            unsafe { fmi2GetReal(self.c, vr.as_ptr(), 2, v.as_mut_ptr()) },
            OK
        );
        v
    }

    fn real(&self, vr: u32) -> f64 {
        let mut v = f64::NAN;
        assert_eq!(unsafe { fmi2GetReal(self.c, &vr, 1, &mut v) }, OK);
        v
    }

    fn integer(&self, vr: u32) -> i32 {
        let mut v = -99;
        assert_eq!(unsafe { fmi2GetInteger(self.c, &vr, 1, &mut v) }, OK);
        v
    }

    fn step(&mut self, h: f64) -> ffi::fmi2Status {
        let status = unsafe { fmi2DoStep(self.c, self.t, h, 1) };
        self.t += h;
        status
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) }
    }
}

const Z0: [f64; 4] = [0.05, 0.05, 0.0, 0.0];
const DT: f64 = 0.025;

/// States and torques of a native closed loop of `seconds` (controller
/// built from the same settings as the FMU's defaults).
fn native_trace(seconds: f64) -> Vec<(SVector<f64, 4>, Vector<2>)> {
    let mut controller = EigenMpc2::settings(Variant::Curved).build::<4>().unwrap();
    let trace = run(
        &mut controller,
        &DoublePendulum::default(),
        &SVector::<f64, 4>::from(Z0),
        seconds,
    )
    .unwrap();
    trace.iter().map(|s| (s.state, s.tau)).collect()
}

#[test]
fn solves_on_the_sample_grid_and_holds_in_between() {
    let native = native_trace(1.0);
    // Communication step = sample period: one solve per step.
    let mut fmu = Fmu::start(&[], &[], Z0);
    assert_eq!(
        fmu.tau(),
        [native[0].1[0], native[0].1[1]],
        "first solve at init"
    );
    assert_eq!(fmu.integer(vref("solver_status")), 0);
    assert!(fmu.integer(vref("qp_iterations")) > 0);
    for (k, (z, tau)) in native.iter().enumerate().take(native.len() - 1) {
        assert_eq!(fmu.set(&state(), z.as_slice()), OK);
        assert_eq!(fmu.step(DT), OK, "{:?}", fmu.instance.log.lines());
        assert_eq!(fmu.tau(), [tau[0], tau[1]], "sample {k}");
        let e = eigenmpc_fmu_energy(z);
        assert!((fmu.real(vref("energy")) - e).abs() < 1e-12);
        assert!(fmu.real(vref("solve_time")) > 0.0);
    }
    // Five communication steps per sample: solves only on the grid; the
    // inputs between grid points do not matter.
    let mut fmu = Fmu::start(&[], &[], Z0);
    for (k, (z, tau)) in native.iter().enumerate().take(native.len() - 1) {
        for i in 0..5 {
            let decoy = z.map(|v| v + 0.3 * i as f64);
            let input = if i == 0 { *z } else { decoy };
            assert_eq!(fmu.set(&state(), input.as_slice()), OK);
            assert_eq!(fmu.step(DT / 5.0), OK);
            assert_eq!(fmu.tau(), [tau[0], tau[1]], "sample {k}, substep {i}");
        }
    }
    assert!(fmu.instance.log.lines().iter().all(|l| l.status == OK));
}

fn eigenmpc_fmu_energy(z: &SVector<f64, 4>) -> f64 {
    eigenmpc::mechanics::state_energy::<_, 2, 4>(&DoublePendulum::default(), z)
}

/// Messages logged under `logStatusWarning` that contain `needle`.
fn warnings_logged(fmu: &Fmu, needle: &str) -> usize {
    fmu.instance
        .log
        .lines()
        .iter()
        .filter(|l| l.category == "logStatusWarning" && l.message.contains(needle))
        .count()
}

/// Off-grid and long steps are documented behaviour: logged once under
/// `logStatusWarning`, and every call returns fmi2OK (fmusim and other
/// masters stop at the first fmi2Warning).
#[test]
fn off_grid_and_long_steps_warn_once_and_keep_solving() {
    // 10 ms steps: the grid points at 25, 75, ... ms fall inside steps.
    // Each communication point gets its own state (q[1] = 0.05 + 0.001 i), so
    // the `energy` output tells exactly which point's inputs the last solve used.
    let mut fmu = Fmu::start(&[], &[], Z0);
    let mut statuses = vec![];
    let mut solved_at = vec![];
    let mut held = eigenmpc_fmu_energy(&SVector::from(Z0));
    for i in 0..20 {
        let z = SVector::from([Z0[0] + 0.001 * i as f64, Z0[1], Z0[2], Z0[3]]);
        assert_eq!(fmu.set(&state(), z.as_slice()), OK);
        let t = fmu.t;
        statuses.push(fmu.step(0.01));
        let energy = fmu.real(vref("energy"));
        if i > 0 && energy == eigenmpc_fmu_energy(&z) {
            solved_at.push(t);
            held = energy;
        } else {
            assert_eq!(energy, held, "no solve at t = {t}: output held");
        }
    }
    assert!(statuses.iter().all(|&s| s == OK), "{statuses:?}");
    assert_eq!(warnings_logged(&fmu, "not on the sample grid"), 1);
    // Grid points 25, 50, ..., 175 ms; each is solved at the first
    // communication point at or after it (t = 0 was solved at initialization).
    let expected = [0.03, 0.05, 0.08, 0.10, 0.13, 0.15, 0.18];
    assert_eq!(solved_at.len(), expected.len(), "solves at {solved_at:?}");
    for (t, e) in solved_at.iter().zip(expected) {
        assert!((t - e).abs() < 1e-12, "solves at {solved_at:?}");
    }

    let mut fmu = Fmu::start(&[], &[], Z0);
    let mut last = fmu.tau();
    for k in 0..5 {
        assert_eq!(fmu.step(0.1), OK);
        if k == 0 {
            // t = 0 was solved at initialization
            assert_eq!(fmu.tau(), last);
        } else {
            assert_ne!(fmu.tau(), last, "one solve per long step");
        }
        last = fmu.tau();
    }
    assert_eq!(warnings_logged(&fmu, "longer than the sample period"), 1);
}

#[test]
fn new_initial_inputs_after_initialization_are_solved_again() {
    let native = native_trace(0.05);
    let mut fmu = Fmu::start(&[], &[], [0.3, -0.2, 0.0, 0.0]);
    let first = fmu.tau();
    assert_eq!(fmu.set(&state(), &Z0), OK);
    assert_eq!(fmu.step(DT), OK);
    assert_ne!(fmu.tau(), first);
    assert_eq!(fmu.tau(), [native[0].1[0], native[0].1[1]]);
}

#[test]
fn tunable_parameters_are_followed_and_checked() {
    let mut fmu = Fmu::start(&[], &[], Z0);
    assert_eq!(fmu.step(DT), OK);
    let model = |f: &Fmu| unsafe {
        let instance = &*(f.c as *const fmi2_slave::Instance<EigenMpcFmu>);
        instance.model().unwrap().controller().config().cost
    };
    assert_eq!(model(&fmu).e_ref, 14.0);
    assert_eq!(model(&fmu).weights.energy, 25.0, "w_E < 0: paper value");
    assert_eq!(fmu.set(&[vref("E_ref"), vref("w_E")], &[8.0, 7.5]), OK);
    assert_eq!(model(&fmu).e_ref, 8.0);
    assert_eq!(model(&fmu).weights.energy, 7.5);
    assert_eq!(fmu.step(DT), OK);
    // out of range: refused, nothing changes, the old values stay readable;
    // fmi2Error puts the instance in the FMI error state until fmi2Reset
    assert_eq!(fmu.set(&[vref("E_ref"), vref("w_F")], &[9.0, 0.0]), ERROR);
    assert!(fmu.instance.log.contains(&["w_F = 0 is below its minimum"]));
    assert_eq!(model(&fmu).e_ref, 8.0);
    assert_eq!(
        (fmu.real(vref("E_ref")), fmu.real(vref("w_F"))),
        (8.0, 225.0)
    );
    assert_eq!(fmu.step(DT), ERROR);
    assert!(
        fmu.instance
            .log
            .contains(&["fmi2DoStep: not allowed in state error"])
    );
    unsafe {
        assert_eq!(fmi2Reset(fmu.c), OK);
        assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
    }
    assert_eq!(fmu.real(vref("E_ref")), 14.0, "reset: start values");

    let mut fmu = Fmu::start(&[], &[], Z0);
    assert_eq!(fmu.step(DT), OK);
    assert_eq!(
        fmu.set(&[vref("tau_max")], &[2.0]),
        ERROR,
        "fixed in step mode"
    );
    assert!(
        fmu.instance
            .log
            .contains(&["tau_max", "cannot be set in state stepComplete"])
    );
}

#[test]
fn invalid_parameters_are_rejected_with_a_message() {
    for (vr, v, needle) in [
        (vref("E_ref"), -1.0, "E_ref = -1 is below its minimum"),
        (
            vref("sample_period"),
            0.0,
            "sample_period = 0 is below its minimum",
        ),
        (vref("m[1]"), f64::NAN, "m[1] = NaN is not a finite number"),
        (vref("c[1]"), 2.0, "c[1] = 2 is above its maximum"),
        (
            vref("q[1]"),
            f64::INFINITY,
            "q[1] = inf is not a finite number",
        ),
    ] {
        let fmu = Fmu::instantiate();
        assert_eq!(fmu.set(&[vr], &[v]), ERROR);
        assert!(
            fmu.instance.log.contains(&[needle]),
            "{:?}",
            fmu.instance.log.lines()
        );
    }
    let fmu = Fmu::instantiate();
    assert_eq!(fmu.set_int(&[vref("variant")], &[4]), ERROR);
    assert!(
        fmu.instance
            .log
            .contains(&["variant = 4 is above its maximum"])
    );
    assert_eq!(unsafe { fmi2Reset(fmu.c) }, OK);
    assert_eq!(fmu.set_int(&[vref("horizon")], &[0]), ERROR);
    // relations checked at exitInitializationMode
    let fmu = Fmu::instantiate();
    assert_eq!(fmu.set(&[vref("c[1]"), vref("c[2]")], &[0.0, 0.0]), OK);
    assert_eq!(
        fmu.set_int(&[vref("chart_source")], &[CHART_SOURCE_PARAMETERS]),
        OK
    );
    initialization_fails(&fmu, &["fmi2ExitInitializationMode", "eigenvector"]);
    // clarabel's work grows faster than N: a long horizon is refused with it
    let fmu = Fmu::instantiate();
    assert_eq!(fmu.set_int(&[vref("horizon")], &[1000]), OK);
    assert_eq!(fmu.set_int(&[vref("qp_solver")], &[QP_SOLVER_CLARABEL]), OK);
    initialization_fails(
        &fmu,
        &["horizon = 1000 with qp_solver = clarabel: at most 200"],
    );
}

/// Initialization of `fmu` fails with a message containing `needles`.
fn initialization_fails(fmu: &Fmu, needles: &[&str]) {
    unsafe {
        assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
        assert_eq!(fmi2ExitInitializationMode(fmu.c), ERROR);
    }
    assert!(
        fmu.instance.log.contains(needles),
        "{:?}",
        fmu.instance.log.lines()
    );
}

/// The chart of the controller behind `fmu`.
fn chart_in_use(fmu: &Fmu) -> Chart<2> {
    let instance = unsafe { &*(fmu.c as *const fmi2_slave::Instance<EigenMpcFmu>) };
    match instance.model().unwrap().controller().reference() {
        r if r.variant() == eigenmpc::mpc::Variant::Curved => r.chart().unwrap().clone(),
        other => panic!("not curved: {other:?}"),
    }
}

/// Largest joint-space distance between two charts along s in [-1, 1] rad.
fn chart_distance(a: &Chart<2>, b: &Chart<2>) -> f64 {
    (0..=40)
        .map(|i| {
            let s = -1.0 + i as f64 / 20.0;
            (a.eval(s).x - b.eval(s).x).amax()
        })
        .fold(0.0, f64::max)
}

/// The default reference is computed from the model: the in-phase family,
/// whose chart at the default E_ref is the pasted 14 J chart (to the fit's
/// accuracy), and a tuned E_ref gets its own chart at the next sample.
#[test]
fn computed_chart_follows_a_tuned_e_ref() {
    let mut fmu = Fmu::start(&[], &[], Z0);
    assert_eq!(fmu.integer(vref("chart_source")), CHART_SOURCE_COMPUTED);
    let (lo, hi) = (
        fmu.real(vref("chart_energy_min")),
        fmu.real(vref("chart_energy_max")),
    );
    assert_eq!(fmu.real(vref("chart_energy")), 14.0);
    assert!(lo < 1.0 && hi >= 17.5, "{lo} .. {hi} J");
    let system = DoublePendulum::default();
    let fitted = |e: f64| {
        mode_and_chart::<_, 2, 4>(&system, 0, e, CHART_COEFFICIENTS - 1)
            .unwrap()
            .1
    };
    let d14 = chart_distance(&chart_in_use(&fmu), &fitted(14.0));
    assert!(d14 < 2e-3, "14 J: computed vs fitted chart {d14} rad");
    assert_eq!(fmu.step(DT), OK);
    assert_eq!(fmu.set(&[vref("E_ref")], &[8.0]), OK);
    assert_eq!(fmu.real(vref("chart_energy")), 8.0);
    let d8 = chart_distance(&chart_in_use(&fmu), &fitted(8.0));
    let d8_fixed = chart_distance(&fitted(14.0), &fitted(8.0));
    assert!(
        d8 < 2e-3 && d8_fixed > 50.0 * d8,
        "8 J: {d8} rad (the 14 J chart: {d8_fixed} rad)"
    );
    assert_eq!(fmu.step(DT), OK);
    // Above the family: clamped, said under logStatusWarning, call OK.
    assert_eq!(fmu.set(&[vref("E_ref")], &[hi + 5.0]), OK);
    assert_eq!(fmu.real(vref("chart_energy")), hi);
    assert!(
        fmu.instance
            .log
            .contains(&["outside the chart family's range"])
    );
    assert_eq!(fmu.step(DT), OK);
}

/// chart_source = parameters uses c[j] and chart.coef[j,k] as given;
/// computed ignores them and says so; mode = 2 computes the anti-phase family.
#[test]
fn chart_source_and_mode_select_the_reference() {
    let anti = mode_and_chart::<_, 2, 4>(&DoublePendulum::default(), 1, 3.0, 9).unwrap();
    let mut params = vec![(vref("E_ref"), 3.0)];
    for j in 0..2 {
        params.push((vref(&format!("c[{}]", j + 1)), anti.1.eigenvector[j]));
        for (k, a) in anti.1.coefficients[j].iter().enumerate() {
            params.push((vref(&format!("chart.coef[{},{k}]", j + 1)), *a));
        }
    }
    let given = Fmu::start(
        &params,
        &[(vref("chart_source"), CHART_SOURCE_PARAMETERS)],
        Z0,
    );
    assert_eq!(chart_distance(&chart_in_use(&given), &anti.1), 0.0);
    assert_eq!(given.real(vref("chart_energy_max")), 0.0, "no family");

    let ignored = Fmu::start(&params, &[], Z0);
    assert!(
        ignored
            .instance
            .log
            .contains(&["are not used: chart_source = computed"])
    );
    let d = chart_distance(&chart_in_use(&ignored), &anti.1);
    assert!(
        d > 0.1,
        "in-phase family, not the given anti-phase chart: {d}"
    );

    let computed = Fmu::start(&params[..1], &[(vref("mode"), 2)], Z0);
    let d = chart_distance(&chart_in_use(&computed), &anti.1);
    assert!(d < 2e-3, "anti-phase family at 3 J vs fitted: {d} rad");
    assert!(computed.instance.log.lines().iter().all(|l| l.status == OK));
}

/// variant = hybrid: the computed chart family, blended; a tuned E_ref
/// moves its chart as for curved.
#[test]
fn hybrid_variant_follows_the_computed_family() {
    let mut fmu = Fmu::start(&[], &[(vref("variant"), VARIANT_HYBRID)], Z0);
    let instance = unsafe { &*(fmu.c as *const fmi2_slave::Instance<EigenMpcFmu>) };
    let controller = instance.model().unwrap().controller();
    assert_eq!(controller.reference().variant(), Variant::Hybrid);
    assert_eq!(controller.config().cost.weights.energy, 25.0);
    assert!(controller.family().is_some());
    assert_eq!(fmu.step(DT), OK);
    assert_eq!(fmu.set(&[vref("E_ref")], &[8.0]), OK);
    assert_eq!(fmu.real(vref("chart_energy")), 8.0);
    assert_eq!(fmu.step(DT), OK);
    assert_eq!(fmu.integer(vref("solver_status")), 0);
}

/// state_estimator = ekf with its noise levels: the FMU filters noisy
/// inputs exactly as the library's controller with that estimator does.
#[test]
fn state_estimator_filters_the_inputs_like_the_library() {
    let mut fmu = Fmu::start(
        &[
            (vref("angle_noise"), 0.02),
            (vref("acceleration_noise"), 0.5),
        ],
        &[(vref("state_estimator"), STATE_ESTIMATOR_EKF)],
        Z0,
    );
    let mut settings = EigenMpc2::settings(Variant::Curved);
    settings.state_estimator = settings::StateEstimator::Ekf;
    settings.noise.angle_noise = 0.02;
    settings.noise.acceleration_noise = 0.5;
    let mut native = settings.build::<4>().unwrap();
    assert_eq!(native.config().estimator, Some(settings.noise));
    let first = native.step(&SVector::from(Z0)).tau;
    assert_eq!(fmu.tau(), [first[0], first[1]]);
    // t = 0: solved at initialization (same inputs: no new solve)
    assert_eq!(fmu.set(&state(), &Z0), OK);
    assert_eq!(fmu.step(DT), OK);
    for (k, (z, _)) in native_trace(0.5).iter().enumerate().skip(1) {
        let noisy = z.map(|v| v + 0.01 * (((k * 37) % 11) as f64 - 5.0) / 5.0);
        assert_eq!(fmu.set(&state(), noisy.as_slice()), OK);
        assert_eq!(fmu.step(DT), OK);
        let tau = native.step(&noisy).tau;
        assert_eq!(fmu.tau(), [tau[0], tau[1]], "sample {k}");
    }
    let instance = unsafe { &*(fmu.c as *const fmi2_slave::Instance<EigenMpcFmu>) };
    assert!(
        instance
            .model()
            .unwrap()
            .controller()
            .state_estimate()
            .is_some()
    );
}

#[test]
fn straight_variant_uses_its_paper_weight() {
    let fmu = Fmu::start(&[], &[(vref("variant"), VARIANT_STRAIGHT)], Z0);
    let instance = unsafe { &*(fmu.c as *const fmi2_slave::Instance<EigenMpcFmu>) };
    let controller = instance.model().unwrap().controller();
    assert_eq!(controller.config().cost.weights.energy, 5.0);
    assert_eq!(controller.reference().variant(), Variant::Straight);
    let tau = fmu.tau();
    assert!(tau[0].abs() <= 1.0 && tau[1].abs() <= 1.0 && tau != [0.0, 0.0]);
}

#[test]
fn a_failed_solve_returns_the_fallback_with_its_status() {
    // A state so fast that the prediction overflows: the QP data are not
    // finite and the QP fails; the FMU logs and holds a bounded torque.
    let mut fmu = Fmu::start(&[], &[], Z0);
    assert_eq!(fmu.set(&state(), &[0.1, 0.1, 1e6, -1e6]), OK);
    let status = fmu.step(DT);
    assert_eq!(status, WARNING, "{:?}", fmu.instance.log.lines());
    let code = fmu.integer(vref("solver_status"));
    assert_eq!(code, STATUS_QP_FAILED);
    assert!(fmu.instance.log.contains(&["QP failed"]));
    let tau = fmu.tau();
    assert!(tau.iter().all(|t| t.is_finite() && t.abs() <= 1.0));
}

/// After a failed QP with a non-finite plan the controller re-initialises its
/// plan, so the next sample with a sane state is solved again.
#[test]
fn the_controller_recovers_after_a_failed_solve() {
    let mut fmu = Fmu::start(&[], &[], Z0);
    assert_eq!(fmu.set(&state(), &[0.1, 0.1, 1e6, -1e6]), OK);
    assert_eq!(fmu.step(DT), WARNING);
    assert_eq!(fmu.integer(vref("solver_status")), STATUS_QP_FAILED);
    assert_eq!(fmu.set(&state(), &Z0), OK);
    assert_eq!(fmu.step(DT), OK, "{:?}", fmu.instance.log.lines());
    assert_eq!(fmu.integer(vref("solver_status")), STATUS_SOLVED);
    assert!(fmu.tau().iter().all(|t| t.is_finite() && t.abs() <= 1.0));
}

#[test]
fn status_codes_match_the_controller() {
    assert_eq!(ControlStatus::Solved.code(), STATUS_SOLVED);
    assert_eq!(ControlStatus::NotConverged.code(), STATUS_NOT_CONVERGED);
    assert_eq!(ControlStatus::InvalidState.code(), STATUS_INVALID_STATE);
    assert_eq!(
        ControlStatus::QpFailed(eigenmpc::qp::QpStatus::MaxIterations).code(),
        STATUS_QP_FAILED
    );
}

#[test]
fn default_chart_and_eigenvector_are_the_14_j_in_phase_mode() {
    let system = DoublePendulum::default();
    let (mode, chart) =
        mode_and_chart::<_, 2, 4>(&system, 0, 14.0, CHART_COEFFICIENTS - 1).unwrap();
    let d = EigenMpcFmu::description();
    let start = |name: &str| match d.variable(name).unwrap().start {
        Some(Value::Real(x)) => x,
        other => panic!("{name}: {other:?}"),
    };
    let c = Vector::<2>::new(start("c[1]"), start("c[2]"));
    assert!(
        (c - chart.eigenvector).amax() < 1e-12,
        "{c} vs {}",
        chart.eigenvector
    );
    assert_eq!(start("E_ref"), 14.0);
    let coefficients: [Vec<f64>; 2] = std::array::from_fn(|j| {
        (0..CHART_COEFFICIENTS)
            .map(|k| start(&format!("chart.coef[{},{k}]", j + 1)))
            .collect()
    });
    // Coefficients agree to fitting noise (the even ones are ~1e-12 noise);
    // the curve itself agrees to far below the fit residual over the mode.
    for (fmu_row, fitted_row) in coefficients.iter().zip(&chart.coefficients) {
        for (k, (a, b)) in fmu_row.iter().zip(fitted_row).enumerate() {
            assert!(
                (a - b).abs() < 1e-8 * (1.0 + b.abs()),
                "power {k}: {a} vs {b}"
            );
        }
    }
    let pasted = Chart::from_coefficients(c, Vector::<2>::zeros(), coefficients).unwrap();
    for q in &mode.path {
        let s = chart.coordinate(q);
        assert!((pasted.eval(s).x - chart.eval(s).x).amax() < 1e-9);
    }
}

#[test]
fn c_api_refuses_bad_arguments_without_crashing() {
    unsafe {
        let mut err = [0 as std::ffi::c_char; 200];
        assert!(eigenmpc_create(ptr::null(), ptr::null(), err.as_mut_ptr(), 200).is_null());
        assert!(
            CStr::from_ptr(err.as_ptr())
                .to_str()
                .unwrap()
                .contains("config is NULL")
        );
        let mut config = eigenmpc_config_default(VARIANT_CURVED);
        config.horizon = 0;
        assert!(eigenmpc_create(&config, ptr::null(), err.as_mut_ptr(), 200).is_null());
        let text = CStr::from_ptr(err.as_ptr()).to_str().unwrap();
        assert!(text.contains("horizon"), "{text}");
        // a too small buffer is truncated, still NUL-terminated
        assert!(eigenmpc_create(&config, ptr::null(), err.as_mut_ptr(), 8).is_null());
        assert_eq!(CStr::from_ptr(err.as_ptr()).to_bytes().len(), 7);
        let config = eigenmpc_config_default(7);
        assert!(eigenmpc_create(&config, ptr::null(), ptr::null_mut(), 0).is_null());

        let config = eigenmpc_config_default(VARIANT_CURVED);
        let mpc = eigenmpc_create(&config, ptr::null(), ptr::null_mut(), 0);
        assert!(!mpc.is_null());
        let mut tau = [f64::NAN; 2];
        assert_eq!(
            eigenmpc_step(ptr::null_mut(), Z0.as_ptr(), tau.as_mut_ptr()),
            -1
        );
        assert_eq!(eigenmpc_step(mpc, ptr::null(), tau.as_mut_ptr()), -1);
        assert!(tau[0].is_nan(), "untouched");
        assert_eq!(eigenmpc_set_e_ref(mpc, f64::NAN), -1);
        let msg = CStr::from_ptr(eigenmpc_last_error(mpc)).to_str().unwrap();
        assert!(msg.contains("e_ref"), "{msg}");
        assert_eq!(
            eigenmpc_step(mpc, Z0.as_ptr(), tau.as_mut_ptr()),
            STATUS_SOLVED
        );
        let nan = [f64::NAN, 0.0, 0.0, 0.0];
        assert_eq!(
            eigenmpc_step(mpc, nan.as_ptr(), tau.as_mut_ptr()),
            STATUS_INVALID_STATE
        );
        assert!(tau.iter().all(|t| t.is_finite() && t.abs() <= 1.0));
        let mut info = EigenMpcStepInfo::default();
        assert_eq!(eigenmpc_last_step(mpc, &mut info), 0);
        assert_eq!(info.status, STATUS_INVALID_STATE);
        assert_eq!(eigenmpc_reset(ptr::null_mut()), -1);
        assert!(!eigenmpc_last_error(ptr::null()).is_null());
        eigenmpc_free(mpc);
        eigenmpc_free(ptr::null_mut());
    }
}

#[test]
fn c_api_steps_like_the_controller() {
    let native = native_trace(0.5);
    unsafe {
        let config = eigenmpc_config_default(VARIANT_CURVED);
        let mpc = eigenmpc_create(&config, ptr::null(), ptr::null_mut(), 0);
        let mut tau = [0.0; 2];
        for (z, t) in &native {
            assert_eq!(eigenmpc_step(mpc, z.as_ptr(), tau.as_mut_ptr()), 0);
            assert_eq!(tau, [t[0], t[1]]);
        }
        eigenmpc_free(mpc);
    }
}

/// `eigenmpc_create_named`: FMU parameter names for 2, 3 and 4 joints; the
/// 3-joint handle steps exactly like the `EigenMPC3` FMU's controller, and
/// a rigid-link model with friction given by name is the controller's model.
#[test]
fn c_api_creates_any_robot_from_parameter_names() {
    use eigenmpc_fmu_models::products::EigenMpc3;
    use std::ffi::CString;
    let named = |joints: u32, pairs: &[(&str, f64)]| -> (*mut EigenMpc, String) {
        let names: Vec<CString> = pairs.iter().map(|p| CString::new(p.0).unwrap()).collect();
        let pointers: Vec<*const std::ffi::c_char> = names.iter().map(|n| n.as_ptr()).collect();
        let values: Vec<f64> = pairs.iter().map(|p| p.1).collect();
        let mut err = [0 as std::ffi::c_char; 300];
        let mpc = unsafe {
            eigenmpc_create_named(
                joints,
                pointers.as_ptr(),
                values.as_ptr(),
                pairs.len(),
                err.as_mut_ptr(),
                err.len(),
            )
        };
        let text = unsafe { CStr::from_ptr(err.as_ptr()) };
        (mpc, text.to_str().unwrap().to_string())
    };
    // 3 joints, defaults: the EigenMPC3 FMU's controller, sample for sample.
    let (mpc, _) = named(3, &[]);
    assert!(!mpc.is_null());
    assert_eq!(unsafe { eigenmpc_joints(mpc) }, 3);
    let mut native = EigenMpc3::settings(Variant::Curved).build::<6>().unwrap();
    let mut z = SVector::<f64, 6>::new(0.05, 0.05, 0.05, 0.0, 0.0, 0.0);
    for _ in 0..20 {
        let mut tau = [f64::NAN; 3];
        assert_eq!(
            unsafe { eigenmpc_step(mpc, z.as_ptr(), tau.as_mut_ptr()) },
            0
        );
        let expected = native.step(&z).tau;
        assert_eq!(tau.as_slice(), expected.as_slice());
        z = z.map(|v| v * 1.01) + SVector::<f64, 6>::repeat(1e-3);
    }
    unsafe { eigenmpc_free(mpc) };

    // 2 joints, a rigid-link robot with friction, by name.
    let robot = [
        ("m[1]", 0.6),
        ("m[2]", 0.6),
        ("l[1]", 0.3),
        ("l[2]", 0.2),
        ("r[1]", 0.3),
        ("r[2]", 0.2),
        ("I[1]", 0.06),
        ("I[2]", 0.025),
        ("b[1]", 0.001),
        ("cf[2]", 0.09),
        ("E_ref", 1.0),
        ("tau_max", 0.5),
    ];
    let (mpc, err) = named(2, &robot);
    assert!(!mpc.is_null(), "{err}");
    let mut settings = EigenMpc2::settings(Variant::Curved);
    settings.model.mass = [0.6, 0.6];
    settings.model.length = [0.3, 0.2];
    settings.model.com = [0.3, 0.2];
    settings.model.inertia = [0.06, 0.025];
    settings.model.joints[0].viscous = 0.001;
    settings.model.joints[1].coulomb = 0.09;
    settings.tuning.e_ref = 1.0;
    settings.tau_max = 0.5;
    let mut native = settings.build::<4>().unwrap();
    assert!(native.system().params().has_friction());
    let z = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
    let mut tau = [f64::NAN; 2];
    let expected = native.step(&z);
    assert_eq!(
        unsafe { eigenmpc_step(mpc, z.as_ptr(), tau.as_mut_ptr()) },
        expected.status.code()
    );
    assert_eq!(tau.as_slice(), expected.tau.as_slice());
    let mut info = EigenMpcStepInfo::default();
    assert_eq!(unsafe { eigenmpc_last_step(mpc, &mut info) }, 0);
    assert!((info.energy - native.energy(&z)).abs() < 1e-15);
    unsafe { eigenmpc_free(mpc) };

    // any joint count of the table: a 4-link chain of point masses (its
    // chart computed from the model, as an exported robot's)
    let four = [
        ("m[1]", 0.5),
        ("m[2]", 0.5),
        ("m[3]", 0.5),
        ("m[4]", 0.5),
        ("l[1]", 0.4),
        ("l[2]", 0.4),
        ("l[3]", 0.4),
        ("l[4]", 0.4),
        ("E_ref", 1.0),
    ];
    let (mpc, err) = named(4, &four);
    assert!(!mpc.is_null(), "{err}");
    assert_eq!(unsafe { eigenmpc_joints(mpc) }, 4);
    let mut settings = eigenmpc_fmu_models::products::default_settings::<4>(Variant::Curved);
    settings.model.mass = [0.5; 4];
    settings.model.length = [0.4; 4];
    settings.tuning.e_ref = 1.0;
    let mut native = settings.build::<8>().unwrap();
    let z = SVector::<f64, 8>::from_column_slice(&[0.05, 0.05, 0.05, 0.05, 0.0, 0.0, 0.0, 0.0]);
    let mut tau = [f64::NAN; 4];
    let expected = native.step(&z);
    assert_eq!(
        unsafe { eigenmpc_step(mpc, z.as_ptr(), tau.as_mut_ptr()) },
        expected.status.code()
    );
    assert_eq!(tau.as_slice(), expected.tau.as_slice());
    unsafe { eigenmpc_free(mpc) };

    // refused with the FMU's messages
    for (joints, pairs, needle) in [
        (2, vec![("m[3]", 1.0)], "m[3] is not a variable of EigenMPC"),
        (3, vec![("q[1]", 0.1)], "q[1] is not a parameter"),
        (2, vec![("cf[1]", -1.0)], "cf[1] = -1 is below its minimum"),
        (2, vec![("mode", 1.5)], "mode = 1.5 must be an integer"),
        (7, vec![], "joints = 7: 7 joints are not supported"),
        (0, vec![], "joints = 0"),
        (
            4,
            vec![("m[5]", 1.0)],
            "m[5] is not a variable of the 4-joint controller",
        ),
    ] {
        let (mpc, err) = named(joints, &pairs);
        assert!(mpc.is_null());
        assert!(
            err.starts_with("eigenmpc_create_named: ") && err.contains(needle),
            "{err}"
        );
    }
    unsafe {
        let mut err = [0 as std::ffi::c_char; 100];
        let mpc = eigenmpc_create_named(2, ptr::null(), ptr::null(), 1, err.as_mut_ptr(), 100);
        assert!(mpc.is_null());
        assert_eq!(eigenmpc_joints(ptr::null()), -1);
    }
}

/// The controller's cdylib built for this test run.
fn library() -> PathBuf {
    fmi2_slave::testing::test_cdylib("eigenmpc_fmu")
}

#[test]
fn shared_library_exports_all_34_functions_and_the_c_api() {
    let exported = fmi2_slave::testing::assert_exports_fmi2_cs(&library());
    for name in [
        "eigenmpc_config_default",
        "eigenmpc_create",
        "eigenmpc_create_named",
        "eigenmpc_joints",
        "eigenmpc_set_e_ref",
        "eigenmpc_set_tuning",
        "eigenmpc_step",
        "eigenmpc_last_step",
        "eigenmpc_reset",
        "eigenmpc_last_error",
        "eigenmpc_free",
    ] {
        assert!(exported.iter().any(|e| e == name), "{name} not exported");
    }
}

#[test]
fn checked_in_model_description_matches_the_table() {
    let d = EigenMpcFmu::description();
    d.validate().unwrap();
    let generated = xml::model_description_xml(&d);
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../modelDescription/EigenMPC.xml");
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        checked_in == generated,
        "{} is out of date with the variable table: run `cargo run --release -p fmu-build -- --update-checked-in` and commit it",
        path.display()
    );
}

/// `adapt` on: the FMU runs the library's adaptation (identification fed
/// with the measured state and the torque it output, a new model and family
/// at every look that found the estimate moved), sample for sample, on a
/// plant it does not know; the estimate and the model count are outputs.
/// Off (the default), the estimate outputs are the model's own.
#[test]
fn adapt_follows_the_identified_plant_like_the_library() {
    use eigenmpc::adapt::Adaptation;
    use eigenmpc::identify::BaseParameters;
    use eigenmpc::integrate::{Dopri5, Tolerances};
    use eigenmpc::mechanics::{PlanarChain, PlanarChainParams, state_derivative};

    let estimate_vrs: Vec<u32> = EigenMpcFmu::description()
        .variables
        .iter()
        .filter(|v| v.name.starts_with("estimate."))
        .map(|v| v.value_reference)
        .collect();
    assert_eq!(estimate_vrs.len(), 11);
    let read_estimate =
        |fmu: &Fmu| -> Vec<f64> { estimate_vrs.iter().map(|&vr| fmu.real(vr)).collect() };

    // Off: the outputs are the paper's pendulum's base parameters.
    let off = Fmu::start(&[], &[], Z0);
    let prior = PlanarChainParams::<2>::default();
    let base = BaseParameters::<2, 11>::of(&prior).unwrap();
    assert_eq!(read_estimate(&off), base.theta.as_slice());
    assert_eq!(off.integer(vref("model_updates")), 0);
    drop(off);

    let mut fmu = Fmu::start_with(&[], &[], &[(vref("adapt"), true)], Z0);

    let mut settings = EigenMpc2::settings(Variant::Curved);
    settings.adapt = true;
    let mut native = settings.build::<4>().unwrap();
    let mut adaptation = Adaptation::<2, 4, 11>::new(&prior, settings.adapt_options()).unwrap();
    let mut plant_params = PlanarChainParams::<2>::point_masses([1.0, 1.2], [1.1, 1.0], 9.81);
    plant_params.joints[0].viscous = 0.05;
    plant_params.joints[1].viscous = 0.05;
    let plant = PlanarChain::new(plant_params).unwrap();
    let tol = Tolerances {
        rtol: 1e-10,
        atol: 1e-10,
    };
    let mut ode = Dopri5::new(0.0, SVector::<f64, 4>::from(Z0), tol);
    let mut tau = Vector::<2>::zeros();
    // Models are taken once the climb is over (about 20 s; issue 19).
    for k in 0..(40.0 / DT) as usize {
        let z = *ode.state();
        let (q, qd) = (Vector::<2>::new(z[0], z[1]), Vector::<2>::new(z[2], z[3]));
        let out = native.step(&z).tau;
        adaptation.sample(&mut native, &q, &qd, &tau, DT);
        tau = out;
        // a solve at t_k takes the inputs set before fmi2DoStep(t_k, h)
        // (t_0: at initialization)
        if k > 0 {
            assert_eq!(fmu.set(&state(), z.as_slice()), OK);
        }
        assert_eq!(fmu.step(DT), OK);
        assert_eq!(fmu.tau(), [tau[0], tau[1]], "sample {k}");
        ode.advance_to(
            |_, z| state_derivative::<_, 2, 4>(&plant, z, &tau),
            (k + 1) as f64 * DT,
        )
        .unwrap();
    }
    assert!(adaptation.model_updates() > 0);
    assert_eq!(
        fmu.integer(vref("model_updates")),
        adaptation.model_updates() as i32
    );
    let estimate = adaptation.identification().estimate();
    assert_eq!(read_estimate(&fmu), estimate.theta.as_slice());
    // the estimate moved towards the plant's (G[2] = g m2 l2: +20 %)
    let truth = BaseParameters::<2, 11>::of(&plant_params).unwrap();
    let g2 = |b: &BaseParameters<2, 11>| b.gravity_amplitude(1);
    assert!(
        (g2(&estimate) - g2(&truth)).abs() < 0.5 * (g2(&base) - g2(&truth)).abs(),
        "G[2]: estimate {}, model {}, plant {}",
        g2(&estimate),
        g2(&base),
        g2(&truth)
    );
    // the chart range output follows the new family
    let family = native.family().unwrap().energy_range();
    assert_eq!(fmu.real(vref("chart_energy_max")), family.1);
}

/// A model with joint springs cannot be identified: `adapt` is refused at
/// initialization with the reason.
#[test]
fn adapt_refuses_a_model_with_springs() {
    let fmu = Fmu::instantiate();
    let on: ffi::fmi2Boolean = 1;
    assert_eq!(unsafe { fmi2SetBoolean(fmu.c, &vref("adapt"), 1, &on) }, OK);
    assert_eq!(fmu.set(&[vref("k[1]")], &[2.0]), OK);
    unsafe {
        assert_eq!(fmi2SetupExperiment(fmu.c, 0, 0.0, 0.0, 0, 0.0), OK);
        assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
        assert_eq!(fmi2ExitInitializationMode(fmu.c), ERROR);
    }
    let log = format!("{:?}", fmu.instance.log.lines());
    assert!(
        log.contains("adapt = true") && log.contains("springs"),
        "{log}"
    );
}

/// The C API adapts as the FMU does: `adapt` in the config (checked) or
/// by name; `eigenmpc_estimate` gives the base parameters in the FMU's
/// output order, the model count is in the step info.
#[test]
fn c_api_adapts_and_reports_the_estimate() {
    use eigenmpc::identify::BaseParameters;
    use eigenmpc::mechanics::PlanarChainParams;
    let mut err = [0 as std::ffi::c_char; 300];
    let mut cfg = eigenmpc_config_default(VARIANT_CURVED);
    assert_eq!(
        (cfg.adapt, cfg.adapt_period, cfg.adapt_realtime),
        (0, 1.0, 0)
    );
    cfg.adapt = 2;
    let bad = unsafe { eigenmpc_create(&cfg, ptr::null(), err.as_mut_ptr(), err.len()) };
    assert!(bad.is_null());
    let text = unsafe { CStr::from_ptr(err.as_ptr()) }.to_str().unwrap();
    assert!(text.contains("adapt = 2 must be 0 or 1"), "{text}");

    // off: the model's base parameters
    cfg.adapt = 0;
    let off = unsafe { eigenmpc_create(&cfg, ptr::null(), err.as_mut_ptr(), err.len()) };
    assert!(!off.is_null());
    assert_eq!(unsafe { eigenmpc_estimate(off, ptr::null_mut(), 0) }, 11);
    let mut theta = [f64::NAN; 11];
    assert_eq!(
        unsafe { eigenmpc_estimate(off, theta.as_mut_ptr(), 11) },
        11
    );
    let prior = BaseParameters::<2, 11>::of(&PlanarChainParams::default()).unwrap();
    assert_eq!(theta.as_slice(), prior.theta.as_slice());
    assert_eq!(
        unsafe { eigenmpc_estimate(off, ptr::null_mut(), 3) },
        STATUS_BAD_ARGUMENT
    );
    unsafe { eigenmpc_free(off) };

    // on, against the FMU's own adaptive controller on the same states
    cfg.adapt = 1;
    let on = unsafe { eigenmpc_create(&cfg, ptr::null(), err.as_mut_ptr(), err.len()) };
    assert!(!on.is_null());
    let mut settings = EigenMpc2::settings(Variant::Curved);
    settings.adapt = true;
    let mut native =
        eigenmpc_fmu_models::controller::adaptive::AdaptiveController::<2, 4, 11, 15>::new(
            &settings,
        )
        .unwrap();
    // a plant with m2 20 % heavier than the model's: the estimate moves
    let plant = eigenmpc::mechanics::PlanarChain::new(PlanarChainParams::point_masses(
        [1.0, 1.2],
        [1.0, 1.0],
        9.81,
    ))
    .unwrap();
    let tol = eigenmpc::integrate::Tolerances {
        rtol: 1e-10,
        atol: 1e-10,
    };
    let mut ode = eigenmpc::integrate::Dopri5::new(0.0, SVector::<f64, 4>::from(Z0), tol);
    for k in 0..(6.0 / DT) as usize {
        let z = *ode.state();
        let mut tau = [f64::NAN; 2];
        assert_eq!(
            unsafe { eigenmpc_step(on, z.as_ptr(), tau.as_mut_ptr()) },
            0
        );
        let expected = native.step(&z, DT).tau;
        assert_eq!(tau.as_slice(), expected.as_slice(), "sample {k}");
        let tau = Vector::<2>::from(tau);
        ode.advance_to(
            |_, z| eigenmpc::mechanics::state_derivative::<_, 2, 4>(&plant, z, &tau),
            (k + 1) as f64 * DT,
        )
        .unwrap();
    }
    let mut info = EigenMpcStepInfo::default();
    assert_eq!(unsafe { eigenmpc_last_step(on, &mut info) }, 0);
    assert_eq!(info.model_updates as usize, native.model_updates());
    assert_eq!(unsafe { eigenmpc_estimate(on, theta.as_mut_ptr(), 11) }, 11);
    assert_eq!(
        theta.as_slice(),
        native.estimate().unwrap().theta.as_slice()
    );
    assert_ne!(theta.as_slice(), prior.theta.as_slice());
    unsafe { eigenmpc_free(on) };
}

/// The C API accepts what the FMU accepts: the config and the tuning are
/// checked by the FMU's variable table (messages name the config field and
/// the FMU parameter), and a message names its function once.
#[test]
fn c_api_ranges_are_the_fmus() {
    let mut err = [0 as std::ffi::c_char; 300];
    let create = |cfg: &EigenMpcConfig, err: &mut [std::ffi::c_char]| {
        let mpc = unsafe { eigenmpc_create(cfg, ptr::null(), err.as_mut_ptr(), err.len()) };
        let text = unsafe { CStr::from_ptr(err.as_ptr()) }
            .to_str()
            .unwrap()
            .to_string();
        (mpc, text)
    };
    let description = EigenMpcFmu::description();
    for (set, needle) in [
        (
            Box::new(|c: &mut EigenMpcConfig| c.sample_period = 1e300)
                as Box<dyn Fn(&mut EigenMpcConfig)>,
            "config.sample_period: sample_period = 1e300 is above its maximum 10",
        ),
        (
            Box::new(|c: &mut EigenMpcConfig| c.e_ref = 2e4),
            "config.e_ref (E_ref): E_ref = 2e4 is above its maximum 1e4",
        ),
        (
            Box::new(|c: &mut EigenMpcConfig| c.masses[1] = -1.0),
            "config.masses[1] (m[2])",
        ),
        (
            Box::new(|c: &mut EigenMpcConfig| c.mode = 3),
            "config.mode: mode = 3 is above its maximum 2",
        ),
    ] {
        let mut cfg = eigenmpc_config_default(VARIANT_CURVED);
        set(&mut cfg);
        let (mpc, text) = create(&cfg, &mut err);
        assert!(mpc.is_null(), "{needle}");
        assert!(text.contains(needle), "{text}");
        assert_eq!(text.matches("eigenmpc_create").count(), 1, "{text}");
    }
    assert_eq!(
        description.variable("sample_period").unwrap().max,
        Some(10.0)
    );
    let (_, text) = {
        let mut e = [0 as std::ffi::c_char; 300];
        let mpc = unsafe { eigenmpc_create(ptr::null(), ptr::null(), e.as_mut_ptr(), e.len()) };
        assert!(mpc.is_null());
        (
            mpc,
            unsafe { CStr::from_ptr(e.as_ptr()) }
                .to_str()
                .unwrap()
                .to_string(),
        )
    };
    assert_eq!(text, "eigenmpc_create: config is NULL");

    let cfg = eigenmpc_config_default(VARIANT_CURVED);
    let (mpc, text) = create(&cfg, &mut err);
    assert!(!mpc.is_null(), "{text}");
    assert_eq!(
        unsafe { eigenmpc_set_e_ref(mpc, 1e300) },
        STATUS_BAD_ARGUMENT
    );
    let msg = unsafe { CStr::from_ptr(eigenmpc_last_error(mpc)) }
        .to_str()
        .unwrap();
    assert!(msg.contains("E_ref = 1e300 is above its maximum"), "{msg}");
    let mut tuned = cfg;
    tuned.w_x = -1.0;
    assert_eq!(
        unsafe { eigenmpc_set_tuning(mpc, &tuned) },
        STATUS_BAD_ARGUMENT
    );
    let msg = unsafe { CStr::from_ptr(eigenmpc_last_error(mpc)) }
        .to_str()
        .unwrap();
    assert!(
        msg.contains("config.w_x: w_x = -1 is below its minimum"),
        "{msg}"
    );
    // The energy scale (the last field) is a tunable too: checked as the
    // FMU's E_scale, and E_ref = 0 only with the paper's residual (0).
    assert_eq!(cfg.e_scale, 14.0);
    let mut tuned = cfg;
    tuned.e_scale = -1.0;
    assert_eq!(
        unsafe { eigenmpc_set_tuning(mpc, &tuned) },
        STATUS_BAD_ARGUMENT
    );
    let msg = unsafe { CStr::from_ptr(eigenmpc_last_error(mpc)) }
        .to_str()
        .unwrap();
    assert!(
        msg.contains("config.e_scale: E_scale = -1 is below its minimum"),
        "{msg}"
    );
    assert_eq!(unsafe { eigenmpc_set_e_ref(mpc, 0.0) }, STATUS_BAD_ARGUMENT);
    tuned.e_scale = 0.0;
    tuned.e_ref = 0.0;
    assert_eq!(unsafe { eigenmpc_set_tuning(mpc, &tuned) }, 0);
    assert_eq!(unsafe { eigenmpc_set_e_ref(mpc, 8.0) }, 0);
    unsafe { eigenmpc_free(mpc) };
}

/// Out-of-range inputs are refused by fmi2SetReal (the energy output then
/// stays finite); a run of failed solves is logged the first time and every
/// 100th, each counted in the message and each in `solver_status`.
#[test]
fn input_ranges_and_rate_limited_failure_warnings() {
    let fmu = Fmu::start(&[], &[], Z0);
    assert_eq!(fmu.set(&[vref("qd[1]")], &[1e308]), ERROR);
    assert!(
        fmu.instance
            .log
            .contains(&["qd[1] = 1e308 is above its maximum 1e6"])
    );
    drop(fmu);

    let mut fmu = Fmu::start(&[], &[], Z0);
    let mut statuses = vec![];
    for _ in 0..250 {
        assert_eq!(fmu.set(&state(), &[0.1, 0.1, 1e6, -1e6]), OK);
        statuses.push(fmu.step(DT));
        assert_eq!(fmu.integer(vref("solver_status")), STATUS_QP_FAILED);
        assert!(fmu.real(vref("energy")).is_finite());
    }
    let failed = fmu.instance.log.lines();
    let logged: Vec<&str> = failed
        .iter()
        .filter(|l| l.message.contains("QP failed"))
        .map(|l| l.message.as_str())
        .collect();
    assert_eq!(logged.len(), 3, "{logged:?}");
    assert!(logged[0].contains("1 unsuccessful solve(s) so far"));
    assert!(logged[2].contains("200 unsuccessful solve(s) so far"));
    assert_eq!(statuses.iter().filter(|&&s| s == WARNING).count(), 3);
    assert!(statuses.iter().all(|&s| s == OK || s == WARNING));
}

/// `fmi2Reset` and the same run again equal a fresh instance bit for bit
/// (fmpy's loops and its Dask example reset between runs), also with the
/// adaptation's worker and estimate in play.
#[test]
fn reset_then_the_same_run_equals_a_fresh_instance() {
    use eigenmpc::integrate::{Dopri5, Tolerances};
    use eigenmpc::mechanics::{PlanarChain, PlanarChainParams, state_derivative};
    let plant = PlanarChain::new(PlanarChainParams::<2>::point_masses(
        [1.0, 1.2],
        [1.0, 1.0],
        9.81,
    ))
    .unwrap();
    // Parameters and inputs of one run from instantiation; the torque trace.
    let run = |fmu: &mut Fmu| -> Vec<[f64; 2]> {
        let on: ffi::fmi2Boolean = 1;
        assert_eq!(unsafe { fmi2SetBoolean(fmu.c, &vref("adapt"), 1, &on) }, OK);
        assert_eq!(fmu.set(&[vref("adapt_period")], &[0.25]), OK);
        unsafe {
            assert_eq!(fmi2SetupExperiment(fmu.c, 0, 0.0, 0.0, 0, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
            assert_eq!(fmu.set(&state(), &Z0), OK);
            assert_eq!(fmi2ExitInitializationMode(fmu.c), OK);
        }
        fmu.t = 0.0;
        let tol = Tolerances {
            rtol: 1e-10,
            atol: 1e-10,
        };
        let mut ode = Dopri5::new(0.0, SVector::<f64, 4>::from(Z0), tol);
        let mut taus = vec![];
        for k in 0..160 {
            let z = *ode.state();
            if k > 0 {
                assert_eq!(fmu.set(&state(), z.as_slice()), OK);
            }
            assert_eq!(fmu.step(DT), OK);
            let tau = fmu.tau();
            taus.push(tau);
            let tau = Vector::<2>::from(tau);
            ode.advance_to(
                |_, z| state_derivative::<_, 2, 4>(&plant, z, &tau),
                (k + 1) as f64 * DT,
            )
            .unwrap();
        }
        // The identification has moved the estimate (a model is taken
        // only after the climb, later than this run).
        assert_ne!(fmu.real(vref("estimate.G[2]")), 9.81);
        taus
    };
    let mut fresh = Fmu::instantiate();
    let first = run(&mut fresh);
    assert_eq!(unsafe { fmi2Reset(fresh.c) }, OK);
    let again = run(&mut fresh);
    let mut other = Fmu::instantiate();
    let new = run(&mut other);
    assert_eq!(first, again, "after fmi2Reset");
    assert_eq!(first, new, "a fresh instance");
}

/// The C API takes the measurement delay and the actuator lag (default 0)
/// and refuses what the controller does not compensate, naming the field.
#[test]
fn c_api_takes_delay_and_lag() {
    let mut err = [0 as std::ffi::c_char; 300];
    let mut cfg = eigenmpc_config_default(VARIANT_CURVED);
    assert_eq!(
        (cfg.measurement_delay, cfg.actuator_time_constant),
        (0.0, 0.0)
    );
    cfg.measurement_delay = 0.1;
    cfg.actuator_time_constant = 0.05;
    let mpc = unsafe { eigenmpc_create(&cfg, ptr::null(), err.as_mut_ptr(), err.len()) };
    assert!(!mpc.is_null());
    let z = [0.05, 0.05, 0.0, 0.0];
    let mut tau = [f64::NAN; 2];
    unsafe {
        assert!(eigenmpc_step(mpc, z.as_ptr(), tau.as_mut_ptr()) >= 0);
        eigenmpc_free(mpc);
    }
    assert!(tau.iter().all(|t| t.is_finite()));
    for (delay, lag, field) in [
        (1.5, 0.0, "measurement_delay"),
        (0.0, -0.1, "actuator_time_constant"),
    ] {
        cfg.measurement_delay = delay;
        cfg.actuator_time_constant = lag;
        let bad = unsafe { eigenmpc_create(&cfg, ptr::null(), err.as_mut_ptr(), err.len()) };
        assert!(bad.is_null());
        let text = unsafe { CStr::from_ptr(err.as_ptr()) }.to_str().unwrap();
        assert!(text.contains(field), "{text}");
    }
}

/// The C API takes the motor's response per sample (default 1, immediate):
/// a declared overshooting motor gets a command that differs from an
/// immediate motor's, and a response outside (0, 2] or one declared with a
/// first-order lag is refused, naming the field.
#[test]
fn c_api_takes_the_torque_response() {
    let mut err = [0 as std::ffi::c_char; 300];
    let cfg = eigenmpc_config_default(VARIANT_CURVED);
    assert_eq!(cfg.torque_response, 1.0);
    let first_command = |cfg: &EigenMpcConfig| {
        let mpc = unsafe { eigenmpc_create(cfg, ptr::null(), err.as_ptr().cast_mut(), 300) };
        assert!(!mpc.is_null());
        let z = [0.05, 0.05, 0.0, 0.0];
        let mut tau = [[f64::NAN; 2]; 2];
        unsafe {
            for t in &mut tau {
                assert!(eigenmpc_step(mpc, z.as_ptr(), t.as_mut_ptr()) >= 0);
            }
            eigenmpc_free(mpc);
        }
        tau
    };
    let immediate = first_command(&cfg);
    let overshooting = first_command(&EigenMpcConfig {
        torque_response: 2.0,
        ..cfg
    });
    // From rest the first command makes a = 2 apply it doubled: half of it.
    for j in 0..2 {
        assert!((overshooting[0][j] - 0.5 * immediate[0][j]).abs() < 1e-12);
    }
    for (response, lag) in [(0.0, 0.0), (2.5, 0.0), (f64::NAN, 0.0), (0.5, 0.05)] {
        let bad_cfg = EigenMpcConfig {
            torque_response: response,
            actuator_time_constant: lag,
            ..cfg
        };
        let bad = unsafe { eigenmpc_create(&bad_cfg, ptr::null(), err.as_mut_ptr(), err.len()) };
        assert!(bad.is_null(), "{response}, {lag}");
        let text = unsafe { CStr::from_ptr(err.as_ptr()) }.to_str().unwrap();
        assert!(text.contains("torque_response"), "{text}");
    }
}
